//! Serializable records of what flows between the layers, written to the log and read back by replay.
//!
//! Layer types whose serde form is plain JSON (`SimplifiedInput`, `SimplifiedOutput`: fixed-size nalgebra
//! vectors serialize as arrays) are logged as they are (wall-clock fields zeroed: those go to the
//! `*/timing` topics). The others get a mirror here with an exact, lossless conversion (f64 values
//! round-trip bit-exactly through JSON), so that every logged vector is a plain array of numbers (never
//! serde's `[data, nrows, ncols]` form of a dynamic nalgebra vector) and every pose a [`PoseRecord`]
//! ([`LOG_FORMAT`] 2). Vectors are borrowed (`Cow`, slices) when writing so logging does not allocate.

use std::borrow::Cow;

use nalgebra::{
    DVector, Isometry3, Quaternion, Translation3, UnitQuaternion, Vector2, Vector3, Vector6,
};
use serde::{Deserialize, Serialize};
use stride_model::RobotState;
use stride_planner::{FootSample, Goal as PlannerGoal, PhaseKind, PlanSample, PlannerInput};
use stride_wbc::{walking, FrameReference, WbcInput};

use crate::config::ControlMode;

/// Version of the logs' message shapes, written as `log_format` in the `stride` metadata record and
/// checked by `stride replay`. 1: the first logs (dynamic vectors in serde's `[data, nrows, ncols]` form,
/// no `log_format` entry); 2: every vector a plain array, poses as [`PoseRecord`].
pub const LOG_FORMAT: u32 = 2;

/// A pose: position \[m\] and orientation quaternion `[x, y, z, w]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct PoseRecord {
    /// Position \[m\].
    pub position: [f64; 3],
    /// Orientation `[x, y, z, w]`.
    pub orientation_xyzw: [f64; 4],
}

impl PoseRecord {
    /// From an isometry.
    pub fn from_iso(p: &Isometry3<f64>) -> Self {
        let q = p.rotation.coords;
        Self {
            position: [p.translation.x, p.translation.y, p.translation.z],
            orientation_xyzw: [q.x, q.y, q.z, q.w],
        }
    }
    /// Back to an isometry (bit-exact inverse of [`PoseRecord::from_iso`]).
    pub fn to_iso(&self) -> Isometry3<f64> {
        let [x, y, z, w] = self.orientation_xyzw;
        Isometry3::from_parts(
            Translation3::new(self.position[0], self.position[1], self.position[2]),
            UnitQuaternion::new_unchecked(Quaternion::new(w, x, y, z)),
        )
    }
}

fn v3(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}
fn v6(v: &Vector6<f64>) -> [f64; 6] {
    [v[0], v[1], v[2], v[3], v[4], v[5]]
}

/// Floating-base state (mixed velocities).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StateRecord<'a> {
    /// Base pose.
    pub base: PoseRecord,
    /// Joint positions \[rad\], model order.
    pub joint_positions: Cow<'a, [f64]>,
    /// Base twist `[v; ω]` (mixed) [m/s; rad/s].
    pub base_velocity: [f64; 6],
    /// Joint velocities [rad/s].
    pub joint_velocities: Cow<'a, [f64]>,
}

impl<'a> StateRecord<'a> {
    /// Borrowing view of a state.
    pub fn from_state(s: &'a RobotState) -> Self {
        Self {
            base: PoseRecord::from_iso(&s.base_pose),
            joint_positions: Cow::Borrowed(s.joint_positions.as_slice()),
            base_velocity: v6(&s.base_velocity),
            joint_velocities: Cow::Borrowed(s.joint_velocities.as_slice()),
        }
    }
    /// Writes into `s` (sizes must match the model).
    pub fn to_state(&self, s: &mut RobotState) -> Result<(), String> {
        if s.joint_positions.len() != self.joint_positions.len()
            || s.joint_velocities.len() != self.joint_velocities.len()
        {
            return Err(format!(
                "state record has {} joints, the model {}",
                self.joint_positions.len(),
                s.joint_positions.len()
            ));
        }
        s.base_pose = self.base.to_iso();
        s.joint_positions.copy_from_slice(&self.joint_positions);
        s.base_velocity = Vector6::from_column_slice(&self.base_velocity);
        s.joint_velocities.copy_from_slice(&self.joint_velocities);
        Ok(())
    }
}

