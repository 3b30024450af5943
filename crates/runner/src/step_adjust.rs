//! The runner's side of the step adjustment (issue 13 part 1): which step is in progress and its nominal
//! (planned before any adjustment), the step-adjustment QP's input from the plan and the measured DCM, the
//! dead bands, and the `/planner/adjusted_footsteps` record.
//!
//! Per simplified tick in single support: the QP ([`stride_simplified::StepAdjuster`], [Khadiv 2020]) gets
//! the measured DCM, the stance foot, the planned single-support ZMP (held until touch-down), the nominal
//! touch-down `u_n`, the nominal offset `b_n = ξ_plan(T_n) − u_n`, the time since the stance foot touched
//! down and the nominal step duration. Its touch-down and time go to [`stride_planner::Planner::adjust_step`]
//! when they differ from the planned ones by more than `deadband` / `time_deadband`. The plan's last
//! step is kept while the ankle can absorb the DCM error (`closing_dcm_margin`).

use std::time::Duration;

use nalgebra::Vector2;
use serde::Serialize;
use stride_block::seconds;
use stride_planner::{CurrentStep, Foot, Plan, PlanSample, StepAdjustmentRequest};
use stride_qp::QpStatus;
use stride_simplified::{
    feet_support_polygon, FootRectangle, StepAdjuster, StepAdjustment, StepAdjustmentInput,
    StepAdjustmentStatus,
};

/// The step in progress: its nominal and what the plan currently has.
#[derive(Debug, Clone, Copy, PartialEq)]
struct TrackedStep {
    /// Lift-off time of the swing \[s\] (identifies the step; a retarget keeps it).
    lift: f64,
    swing_foot: Foot,
    stance_touchdown: f64,
    nominal_target: Vector2<f64>,
    nominal_land: f64,
    nominal_offset: Vector2<f64>,
    /// Touch-down position and time the plan has now \[m, s\].
    target: Vector2<f64>,
    land: f64,
}

/// Follows the steps of the plan; no allocation.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepTracker {
    step: Option<TrackedStep>,
    /// Time \[s\] and value of the low-passed DCM error (`dcm_error_cutoff`).
    error: Option<(f64, Vector2<f64>)>,
}

impl StepTracker {
    /// The adjustment to apply at `time`, if any: `None` outside single support, with less than
    /// `min_remaining_time` before the planned touch-down (frozen), when the QP falls back or when its
    /// answer is within the dead bands of what the plan has. `push.0` is the single-support ZMP the
    /// QP predicts the DCM with (the plan's, or the push-aware one of [`crate::push::PushResponse`]),
    /// `push.1` the shift of the nominal DCM offset at touch-down (zero, or
    /// [`crate::push::PushResponse::step_offset_shift`]).
    pub fn request(
        &mut self,
        plan: &Plan,
        adjuster: &mut StepAdjuster,
        dcm: &Vector2<f64>,
        sample: &PlanSample,
        push: (Vector2<f64>, Vector2<f64>),
        time: Duration,
    ) -> Option<StepAdjustmentRequest> {
        let (stance_cop, offset_shift) = push;
        let t = seconds(time);
        let cutoff = adjuster.config().dcm_error_cutoff;
        let dcm = &self.filtered_dcm(cutoff, dcm, sample.dcm_position.xy(), t);
        let Some(step) = plan.current_step(t) else {
            self.step = None;
            return None;
        };
        let lift = step.swing.lift_time;
        let tracked = match self.step {
            Some(s) if s.lift == lift && s.swing_foot == step.swing.foot => s,
            _ => {
                let target = step.swing.end.translation.vector.xy();
                let land = step.swing.land_time;
                let s = TrackedStep {
                    lift,
                    swing_foot: step.swing.foot,
                    stance_touchdown: step.stance_touchdown,
                    nominal_target: target,
                    nominal_land: land,
                    nominal_offset: plan.planar_at(land).dcm - target,
                    target,
                    land,
                };
                self.step = Some(s);
                s
            }
        };
        // frozen near touch-down: the planner would refuse, and the QP's remaining-time bound would ask
        // for a later touch-down than planned
        if tracked.land - t < adjuster.config().min_remaining_time {
            return None;
        }
        let c = adjuster.config();
        let cop_box = Vector2::new(c.cop_x, c.cop_y);
        let closing = ClosingStep {
            target: tracked.target,
            land: tracked.land,
            margin: c.closing_dcm_margin,
        };
        if closing_step_holds(
            plan,
            &step,
            &closing,
            dcm,
            (&stance_cop, cop_box),
            sample.omega,
            t,
        ) {
            return None;
        }
        let input = StepAdjustmentInput {
            dcm: *dcm,
            omega: sample.omega,
            stance: step.stance,
            stance_position: step.stance_pose.translation.vector.xy(),
            stance_yaw: step.stance_pose.rotation.euler_angles().2,
            stance_cop,
            nominal_step: tracked.nominal_target,
            nominal_offset: tracked.nominal_offset + offset_shift,
            time_since_touchdown: t - tracked.stance_touchdown,
            nominal_duration: tracked.nominal_land - tracked.stance_touchdown,
        };
        let r = *adjuster.solve(&input).ok()?;
        if r.diagnostics.status != StepAdjustmentStatus::Solved {
            return None;
        }
        let c = adjuster.config();
        let land = tracked.stance_touchdown + r.duration;
        let moved = (r.touchdown - tracked.target).norm() > c.deadband;
        let retimed = (land - tracked.land).abs() > c.time_deadband;
        (moved || retimed).then_some(StepAdjustmentRequest {
            time,
            target: r.touchdown,
            land_time: land,
            min_remaining: c.min_remaining_time,
        })
    }

