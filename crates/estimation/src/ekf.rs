//! Contact-aided invariant EKF [Hartley 2020] in the fixed two-feet form of bipedal-locomotion-framework.
//!
//! State: `X ∈ SE_4(3)` holding the IMU orientation `R` (IMU to world), velocity `v` and position `p` of the
//! IMU origin (world), and the left and right contact points `d_l`, `d_r` (world); the left and right sole
//! orientations `F_l`, `F_r ∈ SO(3)` (sole to world, DILIGENT-KIO's foot orientations [Ramadoss 2021]); plus
//! the gyroscope and accelerometer biases `b_g`, `b_a` (IMU frame) outside the group. Error:
//! right-invariant, `X = Exp(ξ) X̂`, `F = Exp(ψ) F̂`, `b = b̂ + δb`, tangent ordered
//! `(φ, v, p, d_l, d_r, ψ_l, ψ_r | b_g, b_a)` (27).
//!
//! Propagation uses the raw gyroscope and accelerometer ([Hartley 2020] process model), never the IMU's
//! on-board orientation: `ω = ω̃ − b_g`, `a = ã − b_a`, `R⁺ = R Exp(ω dt)`, `v⁺ = v + (R a + g) dt`,
//! `p⁺ = p + v dt + ½ (R a + g) dt²`. A contact point is static up to white velocity noise in its sole
//! frame (which lets a foot slip); the swing foot's point is reset to kinematics (see
//! [`InvariantEkf::reset_foot`]). The kinematic update [`InvariantEkf::update_foot`] has the
//! right-invariant form `Y = X⁻¹ b + V` with the constant Jacobian `H = [0 0 −I … I …]`; its orientation
//! part (a flat foot in contact does not rotate: `Rᵀ F = R_h(q)`) has the constant Jacobian
//! `[−I … I at ψ …]` too. The sole orientation is what makes the yaw and the gyroscope's yaw bias
//! observable while a foot is in contact: a point contact pins the IMU's position, not its heading.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};
use stride_model::spatial::skew;

use crate::config::EkfConfig;
use crate::error::{EstimatorError, Result};
use crate::sole_spin::SoleSpin;

/// Dimension of the error state.
pub const DIM: usize = 27;
/// Error-state covariance.
pub type Covariance = SMatrix<f64, DIM, DIM>;

const PHI: usize = 0;
const VEL: usize = 3;
const POS: usize = 6;
const FOOT: [usize; 2] = [9, 12];
const FOOT_ROT: [usize; 2] = [15, 18];
const BG: usize = 21;
const BA: usize = 24;
/// Rows of the error state the gyroscope noise enters, `(φ, v, p, d_l, d_r)` (`ψ` has its own noise).
const NGYRO: usize = 15;

/// The filter's state and covariance, with its noise model.
#[derive(Debug, Clone)]
pub struct InvariantEkf {
    rot: Matrix3<f64>,
    vel: Vector3<f64>,
    pos: Vector3<f64>,
    feet: [Vector3<f64>; 2],
    foot_rot: [Matrix3<f64>; 2],
    gyro_bias: Vector3<f64>,
    acc_bias: Vector3<f64>,
    cov: Covariance,
    gravity: Vector3<f64>,
    gyro_var: Matrix3<f64>,
    acc_var: Matrix3<f64>,
    gyro_bias_var: Matrix3<f64>,
    acc_bias_var: Matrix3<f64>,
    foot_var: Matrix3<f64>,
    foot_rot_var: Matrix3<f64>,
    kin_var: f64,
    kin_rot_var: f64,
    foot_orientation: bool,
    foot_tilt: bool,
    bias_estimation: bool,
    /// The base heading integrated from the gyroscope alone \[rad\] (never corrected; only its changes
    /// over a stance are used, by [`SoleSpin`]).
    gyro_heading: f64,
    sole_spin: [SoleSpin; 2],
}

/// The mean of the filter's state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EkfState {
    /// `world_R_imu`.
    pub rotation: Matrix3<f64>,
    /// IMU origin velocity, world \[m/s\].
    pub velocity: Vector3<f64>,
    /// IMU origin position, world \[m\].
    pub position: Vector3<f64>,
    /// Left and right contact points, world \[m\].
    pub feet: [Vector3<f64>; 2],
    /// Left and right sole orientations, `world_R_sole`.
    pub foot_rotations: [Matrix3<f64>; 2],
    /// Gyroscope bias, IMU frame \[rad/s\].
    pub gyro_bias: Vector3<f64>,
    /// Accelerometer bias, IMU frame \[m/s²\].
    pub accelerometer_bias: Vector3<f64>,
}

fn diag_sq(s: &[f64; 3]) -> Matrix3<f64> {
    Matrix3::from_diagonal(&Vector3::new(s[0] * s[0], s[1] * s[1], s[2] * s[2]))
}

/// `Exp` of SO(3) and its left Jacobian `J_l(φ)`.
fn so3_exp_and_jacobian(phi: &Vector3<f64>) -> (Matrix3<f64>, Matrix3<f64>) {
    let theta2 = phi.norm_squared();
    let theta = theta2.sqrt();
    let k = skew(phi);
    let k2 = k * k;
    // sin θ/θ, (1 − cos θ)/θ², (θ − sin θ)/θ³ with their series near 0.
    let (a, b, c) = if theta < 1e-5 {
        (
            1.0 - theta2 / 6.0,
            0.5 - theta2 / 24.0,
            1.0 / 6.0 - theta2 / 120.0,
        )
    } else {
        (
            theta.sin() / theta,
            (1.0 - theta.cos()) / theta2,
            (theta - theta.sin()) / (theta2 * theta),
        )
    };
    let i = Matrix3::identity();
    (i + k * a + k2 * b, i + k * b + k2 * c)
}

/// `Log` of SO(3): the rotation vector of `r` (a rotation matrix), for angles below π (the residuals it
/// serves are small). The cosine is clamped: a product of rotations may have a trace slightly above 3.
fn so3_log(r: &Matrix3<f64>) -> Vector3<f64> {
    let vee = 0.5
        * Vector3::new(
            r[(2, 1)] - r[(1, 2)],
            r[(0, 2)] - r[(2, 0)],
            r[(1, 0)] - r[(0, 1)],
        );
    let cos = (0.5 * (r.trace() - 1.0)).clamp(-1.0, 1.0);
    let theta = cos.acos();
    // θ / sin θ with its series near 0 (vee = sin θ · axis).
    let scale = if theta < 1e-4 {
        1.0 + theta * theta / 6.0
    } else {
        theta / theta.sin()
    };
    vee * scale
}

