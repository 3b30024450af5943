//! Task presets: the whole-body task lists of a walking humanoid, built from its frame names and its
//! posture, so a new robot states only what is its own.
//!
//! [`walking_ik`] and [`walking_tsid`] give the QP-IK [Romualdi 2022, eq. 7.1.16] and TSID [Romualdi 2022,
//! eq. 7.2.31] task lists the bundled humanoid walks with (`IkConfig::default_for_bundled_model` and
//! `TsidConfig::default_for_bundled_model` are these presets with [`WalkingPreset::bundled`]);
//! [`with_overrides`] replaces a preset's task by name or adds one. The runner builds the preset from
//! `robot.left_sole`, `robot.right_sole`, `robot.torso_frame`, `robot.base_frame` and
//! `robot.initial_joint_positions` (docs/wbc.md, "Task presets").
//!
//! ```
//! use stride_wbc::presets::{walking_ik, with_overrides, WalkingFrames, WalkingPreset};
//! use stride_wbc::{ComTaskConfig, Priority, TaskConfig};
//! let frames = WalkingFrames::new("left_sole", "right_sole", "torso_link", "pelvis");
//! let posture = [("left_knee_joint".to_string(), 0.7)].into_iter().collect();
//! let mut ik = walking_ik(&WalkingPreset::new(frames, posture));
//! let softer_com = TaskConfig::Com(ComTaskConfig {
//!     name: "com".into(), kp: 1.0, kd: 0.0, kp_z: None, kd_z: None, mask: [true; 3],
//!     priority: Priority::Hard, weight: None,
//! });
//! with_overrides(&mut ik.tasks, &[softer_com]);
//! assert_eq!(ik.tasks.len(), 8);
//! ```

use std::collections::BTreeMap;

use stride_model::bundled;

use crate::builder::{com, com_config, limits};
use crate::config::*;

/// The frames a walking preset uses.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WalkingFrames {
    /// Left sole (centre of the sole, z up, x forward): SE(3) task and contact.
    pub left_sole: String,
    /// Right sole.
    pub right_sole: String,
    /// Torso (chest) frame, held upright (`torso` tasks).
    pub torso: String,
    /// Floating base (pelvis) frame, held upright (`pelvis` tasks).
    pub base: String,
}

impl WalkingFrames {
    /// The four frames by name.
    pub fn new(left_sole: &str, right_sole: &str, torso: &str, base: &str) -> Self {
        Self {
            left_sole: left_sole.into(),
            right_sole: right_sole.into(),
            torso: torso.into(),
            base: base.into(),
        }
    }

    /// The bundled humanoid's (`l_sole`, `r_sole`, `chest`, `root_link`).
    pub fn bundled() -> Self {
        Self::new(
            bundled::LEFT_SOLE,
            bundled::RIGHT_SOLE,
            bundled::TORSO,
            bundled::PELVIS,
        )
    }
}

/// What a walking preset is built from.
///
/// | field | unit | meaning |
/// |---|---|---|
/// | `frames` | – | soles, torso and base frames |
/// | `posture` | rad by joint | the regularization posture (the robot's initial posture; joints not listed: 0) |
/// | `posture_joint_weights` | by joint | weights of the posture task's joints (others 1) |
/// | `upright_offset` | – | `reference_offset` of the torso and pelvis orientation tasks ([`ReferenceOffset`]) |
/// | `cop_x`, `cop_y` | m | CoP region of the TSID contacts in the sole frame |
#[derive(Debug, Clone, PartialEq)]
pub struct WalkingPreset {
    /// The frames.
    pub frames: WalkingFrames,
    /// Posture the posture task regularizes to \[rad\].
    pub posture: BTreeMap<String, f64>,
    /// Per-joint weights of the posture task (joints not listed: 1).
    pub posture_joint_weights: BTreeMap<String, f64>,
    /// How the torso and pelvis orientation tasks relate the upright reference to their frames.
    pub upright_offset: ReferenceOffset,
    /// CoP region of the TSID contacts along the sole's x \[m\].
    pub cop_x: [f64; 2],
    /// CoP region of the TSID contacts along the sole's y \[m\].
    pub cop_y: [f64; 2],
}

