//! The step-adjustment QP against closed forms of the capture-point dynamics [Khadiv 2020], its bounds,
//! the nominal case, the KKT conditions and a second backend (clarabel through stride-qp).
use nalgebra::{Matrix2, Rotation2, Vector2};
use proptest::prelude::*;
use stride_qp::{check_kkt, ClarabelSolver, QpSolver, SolverOutput};
use stride_simplified::*;

/// ω of the bundled humanoid (CoM height 0.54 m, g = 9.81 m/s²).
const OMEGA: f64 = 4.262_237_284_282_101;
const T_NOM: f64 = 1.0;
const T_NOW: f64 = 0.5;

/// A single-support instant consistent with a plan: stance foot at `p_s` with yaw `yaw`, CoP 1 cm ahead of
/// the sole origin, nominal step 0.1 m forward and 0.2 m outward (inside the default box with a margin), planned DCM `xi_p` now, and the
/// planned offset `b_n = ξ_plan(T_n) − u_n` from the LIPM closed form with the CoP held.
struct Case {
    input: StepAdjustmentInput,
    planned_dcm: Vector2<f64>,
}

fn case(stance: Foot, yaw: f64) -> Case {
    let rot = Rotation2::new(yaw);
    let side = stance.other().side();
    let p_s = Vector2::new(0.3, -0.075 * side);
    let cop = p_s + rot * Vector2::new(0.01, 0.0);
    let u_n = p_s + rot * Vector2::new(0.1, 0.2 * side);
    let planned_dcm = cop + rot * Vector2::new(0.02, 0.02 * side);
    let xi_end = cop + (planned_dcm - cop) * (OMEGA * (T_NOM - T_NOW)).exp();
    Case {
        input: StepAdjustmentInput {
            dcm: planned_dcm,
            omega: OMEGA,
            stance,
            stance_position: p_s,
            stance_yaw: yaw,
            stance_cop: cop,
            nominal_step: u_n,
            nominal_offset: xi_end - u_n,
            time_since_touchdown: T_NOW,
            nominal_duration: T_NOM,
        },
        planned_dcm,
    }
}

/// The equality-constrained minimiser when no bound is active: with `A = [I, −k, I, αI]` over
/// `(u, τ, b, δr)` (`α = e^{ω(T_n − t)} − 1`, the CoP lever), weights
/// `W = diag(w_u I, w_τ/τ_n², w_b I, w_r I)` and the residual `D = Rᵀ Δ e^{ω(T_n − t)}` of the dynamics at
/// the nominal point, `δ = W⁻¹Aᵀ(AW⁻¹Aᵀ)⁻¹D`, so `δu = M⁻¹D / w_u`, `δτ = −kᵀM⁻¹D (τ_n²/w_τ)` with
/// `M = (1/w_u + 1/w_b + α²/w_r) I + k kᵀ τ_n²/w_τ` (stance frame). `ankle = false`: the CoP box is
/// zero, `δr` is fixed and the `α²/w_r` term drops.
fn closed_form(
    c: &StepAdjustmentConfig,
    i: &StepAdjustmentInput,
    ankle: bool,
) -> (Vector2<f64>, f64, Vector2<f64>) {
    let rot = Rotation2::new(i.stance_yaw);
    let delta = i.dcm - planned_of(i);
    let d = rot.inverse() * delta * (OMEGA * (T_NOM - T_NOW)).exp();
    let k = rot.inverse() * (i.dcm - i.stance_cop) * (-OMEGA * T_NOW).exp();
    let tau_n = (OMEGA * T_NOM).exp();
    let wt = c.timing_weight / (tau_n * tau_n);
    let alpha = (OMEGA * (T_NOM - T_NOW)).exp() - 1.0;
    let lever = if ankle {
        alpha * alpha / c.cop_weight
    } else {
        0.0
    };
    let m = Matrix2::identity() * (1.0 / c.step_weight + 1.0 / c.offset_weight + lever)
        + k * k.transpose() / wt;
    let md = m.try_inverse().unwrap() * d;
    let du = rot * md / c.step_weight;
    let dtau = -k.dot(&md) / wt;
    let duration = (tau_n + dtau).ln() / OMEGA;
    let dr = rot * md * alpha / c.cop_weight;
    (du, duration, dr)
}

