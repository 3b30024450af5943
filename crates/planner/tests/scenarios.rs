//! The scenarios the runner uses: a 2 m straight walk, a 90° turn in place, a curve, a velocity command.

mod common;

use std::time::Duration;

use common::*;
use stride_planner::{plan_from_standing, Goal, PlanOutcome, PlannerConfig, Waypoint};

fn run(goal: Goal) -> stride_planner::Plan {
    let cfg = PlannerConfig::default();
    let (l, r) = standing(0.0, 0.0, 0.0, cfg.nominal_width);
    let plan = plan_from_standing(&cfg, GRAVITY, 0.0, &l, &r, &goal).expect("plan");
    check_all(&cfg, &plan, true);
    plan
}

fn final_mid(plan: &stride_planner::Plan) -> (f64, f64, f64) {
    let l = &plan.left_contacts.contacts.last().unwrap().pose;
    let r = &plan.right_contacts.contacts.last().unwrap().pose;
    let m = (l.translation.vector + r.translation.vector) * 0.5;
    (m.x, m.y, yaw_of(l))
}

#[test]
fn straight_two_meters() {
    let plan = run(Goal::Pose {
        x: 2.0,
        y: 0.0,
        yaw: 0.0,
    });
    let (x, y, yaw) = final_mid(&plan);
    assert!(
        (x - 2.0).abs() < 0.01 && y.abs() < 0.01 && yaw.abs() < 0.01,
        "{x} {y} {yaw}"
    );
    assert_eq!(plan.outcome, PlanOutcome::Complete);
    assert!(plan.step_count() >= 10, "steps {}", plan.step_count());
    eprintln!("2 m: {} steps, {:.2} s", plan.step_count(), plan.end_time);
}

#[test]
fn turn_in_place_90_degrees() {
    let plan = run(Goal::Pose {
        x: 0.0,
        y: 0.0,
        yaw: std::f64::consts::FRAC_PI_2,
    });
    let (x, y, yaw) = final_mid(&plan);
    assert!(x.abs() < 0.01 && y.abs() < 0.01, "{x} {y}");
    assert!((yaw - std::f64::consts::FRAC_PI_2).abs() < 0.01, "{yaw}");
}

#[test]
fn curve_through_waypoints() {
    let plan = run(Goal::Waypoints {
        points: vec![
            Waypoint {
                x: 0.6,
                y: 0.0,
                yaw: None,
            },
            Waypoint {
                x: 1.2,
                y: 0.4,
                yaw: None,
            },
            Waypoint {
                x: 1.5,
                y: 1.0,
                yaw: Some(1.2),
            },
        ],
    });
    let (x, y, yaw) = final_mid(&plan);
    assert!((x - 1.5).abs() < 0.02 && (y - 1.0).abs() < 0.02, "{x} {y}");
    assert!((yaw - 1.2).abs() < 0.02, "{yaw}");
}

#[test]
fn velocity_command() {
    let plan = run(Goal::Velocity {
        forward: 0.1,
        lateral: 0.0,
        yaw_rate: 0.05,
        duration: Some(8.0),
    });
    let (x, _, yaw) = final_mid(&plan);
    assert!(x > 0.5, "{x}");
    assert!(yaw > 0.2, "{yaw}");
}

/// Where a plan ends and how it gets there: the final feet mid-point and yaw, the final DCM, and the
/// extreme sole yaw and the monotonicity of the touch-downs along `direction` (unit, world xy).
struct Motion {
    end: (f64, f64, f64),
    dcm_end: (f64, f64),
    max_abs_sole_yaw: f64,
    /// Largest step of a touch-down against `direction` compared with the previous touch-down of the
    /// same foot \[m\] (0 when every foot only moves forward along `direction`).
    largest_step_back: f64,
}

fn motion(plan: &stride_planner::Plan, direction: (f64, f64)) -> Motion {
    let dcm = sample(plan, plan.end_time + 1.0).dcm_position;
    let mut max_abs_sole_yaw: f64 = 0.0;
    let mut largest_step_back: f64 = 0.0;
    for list in [&plan.left_contacts, &plan.right_contacts] {
        for pair in list.contacts.windows(2) {
            let (a, b) = (&pair[0].pose.translation, &pair[1].pose.translation);
            let along = (b.x - a.x) * direction.0 + (b.y - a.y) * direction.1;
            largest_step_back = largest_step_back.max(-along);
        }
        for c in &list.contacts {
            max_abs_sole_yaw = max_abs_sole_yaw.max(yaw_of(&c.pose).abs());
        }
    }
    Motion {
        end: final_mid(plan),
        dcm_end: (dcm.x, dcm.y),
        max_abs_sole_yaw,
        largest_step_back,
    }
}

