//! `Plan::verify` rejects each kind of broken plan with the right invariant, and the `Planner` runs it.
//! (That it accepts every valid plan is checked by `common::check_all`, which every scenario and property
//! test calls.)

mod common;

use std::time::Duration;

use common::*;
use nalgebra::{UnitQuaternion, Vector2, Vector3};
use stride_planner::{
    plan_from_standing, Goal, Invariant, Plan, PlanVerification, Planner, PlannerConfig,
};

fn config() -> PlannerConfig {
    PlannerConfig::default()
}

fn plan(goal: Goal) -> Plan {
    let cfg = config();
    let (l, r) = standing(0.0, 0.0, 0.0, cfg.nominal_width);
    plan_from_standing(&cfg, GRAVITY, 0.0, &l, &r, &goal).expect("plan")
}

fn straight() -> Plan {
    plan(Goal::Pose {
        x: 1.0,
        y: 0.0,
        yaw: 0.0,
    })
}

fn curve() -> Plan {
    plan(Goal::Pose {
        x: 0.8,
        y: 0.6,
        yaw: 1.2,
    })
}

/// The invariant `verify` reports for `plan` checked against `cfg`.
fn rejected(plan: &Plan, cfg: &PlannerConfig) -> Invariant {
    match plan.verify(cfg, 0.01) {
        Ok(report) => panic!("accepted: {report:?}"),
        Err(e) => {
            assert!(e.time.is_finite(), "{e}");
            assert!(e.to_string().contains(e.invariant.name()), "{e}");
            e.invariant
        }
    }
}

#[test]
fn valid_plans_pass_with_their_margins() {
    let cfg = config();
    for p in [straight(), curve()] {
        let report = p.verify(&cfg, 0.01).expect("valid plan");
        assert_eq!(report.touch_downs, p.step_count());
        assert!(report.samples as f64 >= (p.end_time - p.start_time) / 0.01);
        // the ZMP-first DCM keeps the ZMP strictly inside the soles, the feet at least min_width apart
        assert!(report.min_zmp_margin > 1e-3, "{report:?}");
        assert!(report.min_width_margin >= -1e-9, "{report:?}");
        assert!(report.final_dcm_error < 1e-3, "{report:?}");
    }
}

#[test]
fn step_bounds_are_checked_against_the_config() {
    let p = curve();
    let cfg = config();
    let bounds = p.verify(&cfg, 0.01).expect("valid");
    // each bound, tightened just below what the plan uses, is caught
    let longest = p
        .footsteps()
        .windows(2)
        .map(|w| {
            (w[1].pose.translation.vector - w[0].pose.translation.vector)
                .xy()
                .norm()
        })
        .fold(0.0, f64::max);
    let tighter = PlannerConfig {
        feet_distance_max: longest - 0.02,
        ..cfg.clone()
    };
    assert_eq!(rejected(&p, &tighter), Invariant::StepLength);
    let wider = PlannerConfig {
        min_width: cfg.min_width + bounds.min_width_margin + 0.005,
        ..cfg.clone()
    };
    assert_eq!(rejected(&p, &wider), Invariant::StepWidth);
    let less_yaw = PlannerConfig {
        max_yaw_per_step: 0.02,
        ..cfg.clone()
    };
    assert_eq!(rejected(&p, &less_yaw), Invariant::StepYaw);
    let shorter = PlannerConfig {
        step_duration_max: cfg.step_duration_min * 0.5,
        ..cfg.clone()
    };
    assert_eq!(rejected(&p, &shorter), Invariant::StepDuration);
}

#[test]
fn overlapping_soles_are_caught() {
    let mut p = straight();
    p.foot_width = 0.5; // soles wider than the feet distance
    assert_eq!(rejected(&p, &config()), Invariant::FeetOverlap);
}

