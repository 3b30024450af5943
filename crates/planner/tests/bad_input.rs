//! Bad input gives an error naming the parameter; never a panic, a NaN or a silent empty plan.

mod common;

use common::*;
use proptest::prelude::*;
use stride_planner::{
    plan_from_standing, Goal, PlanOutcome, Planner, PlannerConfig, PlannerError, Waypoint,
};

fn param_of(e: PlannerError) -> String {
    match e {
        PlannerError::InvalidParameter { name, .. } => name.to_string(),
        PlannerError::InvalidGoal { name, .. } => name,
        PlannerError::InvalidStart { name, .. } => name.to_string(),
        PlannerError::InvalidTime { name, .. } => name.to_string(),
        other => format!("{other:?}"),
    }
}

fn plan_err(cfg: &PlannerConfig, goal: &Goal) -> String {
    let (l, r) = standing(0.0, 0.0, 0.0, 0.16);
    param_of(plan_from_standing(cfg, GRAVITY, 0.0, &l, &r, goal).unwrap_err())
}

#[test]
fn bad_parameters_are_named() {
    let goal = Goal::Pose {
        x: 1.0,
        y: 0.0,
        yaw: 0.0,
    };
    type Edit = Box<dyn Fn(&mut PlannerConfig)>;
    let cases: Vec<(&str, Edit)> = vec![
        (
            "step_duration_min",
            Box::new(|c| c.step_duration_min = -0.5),
        ),
        ("step_duration_min", Box::new(|c| c.step_duration_min = 0.0)),
        ("step_duration_max", Box::new(|c| c.step_duration_max = 0.5)),
        (
            "feet_distance_max",
            Box::new(|c| c.feet_distance_max = 0.15),
        ),
        ("com_height", Box::new(|c| c.com_height = f64::NAN)),
        // ω ≈ 1e-4 rad/s: the closed forms (1/ω³ terms) lose every digit (found by never_panics_or_nans)
        ("com_height", Box::new(|c| c.com_height = 1e9)),
        (
            "double_support_fraction",
            Box::new(|c| c.double_support_fraction = 1.0),
        ),
        ("min_width", Box::new(|c| c.min_width = 0.05)),
        ("nominal_width", Box::new(|c| c.nominal_width = 0.13)),
        (
            "reference_point",
            Box::new(|c| c.reference_point = [0.0, 0.0]),
        ),
        (
            "initial_double_support_duration",
            Box::new(|c| c.initial_double_support_duration = -1.0),
        ),
        ("landing_velocity", Box::new(|c| c.landing_velocity = 0.1)),
        ("horizon", Box::new(|c| c.horizon = f64::INFINITY)),
        ("foot_length", Box::new(|c| c.foot_length = 0.0)),
    ];
    for (name, edit) in cases {
        let mut cfg = PlannerConfig::default();
        edit(&mut cfg);
        assert_eq!(plan_err(&cfg, &goal), name);
        assert_eq!(param_of(Planner::new(cfg, GRAVITY).unwrap_err()), name);
    }
}

/// Gravity is a constructor input, not a config field: a non-finite or non-positive magnitude is
/// refused by both entry points with its value.
#[test]
fn bad_gravity_is_refused() {
    let cfg = PlannerConfig::default();
    let (l, r) = standing(0.0, 0.0, 0.0, 0.16);
    for g in [0.0, -9.81, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        for e in [
            Planner::new(cfg.clone(), g).unwrap_err(),
            plan_from_standing(&cfg, g, 0.0, &l, &r, &Goal::Stand).unwrap_err(),
        ] {
            match e {
                PlannerError::InvalidGravity { value } => {
                    assert!(value.to_bits() == g.to_bits(), "{value} for {g}")
                }
                other => panic!("gravity {g}: {other:?}"),
            }
        }
    }
    let planner = Planner::new(cfg.clone(), 3.71).unwrap();
    assert_eq!(planner.gravity(), 3.71);
    // ω follows the gravity given: √(g/h)
    let plan = plan_from_standing(&cfg, 3.71, 0.0, &l, &r, &Goal::Stand).unwrap();
    assert_eq!(plan.omega, (3.71 / cfg.com_height).sqrt());
    // a config that still names gravity is refused (deny_unknown_fields)
    assert!(toml::from_str::<PlannerConfig>("gravity = 9.81").is_err());
}

