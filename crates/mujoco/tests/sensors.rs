//! The MuJoCo plant's sensors are stride-sim's models fed with MuJoCo's motion (needs `--features mujoco`).
#![cfg(feature = "mujoco")]

mod common;

use std::sync::Arc;

use common::*;
use nalgebra::Vector3;
use stride_model::{KinDyn, Model};
use stride_sim::{SensorConfig, SimInput};

/// Exact sensors delayed by 3 steps: every encoder, IMU and FT reading is the truth of 3 steps before,
/// bit for bit (the truth being the plant's state and its noise-free FT wrenches).
#[test]
fn readings_are_the_truth_delayed_by_the_configured_steps() {
    let urdf = humanoid_urdf();
    let model = Arc::new(Model::from_urdf_file(&urdf).expect("humanoid"));
    let mut sim = ideal_sim(10000.0, 200.0);
    sim.sensors.delay_steps = 3;
    sim.sensors.encoder.velocity_source = stride_sim::VelocitySource::Truth;
    let mut plant = plant(&model, &urdf, &sim, ["l_sole", "r_sole"]);
    let q = crouch(&model);
    plant
        .set_initial_state(&standing(&model, &q))
        .expect("state");
    let mut history = vec![plant.output().clone()];
    for _ in 0..200 {
        history.push(plant.step(&SimInput::hold(&q)).expect("step").clone());
    }
    for k in 3..history.len() {
        let (now, then) = (&history[k], &history[k - 3]);
        assert_eq!(now.joint_positions, then.state.joint_positions);
        assert_eq!(now.joint_velocities, then.state.joint_velocities);
        assert_eq!(now.ft_wrenches, then.ft_wrenches_truth);
    }
}

/// The default (realistic) sensors standing still: encoders on the 4096-count grid within half a count of
/// the truth, the IMU reads gravity in its frame (within its bias, noise and tilt error), and the foot
/// sensors' forces are the measured truth within their offsets and noise.
#[test]
fn realistic_sensors_read_the_standing_robot() {
    let urdf = humanoid_urdf();
    let model = Arc::new(Model::from_urdf_file(&urdf).expect("humanoid"));
    let mut sim = ideal_sim(10000.0, 200.0);
    sim.sensors = SensorConfig::default();
    let mut plant = plant(&model, &urdf, &sim, ["l_sole", "r_sole"]);
    let q = crouch(&model);
    plant
        .set_initial_state(&standing(&model, &q))
        .expect("state");
    for _ in 0..2000 {
        plant.step(&SimInput::hold(&q)).expect("step");
    }
    let out = plant.output();
    let step = std::f64::consts::TAU / 4096.0;
    for (j, &qj) in out.joint_positions.iter().enumerate() {
        let counts = qj / step;
        assert!(
            (counts - counts.round()).abs() < 1e-9,
            "joint {j} off the grid"
        );
        assert!(
            (qj - out.state.joint_positions[j]).abs() < 0.5 * step + 1e-3,
            "joint {j}"
        );
    }
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_state(&out.state).expect("state");
    let imu = model.frame_id("imu_frame").expect("imu");
    let g_imu = kd.frame_pose(imu).rotation.inverse() * Vector3::new(0.0, 0.0, 9.81);
    assert!(
        (out.imu.proper_acceleration - g_imu).norm() < 0.3,
        "{}",
        out.imu.proper_acceleration
    );
    for (m, t) in out.ft_wrenches.iter().zip(&out.ft_wrenches_truth) {
        let df = (m - t).fixed_rows::<3>(0).norm();
        assert!(
            df < 3.0_f64.sqrt() * 5.0 + 6.0 * 1.5 + 1.0,
            "force error {df} N"
        );
    }
}