/// No ankle: the CoP box is zero, the step absorbs the DCM error alone (the capture-point case).
fn no_ankle() -> StepAdjustmentConfig {
    StepAdjustmentConfig {
        cop_x: 0.0,
        cop_y: 0.0,
        ..Default::default()
    }
}

/// The planned DCM now, recovered from the nominal offset (the inverse of `case`).
fn planned_of(i: &StepAdjustmentInput) -> Vector2<f64> {
    let xi_end = i.nominal_step + i.nominal_offset;
    i.stance_cop + (xi_end - i.stance_cop) * (-OMEGA * (T_NOM - T_NOW)).exp()
}

#[test]
fn nominal_dcm_gives_the_nominal_step_and_timing() {
    let config = StepAdjustmentConfig::default();
    for stance in [Foot::Left, Foot::Right] {
        for yaw in [0.0, 0.4, -2.5] {
            let c = case(stance, yaw);
            assert!((planned_of(&c.input) - c.planned_dcm).norm() < 1e-12);
            let mut adj = StepAdjuster::new(&config).unwrap();
            let r = *adj.solve(&c.input).unwrap();
            assert_eq!(r.diagnostics.status, StepAdjustmentStatus::Solved);
            assert!(r.displacement.norm() < 1e-9, "{stance:?} {yaw}: {r:?}");
            assert!((r.duration - T_NOM).abs() < 1e-9);
            assert!((r.remaining - (T_NOM - T_NOW)).abs() < 1e-9);
            assert!((r.diagnostics.offset - c.input.nominal_offset).norm() < 1e-9);
            assert!(!r.diagnostics.bound_active);
        }
    }
}

#[test]
fn dcm_offset_moves_the_step_as_the_closed_form_says() {
    let config = no_ankle();
    for stance in [Foot::Left, Foot::Right] {
        for yaw in [0.0, 0.4] {
            // x and y of the world (y outward: inward, the no-crossing bound would be active), and the
            // outward direction of the stance frame
            let outward = Rotation2::new(yaw) * Vector2::new(0.0, stance.other().side());
            let world_y = Vector2::new(0.0, 0.01 * stance.other().side());
            for delta in [Vector2::new(0.01, 0.0), world_y, outward * 0.01] {
                let mut c = case(stance, yaw);
                c.input.dcm += delta;
                let mut adj = StepAdjuster::new(&config).unwrap();
                let r = *adj.solve(&c.input).unwrap();
                let (du, duration, _) = closed_form(&config, &c.input, false);
                assert!(!r.diagnostics.bound_active, "{stance:?} {yaw} {delta:?}");
                assert!(
                    (r.displacement - du).norm() < 1e-9,
                    "{stance:?} {yaw} {delta:?}: {:?} vs {du:?}",
                    r.displacement
                );
                assert!((r.duration - duration).abs() < 1e-9);
                // the step moves by nearly the amplified offset Δ e^{ω(T−t)} (the rest goes to b and τ)
                let amplified = delta * (OMEGA * (T_NOM - T_NOW)).exp();
                assert!((r.displacement - amplified).norm() < 0.2 * amplified.norm());
            }
        }
    }
}

#[test]
fn with_fixed_timing_the_step_takes_the_weighted_share_of_the_amplified_offset() {
    // T_min = T_max = T_n: τ is fixed and δu = Δ e^{ω(T_n − t)} w_b/(w_u + w_b) exactly.
    let config = StepAdjustmentConfig {
        step_duration_min: T_NOM - 1e-15,
        step_duration_max: T_NOM,
        ..no_ankle()
    };
    for stance in [Foot::Left, Foot::Right] {
        for delta in [
            Vector2::new(0.01, 0.0),
            Vector2::new(0.0, 0.01 * stance.other().side()),
        ] {
            let mut c = case(stance, 0.0);
            c.input.dcm += delta;
            let mut adj = StepAdjuster::new(&config).unwrap();
            let r = *adj.solve(&c.input).unwrap();
            let share = config.offset_weight / (config.step_weight + config.offset_weight);
            let expected = delta * (OMEGA * (T_NOM - T_NOW)).exp() * share;
            assert!(
                (r.displacement - expected).norm() < 1e-9,
                "{r:?} vs {expected:?}"
            );
            assert!((r.duration - T_NOM).abs() < 1e-9);
        }
    }
}

