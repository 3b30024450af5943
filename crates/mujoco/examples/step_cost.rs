//! Where the MuJoCo plant's time goes: the bundled humanoid, and the official iCub (iCubGazeboV2_7, when
//! `STRIDE_ICUB_MODELS_DIR` is set) on its two sole boxes, standing in their crouch on the position servos
//! of the scenarios with the default (realistic) sensors, 2 kHz. Prints the thread CPU time per step of
//! `MujocoRobot::step` and of MuJoCo's `mj_step` alone on the same model and state, and of the phases of
//! MuJoCo's forward dynamics on that state (each repeated on the frozen state: position-dependent terms
//! with collision detection and the constraint rows, velocity terms, actuation, unconstrained
//! acceleration, constraint solver; repeated on one state the solver's warm start differs from a real
//! step's, so their sum only approximates `mj_step`, which adds the `implicitfast` integration).
//!
//! `MUJOCO_DYNAMIC_LINK_DIR=$(bash tools/mujoco/setup.sh) cargo run --release -p stride-mujoco --features mujoco --example step_cost`

#[path = "../tests/common/mod.rs"]
mod common;

use std::path::Path;
use std::sync::Arc;

use common::*;
use mujoco_rs::prelude::*;
use nalgebra::DVector;
use std::time::Duration;
use stride_model::Model;
use stride_sim::{SensorConfig, SimInput};

/// CPU time of this thread (the machine is shared: wall-clock time would count waiting for a core).
fn cpu() -> Duration {
    stride_testkit::thread_cpu_time().expect("thread CPU time")
}

const STEPS: u32 = 20_000;

fn main() {
    let urdf = humanoid_urdf();
    let model = Arc::new(Model::from_urdf_file(&urdf).expect("humanoid"));
    let q = crouch(&model);
    for friction in [0.0, 0.1] {
        measure("bundled humanoid", &urdf, &model, &q, friction);
    }
    match stride_testkit::icub_model_urdf("step_cost", "iCubGazeboV2_7") {
        Some(urdf) => {
            let model = Arc::new(Model::from_urdf_file(&urdf).expect("iCub"));
            let q = icub_crouch(&model);
            for friction in [0.0, 0.1] {
                measure("iCubGazeboV2_7", &urdf, &model, &q, friction);
            }
        }
        None => println!("STRIDE_ICUB_MODELS_DIR not set: iCub not measured"),
    }
}

/// CPU time per call of `f` \[s\], over [`STEPS`] calls.
fn per_call(mut f: impl FnMut()) -> f64 {
    let t0 = cpu();
    for _ in 0..STEPS {
        f();
    }
    (cpu() - t0).as_secs_f64() / f64::from(STEPS)
}

/// One measurement with joint Coulomb friction `friction` N·m (MuJoCo `frictionloss`: one constraint row
/// per joint; the scenarios' `[sim.actuation]` default is 0.1).
fn measure(name: &str, urdf: &Path, model: &Arc<Model>, q: &DVector<f64>, friction: f64) {
    let mut sim = ideal_sim(10000.0, 200.0);
    sim.sensors = SensorConfig::default();
    sim.actuation.default.coulomb_friction = friction;
    let mut plant = plant(model, urdf, &sim, ["l_sole", "r_sole"]);
    plant.set_initial_state(&standing(model, q)).expect("state");
    let input = SimInput::hold(q);
    let total = per_call(|| {
        plant.step(&input).expect("step");
    });
    let mut raw = MjData::new(plant.mj_model());
    raw.qpos_mut().copy_from_slice(plant.mj_data().qpos());
    raw.qvel_mut().copy_from_slice(plant.mj_data().qvel());
    raw.ctrl_mut().copy_from_slice(plant.mj_data().ctrl());
    let mj = per_call(|| raw.step());
    let mut frozen = MjData::new(plant.mj_model());
    frozen.qpos_mut().copy_from_slice(raw.qpos());
    frozen.qvel_mut().copy_from_slice(raw.qvel());
    frozen.ctrl_mut().copy_from_slice(raw.ctrl());
    frozen.forward();
    // Collision first: `mj_collision` resets the arena, and the constraint rows are rebuilt by the last
    // `mj_fwdPosition` for the phases after it.
    let collision = per_call(|| frozen.collision());
    let position = per_call(|| frozen.fwd_position());
    let velocity = per_call(|| frozen.fwd_velocity());
    let actuation = per_call(|| frozen.fwd_actuation());
    let acceleration = per_call(|| frozen.fwd_acceleration());
    let constraint = per_call(|| frozen.fwd_constraint());
    let us = |s: f64| s * 1e6;
    println!(
        "{name}, friction {friction} N·m: MujocoRobot::step {:.1} µs = mj_step {:.1} µs + the rest {:.1} µs \
         ({} contacts, {} constraint rows); mj_step: position {:.1} µs (of which collision {:.1}), velocity \
         {:.1}, actuation {:.1}, acceleration {:.1}, constraint solver {:.1} (sum {:.1})",
        us(total),
        us(mj),
        us(total - mj),
        frozen.ncon(),
        frozen.nefc(),
        us(position),
        us(collision),
        us(velocity),
        us(actuation),
        us(acceleration),
        us(constraint),
        us(position + velocity + actuation + acceleration + constraint)
    );
}
