//! What the scheduler measures while the loop runs: tracking errors, solve times, joint saturation, and
//! the end checks (fall, goal reached). The figures end up in the [`RunSummary`].

use std::sync::Arc;

use nalgebra::Vector3;
use stride_model::KinDyn;

use crate::config::{EstimationKind, Goal, Scenario};
use crate::diagnosis::{loaded_region, loaded_support, FallDiagnosis, COP_BOUND_MARGIN};
use crate::estimation_summary::EstimationSummary;
use crate::gait::GaitTracker;
use crate::records::{PlantTrackingMsg, TrackingMsg};
use crate::robot::{Measurement, Robot};
use stride_planner::geometry::wrap_angle;

use crate::stack::Stack;
use crate::summary::{goal_pose, mid_pose, Outcome, RunSummary, SolveTimes};

/// The running figures of a run (preallocated: the loop allocates nothing).
pub(crate) struct Tracker {
    pub(crate) summary: RunSummary,
    /// Whole-body solve times \[s\], one per tick.
    pub(crate) wbc_times: Vec<f64>,
    /// Simplified-layer solve times \[s\], one per tick.
    pub(crate) simplified_times: Vec<f64>,
    /// Per joint: simulated time spent at the effort limit \[s\].
    saturated_time: Vec<f64>,
    plant_period: f64,
    gait: GaitTracker,
    simplified_period: f64,
    /// Half length and half width of the sole rectangle \[m\] (`planner.foot_length`, `foot_width`).
    sole_half_size: [f64; 2],
    /// The walking preset's CoP region in the sole frame, `[x, y]` each `[min, max]` \[m\]
    /// (`wbc.walking.cop_x`, `cop_y`).
    cop_region: [[f64; 2]; 2],
    initial_base_height: f64,
    start_mid: [f64; 3],
    standstill_since: Option<u64>,
    /// The plant's own model when its inertial parameters differ from the controllers' (`[sim.model]`):
    /// the plant's CoM and DCM for the summary's ground-truth tracking errors. `None` when the plant's
    /// inertias are the controllers' (then [`Stack::truth`] is already the plant's).
    plant_kd: Option<KinDyn>,
}

impl Tracker {
    /// Starts tracking at the robot's initial measurement (`stack` already estimated from it), with room
    /// for `wbc_ticks` and `simplified_ticks` solve times and the touch-downs of `duration` \[s\].
    pub(crate) fn new(
        scenario: &Scenario,
        robot: &dyn Robot,
        stack: &Stack,
        wbc_ticks: u64,
        simplified_ticks: u64,
        duration: f64,
    ) -> Self {
        let m = robot.measurement();
        let c = &scenario.config;
        let start_mid = mid_pose(&stack.truth.soles);
        let mass = robot.model().total_mass();
        let mut summary = RunSummary::new(&scenario.config.scenario.name, robot.name());
        let plant_kd = (robot.model().inertial_parameters() != stack.model().inertial_parameters())
            .then(|| KinDyn::new(Arc::clone(robot.model())));
        if plant_kd.is_some() {
            summary.plant_tracking = Some(Default::default());
        }
        summary.estimation = EstimationSummary::new(match scenario.config.estimation.kind {
            EstimationKind::Ekf => "ekf",
            EstimationKind::GroundTruth => "ground_truth",
        });
        Self {
            summary,
            wbc_times: Vec::with_capacity(wbc_ticks as usize),
            simplified_times: Vec::with_capacity(simplified_ticks as usize),
            saturated_time: vec![0.0; m.truth.saturated.len()],
            plant_period: robot.period_ns() as f64 * 1e-9,
            gait: GaitTracker::new(&m.truth, mass, duration),
            simplified_period: 1.0 / f64::from(c.rates.simplified_hz),
            sole_half_size: [0.5 * c.planner.foot_length, 0.5 * c.planner.foot_width],
            cop_region: [c.wbc.walking.cop_x, c.wbc.walking.cop_y],
            initial_base_height: m.truth.state.base_pose.translation.z,
            start_mid,
            standstill_since: None,
            plant_kd,
        }
    }

    /// Planar distance of the stance from its start \[m\].
    pub(crate) fn distance(&self, stack: &Stack) -> f64 {
        let mid = mid_pose(&stack.truth.soles);
        ((mid[0] - self.start_mid[0]).powi(2) + (mid[1] - self.start_mid[1]).powi(2)).sqrt()
    }

    /// After a whole-body tick: the estimate against the plant's truth.
    pub(crate) fn estimation(&mut self, stack: &Stack, m: &Measurement) {
        self.summary.estimation.add(&stack.estimate, &m.truth);
    }

