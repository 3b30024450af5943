//! The estimation block: one tick runs kinematics, the EKF prediction, foot wrenches from the force/torque
//! sensors, contact detection, the EKF update, offset estimation and joint torques.

use std::sync::Arc;

use nalgebra::{
    DVector, Isometry3, Matrix3, Matrix6, Rotation3, Translation3, UnitQuaternion, Vector3, Vector6,
};
use stride_block::Block;
use stride_model::{ExternalWrench, FrameId, KinDyn, Model, RobotState, VelocityRepresentation};

use crate::config::EstimatorConfig;
use crate::ekf::{EkfState, InvariantEkf};
use crate::error::{check_positive, EstimatorError, Result};
use crate::io::{EstimatorInput, EstimatorOutput};
use crate::joint_velocity::JointVelocityFilter;
use crate::schmitt::SchmittTrigger;
use crate::sole_sink::SoleSink;
use crate::stance_leg::StanceLegs;
use crate::standing::{standing_foot_wrenches, StandingOffsets};

/// The estimation layer.
///
/// One tick ([`Block::step`]; every sample, also a pre-integrated one, first steps the joint velocity
/// filter when `joint_velocity_bandwidth` > 0, whose velocities then replace the encoders' below):
/// 1. forward kinematics from the encoders: each sole's position and orientation in the IMU frame, `imu_H_base`
///    (one pass per step when the IMU frame is on the base link, the robot placed at the predicted mean;
///    two otherwise: relative to the base, then at the predicted state);
/// 2. EKF propagation with the raw gyroscope and accelerometer ([`InvariantEkf::propagate`]; the IMU's
///    on-board orientation is not used);
/// 3. the predicted robot state (base pose and mixed twist from the propagated EKF, joints as measured)
///    and its acceleration: base linear acceleration from the accelerometer, `R (ã − b_a) + g`, moved from
///    the IMU to the base origin with the centripetal term; base angular acceleration and joint
///    accelerations **zero** (a foot wrench estimate is then off by the unmodelled inertial wrench of the
///    links between its sensor and the sole: 0.7 kg of foot on the bundled robot);
/// 4. foot wrenches `w = A⁻¹ (y − o − y₀)` [Traversaro 2017, eq. 4.21]: `y` the reading of the foot's
///    sensor, `o` its offset, `y₀` the reading the model predicts with no external wrench, `A` the map from
///    a wrench on the sole (world orientation, about the sole origin) to the reading;
/// 5. contact detection: a [`SchmittTrigger`] per foot on the normal force `w_z`;
/// 6. EKF: feet in swing are placed by kinematics (position and sole orientation), feet in contact update
///    the filter with their kinematics (position and, option, sole orientation) and (option) the
///    flat-ground pseudo-measurement; while the robot stands at start-up on both feet
///    (`ekf.level_soles_while_standing`), both soles are measured level
///    ([`InvariantEkf::update_level_sole`]);
/// 7. offsets: on a sensor whose child side carries no contact, `y − y₀` is an offset sample
///    [Traversaro 2017, §4.7], averaged by a first-order filter;
/// 8. joint torques by inverse dynamics with the estimated foot wrenches acting on the soles (both feet,
///    in swing too: there it is what the sensor attributes to the sole, ≈ 0) [Traversaro 2017, §4.6];
/// 9. the output: base pose `world_H_imu · imu_H_base` and the base's mixed twist from the corrected EKF.
///
/// Steps 3–5 and 8 use the state predicted at step 2 (before the update of step 6): the difference is one
/// tick's correction. A step that fails on its input (size, non-finite value, time, not initialised)
/// changes nothing: inputs are checked first. After the checks only
/// [`EstimatorError::SingularInnovation`] can occur (a degenerate covariance, e.g. every σ zero); the
/// filter has then been propagated but not updated.
#[derive(Debug)]
pub struct Estimator {
    model: Arc<Model>,
    config: EstimatorConfig,
    period: f64,
    kd: KinDyn,
    ekf: InvariantEkf,
    triggers: [SchmittTrigger; 2],
    soles: [FrameId; 2],
    imu: FrameId,
    base: FrameId,
    /// `imu_H_base` when the IMU frame is on the base link (constant; one kinematics pass per step).
    imu_on_base: Option<Isometry3<f64>>,
    foot_sensors: [usize; 2],
    /// For each sensor, which soles lie on its child side.
    sensor_feet: Vec<[bool; 2]>,
    wrench_maps: [Matrix6<f64>; 2],
    initial_offsets: Vec<Vector6<f64>>,
    /// Per sensor, its calibration matrix `C` and `C⁻¹` from `ft_calibration` (`None`: identity).
    calibration: Vec<Option<Calibration>>,
    predicted: Vec<Vector6<f64>>,
    nu_dot: DVector<f64>,
    /// `stance_leg_accelerations`: the legs' chains for the stance feet's joint accelerations in `nu_dot`.
    stance_legs: Option<StanceLegs>,
    generalized: DVector<f64>,
    scratch: RobotState,
    swing_since_ns: [Option<u64>; 2],
    ground_height: f64,
    /// The ground the soles sink into (`ground_stiffness`, `ground_damping`; rigid by default).
    sole_sink: SoleSink,
    /// Each sole's sink \[m\], world: its origin's displacement from its zero-force point, the EKF's
    /// contact point ([`crate::sole_sink`]); `None` until the first tick has measured the standing load.
    sinks: Option<[Vector3<f64>; 2]>,
    thresholds: (f64, f64),
    last_time_ns: Option<u64>,
    /// Time \[s\] pre-integrated since the last full tick ([`Estimator::preintegrate`]).
    preintegrated: f64,
    initialized: bool,
    /// The joint velocity filter (`joint_velocity_bandwidth` > 0), stepped on every sample.
    joint_velocity: Option<JointVelocityFilter>,
    /// The offsets learnt while standing (`ft_offsets.learn_while_standing` > 0), until that time is over.
    standing: Option<StandingOffsets>,
    output: EstimatorOutput,
}

