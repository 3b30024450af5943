//! The log sink of a run: registers the topics, writes what the scheduler hands it, and stores the
//! config, the URDF and the provenance. Message types are in [`crate::records`]; the MCAP writer (a
//! background thread with preallocated buffers) is [`crate::log::LogWriter`].

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Serialize;
use stride_model::{FrameId, FrameKind, KinDyn, Model};

use crate::config::Scenario;
use crate::log::{
    FoxgloveQuaternion, FoxgloveTime, FoxgloveVector3, FrameTransform, FrameTransforms, LogError,
    LogOptions, LogStats, LogWriter, TopicId, FRAME_TRANSFORMS_SCHEMA,
};
use crate::log_json::Json;
use crate::records::{
    simplified_output_record, ContactsMsg, DiagnosisMsg, EstimationMsg, EventRecord, FeetMsg,
    FootMsg, FootstepMsg, FootstepsMsg, FtMsg, GroundEstimateRecord, IkOutputRecord, ImuMsg,
    PlanSampleRecord, PlannerInputRecord, PoseRecord, RobotDescription, RunnerTimingMsg,
    SimStateMsg, StateRecord, TimingRecord, TrackingMsg, TsidOutputRecord, WbcInputRecord,
};
use crate::robot::Measurement;
use crate::stack::{Stack, Wbc};
use crate::summary::RunSummary;
use stride_estimation::EstimatorOutput;

/// Topics whose content depends on wall-clock time (excluded from determinism comparisons).
pub const WALL_CLOCK_TOPICS: &[&str] = &["/simplified/timing", "/wbc/timing", "/runner/timing"];

struct Topics {
    description: TopicId,
    planner_input: TopicId,
    planner_references: TopicId,
    planner_footsteps: TopicId,
    planner_adjusted_footsteps: TopicId,
    simplified_input: TopicId,
    simplified_output: TopicId,
    simplified_timing: TopicId,
    wbc_input: TopicId,
    wbc_output: TopicId,
    wbc_timing: TopicId,
    wbc_ground_estimate: TopicId,
    sim_state: TopicId,
    sensors_feet: TopicId,
    sensors_imu: TopicId,
    sensors_ft: TopicId,
    estimation_state: TopicId,
    tf: TopicId,
    tf_static: TopicId,
    tracking: TopicId,
    diagnosis: TopicId,
    runner_timing: TopicId,
    events: TopicId,
}

impl Topics {
    fn register(w: &mut LogWriter) -> Result<Self, LogError> {
        let tf_schema = || Some(FRAME_TRANSFORMS_SCHEMA.to_string());
        Ok(Self {
            description: w.topic("/robot/description", "stride.RobotDescription", None)?,
            planner_input: w.topic("/planner/input", "stride.planner.Input", None)?,
            planner_references: w.topic("/planner/references", "stride.planner.Sample", None)?,
            planner_footsteps: w.topic("/planner/footsteps", "stride.planner.Footsteps", None)?,
            planner_adjusted_footsteps: w.topic(
                "/planner/adjusted_footsteps",
                "stride.planner.AdjustedFootstep",
                None,
            )?,
            simplified_input: w.topic("/simplified/input", "stride.simplified.Input", None)?,
            simplified_output: w.topic("/simplified/output", "stride.simplified.Output", None)?,
            simplified_timing: w.topic("/simplified/timing", "stride.Timing", None)?,
            wbc_input: w.topic("/wbc/input", "stride.wbc.Input", None)?,
            wbc_output: w.topic("/wbc/output", "stride.wbc.Output", None)?,
            wbc_timing: w.topic("/wbc/timing", "stride.Timing", None)?,
            wbc_ground_estimate: w.topic(
                "/wbc/ground_estimate",
                "stride.wbc.GroundEstimate",
                None,
            )?,
            sim_state: w.topic("/sim/state", "stride.sim.State", None)?,
            sensors_feet: w.topic("/sensors/feet", "stride.sensors.Feet", None)?,
            sensors_imu: w.topic("/sensors/imu", "stride.sensors.Imu", None)?,
            sensors_ft: w.topic("/sensors/ft", "stride.sensors.ForceTorque", None)?,
            estimation_state: w.topic("/estimation/state", "stride.estimation.State", None)?,
            tf: w.topic("/tf", "foxglove.FrameTransforms", tf_schema())?,
            tf_static: w.topic("/tf_static", "foxglove.FrameTransforms", tf_schema())?,
            tracking: w.topic("/runner/tracking", "stride.runner.Tracking", None)?,
            diagnosis: w.topic("/runner/diagnosis", "stride.runner.Diagnosis", None)?,
            runner_timing: w.topic("/runner/timing", "stride.runner.Timing", None)?,
            events: w.topic("/events", "stride.Event", None)?,
        })
    }
}