    /// After a plant period: joint saturation, actuator work, forward progress (along the soles' heading of
    /// the stack's last measurement) and touch-downs.
    pub(crate) fn plant_period(&mut self, m: &Measurement, stack: &Stack) {
        let time = m.time_ns as f64 * 1e-9;
        let soles = &stack.truth.soles;
        let heading = crate::stack::soles_heading(&soles[0], &soles[1]);
        self.gait.add(time, self.plant_period, &m.truth, heading);
        for (time, saturated) in self.saturated_time.iter_mut().zip(&m.truth.saturated) {
            if *saturated {
                *time += self.plant_period;
            }
        }
    }

    /// Tracking errors and the ZMP's distance to the sole edges at a simplified tick (after the layer ran;
    /// `plant` the robot's measurement), accumulated and returned for the log.
    pub(crate) fn track(&mut self, t: u64, stack: &Stack, plant: &Measurement) -> TrackingMsg {
        let s = &stack.plan_sample;
        let m = &stack.truth;
        let dcm_err = (m.dcm - s.dcm_position.xy()).norm();
        let so = &stack.simplified_output;
        let com_ref = Vector3::new(so.com_position.x, so.com_position.y, s.com_position.z);
        let com_err = (m.com - com_ref).norm();
        let plant_tracking = self.plant_kd.as_mut().and_then(|kd| {
            // The plant's true state and its own model: CoM, CoM velocity and DCM (the plan's ω).
            kd.set_state(&plant.truth.state).ok()?;
            let com = kd.com_position();
            let dcm = com.xy() + kd.com_velocity().xy() / s.omega;
            Some(PlantTrackingMsg {
                dcm_error: (dcm - s.dcm_position.xy()).norm(),
                com_error: (com - com_ref).norm(),
                com: com.into(),
                dcm: dcm.into(),
            })
        });
        if let (Some(p), Some(stats)) = (&plant_tracking, &mut self.summary.plant_tracking) {
            stats.dcm_error.add(p.dcm_error);
            stats.com_error.add(p.com_error);
        }
        let zmp_err = m.zmp_from_wrenches.then(|| (m.zmp - so.desired_zmp).norm());
        let foot_err = |k: usize, planned: &nalgebra::Isometry3<f64>| {
            (m.soles[k].translation.vector - planned.translation.vector).norm()
        };
        let feet_err = foot_err(0, &s.left.pose).max(foot_err(1, &s.right.pose));
        let zmp_edge_distance = self.zmp_edge(stack, plant);
        let summary = &mut self.summary;
        summary
            .diagnosis
            .dcm_error_peak
            .add(dcm_err, t as f64 * 1e-9);
        summary.dcm_error.add(dcm_err);
        summary.com_error.add(com_err);
        if let Some(z) = zmp_err {
            summary.zmp_error.add(z);
        }
        summary.feet_error.add(feet_err);
        TrackingMsg {
            time: t as f64 * 1e-9,
            dcm_error: dcm_err,
            com_error: com_err,
            zmp_error: zmp_err,
            zmp_edge_distance,
            feet_error: feet_err,
            measured_com: m.com.into(),
            measured_dcm: m.dcm.into(),
            measured_zmp: m.zmp.into(),
            base_height: m.base_height,
            tilt_deg: m.tilt.to_degrees(),
            push_estimate: stack.push.as_ref().map(|p| p.estimate().into()),
            plant: plant_tracking,
        }
    }

    /// The measured ZMP against the support polygon of the loaded feet (as [`Stack::measure`] loads them),
    /// accumulated over a simplified period, and against the hull of their CoP regions: its signed distance
    /// to the support polygon's boundary \[m\] (`None` without a measurable ZMP).
    fn zmp_edge(&mut self, stack: &Stack, plant: &Measurement) -> Option<f64> {
        let m = &stack.truth;
        let truth = &plant.truth;
        let loaded = [0, 1].map(|k| truth.feet_in_contact[k] && truth.foot_wrenches[k][2] > 0.0);
        let [hl, hw] = self.sole_half_size;
        let polygon = loaded_support(&m.soles, loaded, hl, hw).filter(|_| m.zmp_from_wrenches)?;
        let heading = crate::stack::soles_heading(&m.soles[0], &m.soles[1]);
        let dt = self.simplified_period;
        let [x, y] = self.cop_region;
        if let Some(region) = loaded_region(&m.soles, loaded, x, y) {
            self.summary.diagnosis.cop_bound.add_within(
                m.zmp,
                &region,
                heading,
                dt,
                COP_BOUND_MARGIN,
            );
        }
        Some(
            self.summary
                .diagnosis
                .zmp_edge
                .add(m.zmp, &polygon, heading, dt),
        )
    }

