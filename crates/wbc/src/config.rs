//! Configuration of the whole-body controllers: a list of tasks, each with a type, a frame, gains, a mask,
//! a priority and a weight. Deserializable from TOML (`serde`, unknown keys and unknown task types are
//! errors). [`IkConfig::default_for_bundled_model`] and [`TsidConfig::default_for_bundled_model`] give
//! working task sets for `models/stride_humanoid.urdf`.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
pub use stride_qp::{Backend, QpSettings, Weight};

/// Priority of an equality task.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Priority {
    /// A hard constraint (`A x = b` exactly).
    Hard,
    /// A weighted least-squares cost `‖A x − b‖²_W`.
    #[default]
    Soft,
}

/// The reference and contact names of the walking stack (stride-walking fills them; the bundled defaults
/// and the runner's robot files use them).
pub mod walking {
    /// Left sole: the frame reference of the left foot's SE(3) task and the left sole's contact flag.
    pub const LEFT_FOOT: &str = "left_foot";
    /// Right sole: frame reference and contact flag.
    pub const RIGHT_FOOT: &str = "right_foot";
    /// Torso orientation reference (upright; translation unused), read by `so3` tasks.
    pub const TORSO: &str = "torso";
}

/// Which foot a contact belongs to: the TOML key `foot = "left"` of a contact task, kept as a shorthand
/// for `contact = "left_foot"` (`"right"`: `"right_foot"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Foot {
    /// The left foot.
    Left,
    /// The right foot.
    Right,
}

impl Foot {
    /// The contact name this foot stands for (`"left_foot"`, `"right_foot"`).
    pub fn contact_name(self) -> &'static str {
        match self {
            Foot::Left => walking::LEFT_FOOT,
            Foot::Right => walking::RIGHT_FOOT,
        }
    }
}

fn default_mask6() -> [bool; 6] {
    [true; 6]
}
fn default_mask3() -> [bool; 3] {
    [true; 3]
}
fn one() -> f64 {
    1.0
}

/// SE(3) tracking of a frame: `J ν = [ṗ*; ω*]` (IK, 7.1.6–7.1.8) or `J ν̇ + J̇ν = [p̈*; ω̇*]` (TSID,
/// 7.2.9–7.2.11), feedforward + PD on R³ × SO(3), orientation error `Log(R_ref Rᵀ)`.
///
/// | key | unit | default | meaning |
/// |---|---|---|---|
/// | `name` | – | required | task name (unique; used in residual reports) |
/// | `frame` | – | required | model frame |
/// | `reference` | – | required | name of the reference in the input ([`crate::WbcInput::set_frame_reference`]), or `"initial"`: the frame's pose at the first tick |
/// | `kp_linear`, `kp_angular` | 1/s (IK), 1/s² (TSID) | 0 | proportional gains |
/// | `kd_linear`, `kd_angular` | 1/s | 0 | derivative gains (TSID only) |
/// | `mask` | – | all true | rows kept: `[x, y, z, rx, ry, rz]` (world axes) |
/// | `priority` | – | `soft` | `hard` or `soft` |
/// | `weight` | – | 1 | soft weight (scalar or per kept row); an error on a hard task |
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Se3TaskConfig {
    /// Task name.
    pub name: String,
    /// Frame name in the model.
    pub frame: String,
    /// Name of the reference in the input (any name; walking uses `left_foot`, `right_foot`, `torso`), or
    /// `"initial"`: the frame's pose at the first tick after construction or reset, held still.
    pub reference: String,
    /// Position gain.
    #[serde(default)]
    pub kp_linear: f64,
    /// Orientation gain.
    #[serde(default)]
    pub kp_angular: f64,
    /// Linear velocity gain (TSID).
    #[serde(default)]
    pub kd_linear: f64,
    /// Angular velocity gain (TSID).
    #[serde(default)]
    pub kd_angular: f64,
    /// Rows kept `[x, y, z, rx, ry, rz]`.
    #[serde(default = "default_mask6")]
    pub mask: [bool; 6],
    /// Hard or soft.
    #[serde(default)]
    pub priority: Priority,
    /// Soft weight (scalar or per kept row; default 1). Setting it on a hard task is an error.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weight: Option<Weight>,
}

/// How an orientation task relates its reference to the frame (`reference_offset` of an `so3` task).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ReferenceOffset {
    /// The reference is the frame's orientation: `R* = R_ref` (the frame is world-aligned when the reference
    /// is; e.g. the bundled humanoid's `chest` and `root_link`, x forward and z up when upright).
    #[default]
    None,
    /// The frame keeps the orientation relative to the reference it has at the first tick after
    /// construction or `reset` (`stride_block::Block`): `R* = R_ref · R_off`, `R_off = R_ref(t₀)ᵀ R(t₀)`;
    /// angular velocity and acceleration references are unchanged (`R_off` is constant). For models whose
    /// frames are not world-aligned when upright (iCub's `chest` has x left, y up, z forward, its
    /// `root_link` x backward), started upright at the reference's heading (as the runner does).
    Initial,
}

/// SO(3) (orientation) or R³ (position) tracking of a frame. Same keys as [`Se3TaskConfig`] with
/// `kp`, `kd` and a 3-entry `mask`, plus `reference_offset` (`so3` only; `none` or `initial`, default
/// `none`, see [`ReferenceOffset`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Frame3TaskConfig {
    /// Task name.
    pub name: String,
    /// Frame name in the model.
    pub frame: String,
    /// Name of the reference in the input, or `"initial"` (see [`Se3TaskConfig::reference`]).
    pub reference: String,
    /// Orientation offset between the reference and the frame (`so3` tasks; `r3` tasks accept only
    /// `none`).
    #[serde(default)]
    pub reference_offset: ReferenceOffset,
    /// Proportional gain (1/s in IK, 1/s² in TSID).
    #[serde(default)]
    pub kp: f64,
    /// Derivative gain (1/s, TSID only).
    #[serde(default)]
    pub kd: f64,
    /// Rows kept `[x, y, z]` (world axes).
    #[serde(default = "default_mask3")]
    pub mask: [bool; 3],
    /// Hard or soft.
    #[serde(default)]
    pub priority: Priority,
    /// Soft weight (scalar or per kept row; default 1). Setting it on a hard task is an error.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weight: Option<Weight>,
}

