//! ZMP-CoM controller: closed-loop convergence at the rate of the analytic characteristic roots,
//! divergence when the gain bound is violated, minimum-jerk gain scheduling.
mod common;

use common::OMEGA;
use nalgebra::{Complex, Vector2};
use stride_simplified::*;

/// Closed loop with ideal CoM-velocity tracking: ẋ = ẋ*, and the measured ZMP is the LIPM ZMP
/// p = x − ẍ/ω² with ẍ the backward difference of the commanded velocity. The loop is implicit
/// (ẋ* depends on p which depends on ẋ*); it is solved exactly using the law's affine dependence on p,
/// evaluated with the controller itself. Reference: standing at the origin.
fn simulate_law(gains: ZmpComGains, e0: f64, dt: f64, seconds: f64) -> Vec<f64> {
    let law = |zmp: f64, x: f64| {
        zmp_com_law(
            &gains,
            Vector2::zeros(),
            Vector2::zeros(),
            Vector2::new(zmp, 0.0),
            Vector2::zeros(),
            Vector2::new(x, 0.0),
        )
        .x
    };
    let mut x = -e0; // e = x_ref − x
    let mut v_prev = 0.0;
    let mut errors = Vec::new();
    let c = 1.0 / (dt * OMEGA * OMEGA);
    for _ in 0..(seconds / dt).round() as usize {
        errors.push(-x);
        let v0 = law(0.0, x);
        let j = law(1.0, x) - v0;
        // v = v0 + j (x − c (v − v_prev))
        let v = (v0 + j * (x + c * v_prev)) / (1.0 + j * c);
        let zmp = x - c * (v - v_prev);
        assert!((law(zmp, x) - v).abs() < 1e-9);
        x += v * dt;
        v_prev = v;
    }
    errors
}

/// Analytic solution of (K_ZMP/ω²) ë + ė + (K_CoM − K_ZMP) e = 0, e(0) = e0, ė(0) = 0.
fn analytic(gains: ZmpComGains, e0: f64, t: f64) -> f64 {
    let a = gains.k_zmp / (OMEGA * OMEGA);
    let c = gains.k_com - gains.k_zmp;
    let disc = Complex::new(1.0 - 4.0 * a * c, 0.0).sqrt();
    let s1 = (-1.0 + disc) / (2.0 * a);
    let s2 = (-1.0 - disc) / (2.0 * a);
    // c1 + c2 = e0, s1 c1 + s2 c2 = 0
    let c1 = -s2 * e0 / (s1 - s2);
    let c2 = s1 * e0 / (s1 - s2);
    (c1 * (s1 * t).exp() + c2 * (s2 * t).exp()).re
}

fn slowest_root(gains: ZmpComGains) -> f64 {
    let a = gains.k_zmp / (OMEGA * OMEGA);
    let c = gains.k_com - gains.k_zmp;
    let disc = 1.0 - 4.0 * a * c;
    if disc >= 0.0 {
        (-1.0 + disc.sqrt()) / (2.0 * a)
    } else {
        -1.0 / (2.0 * a)
    }
}

#[test]
fn converges_with_the_predicted_dynamics() {
    let dt = 1e-4;
    let e0 = 0.02;
    // repo pairs (K_CoM, K_ZMP) = (10, 3), (6, 1.2), (5, 2.5), (4, 1), and an overdamped pair.
    for (k_com, k_zmp) in [(10.0, 3.0), (6.0, 1.2), (5.0, 2.5), (4.0, 1.0), (2.0, 0.2)] {
        let gains = ZmpComGains { k_zmp, k_com };
        gains.validate("test").unwrap();
        assert!(slowest_root(gains) < 0.0);
        let errors = simulate_law(gains, e0, dt, 3.0);
        let mut worst: f64 = 0.0;
        for (k, e) in errors.iter().enumerate().step_by(50) {
            worst = worst.max((e - analytic(gains, e0, k as f64 * dt)).abs());
        }
        assert!(worst < 2e-3 * e0, "({k_com}, {k_zmp}): worst {worst}");
        let final_error = errors.last().unwrap().abs();
        assert!(
            final_error < e0 * (slowest_root(gains) * 2.5).exp() * 3.0,
            "({k_com}, {k_zmp})"
        );
    }
}