/// The heading of a rotation \[rad\]: the angle of its x axis projected on the world's horizontal plane.
fn heading(r: &Matrix3<f64>) -> f64 {
    r[(1, 0)].atan2(r[(0, 0)])
}

/// Re-orthonormalises a rotation matrix that may be far from orthonormal (the initial state): the rotation
/// nearest to `r`, by nalgebra's iteration (`Rotation3::from_matrix_eps`) to machine precision.
fn orthonormalize(r: &Matrix3<f64>) -> Matrix3<f64> {
    let rot =
        nalgebra::Rotation3::from_matrix_eps(r, f64::EPSILON, 0, nalgebra::Rotation3::identity());
    *rot.matrix()
}

/// Re-orthonormalises `r`, a product of rotations that is orthonormal up to rounding (`‖RᵀR − I‖` of a few
/// ulps), by one step of the Newton–Schulz iteration for the polar factor, `R ← ½ R (3I − RᵀR)`: the
/// symmetric error `E = RᵀR − I` becomes `O(E²)`, below rounding, so the result is the
/// nearest rotation (what nalgebra's `Rotation3::from_matrix_eps` iterates to) to rounding. Two 3×3 products
/// instead of nalgebra's iteration (docs/performance.md, "Estimation layer, 2026-12-02").
fn renormalize(r: &Matrix3<f64>) -> Matrix3<f64> {
    let e = r.tr_mul(r);
    r * (Matrix3::identity() * 3.0 - e) * 0.5
}

impl InvariantEkf {
    /// A filter with the noise model of `config`, gravity `gravity` (world, m/s²), at the identity state.
    pub fn new(config: &EkfConfig, gravity: Vector3<f64>) -> Self {
        Self {
            rot: Matrix3::identity(),
            vel: Vector3::zeros(),
            pos: Vector3::zeros(),
            feet: [Vector3::zeros(); 2],
            foot_rot: [Matrix3::identity(); 2],
            gyro_bias: Vector3::from(config.initial_gyro_bias),
            acc_bias: Vector3::from(config.initial_accelerometer_bias),
            cov: Covariance::identity(),
            gravity,
            gyro_var: diag_sq(&config.gyro_noise),
            acc_var: diag_sq(&config.accelerometer_noise),
            gyro_bias_var: diag_sq(&config.gyro_bias_noise),
            acc_bias_var: diag_sq(&config.accelerometer_bias_noise),
            foot_var: diag_sq(&config.contact_foot_velocity_noise),
            foot_rot_var: diag_sq(&config.contact_foot_angular_velocity_noise),
            kin_var: config.kinematics_noise * config.kinematics_noise,
            kin_rot_var: config.kinematics_orientation_noise * config.kinematics_orientation_noise,
            foot_orientation: config.foot_orientation,
            foot_tilt: config.foot_tilt,
            bias_estimation: config.bias_estimation,
            gyro_heading: 0.0,
            sole_spin: [SoleSpin::new(config.sole_spin_threshold); 2],
        }
    }

    /// Sets the state: IMU pose and velocity, contact points and sole orientations (`world_R_sole`),
    /// biases; covariance from `config.prior` (orientation σ's about world axes; each foot's error equals
    /// the position and orientation error plus `kinematics_noise` and `kinematics_orientation_noise`, as
    /// when a foot is placed by kinematics). Biases without estimation get no uncertainty.
    #[allow(clippy::too_many_arguments)]
    pub fn initialize(
        &mut self,
        config: &EkfConfig,
        rotation: Matrix3<f64>,
        velocity: Vector3<f64>,
        position: Vector3<f64>,
        feet: [Vector3<f64>; 2],
        foot_rotations: [Matrix3<f64>; 2],
    ) {
        self.rot = orthonormalize(&rotation);
        self.vel = velocity;
        self.pos = position;
        self.feet = feet;
        self.foot_rot = foot_rotations.map(|r| orthonormalize(&r));
        self.gyro_bias = Vector3::from(config.initial_gyro_bias);
        self.acc_bias = Vector3::from(config.initial_accelerometer_bias);
        let prior = &config.prior;
        let mut cov = Covariance::zeros();
        cov.fixed_view_mut::<3, 3>(PHI, PHI)
            .copy_from(&diag_sq(&prior.orientation));
        for (i, s) in [(VEL, prior.velocity), (POS, prior.position)] {
            cov.fixed_view_mut::<3, 3>(i, i)
                .copy_from(&(Matrix3::identity() * (s * s)));
        }
        if self.bias_estimation {
            for (i, s) in [(BG, prior.gyro_bias), (BA, prior.accelerometer_bias)] {
                cov.fixed_view_mut::<3, 3>(i, i)
                    .copy_from(&(Matrix3::identity() * (s * s)));
            }
        }
        self.cov = cov;
        for foot in 0..2 {
            self.copy_base_error_to_foot(foot);
            self.sole_spin[foot].lift();
        }
    }

    /// The mean.
    pub fn state(&self) -> EkfState {
        EkfState {
            rotation: self.rot,
            velocity: self.vel,
            position: self.pos,
            feet: self.feet,
            foot_rotations: self.foot_rot,
            gyro_bias: self.gyro_bias,
            accelerometer_bias: self.acc_bias,
        }
    }

    /// The error-state covariance, tangent ordered `(φ, v, p, d_l, d_r, ψ_l, ψ_r, b_g, b_a)`.
    pub fn covariance(&self) -> &Covariance {
        &self.cov
    }

    /// Angular velocity of the IMU, world \[rad/s\], from a gyroscope sample and the bias estimate.
    pub fn angular_velocity_world(&self, gyro: &Vector3<f64>) -> Vector3<f64> {
        self.rot * (gyro - self.gyro_bias)
    }

    /// Linear acceleration of the IMU origin, world \[m/s²\], from an accelerometer sample and the bias
    /// estimate: `R (ã − b_a) + g`.
    pub fn acceleration_world(&self, acc: &Vector3<f64>) -> Vector3<f64> {
        self.rot * (acc - self.acc_bias) + self.gravity
    }