/// `/planner/input`: what the planner block received on an event tick.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlannerInputRecord {
    /// Time \[ns\].
    pub time_ns: u64,
    /// The new goal, if any.
    pub goal: Option<PlannerGoal>,
    /// Measured left sole pose.
    pub left_sole: PoseRecord,
    /// Measured right sole pose.
    pub right_sole: PoseRecord,
}

impl PlannerInputRecord {
    /// From the block input.
    pub fn from_input(time_ns: u64, i: &PlannerInput) -> Self {
        Self {
            time_ns,
            goal: i.goal.clone(),
            left_sole: PoseRecord::from_iso(&i.left_sole),
            right_sole: PoseRecord::from_iso(&i.right_sole),
        }
    }
    /// Back to the block input.
    pub fn to_input(&self) -> PlannerInput {
        PlannerInput {
            time: std::time::Duration::from_nanos(self.time_ns),
            goal: self.goal.clone(),
            left_sole: self.left_sole.to_iso(),
            right_sole: self.right_sole.to_iso(),
        }
    }
}

/// A planned foot sample.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct FootSampleRecord {
    /// Sole pose.
    pub pose: PoseRecord,
    /// Twist `[v; ω]` (mixed).
    pub twist: [f64; 6],
    /// Acceleration `[a; α]`.
    pub acceleration: [f64; 6],
    /// In contact.
    pub in_contact: bool,
}

impl FootSampleRecord {
    fn from_sample(f: &FootSample) -> Self {
        Self {
            pose: PoseRecord::from_iso(&f.pose),
            twist: v6(&f.twist),
            acceleration: v6(&f.acceleration),
            in_contact: f.in_contact,
        }
    }
}

/// `/planner/references`: the plan sampled at a tick.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct PlanSampleRecord {
    /// Plan time \[s\].
    pub time: f64,
    /// LIPM natural frequency [1/s].
    pub omega: f64,
    /// DCM \[m\].
    pub dcm_position: [f64; 3],
    /// DCM velocity [m/s].
    pub dcm_velocity: [f64; 3],
    /// ZMP \[m\].
    pub zmp: [f64; 3],
    /// CoM \[m\].
    pub com_position: [f64; 3],
    /// CoM velocity [m/s].
    pub com_velocity: [f64; 3],
    /// CoM acceleration [m/s²].
    pub com_acceleration: [f64; 3],
    /// Left foot.
    pub left: FootSampleRecord,
    /// Right foot.
    pub right: FootSampleRecord,
    /// `double_support`, `left_stance` or `right_stance`.
    pub phase: Cow<'static, str>,
}

/// Name of a gait phase.
pub fn phase_name(p: &PhaseKind) -> &'static str {
    match p {
        PhaseKind::DoubleSupport => "double_support",
        PhaseKind::SingleSupport {
            stance: stride_planner::Foot::Left,
        } => "left_stance",
        PhaseKind::SingleSupport {
            stance: stride_planner::Foot::Right,
        } => "right_stance",
    }
}

impl PlanSampleRecord {
    /// From a plan sample.
    pub fn from_sample(s: &PlanSample) -> Self {
        Self {
            time: s.time,
            omega: s.omega,
            dcm_position: v3(&s.dcm_position),
            dcm_velocity: v3(&s.dcm_velocity),
            zmp: v3(&s.zmp),
            com_position: v3(&s.com_position),
            com_velocity: v3(&s.com_velocity),
            com_acceleration: v3(&s.com_acceleration),
            left: FootSampleRecord::from_sample(&s.left),
            right: FootSampleRecord::from_sample(&s.right),
            phase: Cow::Borrowed(phase_name(&s.phase)),
        }
    }
}