impl WalkingPreset {
    /// A preset for `frames` and `posture`: posture weights 1, no orientation offset, the bundled robot's
    /// CoP region ([`BUNDLED_COP_X`], [`BUNDLED_COP_Y`]).
    pub fn new(frames: WalkingFrames, posture: BTreeMap<String, f64>) -> Self {
        Self {
            frames,
            posture,
            posture_joint_weights: BTreeMap::new(),
            upright_offset: ReferenceOffset::None,
            cop_x: BUNDLED_COP_X,
            cop_y: BUNDLED_COP_Y,
        }
    }

    /// The bundled humanoid's: its frames and posture ([`bundled_posture`]), weight 2 on the 14 arm
    /// joints.
    pub fn bundled() -> Self {
        Self {
            posture_joint_weights: bundled_arm_weights(),
            ..Self::new(WalkingFrames::bundled(), bundled_posture())
        }
    }
}

/// Weight of the bundled humanoid's arm joints in the posture task.
pub const BUNDLED_ARM_POSTURE_WEIGHT: f64 = 2.0;

/// The bundled humanoid's posture weights: [`BUNDLED_ARM_POSTURE_WEIGHT`] on every shoulder, elbow and
/// wrist joint.
pub fn bundled_arm_weights() -> BTreeMap<String, f64> {
    let joints = [
        "shoulder_pitch",
        "shoulder_roll",
        "shoulder_yaw",
        "elbow",
        "wrist_prosup",
        "wrist_pitch",
        "wrist_yaw",
    ];
    ["l", "r"]
        .iter()
        .flat_map(|side| joints.iter().map(move |j| format!("{side}_{j}")))
        .map(|name| (name, BUNDLED_ARM_POSTURE_WEIGHT))
        .collect()
}

/// The posture task of a preset: gains `kp`, `kd`, soft.
fn posture_task(p: &WalkingPreset, kp: f64, kd: f64) -> TaskConfig {
    TaskConfig::JointRegularization(JointRegularizationTaskConfig {
        name: "posture".into(),
        kp,
        kd,
        posture: p.posture.clone(),
        weight: None,
        joint_weights: p.posture_joint_weights.clone(),
        priority: Priority::Soft,
    })
}

/// A soft orientation task holding `frame` upright (the walking `torso` reference).
fn upright_task(
    p: &WalkingPreset,
    name: &str,
    frame: &str,
    gains: [f64; 2],
    weight: f64,
) -> TaskConfig {
    TaskConfig::So3(Frame3TaskConfig {
        name: name.into(),
        frame: frame.into(),
        reference: walking::TORSO.into(),
        reference_offset: p.upright_offset,
        kp: gains[0],
        kd: gains[1],
        mask: [true; 3],
        priority: Priority::Soft,
        weight: Some(Weight::Scalar(weight)),
    })
}

/// A hard SE(3) task on a sole tracking the walking reference of the same foot: gains
/// `kp = [linear, angular]` and `kd` (linear and angular).
fn foot_task(name: &str, frame: &str, reference: &str, kp: [f64; 2], kd: f64) -> TaskConfig {
    TaskConfig::Se3(Se3TaskConfig {
        name: name.into(),
        frame: frame.into(),
        reference: reference.into(),
        kp_linear: kp[0],
        kp_angular: kp[1],
        kd_linear: kd,
        kd_angular: kd,
        mask: [true; 6],
        priority: Priority::Hard,
        weight: None,
    })
}

