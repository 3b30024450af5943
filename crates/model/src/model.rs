//! The immutable model: bodies (links joined by movable joints, fixed joints merged), joints, frames, sensors.

use std::collections::HashMap;

use nalgebra::{Isometry3, Matrix3, Vector3};

use crate::error::ModelError;
use crate::spatial::Inertia;

/// Type of a movable joint.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JointKind {
    /// Rotation about `axis`, with position limits.
    Revolute,
    /// Rotation about `axis`, unbounded (`lower = −∞`, `upper = +∞`).
    Continuous,
    /// Translation along `axis`.
    Prismatic,
}

impl JointKind {
    /// The URDF name of the type (`revolute`, `continuous`, `prismatic`).
    pub fn as_str(&self) -> &'static str {
        match self {
            JointKind::Revolute => "revolute",
            JointKind::Continuous => "continuous",
            JointKind::Prismatic => "prismatic",
        }
    }
}

/// The `<mimic>` element of a joint. Mimic joints are loaded as independent joints (as iDynTree and Pinocchio do
/// by default); this records the declared relation `q = multiplier · q_joint + offset`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Mimic {
    /// The joint that is mimicked.
    pub joint: String,
    /// Multiplier (default 1).
    pub multiplier: f64,
    /// Offset in rad or m (default 0).
    pub offset: f64,
}

/// A movable joint (one degree of freedom).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Joint {
    /// Joint name.
    pub name: String,
    /// Revolute, continuous or prismatic.
    pub kind: JointKind,
    /// Unit axis in the child link frame (= joint frame).
    pub axis: Vector3<f64>,
    /// Lower position limit (rad or m); `−∞` for continuous joints and joints declared without `<limit>`.
    pub lower: f64,
    /// Upper position limit (rad or m); `+∞` for continuous joints and joints declared without `<limit>`.
    pub upper: f64,
    /// Velocity limit (rad/s or m/s); `+∞` when not declared.
    pub velocity_limit: f64,
    /// Effort limit (N·m or N); `+∞` when not declared.
    pub effort_limit: f64,
    /// `Some` when the URDF declares the joint as a mimic joint (it is still an independent DoF).
    pub mimic: Option<Mimic>,
    /// URDF parent link of the joint.
    pub parent_link: String,
    /// URDF child link of the joint.
    pub child_link: String,
}

/// Identifier of a frame of a [`Model`] (index into [`Model::frames`]). Obtain it from [`Model::frame_id`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct FrameId(pub(crate) usize);

impl FrameId {
    /// Index into [`Model::frames`].
    pub fn index(self) -> usize {
        self.0
    }
}

/// What a frame is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FrameKind {
    /// The frame of a body (a URDF link moved by a movable joint, or the root link).
    Body,
    /// A URDF link attached by a fixed joint, merged into the body it is rigidly attached to.
    MergedLink,
    /// A sensor frame that is not a URDF link.
    Sensor,
    /// A frame added after loading ([`Model::add_frame`]), e.g. a sole frame from the configuration.
    Added,
}

/// A named frame rigidly attached to a body.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Name (the URDF link name, or the sensor name).
    pub name: String,
    /// Index of the body it is attached to (into [`Model::bodies`]).
    pub link: usize,
    /// `body_H_frame`.
    pub placement: Isometry3<f64>,
    /// What the frame is.
    pub kind: FrameKind,
    /// For an [`FrameKind::Added`] frame, the frame it was attached to (index into [`Model::frames`]);
    /// `None` for the others.
    pub attached_to: Option<usize>,
}

/// A rigid body of the model: one URDF link moved by a movable joint (or the root), with the inertias of every
/// link attached to it through fixed joints lumped in.
#[derive(Clone, Debug, PartialEq)]
pub struct Body {
    /// Name of the URDF link that defines the body frame.
    pub name: String,
    /// Parent body (`None` for the root / floating base).
    pub parent: Option<usize>,
    /// Index of the movable joint connecting it to its parent (`None` for the root). Always `Some(body − 1)`.
    pub joint: Option<usize>,
    /// `parent_body_H_body` at zero joint position.
    pub placement_in_parent: Isometry3<f64>,
    /// Mass (kg), lumped.
    pub mass: f64,
    /// Centre of mass in the body frame (m).
    pub com: Vector3<f64>,
    /// Rotational inertia about the CoM, body orientation (kg·m²).
    pub inertia_at_com: Matrix3<f64>,
}

