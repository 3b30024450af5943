//! The MuJoCo model of a scenario: the URDF compiled by MuJoCo, a free joint on the root link (a mocap root
//! body for a fixed base), a ground
//! plane, the robot's own collision geometry restricted to the soles, the joint actuators, the solver
//! options; and the map from stride's joints and bodies to MuJoCo's.

use std::path::Path;

use mujoco_rs::prelude::*;
use mujoco_rs::wrappers::mj_editing::MjtLimited;
use nalgebra::{UnitQuaternion, Vector3};
use stride_model::Model;
use stride_sim::{ActuationMode, GroundConfig};

use crate::actuators::Servo;
use crate::config::{Cone, MujocoConfig};
use crate::urdf::{prepare, UrdfEdit};
use crate::MujocoError;

/// Name of the ground plane geom.
pub const FLOOR: &str = "floor";

/// What [`build`] needs besides the stride model.
pub struct SceneSpec<'a> {
    /// The URDF file.
    pub urdf: &'a Path,
    /// One servo per stride joint.
    pub servos: &'a [Servo],
    /// The ground plane.
    pub ground: &'a GroundConfig,
    /// Sliding friction coefficient.
    pub friction: f64,
    /// Contact and solver parameters.
    pub config: &'a MujocoConfig,
    /// Frames whose bodies' collision geometry may touch the ground (the soles).
    pub contact_frames: &'a [String],
    /// Timestep \[s\].
    pub timestep: f64,
    /// Hold the root link where it is put (`sim.fixed_base`, a robot on a pole): the root body is a mocap
    /// body (its pose set through `mocap_pos` / `mocap_quat`) instead of carrying a free joint.
    pub fixed_base: bool,
}

/// A compiled scene and the index maps into it.
pub struct Scene {
    /// The MuJoCo model.
    pub model: MjModel,
    /// `qpos` address of each stride joint.
    pub joint_qpos: Vec<usize>,
    /// `qvel` address of each stride joint.
    pub joint_dof: Vec<usize>,
    /// MuJoCo body of each stride body ([`Model::bodies`] order).
    pub body: Vec<usize>,
    /// Per MuJoCo geom: the index in `contact_frames` whose body holds it, if it may collide.
    pub geom_contact: Vec<Option<usize>>,
}

/// Builds the scene (see the module documentation). Errors name what MuJoCo or the maps rejected.
pub fn build(model: &Model, s: &SceneSpec<'_>) -> Result<Scene, MujocoError> {
    let compile_error = |message: String| MujocoError::Compile {
        path: s.urdf.to_path_buf(),
        message,
    };
    let text = std::fs::read_to_string(s.urdf).map_err(|source| MujocoError::Urdf {
        path: s.urdf.to_path_buf(),
        source,
    })?;
    let contact_links = contact_links(model, s.contact_frames)?;
    // stride's frames are named after their URDF links; a frame the configuration added (a sole frame on
    // the sole's bottom face) stands for the link it is attached to.
    let urdf_links: Vec<String> = s
        .contact_frames
        .iter()
        .filter_map(|name| model.frame_id(name))
        .map(|f| model.urdf_frame_name(f).to_string())
        .collect();
    let (text, _) = prepare(
        &text,
        &UrdfEdit {
            path: s.urdf,
            contact_links: &urdf_links,
        },
    )?;
    let mut spec = MjSpec::from_xml_string(&text).map_err(|e| compile_error(e.to_string()))?;
    let root = model.root_link();
    let root_body = spec
        .body_mut(root)
        .ok_or_else(|| MujocoError::Mismatch(format!("MuJoCo has no body `{root}`")))?;
    if s.fixed_base {
        root_body.set_mocap(true);
    } else {
        root_body
            .add_free_joint()
            .set_name(&format!("{root}_free_joint"))
            .map_err(|e| compile_error(e.to_string()))?;
    }
    set_joints(model, &mut spec, s.servos, s.config)?;
    add_floor(&mut spec, s);
    add_actuators(model, &mut spec, s.servos);
    set_options(model, &mut spec, s);
    let mj = spec.compile().map_err(|e| compile_error(e.to_string()))?;
    map(model, mj, &contact_links, s.contact_frames, s.fixed_base)
}