    /// Propagates by `dt` \[s\] with a gyroscope sample `gyro` \[rad/s\] and an accelerometer sample `acc`
    /// (proper acceleration) \[m/s²\], IMU frame. `stance[i]` says whether foot `i` was in contact over the
    /// interval, and `imu_r_sole[i]` is its sole orientation in the IMU frame (the frame of its velocity
    /// noise). A sole in contact turns by white angular-velocity noise in its own frame
    /// (`contact_foot_angular_velocity_noise`, rotated to world by `F̂`); no other term moves `ψ`. Covariance: `P⁻ = Φ (P + G Q_c Gᵀ dt) Φᵀ` [Hartley 2020], with `Φ = I + A dt + ½ (A dt)²`,
    /// `A` the right-invariant error dynamics evaluated at the current estimate and `G = blkdiag(Ad_X̂, I₆)`.
    pub fn propagate(
        &mut self,
        gyro: &Vector3<f64>,
        acc: &Vector3<f64>,
        dt: f64,
        stance: [bool; 2],
        imu_r_sole: &[Matrix3<f64>; 2],
    ) {
        self.propagate_over(gyro, acc, dt, dt, stance, imu_r_sole);
    }

    /// [`Self::propagate`] at the end of a pre-integrated interval: the samples before this one moved the
    /// mean only ([`Self::propagate_mean`]); the covariance is propagated once over the whole `interval`
    /// \[s\] (this sample's `dt` included), with `Φ` and `G` evaluated at the current estimate, and the mean
    /// over `dt`. The group part of the right-invariant error dynamics does not depend on the state and is
    /// nilpotent (`A³ = 0`), so its `Φ = I + A Δt + ½ (A Δt)²` is exact for any interval; the bias columns and
    /// the noise's adjoint `Ad_X̂` are frozen over the interval [Hartley 2020]. With `interval == dt` this is
    /// [`Self::propagate`] bit for bit.
    pub fn propagate_over(
        &mut self,
        gyro: &Vector3<f64>,
        acc: &Vector3<f64>,
        dt: f64,
        interval: f64,
        stance: [bool; 2],
        imu_r_sole: &[Matrix3<f64>; 2],
    ) {
        self.propagate_covariance(interval, stance, imu_r_sole);
        self.propagate_mean(gyro, acc, dt);
    }

    /// Moves the mean by one IMU sample (the mean of [`Self::propagate`], bit for bit) and leaves the
    /// covariance as it is: the pre-integration of the samples between two full ticks, whose covariance
    /// [`Self::propagate_over`] then propagates at once.
    pub fn propagate_mean(&mut self, gyro: &Vector3<f64>, acc: &Vector3<f64>, dt: f64) {
        self.gyro_heading += (self.rot * (gyro - self.gyro_bias)).z * dt;
        let predicted = self.predicted_state(gyro, acc, dt);
        self.rot = predicted.rotation;
        self.vel = predicted.velocity;
        self.pos = predicted.position;
    }

    /// The mean that [`Self::propagate`] leads to, bit for bit, without changing the filter: `R⁺ = R Exp(ω dt)`,
    /// `v⁺ = v + (R a + g) dt`, `p⁺ = p + v dt + ½ (R a + g) dt²` with `ω = ω̃ − b_g`, `a = ã − b_a`
    /// [Hartley 2020]. Lets a caller place the robot at the predicted state before the propagation.
    pub fn predicted_state(&self, gyro: &Vector3<f64>, acc: &Vector3<f64>, dt: f64) -> EkfState {
        let w = gyro - self.gyro_bias;
        let a = acc - self.acc_bias;
        let acc_world = self.rot * a + self.gravity;
        let (exp_w, _) = so3_exp_and_jacobian(&(w * dt));
        EkfState {
            rotation: renormalize(&(self.rot * exp_w)),
            velocity: self.vel + acc_world * dt,
            position: self.pos + (self.vel * dt + acc_world * (0.5 * dt * dt)),
            ..self.state()
        }
    }

    /// The off-identity 3×3 blocks `(row, column, block)` of `Φ = I + A dt + ½ A² dt²`, the transition of
    /// the linearised right-invariant error dynamics ([Hartley 2020]; bias columns as in
    /// bipedal-locomotion-framework's `calcFc`), evaluated at the current estimate. `Φ` is sparse: products
    /// with it go block by block.
    fn transition_blocks(&self, dt: f64) -> ([(usize, usize, Matrix3<f64>); 11], usize) {
        let gx = skew(&self.gravity);
        let r = self.rot;
        let dt2 = 0.5 * dt * dt;
        let mut blocks = [(0, 0, Matrix3::zeros()); 11];
        blocks[0] = (VEL, PHI, gx * dt);
        blocks[1] = (POS, VEL, Matrix3::identity() * dt);
        blocks[2] = (POS, PHI, gx * dt2);
        if !self.bias_estimation {
            return (blocks, 3);
        }
        let vx_r = skew(&self.vel) * r;
        blocks[3] = (PHI, BG, -r * dt);
        blocks[4] = (VEL, BG, -vx_r * dt - gx * r * dt2);
        blocks[5] = (VEL, BA, -r * dt);
        blocks[6] = (POS, BG, -skew(&self.pos) * r * dt - vx_r * dt2);
        blocks[7] = (POS, BA, -r * dt2);
        blocks[8] = (FOOT[0], BG, -skew(&self.feet[0]) * r * dt);
        blocks[9] = (FOOT[1], BG, -skew(&self.feet[1]) * r * dt);
        (blocks, 10)
    }

    /// The dense `Φ` (for tests).
    pub fn transition(&self, dt: f64) -> Covariance {
        let (blocks, n) = self.transition_blocks(dt);
        let mut phi = Covariance::identity();
        for (r, c, b) in &blocks[..n] {
            phi.fixed_view_mut::<3, 3>(*r, *c).copy_from(b);
        }
        phi
    }

    /// `P ← Φ P Φᵀ` in place, with `Φ = I + N` given by its 3×3 blocks, on the column-major storage
    /// (`P[(i, j)]` at `j·DIM + i`): `M = P + N P` (block rows), then `M + M Nᵀ` (block columns) on the
    /// upper triangle only, which is then copied onto the lower one (the result is exactly symmetric). Both
    /// passes write the destination rows (columns) in an order that leaves every source row (column)
    /// unchanged until it has been read: the feet's and `p`'s first, then `v`'s (a source of `p`'s), then
    /// `φ`'s (a source of both).
    fn sandwich(blocks: &[(usize, usize, Matrix3<f64>)], p: &mut Covariance) {
        let data = p.as_mut_slice();
        let last = |r: usize| match r {
            PHI => 2,
            VEL => 1,
            _ => 0,
        };
        for pass in 0..3 {
            for &(r, c, ref b) in blocks.iter().filter(|(r, _, _)| last(*r) == pass) {
                for col in data.chunks_exact_mut(DIM) {
                    let x = [col[c], col[c + 1], col[c + 2]];
                    for (k, d) in col[r..r + 3].iter_mut().enumerate() {
                        *d += b[(k, 0)] * x[0] + b[(k, 1)] * x[1] + b[(k, 2)] * x[2];
                    }
                }
            }
        }
        for pass in 0..3 {
            for &(r, c, ref b) in blocks.iter().filter(|(r, _, _)| last(*r) == pass) {
                for k in 0..3 {
                    let j = r + k;
                    let (dst, x0, x1, x2) = column_and_sources(data, j, c);
                    let (b0, b1, b2) = (b[(k, 0)], b[(k, 1)], b[(k, 2)]);
                    for (i, y) in dst.iter_mut().enumerate() {
                        *y += b0 * x0[i];
                        *y += b1 * x1[i];
                        *y += b2 * x2[i];
                    }
                }
            }
        }
        mirror_upper(p);
    }

