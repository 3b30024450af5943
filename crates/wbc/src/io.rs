//! Plain-data inputs and outputs of the whole-body controllers.

use std::sync::Arc;

use nalgebra::{DVector, Isometry3, Vector2, Vector3, Vector6};
use serde::{Deserialize, Serialize};
use stride_model::RobotState;
use stride_qp::QpStatus;

use crate::error::WbcError;

/// Reference of a frame: pose, mixed twist `[ṗ; ω]` and mixed acceleration `[p̈; ω̇]`, all in world
/// coordinates. An `so3` task reads only the orientation parts, an `r3` task only the position parts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FrameReference {
    /// world_H_frame.
    pub pose: Isometry3<f64>,
    /// `[linear velocity (m/s); angular velocity (rad/s)]`.
    pub velocity: Vector6<f64>,
    /// `[linear acceleration (m/s²); angular acceleration (rad/s²)]`.
    pub acceleration: Vector6<f64>,
}

impl Default for FrameReference {
    fn default() -> Self {
        FrameReference {
            pose: Isometry3::identity(),
            velocity: Vector6::zeros(),
            acceleration: Vector6::zeros(),
        }
    }
}

impl FrameReference {
    /// A frame held still at `pose` (zero twist and acceleration).
    pub fn still(pose: Isometry3<f64>) -> Self {
        FrameReference {
            pose,
            ..Default::default()
        }
    }
}

/// What the input says about one named contact: whether it is (planned to be) closed, and the wrench
/// the `wrench_regularization` task pulls it toward (mixed: force (N) and torque (N m) about the contact
/// frame origin, world axes, applied on the robot; zero by default).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ContactInput {
    /// Closed (loaded through the contact's ramp) or open.
    pub active: bool,
    /// Reference of the contact wrench regularization.
    pub desired_wrench: Vector6<f64>,
    /// The measured (or estimated) wrench of the contact, same convention as `desired_wrench`; read by
    /// the compliant TSID only ([`crate::ContactModel::Compliant`], [Romualdi 2022, eq. 8.2.1, 8.2.13]).
    pub measured_wrench: Vector6<f64>,
}

impl Default for ContactInput {
    fn default() -> Self {
        ContactInput {
            active: true,
            desired_wrench: Vector6::zeros(),
            measured_wrench: Vector6::zeros(),
        }
    }
}

/// Input of one tick of [`crate::QpIk`] or [`crate::Tsid`].
///
/// `state` is the measured robot state in the **mixed** representation. The QP-IK in
/// [`crate::IkFeedback::Integrated`] mode reads it only at its first tick after construction/reset.
///
/// Frame references and contacts are tables addressed by name, fixed at construction by an
/// [`InputLayout`] (usually the controller's: [`crate::Tsid::input`], [`crate::QpIk::input`]). Set them by
/// name ([`WbcInput::set_frame_reference`], [`WbcInput::set_contact`]) or, in a control loop, through a
/// handle resolved once ([`WbcInput::frame_id`], [`WbcInput::contact_id`]): no string lookup per tick.
/// Contacts start closed, references at identity / zero.
///
/// ```
/// use std::{sync::Arc, time::Duration};
/// use stride_wbc::prelude::*;
/// use stride_model::{bundled, Model, RobotState};
///
/// let model = Arc::new(Model::from_urdf_str(bundled::URDF)?);
/// let tsid = Tsid::new(model.clone(), TsidConfig::default_for_bundled_model(), Duration::from_millis(2))?;
/// let mut input = tsid.input(&RobotState::zero(&model));
/// input.set_contact("right_foot", false)?;                    // by name
/// let left = input.frame_id("left_foot")?;                     // or by handle, in a loop
/// input.frame_mut(left)?.velocity[0] = 0.1;
/// assert!(input.set_contact("l_hand", true).is_err());        // not in this controller's table
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct WbcInput {
    /// Measured robot state (mixed velocities).
    pub state: RobotState,
    /// CoM reference position (m).
    pub com_position: Vector3<f64>,
    /// CoM reference velocity (m/s).
    pub com_velocity: Vector3<f64>,
    /// CoM reference acceleration (m/s²; TSID feedforward).
    pub com_acceleration: Vector3<f64>,
    /// Desired global ZMP (world x, y), used by a `zmp` task when present.
    pub desired_zmp: Option<Vector2<f64>>,
    /// Posture reference (n joint positions, model order); `None`: the task's configured posture.
    pub posture: Option<DVector<f64>>,
    /// Centroidal angular momentum reference (kg m²/s) for `angular_momentum` tasks.
    pub angular_momentum: Vector3<f64>,
    /// Torque of each passive flexible joint (n entries, model order, N·m; only the TSID's
    /// `flexible_joints` are read): `τ^f = −k s^f − d ṡ^f` as estimated [Romualdi 2022, eq. (9.1.1), §9.3].
    pub flexible_torques: DVector<f64>,
    layout: Arc<InputLayout>,
    frames: Vec<FrameReference>,
    contacts: Vec<ContactInput>,
}

