//! Configuration of the estimation layer: frames, sensors, the EKF's noise model and priors, the contact
//! detector and the force/torque offset filter.

use serde::{Deserialize, Serialize};

use crate::error::{check_non_negative, check_positive, EstimatorError, Result};

/// The estimator's configuration.
///
/// | field | default | meaning |
/// |---|---|---|
/// | `left_sole`, `right_sole` | `"l_sole"`, `"r_sole"` | sole frames: the contact point of each foot (the EKF's `d_l`, `d_r`) and the point the foot wrenches are reported about |
/// | `imu_frame` | `"imu_frame"` | frame of the IMU whose gyroscope and accelerometer drive the EKF (any link) |
/// | `left_foot_ft_sensor`, `right_foot_ft_sensor` | none | force/torque sensor of each foot; none: the sensor nearest to the sole (at the zero configuration) among those whose child side contains it [Traversaro 2017, §4.5] |
/// | `ekf` | [`EkfConfig`] | noise densities, priors and options of the invariant EKF [Hartley 2020] |
/// | `contact` | [`ContactConfig`] | Schmitt-trigger contact detection on each foot's normal force |
/// | `ft_offsets` | [`FtOffsetConfig`] | model-based offset estimation [Traversaro 2017, §4.7] |
/// | `sole_size` | `[0.20, 0.09]` | \[m\] length and width of the sole rectangles (the bundled humanoid's), for the weight's split between the soles when `ft_offsets.learn_while_standing` > 0 ([`crate::standing_foot_wrenches`]; the runner takes `planner.foot_length`, `foot_width`) |
/// | `ground_stiffness` | 0 | \[N/m³\] stiffness density `k` of the ground under the soles ([`crate::sole_sink`]); 0: a rigid ground. > 0: a stance foot's contact point is its sole's zero-force point, and the kinematics measure it as the sole's position minus its sink `s`, `ṡ = −(f/A + k s)/b` from the foot's estimated force `f` (`A` the area of `sole_size`); the runner sets it from the compliant TSID's ground with `estimation.sole_sink = "controller_ground"` |
/// | `stance_leg_accelerations` | false | true: in the inverse dynamics (foot wrenches, joint torques), a foot in contact's leg gets the six actuated joints' accelerations that keep its sole still under the base's acceleration ([`crate::FlexibleJointObserver`]'s passive hip torques then carry the stance leg's inertia); false: zero joint accelerations |
/// | `passive_joints` | `[]` | joints without a motor (the runner gives TSID-Flex's `flexible_joints`): their acceleration stays zero in that solve |
/// | `ground_damping` | 0 | \[N·s/m³\] damping density `b` of the same ground (0: the sink follows the force at once) |
/// | `joint_velocity_bandwidth` | 0 | \[Hz\] 0: the joint velocities as the encoders report them; > 0: the velocities of a critically damped α–β filter of that bandwidth on the encoder positions ([`crate::JointVelocityFilter`]) |
/// | `ft_calibration` | sensor name → 6 × 6 rows | calibration matrix `C` of each named force/torque sensor: every reading `r` is used as the wrench `C (r − b)` [Traversaro 2017, eq. (5.1)], `b` the offset; sensors not named: identity (`stride calibrate` with added-mass logs writes it) |
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EstimatorConfig {
    /// Left sole frame.
    pub left_sole: String,
    /// Right sole frame.
    pub right_sole: String,
    /// IMU frame.
    pub imu_frame: String,
    /// Force/torque sensor of the left foot (none: chosen from the model).
    pub left_foot_ft_sensor: Option<String>,
    /// Force/torque sensor of the right foot (none: chosen from the model).
    pub right_foot_ft_sensor: Option<String>,
    /// The floating-base EKF.
    pub ekf: EkfConfig,
    /// Contact detection.
    pub contact: ContactConfig,
    /// Force/torque offset estimation.
    pub ft_offsets: FtOffsetConfig,
    /// Calibration matrix `C` (rows) of each named force/torque sensor: the wrench is `C (r − b)`
    /// [Traversaro 2017, eq. (5.1)]; a sensor not named keeps the identity.
    pub ft_calibration: std::collections::BTreeMap<String, [[f64; 6]; 6]>,
    /// Bandwidth \[Hz\] of the joint velocity filter on the encoder positions
    /// ([`crate::JointVelocityFilter`]); 0: the encoders' velocities as read.
    pub joint_velocity_bandwidth: f64,
    /// Stiffness density `k` \[N/m³\] of the ground the soles sink into ([`crate::sole_sink`]); 0: rigid.
    pub ground_stiffness: f64,
    /// Damping density `b` \[N·s/m³\] of that ground.
    pub ground_damping: f64,
    /// Sole rectangle `[length, width]` \[m\] for the standing split of `ft_offsets.learn_while_standing`.
    pub sole_size: [f64; 2],
    /// The inverse dynamics give a foot in contact's leg the joint accelerations that keep its sole still
    /// (`crate::stance_leg`); false: zero joint accelerations.
    pub stance_leg_accelerations: bool,
    /// Joints without a motor (passive springs): their acceleration stays zero in that solve.
    pub passive_joints: Vec<String>,
}

