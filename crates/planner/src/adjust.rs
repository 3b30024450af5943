//! Mid-swing step adjustment of a plan: the swinging foot is retargeted to a new touch-down (position and
//! time) and the rest of the plan is replanned from that touch-down, the way a merge point replans
//! [Griffin 2017; Khadiv 2020].
//!
//! What changes, at the adjustment time `t` (inside a single support, stance foot S, swing foot W):
//! * W's swing: [`SwingTrajectory::retarget`] from its desired state at `t` to the new target, landing at
//!   the new time `T` (continuous position, velocity and acceleration at `t`); going round S's sole
//!   ([`SwingTrajectory::go_round`]) when the straight path to a crossed target would pass over it.
//! * DCM/ZMP/CoM: unchanged up to `T`. The single-support segment holds the ZMP on S; its closed form is
//!   extended (or cut) to end at `T` instead of the planned touch-down, so the plan is continuous at `t`
//!   and at `T`.
//! * Everything after `T`: a new plan from the state at `T` with W standing on the new target (the
//!   unicycle re-anchored on it, as the planner's replanning does on the last touch-down) and S swinging
//!   first, towards the same goal; it starts with a double support whose extra ZMP term makes the DCM
//!   start exactly at the old plan's state (see [`crate::dcm`]).
//! * A crossed touch-down (W lands past S, the step a push towards the stance foot calls for): the old
//!   plan's DCM at `T` lies outside the hull of the two soles, where no ZMP inside the support can bring it
//!   back (ξ̇ = ω(ξ − ZMP) drives it away from every support point). The rest of the single support then
//!   moves its ZMP inside S's sole (a smooth transition from its value at `t`, so ZMP, DCM and CoM stay
//!   continuous) to the point that brings the DCM at `T` nearest the middle of the two soles
//!   (`support_tail`), and the plan after `T` starts from the crossed pair: its first double support keeps
//!   the ZMP in the crossed hull, and the unicycle, re-anchored on W, puts S out past W at the nominal width
//!   (the step that uncrosses).
//! * A replan from the measured DCM ([`crate::Planner::adjust_step_from`], for a push): the rest of the
//!   single support is always the moved-ZMP tail above, but its DCM starts at the given DCM instead of the
//!   old plan's (the segment is marked [`DcmSegment::restart`]: the CoM and the ZMP stay continuous, the
//!   DCM jumps to where the robot is), so the touch-down state, and the plan after it, are predicted from
//!   the pushed robot rather than from a plan the push has left: a crossover the old plan's DCM could not
//!   reach (it diverges to the uncrossed side from the stance sole's centre) is planned when the measured
//!   one is already on the crossed side.

use std::time::Duration;

use nalgebra::{Isometry3, Vector2, Vector3};
use serde::{Deserialize, Serialize};
use stride_block::seconds;

use crate::build::{build_plan, double_support_polygon, xy, StartState};
use crate::config::PlannerConfig;
use crate::contacts::{Foot, Phase, PhaseKind};
use crate::dcm::{zmp_constant, zmp_transition, DcmSegment};
use crate::error::PlannerError;
use crate::geometry::Pose2;
use crate::goal::Goal;
use crate::plan::Plan;
use crate::planner::spliced_plan;
use crate::swing::{RetargetOutcome, SwingTrajectory};
use crate::unicycle::waypoints_passed;

/// The step of a plan that is being executed at some instant of single support (borrowed from the plan:
/// no allocation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurrentStep<'a> {
    /// The foot on the ground.
    pub stance: Foot,
    /// Its sole pose.
    pub stance_pose: nalgebra::Isometry3<f64>,
    /// When it touched down (the plan start for the initial stance) \[s\].
    pub stance_touchdown: f64,
    /// The swing of the other foot (lift-off, touch-down, target pose).
    pub swing: &'a SwingTrajectory,
}

impl Plan {
    /// The step being executed at `t` \[s\]: `None` unless `t` is inside a single support with the other
    /// foot swinging.
    pub fn current_step(&self, t: f64) -> Option<CurrentStep<'_>> {
        let PhaseKind::SingleSupport { stance } = self.phase_at(t) else {
            return None;
        };
        let contact = self.contacts(stance).active_at(t)?;
        let swings = self.swings(stance.other());
        let i = swings
            .partition_point(|s| s.lift_time <= t)
            .checked_sub(1)?;
        let swing = &swings[i];
        (t < swing.land_time).then_some(CurrentStep {
            stance,
            stance_pose: contact.pose,
            stance_touchdown: contact.activation_time,
            swing,
        })
    }
}