/// A foot reference of the whole-body input.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct FootReferenceRecord {
    /// Pose.
    pub pose: PoseRecord,
    /// Twist (mixed).
    pub velocity: [f64; 6],
    /// Acceleration.
    pub acceleration: [f64; 6],
}

/// Torso orientation reference.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct OrientationRecord {
    /// Orientation `[x, y, z, w]`.
    pub orientation_xyzw: [f64; 4],
    /// Angular velocity [rad/s].
    pub angular_velocity: [f64; 3],
    /// Angular acceleration [rad/s²].
    pub angular_acceleration: [f64; 3],
}

/// `/wbc/input`: everything the whole-body block received.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WbcInputRecord<'a> {
    /// Time \[ns\].
    pub time_ns: u64,
    /// Measured state.
    pub state: StateRecord<'a>,
    /// CoM position reference \[m\].
    pub com_position: [f64; 3],
    /// CoM velocity reference [m/s].
    pub com_velocity: [f64; 3],
    /// CoM acceleration reference [m/s²].
    pub com_acceleration: [f64; 3],
    /// Left sole reference.
    pub left_foot: FootReferenceRecord,
    /// Right sole reference.
    pub right_foot: FootReferenceRecord,
    /// Left foot in contact.
    pub left_in_contact: bool,
    /// Right foot in contact.
    pub right_in_contact: bool,
    /// Desired ZMP \[m\].
    pub desired_zmp: Option<[f64; 2]>,
    /// Desired contact wrenches.
    pub desired_wrenches: Option<[[f64; 6]; 2]>,
    /// Torso orientation reference.
    pub torso: OrientationRecord,
    /// Posture reference \[rad\] (model order), if overriding the configured one.
    pub posture: Option<Cow<'a, [f64]>>,
    /// Centroidal angular momentum reference [kg m²/s].
    pub angular_momentum: [f64; 3],
}

fn foot_ref(f: &FrameReference) -> FootReferenceRecord {
    FootReferenceRecord {
        pose: PoseRecord::from_iso(&f.pose),
        velocity: v6(&f.velocity),
        acceleration: v6(&f.acceleration),
    }
}

fn foot_ref_back(r: &FootReferenceRecord) -> FrameReference {
    FrameReference {
        pose: r.pose.to_iso(),
        velocity: Vector6::from_column_slice(&r.velocity),
        acceleration: Vector6::from_column_slice(&r.acceleration),
    }
}

/// The walking frame reference `name` of `i` (default when the input lacks it).
fn walking_frame(i: &WbcInput, name: &str) -> FrameReference {
    i.frame_reference(name).copied().unwrap_or_default()
}

/// The walking contact `name` of `i`: (closed, desired wrench); (false, 0) when the input lacks it.
fn walking_contact(i: &WbcInput, name: &str) -> (bool, Vector6<f64>) {
    i.contact_named(name)
        .map(|c| (c.active, c.desired_wrench))
        .unwrap_or((false, Vector6::zeros()))
}

impl<'a> WbcInputRecord<'a> {
    /// Borrowing view of a whole-body input.
    /// The walking names of the input ([`stride_wbc::walking`]) fill the record's fixed fields (the
    /// runner's inputs always carry them); the desired wrenches are logged when one is not zero.
    pub fn from_input(time_ns: u64, i: &'a WbcInput) -> Self {
        let torso = walking_frame(i, walking::TORSO);
        let q = torso.pose.rotation.coords;
        let (left_in_contact, left_wrench) = walking_contact(i, walking::LEFT_FOOT);
        let (right_in_contact, right_wrench) = walking_contact(i, walking::RIGHT_FOOT);
        let desired_wrenches = (left_wrench != Vector6::zeros()
            || right_wrench != Vector6::zeros())
        .then(|| [v6(&left_wrench), v6(&right_wrench)]);
        Self {
            time_ns,
            state: StateRecord::from_state(&i.state),
            com_position: v3(&i.com_position),
            com_velocity: v3(&i.com_velocity),
            com_acceleration: v3(&i.com_acceleration),
            left_foot: foot_ref(&walking_frame(i, walking::LEFT_FOOT)),
            right_foot: foot_ref(&walking_frame(i, walking::RIGHT_FOOT)),
            left_in_contact,
            right_in_contact,
            desired_zmp: i.desired_zmp.map(|z| [z.x, z.y]),
            desired_wrenches,
            torso: OrientationRecord {
                orientation_xyzw: [q.x, q.y, q.z, q.w],
                angular_velocity: v3(&torso.velocity.fixed_rows::<3>(3).into_owned()),
                angular_acceleration: v3(&torso.acceleration.fixed_rows::<3>(3).into_owned()),
            },
            posture: i.posture.as_ref().map(|p| Cow::Borrowed(p.as_slice())),
            angular_momentum: v3(&i.angular_momentum),
        }
    }