    /// The DCM the QP reads: the planned DCM plus the measured error low-passed at `cutoff` Hz (first
    /// order, discretised exactly over the time since the last call); `cutoff` 0: the measured DCM.
    fn filtered_dcm(
        &mut self,
        cutoff: f64,
        dcm: &Vector2<f64>,
        planned: Vector2<f64>,
        t: f64,
    ) -> Vector2<f64> {
        if cutoff <= 0.0 {
            self.error = None;
            return *dcm;
        }
        let error = dcm - planned;
        let filtered = match self.error {
            Some((t0, e)) if t > t0 => {
                let a = 1.0 - (-std::f64::consts::TAU * cutoff * (t - t0)).exp();
                e + a * (error - e)
            }
            _ => error,
        };
        self.error = Some((t, filtered));
        planned + filtered
    }

    /// Records that the planner applied `request` (solved as `result`); returns the log record.
    pub fn applied(
        &mut self,
        request: &StepAdjustmentRequest,
        result: &StepAdjustment,
        dcm: &Vector2<f64>,
    ) -> AdjustedFootstepMsg {
        let Some(s) = self.step.as_mut() else {
            return AdjustedFootstepMsg::default();
        };
        s.target = request.target;
        s.land = request.land_time;
        AdjustedFootstepMsg {
            time: seconds(request.time),
            foot: match s.swing_foot {
                Foot::Left => "left",
                Foot::Right => "right",
            },
            nominal_position: s.nominal_target.into(),
            position: request.target.into(),
            displacement: (request.target - s.nominal_target).into(),
            nominal_touchdown_time: s.nominal_land,
            touchdown_time: request.land_time,
            measured_dcm: (*dcm).into(),
            offset_slack: result.diagnostics.offset_slack.into(),
            bound_active: result.diagnostics.bound_active,
            qp_status: result.diagnostics.qp_status,
            iterations: result.diagnostics.iterations,
        }
    }
}

/// The step in progress as the plan has it now, and the depth the closing-step rule asks for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ClosingStep {
    /// Planned touch-down position \[m\].
    pub target: Vector2<f64>,
    /// Planned touch-down time \[s\].
    pub land: f64,
    /// `closing_dcm_margin` \[m\]; 0: the rule is off.
    pub margin: f64,
}