/// The stride body of each contact frame.
fn contact_links(model: &Model, contact_frames: &[String]) -> Result<Vec<usize>, MujocoError> {
    contact_frames
        .iter()
        .map(|name| {
            let f = model.frame_id(name).ok_or_else(|| {
                MujocoError::Mismatch(format!("stride's model has no frame `{name}`"))
            })?;
            Ok(model.frames()[f.index()].link)
        })
        .collect()
}

/// Passive joint dynamics from the servos: damping, armature (at least `min_armature`), Coulomb friction
/// (`frictionloss`); the URDF's position limits kept or dropped.
fn set_joints(
    model: &Model,
    spec: &mut MjSpec,
    servos: &[Servo],
    config: &MujocoConfig,
) -> Result<(), MujocoError> {
    for (j, servo) in model.joints().iter().zip(servos) {
        let joint = spec
            .joint_mut(&j.name)
            .ok_or_else(|| MujocoError::Mismatch(format!("MuJoCo has no joint `{}`", j.name)))?;
        joint.damping_mut()[0] = servo.damping;
        joint.set_armature(servo.armature.max(config.min_armature));
        if !config.joint_limits {
            joint.set_limited(MjtLimited::mjLIMITED_FALSE);
        }
        joint.set_frictionloss(servo.coulomb_friction);
    }
    Ok(())
}

/// The ground plane: through `[0, 0, height]` with normal `R_x(roll) R_y(pitch) e_z` (stride-sim's
/// `GroundPlane`), carrying the contact parameters with priority over the robot's geoms.
fn add_floor(spec: &mut MjSpec, s: &SceneSpec<'_>) {
    let [roll, pitch] = s.ground.inclination;
    let q = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), roll)
        * UnitQuaternion::from_axis_angle(&Vector3::y_axis(), pitch);
    let c = s.config;
    let floor = spec
        .world_body_mut()
        .add_geom()
        .with_type(MjtGeomBase::mjGEOM_PLANE)
        .with_size([0.0, 0.0, 1.0])
        .with_pos([0.0, 0.0, s.ground.height])
        .with_quat([q.w, q.i, q.j, q.k])
        .with_friction([s.friction, c.torsional_friction, c.rolling_friction])
        .with_solref(c.solref)
        .with_solimp(c.solimp);
    floor.set_condim(c.condim);
    floor.set_priority(1);
    floor.set_contype(1);
    floor.set_conaffinity(1);
    let _ = floor.set_name(FLOOR);
}

/// One actuator per stride joint, in model order (actuator `i` drives joint `i`).
fn add_actuators(model: &Model, spec: &mut MjSpec, servos: &[Servo]) {
    for (j, servo) in model.joints().iter().zip(servos) {
        let a = spec.add_actuator().with_trntype(MjtTrn::mjTRN_JOINT);
        a.set_target(&j.name);
        match servo.mode {
            ActuationMode::Position => {
                a.gainprm_mut()[0] = servo.kp;
                a.biasprm_mut()[..3].copy_from_slice(&[0.0, -servo.kp, -servo.kd]);
                a.set_gaintype(MjtGain::mjGAIN_FIXED);
                a.set_biastype(MjtBias::mjBIAS_AFFINE);
            }
            ActuationMode::Velocity => {
                a.gainprm_mut()[0] = servo.kd;
                a.biasprm_mut()[..3].copy_from_slice(&[0.0, 0.0, -servo.kd]);
                a.set_gaintype(MjtGain::mjGAIN_FIXED);
                a.set_biastype(MjtBias::mjBIAS_AFFINE);
            }
            ActuationMode::Torque => {
                a.gainprm_mut()[0] = 1.0;
                a.set_gaintype(MjtGain::mjGAIN_FIXED);
                a.set_biastype(MjtBias::mjBIAS_NONE);
                if servo.torque_bandwidth > 0.0 {
                    // τ̇ = (u − τ)/T, integrated exactly: stride-sim's torque lag.
                    a.set_dyntype(MjtDyn::mjDYN_FILTEREXACT);
                    a.dynprm_mut()[0] = 1.0 / (std::f64::consts::TAU * servo.torque_bandwidth);
                }
            }
        }
        a.gear_mut()[0] = 1.0;
        a.set_ctrllimited(MjtLimited::mjLIMITED_FALSE);
        if servo.limit.is_finite() {
            a.set_forcelimited(MjtLimited::mjLIMITED_TRUE);
            *a.forcerange_mut() = [-servo.limit, servo.limit];
        } else {
            a.set_forcelimited(MjtLimited::mjLIMITED_FALSE);
        }
        let _ = a.set_name(&j.name);
    }
}

