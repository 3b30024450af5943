//! The three layers wired together: planner → simplified → whole-body, and the conversions between them.
//!
//! [`Stack`] owns one instance of each layer, their preallocated inputs and the runner's own kinematics
//! workspace for the measured quantities. The scheduler ([`crate::run`]) calls, within one base tick and
//! in this order: [`Stack::sense`] (the estimation layer, on each fresh measurement), [`Stack::measure`]
//! (measured CoM, DCM, ZMP from the estimate, and the same from the plant's truth for the summary),
//! [`Stack::planner_tick`] (only on events: start, new goal segment), [`Stack::simplified_tick`] and
//! [`Stack::wbc_tick`] (each at its rate), then the command goes to the robot.
//!
//! Measured quantities: the CoM position and velocity from the estimated base state and joints through
//! the model; the DCM `ξ = x + ẋ/ω` with the plan's ω (computed once per simplified tick); the ZMP from the
//! feet wrenches by the walking stack's rule ([`stride_walking::feet_zmp`]), falling back to the CoM's ground
//! projection when the feet in contact carry less than 5 % of the weight. The simplified layer reads that ZMP through a first-order
//! low-pass filter ([`Stack::filter_measured_zmp`], `estimation.measured_zmp_cutoff`), updated at every
//! simplified and whole-body tick.

use std::sync::Arc;
use std::time::Duration;

use nalgebra::{Isometry3, Vector2, Vector3, Vector6};
use stride_block::{seconds, FirstOrderLowPass};
use stride_estimation::{Estimator, EstimatorOutput};
use stride_model::{FrameId, KinDyn, Model, RobotState, VelocityRepresentation};
use stride_planner::{Goal as PlannerGoal, PlanSample, Planner, PlannerInput, Waypoint};
use stride_simplified::{
    DcmControllerKind, FootAdmittance, FootAdmittanceInput, SimplifiedController, SimplifiedInput,
    SimplifiedOutput, StepAdjuster,
};
pub use stride_walking::soles_heading;
use stride_walking::{
    scale_plan_sample, MeasuredCentroidal, PlanClock, SimplifiedInputBuilder, WalkingHandles,
};
use stride_wbc::{ActuatorCompensation, ContactId, ContactModel, QpIk, Tsid, WbcInput};

use crate::centroidal::{CentroidalLayer, CentroidalMeasurement};
use crate::config::{ControlMode, EstimationKind, EstimationUpdate, Goal, Scenario};
use crate::error::RunError;
use crate::flexible::{FlexibleObserver, FlexibleSprings};
use crate::push::PushResponse;
use crate::push_weights::PushWeights;
use crate::robot::{JointCommand, Measurement};
use crate::setup::frame_of;
use crate::soft_soles::zero_force_sole;
use crate::step_adjust::{AdjustedFootstepMsg, StepTracker};
use crate::wrench_split::planned_foot_wrenches;

/// The whole-body controller of the configured control mode.
#[allow(clippy::large_enum_variant)]
pub enum Wbc {
    /// Kinematic QP-IK (position mode).
    Ik(QpIk),
    /// TSID (torque mode).
    Tsid(Tsid),
}

impl Wbc {
    /// The whole-body controller of the scenario's control mode, at the period of `rates.wbc_hz`.
    pub fn new(scenario: &Scenario, model: &Arc<Model>) -> Result<Self, RunError> {
        let c = &scenario.config;
        let period = Duration::from_nanos(1_000_000_000 / u64::from(c.rates.wbc_hz));
        let wbc = match c.scenario.control_mode {
            ControlMode::Position => Wbc::Ik(QpIk::new(
                Arc::clone(model),
                scenario.ik_config(model)?,
                period,
            )?),
            ControlMode::Torque => Wbc::Tsid(Tsid::new(
                Arc::clone(model),
                scenario.tsid_config(model)?,
                period,
            )?),
        };
        wbc.check_walking_names()?;
        Ok(wbc)
    }

    /// The runner fills only the walking references and contacts (`stride_walking::walking_layout`):
    /// any other name would stay at its initial value (identity pose, closed contact) for the whole run.
    fn check_walking_names(&self) -> Result<(), stride_wbc::WbcError> {
        let (layout, tasks) = match self {
            Wbc::Ik(ik) => (ik.input_layout(), &ik.config().tasks),
            Wbc::Tsid(t) => (t.input_layout(), &t.config().tasks),
        };
        let walking = stride_walking::walking_layout();
        let unknown =
            |names: &[String], known: &[String]| names.iter().find(|n| !known.contains(n)).cloned();
        let (key, name) = match (
            unknown(layout.frames(), walking.frames()),
            unknown(layout.contacts(), walking.contacts()),
        ) {
            (Some(name), _) => ("reference", name),
            (None, Some(name)) => ("contact", name),
            (None, None) => return Ok(()),
        };
        let task = tasks
            .iter()
            .find(|t| match t {
                stride_wbc::TaskConfig::Se3(c) => c.reference == name,
                stride_wbc::TaskConfig::So3(c) | stride_wbc::TaskConfig::R3(c) => {
                    c.reference == name
                }
                stride_wbc::TaskConfig::Contact(c) => c.contact_name().is_ok_and(|n| n == name),
                _ => false,
            })
            .map_or("<wbc>", |t| t.name());
        Err(stride_wbc::WbcError::InvalidConfig {
            task: task.to_owned(),
            key,
            reason: format!(
                "`{name}`: the runner sets only the walking names ({}, {} and `initial` for references)",
                walking.frames().join(", "),
                walking.contacts().join(", ")
            ),
        })
    }

    /// An input holding the robot at `state` with the controller's names and the walking ones
    /// ([`stride_walking::walking_input`]).
    pub fn input(&self, state: &RobotState) -> WbcInput {
        let layout = match self {
            Wbc::Ik(ik) => ik.input_layout(),
            Wbc::Tsid(t) => t.input_layout(),
        };
        stride_walking::walking_input(state, layout)
    }
}

/// Where the controllers' view of the robot comes from.
#[allow(clippy::large_enum_variant)]
pub enum Estimation {
    /// The estimation layer (`estimation.kind = "ekf"`, the default).
    Estimator(Estimator),
    /// The plant's truth, for debugging (`estimation.kind = "ground_truth"`); the summary says so.
    GroundTruth,
}

