//! The IMU's biases learnt while standing (`ekf.level_soles_while_standing`): a robot standing still on both
//! feet on a level ground, its IMU read with a known gyroscope bias and an accelerometer bias across gravity.
//! Gravity alone takes that accelerometer bias for a tilt; with the soles measured level the legs' kinematics
//! give the tilt, and the filter learns the bias.

mod common;

use std::time::Duration;

use common::{bundled_model, standing_input, standing_split, standing_state, tilt_between, Gauss};
use nalgebra::{Matrix3, Vector3, Vector6};
use stride_estimation::{Estimator, EstimatorConfig, EstimatorError};
use stride_model::KinDyn;

const PERIOD_NS: u64 = 1_000_000;

/// What the estimator holds after `seconds` of a robot standing still with IMU biases `gyro_bias`,
/// `acc_bias` (IMU frame) and white noise on the IMU, learning for the first second (`level` the key):
/// the accelerometer bias's error across gravity \[m/s²\] (the norm of its component orthogonal to the
/// gravity direction in the IMU frame), the gyroscope bias's error \[rad/s\], the tilt error \[rad\], and the
/// true bias across gravity's norm.
fn stand(level: bool, gyro_bias: Vector3<f64>, acc_bias: Vector3<f64>) -> (f64, f64, f64, f64) {
    let model = bundled_model();
    let state = standing_state(&model);
    let mut kd = KinDyn::new(model.clone());
    kd.set_state(&state).unwrap();
    let (r_imu, _) = kd.frame_rotation_translation(model.frame_id("imu_frame").unwrap());
    let mut config = EstimatorConfig {
        sole_size: [0.20, 0.09],
        ..EstimatorConfig::default()
    };
    config.ft_offsets.learn_while_standing = 1.0;
    config.ekf.level_soles_while_standing = level;
    let ground = standing_split(&model, &state, config.sole_size);
    let offsets = vec![Vector6::zeros(); model.ft_sensors().len()];
    let mut est = Estimator::new(model.clone(), &config, Duration::from_millis(1)).unwrap();
    est.set_initial_state(&state).unwrap();
    let mut rng = Gauss::new(7);
    // The IMU's white noise: the simulated IMU's densities (stride-sim's defaults, 1.2e-4 rad/s/√Hz and
    // 1.2e-3 m/s²/√Hz) at 1 kHz (σ = density·√rate).
    let (gyro_sigma, acc_sigma) = ([1.2e-4 * 1000f64.sqrt(); 3], [1.2e-3 * 1000f64.sqrt(); 3]);
    for k in 1..=2000 {
        let mut input = standing_input(&model, &state, &ground, &offsets, k * PERIOD_NS);
        input.imu.angular_velocity += gyro_bias + rng.vec3(&gyro_sigma);
        input.imu.proper_acceleration += acc_bias + rng.vec3(&acc_sigma);
        est.step(&input).unwrap();
    }
    let s = est.ekf().state();
    let down = r_imu.transpose() * Vector3::z();
    let across = |b: Vector3<f64>| b - down * b.dot(&down);
    let acc_error = across(s.accelerometer_bias - acc_bias).norm();
    let gyro_error = (s.gyro_bias - gyro_bias).norm();
    let r_est: Matrix3<f64> = s.rotation;
    (
        acc_error,
        gyro_error,
        tilt_between(&r_est, &r_imu),
        across(acc_bias).norm(),
    )
}

#[test]
fn the_accelerometer_bias_across_gravity_is_learnt_with_level_soles_and_not_without() {
    // The simulated IMU's turn-on biases are up to 3.5e-3 rad/s and 0.05 m/s² per axis (docs/sim.md).
    let gyro_bias = Vector3::new(3.0e-3, -2.0e-3, 2.5e-3);
    let acc_bias = Vector3::new(0.05, -0.04, 0.03);
    let (acc_error, gyro_error, tilt, across) = stand(true, gyro_bias, acc_bias);
    // With the soles level: the bias across gravity within 10 % (5 mm/s², 0.03° of tilt), the tilt, 1 s after
    // the window, within 0.1° (0.05° measured; the bias makes 0.37° without). The gyroscope's bias is the filter's own estimate (its mean reading would take the robot's own
    // turning for bias): after 2 s it holds more than half of it (1.5e-3 rad/s off of 4.4e-3 measured).
    assert!(across > 0.05, "the injected bias across gravity: {across}");
    assert!(
        acc_error < 0.1 * across,
        "accelerometer bias error {acc_error} m/s² of {across}"
    );
    assert!(
        gyro_error < 0.5 * gyro_bias.norm(),
        "gyroscope bias error {gyro_error} rad/s"
    );
    assert!(
        tilt < 0.1_f64.to_radians(),
        "tilt error {}°",
        tilt.to_degrees()
    );
    // Without: gravity takes most of the bias for a tilt of about |b|/g.
    let (acc_error, _, tilt, _) = stand(false, gyro_bias, acc_bias);
    assert!(
        acc_error > 0.5 * across,
        "accelerometer bias error {acc_error} m/s² of {across}"
    );
    assert!(
        tilt > 0.5 * across / 9.81,
        "tilt error {}°",
        tilt.to_degrees()
    );
}

#[test]
fn level_soles_need_the_standing_window_and_a_non_negative_noise() {
    let model = bundled_model();
    let mut config = EstimatorConfig::default();
    config.ekf.level_soles_while_standing = true;
    let refused = |c: &EstimatorConfig| {
        matches!(
            Estimator::new(model.clone(), c, Duration::from_millis(1)),
            Err(EstimatorError::InvalidParameter { .. })
        )
    };
    assert!(refused(&config));
    config.ft_offsets.learn_while_standing = 1.0;
    assert!(!refused(&config));
    config.ekf.level_soles_noise = -1e-3;
    assert!(refused(&config));
    assert!(!EstimatorConfig::default().ekf.level_soles_while_standing);
}

#[test]
fn a_level_sole_measurement_turns_the_tilt_toward_the_legs() {
    // A filter 0.6° off in roll and −0.4° in pitch (1° prior), the sole level and aligned with the IMU: one
    // update with σ 1e-4 rad takes the tilt to within 1 % of its error, the heading untouched.
    use stride_estimation::{EkfConfig, InvariantEkf};
    let config = EkfConfig::default();
    let mut ekf = InvariantEkf::new(&config, Vector3::new(0.0, 0.0, -9.81));
    let off =
        nalgebra::Rotation3::from_euler_angles(0.6_f64.to_radians(), -0.4_f64.to_radians(), 0.0)
            .into_inner();
    let feet = [Vector3::new(0.0, 0.1, -0.5), Vector3::new(0.0, -0.1, -0.5)];
    ekf.initialize(
        &config,
        off,
        Vector3::zeros(),
        Vector3::zeros(),
        feet,
        [off; 2],
    );
    let before = tilt_between(&ekf.state().rotation, &Matrix3::identity());
    ekf.update_level_sole(&Matrix3::identity(), &Vector3::z(), 1e-4)
        .unwrap();
    let r = ekf.state().rotation;
    let after = tilt_between(&r, &Matrix3::identity());
    assert!(after < 0.01 * before, "tilt {before} → {after} rad");
    // The heading moves by second-order terms only (roll × pitch ≈ 7e-5 rad).
    assert!(r[(1, 0)].atan2(r[(0, 0)]).abs() < 1e-4);
}
