//! The deterministic multi-rate loop.
//!
//! # Clock and order
//! Simulated time is an integer count of nanoseconds. The base tick is `1e9 / rates.base_hz` ns; every
//! layer runs on the ticks that are multiples of `base_hz / layer_hz`. Within tick `k` at time
//! `t = k · T_base` the order is fixed:
//!
//! 1. **measure**: read the robot's measurement at `t`; if any layer runs this tick, estimate the
//!    measured CoM, DCM, ZMP and sole poses from it;
//! 2. **planner**: on events only (first tick; start of a new goal segment), replan from the measured
//!    soles (or at `rates.planner_hz` in `periodic` mode);
//! 3. **simplified layer** (every `base/simplified` ticks): plan sampled at `t`, DCM controller and
//!    ZMP-CoM controller;
//! 4. **whole-body layer** (every `base/wbc` ticks): plan feet and CoM height at `t`, simplified CoM and
//!    ZMP references → joint command, handed to the robot;
//! 5. **log** the state topics (every `base/log.state_hz`... on sim ticks) and the layer topics of the
//!    layers that ran;
//! 6. **end checks** (fall, goal reached and standing still, Ctrl-C/stop flag, duration);
//! 7. **plant**: the robot advances one period (every `base/sim` ticks) from `t` to `t + T_sim`.
//!
//! Each layer therefore sees the measurement of its own tick time and the latest outputs of the layers
//! above it (computed in the same tick when their ticks coincide). Nothing depends on wall-clock time
//! except the `*/timing` topics, the progress bar and, with `realtime`, the pacing itself.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use nalgebra::{DVector, Vector3};
use serde::Serialize;
use stride_model::{KinDyn, Model};

use crate::config::{ControlMode, Goal, PlannerMode, PlantKind, Scenario};
use crate::log::{
    FoxgloveQuaternion, FoxgloveTime, FoxgloveVector3, FrameTransform, FrameTransforms, LogError,
    LogOptions, LogStats, LogWriter, TopicId, FRAME_TRANSFORMS_SCHEMA,
};
use crate::records::{
    phase_name, simplified_output_record, EventRecord, IkOutputRecord, PlanSampleRecord,
    PlannerInputRecord, PoseRecord, StateRecord, TimingRecord, TsidOutputRecord, WbcInputRecord,
};
use crate::robot::{standing_state, IdealPlant, Robot};
use crate::sim_plant::SimPlant;
use crate::stack::{wrap_angle, Stack, StackError, Wbc};

/// Why a run could not start or stopped with an error.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// Configuration problem found while building.
    #[error(transparent)]
    Config(#[from] crate::config::ConfigError),
    /// The model could not be loaded.
    #[error("model {}: {source}", path.display())]
    Model {
        /// URDF path.
        path: PathBuf,
        /// Loader error.
        source: stride_model::ModelError,
    },
    /// A layer failed to build.
    #[error(transparent)]
    Stack(#[from] StackError),
    /// The robot failed to build.
    #[error(transparent)]
    Robot(#[from] crate::robot::RobotError),
    /// The log could not be written.
    #[error(transparent)]
    Log(#[from] LogError),
}

/// How a run ended.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Outcome {
    /// The scenario duration elapsed.
    DurationReached,
    /// The goal was reached and the robot stood still.
    GoalReached,
    /// The robot fell.
    Fell {
        /// Why (height, tilt, simulator).
        reason: String,
    },
    /// Ctrl-C (or the stop flag).
    Interrupted,
    /// A layer or the robot failed, or panicked.
    Error {
        /// The error.
        message: String,
    },
}

impl std::fmt::Display for Outcome {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Outcome::DurationReached => write!(f, "duration reached"),
            Outcome::GoalReached => write!(f, "goal reached, standing still"),
            Outcome::Fell { reason } => write!(f, "FELL ({reason})"),
            Outcome::Interrupted => write!(f, "interrupted"),
            Outcome::Error { message } => write!(f, "ERROR: {message}"),
        }
    }
}

/// Options of one run (the command line's).
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Log path (overrides the scenario's).
    pub output: Option<PathBuf>,
    /// Duration override \[s\].
    pub duration: Option<f64>,
    /// Pace at 1× wall-clock time.
    pub realtime: bool,
    /// Draw a progress bar (only when stderr is a terminal).
    pub progress: bool,
    /// Plant override.
    pub plant: Option<PlantKind>,
    /// Set from outside (Ctrl-C handler, tests) to stop the run; the log is closed properly.
    pub stop: Option<Arc<AtomicBool>>,
    /// Stop after this many base ticks (tests of interrupted runs).
    pub stop_after_ticks: Option<u64>,
    /// Do not write a log.
    pub no_log: bool,
}

/// Root-mean-square and maximum of a tracking error.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct ErrorStats {
    /// RMS \[m\].
    pub rms: f64,
    /// Max \[m\].
    pub max: f64,
    #[serde(skip)]
    sum_sq: f64,
    #[serde(skip)]
    n: u64,
}

impl ErrorStats {
    fn add(&mut self, e: f64) {
        self.sum_sq += e * e;
        self.n += 1;
        self.max = self.max.max(e);
        self.rms = (self.sum_sq / self.n as f64).sqrt();
    }
}

/// Percentiles of a layer's solve times \[s\].
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct SolveTimes {
    /// Median.
    pub p50: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Maximum.
    pub max: f64,
    /// Number of solves.
    pub count: usize,
}

impl SolveTimes {
    fn from(samples: &mut [f64]) -> Self {
        if samples.is_empty() {
            return Self::default();
        }
        samples.sort_by(f64::total_cmp);
        let q = |p: f64| samples[((samples.len() - 1) as f64 * p).round() as usize];
        Self {
            p50: q(0.5),
            p99: q(0.99),
            max: samples[samples.len() - 1],
            count: samples.len(),
        }
    }
}