/// `/tf` and `/tf_static`: the bodies (moved by joints) at every state tick, the frames rigidly attached
/// to them (merged fixed links, sensors; iCub's URDF has 214 frames on 33 bodies) once a second.
struct Transforms {
    bodies: Vec<FrameId>,
    moving: FrameTransforms,
    attached: FrameTransforms,
    attached_every: u64,
    state_ticks: u64,
}

impl Transforms {
    fn new(model: &Model, state_hz: u32) -> Self {
        let frames = model.frames();
        let bodies: Vec<_> = frames
            .iter()
            .filter(|f| f.kind == FrameKind::Body)
            .filter_map(|f| model.frame_id(&f.name))
            .collect();
        let moving = FrameTransforms {
            transforms: bodies
                .iter()
                .map(|f| FrameTransform {
                    parent_frame_id: "world".into(),
                    child_frame_id: model.frame_name(*f).to_string(),
                    ..FrameTransform::default()
                })
                .collect(),
        };
        let attached = FrameTransforms {
            transforms: frames
                .iter()
                .filter(|f| f.kind != FrameKind::Body)
                .map(|f| FrameTransform {
                    parent_frame_id: model.bodies()[f.link].name.clone(),
                    child_frame_id: f.name.clone(),
                    translation: vector(&f.placement.translation.vector),
                    rotation: quaternion(&f.placement.rotation),
                    ..FrameTransform::default()
                })
                .collect(),
        };
        Self {
            bodies,
            moving,
            attached,
            attached_every: u64::from(state_hz.max(1)),
            state_ticks: 0,
        }
    }

    /// Fills `/tf` from `kd` (set to the measured state).
    fn update(&mut self, kd: &KinDyn, stamp: FoxgloveTime) {
        for (tr, f) in self.moving.transforms.iter_mut().zip(&self.bodies) {
            let p = kd.frame_pose(*f);
            tr.timestamp = stamp;
            tr.translation = vector(&p.translation.vector);
            tr.rotation = quaternion(&p.rotation);
        }
    }
}

