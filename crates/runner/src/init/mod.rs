//! `stride init <URDF> --name NAME`: a robot file and two walking scenarios for a robot nobody has
//! configured, derived from its URDF.
//!
//! [`derive()`] reads the model and finds, in order: the soles ([`crate::feet::propose_feet`], or the
//! URDF's own frame where one lies on the proposed sole), the legs, their knees and flexion sign
//! ([`limbs::find_leg`]), the arms (the longest other chains on each side), the light hand chains to lock
//! ([`limbs::proposed_locks`]), the flat-footed crouch at a target CoM height ([`crouch::crouch`]) and the
//! geometry of the robot standing in it ([`crate::check::posture::Stance`]), and the robot-scaled planner
//! limits and servo gains ([`scaling::scale`]). [`write::write()`] turns the result into
//! `<dir>/robots/NAME.toml`, `<dir>/walk_NAME.toml` (position control) and `<dir>/walk_NAME_torque.toml`.

pub mod crouch;
pub mod limbs;
pub mod scaling;
pub mod write;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use nalgebra::{DVector, Isometry3};
use stride_model::{FrameId, InertiaEdits, JointLock, KinDyn, Model, RobotState};

use crate::check::posture::Stance;
use crate::feet::{propose_feet, FeetError, FootProposal};
use limbs::Leg;

/// A sole frame that coincides with the proposed one within this distance \[m\] (and
/// [`SAME_FRAME_ANGLE`]) is used by name instead of adding a frame.
pub const SAME_FRAME_DISTANCE: f64 = 5e-4;
/// See [`SAME_FRAME_DISTANCE`] \[rad\].
pub const SAME_FRAME_ANGLE: f64 = 0.01;
/// Joints outside the legs start at 0 moved this far inside their limits when 0 is closer to a limit
/// \[rad or m\] (a posture on a limit leaves the whole-body layer no room).
pub const LIMIT_MARGIN: f64 = 0.1;
/// An arm has at least this many joints.
pub const MIN_ARM_JOINTS: usize = 3;