/// CoM tracking: IK `J_com ν = ẋ_ref + K_p (x_ref − x)` [Romualdi 2022, eq. 7.1.4]; TSID linear momentum rate
/// `Σ f_lin = m (ẍ_ref + K_d (ẋ_ref − ẋ) + K_p (x_ref − x)) − m g` (7.2.4, 7.2.7).
///
/// | key | unit | default |
/// |---|---|---|
/// | `name` | – | required |
/// | `kp` | 1/s (IK), 1/s² (TSID) | 0 |
/// | `kd` | 1/s (TSID) | 0 |
/// | `kp_z` | as `kp` | `kp` | the vertical row's `K_p` |
/// | `kd_z` | 1/s (TSID) | `kd` | the vertical row's `K_d` |
/// | `mask` | – | `[true, true, true]` |
/// | `priority` | – | `soft` |
/// | `weight` | – | 1 (soft only: an error on a hard task) |
///
/// The vertical gains are separate because the horizontal ones are bounded by the simplified layer's
/// ZMP-CoM loop, which closes through them ([`BUNDLED_TSID_COM_KD`]), and the CoM height is in no such loop:
/// the walking TSID's `K_p` 25 s⁻² leaves the height 1 mm off per 0.8 N of force the torques do not deliver
/// (the joints' Coulomb friction, the torque lag at start-up), [`BUNDLED_TSID_COM_KP_Z`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ComTaskConfig {
    /// Task name.
    pub name: String,
    /// Proportional gain.
    #[serde(default)]
    pub kp: f64,
    /// Derivative gain (TSID).
    #[serde(default)]
    pub kd: f64,
    /// Proportional gain of the vertical row (`None`: `kp`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kp_z: Option<f64>,
    /// Derivative gain of the vertical row, TSID (`None`: `kd`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kd_z: Option<f64>,
    /// Rows kept `[x, y, z]`.
    #[serde(default = "default_mask3")]
    pub mask: [bool; 3],
    /// Hard or soft.
    #[serde(default)]
    pub priority: Priority,
    /// Soft weight (scalar or per kept row; default 1). Setting it on a hard task is an error.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weight: Option<Weight>,
}

/// Centroidal angular momentum about the CoM: IK `J_CMM,ω ν = h_ref + K_p ∫…` (here `h_ref`, 7.1.5);
/// TSID `Σ (p_j − x_com) × f_j + μ_j = ḣ_ref + K_p (h_ref − h)` (7.2.5, 7.2.8). The reference comes from
/// `input.angular_momentum` (usually zero).
///
/// | key | unit | default |
/// |---|---|---|
/// | `name` | – | required |
/// | `kp` | 1/s (TSID) | 0 |
/// | `reference_joints` | joint names (TSID) | empty: the reference is `input.angular_momentum` |
/// | `reference_frames` | `{ frame, reference }` list (TSID) | empty |
/// | `priority` | – | `soft` |
/// | `weight` | – | 1 (soft only: an error on a hard task) |
///
/// `reference_joints` (TSID only; the QP-IK refuses it): the reference is instead the angular momentum of
/// the listed joints' motion with the base not rotating and the other joints still,
/// `h* = A_ω(q) [v_B; 0; ṡ_listed]` (`A_ω`: the angular rows of the centroidal momentum matrix [Orin 2013]).
/// Listing the legs asks the ground to carry the momentum of the legs' motion, where a zero reference makes
/// the torso, pelvis and arms counter-rotate them (docs/soft-ground.md); it stands in for the momentum of
/// the planned whole-body motion `h^ref` of [Romualdi 2022, eq. 8.2.4].
///
/// `reference_frames` (TSID only): the joints between the base and each listed frame instead move so that
/// the frame follows its reference's velocity (the planned one) with the base translating at its measured
/// velocity and not rotating, `ṡ_chain = J_chainᵀ (J_chain J_chainᵀ + λ² I)⁻¹ (v* − J_base,lin v_B)`
/// (λ = 1e-3): the momentum of the planned feet motion, a velocity-level inverse kinematics of the planned
/// references through the centroidal momentum matrix (the thesis's `h^ref`); joints of no listed chain keep
/// their `reference_joints` velocity or none.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AngularMomentumTaskConfig {
    /// Task name.
    pub name: String,
    /// Proportional gain (TSID).
    #[serde(default)]
    pub kp: f64,
    /// TSID: the joints whose motion (base not rotating) sets the reference; empty: `input.angular_momentum`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub reference_joints: Vec<String>,
    /// TSID: frames whose chains from the base follow their references' velocities in the reference
    /// (see above); empty: none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub reference_frames: Vec<MomentumReferenceFrame>,
    /// Hard or soft.
    #[serde(default)]
    pub priority: Priority,
    /// Soft weight (scalar or per kept row; default 1). Setting it on a hard task is an error.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weight: Option<Weight>,
}

/// A frame of an angular momentum task's `reference_frames`: the model frame and the name of its reference
/// in the input (walking: `left_foot`, `right_foot` for the soles).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MomentumReferenceFrame {
    /// Frame name in the model.
    pub frame: String,
    /// Name of its reference in the input.
    pub reference: String,
}

/// Joint regularization / tracking: IK `ṡ = ṡ_ref + K_p (s_ref − s)` [Romualdi 2022, eq. 7.1.12]; TSID
/// `s̈ = s̈_ref + K_d (ṡ_ref − ṡ) + K_p (s_ref − s)` [Romualdi 2022, eq. 7.2.17]. `s_ref` is `input.posture` when given,
/// else `posture` below (joints not listed: 0). Velocity and acceleration references are zero.
///
/// | key | unit | default |
/// |---|---|---|
/// | `name` | – | required |
/// | `kp` | 1/s (IK), 1/s² (TSID) | 0 |
/// | `kd` | 1/s (TSID) | 0 |
/// | `posture` | rad by joint name | empty (all 0) |
/// | `weight` | – | 1 (every joint; soft only: an error on a hard task) |
/// | `joint_weights` | by joint name | empty (overrides `weight`) |
/// | `priority` | – | `soft` |
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointRegularizationTaskConfig {
    /// Task name.
    pub name: String,
    /// Proportional gain.
    #[serde(default)]
    pub kp: f64,
    /// Derivative gain (TSID).
    #[serde(default)]
    pub kd: f64,
    /// Reference posture by joint name (rad).
    #[serde(default)]
    pub posture: BTreeMap<String, f64>,
    /// Weight of every joint not in `joint_weights` (soft tasks; default 1). Setting it, or
    /// `joint_weights`, on a hard task is an error.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weight: Option<f64>,
    /// Per-joint weights.
    #[serde(default)]
    pub joint_weights: BTreeMap<String, f64>,
    /// Hard or soft.
    #[serde(default)]
    pub priority: Priority,
}