/// A request to move the touch-down of the swinging foot.
///
/// `time` is the instant of the request (plan time `stride_block::seconds(time)`); `land_time` is a plan
/// time, like the plan's own touch-down times it is compared with exactly (a request that keeps the
/// planned touch-down passes the plan's `f64` unchanged, which a nanosecond `Duration` could not).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepAdjustmentRequest {
    /// When (inside the single support).
    pub time: Duration,
    /// New touch-down position of the sole (world x, y; the height and the orientation stay) \[m\].
    pub target: Vector2<f64>,
    /// New touch-down time, plan time \[s\].
    pub land_time: f64,
    /// No retarget with less than this left before the current or the new touch-down \[s\] (freeze).
    pub min_remaining: f64,
}

/// Adjusts `plan` (see the module documentation); `start_dcm`: the DCM \[m\] the rest of the single
/// support restarts from (`None`: the old plan's, continuous). `Ok(None)` when the swing is frozen or
/// unchanged (nothing to do); errors leave the caller's plan as it was (it is not modified here).
pub(crate) fn adjusted_plan(
    cfg: &PlannerConfig,
    omega: f64,
    plan: &Plan,
    request: &StepAdjustmentRequest,
    goal: &Goal,
    start_dcm: Option<Vector2<f64>>,
) -> Result<Option<Plan>, PlannerError> {
    let t = seconds(request.time);
    let step = plan
        .current_step(t)
        .ok_or(PlannerError::NoMergePoint { time: t })?;
    let swing_foot = step.stance.other();
    let mut swing = step.swing.clone();
    let z = swing.end.translation.z;
    let target = Vector3::new(request.target.x, request.target.y, z);
    match swing.retarget(t, target, request.land_time, request.min_remaining) {
        RetargetOutcome::Retargeted => {}
        RetargetOutcome::Unchanged | RetargetOutcome::Frozen => return Ok(None),
    }
    // a crossed target: the rest of the swing goes round the stance sole
    if !swing.go_round(t, &step.stance_pose, cfg.foot_length, cfg.foot_width) {
        return Err(PlannerError::SwingOverStance { time: t });
    }
    let land = swing.land_time;
    let tail = support_tail(
        cfg,
        omega,
        plan,
        (t, land),
        (&step.stance_pose, &swing.end),
        start_dcm,
    );
    let state = match &tail {
        Some([_, hold]) => hold.evaluate_local(land - hold.start, omega),
        None => single_support_state(plan, omega, t, land),
    };
    let landed = Pose2::from_isometry(&swing.end);
    let anchor_xy = landed.transform_point(Vector2::new(
        0.0,
        -swing_foot.side() * 0.5 * cfg.nominal_width,
    ));
    let (left, right, left_since, right_since) = match swing_foot {
        Foot::Left => (swing.end, step.stance_pose, land, step.stance_touchdown),
        Foot::Right => (step.stance_pose, swing.end, step.stance_touchdown, land),
    };
    let start = StartState {
        t_start: land,
        anchor_time: land,
        anchor: Pose2 {
            x: anchor_xy.x,
            y: anchor_xy.y,
            yaw: landed.yaw,
        },
        min_initial_ds: 0.5
            * (1.0 - cfg.merge_point_fraction)
            * cfg.double_support_fraction
            * cfg.step_duration_min,
        left,
        right,
        left_since,
        right_since,
        zmp0: state.zmp,
        dcm0: state.dcm,
        com0: state.com,
        ground: plan.ground_height,
        first_swing: Some(step.stance),
    };
    // towards the waypoints not yet passed: the full list would send the robot back to the first one
    let (goal, passed) = remaining_goal(cfg, plan, goal, anchor_xy)?;
    let goal = closing_goal(cfg, goal, &start.anchor);
    let mut new = build_plan(cfg, omega, &start, &goal)?;
    if let Some(p) = new.waypoint_progress.as_mut() {
        p.passed = passed;
    }
    Ok(Some(splice(plan, new, t, swing, tail)))
}

