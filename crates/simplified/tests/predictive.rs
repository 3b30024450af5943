//! DCM predictive controller: plan reproduction, constraint satisfaction, KKT conditions in the thesis'
//! condensed ZMP formulation (built here independently), agreement with clarabel on that dense
//! formulation and with the unconstrained closed form.
mod common;

use std::time::Duration;

use common::{Plan, OMEGA};
use nalgebra::{DMatrix, DVector, Vector2};
use stride_qp::{ClarabelSettings, ClarabelSolver, DenseQp, QpSolver, SolverOutput};
use stride_simplified::*;

fn fill_horizon(horizon: &mut DcmHorizon, plan: &Plan, k: usize, samples: usize) {
    horizon.clear();
    for j in k..(k + samples).min(plan.len()) {
        horizon
            .push(HorizonSample {
                dcm_position: plan.dcm[j],
                zmp: plan.zmp[j],
                support: plan.support[j],
            })
            .unwrap();
    }
}

fn predictive(horizon: f64) -> SimplifiedConfig {
    SimplifiedConfig {
        dcm_controller: DcmControllerKind::Predictive,
        predictive: DcmPredictiveConfig {
            horizon,
            ..DcmPredictiveConfig::default()
        },
        ..SimplifiedConfig::default()
    }
}

#[test]
fn closed_loop_lipm_follows_the_plan_exactly() {
    let plan = Plan::default_walk();
    let d = LipmDiscretization::new(plan.omega, plan.period).unwrap();
    let mut block = SimplifiedController::new(&predictive(2.0), Duration::from_millis(10)).unwrap();
    let samples = block.horizon_samples();
    assert_eq!(samples, 201);
    let mut input = SimplifiedInput::new(samples, plan.support[0]);
    let (mut x, mut v) = (plan.com[0], plan.com_velocity[0]);
    let mut worst: f64 = 0.0;
    for k in 0..plan.len() {
        fill_horizon(&mut input.horizon, &plan, k, samples);
        input.time = Duration::from_secs_f64(k as f64 * plan.period);
        input.omega = plan.omega;
        input.walking = plan.walking[k];
        input.planned_dcm_position = plan.dcm[k];
        input.planned_dcm_velocity = plan.dcm_velocity[k];
        input.planned_zmp = plan.zmp[k];
        input.planned_com_position = plan.com[k];
        input.planned_com_velocity = plan.com_velocity[k];
        input.support_polygon = plan.support[k];
        input.measured_com_position = x;
        input.measured_com_velocity = v;
        input.measured_dcm = dcm_from_com(x, v, plan.omega);
        input.measured_zmp = plan.zmp[k];
        let out = *block.step(&input).unwrap();
        worst = worst.max((input.measured_dcm - plan.dcm[k]).norm());
        worst = worst.max((out.desired_zmp - plan.zmp[k]).norm());
        worst = worst.max((out.com_position - plan.com[k]).norm());
        worst = worst.max((out.com_velocity - plan.com_velocity[k]).norm());
        assert!(matches!(
            out.diagnostics.mpc.status,
            MpcStatus::Unconstrained | MpcStatus::Solved
        ));
        assert_eq!(
            out.diagnostics.mpc.held_samples,
            (k + samples).saturating_sub(plan.len())
        );
        (x, v) = d.step_com(x, v, out.desired_zmp);
    }
    assert!(worst <= 1e-9, "worst deviation {worst}");
}

/// The thesis' condensed problem [Romualdi 2022, eq. 10.2.24] in w = [z_x(0..N); z_y(0..N)], built from the problem data
/// only: H, g, A, b.
struct Dense {
    h: DMatrix<f64>,
    g: DVector<f64>,
    a: DMatrix<f64>,
    b: DVector<f64>,
    n: usize,
}