/// The end-of-run summary.
#[derive(Debug, Clone, Serialize)]
pub struct RunSummary {
    /// Scenario name.
    pub scenario: String,
    /// Plant used.
    pub plant: String,
    /// How the run ended.
    pub outcome: Outcome,
    /// Simulated time \[s\].
    pub simulated_time: f64,
    /// Wall-clock time of the loop \[s\].
    pub wall_time: f64,
    /// Simulated / wall-clock time.
    pub real_time_factor: f64,
    /// Planar distance of the soles' mid-point from its start \[m\].
    pub distance: f64,
    /// Forward displacement (along the initial heading) / simulated time [m/s].
    pub mean_forward_speed: f64,
    /// Final planar position of the soles' mid-point \[m\] and heading \[deg\].
    pub final_pose: [f64; 3],
    /// Planar distance to the goal at the end \[m\] (pose/waypoint goals).
    pub goal_distance: Option<f64>,
    /// Heading error to the goal at the end \[deg\].
    pub goal_heading_error_deg: Option<f64>,
    /// Lowest base height relative to the initial one [-].
    pub min_base_height_fraction: f64,
    /// Largest torso tilt \[deg\].
    pub max_tilt_deg: f64,
    /// DCM tracking error (measured vs planned, planar) \[m\].
    pub dcm_error: ErrorStats,
    /// CoM tracking error (measured vs simplified-layer reference, 3D) \[m\].
    pub com_error: ErrorStats,
    /// ZMP tracking error (measured vs desired) \[m\], over ticks with a measurable ZMP.
    pub zmp_error: ErrorStats,
    /// Feet tracking error (measured vs planned sole positions, worst foot) \[m\].
    pub feet_error: ErrorStats,
    /// Whole-body QP solve times \[s\].
    pub wbc_solve_time: SolveTimes,
    /// Simplified-layer solve times \[s\] (MPC; 0 for the instantaneous controller).
    pub simplified_solve_time: SolveTimes,
    /// Whole-body ticks solved by the relaxed fallback QP.
    pub wbc_fallbacks: u64,
    /// Whole-body ticks that held the previous command.
    pub wbc_holds: u64,
    /// Simplified-layer ticks that held the previous references.
    pub simplified_holds: u64,
    /// Planner replans.
    pub replans: u64,
    /// Realtime mode: whole-body ticks that started late.
    pub deadline_misses: u64,
    /// Log file and counters.
    pub log: Option<(PathBuf, LogStats)>,
}

struct Topics {
    planner_input: TopicId,
    planner_references: TopicId,
    planner_footsteps: TopicId,
    simplified_input: TopicId,
    simplified_output: TopicId,
    simplified_timing: TopicId,
    wbc_input: TopicId,
    wbc_output: TopicId,
    wbc_timing: TopicId,
    sim_state: TopicId,
    sensors_feet: TopicId,
    sensors_imu: TopicId,
    tf: TopicId,
    tf_static: TopicId,
    tracking: TopicId,
    runner_timing: TopicId,
    events: TopicId,
    description: TopicId,
}

impl Topics {
    fn register(w: &mut LogWriter) -> Result<Self, LogError> {
        Ok(Self {
            description: w.topic("/robot/description", "stride.RobotDescription", None)?,
            planner_input: w.topic("/planner/input", "stride.planner.Input", None)?,
            planner_references: w.topic("/planner/references", "stride.planner.Sample", None)?,
            planner_footsteps: w.topic("/planner/footsteps", "stride.planner.Footsteps", None)?,
            simplified_input: w.topic("/simplified/input", "stride.simplified.Input", None)?,
            simplified_output: w.topic("/simplified/output", "stride.simplified.Output", None)?,
            simplified_timing: w.topic("/simplified/timing", "stride.Timing", None)?,
            wbc_input: w.topic("/wbc/input", "stride.wbc.Input", None)?,
            wbc_output: w.topic("/wbc/output", "stride.wbc.Output", None)?,
            wbc_timing: w.topic("/wbc/timing", "stride.Timing", None)?,
            sim_state: w.topic("/sim/state", "stride.sim.State", None)?,
            sensors_feet: w.topic("/sensors/feet", "stride.sensors.Feet", None)?,
            sensors_imu: w.topic("/sensors/imu", "stride.sensors.Imu", None)?,
            tf: w.topic(
                "/tf",
                "foxglove.FrameTransforms",
                Some(FRAME_TRANSFORMS_SCHEMA.to_string()),
            )?,
            tf_static: w.topic(
                "/tf_static",
                "foxglove.FrameTransforms",
                Some(FRAME_TRANSFORMS_SCHEMA.to_string()),
            )?,
            tracking: w.topic("/runner/tracking", "stride.runner.Tracking", None)?,
            runner_timing: w.topic("/runner/timing", "stride.runner.Timing", None)?,
            events: w.topic("/events", "stride.Event", None)?,
        })
    }
}

/// Topics whose content depends on wall-clock time (excluded from determinism comparisons).
pub const WALL_CLOCK_TOPICS: &[&str] = &["/simplified/timing", "/wbc/timing", "/runner/timing"];

#[derive(Serialize)]
struct RobotDescription<'a> {
    robot: &'a str,
    root_link: &'a str,
    joint_names: Vec<&'a str>,
    left_sole: &'a str,
    right_sole: &'a str,
    control_mode: ControlMode,
    plant: &'a str,
}