impl Default for EstimatorConfig {
    fn default() -> Self {
        Self {
            left_sole: "l_sole".into(),
            right_sole: "r_sole".into(),
            imu_frame: "imu_frame".into(),
            left_foot_ft_sensor: None,
            right_foot_ft_sensor: None,
            ekf: EkfConfig::default(),
            contact: ContactConfig::default(),
            ft_offsets: FtOffsetConfig::default(),
            ft_calibration: std::collections::BTreeMap::new(),
            joint_velocity_bandwidth: 0.0,
            ground_stiffness: 0.0,
            ground_damping: 0.0,
            sole_size: [0.20, 0.09],
            stance_leg_accelerations: false,
            passive_joints: Vec::new(),
        }
    }
}

impl EstimatorConfig {
    /// Checks the ranges documented on each section.
    pub fn validate(&self) -> Result<()> {
        self.ekf.validate()?;
        self.contact.validate()?;
        self.ft_offsets.validate()?;
        if self.ekf.level_soles_while_standing && self.ft_offsets.learn_while_standing <= 0.0 {
            return Err(EstimatorError::InvalidParameter {
                name: "ekf.level_soles_while_standing",
                value: self.ft_offsets.learn_while_standing,
                reason: "measures the soles level while the robot stands at start-up: needs that window, \
                         ft_offsets.learn_while_standing > 0 (the value)",
            });
        }
        check_non_negative("joint_velocity_bandwidth", self.joint_velocity_bandwidth)?;
        check_positive("sole_size", self.sole_size[0])?;
        check_positive("sole_size", self.sole_size[1])?;
        crate::sole_sink::SoleSink::new(
            self.ground_stiffness,
            self.ground_damping,
            self.sole_size[0] * self.sole_size[1],
        )?;
        for rows in self.ft_calibration.values() {
            if !rows.iter().flatten().all(|v| v.is_finite()) {
                return Err(EstimatorError::InvalidParameter {
                    name: "ft_calibration",
                    value: f64::NAN,
                    reason: "every entry of a calibration matrix must be finite",
                });
            }
        }
        Ok(())
    }
}