impl Estimation {
    /// The scenario's estimation, started at the robot's initial state `initial` (standing still: the
    /// world frame is defined by it).
    pub fn new(
        scenario: &Scenario,
        model: &Arc<Model>,
        initial: &RobotState,
    ) -> Result<Self, RunError> {
        let c = &scenario.config;
        Ok(match c.estimation.kind {
            EstimationKind::GroundTruth => Estimation::GroundTruth,
            EstimationKind::Ekf => {
                let config = c.estimator_config();
                let mut estimator =
                    Estimator::new(Arc::clone(model), &config, scenario.sim_period())?;
                estimator.set_initial_state(initial)?;
                Estimation::Estimator(estimator)
            }
        })
    }
}

/// A planner event scheduled in simulated time.
#[derive(Debug, Clone, PartialEq)]
pub struct GoalEvent {
    /// When \[ns\].
    pub time_ns: u64,
    /// The goal handed to the planner.
    pub goal: PlannerGoal,
}

/// Converts the scenario goal into the planner's goal events (one at t = 0, one per velocity segment).
pub fn goal_events(goal: &Goal) -> Vec<GoalEvent> {
    let to_ns = |s: f64| (s.max(0.0) * 1e9).round() as u64;
    match goal {
        Goal::Pose(p) => vec![GoalEvent {
            time_ns: 0,
            goal: PlannerGoal::Pose {
                x: p.x,
                y: p.y,
                yaw: p.heading_deg.to_radians(),
            },
        }],
        Goal::Waypoints { points } => vec![GoalEvent {
            time_ns: 0,
            goal: PlannerGoal::Waypoints {
                points: points
                    .iter()
                    .map(|p| Waypoint {
                        x: p.x,
                        y: p.y,
                        yaw: Some(p.heading_deg.to_radians()),
                    })
                    .collect(),
            },
        }],
        Goal::Velocity { segments } => segments
            .iter()
            .enumerate()
            .map(|(i, s)| GoalEvent {
                time_ns: to_ns(s.start),
                goal: PlannerGoal::Velocity {
                    forward: s.forward,
                    lateral: s.lateral,
                    yaw_rate: s.yaw_rate_deg.to_radians(),
                    duration: segments.get(i + 1).map(|n| n.start - s.start),
                },
            })
            .collect(),
        Goal::Stand {} => vec![GoalEvent {
            time_ns: 0,
            goal: PlannerGoal::Stand,
        }],
    }
}

/// The goal events `events` held back by `standing` \[s\], the robot standing until then
/// (`estimation.ft_offsets.learn_while_standing`: the estimation layer learns the force/torque offsets while
/// the robot stands still on both feet, docs/estimation.md). `standing` ≤ 0: unchanged.
pub fn standing_first(mut events: Vec<GoalEvent>, standing: f64) -> Vec<GoalEvent> {
    if standing > 0.0 {
        let delay = (standing * 1e9).round() as u64;
        for e in &mut events {
            e.time_ns = e.time_ns.saturating_add(delay);
        }
        events.insert(
            0,
            GoalEvent {
                time_ns: 0,
                goal: PlannerGoal::Stand,
            },
        );
    }
    events
}

/// Measured quantities of one tick.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Measured {
    /// CoM \[m\].
    pub com: Vector3<f64>,
    /// CoM velocity [m/s].
    pub com_velocity: Vector3<f64>,
    /// DCM (xy) with the plan's ω at the last simplified tick \[m\].
    pub dcm: Vector2<f64>,
    /// ZMP from the feet wrenches \[m\].
    pub zmp: Vector2<f64>,
    /// Whether the ZMP came from the wrenches (false: CoM projection fallback).
    pub zmp_from_wrenches: bool,
    /// Left and right sole poses.
    pub soles: [nalgebra::Isometry3<f64>; 2],
    /// Torso tilt \[rad\]: angle between the vertical and the torso frame's axis that was vertical in the
    /// initial posture.
    pub tilt: f64,
    /// The torso's up axis in the world (unit; the world vertical in the initial posture): its horizontal
    /// part points where the torso leans.
    pub torso_up: Vector3<f64>,
    /// Base height \[m\].
    pub base_height: f64,
}

