//! Bad input, divergence, effort limits, determinism, sensors and configuration files.
#![allow(clippy::field_reassign_with_default)]

mod common;

use std::sync::Arc;
use std::time::Duration;

use nalgebra::{DVector, Vector3};
use stride_block::Block;
use stride_model::RobotState;
use stride_sim::{
    ActuationMode, EffortLimitPolicy, IntegratorKind, JointActuatorOverride, PushConfig, SimConfig,
    SimError, SimInput, SimRobot,
};

fn standing_sim(config: SimConfig) -> (SimRobot, SimInput) {
    let model = common::humanoid();
    let q = common::bent_knees(&model, 0.2);
    let mut sim = SimRobot::new(Arc::clone(&model), config, common::PERIOD).unwrap();
    sim.set_standing_on_ground(&q).unwrap();
    (sim, SimInput::hold(&q))
}

fn bits(state: &RobotState) -> Vec<u64> {
    let mut v: Vec<u64> = state
        .base_pose
        .translation
        .vector
        .iter()
        .map(|x| x.to_bits())
        .collect();
    v.extend(state.base_pose.rotation.coords.iter().map(|x| x.to_bits()));
    v.extend(state.base_velocity.iter().map(|x| x.to_bits()));
    v.extend(state.joint_positions.iter().map(|x| x.to_bits()));
    v.extend(state.joint_velocities.iter().map(|x| x.to_bits()));
    v
}

#[test]
fn non_finite_commands_are_rejected_naming_the_joint_and_keep_the_state() {
    let (mut sim, input) = standing_sim(common::ideal_config());
    for _ in 0..10 {
        sim.step(&input).unwrap();
    }
    let before = bits(sim.state());
    let time = sim.time();
    let knee = sim.model().joint_index("l_knee").unwrap();
    for (which, value) in [(0, f64::NAN), (1, f64::INFINITY), (2, f64::NEG_INFINITY)] {
        let mut bad = input.clone();
        match which {
            0 => bad.joint_positions[knee] = value,
            1 => bad.joint_velocities[knee] = value,
            _ => bad.joint_torques[knee] = value,
        }
        let err = sim.step(&bad).unwrap_err();
        assert!(
            matches!(&err, SimError::NonFiniteCommand { joint, .. } if joint == "l_knee"),
            "{err}"
        );
        assert!(err.to_string().contains("l_knee"));
        assert_eq!(bits(sim.state()), before);
        assert_eq!(sim.time(), time);
    }
    let mut short = input.clone();
    short.joint_torques = DVector::zeros(3);
    assert!(matches!(sim.step(&short), Err(SimError::Dimension { .. })));
    // The simulation continues normally afterwards.
    sim.step(&input).unwrap();
    assert!(sim.time() > time);
}

#[test]
fn effort_limits_saturate_and_are_reported_or_fail_by_policy() {
    let (mut sim, mut input) = standing_sim(common::ideal_config());
    let elbow = sim.model().joint_index("l_elbow").unwrap();
    let limit = sim.model().joints()[elbow].effort_limit;
    input.joint_positions[elbow] = 1.5; // kp · 1.5 rad = 1500 N·m ≫ 20 N·m
    let model = Arc::clone(sim.model());
    let out = sim.step(&input).unwrap();
    assert!(out.saturated[elbow]);
    assert_eq!(out.joint_torques[elbow], limit);
    for (j, s) in out.saturated.iter().enumerate() {
        let limit = model.joints()[j].effort_limit;
        assert!(out.joint_torques[j].abs() <= limit * (1.0 + 1e-12));
        // Reported saturated exactly when the torque sits at the limit.
        assert_eq!(
            *s,
            out.joint_torques[j].abs() == limit,
            "joint {}",
            model.joints()[j].name
        );
    }
    // A feed-forward torque beyond the limit with the `error` policy.
    let mut config = common::ideal_config();
    config.actuation.effort_limit_policy = EffortLimitPolicy::Error;
    let (mut sim, mut input) = standing_sim(config);
    let before = bits(sim.state());
    input.joint_torques[elbow] = 2.0 * limit;
    let err = sim.step(&input).unwrap_err();
    assert!(
        matches!(&err, SimError::EffortLimit { joint, .. } if joint == "l_elbow"),
        "{err}"
    );
    assert_eq!(bits(sim.state()), before);
}

