//! `MujocoRobot::step` allocates nothing after start-up (counted with a global allocator; needs
//! `--features mujoco`).
#![cfg(feature = "mujoco")]

mod common;

use std::sync::Arc;

use common::*;
use stride_model::Model;
use stride_sim::{JointActuatorOverride, PushConfig, SensorConfig, SimInput};

#[global_allocator]
static ALLOC: stride_testkit::CountingAllocator = stride_testkit::CountingAllocator::new();

/// The realistic sensors, joint friction, a command delay, a push and a servo at its effort limit (the
/// elbow's 0.05 N·m cannot hold the forearm: steps taken again with it pinned) during the counted steps.
#[test]
fn stepping_does_not_allocate() {
    let urdf = humanoid_urdf();
    let model = Arc::new(Model::from_urdf_file(&urdf).expect("humanoid"));
    let mut sim = ideal_sim(10000.0, 200.0);
    sim.sensors = SensorConfig::default();
    sim.actuation.default.coulomb_friction = 0.1;
    sim.actuation.command_delay_steps = 2;
    sim.actuation.joints.push(JointActuatorOverride {
        name: "l_elbow".into(),
        mode: None,
        kp: None,
        kd: None,
        effort_limit: Some(0.05),
        damping: None,
        armature: None,
        coulomb_friction: None,
        torque_bandwidth: None,
    });
    sim.pushes.push(PushConfig {
        frame: "chest".into(),
        start: 0.1,
        duration: 0.1,
        wrench: [20.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    });
    let mut plant = plant(&model, &urdf, &sim, ["l_sole", "r_sole"]);
    let q = crouch(&model);
    plant
        .set_initial_state(&standing(&model, &q))
        .expect("state");
    let input = SimInput::hold(&q);
    let elbow = model.joint_index("l_elbow").expect("l_elbow");
    let mut saturated = 0;
    plant.step(&input).expect("first step");
    let (_, allocations) = ALLOC.allocations_during(|| {
        for _ in 0..1000 {
            saturated += usize::from(plant.step(&input).expect("step").saturated[elbow]);
        }
    });
    assert_eq!(allocations, 0, "{allocations} allocations in 1000 steps");
    assert!(
        saturated > 100,
        "the elbow saturated in {saturated} of 1000 steps"
    );
}