/// Joint position limits as bounds on the decision variable (always hard). IK: one-step Euler
/// look-ahead `(s⁻ − s)/dt ≤ ṡ ≤ (s⁺ − s)/dt` [Romualdi 2022, eq. 7.1.15]; TSID: `2(s⁻ − s − T ṡ)/T² ≤ s̈ ≤ 2(s⁺ − s − T ṡ)/T²`
/// (7.2.29 with erratum 13) with look-ahead time `T`.
///
/// | key | unit | default | meaning |
/// |---|---|---|---|
/// | `name` | – | required | |
/// | `margin` | rad | 0 | limits shrunk by this on both sides |
/// | `look_ahead` | s | the controller period | `dt` / `T` above |
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointPositionLimitsTaskConfig {
    /// Task name.
    pub name: String,
    /// Margin inside the URDF limits (rad).
    #[serde(default)]
    pub margin: f64,
    /// Look-ahead time (s); `None`: the controller period.
    #[serde(default)]
    pub look_ahead: Option<f64>,
}

/// Joint velocity limits (always hard): IK `|ṡ| ≤ scale v_max`; TSID `(−scale v_max − ṡ)/dt ≤ s̈ ≤
/// (scale v_max − ṡ)/dt`. `v_max` from the URDF.
///
/// | key | unit | default |
/// |---|---|---|
/// | `name` | – | required |
/// | `scale` | – | 1 |
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointVelocityLimitsTaskConfig {
    /// Task name.
    pub name: String,
    /// Fraction of the URDF velocity limit.
    #[serde(default = "one")]
    pub scale: f64,
}

/// Floating-base dynamics `M ν̇ + h = [0; τ] + Σ Jⱼᵀ fⱼ` (7.2.14–7.2.15), always hard. The joint rows
/// define τ, which is eliminated (see docs/wbc.md); the 6 base rows stay as equality constraints.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FloatingBaseDynamicsTaskConfig {
    /// Task name.
    pub name: String,
}

/// Joint torque limits `−scale τ_max ≤ τ ≤ scale τ_max` [Romualdi 2022, eq. 7.2.30], always hard; `τ_max` is the URDF
/// effort limit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointTorqueLimitsTaskConfig {
    /// Task name.
    pub name: String,
    /// Fraction of the URDF effort limit.
    #[serde(default = "one")]
    pub scale: f64,
}

/// A rigid planar contact on any frame (feet, hands; TSID), switched by name in the input
/// ([`crate::WbcInput::set_contact`]). While the contact is loaded it brings: a 6D contact wrench
/// variable (mixed: force and torque about the frame origin, world orientation), the contact constraint
/// `J ν̇ + J̇ν = −K_d v − K_p e` (feet do not accelerate; `K_p = K_d = 0` by default) which replaces any
/// frame task on the same frame, and the feasibility rows (linearized friction cone, unilateral and bounded
/// normal force, CoP inside the sole rectangle, torsional friction) expressed in the frame's orientation.
/// Load changes ramp the normal-force upper bound over `ramp_time` (see docs/wbc.md).
///
/// | key | unit | default | meaning |
/// |---|---|---|---|
/// | `name` | – | required | |
/// | `frame` | – | required | contact frame (centre of the contact surface, z its normal, pointing into the robot) |
/// | `contact` | – | required (or `foot`) | name of the contact flag in the input, e.g. `left_foot`, `l_hand` |
/// | `foot` | – | – | shorthand: `left` = `contact = "left_foot"`, `right` = `"right_foot"` (not with `contact`) |
/// | `friction` | – | 0.33 | static friction coefficient μ |
/// | `facets` | – | 1 | friction pyramid slices S (4S facets, inscribed) |
/// | `foot_x` | m | [-0.1, 0.1] | sole rectangle, x in the frame |
/// | `foot_y` | m | [-0.045, 0.045] | sole rectangle, y in the frame |
/// | `torsional_friction` | m | 0.01 | `|μ_z| ≤ γ f_z` |
/// | `min_normal_force` | N | 0 | lower bound on f_z while loaded |
/// | `max_normal_force` | N | 1000 | upper bound on f_z when fully loaded |
/// | `ramp_time` | s | 0.02 | load / unload ramp of the f_z upper bound |
/// | `kp`, `kd` | 1/s², 1/s | 0, 0 | contact-constraint stabilization |
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactTaskConfig {
    /// Task name.
    pub name: String,
    /// Contact frame.
    pub frame: String,
    /// Name of the input's contact flag that closes and opens it (`""`: from `foot`).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub contact: String,
    /// Shorthand for `contact = "left_foot"` / `"right_foot"` (TOML files of the feet).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub foot: Option<Foot>,
    /// Friction coefficient.
    #[serde(default = "default_friction")]
    pub friction: f64,
    /// Friction pyramid slices.
    #[serde(default = "default_facets")]
    pub facets: usize,
    /// Sole rectangle along x (m).
    #[serde(default = "default_foot_x")]
    pub foot_x: [f64; 2],
    /// Sole rectangle along y (m).
    #[serde(default = "default_foot_y")]
    pub foot_y: [f64; 2],
    /// Torsional friction length (m).
    #[serde(default = "default_torsional")]
    pub torsional_friction: f64,
    /// Minimum normal force (N).
    #[serde(default)]
    pub min_normal_force: f64,
    /// Maximum normal force (N).
    #[serde(default = "default_max_fz")]
    pub max_normal_force: f64,
    /// Ramp time of load changes (s).
    #[serde(default = "default_ramp")]
    pub ramp_time: f64,
    /// Position stabilization gain.
    #[serde(default)]
    pub kp: f64,
    /// Velocity stabilization gain.
    #[serde(default)]
    pub kd: f64,
}