fn dense_problem(view: &MpcProblemView) -> Dense {
    let n = view.zmp.len();
    let f = (view.omega * view.period).exp();
    let gg = 1.0 - f;
    let w_xi = view.config.dcm_weight;
    let w_z = view.config.zmp_rate_weight;
    // Per axis: ξ = s0 ξ̄ + S z (rows k = 1..N).
    let mut s = DMatrix::zeros(n, n);
    let mut s0 = DVector::zeros(n);
    for k in 1..=n {
        s0[k - 1] = f.powi(k as i32);
        for j in 0..k {
            s[(k - 1, j)] = f.powi((k - 1 - j) as i32) * gg;
        }
    }
    let mut dmat = DMatrix::zeros(n, n);
    for k in 0..n {
        dmat[(k, k)] = 1.0;
        if k > 0 {
            dmat[(k, k - 1)] = -1.0;
        }
    }
    let mut h = DMatrix::zeros(2 * n, 2 * n);
    let mut g = DVector::zeros(2 * n);
    let block_h = &s.transpose() * &s * w_xi + &dmat.transpose() * &dmat * w_z;
    for axis in 0..2 {
        let xi_bar = view.initial_dcm[axis];
        let r = DVector::from_iterator(n, (1..=n).map(|k| view.reference_dcm[k][axis]));
        let mut rate_target = DVector::zeros(n);
        for k in 0..n {
            let zhat_prev = if k == 0 {
                view.previous_planned_zmp[axis]
            } else {
                view.reference_zmp[k - 1][axis]
            };
            let planned_rate = match view.config.zmp_rate_reference {
                ZmpRateReference::Plan => view.reference_zmp[k][axis] - zhat_prev,
                ZmpRateReference::Zero => 0.0,
            };
            rate_target[k] = planned_rate + if k == 0 { view.previous_zmp[axis] } else { 0.0 };
        }
        let ga = s.transpose() * (&s0 * xi_bar - r) * w_xi - dmat.transpose() * rate_target * w_z;
        h.view_mut((axis * n, axis * n), (n, n)).copy_from(&block_h);
        g.rows_mut(axis * n, n).copy_from(&ga);
    }
    let rows: usize = view.supports.iter().map(|p| p.len()).sum();
    let mut a = DMatrix::zeros(rows, 2 * n);
    let mut b = DVector::zeros(rows);
    let mut r = 0;
    for (k, polygon) in view.supports.iter().enumerate() {
        for e in 0..polygon.len() {
            let (normal, bound) = polygon.half_plane(e);
            a[(r, k)] = normal.x;
            a[(r, n + k)] = normal.y;
            b[r] = bound;
            r += 1;
        }
    }
    Dense { h, g, a, b, n }
}

fn solution_vector(view: &MpcProblemView) -> DVector<f64> {
    let n = view.zmp.len();
    DVector::from_iterator(
        2 * n,
        (0..2 * n).map(|i| {
            if i < n {
                view.zmp[i].x
            } else {
                view.zmp[i - n].y
            }
        }),
    )
}

fn multipliers_in_dense_order(view: &MpcProblemView) -> DVector<f64> {
    // rows of the dense problem are stage-major, edges in polygon order: the same order as the MPC's
    let rows: usize = view.supports.iter().map(|p| p.len()).sum();
    assert_eq!(rows, view.multipliers.len());
    let mut r = 0;
    for (k, polygon) in view.supports.iter().enumerate() {
        for e in 0..polygon.len() {
            assert_eq!(view.constraint_rows[r], (k, e));
            r += 1;
        }
    }
    DVector::from_column_slice(view.multipliers)
}

