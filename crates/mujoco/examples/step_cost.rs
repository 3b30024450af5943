//! Where the MuJoCo plant's time goes: the bundled humanoid standing on the position servos of the
//! scenarios with the default (realistic) sensors, 2 kHz. Prints the thread CPU time per step of
//! `MujocoRobot::step` and of MuJoCo's `mj_step` alone on the same model and state.
//!
//! `MUJOCO_DYNAMIC_LINK_DIR=$(bash tools/mujoco/setup.sh) cargo run --release -p stride-mujoco --features mujoco --example step_cost`

#[path = "../tests/common/mod.rs"]
mod common;

use std::sync::Arc;

use common::*;
use mujoco_rs::prelude::*;
use std::time::Duration;
use stride_model::Model;
use stride_sim::{SensorConfig, SimInput};

/// CPU time of this thread (the machine is shared: wall-clock time would count waiting for a core).
fn cpu() -> Duration {
    stride_testkit::thread_cpu_time().expect("thread CPU time")
}

const STEPS: u32 = 20_000;

fn main() {
    for friction in [0.0, 0.1] {
        measure(friction);
    }
}

/// One measurement with joint Coulomb friction `friction` N·m (MuJoCo `frictionloss`: one constraint row
/// per joint; the scenarios' `[sim.actuation]` default is 0.1).
fn measure(friction: f64) {
    let urdf = humanoid_urdf();
    let model = Arc::new(Model::from_urdf_file(&urdf).expect("humanoid"));
    let mut sim = ideal_sim(10000.0, 200.0);
    sim.sensors = SensorConfig::default();
    sim.actuation.default.coulomb_friction = friction;
    let mut plant = plant(&model, &urdf, &sim, ["l_sole", "r_sole"]);
    let q = crouch(&model);
    plant
        .set_initial_state(&standing(&model, &q))
        .expect("state");
    let input = SimInput::hold(&q);
    let t0 = cpu();
    for _ in 0..STEPS {
        plant.step(&input).expect("step");
    }
    let total = (cpu() - t0).as_secs_f64() / f64::from(STEPS);
    let mut raw = MjData::new(plant.mj_model());
    raw.qpos_mut().copy_from_slice(plant.mj_data().qpos());
    raw.ctrl_mut().copy_from_slice(plant.mj_data().ctrl());
    let t0 = cpu();
    for _ in 0..STEPS {
        raw.step();
    }
    let mj = (cpu() - t0).as_secs_f64() / f64::from(STEPS);
    println!(
        "friction {friction} N·m: MujocoRobot::step {:.1} µs, mj_step {:.1} µs ({} contacts, {} constraint \
         rows), the rest {:.1} µs",
        total * 1e6,
        mj * 1e6,
        raw.ncon(),
        raw.nefc(),
        (total - mj) * 1e6
    );
}
