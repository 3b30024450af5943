//! The realistic sensors and actuators: statistics of each sensor on a still robot, quantisation, delays,
//! Coulomb friction, the torque lag and the six-axis force/torque sensors against the contact wrenches and the
//! model's inverse dynamics.

mod common;

use std::sync::Arc;

use nalgebra::{DVector, UnitQuaternion, Vector3, Vector6};
use stride_model::{ExternalWrench, KinDyn, Model, VelocityRepresentation};
use stride_sim::{
    ActuationMode, FtSensorConfig, ImuConfig, JointActuatorConfig, SimConfig, SimInput, SimOutput,
    SimRobot, VelocitySource,
};

/// Steps of the statistics tests (10 s at 2 kHz).
const SAMPLES: usize = 20_000;

fn standing(config: SimConfig) -> (SimRobot, SimInput) {
    let model = common::humanoid();
    let q = common::bent_knees(&model, 0.2);
    let mut sim = SimRobot::new(Arc::clone(&model), config, common::PERIOD).unwrap();
    sim.set_standing_on_ground(&q).unwrap();
    (sim, SimInput::hold(&q))
}

fn mean_std(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    let var = x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n;
    (mean, var.sqrt())
}

fn within(value: f64, expected: f64, relative: f64) -> bool {
    (value - expected).abs() <= relative * expected
}

#[test]
fn encoder_positions_are_quantised_to_the_exact_step_and_noise_has_its_sigma() {
    let mut config = common::ideal_config();
    config.sensors.encoder.counts_per_revolution = 4096;
    let (mut sim, input) = standing(config);
    let step = std::f64::consts::TAU / 4096.0;
    for _ in 0..200 {
        let out = sim.step(&input).unwrap();
        for (q, truth) in out.joint_positions.iter().zip(&out.state.joint_positions) {
            let counts = q / step;
            assert_eq!(counts, counts.round(), "{q} is not a multiple of the step");
            assert!((q - truth).abs() <= step / 2.0 + 1e-15);
        }
    }
    let mut config = common::ideal_config();
    config.sensors.encoder.position_noise = 1e-3;
    config.sensors.encoder.velocity_noise = 0.02;
    let (mut sim, input) = standing(config);
    let (mut dq, mut dv) = (Vec::new(), Vec::new());
    for _ in 0..SAMPLES / 10 {
        let out = sim.step(&input).unwrap();
        dq.extend(
            out.joint_positions
                .iter()
                .zip(&out.state.joint_positions)
                .map(|(a, b)| a - b),
        );
        dv.extend(
            out.joint_velocities
                .iter()
                .zip(&out.state.joint_velocities)
                .map(|(a, b)| a - b),
        );
    }
    let (m, s) = mean_std(&dq);
    assert!(
        m.abs() < 3e-5 && within(s, 1e-3, 0.03),
        "position noise mean {m}, σ {s}"
    );
    let (m, s) = mean_std(&dv);
    assert!(
        m.abs() < 6e-4 && within(s, 0.02, 0.03),
        "velocity noise mean {m}, σ {s}"
    );
}