    /// Writes the record into a whole-body input sized for the model, with the walking names.
    pub fn to_input(&self, i: &mut WbcInput) -> Result<(), String> {
        let name_error = |e: stride_wbc::WbcError| e.to_string();
        self.state.to_state(&mut i.state)?;
        i.com_position = Vector3::from(self.com_position);
        i.com_velocity = Vector3::from(self.com_velocity);
        i.com_acceleration = Vector3::from(self.com_acceleration);
        i.set_frame_reference(walking::LEFT_FOOT, foot_ref_back(&self.left_foot))
            .map_err(name_error)?;
        i.set_frame_reference(walking::RIGHT_FOOT, foot_ref_back(&self.right_foot))
            .map_err(name_error)?;
        let wrenches = self.desired_wrenches.unwrap_or([[0.0; 6]; 2]);
        for (name, active, wrench) in [
            (walking::LEFT_FOOT, self.left_in_contact, &wrenches[0]),
            (walking::RIGHT_FOOT, self.right_in_contact, &wrenches[1]),
        ] {
            let id = i.contact_id(name).map_err(name_error)?;
            let contact = i.contact_mut(id).map_err(name_error)?;
            contact.active = active;
            contact.desired_wrench = Vector6::from_column_slice(wrench);
        }
        i.desired_zmp = self.desired_zmp.map(|z| Vector2::new(z[0], z[1]));
        let [x, y, z, w] = self.torso.orientation_xyzw;
        let mut torso = FrameReference::default();
        torso.pose.rotation = UnitQuaternion::new_unchecked(Quaternion::new(w, x, y, z));
        torso
            .velocity
            .fixed_rows_mut::<3>(3)
            .copy_from(&Vector3::from(self.torso.angular_velocity));
        torso
            .acceleration
            .fixed_rows_mut::<3>(3)
            .copy_from(&Vector3::from(self.torso.angular_acceleration));
        i.set_frame_reference(walking::TORSO, torso)
            .map_err(name_error)?;
        i.posture = self.posture.as_ref().map(|p| DVector::from_column_slice(p));
        i.angular_momentum = Vector3::from(self.angular_momentum);
        Ok(())
    }
}

/// `/wbc/output` in position mode: `stride_wbc::IkOutput` with the wall-clock fields of its report zeroed,
/// every vector a plain JSON array and the base pose a [`PoseRecord`].
#[derive(Debug, Serialize)]
pub struct IkOutputRecord<'a> {
    /// Joint position commands \[rad\], model order.
    pub joint_positions: &'a [f64],
    /// Joint velocities [rad/s], model order.
    pub joint_velocities: &'a [f64],
    /// Base twist `[v; ω]` (mixed) [m/s; rad/s].
    pub base_velocity: [f64; 6],
    /// Integrated base pose.
    pub base_pose: PoseRecord,
    /// Solver report (solve_time and tick_time set to 0).
    pub report: stride_wbc::SolveReport,
    /// Task residuals.
    pub residuals: &'a [stride_wbc::TaskResidual],
}

