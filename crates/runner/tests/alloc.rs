//! The loop allocates nothing per tick in steady state (ideal plant, no log): two runs that differ only
//! in duration differ by fewer allocations than whole-body ticks in the extra time.
mod common;

use common::Scratch;
use stride_runner::config::{PlantKind, Scenario};
use stride_runner::run::{run_scenario, RunOptions};

#[global_allocator]
static ALLOC: stride_testkit::CountingAllocator = stride_testkit::CountingAllocator::new();

fn allocations_for(sc: &Scenario, duration: f64) -> usize {
    let options = RunOptions {
        duration: Some(duration),
        plant: Some(PlantKind::Ideal),
        no_log: true,
        ..RunOptions::default()
    };
    let before = ALLOC.allocations();
    run_scenario(sc, &options).unwrap();
    ALLOC.allocations() - before
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
    let short = allocations_for(&sc, 0.5);
    let long = allocations_for(&sc, 1.5);
    let wbc_ticks = (1.0 * f64::from(sc.config.rates.wbc_hz)) as usize;
    assert!(
        long.saturating_sub(short) < wbc_ticks / 10,
        "{} allocations in 1 s of steady state ({wbc_ticks} whole-body ticks)",
        long.saturating_sub(short)
    );
}
