//! The estimator on the bundled model: foot wrenches recovered exactly from synthesised readings with
//! offsets, joint torques equal to inverse dynamics, offsets learnt on a foot in swing, configuration and
//! input errors.

mod common;

use std::time::Duration;

use common::{bundled_model, standing_input, standing_state};
use nalgebra::{DVector, Vector6};
use stride_block::Block;
use stride_estimation::{Estimator, EstimatorConfig, EstimatorError};
use stride_model::{ExternalWrench, KinDyn};

const PERIOD_NS: u64 = 2_000_000;

fn offsets(n: usize) -> Vec<Vector6<f64>> {
    (0..n)
        .map(|k| {
            let s = k as f64 + 1.0;
            Vector6::new(3.0 * s, -2.0 * s, 4.0 + s, 0.1 * s, -0.2, 0.05 * s)
        })
        .collect()
}

#[test]
fn foot_wrenches_and_joint_torques_are_recovered_exactly() {
    let model = bundled_model();
    let state = standing_state(&model);
    let n_ft = model.ft_sensors().len();
    let offsets = offsets(n_ft);
    let ground = [
        Vector6::new(12.0, -5.0, 190.0, 2.0, -3.5, 0.4),
        Vector6::new(-8.0, 6.0, 135.0, -1.5, 2.5, -0.3),
    ];
    let mut config = EstimatorConfig::default();
    config.ft_offsets.enabled = false;
    config.ft_offsets.initial = offsets.iter().map(|o| (*o).into()).collect();
    let mut est = Estimator::new(model.clone(), &config, Duration::from_millis(2)).unwrap();
    est.set_initial_state(&state).unwrap();
    let mut out = None;
    for k in 1..=50 {
        let input = standing_input(&model, &state, &ground, &offsets, k * PERIOD_NS);
        out = Some(est.step(&input).unwrap().clone());
    }
    let out = out.unwrap();
    for (estimate, truth) in out.foot_wrenches.iter().zip(&ground) {
        let err = (estimate - truth).norm();
        assert!(err < 1e-8, "{estimate} vs {truth}");
    }
    assert_eq!(out.contacts, [true, true]);
    // The pose stays where it started.
    let pose_err = (out.state.base_pose.translation.vector - state.base_pose.translation.vector)
        .norm()
        + out
            .state
            .base_pose
            .rotation
            .angle_to(&state.base_pose.rotation);
    assert!(pose_err < 1e-9, "pose drift {pose_err}");
    assert!(out.state.base_velocity.norm() < 1e-9);
    // Joint torques: inverse dynamics at rest with the true ground wrenches.
    let mut kd = KinDyn::new(model.clone());
    kd.set_state(&state).unwrap();
    let soles = ["l_sole", "r_sole"].map(|s| model.frame_id(s).unwrap());
    let ext = [0, 1].map(|i| ExternalWrench {
        frame: soles[i],
        wrench: ground[i],
    });
    let mut tau = DVector::zeros(model.nv());
    kd.inverse_dynamics(&DVector::zeros(model.nv()), &ext, &mut tau)
        .unwrap();
    let err = (out.joint_torques - tau.rows(6, model.dof())).amax();
    assert!(err < 1e-8, "joint torque error {err}");
}

#[test]
fn the_default_foot_sensors_are_the_ones_between_ankle_and_sole() {
    let model = bundled_model();
    let est = Estimator::new(
        model.clone(),
        &EstimatorConfig::default(),
        Duration::from_millis(2),
    )
    .unwrap();
    let names = est
        .foot_sensors()
        .map(|s| model.ft_sensors()[s].name.clone());
    assert_eq!(names, ["l_foot_ft_sensor", "r_foot_ft_sensor"]);
    // A sensor that has the sole on its parent side is refused.
    let config = EstimatorConfig {
        left_foot_ft_sensor: Some("r_foot_ft_sensor".into()),
        ..EstimatorConfig::default()
    };
    let err = Estimator::new(model.clone(), &config, Duration::from_millis(2)).unwrap_err();
    assert!(matches!(err, EstimatorError::NoFootSensor { .. }), "{err}");
    let config = EstimatorConfig {
        left_foot_ft_sensor: Some("l_leg_ft_sensor".into()),
        ..EstimatorConfig::default()
    };
    let est = Estimator::new(model.clone(), &config, Duration::from_millis(2)).unwrap();
    assert_eq!(
        model.ft_sensors()[est.foot_sensors()[0]].name,
        "l_leg_ft_sensor"
    );
}