#[test]
fn bad_goals_are_named() {
    let cfg = PlannerConfig::default();
    assert_eq!(
        plan_err(
            &cfg,
            &Goal::Pose {
                x: f64::NAN,
                y: 0.0,
                yaw: 0.0
            }
        ),
        "pose.x"
    );
    assert_eq!(
        plan_err(&cfg, &Goal::Waypoints { points: vec![] }),
        "waypoints.points"
    );
    assert_eq!(
        plan_err(
            &cfg,
            &Goal::Waypoints {
                points: vec![
                    Waypoint {
                        x: 1.0,
                        y: 0.0,
                        yaw: None
                    },
                    Waypoint {
                        x: 1.0,
                        y: f64::INFINITY,
                        yaw: None
                    }
                ]
            }
        ),
        "waypoints.points[1].y"
    );
    assert_eq!(
        plan_err(
            &cfg,
            &Goal::Velocity {
                forward: 0.1,
                lateral: f64::NAN,
                yaw_rate: 0.0,
                duration: None
            }
        ),
        "velocity.lateral"
    );
    assert_eq!(
        plan_err(
            &cfg,
            &Goal::Velocity {
                forward: 0.1,
                lateral: 0.0,
                yaw_rate: 0.0,
                duration: Some(-1.0)
            }
        ),
        "velocity.duration"
    );
}

#[test]
fn bad_start_is_named() {
    let cfg = PlannerConfig::default();
    let goal = Goal::Pose {
        x: 1.0,
        y: 0.0,
        yaw: 0.0,
    };
    // crossed feet
    let (l, r) = standing(0.0, 0.0, 0.0, 0.16);
    let e = plan_from_standing(&cfg, GRAVITY, 0.0, &r, &l, &goal).unwrap_err();
    assert!(
        matches!(
            e,
            PlannerError::InvalidStart {
                name: "left_sole",
                ..
            }
        ),
        "{e}"
    );
    // NaN pose
    let mut bad = l;
    bad.translation.x = f64::NAN;
    let e = plan_from_standing(&cfg, GRAVITY, 0.0, &bad, &r, &goal).unwrap_err();
    assert!(
        matches!(
            e,
            PlannerError::InvalidStart {
                name: "left_sole",
                ..
            }
        ),
        "{e}"
    );
    // NaN time
    let e = plan_from_standing(&cfg, GRAVITY, f64::NAN, &l, &r, &goal).unwrap_err();
    assert_eq!(param_of(e), "t0");
    // replanning without a plan
    let mut p = Planner::new(cfg, GRAVITY).unwrap();
    let one_second = std::time::Duration::from_secs(1);
    assert_eq!(
        p.replan(one_second, &goal).unwrap_err(),
        PlannerError::NoPlan
    );
    assert_eq!(p.merge_time(one_second).unwrap_err(), PlannerError::NoPlan);
}

#[test]
fn unknown_config_fields_are_rejected() {
    let e = toml::from_str::<PlannerConfig>("com_height = 0.5\nstep_lenght_max = 0.2\n");
    assert!(e.is_err());
    let c: PlannerConfig = toml::from_str("com_height = 0.6\n").unwrap();
    assert_eq!(c.com_height, 0.6);
    assert_eq!(c.nominal_width, PlannerConfig::default().nominal_width);
    let g: Goal = toml::from_str("type = \"pose\"\nx = 1.0\ny = 2.0\nyaw = 0.5\n").unwrap();
    assert_eq!(
        g,
        Goal::Pose {
            x: 1.0,
            y: 2.0,
            yaw: 0.5
        }
    );
    let g: Goal =
        toml::from_str("type = \"velocity\"\nforward = 0.1\nlateral = 0.0\nyaw_rate = 0.0\n")
            .unwrap();
    assert_eq!(
        g,
        Goal::Velocity {
            forward: 0.1,
            lateral: 0.0,
            yaw_rate: 0.0,
            duration: None
        }
    );
}

