//! A tick of the QP-IK and of the TSID allocates nothing (counting global allocator).

mod common;

use std::sync::Arc;

use common::*;
use nalgebra::Vector2;
use stride_block::Block;
use stride_qp::Backend;
use stride_wbc::{IkConfig, QpIk, Tsid, TsidConfig};

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
    input.right_in_contact = false;
    input.desired_zmp = Some(Vector2::new(input.com_position.x, input.com_position.y));
    let (_, n) = ALLOC.allocations_during(|| {
        for _ in 0..100 {
            assert!(tsid.step(&input).unwrap().report.status.is_success());
        }
    });
    assert_eq!(n, 0, "TSID ticks across a lift-off allocated {n} times");
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
    use nalgebra::{Rotation3, Vector3};
    use stride_wbc::{
        EstimatorSettings, GroundEstimator, GroundParameters, SoleGeometry, SoleState,
    };
    let sole = SoleGeometry {
        length: 0.2,
        width: 0.09,
    };
    let ground = GroundParameters {
        stiffness: 1e6,
        damping: 1e4,
    };
    let state = SoleState {
        position: Vector3::new(0.01, 0.0, -0.01),
        rotation: Rotation3::new(Vector3::new(0.02, -0.03, 0.1)),
        linear_velocity: Vector3::new(0.01, 0.0, -0.02),
        angular_velocity: Vector3::new(0.1, 0.2, 0.0),
        rest_position: Vector3::zeros(),
        rest_rotation: Rotation3::identity(),
    };
    let mut estimator = GroundEstimator::new(&EstimatorSettings {
        initial: GroundParameters {
            stiffness: 3e7,
            damping: 3e5,
        },
        initial_std: [3e7, 3e5],
        wrench_std: [2.0, 0.2],
    })
    .unwrap();
    let (_, n) = ALLOC.allocations_during(|| {
        for _ in 0..20 {
            let wrench = sole.wrench(&state, &ground);
            let _ = sole.wrench_rate(&state, &ground);
            estimator.touch_down();
            assert!(estimator.update(&sole.regressor(&state), &wrench));
        }
    });
    assert_eq!(n, 0, "soft-contact model and estimator allocated {n} times");
}
