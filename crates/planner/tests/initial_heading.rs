//! A start with a tiny heading error walks like a start without one, whatever its sign.
//!
//! The width constraint used to be measured in the right-sole frame only: with `min_width == nominal_width`
//! (the iCub configuration) every step of the left foot after a right turn was infeasible, so a start yawed
//! by +3e-6 rad (an estimated heading) made the unicycle crawl and the robot mark time for seconds, while
//! −3e-6 rad walked normally.

mod common;

use common::*;
use stride_planner::{plan_from_standing, Foot, Goal, Plan, PlanOutcome, PlannerConfig, Waypoint};

/// The planner part of `configs/robots/icub_v2_7.toml` (its `min_width` is the default, equal to
/// `nominal_width`).
fn icub() -> PlannerConfig {
    PlannerConfig {
        com_height: 0.5345,
        nominal_width: 0.14,
        foot_length: 0.11,
        feet_distance_max: 0.20,
        ..PlannerConfig::default()
    }
}

/// Soles at (0, ±w/2) with heading `yaw`, walking to 2.05 m straight ahead.
fn plan_with_heading(cfg: &PlannerConfig, yaw: f64) -> Plan {
    let h = 0.5 * cfg.nominal_width;
    let (l, r) = (sole(0.0, h, yaw), sole(0.0, -h, yaw));
    let goal = Goal::Pose {
        x: 2.05,
        y: 0.0,
        yaw: 0.0,
    };
    let plan = plan_from_standing(cfg, GRAVITY, 0.0, &l, &r, &goal).expect("plan");
    check_all(cfg, &plan, true);
    assert_eq!(plan.outcome, PlanOutcome::Complete, "yaw {yaw:e}");
    plan
}

/// The first touch-down: which foot, and how far it moved forward (x) from its standing pose.
fn first_step(plan: &Plan) -> (Foot, f64) {
    let advance = |contacts: &[stride_planner::PlannedContact]| {
        contacts.get(1).map(|c| {
            (
                c.activation_time,
                c.pose.translation.x - contacts[0].pose.translation.x,
            )
        })
    };
    let l = advance(&plan.left_contacts.contacts).expect("left steps");
    let r = advance(&plan.right_contacts.contacts).expect("right steps");
    if l.0 <= r.0 {
        (Foot::Left, l.1)
    } else {
        (Foot::Right, r.1)
    }
}

#[test]
fn small_initial_heading_walks_like_zero_heading() {
    let cfg = icub();
    let base = plan_with_heading(&cfg, 0.0);
    let (_, base_advance) = first_step(&base);
    // a full first step: the feet at feet_distance_max apart, √(l_max² − w²) ≈ 0.143 m forward
    let full = (cfg.feet_distance_max.powi(2) - cfg.nominal_width.powi(2)).sqrt();
    assert!(
        base_advance > 0.95 * full,
        "θ = 0: first step {base_advance}"
    );
    for exponent in 1..=9 {
        for sign in [1.0, -1.0] {
            let yaw = sign * 10f64.powi(-exponent);
            let plan = plan_with_heading(&cfg, yaw);
            let (foot, advance) = first_step(&plan);
            assert!(
                plan.step_count().abs_diff(base.step_count()) <= 1,
                "yaw {yaw:e}: {} steps, {} at θ = 0",
                plan.step_count(),
                base.step_count()
            );
            assert!(
                (plan.end_time - base.end_time).abs() <= cfg.step_duration_max,
                "yaw {yaw:e}: ends at {} s, {} s at θ = 0",
                plan.end_time,
                base.end_time
            );
            assert!(
                advance > 0.9 * full,
                "yaw {yaw:e}: first step ({foot:?}) {advance} m forward, full is {full} m"
            );
        }
    }
}

/// Curving left and curving right take the same number of steps (mirror images are equally feasible). The
/// waypoint has no heading: the final turn in place is a different matter (with `min_width ==
/// nominal_width` it cannot keep the width at all). Before the width was measured symmetrically the left
/// curves took 50–67 steps instead of 16–17.
#[test]
fn left_and_right_curves_are_mirror_images() {
    let cfg = icub();
    let (l, r) = standing(0.0, 0.0, 0.0, cfg.nominal_width);
    let straight = plan_with_heading(&cfg, 0.0).step_count();
    for y in [0.3, 0.8] {
        let plans = [y, -y].map(|y| {
            let points = vec![Waypoint {
                x: 2.0,
                y,
                yaw: None,
            }];
            let goal = Goal::Waypoints { points };
            let plan = plan_from_standing(&cfg, GRAVITY, 0.0, &l, &r, &goal).expect("plan");
            check_all(&cfg, &plan, true);
            assert_eq!(plan.outcome, PlanOutcome::Complete, "goal y = {y}");
            plan
        });
        assert_eq!(
            plans[0].step_count(),
            plans[1].step_count(),
            "goal y = ±{y}"
        );
        assert!(
            (plans[0].end_time - plans[1].end_time).abs() < 1e-6,
            "goal y = ±{y}"
        );
        assert!(
            plans[0].step_count() <= straight + 2,
            "goal y = ±{y}: {} steps",
            plans[0].step_count()
        );
    }
}
