//! Passive visco-elastic joints (`[sim.passive_joints]`, `τ = −k q − b q̇`, Romualdi 2022, eq. (9.1.1)):
//! an arm on a torsional spring, on a fixed base, against the closed forms of the damped oscillator
//! (frequency, decay, whole trajectory), the static deflection under gravity, and the energy balance.

mod common;

use std::sync::Arc;

use stride_model::{Model, RobotState};
use stride_sim::{ActuationMode, PassiveJointConfig, SimConfig, SimInput, SimRobot};

/// Arm mass (kg), distance of its centre of mass from the joint (m), its own inertia about the axis (kg·m²).
const MASS: f64 = 2.0;
const ARM: f64 = 0.3;
const OWN_INERTIA: f64 = 1e-3;
/// Spring stiffness, N·m/rad.
const K: f64 = 50.0;

/// Inertia of the arm about the joint axis, kg·m².
fn inertia() -> f64 {
    MASS * ARM * ARM + OWN_INERTIA
}

/// A fixed pole and an arm on the revolute joint `spring` about `axis` (the arm along +x).
fn arm_model(axis: &str) -> Arc<Model> {
    let urdf = format!(
        r#"<?xml version="1.0"?>
<robot name="spring_arm">
  <link name="pole">
    <inertial><origin xyz="0 0 0" rpy="0 0 0"/><mass value="5"/>
      <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
  </link>
  <link name="arm">
    <inertial><origin xyz="{ARM} 0 0" rpy="0 0 0"/><mass value="{MASS}"/>
      <inertia ixx="{OWN_INERTIA}" ixy="0" ixz="0" iyy="{OWN_INERTIA}" iyz="0" izz="{OWN_INERTIA}"/></inertial>
  </link>
  <joint name="spring" type="revolute">
    <origin xyz="0 0 1" rpy="0 0 0"/><parent link="pole"/><child link="arm"/>
    <axis xyz="{axis}"/><limit lower="-3" upper="3" velocity="100" effort="10"/>
  </joint>
</robot>"#
    );
    Arc::new(Model::from_urdf_str(&urdf).expect("spring arm URDF"))
}

/// The pole held still, the joint passive with `spring`, actuators in torque mode (ideal otherwise).
fn sim(model: &Arc<Model>, spring: PassiveJointConfig, rate_hz: u32, q0: f64) -> SimRobot {
    let mut config: SimConfig = common::ideal_config();
    config.fixed_base = true;
    config.contact.surfaces.clear();
    config.actuation.default.mode = ActuationMode::Torque;
    config.passive_joints.push(spring);
    let mut sim = SimRobot::new(Arc::clone(model), config, common::period(rate_hz)).unwrap();
    let mut state = RobotState::zero(model);
    state.joint_positions[0] = q0;
    sim.set_initial_state(&state).unwrap();
    sim
}

/// A command the passive joint must ignore: 100 N·m and a position reference far from zero.
fn ignored_command() -> SimInput {
    let mut input = SimInput::zeros(1);
    input.joint_torques[0] = 100.0;
    input.joint_positions[0] = 1.0;
    input
}

/// `θ(t)` of `I θ̈ + b θ̇ + k θ = 0` from `θ(0) = θ0`, `θ̇(0) = 0` (under-, critically or over-damped).
fn closed_form(k: f64, b: f64, i: f64, theta0: f64, t: f64) -> f64 {
    let wn = (k / i).sqrt();
    let zeta = b / (2.0 * (k * i).sqrt());
    if zeta < 1.0 {
        let wd = wn * (1.0 - zeta * zeta).sqrt();
        theta0 * (-zeta * wn * t).exp() * ((wd * t).cos() + zeta * wn / wd * (wd * t).sin())
    } else if zeta > 1.0 {
        let s = wn * (zeta * zeta - 1.0).sqrt();
        let (r1, r2) = (-zeta * wn + s, -zeta * wn - s);
        theta0 * (r2 * (r1 * t).exp() - r1 * (r2 * t).exp()) / (r2 - r1)
    } else {
        theta0 * (-wn * t).exp() * (1.0 + wn * t)
    }
}

/// Steps `sim` for `seconds` with the ignored command; the joint's (position, velocity) after each step.
fn run(sim: &mut SimRobot, seconds: f64) -> Vec<(f64, f64)> {
    let steps = (seconds / sim.period()).round() as usize;
    let input = ignored_command();
    (0..steps)
        .map(|_| {
            let s = sim.step(&input).unwrap();
            (s.state.joint_positions[0], s.state.joint_velocities[0])
        })
        .collect()
}

