//! The robot's limbs read from its kinematic tree: the legs (the joints between the root body and each
//! sole), their knees and flexion sign, the other chains (arms, head, torso), and the light distal
//! chains (grippers, fingers) a walking controller should not see.

use std::sync::Arc;

use nalgebra::Vector3;
use stride_model::{FrameId, KinDyn, Model, RobotState};

/// A leg needs at least this many joints (hip pitch, knee, ankle pitch) to crouch flat-footed.
pub const MIN_LEG_JOINTS: usize = 3;
/// A joint axis is a pitch axis when it is within this angle of the model's y axis at the zero posture
/// \[deg\].
pub const PITCH_AXIS_TOLERANCE_DEG: f64 = 10.0;
/// Knee probe angle used to find the flexion direction \[rad\].
const KNEE_PROBE: f64 = 0.1;
/// A distal chain named like a hand is proposed for locking when its mass is below this fraction of the
/// robot's [-].
pub const LOCK_MASS_FRACTION: f64 = 0.02;
/// A joint whose subtree has a rotational inertia about its axis below this is proposed for locking
/// whatever its name: its mass-matrix diagonal is that inertia, so the matrix is near singular
/// \[kg·m²\].
pub const LOCK_AXIS_INERTIA: f64 = 1e-6;
/// Name fragments of hand chains (grippers, fingers) that a walking controller should not move.
pub const HAND_WORDS: &[&str] = &["gripper", "finger", "hand", "thumb", "index", "pinky"];