/// Whether the step in progress is the plan's last and the ankle can still absorb the DCM error: the
/// DCM predicted at its touch-down from the stance CoP, `p + (ξ − p) e^{ω(T−t)}`, moved by what the CoP
/// box `p ± cop_box` (stance frame) can shift it by over the remaining time, `cop_box (e^{ω(T−t)} − 1)`,
/// towards the middle of the final double support, ends at least `margin` inside the hull of the stance
/// sole and the planned landed sole. Then the step is not adjusted (a closing step moved for an error
/// the ankle takes costs CoM and feet tracking with no gain, docs/push-recovery.md). `margin` 0: never.
pub(crate) fn closing_step_holds(
    plan: &Plan,
    step: &CurrentStep<'_>,
    closing: &ClosingStep,
    dcm: &Vector2<f64>,
    (stance_cop, cop_box): (&Vector2<f64>, Vector2<f64>),
    omega: f64,
    t: f64,
) -> bool {
    if closing.margin <= 0.0 {
        return false;
    }
    let later = |foot: Foot| {
        plan.swings(foot)
            .last()
            .is_some_and(|s| s.lift_time > step.swing.lift_time)
    };
    if later(step.stance) || later(step.stance.other()) {
        return false;
    }
    let mut landed = step.swing.end;
    landed.translation.vector.x = closing.target.x;
    landed.translation.vector.y = closing.target.y;
    let soles = [
        FootRectangle::centred(&step.stance_pose, plan.foot_length, plan.foot_width),
        FootRectangle::centred(&landed, plan.foot_length, plan.foot_width),
    ];
    let Ok(hull) = feet_support_polygon(&soles) else {
        return false;
    };
    let growth = (omega * (closing.land - t).max(0.0)).exp();
    let predicted = stance_cop + (dcm - stance_cop) * growth;
    let mid = (step.stance_pose.translation.vector.xy() + closing.target) * 0.5;
    let (sin, cos) = step.stance_pose.rotation.euler_angles().2.sin_cos();
    let to_mid = mid - predicted;
    let local = Vector2::new(
        cos * to_mid.x + sin * to_mid.y,
        -sin * to_mid.x + cos * to_mid.y,
    );
    let reach = cop_box * (growth - 1.0);
    let moved = Vector2::new(
        local.x.clamp(-reach.x, reach.x),
        local.y.clamp(-reach.y, reach.y),
    );
    let nearest =
        predicted + Vector2::new(cos * moved.x - sin * moved.y, sin * moved.x + cos * moved.y);
    hull.max_violation(nearest) <= -closing.margin
}