impl<'a> IkOutputRecord<'a> {
    /// View of an output without its wall-clock fields.
    pub fn new(o: &'a stride_wbc::IkOutput) -> Self {
        Self {
            joint_positions: o.joint_positions.as_slice(),
            joint_velocities: o.joint_velocities.as_slice(),
            base_velocity: v6(&o.base_velocity),
            base_pose: PoseRecord::from_iso(&o.base_pose),
            report: without_wall_clock(o.report),
            residuals: &o.residuals,
        }
    }
}

/// `/wbc/output` in torque mode: `stride_wbc::TsidOutput` with wall-clock fields zeroed and every vector a
/// plain JSON array.
#[derive(Debug, Serialize)]
pub struct TsidOutputRecord<'a> {
    /// Joint torques [N m], model order.
    pub joint_torques: &'a [f64],
    /// ν̇ `[base (mixed) [m/s²; rad/s²]; joints [rad/s²]]`.
    pub accelerations: &'a [f64],
    /// Planned contact wrenches, each `[f; τ]` [N; N m].
    pub contact_wrenches: &'a [Vector6<f64>],
    /// Contact load factors.
    pub contact_load: &'a [f64],
    /// Solver report (solve_time and tick_time set to 0).
    pub report: stride_wbc::SolveReport,
    /// Task residuals.
    pub residuals: &'a [stride_wbc::TaskResidual],
}

impl<'a> TsidOutputRecord<'a> {
    /// View of an output without its wall-clock fields.
    pub fn new(o: &'a stride_wbc::TsidOutput) -> Self {
        Self {
            joint_torques: o.joint_torques.as_slice(),
            accelerations: o.accelerations.as_slice(),
            contact_wrenches: &o.contact_wrenches,
            contact_load: &o.contact_load,
            report: without_wall_clock(o.report),
            residuals: &o.residuals,
        }
    }
}

/// `report` with its wall-clock fields (`solve_time`, `tick_time`) zeroed.
fn without_wall_clock(mut report: stride_wbc::SolveReport) -> stride_wbc::SolveReport {
    report.solve_time = 0.0;
    report.tick_time = 0.0;
    report
}

/// `/simplified/output`: the layer's output with the solve times zeroed.
pub fn simplified_output_record(
    o: &stride_simplified::SimplifiedOutput,
) -> stride_simplified::SimplifiedOutput {
    let mut r = *o;
    r.diagnostics.mpc.solve_time = 0.0;
    r.diagnostics.solve_time = 0.0;
    r
}

/// `/*/timing`: wall-clock measurements of one layer tick (not deterministic, kept apart).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct TimingRecord {
    /// QP solve time \[s\].
    pub solve_time: f64,
    /// Whole tick time \[s\].
    pub tick_time: f64,
}

/// `/events`: something that happened.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EventRecord {
    /// Simulated time \[s\].
    pub time: f64,
    /// `start`, `replan`, `phase`, `fallback`, `hold`, `fall`, `push`, `end`, `error`.
    pub kind: String,
    /// Human-readable detail.
    pub detail: String,
}

// ---- Runner topics: messages the log sink writes that are not a layer's input or output. ----

/// `/robot/description`: what a reader needs to interpret the log.
#[derive(Serialize)]
pub(crate) struct RobotDescription<'a> {
    pub(crate) robot: &'a str,
    pub(crate) root_link: &'a str,
    pub(crate) joint_names: Vec<&'a str>,
    pub(crate) left_sole: &'a str,
    pub(crate) right_sole: &'a str,
    pub(crate) control_mode: ControlMode,
    pub(crate) plant: &'a str,
}

/// `/sim/state`: the plant's true state, motor torques and per-joint saturation.
#[derive(Serialize)]
pub(crate) struct SimStateMsg<'a> {
    pub(crate) time: f64,
    #[serde(flatten)]
    pub(crate) state: StateRecord<'a>,
    pub(crate) joint_torques: &'a [f64],
    pub(crate) saturated: &'a [bool],
}

/// One foot of `/sensors/feet`.
#[derive(Serialize)]
pub(crate) struct FootMsg {
    pub(crate) in_contact: bool,
    /// Yaw of the true sole frame about world z \[rad\].
    pub(crate) yaw: f64,
    pub(crate) force: [f64; 3],
    pub(crate) torque: [f64; 3],
    pub(crate) point: [f64; 3],
}