/// A joint moving at a constant speed: the differenced, quantised, low-passed velocity settles on it, and
/// lags a ramp of the speed by `1/(2π f_c)`.
#[test]
fn the_differenced_velocity_follows_a_joint_with_the_filter_delay() {
    let mut config = common::ideal_config();
    config.sensors.encoder = Default::default();
    assert_eq!(
        config.sensors.encoder.velocity_source,
        VelocitySource::FilteredDifference
    );
    let (mut sim, mut input) = standing(config);
    let j = sim.model().joint_index("l_elbow").unwrap();
    let q0 = input.joint_positions[j];
    let dt = 0.0005;
    // A ramp of 0.4 rad/s for 1 s, followed by the servo.
    let mut lagged = Vec::new();
    for k in 1..=2000 {
        let t = k as f64 * dt;
        input.joint_positions[j] = q0 + 0.4 * t;
        input.joint_velocities[j] = 0.4;
        let out = sim.step(&input).unwrap();
        if k > 1000 {
            lagged.push(out.joint_velocities[j]);
        }
    }
    let (m, _) = mean_std(&lagged);
    assert!((m - 0.4).abs() < 0.01, "mean differenced velocity {m}");
    // The step response of the filter to the start of the ramp: 63 % of the speed after 1/(2π f_c).
    let mut config = common::ideal_config();
    config.sensors.encoder = Default::default();
    config.sensors.encoder.counts_per_revolution = 0;
    let (mut sim, mut input) = standing(config);
    let tau = 1.0 / (std::f64::consts::TAU * 10.0);
    let n = (tau / dt).round() as usize;
    let mut reading = 0.0;
    let mut truth = 0.0;
    for k in 1..=n {
        input.joint_positions[j] = q0 + 0.4 * k as f64 * dt;
        input.joint_velocities[j] = 0.4;
        let out = sim.step(&input).unwrap();
        reading = out.joint_velocities[j];
        truth = out.state.joint_velocities[j];
    }
    assert!(truth > 0.38, "the servo follows the ramp: {truth}");
    assert!(
        reading > 0.5 * truth && reading < 0.7 * truth,
        "filtered {reading} vs true {truth} after one time constant"
    );
}

#[test]
fn imu_biases_noise_and_orientation_error_have_their_statistics() {
    // A resting box: true angular velocity 0, proper acceleration +g.
    let model = common::box_model(20.0, 0.4, 0.3, 0.2);
    let mut config = common::box_config(0.4, 0.3, [2, 2]);
    config.sensors.imu = ImuConfig {
        gyro_bias_random_walk: 0.0,
        accel_bias_random_walk: 0.0,
        gyro_bias: 0.01,
        accel_bias: 0.1,
        ..ImuConfig::default()
    };
    config.sensors.seed = 3;
    let c = config.sensors.imu.clone();
    let mut sim = SimRobot::new(Arc::clone(&model), config, common::PERIOD).unwrap();
    let q = DVector::zeros(model.dof());
    sim.set_standing_on_ground(&q).unwrap();
    let input = SimInput::zeros(model.dof());
    for _ in 0..200 {
        sim.step(&input).unwrap();
    }
    let mut gyro = vec![Vec::new(); 3];
    let mut accel = vec![Vec::new(); 3];
    let mut errors = Vec::new();
    for _ in 0..SAMPLES {
        let out = sim.step(&input).unwrap();
        let truth = out.state.base_pose.rotation;
        let g_imu = truth.inverse_transform_vector(&Vector3::new(0.0, 0.0, 9.81));
        for k in 0..3 {
            gyro[k].push(out.imu.angular_velocity[k]);
            accel[k].push(out.imu.proper_acceleration[k] - g_imu[k]);
        }
        errors.push((
            out.time.as_secs_f64(),
            (out.imu.orientation * truth.inverse()).scaled_axis(),
        ));
    }
    let sigma_gyro = c.gyro_noise_density / common::PERIOD.as_secs_f64().sqrt();
    let sigma_accel = c.accel_noise_density / common::PERIOD.as_secs_f64().sqrt();
    let mut biases = Vec::new();
    for k in 0..3 {
        let (m, s) = mean_std(&gyro[k]);
        assert!(
            m.abs() <= c.gyro_bias + 4.0 * s / (SAMPLES as f64).sqrt(),
            "gyro bias {m}"
        );
        assert!(within(s, sigma_gyro, 0.03), "gyro σ {s} vs {sigma_gyro}");
        biases.push(m);
        let (m, s) = mean_std(&accel[k]);
        assert!(
            m.abs() <= c.accel_bias + 4.0 * s / (SAMPLES as f64).sqrt(),
            "accel bias {m}"
        );
        assert!(within(s, sigma_accel, 0.03), "accel σ {s} vs {sigma_accel}");
        biases.push(m);
    }
    // The biases are drawn (not all near zero).
    assert!(biases.iter().any(|b| b.abs() > 1e-3), "{biases:?}");
    // Orientation: constant tilt within its bound, yaw growing at a constant rate within its bound, noise σ.
    let fit = |axis: usize| {
        let (sx, sy, sxx, sxy) = errors.iter().fold((0.0, 0.0, 0.0, 0.0), |a, (t, e)| {
            (a.0 + t, a.1 + e[axis], a.2 + t * t, a.3 + t * e[axis])
        });
        let n = errors.len() as f64;
        let slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
        ((sy - slope * sx) / n, slope)
    };
    for axis in 0..2 {
        let (offset, slope) = fit(axis);
        assert!(offset.abs() <= c.tilt_error + 1e-4, "tilt {offset}");
        assert!(slope.abs() < 1e-5, "tilt drifts: {slope}");
    }
    let (offset, slope) = fit(2);
    assert!(offset.abs() < 1e-4, "initial yaw error {offset}");
    assert!(
        slope.abs() <= c.yaw_drift_rate * 1.01 && slope != 0.0,
        "yaw rate {slope}"
    );
    let residual: Vec<f64> = errors
        .iter()
        .map(|(t, e)| e[0] - fit(0).0 - fit(0).1 * t)
        .collect();
    let (_, s) = mean_std(&residual);
    assert!(within(s, c.orientation_noise, 0.03), "orientation σ {s}");
}

