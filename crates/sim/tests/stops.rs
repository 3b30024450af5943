//! `joint_stops`: a joint driven past its URDF position limit meets its mechanical stop. The bundled
//! humanoid on a pole (fixed base, no gravity, ideal actuators, the other joints held by their servos): the
//! left elbow, in torque mode, driven by a
//! constant torque from mid-range towards its upper limit, comes to rest at the limit plus the stop's
//! static deflection `τ / k`, and its largest penetration stays under the energy bound of a spring that
//! absorbs the motor's work; without stops it runs past the limit. Stops need the implicit integrator.

mod common;

use std::sync::Arc;

use stride_model::RobotState;
use stride_sim::{IntegratorKind, JointStopsConfig, SimConfig, SimInput, SimRobot};

/// Torque on the elbow, N·m.
const TORQUE: f64 = 2.0;

struct Run {
    /// Largest `q − upper` over the run, rad.
    max_excess: f64,
    /// `q − upper` at the end, rad.
    final_excess: f64,
    /// `|q̇|` at the end, rad/s.
    final_speed: f64,
    /// `upper − q₀`, rad.
    travel: f64,
}

fn drive_the_elbow(stops: bool) -> Run {
    let model = common::weightless(&common::humanoid());
    let mut config: SimConfig = common::ideal_config();
    config.fixed_base = true;
    config.contact.surfaces.clear();
    // the other joints held at 0 by their servos, the elbow driven by torque alone
    config.actuation.joints.push(common::torque_mode("l_elbow"));
    config.joint_stops = JointStopsConfig {
        enabled: stops,
        ..JointStopsConfig::default()
    };
    let mut sim = SimRobot::new(Arc::clone(&model), config, common::PERIOD).unwrap();
    let elbow = model.joint_index("l_elbow").unwrap();
    let (lower, upper) = (model.joints()[elbow].lower, model.joints()[elbow].upper);
    let mut state = RobotState::zero(&model);
    state.joint_positions[elbow] = 0.5 * (lower + upper);
    sim.set_initial_state(&state).unwrap();
    let mut input = SimInput::zeros(model.dof());
    input.joint_torques[elbow] = TORQUE;
    let mut max_excess = f64::NEG_INFINITY;
    for _ in 0..4000 {
        sim.step(&input).unwrap();
        max_excess = max_excess.max(sim.state().joint_positions[elbow] - upper);
    }
    Run {
        max_excess,
        final_excess: sim.state().joint_positions[elbow] - upper,
        final_speed: sim.state().joint_velocities[elbow].abs(),
        travel: upper - state.joint_positions[elbow],
    }
}

#[test]
fn a_joint_driven_into_its_stop_rests_at_the_limit_and_runs_past_it_without_stops() {
    let stop = JointStopsConfig::default();
    let k = stop.stiffness;
    let run = drive_the_elbow(true);
    // at rest: the spring holds the motor, τ = k d
    let static_deflection = TORQUE / k;
    assert!(
        (run.final_excess - static_deflection).abs() < 0.05 * static_deflection,
        "rests {} rad past the limit, expected τ/k = {static_deflection}",
        run.final_excess
    );
    assert!(run.final_speed < 1e-3, "{} rad/s", run.final_speed);
    // the stop stores at most the motor's work: ½ k d² ≤ τ (travel + d) (the damper only takes energy)
    let bound = (TORQUE + (TORQUE * TORQUE + 2.0 * k * TORQUE * run.travel).sqrt()) / k;
    assert!(
        run.max_excess <= bound,
        "{} rad past the limit, the energy bound is {bound}",
        run.max_excess
    );
    // without stops nothing holds the joint: after 2 s of 2 N·m it is far past its limit
    let free = drive_the_elbow(false);
    assert!(free.final_excess > 1.0, "{}", free.final_excess);
}

#[test]
fn stop_parameters_out_of_range_are_rejected() {
    for (stiffness, damping, integrator, parameter) in [
        (
            0.0,
            100.0,
            IntegratorKind::Implicit,
            "joint_stops.stiffness",
        ),
        (
            f64::NAN,
            100.0,
            IntegratorKind::Implicit,
            "joint_stops.stiffness",
        ),
        (1e4, -1.0, IntegratorKind::Implicit, "joint_stops.damping"),
        (1e4, 100.0, IntegratorKind::Explicit, "joint_stops.enabled"),
    ] {
        let mut config = common::ideal_config();
        config.integrator = integrator;
        config.joint_stops = JointStopsConfig {
            enabled: true,
            stiffness,
            damping,
        };
        let err = SimRobot::new(common::humanoid(), config, common::PERIOD).unwrap_err();
        assert!(err.to_string().contains(parameter), "{err}");
    }
}