/// The three layers and their wiring.
pub struct Stack {
    model: Arc<Model>,
    /// The kinematics workspace of the true state, set to the last measured one (the log sink's `/tf`
    /// reads it too).
    pub(crate) kd: KinDyn,
    /// The kinematics workspace of the estimated state. Apart from `kd` so that each sees one state's
    /// sequence: the estimate's joint positions are encoder readings, and a joint whose reading did not
    /// change since the last tick keeps its rotation ([`KinDyn::set_state`] reuses it, bit for bit).
    kd_estimate: KinDyn,
    frames: MeasureFrames,
    /// Gravity magnitude \[m/s²\] (the model's, along −z).
    gravity: f64,
    foot_half_length: f64,
    foot_half_width: f64,
    /// The planner.
    pub planner: Planner,
    /// The last planner input (event ticks).
    pub planner_input: PlannerInput,
    /// The plan sampled at the current tick.
    pub plan_sample: PlanSample,
    horizon_sample: PlanSample,
    /// The simplified layer.
    pub simplified: SimplifiedController,
    /// Its input of the last tick.
    pub simplified_input: SimplifiedInput,
    /// Fills [`Stack::simplified_input`] from the plan and the measurements (the library glue).
    simplified_glue: SimplifiedInputBuilder,
    /// Its last valid output (held on error).
    pub simplified_output: SimplifiedOutput,
    simplified_valid: bool,
    /// The whole-body layer.
    pub wbc: Wbc,
    /// Its input of the last tick.
    pub wbc_input: WbcInput,
    /// The walking slots of `wbc_input`.
    wbc_handles: WalkingHandles,
    /// The left and right sole contacts of the whole-body input, which carry the measured foot wrenches
    /// (read by the compliant TSID).
    foot_contacts: [ContactId; 2],
    /// The command of the last whole-body tick.
    pub command: JointCommand,
    /// The estimation layer (or the ground-truth bypass).
    pub estimation: Estimation,
    /// The estimation layer's output of the last plant period: all the controllers read of the robot.
    pub estimate: EstimatorOutput,
    /// Measured quantities of the last tick, from [`Stack::estimate`] (what the layers use).
    pub measured: Measured,
    /// The same quantities from the plant's truth (what the summary reports; equal to
    /// [`Stack::measured`] with the ground-truth bypass).
    pub truth: Measured,
    /// The low-passed measured ZMP the simplified layer reads, and the time of its last sample \[ns\].
    zmp_filter: (FirstOrderLowPass<Vector2<f64>>, u64),
    events: Vec<GoalEvent>,
    next_event: usize,
    /// The goal the planner works towards (the last one handed to it).
    goal: PlannerGoal,
    /// The step-adjustment QP (`simplified.step_adjustment.enabled`), with the nominal of the step in
    /// progress.
    step_adjustment: Option<(StepAdjuster, StepTracker)>,
    /// The footstep adjusted at the last simplified tick, for `/planner/adjusted_footsteps` (taken by the
    /// scheduler).
    pub adjusted_footstep: Option<AdjustedFootstepMsg>,
    /// The centroidal MPC (`simplified.dcm_controller = "centroidal_mpc"`).
    pub centroidal: Option<CentroidalLayer>,
    /// The plan's clock: plan time, which stops while a push holds the double support (identity
    /// otherwise).
    pub plan_clock: PlanClock,
    /// The push estimate and the double-support hold (`simplified.push.enabled`).
    pub push: Option<PushResponse>,
    /// The TSID's weights during a push (`simplified.push.wbc_com_weight`, `wbc_upright_weight`; torque
    /// control with the push response only).
    pub push_weights: Option<PushWeights>,
    /// The push estimate \[N\] when a double-support hold started at the last simplified tick, for the
    /// `push_hold` event (taken by the scheduler).
    pub push_hold_started: Option<Vector2<f64>>,
    /// How far \[m\] the DCM with the push was outside the support polygon when `step_out` ended a
    /// hold at the last simplified tick, for the `push_step_out` event (taken by the scheduler).
    pub push_step_out: Option<f64>,
    /// Whether [`Stack::adjusted_footstep`] is an early touch-down (`step_adjustment.touchdown_force`)
    /// rather than a step moved by the step-adjustment QP.
    pub early_touchdown: bool,
    /// The whole-body period \[s\] (the push observer's step).
    wbc_period: f64,
    /// Angular momentum reference of the last simplified tick (the centroidal MPC's; zero otherwise)
    /// \[kg m²/s\].
    angular_momentum_reference: Vector3<f64>,
    /// The springs of TSID-Flex's flexible joints (empty for the rigid TSID and the QP-IK).
    flexible: FlexibleSprings,
    /// The observer of TSID-Flex's unmeasured flexible joints, in the estimation loop.
    flexible_observer: Option<FlexibleObserver>,
    /// `estimation.update = "when_read"`: the samples of ticks that do not read the estimate are
    /// pre-integrated ([`Stack::preintegrate`]).
    pub preintegrate_unread: bool,
    /// `estimation.joint_velocity_prediction`: the TSID's joint accelerations feed the estimation layer's
    /// joint velocity filter ([`predict_joint_velocities`]).
    predict_joint_velocities: bool,
    /// `wbc.tsid.actuators`: the motors' torque lag and friction the TSID's torques are compensated for
    /// (`None`: ideal motors, the command is the TSID's torques).
    actuators: Option<ActuatorCompensation>,
    /// The foot admittance of position control (`simplified.foot_admittance.enabled`, QP-IK only) and
    /// the whole-body period it runs at \[s\].
    pub foot_admittance: Option<(FootAdmittance, f64)>,
    /// Fallback/hold counters: simplified errors held, wbc QP fallbacks, wbc holds.
    pub counters: Counters,
}

/// Counters the summary reports.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counters {
    /// Simplified-layer ticks that failed and held the previous references.
    pub simplified_holds: u64,
    /// Whole-body ticks solved by the relaxed fallback QP.
    pub wbc_fallbacks: u64,
    /// Whole-body ticks that held the last command.
    pub wbc_holds: u64,
    /// Planner replans.
    pub replans: u64,
    /// Footstep adjustments applied to the plan.
    pub step_adjustments: u64,
    /// Footstep adjustments the planner refused (the plan was kept).
    pub step_adjustment_failures: u64,
    /// Early touch-downs: late swings landed where the foot struck the ground.
    pub early_touchdowns: u64,
}

impl Stack {
    /// The plan time at controller time `time_ns` (advances [`Stack::plan_clock`]).
    fn plan_time(&mut self, time_ns: u64) -> Duration {
        self.plan_clock.plan_time(Duration::from_nanos(time_ns))
    }

    /// Double supports held by a push so far, and the plan's delay behind the controller's time \[s\].
    pub fn push_holds(&self) -> (u64, f64) {
        (
            self.push.as_ref().map_or(0, |p| p.holds),
            self.plan_clock.delay(),
        )
    }
}