impl ContactTaskConfig {
    /// A contact task named `frame` on frame `frame`, switched by the contact flag `frame`, with friction
    /// coefficient `friction` and the defaults of the table above (a 0.2 m × 0.09 m rectangle: set
    /// `foot_x` / `foot_y` for a hand).
    pub fn new(frame: &str, friction: f64) -> Self {
        ContactTaskConfig {
            name: frame.to_owned(),
            frame: frame.to_owned(),
            contact: frame.to_owned(),
            foot: None,
            friction,
            facets: default_facets(),
            foot_x: default_foot_x(),
            foot_y: default_foot_y(),
            torsional_friction: default_torsional(),
            min_normal_force: 0.0,
            max_normal_force: default_max_fz(),
            ramp_time: default_ramp(),
            kp: 0.0,
            kd: 0.0,
        }
    }

    /// The input contact flag's name: `contact`, or the one of `foot`. Errors: both or neither given.
    pub fn contact_name(&self) -> Result<&str, crate::error::WbcError> {
        let bad = |reason: &str| crate::error::WbcError::InvalidConfig {
            task: self.name.clone(),
            key: "contact",
            reason: reason.into(),
        };
        match (self.contact.is_empty(), self.foot) {
            (false, None) => Ok(&self.contact),
            (true, Some(foot)) => Ok(foot.contact_name()),
            (true, None) => Err(bad(
                "missing: name the input's contact flag (e.g. `left_foot`)",
            )),
            (false, Some(_)) => Err(bad("give `contact` or its shorthand `foot`, not both")),
        }
    }
}

pub(crate) fn default_friction() -> f64 {
    0.33
}
fn default_facets() -> usize {
    1
}
fn default_foot_x() -> [f64; 2] {
    [-0.1, 0.1]
}
fn default_foot_y() -> [f64; 2] {
    [-0.045, 0.045]
}
fn default_torsional() -> f64 {
    0.01
}
fn default_max_fz() -> f64 {
    1000.0
}
fn default_ramp() -> f64 {
    0.02
}

/// Regularization of the contact wrenches toward `input.desired_wrenches` (zero when absent):
/// `‖f − f_ref‖²_W` [Romualdi 2022, eq. 7.2.25].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WrenchRegularizationTaskConfig {
    /// Task name.
    pub name: String,
    /// Weight (scalar or 6 values `[fx, fy, fz, mx, my, mz]`, applied to every contact).
    #[serde(default)]
    pub weight: Weight,
}

/// Regularization of the joint torques toward zero: `‖τ‖²_W` [Romualdi 2022, eq. 7.2.25], with τ expressed through the
/// dynamics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TorqueRegularizationTaskConfig {
    /// Task name.
    pub name: String,
    /// Weight (scalar or one per joint).
    #[serde(default)]
    pub weight: Weight,
}

/// Global ZMP of the contact wrenches equal to `input.desired_zmp` (7.2.23–7.2.24). Inactive (rows
/// zeroed) when the input has no desired ZMP. Assumes coplanar horizontal contacts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ZmpTaskConfig {
    /// Task name.
    pub name: String,
    /// Hard or soft.
    #[serde(default)]
    pub priority: Priority,
    /// Soft weight (scalar or per kept row; default 1). Setting it on a hard task is an error.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weight: Option<Weight>,
}

/// One entry of a controller's task list; the TOML key `type` selects the variant.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum TaskConfig {
    /// SE(3) tracking of a frame.
    Se3(Se3TaskConfig),
    /// Orientation tracking of a frame.
    So3(Frame3TaskConfig),
    /// Position tracking of a frame.
    R3(Frame3TaskConfig),
    /// CoM tracking.
    Com(ComTaskConfig),
    /// Centroidal angular momentum.
    AngularMomentum(AngularMomentumTaskConfig),
    /// Joint regularization / posture tracking.
    JointRegularization(JointRegularizationTaskConfig),
    /// Joint position limits.
    JointPositionLimits(JointPositionLimitsTaskConfig),
    /// Joint velocity limits.
    JointVelocityLimits(JointVelocityLimitsTaskConfig),
    /// Floating-base dynamics (TSID only).
    FloatingBaseDynamics(FloatingBaseDynamicsTaskConfig),
    /// Joint torque limits (TSID only).
    JointTorqueLimits(JointTorqueLimitsTaskConfig),
    /// Rigid contact + wrench feasibility (TSID only).
    Contact(ContactTaskConfig),
    /// Contact wrench regularization (TSID only).
    WrenchRegularization(WrenchRegularizationTaskConfig),
    /// Joint torque regularization (TSID only).
    TorqueRegularization(TorqueRegularizationTaskConfig),
    /// Global ZMP (TSID only).
    Zmp(ZmpTaskConfig),
}

impl TaskConfig {
    /// The task's name.
    pub fn name(&self) -> &str {
        match self {
            TaskConfig::Se3(c) => &c.name,
            TaskConfig::So3(c) | TaskConfig::R3(c) => &c.name,
            TaskConfig::Com(c) => &c.name,
            TaskConfig::AngularMomentum(c) => &c.name,
            TaskConfig::JointRegularization(c) => &c.name,
            TaskConfig::JointPositionLimits(c) => &c.name,
            TaskConfig::JointVelocityLimits(c) => &c.name,
            TaskConfig::FloatingBaseDynamics(c) => &c.name,
            TaskConfig::JointTorqueLimits(c) => &c.name,
            TaskConfig::Contact(c) => &c.name,
            TaskConfig::WrenchRegularization(c) => &c.name,
            TaskConfig::TorqueRegularization(c) => &c.name,
            TaskConfig::Zmp(c) => &c.name,
        }
    }

    /// The TOML `type` string.
    pub fn type_name(&self) -> &'static str {
        match self {
            TaskConfig::Se3(_) => "se3",
            TaskConfig::So3(_) => "so3",
            TaskConfig::R3(_) => "r3",
            TaskConfig::Com(_) => "com",
            TaskConfig::AngularMomentum(_) => "angular_momentum",
            TaskConfig::JointRegularization(_) => "joint_regularization",
            TaskConfig::JointPositionLimits(_) => "joint_position_limits",
            TaskConfig::JointVelocityLimits(_) => "joint_velocity_limits",
            TaskConfig::FloatingBaseDynamics(_) => "floating_base_dynamics",
            TaskConfig::JointTorqueLimits(_) => "joint_torque_limits",
            TaskConfig::Contact(_) => "contact",
            TaskConfig::WrenchRegularization(_) => "wrench_regularization",
            TaskConfig::TorqueRegularization(_) => "torque_regularization",
            TaskConfig::Zmp(_) => "zmp",
        }
    }
}