/// Noise model, priors and options of the contact-aided invariant EKF [Hartley 2020] in the two-feet form of
/// bipedal-locomotion-framework. Process noises are continuous-time densities (σ² is the entry of `Q_c`;
/// the discrete covariance is `Φ G Q_c Gᵀ Φᵀ dt`, [Hartley 2020]); each `[x, y, z]` is per axis of the named
/// frame.
///
/// | field | unit | default | source |
/// |---|---|---|---|
/// | `gyro_noise` | rad/s/√Hz | `[0.01; 3]` | Hartley's InEKF defaults (an MTi-class gyro is 0.007 °/s/√Hz = 1.2e-4; the default leaves room for vibration and model error) |
/// | `accelerometer_noise` | m/s²/√Hz | `[0.1; 3]` | Hartley's InEKF defaults |
/// | `gyro_bias_noise` | rad/s²/√Hz | `[1e-5; 3]` | Hartley's InEKF defaults (random walk) |
/// | `accelerometer_bias_noise` | m/s³/√Hz | `[1e-4; 3]` | Hartley's InEKF defaults (random walk) |
/// | `contact_foot_velocity_noise` | m/s/√Hz, sole frame | `[9e-3, 9.5e-3, 7e-3]` | bipedal-locomotion-framework, iCub Gazebo InvEKF configuration (stance foot); how much a foot in contact may slip |
/// | `kinematics_noise` | m | 1e-3 | σ of the sole position measured by forward kinematics, isotropic (bipedal-locomotion-framework's `forward_kinematic_measurement_noise_std_dev`); stands for `R J Σ_enc Jᵀ Rᵀ` [Hartley 2020] |
/// | `foot_orientation` | – | true | measure the sole orientation of a foot in contact against its (estimated) world orientation, which stays put while the foot is down [Ramadoss 2021]: makes the yaw and the gyro's yaw bias observable in contact |
/// | `foot_tilt` | – | false | measure the sole's roll and pitch too, not only its heading. Off: roll and pitch are observable from gravity already, and a sole that rocks on its compliant contact or peels off before the break is detected pulls the IMU tilt with it (walk_straight: tilt error 0.44° RMS with it, 0.18° without; walk_straight_torque falls with it) |
/// | `contact_foot_angular_velocity_noise` | rad/s/√Hz, sole frame | `[7e-3, 7.5e-3, 4e-3]` | how much a sole in contact may turn (rocking on a compliant sole, yaw slip); bipedal-locomotion-framework's `contact_foot_angular_velocity_noise_std_dev` (iCub Gazebo) |
/// | `kinematics_orientation_noise` | rad | 1e-3 | σ of the sole orientation measured by forward kinematics, isotropic: six joints in series, each quantised by a 12-bit encoder (1.5e-3 rad steps, σ = 1.5e-3/√12 = 4.4e-4 rad), give √6 × 4.4e-4 ≈ 1.1e-3 rad (bipedal-locomotion-framework uses 1e-6 rad, i.e. exact kinematics) |
/// | `sole_spin_threshold` | rad | 0 | a sole in contact whose heading, as the gyroscope and the kinematics see it, has turned by more than this since touch-down is spinning on the floor: until it lifts, its estimated orientation turns with what they see, so the gyroscope carries the heading ([`crate::sole_spin::SoleSpin`]); 0 = off (the sole's heading is held from touch-down) |
/// | `flat_ground` | – | true | a foot in contact is at the ground height (the soles' height in the initial state): a pseudo-measurement of the contact point's z that bounds the height drift |
/// | `ground_height_noise` | m | 2e-3 | σ of that pseudo-measurement (floor unevenness, sole compliance) |
/// | `bias_estimation` | – | true | estimate the gyro and accelerometer biases (false: they stay at `initial_*_bias`) |
/// | `level_soles_while_standing` | – | false | while the robot stands on both feet at start-up (the window of `ft_offsets.learn_while_standing`, which must be > 0), its soles are taken level: the legs' kinematics give the IMU's tilt, and the accelerometer's bias (across gravity a tilt to the filter, unobservable otherwise) is learnt as the mean of its reading less a still IMU's and set as the filter's estimate (docs/estimation.md, "The IMU's biases learnt while standing") |
/// | `level_soles_noise` | rad | 0 | > 0: each sole in contact is also measured level by the filter over that window, σ this per axis ([`crate::InvariantEkf::update_level_sole`]); 0: not (on soft ground the pseudo-measurement closes a loop through the controller's ankles and the soles' rocking: docs/soft-ground.md) |
/// | `initial_gyro_bias` | rad/s | `[0; 3]` | IMU frame |
/// | `initial_accelerometer_bias` | m/s² | `[0; 3]` | IMU frame |
/// | `prior` | | [`EkfPrior`] | σ's of the initial state |
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EkfConfig {
    /// Gyroscope white-noise density \[rad/s/√Hz\], IMU axes.
    pub gyro_noise: [f64; 3],
    /// Accelerometer white-noise density \[m/s²/√Hz\], IMU axes.
    pub accelerometer_noise: [f64; 3],
    /// Gyroscope bias random-walk density \[rad/s²/√Hz\].
    pub gyro_bias_noise: [f64; 3],
    /// Accelerometer bias random-walk density \[m/s³/√Hz\].
    pub accelerometer_bias_noise: [f64; 3],
    /// Velocity noise density of a foot in contact \[m/s/√Hz\], sole axes.
    pub contact_foot_velocity_noise: [f64; 3],
    /// σ of a sole position from forward kinematics \[m\].
    pub kinematics_noise: f64,
    /// Use the sole-orientation measurement on feet in contact.
    pub foot_orientation: bool,
    /// Measure the sole's roll and pitch too (false: its heading only).
    pub foot_tilt: bool,
    /// Angular-velocity noise density of a foot in contact \[rad/s/√Hz\], sole axes.
    pub contact_foot_angular_velocity_noise: [f64; 3],
    /// σ of a sole orientation from forward kinematics \[rad\].
    pub kinematics_orientation_noise: f64,
    /// Turn from touch-down past which a stance sole is spinning \[rad\] (0: off).
    pub sole_spin_threshold: f64,
    /// Use the flat-ground pseudo-measurement on feet in contact.
    pub flat_ground: bool,
    /// σ of the flat-ground pseudo-measurement \[m\].
    pub ground_height_noise: f64,
    /// Estimate the IMU biases.
    pub bias_estimation: bool,
    /// Learn the accelerometer's bias with the soles taken level while the robot stands at start-up (the
    /// window of `ft_offsets.learn_while_standing`).
    pub level_soles_while_standing: bool,
    /// σ of the level-sole pseudo-measurement \[rad\] (0: none).
    pub level_soles_noise: f64,
    /// Initial gyroscope bias \[rad/s\], IMU axes.
    pub initial_gyro_bias: [f64; 3],
    /// Initial accelerometer bias \[m/s²\], IMU axes.
    pub initial_accelerometer_bias: [f64; 3],
    /// Initial uncertainty.
    pub prior: EkfPrior,
}