#[test]
fn bias_and_drift_random_walks_have_their_increments() {
    let model = common::box_model(20.0, 0.4, 0.3, 0.2);
    let mut config = common::box_config(0.4, 0.3, [2, 2]);
    config.sensors.imu = ImuConfig {
        gyro_bias_random_walk: 1e-3,
        ..ImuConfig::ideal()
    };
    let mut sim = SimRobot::new(Arc::clone(&model), config, common::PERIOD).unwrap();
    sim.set_standing_on_ground(&DVector::zeros(model.dof()))
        .unwrap();
    let input = SimInput::zeros(model.dof());
    for _ in 0..200 {
        sim.step(&input).unwrap();
    }
    let mut previous = sim.output().imu.angular_velocity;
    let mut increments = Vec::new();
    for _ in 0..SAMPLES {
        let w = sim.step(&input).unwrap().imu.angular_velocity;
        increments.extend((w - previous).iter());
        previous = w;
    }
    let (_, s) = mean_std(&increments);
    let expected = 1e-3 * common::PERIOD.as_secs_f64().sqrt();
    assert!(
        within(s, expected, 0.03),
        "bias increments σ {s} vs {expected}"
    );
}

fn sensor_index(model: &Model, name: &str) -> usize {
    model
        .ft_sensors()
        .iter()
        .position(|s| s.name == name)
        .unwrap()
}