/// Lateral and backward commands move the feet and the DCM the way asked (left, right, backwards),
/// without turning, by about the commanded speed (saturated at the planner's limits) times the
/// duration, every touch-down progressing in that direction.
#[test]
fn lateral_and_backward_velocity() {
    let cfg = PlannerConfig::default();
    let lateral_speed = 0.05_f64.min(cfg.max_lateral_speed());
    let backward_speed = 0.1_f64.min(cfg.max_backward_speed());
    let duration = 6.0;
    for (forward, lateral, direction, speed) in [
        (0.0, 0.05, (0.0, 1.0), lateral_speed),
        (0.0, -0.05, (0.0, -1.0), lateral_speed),
        (-0.1, 0.0, (-1.0, 0.0), backward_speed),
    ] {
        let plan = run(Goal::Velocity {
            forward,
            lateral,
            yaw_rate: 0.0,
            duration: Some(duration),
        });
        let m = motion(&plan, direction);
        let (x, y, yaw) = m.end;
        let along = x * direction.0 + y * direction.1;
        let across = -x * direction.1 + y * direction.0;
        let commanded = speed * duration;
        assert!(
            (along - commanded).abs() < 0.2 * commanded,
            "({forward}, {lateral}): moved {along} m along the command, expected about {commanded} m"
        );
        assert!(
            across.abs() < 0.1 * commanded,
            "({forward}, {lateral}): drifted {across} m"
        );
        assert!(
            yaw.abs() < 0.01,
            "({forward}, {lateral}): turned by {yaw} rad"
        );
        assert!(
            m.max_abs_sole_yaw < 0.01,
            "({forward}, {lateral}): a sole turned by {}",
            m.max_abs_sole_yaw
        );
        assert!(
            m.largest_step_back < 1e-3,
            "({forward}, {lateral}): a foot stepped {} m against the command",
            m.largest_step_back
        );
        // the DCM ends on the final feet mid-point, i.e. it moved with them
        assert!(
            (m.dcm_end.0 - x).abs() < 1e-3 && (m.dcm_end.1 - y).abs() < 1e-3,
            "{:?} vs ({x}, {y})",
            m.dcm_end
        );
    }
    // a goal 0.3 m behind (closer than backward_max_distance) is reached walking backwards
    assert!(0.3 < cfg.backward_max_distance);
    let plan = run(Goal::Pose {
        x: -0.3,
        y: 0.0,
        yaw: 0.0,
    });
    let m = motion(&plan, (-1.0, 0.0));
    let (x, y, yaw) = m.end;
    assert!(
        (x + 0.3).abs() < 0.01 && y.abs() < 0.01 && yaw.abs() < 0.01,
        "{x} {y} {yaw}"
    );
    assert!(
        m.max_abs_sole_yaw < 0.01,
        "a sole turned by {}",
        m.max_abs_sole_yaw
    );
    assert!(
        m.largest_step_back < 1e-3,
        "a foot stepped {} m forwards",
        m.largest_step_back
    );
    assert!((m.dcm_end.0 - x).abs() < 1e-3 && (m.dcm_end.1 - y).abs() < 1e-3);
}

#[test]
fn stand_goal_is_a_valid_standing_plan() {
    let plan = run(Goal::Stand);
    assert_eq!(plan.step_count(), 0);
}

/// Replanning towards the same goal mid-walk keeps the gait: the new footsteps land where the old ones would
/// have (the unicycle is re-anchored on the last touch-down), so the merge is seamless.
#[test]
fn replanning_with_the_same_goal_keeps_the_footsteps() {
    let cfg = PlannerConfig::default();
    let (l, r) = standing(0.0, 0.0, 0.0, cfg.nominal_width);
    let goal = Goal::Pose {
        x: 2.0,
        y: 0.0,
        yaw: 0.0,
    };
    let mut planner = stride_planner::Planner::new(cfg.clone(), GRAVITY).unwrap();
    let old = planner
        .start(Duration::ZERO, &l, &r, &goal)
        .unwrap()
        .clone();
    let m = planner.replan(Duration::from_secs(4), &goal).unwrap();
    let new = planner.plan().unwrap();
    assert_eq!(new.merge_times, vec![m]);
    check_steps(&cfg, new, false);
    check_dynamics(&cfg, new, 0.01);
    check_swings(&cfg, new);
    let (a, b) = (old.footsteps(), new.footsteps());
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b.iter()) {
        assert_eq!(x.foot, y.foot);
        assert!((x.pose.translation.vector - y.pose.translation.vector).norm() < 0.02);
    }
}