/// Kinematics of one tick, relative to the base (base at the identity, zero base velocity).
#[derive(Debug, Clone, Copy)]
struct RelativeKinematics {
    imu_h_sole: [Isometry3<f64>; 2],
    imu_h_base: Isometry3<f64>,
    /// Velocity of the IMU due to the joints alone, `[ṗ; ω]`, base orientation.
    imu_velocity_from_joints: Vector6<f64>,
}

impl Estimator {
    /// Builds the estimator (allocates everything). `period` is the nominal sampling period (used for the
    /// first sample; later samples use the difference of their time stamps).
    ///
    /// # Errors
    /// An invalid configuration, an unknown frame or sensor, a foot no sensor measures.
    pub fn new(
        model: Arc<Model>,
        config: &EstimatorConfig,
        period: std::time::Duration,
    ) -> Result<Self> {
        config.validate()?;
        let period = period.as_secs_f64();
        check_positive("period", period)?;
        let frame = |key: &'static str, name: &str| {
            model.frame_id(name).ok_or(EstimatorError::UnknownFrame {
                key,
                name: name.to_string(),
            })
        };
        let soles = [
            frame("left_sole", &config.left_sole)?,
            frame("right_sole", &config.right_sole)?,
        ];
        let imu = frame("imu_frame", &config.imu_frame)?;
        let base = frame("root link", model.root_link())?;
        let mut kd = KinDyn::new(Arc::clone(&model));
        kd.set_representation(VelocityRepresentation::Mixed);
        // At the zero state (base at the identity) as in `relative_kinematics`, so bit for bit the same.
        let imu_on_base = (model.frames()[imu.index()].link == model.frames()[base.index()].link)
            .then(|| kd.relative_transform(imu, base));
        let n_ft = model.ft_sensors().len();
        let mut sensor_feet = vec![[false; 2]; n_ft];
        let mut map = Matrix6::zeros();
        for (s, feet) in sensor_feet.iter_mut().enumerate() {
            for foot in 0..2 {
                kd.ft_sensor_wrench_map(s, soles[foot], &mut map)?;
                feet[foot] = map.abs().max() > 0.0;
            }
        }
        let names = [&config.left_foot_ft_sensor, &config.right_foot_ft_sensor];
        let keys = ["left_foot_ft_sensor", "right_foot_ft_sensor"];
        let mut foot_sensors = [0; 2];
        for foot in 0..2 {
            foot_sensors[foot] = choose_foot_sensor(
                &model,
                &kd,
                &sensor_feet,
                soles[foot],
                foot,
                names[foot],
                keys[foot],
            )?;
        }
        if !config.ft_offsets.initial.is_empty() && config.ft_offsets.initial.len() != n_ft {
            return Err(EstimatorError::InvalidParameter {
                name: "ft_offsets.initial",
                value: config.ft_offsets.initial.len() as f64,
                reason: "must be empty or have one entry per force/torque sensor of the model",
            });
        }
        let initial_offsets = if config.ft_offsets.initial.is_empty() {
            vec![Vector6::zeros(); n_ft]
        } else {
            config
                .ft_offsets
                .initial
                .iter()
                .map(|o| Vector6::from(*o))
                .collect()
        };
        let calibration = calibration_matrices(&model, config)?;
        let weight = model.total_mass() * model.gravity().norm();
        let thresholds = config.contact.thresholds_newton(weight);
        let trigger = SchmittTrigger::new(
            thresholds.0,
            thresholds.1,
            config.contact.make_delay,
            config.contact.break_delay,
            true,
        );
        let mut output = EstimatorOutput::new(&model);
        output.ft_offsets.clone_from(&initial_offsets);
        Ok(Self {
            ekf: InvariantEkf::new(&config.ekf, model.gravity()),
            config: config.clone(),
            period,
            triggers: [trigger.clone(), trigger],
            soles,
            imu,
            base,
            imu_on_base,
            foot_sensors,
            sensor_feet,
            wrench_maps: [Matrix6::zeros(); 2],
            initial_offsets,
            calibration,
            predicted: vec![Vector6::zeros(); n_ft],
            nu_dot: DVector::zeros(model.nv()),
            stance_legs: match config.stance_leg_accelerations {
                true => Some(StanceLegs::new(&model, soles, &config.passive_joints)?),
                false => None,
            },
            generalized: DVector::zeros(model.nv()),
            scratch: RobotState::zero(&model),
            swing_since_ns: [None; 2],
            ground_height: 0.0,
            sole_sink: SoleSink::new(
                config.ground_stiffness,
                config.ground_damping,
                config.sole_size[0] * config.sole_size[1],
            )?,
            sinks: None,
            thresholds,
            last_time_ns: None,
            preintegrated: 0.0,
            initialized: false,
            joint_velocity: match config.joint_velocity_bandwidth {
                b if b > 0.0 => Some(JointVelocityFilter::new(model.dof(), b)?),
                _ => None,
            },
            standing: (config.ft_offsets.learn_while_standing > 0.0).then(|| {
                StandingOffsets::new(config.ft_offsets.learn_while_standing, n_ft, model.nv())
            }),
            output,
            kd,
            model,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &EstimatorConfig {
        &self.config
    }

    /// The filter (state, covariance).
    pub fn ekf(&self) -> &InvariantEkf {
        &self.ekf
    }

    /// Indices (into [`Model::ft_sensors`]) of the left and right foot sensors.
    pub fn foot_sensors(&self) -> [usize; 2] {
        self.foot_sensors
    }

    /// The ground height used by the flat-ground pseudo-measurement \[m\] (the soles' mean height in the
    /// initial state).
    pub fn ground_height(&self) -> f64 {
        self.ground_height
    }

    /// The last output.
    pub fn output(&self) -> &EstimatorOutput {
        &self.output
    }

    /// Starts the estimate from a known state of the robot standing still on both feet: `state.base_pose`
    /// defines the world frame (its base velocity is ignored and taken as zero), both feet are in contact,
    /// the ground is at the soles' mean height, the offsets are `ft_offsets.initial`.
    ///
    /// # Errors
    /// A state that does not fit the model.
    pub fn set_initial_state(&mut self, state: &RobotState) -> Result<()> {
        self.scratch.copy_from(state);
        self.scratch.base_velocity = Vector6::zeros();
        self.kd.set_state(&self.scratch)?;
        let (r_imu, p_imu) = self.kd.frame_rotation_translation(self.imu);
        let soles = self.soles.map(|s| self.kd.frame_rotation_translation(s));
        let feet = soles.map(|(_, p)| p);
        let foot_rotations = soles.map(|(r, _)| r);
        self.ekf.initialize(
            &self.config.ekf,
            r_imu,
            Vector3::zeros(),
            p_imu,
            feet,
            foot_rotations,
        );
        self.ground_height = 0.5 * (feet[0].z + feet[1].z);
        self.sinks = None;
        for t in &mut self.triggers {
            t.set_state(true, 0);
        }
        self.swing_since_ns = [None; 2];
        self.last_time_ns = None;
        self.preintegrated = 0.0;
        self.initialized = true;
        if let Some(st) = &mut self.standing {
            st.restart();
        }
        let out = &mut self.output;
        out.state.copy_from(&self.scratch);
        out.contacts = [true; 2];
        out.foot_wrenches = [Vector6::zeros(); 2];
        out.joint_torques.fill(0.0);
        for (o, i) in out.ft_offsets.iter_mut().zip(&self.initial_offsets) {
            *o = *i;
        }
        Ok(())
    }

    fn check_input(&self, input: &EstimatorInput) -> Result<f64> {
        if !self.initialized {
            return Err(EstimatorError::NotInitialized);
        }
        let n = self.model.dof();
        let sizes = [
            ("joint_positions", n, input.joint_positions.len()),
            ("joint_velocities", n, input.joint_velocities.len()),
            ("ft_wrenches", self.predicted.len(), input.ft_wrenches.len()),
        ];
        for (name, expected, actual) in sizes {
            if expected != actual {
                return Err(EstimatorError::InputSize {
                    name,
                    expected,
                    actual,
                });
            }
        }
        let finite = [
            (
                "joint_positions",
                input.joint_positions.iter().all(|v| v.is_finite()),
            ),
            (
                "joint_velocities",
                input.joint_velocities.iter().all(|v| v.is_finite()),
            ),
            (
                "imu.angular_velocity",
                input.imu.angular_velocity.iter().all(|v| v.is_finite()),
            ),
            (
                "imu.proper_acceleration",
                input.imu.proper_acceleration.iter().all(|v| v.is_finite()),
            ),
            (
                "ft_wrenches",
                input
                    .ft_wrenches
                    .iter()
                    .all(|w| w.iter().all(|v| v.is_finite())),
            ),
        ];
        for (name, ok) in finite {
            if !ok {
                return Err(EstimatorError::NonFiniteInput { name });
            }
        }
        match self.last_time_ns {
            None => Ok(self.period),
            Some(previous_ns) if input.time_ns > previous_ns => {
                Ok((input.time_ns - previous_ns) as f64 * 1e-9)
            }
            Some(previous_ns) => Err(EstimatorError::NonIncreasingTime {
                time_ns: input.time_ns,
                previous_ns,
            }),
        }
    }

    /// Step 1: kinematics relative to the base.
    fn relative_kinematics(&mut self, input: &EstimatorInput) -> Result<RelativeKinematics> {
        self.set_kinematics(Isometry3::identity(), Vector6::zeros(), input)?;
        Ok(RelativeKinematics {
            imu_h_sole: self.soles.map(|s| self.kd.relative_transform(self.imu, s)),
            imu_h_base: self.kd.relative_transform(self.imu, self.base),
            imu_velocity_from_joints: self.kd.frame_velocity(self.imu),
        })
    }

    /// Base pose, mixed twist and linear acceleration from the EKF's IMU state `s` (steps 3 and 9), with
    /// `imu_H_base` and the IMU's velocity due to the joints from `kin`.
    fn base_from_imu(
        &self,
        s: &EkfState,
        kin: &RelativeKinematics,
        input: &EstimatorInput,
    ) -> (Isometry3<f64>, Vector6<f64>, Vector3<f64>) {
        let world_h_imu = Isometry3::from_parts(
            Translation3::from(s.position),
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(s.rotation)),
        );
        let world_h_base = world_h_imu * kin.imu_h_base;
        let r_base: Matrix3<f64> = *world_h_base.rotation.to_rotation_matrix().matrix();
        let rel = kin.imu_velocity_from_joints;
        // ω = R (ω̃ − b_g), a = R (ã − b_a) + g ([`InvariantEkf::angular_velocity_world`] at state `s`).
        let omega_imu = s.rotation * (input.imu.angular_velocity - s.gyro_bias);
        let omega_base = omega_imu - r_base * rel.fixed_rows::<3>(3);
        let lever = s.position - world_h_base.translation.vector;
        let v_base = s.velocity - r_base * rel.fixed_rows::<3>(0) - omega_base.cross(&lever);
        let a_imu = s.rotation * (input.imu.proper_acceleration - s.accelerometer_bias)
            + self.model.gravity();
        let a_base = a_imu - omega_base.cross(&omega_base.cross(&lever));
        let mut twist = Vector6::zeros();
        twist.fixed_rows_mut::<3>(0).copy_from(&v_base);
        twist.fixed_rows_mut::<3>(3).copy_from(&omega_base);
        (world_h_base, twist, a_base)
    }

    /// Steps 1–3: kinematics, EKF propagation, and the robot placed at the predicted state (`self.kd`,
    /// with `self.nu_dot` its acceleration). Returns the kinematics and the soles' orientations in the IMU
    /// frame.
    ///
    /// With the IMU frame on the base link, one kinematics pass: `imu_H_base` is constant and the joints do
    /// not move the IMU relative to the base, so the base pose and twist follow from the predicted mean
    /// ([`InvariantEkf::predicted_state`], the state [`InvariantEkf::propagate`] then reaches bit for bit),
    /// and the soles relative to the IMU are read from the placed robot (the same to rounding as from a pass
    /// with the base at the identity). Otherwise a first pass relative to the base gives them.
    fn predict(
        &mut self,
        input: &EstimatorInput,
        dt: f64,
        interval: f64,
    ) -> Result<(RelativeKinematics, [Matrix3<f64>; 2])> {
        let imu = &input.imu;
        let (gyro, acc) = (&imu.angular_velocity, &imu.proper_acceleration);
        let kin = match self.imu_on_base {
            Some(imu_h_base) => {
                let mut kin = RelativeKinematics {
                    imu_h_sole: [Isometry3::identity(); 2],
                    imu_h_base,
                    imu_velocity_from_joints: Vector6::zeros(),
                };
                let predicted = self.ekf.predicted_state(gyro, acc, dt);
                self.place_robot(&predicted, &kin, input)?;
                kin.imu_h_sole = self.soles.map(|s| self.kd.relative_transform(self.imu, s));
                kin
            }
            None => self.relative_kinematics(input)?,
        };
        let imu_r_sole = kin
            .imu_h_sole
            .map(|h| *h.rotation.to_rotation_matrix().matrix());
        self.ekf
            .propagate_over(gyro, acc, dt, interval, self.output.contacts, &imu_r_sole);
        if self.imu_on_base.is_none() {
            self.place_robot(&self.ekf.state(), &kin, input)?;
        }
        Ok((kin, imu_r_sole))
    }

    /// Step 3: the robot at EKF state `s` (base pose and mixed twist, joints as measured) in `self.kd`, and
    /// its acceleration in `self.nu_dot`: the base's linear acceleration, and with
    /// `stance_leg_accelerations` the joints of the legs in contact (last tick's) that keep their soles
    /// still ([`crate::stance_leg`]).
    fn place_robot(
        &mut self,
        s: &EkfState,
        kin: &RelativeKinematics,
        input: &EstimatorInput,
    ) -> Result<()> {
        let (pose, twist, acc) = self.base_from_imu(s, kin, input);
        self.set_kinematics(pose, twist, input)?;
        self.nu_dot.fill(0.0);
        self.nu_dot.fixed_rows_mut::<3>(0).copy_from(&acc);
        if let Some(legs) = &mut self.stance_legs {
            for foot in 0..2 {
                if self.output.contacts[foot] {
                    legs.hold_sole(&self.kd, foot, self.soles[foot], &mut self.nu_dot)?;
                }
            }
        }
        Ok(())
    }

    /// `self.kd` at the base `pose` and mixed `twist` with the joints as measured.
    fn set_kinematics(
        &mut self,
        pose: Isometry3<f64>,
        twist: Vector6<f64>,
        input: &EstimatorInput,
    ) -> Result<()> {
        self.scratch.base_pose = pose;
        self.scratch.base_velocity = twist;
        self.scratch
            .joint_positions
            .copy_from(&input.joint_positions);
        self.scratch
            .joint_velocities
            .copy_from(joint_velocities(&self.joint_velocity, input));
        self.kd.set_state(&self.scratch)?;
        Ok(())
    }

    /// Step 4: the predicted readings and the foot wrenches (world orientation, about the soles), with the
    /// robot placed by [`Self::predict`].
    fn foot_wrenches(&mut self, input: &EstimatorInput) -> Result<[Vector6<f64>; 2]> {
        self.kd
            .ft_sensor_wrenches(&self.nu_dot, &[], &mut self.predicted)?;
        let mut wrenches = [Vector6::zeros(); 2];
        for (foot, wrench) in wrenches.iter_mut().enumerate() {
            let s = self.foot_sensors[foot];
            self.kd
                .ft_sensor_wrench_map(s, self.soles[foot], &mut self.wrench_maps[foot])?;
            let raw = input.ft_wrenches[s] - self.output.ft_offsets[s];
            let measured = match &self.calibration[s] {
                Some((c, _)) => c * raw,
                None => raw,
            };
            let rhs = measured - self.predicted[s];
            *wrench = self.wrench_maps[foot].lu().solve(&rhs).ok_or_else(|| {
                EstimatorError::SingularWrenchMap {
                    sensor: self.model.ft_sensors()[s].name.clone(),
                    sole: self.model.frame_name(self.soles[foot]).to_string(),
                }
            })?;
        }
        Ok(wrenches)
    }

    /// Step 7: offsets from the sensors whose child side carries no contact.
    fn update_offsets(&mut self, input: &EstimatorInput, wrenches: &[Vector6<f64>; 2], dt: f64) {
        let cfg = &self.config.ft_offsets;
        if !cfg.enabled {
            return;
        }
        let min_swing_ns = (cfg.min_swing_time * 1e9).round() as u64;
        let free = [0, 1].map(|foot| {
            self.swing_since_ns[foot]
                .is_some_and(|since| input.time_ns.saturating_sub(since) >= min_swing_ns)
                && wrenches[foot].z < self.thresholds.1
        });
        let alpha = dt / (cfg.time_constant + dt);
        for (s, feet) in self.sensor_feet.iter().enumerate() {
            if (feet[0] && !free[0]) || (feet[1] && !free[1]) {
                continue;
            }
            // The offset is in raw units: `b = r − C⁻¹ f` with `f` the predicted wrench (5.1).
            let predicted_raw = match &self.calibration[s] {
                Some((_, c_inv)) => c_inv * self.predicted[s],
                None => self.predicted[s],
            };
            let sample = input.ft_wrenches[s] - predicted_raw;
            let o = &mut self.output.ft_offsets[s];
            *o += (sample - *o) * alpha;
        }
    }

    /// Step 7b (`ft_offsets.learn_while_standing`): while the robot stands still on both feet, each sensor's
    /// offset is the mean of its reading minus the model's prediction with the weight split between the soles
    /// by [`standing_foot_wrenches`] (static: the force is the weight `−m g`, no moment about the CoM, no
    /// acceleration). Runs after the joint torques (its sensor pass would replace the one they read). The
    /// running mean is the offset from the first sample on.
    ///
    /// The prediction is the standing robot's, `ν̇ = 0`: with the estimated base acceleration in the force
    /// (and nothing of the joints' accelerations nor of the angular momentum rate, which the split takes as
    /// zero) a robot that moves while it learns had each sample's prediction swing with the accelerometer,
    /// the split turning a horizontal acceleration into opposite vertical forces of the two feet, and the
    /// first samples' swings stayed in the offsets: on soft ground the estimated normal forces jumped between
    /// 54 and 282 N within 20 ms and the compliant TSID diverged at 0.06 s (docs/soft-ground.md, "TSID-Compliant
    /// with real actuators, 2026-12-06 night"). Static, a sample's error is the robot's real dynamic wrench,
    /// which the running mean averages out.
    fn learn_standing_offsets(&mut self, input: &EstimatorInput) -> Result<()> {
        let Some(st) = &mut self.standing else {
            return Ok(());
        };
        if !st.active(input.time_ns) {
            return Ok(());
        }
        let soles = self.soles.map(|s| self.kd.frame_rotation_translation(s));
        let force = -self.model.total_mass() * self.model.gravity();
        let com = self.kd.com_position();
        let Some(split) = standing_foot_wrenches(&force, &com, &soles, self.config.sole_size)
        else {
            return Ok(());
        };
        let external = [0, 1].map(|foot| ExternalWrench {
            frame: self.soles[foot],
            wrench: split[foot],
        });
        self.kd
            .ft_sensor_wrenches(&st.still, &external, &mut st.expected)?;
        st.count += 1;
        let n = st.count as f64;
        for (s, (sum, expected)) in st.sum.iter_mut().zip(&st.expected).enumerate() {
            let expected_raw = match &self.calibration[s] {
                Some((_, c_inv)) => c_inv * expected,
                None => *expected,
            };
            *sum += input.ft_wrenches[s] - expected_raw;
            self.output.ft_offsets[s] = *sum / n;
        }
        Ok(())
    }

    /// Step 6b (`ekf.level_soles_while_standing`): while the robot stands still at start-up (the window of
    /// `ft_offsets.learn_while_standing`) on both feet on a level ground, its soles' attitude is the
    /// ground's, so the legs' kinematics give the IMU's tilt: the accelerometer's bias is learnt as the
    /// running mean of its reading less a still IMU's (`StandingOffsets::accelerometer_bias`) and set as the
    /// filter's estimate ([`InvariantEkf::set_accelerometer_bias`]); with `level_soles_noise` > 0 each sole
    /// is also measured level ([`InvariantEkf::update_level_sole`], that σ). The mean, not the filter, learns the
    /// bias: with the filter's accelerometer noise density (0.1 m/s²/√Hz) one second standing still leaves
    /// its bias σ near 0.1 m/s², twice the bias to learn. The gyroscope's bias is the filter's (observable
    /// through roll and pitch): its mean reading would take the robot's own turning for bias.
    fn level_soles(
        &mut self,
        input: &EstimatorInput,
        imu_r_sole: &[Matrix3<f64>; 2],
    ) -> Result<()> {
        if !self.config.ekf.level_soles_while_standing || self.output.contacts != [true; 2] {
            return Ok(());
        }
        let Some(st) = self.standing.as_mut() else {
            return Ok(());
        };
        if !st.active(input.time_ns) {
            return Ok(());
        }
        let bias = st.accelerometer_bias(
            &input.imu.proper_acceleration,
            self.model.gravity().norm(),
            imu_r_sole,
        );
        self.ekf.set_accelerometer_bias(&bias);
        if self.config.ekf.level_soles_noise <= 0.0 {
            return Ok(());
        }
        let level = Vector3::z();
        for r_h in imu_r_sole {
            self.ekf
                .update_level_sole(r_h, &level, self.config.ekf.level_soles_noise)?;
        }
        Ok(())
    }

    /// Step 8: joint torques, from the RNEA of [`Self::foot_wrenches`] (same state and `ν̇`) with the foot
    /// wrenches subtracted ([`KinDyn::inverse_dynamics_after_ft_sensors`]).
    fn joint_torques(&mut self, wrenches: &[Vector6<f64>; 2]) -> Result<()> {
        let external = [0, 1].map(|foot| ExternalWrench {
            frame: self.soles[foot],
            wrench: wrenches[foot],
        });
        self.kd
            .inverse_dynamics_after_ft_sensors(&external, &mut self.generalized)?;
        let n = self.model.dof();
        self.output
            .joint_torques
            .copy_from(&self.generalized.rows(6, n));
        Ok(())
    }
}

/// A sensor's calibration matrix `C` and its inverse.
type Calibration = (Matrix6<f64>, Matrix6<f64>);

/// Each sensor's calibration matrix `C` and its inverse from `config.ft_calibration` (rows), in
/// [`Model::ft_sensors`] order; `None` for a sensor not named (identity) [Traversaro 2017, eq. (5.1)].
fn calibration_matrices(
    model: &Model,
    config: &EstimatorConfig,
) -> Result<Vec<Option<Calibration>>> {
    let mut out = vec![None; model.ft_sensors().len()];
    for (name, rows) in &config.ft_calibration {
        let s = model
            .ft_sensor_index(name)
            .ok_or_else(|| EstimatorError::UnknownFtSensor {
                key: "ft_calibration",
                name: name.clone(),
            })?;
        let c = Matrix6::from_fn(|i, j| rows[i][j]);
        let c_inv = c
            .try_inverse()
            .filter(|m| m.iter().all(|v| v.is_finite()))
            .ok_or(EstimatorError::InvalidParameter {
                name: "ft_calibration",
                value: c.determinant(),
                reason: "a calibration matrix must be invertible (the value is its determinant)",
            })?;
        out[s] = Some((c, c_inv));
    }
    Ok(out)
}

/// The sensor measuring foot `foot`: the named one (which must have the sole on its child side), or the
/// nearest to the sole at the zero configuration among those that have it on their child side.
fn choose_foot_sensor(
    model: &Model,
    kd: &KinDyn,
    sensor_feet: &[[bool; 2]],
    sole: FrameId,
    foot: usize,
    name: &Option<String>,
    key: &'static str,
) -> Result<usize> {
    let sole_name = model.frame_name(sole).to_string();
    if let Some(name) = name {
        let s = model
            .ft_sensor_index(name)
            .ok_or_else(|| EstimatorError::UnknownFtSensor {
                key,
                name: name.clone(),
            })?;
        if !sensor_feet[s][foot] {
            return Err(EstimatorError::NoFootSensor {
                sole: sole_name,
                reason: "the named sensor has the sole on its parent side",
            });
        }
        return Ok(s);
    }
    let p_sole = kd.frame_rotation_translation(sole).1;
    model
        .ft_sensors()
        .iter()
        .enumerate()
        .filter(|(s, _)| sensor_feet[*s][foot])
        .map(|(s, sensor)| {
            (
                s,
                (kd.frame_rotation_translation(sensor.frame).1 - p_sole).norm(),
            )
        })
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(s, _)| s)
        .ok_or(EstimatorError::NoFootSensor {
            sole: sole_name,
            reason: "no sensor has it on its child side",
        })
}