#[test]
fn ft_offsets_drift_noise_and_saturation() {
    let mut config = common::ideal_config();
    config.sensors.ft = FtSensorConfig {
        force_drift: 0.0,
        torque_drift: 0.0,
        ..FtSensorConfig::default()
    };
    let c = config.sensors.ft.clone();
    let (mut sim, input) = standing(config);
    let n_ft = sim.model().ft_sensors().len();
    assert_eq!(n_ft, 4);
    let mut errors = vec![vec![Vec::new(); 6]; n_ft];
    for _ in 0..SAMPLES / 4 {
        let out = sim.step(&input).unwrap();
        for (i, (w, t)) in out
            .ft_wrenches
            .iter()
            .zip(&out.ft_wrenches_truth)
            .enumerate()
        {
            for k in 0..6 {
                errors[i][k].push(w[k] - t[k]);
            }
        }
    }
    let mut offsets = Vec::new();
    for sensor in &errors {
        for (k, e) in sensor.iter().enumerate() {
            let (bound, sigma) = if k < 3 {
                (c.force_offset, c.force_noise)
            } else {
                (c.torque_offset, c.torque_noise)
            };
            let (m, s) = mean_std(e);
            assert!(
                m.abs() <= bound + 4.0 * sigma / (e.len() as f64).sqrt(),
                "offset {m}"
            );
            assert!(within(s, sigma, 0.03), "noise σ {s} vs {sigma}");
            offsets.push(m / bound);
        }
    }
    // 24 offsets uniform on ±bound: spread over the range.
    let (_, spread) = mean_std(&offsets);
    assert!(
        spread > 0.4 && spread < 0.75,
        "offsets / bound: σ {spread} (uniform: 0.577)"
    );

    // Drift: a random walk with σ·√dt increments.
    let mut config = common::ideal_config();
    config.sensors.ft.force_drift = 0.5;
    let (mut sim, input) = standing(config);
    let error = |out: &SimOutput, i: usize| out.ft_wrenches[i][0] - out.ft_wrenches_truth[i][0];
    let mut previous: Vec<f64> = (0..n_ft).map(|i| error(sim.output(), i)).collect();
    let mut increments = Vec::new();
    for _ in 0..SAMPLES / 4 {
        let out = sim.step(&input).unwrap();
        for (i, p) in previous.iter_mut().enumerate() {
            let e = error(out, i);
            increments.push(e - *p);
            *p = e;
        }
    }
    let (_, s) = mean_std(&increments);
    let expected = 0.5 * common::PERIOD.as_secs_f64().sqrt();
    assert!(
        within(s, expected, 0.05),
        "drift increments σ {s} vs {expected}"
    );

    // Saturation: a foot sensor carrying ~160 N clamps at a 50 N full scale.
    let mut config = common::ideal_config();
    config.sensors.ft.force_range = [10.0, 10.0, 50.0];
    let (mut sim, input) = standing(config);
    let foot = sensor_index(sim.model(), "l_foot_ft_sensor");
    let out = sim.step(&input).unwrap();
    assert!(out.ft_wrenches_truth[foot][2].abs() > 100.0);
    assert_eq!(out.ft_wrenches[foot][2].abs(), 50.0);
}

/// Standing still: the foot sensor reads the ground wrench of its sole plus the weight of the foot below it,
/// the leg sensor the ground wrench plus the weight of the leg below it (masses from the bundled URDF).
#[test]
fn ft_sensors_standing_still_read_the_ground_wrench_plus_the_weight_below() {
    let (mut sim, input) = standing(common::ideal_config());
    for _ in 0..4000 {
        sim.step(&input).unwrap();
    }
    let out = sim.output().clone();
    let model = Arc::clone(sim.model());
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_representation(VelocityRepresentation::Mixed);
    kd.set_state(&out.state).unwrap();
    let g = model.gravity();
    // l_foot 0.7 kg; l_thigh 2.2 + l_lower_leg 1.7 + l_ankle_1 0.4 + l_ankle_2 0.15 + l_foot 0.7 kg.
    for (side, surface) in [("l", 0), ("r", 1)] {
        let ground = out.surfaces[surface].wrench;
        assert_eq!(
            out.surfaces[surface].name,
            if side == "l" { "left" } else { "right" }
        );
        for (sensor, mass) in [("foot", 0.7), ("leg", 5.15)] {
            let name = format!("{side}_{sensor}_ft_sensor");
            let i = sensor_index(&model, &name);
            let frame = model.ft_sensors()[i].frame;
            // child_to_parent: the wrench the part below applies on the part above.
            let reading = kd.frame_pose(frame).rotation * out.ft_wrenches[i].fixed_rows::<3>(0);
            let expected = ground.fixed_rows::<3>(0) + mass * g;
            assert!(
                (reading - expected).norm() < 0.05,
                "{name}: {reading} vs ground + weight {expected}"
            );
        }
    }
}