fn check_kkt(view: &MpcProblemView, dense: &Dense, label: &str) {
    let w = solution_vector(view);
    let lambda = multipliers_in_dense_order(view);
    // primal feasibility
    let slack = &dense.b - &dense.a * &w;
    assert!(
        slack.min() >= -1e-6,
        "constraint violation {}",
        -slack.min()
    );
    // dual feasibility
    assert!(
        lambda.min() >= -1e-9 * lambda.amax().max(1.0),
        "negative multiplier {}",
        lambda.min()
    );
    // stationarity, relative to the size of the terms
    let hw = &dense.h * &w;
    let at_l = dense.a.transpose() * &lambda;
    let stationarity = &hw + &dense.g + &at_l;
    let scale = hw.amax().max(dense.g.amax()).max(at_l.amax()).max(1.0);
    assert!(
        stationarity.amax() <= 1e-6 * scale,
        "stationarity {} (scale {scale})",
        stationarity.amax()
    );
    // complementarity: every row is active (slack ≤ 1e-6 m) or has a vanishing multiplier
    // (≤ 1e-6 of the largest), and no product exceeds the largest multiplier × 1 nm.
    let lambda_max = lambda.amax().max(1e-300);
    for i in 0..lambda.len() {
        assert!(
            slack[i] <= 1e-6 || lambda[i] <= 1e-6 * lambda_max,
            "{label}: row {i}: slack {} multiplier {} (max {lambda_max})",
            slack[i],
            lambda[i]
        );
    }
    let comp = slack.component_mul(&lambda).amax();
    assert!(
        comp <= lambda_max * 1e-9,
        "complementarity {comp} (max multiplier {lambda_max})"
    );
}

fn solve_dense_with_clarabel(dense: &Dense) -> DVector<f64> {
    let n = 2 * dense.n;
    let mut qp = DenseQp::new(n, 0, dense.b.len());
    // H must be symmetric: its upper triangle mirrored.
    let upper = dense.h.upper_triangle();
    qp.hessian_mut()
        .copy_from(&(&upper + upper.transpose() - DMatrix::from_diagonal(&upper.diagonal())));
    qp.gradient_mut().copy_from(&dense.g);
    qp.ineq_matrix_mut().copy_from(&dense.a);
    qp.ineq_upper_mut().copy_from(&dense.b);
    let mut solver = ClarabelSolver::new(ClarabelSettings {
        tolerance: 1e-12,
        max_iterations: 300,
    });
    let mut out = SolverOutput::new(&qp);
    solver.solve(&qp, &mut out);
    assert!(out.status.is_success(), "{:?}", out.status);
    assert_eq!(out.x.len(), n);
    out.x
}

/// A standing-on-one-foot plan with a pushed DCM: the MPC must put the ZMP on the foot's edge.
/// With `transfer = false` the plan stays on the foot for the whole horizon.
fn pushed_problem(
    controller: &mut DcmPredictiveController,
    push: Vector2<f64>,
    transfer: bool,
) -> DcmPredictiveOutput {
    let foot = SupportPolygon::rectangle(-0.05, 0.07, -0.03, 0.03).unwrap();
    let both = SupportPolygon::rectangle(-0.05, 0.07, -0.03, 0.19).unwrap();
    let mut horizon = DcmHorizon::with_capacity(controller.horizon_samples());
    let center = Vector2::new(0.01, 0.0);
    for k in 0..controller.horizon_samples() {
        // single support for 0.3 s, then double support with the ZMP moving to the middle
        let (support, zmp) = if k < 30 || !transfer {
            (foot, center)
        } else {
            let s = ((k - 30) as f64 / 20.0).min(1.0);
            (both, center + Vector2::new(0.0, 0.08 * s))
        };
        horizon
            .push(HorizonSample {
                dcm_position: zmp,
                zmp,
                support,
            })
            .unwrap();
    }
    controller
        .step(OMEGA, center + push, &horizon, &foot)
        .unwrap()
}

