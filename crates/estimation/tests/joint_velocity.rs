//! The joint velocity filter (`JointVelocityFilter`, `joint_velocity_bandwidth`) against its closed forms
//! [Kalata 1984], and inside the estimator on both of its paths (full ticks and pre-integrated samples).

mod common;

use std::f64::consts::PI;
use std::time::Duration;

use common::{bundled_model, standing_input, standing_state};
use nalgebra::{DVector, Vector6};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use stride_estimation::{Estimator, EstimatorConfig, EstimatorError, JointVelocityFilter};

const DT: f64 = 2.5e-4;

/// Runs a one-joint filter at `bandwidth` on `q(t)` for `samples` samples from rest; returns the last
/// velocity estimate.
fn run(bandwidth: f64, samples: usize, q: impl Fn(f64) -> f64) -> f64 {
    let mut f = JointVelocityFilter::new(1, bandwidth).unwrap();
    let zero = DVector::zeros(1);
    for k in 0..samples {
        f.step(&DVector::from_element(1, q(k as f64 * DT)), &zero, DT);
    }
    f.velocities()[0]
}

#[test]
fn a_constant_velocity_is_tracked_without_error() {
    // Type-2 loop: the error of a ramp decays as k pᵏ (p = exp(−2π·80·T) = 0.882): gone after 0.2 s.
    let v = run(80.0, 800, |t| 0.3 + 1.7 * t);
    assert!((v - 1.7).abs() < 1e-9, "{v}");
}

#[test]
fn a_constant_acceleration_leaves_the_closed_form_lag() {
    let a = 30.0;
    for bandwidth in [20.0, 80.0] {
        let samples = 8000;
        let v = run(bandwidth, samples, |t| 0.5 * a * t * t);
        let truth = a * (samples - 1) as f64 * DT;
        let (alpha, beta) = JointVelocityFilter::new(1, bandwidth).unwrap().gains(DT);
        let lag = a * DT * (alpha / beta - 0.5);
        assert!(
            ((truth - v) - lag).abs() < 1e-9 * truth,
            "{bandwidth} Hz: lag {} vs {lag}",
            truth - v
        );
    }
    // The continuous-time limit 2a/ω: at 20 Hz and 4 kHz (ωT = 0.03) the discrete lag is 0.8 % below it.
    let (alpha, beta) = JointVelocityFilter::new(1, 20.0).unwrap().gains(DT);
    let continuous = 2.0 * a / (2.0 * PI * 20.0);
    let lag = a * DT * (alpha / beta - 0.5);
    assert!(
        (lag / continuous - 1.0).abs() < 0.01,
        "{lag} vs {continuous}"
    );
}

/// With the acceleration known (`set_accelerations`, the prediction `q⁻ = q̂ + T v̂ + T² a/2`,
/// `v⁻ = v̂ + T a`) a constant acceleration is tracked without the lag `a T (α/β − ½)` of the plain filter;
/// the estimator forwards it and refuses a wrong size or a non-finite value by name.
#[test]
fn a_known_acceleration_is_tracked_without_lag() {
    let a = 30.0;
    let samples = 8000;
    let mut f = JointVelocityFilter::new(1, 20.0).unwrap();
    f.set_accelerations(&[a]);
    let zero = DVector::zeros(1);
    for k in 0..samples {
        let t = k as f64 * DT;
        f.step(&DVector::from_element(1, 0.5 * a * t * t), &zero, DT);
    }
    let truth = a * (samples - 1) as f64 * DT;
    assert!(
        (f.velocities()[0] - truth).abs() < 1e-9 * truth,
        "{} vs {truth}",
        f.velocities()[0]
    );
    // after a reset the prediction is gone: the plain filter's lag again
    f.reset();
    for k in 0..samples {
        let t = k as f64 * DT;
        f.step(&DVector::from_element(1, 0.5 * a * t * t), &zero, DT);
    }
    let (alpha, beta) = f.gains(DT);
    let lag = a * DT * (alpha / beta - 0.5);
    assert!(((truth - f.velocities()[0]) - lag).abs() < 1e-9 * truth);
    let model = bundled_model();
    let config = EstimatorConfig {
        joint_velocity_bandwidth: 150.0,
        ..Default::default()
    };
    let mut estimator = Estimator::new(model.clone(), &config, Duration::from_micros(500)).unwrap();
    let n = model.dof();
    assert!(estimator.set_joint_accelerations(&vec![1.0; n]).is_ok());
    assert!(matches!(
        estimator.set_joint_accelerations(&vec![1.0; n + 1]),
        Err(EstimatorError::InputSize {
            name: "joint_accelerations",
            ..
        })
    ));
    let mut nan = vec![0.0; n];
    nan[0] = f64::NAN;
    assert!(matches!(
        estimator.set_joint_accelerations(&nan),
        Err(EstimatorError::NonFiniteInput {
            name: "joint_accelerations"
        })
    ));
}