#[test]
fn the_ankle_takes_small_errors_first_as_the_closed_form_says() {
    // With the CoP box free (|δr| below its bounds), the CoP lever α ≈ 7.4 takes α²/(α² + w_r/w_u) ≈ 98 %
    // of the error: the step moves by about 2 % of the capture-point shift.
    let config = StepAdjustmentConfig::default();
    for stance in [Foot::Left, Foot::Right] {
        for yaw in [0.0, 0.4] {
            let outward = Rotation2::new(yaw) * Vector2::new(0.0, stance.other().side());
            for delta in [Vector2::new(0.004, 0.0), outward * 0.0015] {
                let mut c = case(stance, yaw);
                c.input.dcm += delta;
                let r = *StepAdjuster::new(&config).unwrap().solve(&c.input).unwrap();
                let (du, duration, dr) = closed_form(&config, &c.input, true);
                assert!((r.displacement - du).norm() < 1e-9, "{r:?} vs {du:?}");
                assert!((r.duration - duration).abs() < 1e-9);
                assert!((r.diagnostics.cop_offset - dr).norm() < 1e-9);
                let amplified = delta * (OMEGA * (T_NOM - T_NOW)).exp();
                assert!(r.displacement.norm() < 0.05 * amplified.norm());
            }
        }
    }
}

#[test]
fn large_pushes_respect_the_box_and_the_timing_bounds() {
    let config = StepAdjustmentConfig::default();
    let tol = 1e-9;
    for stance in [Foot::Left, Foot::Right] {
        for yaw in [0.0, 0.7] {
            let rot = Rotation2::new(yaw);
            for dir in [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0), (0.7, 0.7)] {
                for t in [0.36, 0.6, 0.9, 1.1] {
                    let mut c = case(stance, yaw);
                    c.input.time_since_touchdown = t;
                    c.input.dcm += rot * Vector2::new(dir.0, dir.1) * 0.15;
                    let mut adj = StepAdjuster::new(&config).unwrap();
                    let r = *adj.solve(&c.input).unwrap();
                    assert_eq!(r.diagnostics.status, StepAdjustmentStatus::Solved);
                    let u = rot.inverse() * (r.touchdown - c.input.stance_position);
                    let out = u.y * stance.other().side();
                    assert!(u.x <= config.forward_max + tol && u.x >= -config.backward_max - tol);
                    assert!(out >= config.lateral_min - tol && out <= config.lateral_max + tol);
                    let t_lo = config.step_duration_min.max(t + config.min_remaining_time);
                    assert!(r.duration >= t_lo - tol, "{t}: {r:?}");
                    assert!(r.duration <= config.step_duration_max.max(t_lo) + tol);
                    assert!(r.remaining >= config.min_remaining_time - tol);
                    assert!(r.diagnostics.bound_active, "{stance:?} {dir:?} {t}: {r:?}");
                    let kkt = check_kkt(adj.qp(), adj.solver_output());
                    assert!(kkt.is_satisfied(1e-9), "{kkt:?}");
                }
            }
        }
    }
}

#[test]
fn an_inward_push_stops_at_the_no_crossing_distance() {
    let config = StepAdjustmentConfig::default();
    for stance in [Foot::Left, Foot::Right] {
        let mut c = case(stance, 0.0);
        c.input.dcm.y -= 0.08 * stance.other().side();
        let r = *StepAdjuster::new(&config).unwrap().solve(&c.input).unwrap();
        let out = (r.touchdown.y - c.input.stance_position.y) * stance.other().side();
        assert!((out - config.lateral_min).abs() < 1e-9, "{r:?}");
        // the offset box then gives: the slack takes what the step cannot
        assert!(r.diagnostics.offset_slack.y > 0.0);
    }
}