/// A new goal mid-walk (turn left) merges and the plan still satisfies every invariant.
#[test]
fn replanning_to_a_new_goal() {
    let cfg = PlannerConfig::default();
    let (l, r) = standing(0.0, 0.0, 0.0, cfg.nominal_width);
    let mut planner = stride_planner::Planner::new(cfg.clone(), GRAVITY).unwrap();
    planner
        .start(
            Duration::ZERO,
            &l,
            &r,
            &Goal::Pose {
                x: 2.0,
                y: 0.0,
                yaw: 0.0,
            },
        )
        .unwrap();
    planner
        .replan(
            Duration::from_secs(5),
            &Goal::Pose {
                x: 1.5,
                y: 1.0,
                yaw: 1.5,
            },
        )
        .unwrap();
    planner
        .replan(
            Duration::from_secs(9),
            &Goal::Velocity {
                forward: 0.1,
                lateral: 0.0,
                yaw_rate: -0.1,
                duration: Some(4.0),
            },
        )
        .unwrap();
    let plan = planner.plan().unwrap();
    assert_eq!(plan.merge_times.len(), 2);
    check_steps(&cfg, plan, false);
    check_dynamics(&cfg, plan, 0.01);
    check_swings(&cfg, plan);
}

/// The `Block` interface: the first tick starts from the measured soles, a tick with a goal replans, the
/// output follows the plan; `reset` forgets the plan.
#[test]
fn block_interface() {
    use std::time::Duration;
    use stride_block::Block;
    use stride_planner::{Planner, PlannerInput};
    let cfg = PlannerConfig::default();
    let (l, r) = standing(1.0, 2.0, 0.5, cfg.nominal_width);
    let mut block = Planner::new(cfg.clone(), GRAVITY).unwrap();
    let mut input = PlannerInput {
        time: Duration::from_secs(3),
        goal: None,
        left_sole: l,
        right_sole: r,
    };
    let out = *block.step(&input).unwrap();
    // no goal: standing on the measured feet, DCM and CoM at the mid-point
    assert!((out.dcm_position.x - 1.0).abs() < 1e-12 && (out.dcm_position.y - 2.0).abs() < 1e-12);
    assert!((out.com_position.z - cfg.com_height).abs() < 1e-12);
    assert_eq!(out.left.pose, l);
    input.time = Duration::from_millis(3500);
    input.goal = Some(Goal::Pose {
        x: 1.5,
        y: 2.3,
        yaw: 0.5,
    });
    block.step(&input).unwrap();
    let plan = block.plan().unwrap();
    assert_eq!(plan.merge_times.len(), 1);
    assert!(plan.step_count() > 2);
    check_steps(&cfg, plan, false);
    check_dynamics(&cfg, plan, 0.01);
    let end = plan.end_time;
    input.goal = None;
    input.time = Duration::from_secs_f64(end + 3.0);
    let out = *block.step(&input).unwrap();
    let (x, y, _) = final_mid(block.plan().unwrap());
    assert!((out.dcm_position.x - x).abs() < 1e-9 && (out.dcm_position.y - y).abs() < 1e-9);
    block.reset();
    assert!(block.plan().is_none());
}

/// The runner's `walk_curve` scenario: waypoints with headings; only the last heading is enforced.
#[test]
fn runner_walk_curve_scenario() {
    let plan = run(Goal::Waypoints {
        points: vec![
            Waypoint {
                x: 0.6,
                y: 0.15,
                yaw: Some(30f64.to_radians()),
            },
            Waypoint {
                x: 1.0,
                y: 1.0,
                yaw: Some(90f64.to_radians()),
            },
        ],
    });
    let (x, y, yaw) = final_mid(&plan);
    assert!((x - 1.0).abs() < 0.02 && (y - 1.0).abs() < 0.02, "{x} {y}");
    assert!((yaw - std::f64::consts::FRAC_PI_2).abs() < 0.01, "{yaw}");
    assert!(plan.end_time < 30.0, "{}", plan.end_time);
}