#[derive(Serialize)]
struct SimStateMsg<'a> {
    time: f64,
    #[serde(flatten)]
    state: StateRecord<'a>,
    joint_torques: &'a [f64],
}

#[derive(Serialize)]
struct FootMsg {
    in_contact: bool,
    force: [f64; 3],
    torque: [f64; 3],
    point: [f64; 3],
}

#[derive(Serialize)]
struct FeetMsg {
    time: f64,
    left: FootMsg,
    right: FootMsg,
}

#[derive(Serialize)]
struct ImuMsg {
    time: f64,
    orientation_xyzw: [f64; 4],
    angular_velocity: [f64; 3],
    linear_acceleration: [f64; 3],
}

#[derive(Serialize)]
struct TrackingMsg {
    time: f64,
    dcm_error: f64,
    com_error: f64,
    zmp_error: Option<f64>,
    feet_error: f64,
    measured_com: [f64; 3],
    measured_dcm: [f64; 2],
    measured_zmp: [f64; 2],
    base_height: f64,
    tilt_deg: f64,
}

#[derive(Serialize)]
struct RunnerTimingMsg {
    wall_time: f64,
    real_time_factor: f64,
    deadline_misses: u64,
}

#[derive(Serialize)]
struct FootstepMsg {
    foot: &'static str,
    position: [f64; 3],
    orientation_xyzw: [f64; 4],
    activation_time: f64,
    deactivation_time: Option<f64>,
}

#[derive(Serialize)]
struct FootstepsMsg {
    time: f64,
    footsteps: Vec<FootstepMsg>,
}

/// Git commit of the source tree, if known at build time or from `git` at run time.
pub fn git_commit() -> Option<String> {
    if let Some(c) = option_env!("STRIDE_GIT_COMMIT") {
        return Some(c.to_string());
    }
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = std::process::Command::new("git")
        .args(["rev-parse", "HEAD"])
        .current_dir(dir)
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
        .filter(|s| !s.is_empty())
}

/// Initial joint positions from the scenario (unknown joint names are configuration errors).
pub fn initial_joint_positions(
    scenario: &Scenario,
    model: &Model,
) -> Result<DVector<f64>, RunError> {
    let mut q = DVector::zeros(model.dof());
    for (name, v) in &scenario.config.robot.initial_joint_positions {
        let i = model.joint_index(name).ok_or_else(|| {
            scenario.invalid(
                &format!("robot.initial_joint_positions.{name}"),
                format!(
                    "the model has no joint `{name}`; expected one of: {}",
                    joint_list(model)
                ),
            )
        })?;
        q[i] = *v;
    }
    Ok(q)
}