/// Why the legs were not found.
#[derive(Debug, thiserror::Error)]
pub enum LimbError {
    /// A sole's body is too close to the root.
    #[error("the {side} sole's link `{link}` hangs from the root body through {joints} movable joint(s); a leg needs at least {MIN_LEG_JOINTS} (hip pitch, knee, ankle pitch)")]
    ShortLeg {
        /// `left` or `right`.
        side: &'static str,
        /// The sole's link.
        link: String,
        /// Its joint count.
        joints: usize,
    },
    /// No joint of a leg bends it like a knee.
    #[error("no knee in the {side} leg ({joints}): a knee is a pitch joint (axis along the model's y) between the hip and the ankle whose flexion moves the sole backwards")]
    NoKnee {
        /// `left` or `right`.
        side: &'static str,
        /// The leg's joint names.
        joints: String,
    },
    /// The model could not be evaluated.
    #[error(transparent)]
    Model(#[from] stride_model::ModelError),
}

/// One leg: its joints from the hip down and its knee.
#[derive(Debug, Clone, PartialEq)]
pub struct Leg {
    /// Joint indices (model order) from the root body down to the sole's body.
    pub joints: Vec<usize>,
    /// The knee's joint index.
    pub knee: usize,
    /// +1 or −1: the sign of the knee position that flexes the knee (the sole moves backwards).
    pub knee_flexion_sign: f64,
    /// Vertical distance from the highest pitch joint (the hip) to the sole at the zero posture \[m\].
    pub length: f64,
}

/// The joints between the root body and `frame`'s body, root first.
pub fn chain_to(model: &Model, frame: FrameId) -> Vec<usize> {
    let mut body = model.frames()[frame.index()].link;
    let mut joints = Vec::new();
    while let Some(j) = model.bodies()[body].joint {
        joints.push(j);
        body = model.bodies()[body].parent.unwrap_or(0);
    }
    joints.reverse();
    joints
}

/// World position of joint `j`'s frame and its axis in the world, for the state `kd` holds.
fn joint_frame(model: &Model, kd: &KinDyn, j: usize) -> Option<(Vector3<f64>, Vector3<f64>)> {
    let joint = &model.joints()[j];
    let id = model.frame_id(&joint.child_link)?;
    let pose = kd.frame_pose(id);
    Some((pose.translation.vector, pose.rotation * joint.axis))
}

/// The leg ending at `sole` (`side` for messages): its joints, knee and flexion sign, and its length.
///
/// The knee is the pitch joint (axis within [`PITCH_AXIS_TOLERANCE_DEG`] of the model's y) that is
/// neither the highest nor the lowest pitch joint of the chain and is farthest from both (the middle of
/// the leg); its flexion sign is the sign of the position that moves the sole backwards (against the
/// sole frame's x axis, where the toes point), probed at the zero posture.
pub fn find_leg(model: &Arc<Model>, sole: FrameId, side: &'static str) -> Result<Leg, LimbError> {
    let joints = chain_to(model, sole);
    let link = model.bodies()[model.frames()[sole.index()].link]
        .name
        .clone();
    if joints.len() < MIN_LEG_JOINTS {
        return Err(LimbError::ShortLeg {
            side,
            link,
            joints: joints.len(),
        });
    }
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_state(&RobotState::zero(model))?;
    let cos_tol = PITCH_AXIS_TOLERANCE_DEG.to_radians().cos();
    let pitch: Vec<(usize, Vector3<f64>)> = joints
        .iter()
        .filter_map(|&j| joint_frame(model, &kd, j).map(|f| (j, f)))
        .filter(|(_, (_, axis))| axis.y.abs() >= cos_tol)
        .map(|(j, (p, _))| (j, p))
        .collect();
    let sole_pos = kd.frame_pose(sole).translation.vector;
    let no_knee = || LimbError::NoKnee {
        side,
        joints: joints
            .iter()
            .map(|&j| model.joints()[j].name.as_str())
            .collect::<Vec<_>>()
            .join(", "),
    };
    let hip = pitch
        .iter()
        .max_by(|a, b| a.1.z.total_cmp(&b.1.z))
        .ok_or_else(no_knee)?;
    let knee = pitch
        .iter()
        .filter(|(_, p)| p.z < hip.1.z - 1e-3 && p.z > sole_pos.z + 1e-3)
        .max_by(|a, b| {
            let d = |p: &Vector3<f64>| (p - hip.1).norm().min((p - sole_pos).norm());
            d(&a.1).total_cmp(&d(&b.1))
        })
        .ok_or_else(no_knee)?
        .0;
    let forward = kd.frame_pose(sole).rotation * Vector3::x();
    let mut state = RobotState::zero(model);
    state.joint_positions[knee] = KNEE_PROBE;
    kd.set_state(&state)?;
    let moved = (kd.frame_pose(sole).translation.vector - sole_pos).dot(&forward);
    if moved.abs() < 1e-6 {
        return Err(no_knee());
    }
    Ok(Leg {
        joints,
        knee,
        knee_flexion_sign: -moved.signum(),
        length: hip.1.z - sole_pos.z,
    })
}

/// Whether a joint name says it belongs to a hand (gripper, finger, ...).
pub fn is_hand_name(name: &str) -> bool {
    let n = name.to_ascii_lowercase();
    HAND_WORDS.iter().any(|w| n.contains(w))
}

/// Mass \[kg\] and rotational inertia about the joint axis \[kg·m²\] of the bodies joint `j` moves, at the
/// zero posture (the composite rigid body of its subtree).
pub fn subtree_inertia(model: &Arc<Model>, j: usize) -> Result<(f64, f64), LimbError> {
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_state(&RobotState::zero(model))?;
    let Some((origin, axis)) = joint_frame(model, &kd, j) else {
        return Ok((0.0, 0.0));
    };
    let root = j + 1;
    let bodies = model.bodies();
    let in_subtree = |mut b: usize| loop {
        if b == root {
            return true;
        }
        match bodies[b].parent {
            Some(p) => b = p,
            None => return false,
        }
    };
    let (mut mass, mut inertia) = (0.0, 0.0);
    for (_, body) in bodies.iter().enumerate().filter(|(b, _)| in_subtree(*b)) {
        let Some(id) = model.frame_id(&body.name) else {
            continue;
        };
        let pose = kd.frame_pose(id);
        let r = pose.rotation.to_rotation_matrix();
        let com = pose * nalgebra::Point3::from(body.com);
        let i_world = r.matrix() * body.inertia_at_com * r.matrix().transpose();
        let d = com.coords - origin;
        let perp = d - axis * axis.dot(&d);
        mass += body.mass;
        inertia += axis.dot(&(i_world * axis)) + body.mass * perp.norm_squared();
    }
    Ok((mass, inertia))
}

/// Joints to lock, with their positions: every movable joint outside the legs whose subtree is nearly
/// massless about its axis (below [`LOCK_AXIS_INERTIA`]), and every joint named like a hand
/// ([`HAND_WORDS`]) whose subtree weighs less than [`LOCK_MASS_FRACTION`] of the robot. The position is
/// 0 clamped into the joint's limits.
pub fn proposed_locks(model: &Arc<Model>, legs: &[&Leg]) -> Result<Vec<(String, f64)>, LimbError> {
    let total = model.total_mass();
    let mut out = Vec::new();
    for (j, joint) in model.joints().iter().enumerate() {
        if legs.iter().any(|l| l.joints.contains(&j)) {
            continue;
        }
        let (mass, axis_inertia) = subtree_inertia(model, j)?;
        let light_hand = is_hand_name(&joint.name) && mass < LOCK_MASS_FRACTION * total;
        if axis_inertia < LOCK_AXIS_INERTIA || light_hand {
            out.push((joint.name.clone(), 0.0_f64.clamp(joint.lower, joint.upper)));
        }
    }
    Ok(out)
}