    fn propagate_covariance(&mut self, dt: f64, stance: [bool; 2], imu_r_sole: &[Matrix3<f64>; 2]) {
        let (blocks, n_blocks) = self.transition_blocks(dt);
        let r = self.rot;
        // Gyro noise enters every group block through Ad_X̂: [R; v×R; p×R; d_l×R; d_r×R].
        let mut g_gyro = SMatrix::<f64, NGYRO, 3>::zeros();
        g_gyro.fixed_view_mut::<3, 3>(PHI, 0).copy_from(&r);
        g_gyro
            .fixed_view_mut::<3, 3>(VEL, 0)
            .copy_from(&(skew(&self.vel) * r));
        g_gyro
            .fixed_view_mut::<3, 3>(POS, 0)
            .copy_from(&(skew(&self.pos) * r));
        for (foot, &row) in FOOT.iter().enumerate() {
            g_gyro
                .fixed_view_mut::<3, 3>(row, 0)
                .copy_from(&(skew(&self.feet[foot]) * r));
        }
        let qg = g_gyro * self.gyro_var * g_gyro.transpose() * dt;
        let p = &mut self.cov;
        {
            let mut group = p.fixed_view_mut::<NGYRO, NGYRO>(0, 0);
            group += qg;
        }
        let mut add = |i: usize, m: Matrix3<f64>| {
            let mut block = p.fixed_view_mut::<3, 3>(i, i);
            block += m * dt;
        };
        add(VEL, r * self.acc_var * r.transpose());
        for foot in 0..2 {
            if stance[foot] {
                let ws = r * imu_r_sole[foot];
                add(FOOT[foot], ws * self.foot_var * ws.transpose());
                let f = self.foot_rot[foot];
                add(FOOT_ROT[foot], f * self.foot_rot_var * f.transpose());
            }
        }
        if self.bias_estimation {
            add(BG, self.gyro_bias_var);
            add(BA, self.acc_bias_var);
        }
        Self::sandwich(&blocks[..n_blocks], &mut self.cov);
    }

    /// Places foot `foot` by kinematics: contact point `d = p + R h` and sole orientation `F = R R_h`, with
    /// `h`, `r_h` the sole position and orientation in the IMU frame; and its error with it: in
    /// right-invariant coordinates the error of `p + R h` is the position error (`ξ_d = ξ_p`) and that of
    /// `R R_h` the orientation error (`ψ = φ`), so the foot's rows and columns of `P` become copies of the
    /// position's and orientation's, plus `kinematics_noise²` and `kinematics_orientation_noise²` on its own
    /// blocks ([Hartley 2020]'s contact augmentation). Used on every sample where the foot is in swing, so
    /// that it touches down where the kinematics put it, with the heading the IMU has then.
    pub fn reset_foot(&mut self, foot: usize, h: &Vector3<f64>, r_h: &Matrix3<f64>) {
        self.feet[foot] = self.pos + self.rot * h;
        self.foot_rot[foot] = self.rot * r_h;
        self.copy_base_error_to_foot(foot);
        self.sole_spin[foot].lift();
    }

    /// Moves the mean of foot `foot`'s contact point by `delta` (world, m), its covariance unchanged: the
    /// contact point redefined as another point of the same foot, known relative to the first
    /// (the estimator's zero-force point of a sunk sole, [`crate::sole_sink`]).
    pub fn shift_contact_point(&mut self, foot: usize, delta: &Vector3<f64>) {
        self.feet[foot] += delta;
    }

    /// Whether the sole of foot `foot` has been found spinning on the floor since its touch-down
    /// ([`SoleSpin`], option `sole_spin_threshold`).
    pub fn sole_spinning(&self, foot: usize) -> bool {
        self.sole_spin[foot].spinning()
    }

    fn copy_base_error_to_foot(&mut self, foot: usize) {
        self.copy_error_block(POS, FOOT[foot], self.kin_var);
        self.copy_error_block(PHI, FOOT_ROT[foot], self.kin_rot_var);
    }

    /// Makes error block `dst` a copy of block `src` (rows and columns; `P[dst, dst] = P[src, src]`), plus
    /// `var` on its diagonal.
    fn copy_error_block(&mut self, src: usize, dst: usize, var: f64) {
        for c in 0..DIM {
            for k in 0..3 {
                let v = self.cov[(src + k, c)];
                self.cov[(dst + k, c)] = v;
            }
        }
        for r in 0..DIM {
            for k in 0..3 {
                let v = self.cov[(r, src + k)];
                self.cov[(r, dst + k)] = v;
            }
        }
        for k in 0..3 {
            self.cov[(dst + k, dst + k)] += var;
        }
    }

