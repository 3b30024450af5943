//! The loop allocates nothing per tick in steady state (ideal plant, no log): two runs that differ only
//! in duration differ by fewer allocations than whole-body ticks in the extra time.
mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicU64, Ordering};

use common::Scratch;
use stride_runner::config::{PlantKind, Scenario};
use stride_runner::run::{run_scenario, RunOptions};

struct Counting;
static ALLOCATIONS: AtomicU64 = AtomicU64::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations_for(sc: &Scenario, duration: f64) -> u64 {
    let options = RunOptions {
        duration: Some(duration),
        plant: Some(PlantKind::Ideal),
        no_log: true,
        ..RunOptions::default()
    };
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    run_scenario(sc, &options).unwrap();
    ALLOCATIONS.load(Ordering::Relaxed) - before
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
    let wbc_ticks = (1.0 * f64::from(sc.config.rates.wbc_hz)) as u64;
    assert!(
        long.saturating_sub(short) < wbc_ticks / 10,
        "{} allocations in 1 s of steady state ({wbc_ticks} whole-body ticks)",
        long.saturating_sub(short)
    );
}