/// Handle of a frame reference in a [`WbcInput`] (valid for every input of the same [`InputLayout`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct FrameRefId(usize);

impl FrameRefId {
    /// Position in the layout's frame list.
    pub fn index(self) -> usize {
        self.0
    }
}

/// Handle of a contact in a [`WbcInput`] (valid for every input of the same [`InputLayout`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ContactId(usize);

impl ContactId {
    /// Position in the layout's contact list.
    pub fn index(self) -> usize {
        self.0
    }
}

impl WbcInput {
    /// An input holding the robot at `state`, with the frame references and contacts of `layout`
    /// (references at identity pose and zero twist, contacts closed, no desired ZMP, CoM references
    /// zero). Meant as a buffer the caller fills each tick; [`crate::Tsid::input`] and
    /// [`crate::QpIk::input`] give one with the controller's layout.
    pub fn new(state: RobotState, layout: Arc<InputLayout>) -> Self {
        WbcInput {
            flexible_torques: DVector::zeros(state.joint_positions.len()),
            state,
            com_position: Vector3::zeros(),
            com_velocity: Vector3::zeros(),
            com_acceleration: Vector3::zeros(),
            desired_zmp: None,
            posture: None,
            angular_momentum: Vector3::zeros(),
            frames: vec![FrameReference::default(); layout.frames.len()],
            contacts: vec![ContactInput::default(); layout.contacts.len()],
            layout,
        }
    }

    /// The names this input carries.
    pub fn layout(&self) -> &Arc<InputLayout> {
        &self.layout
    }

    /// Handle of the frame reference `name`. Errors: `name` is not in the layout.
    pub fn frame_id(&self, name: &str) -> Result<FrameRefId, WbcError> {
        position(&self.layout.frames, name)
            .map(FrameRefId)
            .ok_or_else(|| unknown("frame reference", name, &self.layout.frames))
    }

    /// Handle of the contact `name`. Errors: `name` is not in the layout.
    pub fn contact_id(&self, name: &str) -> Result<ContactId, WbcError> {
        position(&self.layout.contacts, name)
            .map(ContactId)
            .ok_or_else(|| unknown("contact", name, &self.layout.contacts))
    }

    /// Sets the reference of the frame tasks with `reference = name`. Errors: unknown name.
    pub fn set_frame_reference(
        &mut self,
        name: &str,
        reference: FrameReference,
    ) -> Result<(), WbcError> {
        let id = self.frame_id(name)?;
        *self.frame_mut(id)? = reference;
        Ok(())
    }

    /// The reference `name`. Errors: unknown name.
    pub fn frame_reference(&self, name: &str) -> Result<&FrameReference, WbcError> {
        let id = self.frame_id(name)?;
        self.frame(id)
    }

    /// The reference of handle `id`. Errors: a handle of a larger layout.
    pub fn frame(&self, id: FrameRefId) -> Result<&FrameReference, WbcError> {
        self.frames.get(id.0).ok_or_else(|| bad_handle("frame"))
    }

    /// The reference of handle `id`, to write. Errors: a handle of a larger layout.
    pub fn frame_mut(&mut self, id: FrameRefId) -> Result<&mut FrameReference, WbcError> {
        self.frames.get_mut(id.0).ok_or_else(|| bad_handle("frame"))
    }

    /// Closes (`true`) or opens the contact `name`. Errors: unknown name.
    pub fn set_contact(&mut self, name: &str, active: bool) -> Result<(), WbcError> {
        let id = self.contact_id(name)?;
        self.contact_mut(id)?.active = active;
        Ok(())
    }

    /// The contact `name`. Errors: unknown name.
    pub fn contact_named(&self, name: &str) -> Result<&ContactInput, WbcError> {
        let id = self.contact_id(name)?;
        self.contact(id)
    }

    /// The contact of handle `id`. Errors: a handle of a larger layout.
    pub fn contact(&self, id: ContactId) -> Result<&ContactInput, WbcError> {
        self.contacts.get(id.0).ok_or_else(|| bad_handle("contact"))
    }

    /// The contact of handle `id`, to write. Errors: a handle of a larger layout.
    pub fn contact_mut(&mut self, id: ContactId) -> Result<&mut ContactInput, WbcError> {
        self.contacts
            .get_mut(id.0)
            .ok_or_else(|| bad_handle("contact"))
    }

    /// Every frame reference, in layout order.
    pub fn frames(&self) -> &[FrameReference] {
        &self.frames
    }

    /// Every contact, in layout order.
    pub fn contacts(&self) -> &[ContactInput] {
        &self.contacts
    }
}

fn position(names: &[String], name: &str) -> Option<usize> {
    names.iter().position(|n| n == name)
}

fn unknown(what: &str, name: &str, names: &[String]) -> WbcError {
    WbcError::UnknownName {
        what: what.to_owned(),
        name: name.to_owned(),
        known: names.join(", "),
    }
}

fn bad_handle(what: &str) -> WbcError {
    WbcError::InvalidInput(format!("{what} handle from another input layout"))
}