impl Default for EkfConfig {
    fn default() -> Self {
        Self {
            gyro_noise: [0.01; 3],
            accelerometer_noise: [0.1; 3],
            gyro_bias_noise: [1e-5; 3],
            accelerometer_bias_noise: [1e-4; 3],
            contact_foot_velocity_noise: [9e-3, 9.5e-3, 7e-3],
            kinematics_noise: 1e-3,
            foot_orientation: true,
            foot_tilt: false,
            contact_foot_angular_velocity_noise: [7e-3, 7.5e-3, 4e-3],
            kinematics_orientation_noise: 1e-3,
            sole_spin_threshold: 0.0,
            flat_ground: true,
            ground_height_noise: 2e-3,
            bias_estimation: true,
            level_soles_while_standing: false,
            level_soles_noise: 0.0,
            initial_gyro_bias: [0.0; 3],
            initial_accelerometer_bias: [0.0; 3],
            prior: EkfPrior::default(),
        }
    }
}

impl EkfConfig {
    /// Checks that every σ is finite and non-negative, the measurement σ's positive.
    pub fn validate(&self) -> Result<()> {
        let triples: [(&'static str, &[f64; 3]); 6] = [
            ("ekf.gyro_noise", &self.gyro_noise),
            ("ekf.accelerometer_noise", &self.accelerometer_noise),
            ("ekf.gyro_bias_noise", &self.gyro_bias_noise),
            (
                "ekf.accelerometer_bias_noise",
                &self.accelerometer_bias_noise,
            ),
            (
                "ekf.contact_foot_velocity_noise",
                &self.contact_foot_velocity_noise,
            ),
            (
                "ekf.contact_foot_angular_velocity_noise",
                &self.contact_foot_angular_velocity_noise,
            ),
        ];
        for (name, values) in triples {
            for &v in values {
                check_non_negative(name, v)?;
            }
        }
        for (name, values) in [
            ("ekf.initial_gyro_bias", &self.initial_gyro_bias),
            (
                "ekf.initial_accelerometer_bias",
                &self.initial_accelerometer_bias,
            ),
        ] {
            for &v in values {
                if !v.is_finite() {
                    return Err(EstimatorError::InvalidParameter {
                        name,
                        value: v,
                        reason: "must be finite",
                    });
                }
            }
        }
        check_positive("ekf.kinematics_noise", self.kinematics_noise)?;
        check_positive(
            "ekf.kinematics_orientation_noise",
            self.kinematics_orientation_noise,
        )?;
        check_positive("ekf.ground_height_noise", self.ground_height_noise)?;
        check_non_negative("ekf.level_soles_noise", self.level_soles_noise)?;
        check_non_negative("ekf.sole_spin_threshold", self.sole_spin_threshold)?;
        self.prior.validate()
    }
}

/// σ's of the EKF's initial state. The world frame is defined by the initial pose the caller gives
/// ([`crate::Estimator::set_initial_state`]), so position and yaw start nearly certain; roll and pitch
/// allow for an initial pose that is slightly off the IMU's gravity direction.
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `orientation` | rad | `[0.0175, 0.0175, 0.0175]` | roll, pitch, yaw of the IMU (1°; bipedal-locomotion-framework's example uses 0.175 rad for roll and pitch when the pose is not given) |
/// | `velocity` | m/s | 0.05 | IMU velocity (the robot stands still) |
/// | `position` | m | 0.001 | IMU position; the feet get it plus `kinematics_noise` |
/// | `gyro_bias` | rad/s | 0.01 | per axis |
/// | `accelerometer_bias` | m/s² | 0.1 | per axis |
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EkfPrior {
    /// Roll, pitch, yaw σ \[rad\] (world axes).
    pub orientation: [f64; 3],
    /// Velocity σ \[m/s\].
    pub velocity: f64,
    /// Position σ \[m\].
    pub position: f64,
    /// Gyroscope bias σ \[rad/s\].
    pub gyro_bias: f64,
    /// Accelerometer bias σ \[m/s²\].
    pub accelerometer_bias: f64,
}

impl Default for EkfPrior {
    fn default() -> Self {
        Self {
            orientation: [0.0175; 3],
            velocity: 0.05,
            position: 1e-3,
            gyro_bias: 0.01,
            accelerometer_bias: 0.1,
        }
    }
}

impl EkfPrior {
    /// Checks that every σ is finite and non-negative.
    pub fn validate(&self) -> Result<()> {
        for &v in &self.orientation {
            check_non_negative("ekf.prior.orientation", v)?;
        }
        check_non_negative("ekf.prior.velocity", self.velocity)?;
        check_non_negative("ekf.prior.position", self.position)?;
        check_non_negative("ekf.prior.gyro_bias", self.gyro_bias)?;
        check_non_negative("ekf.prior.accelerometer_bias", self.accelerometer_bias)
    }
}

/// Contact detection: one Schmitt trigger per foot on the normal force the ground applies on it (the z
/// component of the estimated foot wrench, world). Semantics in [`crate::SchmittTrigger`]: a level must hold
/// continuously for its delay (the timer restarts when the force re-crosses the threshold).
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `thresholds_in_body_weight` | – | true | thresholds are fractions of the robot's weight `m g` (else newtons) |
/// | `make_threshold` | BW or N | 0.3 | a foot makes contact when its normal force stays ≥ this |
/// | `break_threshold` | BW or N | 0.1 | a foot breaks contact when its normal force stays ≤ this |
/// | `make_delay` | s | 0.02 | for this long |
/// | `break_delay` | s | 0.01 | for this long |
///
/// Sources: bipedal-locomotion-framework's InvEKF device on iCub in Gazebo uses make ≈ 52 % BW / 0.05 s,
/// break ≈ 23 % BW / 0.02 s; whole-body-estimators on the real iCub 40–46 % BW / 8 % BW with 0.5 s delays,
/// which suits balancing, not walking. With 0.8–1 s steps the make delay must be shorter than the shortest
/// double support and the break delay than a single support; a late break is worse for the EKF than a late
/// make (a lifted foot taken as fixed drags the estimate), hence the shorter break delay. 10 % BW (32 N on
/// the bundled robot) is well above a foot sensor's noise.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ContactConfig {
    /// Thresholds as fractions of the body weight (true) or in newtons (false).
    pub thresholds_in_body_weight: bool,
    /// Make threshold.
    pub make_threshold: f64,
    /// Break threshold (< make threshold).
    pub break_threshold: f64,
    /// Make delay \[s\].
    pub make_delay: f64,
    /// Break delay \[s\].
    pub break_delay: f64,
}

impl Default for ContactConfig {
    fn default() -> Self {
        Self {
            thresholds_in_body_weight: true,
            make_threshold: 0.3,
            break_threshold: 0.1,
            make_delay: 0.02,
            break_delay: 0.01,
        }
    }
}

impl ContactConfig {
    /// Checks finite, non-negative values and break < make.
    pub fn validate(&self) -> Result<()> {
        check_non_negative("contact.make_threshold", self.make_threshold)?;
        check_non_negative("contact.break_threshold", self.break_threshold)?;
        check_non_negative("contact.make_delay", self.make_delay)?;
        check_non_negative("contact.break_delay", self.break_delay)?;
        if self.break_threshold >= self.make_threshold {
            return Err(EstimatorError::InvalidParameter {
                name: "contact.break_threshold",
                value: self.break_threshold,
                reason: "must be below contact.make_threshold (hysteresis)",
            });
        }
        Ok(())
    }