/// Smallest depth of the DCM inside the two soles' hull at a touch-down for the single support to be kept
/// as planned \[m\].
const TOUCHDOWN_DCM_MARGIN: f64 = 0.01;
/// Margin of the moved ZMP inside the stance sole's edges \[m\].
const TAIL_ZMP_MARGIN: f64 = 0.01;
/// Time the moved ZMP takes to reach its point in the stance sole \[s\].
const TAIL_ZMP_RISE: f64 = 0.05;

/// The rest of the single support `[t, land]` with its ZMP moved inside the stance sole, when the old
/// plan's DCM at `land` would lie less than [`TOUCHDOWN_DCM_MARGIN`] inside the hull of the stance sole and
/// the landed one (a crossed touch-down); `None` otherwise (the plan is kept as it is up to `land`).
///
/// Two segments: the ZMP goes from its value at `t` to a point `z` of the sole in [`TAIL_ZMP_RISE`] (or half
/// the time left) with the smooth step of [`zmp_transition`], then stays there; the DCM starts at the old
/// plan's. The DCM at `land` is affine in `z` with the same scalar gain on both axes, so the `z` that brings
/// it onto the middle of the two soles is one division, then clamped into the sole (shrunk by
/// [`TAIL_ZMP_MARGIN`]; the clamp of a rectangle in its own frame is the nearest point, and the map from `z`
/// to the DCM is a scaling). The DCM moves by at most the sole's half width times `e^{ωΔ} − 1` (`Δ` the time
/// left): a crossover asked for late in the swing may still be refused.
///
/// With `start_dcm` the tail is always built and its DCM starts there (the first segment marked
/// [`DcmSegment::restart`]; the CoM and the ZMP start at the old plan's).
pub(crate) fn support_tail(
    cfg: &PlannerConfig,
    omega: f64,
    plan: &Plan,
    (t, land): (f64, f64),
    (stance, landed): (&Isometry3<f64>, &Isometry3<f64>),
    start_dcm: Option<Vector2<f64>>,
) -> Option<[DcmSegment; 2]> {
    let hull = double_support_polygon(cfg, &[*stance, *landed])?;
    let kept = hull.signed_distance(single_support_state(plan, omega, t, land).dcm)
        >= TOUCHDOWN_DCM_MARGIN;
    if kept && start_dcm.is_none() {
        return None;
    }
    let mut now = single_support_state(plan, omega, t, t);
    if let Some(dcm) = start_dcm {
        now.dcm = dcm;
    }
    let rise = TAIL_ZMP_RISE.min(0.5 * (land - t));
    let tail_to = |z: Vector2<f64>| {
        let mut up = DcmSegment::new(
            t,
            Some(rise),
            zmp_transition(now.zmp, z, Vector2::zeros(), rise),
            omega,
        );
        up.growth = now.dcm - up.dcm_poly[0];
        up.restart = start_dcm.is_some();
        up.set_com_start(now.com);
        let top = up.evaluate_local(rise, omega);
        let mut hold = DcmSegment::new(t + rise, Some(land - t - rise), zmp_constant(z), omega);
        hold.growth = top.dcm - hold.dcm_poly[0];
        hold.set_com_start(top.com);
        [up, hold]
    };
    let end_dcm = |z: Vector2<f64>| {
        let [_, hold] = tail_to(z);
        hold.evaluate_local(land - t - rise, omega).dcm
    };
    let base = end_dcm(now.zmp);
    let gain = end_dcm(now.zmp + Vector2::x()).x - base.x;
    let aim = (xy(stance) + xy(landed)) * 0.5;
    let wanted = now.zmp + (aim - base) / gain;
    let sole = Pose2::from_isometry(stance);
    let local = sole.inverse_transform_point(wanted);
    let (hx, hy) = (
        (0.5 * cfg.foot_length - TAIL_ZMP_MARGIN).max(0.0),
        (0.5 * cfg.foot_width - TAIL_ZMP_MARGIN).max(0.0),
    );
    let clamped = Vector2::new(local.x.clamp(-hx, hx), local.y.clamp(-hy, hy));
    Some(tail_to(sole.transform_point(clamped)))
}