fn joint_list(model: &Model) -> String {
    model
        .joints()
        .iter()
        .map(|j| j.name.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Loads the scenario's model.
pub fn load_model(scenario: &Scenario) -> Result<Arc<Model>, RunError> {
    Model::from_urdf_file(&scenario.urdf_path)
        .map(Arc::new)
        .map_err(|e| RunError::Model {
            path: scenario.urdf_path.clone(),
            source: e,
        })
}

/// Builds the plant of the scenario (or of the override).
pub fn build_robot(
    scenario: &Scenario,
    model: &Arc<Model>,
    plant: PlantKind,
) -> Result<Box<dyn Robot>, RunError> {
    let c = &scenario.config;
    let q0 = initial_joint_positions(scenario, model)?;
    let sole = |name: &str, key: &str| {
        model.frame_id(name).ok_or_else(|| {
            RunError::Config(scenario.invalid(key, format!("the model has no frame `{name}`")))
        })
    };
    let soles = [
        sole(&c.robot.left_sole, "robot.left_sole")?,
        sole(&c.robot.right_sole, "robot.right_sole")?,
    ];
    Ok(match plant {
        PlantKind::Simulator => Box::new(SimPlant::new(
            Arc::clone(model),
            scenario.sim_config(),
            c.scenario.control_mode,
            &q0,
            soles,
        )?),
        PlantKind::Ideal => {
            let state = standing_state(model, &q0, soles[0], soles[1])?;
            let period = 1_000_000_000 / u64::from(c.rates.sim_hz);
            Box::new(IdealPlant::new(
                Arc::clone(model),
                period,
                soles[0],
                soles[1],
                &state,
            )?)
        }
    })
}

/// Default log path of a scenario.
pub fn default_log_path(scenario: &Scenario) -> PathBuf {
    let p = &scenario.config.log.path;
    if p.as_os_str().is_empty() {
        PathBuf::from(format!("{}.mcap", scenario.config.scenario.name))
    } else {
        p.clone()
    }
}

struct Loop<'a> {
    scenario: &'a Scenario,
    robot: Box<dyn Robot>,
    stack: Stack,
    log: Option<(&'a mut LogWriter, Topics)>,
    tf_kd: KinDyn,
    tf_msg: FrameTransforms,
    tf_frames: Vec<stride_model::FrameId>,
    /// Frames rigidly attached to a body (merged fixed links, sensors), relative to their body: written
    /// on `/tf_static` at the first state tick and then every `tf_static_every` state ticks.
    tf_static_msg: FrameTransforms,
    tf_static_every: u64,
    state_ticks: u64,
    wbc_times: Vec<f64>,
    simplified_times: Vec<f64>,
    summary: RunSummary,
    initial_base_height: f64,
    start_mid: [f64; 3],
    standstill_since: Option<u64>,
    last_phase: &'static str,
}

fn mid_pose(soles: &[nalgebra::Isometry3<f64>; 2]) -> [f64; 3] {
    let p = (soles[0].translation.vector + soles[1].translation.vector) * 0.5;
    [p.x, p.y, crate::stack::soles_heading(&soles[0], &soles[1])]
}

impl Loop<'_> {
    fn write<T: Serialize + ?Sized>(
        &mut self,
        pick: impl Fn(&Topics) -> TopicId,
        t: u64,
        v: &T,
    ) -> Result<(), LogError> {
        if let Some((w, topics)) = self.log.as_mut() {
            w.write(pick(topics), t, v)?;
        }
        Ok(())
    }

    fn event(&mut self, t: u64, kind: &str, detail: String) -> Result<(), LogError> {
        tracing::info!(time = t as f64 * 1e-9, kind, "{detail}");
        let e = EventRecord {
            time: t as f64 * 1e-9,
            kind: kind.into(),
            detail,
        };
        self.write(|tp| tp.events, t, &e)
    }

    fn log_state(&mut self, t: u64) -> Result<(), LogError> {
        if self.log.is_none() {
            return Ok(());
        }
        let m = self.robot.measurement();
        let time = t as f64 * 1e-9;
        let state_msg = SimStateMsg {
            time,
            state: StateRecord::from_state(&m.state),
            joint_torques: m.joint_torques.as_slice(),
        };
        let foot = |f: &crate::robot::FootMeasurement| FootMsg {
            in_contact: f.in_contact,
            force: [f.wrench[0], f.wrench[1], f.wrench[2]],
            torque: [f.wrench[3], f.wrench[4], f.wrench[5]],
            point: [f.point.x, f.point.y, f.point.z],
        };
        let feet = FeetMsg {
            time,
            left: foot(&m.feet[0]),
            right: foot(&m.feet[1]),
        };
        let q = m.imu.orientation.coords;
        let imu = ImuMsg {
            time,
            orientation_xyzw: [q.x, q.y, q.z, q.w],
            angular_velocity: m.imu.angular_velocity.into(),
            linear_acceleration: m.imu.linear_acceleration.into(),
        };
        // /tf: world → every body (the links moved by joints, and the root), from the measured state; the
        // frames rigidly attached to them go to /tf_static.
        let _ = self.tf_kd.set_state(&m.state);
        let stamp = FoxgloveTime::from_ns(t);
        for (i, f) in self.tf_frames.iter().enumerate() {
            let p = self.tf_kd.frame_pose(*f);
            let tr = &mut self.tf_msg.transforms[i];
            tr.timestamp = stamp;
            tr.translation = FoxgloveVector3 {
                x: p.translation.x,
                y: p.translation.y,
                z: p.translation.z,
            };
            let c = p.rotation.coords;
            tr.rotation = FoxgloveQuaternion {
                x: c.x,
                y: c.y,
                z: c.z,
                w: c.w,
            };
        }
        if let Some((w, topics)) = self.log.as_mut() {
            w.write(topics.sim_state, t, &state_msg)?;
            w.write(topics.sensors_feet, t, &feet)?;
            w.write(topics.sensors_imu, t, &imu)?;
            w.write(topics.tf, t, &self.tf_msg)?;
            if self.state_ticks % self.tf_static_every == 0 {
                let stamp = FoxgloveTime::from_ns(t);
                for tr in &mut self.tf_static_msg.transforms {
                    tr.timestamp = stamp;
                }
                w.write(topics.tf_static, t, &self.tf_static_msg)?;
            }
        }
        self.state_ticks += 1;
        Ok(())
    }

    /// Tracking errors at a simplified tick (after the layer ran).
    fn track(&mut self, t: u64) -> Result<(), LogError> {
        let s = &self.stack.plan_sample;
        let m = &self.stack.measured;
        let dcm_err = (m.dcm - s.dcm_position.xy()).norm();
        let so = &self.stack.simplified_output;
        let com_ref = Vector3::new(so.com_position.x, so.com_position.y, s.com_position.z);
        let com_err = (m.com - com_ref).norm();
        let zmp_err = m.zmp_from_wrenches.then(|| (m.zmp - so.desired_zmp).norm());
        let feet_err = (m.soles[0].translation.vector - s.left.pose.translation.vector)
            .norm()
            .max((m.soles[1].translation.vector - s.right.pose.translation.vector).norm());
        self.summary.dcm_error.add(dcm_err);
        self.summary.com_error.add(com_err);
        if let Some(z) = zmp_err {
            self.summary.zmp_error.add(z);
        }
        self.summary.feet_error.add(feet_err);
        let msg = TrackingMsg {
            time: t as f64 * 1e-9,
            dcm_error: dcm_err,
            com_error: com_err,
            zmp_error: zmp_err,
            feet_error: feet_err,
            measured_com: m.com.into(),
            measured_dcm: m.dcm.into(),
            measured_zmp: m.zmp.into(),
            base_height: m.base_height,
            tilt_deg: m.tilt.to_degrees(),
        };
        self.write(|tp| tp.tracking, t, &msg)
    }

    /// Fall / goal checks after the layers ran (needs a fresh estimate).
    fn check_end(&mut self, t: u64) -> Option<Outcome> {
        let e = &self.scenario.config.end;
        let m = self.stack.measured;
        let frac = m.base_height / self.initial_base_height;
        self.summary.min_base_height_fraction = self.summary.min_base_height_fraction.min(frac);
        self.summary.max_tilt_deg = self.summary.max_tilt_deg.max(m.tilt.to_degrees());
        if frac < e.fall_height_fraction {
            return Some(Outcome::Fell {
                reason: format!(
                    "base height {:.3} m is below {:.0} % of the initial {:.3} m",
                    m.base_height,
                    e.fall_height_fraction * 100.0,
                    self.initial_base_height
                ),
            });
        }
        if m.tilt.to_degrees() > e.fall_tilt_deg {
            return Some(Outcome::Fell {
                reason: format!(
                    "torso tilt {:.1}° exceeds {:.1}°",
                    m.tilt.to_degrees(),
                    e.fall_tilt_deg
                ),
            });
        }
        if self.robot.measurement().fallen {
            return Some(Outcome::Fell {
                reason: "the simulator's fall detector fired".into(),
            });
        }
        if e.stop_at_goal && self.stack.plan_finished(t) {
            let goal_ok = match goal_pose(&self.scenario.config.goal) {
                Some(g) => {
                    let p = mid_pose(&m.soles);
                    let d = ((p[0] - g[0]).powi(2) + (p[1] - g[1]).powi(2)).sqrt();
                    d <= e.goal_position_tolerance
                        && wrap_angle(p[2] - g[2]).abs().to_degrees()
                            <= e.goal_heading_tolerance_deg
                }
                None => false,
            };
            if goal_ok && m.com_velocity.xy().norm() < e.standstill_speed {
                let since = *self.standstill_since.get_or_insert(t);
                if (t - since) as f64 * 1e-9 >= e.standstill_time {
                    return Some(Outcome::GoalReached);
                }
            } else {
                self.standstill_since = None;
            }
        }
        None
    }
}

/// Final planar goal pose (x, y, heading rad) of pose and waypoint goals.
pub fn goal_pose(goal: &Goal) -> Option<[f64; 3]> {
    match goal {
        Goal::Pose(p) => Some([p.x, p.y, p.heading_deg.to_radians()]),
        Goal::Waypoints { points } => points
            .last()
            .map(|p| [p.x, p.y, p.heading_deg.to_radians()]),
        _ => None,
    }
}

/// Runs a scenario to its end. The log (if any) is finished whatever happens, panics in a layer
/// included; the outcome says how the run ended.
pub fn run_scenario(scenario: &Scenario, options: &RunOptions) -> Result<RunSummary, RunError> {
    let model = load_model(scenario)?;
    let plant = options.plant.unwrap_or(scenario.config.scenario.plant);
    let robot = build_robot(scenario, &model, plant)?;
    run_with_robot(scenario, options, robot)
}

/// Runs a scenario against any [`Robot`] (a real robot interface, another simulator, a test double).
/// The robot's model must be the scenario's and its period `1 / rates.sim_hz`.
pub fn run_with_robot(
    scenario: &Scenario,
    options: &RunOptions,
    robot: Box<dyn Robot>,
) -> Result<RunSummary, RunError> {
    let c = &scenario.config;
    let model = Arc::clone(robot.model());
    let initial = robot.measurement().state.clone();
    let stack = Stack::new(scenario, Arc::clone(&model), &initial)?;
    let duration = options.duration.unwrap_or(c.scenario.duration);
    let base_ns = 1_000_000_000 / u64::from(c.rates.base_hz);
    let every = |hz: u32| u64::from(c.rates.base_hz / hz);
    let sim_every = every(c.rates.sim_hz);
    if robot.period_ns() != sim_every * base_ns {
        return Err(RunError::Robot(crate::robot::RobotError(format!(
            "the robot's period {} ns differs from rates.sim_hz ({} ns)",
            robot.period_ns(),
            sim_every * base_ns
        ))));
    }
    let wbc_every = every(c.rates.wbc_hz);
    let simplified_every = every(c.rates.simplified_hz);
    let planner_every =
        (c.rates.planner_mode == PlannerMode::Periodic).then(|| every(c.rates.planner_hz));
    let state_every = u64::from(c.rates.base_hz / c.log.state_hz.max(1)).max(sim_every);
    let total_ticks = (duration * 1e9 / base_ns as f64).round() as u64;

    // The log.
    let log_path = options
        .output
        .clone()
        .unwrap_or_else(|| default_log_path(scenario));
    let mut writer = if c.log.enabled && !options.no_log {
        Some(LogWriter::create(
            &log_path,
            &LogOptions {
                compression: c.log.compression,
                chunk_size: c.log.chunk_size,
                queue_capacity: c.log.queue_capacity,
            },
        )?)
    } else {
        None
    };
    let mut log = None;
    if let Some(w) = writer.as_mut() {
        let topics = Topics::register(w)?;
        let urdf = std::fs::read(&scenario.urdf_path).unwrap_or_default();
        w.attach("model.urdf", "application/xml", urdf)?;
        w.attach(
            "scenario.toml",
            "application/toml",
            scenario.merged_toml().into_bytes(),
        )?;
        let mut prov = std::collections::BTreeMap::new();
        prov.insert(
            "stride_version".into(),
            env!("CARGO_PKG_VERSION").to_string(),
        );
        prov.insert(
            "git_commit".into(),
            git_commit().unwrap_or_else(|| "unknown".into()),
        );
        prov.insert("scenario".into(), c.scenario.name.clone());
        prov.insert(
            "config_files".into(),
            scenario
                .sources
                .files
                .iter()
                .map(|f| f.path.display().to_string())
                .collect::<Vec<_>>()
                .join(", "),
        );
        prov.insert("plant".into(), robot.name().to_string());
        prov.insert("base_hz".into(), c.rates.base_hz.to_string());
        w.metadata("stride", prov)?;
        log = Some((w, topics));
    }

    // /tf carries the bodies (moved by joints), /tf_static the frames rigidly attached to them (iCub's
    // URDF has 214 frames on 33 bodies): the static part is written once a second, not at every state tick.
    let frames = model.frames();
    let tf_frames: Vec<_> = frames
        .iter()
        .filter(|f| f.kind == stride_model::FrameKind::Body)
        .filter_map(|f| model.frame_id(&f.name))
        .collect();
    let tf_msg = FrameTransforms {
        transforms: tf_frames
            .iter()
            .map(|f| FrameTransform {
                parent_frame_id: "world".into(),
                child_frame_id: model.frame_name(*f).to_string(),
                ..FrameTransform::default()
            })
            .collect(),
    };
    let tf_static_msg = FrameTransforms {
        transforms: frames
            .iter()
            .filter(|f| f.kind != stride_model::FrameKind::Body)
            .map(|f| {
                let (p, q) = (f.placement.translation.vector, f.placement.rotation.coords);
                FrameTransform {
                    parent_frame_id: model.bodies()[f.link].name.clone(),
                    child_frame_id: f.name.clone(),
                    translation: FoxgloveVector3 {
                        x: p.x,
                        y: p.y,
                        z: p.z,
                    },
                    rotation: FoxgloveQuaternion {
                        x: q.x,
                        y: q.y,
                        z: q.z,
                        w: q.w,
                    },
                    ..FrameTransform::default()
                }
            })
            .collect(),
    };
    let tf_static_every = u64::from(c.log.state_hz.max(1));
    let wbc_ticks = (total_ticks / wbc_every + 2) as usize;
    let simplified_ticks = (total_ticks / simplified_every + 2) as usize;
    let mut lp = Loop {
        scenario,
        stack,
        log,
        tf_kd: KinDyn::new(Arc::clone(&model)),
        tf_msg,
        tf_frames,
        tf_static_msg,
        tf_static_every,
        state_ticks: 0,
        wbc_times: Vec::with_capacity(wbc_ticks),
        simplified_times: Vec::with_capacity(simplified_ticks),
        summary: RunSummary {
            scenario: c.scenario.name.clone(),
            plant: robot.name().to_string(),
            outcome: Outcome::DurationReached,
            simulated_time: 0.0,
            wall_time: 0.0,
            real_time_factor: 0.0,
            distance: 0.0,
            mean_forward_speed: 0.0,
            final_pose: [0.0; 3],
            goal_distance: None,
            goal_heading_error_deg: None,
            min_base_height_fraction: 1.0,
            max_tilt_deg: 0.0,
            dcm_error: ErrorStats::default(),
            com_error: ErrorStats::default(),
            zmp_error: ErrorStats::default(),
            feet_error: ErrorStats::default(),
            wbc_solve_time: SolveTimes::default(),
            simplified_solve_time: SolveTimes::default(),
            wbc_fallbacks: 0,
            wbc_holds: 0,
            simplified_holds: 0,
            replans: 0,
            deadline_misses: 0,
            log: None,
        },
        initial_base_height: initial.base_pose.translation.z,
        start_mid: [0.0; 3],
        standstill_since: None,
        last_phase: "",
        robot,
    };
    if let Some((w, topics)) = lp.log.as_mut() {
        let desc = RobotDescription {
            robot: model.name(),
            root_link: model.root_link(),
            joint_names: model.joints().iter().map(|j| j.name.as_str()).collect(),
            left_sole: &c.robot.left_sole,
            right_sole: &c.robot.right_sole,
            control_mode: c.scenario.control_mode,
            plant: lp.summary.plant.as_str(),
        };
        w.write(topics.description, 0, &desc)?;
    }
    lp.stack.estimate(lp.robot.measurement())?;
    lp.start_mid = mid_pose(&lp.stack.measured.soles);

    let progress = progress_bar(options.progress, duration);
    let wall_start = Instant::now();
    let stop = options.stop.clone();
    let realtime = options.realtime;

    // The loop proper, inside catch_unwind: a panic in a layer ends the run with an error outcome and the
    // log is still finished below (the writer lives outside the closure's unwinding).
    let result = catch_unwind(AssertUnwindSafe(|| -> Result<Outcome, String> {
        let mut k: u64 = 0;
        loop {
            let t = k * base_ns;
            if k >= total_ticks {
                return Ok(Outcome::DurationReached);
            }
            if stop.as_ref().is_some_and(|s| s.load(Ordering::Relaxed))
                || options.stop_after_ticks.is_some_and(|n| k >= n)
            {
                return Ok(Outcome::Interrupted);
            }
            let run_simplified = k % simplified_every == 0;
            let run_wbc = k % wbc_every == 0;
            let run_planner = lp.stack.planner_due(t) || planner_every.is_some_and(|e| k % e == 0);
            let any = run_simplified || run_wbc || run_planner;
            // 1. measure
            if any {
                let m = lp.robot.measurement();
                lp.stack.estimate(m).map_err(|e| e.to_string())?;
            }
            // 2. planner (events)
            if run_planner && lp.stack.planner_tick(t).map_err(|e| e.to_string())? {
                let rec = PlannerInputRecord::from_input(t, &lp.stack.planner_input);
                lp.write(|tp| tp.planner_input, t, &rec)
                    .map_err(|e| e.to_string())?;
                if let Some(plan) = lp.stack.planner.plan() {
                    let end_time = plan.end_time;
                    let steps = FootstepsMsg {
                        time: t as f64 * 1e-9,
                        footsteps: plan
                            .footsteps()
                            .iter()
                            .map(|f| {
                                let p = PoseRecord::from_iso(&f.pose);
                                FootstepMsg {
                                    foot: match f.foot {
                                        stride_planner::Foot::Left => "left",
                                        stride_planner::Foot::Right => "right",
                                    },
                                    position: p.position,
                                    orientation_xyzw: p.orientation_xyzw,
                                    activation_time: f.activation_time,
                                    deactivation_time: f.deactivation_time,
                                }
                            })
                            .collect(),
                    };
                    let n = steps.footsteps.len();
                    lp.write(|tp| tp.planner_footsteps, t, &steps)
                        .map_err(|e| e.to_string())?;
                    let kind = if k == 0 { "start" } else { "replan" };
                    lp.event(
                        t,
                        kind,
                        format!("plan with {n} contacts, ends at {end_time:.2} s"),
                    )
                    .map_err(|e| e.to_string())?;
                }
            }
            // 3. simplified
            if run_simplified {
                let held = lp.stack.simplified_tick(t).map_err(|e| e.to_string())?;
                let rec = PlanSampleRecord::from_sample(&lp.stack.plan_sample);
                lp.write(|tp| tp.planner_references, t, &rec)
                    .map_err(|e| e.to_string())?;
                let input = &lp.stack.simplified_input;
                if let Some((w, topics)) = lp.log.as_mut() {
                    w.write(topics.simplified_input, t, input)
                        .map_err(|e| e.to_string())?;
                    let out = simplified_output_record(&lp.stack.simplified_output);
                    w.write(topics.simplified_output, t, &out)
                        .map_err(|e| e.to_string())?;
                    let st = lp.stack.simplified_output.diagnostics.solve_time;
                    w.write(
                        topics.simplified_timing,
                        t,
                        &TimingRecord {
                            solve_time: st,
                            tick_time: st,
                        },
                    )
                    .map_err(|e| e.to_string())?;
                }
                lp.simplified_times
                    .push(lp.stack.simplified_output.diagnostics.solve_time);
                if let Some(msg) = held {
                    lp.event(
                        t,
                        "hold",
                        format!("simplified layer held its references: {msg}"),
                    )
                    .map_err(|e| e.to_string())?;
                }
                lp.track(t).map_err(|e| e.to_string())?;
            }
            // 4. whole-body
            if run_wbc {
                let fallbacks = lp.stack.counters.wbc_fallbacks;
                let m = lp.robot.measurement();
                lp.stack.wbc_tick(t, m).map_err(|e| e.to_string())?;
                let (solve, tick) = match &lp.stack.wbc {
                    Wbc::Ik(ik) => {
                        let r = ik_output(ik).report;
                        (r.solve_time, r.tick_time)
                    }
                    Wbc::Tsid(ts) => {
                        let r = tsid_output(ts).report;
                        (r.solve_time, r.tick_time)
                    }
                };
                lp.wbc_times.push(solve);
                if let Some((w, topics)) = lp.log.as_mut() {
                    let rec = WbcInputRecord::from_input(t, &lp.stack.wbc_input);
                    w.write(topics.wbc_input, t, &rec)
                        .map_err(|e| e.to_string())?;
                    match &lp.stack.wbc {
                        Wbc::Ik(ik) => {
                            w.write(topics.wbc_output, t, &IkOutputRecord::new(ik_output(ik)))
                        }
                        Wbc::Tsid(ts) => w.write(
                            topics.wbc_output,
                            t,
                            &TsidOutputRecord::new(tsid_output(ts)),
                        ),
                    }
                    .map_err(|e| e.to_string())?;
                    w.write(
                        topics.wbc_timing,
                        t,
                        &TimingRecord {
                            solve_time: solve,
                            tick_time: tick,
                        },
                    )
                    .map_err(|e| e.to_string())?;
                }
                if lp.stack.counters.wbc_fallbacks > fallbacks {
                    lp.event(
                        t,
                        "fallback",
                        "whole-body QP solved by the relaxed fallback".into(),
                    )
                    .map_err(|e| e.to_string())?;
                }
                let phase = phase_name(&lp.stack.plan_sample.phase);
                if phase != lp.last_phase {
                    lp.last_phase = phase;
                    lp.event(t, "phase", phase.to_string())
                        .map_err(|e| e.to_string())?;
                }
                lp.robot
                    .command(&lp.stack.command)
                    .map_err(|e| e.to_string())?;
                if realtime {
                    let target = Duration::from_nanos(t);
                    let now = wall_start.elapsed();
                    if now < target {
                        std::thread::sleep(target - now);
                    } else if now > target + Duration::from_nanos(wbc_every * base_ns) {
                        lp.summary.deadline_misses += 1;
                    }
                }
            }
            // 5. state topics
            if k % state_every == 0 {
                lp.log_state(t).map_err(|e| e.to_string())?;
                let wall = wall_start.elapsed().as_secs_f64();
                let rtf = if wall > 0.0 {
                    t as f64 * 1e-9 / wall
                } else {
                    0.0
                };
                let misses = lp.summary.deadline_misses;
                lp.write(
                    |tp| tp.runner_timing,
                    t,
                    &RunnerTimingMsg {
                        wall_time: wall,
                        real_time_factor: rtf,
                        deadline_misses: misses,
                    },
                )
                .map_err(|e| e.to_string())?;
                if let Some(pb) = progress.as_ref() {
                    let mid = mid_pose(&lp.stack.measured.soles);
                    let d = ((mid[0] - lp.start_mid[0]).powi(2)
                        + (mid[1] - lp.start_mid[1]).powi(2))
                    .sqrt();
                    pb.set_position(t / 1_000_000);
                    pb.set_message(format!("{:.2} m  {:.1}x real time", d, rtf));
                }
            }
            // 6. end checks
            if run_wbc || run_simplified {
                if let Some(o) = lp.check_end(t) {
                    return Ok(o);
                }
            }
            // 7. plant
            if k % sim_every == 0 {
                lp.robot.advance().map_err(|e| e.to_string())?;
            }
            k += 1;
            lp.summary.simulated_time = k as f64 * base_ns as f64 * 1e-9;
        }
    }));
    let outcome = match result {
        Ok(Ok(o)) => o,
        Ok(Err(message)) => Outcome::Error { message },
        Err(panic) => Outcome::Error {
            message: format!(
                "panic in the loop: {}",
                panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_else(|| "unknown payload".into())
            ),
        },
    };
    if let Some(pb) = progress {
        pb.finish_and_clear();
    }
    let wall = wall_start.elapsed().as_secs_f64();
    let t_end_ns = (lp.summary.simulated_time * 1e9).round() as u64;
    let _ = lp.event(t_end_ns, "end", outcome.to_string());
    // Summary.
    let _ = lp.stack.estimate(lp.robot.measurement());
    let mid = mid_pose(&lp.stack.measured.soles);
    let s = &mut lp.summary;
    s.outcome = outcome;
    s.wall_time = wall;
    s.real_time_factor = if wall > 0.0 {
        s.simulated_time / wall
    } else {
        0.0
    };
    let dx = mid[0] - lp.start_mid[0];
    let dy = mid[1] - lp.start_mid[1];
    s.distance = (dx * dx + dy * dy).sqrt();
    let h = lp.start_mid[2];
    s.mean_forward_speed = if s.simulated_time > 0.0 {
        (dx * h.cos() + dy * h.sin()) / s.simulated_time
    } else {
        0.0
    };
    s.final_pose = [mid[0], mid[1], mid[2].to_degrees()];
    if let Some(g) = goal_pose(&c.goal) {
        s.goal_distance = Some(((mid[0] - g[0]).powi(2) + (mid[1] - g[1]).powi(2)).sqrt());
        s.goal_heading_error_deg = Some(wrap_angle(mid[2] - g[2]).to_degrees());
    }
    s.wbc_solve_time = SolveTimes::from(&mut lp.wbc_times);
    s.simplified_solve_time = SolveTimes::from(&mut lp.simplified_times);
    s.wbc_fallbacks = lp.stack.counters.wbc_fallbacks;
    s.wbc_holds = lp.stack.counters.wbc_holds;
    s.simplified_holds = lp.stack.counters.simplified_holds;
    s.replans = lp.stack.counters.replans;
    let mut summary = lp.summary.clone();
    drop(lp);
    if let Some(mut w) = writer {
        let stats = w.finish()?;
        summary.log = Some((log_path, stats));
    }
    Ok(summary)
}

fn ik_output(ik: &stride_wbc::QpIk) -> &stride_wbc::IkOutput {
    ik.output()
}

fn tsid_output(t: &stride_wbc::Tsid) -> &stride_wbc::TsidOutput {
    t.output()
}

fn progress_bar(enabled: bool, duration: f64) -> Option<indicatif::ProgressBar> {
    use std::io::IsTerminal;
    if !enabled || !std::io::stderr().is_terminal() {
        return None;
    }
    let pb = indicatif::ProgressBar::new((duration * 1000.0) as u64);
    let style =
        indicatif::ProgressStyle::with_template("{bar:40} {pos:>6}/{len} ms simulated  {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar());
    pb.set_style(style);
    Some(pb)
}

impl RunSummary {
    /// The summary as printed at the end of `stride run`.
    pub fn render(&self) -> String {
        let mut s = String::new();
        use std::fmt::Write as _;
        let _ = writeln!(
            s,
            "scenario {} on the {} plant: {}",
            self.scenario, self.plant, self.outcome
        );
        let _ = writeln!(
            s,
            "  simulated {:.2} s in {:.2} s wall clock: {:.1}x real time",
            self.simulated_time, self.wall_time, self.real_time_factor
        );
        let _ = writeln!(
            s,
            "  walked {:.3} m, mean forward speed {:.3} m/s, final pose x {:.3} m y {:.3} m heading {:.1}°",
            self.distance, self.mean_forward_speed, self.final_pose[0], self.final_pose[1], self.final_pose[2]
        );
        if let (Some(d), Some(h)) = (self.goal_distance, self.goal_heading_error_deg) {
            let _ = writeln!(s, "  goal: {:.3} m away, heading error {:.1}°", d, h);
        }
        let _ = writeln!(
            s,
            "  lowest base height {:.0} % of initial, largest torso tilt {:.1}°",
            self.min_base_height_fraction * 100.0,
            self.max_tilt_deg
        );
        let _ = writeln!(s, "  tracking        RMS [mm]   max [mm]");
        for (name, e) in [
            ("DCM", &self.dcm_error),
            ("CoM", &self.com_error),
            ("ZMP", &self.zmp_error),
            ("feet", &self.feet_error),
        ] {
            let _ = writeln!(
                s,
                "    {:<10} {:>10.1} {:>10.1}",
                name,
                e.rms * 1e3,
                e.max * 1e3
            );
        }
        let _ = writeln!(
            s,
            "  solve time      p50 [ms]   p99 [ms]   max [ms]   solves"
        );
        for (name, t) in [
            ("whole-body", &self.wbc_solve_time),
            ("simplified", &self.simplified_solve_time),
        ] {
            let _ = writeln!(
                s,
                "    {:<10} {:>10.3} {:>10.3} {:>10.3} {:>8}",
                name,
                t.p50 * 1e3,
                t.p99 * 1e3,
                t.max * 1e3,
                t.count
            );
        }
        let _ = writeln!(
            s,
            "  QP fallbacks {}, held commands {}, simplified holds {}, replans {}, deadline misses {}",
            self.wbc_fallbacks, self.wbc_holds, self.simplified_holds, self.replans, self.deadline_misses
        );
        if let Some((p, st)) = &self.log {
            let _ = writeln!(
                s,
                "  log: {} ({} messages, {:.1} MB, writer waits {})",
                p.display(),
                st.messages,
                st.bytes as f64 / 1e6,
                st.stalls
            );
        }
        s
    }
}