/// `/planner/adjusted_footsteps`: one footstep adjustment applied to the plan (world frame, SI units).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Default)]
pub struct AdjustedFootstepMsg {
    /// When \[s\].
    pub time: f64,
    /// The swinging foot (`left` / `right`).
    pub foot: &'static str,
    /// Touch-down position of the step as planned before any adjustment \[m\].
    pub nominal_position: [f64; 2],
    /// Adjusted touch-down position \[m\].
    pub position: [f64; 2],
    /// `position − nominal_position` \[m\].
    pub displacement: [f64; 2],
    /// Planned touch-down time before any adjustment \[s\].
    pub nominal_touchdown_time: f64,
    /// Adjusted touch-down time \[s\].
    pub touchdown_time: f64,
    /// The measured DCM the QP used \[m\].
    pub measured_dcm: [f64; 2],
    /// Slacks of the DCM-offset bounds \[m\] (stance frame).
    pub offset_slack: [f64; 2],
    /// Whether a box or duration bound was active.
    pub bound_active: bool,
    /// The QP's status.
    pub qp_status: QpStatus,
    /// Active-set iterations.
    pub iterations: usize,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 40 mm jump of the measured DCM lasting 20 ms (the iCub's transient, docs/push-recovery.md)
    /// reaches the QP as `1 − e^{−2π f 0.02}` of itself at `f` = 2 Hz (8.9 mm) and decays after it; a
    /// lasting error is passed whole (to 0.1 mm after 1 s); cut-off 0 passes the measured DCM unchanged.
    #[test]
    fn the_dcm_error_filter_attenuates_a_short_transient_and_passes_a_lasting_error() {
        let planned = Vector2::new(0.15, -0.06);
        let jump = Vector2::new(0.0, -0.04);
        let mut tracker = StepTracker::default();
        let dt = 0.002;
        let at = |k: usize| k as f64 * dt;
        for k in 0..100 {
            assert_eq!(tracker.filtered_dcm(2.0, &planned, planned, at(k)), planned);
        }
        let mut seen = Vector2::zeros();
        for k in 100..110 {
            seen = tracker.filtered_dcm(2.0, &(planned + jump), planned, at(k)) - planned;
        }
        let expected = jump * (1.0 - (-std::f64::consts::TAU * 2.0 * 0.02).exp());
        assert!(
            (seen - expected).norm() < 1e-12,
            "{seen:?} against {expected:?}"
        );
        assert!(seen.norm() < 0.009);
        let after = tracker.filtered_dcm(2.0, &planned, planned, at(160)) - planned;
        assert!(after.norm() < seen.norm());
        let mut lasting = Vector2::zeros();
        for k in 161..=660 {
            lasting = tracker.filtered_dcm(2.0, &(planned + jump), planned, at(k)) - planned;
        }
        assert!((lasting - jump).norm() < 1e-4, "{lasting:?}");
        let raw = planned + Vector2::new(0.0123, -0.0456);
        assert_eq!(tracker.filtered_dcm(0.0, &raw, planned, at(661)), raw);
    }

    /// A plan from standing at the origin to (0.6, 0) with the planner's defaults, and the middle of its
    /// `n`-th single support counted from the end (0: the last) as plan time.
    fn short_walk(from_end: usize) -> (Plan, f64) {
        use stride_planner::{Goal, PhaseKind, Planner, PlannerConfig};
        let cfg = PlannerConfig::default();
        let sole = |y: f64| nalgebra::Isometry3::translation(0.0, y, 0.0);
        let h = 0.5 * cfg.nominal_width;
        let mut planner = Planner::new(cfg, 9.81).unwrap();
        let goal = Goal::Pose {
            x: 0.6,
            y: 0.0,
            yaw: 0.0,
        };
        planner
            .start(Duration::ZERO, &sole(h), &sole(-h), &goal)
            .unwrap();
        let plan = planner.plan().unwrap().clone();
        let phase = plan
            .phases
            .iter()
            .rev()
            .filter(|ph| matches!(ph.kind, PhaseKind::SingleSupport { .. }))
            .nth(from_end)
            .copied()
            .unwrap();
        (plan, 0.5 * (phase.start + phase.end))
    }

    /// The closing step is kept on the planned DCM and on a 1 cm error the ankle absorbs; it is left to
    /// the QP on a 12 cm lateral error the CoP box cannot bring back into the final double support, on
    /// any step but the last, and with `closing_dcm_margin` 0.
    #[test]
    fn the_closing_step_is_kept_while_the_ankle_absorbs_the_dcm_error() {
        let config = stride_simplified::StepAdjustmentConfig::default();
        assert_eq!(config.closing_dcm_margin, 0.02);
        let cop_box = Vector2::new(config.cop_x, config.cop_y);
        let holds = |from_end: usize, error: Vector2<f64>, margin: f64| {
            let (plan, t) = short_walk(from_end);
            let mut s = PlanSample::default();
            plan.sample(t, &mut s);
            let step = plan.current_step(t).unwrap();
            let closing = ClosingStep {
                target: step.swing.end.translation.vector.xy(),
                land: step.swing.land_time,
                margin,
            };
            let cop = s.zmp.xy();
            let dcm = s.dcm_position.xy() + error;
            closing_step_holds(&plan, &step, &closing, &dcm, (&cop, cop_box), s.omega, t)
        };
        let margin = config.closing_dcm_margin;
        assert!(holds(0, Vector2::zeros(), margin));
        assert!(holds(0, Vector2::new(0.01, 0.0), margin));
        assert!(holds(0, Vector2::new(0.0, -0.01), margin));
        for outward in [0.12, -0.12] {
            assert!(!holds(0, Vector2::new(0.0, outward), margin), "{outward}");
        }
        assert!(!holds(0, Vector2::new(0.25, 0.0), margin));
        assert!(!holds(1, Vector2::zeros(), margin));
        assert!(!holds(0, Vector2::zeros(), 0.0));
    }
}