#[test]
fn white_position_noise_gives_the_closed_form_velocity_variance() {
    let sigma = 1e-3;
    let bandwidth = 50.0;
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    // Box–Muller: one standard normal sample from two uniform ones.
    let mut normal = move || {
        let (u, v): (f64, f64) = (1.0 - rng.random::<f64>(), rng.random::<f64>());
        (-2.0 * u.ln()).sqrt() * (2.0 * PI * v).cos()
    };
    let mut f = JointVelocityFilter::new(1, bandwidth).unwrap();
    let zero = DVector::zeros(1);
    let (mut sum, mut n) = (0.0, 0);
    for k in 0..400_000 {
        f.step(&DVector::from_element(1, sigma * normal()), &zero, DT);
        if k > 2000 {
            sum += f.velocities()[0].powi(2);
            n += 1;
        }
    }
    let (a, b) = f.gains(DT);
    let expected = sigma * (2.0 * b * b / (DT * DT * a * (4.0 - 2.0 * a - b))).sqrt();
    let measured = (sum / f64::from(n)).sqrt();
    assert!(
        (measured / expected - 1.0).abs() < 0.03,
        "{measured} vs {expected}"
    );
}

#[test]
fn a_bandwidth_that_is_not_positive_is_refused() {
    for b in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let err = JointVelocityFilter::new(3, b).unwrap_err();
        assert!(
            matches!(
                err,
                EstimatorError::InvalidParameter {
                    name: "joint_velocity_bandwidth",
                    ..
                }
            ),
            "{err}"
        );
    }
    let config = EstimatorConfig {
        joint_velocity_bandwidth: -5.0,
        ..EstimatorConfig::default()
    };
    assert!(config.validate().is_err());
}

#[test]
fn the_estimator_reports_the_filters_velocities_on_both_paths() {
    let model = bundled_model();
    let state = standing_state(&model);
    let offsets = vec![Vector6::zeros(); model.ft_sensors().len()];
    let ground = [Vector6::new(0.0, 0.0, 160.0, 0.0, 0.0, 0.0); 2];
    let period_ns = 250_000;
    let config = EstimatorConfig {
        joint_velocity_bandwidth: 80.0,
        ..EstimatorConfig::default()
    };
    let mut est = Estimator::new(model.clone(), &config, Duration::from_nanos(period_ns)).unwrap();
    est.set_initial_state(&state).unwrap();
    let mut reference = JointVelocityFilter::new(model.dof(), 80.0).unwrap();
    // The estimator's sample period, from the time stamps.
    let dt = period_ns as f64 * 1e-9;
    for k in 1..=200u64 {
        let mut input = standing_input(&model, &state, &ground, &offsets, k * period_ns);
        // Every joint moves at its own constant acceleration from the standing posture.
        let t = k as f64 * DT;
        for (j, q) in input.joint_positions.iter_mut().enumerate() {
            *q += 0.5 * (j as f64 - 10.0) * t * t;
        }
        input.joint_velocities.fill(0.0);
        reference.step(&input.joint_positions, &input.joint_velocities, dt);
        if k % 4 == 1 {
            let out = est.step(&input).unwrap();
            assert_eq!(
                out.state.joint_velocities,
                *reference.velocities(),
                "tick {k}"
            );
        } else {
            est.preintegrate(&input).unwrap();
        }
    }
    // The filter followed the motion: the last estimate within its closed-form lag of the truth.
    let (alpha, beta) = reference.gains(DT);
    let t = 200.0 * DT;
    let v = est.output().state.joint_velocities[0];
    assert!(
        (v - (-10.0 * t - (-10.0) * DT * (alpha / beta - 0.5))).abs() < 0.05,
        "{v}"
    );
}
