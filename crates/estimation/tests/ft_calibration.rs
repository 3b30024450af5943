//! `ft_calibration`: the estimator applies each named sensor's calibration matrix, `f = C (r − b)`
//! [Traversaro 2017, eq. (5.1)], before anything uses a reading: the foot wrenches are exact with it and
//! wrong without it, and the offsets learnt on a foot in swing are the raw-space offsets `b`.

mod common;

use std::time::Duration;

use common::{bundled_model, standing_input, standing_state};
use nalgebra::{Matrix6, Vector6};
use stride_estimation::{Estimator, EstimatorConfig, EstimatorError, EstimatorInput};

const PERIOD_NS: u64 = 2_000_000;

/// A calibration matrix `C = (1 + E)⁻¹` with `E` a fixed pattern within ±5 % (sensor `k`).
fn calibration(k: usize) -> Matrix6<f64> {
    let e = Matrix6::from_fn(|i, j| 0.05 * (((7 * i + 3 * j + 5 * k) % 11) as f64 / 5.0 - 1.0));
    (Matrix6::identity() + e).try_inverse().unwrap()
}

fn offsets(n: usize) -> Vec<Vector6<f64>> {
    (0..n)
        .map(|k| Vector6::new(3.0, -2.0 - k as f64, 4.0, 0.1, -0.2, 0.05 * k as f64))
        .collect()
}

/// `standing_input` with every reading turned raw: `r = C⁻¹ w + b`.
fn raw_input(input: &mut EstimatorInput, offsets: &[Vector6<f64>]) {
    for (k, (r, b)) in input.ft_wrenches.iter_mut().zip(offsets).enumerate() {
        let w = *r - b;
        *r = calibration(k).try_inverse().unwrap() * w + b;
    }
}

fn rows(c: &Matrix6<f64>) -> [[f64; 6]; 6] {
    std::array::from_fn(|i| std::array::from_fn(|j| c[(i, j)]))
}

fn with_matrices(model: &stride_model::Model) -> EstimatorConfig {
    let mut config = EstimatorConfig::default();
    for (k, s) in model.ft_sensors().iter().enumerate() {
        config
            .ft_calibration
            .insert(s.name.clone(), rows(&calibration(k)));
    }
    config
}

#[test]
fn foot_wrenches_are_exact_with_the_calibration_matrices_and_wrong_without() {
    let model = bundled_model();
    let state = standing_state(&model);
    let offsets = offsets(model.ft_sensors().len());
    let ground = [
        Vector6::new(12.0, -5.0, 190.0, 2.0, -3.5, 0.4),
        Vector6::new(-8.0, 6.0, 135.0, -1.5, 2.5, -0.3),
    ];
    let error = |mut config: EstimatorConfig| {
        config.ft_offsets.enabled = false;
        config.ft_offsets.initial = offsets.iter().map(|o| (*o).into()).collect();
        let mut est = Estimator::new(model.clone(), &config, Duration::from_millis(2)).unwrap();
        est.set_initial_state(&state).unwrap();
        let mut worst: f64 = 0.0;
        for k in 1..=20 {
            let mut input = standing_input(&model, &state, &ground, &offsets, k * PERIOD_NS);
            raw_input(&mut input, &offsets);
            let out = est.step(&input).unwrap();
            for (e, t) in out.foot_wrenches.iter().zip(&ground) {
                worst = worst.max((e - t).norm());
            }
        }
        worst
    };
    let calibrated = error(with_matrices(&model));
    let uncalibrated = error(EstimatorConfig::default());
    assert!(calibrated < 1e-8, "with C: error {calibrated}");
    assert!(uncalibrated > 1.0, "without C: error {uncalibrated}");
}

#[test]
fn offsets_learnt_in_swing_are_the_raw_offsets() {
    // The left foot in the air: its sensors' offsets are learnt as `r − C⁻¹ f̂` (raw space).
    let model = bundled_model();
    let state = standing_state(&model);
    let truth = offsets(model.ft_sensors().len());
    let weight = model.total_mass() * 9.81;
    let ground = [
        Vector6::zeros(),
        Vector6::new(0.0, 0.0, weight, 0.0, 0.0, 0.0),
    ];
    let mut config = with_matrices(&model);
    config.ft_offsets.time_constant = 1.0;
    let mut est = Estimator::new(model.clone(), &config, Duration::from_millis(2)).unwrap();
    est.set_initial_state(&state).unwrap();
    for k in 1..=5000 {
        let mut input = standing_input(&model, &state, &ground, &truth, k * PERIOD_NS);
        raw_input(&mut input, &truth);
        est.step(&input).unwrap();
    }
    let out = est.output();
    assert_eq!(out.contacts, [false, true]);
    for name in ["l_foot_ft_sensor", "l_leg_ft_sensor"] {
        let s = model.ft_sensor_index(name).unwrap();
        let err = (out.ft_offsets[s] - truth[s]).norm();
        assert!(err < 1e-3, "{name}: offset error {err}");
    }
}

#[test]
fn an_unknown_sensor_or_a_singular_matrix_is_refused() {
    let model = bundled_model();
    let mut config = EstimatorConfig::default();
    config
        .ft_calibration
        .insert("no_such_sensor".into(), rows(&Matrix6::identity()));
    let err = Estimator::new(model.clone(), &config, Duration::from_millis(2)).unwrap_err();
    assert!(
        matches!(err, EstimatorError::UnknownFtSensor { ref name, .. } if name == "no_such_sensor"),
        "{err}"
    );
    let mut config = EstimatorConfig::default();
    config
        .ft_calibration
        .insert("l_foot_ft_sensor".into(), [[0.0; 6]; 6]);
    let err = Estimator::new(model.clone(), &config, Duration::from_millis(2))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("ft_calibration") && err.contains("invertible"),
        "{err}"
    );
    let mut config = EstimatorConfig::default();
    let mut bad = rows(&Matrix6::identity());
    bad[2][3] = f64::NAN;
    config.ft_calibration.insert("l_foot_ft_sensor".into(), bad);
    let err = Estimator::new(model, &config, Duration::from_millis(2))
        .unwrap_err()
        .to_string();
    assert!(err.contains("finite"), "{err}");
}
