//! Shared helpers of the integration tests.
#![allow(dead_code)]

pub mod soft;

use std::sync::Arc;

use nalgebra::{DVector, Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use stride_model::{KinDyn, Model, RobotState, VelocityRepresentation};
use stride_wbc::{bundled_posture, walking, FrameReference, InputLayout, WbcInput};

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

/// The walking stack's names: frame references `left_foot`, `right_foot`, `torso`; contacts
/// `left_foot`, `right_foot`.
pub fn walking_layout() -> Arc<InputLayout> {
    Arc::new(InputLayout::new(
        [walking::LEFT_FOOT, walking::RIGHT_FOOT, walking::TORSO],
        [walking::LEFT_FOOT, walking::RIGHT_FOOT],
    ))
}

/// References that hold the robot exactly where `state` puts it (feet, CoM, chest orientation, posture),
/// in an input with the walking names ([`walking_layout`]).
pub fn references_at(model: &Arc<Model>, state: &RobotState) -> WbcInput {
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_representation(VelocityRepresentation::Mixed);
    kd.set_state(state).unwrap();
    let mut input = WbcInput::new(state.clone(), walking_layout());
    input.com_position = kd.com_position();
    *input.lf_mut() = FrameReference::still(kd.frame_pose(model.frame_id("l_sole").unwrap()));
    *input.rf_mut() = FrameReference::still(kd.frame_pose(model.frame_id("r_sole").unwrap()));
    input.torso_mut().pose.rotation = kd.frame_pose(model.frame_id("chest").unwrap()).rotation;
    input.posture = Some(state.joint_positions.clone());
    input
}

/// Access to the walking references of a [`walking_layout`] input (tests only: names resolved per call).
pub trait Walking {
    /// Left sole reference.
    fn lf(&self) -> FrameReference;
    /// Right sole reference.
    fn rf(&self) -> FrameReference;
    /// Torso reference.
    fn torso(&self) -> FrameReference;
    /// Left sole reference, to write.
    fn lf_mut(&mut self) -> &mut FrameReference;
    /// Right sole reference, to write.
    fn rf_mut(&mut self) -> &mut FrameReference;
    /// Torso reference, to write.
    fn torso_mut(&mut self) -> &mut FrameReference;
    /// Torso angular velocity reference (rad/s).
    fn torso_angular_velocity(&self) -> Vector3<f64> {
        self.torso().velocity.fixed_rows::<3>(3).into_owned()
    }
    /// Sets the torso angular velocity reference (rad/s).
    fn set_torso_angular_velocity(&mut self, w: Vector3<f64>) {
        self.torso_mut()
            .velocity
            .fixed_rows_mut::<3>(3)
            .copy_from(&w);
    }
}

impl Walking for WbcInput {
    fn lf(&self) -> FrameReference {
        *self.frame_reference(walking::LEFT_FOOT).unwrap()
    }
    fn rf(&self) -> FrameReference {
        *self.frame_reference(walking::RIGHT_FOOT).unwrap()
    }
    fn torso(&self) -> FrameReference {
        *self.frame_reference(walking::TORSO).unwrap()
    }
    fn lf_mut(&mut self) -> &mut FrameReference {
        let id = self.frame_id(walking::LEFT_FOOT).unwrap();
        self.frame_mut(id).unwrap()
    }
    fn rf_mut(&mut self) -> &mut FrameReference {
        let id = self.frame_id(walking::RIGHT_FOOT).unwrap();
        self.frame_mut(id).unwrap()
    }
    fn torso_mut(&mut self) -> &mut FrameReference {
        let id = self.frame_id(walking::TORSO).unwrap();
        self.frame_mut(id).unwrap()
    }
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

/// `M ν̇ + h − Σ Jᵀ w − [0; τ]` (largest entry) with stride-model's RNEA: how far a TSID output is from the
/// equations of motion at `state`, its contact wrenches acting at `frames`.
pub fn dynamics_residual(
    model: &Arc<Model>,
    state: &RobotState,
    frames: &[String],
    out: &stride_wbc::TsidOutput,
) -> f64 {
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_representation(VelocityRepresentation::Mixed);
    kd.set_state(state).unwrap();
    let wrenches: Vec<stride_model::ExternalWrench> = frames
        .iter()
        .zip(&out.contact_wrenches)
        .map(|(f, w)| stride_model::ExternalWrench {
            frame: model.frame_id(f).unwrap(),
            wrench: *w,
        })
        .collect();
    let mut gen = DVector::zeros(model.nv());
    kd.inverse_dynamics(&out.accelerations, &wrenches, &mut gen)
        .unwrap();
    let base = gen.rows(0, 6).amax();
    let joints = (gen.rows(6, model.dof()) - &out.joint_torques).amax();
    base.max(joints)
}
