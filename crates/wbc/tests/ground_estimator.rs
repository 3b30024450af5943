//! The recursive least-squares estimate of the ground's `k` and `b` [Romualdi 2022, §8.2.3] on synthetic
//! wrenches of Lemma 1 with known parameters and Gaussian noise: it equals the batch least-squares solution,
//! converges to the true values, tracks a change of ground only when the covariance is reset at touch-down,
//! and learns nothing about `b` from a sole at rest.

mod common;

use common::soft::{rigid_guess_settings, SOLE};

use nalgebra::{Matrix2, Rotation3, Vector2, Vector3, Vector6};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use stride_sim::GaussianNoise as GaussianSampler;
use stride_wbc::{EstimatorSettings, GroundEstimator, GroundParameters, SoleState, WbcError};

const WRENCH_STD: [f64; 2] = [2.0, 0.2];

/// A rigid-floor guess, far from the soft grounds of Table 8.1, and the noise of the samples.
fn settings() -> EstimatorSettings {
    EstimatorSettings {
        wrench_std: WRENCH_STD,
        ..rigid_guess_settings()
    }
}

/// A sole in stance on soft ground: sunk by 5–15 mm, tilted by up to 0.05 rad, moving at up to 5 cm/s and
/// 0.5 rad/s.
fn stance_state(rng: &mut ChaCha8Rng, moving: bool) -> SoleState {
    let mut r = |a: f64| rng.random_range(-a..a);
    let rest = Vector3::new(r(1.0), r(1.0), 0.0);
    let speed = if moving { 1.0 } else { 0.0 };
    SoleState {
        position: rest + Vector3::new(r(0.005), r(0.005), -0.01 + r(0.005)),
        rotation: Rotation3::new(Vector3::new(r(0.05), r(0.05), r(0.1))),
        linear_velocity: Vector3::new(r(0.05), r(0.05), r(0.05)) * speed,
        angular_velocity: Vector3::new(r(0.5), r(0.5), r(0.5)) * speed,
        rest_position: rest,
        rest_rotation: Rotation3::identity(),
    }
}

/// A noisy measurement of the Lemma 1 wrench of `ground` at a random stance state, with its regressor.
fn sample(
    rng: &mut ChaCha8Rng,
    noise: &mut GaussianSampler,
    ground: &GroundParameters,
    moving: bool,
) -> (nalgebra::Matrix6x2<f64>, Vector6<f64>) {
    let state = stance_state(rng, moving);
    let y = SOLE.regressor(&state);
    let mut f = SOLE.wrench(&state, ground);
    for i in 0..6 {
        f[i] += noise.sample(WRENCH_STD[i / 3]);
    }
    (y, f)
}

const SOFT: GroundParameters = GroundParameters {
    stiffness: 1e6,
    damping: 1e4,
};

#[test]
fn rls_equals_the_batch_least_squares_with_the_prior_and_converges() {
    let mut rng = common::rng(91);
    let mut noise = GaussianSampler::new(92);
    let s = settings();
    let mut rls = GroundEstimator::new(&s).unwrap();
    // Batch: π = (P₀⁻¹ + Σ 𝒴ᵀΓ⁻¹𝒴)⁻¹ (P₀⁻¹ π₀ + Σ 𝒴ᵀΓ⁻¹ f), the minimiser of eq. 8.2.19 with the prior.
    let p0_inv = Matrix2::new(
        1.0 / (s.initial_std[0] * s.initial_std[0]),
        0.0,
        0.0,
        1.0 / (s.initial_std[1] * s.initial_std[1]),
    );
    let mut information = p0_inv;
    let mut vector = p0_inv * s.initial.vector();
    let gamma_inv = Vector6::from_iterator((0..6).map(|i| WRENCH_STD[i / 3].powi(-2)));
    for _ in 0..500 {
        let (y, f) = sample(&mut rng, &mut noise, &SOFT, true);
        assert!(rls.update(&y, &f));
        let weighted = nalgebra::Matrix6::from_diagonal(&gamma_inv) * y;
        information += y.transpose() * weighted;
        vector += weighted.transpose() * f;
    }
    let batch: Vector2<f64> = information.try_inverse().unwrap() * vector;
    let estimate = rls.estimate().vector();
    assert!(
        (estimate - batch).component_div(&batch).abs().max() < 1e-8,
        "{estimate} vs {batch}"
    );
    assert!(
        ((estimate[0] - SOFT.stiffness) / SOFT.stiffness).abs() < 0.01,
        "{estimate}"
    );
    assert!(
        ((estimate[1] - SOFT.damping) / SOFT.damping).abs() < 0.05,
        "{estimate}"
    );
    // The covariance is the inverse information (Joseph form kept it symmetric and positive).
    let p = rls.covariance();
    assert!((p * information - Matrix2::identity()).norm() < 1e-6, "{p}");
}

