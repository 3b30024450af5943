//! Generic whole-body control: tasks and contacts on any frame, references and contacts by name, run-time
//! edits, the builders. The TSID with a hand contact (a hand pressing on a wall, plus the feet) and a hand
//! SE(3) task; the QP-IK with a hand SE(3) task.

mod common;

use std::sync::Arc;
use std::time::Duration;

use common::*;
use nalgebra::{DMatrix, DVector, Isometry3, Translation3, Vector3, Vector6};
use stride_model::{bundled, KinDyn, Model, RobotState, VelocityRepresentation};
use stride_wbc::prelude::*;
use stride_wbc::{ContactTaskConfig, IkFeedback};

const PERIOD: Duration = Duration::from_millis(2);
const HAND_X: [f64; 2] = [-0.03, 0.03];
const HAND_Y: [f64; 2] = [-0.02, 0.02];
const HAND_MU: f64 = 0.5;
const HAND_MIN_FORCE: f64 = 10.0;

fn kd_at(model: &Arc<Model>, state: &RobotState) -> KinDyn {
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_representation(VelocityRepresentation::Mixed);
    kd.set_state(state).unwrap();
    kd
}

fn posture() -> Vec<(&'static str, f64)> {
    bundled::POSTURE.to_vec()
}

/// Feet and left palm in contact (the palm pressing with at least 10 N on a wall whose normal is the
/// palm frame's z), the right palm tracking the user's reference `target` (hard SE(3)), CoM hard,
/// chest upright, posture, limits.
fn hand_tsid_config() -> TsidConfig {
    let hand = ContactTaskConfig {
        foot_x: HAND_X,
        foot_y: HAND_Y,
        min_normal_force: HAND_MIN_FORCE,
        ..ContactTaskConfig::new("l_hand_palm", HAND_MU)
    };
    let reach = Se3TaskConfig {
        name: "reach".into(),
        frame: "r_hand_palm".into(),
        reference: "target".into(),
        kp_linear: 100.0,
        kp_angular: 100.0,
        kd_linear: 20.0,
        kd_angular: 20.0,
        mask: [true; 6],
        priority: Priority::Hard,
        weight: None,
    };
    TsidConfig::builder()
        .contact(bundled::LEFT_SOLE, 0.33)
        .contact(bundled::RIGHT_SOLE, 0.33)
        .task(TaskConfig::Contact(hand))
        .task(TaskConfig::Se3(reach))
        .com(25.0, 5.0)
        .so3(bundled::TORSO, "upright", 100.0, 20.0, 50.0)
        .posture(100.0, 20.0, &posture())
        .limits(0.05)
        .build()
        .unwrap()
}