/// `/sensors/feet`: the plant's contact wrenches (truth: the ground on the foot, world orientation, about
/// `point`); what the controllers use is in `/estimation/state`.
#[derive(Serialize)]
pub(crate) struct FeetMsg {
    pub(crate) time: f64,
    pub(crate) left: FootMsg,
    pub(crate) right: FootMsg,
}

/// `/sensors/ft`: the six-axis force/torque sensor readings as the robot senses them (offsets and noise
/// included), each `[f; τ]` in its sensor frame, in the order of `names`.
#[derive(Serialize)]
pub(crate) struct FtMsg<'a> {
    pub(crate) time: f64,
    pub(crate) names: &'a [String],
    pub(crate) wrenches: &'a [[f64; 6]],
}

/// Contact flags of `/estimation/state`.
#[derive(Serialize)]
pub(crate) struct ContactsMsg {
    pub(crate) left: bool,
    pub(crate) right: bool,
}

/// `/estimation/state`: the estimation layer's output, what the controllers read of the robot. Base
/// quantities in the world frame; foot wrenches are the ground on the foot, world orientation, about the
/// sole frame origin.
#[derive(Serialize)]
pub(crate) struct EstimationMsg<'a> {
    pub(crate) time: f64,
    pub(crate) base_position: [f64; 3],
    pub(crate) base_orientation_xyzw: [f64; 4],
    pub(crate) base_linear_velocity: [f64; 3],
    pub(crate) base_angular_velocity: [f64; 3],
    pub(crate) contacts: ContactsMsg,
    pub(crate) left_foot_wrench: [f64; 6],
    pub(crate) right_foot_wrench: [f64; 6],
    pub(crate) joint_torques: &'a [f64],
}

/// `/sensors/imu`.
#[derive(Serialize)]
pub(crate) struct ImuMsg {
    pub(crate) time: f64,
    pub(crate) orientation_xyzw: [f64; 4],
    pub(crate) angular_velocity: [f64; 3],
    pub(crate) linear_acceleration: [f64; 3],
}

/// `/runner/tracking`: tracking errors and measured quantities at a simplified tick.
#[derive(Serialize)]
pub(crate) struct TrackingMsg {
    pub(crate) time: f64,
    pub(crate) dcm_error: f64,
    pub(crate) com_error: f64,
    pub(crate) zmp_error: Option<f64>,
    /// Signed distance of the measured ZMP to the boundary of the loaded feet's support polygon \[m\]
    /// (≤ 0 inside; `crate::diagnosis`).
    pub(crate) zmp_edge_distance: Option<f64>,
    pub(crate) feet_error: f64,
    pub(crate) measured_com: [f64; 3],
    pub(crate) measured_dcm: [f64; 2],
    pub(crate) measured_zmp: [f64; 2],
    pub(crate) base_height: f64,
    pub(crate) tilt_deg: f64,
    /// The push response's horizontal push estimate \[N\] (absent when `simplified.push` is off).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) push_estimate: Option<[f64; 2]>,
    /// The same errors from the plant's own model (absent when the plant runs on the controllers' model).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub(crate) plant: Option<PlantTrackingMsg>,
}

/// `/runner/tracking.plant`: the DCM and CoM of the plant's true state computed with the plant's own model
/// (`[sim.model]`), and their errors against the same references as [`TrackingMsg`]'s.
#[derive(Serialize)]
pub(crate) struct PlantTrackingMsg {
    pub(crate) dcm_error: f64,
    pub(crate) com_error: f64,
    pub(crate) com: [f64; 3],
    pub(crate) dcm: [f64; 2],
}

/// One joint of `/runner/diagnosis`: time at its effort limit.
#[derive(Serialize)]
pub(crate) struct JointSaturationMsg<'a> {
    pub(crate) joint: &'a str,
    pub(crate) time: f64,
}