    /// Kinematic update with foot `foot` in contact: `h`, `r_h` are the sole position and orientation in the
    /// IMU frame from the encoders.
    ///
    /// - Position [Hartley 2020]: innovation `R̂ h − (d̂ − p̂)`, `H = [0 0 −I … I at d …]` (constant), noise
    ///   `kinematics_noise² I`.
    /// - Orientation (option `foot_orientation`; a flat foot in contact does not rotate, so `Rᵀ F = R_h`):
    ///   innovation `Log(R̂ R_h F̂ᵀ)`, which is `ψ − φ` to first order (`R̂ R_h F̂ᵀ = Exp(−φ) Exp(ψ)`), so
    ///   `H = [−I … I at ψ …]`, constant like the position's; noise `kinematics_orientation_noise² I`.
    ///   As in DILIGENT-KIO [Ramadoss 2021] the sole's orientation is a state with its own uncertainty
    ///   (`ψ`, growing by `contact_foot_angular_velocity_noise` while in contact), so the repeated use of
    ///   one touchdown reference does not make the filter overconfident. A sole found spinning on the
    ///   floor (`sole_spin_threshold`, [`SoleSpin`]) first has `F̂` turned by what the gyroscope and the
    ///   kinematics saw it turn, so the gyroscope carries the heading while it spins.
    ///
    /// By default (`foot_tilt` false) only the heading row of the orientation part is used (the world-z
    /// row of the residual and of `H`): roll and pitch come from gravity, and a sole that rocks on a
    /// compliant contact would pull them. Both parts go in one correction (4 or 6 rows).
    pub fn update_foot(&mut self, foot: usize, h: &Vector3<f64>, r_h: &Matrix3<f64>) -> Result<()> {
        let residual = self.rot * h - (self.feet[foot] - self.pos);
        // Row k of the position part: −e_k at p, +e_k at d.
        let pos_row = |k: usize| [(POS + k, -1.0), (FOOT[foot] + k, 1.0), (0, 0.0)];
        if !self.foot_orientation {
            let noise = Matrix3::identity() * self.kin_var;
            let jac = [0, 1, 2].map(pos_row);
            return self.correct(&jac, &residual, &noise, "foot kinematics");
        }
        // A sole spinning on the floor turns `F̂` by what the gyroscope and the kinematics see (`SoleSpin`).
        let seen = self.gyro_heading + heading(&(self.rot * r_h)) - heading(&self.rot);
        let spin = self.sole_spin[foot].step(seen);
        if spin != 0.0 {
            let (rz, _) = so3_exp_and_jacobian(&Vector3::new(0.0, 0.0, spin));
            self.foot_rot[foot] = rz * self.foot_rot[foot];
        }
        let rot_residual = so3_log(&(self.rot * r_h * self.foot_rot[foot].transpose()));
        let rot_row = |k: usize| [(PHI + k, -1.0), (FOOT_ROT[foot] + k, 1.0), (0, 0.0)];
        if !self.foot_tilt {
            // Heading only: the world-z row of the orientation residual.
            let jac = [pos_row(0), pos_row(1), pos_row(2), rot_row(2)];
            let r4 = SVector::<f64, 4>::new(residual.x, residual.y, residual.z, rot_residual.z);
            let noise = SMatrix::<f64, 4, 4>::from_diagonal(&SVector::<f64, 4>::new(
                self.kin_var,
                self.kin_var,
                self.kin_var,
                self.kin_rot_var,
            ));
            return self.correct(&jac, &r4, &noise, "foot kinematics");
        }
        let jac = [0, 1, 2, 3, 4, 5].map(|k| if k < 3 { pos_row(k) } else { rot_row(k - 3) });
        let mut r6 = SVector::<f64, 6>::zeros();
        let mut noise = SMatrix::<f64, 6, 6>::zeros();
        for k in 0..3 {
            r6[k] = residual[k];
            r6[3 + k] = rot_residual[k];
            noise[(k, k)] = self.kin_var;
            noise[(3 + k, 3 + k)] = self.kin_rot_var;
        }
        self.correct(&jac, &r6, &noise, "foot kinematics")
    }

    /// Flat-ground pseudo-measurement on foot `foot` in contact: its contact point's height is `height`
    /// (σ `sigma`). Linearised at the estimate: `d_z = d̂_z + (φ × d̂)_z + ξ_{d,z}`, so
    /// `H = [d̂_y, −d̂_x, 0 | … | e_zᵀ at d]`. Not invariant (the row depends on `d̂`), but it is what bounds
    /// the height drift the point-contact model leaves unobservable.
    pub fn update_ground_height(&mut self, foot: usize, height: f64, sigma: f64) -> Result<()> {
        let d = self.feet[foot];
        let jac = [[(PHI, d.y), (PHI + 1, -d.x), (FOOT[foot] + 2, 1.0)]];
        let residual = SVector::<f64, 1>::new(height - d.z);
        let noise = SMatrix::<f64, 1, 1>::new(sigma * sigma);
        self.correct(&jac, &residual, &noise, "flat ground")
    }

    /// Sets the accelerometer bias estimate (IMU frame, m/s²), its covariance unchanged: a bias learnt
    /// outside the filter (the estimator's standing window, `level_soles_while_standing`).
    pub fn set_accelerometer_bias(&mut self, acc: &Vector3<f64>) {
        self.acc_bias = *acc;
    }

    /// Level-sole pseudo-measurement on a sole in contact while the robot stands
    /// (`level_soles_while_standing`): the sole's normal in the world, `n = R R_h e_z` (`r_h` its orientation
    /// in the IMU frame from the encoders), is `normal` (the level ground's `e_z`, or that tilted by the
    /// sole's sink under its moments), σ `sigma` per axis. With `R = Exp(φ) R̂`, `n ≈ n̂ + φ × n̂ = n̂ − [n̂]× φ`,
    /// so the x and y rows of the residual `normal − n̂` have `H = −[n̂]×` (rows x, y) on `φ` alone: the IMU's
    /// roll and pitch from the legs' kinematics. Gravity alone cannot tell a tilt `φ` from the accelerometer's
    /// bias across it (`R (ã − b_a) + g` is the same for `φ × g = R δb_a`), so while this holds the tilt,
    /// a still robot's kinematics make that bias observable. Not invariant (the row depends on `R̂`), like
    /// [`Self::update_ground_height`].
    pub fn update_level_sole(
        &mut self,
        r_h: &Matrix3<f64>,
        normal: &Vector3<f64>,
        sigma: f64,
    ) -> Result<()> {
        let n = self.rot * r_h.column(2);
        // −[n̂]× rows x and y: (0, n_z, −n_y) and (−n_z, 0, n_x).
        let jac = [
            [(PHI + 1, n.z), (PHI + 2, -n.y), (PHI, 0.0)],
            [(PHI, -n.z), (PHI + 2, n.x), (PHI + 1, 0.0)],
        ];
        let residual = SVector::<f64, 2>::new(normal.x - n.x, normal.y - n.y);
        let noise = SMatrix::<f64, 2, 2>::identity() * (sigma * sigma);
        self.correct(&jac, &residual, &noise, "level sole")
    }