#[test]
fn tsid_with_a_hand_contact_and_a_hand_task_holds_the_dynamics_and_the_hand_cone() {
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let mut tsid = Tsid::new(Arc::clone(&model), hand_tsid_config(), PERIOD).unwrap();
    let contacts: Vec<String> = tsid.contact_tasks().map(str::to_owned).collect();
    assert_eq!(contacts, ["l_sole", "r_sole", "l_hand_palm"]);
    let kd = kd_at(&model, &state);
    let pose = |f: &str| kd.frame_pose(model.frame_id(f).unwrap());
    // the user's references, by name
    let mut input = tsid.input(&state);
    input.com_position = kd.com_position();
    let target = Isometry3::from_parts(
        Translation3::from(pose("r_hand_palm").translation.vector + Vector3::new(0.05, 0.0, 0.03)),
        pose("r_hand_palm").rotation,
    );
    input
        .set_frame_reference("target", FrameReference::still(target))
        .unwrap();
    input
        .set_frame_reference("upright", FrameReference::still(pose(bundled::TORSO)))
        .unwrap();
    assert!(input
        .set_frame_reference("l_hand", FrameReference::default())
        .is_err());
    let out = tsid.step(&input).unwrap().clone();
    assert!(out.report.is_nominal(), "{:?}", out.report);
    // floating-base dynamics with the three contact wrenches
    let residual = dynamics_residual(&model, &state, &contacts, &out);
    assert!(residual < 1e-8, "dynamics residual {residual}");
    // the hand wrench in its friction pyramid and CoP rectangle, pressing with at least 10 N
    let rt = pose("l_hand_palm").rotation.inverse();
    let w = out.contact_wrenches[2];
    let force = rt * Vector3::new(w[0], w[1], w[2]);
    let torque = rt * Vector3::new(w[3], w[4], w[5]);
    assert!(
        force.z >= HAND_MIN_FORCE - 1e-7,
        "hand normal force {}",
        force.z
    );
    assert!(
        force.x.abs() + force.y.abs() <= HAND_MU * force.z + 1e-7,
        "friction {force:?}"
    );
    let cop = (-torque.y / force.z, torque.x / force.z);
    assert!(
        cop.0 >= HAND_X[0] - 1e-9 && cop.0 <= HAND_X[1] + 1e-9,
        "CoP x {}",
        cop.0
    );
    assert!(
        cop.1 >= HAND_Y[0] - 1e-9 && cop.1 <= HAND_Y[1] + 1e-9,
        "CoP y {}",
        cop.1
    );
    assert_eq!(out.contact_load, [1.0, 1.0, 1.0]);
    // the hand contact holds the palm still: J ν̇ + J̇ν = 0 (the robot is at rest)
    let palm_acc = frame_acceleration(&model, &state, "l_hand_palm", &out.accelerations);
    assert!(palm_acc.amax() < 1e-8, "palm acceleration {palm_acc:?}");
    // the hard reach task: J ν̇ + J̇ν = K_p e (at rest, no feedforward)
    let reach = frame_acceleration(&model, &state, "r_hand_palm", &out.accelerations);
    let mut expected = Vector6::zeros();
    expected
        .fixed_rows_mut::<3>(0)
        .copy_from(&(100.0 * Vector3::new(0.05, 0.0, 0.03)));
    assert!(
        (reach - expected).amax() < 1e-6,
        "hand acceleration {reach:?}"
    );
    // opening the hand contact by name takes its wrench to zero once the ramp has run
    input.set_contact("l_hand_palm", false).unwrap();
    for _ in 0..20 {
        tsid.step(&input).unwrap();
    }
    assert_eq!(tsid.output().contact_wrenches[2], Vector6::zeros());
    assert_eq!(tsid.output().contact_load[2], 0.0);
}

/// `J ν̇ + J̇ν` of `frame` (mixed, world axes).
fn frame_acceleration(
    model: &Arc<Model>,
    state: &RobotState,
    frame: &str,
    accelerations: &DVector<f64>,
) -> Vector6<f64> {
    let kd = kd_at(model, state);
    let id = model.frame_id(frame).unwrap();
    let mut j = DMatrix::zeros(6, model.nv());
    kd.frame_jacobian(id, &mut j).unwrap();
    let a = &j * accelerations;
    Vector6::from_column_slice(a.as_slice()) + kd.frame_bias_acceleration(id)
}