/// The noise-free reading of step k is the model's `ft_sensor_wrenches` at the state before the step, with the
/// step's acceleration `(ν_k − ν_{k−1}) / dt` and the contact forces applied at the points' start-of-step
/// positions; here with a push on the chest and the robot swaying.
#[test]
fn the_noise_free_reading_is_the_models_transmitted_wrench() {
    let mut config = SimConfig::default();
    config.pushes.push(stride_sim::PushConfig {
        frame: "chest".into(),
        start: 0.05,
        duration: 0.1,
        wrench: [30.0, -10.0, 0.0, 0.0, 1.0, 0.0],
    });
    let (mut sim, input) = standing(config);
    let model = Arc::clone(sim.model());
    let chest = model.frame_id("chest").unwrap();
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_representation(VelocityRepresentation::Mixed);
    let dt = common::PERIOD.as_secs_f64();
    let mut before: SimOutput = sim.output().clone();
    let mut expected = vec![Vector6::zeros(); model.ft_sensors().len()];
    let mut worst: f64 = 0.0;
    for k in 0..400 {
        let out = sim.step(&input).unwrap().clone();
        let mut nu_dot = DVector::zeros(model.nv());
        for i in 0..6 {
            nu_dot[i] = (out.state.base_velocity[i] - before.state.base_velocity[i]) / dt;
        }
        for j in 0..model.dof() {
            nu_dot[6 + j] = (out.state.joint_velocities[j] - before.state.joint_velocities[j]) / dt;
        }
        let mut external = Vec::new();
        for (surface, frame) in [(0, "l_sole"), (1, "r_sole")] {
            let f = model.frame_id(frame).unwrap();
            kd.set_state(&before.state).unwrap();
            let o = kd.frame_pose(f).translation.vector;
            let mut w = Vector6::zeros();
            for (p0, p1) in before.contact_points.iter().zip(&out.contact_points) {
                if p1.surface == surface {
                    let t = (p0.position - o).cross(&p1.force);
                    w += Vector6::new(p1.force.x, p1.force.y, p1.force.z, t.x, t.y, t.z);
                }
            }
            external.push(ExternalWrench {
                frame: f,
                wrench: w,
            });
        }
        let t = before.time.as_secs_f64();
        if (0.05..0.15).contains(&(t + 1e-9)) && t + 1e-9 < 0.15 {
            external.push(ExternalWrench {
                frame: chest,
                wrench: Vector6::new(30.0, -10.0, 0.0, 0.0, 1.0, 0.0),
            });
        }
        kd.set_state(&before.state).unwrap();
        kd.ft_sensor_wrenches(&nu_dot, &external, &mut expected)
            .unwrap();
        for (a, b) in out.ft_wrenches_truth.iter().zip(&expected) {
            let scale = 1.0 + b.norm();
            worst = worst.max((a - b).norm() / scale);
        }
        assert!(worst < 1e-6, "step {k}: relative difference {worst}");
        before = out;
    }
}

#[test]
fn sensor_and_command_delays_shift_everything_by_exactly_n_steps() {
    const N: usize = 3;
    let run = |sensor_delay: usize, command_delay: usize, late_inputs: bool| {
        let mut config = SimConfig::default();
        config.sensors.delay_steps = sensor_delay;
        config.actuation.command_delay_steps = command_delay;
        let (mut sim, hold) = standing(config);
        let j = sim.model().joint_index("l_shoulder_pitch").unwrap();
        let mut outputs = Vec::new();
        for k in 0..400usize {
            let mut input = hold.clone();
            // The undelayed run receives the commands N steps late itself (the hold posture before).
            let t = if late_inputs {
                k.checked_sub(N)
            } else {
                Some(k)
            };
            if let Some(t) = t {
                input.joint_positions[j] += 0.3 * (t as f64 * 0.01).sin();
            }
            outputs.push(sim.step(&input).unwrap().clone());
        }
        outputs
    };
    let undelayed = run(0, 0, false);
    let sensed_late = run(N, 0, false);
    for k in N..undelayed.len() {
        let (a, b) = (&sensed_late[k], &undelayed[k - N]);
        assert_eq!(a.joint_positions, b.joint_positions, "step {k}");
        assert_eq!(a.joint_velocities, b.joint_velocities);
        assert_eq!(a.imu, b.imu);
        assert_eq!(a.ft_wrenches, b.ft_wrenches);
        // Ground truth is not delayed.
        assert_eq!(a.state, undelayed[k].state);
    }
    let commanded_late = run(0, N, false);
    let fed_late = run(0, 0, true);
    for (a, b) in commanded_late.iter().zip(&fed_late) {
        assert_eq!(a.state, b.state);
        assert_eq!(a.joint_positions, b.joint_positions);
    }
    assert_ne!(commanded_late[200].state, undelayed[200].state);
}