/// How the kinematic QP evaluates its feedback terms [Romualdi 2022, §7.1.3].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum IkFeedback {
    /// Position-controlled robot: the IK integrates its own state and uses it for the task errors
    /// (open-loop IK; the measured state only initializes it at the first tick after reset).
    #[default]
    Integrated,
    /// Velocity-controlled robot: the task errors use the measured state of every tick; the integrated
    /// joint positions are still returned (measured + dt ν).
    Measured,
}

/// Kinematic QP-IK configuration [Romualdi 2022, eq. 7.1.16]. The control period (integration step, default limit
/// look-ahead) is an argument of [`crate::QpIk::new`], not a key.
///
/// | key | unit | default | meaning |
/// |---|---|---|---|
/// | `feedback` | – | `integrated` | `integrated` (position control) or `measured` |
/// | `qp` | – | stride-qp defaults | `backend` (`active_set` / `clarabel`), `regularization`, `fallback`, `relaxation_weight`, … |
/// | `eliminate_equalities` | – | true | solve the null-space reduced QP (no hard equalities) first; the full QP only when that fails |
/// | `tasks` | – | see `default_for_bundled_model` | task list |
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IkConfig {
    /// Feedback source.
    #[serde(default)]
    pub feedback: IkFeedback,
    /// stride-qp settings (backend, regularization, fallback, relaxation weight, backend settings).
    #[serde(default)]
    pub qp: QpSettings,
    /// Solve stride-qp's null-space reduced problem first (hard equalities eliminated), else the full one.
    #[serde(default = "yes")]
    pub eliminate_equalities: bool,
    /// Tasks.
    pub tasks: Vec<TaskConfig>,
}

fn yes() -> bool {
    true
}

/// Torque TSID configuration [Romualdi 2022, eq. 7.2.31]. The control period (load ramps, limit look-ahead) is an
/// argument of [`crate::Tsid::new`]; gravity is the model's ([`stride_model::Model::gravity`]).
///
/// | key | unit | default | meaning |
/// |---|---|---|---|
/// | `qp` | – | stride-qp defaults | `backend` (`active_set` / `clarabel`), `regularization`, `fallback`, `relaxation_weight`, … |
/// | `eliminate_equalities` | – | true | solve the null-space reduced QP (no hard equalities) first; the full QP only when that fails |
/// | `tasks` | – | see `default_for_bundled_model` | task list |
/// | `flexible_joints` | – | `[]` | passive flexible joints (TSID-Flex) |
/// | `contact_model` | – | `"rigid"` | `"rigid"` or `"compliant"` (TSID-Compliant; settings `compliant`) |
/// | `actuators` | – | ideal | the motors' torque lag and friction the command compensates ([`crate::ActuatorConfig`]) |
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TsidConfig {
    /// stride-qp settings (backend, regularization, fallback, relaxation weight, backend settings).
    #[serde(default)]
    pub qp: QpSettings,
    /// Solve stride-qp's null-space reduced problem first (hard equalities eliminated), else the full one.
    #[serde(default = "yes")]
    pub eliminate_equalities: bool,
    /// Tasks.
    pub tasks: Vec<TaskConfig>,
    /// Passive flexible joints (TSID-Flex, [Romualdi 2022, §9.2]): joint names whose torque is not a
    /// decision but the measured passive torque `WbcInput::flexible_torques`; their rows of the joint
    /// dynamics join the `floating_base_dynamics` task as hard equalities [Romualdi 2022, eq. (9.2.6)].
    /// Empty (default): every joint is actuated (the rigid TSID).
    #[serde(default)]
    pub flexible_joints: Vec<String>,
    /// `"rigid"` (default): the contacts do not move and their wrenches are decisions
    /// [Romualdi 2022, eq. 7.2.31]. `"compliant"`: TSID-Compliant [Romualdi 2022, §8.2, eq. 8.2.16], the
    /// wrench **rates** of the loaded contacts are decisions and the measured wrenches
    /// (`ContactInput::measured_wrench`) enter the dynamics; its settings are `compliant`.
    #[serde(default)]
    pub contact_model: ContactModel,
    /// Settings of the compliant contact model (read when `contact_model = "compliant"`).
    #[serde(default)]
    pub compliant: CompliantConfig,
    /// The motors' dynamics the commanded torques compensate (`[wbc.tsid.actuators]`, applied by the
    /// runner to the TSID's torques: [`crate::ActuatorCompensation`]); default ideal motors, no
    /// compensation.
    #[serde(default)]
    pub actuators: crate::ActuatorConfig,
}

/// How the TSID models its contacts (`[wbc.tsid] contact_model`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ContactModel {
    /// Rigid contacts: the sole does not move, the wrench is a decision.
    #[default]
    Rigid,
    /// Visco-elastic ground [Romualdi 2022, §8.1]: the wrench follows the sole's motion (Lemma 1), its
    /// rate is a decision.
    Compliant,
}