/// Timestep, `implicitfast`, the cone, gravity (the model's).
fn set_options(model: &Model, spec: &mut MjSpec, s: &SceneSpec<'_>) {
    let o = spec.option_mut();
    o.timestep = s.timestep;
    o.integrator = MjtIntegrator::mjINT_IMPLICITFAST as i32;
    o.cone = match s.config.cone {
        Cone::Pyramidal => MjtCone::mjCONE_PYRAMIDAL,
        Cone::Elliptic => MjtCone::mjCONE_ELLIPTIC,
    } as i32;
    o.impratio = s.config.impratio;
    let g = model.gravity();
    o.gravity = [g.x, g.y, g.z];
}

/// The index maps, and the collision filter: only the floor and the geoms of the contact frames' bodies
/// collide (stride-sim's contact is the soles on the ground, and fewer geoms make MuJoCo's collision
/// detection cheaper).
fn map(
    model: &Model,
    mut mj: MjModel,
    contact_links: &[usize],
    contact_frames: &[String],
    fixed_base: bool,
) -> Result<Scene, MujocoError> {
    let mut joint_qpos = Vec::with_capacity(model.dof());
    let mut joint_dof = Vec::with_capacity(model.dof());
    for j in model.joints() {
        let id = mj
            .name_to_id(MjtObjBase::mjOBJ_JOINT, &j.name)
            .ok_or_else(|| MujocoError::Mismatch(format!("MuJoCo has no joint `{}`", j.name)))?;
        joint_qpos.push(mj.jnt_qposadr()[id] as usize);
        joint_dof.push(mj.jnt_dofadr()[id] as usize);
    }
    // the free joint's 7 coordinates and 6 velocities, none for a fixed (mocap) base
    let (base_q, base_v) = if fixed_base { (0, 0) } else { (7, 6) };
    if mj.nq() as usize != base_q + model.dof() || mj.nv() as usize != base_v + model.dof() {
        return Err(MujocoError::Mismatch(format!(
            "MuJoCo has nq {} and nv {}, stride {} joints (expected nq = {base_q} + n, nv = {base_v} + n)",
            mj.nq(),
            mj.nv(),
            model.dof()
        )));
    }
    let mut body = Vec::with_capacity(model.bodies().len());
    for b in model.bodies() {
        let id = mj
            .name_to_id(MjtObjBase::mjOBJ_BODY, &b.name)
            .ok_or_else(|| MujocoError::Mismatch(format!("MuJoCo has no body `{}`", b.name)))?;
        body.push(id);
    }
    let contact_bodies: Vec<usize> = contact_links.iter().map(|&l| body[l]).collect();
    let floor = mj.name_to_id(MjtObjBase::mjOBJ_GEOM, FLOOR);
    let ngeom = mj.ngeom() as usize;
    let mut geom_contact = vec![None; ngeom];
    for (g, contact) in geom_contact.iter_mut().enumerate() {
        let b = mj.geom_bodyid()[g] as usize;
        *contact = contact_bodies.iter().position(|&c| c == b);
        let collides = contact.is_some() || Some(g) == floor;
        mj.geom_contype_mut()[g] = i32::from(collides);
        mj.geom_conaffinity_mut()[g] = i32::from(collides);
    }
    // (no contact frame at all is a robot on a pole: nothing should touch the floor)
    if !contact_frames.is_empty() && !geom_contact.iter().any(Option::is_some) {
        return Err(MujocoError::Mismatch(format!(
            "no collision geometry on the bodies of {contact_frames:?}: the robot could not stand"
        )));
    }
    Ok(Scene {
        model: mj,
        joint_qpos,
        joint_dof,
        body,
        geom_contact,
    })
}