/// A six-axis force/torque sensor declared in the URDF (on a fixed joint).
#[derive(Clone, Debug, PartialEq)]
pub struct FtSensor {
    /// Sensor name.
    pub name: String,
    /// The fixed joint the sensor is mounted on.
    pub joint: String,
    /// Measurement frame.
    pub frame: FrameId,
    /// Parent link of the joint.
    pub parent_link: String,
    /// Child link of the joint.
    pub child_link: String,
    /// Declared measurement direction (`child_to_parent` or `parent_to_child`; `child_to_parent` if not declared).
    pub measure_direction: String,
}

/// How the fixed joint of a force/torque sensor splits the model, computed at load time: the sensor's
/// fixed joint lies inside one lumped body (the host), so the inertia of the URDF links on the joint's child
/// side within the host is kept apart, with the bodies that hang from that side [Traversaro 2017, §4.5].
#[derive(Clone, Debug)]
pub(crate) struct FtSensorSide {
    /// The lumped body that contains the sensor's fixed joint.
    pub(crate) host: usize,
    /// Mass (kg) of the child-side links of the host body.
    pub(crate) mass: f64,
    /// Their centre of mass, host body frame (m).
    pub(crate) com: Vector3<f64>,
    /// Their rotational inertia about that centre of mass, host body orientation (kg·m²).
    pub(crate) inertia_at_com: Matrix3<f64>,
    /// Bodies whose parent is the host and whose joint hangs from a child-side link (their subtrees are on
    /// the child side).
    pub(crate) child_bodies: Vec<usize>,
    /// Per frame ([`FrameId::index`]): whether the frame's URDF link is on the child side.
    pub(crate) child_side_frame: Vec<bool>,
    /// `true` for `child_to_parent` (the reading is the wrench the child side applies on the parent side),
    /// `false` for `parent_to_child`.
    pub(crate) child_to_parent: bool,
}

/// The immutable floating-base model. Build it with [`Model::from_urdf_file`] or [`Model::from_urdf_str`]
/// and share it with [`std::sync::Arc`].
///
/// # Examples
///
/// A 2 kg base with a 1 kg arm on a hinge: one joint, `nv = 6 + 1`, 3 kg.
///
/// ```
/// use stride_model::{JointKind, Model};
///
/// let model = Model::from_urdf_str(
///     r#"<robot name="pendulum">
///       <link name="base"><inertial><mass value="2"/>
///         <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
///       <link name="arm"><inertial><origin xyz="0 0 -0.5"/><mass value="1"/>
///         <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
///       <joint name="hinge" type="revolute"><parent link="base"/><child link="arm"/>
///         <axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="10" velocity="5"/></joint>
///     </robot>"#,
/// )?;
/// assert_eq!((model.dof(), model.nv()), (1, 7));
/// assert_eq!(model.root_link(), "base");
/// assert_eq!(model.joint_index("hinge"), Some(0));
/// assert_eq!(model.joints()[0].kind, JointKind::Revolute);
/// assert_eq!(model.total_mass(), 3.0);
/// assert!(model.frame_id("arm").is_some() && model.frame_id("hand").is_none());
/// # Ok::<(), stride_model::ModelError>(())
/// ```
#[derive(Clone, Debug)]
pub struct Model {
    pub(crate) name: String,
    pub(crate) root_link: String,
    pub(crate) joints: Vec<Joint>,
    pub(crate) bodies: Vec<Body>,
    pub(crate) frames: Vec<Frame>,
    pub(crate) frame_index: HashMap<String, usize>,
    pub(crate) joint_index: HashMap<String, usize>,
    pub(crate) ft_sensors: Vec<FtSensor>,
    /// Per force/torque sensor (same order): how its fixed joint splits the hosting lumped body.
    pub(crate) ft_sides: Vec<FtSensorSide>,
    pub(crate) warnings: Vec<String>,
    pub(crate) total_mass: f64,
    /// Gravity acceleration in world coordinates (m/s²).
    pub(crate) gravity: Vector3<f64>,
    // Flat data for the algorithms (index = body).
    pub(crate) parent: Vec<usize>,
    pub(crate) placement_rot: Vec<Matrix3<f64>>,
    pub(crate) placement_pos: Vec<Vector3<f64>>,
    /// Joint axis in the parent body frame (`placement_rot · axis`).
    pub(crate) axis_in_parent: Vec<Vector3<f64>>,
    /// `placement_rot · K` and `placement_rot · K²` with `K = skew(axis)` (Rodrigues).
    pub(crate) placement_k: Vec<Matrix3<f64>>,
    pub(crate) placement_k2: Vec<Matrix3<f64>>,
    pub(crate) prismatic: Vec<bool>,
    pub(crate) inertia: Vec<Inertia>,
    pub(crate) body_com: Vec<Vector3<f64>>,
    pub(crate) body_inertia_com: Vec<Matrix3<f64>>,
    pub(crate) frame_rot: Vec<Matrix3<f64>>,
    pub(crate) frame_pos: Vec<Vector3<f64>>,
}

