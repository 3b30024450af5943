//! The bundled humanoid's facts (`stride_model::bundled`) agree with the model: the planner geometry
//! stated there is what the robot has when standing at its posture.

use std::sync::Arc;

use nalgebra::DVector;
use stride_model::{bundled, KinDyn, Model, ModelError, RobotState};

fn standing() -> (Arc<Model>, KinDyn, RobotState) {
    let model = Arc::new(bundled::model().expect("bundled URDF"));
    let mut q = DVector::zeros(model.dof());
    for (name, value) in bundled::POSTURE {
        q[model.joint_index(name).expect("posture joint")] = value;
    }
    let l = model.frame_id(bundled::LEFT_SOLE).expect("left sole");
    let r = model.frame_id(bundled::RIGHT_SOLE).expect("right sole");
    let state = RobotState::standing(&model, &q, l, r).expect("standing state");
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_state(&state).expect("state");
    (model, kd, state)
}

#[test]
fn com_height_and_nominal_width_are_the_standing_robots() {
    let (model, kd, _) = standing();
    let l = kd.frame_pose(model.frame_id(bundled::LEFT_SOLE).unwrap());
    let r = kd.frame_pose(model.frame_id(bundled::RIGHT_SOLE).unwrap());
    assert!(l.translation.z.abs() < 1e-12 && r.translation.z.abs() < 1e-12);
    let com = kd.com_position();
    assert!(
        (com.z - bundled::COM_HEIGHT).abs() < 5e-3,
        "standing CoM height {} m vs COM_HEIGHT {} m",
        com.z,
        bundled::COM_HEIGHT
    );
    let width = (l.translation.vector - r.translation.vector).norm();
    assert!(
        (width - bundled::NOMINAL_WIDTH).abs() < 1e-3,
        "sole distance {width} m vs NOMINAL_WIDTH {} m",
        bundled::NOMINAL_WIDTH
    );
}

#[test]
fn standing_rejects_a_joint_outside_its_limits_by_name() {
    let (model, _, state) = standing();
    let k = model.joint_index("l_knee").expect("knee");
    let joint = &model.joints()[k];
    assert!(joint.upper.is_finite(), "the knee has limits");
    let mut q = state.joint_positions.clone();
    q[k] = joint.upper + 0.1;
    let l = model.frame_id(bundled::LEFT_SOLE).unwrap();
    let r = model.frame_id(bundled::RIGHT_SOLE).unwrap();
    match RobotState::standing(&model, &q, l, r) {
        Err(ModelError::JointOutOfLimits {
            joint: name,
            value,
            upper,
            ..
        }) => {
            assert_eq!(name, "l_knee");
            assert_eq!(value, joint.upper + 0.1);
            assert_eq!(upper, joint.upper);
        }
        other => panic!("expected JointOutOfLimits, got {other:?}"),
    }
    let message = RobotState::standing(&model, &q, l, r)
        .unwrap_err()
        .to_string();
    assert!(message.contains("l_knee"), "{message}");
    let short = DVector::zeros(model.dof() - 1);
    assert!(matches!(
        RobotState::standing(&model, &short, l, r),
        Err(ModelError::DimensionMismatch { .. })
    ));
}

#[test]
fn check_joint_limits_accepts_the_posture_and_rejects_nan() {
    let (model, _, mut state) = standing();
    state
        .check_joint_limits(&model)
        .expect("posture within limits");
    state.joint_positions[0] = f64::NAN;
    assert!(matches!(
        state.check_joint_limits(&model),
        Err(ModelError::JointOutOfLimits { .. })
    ));
}
