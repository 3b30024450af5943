//! Property tests over random goals, random starting feet and random valid parameter sets.

mod common;

use std::time::Duration;

use common::*;
use proptest::prelude::*;
use stride_planner::{plan_from_standing, Goal, Planner, PlannerConfig, PlannerError, Waypoint};

/// 48 cases by default; `PROPTEST_CASES=n` for longer runs.
fn cases() -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(48)
}

fn config_strategy() -> impl Strategy<Value = PlannerConfig> {
    (
        0.45f64..0.75, // com height
        0.7f64..1.0,   // t_min
        0.0f64..0.4,   // t_max - t_min
        0.2f64..0.45,  // ds fraction
        0.14f64..0.2,  // nominal width
        0.05f64..0.12, // step length max - width
        0.15f64..0.35, // max yaw
        0.02f64..0.06, // swing height
        0.3f64..0.7,   // apex fraction
        -0.2f64..=0.0, // landing velocity
        0.6f64..1.5,   // initial ds
    )
        .prop_map(
            |(h, tmin, dt, f, w, dl, yaw, sh, apex, lv, ids)| PlannerConfig {
                com_height: h,
                step_duration_min: tmin,
                step_duration_max: tmin + dt,
                step_duration_nominal: tmin + 0.5 * dt,
                double_support_fraction: f,
                nominal_width: w,
                min_width: (w - 0.02).max(0.125),
                feet_distance_max: w + dl,
                max_yaw_per_step: yaw,
                swing_height: sh,
                swing_apex_fraction: apex,
                landing_velocity: lv,
                initial_double_support_duration: ids,
                horizon: 40.0,
                ..PlannerConfig::default()
            },
        )
        .prop_filter("valid", |c| c.validate().is_ok())
}

fn goal_strategy() -> impl Strategy<Value = Goal> {
    prop_oneof![
        (-1.0f64..2.5, -1.5f64..1.5, -3.2f64..3.2).prop_map(|(x, y, yaw)| Goal::Pose { x, y, yaw }),
        proptest::collection::vec((-1.5f64..1.5, -1.5f64..1.5), 1..4).prop_map(|pts| {
            Goal::Waypoints {
                points: pts
                    .into_iter()
                    .map(|(x, y)| Waypoint { x, y, yaw: None })
                    .collect(),
            }
        }),
        (-0.2f64..0.3, -0.05f64..0.05, -0.3f64..0.3, 1.0f64..8.0).prop_map(|(v, l, w, d)| {
            Goal::Velocity {
                forward: v,
                lateral: l,
                yaw_rate: w,
                duration: Some(d),
            }
        }),
    ]
}

