//! DCM instantaneous controller + ZMP-CoM controller through the block: plan reproduction, closed-loop
//! LIPM error decay, bias removal, polygon containment.
mod common;

use std::time::Duration;

use common::{Plan, OMEGA};
use nalgebra::{Matrix2, Vector2};
use proptest::prelude::*;
use stride_simplified::*;

fn input_from_plan(plan: &Plan, k: usize, horizon_capacity: usize) -> SimplifiedInput {
    let mut input = SimplifiedInput::new(horizon_capacity, plan.support[k]);
    fill_plan(&mut input, plan, k);
    input.measured_com_position = plan.com[k];
    input.measured_com_velocity = plan.com_velocity[k];
    input.measured_dcm = plan.dcm[k];
    input.measured_zmp = plan.zmp[k];
    input
}

fn fill_plan(input: &mut SimplifiedInput, plan: &Plan, k: usize) {
    input.time = Duration::from_secs_f64(k as f64 * plan.period);
    input.omega = plan.omega;
    input.walking = plan.walking[k];
    input.planned_dcm_position = plan.dcm[k];
    input.planned_dcm_velocity = plan.dcm_velocity[k];
    input.planned_zmp = plan.zmp[k];
    input.planned_com_position = plan.com[k];
    input.planned_com_velocity = plan.com_velocity[k];
    input.support_polygon = plan.support[k];
}

fn instantaneous(kp: f64, ki: f64) -> SimplifiedConfig {
    SimplifiedConfig {
        dcm_controller: DcmControllerKind::Instantaneous,
        instantaneous: DcmInstantaneousConfig {
            kp,
            ki,
            integral_limit: 0.05,
        },
        ..SimplifiedConfig::default()
    }
}

#[test]
fn plan_is_consistent_with_the_lipm() {
    // The test plan itself: ZMP recovered from the DCM equals the planned ZMP, and one exact LIPM step
    // from the planned CoM state lands on the next planned CoM state.
    let plan = Plan::default_walk();
    let d = LipmDiscretization::new(plan.omega, plan.period).unwrap();
    for k in 0..plan.len() - 1 {
        let z = zmp_from_dcm(plan.dcm[k], plan.dcm_velocity[k], plan.omega);
        assert!((z - plan.zmp[k]).norm() < 1e-12);
        let (x, v) = d.step_com(plan.com[k], plan.com_velocity[k], plan.zmp[k]);
        assert!((x - plan.com[k + 1]).norm() < 1e-10, "k {k}");
        assert!((v - plan.com_velocity[k + 1]).norm() < 1e-9, "k {k}");
        assert!(plan.support[k].contains(plan.zmp[k], 1e-12));
    }
}

#[test]
fn perfect_measurements_reproduce_the_plan_exactly() {
    let plan = Plan::default_walk();
    for ki in [0.0, 2.0] {
        let mut block =
            SimplifiedController::new(&instantaneous(1.2, ki), Duration::from_millis(10)).unwrap();
        for k in 0..plan.len() {
            let input = input_from_plan(&plan, k, 0);
            let out = block.step(&input).unwrap();
            assert!((out.desired_zmp - plan.zmp[k]).norm() <= 1e-9, "zmp at {k}");
            assert!(
                (out.com_position - plan.com[k]).norm() <= 1e-9,
                "com at {k}"
            );
            assert!(
                (out.com_velocity - plan.com_velocity[k]).norm() <= 1e-9,
                "com vel at {k}"
            );
            let acc = (plan.com[k] - plan.zmp[k]) * OMEGA * OMEGA;
            assert!((out.com_acceleration - acc).norm() <= 1e-7);
            assert!(!out.diagnostics.projection_active);
        }
    }
}

#[test]
fn closed_loop_lipm_follows_the_plan_exactly() {
    // The robot is an exact LIPM whose ZMP is the desired ZMP; measured = true state.
    let plan = Plan::default_walk();
    let d = LipmDiscretization::new(plan.omega, plan.period).unwrap();
    let mut block =
        SimplifiedController::new(&instantaneous(1.2, 1.0), Duration::from_millis(10)).unwrap();
    let (mut x, mut v) = (plan.com[0], plan.com_velocity[0]);
    let mut worst: f64 = 0.0;
    for k in 0..plan.len() {
        let mut input = input_from_plan(&plan, k, 0);
        input.measured_com_position = x;
        input.measured_com_velocity = v;
        input.measured_dcm = dcm_from_com(x, v, plan.omega);
        let out = *block.step(&input).unwrap();
        worst = worst.max((input.measured_dcm - plan.dcm[k]).norm());
        worst = worst.max((out.desired_zmp - plan.zmp[k]).norm());
        (x, v) = d.step_com(x, v, out.desired_zmp);
    }
    assert!(worst <= 1e-9, "worst deviation {worst}");
}

