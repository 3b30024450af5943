//! `step` allocates nothing after construction: PI, ZMP-CoM, the whole block with either controller
//! (MPC with the banded interior-point solver), counted with a global allocator.
use std::time::Duration;

use nalgebra::Vector2;
use stride_simplified::*;

/// Only allocations of the thread under test are counted (the test harness's own threads may
/// allocate at any time): see `CountingAllocator::allocations_during`.
#[global_allocator]
static ALLOC: stride_testkit::CountingAllocator = stride_testkit::CountingAllocator::new();

const OMEGA: f64 = 4.302_325_511_579_751;

#[test]
fn steps_do_not_allocate() {
    let foot = SupportPolygon::rectangle(-0.05, 0.07, -0.03, 0.03).unwrap();
    let both = SupportPolygon::rectangle(-0.05, 0.07, -0.03, 0.19).unwrap();

    let mut pi = DcmInstantaneousController::new(DcmInstantaneousConfig {
        ki: 1.0,
        ..Default::default()
    })
    .unwrap();
    let (_, n) = ALLOC.allocations_during(|| {
        for i in 0..100 {
            let e = 0.001 * i as f64;
            pi.step(
                Vector2::zeros(),
                Vector2::new(0.1, 0.0),
                Vector2::new(e, -e),
                OMEGA,
                &foot,
                0.01,
            )
            .unwrap();
        }
    });
    assert_eq!(n, 0, "DCM PI step allocated");

    let mut zc = ZmpComController::new(ZmpComConfig::default()).unwrap();
    let (_, n) = ALLOC.allocations_during(|| {
        for i in 0..100 {
            let z = Vector2::new(0.001 * i as f64, 0.0);
            zc.step(i % 30 < 15, OMEGA, z, -z, z, z, -z, 0.01).unwrap();
        }
    });
    assert_eq!(n, 0, "ZMP-CoM step allocated");

    for (kind, warm_start) in [
        (DcmControllerKind::Instantaneous, false),
        (DcmControllerKind::Predictive, false),
        (DcmControllerKind::Predictive, true),
    ] {
        let config = SimplifiedConfig {
            dcm_controller: kind,
            predictive: DcmPredictiveConfig {
                warm_start,
                ..Default::default()
            },
            ..Default::default()
        };
        let mut block = SimplifiedController::new(&config, Duration::from_millis(10)).unwrap();
        let samples = block.horizon_samples();
        let mut input = SimplifiedInput::new(samples, foot);
        input.omega = OMEGA;
        let (_, n) = ALLOC.allocations_during(|| {
            for tick in 0..40 {
                input.horizon.clear();
                for k in 0..samples {
                    let support = if k + tick < 60 { foot } else { both };
                    input
                        .horizon
                        .push(HorizonSample {
                            dcm_position: Vector2::new(0.01, 0.0),
                            zmp: Vector2::new(0.01, 0.0),
                            support,
                        })
                        .unwrap();
                }
                input.walking = tick % 20 < 10;
                // pushes large enough to activate the polygon constraints on some ticks
                input.measured_dcm = Vector2::new(0.01 + 0.0015 * tick as f64, 0.0);
                input.measured_zmp = Vector2::new(0.01, 0.0);
                let out = block.step(&input).unwrap();
                assert!(out.valid);
            }
        });
        assert_eq!(
            n, 0,
            "block step allocated with {kind:?} (warm start {warm_start})"
        );
        if kind == DcmControllerKind::Predictive {
            // make sure the constrained (iterative) path ran
            assert_eq!(block.output().diagnostics.mpc.status, MpcStatus::Solved);
        }
    }
}

/// Logging the layer's input every tick serializes its support polygons: the serde form (a list of
/// `[x, y]` vertices, unchanged) is written without building a `Vec`. (It used to go through
/// `Vec<[f64; 2]>`, one allocation per polygon per logged tick.)
#[test]
fn serializing_a_support_polygon_does_not_allocate() {
    let polygon = SupportPolygon::rectangle(-0.1, 0.1, -0.05, 0.12).unwrap();
    let as_vec: Vec<[f64; 2]> = polygon.into();
    let expected = serde_json::to_vec(&as_vec).unwrap();
    let mut buffer: Vec<u8> = Vec::with_capacity(4096);
    let (_, allocations) = ALLOC.allocations_during(|| {
        for _ in 0..100 {
            buffer.clear();
            serde_json::to_writer(&mut buffer, &polygon).unwrap();
        }
    });
    assert_eq!(allocations, 0);
    assert_eq!(buffer, expected);
    let back: SupportPolygon = serde_json::from_slice(&buffer).unwrap();
    assert_eq!(back, polygon);
}