#[test]
fn solutions_satisfy_constraints_and_kkt_and_agree_with_clarabel() {
    for (horizon, push, rate) in [
        (0.5, Vector2::new(0.05, 0.0), ZmpRateReference::Plan),
        (0.5, Vector2::new(-0.04, 0.02), ZmpRateReference::Zero),
        (0.3, Vector2::new(0.0, -0.025), ZmpRateReference::Plan),
        (2.0, Vector2::new(0.055, 0.0), ZmpRateReference::Plan),
    ] {
        for solver in [
            MpcSolverKind::BandedInteriorPoint,
            MpcSolverKind::Clarabel,
            MpcSolverKind::StrideQp,
        ] {
            let config = DcmPredictiveConfig {
                horizon,
                zmp_rate_reference: rate,
                solver,
                ..Default::default()
            };
            let mut controller = DcmPredictiveController::new(config, 0.01).unwrap();
            let out = pushed_problem(&mut controller, push, true);
            assert_eq!(
                out.diagnostics.status,
                MpcStatus::Solved,
                "{horizon} {push:?} {solver:?}"
            );
            assert!(out.diagnostics.active_constraints > 0);
            let view = controller.last_problem().unwrap();
            let dense = dense_problem(&view);
            if solver == MpcSolverKind::BandedInteriorPoint {
                check_kkt(&view, &dense, &format!("{horizon} {push:?} {solver:?}"));
            } else {
                // clarabel (reference backends) stops with complementarity ~1e-5 relative on weakly
                // active rows; its primal solution is checked for feasibility and against the dense
                // reference below.
                let slack = &dense.b - &dense.a * solution_vector(&view);
                assert!(slack.min() >= -1e-6);
            }
            let w = solution_vector(&view);
            let reference = solve_dense_with_clarabel(&dense);
            let difference = (&w - &reference).amax();
            assert!(
                difference <= 1e-6,
                "{horizon} {push:?} {solver:?}: differs from dense clarabel by {difference}"
            );
            // the predicted DCM follows the prediction model from the measured DCM
            let d = LipmDiscretization::new(view.omega, view.period).unwrap();
            for k in 0..view.zmp.len() {
                let next = d.step_dcm(view.dcm[k], view.zmp[k]);
                assert!((next - view.dcm[k + 1]).norm() <= 1e-9 * (1.0 + next.norm()));
            }
            assert!(view.supports[0].contains(out.desired_zmp, 1e-12));
        }
    }
}

#[test]
fn unconstrained_solution_matches_the_closed_form() {
    // A small push: no constraint is active, the optimum is −H⁻¹g of the dense condensed problem.
    for rate in [ZmpRateReference::Plan, ZmpRateReference::Zero] {
        let config = DcmPredictiveConfig {
            horizon: 0.5,
            zmp_rate_reference: rate,
            ..Default::default()
        };
        let mut controller = DcmPredictiveController::new(config, 0.01).unwrap();
        let out = pushed_problem(&mut controller, Vector2::new(0.004, -0.003), false);
        assert_eq!(out.diagnostics.status, MpcStatus::Unconstrained);
        let view = controller.last_problem().unwrap();
        let dense = dense_problem(&view);
        let closed_form = -dense.h.clone().cholesky().unwrap().solve(&dense.g);
        let w = solution_vector(&view);
        assert!(
            (&w - &closed_form).amax() <= 1e-8,
            "{}",
            (&w - &closed_form).amax()
        );
        check_kkt(&view, &dense, "unconstrained");
    }
}

#[test]
fn plan_is_a_fixed_point_and_constant_reference_gives_constant_zmp() {
    // 17.4 #24: a constant DCM reference inside the support yields x_ZMP ≡ ξ_ref.
    let foot = SupportPolygon::rectangle(-0.05, 0.07, -0.03, 0.03).unwrap();
    let mut controller =
        DcmPredictiveController::new(DcmPredictiveConfig::default(), 0.01).unwrap();
    let mut horizon = DcmHorizon::with_capacity(controller.horizon_samples());
    let reference = Vector2::new(0.02, -0.01);
    for _ in 0..controller.horizon_samples() {
        horizon
            .push(HorizonSample {
                dcm_position: reference,
                zmp: reference,
                support: foot,
            })
            .unwrap();
    }
    for config_rate in [ZmpRateReference::Plan, ZmpRateReference::Zero] {
        let mut c = DcmPredictiveController::new(
            DcmPredictiveConfig {
                zmp_rate_reference: config_rate,
                ..Default::default()
            },
            0.01,
        )
        .unwrap();
        let out = c.step(OMEGA, reference, &horizon, &foot).unwrap();
        assert!((out.desired_zmp - reference).norm() < 1e-12);
        assert!(c
            .last_problem()
            .unwrap()
            .zmp
            .iter()
            .all(|z| (z - reference).norm() < 1e-10));
    }
    let out = controller.step(OMEGA, reference, &horizon, &foot).unwrap();
    assert_eq!(out.diagnostics.status, MpcStatus::Unconstrained);
    assert!(out.diagnostics.cost < 1e-18);
}