/// Standard gravity g₀ (m/s²), the magnitude of the default gravity `[0, 0, −g₀]` of a [`Model`].
pub const STANDARD_GRAVITY: f64 = 9.81;

impl Model {
    /// Gravity acceleration in world coordinates (m/s²; default `[0, 0, −9.81]`): the one gravity of a
    /// model, which every [`KinDyn`](crate::KinDyn) workspace built on it starts from, and which
    /// controllers and simulators built on the model read (like Pinocchio's `Model::gravity`).
    pub fn gravity(&self) -> Vector3<f64> {
        self.gravity
    }

    /// Sets the model's gravity (m/s², world coordinates). Set it before sharing the model: workspaces
    /// built earlier keep the value they copied.
    ///
    /// # Errors
    /// [`ModelError::NonFiniteInput`] when a component is not finite.
    pub fn set_gravity(&mut self, gravity: Vector3<f64>) -> Result<(), ModelError> {
        if !gravity.iter().all(|g| g.is_finite()) {
            return Err(ModelError::NonFiniteInput { what: "gravity" });
        }
        self.gravity = gravity;
        Ok(())
    }

    /// Sets the effort limit of joint `index` (N·m, or N for a prismatic joint), e.g. to bound a joint whose
    /// URDF `effort` is a placeholder. Set it before sharing the model: workspaces built earlier keep the
    /// limits they copied.
    ///
    /// # Errors
    /// [`ModelError::InvalidJointLimit`] when `index` is not a joint of the model or `limit` is not a
    /// positive finite number.
    pub fn set_effort_limit(&mut self, index: usize, limit: f64) -> Result<(), ModelError> {
        self.joint_for_limit(index, "effort", limit)?.effort_limit = limit;
        Ok(())
    }

    /// Sets the velocity limit of joint `index` (rad/s, or m/s for a prismatic joint); as
    /// [`Model::set_effort_limit`].
    ///
    /// # Errors
    /// As [`Model::set_effort_limit`].
    pub fn set_velocity_limit(&mut self, index: usize, limit: f64) -> Result<(), ModelError> {
        self.joint_for_limit(index, "velocity", limit)?
            .velocity_limit = limit;
        Ok(())
    }

    /// Joint `index`, when `limit` is a valid `what` limit for it.
    fn joint_for_limit(
        &mut self,
        index: usize,
        what: &'static str,
        limit: f64,
    ) -> Result<&mut Joint, ModelError> {
        let count = self.joints.len();
        let joint = self
            .joints
            .get_mut(index)
            .ok_or_else(|| ModelError::InvalidJointLimit {
                joint: format!("#{index} (the model has {count} joints)"),
                what,
                value: limit,
            })?;
        if !(limit.is_finite() && limit > 0.0) {
            return Err(ModelError::InvalidJointLimit {
                joint: joint.name.clone(),
                what,
                value: limit,
            });
        }
        Ok(joint)
    }