/// A step-adjustment problem mid-swing on the left foot with the measured DCM at `y` \[m\].
fn left_stance_input(y: f64) -> StepAdjustmentInput {
    StepAdjustmentInput {
        dcm: Vector2::new(0.35, y),
        omega: OMEGA,
        stance: Foot::Left,
        stance_position: Vector2::new(0.3, 0.075),
        stance_yaw: 0.1,
        stance_cop: Vector2::new(0.31, 0.075),
        nominal_step: Vector2::new(0.4, -0.075),
        nominal_offset: Vector2::new(0.0, 0.05),
        time_since_touchdown: 0.35,
        nominal_duration: 1.0,
    }
}

#[test]
fn step_adjustment_does_not_allocate() {
    let mut adj = StepAdjuster::new(&StepAdjustmentConfig::default()).unwrap();
    let mut input = left_stance_input(-0.05);
    let (_, n) = ALLOC.allocations_during(|| {
        for i in 0..200 {
            // from the nominal case to pushes that activate the box and the timing bounds
            input.dcm.y = -0.05 - 0.002 * i as f64;
            input.time_since_touchdown = 0.35 + 0.004 * i as f64;
            adj.solve(&input).unwrap();
        }
    });
    assert_eq!(n, 0, "step adjustment allocated");
    assert!(adj.result().diagnostics.bound_active);
}

#[test]
fn step_adjustment_with_the_crossover_does_not_allocate() {
    let config = StepAdjustmentConfig {
        crossover_min: 0.10,
        crossover_max: 0.25,
        ..Default::default()
    };
    let mut adj = StepAdjuster::new(&config).unwrap();
    let mut input = left_stance_input(0.0);
    let mut crossed = 0;
    let (_, n) = ALLOC.allocations_during(|| {
        for i in 0..200 {
            // pushed towards the stance foot (left): to the no-crossing bound, then past the stance foot
            input.dcm.y = 0.002 * i as f64;
            input.time_since_touchdown = 0.35 + 0.002 * i as f64;
            if adj.solve(&input).unwrap().diagnostics.crossover {
                crossed += 1;
            }
        }
    });
    assert_eq!(n, 0, "step adjustment with the crossover allocated");
    assert!(crossed > 0 && crossed < 200, "{crossed}");
}

#[test]
fn foot_admittance_does_not_allocate() {
    use nalgebra::{Isometry3, Vector6};
    let config = FootAdmittanceConfig {
        enabled: true,
        touchdown_search_speed: 0.1,
        ground_stiffness: 1e6,
        tilt_feedforward_gain: 0.1,
        measured_tilt_gain: 0.5,
        swing_tilt_gain: 1.0,
        ..Default::default()
    };
    let mut admittance = FootAdmittance::new(&config, 0.2, 0.09, 320.0).unwrap();
    let mut input = FootAdmittanceInput {
        desired_zmp: Vector2::new(0.02, 0.0),
        soles: [
            Isometry3::translation(0.0, 0.07, 0.0),
            Isometry3::translation(0.0, -0.07, 0.0),
        ],
        wrenches: [Vector6::new(0.0, 0.0, 200.0, 1.0, -2.0, 0.0); 2],
        contacts: [true, true],
        planned: [true, true],
        dt: 0.002,
    };
    let (_, n) = ALLOC.allocations_during(|| {
        for i in 0..200 {
            // double support, then each foot alone
            input.contacts = [i % 3 != 1, i % 3 != 2];
            input.planned = input.contacts;
            input.wrenches[0][4] = -0.01 * i as f64;
            admittance.step(&input).unwrap();
        }
    });
    assert_eq!(n, 0, "foot admittance step allocated");
    // the left CoP (x ≤ 1 cm) stays behind its desired 2 cm: toe down (positive pitch)
    assert!(admittance.output().feet[0].tilt.y > 0.0);
}

#[test]
fn push_observer_does_not_allocate() {
    use nalgebra::Vector3;
    let mut observer =
        PushObserver::new(&PushConfig::default(), 32.8, Vector3::new(0.0, 0.0, -9.81)).unwrap();
    let weight = Vector3::new(0.0, 0.0, 32.8 * 9.81);
    let (_, n) = ALLOC.allocations_during(|| {
        for i in 0..200 {
            let v = Vector3::new(0.0, 0.02 * i as f64, 0.0);
            observer.update(0.01, &v, &weight).unwrap();
        }
    });
    assert_eq!(n, 0, "push observer allocated");
    assert!(observer.horizontal().y > 0.0);
}