/// Simulates the DCM error of the exact LIPM under the controller for a constant plan, returning
/// e(t_k) samples (x component).
fn simulate_error(kp: f64, ki: f64, dt: f64, e0: f64, seconds: f64, zmp_bias: f64) -> Vec<f64> {
    let support = SupportPolygon::rectangle(-10.0, 10.0, -10.0, 10.0).unwrap();
    let mut controller = DcmInstantaneousController::new(DcmInstantaneousConfig {
        kp,
        ki,
        integral_limit: 100.0,
    })
    .unwrap();
    let d = LipmDiscretization::new(OMEGA, dt).unwrap();
    let reference = Vector2::zeros();
    let mut dcm = Vector2::new(e0, 0.0);
    let mut errors = Vec::new();
    for _ in 0..(seconds / dt).round() as usize {
        errors.push(dcm.x - reference.x);
        let out = controller
            .step(reference, Vector2::zeros(), dcm, OMEGA, &support, dt)
            .unwrap();
        dcm = d.step_dcm(dcm, out.desired_zmp + Vector2::new(zmp_bias, 0.0));
    }
    errors
}

#[test]
fn proportional_error_decays_at_the_predicted_rate() {
    for kp in [1.1, 1.5, 3.0] {
        let dt = 1e-3;
        let errors = simulate_error(kp, 0.0, dt, 0.02, 2.0, 0.0);
        // Fitted exponent from the log of the error over the run.
        let k1 = 100;
        let k2 = errors.len() - 1;
        let fitted = (errors[k2] / errors[k1]).ln() / ((k2 - k1) as f64 * dt);
        let continuous = -OMEGA * (kp - 1.0);
        // Exact for the ZOH loop: e⁺ = (F + G kp) e.
        let discrete = ((OMEGA * dt).exp() + (1.0 - (OMEGA * dt).exp()) * kp).ln() / dt;
        assert!(
            (fitted - discrete).abs() <= 1e-9 * discrete.abs(),
            "kp {kp}: {fitted} vs {discrete}"
        );
        // The ZOH rate approaches the continuous one: relative difference kp ω dt / 2 to first order.
        assert!(
            (fitted - continuous).abs() <= kp * OMEGA * dt * continuous.abs(),
            "kp {kp}"
        );
        assert!(errors.iter().all(|e| *e > 0.0));
    }
}

#[test]
fn proportional_gain_at_or_below_one_diverges() {
    // With kp ≤ 1 (rejected by the config) the closed loop ė = ω(1 − kp)e does not converge.
    let dt = 1e-3;
    let d = LipmDiscretization::new(OMEGA, dt).unwrap();
    for kp in [0.9, 1.0] {
        let mut dcm = Vector2::new(0.01, 0.0);
        for _ in 0..2000 {
            let z = dcm_instantaneous_law(
                Vector2::zeros(),
                Vector2::zeros(),
                dcm,
                Vector2::zeros(),
                kp,
                0.0,
                OMEGA,
            );
            dcm = d.step_dcm(dcm, z);
        }
        let expected = 0.01 * (OMEGA * (1.0 - kp) * 2.0).exp();
        assert!(
            dcm.x >= 0.01 * 0.999 && (dcm.x - expected).abs() < 0.01 * expected,
            "kp {kp}: {}",
            dcm.x
        );
    }
    assert!(DcmInstantaneousController::new(DcmInstantaneousConfig {
        kp: 1.0,
        ..Default::default()
    })
    .is_err());
}

#[test]
fn proportional_integral_error_matches_the_closed_loop_solution() {
    // [Romualdi 2022, eq. 10.2.18]: d/dt [e; I] = [[−ω(kp−1), −ω ki], [1, 0]] [e; I], e(0) = e0, I(0) = 0.
    let (kp, ki, e0, dt) = (1.5, 1.2, 0.02, 1e-4);
    let errors = simulate_error(kp, ki, dt, e0, 3.0, 0.0);
    let a = Matrix2::new(-OMEGA * (kp - 1.0), -OMEGA * ki, 1.0, 0.0);
    let mut worst: f64 = 0.0;
    for (k, e) in errors.iter().enumerate().step_by(100) {
        let state = (a * (k as f64 * dt)).exp() * nalgebra::Vector2::new(e0, 0.0);
        worst = worst.max((e - state.x).abs());
    }
    assert!(worst < 1e-3 * e0, "worst {worst}");
}

#[test]
fn integral_removes_a_constant_zmp_bias() {
    let bias = 0.01;
    let (kp, dt) = (1.5, 1e-3);
    // P only: steady error −bias/(kp − 1) (from ė = ω(1 − kp)e − ω bias).
    let p_only = simulate_error(kp, 0.0, dt, 0.0, 10.0, bias);
    let steady = -bias / (kp - 1.0);
    assert!(
        (p_only.last().unwrap() - steady).abs() < 1e-3 * bias,
        "{}",
        p_only.last().unwrap()
    );
    // PI: the error goes to zero.
    let pi = simulate_error(kp, 1.0, dt, 0.0, 30.0, bias);
    assert!(pi.last().unwrap().abs() < 1e-6, "{}", pi.last().unwrap());
}