impl Stack {
    /// Builds every layer from the scenario. `initial` is the robot's measured initial state.
    pub fn new(
        scenario: &Scenario,
        model: Arc<Model>,
        initial: &RobotState,
    ) -> Result<Self, RunError> {
        let c = &scenario.config;
        let soles = [
            frame_of(scenario, &model, "robot.left_sole", &c.robot.left_sole)?,
            frame_of(scenario, &model, "robot.right_sole", &c.robot.right_sole)?,
        ];
        let torso = frame_of(scenario, &model, "robot.torso_frame", &c.robot.torso_frame)?;
        let mut kd = KinDyn::new(Arc::clone(&model));
        kd.set_representation(VelocityRepresentation::Mixed);
        kd.set_state(initial)?;
        // The initial posture is upright by construction (soles flat on the ground): the torso's up axis is
        // the world vertical seen from the torso frame there.
        let torso_up = kd.frame_pose(torso).rotation.inverse() * Vector3::z();
        let planner = Planner::new(c.planner.clone(), -model.gravity().z)?;
        let simplified_period =
            Duration::from_nanos(1_000_000_000 / u64::from(c.rates.simplified_hz));
        let simplified = SimplifiedController::new(&c.simplified, simplified_period)?;
        let mut wbc = Wbc::new(scenario, &model)?;
        let push_weights = match &wbc {
            Wbc::Tsid(t) if c.simplified.push.enabled => PushWeights::new(&c.simplified.push, t)?,
            _ => None,
        };
        let flexible = match &mut wbc {
            Wbc::Tsid(t) => {
                let springs = FlexibleSprings::new(scenario, &model, &t.config().flexible_joints)?;
                t.set_flexible_springs(&springs.springs())?;
                springs
            }
            Wbc::Ik(_) => FlexibleSprings::default(),
        };
        let actuators = match &wbc {
            Wbc::Tsid(t) if t.config().actuators.is_active() => Some(ActuatorCompensation::new(
                t.config().actuators,
                model.dof(),
                1.0 / f64::from(c.rates.wbc_hz),
            )?),
            _ => None,
        };
        let flexible_observer = match c.estimation.kind {
            EstimationKind::Ekf => flexible.observer(&model, scenario.sim_period())?,
            EstimationKind::GroundTruth => None,
        };
        let predict_joint_velocities = c.estimation.joint_velocity_prediction;
        if predict_joint_velocities && c.estimation.joint_velocity_bandwidth <= 0.0 {
            return Err(scenario
                .invalid(
                    "estimation.joint_velocity_prediction",
                    "predicts in the joint velocity filter; expected estimation.joint_velocity_bandwidth > 0",
                )
                .into());
        }
        let preintegrate_unread = c.estimation.update == EstimationUpdate::WhenRead;
        if preintegrate_unread && flexible_observer.is_some() {
            return Err(scenario
                .invalid(
                    "estimation.update",
                    "the observer of the flexible joints without encoders (wbc.tsid.flexible_joints) \
                     steps on every sample; expected `every_sample` with it",
                )
                .into());
        }
        let simplified_glue =
            SimplifiedInputBuilder::new(&simplified, c.planner.foot_length, c.planner.foot_width);
        let simplified_input =
            simplified_glue.new_input(&[kd.frame_pose(soles[0]), kd.frame_pose(soles[1])])?;
        let wbc_input = wbc.input(initial);
        let wbc_handles = WalkingHandles::new(&wbc_input)?;
        let foot_contacts = [
            wbc_input.contact_id(stride_wbc::walking::LEFT_FOOT)?,
            wbc_input.contact_id(stride_wbc::walking::RIGHT_FOOT)?,
        ];
        let command = JointCommand::hold(c.scenario.control_mode, &initial.joint_positions);
        let estimation = Estimation::new(scenario, &model, initial)?;
        let mut estimate = EstimatorOutput::new(&model);
        estimate.state.clone_from(initial);
        let planner_input = PlannerInput {
            time: Duration::ZERO,
            goal: None,
            left_sole: kd.frame_pose(soles[0]),
            right_sole: kd.frame_pose(soles[1]),
        };
        Ok(Self {
            frames: MeasureFrames {
                soles,
                torso,
                torso_up,
            },
            gravity: -model.gravity().z,
            foot_half_length: c.planner.foot_length * 0.5,
            foot_half_width: c.planner.foot_width * 0.5,
            planner,
            planner_input,
            plan_sample: PlanSample::default(),
            horizon_sample: PlanSample::default(),
            simplified_output: *simplified.output(),
            simplified,
            simplified_input,
            simplified_glue,
            simplified_valid: false,
            wbc,
            wbc_input,
            wbc_handles,
            foot_contacts,
            command,
            estimation,
            estimate,
            measured: Measured::default(),
            truth: Measured::default(),
            zmp_filter: (FirstOrderLowPass::new(c.estimation.measured_zmp_cutoff), 0),
            events: standing_first(
                goal_events(&c.goal),
                c.estimation.ft_offsets.learn_while_standing,
            ),
            next_event: 0,
            goal: PlannerGoal::Stand,
            step_adjustment: if c.simplified.step_adjustment.enabled {
                let adjuster = StepAdjuster::new(&c.simplified.step_adjustment)?;
                Some((adjuster, StepTracker::default()))
            } else {
                None
            },
            adjusted_footstep: None,
            centroidal: match c.simplified.dcm_controller {
                DcmControllerKind::CentroidalMpc => Some(CentroidalLayer::new(
                    &c.simplified.centroidal_mpc,
                    kd.total_mass(),
                    -model.gravity().z,
                )?),
                _ => None,
            },
            angular_momentum_reference: Vector3::zeros(),
            plan_clock: PlanClock::new(c.simplified.push.hold_ramp),
            push: if c.simplified.push.enabled {
                Some(PushResponse::new(
                    &c.simplified.push,
                    kd.total_mass(),
                    model.gravity(),
                )?)
            } else {
                None
            },
            push_weights,
            push_hold_started: None,
            push_step_out: None,
            early_touchdown: false,
            wbc_period: 1.0 / f64::from(c.rates.wbc_hz),
            flexible,
            flexible_observer,
            preintegrate_unread,
            predict_joint_velocities,
            actuators,
            foot_admittance: foot_admittance(scenario, &model)?,
            counters: Counters::default(),
            kd_estimate: kd.clone(),
            kd,
            model,
        })
    }

    /// The model.
    pub fn model(&self) -> &Arc<Model> {
        &self.model
    }