fn vector(v: &nalgebra::Vector3<f64>) -> FoxgloveVector3 {
    FoxgloveVector3 {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

fn quaternion(q: &nalgebra::UnitQuaternion<f64>) -> FoxgloveQuaternion {
    let c = q.coords;
    FoxgloveQuaternion {
        x: c.x,
        y: c.y,
        z: c.z,
        w: c.w,
    }
}

/// The open log of a run.
pub(crate) struct LogSink {
    writer: LogWriter,
    topics: Topics,
    path: PathBuf,
    tf: Transforms,
    /// The model's force/torque sensor names and a buffer of their readings (`/sensors/ft`).
    ft_names: Vec<String>,
    ft_wrenches: Vec<[f64; 6]>,
}

/// `/estimation/state` from the estimation layer's output.
fn estimation_msg(time: f64, e: &EstimatorOutput) -> EstimationMsg<'_> {
    let s = &e.state;
    let q = s.base_pose.rotation.coords;
    let v = &s.base_velocity;
    EstimationMsg {
        time,
        base_position: s.base_pose.translation.vector.into(),
        base_orientation_xyzw: [q.x, q.y, q.z, q.w],
        base_linear_velocity: [v[0], v[1], v[2]],
        base_angular_velocity: [v[3], v[4], v[5]],
        contacts: ContactsMsg {
            left: e.contacts[0],
            right: e.contacts[1],
        },
        left_foot_wrench: e.foot_wrenches[0].into(),
        right_foot_wrench: e.foot_wrenches[1].into(),
        joint_torques: e.joint_torques.as_slice(),
    }
}

impl LogSink {
    /// Creates the file at `path`, registers the topics and writes the attachments (URDF, merged
    /// config), the provenance metadata and `/robot/description`.
    pub(crate) fn open(
        path: &Path,
        scenario: &Scenario,
        model: &Model,
        plant: &str,
    ) -> Result<Self, LogError> {
        let c = &scenario.config;
        let options = LogOptions {
            compression: c.log.compression,
            chunk_size: c.log.chunk_size,
            queue_capacity: c.log.queue_capacity,
        };
        let mut writer = LogWriter::create(path, &options)?;
        let topics = Topics::register(&mut writer)?;
        let urdf = std::fs::read(&scenario.urdf_path).unwrap_or_default();
        writer.attach("model.urdf", "application/xml", urdf)?;
        let merged = scenario.merged_toml().into_bytes();
        writer.attach("scenario.toml", "application/toml", merged)?;
        writer.metadata("stride", provenance(scenario, plant))?;
        let description = RobotDescription {
            robot: model.name(),
            root_link: model.root_link(),
            joint_names: model.joints().iter().map(|j| j.name.as_str()).collect(),
            left_sole: &c.robot.left_sole,
            right_sole: &c.robot.right_sole,
            control_mode: c.scenario.control_mode,
            plant,
        };
        writer.write(topics.description, 0, &description)?;
        Ok(Self {
            writer,
            topics,
            path: path.to_path_buf(),
            tf: Transforms::new(model, c.log.state_hz),
            ft_names: model.ft_sensors().iter().map(|f| f.name.clone()).collect(),
            ft_wrenches: vec![[0.0; 6]; model.ft_sensors().len()],
        })
    }

    fn write<T: Serialize + ?Sized>(
        &mut self,
        pick: impl Fn(&Topics) -> TopicId,
        t: u64,
        v: &T,
    ) -> Result<(), LogError> {
        self.writer.write(pick(&self.topics), t, v)
    }

    /// [`LogSink::write`] for the messages with a hand-written JSON writer (`crate::log_json`): the same
    /// bytes.
    fn write_json<T: Json + ?Sized>(
        &mut self,
        pick: impl Fn(&Topics) -> TopicId,
        t: u64,
        v: &T,
    ) -> Result<(), LogError> {
        self.writer
            .write_encoded(pick(&self.topics), t, |buf| v.json(buf))
    }

    /// `/events`.
    pub(crate) fn event(&mut self, t: u64, kind: &str, detail: String) -> Result<(), LogError> {
        let e = EventRecord {
            time: t as f64 * 1e-9,
            kind: kind.into(),
            detail,
        };
        self.write(|tp| tp.events, t, &e)
    }

    /// The state topics at a state tick: `/sim/state` and `/sensors/feet` (the plant's truth),
    /// `/sensors/imu` and `/sensors/ft` (what the robot senses), `/estimation/state` (what the controllers
    /// read), `/tf` (from the stack's kinematics, set to the true state of this tick) and, once a second,
    /// `/tf_static`.
    pub(crate) fn state(&mut self, t: u64, m: &Measurement, stack: &Stack) -> Result<(), LogError> {
        let kd = &stack.kd;
        let time = t as f64 * 1e-9;
        let truth = &m.truth;
        let state = SimStateMsg {
            time,
            state: StateRecord::from_state(&truth.state),
            joint_torques: truth.joint_torques.as_slice(),
            saturated: &truth.saturated,
        };
        let foot = |k: usize| {
            let w = &truth.foot_wrenches[k];
            FootMsg {
                in_contact: truth.feet_in_contact[k],
                yaw: stack.truth.soles[k].rotation.euler_angles().2,
                force: [w[0], w[1], w[2]],
                torque: [w[3], w[4], w[5]],
                point: stack.truth.soles[k].translation.vector.into(),
            }
        };
        let feet = FeetMsg {
            time,
            left: foot(0),
            right: foot(1),
        };
        let imu = &m.sensors.imu;
        let q = imu.orientation.coords;
        let imu = ImuMsg {
            time,
            orientation_xyzw: [q.x, q.y, q.z, q.w],
            angular_velocity: imu.angular_velocity.into(),
            linear_acceleration: imu.proper_acceleration.into(),
        };
        for (out, w) in self.ft_wrenches.iter_mut().zip(&m.sensors.ft_wrenches) {
            *out = (*w).into();
        }
        let ft = FtMsg {
            time,
            names: &self.ft_names,
            wrenches: &self.ft_wrenches,
        };
        let sensors_ft = self.topics.sensors_ft;
        self.writer
            .write_encoded(sensors_ft, t, |buf| ft.json(buf))?;
        self.write_json(
            |tp| tp.estimation_state,
            t,
            &estimation_msg(time, &stack.estimate),
        )?;
        let stamp = FoxgloveTime::from_ns(t);
        self.tf.update(kd, stamp);
        self.write_json(|tp| tp.sim_state, t, &state)?;
        self.write_json(|tp| tp.sensors_feet, t, &feet)?;
        self.write_json(|tp| tp.sensors_imu, t, &imu)?;
        let moving = &self.tf.moving;
        self.writer.write_encoded(self.topics.tf, t, |buf| {
            crate::tf_json::write_frame_transforms(buf, moving)
        })?;
        if self.tf.state_ticks % self.tf.attached_every == 0 {
            for tr in &mut self.tf.attached.transforms {
                tr.timestamp = stamp;
            }
            let attached = &self.tf.attached;
            self.writer.write_encoded(self.topics.tf_static, t, |buf| {
                crate::tf_json::write_frame_transforms(buf, attached)
            })?;
        }
        self.tf.state_ticks += 1;
        Ok(())
    }

    /// `/planner/input` and `/planner/footsteps` after the planner ran.
    pub(crate) fn plan(&mut self, t: u64, stack: &Stack) -> Result<(), LogError> {
        let input = PlannerInputRecord::from_input(t, &stack.planner_input);
        self.write(|tp| tp.planner_input, t, &input)?;
        let Some(plan) = stack.planner.plan() else {
            return Ok(());
        };
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
        self.write(|tp| tp.planner_footsteps, t, &steps)
    }

    /// `/planner/adjusted_footsteps`: a footstep adjustment applied to the plan.
    pub(crate) fn adjusted_footstep(
        &mut self,
        t: u64,
        msg: &crate::step_adjust::AdjustedFootstepMsg,
    ) -> Result<(), LogError> {
        self.write(|tp| tp.planner_adjusted_footsteps, t, msg)
    }

    /// `/planner/references`, `/simplified/input`, `/simplified/output`, `/simplified/timing` after a
    /// simplified tick; `time` is the running controller's time \[s\].
    pub(crate) fn simplified(&mut self, t: u64, stack: &Stack, time: f64) -> Result<(), LogError> {
        let sample = PlanSampleRecord::from_sample(&stack.plan_sample);
        self.write_json(|tp| tp.planner_references, t, &sample)?;
        self.write_json(|tp| tp.simplified_input, t, &stack.simplified_input)?;
        let out = simplified_output_record(&stack.simplified_output);
        self.write_json(|tp| tp.simplified_output, t, &out)?;
        let timing = TimingRecord {
            solve_time: time,
            tick_time: time,
        };
        self.write(|tp| tp.simplified_timing, t, &timing)
    }

    /// `/wbc/input`, `/wbc/output`, `/wbc/timing` (and `/wbc/ground_estimate` with TSID-Compliant's
    /// `estimate_ground`) after a whole-body tick.
    pub(crate) fn wbc(
        &mut self,
        t: u64,
        stack: &Stack,
        timing: TimingRecord,
    ) -> Result<(), LogError> {
        let input = WbcInputRecord::from_input(t, &stack.wbc_input);
        self.write_json(|tp| tp.wbc_input, t, &input)?;
        match &stack.wbc {
            Wbc::Ik(ik) => {
                self.write_json(|tp| tp.wbc_output, t, &IkOutputRecord::new(ik.output()))
            }
            Wbc::Tsid(ts) => {
                if let (Some(grounds), Some(models)) = (ts.ground_estimates(), ts.ground_models()) {
                    let record = GroundEstimateRecord {
                        tsid: ts,
                        grounds,
                        models,
                    };
                    self.write(|tp| tp.wbc_ground_estimate, t, &record)?;
                }
                self.write_json(|tp| tp.wbc_output, t, &TsidOutputRecord::new(ts.output()))
            }
        }?;
        self.write(|tp| tp.wbc_timing, t, &timing)
    }

    /// `/runner/tracking`.
    pub(crate) fn tracking(&mut self, t: u64, msg: &TrackingMsg) -> Result<(), LogError> {
        self.write_json(|tp| tp.tracking, t, msg)
    }

    /// `/runner/diagnosis`: the end-of-run diagnosis and gait figures of `summary`, at `t`.
    pub(crate) fn diagnosis(&mut self, t: u64, summary: &RunSummary) -> Result<(), LogError> {
        self.write(|tp| tp.diagnosis, t, &DiagnosisMsg::new(summary))
    }

    /// `/runner/timing`.
    pub(crate) fn runner_timing(&mut self, t: u64, msg: &RunnerTimingMsg) -> Result<(), LogError> {
        self.write(|tp| tp.runner_timing, t, msg)
    }

    /// Flushes and closes the file.
    pub(crate) fn finish(mut self) -> Result<(PathBuf, LogStats), LogError> {
        let stats = self.writer.finish()?;
        Ok((self.path, stats))
    }
}

/// Provenance stored as the `stride` metadata record.
fn provenance(scenario: &Scenario, plant: &str) -> BTreeMap<String, String> {
    let c = &scenario.config;
    let files: Vec<String> = scenario
        .sources
        .files
        .iter()
        .map(|f| f.path.display().to_string())
        .collect();
    BTreeMap::from([
        ("stride_version".into(), env!("CARGO_PKG_VERSION").into()),
        (
            "git_commit".into(),
            git_commit().unwrap_or_else(|| "unknown".into()),
        ),
        ("scenario".into(), c.scenario.name.clone()),
        ("config_files".into(), files.join(", ")),
        ("plant".into(), plant.into()),
        ("base_hz".into(), c.rates.base_hz.to_string()),
        ("log_format".into(), crate::records::LOG_FORMAT.to_string()),
    ])
}

/// Git commit of the source tree: `STRIDE_GIT_COMMIT` at build time, else `git rev-parse HEAD` in the
/// crate's folder at run time (a build outside a checkout records `unknown`).
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