/// TSID-Compliant settings [Romualdi 2022, §8.2] (`[wbc.tsid.compliant]`).
///
/// | key | unit | default | meaning |
/// |---|---|---|---|
/// | `ground_stiffness` | N/m³ | 1e6 | `k` of the ground's density `ρ = k(x̄ − x) − b ẋ` [eq. 8.1.6] |
/// | `ground_damping` | N·s/m³ | 1e4 | `b` of the same density |
/// | `sole_length`, `sole_width` | m | 0.20, 0.09 | the sole rectangle `l × w`, centred on the contact frame |
/// | `momentum_rate_gain` | 1/s | 20 | `k_h`: the momentum tasks ask `ḧ = k_h (ḣ* − ḣ)` |
/// | `wrench_rate_gain` | 1/s | 10 | `k_f`: the wrench regularization asks `ḟ = k_f (f* − f)` [eq. 8.2.9] |
/// | `feasibility_horizon` | s | 0.02 | `T` of the one-step-ahead feasibility `A (f + ḟ T) ≤ 0` [eq. 8.2.12] |
/// | `angular_momentum_damping` | – | 0 (off) | `ζ`: the angular momentum tasks' `K_p` derived from `k_h`, `K_p = k_h / (4 ζ²)`, so that their rows' loop `ḧ = k_h (K_p (h* − h) − ḣ)` has the damping ratio `ζ` at any `k_h` (1: critically damped, both poles at `−k_h/2`); 0: each task's own `kp` |
/// | `estimate_ground` | – | false | estimate `k`, `b` online (RLS, [eq. 8.2.20–8.2.22]), one estimate per contact from its loaded sole, covariance reset at its touch-down, prior the two values above with their own size as standard deviation; each contact's model uses its estimate |
/// | `estimator_wrench_std` | N, N·m | [2, 0.2] | standard deviations of the measured force and torque for that estimate |
/// | `estimator_contact_force` | N | 5 | with `estimate_ground`: a sole after its planned touch-down meets the ground when its measured normal force exceeds this; until then its rest pose follows it and its estimate is not fed, then the covariance is reset and the rest pose set there |
/// | `estimator_rest_pose` | – | `"level"` | with `estimate_ground`: the zero-force pose of a sole where it meets the ground: `"level"` its pose rotated about its lowest corner until flat (the horizontal plane through that corner: flat ground); `"impact"` its pose there as it is (tilted as it landed), raised by the static sink of its force (see [`EstimatorRestPose`]) |
/// | `estimator_rows` | – | `"all"` | with `estimate_ground`: the rows of the measured wrench (world axes) the estimate reads: `"all"` the six of [eq. 8.2.17]; `"normal"` those the ground's normal density makes on flat ground, the vertical force and the roll and pitch torques; `"vertical_force"` the vertical force alone (see [`EstimatorRows`]) |
/// | `estimate_rest_height` | – | false | with `estimate_ground`: estimate a third parameter, the error `δ` of the rest (zero-force) height the regressor measures the sole's sink from, as `k δ` with the column `l w abs(e₃ᵀRe₃) e₃` (see [`crate::GroundRestEstimator`]), reset to zero at each touch-down; `k̂`, `b̂` then do not absorb the rest plane's error |
/// | `estimator_rest_height_std` | m | 0.001 | with `estimate_rest_height`: the standard deviation of `δ`'s prior (zero) |
/// | `estimator_open_loop` | – | false | with `estimate_ground`: run and log the estimate but give the contact models (and the runner's `plan_on_surface`) the configured `ground_stiffness`, `ground_damping` |
/// | `estimator_accept_std` | – | inf | with `estimate_ground` (closed loop): the gate. from each planned touch-down a contact's model keeps the prior until a parameter of the new landing's estimate has a standard deviation (the covariance's) at most this fraction of it, then takes it (holding the last one taken while the bound is not met); `inf`: every estimate, at once (off) |
/// | `estimator_reset` | – | true | with `estimate_ground`: reset a contact's estimate covariance at its touch-down [Colman 2006] (`false` only to show what the reset buys) |
/// | `plan_on_surface` | – | false | the runner plans the footholds from the soles' zero-force poses (raised by their static sink `f_z / (k l w)`), so the swing feet land on the ground's surface, not as deep as the standing feet sank |
/// | `held_acceleration` | – | false | the contact dynamics give the wrench rate averaged over one control period of a held acceleration: the acceleration gain of eq. 8.2.14 uses the damping `b + k·period/2` (see [`crate::soft_contact::WrenchRate::held_over`]) |
/// | `wrench_source` | – | `"measured"` | the wrench `f_c` the rows read: `"measured"` the input's (`ContactInput::measured_wrench`, every tick); `"model"` Lemma 1's wrench of the sole's state about its rest (touch-down) pose [eq. 8.1.7] (zero for a contact out of the QP); `"filtered"` the wrench the last solve predicted (`f + ḟ·period`) corrected toward the measured one with the time constant `wrench_filter_time` (see [`WrenchSource`]) |
/// | `wrench_filter_time` | s | 0.05 | time constant of the `"filtered"` wrench's correction toward the measured one |
/// | `lift_off_force` | N | inf | a contact whose load ramp has ended (planned lift-off) stays in the QP while its measured normal force exceeds this, its normal-force bound that measured force (the sole may only unload, toward the planned zero wrench of the wrench regularization), so that the swing task takes a sole that no longer carries the robot; `inf`: it leaves the QP when its ramp ends |
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CompliantConfig {
    /// Ground stiffness density `k`, N/m³.
    pub ground_stiffness: f64,
    /// Ground damping density `b`, N·s/m³.
    pub ground_damping: f64,
    /// Sole length along the contact frame's x, m.
    pub sole_length: f64,
    /// Sole width along the contact frame's y, m.
    pub sole_width: f64,
    /// `k_h`: the CoM and angular momentum tasks ask `ḧ = k_h (ḣ* − ḣ)` [Romualdi 2022, eq. 8.2.4], 1/s.
    pub momentum_rate_gain: f64,
    /// `k_f`: the wrench regularization asks `ḟ = k_f (f* − f)` [Romualdi 2022, eq. 8.2.9], 1/s.
    pub wrench_rate_gain: f64,
    /// `T`: the wrench feasibility holds for `f + T ḟ` [Romualdi 2022, eq. 8.2.12], s.
    pub feasibility_horizon: f64,
    /// `ζ` (> 0): the angular momentum tasks' `K_p` is `k_h / (4 ζ²)` (the damping ratio `ζ` of their rows'
    /// second-order loop at any `k_h`); 0: each task's configured `kp`.
    pub angular_momentum_damping: f64,
    /// Estimate `k`, `b` online from the measured wrenches of the loaded soles [Romualdi 2022, §8.2.3].
    pub estimate_ground: bool,
    /// `[force (N), torque (N·m)]` standard deviations of the measured wrench for the ground estimate.
    pub estimator_wrench_std: [f64; 2],
    /// With `estimate_ground`: reset a contact's estimate covariance at its touch-down [Colman 2006].
    pub estimator_reset: bool,
    /// With `estimate_ground`: also estimate the rest height's error `δ` (as `k δ`, a third regressor
    /// column), reset to zero at each touch-down ([`crate::GroundRestEstimator`]).
    pub estimate_rest_height: bool,
    /// With `estimate_rest_height`: standard deviation of the prior `δ = 0`, m (> 0).
    pub estimator_rest_height_std: f64,
    /// With `estimate_ground`: the estimate runs and is logged, the contact models keep the configured
    /// ground (open loop).
    pub estimator_open_loop: bool,
    /// With `estimate_ground`, closed loop: from each planned touch-down a contact's model keeps the prior
    /// until a parameter of the estimate has a standard deviation at most this fraction of it, then takes
    /// it (holding the last one taken while the bound is not met); `inf`: off (every estimate at once).
    pub estimator_accept_std: f64,
    /// With `estimate_ground`: the measured normal force (N) above which a sole that touched down in the
    /// plan is on the ground (its rest pose is set and its estimate fed from then on).
    pub estimator_contact_force: f64,
    /// With `estimate_ground`: the zero-force pose of a sole where it meets the ground
    /// ([`EstimatorRestPose`]).
    pub estimator_rest_pose: EstimatorRestPose,
    /// With `estimate_ground`: the rows of the measured wrench the estimate reads ([`EstimatorRows`]).
    pub estimator_rows: EstimatorRows,
    /// The runner plans the footholds from the soles' zero-force poses, raised by their static sink
    /// `f_z / (k l w)` of a flat sole [Romualdi 2022, eq. 8.1.7a], so that the swing feet land on the
    /// ground's surface rather than as deep as the standing feet sank.
    pub plan_on_surface: bool,
    /// The contact dynamics give the wrench rate averaged over one control period of a held acceleration
    /// (the acceleration gain of [Romualdi 2022, eq. 8.2.14] with the damping `b + k·period/2`); `false`:
    /// the instantaneous rate, whose sampled loop diverges for `period > 2b/k`.
    pub held_acceleration: bool,
    /// A contact whose load ramp has ended (its planned lift-off) stays in the QP while its measured normal
    /// force exceeds this (N), with that force as its normal-force bound (the sole may only unload): the
    /// swing task takes a sole that no longer carries the robot; `inf` (the default): the contact leaves
    /// the QP when its ramp ends.
    pub lift_off_force: f64,
    /// The wrench the rows read as `f_c` ([`WrenchSource`]).
    pub wrench_source: WrenchSource,
    /// Time constant of the `"filtered"` wrench's correction toward the measured one, s (> 0).
    pub wrench_filter_time: f64,
}