#[test]
fn offsets_converge_while_a_foot_is_in_swing() {
    // The robot stands on its right foot with the left one in the air (no wrench on it); the left foot and
    // left leg sensors have offsets the estimator does not know. The left foot breaks contact (its
    // offset-only normal force is below the break threshold), and after `min_swing_time` its sensors'
    // offsets are learnt; the right foot sensor, loaded, keeps its initial (zero) offset.
    let model = bundled_model();
    let state = standing_state(&model);
    let n_ft = model.ft_sensors().len();
    let truth = offsets(n_ft);
    let weight = model.total_mass() * 9.81;
    let ground = [
        Vector6::zeros(),
        Vector6::new(0.0, 0.0, weight, 0.0, 0.0, 0.0),
    ];
    let mut config = EstimatorConfig::default();
    config.ft_offsets.time_constant = 1.0;
    let mut est = Estimator::new(model.clone(), &config, Duration::from_millis(2)).unwrap();
    est.set_initial_state(&state).unwrap();
    let mut out = None;
    for k in 1..=5000 {
        let input = standing_input(&model, &state, &ground, &truth, k * PERIOD_NS);
        out = Some(est.step(&input).unwrap().clone());
    }
    let out = out.unwrap();
    assert_eq!(out.contacts, [false, true]);
    for (s, sensor) in model.ft_sensors().iter().enumerate() {
        let err = (out.ft_offsets[s] - truth[s]).norm();
        println!(
            "{}: offset error {err:.2e} (offset {:.1})",
            sensor.name,
            truth[s].norm()
        );
        if sensor.name.starts_with("l_") {
            // 9.9 s of samples with τ = 1 s: e^{-9.9} ≈ 5e-5 of the offset left.
            assert!(err < 1e-3 * truth[s].norm(), "{}: {err}", sensor.name);
        } else {
            assert_eq!(out.ft_offsets[s], Vector6::zeros(), "{}", sensor.name);
        }
    }
    // With the offset learnt the left foot's wrench is zero again.
    assert!(
        out.foot_wrenches[0].norm() < 1e-3,
        "{}",
        out.foot_wrenches[0]
    );
}

#[test]
fn configuration_defaults_round_trip_and_unknown_keys_are_refused() {
    let config = EstimatorConfig::default();
    let text = toml::to_string(&config).unwrap();
    let back: EstimatorConfig = toml::from_str(&text).unwrap();
    assert_eq!(back, config);
    let empty: EstimatorConfig = toml::from_str("").unwrap();
    assert_eq!(empty, config);
    assert!(toml::from_str::<EstimatorConfig>("[ekf]\ngyro_nosie = [0.1, 0.1, 0.1]").is_err());
    let bad = EstimatorConfig {
        contact: stride_estimation::ContactConfig {
            break_threshold: 0.5,
            ..Default::default()
        },
        ..EstimatorConfig::default()
    };
    assert!(matches!(
        bad.validate(),
        Err(EstimatorError::InvalidParameter {
            name: "contact.break_threshold",
            ..
        })
    ));
}

#[test]
fn bad_inputs_are_refused_and_change_nothing() {
    let model = bundled_model();
    let state = standing_state(&model);
    let offsets = vec![Vector6::zeros(); model.ft_sensors().len()];
    let ground = [Vector6::new(0.0, 0.0, 160.0, 0.0, 0.0, 0.0); 2];
    let mut est = Estimator::new(
        model.clone(),
        &EstimatorConfig::default(),
        Duration::from_millis(2),
    )
    .unwrap();
    let input = standing_input(&model, &state, &ground, &offsets, PERIOD_NS);
    assert!(matches!(
        est.step(&input),
        Err(EstimatorError::NotInitialized)
    ));
    est.set_initial_state(&state).unwrap();
    est.step(&input).unwrap();
    let before = est.output().clone();
    assert!(matches!(
        est.step(&input),
        Err(EstimatorError::NonIncreasingTime { .. })
    ));
    let mut nan = standing_input(&model, &state, &ground, &offsets, 2 * PERIOD_NS);
    nan.imu.proper_acceleration.x = f64::NAN;
    assert!(matches!(
        est.step(&nan),
        Err(EstimatorError::NonFiniteInput { .. })
    ));
    let mut short = standing_input(&model, &state, &ground, &offsets, 2 * PERIOD_NS);
    short.ft_wrenches.pop();
    assert!(matches!(
        est.step(&short),
        Err(EstimatorError::InputSize { .. })
    ));
    assert_eq!(est.output(), &before);
    est.reset();
    assert!(matches!(
        est.step(&input),
        Err(EstimatorError::NotInitialized)
    ));
}
