//! The loop allocates nothing per tick in steady state, with and without the MCAP log: runs that differ
//! only in duration make the same number of allocations on the loop thread, give or take a few one-off
//! ones (the writer thread's own allocations, e.g. chunk compression, are not counted).
mod common;

use common::Scratch;
use stride_runner::config::{PlantKind, Scenario};
use stride_runner::run::{run_scenario, RunOptions};

#[global_allocator]
static ALLOC: stride_testkit::CountingAllocator = stride_testkit::CountingAllocator::new();

/// Allocations made by this (the loop's) thread during a run of `duration` seconds.
fn allocations_for(
    s: &Scratch,
    sc: &Scenario,
    plant: PlantKind,
    duration: f64,
    log: bool,
) -> usize {
    let options = RunOptions {
        duration: Some(duration),
        plant: Some(plant),
        no_log: !log,
        output: Some(s.path(&format!("alloc-{duration}.mcap"))),
        ..RunOptions::default()
    };
    ALLOC
        .allocations_during(|| run_scenario(sc, &options).unwrap())
        .1
}

/// Asserts that the scenario `top` on the simulator makes the same number of allocations (±5) in 1.5 s and
/// in 1.5 + `extra_seconds` s.
fn assert_steady_on_simulator(s: &Scratch, top: &std::path::Path, extra_seconds: f64, what: &str) {
    let sc = Scenario::load(top).unwrap();
    let short = allocations_for(s, &sc, PlantKind::Simulator, 1.5, false);
    let long = allocations_for(s, &sc, PlantKind::Simulator, 1.5 + extra_seconds, false);
    assert!(
        long.abs_diff(short) <= 5,
        "{what}: {short} allocations in 1.5 s, {long} in {} s",
        1.5 + extra_seconds
    );
}

#[test]
fn steady_state_ticks_do_not_allocate() {
    let s = Scratch::new("alloc");
    s.write("r.toml", &common::robot_section());
    // Standing: no phase-change events in the measured window.
    let top = s.write(
        "s.toml",
        "include = [\"r.toml\"]\n[goal.stand]\n[end]\nstop_at_goal = false\n",
    );
    let sc = Scenario::load(&top).unwrap();
    let extra_seconds = 4.5;
    let wbc_ticks = (extra_seconds * f64::from(sc.config.rates.wbc_hz)) as usize;
    // The ideal plant (ground truth) and the simulator with the estimation layer in the loop.
    for (plant, log) in [
        (PlantKind::Ideal, false),
        (PlantKind::Ideal, true),
        (PlantKind::Simulator, false),
        (PlantKind::Simulator, true),
    ] {
        let short = allocations_for(&s, &sc, plant, 1.5, log);
        let long = allocations_for(&s, &sc, plant, 1.5 + extra_seconds, log);
        // one allocation per tick would be thousands; a few one-off ones (e.g. a summary string whose
        // length depends on the run) are allowed
        assert!(
            long.abs_diff(short) <= 5,
            "{plant:?}, log {log}: {short} allocations in 1.5 s, {long} in {} s ({wbc_ticks} extra whole-body ticks)",
            1.5 + extra_seconds
        );
    } // position control with the foot admittance (`simplified.foot_admittance`) in the whole-body tick
    let admittance = s.write(
        "a.toml",
        "include = [\"s.toml\"]\n[simplified.foot_admittance]\nenabled = true\n",
    );
    assert_steady_on_simulator(&s, &admittance, extra_seconds, "foot admittance");
    // position control with the interpolated command (`wbc.position_command`) at every plant step
    let interpolated = s.write(
        "i.toml",
        "include = [\"s.toml\"]\n[wbc]\nposition_command = \"interpolate\"\n",
    );
    assert_steady_on_simulator(&s, &interpolated, extra_seconds, "interpolated command");
    // torque control with the push response (`simplified.push`: momentum observer, plan clock) under a
    // push in the measured window
    let push = s.write(
        "p.toml",
        "include = [\"s.toml\"]\n[scenario]\ncontrol_mode = \"torque\"\n[simplified.push]\nenabled = true\n\
         [[sim.pushes]]\nframe = \"chest\"\nstart = 2.0\nduration = 1.0\nwrench = [0.0, 15.0, 0.0, 0.0, 0.0, 0.0]\n",
    );
    assert_steady_on_simulator(&s, &push, extra_seconds, "push response");
    // the same with the hold ended for a step (`simplified.push.step_out`: the pushed capture point
    // against the support polygon at every simplified tick)
    let step_out = s.write(
        "po.toml",
        "include = [\"p.toml\"]\n[simplified.push]\nstep_out = true\n",
    );
    assert_steady_on_simulator(&s, &step_out, extra_seconds, "push response, step out");
    // the TSID's weights switched while the push lasts (`simplified.push.wbc_com_weight`,
    // `wbc_upright_weight`; on at the push, off after it, both inside the measured window)
    let weights = s.write(
        "w.toml",
        "include = [\"p.toml\"]\n[simplified.push]\nwbc_force = 5.0\nwbc_com_weight = 10.0\n\
         wbc_upright_weight = 500.0\n[[wbc.tsid.tasks]]\ntype = \"com\"\nname = \"com\"\nkp = 25.0\n\
         kd = 5.0\npriority = \"soft\"\nweight = 100.0\n",
    );
    assert_steady_on_simulator(&s, &weights, extra_seconds, "push weights");
    // torque control with the actuator compensation (`wbc.tsid.actuators`: the lead, the friction
    // feed-forward, the delay's prediction) on the simulator's default actuators
    let actuators = s.write(
        "c.toml",
        "include = [\"s.toml\"]\n[scenario]\ncontrol_mode = \"torque\"\n[wbc.tsid.actuators]\n\
         torque_bandwidth = 30.0\ncoulomb_friction = 0.1\ncommand_delay = 0.001\n",
    );
    assert_steady_on_simulator(&s, &actuators, extra_seconds, "actuator compensation");
    // a plant with inertias of its own (`[sim.model]`): the plant model's CoM and DCM for the summary
    let mismatch = s.write(
        "m.toml",
        "include = [\"s.toml\"]\n[sim.model]\nmass_scale = 1.1\n",
    );
    assert_steady_on_simulator(&s, &mismatch, extra_seconds, "plant model");
}
