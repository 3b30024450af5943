//! A step of the estimator allocates nothing (counting global allocator).

mod common;

use std::time::Duration;

use common::{bundled_model, standing_input, standing_state};
use nalgebra::Vector6;
use stride_estimation::{Estimator, EstimatorConfig};

#[global_allocator]
static ALLOC: stride_testkit::CountingAllocator = stride_testkit::CountingAllocator::new();

#[test]
fn a_step_allocates_nothing() {
    let model = bundled_model();
    let state = standing_state(&model);
    let offsets = vec![Vector6::zeros(); model.ft_sensors().len()];
    let ground = [
        Vector6::new(0.0, 0.0, 10.0, 0.0, 0.0, 0.0),
        Vector6::new(0.0, 0.0, 300.0, 0.0, 0.0, 0.0),
    ];
    let inputs: Vec<_> = (1..=200)
        .map(|k| standing_input(&model, &state, &ground, &offsets, k * 2_000_000))
        .collect();
    let mut est =
        Estimator::new(model, &EstimatorConfig::default(), Duration::from_millis(2)).unwrap();
    est.set_initial_state(&state).unwrap();
    est.step(&inputs[0]).unwrap();
    let (_, n) = ALLOC.allocations_during(|| {
        for input in &inputs[1..] {
            est.step(input).unwrap();
        }
    });
    // The left foot breaks contact and goes through swing (offset samples) within these steps.
    assert_eq!(est.output().contacts, [false, true]);
    assert_eq!(n, 0, "a step allocated {n} times");
}

#[test]
fn preintegrating_allocates_nothing() {
    let model = bundled_model();
    let state = standing_state(&model);
    let offsets = vec![Vector6::zeros(); model.ft_sensors().len()];
    let ground = [
        Vector6::new(0.0, 0.0, 150.0, 0.0, 0.0, 0.0),
        Vector6::new(0.0, 0.0, 150.0, 0.0, 0.0, 0.0),
    ];
    let inputs: Vec<_> = (1..=40)
        .map(|k| standing_input(&model, &state, &ground, &offsets, k * 500_000))
        .collect();
    let mut est = Estimator::new(
        model,
        &EstimatorConfig::default(),
        Duration::from_micros(500),
    )
    .unwrap();
    est.set_initial_state(&state).unwrap();
    est.step(&inputs[0]).unwrap();
    let (_, n) = ALLOC.allocations_during(|| {
        for (k, input) in inputs.iter().enumerate().skip(1) {
            if k % 4 == 0 {
                est.step(input).unwrap();
            } else {
                est.preintegrate(input).unwrap();
            }
        }
    });
    assert_eq!(n, 0, "pre-integrating allocated {n} times");
}