    /// Steps the estimation layer on a fresh measurement (every plant period): its output
    /// ([`Stack::estimate`]) is all the controllers read of the robot. With `estimation.kind =
    /// "ground_truth"` (debugging only) it copies the plant's truth instead.
    pub fn sense(&mut self, m: &Measurement) -> Result<(), RunError> {
        match &mut self.estimation {
            Estimation::Estimator(estimator) => {
                let sensors = match &mut self.flexible_observer {
                    Some(o) => o.readings(&m.sensors)?,
                    None => &m.sensors,
                };
                let out = estimator.step(sensors)?;
                self.estimate.state.copy_from(&out.state);
                self.estimate.contacts = out.contacts;
                self.estimate.foot_wrenches = out.foot_wrenches;
                self.estimate.joint_torques.copy_from(&out.joint_torques);
                for (o, e) in self.estimate.ft_offsets.iter_mut().zip(&out.ft_offsets) {
                    *o = *e;
                }
                if let Some(o) = &mut self.flexible_observer {
                    o.update(&out.joint_torques, &mut self.estimate.state)?;
                }
            }
            Estimation::GroundTruth => {
                let t = &m.truth;
                self.estimate.state.copy_from(&t.state);
                self.estimate.contacts = t.feet_in_contact;
                self.estimate.foot_wrenches = t.foot_wrenches;
                self.estimate.joint_torques.copy_from(&t.joint_torques);
            }
        }
        Ok(())
    }

    /// Pre-integrates a fresh measurement that no layer reads (`estimation.update = "when_read"`): the
    /// estimation layer moves its EKF's mean by the IMU sample ([`Estimator::preintegrate`]); the estimate
    /// stays that of the last [`Stack::sense`], which covers the pre-integrated samples. With
    /// `estimation.kind = "ground_truth"` it is [`Stack::sense`].
    pub fn preintegrate(&mut self, m: &Measurement) -> Result<(), RunError> {
        match &mut self.estimation {
            Estimation::Estimator(estimator) => Ok(estimator.preintegrate(&m.sensors)?),
            Estimation::GroundTruth => self.sense(m),
        }
    }

    /// Measured CoM, ZMP, soles and tilt, twice: [`Stack::measured`] from the estimate (what the layers
    /// use) and [`Stack::truth`] from the plant's truth (what the summary reports). First step of every tick
    /// that runs a layer or logs the state; it leaves the kinematics at the true state (for `/tf`). The DCM
    /// needs the plan's ω: the simplified tick computes it. `plant`: the plant's kinematics of its true
    /// state if it keeps them ([`crate::robot::Robot::kinematics`]), copied instead of recomputed.
    pub fn measure(&mut self, m: &Measurement, plant: Option<&KinDyn>) -> Result<(), RunError> {
        let weight = self.model.total_mass() * self.gravity;
        let e = &self.estimate;
        let frames = &self.frames;
        self.kd_estimate.set_state(&e.state)?;
        let measured = measure_state(
            &mut self.kd_estimate,
            frames,
            weight,
            &e.state,
            &e.foot_wrenches,
            e.contacts,
        );
        self.measured = Measured {
            dcm: self.measured.dcm,
            ..measured
        };
        let t = &m.truth;
        match plant {
            Some(source) => self.kd.set_state_from(&t.state, source)?,
            None => self.kd.set_state(&t.state)?,
        }
        let truth = measure_state(
            &mut self.kd,
            frames,
            weight,
            &t.state,
            &t.foot_wrenches,
            t.feet_in_contact,
        );
        self.truth = Measured {
            dcm: self.truth.dcm,
            ..truth
        };
        Ok(())
    }

    /// Feeds the measured ZMP of this tick ([`Stack::measure`] first) to the low-pass filter the simplified
    /// layer reads it through (`estimation.measured_zmp_cutoff`). The scheduler calls it at every simplified
    /// and whole-body tick, a fixed rate that does not depend on the logging rate. The filter keeps the
    /// ZMP's noise (force/torque noise, contact chatter) out of the ZMP-CoM controller's CoM velocity
    /// reference, which the position servos' damping turns into torque spikes (docs/estimation.md).
    pub fn filter_measured_zmp(&mut self, time_ns: u64) {
        let (filter, last_ns) = &mut self.zmp_filter;
        let dt = time_ns.saturating_sub(*last_ns) as f64 * 1e-9;
        filter.update(self.measured.zmp, dt);
        *last_ns = time_ns;
    }

    /// The measured DCM `ξ = x + ẋ/ω` \[m\] [Romualdi 2022, eq. 4.4.2] (b = 1/ω) with the plan's ω (the one rule for
    /// ω), stored in [`Stack::measured`]; called by the simplified tick after sampling the plan.
    fn measure_dcm(&mut self, omega: f64) {
        for m in [&mut self.measured, &mut self.truth] {
            m.dcm = m.com.xy() + m.com_velocity.xy() / omega;
        }
    }

    /// Whether a planner event is due at `time_ns` (the first tick always is).
    pub fn planner_due(&self, time_ns: u64) -> bool {
        self.planner.plan().is_none()
            || self
                .events
                .get(self.next_event)
                .is_some_and(|e| e.time_ns <= time_ns)
    }

    /// Runs the planner block with the due event's goal (a replan, or the first plan from the measured
    /// soles). Returns true when it ran.
    pub fn planner_tick(&mut self, time_ns: u64) -> Result<bool, RunError> {
        if !self.planner_due(time_ns) {
            return Ok(false);
        }
        let goal = match self.events.get(self.next_event) {
            Some(e) if e.time_ns <= time_ns => {
                self.next_event += 1;
                Some(e.goal.clone())
            }
            _ => None,
        };
        if self.planner.plan().is_some() {
            self.counters.replans += 1;
        }
        if let Some(g) = &goal {
            self.goal = g.clone();
        }
        let soles = self.planning_soles();
        self.planner_input = PlannerInput {
            time: self.plan_time(time_ns),
            goal,
            left_sole: soles[0],
            right_sole: soles[1],
        };
        let sample = self.planner.step(&self.planner_input)?;
        self.plan_sample = *sample;
        Ok(true)
    }

    /// The soles the planner starts from: the measured ones, or with the compliant TSID's
    /// `plan_on_surface` their zero-force poses on its ground ([`zero_force_sole`]).
    fn planning_soles(&self) -> [Isometry3<f64>; 2] {
        let mut soles = self.measured.soles;
        if let Wbc::Tsid(t) = &self.wbc {
            let c = &t.config().compliant;
            if let (ContactModel::Compliant, true, Some(ground)) =
                (t.config().contact_model, c.plan_on_surface, t.ground())
            {
                let area = c.sole_length * c.sole_width;
                for (i, (s, w)) in soles
                    .iter_mut()
                    .zip(&self.estimate.foot_wrenches)
                    .enumerate()
                {
                    let flag = [
                        stride_wbc::walking::LEFT_FOOT,
                        stride_wbc::walking::RIGHT_FOOT,
                    ][i];
                    let k = t.ground_estimate_of(flag).unwrap_or(ground).stiffness;
                    *s = zero_force_sole(s, w, k, area);
                }
            }
        }
        soles
    }