#[test]
fn divergence_is_reported_and_the_last_good_state_kept() {
    // Explicit integration of a 1e6 N·m/rad servo at 2 kHz is unstable.
    let mut config = common::ideal_config();
    config.integrator = IntegratorKind::Explicit;
    config.actuation.default.kp = 1e6;
    config.actuation.default.kd = 0.0;
    config.actuation.default.effort_limit = Some(1e9);
    let (mut sim, mut input) = standing_sim(config);
    input.joint_positions[0] += 0.01;
    let mut last_good = bits(sim.state());
    let mut failure = None;
    for k in 0..2000 {
        match sim.step(&input) {
            Ok(_) => last_good = bits(sim.state()),
            Err(e) => {
                failure = Some((k, e));
                break;
            }
        }
    }
    let (k, err) = failure.expect("the unstable servo must diverge");
    println!("diverged at step {k}: {err}");
    assert!(matches!(err, SimError::Diverged { .. }), "{err}");
    assert_eq!(bits(sim.state()), last_good);
    assert!(sim.state().joint_velocities.iter().all(|v| v.is_finite()));
    // The same step fails again (the state was not advanced).
    assert!(sim.step(&input).is_err());
}

#[test]
fn bad_configurations_are_rejected_with_the_parameter() {
    let model = common::humanoid();
    assert!(
        matches!(SimRobot::new(Arc::clone(&model), common::ideal_config(), Duration::ZERO), Err(SimError::InvalidConfig { parameter, .. }) if parameter == "period")
    );
    let mut c = common::ideal_config();
    c.contact.surfaces[0].frame = "no_such_frame".into();
    let err = SimRobot::new(Arc::clone(&model), c, common::PERIOD).unwrap_err();
    assert!(err.to_string().contains("no_such_frame"), "{err}");
    let mut c = common::ideal_config();
    c.actuation
        .joints
        .push(common::torque_mode("no_such_joint"));
    assert!(matches!(
        SimRobot::new(Arc::clone(&model), c, common::PERIOD),
        Err(SimError::UnknownJoint { .. })
    ));
    let mut c = common::ideal_config();
    c.contact.normal_stiffness = f64::NAN;
    assert!(matches!(
        SimRobot::new(Arc::clone(&model), c, common::PERIOD),
        Err(SimError::InvalidConfig { .. })
    ));
    let mut c = common::ideal_config();
    c.pushes.push(PushConfig {
        frame: "nowhere".into(),
        start: 0.0,
        duration: 1.0,
        wrench: [0.0; 6],
    });
    assert!(matches!(
        SimRobot::new(Arc::clone(&model), c, common::PERIOD),
        Err(SimError::UnknownFrame { .. })
    ));
    // A non-finite state.
    let mut sim =
        SimRobot::new(Arc::clone(&model), common::ideal_config(), common::PERIOD).unwrap();
    let mut s = RobotState::zero(&model);
    s.joint_velocities[2] = f64::NAN;
    assert!(matches!(
        sim.set_state(&s),
        Err(SimError::NonFiniteState { .. })
    ));
}

#[test]
fn configs_parse_from_toml_and_reject_unknown_fields() {
    let c: SimConfig = toml::from_str(
        r#"
momentum_projection = true
[ground]
inclination = [0.0, 0.1]
[contact]
friction_coefficient = 1.0
[[contact.surfaces]]
name = "left"
frame = "l_sole"
[actuation.default]
kp = 500.0
[[actuation.joints]]
name = "l_knee"
mode = "torque"
[[pushes]]
frame = "root_link"
start = 1.0
duration = 0.1
wrench = [50.0, 0.0, 0.0, 0.0, 0.0, 0.0]
"#,
    )
    .unwrap();
    assert!(c.momentum_projection);
    assert_eq!(c.contact.surfaces.len(), 1);
    assert_eq!(c.contact.surfaces[0].length, 0.20);
    assert_eq!(c.actuation.joints[0].mode, Some(ActuationMode::Torque));
    SimRobot::new(common::humanoid(), c, common::PERIOD).unwrap();
    assert!(toml::from_str::<SimConfig>("momentum_projection = true\ntypo = 1").is_err());
    assert!(toml::from_str::<SimConfig>("[contact]\nstiffness = 1.0").is_err());
    let default = SimConfig::default();
    let text = toml::to_string(&default).unwrap();
    assert_eq!(toml::from_str::<SimConfig>(&text).unwrap(), default);
}