/// The zero-force (rest) pose of a sole where it meets the ground, with `estimate_ground`
/// (`[wbc.tsid.compliant] estimator_rest_pose`): the pose about which the regressor of the ground estimate
/// [Romualdi 2022, eq. 8.2.17] and the contact model measure the sole's deflection.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum EstimatorRestPose {
    /// Flat ground: the sole's pose at its impact rotated about its lowest corner until flat (roll and
    /// pitch removed, heading kept), the horizontal plane through the corner that met the ground.
    #[default]
    Level,
    /// The sole's pose at its impact as it is (tilted as it landed), raised by the static sink of its
    /// measured force: millimetres above flat ground for a sole landing on its heel.
    Impact,
}

/// The rows of a sole's measured wrench (force, torque about the sole centre; world axes) the ground
/// estimate reads, with `estimate_ground` (`[wbc.tsid.compliant] estimator_rows`). Lemma 1's density is
/// isotropic [Romualdi 2022, eq. 8.1.6]; a ground whose tangential law is not its normal one (stride-sim's
/// stick springs, anchored where each point touched down, with their own densities) makes the
/// horizontal forces and the yaw torque of a different law.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum EstimatorRows {
    /// The six rows of the regressor [Romualdi 2022, eq. 8.2.17]: an isotropic ground.
    #[default]
    All,
    /// The rows the normal density makes on flat ground: the vertical force and the roll and pitch
    /// torques.
    Normal,
    /// The vertical force alone.
    VerticalForce,
}

impl EstimatorRows {
    /// The rows (of `[f; μ]`, world axes) the estimate does not read.
    pub fn unread(self) -> &'static [usize] {
        match self {
            EstimatorRows::All => &[],
            EstimatorRows::Normal => &[0, 1, 5],
            EstimatorRows::VerticalForce => &[0, 1, 3, 4, 5],
        }
    }
}

/// The wrench `f_c` TSID-Compliant's rows read (`[wbc.tsid.compliant] wrench_source`).
///
/// The contact dynamics rows feed `f_c` back every tick [Romualdi 2022, eq. 8.2.13, 8.2.15]; a measured
/// wrench brings the sensors' noise and the estimate's inertial errors into that loop at the tick rate
/// (docs/soft-ground.md, "Stage 3 on the estimated state").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum WrenchSource {
    /// The input's measured wrench (`ContactInput::measured_wrench`), read every tick.
    #[default]
    Measured,
    /// Lemma 1's wrench [Romualdi 2022, eq. 8.1.7] of the sole's state (the input's) about its rest pose
    /// (its pose at touch-down, raised by the static sink of the measured wrench then), for the contacts
    /// in the QP; zero for the others.
    Model,
    /// The wrench the last solve predicted for this tick, `f + ḟ·period` (the QP's chosen rate), corrected
    /// toward the measured one by `period / (wrench_filter_time + period)` per tick: a complementary filter
    /// whose fast part is the controller's own wrench-rate model and whose slow part is the sensor.
    Filtered,
}

impl Default for CompliantConfig {
    fn default() -> Self {
        CompliantConfig {
            ground_stiffness: 1e6,
            ground_damping: 1e4,
            sole_length: stride_model::bundled::FOOT_LENGTH,
            sole_width: stride_model::bundled::FOOT_WIDTH,
            momentum_rate_gain: 20.0,
            wrench_rate_gain: 10.0,
            feasibility_horizon: 0.02,
            angular_momentum_damping: 0.0,
            estimate_ground: false,
            estimator_wrench_std: [2.0, 0.2],
            estimator_reset: true,
            estimate_rest_height: false,
            estimator_rest_height_std: 1e-3,
            estimator_open_loop: false,
            estimator_accept_std: f64::INFINITY,
            estimator_contact_force: 5.0,
            estimator_rest_pose: EstimatorRestPose::Level,
            estimator_rows: EstimatorRows::All,
            plan_on_surface: false,
            held_acceleration: false,
            lift_off_force: f64::INFINITY,
            wrench_source: WrenchSource::Measured,
            wrench_filter_time: 0.05,
        }
    }
}

/// Default posture of the bundled model (rad), slightly crouched, arms off the torso:
/// [`stride_model::bundled::POSTURE`].
pub fn bundled_posture() -> BTreeMap<String, f64> {
    stride_model::bundled::POSTURE
        .iter()
        .map(|&(joint, q)| (joint.to_owned(), q))
        .collect()
}