    /// Samples the plan at the plan time of `time_ns` into [`Stack::plan_sample`], its derivatives
    /// scaled by the plan clock's rate ([`stride_walking::scale_plan_sample`]).
    pub fn sample_plan(&mut self, time_ns: u64) -> Result<(), RunError> {
        let t = self.plan_time(time_ns);
        self.planner.sample(t, &mut self.plan_sample)?;
        scale_plan_sample(&mut self.plan_sample, self.plan_clock.rate());
        Ok(())
    }

    /// One simplified-layer tick at `time_ns` (plan sampled first). On a layer error the previous
    /// references are held and the error is returned as `Ok(Some(message))` for the event log.
    pub fn simplified_tick(&mut self, time_ns: u64) -> Result<Option<String>, RunError> {
        self.sample_plan(time_ns)?;
        self.measure_dcm(self.plan_sample.omega);
        self.respond_to_push();
        self.adjust_step(time_ns);
        self.early_touch_down(time_ns);
        if let Some(push) = &self.push {
            push.lean(&mut self.plan_sample);
        }
        let centroidal_error = self.centroidal_tick(time_ns)?;
        let plan = self.planner.plan().ok_or(RunError::NoPlan {
            layer: "simplified",
        })?;
        let m = &self.measured;
        let measured = MeasuredCentroidal {
            com: m.com,
            com_velocity: m.com_velocity,
            dcm: m.dcm,
            zmp: self.zmp_filter.0.output().unwrap_or(m.zmp),
            soles: m.soles,
        };
        let i = &mut self.simplified_input;
        let plan_time = self.plan_clock.plan_time(Duration::from_nanos(time_ns));
        self.simplified_glue
            .fill(i, plan_time, plan, &self.plan_sample, &measured)?;
        if let Some(layer) = &self.centroidal {
            let r = layer.write_references(i, seconds(plan_time));
            self.angular_momentum_reference = r.angular_momentum;
        }
        match self.simplified.step(&self.simplified_input) {
            Ok(out) => {
                self.simplified_output = *out;
                self.simplified_valid = true;
                Ok(centroidal_error)
            }
            Err(e) => {
                self.counters.simplified_holds += 1;
                Ok(Some(e.to_string()))
            }
        }
    }

    /// The step adjustment of one simplified tick (when enabled): during single support, the QP's touch-down
    /// and time from the measured DCM, applied to the plan (swing retargeted, later steps replanned) when
    /// they differ from the planned ones by more than the dead bands. A refusal by the planner keeps the
    /// plan (counted).
    fn adjust_step(&mut self, time_ns: u64) {
        let Some((adjuster, tracker)) = self.step_adjustment.as_mut() else {
            return;
        };
        let Some(plan) = self.planner.plan() else {
            return;
        };
        let time = self.plan_clock.plan_time(Duration::from_nanos(time_ns));
        let cop = self.plan_sample.zmp.xy();
        let omega = self.plan_sample.omega;
        let push = self.push.as_ref().map_or((cop, Vector2::zeros()), |p| {
            (p.effective_cop(cop, omega), p.step_offset_shift(omega))
        });
        let Some(request) = tracker.request(
            plan,
            adjuster,
            &self.measured.dcm,
            &self.plan_sample,
            push,
            time,
        ) else {
            return;
        };
        match self.planner.adjust_step(&request, &self.goal) {
            Ok(true) => {
                self.counters.step_adjustments += 1;
                self.adjusted_footstep =
                    Some(tracker.applied(&request, adjuster.result(), &self.measured.dcm));
            }
            Ok(false) => {}
            Err(_) => self.counters.step_adjustment_failures += 1,
        }
    }

    /// The early touch-down of one simplified tick (when the step adjustment is on and its
    /// `touchdown_force` is positive): in the second half of a swing, a swing foot that carries more than
    /// `touchdown_force` of estimated vertical ground force has struck the ground before its plan (a body
    /// roll under a side push lowers the sole) while the plan still has the sole `touchdown_height` or
    /// more up. The step then lands where the foot is, `touchdown_lead`
    /// later: the swing is retargeted to the measured sole position and the later steps replanned from
    /// it (`Planner::adjust_step`), instead of the sole being dragged on towards its planned touch-down.
    /// Once per swing (after it less than `touchdown_lead` is left).
    fn early_touch_down(&mut self, time_ns: u64) {
        let Some((adjuster, tracker)) = self.step_adjustment.as_mut() else {
            return;
        };
        let c = *adjuster.config();
        let Some(plan) = self.planner.plan() else {
            return;
        };
        if c.touchdown_force <= 0.0 {
            return;
        }
        let time = self.plan_clock.plan_time(Duration::from_nanos(time_ns));
        let t = seconds(time);
        let Some(step) = plan.current_step(t) else {
            return;
        };
        let (lift, land) = (step.swing.lift_time, step.swing.land_time);
        let i = match step.swing.foot {
            stride_planner::Foot::Left => 0,
            stride_planner::Foot::Right => 1,
        };
        let sole = [&self.plan_sample.left, &self.plan_sample.right][i];
        let height = sole.pose.translation.z - step.swing.end.translation.z;
        let late = t > 0.5 * (lift + land) && land - t > c.touchdown_lead;
        let airborne = !sole.in_contact && height >= c.touchdown_height;
        if !late || !airborne || self.estimate.foot_wrenches[i][2] < c.touchdown_force {
            return;
        }
        let request = stride_planner::StepAdjustmentRequest {
            time,
            target: self.measured.soles[i].translation.vector.xy(),
            land_time: t + c.touchdown_lead,
            min_remaining: 0.0,
        };
        match self.planner.adjust_step(&request, &self.goal) {
            Ok(true) => {
                self.counters.early_touchdowns += 1;
                self.early_touchdown = true;
                self.adjusted_footstep =
                    Some(tracker.applied(&request, adjuster.result(), &self.measured.dcm));
            }
            Ok(false) => {}
            Err(_) => self.counters.step_adjustment_failures += 1,
        }
    }

