//! `Planner::adjust_step_from`: a step adjustment replanned from a given (measured) DCM. The early crossed
//! touch-down that `Planner::adjust_step` refuses (the plan's own DCM diverges to the uncrossed side, see
//! `adjust_step.rs`) is planned when the DCM it restarts from is already on the crossed side, and still
//! refused when it restarts from the plan's own DCM or from one on the uncrossed side; the restarted plan
//! keeps the CoM and the ZMP continuous, starts its DCM where asked, passes the run-time verification and
//! reaches the goal.

mod common;

use common::*;
use std::time::Duration;

use nalgebra::Vector2;
use stride_planner::{
    Goal, PhaseKind, PlanVerification, Planner, PlannerConfig, PlannerError, StepAdjustmentRequest,
};

const GOAL: Goal = Goal::Pose {
    x: 2.0,
    y: 0.0,
    yaw: 0.0,
};

fn planner() -> Planner {
    let cfg = PlannerConfig {
        com_height: 0.54,
        nominal_width: 0.15,
        verify_plans: PlanVerification::Always,
        ..Default::default()
    };
    let (l, r) = standing(0.0, 0.0, 0.0, cfg.nominal_width);
    let mut p = Planner::new(cfg, GRAVITY).unwrap();
    p.start(Duration::ZERO, &l, &r, &GOAL).unwrap();
    p
}

/// The `n`-th single support of a fresh plan, 0.02 s after its lift-off, its swing retargeted `inward`
/// metres past the stance foot to land 0.39 s later (the step a released hold asks for): the planner, the
/// request, the stance foot's position and its side (+1 left).
fn early_crossed(n: usize, inward: f64) -> (Planner, StepAdjustmentRequest, Vector2<f64>, f64) {
    let p = planner();
    let phase = p
        .plan()
        .unwrap()
        .phases
        .iter()
        .filter(|ph| matches!(ph.kind, PhaseKind::SingleSupport { .. }))
        .nth(n)
        .copied()
        .unwrap();
    let (time, t) = instant(phase.start + 0.02);
    let step = p.plan().unwrap().current_step(t).unwrap();
    let stance = step.stance_pose.translation.vector.xy();
    let side = step.stance.side();
    let nominal = step.swing.end.translation.vector.xy();
    let request = StepAdjustmentRequest {
        time,
        target: Vector2::new(nominal.x, stance.y + side * inward),
        land_time: t + 0.39,
        min_remaining: 0.1,
    };
    (p, request, stance, side)
}

#[test]
fn an_early_crossed_touch_down_is_planned_from_a_dcm_on_the_crossed_side_and_refused_from_the_plans(
) {
    for n in [1, 2, 3] {
        for inward in [0.15, 0.25] {
            // `adjust_step` (the plan's own DCM, the tail only when the DCM would land outside the
            // crossed pair) and a restart from a DCM 5 cm on the uncrossed side of the stance foot:
            // refused, the plan unchanged
            let (mut p, request, stance, side) = early_crossed(n, inward);
            let t = stride_block::seconds(request.time);
            let before = p.plan().unwrap().clone();
            let own = sample(&before, t).dcm_position.xy();
            for from in [None, Some(stance - Vector2::new(0.0, side * 0.05))] {
                let refused = p.adjust_step_from(&request, &GOAL, from);
                assert!(
                    matches!(refused, Err(PlannerError::ZmpOutsideSupport { .. })),
                    "step {n}, {inward} m from {from:?}: {refused:?}"
                );
                assert_eq!(p.plan().unwrap(), &before);
            }
            // restarted from the plan's own DCM (the tail always built) or from one 5 cm past the stance
            // foot's centre on the crossed side (a push towards the stance foot): planned
            for dcm in [own, stance + Vector2::new(0.0, side * 0.05)] {
                let (mut p, ..) = early_crossed(n, inward);
                let applied = p.adjust_step_from(&request, &GOAL, Some(dcm));
                assert!(
                    matches!(applied, Ok(true)),
                    "step {n}, {inward} m from {dcm:?}: {applied:?}"
                );
                restarted_plan_holds(&p, &before, &request, dcm);
            }
        }
    }
}

/// The plan of `p`, restarted from `dcm` at `request`'s time: CoM and ZMP continuous there, the DCM
/// starting at `dcm`; continuous at the crossed touch-down, which lands on the target; ZMP in the support,
/// the LIPM relations and the swing shapes on the whole plan; the walk ends at the goal.
fn restarted_plan_holds(
    p: &Planner,
    before: &stride_planner::Plan,
    request: &StepAdjustmentRequest,
    dcm: Vector2<f64>,
) {
    let t = stride_block::seconds(request.time);
    let new = p.plan().unwrap();
    let (a, b) = (sample(new, t - 1e-7), sample(new, t + 1e-7));
    assert!(
        (a.com_position - b.com_position).norm() < 1e-6,
        "CoM at {t}"
    );
    assert!((a.zmp - b.zmp).norm() < 1e-5, "ZMP at {t}");
    assert!((b.dcm_position.xy() - dcm).norm() < 1e-6, "DCM at {t}");
    // continuous at the crossed touch-down; lands on the target
    let land = request.land_time;
    let (a, b) = (sample(new, land - 1e-7), sample(new, land + 1e-7));
    assert!((a.dcm_position - b.dcm_position).norm() < 1e-6);
    assert!((a.com_position - b.com_position).norm() < 1e-6);
    let step = before.current_step(t).unwrap();
    let crossed = new
        .contacts(step.stance.other())
        .active_at(land + 1e-3)
        .unwrap();
    assert!((crossed.pose.translation.vector.xy() - request.target).norm() < 1e-12);
    // ZMP in the support, the LIPM relations and the continuity from the restart on (the DCM jumps at
    // `t`: the plan before it is the old one), the swing shapes on the whole plan; the walk ends at the
    // goal
    let mut after = new.clone();
    after.segments.retain(|g| g.start >= t);
    after.start_time = t;
    assert!(after.segments[0].restart && after.segments.iter().skip(1).all(|g| !g.restart));
    check_dynamics(p.config(), &after, 0.01);
    check_swings(p.config(), new);
    let l = new
        .contacts(stride_planner::Foot::Left)
        .contacts
        .last()
        .unwrap();
    let r = new
        .contacts(stride_planner::Foot::Right)
        .contacts
        .last()
        .unwrap();
    let mid = (l.pose.translation.vector + r.pose.translation.vector) * 0.5;
    assert!((mid.x - 2.0).abs() < 0.02 && mid.y.abs() < 0.02, "{mid:?}");
}

#[test]
fn a_non_finite_dcm_is_refused() {
    let (mut p, request, _, _) = early_crossed(1, 0.15);
    let before = p.plan().unwrap().clone();
    for bad in [f64::NAN, f64::INFINITY] {
        let r = p.adjust_step_from(&request, &GOAL, Some(Vector2::new(0.3, bad)));
        assert!(matches!(r, Err(PlannerError::InvalidTime { .. })), "{r:?}");
        assert_eq!(p.plan().unwrap(), &before);
    }
}