#[test]
fn an_inward_push_past_the_no_crossing_bound_crosses_over_when_enabled() {
    let config = StepAdjustmentConfig {
        crossover_min: 0.10,
        crossover_max: 0.25,
        ..Default::default()
    };
    let tol = 1e-9;
    for stance in [Foot::Left, Foot::Right] {
        let side = stance.other().side();
        for (push, t) in [(0.08, 0.5), (0.15, 0.6), (0.3, 0.5)] {
            let mut c = case(stance, 0.0);
            c.input.dcm.y -= push * side;
            c.input.time_since_touchdown = t;
            let mut off = StepAdjuster::new(&StepAdjustmentConfig::default()).unwrap();
            let main = *off.solve(&c.input).unwrap();
            let main_cost = off.solver_output().objective;
            let mut adj = StepAdjuster::new(&config).unwrap();
            let r = *adj.solve(&c.input).unwrap();
            assert_eq!(r.diagnostics.status, StepAdjustmentStatus::Solved);
            assert!(r.diagnostics.crossover, "{stance:?} {push}: {r:?}");
            // past the stance foot, inside the crossover interval, cheaper than the bound's solution
            let past = -(r.touchdown.y - c.input.stance_position.y) * side;
            assert!(
                past >= config.crossover_min - tol && past <= config.crossover_max + tol,
                "{past}"
            );
            assert!(adj.solver_output().objective < main_cost);
            // the crossover's QP is a QP: its KKT conditions hold at the solution
            let kkt = check_kkt(adj.qp(), adj.solver_output());
            assert!(kkt.is_satisfied(1e-9), "{kkt:?}");
            // without the crossover the same push stops at the bound
            let out = (main.touchdown.y - c.input.stance_position.y) * side;
            assert!((out - config.lateral_min).abs() < 1e-9 && !main.diagnostics.crossover);
            // the step stays crossed for the rest of its solves, even with the DCM back on the plan;
            // a fresh adjuster, or the next step (another stance position), does not cross
            let mut back = c.input;
            back.dcm = c.planned_dcm;
            assert!(adj.solve(&back).unwrap().diagnostics.crossover);
            let fresh = *StepAdjuster::new(&config).unwrap().solve(&back).unwrap();
            assert!(!fresh.diagnostics.crossover);
            back.stance_position.x += 0.2;
            back.stance_cop.x += 0.2;
            back.nominal_step.x += 0.2;
            assert!(!adj.solve(&back).unwrap().diagnostics.crossover);
        }
        // a push that the outward region absorbs (the bound inactive) is solved as without the crossover
        for (dx, dy) in [(0.0, 0.0), (0.05, 0.0), (0.0, 0.06 * side)] {
            let mut c = case(stance, 0.0);
            c.input.dcm += Vector2::new(dx, dy);
            let with = *StepAdjuster::new(&config).unwrap().solve(&c.input).unwrap();
            let without = *StepAdjuster::new(&StepAdjustmentConfig::default())
                .unwrap()
                .solve(&c.input)
                .unwrap();
            assert_eq!(with, without);
        }
    }
    // an empty crossover interval is refused
    let bad = StepAdjustmentConfig {
        crossover_min: 0.2,
        crossover_max: 0.15,
        ..Default::default()
    };
    assert!(matches!(
        StepAdjuster::new(&bad),
        Err(SimplifiedError::InvalidParameter {
            name: "step_adjustment.crossover_max",
            ..
        })
    ));
}

#[test]
fn kkt_holds_and_clarabel_agrees() {
    let config = StepAdjustmentConfig::default();
    let mut clarabel = ClarabelSolver::new(Default::default());
    for stance in [Foot::Left, Foot::Right] {
        for (dx, dy, t) in [
            (0.0, 0.0, 0.5),
            (0.01, -0.02, 0.4),
            (0.1, 0.05, 0.7),
            (-0.2, 0.1, 0.9),
            (0.05, -0.3, 1.1),
        ] {
            let mut c = case(stance, 0.3);
            c.input.dcm += Vector2::new(dx, dy);
            c.input.time_since_touchdown = t;
            let mut adj = StepAdjuster::new(&config).unwrap();
            adj.solve(&c.input).unwrap();
            let kkt = check_kkt(adj.qp(), adj.solver_output());
            assert!(kkt.is_satisfied(1e-9), "{kkt:?}");
            let mut out = SolverOutput::new(adj.qp());
            clarabel.solve(adj.qp(), &mut out);
            assert!(out.status.is_success());
            let x = &adj.solver_output().x;
            // The step, τ, the offset and the CoP offset to 1e-6 (relative). The slacks sit on their bound `s ≥ 0`
            // with a zero multiplier whenever the offset box is not violated (a degenerate active bound),
            // which an interior-point method approaches only as √μ: clarabel stops ~3e-6 m above it.
            const SLACKS: [usize; 2] = [5, 6];
            for j in (0..STEP_ADJUSTMENT_VARIABLES).filter(|j| !SLACKS.contains(j)) {
                let scale = 1.0 + x[j].abs();
                assert!(
                    (out.x[j] - x[j]).abs() < 1e-6 * scale,
                    "variable {j}: clarabel {} vs active set {}",
                    out.x[j],
                    x[j]
                );
            }
            for j in SLACKS {
                assert!(
                    (out.x[j] - x[j]).abs() < 1e-5,
                    "slack {j}: {} vs {}",
                    out.x[j],
                    x[j]
                );
            }
        }
    }
}

