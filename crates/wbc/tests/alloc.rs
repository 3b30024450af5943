//! A tick of the QP-IK and of the TSID allocates nothing (counting global allocator).

mod common;

use std::sync::Arc;

use common::*;
use nalgebra::Vector2;
use stride_qp::Backend;
use stride_wbc::{walking, IkConfig, QpIk, Tsid, TsidConfig};

#[global_allocator]
static ALLOC: stride_testkit::CountingAllocator = stride_testkit::CountingAllocator::new();

#[test]
fn ik_and_tsid_ticks_allocate_nothing() {
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let mut input = references_at(&model, &state);
    input.com_position.x += 0.01;

    let mut ik = QpIk::new(
        Arc::clone(&model),
        IkConfig::default_for_bundled_model(),
        std::time::Duration::from_millis(2),
    )
    .unwrap();
    ik.step(&input).unwrap();
    let (_, n) = ALLOC.allocations_during(|| {
        for _ in 0..20 {
            assert!(ik.step(&input).unwrap().report.status.is_success());
        }
    });
    assert_eq!(n, 0, "QP-IK ticks allocated {n} times");

    let mut tsid = Tsid::new(
        Arc::clone(&model),
        TsidConfig::default_for_bundled_model(),
        std::time::Duration::from_millis(1),
    )
    .unwrap();
    tsid.step(&input).unwrap();
    let (_, n) = ALLOC.allocations_during(|| {
        for _ in 0..20 {
            assert!(tsid.step(&input).unwrap().report.status.is_success());
        }
    });
    assert_eq!(n, 0, "TSID ticks allocated {n} times");
    // a contact change (another prebuilt QP, first solve of that QP included) and a ZMP task
    input.set_contact("right_foot", false).unwrap();
    input.desired_zmp = Some(Vector2::new(input.com_position.x, input.com_position.y));
    let (_, n) = ALLOC.allocations_during(|| {
        for _ in 0..100 {
            assert!(tsid.step(&input).unwrap().report.status.is_success());
        }
    });
    assert_eq!(n, 0, "TSID ticks across a lift-off allocated {n} times");
    // run-time edits: contacts and references through handles, weights, gains, tasks taken out and put
    // back (a hard one too: the full solve path instead of the null-space one)
    let right = input.contact_id(walking::RIGHT_FOOT).unwrap();
    let left = input.frame_id(walking::LEFT_FOOT).unwrap();
    let (_, n) = ALLOC.allocations_during(|| {
        for k in 0..60 {
            input.contact_mut(right).unwrap().active = k % 20 < 10;
            input.frame_mut(left).unwrap().velocity[0] = 1e-4 * k as f64;
            tsid.set_task_weight("posture", &[1.0 + k as f64]).unwrap();
            tsid.set_task_gains("com", 25.0 + k as f64, 5.0).unwrap();
            tsid.set_task_gains("left_foot", 400.0, 40.0 + k as f64)
                .unwrap();
            tsid.set_task_enabled("torso", k % 2 == 0).unwrap();
            tsid.set_task_enabled("right_foot", k % 3 != 0).unwrap();
            assert!(tsid.step(&input).unwrap().report.status.is_success());
        }
    });
    assert_eq!(n, 0, "TSID ticks with run-time edits allocated {n} times");
    let (_, n) = ALLOC.allocations_during(|| {
        for k in 0..60 {
            input.frame_mut(left).unwrap().velocity[0] = 1e-4 * k as f64;
            ik.set_task_weight("posture", &[1.0 + k as f64]).unwrap();
            ik.set_task_gain("com", 2.0 + 0.1 * k as f64).unwrap();
            ik.set_task_enabled("torso", k % 2 == 0).unwrap();
            ik.set_task_enabled("com", k % 3 != 0).unwrap();
            assert!(ik.step(&input).unwrap().report.status.is_success());
        }
    });
    assert_eq!(n, 0, "QP-IK ticks with run-time edits allocated {n} times");
}

#[test]
fn clarabel_ticks_are_reported_not_asserted() {
    // clarabel builds its solver per solve (allocates); only check the ticks work with it
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let input = references_at(&model, &state);
    let mut c = IkConfig::default_for_bundled_model();
    c.qp.backend = Backend::Clarabel;
    let mut ik = QpIk::new(Arc::clone(&model), c, std::time::Duration::from_millis(2)).unwrap();
    assert!(ik.step(&input).unwrap().report.status.is_success());
}

