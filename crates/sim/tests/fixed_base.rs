//! `fixed_base = true` (a robot held on a pole): the base stays where it starts and the joints follow the
//! fixed-base dynamics, checked against stride-model's inverse dynamics (RNEA) and articulated-body
//! algorithm (ABA) with the pole's wrench.

mod common;

use std::sync::Arc;

use nalgebra::{DVector, Isometry3, Translation3, UnitQuaternion};
use stride_model::{ExternalWrench, KinDyn, RobotState};
use stride_sim::{IntegratorKind, SimConfig, SimInput, SimRobot};

fn pole_config() -> SimConfig {
    let mut config = common::ideal_config();
    config.fixed_base = true;
    config.contact.surfaces.clear();
    config
}

fn pole_state(model: &stride_model::Model) -> RobotState {
    let mut state = RobotState::zero(model);
    state.base_pose = Isometry3::from_parts(
        Translation3::new(0.1, -0.2, 1.2),
        UnitQuaternion::from_euler_angles(0.2, -0.1, 0.4),
    );
    state.joint_positions = common::bent_knees(model, 0.3);
    state
}

/// Position servo references that swing every joint by up to 0.4 rad about `q0`, a different phase each.
fn swing(q0: &DVector<f64>, step: usize) -> SimInput {
    let mut input = SimInput::hold(q0);
    for j in 0..q0.len() {
        input.joint_positions[j] += 0.4 * ((0.7 * j as f64) + 0.004 * step as f64).sin();
    }
    input
}

#[test]
fn the_base_stays_put_and_the_joints_follow_the_fixed_base_dynamics() {
    let model = common::humanoid();
    let mut sim = SimRobot::new(Arc::clone(&model), pole_config(), common::PERIOD).unwrap();
    let start = pole_state(&model);
    sim.set_initial_state(&start).unwrap();
    let mut kd = KinDyn::new(Arc::clone(&model));
    let n = model.dof();
    let dt = sim.period();
    let (mut worst_rnea, mut worst_aba, mut moved) = (0.0f64, 0.0f64, 0.0f64);
    let mut rnea = DVector::zeros(model.nv());
    let mut aba = DVector::zeros(model.nv());
    for step in 0..2000 {
        let before = sim.state().clone();
        sim.step(&swing(&start.joint_positions, step)).unwrap();
        let after = sim.state();
        // The base: not moved, no velocity.
        let d = before.base_pose.inverse() * after.base_pose;
        moved = moved
            .max(d.translation.vector.norm())
            .max(d.rotation.angle())
            .max(after.base_velocity.norm());
        // q̈ of the step (semi-implicit Euler: q̇⁺ = q̇ + dt q̈), at the start-of-step state.
        let mut nu_dot = DVector::zeros(model.nv());
        for j in 0..n {
            nu_dot[6 + j] = (after.joint_velocities[j] - before.joint_velocities[j]) / dt;
        }
        kd.set_state(&before).unwrap();
        // RNEA: the joint rows are the motor torques (ideal actuators: no friction, damping or armature);
        // the base rows are what the pole applies.
        kd.inverse_dynamics(&nu_dot, &[], &mut rnea).unwrap();
        let tau = &sim.output().joint_torques;
        for j in 0..n {
            worst_rnea = worst_rnea.max((rnea[6 + j] - tau[j]).abs());
        }
        // ABA of the floating robot with the pole's wrench on the base: the base does not accelerate and the
        // joints accelerate as simulated.
        let pole = ExternalWrench {
            frame: model.frame_id(model.root_link()).unwrap(),
            wrench: rnea.fixed_rows::<6>(0).into_owned(),
        };
        kd.forward_dynamics(tau, &[pole], &mut aba).unwrap();
        worst_aba = worst_aba.max((&aba - &nu_dot).amax());
    }
    assert_eq!(moved, 0.0, "the base moved");
    assert!(
        worst_rnea < 1e-8,
        "RNEA vs applied torques: {worst_rnea:.2e} N·m"
    );
    assert!(
        worst_aba < 1e-6,
        "ABA vs simulated accelerations: {worst_aba:.2e}"
    );
    // And the legs did swing.
    let swing = (&sim.state().joint_positions - &start.joint_positions).amax();
    assert!(swing > 0.1, "joints moved only {swing} rad");
}

#[test]
fn a_free_base_moves_under_the_same_commands() {
    // The other side of the option: without it the same run moves the base.
    let model = common::humanoid();
    let mut config = pole_config();
    config.fixed_base = false;
    config.fall.min_base_height = -1e9;
    let mut sim = SimRobot::new(Arc::clone(&model), config, common::PERIOD).unwrap();
    let start = pole_state(&model);
    sim.set_initial_state(&start).unwrap();
    for step in 0..200 {
        sim.step(&swing(&start.joint_positions, step)).unwrap();
    }
    let d = start.base_pose.translation.vector - sim.state().base_pose.translation.vector;
    assert!(d.norm() > 0.01, "a free base falls: moved {} m", d.norm());
}

#[test]
fn fixed_base_needs_the_implicit_integrator() {
    let mut config = pole_config();
    config.integrator = IntegratorKind::Explicit;
    let err = config.validate().unwrap_err().to_string();
    assert!(err.contains("fixed_base"), "{err}");
}