    /// Robot name (`<robot name>`).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Number of movable joints n.
    pub fn dof(&self) -> usize {
        self.joints.len()
    }

    /// Size of the generalized velocity, 6 + n.
    pub fn nv(&self) -> usize {
        6 + self.joints.len()
    }

    /// Movable joints in model order (depth-first from the root, children in file order). Joint `i` is DoF `i`
    /// and moves body `i + 1`.
    pub fn joints(&self) -> &[Joint] {
        &self.joints
    }

    /// Index (DoF) of a movable joint by name.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joint_index.get(name).copied()
    }

    /// Frame by name: every URDF link (bodies and fixed-joint-merged links) and every sensor frame.
    pub fn frame_id(&self, name: &str) -> Option<FrameId> {
        self.frame_index.get(name).map(|&i| FrameId(i))
    }

    /// Name of a frame. Panics if `frame` comes from another, smaller model.
    pub fn frame_name(&self, frame: FrameId) -> &str {
        &self.frames[frame.0].name
    }

    /// The URDF link or sensor frame `frame` is attached to: its own name, or for an added frame
    /// ([`Model::add_frame`]) the name of the first frame down its chain of attachments that is not added
    /// (e.g. a sole frame attached to `l_sole` → `l_sole`). Panics if `frame` comes from another, smaller
    /// model.
    pub fn urdf_frame_name(&self, frame: FrameId) -> &str {
        let mut f = &self.frames[frame.0];
        while let Some(parent) = f.attached_to {
            f = &self.frames[parent];
        }
        &f.name
    }

    /// All frames; [`FrameId::index`] indexes this slice. The first `bodies().len()` frames are the body frames.
    pub fn frames(&self) -> &[Frame] {
        &self.frames
    }

    /// Bodies (index 0 is the root / floating base); body `i > 0` is moved by joint `i − 1`.
    pub fn bodies(&self) -> &[Body] {
        &self.bodies
    }

    /// Name of the root link (the floating base).
    pub fn root_link(&self) -> &str {
        &self.root_link
    }

    /// Total mass (kg).
    pub fn total_mass(&self) -> f64 {
        self.total_mass
    }

    /// Six-axis force/torque sensors.
    pub fn ft_sensors(&self) -> &[FtSensor] {
        &self.ft_sensors
    }

    /// Index into [`Model::ft_sensors`] of the force/torque sensor called `name`.
    pub fn ft_sensor_index(&self, name: &str) -> Option<usize> {
        self.ft_sensors.iter().position(|s| s.name == name)
    }

    /// Whether `frame`'s URDF link lies on force/torque sensor `sensor`'s child side (below its fixed joint).
    ///
    /// # Errors
    /// [`ModelError::FtSensorOutOfRange`], [`ModelError::FrameOutOfRange`].
    pub fn ft_child_side_holds(&self, sensor: usize, frame: FrameId) -> Result<bool, ModelError> {
        let side = self
            .ft_sides
            .get(sensor)
            .ok_or(ModelError::FtSensorOutOfRange {
                index: sensor,
                count: self.ft_sides.len(),
            })?;
        side.child_side_frame
            .get(frame.index())
            .copied()
            .ok_or(ModelError::FrameOutOfRange {
                index: frame.index(),
                count: self.frames.len(),
            })
    }

    /// The force/torque sensor closest to `frame` on its way to the root: among the sensors whose child
    /// side holds `frame`, the one with the fewest frames on its child side (a foot sensor rather than the
    /// leg sensor above it). `None` when no sensor's child side holds it, or `frame` is not of this model.
    pub fn innermost_ft_sensor_holding(&self, frame: FrameId) -> Option<usize> {
        let side_size = |k: usize| {
            self.ft_sides[k]
                .child_side_frame
                .iter()
                .filter(|&&held| held)
                .count()
        };
        (0..self.ft_sides.len())
            .filter(|&k| matches!(self.ft_child_side_holds(k, frame), Ok(true)))
            .min_by_key(|&k| side_size(k))
    }

    /// Warnings raised while loading (physically inconsistent inertias, missing limits, massless bodies, ...).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Number of bodies (n + 1).
    pub fn body_count(&self) -> usize {
        self.bodies.len()
    }
}