/// QP-IK foot position gain K_p \[1/s\] (the iCub walking controller's).
pub const IK_FOOT_KP_LINEAR: f64 = 7.0;
/// QP-IK foot orientation gain K_p \[1/s\].
pub const IK_FOOT_KP_ANGULAR: f64 = 5.0;
/// QP-IK CoM gain \[1/s\] (2 for a 500 Hz loop).
pub const IK_COM_KP: f64 = 2.0;
/// QP-IK gain of the torso, pelvis and posture tasks \[1/s\].
pub const IK_UPRIGHT_KP: f64 = 5.0;
/// QP-IK torso (chest) orientation weight: the pelvis's. At 5 the chest pitched 12–20° at 0.4 m/s and the
/// fast walks fell while stopping; at 50 every position walk measured tracks as well or better, the tilt
/// under 7° (docs/gait.md, "Walking at 0.40 m/s").
pub const IK_TORSO_WEIGHT: f64 = 50.0;
/// QP-IK pelvis orientation weight: without it the QP lets the base roll and pitch by up to 8–9° in single
/// support, the torso joints compensate, and the angular momentum this creates drives the ZMP to the foot
/// edge (measured in stride-sim: the bundled robot fell in its first step).
pub const IK_PELVIS_WEIGHT: f64 = 50.0;

/// The walking QP-IK [Romualdi 2022, eq. 7.1.16] with the gains of the iCub walking controller: feet SE(3)
/// hard (K_p 7 / 5), CoM hard (K 2 for a 500 Hz loop), torso SO(3) soft (K 5, weight 50), pelvis SO(3) soft
/// (K 5, weight 50), posture soft (K 5), joint position and velocity limits; integrated feedback.
pub fn walking_ik(p: &WalkingPreset) -> IkConfig {
    let f = &p.frames;
    let foot_kp = [IK_FOOT_KP_LINEAR, IK_FOOT_KP_ANGULAR];
    let upright_gains = [IK_UPRIGHT_KP, 0.0];
    let mut config = IkConfig {
        feedback: IkFeedback::Integrated,
        qp: QpSettings::default(),
        eliminate_equalities: true,
        tasks: vec![
            foot_task("left_foot", &f.left_sole, walking::LEFT_FOOT, foot_kp, 0.0),
            foot_task(
                "right_foot",
                &f.right_sole,
                walking::RIGHT_FOOT,
                foot_kp,
                0.0,
            ),
            com(IK_COM_KP, 0.0),
            upright_task(p, "torso", &f.torso, upright_gains, IK_TORSO_WEIGHT),
            upright_task(p, "pelvis", &f.base, upright_gains, IK_PELVIS_WEIGHT),
            posture_task(p, IK_UPRIGHT_KP, 0.0),
        ],
    };
    config.tasks.extend(limits(None));
    config
}

/// TSID foot SE(3) gain K_p \[1/s²\], linear and angular.
pub const TSID_FOOT_KP: f64 = 400.0;
/// TSID foot SE(3) gain K_d \[1/s\], linear and angular.
pub const TSID_FOOT_KD: f64 = 40.0;
/// TSID torso, pelvis and posture gains `[K_p (1/s²), K_d (1/s)]`.
pub const TSID_UPRIGHT_GAINS: [f64; 2] = [100.0, 20.0];
/// TSID look-ahead of the joint position limits \[s\].
pub const TSID_LIMIT_LOOK_AHEAD: f64 = 0.05;