/// The goal a step adjustment replans towards from `anchor`, and how many of `goal`'s waypoints it drops:
/// a waypoint goal without the waypoints the plan's path has passed where it comes closest to `anchor`
/// (never the last one); any other goal as it is.
fn remaining_goal(
    cfg: &PlannerConfig,
    plan: &Plan,
    goal: &Goal,
    anchor: Vector2<f64>,
) -> Result<(Goal, usize), PlannerError> {
    let (Goal::Waypoints { points }, Some(progress)) = (goal, plan.waypoint_progress) else {
        return Ok((goal.clone(), 0));
    };
    let before = progress.passed.min(points.len().saturating_sub(1));
    let passed = before + waypoints_passed(cfg, progress.origin, &points[before..], anchor)?;
    let points = points[passed..].to_vec();
    Ok((Goal::Waypoints { points }, passed))
}

/// The goal a step adjustment replans towards when its anchor (the feet's mid-point once the other foot
/// stands beside the adjusted step) is within `arrival_tolerance` of the final goal position: that goal
/// moved onto the anchor, its heading kept (the plan closes in place: the stance foot steps beside the
/// adjusted one, and turns only if the heading differs); `goal` itself otherwise, and for a velocity goal
/// or standing.
///
/// Without it, a closing step adjusted sideways by a few centimetres replanned towards the goal's position:
/// the unicycle cannot move sideways, so the plan turned in place towards it (the direction of a 2.5 cm
/// lateral offset is ±90°), walked the 2.5 cm and turned back. On `walk_fast` with the push layers and the
/// step adjustment each adjustment of a step round the goal did so again: 41 steps at the goal, the walk
/// ending at 45 s turned by −101° (docs/push-recovery.md, "Without pushes nothing gets worse").
fn closing_goal(cfg: &PlannerConfig, goal: Goal, anchor: &Pose2) -> Goal {
    let (position, yaw) = match &goal {
        Goal::Pose { x, y, yaw } => (Vector2::new(*x, *y), Some(*yaw)),
        Goal::Waypoints { points } if points.len() == 1 => {
            (Vector2::new(points[0].x, points[0].y), points[0].yaw)
        }
        _ => return goal,
    };
    if (position - anchor.position()).norm() > cfg.arrival_tolerance {
        return goal;
    }
    match goal {
        Goal::Pose { .. } => Goal::Pose {
            x: anchor.x,
            y: anchor.y,
            yaw: yaw.unwrap_or(anchor.yaw),
        },
        _ => Goal::Waypoints {
            points: vec![crate::goal::Waypoint {
                x: anchor.x,
                y: anchor.y,
                yaw,
            }],
        },
    }
}

/// The old plan's DCM/ZMP/CoM at `land`, with the single-support segment at `t` extended to `land`.
fn single_support_state(plan: &Plan, omega: f64, t: f64, land: f64) -> crate::dcm::PlanarState {
    let i = plan.segments.partition_point(|s| s.start <= t).max(1) - 1;
    let mut seg = plan.segments[i].clone();
    seg.duration = Some(land - seg.start);
    seg.evaluate_local(land - seg.start, omega)
}

/// The old plan up to `t` (its single-support segment and phase stretched to the new touch-down, or cut
/// at `t` and followed by `tail` up to it), the retargeted `swing`, then `new` from the touch-down on.
fn splice(
    old: &Plan,
    mut new: Plan,
    t: f64,
    swing: SwingTrajectory,
    tail: Option<[DcmSegment; 2]>,
) -> Plan {
    let land = swing.land_time;
    let mut segments: Vec<_> = old
        .segments
        .iter()
        .filter(|s| s.start <= t)
        .cloned()
        .collect();
    let cut = if tail.is_some() { t } else { land };
    if let Some(last) = segments.last_mut() {
        last.duration = Some(cut - last.start);
    }
    if let Some(tail) = tail {
        if segments.last().is_some_and(|s| s.duration == Some(0.0)) {
            segments.pop();
        }
        segments.extend(tail);
    }
    segments.append(&mut new.segments);
    let mut phases: Vec<Phase> = old
        .phases
        .iter()
        .filter(|p| p.start <= t)
        .cloned()
        .collect();
    if let Some(last) = phases.last_mut() {
        last.end = land;
    }
    phases.append(&mut new.phases);
    spliced_plan(old, new, t, segments, phases, Some(swing))
}