#[test]
fn same_config_gives_bit_identical_trajectories() {
    let run = || {
        let mut config = SimConfig::default();
        config.sensors.seed = 42;
        config.sensors.encoder.position_noise = 1e-3;
        config.pushes.push(PushConfig {
            frame: "chest".into(),
            start: 0.05,
            duration: 0.1,
            wrench: [40.0, 10.0, 0.0, 0.0, 0.0, 0.0],
        });
        let (mut sim, input) = standing_sim(config);
        let mut trace = Vec::new();
        for _ in 0..1000 {
            let out = sim.step(&input).unwrap();
            trace.extend(bits(&out.state));
            trace.extend(out.joint_positions.iter().map(|x| x.to_bits()));
            trace.extend(out.joint_velocities.iter().map(|x| x.to_bits()));
            trace.extend(out.imu.angular_velocity.iter().map(|x| x.to_bits()));
            trace.extend(out.imu.orientation.coords.iter().map(|x| x.to_bits()));
            trace.extend(out.ft_wrenches.iter().flatten().map(|x| x.to_bits()));
            trace.extend(
                out.surfaces
                    .iter()
                    .flat_map(|s| s.sensor_wrench.iter().map(|x| x.to_bits())),
            );
        }
        trace
    };
    assert_eq!(run(), run());
}

#[test]
fn reset_returns_to_the_initial_state() {
    let (mut sim, input) = standing_sim(SimConfig::default());
    let initial = bits(sim.state());
    let first = sim.step(&input).unwrap().clone();
    for _ in 0..100 {
        sim.step(&input).unwrap();
    }
    sim.reset();
    assert_eq!(bits(sim.state()), initial);
    assert_eq!(sim.time().as_nanos(), 0);
    assert_eq!(*sim.step(&input).unwrap(), first);
}

