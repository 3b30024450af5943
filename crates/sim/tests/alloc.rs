//! `step` allocates nothing after start-up (counted with a global allocator).
#![allow(clippy::field_reassign_with_default)]

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

use stride_block::Block;
use stride_sim::{IntegratorKind, PushConfig, SimConfig, SimInput, SimRobot};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

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
        config.integrator = integrator;
        config.momentum_projection = projection;
        if integrator == IntegratorKind::Explicit {
            config.rate_hz = 10_000;
            config.actuation.default.kp = 300.0;
            config.actuation.default.kd = 3.0;
        }
        config.sensors.noise.force = 0.5;
        config.sensors.noise.joint_position = 1e-4;
        config.pushes.push(PushConfig {
            frame: "chest".into(),
            start: 0.0,
            duration: 1.0,
            wrench: [20.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        });
        let mut sim = SimRobot::new(Arc::clone(&model), config).unwrap();
        sim.set_standing_on_ground(&q).unwrap();
        let mut input = SimInput::hold(&q);
        // Saturate one joint too.
        input.joint_positions[model.joint_index("l_elbow").unwrap()] = 1.5;
        for _ in 0..10 {
            sim.step(&input).unwrap();
        }
        let before = ALLOCATIONS.load(Ordering::SeqCst);
        for _ in 0..500 {
            sim.step(&input).unwrap();
        }
        let after = ALLOCATIONS.load(Ordering::SeqCst);
        assert_eq!(
            after - before,
            0,
            "{integrator:?}: {} allocations in 500 steps",
            after - before
        );
    }
}