#[test]
fn a_zmp_off_the_feet_is_caught() {
    // shifting the whole DCM/ZMP/CoM plan sideways keeps it continuous and dynamically consistent, but moves
    // the ZMP off the soles
    let mut p = straight();
    for seg in &mut p.segments {
        let shift = Vector2::new(0.0, 0.3);
        seg.zmp[0] += shift;
        seg.dcm_poly[0] += shift;
        seg.com_poly[0] += shift;
    }
    assert_eq!(rejected(&p, &config()), Invariant::ZmpInSupport);
}

#[test]
fn a_wrong_natural_frequency_is_caught() {
    let mut p = straight();
    p.omega *= 1.01;
    assert_eq!(rejected(&p, &config()), Invariant::DcmDynamics);
}

#[test]
fn a_jump_between_segments_is_caught() {
    let mut p = straight();
    let k = p.segments.len() / 2;
    let seg = &mut p.segments[k];
    let shift = Vector2::new(0.002, 0.0); // 2 mm, consistent inside the segment
    seg.zmp[0] += shift;
    seg.dcm_poly[0] += shift;
    seg.com_poly[0] += shift;
    assert_eq!(rejected(&p, &config()), Invariant::Continuity);
}

#[test]
fn swing_and_contact_disagreements_are_caught() {
    let mut p = straight();
    p.left_swings[0].landing_velocity -= 0.05;
    assert_eq!(rejected(&p, &config()), Invariant::SwingBoundary);

    // a contact moved after the fact no longer matches the swing that lands on it
    let mut p = straight();
    let t = p.left_swings[0].land_time;
    let c = p
        .left_contacts
        .contacts
        .iter_mut()
        .find(|c| c.activation_time == t)
        .expect("landing contact");
    c.pose.rotation = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.01) * c.pose.rotation;
    assert_eq!(rejected(&p, &config()), Invariant::SwingBoundary);
}

#[test]
fn a_plan_that_does_not_end_standing_is_caught() {
    let mut p = straight();
    let end = p.end_time;
    let last = p.left_contacts.contacts.last_mut().expect("final contact");
    last.deactivation_time = Some(end + 1.0);
    assert_eq!(rejected(&p, &config()), Invariant::FinalState);
}

#[test]
fn non_finite_numbers_are_caught_first() {
    let mut p = straight();
    p.right_contacts.contacts[1].pose.translation.x = f64::NAN;
    assert_eq!(rejected(&p, &config()), Invariant::Finite);
    let mut p = straight();
    p.segments[2].growth.x = f64::INFINITY;
    assert_eq!(rejected(&p, &config()), Invariant::Finite);
    assert_eq!(
        straight().verify(&config(), 0.0).map_err(|e| e.invariant),
        Err(Invariant::Finite)
    );
}

/// With `verify_plans = "always"` the planner verifies every plan it makes (also in release builds) and
/// keeps working through replans; `"never"` skips it; the default follows debug assertions.
#[test]
fn the_planner_verifies_its_plans_when_asked() {
    assert_eq!(
        PlanVerification::default().enabled(),
        cfg!(debug_assertions)
    );
    assert!(PlanVerification::Always.enabled() && !PlanVerification::Never.enabled());
    let cfg = PlannerConfig {
        verify_plans: PlanVerification::Always,
        ..config()
    };
    let (l, r) = standing(0.0, 0.0, 0.0, cfg.nominal_width);
    let mut planner = Planner::new(cfg.clone(), GRAVITY).expect("config");
    planner
        .start(
            Duration::ZERO,
            &l,
            &r,
            &Goal::Pose {
                x: 1.0,
                y: 0.0,
                yaw: 0.0,
            },
        )
        .expect("start");
    for (t, goal) in [
        (
            Duration::from_secs(2),
            Goal::Pose {
                x: 1.0,
                y: 0.5,
                yaw: 0.8,
            },
        ),
        (
            Duration::from_millis(4500),
            Goal::Velocity {
                forward: 0.1,
                lateral: 0.0,
                yaw_rate: -0.1,
                duration: Some(3.0),
            },
        ),
    ] {
        planner.replan(t, &goal).expect("replan");
        let merged = planner.plan().expect("plan");
        check_all(&cfg, merged, false);
        assert!(merged.left_contacts.contacts.len() > 1);
    }
}