fn start_strategy() -> impl Strategy<Value = (f64, f64, f64, f64, f64)> {
    // mid-point, heading, width offset, start time
    (
        -1.0f64..1.0,
        -1.0f64..1.0,
        -3.1f64..3.1,
        -0.01f64..0.03,
        0.0f64..100.0,
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), .. ProptestConfig::default() })]

    #[test]
    fn every_plan_satisfies_the_invariants(cfg in config_strategy(), goal in goal_strategy(),
                                           (x, y, yaw, dw, t0) in start_strategy()) {
        let (l, r) = standing(x, y, yaw, cfg.nominal_width + dw);
        // goals are relative to the start pose for poses/waypoints
        let goal = match goal {
            Goal::Pose { x: gx, y: gy, yaw: gyaw } => {
                let (s, c) = yaw.sin_cos();
                Goal::Pose { x: x + c * gx - s * gy, y: y + s * gx + c * gy, yaw: yaw + gyaw }
            }
            g => g,
        };
        let plan = plan_from_standing(&cfg, GRAVITY, t0, &l, &r, &goal);
        let plan = match plan {
            Ok(p) => p,
            Err(e) => panic!("planning failed: {e}"),
        };
        check_all(&cfg, &plan, true);
        // bit-identical determinism
        let again = plan_from_standing(&cfg, GRAVITY, t0, &l, &r, &goal).unwrap();
        prop_assert_eq!(serde_json::to_string(&plan).unwrap(), serde_json::to_string(&again).unwrap());
        prop_assert!(plan == again);
    }

    #[test]
    fn replanning_keeps_the_past_and_is_continuous(cfg in config_strategy(), goal1 in goal_strategy(),
                                                    goal2 in goal_strategy(), frac in 0.0f64..1.0) {
        let (l, r) = standing(0.0, 0.0, 0.0, cfg.nominal_width);
        let mut planner = Planner::new(cfg.clone(), GRAVITY).unwrap();
        let old = planner.start(Duration::ZERO, &l, &r, &goal1).unwrap().clone();
        let (time, t) = instant(old.start_time + frac * (old.end_time - old.start_time + 1.0));
        let m = match planner.replan(time, &goal2) {
            Ok(m) => m,
            Err(PlannerError::NoMergePoint { .. }) => return Ok(()),
            Err(e) => panic!("replanning failed: {e}"),
        };
        prop_assert!(m >= t);
        let new = planner.plan().unwrap();
        // the past is unchanged: samples before the merge point are identical
        let mut k = 0.0;
        while k < m {
            let (a, b) = (sample(&old, k), sample(new, k));
            prop_assert!(a == b, "sample differs at {} < merge {}", k, m);
            k += 0.01;
        }
        // continuity at the merge point
        let (a, b) = (sample(&old, m - 1e-9), sample(new, m));
        prop_assert!((a.dcm_position - b.dcm_position).norm() < 1e-7);
        prop_assert!((a.dcm_velocity - b.dcm_velocity).norm() < 1e-6);
        prop_assert!((a.com_position - b.com_position).norm() < 1e-7);
        prop_assert!((a.left.pose.translation.vector - b.left.pose.translation.vector).norm() < 1e-9);
        prop_assert!((a.right.pose.translation.vector - b.right.pose.translation.vector).norm() < 1e-9);
        prop_assert!((a.left.twist - b.left.twist).norm() < 1e-9 && (a.right.twist - b.right.twist).norm() < 1e-9);
        check_steps(&cfg, new, false);
        check_dynamics(&cfg, new, 0.01);
        check_swings(&cfg, new);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), .. ProptestConfig::default() })]

    /// The thesis' DCM cubics (option `dcm_cubic`): either a plan satisfying every invariant, or the documented
    /// refusal `ZmpOutsideSupport` (its ZMP is not in the support polygon by construction).
    #[test]
    fn thesis_dcm_cubic_plans_satisfy_the_invariants_or_refuse(cfg in config_strategy(), goal in goal_strategy(),
                                                               alpha in 0.0f64..=1.0) {
        let cfg = PlannerConfig {
            dcm_interpolation: stride_planner::DcmInterpolation::DcmCubic,
            last_step_dcm_alpha: alpha,
            ..cfg
        };
        let (l, r) = standing(0.0, 0.0, 0.0, cfg.nominal_width);
        match plan_from_standing(&cfg, GRAVITY, 0.0, &l, &r, &goal) {
            Ok(plan) => check_all(&cfg, &plan, true),
            Err(PlannerError::ZmpOutsideSupport { .. }) => {}
            Err(e) => panic!("planning failed: {e}"),
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases() / 2 + 1, .. ProptestConfig::default() })]

    /// A chain of replans at random increasing times (as a joystick would send) keeps every invariant.
    #[test]
    fn chained_replanning(goals in proptest::collection::vec(goal_strategy(), 2..6),
                          gaps in proptest::collection::vec(0.05f64..3.0, 6)) {
        let cfg = PlannerConfig { horizon: 30.0, ..PlannerConfig::default() };
        let (l, r) = standing(0.0, 0.0, 0.0, cfg.nominal_width);
        let mut planner = Planner::new(cfg.clone(), GRAVITY).unwrap();
        planner.start(Duration::ZERO, &l, &r, &goals[0]).unwrap();
        let mut t = 0.0;
        for (g, gap) in goals.iter().skip(1).zip(gaps.iter()) {
            t += gap;
            let (time, t) = instant(t);
            match planner.replan(time, g) {
                Ok(m) => prop_assert!(m >= t),
                Err(PlannerError::NoMergePoint { .. }) => {}
                Err(e) => panic!("replanning failed: {e}"),
            }
        }
        let plan = planner.plan().unwrap();
        check_steps(&cfg, plan, false);
        check_dynamics(&cfg, plan, 0.01);
        check_swings(&cfg, plan);
    }
}