/// Why `stride init` failed; every variant names the URDF.
#[derive(Debug, thiserror::Error)]
pub enum InitError {
    /// The URDF path could not be expanded or the file does not exist.
    #[error("URDF `{written}`: {message}")]
    Path {
        /// The path as written.
        written: String,
        /// What went wrong.
        message: String,
    },
    /// The model could not be loaded or evaluated.
    #[error("{}: {message}", path.display())]
    Model {
        /// The URDF.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// No feet, or no legs to them.
    #[error("{}: no legs found: {message}", path.display())]
    NoLegs {
        /// The URDF.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// No crouch.
    #[error("{}: {source}", path.display())]
    Crouch {
        /// The URDF.
        path: PathBuf,
        /// Why.
        source: crouch::CrouchError,
    },
    /// An output file could not be written (or exists without `--force`).
    #[error("{}: {message}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
}

/// A sole: a frame of the model, or one to attach to a link.
#[derive(Debug, Clone, PartialEq)]
pub enum Sole {
    /// The URDF's own frame.
    Frame(String),
    /// A frame attached to `parent` at `xyz` \[m\], `rpy` \[rad\].
    Attached {
        /// The foot link.
        parent: String,
        /// Origin in the link \[m\].
        xyz: [f64; 3],
        /// Roll, pitch, yaw in the link \[rad\].
        rpy: [f64; 3],
    },
}

/// Everything `stride init` derives from a URDF.
#[derive(Debug, Clone)]
pub struct RobotSetup {
    /// The URDF as found on disk.
    pub urdf: PathBuf,
    /// The model's name.
    pub model_name: String,
    /// Total mass \[kg\].
    pub mass: f64,
    /// Left and right soles.
    pub soles: [Sole; 2],
    /// The smaller sole's length and width \[m\].
    pub foot: [f64; 2],
    /// Joint names of the left and right leg, hip first.
    pub legs: [Vec<String>; 2],
    /// The knees' names and flexion signs.
    pub knees: [(String, f64); 2],
    /// Leg length (hip pitch axis to sole, zero posture) \[m\].
    pub leg_length: f64,
    /// Joint names of the arms found (left, right; empty when none).
    pub arms: [Vec<String>; 2],
    /// The frame fall detection and the torso task use: the body the arms hang from (else the root).
    pub torso_frame: String,
    /// Joints to lock, with positions.
    pub locks: Vec<(String, f64)>,
    /// The crouch: joint name → position, for every joint not at 0.
    pub posture: Vec<(String, f64)>,
    /// The CoM height above the soles targeted by the crouch search \[m\].
    pub target_height: f64,
    /// The robot standing in the crouch.
    pub stance: Stance,
    /// Robot-scaled planner limits, CoP region and servo gains.
    pub scaled: scaling::Scaled,
    /// Force/torque sensors in the URDF.
    pub ft_sensors: usize,
    /// The simulated contact grid when both feet touch the ground through spheres in a grid
    /// ([`FootProposal::point_contact_grid`]); `None`: the simulator's default grid for flat soles.
    pub contact_grid: Option<[usize; 2]>,
    /// Whether the torso frame or the root body is not x forward, z up in the crouch (more than
    /// [`UPRIGHT_TOLERANCE_DEG`] from the left sole's orientation): the walking preset then holds their
    /// initial orientation (`wbc.walking.upright_offset = "initial"`, as iCub's).
    pub upright_initial: bool,
}

/// See [`RobotSetup::upright_initial`] \[deg\].
pub const UPRIGHT_TOLERANCE_DEG: f64 = 1.0;

/// Expands `${VAR}` in `written` and checks that the file exists.
pub fn resolve_urdf(written: &str) -> Result<PathBuf, InitError> {
    let expanded =
        crate::config::expand_env_vars(written, |n| std::env::var(n).ok()).map_err(|message| {
            InitError::Path {
                written: written.into(),
                message,
            }
        })?;
    let path = PathBuf::from(expanded);
    if !path.is_file() {
        return Err(InitError::Path {
            written: written.into(),
            message: format!("no such file `{}`", path.display()),
        });
    }
    Ok(path)
}

/// Derives the robot's configuration from the URDF at `urdf`; `target_height` overrides the crouch's CoM
/// height (default [`crouch::default_target_height`]).
pub fn derive(urdf: &Path, target_height: Option<f64>) -> Result<RobotSetup, InitError> {
    let model_err = |message: String| InitError::Model {
        path: urdf.to_path_buf(),
        message,
    };
    let no_legs = |message: String| InitError::NoLegs {
        path: urdf.to_path_buf(),
        message,
    };
    let feet = propose_feet(urdf).map_err(|e| match e {
        FeetError::NoFoot { .. } => no_legs(e.to_string()),
        FeetError::Load { message, .. } => model_err(message),
    })?;
    let full = Model::from_urdf_file(urdf).map_err(|e| model_err(e.to_string()))?;
    let (full, soles, sole_ids) = with_soles(full, &feet).map_err(model_err)?;
    let legs = find_legs(&full, sole_ids).map_err(|e| no_legs(e.to_string()))?;
    let locks = limbs::proposed_locks(&full, &[&legs[0], &legs[1]])
        .map_err(|e| model_err(e.to_string()))?;
    let lock_list: Vec<JointLock> = locks.iter().map(|(n, q)| JointLock::new(n, *q)).collect();
    let reduced = Model::from_urdf_file_reduced(urdf, &InertiaEdits::default(), &lock_list)
        .map_err(|e| model_err(e.to_string()))?;
    let (model, _, sole_ids) = with_soles(reduced, &feet).map_err(model_err)?;
    let legs = find_legs(&model, sole_ids).map_err(|e| no_legs(e.to_string()))?;
    let arms = find_arms(&model, &legs, sole_ids);
    let start = start_posture(&model, &legs);
    let zero = Stance::new(&model, &start_zero_legs(&model, &start, &legs), sole_ids)
        .map_err(|e| model_err(e.to_string()))?;
    let leg_length = 0.5 * (legs[0].length + legs[1].length);
    let target = target_height
        .unwrap_or_else(|| crouch::default_target_height(zero.com_height(), leg_length));
    let torso_frame = arms
        .iter()
        .find_map(|a| a.first())
        .and_then(|&j| model.bodies()[j + 1].parent)
        .map_or_else(
            || model.root_link().to_string(),
            |b| model.bodies()[b].name.clone(),
        );
    let q = crouch::crouch(&model, sole_ids, [&legs[0], &legs[1]], &start, target).map_err(
        |source| InitError::Crouch {
            path: urdf.to_path_buf(),
            source,
        },
    )?;
    let stance = Stance::new(&model, &q, sole_ids).map_err(|e| model_err(e.to_string()))?;
    let upright_initial = !upright_frames(&model, &q, sole_ids, &torso_frame)
        .map_err(|e| model_err(e.to_string()))?;
    let foot = [
        feet[0].patch.length.min(feet[1].patch.length),
        feet[0].patch.width.min(feet[1].patch.width),
    ];
    let scaled = scaling::scale(
        stance.mass,
        stance.com_height(),
        stance.gravity,
        stance.feet_width(),
        foot,
    );
    let names = |joints: &[usize]| -> Vec<String> {
        joints
            .iter()
            .map(|&j| model.joints()[j].name.clone())
            .collect()
    };
    Ok(RobotSetup {
        urdf: urdf.to_path_buf(),
        model_name: model.name().to_string(),
        mass: model.total_mass(),
        soles,
        foot,
        legs: [names(&legs[0].joints), names(&legs[1].joints)],
        knees: [0, 1].map(|i| {
            (
                model.joints()[legs[i].knee].name.clone(),
                legs[i].knee_flexion_sign,
            )
        }),
        leg_length,
        arms: [names(&arms[0]), names(&arms[1])],
        torso_frame,
        locks,
        posture: model
            .joints()
            .iter()
            .zip(q.iter())
            .filter(|(_, v)| v.abs() > 1e-9)
            .map(|(j, v)| (j.name.clone(), *v))
            .collect(),
        target_height: target,
        stance,
        scaled,
        ft_sensors: model.ft_sensors().len(),
        upright_initial,
        contact_grid: feet[0]
            .point_contact_grid()
            .filter(|g| Some(*g) == feet[1].point_contact_grid()),
    })
}

/// A model with its sole frames, the soles as the robot file writes them, and their frame ids.
type WithSoles = (Arc<Model>, [Sole; 2], [FrameId; 2]);

/// `model` with the proposed sole frames: the URDF's own frame where one lies on the proposal (within
/// [`SAME_FRAME_DISTANCE`], [`SAME_FRAME_ANGLE`]), else a frame `left_sole` / `right_sole` attached to
/// the foot link.
fn with_soles(mut model: Model, feet: &[FootProposal; 2]) -> Result<WithSoles, String> {
    let mut soles = Vec::new();
    for foot in feet {
        let parent = model
            .frame_id(&foot.link)
            .ok_or_else(|| format!("no frame `{}`", foot.link))?;
        let body = model.frames()[parent.index()].link;
        let wanted = model.frames()[parent.index()].placement * foot.sole_in_link;
        let existing = model.frames().iter().find(|f| {
            f.link == body && {
                let d: Isometry3<f64> = f.placement.inverse() * wanted;
                d.translation.vector.norm() < SAME_FRAME_DISTANCE
                    && d.rotation.angle() < SAME_FRAME_ANGLE
            }
        });
        let sole = match existing {
            Some(f) => Sole::Frame(f.name.clone()),
            None => {
                let (r, p, y) = foot.sole_in_link.rotation.euler_angles();
                let t = foot.sole_in_link.translation.vector;
                let name = format!("{}_sole", foot.side);
                model
                    .add_frame(&name, &foot.link, foot.sole_in_link)
                    .map_err(|e| e.to_string())?;
                Sole::Attached {
                    parent: foot.link.clone(),
                    xyz: [t.x, t.y, t.z],
                    rpy: [r, p, y],
                }
            }
        };
        soles.push(sole);
    }
    let name = |s: &Sole, side: &str| match s {
        Sole::Frame(n) => n.clone(),
        Sole::Attached { .. } => format!("{side}_sole"),
    };
    let ids = [
        model.frame_id(&name(&soles[0], "left")),
        model.frame_id(&name(&soles[1], "right")),
    ];
    let [Some(l), Some(r)] = ids else {
        return Err("the sole frames were not added".into());
    };
    let soles = [soles[0].clone(), soles[1].clone()];
    Ok((Arc::new(model), soles, [l, r]))
}

/// Whether the torso frame and the root body are x forward, z up (within [`UPRIGHT_TOLERANCE_DEG`] of
/// the left sole) with the robot standing at `q`.
fn upright_frames(
    model: &Arc<Model>,
    q: &DVector<f64>,
    soles: [FrameId; 2],
    torso: &str,
) -> Result<bool, stride_model::ModelError> {
    let state = RobotState::standing(model, q, soles[0], soles[1])?;
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_state(&state)?;
    let sole = kd.frame_pose(soles[0]).rotation;
    let tol = UPRIGHT_TOLERANCE_DEG.to_radians();
    let aligned = |name: &str| {
        model
            .frame_id(name)
            .is_some_and(|f| sole.angle_to(&kd.frame_pose(f).rotation) <= tol)
    };
    Ok(aligned(torso) && aligned(model.root_link()))
}

/// Both legs.
fn find_legs(model: &Arc<Model>, soles: [FrameId; 2]) -> Result<[Leg; 2], limbs::LimbError> {
    Ok([
        limbs::find_leg(model, soles[0], "left")?,
        limbs::find_leg(model, soles[1], "right")?,
    ])
}

/// The arms: on each side (the leaf's side of the sagittal plane at the zero posture, along the line from
/// the right sole to the left one: the root frame's axes are the URDF's, e.g. iCub's `root_link` has x
/// backwards and y to the right), the longest chain from the root to a leaf body that shares no joint with
/// the legs, counting only its joints after the last one it shares with the other side (the torso), with
/// at least [`MIN_ARM_JOINTS`] joints.
fn find_arms(model: &Arc<Model>, legs: &[Leg; 2], soles: [FrameId; 2]) -> [Vec<usize>; 2] {
    let mut kd = KinDyn::new(Arc::clone(model));
    if kd.set_state(&RobotState::zero(model)).is_err() {
        return [Vec::new(), Vec::new()];
    }
    let [left, right] = soles.map(|s| kd.frame_pose(s).translation.vector);
    let (middle, leftwards) = (0.5 * (left + right), left - right);
    let bodies = model.bodies();
    let is_leaf = |b: usize| !bodies.iter().any(|c| c.parent == Some(b));
    let mut best: [Vec<usize>; 2] = [Vec::new(), Vec::new()];
    for (b, body) in bodies.iter().enumerate().skip(1) {
        if !is_leaf(b) {
            continue;
        }
        let Some(frame) = model.frame_id(&body.name) else {
            continue;
        };
        let chain = limbs::chain_to(model, frame);
        if chain
            .iter()
            .any(|j| legs.iter().any(|l| l.joints.contains(j)))
        {
            continue;
        }
        let side =
            usize::from((kd.frame_pose(frame).translation.vector - middle).dot(&leftwards) < 0.0);
        if chain.len() > best[side].len() {
            best[side] = chain;
        }
    }
    let shared = best[0].iter().take_while(|j| best[1].contains(j)).count();
    best.map(|c| {
        let arm: Vec<usize> = c.into_iter().skip(shared).collect();
        if arm.len() >= MIN_ARM_JOINTS {
            arm
        } else {
            Vec::new()
        }
    })
}

/// Every joint at 0, moved [`LIMIT_MARGIN`] inside its limits when 0 is closer to one (legs included;
/// the crouch search then moves the legs).
fn start_posture(model: &Model, legs: &[Leg; 2]) -> DVector<f64> {
    let mut q = DVector::zeros(model.dof());
    for (j, joint) in model.joints().iter().enumerate() {
        if legs.iter().any(|l| l.joints.contains(&j)) {
            continue;
        }
        let margin = LIMIT_MARGIN.min(0.25 * (joint.upper - joint.lower));
        q[j] = 0.0_f64.clamp(joint.lower + margin, joint.upper - margin);
    }
    q
}

/// `q` with the legs' joints at 0, within their limits (the straight-legged stance the target height
/// starts from).
fn start_zero_legs(model: &Model, q: &DVector<f64>, legs: &[Leg; 2]) -> DVector<f64> {
    let mut q = q.clone();
    for &j in legs.iter().flat_map(|l| &l.joints) {
        let joint = &model.joints()[j];
        q[j] = 0.0_f64.clamp(joint.lower, joint.upper);
    }
    q
}
