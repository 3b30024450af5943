//! A step of the estimator allocates nothing (counting global allocator).

mod common;

use std::time::Duration;

use common::{bundled_model, standing_input, standing_state};
use nalgebra::Vector6;
use stride_estimation::{Estimator, EstimatorConfig, EstimatorInput};

#[global_allocator]
static ALLOC: stride_testkit::CountingAllocator = stride_testkit::CountingAllocator::new();

/// An estimator started standing on the bundled robot, stepped once, and `count` more standing samples
/// `period_ns` apart with the vertical foot forces `forces` (N, left and right).
fn started(forces: [f64; 2], period_ns: u64, count: u64) -> (Estimator, Vec<EstimatorInput>) {
    started_with(&EstimatorConfig::default(), forces, period_ns, count)
}

/// [`started`] with `config`.
fn started_with(
    config: &EstimatorConfig,
    forces: [f64; 2],
    period_ns: u64,
    count: u64,
) -> (Estimator, Vec<EstimatorInput>) {
    let model = bundled_model();
    let state = standing_state(&model);
    let offsets = vec![Vector6::zeros(); model.ft_sensors().len()];
    let ground = forces.map(|f| Vector6::new(0.0, 0.0, f, 0.0, 0.0, 0.0));
    let inputs: Vec<_> = (1..=count)
        .map(|k| standing_input(&model, &state, &ground, &offsets, k * period_ns))
        .collect();
    let period = Duration::from_nanos(period_ns);
    let mut est = Estimator::new(model, config, period).unwrap();
    est.set_initial_state(&state).unwrap();
    est.step(&inputs[0]).unwrap();
    (est, inputs)
}

#[test]
fn a_step_allocates_nothing() {
    let (mut est, inputs) = started([10.0, 300.0], 2_000_000, 200);
    let (_, n) = ALLOC.allocations_during(|| {
        for input in &inputs[1..] {
            est.step(input).unwrap();
        }
    });
    // The left foot breaks contact and goes through swing (offset samples) within these steps.
    assert_eq!(est.output().contacts, [false, true]);
    assert_eq!(n, 0, "a step allocated {n} times");
}

/// Allocations while `est` pre-integrates three samples of four and runs a full tick on the fourth.
fn allocations_preintegrating(est: &mut Estimator, inputs: &[EstimatorInput]) -> usize {
    let (_, n) = ALLOC.allocations_during(|| {
        for (k, input) in inputs.iter().enumerate().skip(1) {
            if k % 4 == 0 {
                est.step(input).unwrap();
            } else {
                est.preintegrate(input).unwrap();
            }
        }
    });
    n
}

#[test]
fn preintegrating_allocates_nothing() {
    let (mut est, inputs) = started([150.0, 150.0], 500_000, 40);
    let n = allocations_preintegrating(&mut est, &inputs);
    assert_eq!(n, 0, "pre-integrating allocated {n} times");
}

#[test]
fn the_joint_velocity_filter_allocates_nothing() {
    let config = EstimatorConfig {
        joint_velocity_bandwidth: 80.0,
        ..EstimatorConfig::default()
    };
    let (mut est, inputs) = started_with(&config, [150.0, 150.0], 500_000, 40);
    let n = allocations_preintegrating(&mut est, &inputs);
    assert_eq!(n, 0, "the filter allocated {n} times");
}

#[test]
fn learning_while_standing_on_level_soles_allocates_nothing() {
    // The force/torque offsets and the accelerometer's bias learnt while standing, with the level-sole
    // pseudo-measurement: every step of these 40 is inside the 1 s window, both feet loaded.
    let mut config = EstimatorConfig::default();
    config.ft_offsets.learn_while_standing = 1.0;
    config.ekf.level_soles_while_standing = true;
    config.ekf.level_soles_noise = 2e-3;
    let (mut est, inputs) = started_with(&config, [150.0, 150.0], 500_000, 40);
    let (_, n) = ALLOC.allocations_during(|| {
        for input in &inputs[1..] {
            est.step(input).unwrap();
        }
    });
    assert_eq!(est.output().contacts, [true, true]);
    assert_eq!(n, 0, "learning while standing allocated {n} times");
}

#[test]
fn the_stance_leg_accelerations_allocate_nothing() {
    let config = EstimatorConfig {
        stance_leg_accelerations: true,
        ..EstimatorConfig::default()
    };
    let (mut est, inputs) = started_with(&config, [10.0, 300.0], 2_000_000, 200);
    let (_, n) = ALLOC.allocations_during(|| {
        for input in &inputs[1..] {
            est.step(input).unwrap();
        }
    });
    // Both feet in contact at the start, then the right one alone: both solves ran.
    assert_eq!(est.output().contacts, [false, true]);
    assert_eq!(n, 0, "a step allocated {n} times");
}
