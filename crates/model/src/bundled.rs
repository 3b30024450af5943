//! The bundled humanoid (`models/stride_humanoid.urdf`, 33 kg, 32 joints): its URDF and every fact about it
//! that a controller needs, in one place. The runner's robot file (`configs/robots/stride_humanoid.toml`)
//! and the layers' library defaults state these values; tests keep them equal to this module.
//!
//! ```
//! let model = stride_model::bundled::model()?;
//! assert!(model.frame_id(stride_model::bundled::LEFT_SOLE).is_some());
//! # Ok::<(), stride_model::ModelError>(())
//! ```

use std::sync::Arc;

use nalgebra::DVector;

use crate::{FrameId, Model, ModelError, RobotState};

/// The URDF text of the bundled humanoid (compiled into the library: no file needed at run time).
pub const URDF: &str = include_str!("../../../models/stride_humanoid.urdf");

/// Left sole frame: origin at the sole's centre on the ground plane, x forward, z up.
pub const LEFT_SOLE: &str = "l_sole";
/// Right sole frame (as [`LEFT_SOLE`]).
pub const RIGHT_SOLE: &str = "r_sole";
/// The torso frame (chest link; z up at the standing posture) held upright by the whole-body layer.
pub const TORSO: &str = "chest";
/// The floating base link (pelvis), also held upright by the whole-body layer.
pub const PELVIS: &str = "root_link";

/// The standing posture \[rad\]: slightly crouched (knees 0.7 rad), arms off the torso. Joints not listed are
/// at zero. The same posture the whole-body layer regularizes to.
pub const POSTURE: [(&str, f64); 12] = [
    ("l_hip_pitch", 0.35),
    ("l_knee", 0.7),
    ("l_ankle_pitch", 0.35),
    ("r_hip_pitch", 0.35),
    ("r_knee", 0.7),
    ("r_ankle_pitch", 0.35),
    ("l_shoulder_pitch", 0.2),
    ("l_shoulder_roll", 0.25),
    ("l_elbow", 0.5),
    ("r_shoulder_pitch", 0.2),
    ("r_shoulder_roll", 0.25),
    ("r_elbow", 0.5),
];

/// CoM height above the soles at [`POSTURE`] \[m\] (0.540 m measured with stride-model): the planner's
/// `com_height` for this robot.
pub const COM_HEIGHT: f64 = 0.54;
/// Lateral distance between the sole origins at [`POSTURE`] \[m\]: the planner's `nominal_width`.
pub const NOMINAL_WIDTH: f64 = 0.15;
/// Sole rectangle length along the sole frame's x \[m\] (the URDF's foot collision box).
pub const FOOT_LENGTH: f64 = 0.20;
/// Sole rectangle width along the sole frame's y \[m\].
pub const FOOT_WIDTH: f64 = 0.09;

/// Period of the planner's event-driven replanning checks and of the simplified layer \[s\] (100 Hz).
pub const SIMPLIFIED_PERIOD: f64 = 0.01;
/// Period of the whole-body layer \[s\] (500 Hz).
pub const WBC_PERIOD: f64 = 0.002;
/// Period of the simulator \[s\] (2 kHz).
pub const SIM_PERIOD: f64 = 0.0005;

/// Loads the bundled humanoid from [`URDF`].
///
/// # Errors
/// None in practice (the URDF is fixed and tested); the `Result` is [`Model::from_urdf_str`]'s.
pub fn model() -> Result<Model, ModelError> {
    Model::from_urdf_str(URDF)
}

/// The joint positions of [`POSTURE`] in `model`'s joint order \[rad\] (joints not listed at zero).
///
/// # Errors
/// [`ModelError::InvalidFrame`] naming a [`POSTURE`] joint `model` does not have (a model that is not the
/// bundled humanoid).
pub fn posture(model: &Model) -> Result<DVector<f64>, ModelError> {
    let mut q = DVector::zeros(model.dof());
    for (joint, angle) in POSTURE {
        let i = model
            .joint_index(joint)
            .ok_or_else(|| not_bundled(joint, "no such joint"))?;
        q[i] = angle;
    }
    Ok(q)
}

/// The sole frames `[left, right]` ([`LEFT_SOLE`], [`RIGHT_SOLE`]) of `model`.
///
/// # Errors
/// [`ModelError::InvalidFrame`] when `model` lacks one.
pub fn soles(model: &Model) -> Result<[FrameId; 2], ModelError> {
    let find = |name| {
        model
            .frame_id(name)
            .ok_or_else(|| not_bundled(name, "no such frame"))
    };
    Ok([find(LEFT_SOLE)?, find(RIGHT_SOLE)?])
}

/// The bundled humanoid standing at [`POSTURE`] with its soles flat on the ground `z = 0`, their mid-point
/// at the world origin, at rest ([`RobotState::standing`]).
///
/// ```
/// let model = std::sync::Arc::new(stride_model::bundled::model()?);
/// let state = stride_model::bundled::standing_state(&model)?;
/// assert_eq!(state.joint_positions, stride_model::bundled::posture(&model)?);
/// # Ok::<(), stride_model::ModelError>(())
/// ```
///
/// # Errors
/// As [`posture`] and [`soles`].
pub fn standing_state(model: &Arc<Model>) -> Result<RobotState, ModelError> {
    let [left, right] = soles(model)?;
    RobotState::standing(model, &posture(model)?, left, right)
}

fn not_bundled(name: &str, reason: &str) -> ModelError {
    ModelError::InvalidFrame {
        name: name.to_string(),
        reason: format!("{reason} (not the bundled humanoid's model?)"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_named_frame_and_posture_joint_exists_in_the_bundled_urdf() {
        let model = model().expect("bundled URDF loads");
        for f in [LEFT_SOLE, RIGHT_SOLE, TORSO, PELVIS] {
            assert!(model.frame_id(f).is_some(), "frame {f}");
        }
        for (j, q) in POSTURE {
            let joint = model.joint_index(j);
            assert!(joint.is_some(), "joint {j}");
            assert!(q.is_finite());
        }
    }

    #[test]
    fn standing_state_puts_the_soles_on_the_ground_and_other_models_are_refused() {
        let model = Arc::new(model().expect("bundled URDF loads"));
        let state = standing_state(&model).expect("the bundled humanoid stands");
        let mut kd = crate::KinDyn::new(Arc::clone(&model));
        kd.set_state(&state).expect("finite state");
        let [l, r] = soles(&model).expect("soles");
        let (pl, pr) = (kd.frame_pose(l), kd.frame_pose(r));
        assert!(pl.translation.z.abs() < 1e-12 && pr.translation.z.abs() < 1e-12);
        assert!((pl.translation.vector + pr.translation.vector).xy().norm() < 1e-12);
        let knee = model.joint_index("l_knee").expect("knee");
        assert_eq!(state.joint_positions[knee], 0.7);

        let other = Model::from_urdf_str(
            r#"<robot name="one"><link name="a"><inertial><mass value="1"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>"#,
        )
        .expect("one-link URDF");
        assert!(matches!(
            posture(&other),
            Err(ModelError::InvalidFrame { .. })
        ));
        assert!(matches!(
            soles(&other),
            Err(ModelError::InvalidFrame { .. })
        ));
    }
}