#[test]
fn bad_inputs_and_configs_are_named() {
    let mut adj = StepAdjuster::new(&StepAdjustmentConfig::default()).unwrap();
    let good = case(Foot::Left, 0.0).input;
    let mut i = good;
    i.dcm.x = f64::NAN;
    assert_eq!(
        adj.solve(&i).unwrap_err(),
        SimplifiedError::NonFiniteInput { name: "dcm" }
    );
    let mut i = good;
    i.omega = 0.0;
    assert!(matches!(
        adj.solve(&i),
        Err(SimplifiedError::InvalidParameter { name: "omega", .. })
    ));
    let mut i = good;
    i.time_since_touchdown = -0.1;
    assert!(matches!(
        adj.solve(&i),
        Err(SimplifiedError::InvalidParameter {
            name: "time_since_touchdown",
            ..
        })
    ));
    for (config, name) in [
        (
            StepAdjustmentConfig {
                lateral_min: 0.4,
                ..Default::default()
            },
            "step_adjustment.lateral_max",
        ),
        (
            StepAdjustmentConfig {
                step_duration_min: 1.5,
                ..Default::default()
            },
            "step_adjustment.step_duration_max",
        ),
        (
            StepAdjustmentConfig {
                offset_weight: -1.0,
                ..Default::default()
            },
            "step_adjustment.offset_weight",
        ),
        (
            StepAdjustmentConfig {
                forward_max: f64::NAN,
                ..Default::default()
            },
            "step_adjustment.forward_max",
        ),
    ] {
        match StepAdjuster::new(&config) {
            Err(SimplifiedError::InvalidParameter { name: n, .. }) => assert_eq!(n, name),
            other => panic!("{name}: {:?}", other.err()),
        }
    }
    let parsed: std::result::Result<SimplifiedConfig, _> =
        toml::from_str("[step_adjustment]\nenabled = true\nforward = 0.1\n");
    assert!(parsed.unwrap_err().to_string().contains("forward"));
    let parsed: SimplifiedConfig =
        toml::from_str("[step_adjustment]\nenabled = true\nlateral_max = 0.25\n").unwrap();
    assert!(parsed.step_adjustment.enabled);
    assert_eq!(parsed.step_adjustment.lateral_max, 0.25);
    assert!(!SimplifiedConfig::default().step_adjustment.enabled);
}

proptest! {
    /// Any finite problem gives a finite step inside the box and the duration bounds, or the nominal step
    /// when the QP fails.
    #[test]
    fn every_finite_problem_gives_a_finite_admissible_step(
        dx in -2.0..2.0f64, dy in -2.0..2.0f64, yaw in -3.2..3.2f64, t in 0.0..3.0f64,
        t_nom in 0.3..2.0f64, left in any::<bool>(),
    ) {
        let config = StepAdjustmentConfig::default();
        let stance = if left { Foot::Left } else { Foot::Right };
        let mut c = case(stance, yaw);
        c.input.dcm += Vector2::new(dx, dy);
        c.input.time_since_touchdown = t;
        c.input.nominal_duration = t_nom;
        let mut adj = StepAdjuster::new(&config).unwrap();
        let r = *adj.solve(&c.input).unwrap();
        prop_assert!(r.touchdown.iter().all(|v| v.is_finite()) && r.duration.is_finite());
        match r.diagnostics.status {
            StepAdjustmentStatus::Solved => {
                let u = Rotation2::new(yaw).inverse() * (r.touchdown - c.input.stance_position);
                let u_n = Rotation2::new(yaw).inverse() * (c.input.nominal_step - c.input.stance_position);
                prop_assert!(u.x <= config.forward_max.max(u_n.x) + 1e-9);
                prop_assert!(u.x >= (-config.backward_max).min(u_n.x) - 1e-9);
                prop_assert!(r.remaining >= config.min_remaining_time - 1e-9);
            }
            _ => {
                prop_assert_eq!(r.touchdown, c.input.nominal_step);
                prop_assert!((r.duration - t_nom).abs() < 1e-12);
            }
        }
    }
}