    /// Kalman correction: `K = P Hᵀ S⁻¹`, `δ = K r`, `X̂ ← Exp(δ) X̂`, `F̂ ← Exp(δ_ψ) F̂`, `b̂ ← b̂ + δ_b`,
    /// `P ← P − K H P`. Fails, changing nothing, if `S = H P Hᵀ + N` is not positive definite.
    ///
    /// `jac` holds `H` by rows, each as at most three `(column, coefficient)` pairs (zero coefficients are
    /// padding). With the Cholesky factor `S = L Lᵀ` and `W = P Hᵀ L⁻ᵀ` (27×M), `K H P = W Wᵀ` and
    /// `δ = W L⁻¹ r`: the covariance update `P ← P − W Wᵀ` is symmetric by construction (bit for bit: each
    /// entry sums the same products in the same order as its mirror), and costs `27² M` multiply-adds.
    fn correct<const M: usize>(
        &mut self,
        jac: &[[(usize, f64); 3]; M],
        residual: &SVector<f64, M>,
        noise: &SMatrix<f64, M, M>,
        what: &'static str,
    ) -> Result<()> {
        // `P Hᵀ` and `S = H P Hᵀ + N` over the nonzeros of `H`.
        let mut pht = SMatrix::<f64, DIM, M>::zeros();
        for (k, row) in jac.iter().enumerate() {
            for &(j, h) in row.iter().filter(|(_, h)| *h != 0.0) {
                pht.column_mut(k).axpy(h, &self.cov.column(j), 1.0);
            }
        }
        let mut s = *noise;
        for (k, row) in jac.iter().enumerate() {
            for &(j, h) in row.iter().filter(|(_, h)| *h != 0.0) {
                for l in 0..M {
                    s[(k, l)] += h * pht[(j, l)];
                }
            }
        }
        let chol = s
            .cholesky()
            .ok_or(EstimatorError::SingularInnovation { what })?;
        let l = chol.l_dirty();
        // Wᵀ = L⁻¹ H P and z = L⁻¹ r (forward substitutions; L is invertible).
        let mut wt = pht.transpose();
        let mut z = *residual;
        if !(l.solve_lower_triangular_mut(&mut wt) && l.solve_lower_triangular_mut(&mut z)) {
            return Err(EstimatorError::SingularInnovation { what });
        }
        let w = wt.transpose();
        let delta = w * z;
        // Upper triangle, column by column, then mirrored.
        let (cov, w) = (self.cov.as_mut_slice(), w.as_slice());
        for (j, col) in cov.chunks_exact_mut(DIM).enumerate() {
            let a: [f64; M] = std::array::from_fn(|k| w[k * DIM + j]);
            let wk: [&[f64]; M] = std::array::from_fn(|k| &w[k * DIM..k * DIM + j + 1]);
            for (i, y) in col[..=j].iter_mut().enumerate() {
                for k in 0..M {
                    *y -= a[k] * wk[k][i];
                }
            }
        }
        mirror_upper(&mut self.cov);
        self.apply(&delta);
        Ok(())
    }

    /// `X̂ ← Exp(δ) X̂` on SE_4(3), `F̂ ← Exp(δ_ψ) F̂` on each SO(3), and the Euclidean bias update.
    fn apply(&mut self, delta: &SVector<f64, DIM>) {
        let phi = delta.fixed_rows::<3>(PHI).into_owned();
        let (r, jl) = so3_exp_and_jacobian(&phi);
        self.rot = renormalize(&(r * self.rot));
        self.vel = r * self.vel + jl * delta.fixed_rows::<3>(VEL);
        self.pos = r * self.pos + jl * delta.fixed_rows::<3>(POS);
        for (foot, &row) in FOOT.iter().enumerate() {
            self.feet[foot] = r * self.feet[foot] + jl * delta.fixed_rows::<3>(row);
        }
        for (foot, &row) in FOOT_ROT.iter().enumerate() {
            let (rf, _) = so3_exp_and_jacobian(&delta.fixed_rows::<3>(row).into_owned());
            // A product of rotations: orthonormal to rounding; `reset_foot` restarts it every swing.
            self.foot_rot[foot] = rf * self.foot_rot[foot];
        }
        if self.bias_estimation {
            self.gyro_bias += delta.fixed_rows::<3>(BG);
            self.acc_bias += delta.fixed_rows::<3>(BA);
        }
    }
}

/// The first `j + 1` entries of column `j` (mutable) and of columns `c`, `c + 1`, `c + 2` (`j` not among
/// them) of a column-major `DIM × DIM` storage.
#[allow(clippy::type_complexity)]
fn column_and_sources(
    data: &mut [f64],
    j: usize,
    c: usize,
) -> (&mut [f64], &[f64], &[f64], &[f64]) {
    let n = j + 1;
    let (dst, src, offset) = if c > j {
        let (a, b) = data.split_at_mut(c * DIM);
        (&mut a[j * DIM..j * DIM + n], &*b, 0)
    } else {
        let (a, b) = data.split_at_mut(j * DIM);
        (&mut b[..n], &*a, c * DIM)
    };
    let x = |l: usize| &src[offset + l * DIM..offset + l * DIM + n];
    (dst, x(0), x(1), x(2))
}

