//! A saturated position servo on a light link (`stride_mujoco`'s `limits` module; needs `--features
//! mujoco`): with the limit applied on the step's force the torque stays at the limit and the link follows
//! the closed form of a constant torque; with MuJoCo's own start-of-step clamp it flips between the limits.
#![cfg(feature = "mujoco")]

mod common;

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::Duration;

use common::*;
use nalgebra::DVector;
use stride_model::{Model, RobotState};
use stride_mujoco::{MujocoConfig, MujocoRobot, PlantSetup, ServoSaturation};
use stride_sim::SimInput;

/// Effort limit of the hinge \[N·m\].
const LIMIT: f64 = 2.0;
/// The arm's inertia about the hinge, `izz + m d²` = 0.002 + 0.5 · 0.1² \[kg·m²\].
const ARM_INERTIA: f64 = 0.007;

/// A base with one hinge about z (gravity along the axis, so no gravity torque) driving a 0.5 kg arm whose
/// centre of mass is 0.1 m from the axis; two sole frames on the base (the plant needs them).
fn hinge_urdf() -> PathBuf {
    let text = format!(
        r#"<robot name="hinge">
  <link name="base"><inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <link name="arm"><inertial><origin xyz="0.1 0 0"/><mass value="0.5"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.002"/></inertial></link>
  <joint name="hinge" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit effort="{LIMIT}" lower="-3" upper="3" velocity="100"/></joint>
  <link name="l_sole"/><joint name="l_fixed" type="fixed"><parent link="base"/><child link="l_sole"/></joint>
  <link name="r_sole"/><joint name="r_fixed" type="fixed"><parent link="base"/><child link="r_sole"/></joint>
</robot>"#
    );
    // One file per call: the tests run in parallel threads of one process.
    static CALLS: AtomicUsize = AtomicUsize::new(0);
    let call = CALLS.fetch_add(1, Ordering::Relaxed);
    let path = std::env::temp_dir().join(format!(
        "stride_mujoco_hinge_{}_{call}.urdf",
        std::process::id()
    ));
    std::fs::write(&path, text).expect("write URDF");
    path
}

/// The hinge on a fixed base with the scenarios' position servo (kp 10⁴ N·m/rad, kd 200 N·m·s/rad, 2 kHz:
/// `kd dt / I` = 0.1 / 0.017 ≈ 5.9 with the 0.01 kg·m² minimum armature), starting at rest at 0.
fn hinge_plant(saturation: ServoSaturation) -> (MujocoRobot, Arc<Model>) {
    let urdf = hinge_urdf();
    let model = Arc::new(Model::from_urdf_file(&urdf).expect("hinge"));
    let mut sim = ideal_sim(10000.0, 200.0);
    sim.fixed_base = true;
    sim.contact.surfaces.clear();
    let mujoco = MujocoConfig {
        servo_saturation: saturation,
        ..MujocoConfig::default()
    };
    let mut plant = MujocoRobot::new(
        Arc::clone(&model),
        &PlantSetup {
            urdf: &urdf,
            sim: &sim,
            mujoco: &mujoco,
            soles: ["l_sole", "r_sole"],
            period: Duration::from_micros(500),
            inertias_from_model: false,
        },
    )
    .expect("MuJoCo plant");
    plant
        .set_initial_state(&RobotState::zero(&model))
        .expect("state");
    (plant, model)
}

/// The hinge's torque, angle and saturation flag over `steps` steps of the set-point `target` \[rad\].
fn step_response(saturation: ServoSaturation, target: f64, steps: usize) -> Vec<(f64, f64, bool)> {
    let (mut plant, _) = hinge_plant(saturation);
    let input = SimInput::hold(&DVector::from_element(1, target));
    (0..steps)
        .map(|_| {
            let out = plant.step(&input).expect("step");
            (
                out.joint_torques[0],
                out.state.joint_positions[0],
                out.saturated[0],
            )
        })
        .collect()
}

/// A 1 rad set-point (kp · 1 rad ≫ 2 N·m): applied on the step's force, the saturated servo pushes with
/// +2 N·m at every step and the arm follows semi-implicit Euler under a constant torque,
/// `q_k = L dt² k (k + 1) / (2 I)` with I the arm's inertia plus the 0.01 kg·m² armature, to 1e-9 rad over
/// 0.1 s.
#[test]
fn a_saturated_servo_pushes_with_its_limit_at_every_step() {
    let dt: f64 = 5e-4;
    let inertia = ARM_INERTIA + MujocoConfig::default().min_armature;
    for (k, (tau, q, saturated)) in step_response(ServoSaturation::AppliedForce, 1.0, 200)
        .into_iter()
        .enumerate()
    {
        let k = (k + 1) as f64;
        assert!(saturated, "step {k}: not saturated");
        assert_eq!(tau, LIMIT, "step {k}");
        let expected = LIMIT * dt * dt * k * (k + 1.0) / (2.0 * inertia);
        assert!(
            (q - expected).abs() < 1e-9,
            "step {k}: q {q}, expected {expected}"
        );
    }
}

/// Sign changes of the torque between two consecutive saturated steps.
fn flips(response: &[(f64, f64, bool)]) -> usize {
    response
        .windows(2)
        .filter(|w| w[0].2 && w[1].2 && w[0].0 * w[1].0 < 0.0)
        .count()
}

/// A 1 mrad set-point step: the servo's start-of-step force kp · 1 mrad = 10 N·m is beyond the 2 N·m limit
/// until the arm is within 0.2 mrad of its set-point. MuJoCo's own clamp of the start-of-step force leaves
/// the clamped servo's damping explicit: with `kd dt / I` ≈ 5.9 the torque flips between +2 and −2 N·m at
/// every one of the first 50 steps (the arm creeps: 29.4 µrad per two steps).
#[test]
fn mujocos_start_of_step_clamp_flips_the_torque_between_the_limits() {
    let response = step_response(ServoSaturation::StartOfStep, 1e-3, 50);
    assert!(response.iter().all(|r| r.2), "not saturated throughout");
    assert_eq!(flips(&response), 49);
}

/// The same step with the limit applied on the step's force: saturated at +2 N·m in the first step only
/// (the kick), then within the limits without a sign flip between saturated steps, and at its set-point within
/// 1e-5 rad after 0.1 s (the overdamped servo's slow pole kp/kd = 50 s⁻¹).
#[test]
fn the_servo_decided_on_the_applied_force_settles_without_flipping() {
    let response = step_response(ServoSaturation::AppliedForce, 1e-3, 200);
    assert_eq!((response[0].0, response[0].2), (LIMIT, true));
    for (k, (tau, _, saturated)) in response.iter().enumerate().skip(1) {
        assert!(!saturated && tau.abs() < LIMIT, "step {k}: torque {tau}");
    }
    let q_end = response.last().expect("steps").1;
    assert!((q_end - 1e-3).abs() < 1e-5, "q {q_end} rad");
}
