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
/// Size of the group part of the error state.
const NG: usize = 21;

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

/// Re-orthonormalises a rotation matrix: the rotation nearest to `r`, by nalgebra's iteration
/// (`Rotation3::from_matrix_eps`) to machine precision, started from the identity.
fn orthonormalize(r: &Matrix3<f64>) -> Matrix3<f64> {
    orthonormalize_near(r, &Matrix3::identity())
}

/// [`orthonormalize`] started from `guess`, a rotation near `r`: the filter's rotation before an
/// increment, from which the iteration needs fewer steps than from the identity (the same rotation to
/// rounding, not bit for bit; measured, docs/performance.md: 147 → 116 M instructions in a 2 s walk).
fn orthonormalize_near(r: &Matrix3<f64>, guess: &Matrix3<f64>) -> Matrix3<f64> {
    let guess = nalgebra::Rotation3::from_matrix_unchecked(*guess);
    let rot = nalgebra::Rotation3::from_matrix_eps(r, f64::EPSILON, 0, guess);
    *rot.matrix()
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
        let w = gyro - self.gyro_bias;
        let a = acc - self.acc_bias;
        self.propagate_covariance(dt, stance, imu_r_sole);
        let acc_world = self.rot * a + self.gravity;
        let (exp_w, _) = so3_exp_and_jacobian(&(w * dt));
        self.pos += self.vel * dt + acc_world * (0.5 * dt * dt);
        self.vel += acc_world * dt;
        self.rot = orthonormalize_near(&(self.rot * exp_w), &self.rot);
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

    /// `Φ P Φᵀ` with `Φ = I + N` given by its blocks: `M = P + N P`, then `M + M Nᵀ`.
    fn sandwich(blocks: &[(usize, usize, Matrix3<f64>)], p: &Covariance) -> Covariance {
        let mut m = *p;
        for (r, c, b) in blocks {
            let rows = b * p.fixed_view::<3, DIM>(*c, 0);
            let mut dst = m.fixed_view_mut::<3, DIM>(*r, 0);
            dst += rows;
        }
        let mut out = m;
        for (r, c, b) in blocks {
            let cols = m.fixed_view::<DIM, 3>(0, *c) * b.transpose();
            let mut dst = out.fixed_view_mut::<DIM, 3>(0, *r);
            dst += cols;
        }
        out
    }

    fn propagate_covariance(&mut self, dt: f64, stance: [bool; 2], imu_r_sole: &[Matrix3<f64>; 2]) {
        let (blocks, n_blocks) = self.transition_blocks(dt);
        let r = self.rot;
        // Gyro noise enters every group block through Ad_X̂: [R; v×R; p×R; d_l×R; d_r×R].
        let mut g_gyro = SMatrix::<f64, NG, 3>::zeros();
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
        let mut p = self.cov;
        {
            let mut group = p.fixed_view_mut::<NG, NG>(0, 0);
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
        self.cov = Self::sandwich(&blocks[..n_blocks], &p);
        symmetrize(&mut self.cov);
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
    ///   one touchdown reference does not make the filter overconfident.
    ///
    /// By default (`foot_tilt` false) only the heading row of the orientation part is used (the world-z
    /// row of the residual and of `H`): roll and pitch come from gravity, and a sole that rocks on a
    /// compliant contact would pull them. Both parts go in one correction (4 or 6 rows).
    pub fn update_foot(&mut self, foot: usize, h: &Vector3<f64>, r_h: &Matrix3<f64>) -> Result<()> {
        let residual = self.rot * h - (self.feet[foot] - self.pos);
        if !self.foot_orientation {
            let mut jac = SMatrix::<f64, 3, DIM>::zeros();
            for k in 0..3 {
                jac[(k, POS + k)] = -1.0;
                jac[(k, FOOT[foot] + k)] = 1.0;
            }
            let noise = Matrix3::identity() * self.kin_var;
            return self.correct(&jac, &residual, &noise, "foot kinematics");
        }
        let rot_residual = so3_log(&(self.rot * r_h * self.foot_rot[foot].transpose()));
        if !self.foot_tilt {
            // Heading only: the world-z row of the orientation residual.
            let mut jac = SMatrix::<f64, 4, DIM>::zeros();
            let mut r4 = SVector::<f64, 4>::zeros();
            let mut noise = SMatrix::<f64, 4, 4>::zeros();
            for k in 0..3 {
                jac[(k, POS + k)] = -1.0;
                jac[(k, FOOT[foot] + k)] = 1.0;
                r4[k] = residual[k];
                noise[(k, k)] = self.kin_var;
            }
            jac[(3, PHI + 2)] = -1.0;
            jac[(3, FOOT_ROT[foot] + 2)] = 1.0;
            r4[3] = rot_residual.z;
            noise[(3, 3)] = self.kin_rot_var;
            return self.correct(&jac, &r4, &noise, "foot kinematics");
        }
        let mut jac = SMatrix::<f64, 6, DIM>::zeros();
        let mut r6 = SVector::<f64, 6>::zeros();
        let mut noise = SMatrix::<f64, 6, 6>::zeros();
        for k in 0..3 {
            jac[(k, POS + k)] = -1.0;
            jac[(k, FOOT[foot] + k)] = 1.0;
            jac[(3 + k, PHI + k)] = -1.0;
            jac[(3 + k, FOOT_ROT[foot] + k)] = 1.0;
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
        let mut jac = SMatrix::<f64, 1, DIM>::zeros();
        jac[(0, PHI)] = d.y;
        jac[(0, PHI + 1)] = -d.x;
        jac[(0, FOOT[foot] + 2)] = 1.0;
        let residual = SVector::<f64, 1>::new(height - d.z);
        let noise = SMatrix::<f64, 1, 1>::new(sigma * sigma);
        self.correct(&jac, &residual, &noise, "flat ground")
    }

    /// Kalman correction: `K = P Hᵀ S⁻¹`, `δ = K r`, `X̂ ← Exp(δ) X̂`, `F̂ ← Exp(δ_ψ) F̂`, `b̂ ← b̂ + δ_b`, `P ← P − K H P`
    /// (symmetrised). Fails, changing nothing, if `S` is not positive definite.
    fn correct<const M: usize>(
        &mut self,
        jac: &SMatrix<f64, M, DIM>,
        residual: &SVector<f64, M>,
        noise: &SMatrix<f64, M, M>,
        what: &'static str,
    ) -> Result<()> {
        // `P Hᵀ` and `H P Hᵀ` over the nonzeros of `H` (a few ±1 and the flat-ground row's lever arms).
        let mut pht = SMatrix::<f64, DIM, M>::zeros();
        let mut s = *noise;
        for k in 0..M {
            for j in 0..DIM {
                let h = jac[(k, j)];
                if h != 0.0 {
                    pht.column_mut(k).axpy(h, &self.cov.column(j), 1.0);
                }
            }
        }
        for k in 0..M {
            for j in 0..DIM {
                let h = jac[(k, j)];
                if h != 0.0 {
                    for l in 0..M {
                        s[(k, l)] += h * pht[(j, l)];
                    }
                }
            }
        }
        let chol = s
            .cholesky()
            .ok_or(EstimatorError::SingularInnovation { what })?;
        // K = P Hᵀ S⁻¹  ⇔  S Kᵀ = H P.
        let kt = chol.solve(&pht.transpose());
        let delta = kt.transpose() * residual;
        for k in 0..M {
            self.cov
                .ger(-1.0, &kt.row(k).transpose(), &pht.column(k), 1.0);
        }
        symmetrize(&mut self.cov);
        self.apply(&delta);
        Ok(())
    }

    /// `X̂ ← Exp(δ) X̂` on SE_4(3), `F̂ ← Exp(δ_ψ) F̂` on each SO(3), and the Euclidean bias update.
    fn apply(&mut self, delta: &SVector<f64, DIM>) {
        let phi = delta.fixed_rows::<3>(PHI).into_owned();
        let (r, jl) = so3_exp_and_jacobian(&phi);
        self.rot = orthonormalize_near(&(r * self.rot), &self.rot);
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

fn symmetrize(p: &mut Covariance) {
    for r in 0..DIM {
        for c in (r + 1)..DIM {
            let v = 0.5 * (p[(r, c)] + p[(c, r)]);
            p[(r, c)] = v;
            p[(c, r)] = v;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        assert!((InvariantEkf::sandwich(&blocks[..n], &p) - dense).amax() < 1e-12);
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
