//! Sampling a plan (and stepping the block without a new goal) allocates nothing.

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Duration;

use common::*;
use stride_block::Block;
use stride_planner::{Goal, PlanSample, Planner, PlannerConfig, PlannerInput};

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
fn sampling_and_stepping_do_not_allocate() {
    let cfg = PlannerConfig::default();
    let (l, r) = standing(0.0, 0.0, 0.0, cfg.nominal_width);
    let mut planner = Planner::new(cfg).unwrap();
    let goal = Goal::Waypoints {
        points: vec![
            stride_planner::Waypoint {
                x: 1.0,
                y: 0.0,
                yaw: None,
            },
            stride_planner::Waypoint {
                x: 1.5,
                y: 0.5,
                yaw: Some(1.0),
            },
        ],
    };
    let mut input = PlannerInput {
        time: Duration::ZERO,
        goal: Some(goal),
        left_sole: l,
        right_sole: r,
    };
    planner.step(&input).unwrap();
    input.goal = None;
    let mut out = PlanSample::default();
    let end = planner.plan().unwrap().end_time;
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    let mut k = 0u64;
    let mut checksum = 0.0;
    while (k as f64) * 0.01 < end + 2.0 {
        let t = k as f64 * 0.01;
        planner.sample(t, &mut out).unwrap();
        checksum += out.dcm_position.x + out.support_polygon.len as f64;
        input.time = Duration::from_millis(10 * k);
        let o = planner.step(&input).unwrap();
        checksum += o.com_position.y;
        k += 1;
    }
    let after = ALLOCATIONS.load(Ordering::SeqCst);
    assert!(checksum.is_finite());
    assert!(k > 1000);
    assert_eq!(
        after - before,
        0,
        "sampling allocated {} times",
        after - before
    );
}
