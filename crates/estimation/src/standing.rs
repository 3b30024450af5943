//! Force/torque offsets learnt while the robot stands still on both feet (`ft_offsets.learn_while_standing`):
//! the model predicts each sensor's reading from the robot's weight split between the soles, and the offset
//! is the mean of the reading minus that prediction [Traversaro 2017, §4.7], as a lab zeroes its sensors
//! before a walk.
//!
//! The split between two feet on the ground is not observable from the weight alone (twelve unknowns, six
//! equations; docs/estimation.md, "FT offsets, and what happens at start-up"): it is taken from a model of
//! the contact, [`standing_foot_wrenches`]. What the real split differs from it by (internal forces, an
//! uneven floor) goes into the offsets: the method suits a robot standing still and symmetric on a flat floor.

use nalgebra::{DVector, Matrix3, Matrix6, SMatrix, Vector3, Vector6};

/// The wrenches `[f; τ]` (world orientation, about each sole origin; N, N·m) the ground applies on two flat
/// soles that carry the total force `force` (N) with no moment about the CoM `com` (the robot standing still:
/// no rate of angular momentum). Soles at `soles` (world position, rotation), rectangles of
/// `sole_size = [length, width]` (m, along the sole's x and y).
///
/// The split is the elastic one of a Winkler (linear spring bed) floor under rigid soles at one height, the
/// minimum of the complementary energy `Σ (|f|² + τ_x²/L_x² + τ_y²/L_y² + τ_z²/L_z²)` subject to the six
/// equilibrium equations, with `L_x² = width²/12`, `L_y² = length²/12`, `L_z² = L_x² + L_y²` (each sole
/// axis's second moment of area over the area): `w = W⁻¹ Gᵀ (G W⁻¹ Gᵀ)⁻¹ [force; 0]`, `G` the 6 × 12
/// map of the two sole wrenches to the total about the CoM. On a symmetric stance it halves the weight and
/// the ankle torques; no tangential force unless the CoM is off the soles' plane of symmetry.
///
/// `None` when `G W⁻¹ Gᵀ` is not positive definite (a sole size that is not finite and positive; the
/// estimator's `sole_size` is validated).
pub fn standing_foot_wrenches(
    force: &Vector3<f64>,
    com: &Vector3<f64>,
    soles: &[(Matrix3<f64>, Vector3<f64>); 2],
    sole_size: [f64; 2],
) -> Option<[Vector6<f64>; 2]> {
    let [length, width] = sole_size;
    let lx2 = width * width / 12.0;
    let ly2 = length * length / 12.0;
    let moments = Matrix3::from_diagonal(&Vector3::new(lx2, ly2, lx2 + ly2));
    // W⁻¹ Gᵀ, block by block, and G W⁻¹ Gᵀ.
    let mut w_inv_gt = SMatrix::<f64, 12, 6>::zeros();
    for (k, (r, p)) in soles.iter().enumerate() {
        let arm = (p - com).cross_matrix();
        let torque_weight = r * moments * r.transpose();
        // Gₖ = [[I, 0]; [[arm]×, I]] (force, then moment about the CoM); W⁻¹ Gₖᵀ = [[I, [arm]×ᵀ]; [0, T]].
        let gt = {
            let mut m = Matrix6::zeros();
            m.fixed_view_mut::<3, 3>(0, 0)
                .copy_from(&Matrix3::identity());
            m.fixed_view_mut::<3, 3>(0, 3).copy_from(&arm.transpose());
            m.fixed_view_mut::<3, 3>(3, 3)
                .copy_from(&Matrix3::identity());
            m
        };
        let mut block = gt;
        let weighted = torque_weight * gt.fixed_view::<3, 6>(3, 0);
        block.fixed_view_mut::<3, 6>(3, 0).copy_from(&weighted);
        w_inv_gt.fixed_view_mut::<6, 6>(6 * k, 0).copy_from(&block);
    }
    let mut g = SMatrix::<f64, 6, 12>::zeros();
    for (k, (_, p)) in soles.iter().enumerate() {
        let arm = (p - com).cross_matrix();
        g.fixed_view_mut::<3, 3>(0, 6 * k)
            .copy_from(&Matrix3::identity());
        g.fixed_view_mut::<3, 3>(3, 6 * k).copy_from(&arm);
        g.fixed_view_mut::<3, 3>(3, 6 * k + 3)
            .copy_from(&Matrix3::identity());
    }
    let normal = g * w_inv_gt;
    let rhs = Vector6::new(force.x, force.y, force.z, 0.0, 0.0, 0.0);
    let lambda = normal.cholesky()?.solve(&rhs);
    let x = w_inv_gt * lambda;
    Some([
        x.fixed_rows::<6>(0).into_owned(),
        x.fixed_rows::<6>(6).into_owned(),
    ])
}