impl Estimator {
    /// One tick (inherent, so a caller need not import [`stride_block::Block`]; the `Block` impl calls it).
    /// After samples given to [`Self::preintegrate`], the tick covers them too: the covariance is propagated
    /// over the whole interval since the last tick ([`InvariantEkf::propagate_over`]) and the offset filter
    /// steps by it.
    pub fn step(&mut self, input: &EstimatorInput) -> Result<&EstimatorOutput> {
        let dt = self.check_input(input)?;
        self.filter_joint_velocities(input, dt);
        let interval = self.preintegrated + dt;
        self.preintegrated = 0.0;
        let (kin, imu_r_sole) = self.predict(input, dt, interval)?;
        let wrenches = self.foot_wrenches(input)?;
        let h = self.contact_points(&kin, &wrenches, interval);
        for foot in 0..2 {
            let contact = self.triggers[foot].update(wrenches[foot].z, input.time_ns);
            if contact {
                self.swing_since_ns[foot] = None;
                self.ekf.update_foot(foot, &h[foot], &imu_r_sole[foot])?;
                if self.config.ekf.flat_ground {
                    self.ekf.update_ground_height(
                        foot,
                        self.ground_height,
                        self.config.ekf.ground_height_noise,
                    )?;
                }
            } else {
                self.swing_since_ns[foot].get_or_insert(input.time_ns);
                self.ekf.reset_foot(foot, &h[foot], &imu_r_sole[foot]);
            }
            self.output.contacts[foot] = contact;
        }
        self.level_soles(input, &imu_r_sole)?;
        self.update_offsets(input, &wrenches, interval);
        self.joint_torques(&wrenches)?;
        self.learn_standing_offsets(input)?;
        let (pose, twist, _) = self.base_from_imu(&self.ekf.state(), &kin, input);
        let out = &mut self.output;
        out.state.base_pose = pose;
        out.state.base_velocity = twist;
        out.state.joint_positions.copy_from(&input.joint_positions);
        out.state
            .joint_velocities
            .copy_from(joint_velocities(&self.joint_velocity, input));
        out.foot_wrenches = wrenches;
        self.last_time_ns = Some(input.time_ns);
        Ok(&self.output)
    }