/// A goal beyond the horizon gives the feasible prefix, ending standing, and says so.
#[test]
fn horizon_gives_feasible_prefix() {
    let cfg = PlannerConfig {
        horizon: 8.0,
        ..PlannerConfig::default()
    };
    let (l, r) = standing(0.0, 0.0, 0.0, cfg.nominal_width);
    let plan = plan_from_standing(
        &cfg,
        GRAVITY,
        0.0,
        &l,
        &r,
        &Goal::Pose {
            x: 5.0,
            y: 0.0,
            yaw: 0.0,
        },
    )
    .unwrap();
    match plan.outcome {
        PlanOutcome::HorizonReached {
            remaining_distance, ..
        } => {
            assert!(
                remaining_distance > 3.0 && remaining_distance < 5.0,
                "{remaining_distance}"
            )
        }
        o => panic!("expected a prefix, got {o:?}"),
    }
    assert!(plan.step_count() > 2);
    check_all(&cfg, &plan, true);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, .. ProptestConfig::default() })]

    /// Arbitrary (also absurd) numbers never panic and never produce NaN: either an error or a plan whose
    /// samples are finite.
    #[test]
    fn never_panics_or_nans(
        vals in proptest::collection::vec(prop_oneof![
            Just(f64::NAN), Just(f64::INFINITY), Just(-1.0), Just(0.0), Just(1e-9), Just(1e9),
            -2.0f64..2.0, 0.0f64..1.0
        ], 12),
        gx in prop_oneof![Just(f64::NAN), -3.0f64..3.0],
        gy in -3.0f64..3.0,
    ) {
        let mut cfg = PlannerConfig { horizon: 20.0, ..PlannerConfig::default() };
        let fields: [&mut f64; 12] = [
            &mut cfg.com_height, &mut cfg.step_duration_min, &mut cfg.step_duration_max,
            &mut cfg.double_support_fraction, &mut cfg.feet_distance_max, &mut cfg.nominal_width,
            &mut cfg.min_width, &mut cfg.max_yaw_per_step, &mut cfg.swing_height,
            &mut cfg.unicycle_gain, &mut cfg.time_weight, &mut cfg.final_double_support_duration,
        ];
        // only replace some fields, keep the others sensible
        for (i, (f, v)) in fields.into_iter().zip(vals.iter()).enumerate() {
            if i % 3 == (vals.len() % 3) { *f = *v; }
        }
        let (l, r) = standing(0.0, 0.0, 0.0, 0.16);
        let goal = Goal::Pose { x: gx, y: gy, yaw: 0.3 };
        if let Ok(plan) = plan_from_standing(&cfg, GRAVITY, 0.0, &l, &r, &goal) {
            let mut t = plan.start_time;
            while t < plan.end_time + 1.0 {
                let s = sample(&plan, t);
                prop_assert!(s.dcm_position.iter().all(|v| v.is_finite()));
                prop_assert!(s.com_position.iter().all(|v| v.is_finite()));
                prop_assert!(s.left.pose.translation.vector.iter().all(|v| v.is_finite()));
                prop_assert!(s.right.twist.iter().all(|v| v.is_finite()));
                t += 0.05;
            }
        }
    }
}

/// Goals far beyond the horizon (pose or very long velocity command) give a prefix bounded by the horizon
/// (so the search cannot run away: at most horizon / step_duration_min steps), never hang.
#[test]
fn far_goals_give_prefixes() {
    let cfg = PlannerConfig {
        horizon: 20.0,
        ..PlannerConfig::default()
    };
    let (l, r) = standing(0.0, 0.0, 0.0, cfg.nominal_width);
    let max_steps = (cfg.horizon / cfg.step_duration_min).ceil() as usize + 2;
    for goal in [
        Goal::Pose {
            x: 1e12,
            y: -1e12,
            yaw: 0.0,
        },
        Goal::Velocity {
            forward: 0.1,
            lateral: 0.0,
            yaw_rate: 0.1,
            duration: Some(1e12),
        },
        Goal::Waypoints {
            points: vec![Waypoint {
                x: 1e9,
                y: 0.0,
                yaw: None,
            }],
        },
    ] {
        let plan = plan_from_standing(&cfg, GRAVITY, 0.0, &l, &r, &goal).unwrap();
        assert!(
            matches!(plan.outcome, PlanOutcome::HorizonReached { .. }),
            "{:?}",
            plan.outcome
        );
        assert!(
            plan.step_count() <= max_steps,
            "{} steps > {max_steps}",
            plan.step_count()
        );
        assert!(
            // initial weight transfer, the unicycle's horizon, the closing steps (at most two, one per foot)
            // and the final double support
            plan.end_time - plan.start_time
                <= cfg.initial_double_support_duration
                    + cfg.horizon
                    + 2.0 * cfg.step_duration_max
                    + cfg.final_double_support_duration,
            "plan spans {} s",
            plan.end_time - plan.start_time
        );
        check_steps(&cfg, &plan, true);
        check_dynamics(&cfg, &plan, 0.02);
    }
}

/// Sampling at NaN/±∞ never yields NaN: before the start clamps to the start, after the end stands.
#[test]
fn sampling_at_extreme_times_is_finite() {
    let cfg = PlannerConfig::default();
    let (l, r) = standing(0.0, 0.0, 0.0, cfg.nominal_width);
    let plan = plan_from_standing(
        &cfg,
        GRAVITY,
        2.0,
        &l,
        &r,
        &Goal::Pose {
            x: 0.5,
            y: 0.0,
            yaw: 0.0,
        },
    )
    .unwrap();
    for t in [f64::NAN, f64::NEG_INFINITY, -1e300, 1e300, f64::INFINITY] {
        let s = sample(&plan, t);
        for v in [
            s.dcm_position,
            s.dcm_velocity,
            s.zmp,
            s.com_position,
            s.com_velocity,
            s.com_acceleration,
        ] {
            assert!(v.iter().all(|x| x.is_finite()), "t = {t}: {v:?}");
        }
        assert!(s.left.pose.translation.vector.iter().all(|x| x.is_finite()));
        assert!(s.left.in_contact && s.right.in_contact);
    }
    assert_eq!(sample(&plan, f64::NAN), sample(&plan, 2.0));
}