/// Stopping mid-walk: `Stand` holds the current feet (no step), a zero velocity command closes the stance
/// with parallel feet. Both end with the DCM at rest on the feet mid-point.
#[test]
fn stopping_mid_walk() {
    let cfg = PlannerConfig::default();
    let (l, r) = standing(0.0, 0.0, 0.0, cfg.nominal_width);
    for (stop, parallel) in [
        (Goal::Stand, false),
        (
            Goal::Velocity {
                forward: 0.0,
                lateral: 0.0,
                yaw_rate: 0.0,
                duration: None,
            },
            true,
        ),
    ] {
        for t in [2.0, 3.3, 4.1, 5.0, 6.7] {
            let mut planner = stride_planner::Planner::new(cfg.clone(), GRAVITY).unwrap();
            planner
                .start(
                    Duration::ZERO,
                    &l,
                    &r,
                    &Goal::Pose {
                        x: 3.0,
                        y: 0.0,
                        yaw: 0.0,
                    },
                )
                .unwrap();
            let (time, t) = instant(t);
            let m = planner.replan(time, &stop).unwrap();
            let plan = planner.plan().unwrap();
            assert!(m >= t);
            check_dynamics(&cfg, plan, 0.01);
            check_swings(&cfg, plan);
            if parallel {
                check_steps(&cfg, plan, false);
            } else {
                // no step after the merge point
                assert!(plan
                    .left_swings
                    .iter()
                    .chain(plan.right_swings.iter())
                    .all(|s| s.lift_time < m));
            }
        }
    }
}

/// `min_width` equal to `nominal_width` (a natural choice: never step narrower than the stance) walks as
/// fast as with slack between them. The unicycle's speed limit used to keep a 2 mm width margin, which made
/// steady walking at the nominal width look infeasible: the plan crawled with about twice as many steps
/// (found with the official iCub model, feet 0.14 m apart).
#[test]
fn min_width_equal_to_nominal_width_walks_at_full_speed() {
    let goal = Goal::Pose {
        x: 2.0,
        y: 0.0,
        yaw: 0.0,
    };
    let with_width = |min_width: f64, start_width: f64| {
        let cfg = PlannerConfig {
            nominal_width: 0.14,
            min_width,
            ..PlannerConfig::default()
        };
        let (l, r) = standing(0.0, 0.0, 0.0, start_width);
        let plan = plan_from_standing(&cfg, GRAVITY, 0.0, &l, &r, &goal).expect("plan");
        check_all(&cfg, &plan, true);
        assert_eq!(plan.outcome, PlanOutcome::Complete);
        plan
    };
    let slack = with_width(0.12, 0.14);
    for start_width in [0.14, 0.1403] {
        let tight = with_width(0.14, start_width);
        assert_eq!(tight.step_count(), slack.step_count());
        assert!((tight.end_time - slack.end_time).abs() < 1e-9);
    }
}

/// `stop_deceleration` slows the reference down over the last `v²/(2a)` of the path: on a fast 4 m walk the
/// step before the last short one is walked slower (longer and at most as long) instead of at the cruise speed,
/// the goal is still reached, and the plan is longer.
#[test]
fn stop_deceleration_slows_the_last_steps() {
    let goal = Goal::Pose {
        x: 4.0,
        y: 0.0,
        yaw: 0.0,
    };
    // forward speed of each step (advance over the time since the previous touch-down) [m/s]
    let plan_with = |deceleration: f64| {
        let cfg = PlannerConfig {
            feet_distance_max: 0.2915,
            step_duration_min: 0.5,
            step_duration_nominal: 0.6,
            step_duration_max: 0.8,
            double_support_fraction: 0.2,
            stop_deceleration: deceleration,
            ..PlannerConfig::default()
        };
        let (l, r) = standing(0.0, 0.0, 0.0, cfg.nominal_width);
        let plan = plan_from_standing(&cfg, GRAVITY, 0.0, &l, &r, &goal).expect("plan");
        check_all(&cfg, &plan, true);
        let mut steps = plan.footsteps();
        steps.sort_by(|a, b| a.activation_time.total_cmp(&b.activation_time));
        let speeds: Vec<f64> = steps
            .windows(2)
            .map(|w| {
                (w[1].pose.translation.x - w[0].pose.translation.x)
                    / (w[1].activation_time - w[0].activation_time)
            })
            .collect();
        (plan, speeds)
    };
    let (abrupt, abrupt_speeds) = plan_with(0.0);
    let (braked, braked_speeds) = plan_with(0.3);
    for plan in [&abrupt, &braked] {
        let (x, y, _) = final_mid(plan);
        assert!((x - 4.0).abs() < 0.02 && y.abs() < 0.02, "{x} {y}");
    }
    let cruise = abrupt_speeds[abrupt_speeds.len() / 2];
    assert!(cruise > 0.39, "{abrupt_speeds:?}");
    // the step before the short last one: at cruise speed without braking, clearly slower with it
    let before_last = |v: &[f64]| v[v.len() - 3];
    assert!(
        before_last(&abrupt_speeds) > 0.99 * cruise,
        "{abrupt_speeds:?}"
    );
    assert!(
        before_last(&braked_speeds) < 0.8 * cruise,
        "{braked_speeds:?}"
    );
    assert!(
        braked.end_time > abrupt.end_time + 0.2,
        "{} {}",
        braked.end_time,
        abrupt.end_time
    );
}