mod containment {
    use super::*;
    use proptest::prelude::*;

    fn arbitrary_polygon() -> impl Strategy<Value = SupportPolygon> {
        prop::collection::vec((-0.2f64..0.2, -0.2f64..0.2), 3..10).prop_filter_map(
            "degenerate",
            |pts| {
                let pts: Vec<Vector2<f64>> =
                    pts.into_iter().map(|(x, y)| Vector2::new(x, y)).collect();
                SupportPolygon::convex_hull(&pts)
                    .ok()
                    .filter(|p| p.area() > 1e-4)
            },
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        #[test]
        fn desired_zmp_never_leaves_the_support_polygon(
            polygon in arbitrary_polygon(),
            ex in -0.5f64..0.5, ey in -0.5f64..0.5,
            rate in prop::bool::ANY,
        ) {
            let config = DcmPredictiveConfig {
                horizon: 0.5,
                zmp_rate_reference: if rate { ZmpRateReference::Plan } else { ZmpRateReference::Zero },
                ..Default::default()
            };
            let mut controller = DcmPredictiveController::new(config, 0.01).unwrap();
            let reference = polygon.vertex_mean();
            let mut horizon = DcmHorizon::with_capacity(controller.horizon_samples());
            for _ in 0..controller.horizon_samples() {
                horizon.push(HorizonSample { dcm_position: reference, zmp: reference, support: polygon }).unwrap();
            }
            let out = controller.step(OMEGA, reference + Vector2::new(ex, ey), &horizon, &polygon).unwrap();
            prop_assert!(polygon.contains(out.desired_zmp, 1e-12));
            prop_assert!(out.desired_zmp.iter().all(|v| v.is_finite()));
            // the QP only falls back once the DCM is outside the polygon
            if polygon.contains(reference + Vector2::new(ex, ey), 0.0) {
                prop_assert!(!out.diagnostics.fallback);
            }
        }
    }
}

/// Closed-loop LIPM walk (the default test plan) with two DCM pushes large enough to activate the
/// polygon constraints for many ticks; returns, per tick, the measured DCM fed to the controllers.
/// The simulation is driven by `driver`'s desired ZMP; `follower` gets the same inputs.
fn pushed_walk(
    driver: &mut DcmPredictiveController,
    follower: &mut DcmPredictiveController,
    mut check: impl FnMut(
        usize,
        &DcmPredictiveOutput,
        &DcmPredictiveOutput,
        &[Vector2<f64>],
        &[Vector2<f64>],
    ),
) {
    let plan = Plan::default_walk();
    let d = LipmDiscretization::new(plan.omega, plan.period).unwrap();
    let samples = driver.horizon_samples();
    let mut horizon = DcmHorizon::with_capacity(samples);
    let (mut x, mut v) = (plan.com[0], plan.com_velocity[0]);
    for k in 0..plan.len() {
        fill_horizon(&mut horizon, &plan, k, samples);
        if k == 150 || k == 420 {
            v += Vector2::new(0.06, -0.03) * plan.omega;
        }
        let dcm = dcm_from_com(x, v, plan.omega);
        let a = driver
            .step(plan.omega, dcm, &horizon, &plan.support[k])
            .unwrap();
        let driver_zmp = driver.last_problem().unwrap().zmp.to_vec();
        let b = follower
            .step(plan.omega, dcm, &horizon, &plan.support[k])
            .unwrap();
        check(k, &a, &b, &driver_zmp, follower.last_problem().unwrap().zmp);
        (x, v) = d.step_com(x, v, a.desired_zmp);
    }
}

#[test]
fn warm_start_reaches_the_cold_optimum_over_a_pushed_walk() {
    let mut cold = DcmPredictiveController::new(DcmPredictiveConfig::default(), 0.01).unwrap();
    let mut warm = DcmPredictiveController::new(
        DcmPredictiveConfig {
            warm_start: true,
            ..Default::default()
        },
        0.01,
    )
    .unwrap();
    let (mut constrained, mut cold_iterations, mut warm_iterations) = (0, 0, 0);
    pushed_walk(&mut cold, &mut warm, |k, a, b, cold_zmp, warm_zmp| {
        assert_eq!(a.diagnostics.status, b.diagnostics.status, "tick {k}");
        assert!(matches!(
            a.diagnostics.status,
            MpcStatus::Unconstrained | MpcStatus::Solved
        ));
        if a.diagnostics.status == MpcStatus::Solved {
            constrained += 1;
            assert!(a.diagnostics.iterations > 0 && b.diagnostics.iterations > 0);
            cold_iterations += a.diagnostics.iterations;
            warm_iterations += b.diagnostics.iterations;
        } else {
            assert_eq!(a.diagnostics.iterations, 0);
            assert_eq!(b.diagnostics.iterations, 0);
        }
        // the whole optimal ZMP sequence, not only its first sample
        let worst = warm_zmp
            .iter()
            .zip(cold_zmp)
            .map(|(p, q)| (p - q).norm())
            .fold(0.0, f64::max);
        assert!(worst <= 1e-8, "tick {k}: warm and cold differ by {worst}");
        assert!((a.desired_zmp - b.desired_zmp).norm() <= 1e-8, "tick {k}");
    });
    assert!(
        constrained >= 50,
        "only {constrained} constrained ticks: the pushes did not exercise the solver"
    );
    // measured: about 1260 cold and 510 warm iterations on this walk
    assert!(
        warm_iterations < cold_iterations,
        "warm {warm_iterations} vs cold {cold_iterations} iterations"
    );
}

#[test]
fn reused_hessian_factor_gives_the_fresh_solution_when_omega_changes() {
    // One controller sees ω change between ticks (its P and factor are rebuilt, then reused); each
    // tick is compared with a controller built for that tick alone.
    let mut reused = DcmPredictiveController::new(DcmPredictiveConfig::default(), 0.01).unwrap();
    for (tick, omega) in [OMEGA, OMEGA, 1.1 * OMEGA, 1.1 * OMEGA, OMEGA]
        .into_iter()
        .enumerate()
    {
        let mut fresh = DcmPredictiveController::new(DcmPredictiveConfig::default(), 0.01).unwrap();
        let foot = SupportPolygon::rectangle(-0.05, 0.07, -0.03, 0.03).unwrap();
        let mut horizon = DcmHorizon::with_capacity(reused.horizon_samples());
        for _ in 0..reused.horizon_samples() {
            horizon
                .push(HorizonSample {
                    dcm_position: Vector2::new(0.01, 0.0),
                    zmp: Vector2::new(0.01, 0.0),
                    support: foot,
                })
                .unwrap();
        }
        // alternate an unconstrained and a constrained tick
        let dcm = Vector2::new(0.01 + if tick % 2 == 0 { 0.004 } else { 0.05 }, 0.0);
        reused.reset();
        let a = reused.step(omega, dcm, &horizon, &foot).unwrap();
        let b = fresh.step(omega, dcm, &horizon, &foot).unwrap();
        assert_eq!(a.diagnostics.status, b.diagnostics.status, "tick {tick}");
        let (p, q) = (
            reused.last_problem().unwrap(),
            fresh.last_problem().unwrap(),
        );
        let worst = p
            .zmp
            .iter()
            .zip(q.zmp)
            .map(|(u, v)| (u - v).norm())
            .fold(0.0, f64::max);
        assert!(worst <= 1e-12, "tick {tick}: {worst}");
    }
}