/// Copies the upper triangle of `p` onto its lower one.
fn mirror_upper(p: &mut Covariance) {
    for c in 1..DIM {
        for r in 0..c {
            p[(c, r)] = p[(r, c)];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn random_vec(rng: &mut ChaCha8Rng, scale: f64) -> Vector3<f64> {
        Vector3::from_fn(|_, _| rng.random_range(-scale..scale))
    }

    fn random_rot(rng: &mut ChaCha8Rng) -> Matrix3<f64> {
        so3_exp_and_jacobian(&random_vec(rng, 2.0)).0
    }

    /// A filter at a random state with a random (symmetric positive definite) covariance.
    fn random_filter(rng: &mut ChaCha8Rng) -> InvariantEkf {
        let mut ekf = InvariantEkf::new(&EkfConfig::default(), Vector3::new(0.0, 0.0, -9.81));
        ekf.rot = random_rot(rng);
        ekf.vel = random_vec(rng, 1.0);
        ekf.pos = random_vec(rng, 3.0);
        ekf.feet = [random_vec(rng, 3.0), random_vec(rng, 3.0)];
        ekf.foot_rot = [random_rot(rng), random_rot(rng)];
        let a = Covariance::from_fn(|_, _| rng.random_range(-0.1..0.1));
        ekf.cov = a * a.transpose() + Covariance::identity() * 1e-3;
        ekf
    }

    fn assert_symmetric(p: &Covariance) {
        assert_eq!(*p, p.transpose(), "not exactly symmetric");
    }

    /// `P⁻ = Φ (P + G Q_c Gᵀ dt) Φᵀ` with the dense `Φ` and the dense noise input `G` (27×24: gyroscope,
    /// accelerometer, the feet's linear and angular velocity noise, the bias random walks).
    #[test]
    fn the_structured_propagation_equals_the_dense_textbook_form() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for stance in [[true, true], [true, false], [false, false]] {
            let mut ekf = random_filter(&mut rng);
            let imu_r_sole = [random_rot(&mut rng), random_rot(&mut rng)];
            let dt = 5e-4;
            let mut g = SMatrix::<f64, DIM, 24>::zeros();
            let mut qc = SMatrix::<f64, 24, 24>::zeros();
            let r = ekf.rot;
            let mut put = |row: usize, col: usize, b: Matrix3<f64>, var: &Matrix3<f64>| {
                g.fixed_view_mut::<3, 3>(row, col).copy_from(&b);
                qc.fixed_view_mut::<3, 3>(col, col).copy_from(var);
            };
            put(PHI, 0, r, &ekf.gyro_var);
            put(VEL, 0, skew(&ekf.vel) * r, &ekf.gyro_var);
            put(POS, 0, skew(&ekf.pos) * r, &ekf.gyro_var);
            put(VEL, 3, r, &ekf.acc_var);
            put(BG, 18, Matrix3::identity(), &ekf.gyro_bias_var);
            put(BA, 21, Matrix3::identity(), &ekf.acc_bias_var);
            for foot in 0..2 {
                put(FOOT[foot], 0, skew(&ekf.feet[foot]) * r, &ekf.gyro_var);
                if stance[foot] {
                    put(
                        FOOT[foot],
                        6 + 3 * foot,
                        r * imu_r_sole[foot],
                        &ekf.foot_var,
                    );
                    put(
                        FOOT_ROT[foot],
                        12 + 3 * foot,
                        ekf.foot_rot[foot],
                        &ekf.foot_rot_var,
                    );
                }
            }
            let phi = ekf.transition(dt);
            let expected = phi * (ekf.cov + g * qc * g.transpose() * dt) * phi.transpose();
            ekf.propagate_covariance(dt, stance, &imu_r_sole);
            assert!((ekf.cov - expected).amax() < 1e-14, "{stance:?}");
            assert_symmetric(&ekf.cov);
        }
    }

    /// `K = P Hᵀ (H P Hᵀ + N)⁻¹`, `δ = K r`, `P ← P − K H P` with dense matrices, against [`InvariantEkf::correct`]
    /// on the foot-kinematics (4 and 6 rows) and flat-ground (1 row) Jacobians.
    #[test]
    fn the_factored_correction_equals_the_dense_textbook_form() {
        fn check<const M: usize>(rng: &mut ChaCha8Rng, jac: [[(usize, f64); 3]; M]) {
            let mut ekf = random_filter(rng);
            let residual = SVector::<f64, M>::from_fn(|_, _| rng.random_range(-0.01..0.01));
            let noise = SMatrix::<f64, M, M>::from_diagonal(&SVector::from_fn(|_, _| {
                rng.random_range(1e-6..1e-4)
            }));
            let mut h = SMatrix::<f64, M, DIM>::zeros();
            for (k, row) in jac.iter().enumerate() {
                for &(j, v) in row {
                    h[(k, j)] += v;
                }
            }
            let p = ekf.cov;
            let s = h * p * h.transpose() + noise;
            let k = p * h.transpose() * s.try_inverse().expect("S invertible");
            let p_dense = p - k * h * p;
            let mut dense = ekf.clone();
            dense.apply(&(k * residual));
            ekf.correct(&jac, &residual, &noise, "test")
                .expect("correct");
            assert!((ekf.cov - p_dense).amax() < 1e-14, "M = {M}");
            assert_symmetric(&ekf.cov);
            let (a, b) = (ekf.state(), dense.state());
            assert!((a.rotation - b.rotation).amax() < 1e-14);
            assert!((a.position - b.position).amax() < 1e-14);
            assert!((a.feet[1] - b.feet[1]).amax() < 1e-14);
            assert!((a.foot_rotations[0] - b.foot_rotations[0]).amax() < 1e-14);
            assert!((a.gyro_bias - b.gyro_bias).amax() < 1e-14);
        }
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let pos_row = |k: usize| [(POS + k, -1.0), (FOOT[1] + k, 1.0), (0, 0.0)];
        let rot_row = |k: usize| [(PHI + k, -1.0), (FOOT_ROT[1] + k, 1.0), (0, 0.0)];
        check(&mut rng, [pos_row(0), pos_row(1), pos_row(2), rot_row(2)]);
        check(
            &mut rng,
            [0, 1, 2, 3, 4, 5].map(|k| if k < 3 { pos_row(k) } else { rot_row(k - 3) }),
        );
        check(
            &mut rng,
            [[(PHI, 0.3), (PHI + 1, -1.2), (FOOT[0] + 2, 1.0)]],
        );
    }

    /// Without process noise and bias estimation the error dynamics are the constant, nilpotent group part
    /// (`A³ = 0`), so `Φ(n dt) = Φ(dt)ⁿ` exactly: one covariance step over a pre-integrated interval equals
    /// `n` steps, and the mean moved by `n − 1` samples of [`InvariantEkf::propagate_mean`] and one of
    /// [`InvariantEkf::propagate_over`] is the mean of `n` full propagations bit for bit.
    #[test]
    fn one_step_over_a_preintegrated_interval_equals_the_steps_without_noise() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let config = EkfConfig {
            gyro_noise: [0.0; 3],
            accelerometer_noise: [0.0; 3],
            contact_foot_velocity_noise: [0.0; 3],
            contact_foot_angular_velocity_noise: [0.0; 3],
            bias_estimation: false,
            ..EkfConfig::default()
        };
        let mut stepped = random_filter(&mut rng);
        let fresh = InvariantEkf::new(&config, stepped.gravity);
        stepped.gyro_var = fresh.gyro_var;
        stepped.acc_var = fresh.acc_var;
        stepped.foot_var = fresh.foot_var;
        stepped.foot_rot_var = fresh.foot_rot_var;
        stepped.bias_estimation = false;
        let mut preintegrated = stepped.clone();
        let imu_r_sole = [random_rot(&mut rng), random_rot(&mut rng)];
        let (dt, n) = (5e-4, 4);
        let samples: Vec<_> = (0..n)
            .map(|_| (random_vec(&mut rng, 1.0), random_vec(&mut rng, 10.0)))
            .collect();
        for (gyro, acc) in &samples {
            stepped.propagate(gyro, acc, dt, [true, false], &imu_r_sole);
        }
        for (gyro, acc) in &samples[..n - 1] {
            preintegrated.propagate_mean(gyro, acc, dt);
        }
        let (gyro, acc) = &samples[n - 1];
        let interval = dt * n as f64;
        preintegrated.propagate_over(gyro, acc, dt, interval, [true, false], &imu_r_sole);
        assert_eq!(preintegrated.state(), stepped.state());
        let diff = (preintegrated.cov - stepped.cov).abs().max();
        assert!(
            diff <= 1e-13 * stepped.cov.abs().max(),
            "covariances differ by {diff}"
        );
        assert_symmetric(&preintegrated.cov);
    }

    /// A robot standing still on its left foot, the IMU level at the origin, for `n` samples of 2 ms:
    /// `base_yaw_rate` is what the gyroscope reads about the vertical and `sole_spin_rate` how fast the sole
    /// turns on the floor (both rad/s). Returns the estimated heading and whether the sole was found spinning.
    fn stand_on_a_turning_sole(
        threshold: f64,
        base_yaw_rate: f64,
        sole_spin_rate: f64,
        n: usize,
    ) -> (f64, bool) {
        let config = EkfConfig {
            sole_spin_threshold: threshold,
            ..EkfConfig::default()
        };
        let g = Vector3::new(0.0, 0.0, -9.81);
        let mut ekf = InvariantEkf::new(&config, g);
        let h = [Vector3::new(0.0, 0.1, -0.6), Vector3::new(0.0, -0.1, -0.6)];
        ekf.initialize(
            &config,
            Matrix3::identity(),
            Vector3::zeros(),
            Vector3::new(0.0, 0.0, 0.6),
            [Vector3::new(0.0, 0.1, 0.0), Vector3::new(0.0, -0.1, 0.0)],
            [Matrix3::identity(); 2],
        );
        let rz = |a: f64| so3_exp_and_jacobian(&Vector3::new(0.0, 0.0, a)).0;
        let (gyro, acc, dt) = (Vector3::new(0.0, 0.0, base_yaw_rate), -g, 2e-3);
        for k in 1..=n {
            let t = k as f64 * dt;
            // The sole in the IMU frame: its own turn on the floor less the base's.
            let r_h = [
                rz((sole_spin_rate - base_yaw_rate) * t),
                Matrix3::identity(),
            ];
            let base = rz(base_yaw_rate * t);
            let h_imu = [base.transpose() * h[0], base.transpose() * h[1]];
            ekf.propagate(&gyro, &acc, dt, [true, false], &r_h);
            ekf.update_foot(0, &h_imu[0], &r_h[0]).expect("update");
            ekf.reset_foot(1, &h_imu[1], &r_h[1]);
        }
        (heading(&ekf.state().rotation), ekf.sole_spinning(0))
    }

    /// The sole spin detector on synthetic data (docs/estimation.md, "A stance sole spinning on the
    /// floor"): a sole that turns 0.1 rad in 0.2 s under a still base turns the estimated heading with it
    /// when the sole's heading is held from touch-down (threshold 0), and leaves it within 1 mrad with the
    /// detector on; a base that turns on a still sole is followed in both cases, and the still sole is not
    /// taken for a spinning one.
    #[test]
    fn a_spinning_stance_sole_does_not_turn_the_heading_with_the_detector() {
        let (held, _) = stand_on_a_turning_sole(0.0, 0.0, 0.5, 100);
        assert!(held < -0.05, "held sole heading: estimated heading {held}");
        let (detected, spinning) = stand_on_a_turning_sole(0.005, 0.0, 0.5, 100);
        assert!(spinning);
        assert!(detected.abs() < 1e-3, "estimated heading {detected}");
        for threshold in [0.0, 0.005] {
            let (turned, spinning) = stand_on_a_turning_sole(threshold, 0.5, 0.0, 100);
            assert!(!spinning, "threshold {threshold}");
            assert!(
                (turned - 0.1).abs() < 1e-3,
                "threshold {threshold}: {turned}"
            );
        }
    }

    #[test]
    fn renormalize_gives_the_nearest_rotation() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..100 {
            let r = random_rot(&mut rng);
            // A product of rotations drifts by a few ulps; a perturbation of 1e-12 is far beyond. The two
            // agree to a few ulps (rounding of two different computations).
            let perturbed = r + Matrix3::from_fn(|_, _| rng.random_range(-1e-12..1e-12));
            let nearest = orthonormalize(&perturbed);
            let fast = renormalize(&perturbed);
            assert!(
                (fast - nearest).amax() < 2e-15,
                "{}",
                (fast - nearest).amax()
            );
            assert!((fast.tr_mul(&fast) - Matrix3::identity()).amax() < 1e-15);
        }
    }

    #[test]
    fn the_block_sandwich_equals_the_dense_product() {
        let mut ekf = InvariantEkf::new(&EkfConfig::default(), Vector3::new(0.0, 0.0, -9.81));
        ekf.rot = *nalgebra::Rotation3::from_euler_angles(0.1, -0.2, 0.3).matrix();
        ekf.vel = Vector3::new(0.3, -0.1, 0.05);
        ekf.pos = Vector3::new(1.0, 2.0, 0.6);
        ekf.feet = [Vector3::new(1.1, 2.1, 0.0), Vector3::new(0.9, 1.9, 0.0)];
        let a = Covariance::from_fn(|r, c| ((r * 7 + c * 3) % 11) as f64 * 0.01);
        let p = a * a.transpose() + Covariance::identity();
        let dt = 0.01;
        let (blocks, n) = ekf.transition_blocks(dt);
        let phi = ekf.transition(dt);
        let dense = phi * p * phi.transpose();
        let mut sandwich = p;
        InvariantEkf::sandwich(&blocks[..n], &mut sandwich);
        assert!((sandwich - dense).amax() < 1e-12);
        assert_symmetric(&sandwich);
    }

    #[test]
    fn log_inverts_exp() {
        for phi in [
            Vector3::new(0.3, -0.2, 0.5),
            Vector3::new(1e-7, 2e-7, -1e-7),
            Vector3::new(0.0, 0.0, 3.0),
            Vector3::zeros(),
        ] {
            let (r, _) = so3_exp_and_jacobian(&phi);
            assert!((so3_log(&r) - phi).norm() < 1e-9, "{phi}");
        }
        // A rotation whose trace rounds above 3 still gives a finite, small vector.
        let r = Matrix3::identity() * (1.0 + 1e-15);
        assert!(so3_log(&r).norm() < 1e-12);
    }

    #[test]
    fn exp_and_left_jacobian_match_their_series() {
        let phi = Vector3::new(0.3, -0.2, 0.5);
        let (r, j) = so3_exp_and_jacobian(&phi);
        let expected = nalgebra::Rotation3::from_scaled_axis(phi);
        assert!((r - expected.matrix()).norm() < 1e-12);
        // J_l φ = φ, and J_l = Σ (φ×)^k/(k+1)!.
        assert!((j * phi - phi).norm() < 1e-12);
        let k = skew(&phi);
        let mut series = Matrix3::zeros();
        let mut term = Matrix3::identity();
        let mut fact = 1.0;
        for n in 1..20 {
            fact *= n as f64;
            series += term / fact;
            term *= k;
        }
        assert!((j - series).norm() < 1e-12);
    }
}