#[test]
fn violating_the_gain_bound_diverges() {
    let dt = 1e-4;
    let e0 = 0.001;
    // K_CoM < K_ZMP: a positive real root, e grows as predicted; the bound is sharp.
    for (k_com, k_zmp, seconds) in [(3.0, 4.0, 3.0), (3.9, 4.0, 20.0)] {
        let gains = ZmpComGains { k_zmp, k_com };
        assert!(gains.validate("test").is_err());
        let root = slowest_root(gains);
        assert!(root > 0.0);
        let errors = simulate_law(gains, e0, dt, seconds);
        let t = seconds - dt;
        let expected = analytic(gains, e0, t);
        assert!(
            errors.last().unwrap().abs() > 1.5 * e0,
            "({k_com}, {k_zmp})"
        );
        assert!(
            (errors.last().unwrap() - expected).abs() < 5e-3 * expected.abs(),
            "({k_com}, {k_zmp})"
        );
    }
    // Just inside the bound converges.
    let gains = ZmpComGains {
        k_zmp: 3.9,
        k_com: 4.0,
    };
    gains.validate("test").unwrap();
    let errors = simulate_law(gains, e0, dt, 30.0);
    assert!(errors.last().unwrap().abs() < 0.1 * e0);
    // A negative K_ZMP makes the leading coefficient negative: divergent too.
    let gains = ZmpComGains {
        k_zmp: -0.5,
        k_com: 5.0,
    };
    assert!(gains.validate("test").is_err());
}

#[test]
fn minimum_jerk_blend_has_zero_rate_at_both_ends() {
    assert_eq!(minimum_jerk_blend(0.0), 0.0);
    assert_eq!(minimum_jerk_blend(1.0), 1.0);
    assert_eq!(minimum_jerk_blend(-1.0), 0.0);
    assert_eq!(minimum_jerk_blend(2.0), 1.0);
    let h = 1e-5;
    for t in [0.0 + h, 1.0 - h] {
        let d = (minimum_jerk_blend(t + h) - minimum_jerk_blend(t - h)) / (2.0 * h);
        assert!(d.abs() < 1e-8);
    }
    // Monotone, symmetric, peak rate 1.875 at the middle.
    let d_mid = (minimum_jerk_blend(0.5 + h) - minimum_jerk_blend(0.5 - h)) / (2.0 * h);
    assert!((d_mid - 1.875).abs() < 1e-6);
    for i in 0..100 {
        let t = i as f64 / 100.0;
        assert!((minimum_jerk_blend(t) + minimum_jerk_blend(1.0 - t) - 1.0).abs() < 1e-14);
        assert!(minimum_jerk_blend(t + 0.01) >= minimum_jerk_blend(t));
    }
}

#[test]
fn gains_blend_smoothly_between_standing_and_walking() {
    let config = ZmpComConfig::default();
    let mut controller = ZmpComController::new(config).unwrap();
    let dt = 0.001;
    let z = Vector2::zeros();
    let step = |c: &mut ZmpComController, walking: bool| {
        c.step(walking, OMEGA, z, z, z, z, z, dt).unwrap()
    };
    let first = step(&mut controller, false);
    assert_eq!(first.gains, config.standing);
    let mut previous = first.gains;
    let max_rate = 1.875 / config.transition_time;
    let mut reached = false;
    for i in 0..200 {
        let out = step(&mut controller, true);
        let dz = (out.gains.k_zmp - previous.k_zmp).abs();
        let dc = (out.gains.k_com - previous.k_com).abs();
        assert!(
            dz <= max_rate * dt * (config.walking.k_zmp - config.standing.k_zmp).abs() + 1e-12,
            "tick {i}"
        );
        assert!(
            dc <= max_rate * dt * (config.walking.k_com - config.standing.k_com).abs() + 1e-12,
            "tick {i}"
        );
        assert!(out.gains.k_com > out.gains.k_zmp);
        previous = out.gains;
        if (i as f64) * dt >= config.transition_time {
            assert_eq!(out.gains, config.walking);
            reached = true;
        }
    }
    assert!(reached);
    // Switching back half-way through a blend starts from the current gains (no jump).
    step(&mut controller, false);
    for _ in 0..20 {
        step(&mut controller, false);
    }
    let mid = controller.current_gains();
    let out = step(&mut controller, true);
    assert!((out.gains.k_zmp - mid.k_zmp).abs() < 0.05);
}

#[test]
fn position_reference_integrates_the_velocity_correction() {
    let mut controller = ZmpComController::new(ZmpComConfig {
        transition_time: 0.0,
        ..Default::default()
    })
    .unwrap();
    let dt = 0.01;
    let planned_v = Vector2::new(0.1, 0.0);
    let mut planned_x = Vector2::zeros();
    let measured = Vector2::new(-0.01, 0.005);
    let mut integral = Vector2::zeros();
    for _ in 0..50 {
        let out = controller
            .step(
                true,
                OMEGA,
                Vector2::zeros(),
                Vector2::zeros(),
                planned_x,
                planned_v,
                measured,
                dt,
            )
            .unwrap();
        assert!((out.com_position - (planned_x + integral)).norm() < 1e-14);
        integral += (out.com_velocity - planned_v) * dt;
        planned_x += planned_v * dt;
    }
}