    /// Each foot's contact point in the IMU frame, the EKF's measurement of it: the sole's origin from the
    /// kinematics `kin`, less its sink on a compliant ground ([`crate::sole_sink`]), stepped over
    /// `interval` \[s\] with the foot's estimated force. On the first tick the sinks start at rest under
    /// the standing load, and the contact points and the ground height move up by them (the soles stay
    /// where the initial state put them). On a rigid ground (the default) the sole's origin, bit for bit.
    fn contact_points(
        &mut self,
        kin: &RelativeKinematics,
        wrenches: &[Vector6<f64>; 2],
        interval: f64,
    ) -> [Vector3<f64>; 2] {
        let h = kin.imu_h_sole.map(|h| h.translation.vector);
        if self.sole_sink.rigid() {
            return h;
        }
        let force = wrenches.map(|w| Vector3::new(w.x, w.y, w.z));
        let sinks = match self.sinks {
            Some(s) => [0, 1].map(|i| self.sole_sink.step(&s[i], &force[i], interval)),
            None => {
                let s = force.map(|f| self.sole_sink.at_rest(&f));
                for (foot, sink) in s.iter().enumerate() {
                    self.ekf.shift_contact_point(foot, &-sink);
                }
                self.ground_height -= 0.5 * (s[0].z + s[1].z);
                s
            }
        };
        self.sinks = Some(sinks);
        let r = self.ekf.state().rotation;
        [0, 1].map(|i| h[i] - r.tr_mul(&sinks[i]))
    }