    /// The centroidal MPC of one simplified tick (when selected, see [`crate::centroidal`]): re-solved
    /// every `update_period`, its adjusted touch-down applied to the swing in progress. An MPC error keeps
    /// its last prediction (counted as a simplified hold) and is returned for the event log.
    fn centroidal_tick(&mut self, time_ns: u64) -> Result<Option<String>, RunError> {
        let Some(layer) = self.centroidal.as_mut() else {
            return Ok(None);
        };
        let plan = self.planner.plan().ok_or(RunError::NoPlan {
            layer: "simplified",
        })?;
        let time = self.plan_clock.plan_time(Duration::from_nanos(time_ns));
        let feet_force = feet_force(&self.estimate);
        let measurement = CentroidalMeasurement {
            com: self.measured.com,
            com_velocity: self.measured.com_velocity,
            feet_force,
            foot_half: (self.foot_half_length, self.foot_half_width),
            push_estimate: self
                .push
                .as_ref()
                .map_or(Vector2::zeros(), |p| p.estimate()),
        };
        match layer.tick(plan, &measurement, &mut self.horizon_sample, time) {
            Ok(true) => {}
            Ok(false) => return Ok(None),
            Err(e) => {
                self.counters.simplified_holds += 1;
                return Ok(Some(e.to_string()));
            }
        }
        let Some(request) = layer.request(plan, time) else {
            return Ok(None);
        };
        let foot = plan.current_step(seconds(time)).map(|s| s.swing.foot);
        match self.planner.adjust_step(&request, &self.goal) {
            Ok(true) => {
                self.counters.step_adjustments += 1;
                if let Some(foot) = foot {
                    self.adjusted_footstep =
                        Some(layer.applied(foot, &request, &self.measured.dcm));
                }
            }
            Ok(false) => {}
            Err(_) => self.counters.step_adjustment_failures += 1,
        }
        Ok(None)
    }

    /// The push observer's step of one whole-body tick (when enabled, see [`crate::push`]): the
    /// measured CoM velocity against both feet's estimated forces (whatever the contact flags: the
    /// estimated wrenches are the ground's on the soles, zero in the air, and the contact detection lags
    /// a touch-down's first braking force).
    fn observe_push(&mut self) -> Result<(), RunError> {
        let w = &self.estimate.foot_wrenches;
        let feet_force = (w[0] + w[1]).fixed_rows::<3>(0).into_owned();
        if let Some(push) = self.push.as_mut() {
            let dt = self.wbc_period;
            push.observe(dt, &self.measured.com_velocity, &feet_force)?;
        }
        Ok(())
    }

    /// The push response of one simplified tick (when enabled): the plan clock held or run for the
    /// next ticks.
    fn respond_to_push(&mut self) {
        let Some(push) = self.push.as_mut() else {
            return;
        };
        let t = self.plan_sample.time;
        let plan = self.planner.plan();
        let walking = plan.is_some_and(|p| stride_walking::is_walking(p, t));
        let start_or_stop = plan.is_some_and(|p| crate::push::in_start_or_stop(p, t));
        let dt = self.simplified.period();
        let outside = push.capture(
            self.measured.dcm,
            self.plan_sample.omega,
            &self.simplified_input.support_polygon,
        );
        let step_outs = push.step_outs;
        if push.decide(
            dt,
            &self.plan_sample,
            walking,
            start_or_stop,
            &mut self.plan_clock,
        ) {
            self.push_hold_started = Some(push.estimate());
        }
        if push.step_outs > step_outs {
            self.push_step_out = Some(outside);
        }
    }

    /// One whole-body tick at `time_ns`: references from the plan (feet, CoM height, torso) and the
    /// simplified layer (CoM xy, desired ZMP), measured state in; [`Stack::command`] out.
    pub fn wbc_tick(&mut self, time_ns: u64) -> Result<(), RunError> {
        self.sample_plan(time_ns)?;
        self.observe_push()?;
        let s = &self.plan_sample;
        let i = &mut self.wbc_input;
        i.state.copy_from(&self.estimate.state);
        if let Some(a) = &self.actuators {
            a.predict(&mut i.state)?;
        }
        let simplified = self.simplified_valid.then_some(&self.simplified_output);
        stride_walking::fill_wbc_input(i, &self.wbc_handles, s, simplified)?;
        for (id, wrench) in self.foot_contacts.iter().zip(&self.estimate.foot_wrenches) {
            i.contact_mut(*id)?.measured_wrench = *wrench;
        }
        if let (Wbc::Tsid(t), Some(w), Some(push)) = (
            &mut self.wbc,
            self.push_weights.as_mut(),
            self.push.as_ref(),
        ) {
            w.update(&push.estimate(), self.plan_clock.holding(), t)?;
        }
        if let Wbc::Tsid(t) = &self.wbc {
            if t.config().contact_model == ContactModel::Compliant {
                let zmp = i.desired_zmp.unwrap_or_else(|| s.zmp.xy());
                let planned = planned_foot_wrenches(
                    self.model.total_mass(),
                    self.gravity,
                    &i.com_acceleration,
                    &zmp,
                    &[
                        s.left.pose.translation.vector,
                        s.right.pose.translation.vector,
                    ],
                    [s.left.in_contact, s.right.in_contact],
                );
                for (id, wrench) in self.foot_contacts.iter().zip(&planned) {
                    i.contact_mut(*id)?.desired_wrench = *wrench;
                }
            }
        }
        i.posture = None;
        i.angular_momentum = self.angular_momentum_reference;
        self.flexible
            .fill(&self.estimate.state, &mut i.flexible_torques);
        self.admit_feet()?;
        let s = &self.plan_sample;
        let cmd = &mut self.command;
        cmd.contacts = [s.left.in_contact, s.right.in_contact];
        match &mut self.wbc {
            Wbc::Ik(ik) => {
                let out = ik.step(&self.wbc_input)?;
                cmd.mode = ControlMode::Position;
                cmd.joint_positions.copy_from(&out.joint_positions);
                cmd.joint_velocities.copy_from(&out.joint_velocities);
                cmd.joint_torques.fill(0.0);
                if out.report.fallback {
                    self.counters.wbc_fallbacks += 1;
                }
                if out.report.held {
                    self.counters.wbc_holds += 1;
                }
            }
            Wbc::Tsid(t) => {
                let out = t.step(&self.wbc_input)?;
                predict_joint_velocities(&mut self.estimation, self.predict_joint_velocities, out)?;
                cmd.mode = ControlMode::Torque;
                cmd.joint_torques.copy_from(&out.joint_torques);
                if let Some(a) = &mut self.actuators {
                    a.apply(
                        &mut cmd.joint_torques,
                        &self.estimate.state.joint_velocities,
                        &out.accelerations,
                    )?;
                }
                cmd.joint_positions
                    .copy_from(&self.estimate.state.joint_positions);
                cmd.joint_velocities.fill(0.0);
                if out.report.fallback {
                    self.counters.wbc_fallbacks += 1;
                }
                if out.report.held {
                    self.counters.wbc_holds += 1;
                }
            }
        }
        Ok(())
    }

