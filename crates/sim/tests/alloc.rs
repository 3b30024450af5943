//! `step` allocates nothing after start-up (counted with a global allocator).
#![allow(clippy::field_reassign_with_default)]

mod common;

use std::sync::Arc;

use stride_sim::{IntegratorKind, PushConfig, SimConfig, SimInput, SimRobot};

#[global_allocator]
static ALLOC: stride_testkit::CountingAllocator = stride_testkit::CountingAllocator::new();

#[test]
fn stepping_does_not_allocate() {
    let model = common::humanoid();
    let q = common::bent_knees(&model, 0.2);
    for (integrator, projection) in [
        (IntegratorKind::Implicit, false),
        (IntegratorKind::Explicit, false),
        (IntegratorKind::Implicit, true),
    ] {
        let mut config = SimConfig::default();
        let mut period = common::PERIOD;
        config.integrator = integrator;
        config.momentum_projection = projection;
        if integrator == IntegratorKind::Explicit {
            period = common::period(10_000);
            config.actuation.default.kp = 300.0;
            config.actuation.default.kd = 3.0;
        }
        // The default, realistic sensors and actuators (quantisation, filters, biases, force/torque sensors,
        // delays, friction), plus a torque-mode joint for the torque lag.
        config.actuation.joints.push(common::torque_mode("r_elbow"));
        config.pushes.push(PushConfig {
            frame: "chest".into(),
            start: 0.0,
            duration: 1.0,
            wrench: [20.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        });
        let mut sim = SimRobot::new(Arc::clone(&model), config, period).unwrap();
        sim.set_standing_on_ground(&q).unwrap();
        let mut input = SimInput::hold(&q);
        // Saturate one joint too.
        input.joint_positions[model.joint_index("l_elbow").unwrap()] = 1.5;
        for _ in 0..10 {
            sim.step(&input).unwrap();
        }
        // only this thread's allocations count (the test harness may allocate on its own threads)
        let (_, allocations) = ALLOC.allocations_during(|| {
            for _ in 0..500 {
                sim.step(&input).unwrap();
            }
        });
        assert_eq!(
            allocations, 0,
            "{integrator:?}: {allocations} allocations in 500 steps"
        );
    }
}
