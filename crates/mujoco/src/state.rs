//! stride's state ↔ MuJoCo's `qpos`/`qvel`.
//!
//! MuJoCo's free joint holds the root body's world position and orientation (`qpos[0..7]`, quaternion
//! `w, x, y, z`); its velocity `qvel[0..6]` is the world velocity of the body origin followed by the
//! angular velocity **in the body frame** [MuJoCo 3.17 documentation, "Floating objects"]. stride's mixed
//! representation has the angular velocity in the world frame: `ω_world = R ω_body`. Joint coordinates are
//! found through the `qpos`/`qvel` address of each stride joint. A fixed base (`sim.fixed_base`) has no free
//! joint: the root body is a mocap body held at the initial base pose, and only the joints are copied.

use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use stride_model::RobotState;

/// Writes `state` (base pose, joints, mixed base twist, joint velocities) into `qpos` and `qvel`.
pub fn state_to_mujoco(
    state: &RobotState,
    joint_qpos: &[usize],
    joint_dof: &[usize],
    qpos: &mut [f64],
    qvel: &mut [f64],
) {
    let p = state.base_pose.translation.vector;
    let r = state.base_pose.rotation;
    qpos[..3].copy_from_slice(p.as_slice());
    qpos[3..7].copy_from_slice(&[r.w, r.i, r.j, r.k]);
    let v = state.base_velocity;
    let w_body = r.inverse_transform_vector(&Vector3::new(v[3], v[4], v[5]));
    qvel[..3].copy_from_slice(&[v[0], v[1], v[2]]);
    qvel[3..6].copy_from_slice(w_body.as_slice());
    joints_to_mujoco(state, joint_qpos, joint_dof, qpos, qvel);
}

/// Writes the joint positions and velocities of `state` into `qpos` and `qvel` (a fixed base has no
/// free joint: these are the whole state).
pub fn joints_to_mujoco(
    state: &RobotState,
    joint_qpos: &[usize],
    joint_dof: &[usize],
    qpos: &mut [f64],
    qvel: &mut [f64],
) {
    for (j, (&a, &d)) in joint_qpos.iter().zip(joint_dof).enumerate() {
        qpos[a] = state.joint_positions[j];
        qvel[d] = state.joint_velocities[j];
    }
}

/// Reads `qpos` and `qvel` into `state` (mixed base twist). The quaternion is normalised.
pub fn state_from_mujoco(
    qpos: &[f64],
    qvel: &[f64],
    joint_qpos: &[usize],
    joint_dof: &[usize],
    state: &mut RobotState,
) {
    let r = UnitQuaternion::from_quaternion(Quaternion::new(qpos[3], qpos[4], qpos[5], qpos[6]));
    state.base_pose = Isometry3::from_parts(Translation3::new(qpos[0], qpos[1], qpos[2]), r);
    let w = r * Vector3::new(qvel[3], qvel[4], qvel[5]);
    state.base_velocity = nalgebra::Vector6::new(qvel[0], qvel[1], qvel[2], w.x, w.y, w.z);
    joints_from_mujoco(qpos, qvel, joint_qpos, joint_dof, state);
}

/// Reads the joint positions and velocities from `qpos` and `qvel` into `state`, leaving its base as it
/// is (a fixed base).
pub fn joints_from_mujoco(
    qpos: &[f64],
    qvel: &[f64],
    joint_qpos: &[usize],
    joint_dof: &[usize],
    state: &mut RobotState,
) {
    for (j, (&a, &d)) in joint_qpos.iter().zip(joint_dof).enumerate() {
        state.joint_positions[j] = qpos[a];
        state.joint_velocities[j] = qvel[d];
    }
}
