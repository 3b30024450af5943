//! Shared helpers of the integration tests.
#![allow(dead_code)]

pub mod soft;

use std::sync::Arc;

use nalgebra::{DVector, Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use stride_model::{KinDyn, Model, RobotState, VelocityRepresentation};
use stride_wbc::{bundled_posture, FootReference, WbcInput};

pub fn model_path() -> String {
    format!(
        "{}/../../models/stride_humanoid.urdf",
        env!("CARGO_MANIFEST_DIR")
    )
}

pub fn bundled_model() -> Arc<Model> {
    Arc::new(Model::from_urdf_file(model_path()).expect("bundled model loads"))
}

pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

/// The bundled default posture in model order.
pub fn default_posture(model: &Model) -> DVector<f64> {
    let mut q = DVector::zeros(model.dof());
    for (name, v) in bundled_posture() {
        q[model.joint_index(&name).unwrap()] = v;
    }
    q
}

/// The default posture perturbed by up to `amplitude` rad per joint, kept `margin` inside the limits.
pub fn random_posture(
    model: &Model,
    rng: &mut ChaCha8Rng,
    amplitude: f64,
    margin: f64,
) -> DVector<f64> {
    let mut q = default_posture(model);
    for (i, j) in model.joints().iter().enumerate() {
        let v = q[i] + rng.random_range(-amplitude..amplitude);
        q[i] = v.clamp(j.lower + margin, j.upper - margin);
    }
    q
}

/// Standing state: `q`, base placed so that the left sole is at the world origin level z = 0.
pub fn standing_state(model: &Arc<Model>, q: &DVector<f64>) -> RobotState {
    let mut state = RobotState::zero(model);
    state.joint_positions.copy_from(q);
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_representation(VelocityRepresentation::Mixed);
    kd.set_state(&state).unwrap();
    let l = kd.frame_pose(model.frame_id("l_sole").unwrap());
    let r = kd.frame_pose(model.frame_id("r_sole").unwrap());
    let z = 0.5 * (l.translation.vector.z + r.translation.vector.z);
    state.base_pose =
        Isometry3::from_parts(Translation3::new(0.0, 0.0, -z), UnitQuaternion::identity());
    state
}

/// References that hold the robot exactly where `state` puts it (feet, CoM, chest orientation, posture).
pub fn references_at(model: &Arc<Model>, state: &RobotState) -> WbcInput {
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_representation(VelocityRepresentation::Mixed);
    kd.set_state(state).unwrap();
    let mut input = WbcInput::new(model);
    input.state = state.clone();
    input.com_position = kd.com_position();
    input.left_foot = FootReference {
        pose: kd.frame_pose(model.frame_id("l_sole").unwrap()),
        ..FootReference::default()
    };
    input.right_foot = FootReference {
        pose: kd.frame_pose(model.frame_id("r_sole").unwrap()),
        ..FootReference::default()
    };
    input.torso.orientation = kd.frame_pose(model.frame_id("chest").unwrap()).rotation;
    input.posture = Some(state.joint_positions.clone());
    input
}

/// A random base pose: translation within ±`t` m, rotation within ±`r` rad about each axis.
pub fn random_pose(rng: &mut ChaCha8Rng, t: f64, r: f64) -> Isometry3<f64> {
    let tr = Vector3::new(
        rng.random_range(-t..t),
        rng.random_range(-t..t),
        rng.random_range(-t..t),
    );
    let rot = Vector3::new(
        rng.random_range(-r..r),
        rng.random_range(-r..r),
        rng.random_range(-r..r),
    );
    Isometry3::from_parts(
        Translation3::from(tr),
        UnitQuaternion::from_scaled_axis(rot),
    )
}

/// Rotates and shifts the base so that `frame` (a sole) is flat on z = 0, keeping its x, y.
pub fn flatten_on(model: &Arc<Model>, state: &mut RobotState, frame: &str) {
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_representation(VelocityRepresentation::Mixed);
    kd.set_state(state).unwrap();
    let sole = kd.frame_pose(model.frame_id(frame).unwrap());
    // keep the sole's yaw, remove its roll and pitch
    let (_, _, yaw) = sole.rotation.euler_angles();
    let flat = Isometry3::from_parts(
        Translation3::new(sole.translation.x, sole.translation.y, 0.0),
        UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
    );
    state.base_pose = flat * sole.inverse() * state.base_pose;
}
