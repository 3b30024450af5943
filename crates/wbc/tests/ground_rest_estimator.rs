//! The ground estimate with the rest height as a third parameter ([`GroundRestEstimator`], `[k; b; k δ]`)
//! on synthetic landings: Lemma 1's wrench [Romualdi 2022, eq. 8.1.7] of known `k`, `b` about a rest plane
//! `δ` above the one the regressor assumes, with Gaussian noise. With `δ` estimated, `k̂` and `b̂` come
//! within 10 % and `δ̂` within 10 % of `δ`; the two-parameter estimate [Romualdi 2022, eq. 8.2.17] on the same
//! data puts the rest plane's error into `b̂`. A touch-down resets the covariance and `δ̂`, not `k̂`, `b̂`.

mod common;

use common::soft::SOLE;
use nalgebra::{Matrix3, Rotation3, Vector3, Vector6};
use stride_sim::GaussianNoise;
use stride_wbc::{
    EstimatorSettings, GroundEstimator, GroundParameters, GroundRestEstimator, SoleState, WbcError,
};

const WRENCH_STD: [f64; 2] = [2.0, 0.2];
const TRUTH: GroundParameters = GroundParameters {
    stiffness: 2e6,
    damping: 1e4,
};
/// The true rest plane above the assumed one (the level plane through a corner already 0.5 mm deep), m.
const DELTA: f64 = 5e-4;
/// Samples of one landing: 1 s at the WBC's 500 Hz.
const SAMPLES: usize = 500;

/// The prior of the closed loop's scenario (`1e6, 1e4`, its own size as standard deviation).
fn settings() -> EstimatorSettings {
    EstimatorSettings {
        initial: GroundParameters {
            stiffness: 1e6,
            damping: 1e4,
        },
        initial_std: [1e6, 1e4],
        wrench_std: WRENCH_STD,
    }
}

/// The sole at time `t` (s) of a landing as the walk's: it sinks to 8.5 mm (340 N on `2e6`) over 0.15 s
/// (half a cosine), then sways ±1 mm at 2 Hz, pitching ±0.02 rad at 1.5 Hz and rolling ±0.01 rad at 2.5 Hz;
/// the assumed rest plane is `z = 0`.
fn landing(t: f64) -> SoleState {
    use std::f64::consts::PI;
    let (depth, ramp) = (8.5e-3, 0.15);
    let (sink, sink_rate) = match t < ramp {
        true => (
            0.5 * depth * (1.0 - (PI * t / ramp).cos()),
            0.5 * depth * PI / ramp * (PI * t / ramp).sin(),
        ),
        false => (depth, 0.0),
    };
    let sway = |a: f64, f: f64| {
        (
            a * (2.0 * PI * f * t).sin(),
            a * 2.0 * PI * f * (2.0 * PI * f * t).cos(),
        )
    };
    let (z, vz) = sway(1e-3, 2.0);
    let (pitch, pitch_rate) = sway(0.02, 1.5);
    let (roll, roll_rate) = sway(0.01, 2.5);
    SoleState {
        position: Vector3::new(0.0, 0.0, -sink + z),
        rotation: Rotation3::from_euler_angles(roll, pitch, 0.0),
        linear_velocity: Vector3::new(0.0, 0.0, -sink_rate + vz),
        angular_velocity: Vector3::new(roll_rate, pitch_rate, 0.0),
        rest_position: Vector3::zeros(),
        rest_rotation: Rotation3::identity(),
    }
}

/// A noisy measured wrench of the true ground at `state`, whose true rest plane is `delta` above the
/// assumed one.
fn measured(state: &SoleState, delta: f64, noise: &mut GaussianNoise) -> Vector6<f64> {
    let truth = SoleState {
        rest_position: state.rest_position + Vector3::new(0.0, 0.0, delta),
        ..*state
    };
    let mut f = SOLE.wrench(&truth, &TRUTH);
    for (i, x) in f.iter_mut().enumerate() {
        *x += noise.sample(WRENCH_STD[i / 3]);
    }
    f
}

/// Relative errors of `k̂`, `b̂` after one landing with rest error `delta`, and `δ̂` (zero for `[k; b]`).
fn one_landing(delta: f64, rest_height: bool) -> (f64, f64, f64) {
    let r = landing_errors(delta, rest_height);
    println!(
        "δ = {:.1} mm, rest height estimated: {rest_height}: k̂ {:+.1} %, b̂ {:+.1} %, δ̂ {:.3} mm",
        delta * 1e3,
        r.0 * 100.0,
        r.1 * 100.0,
        r.2 * 1e3
    );
    r
}