/// `/runner/diagnosis`: the summary's fall diagnosis and gait figures, once at the end of the run.
#[derive(Serialize)]
pub(crate) struct DiagnosisMsg<'a> {
    pub(crate) time: f64,
    pub(crate) outcome: &'a crate::summary::Outcome,
    #[serde(flatten)]
    pub(crate) diagnosis: &'a crate::diagnosis::Diagnosis,
    pub(crate) joint_saturation: Vec<JointSaturationMsg<'a>>,
    #[serde(flatten)]
    pub(crate) gait: &'a crate::gait::GaitFigures,
    pub(crate) distance: f64,
}

impl<'a> DiagnosisMsg<'a> {
    /// The message of a finished run's summary.
    pub(crate) fn new(s: &'a crate::summary::RunSummary) -> Self {
        Self {
            time: s.simulated_time,
            outcome: &s.outcome,
            diagnosis: &s.diagnosis,
            joint_saturation: s
                .joint_saturation
                .iter()
                .map(|(joint, time)| JointSaturationMsg { joint, time: *time })
                .collect(),
            gait: &s.gait,
            distance: s.distance,
        }
    }
}

/// `/runner/timing`: wall-clock progress (excluded from determinism comparisons).
#[derive(Serialize)]
pub(crate) struct RunnerTimingMsg {
    pub(crate) wall_time: f64,
    pub(crate) real_time_factor: f64,
    pub(crate) deadline_misses: u64,
}

/// One footstep of `/planner/footsteps`.
#[derive(Serialize)]
pub(crate) struct FootstepMsg {
    pub(crate) foot: &'static str,
    pub(crate) position: [f64; 3],
    pub(crate) orientation_xyzw: [f64; 4],
    pub(crate) activation_time: f64,
    pub(crate) deactivation_time: Option<f64>,
}

/// `/planner/footsteps`: the contact list of a new plan.
#[derive(Serialize)]
pub(crate) struct FootstepsMsg {
    pub(crate) time: f64,
    pub(crate) footsteps: Vec<FootstepMsg>,
}

/// `/wbc/ground_estimate`: TSID-Compliant's ground estimate per contact (`[wbc.tsid.compliant]
/// estimate_ground`, [Romualdi 2022, §8.2.3]): `{"contacts": [names], "stiffness": [N/m³],
/// "damping": [N·s/m³], "model_stiffness": [N/m³], "model_damping": [N·s/m³]}`, the arrays in the TSID's
/// contact order: the estimate, and the ground each contact's model uses
/// ([`stride_wbc::Tsid::ground_models`]: the prior open loop, what the gate accepted with
/// `estimator_accept_std`). Serialized without allocating.
pub struct GroundEstimateRecord<'a> {
    /// The TSID (its contact names and estimates).
    pub tsid: &'a stride_wbc::Tsid,
    /// Its estimates ([`stride_wbc::Tsid::ground_estimates`]).
    pub grounds: &'a [stride_wbc::GroundParameters],
    /// The grounds of its contact models ([`stride_wbc::Tsid::ground_models`]).
    pub models: &'a [stride_wbc::GroundParameters],
}

impl Serialize for GroundEstimateRecord<'_> {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        struct Seq<I>(I);
        impl<I: Iterator<Item = T> + Clone, T: Serialize> Serialize for Seq<I> {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.collect_seq(self.0.clone())
            }
        }
        let mut st = serializer.serialize_struct("GroundEstimate", 5)?;
        st.serialize_field("contacts", &Names(self.tsid))?;
        st.serialize_field("stiffness", &Seq(self.grounds.iter().map(|g| g.stiffness)))?;
        st.serialize_field("damping", &Seq(self.grounds.iter().map(|g| g.damping)))?;
        st.serialize_field(
            "model_stiffness",
            &Seq(self.models.iter().map(|g| g.stiffness)),
        )?;
        st.serialize_field("model_damping", &Seq(self.models.iter().map(|g| g.damping)))?;
        st.end()
    }
}

/// The contact names of a TSID as a JSON array.
struct Names<'a>(&'a stride_wbc::Tsid);

impl Serialize for Names<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.0.contact_tasks())
    }
}