#[test]
fn qp_ik_drives_a_hand_to_the_users_reference_with_the_feet_held() {
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let config = IkConfig::builder()
        .se3_hard(bundled::LEFT_SOLE, 7.0)
        .se3_hard(bundled::RIGHT_SOLE, 7.0)
        .se3_hard("l_hand_palm", 10.0)
        .com(2.0)
        .posture(5.0, &posture())
        .limits()
        .build()
        .unwrap();
    let mut ik = QpIk::new(Arc::clone(&model), config, PERIOD).unwrap();
    let kd = kd_at(&model, &state);
    let pose = |f: &str| kd.frame_pose(model.frame_id(f).unwrap());
    let mut input = ik.input(&state);
    input.com_position = kd.com_position();
    for sole in [bundled::LEFT_SOLE, bundled::RIGHT_SOLE] {
        input
            .set_frame_reference(sole, FrameReference::still(pose(sole)))
            .unwrap();
    }
    let hand0 = pose("l_hand_palm");
    let target = Isometry3::from_parts(
        Translation3::from(hand0.translation.vector + Vector3::new(0.06, 0.02, 0.05)),
        hand0.rotation,
    );
    let hand = input.frame_id("l_hand_palm").unwrap();
    *input.frame_mut(hand).unwrap() = FrameReference::still(target);
    for _ in 0..1500 {
        assert!(ik.step(&input).unwrap().report.is_nominal());
    }
    let kd = kd_at(&model, ik.integrated_state());
    let reached = kd.frame_pose(model.frame_id("l_hand_palm").unwrap());
    let error = (reached.translation.vector - target.translation.vector).norm();
    assert!(error < 1e-3, "hand away from its reference by {error} m");
    for sole in [bundled::LEFT_SOLE, bundled::RIGHT_SOLE] {
        let moved = (kd
            .frame_pose(model.frame_id(sole).unwrap())
            .translation
            .vector
            - pose(sole).translation.vector)
            .norm();
        assert!(moved < 1e-6, "{sole} moved {moved} m");
    }
}

#[test]
fn a_disabled_soft_task_gives_the_solution_of_a_controller_without_it() {
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let full = IkConfig::builder()
        .se3_hard(bundled::LEFT_SOLE, 7.0)
        .se3_hard(bundled::RIGHT_SOLE, 7.0)
        .se3("l_hand_palm", 10.0)
        .com(2.0)
        .posture(5.0, &posture())
        .feedback(IkFeedback::Measured)
        .build()
        .unwrap();
    let mut without = full.clone();
    without.tasks.retain(|t| t.name() != "l_hand_palm");
    let mut ik = QpIk::new(Arc::clone(&model), full, PERIOD).unwrap();
    let mut reference = QpIk::new(Arc::clone(&model), without, PERIOD).unwrap();
    let kd = kd_at(&model, &state);
    let mut input = ik.input(&state);
    input.com_position = kd.com_position() + Vector3::new(0.01, 0.0, 0.0);
    for sole in [bundled::LEFT_SOLE, bundled::RIGHT_SOLE] {
        let pose = kd.frame_pose(model.frame_id(sole).unwrap());
        input
            .set_frame_reference(sole, FrameReference::still(pose))
            .unwrap();
    }
    input
        .set_frame_reference("l_hand_palm", FrameReference::default())
        .unwrap();
    let with_hand = ik.step(&input).unwrap().joint_velocities.clone();
    ik.set_task_enabled("l_hand_palm", false).unwrap();
    assert!(!ik.is_task_enabled("l_hand_palm").unwrap());
    assert!(ik.set_task_weight("l_hand_palm", &[2.0]).is_err());
    let disabled = ik.step(&input).unwrap().joint_velocities.clone();
    let expected = reference.step(&input).unwrap().joint_velocities.clone();
    assert!((&disabled - &expected).amax() < 1e-9);
    assert!((&with_hand - &disabled).amax() > 1e-3);
    // back on: the first solution again
    ik.set_task_enabled("l_hand_palm", true).unwrap();
    let again = ik.step(&input).unwrap().joint_velocities.clone();
    assert!((&again - &with_hand).amax() < 1e-9);
    // limits cannot be disabled, unknown names are errors
    assert!(ik.set_task_enabled("nope", false).is_err());
    assert!(ik.set_task_gain("com", -1.0).is_err());
}