/// The names of the frame references and contacts a [`WbcInput`] carries, fixed when it is built.
/// `"initial"` is never a frame reference (a task with `reference = "initial"` holds the frame's first
/// pose).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct InputLayout {
    frames: Vec<String>,
    contacts: Vec<String>,
}

impl InputLayout {
    /// A layout with these names (duplicates kept once, first occurrence order; `"initial"` dropped).
    pub fn new<F, C>(frames: F, contacts: C) -> Self
    where
        F: IntoIterator,
        F::Item: AsRef<str>,
        C: IntoIterator,
        C::Item: AsRef<str>,
    {
        let mut layout = InputLayout::default();
        for f in frames {
            layout.add_frame(f.as_ref());
        }
        for c in contacts {
            layout.add_contact(c.as_ref());
        }
        layout
    }

    /// The union of two layouts (this one's names first).
    pub fn union(&self, other: &InputLayout) -> Self {
        InputLayout::new(
            self.frames.iter().chain(&other.frames),
            self.contacts.iter().chain(&other.contacts),
        )
    }

    pub(crate) fn add_frame(&mut self, name: &str) {
        if name != INITIAL && !self.frames.iter().any(|n| n == name) {
            self.frames.push(name.to_owned());
        }
    }

    pub(crate) fn add_contact(&mut self, name: &str) {
        if !self.contacts.iter().any(|n| n == name) {
            self.contacts.push(name.to_owned());
        }
    }

    /// Frame reference names.
    pub fn frames(&self) -> &[String] {
        &self.frames
    }

    /// Contact names.
    pub fn contacts(&self) -> &[String] {
        &self.contacts
    }
}

/// The reference name that means "the frame's pose at the first tick after construction or reset".
pub const INITIAL: &str = "initial";

/// Solver report of one tick.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SolveReport {
    /// Status of the nominal solve.
    pub status: QpStatus,
    /// Status of the relaxed solve (hard tasks made heavily weighted soft), when it ran.
    pub relaxed_status: Option<QpStatus>,
    /// Backend iterations (nominal + relaxed).
    pub iterations: usize,
    /// Wall time of the QP solve(s), seconds.
    pub solve_time: f64,
    /// Wall time of the whole tick (task update + QP build + solve), seconds.
    pub tick_time: f64,
    /// The relaxed problem produced the command (hard tasks may be violated: see residuals).
    pub fallback: bool,
    /// Both solves failed: the command is the last valid one, held.
    pub held: bool,
}

impl SolveReport {
    /// The nominal problem was solved: no fallback to the relaxed problem, no held command.
    pub fn is_nominal(&self) -> bool {
        self.status.is_success() && !self.fallback && !self.held
    }
}

impl Default for SolveReport {
    fn default() -> Self {
        SolveReport {
            status: QpStatus::NotSolved,
            relaxed_status: None,
            iterations: 0,
            solve_time: 0.0,
            tick_time: 0.0,
            fallback: false,
            held: false,
        }
    }
}

/// Residual of one task at the returned solution.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TaskResidual {
    /// Task name (from the config).
    pub name: String,
    /// Whether the task is a hard constraint in the current problem.
    pub hard: bool,
    /// Equality tasks: `‖A x − b‖₂`; inequality tasks: `‖max(l − A x, 0) + max(A x − u, 0)‖₂`
    /// (0 when satisfied); tasks not in the current problem (e.g. an unloaded contact): 0.
    pub residual: f64,
}

/// Output of one tick of [`crate::QpIk`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IkOutput {
    /// Integrated joint positions (rad): the position command.
    pub joint_positions: DVector<f64>,
    /// Joint velocities ṡ (rad/s).
    pub joint_velocities: DVector<f64>,
    /// Base velocity (mixed `[ṗ; ω]`).
    pub base_velocity: Vector6<f64>,
    /// Integrated base pose (world_H_base) of the IK's internal state.
    pub base_pose: Isometry3<f64>,
    /// Solver report.
    pub report: SolveReport,
    /// Per-task residuals, in config order.
    pub residuals: Vec<TaskResidual>,
}

/// Output of one tick of [`crate::Tsid`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TsidOutput {
    /// Joint torques τ (N m): the command.
    pub joint_torques: DVector<f64>,
    /// Generalized acceleration ν̇ (mixed base acceleration, joint accelerations).
    pub accelerations: DVector<f64>,
    /// Planned contact wrenches, one per contact task in config order ([`crate::Tsid::contact_tasks`];
    /// mixed: force (N) and torque (N m) about the contact frame origin, world axes, applied on the
    /// robot); zero when unloaded.
    pub contact_wrenches: Vec<Vector6<f64>>,
    /// Load factor in [0, 1] of each contact's normal-force bound (the contact ramp), same order.
    pub contact_load: Vec<f64>,
    /// Solver report.
    pub report: SolveReport,
    /// Per-task residuals, in config order.
    pub residuals: Vec<TaskResidual>,
}