    /// The summary at the end of the run, with the stance pose `end` ([`mid_pose`]) and the loop's
    /// wall-clock time \[s\].
    pub(crate) fn finish(
        mut self,
        stack: &Stack,
        goal: &Goal,
        outcome: Outcome,
        end: [f64; 3],
        wall: f64,
    ) -> RunSummary {
        let model = stack.model();
        let mut saturation: Vec<(String, f64)> = self
            .saturated_time
            .iter()
            .enumerate()
            .filter(|(_, t)| **t > 0.0)
            .map(|(i, t)| (model.joints()[i].name.clone(), *t))
            .collect();
        saturation.sort_by(|a, b| b.1.total_cmp(&a.1));
        let s = &mut self.summary;
        s.outcome = outcome;
        s.joint_saturation = saturation;
        s.wbc_solve_time = SolveTimes::from(&mut self.wbc_times);
        s.simplified_solve_time = SolveTimes::from(&mut self.simplified_times);
        let counters = &stack.counters;
        s.wbc_fallbacks = counters.wbc_fallbacks;
        s.wbc_holds = counters.wbc_holds;
        s.simplified_holds = counters.simplified_holds;
        s.replans = counters.replans;
        s.step_adjustments = (counters.step_adjustments, counters.step_adjustment_failures);
        s.early_touchdowns = counters.early_touchdowns;
        s.push_holds = stack.push_holds();
        s.push_weight_ticks = stack.push_weights.as_ref().map_or(0, |w| w.ticks);
        s.finish(self.start_mid, end, goal, wall);
        s.gait = self.gait.finish(s.distance);
        s.estimation.finish(s.distance);
        self.summary
    }
}

/// Fall and goal checks after the layers ran (on a fresh estimate); `fallen` is the plant's own fall
/// detector. `None` while the run goes on.
pub(crate) fn end_check(
    tracker: &mut Tracker,
    scenario: &Scenario,
    stack: &Stack,
    t: u64,
    fallen: bool,
) -> Option<Outcome> {
    let outcome = fall_check(tracker, scenario, stack, fallen);
    if outcome.is_some() {
        let fall = FallDiagnosis::new(t as f64 * 1e-9, &stack.truth, &stack.plan_sample);
        tracker.summary.diagnosis.fall = Some(fall);
        return outcome;
    }
    goal_check(tracker, scenario, stack, t)
}

/// The fall checks: base height, torso tilt, the plant's own detector; `None` while standing.
fn fall_check(
    tracker: &mut Tracker,
    scenario: &Scenario,
    stack: &Stack,
    fallen: bool,
) -> Option<Outcome> {
    let e = &scenario.config.end;
    let m = &stack.truth;
    let frac = m.base_height / tracker.initial_base_height;
    let summary = &mut tracker.summary;
    summary.min_base_height_fraction = summary.min_base_height_fraction.min(frac);
    summary.max_tilt_deg = summary.max_tilt_deg.max(m.tilt.to_degrees());
    if frac < e.fall_height_fraction {
        let reason = format!(
            "base height {:.3} m is below {:.0} % of the initial {:.3} m",
            m.base_height,
            e.fall_height_fraction * 100.0,
            tracker.initial_base_height
        );
        return Some(Outcome::Fell { reason });
    }
    if m.tilt.to_degrees() > e.fall_tilt_deg {
        let reason = format!(
            "torso tilt {:.1}° exceeds {:.1}°",
            m.tilt.to_degrees(),
            e.fall_tilt_deg
        );
        return Some(Outcome::Fell { reason });
    }
    if fallen {
        let reason = "the simulator's fall detector fired".into();
        return Some(Outcome::Fell { reason });
    }
    None
}

/// Goal reached and standing still for `end.standstill_time`; `None` while the run goes on.
fn goal_check(
    tracker: &mut Tracker,
    scenario: &Scenario,
    stack: &Stack,
    t: u64,
) -> Option<Outcome> {
    let e = &scenario.config.end;
    let m = &stack.truth;
    if !(e.stop_at_goal && stack.plan_finished(t)) {
        return None;
    }
    let goal_ok = goal_pose(&scenario.config.goal).is_some_and(|g| {
        let p = mid_pose(&m.soles);
        let heading_error = wrap_angle(p[2] - g[2]).abs().to_degrees();
        ((p[0] - g[0]).powi(2) + (p[1] - g[1]).powi(2)).sqrt() <= e.goal_position_tolerance
            && heading_error <= e.goal_heading_tolerance_deg
    });
    if goal_ok && m.com_velocity.xy().norm() < e.standstill_speed {
        let since = *tracker.standstill_since.get_or_insert(t);
        if (t - since) as f64 * 1e-9 >= e.standstill_time {
            return Some(Outcome::GoalReached);
        }
    } else {
        tracker.standstill_since = None;
    }
    None
}