/// The walking TSID [Romualdi 2022, eq. 7.2.31]: floating-base dynamics, sole contacts (CoP region
/// `cop_x` × `cop_y`), feet SE(3) hard (K_p 400, K_d 40), CoM hard ([`BUNDLED_TSID_COM_KP`],
/// [`BUNDLED_TSID_COM_KD`]; the height [`BUNDLED_TSID_COM_KP_Z`], [`BUNDLED_TSID_COM_KD_Z`]), torso and
/// pelvis SO(3) soft at [`BUNDLED_TSID_UPRIGHT_WEIGHT`] (K_p 100, K_d 20), posture soft (K_p 100, K_d 20),
/// wrench and torque regularization (1e-4), ZMP (1e-3), torque, position (look-ahead 0.05 s) and velocity
/// limits.
pub fn walking_tsid(p: &WalkingPreset) -> TsidConfig {
    let f = &p.frames;
    let contact = |name: &str, frame: &str, foot: Foot| {
        TaskConfig::Contact(ContactTaskConfig {
            name: name.into(),
            contact: String::new(),
            foot: Some(foot),
            foot_x: p.cop_x,
            foot_y: p.cop_y,
            ..ContactTaskConfig::new(frame, default_friction())
        })
    };
    let w = BUNDLED_TSID_UPRIGHT_WEIGHT;
    let foot_kp = [TSID_FOOT_KP, TSID_FOOT_KP];
    let mut config = TsidConfig {
        qp: QpSettings::default(),
        eliminate_equalities: true,
        flexible_joints: Vec::new(),
        contact_model: ContactModel::Rigid,
        compliant: CompliantConfig::default(),
        actuators: crate::ActuatorConfig::default(),
        tasks: vec![
            TaskConfig::FloatingBaseDynamics(FloatingBaseDynamicsTaskConfig {
                name: "dynamics".into(),
            }),
            contact("left_contact", &f.left_sole, Foot::Left),
            contact("right_contact", &f.right_sole, Foot::Right),
            foot_task(
                "left_foot",
                &f.left_sole,
                walking::LEFT_FOOT,
                foot_kp,
                TSID_FOOT_KD,
            ),
            foot_task(
                "right_foot",
                &f.right_sole,
                walking::RIGHT_FOOT,
                foot_kp,
                TSID_FOOT_KD,
            ),
            TaskConfig::Com(ComTaskConfig {
                kp_z: Some(BUNDLED_TSID_COM_KP_Z),
                kd_z: Some(BUNDLED_TSID_COM_KD_Z),
                ..com_config(BUNDLED_TSID_COM_KP, BUNDLED_TSID_COM_KD)
            }),
            upright_task(p, "torso", &f.torso, TSID_UPRIGHT_GAINS, w),
            upright_task(p, "pelvis", &f.base, TSID_UPRIGHT_GAINS, w),
            posture_task(p, TSID_UPRIGHT_GAINS[0], TSID_UPRIGHT_GAINS[1]),
            TaskConfig::WrenchRegularization(WrenchRegularizationTaskConfig {
                name: "wrench_regularization".into(),
                weight: Weight::Scalar(1e-4),
            }),
            TaskConfig::TorqueRegularization(TorqueRegularizationTaskConfig {
                name: "torque_regularization".into(),
                weight: Weight::Scalar(1e-4),
            }),
            TaskConfig::Zmp(ZmpTaskConfig {
                name: "zmp".into(),
                priority: Priority::Soft,
                weight: Some(Weight::Scalar(1e-3)),
            }),
            TaskConfig::JointTorqueLimits(JointTorqueLimitsTaskConfig {
                name: "joint_torque_limits".into(),
                scale: 1.0,
            }),
        ],
    };
    config.tasks.extend(limits(Some(TSID_LIMIT_LOOK_AHEAD)));
    config
}

/// Overrides a preset task by task: each entry of `overrides` replaces the task of `tasks` with the same
/// name, in its place, or is appended when no task has its name (in `overrides`' order).
pub fn with_overrides(tasks: &mut Vec<TaskConfig>, overrides: &[TaskConfig]) {
    for o in overrides {
        match tasks.iter_mut().find(|t| t.name() == o.name()) {
            Some(t) => *t = o.clone(),
            None => tasks.push(o.clone()),
        }
    }
}

/// Removes the tasks named in `names` from `tasks`; returns the names no task has.
pub fn without<'a>(tasks: &mut Vec<TaskConfig>, names: &'a [String]) -> Vec<&'a str> {
    let unknown = names
        .iter()
        .filter(|n| !tasks.iter().any(|t| t.name() == n.as_str()))
        .map(String::as_str)
        .collect();
    tasks.retain(|t| !names.iter().any(|n| n == t.name()));
    unknown
}