/// Samples after which the `k` and `b` estimates are within 10 % of `ground`'s, up to `limit`.
fn samples_to_converge(
    rls: &mut GroundEstimator,
    rng: &mut ChaCha8Rng,
    noise: &mut GaussianSampler,
    ground: &GroundParameters,
    limit: usize,
) -> usize {
    for n in 1..=limit {
        let (y, f) = sample(rng, noise, ground, true);
        rls.update(&y, &f);
        let e = rls.estimate();
        if ((e.stiffness - ground.stiffness) / ground.stiffness).abs() < 0.1
            && ((e.damping - ground.damping) / ground.damping).abs() < 0.1
        {
            return n;
        }
    }
    limit + 1
}

#[test]
fn a_change_of_ground_is_tracked_only_with_the_touch_down_reset() {
    let other = GroundParameters {
        stiffness: 2e6,
        damping: 1e3,
    };
    let mut reset_counts = Vec::new();
    let mut kept_counts = Vec::new();
    for reset in [true, false] {
        let mut rng = common::rng(93);
        let mut noise = GaussianSampler::new(94);
        let mut rls = GroundEstimator::new(&settings()).unwrap();
        // A long stance on the first ground: the covariance shrinks.
        for _ in 0..2000 {
            let (y, f) = sample(&mut rng, &mut noise, &SOFT, true);
            rls.update(&y, &f);
        }
        if reset {
            rls.touch_down();
        }
        let n = samples_to_converge(&mut rls, &mut rng, &mut noise, &other, 500);
        if reset {
            reset_counts.push(n);
        } else {
            kept_counts.push(n);
        }
    }
    // With the reset: within 10 % in well under the 500 samples of 1 s at the 500 Hz control rate; without
    // it the shrunken covariance keeps the old ground for longer than that.
    assert!(reset_counts[0] <= 50, "with reset: {reset_counts:?}");
    assert!(kept_counts[0] > 500, "without reset: {kept_counts:?}");
}

#[test]
fn a_sole_at_rest_says_nothing_about_the_damping() {
    let mut rng = common::rng(95);
    let mut noise = GaussianSampler::new(96);
    let s = settings();
    let mut rls = GroundEstimator::new(&s).unwrap();
    for _ in 0..200 {
        let (y, f) = sample(&mut rng, &mut noise, &SOFT, false);
        rls.update(&y, &f);
    }
    let p = rls.covariance();
    // The second regressor column vanishes: b keeps its prior, k is learnt.
    assert!(
        (p[(1, 1)] - s.initial_std[1].powi(2)).abs() < 1e-9 * p[(1, 1)],
        "{p}"
    );
    assert_eq!(rls.estimate().damping, s.initial.damping);
    assert!(((rls.estimate().stiffness - SOFT.stiffness) / SOFT.stiffness).abs() < 0.01);
}

#[test]
fn bad_settings_are_refused_and_bad_samples_skipped() {
    let mut s = settings();
    s.initial_std[1] = 0.0;
    assert!(matches!(
        GroundEstimator::new(&s),
        Err(WbcError::InvalidConfig {
            key: "initial_std",
            ..
        })
    ));
    let mut s = settings();
    s.wrench_std[0] = f64::NAN;
    assert!(matches!(
        GroundEstimator::new(&s),
        Err(WbcError::InvalidConfig {
            key: "wrench_std",
            ..
        })
    ));
    let mut s = settings();
    s.initial.stiffness = f64::INFINITY;
    assert!(matches!(
        GroundEstimator::new(&s),
        Err(WbcError::InvalidConfig { key: "initial", .. })
    ));
    let mut rls = GroundEstimator::new(&settings()).unwrap();
    let before = rls.estimate();
    let mut f = Vector6::zeros();
    f[2] = f64::NAN;
    assert!(!rls.update(&nalgebra::Matrix6x2::zeros(), &f));
    assert_eq!(rls.estimate(), before);
}