#[test]
fn damping_defaults_to_twice_the_square_root_of_the_stiffness() {
    let spring = PassiveJointConfig::with_default_damping(&["spring"], 400.0);
    assert_eq!(spring.damping(), 40.0);
    assert_eq!(spring.torque(0.01, -0.5), -400.0 * 0.01 + 40.0 * 0.5);
}

/// Horizontal swing (axis z: gravity does no work), light damping: the free vibration follows the closed
/// form; the damped period and the logarithmic decrement match `ω_d = ω_n √(1 − ζ²)` and `2π ζ / √(1 − ζ²)`.
#[test]
fn free_vibration_matches_the_damped_oscillator() {
    let model = arm_model("0 0 1");
    let (i, theta0) = (inertia(), 0.2);
    let b = 0.2 * (K * i).sqrt(); // ζ = 0.1
    let spring = PassiveJointConfig {
        joints: vec!["spring".into()],
        encoder: false,
        stiffness: K,
        damping: Some(b),
    };
    let mut sim = sim(&model, spring, 10_000, theta0);
    let dt = sim.period();
    let trace = run(&mut sim, 2.0);
    let worst = trace
        .iter()
        .enumerate()
        .map(|(n, &(q, _))| (q - closed_form(K, b, i, theta0, (n + 1) as f64 * dt)).abs())
        .fold(0.0, f64::max);
    assert!(worst < 0.01 * theta0, "trajectory error {worst} rad");
    // Peaks (velocity sign changes from + to −) give the damped period and the decrement.
    let peaks: Vec<(f64, f64)> = trace
        .windows(2)
        .enumerate()
        .filter(|(_, w)| w[0].1 > 0.0 && w[1].1 <= 0.0)
        .map(|(n, w)| ((n + 1) as f64 * dt, w[1].0))
        .collect();
    assert!(peaks.len() >= 3, "{} peaks", peaks.len());
    let zeta = 0.1;
    let wd = (K / i).sqrt() * (1.0f64 - zeta * zeta).sqrt();
    let period = (peaks[2].0 - peaks[0].0) / 2.0;
    let expected_period = std::f64::consts::TAU / wd;
    assert!(
        (period / expected_period - 1.0).abs() < 0.005,
        "period {period} s, closed form {expected_period} s"
    );
    let decrement = (peaks[0].1 / peaks[1].1).ln();
    let expected = std::f64::consts::TAU * zeta / (1.0f64 - zeta * zeta).sqrt();
    assert!(
        (decrement / expected - 1.0).abs() < 0.03,
        "log decrement {decrement}, closed form {expected}"
    );
}

/// The thesis's damping `b = 2√k` on this arm is over-damped (`ζ = 1/√I` > 1): no overshoot, and the
/// trajectory is the closed form's sum of two exponentials.
#[test]
fn default_damping_follows_the_overdamped_closed_form() {
    let model = arm_model("0 0 1");
    let (i, theta0) = (inertia(), 0.2);
    let spring = PassiveJointConfig::with_default_damping(&["spring"], K);
    let b = spring.damping();
    let mut sim = sim(&model, spring, 10_000, theta0);
    let dt = sim.period();
    let trace = run(&mut sim, 3.0);
    for (n, &(q, _)) in trace.iter().enumerate() {
        let expected = closed_form(K, b, i, theta0, (n + 1) as f64 * dt);
        assert!(
            (q - expected).abs() < 0.005 * theta0,
            "step {n}: {q} vs {expected}"
        );
        assert!(q > 0.0, "over-damped: no overshoot (step {n}: {q})");
    }
}

/// Arm horizontal under gravity, axis y: it settles where the spring holds the weight, `k θ = m g l cos θ`,
/// whatever torque and position the controllers command.
#[test]
fn static_deflection_under_gravity_balances_the_spring() {
    let model = arm_model("0 1 0");
    let spring = PassiveJointConfig::with_default_damping(&["spring"], K);
    let mut sim = sim(&model, spring, 2_000, 0.0);
    let trace = run(&mut sim, 8.0);
    let (q, v) = *trace.last().unwrap();
    let mgl = MASS * 9.81 * ARM;
    // Newton on k θ − m g l cos θ = 0.
    let mut theta = mgl / K;
    for _ in 0..20 {
        theta -= (K * theta - mgl * theta.cos()) / (K + mgl * theta.sin());
    }
    assert!(v.abs() < 1e-6, "settled: velocity {v}");
    // No encoder (the default): the reading is 0 whatever the deflection.
    assert_eq!(sim.output().joint_positions[0], 0.0);
    assert_eq!(sim.output().joint_velocities[0], 0.0);
    assert!(
        (q - theta).abs() < 1e-6,
        "deflection {q} rad, closed form {theta} rad"
    );
}

