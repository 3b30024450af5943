//! Sampling a plan (and stepping the block without a new goal) allocates nothing.

mod common;

use std::time::Duration;

use common::*;
use stride_planner::{Goal, PlanSample, Planner, PlannerConfig, PlannerInput};

#[global_allocator]
static ALLOC: stride_testkit::CountingAllocator = stride_testkit::CountingAllocator::new();

#[test]
fn sampling_and_stepping_do_not_allocate() {
    let cfg = PlannerConfig::default();
    let (l, r) = standing(0.0, 0.0, 0.0, cfg.nominal_width);
    let mut planner = Planner::new(cfg, GRAVITY).unwrap();
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
    let mut k = 0u64;
    let mut checksum = 0.0;
    // only this thread's allocations count (the test harness may allocate on its own threads)
    let (_, allocations) = ALLOC.allocations_during(|| {
        while (k as f64) * 0.01 < end + 2.0 {
            planner
                .sample(Duration::from_millis(10 * k), &mut out)
                .unwrap();
            checksum += out.dcm_position.x + out.support_polygon.map_or(0, |p| p.len()) as f64;
            input.time = Duration::from_millis(10 * k);
            let o = planner.step(&input).unwrap();
            checksum += o.com_position.y;
            k += 1;
        }
    });
    assert!(checksum.is_finite());
    assert!(k > 1000);
    assert_eq!(allocations, 0, "sampling allocated {allocations} times");
}