#[test]
fn foot_sensors_measure_the_weight_upwards_in_their_frames_and_a_push_tips_the_robot() {
    let (mut sim, input) = standing_sim(common::ideal_config());
    for _ in 0..6000 {
        sim.step(&input).unwrap();
    }
    let out = sim.output().clone();
    let weight = sim.model().total_mass() * 9.81;
    for s in &out.surfaces {
        assert!(s.in_contact);
        // Symmetric stance: each foot carries half the weight; the sensor frames are upright.
        assert!(
            (s.sensor_wrench[2] - weight / 2.0).abs() < 0.01 * weight,
            "{}: {}",
            s.name,
            s.sensor_wrench
        );
        assert!((s.normal_force - weight / 2.0).abs() < 0.01 * weight);
    }
    // The IMU on the (slightly pitched) pelvis reads +g rotated into its frame.
    let expected = out
        .imu
        .orientation
        .inverse_transform_vector(&Vector3::new(0.0, 0.0, 9.81));
    assert!(
        (out.imu.proper_acceleration - expected).norm() < 0.02,
        "{} vs {}",
        out.imu.proper_acceleration,
        expected
    );
    assert!(!out.fallen);
    // A hard, long forward push on the chest makes it fall, and the fall is reported.
    sim.add_push(&PushConfig {
        frame: "chest".into(),
        start: 3.1,
        duration: 1.0,
        wrench: [300.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    })
    .unwrap();
    let mut fell = false;
    for _ in 0..8000 {
        match sim.step(&input) {
            Ok(out) if out.fallen => {
                fell = true;
                break;
            }
            Ok(_) => {}
            Err(e) => panic!("{e}"),
        }
    }
    assert!(fell, "a 300 N push for 1 s must tip the robot over");
}

#[test]
fn torque_mode_joint_is_limp() {
    let mut config = common::ideal_config();
    config.actuation.joints.push(JointActuatorOverride {
        name: "l_elbow".into(),
        mode: Some(ActuationMode::Torque),
        kp: None,
        kd: None,
        effort_limit: None,
        damping: Some(0.5),
        armature: None,
        coulomb_friction: None,
        torque_bandwidth: None,
    });
    let (mut sim, mut input) = standing_sim(config);
    let elbow = sim.model().joint_index("l_elbow").unwrap();
    // Position commands are ignored in torque mode; a positive torque flexes the elbow.
    input.joint_positions[elbow] = -1.0;
    input.joint_torques[elbow] = 2.0;
    for _ in 0..200 {
        sim.step(&input).unwrap();
    }
    assert!(
        sim.state().joint_positions[elbow] > 0.05,
        "{}",
        sim.state().joint_positions[elbow]
    );
    assert_eq!(sim.output().joint_torques[elbow], 2.0);
}

#[test]
fn velocity_servo_tracks_the_commanded_velocity() {
    let mut config = common::ideal_config();
    config.contact.surfaces.clear();
    config.fall.min_base_height = -1e9;
    config.actuation.default.mode = ActuationMode::Velocity;
    config.actuation.default.kd = 50.0;
    let model = common::weightless(&common::humanoid());
    let mut sim = SimRobot::new(Arc::clone(&model), config, common::PERIOD).unwrap();
    let elbow = model.joint_index("l_elbow").unwrap();
    let mut input = SimInput::zeros(model.dof());
    input.joint_velocities[elbow] = 0.5;
    input.joint_positions[elbow] = -3.0; // ignored in velocity mode
    for _ in 0..400 {
        sim.step(&input).unwrap();
    }
    let v = sim.state().joint_velocities[elbow];
    assert!((v - 0.5).abs() < 1e-3, "elbow velocity {v}");
    // The other joints are held at zero velocity.
    for (j, v) in sim.state().joint_velocities.iter().enumerate() {
        if j != elbow {
            assert!(v.abs() < 1e-2, "joint {j}: {v}");
        }
    }
}

#[test]
fn a_torque_mode_joint_commanded_beyond_its_limit_is_saturated_every_step_with_both_integrators() {
    for integrator in [IntegratorKind::Implicit, IntegratorKind::Explicit] {
        let mut config = common::ideal_config();
        let mut period = common::PERIOD;
        config.integrator = integrator;
        if integrator == IntegratorKind::Explicit {
            period = common::period(10_000);
            config.actuation.default.kp = 300.0;
            config.actuation.default.kd = 3.0;
        }
        config.actuation.joints.push(common::torque_mode("l_elbow"));
        let model = common::humanoid();
        let q = common::bent_knees(&model, 0.2);
        let mut sim = SimRobot::new(Arc::clone(&model), config, period).unwrap();
        sim.set_standing_on_ground(&q).unwrap();
        let mut input = SimInput::hold(&q);
        let elbow = model.joint_index("l_elbow").unwrap();
        let limit = model.joints()[elbow].effort_limit;
        assert!(limit.is_finite() && limit > 0.0);
        for (torque, steps) in [(-3.0 * limit, 50), (0.5 * limit, 5), (3.0 * limit, 50)] {
            input.joint_torques[elbow] = torque;
            for k in 0..steps {
                let out = sim.step(&input).unwrap();
                let beyond = torque.abs() > limit;
                assert_eq!(
                    out.saturated[elbow], beyond,
                    "{integrator:?}, {torque} N·m, step {k}"
                );
                let applied = if beyond {
                    limit.copysign(torque)
                } else {
                    torque
                };
                assert_eq!(out.joint_torques[elbow], applied, "{integrator:?} step {k}");
                // Every joint is flagged exactly when its torque sits at its limit.
                for (j, s) in out.saturated.iter().enumerate() {
                    let at_limit = out.joint_torques[j].abs() == model.joints()[j].effort_limit;
                    assert_eq!(*s, at_limit, "{integrator:?} joint {j} step {k}");
                }
            }
        }
    }
}

#[test]
fn a_position_servo_far_from_its_target_saturates_until_it_gets_close() {
    let (mut sim, mut input) = standing_sim(common::ideal_config());
    let model = Arc::clone(sim.model());
    let elbow = model.joint_index("l_elbow").unwrap();
    input.joint_positions[elbow] = 1.5; // kp · 1.5 rad = 1500 N·m ≫ 20 N·m
    let mut saturated_steps = 0;
    let mut last = true;
    for k in 0..4000 {
        let out = sim.step(&input).unwrap();
        if k == 0 {
            assert!(out.saturated[elbow]);
        }
        for (j, s) in out.saturated.iter().enumerate() {
            // Flagged exactly when the applied torque sits at the limit, at every step.
            let at_limit = out.joint_torques[j].abs() == model.joints()[j].effort_limit;
            assert_eq!(*s, at_limit, "joint {} step {k}", model.joints()[j].name);
        }
        saturated_steps += usize::from(out.saturated[elbow]);
        last = out.saturated[elbow];
    }
    assert!(saturated_steps > 1, "{saturated_steps}");
    // Near its target the servo needs less than its limit again.
    assert!(!last);
    let q = sim.state().joint_positions[elbow];
    assert!((q - 1.5).abs() < 0.05, "elbow at {q} rad");
}