impl IkConfig {
    /// The QP-IK of [Romualdi 2022, eq. 7.1.16] for `models/stride_humanoid.urdf`: the walking preset
    /// ([`crate::presets::walking_ik`]) with the bundled robot's frames, posture and arm weights
    /// ([`crate::presets::WalkingPreset::bundled`]).
    pub fn default_for_bundled_model() -> Self {
        crate::presets::walking_ik(&crate::presets::WalkingPreset::bundled())
    }
}

/// CoP region of the default TSID contacts along the sole's x axis (m): 60 % of the 0.20 m sole's
/// half-length.
///
/// A compliant sole (stride-sim: a 3 × 3 grid of spring-damper points over 0.20 m × 0.09 m) keeps every
/// point loaded only while the CoP stays within 2/3 of the half-size from the centre (linear springs at
/// `−a, 0, a`: the far row unloads when the CoP reaches `2a/3`). Beyond that the foot rolls on its edge row,
/// which the rigid contact constraint does not model: with the full sole rectangle the TSID put the stance
/// foot's CoP on its edge at the first lift-off and the foot rolled over within 10 ms (ankle roll velocity
/// ×1.5 per tick up to 18 rad/s, then infeasible QPs). The region is kept at 90 % (x) and 83 % (y) of
/// that 2/3 bound; measured in stride-sim: 0.08 × 0.035 → 7 QP fallbacks in `walk_straight_torque`,
/// 0.07 × 0.03 and 0.06 × 0.025 → none.
pub const BUNDLED_COP_X: [f64; 2] = [-0.06, 0.06];
/// CoP region of the default TSID contacts along the sole's y axis (m): 56 % of the 0.09 m sole's
/// half-width; see [`BUNDLED_COP_X`].
pub const BUNDLED_COP_Y: [f64; 2] = [-0.025, 0.025];
/// CoM gain K_p (1/s²) of the default TSID.
pub const BUNDLED_TSID_COM_KP: f64 = 25.0;
/// CoM gain K_d (1/s) of the default TSID.
///
/// The runner closes the simplified layer's ZMP-CoM loop through the TSID's CoM task: that layer sets
/// `ẋ* = … + k_zmp (r_measured − r_desired)` at 100 Hz and the TSID turns it into `ẍ ≈ K_d (ẋ* − ẋ)`, which
/// moves the measured ZMP by `−(z_com/g) ẍ` within the same simplified tick. The loop gain per tick is
/// `(z_com/g) K_d k_zmp` ≈ 0.055 K_d k_zmp for the bundled robot (z_com 0.54 m; stride-simplified's
/// k_zmp is 1 standing, 1.5 walking): K_d = 20 gives 1.1 standing, a sign-alternating ZMP limit cycle at
/// 50 Hz that saturates at the sole edges (measured: ZMP error 94 mm RMS, 277 QP fallbacks, fall after
/// 2.8 s when standing). K_d = 5 gives 0.28 standing and 0.41 walking.
pub const BUNDLED_TSID_COM_KD: f64 = 5.0;
/// Vertical CoM gain K_p (1/s²) of the default TSID (`kp_z` of its `com` task), with
/// [`BUNDLED_TSID_COM_KD_Z`]: the torso's, pelvis's and posture's gains, critically damped.
///
/// The horizontal gains (25, 5) are bounded by the ZMP-CoM loop ([`BUNDLED_TSID_COM_KD`]); the height is not
/// in that loop. At `K_p` 25 the CoM task is a vertical spring of `m K_p` ≈ 820 N/m on the bundled robot, and
/// the force the torques fail to deliver stays in the height: stride-sim's default actuators (0.1 N·m
/// Coulomb friction per joint, a 30 Hz torque lag from zero at start-up) left the CoM 3–5 mm low while
/// standing at the start, 2.6 mm high standing at the end and 1 mm low walking. Measured on
/// `walk_straight_torque` to 1 m (docs/wbc.md, "The CoM height"): the height error 1.76 → 0.69 mm RMS, the
/// CoM error 2.7 → 2.3 mm.
pub const BUNDLED_TSID_COM_KP_Z: f64 = 100.0;
/// Vertical CoM gain K_d (1/s) of the default TSID; see [`BUNDLED_TSID_COM_KP_Z`].
pub const BUNDLED_TSID_COM_KD_Z: f64 = 20.0;

/// Weight of the bundled humanoid's TSID chest and pelvis (`root_link`) orientation tasks (K_p 100 s⁻², K_d
/// 20 s⁻¹, soft). Measured in stride-sim on a 4 m walk of 0.22 m steps every 0.5 s: chest alone at weight 10
/// (the previous default), the pelvis swung ±26° in roll and pitch and the robot fell after 2.4 m; pelvis
/// 50 with the chest at 10, the chest swung instead (fell at 0.2 m); both at 10, fell at 0.4 m; both at 50,
/// the goal at 0.26 m/s average. On the default walk both at 50 track better than the chest alone (DCM 7.3 vs
/// 7.9 mm RMS, largest tilt 1.8° vs 3.1°).
pub const BUNDLED_TSID_UPRIGHT_WEIGHT: f64 = 50.0;

impl TsidConfig {
    /// The TSID of [Romualdi 2022, eq. 7.2.31] for `models/stride_humanoid.urdf`: the walking preset
    /// ([`crate::presets::walking_tsid`]) with the bundled robot's frames, posture and arm weights.
    ///
    /// Two values are tuned for the torque-controlled robot in stride-sim (see their docs): the CoP region
    /// of the contacts ([`BUNDLED_COP_X`], [`BUNDLED_COP_Y`], a margin inside the sole for a compliant
    /// floor) and the CoM gains ([`BUNDLED_TSID_COM_KP`], [`BUNDLED_TSID_COM_KD`], low enough for the
    /// ZMP-CoM feedback of the simplified layer to stay stable).
    pub fn default_for_bundled_model() -> Self {
        crate::presets::walking_tsid(&crate::presets::WalkingPreset::bundled())
    }
}

/// Every task of a controller has its own name (names address tasks in errors, residuals and logs).
pub(crate) fn check_unique_names(tasks: &[TaskConfig]) -> Result<(), crate::error::WbcError> {
    let mut names = std::collections::BTreeSet::new();
    for task in tasks {
        if !names.insert(task.name()) {
            return Err(crate::error::WbcError::InvalidConfig {
                task: task.name().to_owned(),
                key: "name",
                reason: "duplicate task name".into(),
            });
        }
    }
    Ok(())
}