    /// `(make, break)` thresholds in newtons for a robot of weight `weight` \[N\].
    pub fn thresholds_newton(&self, weight: f64) -> (f64, f64) {
        if self.thresholds_in_body_weight {
            (self.make_threshold * weight, self.break_threshold * weight)
        } else {
            (self.make_threshold, self.break_threshold)
        }
    }
}

/// Model-based force/torque offset estimation [Traversaro 2017, §4.7]: on a sample where the child side of
/// a sensor carries no external wrench (every foot on that side detected in swing for at least
/// `min_swing_time`, and its estimated normal force below the break threshold), the reading minus the
/// model's prediction is an offset sample; a first-order filter with time constant `time_constant` averages
/// the samples. Sensors with no foot on their child side are estimated on every sample (no other contact is
/// assumed).
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `enabled` | – | true | estimate offsets (false: keep `initial`) |
/// | `time_constant` | s | 5.0 | filter time constant (offsets drift over hours with temperature; a 0.4 s swing moves the estimate 8 % of the way) |
/// | `min_swing_time` | s | 0.1 | samples are used only after the foot has been in swing this long (skips the lift-off transient) |
/// | `initial` | N, N·m | zeros | offsets before any sample, [`stride_model::Model::ft_sensors`] order (empty: zeros); e.g. from a calibration with the robot hung, or the last session |
/// | `learn_while_standing` | s | 0 | > 0: for this long from the first tick the robot is taken to stand still on both feet, and every sensor's offset is the mean of its reading minus the model's prediction with the weight split between the soles ([`crate::standing_foot_wrenches`]); the offsets apply from the first sample on (0: off) |
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FtOffsetConfig {
    /// Estimate the offsets.
    pub enabled: bool,
    /// Filter time constant \[s\].
    pub time_constant: f64,
    /// Minimum time in swing before a sample is used \[s\].
    pub min_swing_time: f64,
    /// Initial offsets `[f; τ]` per sensor (empty: zeros).
    pub initial: Vec<[f64; 6]>,
    /// Learn the offsets while standing for this long from the first tick \[s\] (0: off).
    pub learn_while_standing: f64,
}

impl Default for FtOffsetConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            time_constant: 5.0,
            min_swing_time: 0.1,
            initial: Vec::new(),
            learn_while_standing: 0.0,
        }
    }
}

impl FtOffsetConfig {
    /// Checks the ranges.
    pub fn validate(&self) -> Result<()> {
        check_positive("ft_offsets.time_constant", self.time_constant)?;
        check_non_negative("ft_offsets.min_swing_time", self.min_swing_time)?;
        check_non_negative("ft_offsets.learn_while_standing", self.learn_while_standing)?;
        for w in &self.initial {
            for &v in w {
                if !v.is_finite() {
                    return Err(EstimatorError::InvalidParameter {
                        name: "ft_offsets.initial",
                        value: v,
                        reason: "must be finite",
                    });
                }
            }
        }
        Ok(())
    }
}