    /// Pre-integrates one sample between two full ticks ([`Self::step`]): checks it as a tick does, then
    /// moves the EKF's mean by its gyroscope and accelerometer reading ([`InvariantEkf::propagate_mean`])
    /// and adds its period to the interval the next tick propagates the covariance over. Kinematics, foot
    /// wrenches, contacts, updates and offsets wait for that tick, and the output stays the last tick's. This
    /// is how the layer runs at the rate its estimate is read (the whole-body rate) without losing the IMU
    /// samples in between: each costs about 2 000 instructions (0.3 µs) instead of a full tick's 95 000.
    ///
    /// # Errors
    /// The input checks of [`Self::step`]; nothing changes then.
    pub fn preintegrate(&mut self, input: &EstimatorInput) -> Result<()> {
        let dt = self.check_input(input)?;
        self.filter_joint_velocities(input, dt);
        let imu = &input.imu;
        self.ekf
            .propagate_mean(&imu.angular_velocity, &imu.proper_acceleration, dt);
        self.preintegrated += dt;
        self.last_time_ns = Some(input.time_ns);
        Ok(())
    }
}

impl Estimator {
    /// The joint accelerations \[rad/s²\] (model order, `dof` values) the joint velocity filter's
    /// prediction holds from the next sample on ([`JointVelocityFilter::set_accelerations`]; the
    /// accelerations a controller commanded). No filter (`joint_velocity_bandwidth` 0): nothing. Errors:
    /// a size other than `dof` or a non-finite value (nothing changes).
    pub fn set_joint_accelerations(&mut self, accelerations: &[f64]) -> Result<()> {
        let dof = self.model.dof();
        if accelerations.len() != dof {
            return Err(EstimatorError::InputSize {
                name: "joint_accelerations",
                expected: dof,
                actual: accelerations.len(),
            });
        }
        if !accelerations.iter().all(|a| a.is_finite()) {
            return Err(EstimatorError::NonFiniteInput {
                name: "joint_accelerations",
            });
        }
        if let Some(f) = &mut self.joint_velocity {
            f.set_accelerations(accelerations);
        }
        Ok(())
    }