#[test]
fn anti_windup_bounds_the_integral_term() {
    let support = SupportPolygon::rectangle(-0.05, 0.05, -0.05, 0.05).unwrap();
    let mut controller = DcmInstantaneousController::new(DcmInstantaneousConfig {
        kp: 1.2,
        ki: 5.0,
        integral_limit: 0.02,
    })
    .unwrap();
    for _ in 0..1000 {
        // a persistent small error keeps the output inside the polygon: the clamp is what bounds it
        let out = controller
            .step(
                Vector2::zeros(),
                Vector2::zeros(),
                Vector2::new(0.001, -0.001),
                OMEGA,
                &support,
                0.01,
            )
            .unwrap();
        assert!(out.integral_term.x <= 0.02 + 1e-15 && out.integral_term.y >= -0.02 - 1e-15);
    }
    let out = controller
        .step(
            Vector2::zeros(),
            Vector2::zeros(),
            Vector2::new(0.001, -0.001),
            OMEGA,
            &support,
            0.01,
        )
        .unwrap();
    assert!((out.integral_term.x - 0.02).abs() < 1e-12);
    // A large error saturates the projection: the integral is frozen.
    let before = controller.error_integral();
    let out = controller
        .step(
            Vector2::zeros(),
            Vector2::zeros(),
            Vector2::new(-0.5, 0.0),
            OMEGA,
            &support,
            0.01,
        )
        .unwrap();
    assert!(out.projection_active);
    assert_eq!(controller.error_integral(), before);
}

fn arbitrary_polygon() -> impl Strategy<Value = SupportPolygon> {
    prop::collection::vec((-0.3f64..0.3, -0.3f64..0.3), 3..12).prop_filter_map(
        "degenerate",
        |pts| {
            let pts: Vec<Vector2<f64>> = pts.into_iter().map(|(x, y)| Vector2::new(x, y)).collect();
            SupportPolygon::convex_hull(&pts)
                .ok()
                .filter(|p| p.area() > 1e-4)
        },
    )
}

proptest! {
    #[test]
    fn desired_zmp_never_leaves_the_support_polygon(
        polygon in arbitrary_polygon(),
        ex in -5.0f64..5.0, ey in -5.0f64..5.0,
        vx in -3.0f64..3.0, vy in -3.0f64..3.0,
        kp in 1.01f64..5.0, ki in 0.0f64..5.0,
    ) {
        let mut controller = DcmInstantaneousController::new(DcmInstantaneousConfig { kp, ki, integral_limit: 1.0 }).unwrap();
        let reference = polygon.vertex_mean();
        for _ in 0..3 {
            let out = controller.step(reference, Vector2::new(vx, vy), reference + Vector2::new(ex, ey), OMEGA, &polygon, 0.01).unwrap();
            prop_assert!(polygon.contains(out.desired_zmp, 1e-12));
            prop_assert!(out.desired_zmp.iter().all(|v| v.is_finite()));
        }
    }
}

/// The block reports the time of the controllers that ran, whichever DCM controller it is: the PI
/// controller's tick time is not the MPC's (absent) solve time, and the MPC's tick contains its solve.
#[test]
fn the_tick_time_is_that_of_the_running_controller() {
    let plan = Plan::default_walk();
    for controller in [
        DcmControllerKind::Instantaneous,
        DcmControllerKind::Predictive,
    ] {
        let config = SimplifiedConfig {
            dcm_controller: controller,
            ..SimplifiedConfig::default()
        };
        let mut block = SimplifiedController::new(&config, Duration::from_millis(10)).unwrap();
        let samples = block.horizon_samples();
        let mut input = input_from_plan(&plan, 0, samples);
        for j in 0..samples.min(plan.len()) {
            input
                .horizon
                .push(HorizonSample {
                    dcm_position: plan.dcm[j],
                    zmp: plan.zmp[j],
                    support: plan.support[j],
                })
                .unwrap();
        }
        let out = *block.step(&input).unwrap();
        let d = out.diagnostics;
        assert!(d.solve_time > 0.0, "{controller:?}: {}", d.solve_time);
        assert!(d.solve_time < 1.0, "{controller:?}: {}", d.solve_time);
        match controller {
            DcmControllerKind::Instantaneous | DcmControllerKind::CentroidalMpc => {
                assert_eq!(d.mpc.solve_time, 0.0)
            }
            DcmControllerKind::Predictive => {
                assert!(d.mpc.solve_time > 0.0);
                assert!(d.solve_time >= d.mpc.solve_time);
            }
        }
    }
}