/// The running mean of the offset samples `y − ŷ` of every sensor while the robot stands
/// ([`crate::Estimator`] keeps one while `ft_offsets.learn_while_standing` lasts).
#[derive(Debug, Clone)]
pub(crate) struct StandingOffsets {
    /// Learning ends at this time \[ns\] (set on the first tick).
    pub(crate) until_ns: Option<u64>,
    /// Duration \[ns\].
    pub(crate) duration_ns: u64,
    /// Sum of the samples, per sensor.
    pub(crate) sum: Vec<Vector6<f64>>,
    /// Samples taken.
    pub(crate) count: usize,
    /// The readings the model predicts with the standing split, per sensor (scratch).
    pub(crate) expected: Vec<Vector6<f64>>,
    /// The standing robot's generalized acceleration: zero (`nv`).
    pub(crate) still: DVector<f64>,
    /// Sum of the accelerometer's bias samples (`ekf.level_soles_while_standing`).
    pub(crate) acc_sum: Vector3<f64>,
    /// Accelerometer samples taken.
    pub(crate) acc_count: usize,
}

impl StandingOffsets {
    /// Learning for `duration` \[s\] over `n_ft` sensors of a model with `nv` velocities.
    pub(crate) fn new(duration: f64, n_ft: usize, nv: usize) -> Self {
        Self {
            until_ns: None,
            duration_ns: (duration * 1e9).round() as u64,
            sum: vec![Vector6::zeros(); n_ft],
            count: 0,
            expected: vec![Vector6::zeros(); n_ft],
            still: DVector::zeros(nv),
            acc_sum: Vector3::zeros(),
            acc_count: 0,
        }
    }

    /// Forgets the samples (a new start).
    pub(crate) fn restart(&mut self) {
        self.until_ns = None;
        self.count = 0;
        self.sum.iter_mut().for_each(|s| *s = Vector6::zeros());
        self.acc_count = 0;
        self.acc_sum = Vector3::zeros();
    }

    /// Whether a tick at `time_ns` learns (fixes the end on the first call).
    pub(crate) fn active(&mut self, time_ns: u64) -> bool {
        let until = *self
            .until_ns
            .get_or_insert(time_ns.saturating_add(self.duration_ns));
        time_ns <= until
    }

    /// Adds an accelerometer bias sample of a robot standing still on two level soles, the reading `acc`
    /// less the proper acceleration of a still IMU, `|g| n` (`gravity` = `|g|`), with `n` the up direction
    /// in the IMU frame, the mean of the soles' normals `imu_r_sole[i] e_z` (a level sole's normal is the
    /// world's up). Returns the running mean, the accelerometer's bias (IMU frame). A robot that moves while
    /// it learns adds its acceleration to the samples, whose mean is its change of velocity over the window
    /// (none, standing), and the tilt of its soles, which a level ground does not give them.
    pub(crate) fn accelerometer_bias(
        &mut self,
        acc: &Vector3<f64>,
        gravity: f64,
        imu_r_sole: &[Matrix3<f64>; 2],
    ) -> Vector3<f64> {
        let up = (imu_r_sole[0].column(2) + imu_r_sole[1].column(2)).normalize();
        self.acc_sum += acc - up * gravity;
        self.acc_count += 1;
        self.acc_sum / self.acc_count as f64
    }
}