    /// Steps the joint velocity filter (when configured) on the sample's encoder positions.
    fn filter_joint_velocities(&mut self, input: &EstimatorInput, dt: f64) {
        if let Some(f) = &mut self.joint_velocity {
            f.step(&input.joint_positions, &input.joint_velocities, dt);
        }
    }
}

/// The joint velocities the estimator uses: the filter's when there is one, else the encoders'.
fn joint_velocities<'a>(
    filter: &'a Option<JointVelocityFilter>,
    input: &'a EstimatorInput,
) -> &'a DVector<f64> {
    filter
        .as_ref()
        .map_or(&input.joint_velocities, JointVelocityFilter::velocities)
}

impl Block for Estimator {
    type Input = EstimatorInput;
    type Output = EstimatorOutput;
    type Error = EstimatorError;

    fn step(&mut self, input: &EstimatorInput) -> Result<&EstimatorOutput> {
        Estimator::step(self, input)
    }

    fn reset(&mut self) {
        self.initialized = false;
        self.last_time_ns = None;
        self.preintegrated = 0.0;
        self.swing_since_ns = [None; 2];
        if let Some(f) = &mut self.joint_velocity {
            f.reset();
        }
        if let Some(st) = &mut self.standing {
            st.restart();
        }
        self.output = EstimatorOutput::new(&self.model);
        self.output.ft_offsets.clone_from(&self.initial_offsets);
    }
}