/// Energy `½ I θ̇² + ½ k θ²`: without damping it never grows and the linearly implicit scheme loses little
/// (< 3 % in 1 s at 10 kHz); with damping the loss equals the damper's work `∫ b θ̇² dt`.
#[test]
fn energy_is_kept_without_damping_and_dissipated_by_the_damper() {
    let model = arm_model("0 0 1");
    let i = inertia();
    let energy = |(q, v): (f64, f64)| 0.5 * i * v * v + 0.5 * K * q * q;
    let undamped = PassiveJointConfig {
        joints: vec!["spring".into()],
        encoder: false,
        stiffness: K,
        damping: Some(0.0),
    };
    let mut sim_free = sim(&model, undamped, 10_000, 0.2);
    let e0 = energy((0.2, 0.0));
    let mut previous = e0;
    for s in run(&mut sim_free, 1.0) {
        let e = energy(s);
        assert!(
            e <= previous * (1.0 + 1e-12),
            "energy grew: {previous} → {e}"
        );
        previous = e;
    }
    assert!(
        previous > 0.97 * e0,
        "lost {} % in 1 s",
        100.0 * (1.0 - previous / e0)
    );

    let b = 0.2 * (K * i).sqrt();
    let damped = PassiveJointConfig {
        joints: vec!["spring".into()],
        encoder: false,
        stiffness: K,
        damping: Some(b),
    };
    let mut sim_damped = sim(&model, damped, 10_000, 0.2);
    let dt = sim_damped.period();
    let trace = run(&mut sim_damped, 1.0);
    let work: f64 = trace.iter().map(|&(_, v)| b * v * v * dt).sum();
    let lost = e0 - energy(*trace.last().unwrap());
    assert!(
        (lost / work - 1.0).abs() < 0.05,
        "energy lost {lost} J, damper work {work} J"
    );
}

/// With `encoder = true` the deflection is read like any joint's (ideal encoders here).
#[test]
fn a_passive_joint_with_an_encoder_is_measured() {
    let model = arm_model("0 1 0");
    let spring = PassiveJointConfig {
        encoder: true,
        ..PassiveJointConfig::with_default_damping(&["spring"], K)
    };
    let mut sim = sim(&model, spring, 2_000, 0.0);
    run(&mut sim, 1.0);
    let q = sim.state().joint_positions[0];
    assert!(q > 0.05, "deflected: {q}");
    assert!((sim.output().joint_positions[0] - q).abs() < 1e-9);
}

#[test]
fn a_passive_joint_the_model_lacks_a_bad_stiffness_or_a_joint_listed_twice_is_refused() {
    let model = arm_model("0 0 1");
    let mut config = common::ideal_config();
    config.contact.surfaces.clear();
    let refused = |entries: Vec<PassiveJointConfig>| {
        let mut config = config.clone();
        config.passive_joints = entries;
        SimRobot::new(Arc::clone(&model), config, common::PERIOD)
            .unwrap_err()
            .to_string()
    };
    let err = refused(vec![PassiveJointConfig::with_default_damping(
        &["no_such_joint"],
        K,
    )]);
    assert!(err.contains("no_such_joint"), "{err}");
    let err = refused(vec![PassiveJointConfig::with_default_damping(
        &["spring"],
        -1.0,
    )]);
    assert!(err.contains("passive_joints[0].stiffness"), "{err}");
    let err = refused(vec![
        PassiveJointConfig::with_default_damping(&["spring"], K),
        PassiveJointConfig::with_default_damping(&["spring"], K),
    ]);
    assert!(
        err.contains("passive_joints[1].joints") && err.contains("already passive"),
        "{err}"
    );
    let err = refused(vec![PassiveJointConfig::with_default_damping(&[], K)]);
    assert!(err.contains("passive_joints[0].joints"), "{err}");
}