#[test]
fn disabling_a_hard_foot_task_frees_the_foot_and_enabling_it_holds_it_again() {
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let mut tsid = Tsid::new(
        Arc::clone(&model),
        TsidConfig::default_for_bundled_model(),
        PERIOD,
    )
    .unwrap();
    let mut input = references_at(&model, &state);
    input.set_contact(walking::RIGHT_FOOT, false).unwrap();
    // the right sole reference 5 cm up: the foot task pulls it up
    input.rf_mut().pose.translation.vector.z += 0.05;
    for _ in 0..20 {
        tsid.step(&input).unwrap();
    }
    let on = frame_acceleration(&model, &state, "r_sole", &tsid.output().accelerations);
    assert!(on[2] > 1.0, "the foot task lifts the foot: {on:?}");
    tsid.set_task_enabled("right_foot", false).unwrap();
    let off = tsid.step(&input).unwrap().clone();
    assert!(off.report.status.is_success());
    let free = frame_acceleration(&model, &state, "r_sole", &off.accelerations);
    assert!(
        free[2] < 0.5 * on[2],
        "without the task the foot is not lifted: {free:?}"
    );
    assert_eq!(
        off.residuals
            .iter()
            .find(|r| r.name == "right_foot")
            .unwrap()
            .residual,
        0.0
    );
    tsid.set_task_enabled("right_foot", true).unwrap();
    tsid.set_task_gains("right_foot", 800.0, 40.0).unwrap();
    let back = tsid.step(&input).unwrap().clone();
    let lifted = frame_acceleration(&model, &state, "r_sole", &back.accelerations);
    // hard again, with K_p doubled: e = 5 cm → 40 m/s² (the foot is at rest)
    assert!((lifted[2] - 800.0 * 0.05).abs() < 1e-6, "{lifted:?}");
    assert!(tsid.set_task_enabled("dynamics", false).is_err());
    assert!(tsid.set_task_enabled("left_contact", false).is_err());
}

#[test]
fn contact_names_come_from_contact_or_foot_and_not_both() {
    let parse = |text: &str| toml::from_str::<TsidConfig>(text).unwrap();
    let base = "[[tasks]]\ntype = \"floating_base_dynamics\"\nname = \"dynamics\"\n\
                [[tasks]]\ntype = \"contact\"\nname = \"c\"\nframe = \"l_hand_palm\"\n";
    let model = bundled_model();
    let named = parse(&format!("{base}contact = \"l_hand\"\n"));
    let tsid = Tsid::new(Arc::clone(&model), named, PERIOD).unwrap();
    assert_eq!(tsid.input_layout().contacts(), ["l_hand"]);
    let foot = parse(&format!("{base}foot = \"left\"\n"));
    let tsid = Tsid::new(Arc::clone(&model), foot, PERIOD).unwrap();
    assert_eq!(tsid.input_layout().contacts(), [walking::LEFT_FOOT]);
    for bad in [
        base.to_owned(),
        format!("{base}foot = \"left\"\ncontact = \"x\"\n"),
    ] {
        let err = Tsid::new(Arc::clone(&model), parse(&bad), PERIOD)
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("contact"), "{err}");
    }
}

#[test]
fn an_input_of_a_larger_layout_works_and_one_missing_a_name_is_an_error() {
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let mut tsid = Tsid::new(
        Arc::clone(&model),
        TsidConfig::default_for_bundled_model(),
        PERIOD,
    )
    .unwrap();
    let own = references_at(&model, &state);
    let expected = tsid.step(&own).unwrap().joint_torques.clone();
    // the same references in an input with more names, in another order
    let layout = InputLayout::new(
        [
            "l_hand",
            walking::TORSO,
            walking::RIGHT_FOOT,
            walking::LEFT_FOOT,
        ],
        ["l_hand", walking::RIGHT_FOOT, walking::LEFT_FOOT],
    );
    let mut larger = WbcInput::new(state.clone(), Arc::new(layout));
    larger.com_position = own.com_position;
    larger.posture = own.posture.clone();
    for name in [walking::LEFT_FOOT, walking::RIGHT_FOOT, walking::TORSO] {
        larger
            .set_frame_reference(name, *own.frame_reference(name).unwrap())
            .unwrap();
    }
    tsid.reset();
    let got = tsid.step(&larger).unwrap().joint_torques.clone();
    assert!((&got - &expected).amax() < 1e-12);
    let missing = WbcInput::new(state, Arc::new(InputLayout::default()));
    let err = tsid.step(&missing).err().unwrap().to_string();
    assert!(err.contains("left_foot"), "{err}");
}