    /// The foot admittance of one whole-body tick (when enabled): the sole references of the feet in
    /// contact (planned and estimated) move with the error between the measured and the desired wrench
    /// (the desired ZMP of the whole-body input distributed on the feet), see
    /// [`stride_simplified::FootAdmittance`].
    fn admit_feet(&mut self) -> Result<(), RunError> {
        let Some((admittance, dt)) = self.foot_admittance.as_mut() else {
            return Ok(());
        };
        let s = &self.plan_sample;
        let planned = [s.left.in_contact, s.right.in_contact];
        let e = &self.estimate;
        let input = FootAdmittanceInput {
            desired_zmp: self.wbc_input.desired_zmp.unwrap_or(s.zmp.xy()),
            soles: self.measured.soles,
            wrenches: e.foot_wrenches,
            contacts: [planned[0] && e.contacts[0], planned[1] && e.contacts[1]],
            planned,
            dt: *dt,
        };
        let out = admittance.step(&input)?;
        stride_walking::apply_foot_admittance(&mut self.wbc_input, &self.wbc_handles, out)?;
        Ok(())
    }

    /// Whether the plan has ended (the robot should be standing at the goal).
    pub fn plan_finished(&self, time_ns: u64) -> bool {
        self.planner.plan().is_some_and(|p| {
            let t = time_ns as f64 * 1e-9 - self.plan_clock.delay();
            t >= p.end_time && self.next_event >= self.events.len()
        })
    }
}

/// `estimation.joint_velocity_prediction`: the joint accelerations the TSID chose (`out.accelerations`
/// past the 6 base entries) become the estimation layer's joint velocity prediction until its next tick
/// (`stride_estimation::Estimator::set_joint_accelerations`; a held solve keeps its last). Off, or on
/// the ground truth: nothing.
fn predict_joint_velocities(
    estimation: &mut Estimation,
    enabled: bool,
    out: &stride_wbc::TsidOutput,
) -> Result<(), RunError> {
    if let (true, Estimation::Estimator(e)) = (enabled, estimation) {
        if !out.report.held {
            e.set_joint_accelerations(&out.accelerations.as_slice()[6..])?;
        }
    }
    Ok(())
}

/// The scenario's foot admittance: `Some` in position control with `simplified.foot_admittance.enabled`,
/// for the planner's sole rectangle and the model's weight, at the whole-body period.
fn foot_admittance(
    scenario: &Scenario,
    model: &Model,
) -> Result<Option<(FootAdmittance, f64)>, RunError> {
    let c = &scenario.config;
    let config = &c.simplified.foot_admittance;
    if !config.enabled || c.scenario.control_mode != ControlMode::Position {
        return Ok(None);
    }
    let weight = model.total_mass() * model.gravity().norm();
    let admittance =
        FootAdmittance::new(config, c.planner.foot_length, c.planner.foot_width, weight)?;
    Ok(Some((admittance, 1.0 / f64::from(c.rates.wbc_hz))))
}

/// The sum of the estimated contact forces of the feet in contact \[N\] (world frame).
fn feet_force(e: &EstimatorOutput) -> Vector3<f64> {
    let mut force = Vector3::zeros();
    for (w, in_contact) in e.foot_wrenches.iter().zip(e.contacts) {
        if in_contact {
            force += w.fixed_rows::<3>(0);
        }
    }
    force
}

/// The frames the measured quantities come from.
struct MeasureFrames {
    /// Left and right sole.
    soles: [FrameId; 2],
    /// The torso frame.
    torso: FrameId,
    /// The world's vertical in the torso frame's coordinates at the initial posture: the torso's "up"
    /// axis, whatever the frame convention of the model (z up on the bundled humanoid, y up on iCub's
    /// `chest`). The tilt is the angle of this axis from the vertical.
    torso_up: Vector3<f64>,
}

/// CoM, ZMP (the walking stack's rule, [`stride_walking::feet_zmp`], the CoM's ground projection when it has none),
/// soles and tilt of `state`, `kd` being at `state`; the DCM is left at zero (it needs the plan's ω).
fn measure_state(
    kd: &mut KinDyn,
    frames: &MeasureFrames,
    weight: f64,
    state: &RobotState,
    foot_wrenches: &[Vector6<f64>; 2],
    contacts: [bool; 2],
) -> Measured {
    let com = kd.com_position();
    let soles = [
        kd.frame_pose(frames.soles[0]),
        kd.frame_pose(frames.soles[1]),
    ];
    let (zmp, ok) = match stride_walking::feet_zmp(&soles, foot_wrenches, contacts, weight) {
        Some(z) => (z, true),
        None => (com.xy(), false),
    };
    let torso = kd.frame_pose(frames.torso);
    let up = torso.rotation * frames.torso_up;
    Measured {
        com,
        com_velocity: kd.com_velocity(),
        dcm: Vector2::zeros(),
        zmp,
        zmp_from_wrenches: ok,
        soles,
        tilt: up.z.clamp(-1.0, 1.0).acos(),
        torso_up: up,
        base_height: state.base_pose.translation.z,
    }
}