/// A floating humanoid without gravity or ground: its elbow in torque mode, all other joints servoed.
fn floating_elbow(coulomb_friction: f64, torque_bandwidth: f64) -> (SimRobot, SimInput, usize) {
    let model = common::weightless(&common::humanoid());
    let mut config = common::ideal_config();
    config.contact.surfaces.clear();
    let mut sim = SimRobot::new(Arc::clone(&model), config, common::PERIOD).unwrap();
    let elbow = model.joint_index("l_elbow").unwrap();
    let q = common::bent_knees(&model, 0.2);
    let mut state = stride_model::RobotState::zero(&model);
    state.joint_positions.copy_from(&q);
    state.base_pose.rotation = UnitQuaternion::identity();
    sim.set_initial_state(&state).unwrap();
    let actuator = JointActuatorConfig {
        mode: ActuationMode::Torque,
        coulomb_friction,
        torque_bandwidth,
        ..JointActuatorConfig::ideal()
    };
    sim.set_joint_actuator("l_elbow", &actuator).unwrap();
    (sim, SimInput::hold(&q), elbow)
}

#[test]
fn coulomb_friction_holds_below_the_breakaway_torque_and_slides_above() {
    let tau_c = 0.5;
    for (command, moves) in [
        (0.8 * tau_c, false),
        (-0.95 * tau_c, false),
        (1.2 * tau_c, true),
    ] {
        let (mut sim, mut input, elbow) = floating_elbow(tau_c, 0.0);
        let q0 = sim.state().joint_positions[elbow];
        input.joint_torques[elbow] = command;
        let mut max_speed: f64 = 0.0;
        for _ in 0..2000 {
            let out = sim.step(&input).unwrap();
            max_speed = max_speed.max(out.state.joint_velocities[elbow].abs());
        }
        let moved = (sim.state().joint_positions[elbow] - q0).abs();
        if moves {
            assert!(moved > 0.05, "{command} N·m: moved only {moved} rad");
        } else {
            assert!(
                moved < 1e-6 && max_speed < 1e-6,
                "{command} N·m: moved {moved} rad, speed up to {max_speed} rad/s"
            );
        }
    }
    // Sliding back to rest: released at speed with no torque, the joint stops and stays stopped (no chatter).
    let (mut sim, mut input, elbow) = floating_elbow(tau_c, 0.0);
    input.joint_torques[elbow] = 2.0;
    for _ in 0..200 {
        sim.step(&input).unwrap();
    }
    input.joint_torques[elbow] = 0.0;
    let mut speeds = Vec::new();
    for _ in 0..2000 {
        speeds.push(sim.step(&input).unwrap().state.joint_velocities[elbow]);
    }
    assert!(speeds[0].abs() > 0.1);
    assert!(
        speeds[1000..].iter().all(|v| v.abs() < 1e-6),
        "still moving: {}",
        speeds[1999]
    );
}

#[test]
fn the_torque_lag_reaches_63_percent_after_one_time_constant() {
    let f = 20.0;
    let (mut sim, mut input, elbow) = floating_elbow(0.0, f);
    input.joint_torques[elbow] = 1.0;
    let dt = common::PERIOD.as_secs_f64();
    let tau = 1.0 / (std::f64::consts::TAU * f);
    let n = (tau / dt).round() as usize;
    let mut torques = Vec::new();
    for _ in 0..4 * n {
        torques.push(sim.step(&input).unwrap().joint_torques[elbow]);
    }
    let at_tau = torques[n - 1];
    let exact = 1.0 - (-(n as f64) * dt / tau).exp();
    assert!((at_tau - exact).abs() < 1e-12, "{at_tau} vs {exact}");
    assert!((at_tau - 0.632).abs() < 0.02, "{at_tau} after {n} steps");
    assert!(torques.windows(2).all(|w| w[1] > w[0]));
    // Ideal tracking with bandwidth 0.
    let (mut sim, mut input, elbow) = floating_elbow(0.0, 0.0);
    input.joint_torques[elbow] = 1.0;
    assert_eq!(sim.step(&input).unwrap().joint_torques[elbow], 1.0);
}