fn landing_errors(delta: f64, rest_height: bool) -> (f64, f64, f64) {
    let mut noise = GaussianNoise::new(41);
    let mut two = GroundEstimator::new(&settings()).unwrap();
    let mut three = GroundRestEstimator::new(&settings(), 1e-3).unwrap();
    for i in 1..=SAMPLES {
        let state = landing(i as f64 / 500.0);
        let f = measured(&state, delta, &mut noise);
        match rest_height {
            true => assert!(three.update(&SOLE.regressor_with_rest_height(&state), &f)),
            false => assert!(two.update(&SOLE.regressor(&state), &f)),
        }
    }
    let (e, d) = match rest_height {
        true => (three.estimate(), three.rest_height()),
        false => (two.estimate(), 0.0),
    };
    (
        (e.stiffness - TRUTH.stiffness) / TRUTH.stiffness,
        (e.damping - TRUTH.damping) / TRUTH.damping,
        d,
    )
}

#[test]
fn the_rest_height_column_is_the_force_of_a_raised_rest_plane() {
    let state = landing(0.3);
    let raised = SoleState {
        rest_position: Vector3::new(0.0, 0.0, DELTA),
        ..state
    };
    let difference = SOLE.wrench(&raised, &TRUTH) - SOLE.wrench(&state, &TRUTH);
    let column = SOLE.rest_height_column(&state) * (TRUTH.stiffness * DELTA);
    assert!(
        (difference - column).norm() < 1e-9 * column.norm(),
        "{difference} vs {column}"
    );
    let y = SOLE.regressor_with_rest_height(&state);
    assert_eq!(y.fixed_columns::<2>(0), SOLE.regressor(&state));
    assert_eq!(y.column(2), SOLE.rest_height_column(&state));
}

#[test]
fn with_the_rest_height_estimated_k_and_b_are_within_ten_percent() {
    let (k, b, d) = one_landing(DELTA, true);
    assert!(k.abs() < 0.1 && b.abs() < 0.1, "k {k:+.3}, b {b:+.3}");
    assert!((d - DELTA).abs() < 0.1 * DELTA, "δ̂ {d}");
    // No rest error: the third parameter stays near zero and costs k, b nothing beyond 10 %.
    let (k, b, d) = one_landing(0.0, true);
    assert!(k.abs() < 0.1 && b.abs() < 0.1, "k {k:+.3}, b {b:+.3}");
    assert!(d.abs() < 0.1 * DELTA, "δ̂ {d}");
}

#[test]
fn without_it_the_rest_plane_error_goes_into_b() {
    let (k, b, _) = one_landing(DELTA, false);
    assert!(
        b.abs() > 0.1,
        "b̂ within 10 % without the rest height: {b:+.3} (k {k:+.3})"
    );
    // The same estimator on the exact rest plane is within 10 %: the error is the rest plane's.
    let (k, b, _) = one_landing(0.0, false);
    assert!(k.abs() < 0.1 && b.abs() < 0.1, "k {k:+.3}, b {b:+.3}");
}

#[test]
fn a_touch_down_resets_the_covariance_and_the_rest_height_and_keeps_k_and_b() {
    let mut noise = GaussianNoise::new(43);
    let mut rls = GroundRestEstimator::new(&settings(), 1e-3).unwrap();
    let p0 = rls.covariance();
    assert_eq!(
        p0,
        Matrix3::from_diagonal(&Vector3::new(1e12, 1e8, (1e6_f64 * 1e-3).powi(2)))
    );
    for i in 1..=SAMPLES {
        let state = landing(i as f64 / 500.0);
        rls.update(
            &SOLE.regressor_with_rest_height(&state),
            &measured(&state, DELTA, &mut noise),
        );
    }
    let before = rls.estimate();
    assert!(rls.rest_height() > 0.0 && rls.covariance()[(0, 0)] < p0[(0, 0)]);
    rls.touch_down();
    assert_eq!(rls.covariance(), p0);
    assert_eq!(rls.rest_height(), 0.0);
    assert_eq!(rls.estimate(), before);
}

#[test]
fn a_bad_rest_height_prior_is_refused() {
    for std in [0.0, -1e-3, f64::NAN] {
        assert!(matches!(
            GroundRestEstimator::new(&settings(), std),
            Err(WbcError::InvalidConfig {
                key: "rest_height_std",
                ..
            })
        ));
    }
}
