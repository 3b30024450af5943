//! Robot-scaled defaults: planner step limits, TSID CoP region and simulated servo gains for a robot of
//! mass `m` whose crouch puts the CoM at height `h`, scaled from the bundled humanoid's hand-tuned values
//! (`configs/robots/stride_humanoid.toml`, `configs/layers/sim_position_servos.toml`, the planner
//! defaults) by dynamic similarity.
//!
//! # The scaling law
//!
//! Walking robots of different size are compared through the inverted pendulum of their CoM: a robot of
//! mass `m` at height `h` topples with the stiffness `m g h` \[N·m/rad\] (gravity torque per radian of
//! tilt) and moves on the time scale `√(h/g)` (Kajita et al. 2001, "The 3D linear inverted pendulum
//! mode"; the Froude number `v²/(g h)` is the same for geometrically similar gaits).
//!
//! - **Servo stiffness** `kp = κ_p · m g h`: a position servo holds the posture against gravity's
//!   toppling torque, so its stiffness must stay the same multiple of `m g h` for the same joint lag
//!   (the bundled humanoid fell with `kp/(m g h) ≈ 6` and walked every scenario at `≈ 58`).
//! - **Servo damping** `kd = κ_d · m h √(g h)`: the same damping ratio `ζ = kd / (2 √(kp I))` of the
//!   pendulum mode, `I = m h²`, gives `kd ∝ √(m g h · m h²) = m h √(g h)`.
//! - **Step length** `s_max ∝ h`, swing height `∝ h`, step durations `∝ √(h/g)` (equal Froude number);
//!   the planner's `feet_distance_max` is `√(s_max² + w²)` with the robot's stance width `w`, and its
//!   `min_width` the same fraction of `w` as the bundled humanoid's.
//! - **CoP region** of the TSID contacts: the same fraction of the sole as the bundled humanoid's.
//!
//! The constants are the bundled humanoid's values over its `m = 32.8 kg`, `h = 0.540 m`, rounded
//! (`κ_p = 60`, `κ_d = 5`): `stride init` on its URDF gives kp 10 400 N·m/rad and kd 204 N·m·s/rad
//! against the hand-tuned 10 000 and 200 (tested in `crates/runner/tests/init.rs`).

/// Reference CoM height of the scaling: the bundled humanoid's crouch \[m\].
pub const REFERENCE_COM_HEIGHT: f64 = 0.54;
/// `kp / (m g h)` of the simulated position servos \[1/rad\].
pub const SERVO_STIFFNESS_RATIO: f64 = 60.0;
/// `kd / (m h √(g h))` of the simulated position servos \[1/rad\].
pub const SERVO_DAMPING_RATIO: f64 = 5.0;
/// Largest forward step at the reference height: the planner defaults' `√(0.22² − 0.15²)` \[m\].
pub const REFERENCE_STEP_LENGTH: f64 = 0.1609;
/// `planner.min_width` over the stance width: the bundled humanoid's 0.14 / 0.15 [-].
pub const MIN_WIDTH_RATIO: f64 = 0.93;
/// Swing apex height at the reference height: the planner default \[m\].
pub const REFERENCE_SWING_HEIGHT: f64 = 0.03;
/// Step durations (min, nominal, max) at the reference height: the planner defaults \[s\].
pub const REFERENCE_STEP_DURATIONS: [f64; 3] = [0.8, 1.0, 1.2];
/// The TSID contacts' CoP region as a fraction of the sole's length and width: the bundled humanoid's
/// 0.12 m × 0.05 m on its 0.20 m × 0.09 m sole [-].
pub const COP_FRACTION: [f64; 2] = [0.6, 0.05 / 0.09];

/// The values `stride init` derives from a robot's mass, crouch and soles.
#[derive(Debug, Clone, PartialEq)]
pub struct Scaled {
    /// `sim.actuation.default.kp` \[N·m/rad\].
    pub servo_kp: f64,
    /// `sim.actuation.default.kd` \[N·m·s/rad\].
    pub servo_kd: f64,
    /// `planner.feet_distance_max` \[m\].
    pub feet_distance_max: f64,
    /// `planner.min_width` \[m\].
    pub min_width: f64,
    /// `planner.swing_height` \[m\].
    pub swing_height: f64,
    /// `planner.step_duration_min`, `_nominal`, `_max` \[s\].
    pub step_durations: [f64; 3],
    /// `wbc.walking.cop_x` half-length and `cop_y` half-width \[m\].
    pub cop_half: [f64; 2],
}

/// The scaled values for mass `mass` \[kg\], CoM height `height` \[m\], gravity `g` \[m/s²\], stance width
/// `width` \[m\] and sole `foot` = (length, width) \[m\] (the law in the module documentation).
pub fn scale(mass: f64, height: f64, g: f64, width: f64, foot: [f64; 2]) -> Scaled {
    let lambda = height / REFERENCE_COM_HEIGHT;
    let step = REFERENCE_STEP_LENGTH * lambda;
    let time = lambda.sqrt();
    Scaled {
        servo_kp: SERVO_STIFFNESS_RATIO * mass * g * height,
        servo_kd: SERVO_DAMPING_RATIO * mass * height * (g * height).sqrt(),
        feet_distance_max: step.hypot(width),
        min_width: MIN_WIDTH_RATIO * width,
        swing_height: REFERENCE_SWING_HEIGHT * lambda,
        step_durations: REFERENCE_STEP_DURATIONS.map(|t| t * time),
        cop_half: [
            0.5 * COP_FRACTION[0] * foot[0],
            0.5 * COP_FRACTION[1] * foot[1],
        ],
    }
}