#[test]
fn soft_contact_model_and_ground_estimator_allocate_nothing() {
    use common::soft::{rigid_guess_settings, stance_sample, GROUND, SOLE};
    let state = stance_sample();
    let mut estimator = stride_wbc::GroundEstimator::new(&rigid_guess_settings()).unwrap();
    let mut with_rest =
        stride_wbc::GroundRestEstimator::new(&rigid_guess_settings(), 1e-3).unwrap();
    let (_, n) = ALLOC.allocations_during(|| {
        for _ in 0..20 {
            let wrench = SOLE.wrench(&state, &GROUND);
            let _ = SOLE.wrench_rate(&state, &GROUND);
            estimator.touch_down();
            assert!(estimator.update(&SOLE.regressor(&state), &wrench));
            with_rest.touch_down();
            assert!(with_rest.update(&SOLE.regressor_with_rest_height(&state), &wrench));
        }
    });
    assert_eq!(n, 0, "soft-contact model and estimator allocated {n} times");
}

/// TSID-Flex (`flexible_joints`: the passive hips of `models/stride_humanoid_flex.urdf`) ticks allocate
/// nothing, with the passive torques changing every tick.
#[test]
fn tsid_flex_ticks_allocate_nothing() {
    let path = format!(
        "{}/../../models/stride_humanoid_flex.urdf",
        env!("CARGO_MANIFEST_DIR")
    );
    let model = Arc::new(stride_model::Model::from_urdf_file(path).unwrap());
    let state = standing_state(&model, &default_posture(&model));
    let mut input = references_at(&model, &state);
    let flex = [
        "l_hip_flex_pitch",
        "l_hip_flex_roll",
        "r_hip_flex_pitch",
        "r_hip_flex_roll",
    ];
    let mut config = TsidConfig::default_for_bundled_model();
    config.flexible_joints = flex.iter().map(|s| s.to_string()).collect();
    let mut tsid = Tsid::new(
        Arc::clone(&model),
        config,
        std::time::Duration::from_millis(1),
    )
    .unwrap();
    let joints: Vec<usize> = flex.iter().map(|n| model.joint_index(n).unwrap()).collect();
    tsid.step(&input).unwrap();
    let (_, n) = ALLOC.allocations_during(|| {
        for k in 0..40 {
            for &j in &joints {
                input.flexible_torques[j] = 0.1 * k as f64;
            }
            input.set_contact("right_foot", k < 20).unwrap();
            assert!(tsid.step(&input).unwrap().report.status.is_success());
        }
    });
    assert_eq!(n, 0, "TSID-Flex ticks allocated {n} times");
}

/// TSID-Compliant (`contact_model = "compliant"`, its ground estimated with the rest height, gated by
/// `estimator_accept_std`) ticks
/// allocate nothing, with the measured wrenches changing every tick and a lift-off and touch-down of the
/// right foot; with the held-period rate
/// (`held_acceleration`), a lift-off held while the sole still carries load (`lift_off_force`) and an
/// angular momentum task whose reference is the legs' momentum (`reference_joints`) and the planned
/// feet's (`reference_frames`); for each `wrench_source`.
#[test]
fn tsid_compliant_ticks_allocate_nothing() {
    for source in [
        stride_wbc::WrenchSource::Measured,
        stride_wbc::WrenchSource::Model,
        stride_wbc::WrenchSource::Filtered,
    ] {
        compliant_ticks_allocate_nothing(source);
    }
}

fn compliant_ticks_allocate_nothing(source: stride_wbc::WrenchSource) {
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let mut input = references_at(&model, &state);
    let mut config = TsidConfig::default_for_bundled_model();
    config.contact_model = stride_wbc::ContactModel::Compliant;
    config.compliant.wrench_source = source;
    config.compliant.held_acceleration = true;
    config.compliant.lift_off_force = 20.0;
    // The ground estimate per contact, with the rest height as its third parameter, fed back through
    // the gate.
    config.compliant.estimate_ground = true;
    config.compliant.estimate_rest_height = true;
    config.compliant.estimator_accept_std = 0.1;
    config.tasks.push(stride_wbc::TaskConfig::AngularMomentum(
        stride_wbc::AngularMomentumTaskConfig {
            name: "angular_momentum".into(),
            kp: 10.0,
            reference_joints: vec!["l_knee".into(), "r_hip_roll".into()],
            reference_frames: vec![stride_wbc::MomentumReferenceFrame {
                frame: "r_sole".into(),
                reference: "right_foot".into(),
            }],
            priority: stride_wbc::Priority::Hard,
            weight: None,
        },
    ));
    let mut tsid = Tsid::new(
        Arc::clone(&model),
        config,
        std::time::Duration::from_millis(2),
    )
    .unwrap();
    let ids = [walking::LEFT_FOOT, walking::RIGHT_FOOT].map(|n| input.contact_id(n).unwrap());
    tsid.step(&input).unwrap();
    let (_, n) = ALLOC.allocations_during(|| {
        for k in 0..40 {
            for id in ids {
                input.contact_mut(id).unwrap().measured_wrench[2] = 150.0 + k as f64;
            }
            input
                .set_contact("right_foot", !(10..20).contains(&k))
                .unwrap();
            assert!(!tsid.step(&input).unwrap().report.held);
        }
    });
    assert_eq!(
        n, 0,
        "TSID-Compliant ticks ({source:?}) allocated {n} times"
    );
}
