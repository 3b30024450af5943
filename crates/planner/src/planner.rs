//! The planner object: start from standing, replan with merge points, sample, `Block` implementation.

use std::time::Duration;

use nalgebra::{Isometry3, Vector2};
use stride_block::seconds;

use crate::adjust::{adjusted_plan, StepAdjustmentRequest};
use crate::build::{build_plan, xy, StartState};
use crate::config::{check_gravity, PlannerConfig};
use crate::contacts::{ContactList, Foot, Phase, PhaseKind, PlannedContact};
use crate::dcm::DcmSegment;
use crate::error::PlannerError;
use crate::geometry::{feet_lateral_separation, wrap_angle, Pose2};
use crate::goal::Goal;
use crate::plan::{Plan, PlanSample};
use crate::swing::SwingTrajectory;

fn check_time(name: &'static str, t: f64) -> Result<(), PlannerError> {
    if t.is_finite() {
        Ok(())
    } else {
        Err(PlannerError::InvalidTime {
            name,
            value: t,
            reason: "must be finite",
        })
    }
}

/// Plans from standing: both feet on the ground at `left`/`right` (sole frames, world), CoM at rest above
/// their mid-point, at time `t0` \[s\], under gravity of magnitude `gravity_m_s2` \[m/s²\] (finite
/// and positive). The plan starts with `initial_double_support_duration` of weight shifting and ends standing
/// with parallel feet and the DCM on their mid-point.
pub fn plan_from_standing(
    config: &PlannerConfig,
    gravity_m_s2: f64,
    t0: f64,
    left: &Isometry3<f64>,
    right: &Isometry3<f64>,
    goal: &Goal,
) -> Result<Plan, PlannerError> {
    config.validate()?;
    check_gravity(gravity_m_s2)?;
    goal.validate()?;
    check_time("t0", t0)?;
    for (name, h) in [("left_sole", left), ("right_sole", right)] {
        let ok = h.translation.vector.iter().all(|v| v.is_finite())
            && h.rotation.coords.iter().all(|v| v.is_finite());
        if !ok {
            return Err(PlannerError::InvalidStart {
                name,
                reason: "pose is not finite".into(),
            });
        }
    }
    let (l2, r2) = (Pose2::from_isometry(left), Pose2::from_isometry(right));
    let rel = r2.inverse_transform_point(l2.position());
    let dyaw = wrap_angle(l2.yaw - r2.yaw);
    if dyaw.abs() > config.max_yaw_per_step {
        return Err(PlannerError::InvalidStart {
            name: "left_sole",
            reason: format!(
                "relative yaw of the feet {dyaw:.4} rad exceeds max_yaw_per_step {}",
                config.max_yaw_per_step
            ),
        });
    }
    if rel.y < config.foot_width
        || rel.norm() > config.feet_distance_max.max(config.nominal_width) * 1.5
    {
        return Err(PlannerError::InvalidStart {
            name: "left_sole",
            reason: format!(
                "left sole at ({:.4}, {:.4}) in the right sole frame: it must be to the left by at least \
                 foot_width and not farther than 1.5 feet_distance_max",
                rel.x, rel.y
            ),
        });
    }
    let mid = (xy(left) + xy(right)) * 0.5;
    let yaw = r2.yaw + 0.5 * dyaw;
    let start = StartState {
        t_start: t0,
        anchor_time: t0,
        anchor: Pose2 {
            x: mid.x,
            y: mid.y,
            yaw,
        },
        min_initial_ds: config.initial_double_support_duration,
        left: *left,
        right: *right,
        left_since: t0,
        right_since: t0,
        zmp0: mid,
        dcm0: mid,
        com0: mid,
        ground: 0.5 * (left.translation.z + right.translation.z),
        first_swing: None,
    };
    build_plan(config, config.omega(gravity_m_s2), &start, goal)
}

/// The trajectory-layer object: holds the current plan, replans on new goals, samples references.
///
/// ```
/// use std::time::Duration;
/// use stride_planner::prelude::*;
/// use nalgebra::Isometry3;
///
/// let mut planner = Planner::new(PlannerConfig::default(), 9.81)?;
/// let input = PlannerInput {
///     time: Duration::ZERO,
///     goal: Some(Goal::Pose { x: 0.5, y: 0.0, yaw: 0.0 }),
///     left_sole: Isometry3::translation(0.0, 0.075, 0.0),
///     right_sole: Isometry3::translation(0.0, -0.075, 0.0),
/// };
/// let sample = planner.step(&input)?; // inherent: no need to import `Block`
/// assert!(sample.left.in_contact && sample.right.in_contact);
/// let mut later = PlanSample::default();
/// planner.sample(Duration::from_secs(2), &mut later)?;
/// assert!(later.com_position.x > 0.0);
/// # Ok::<(), PlannerError>(())
/// ```
#[derive(Clone, Debug)]
pub struct Planner {
    config: PlannerConfig,
    /// Gravity magnitude \[m/s²\] (validated).
    gravity: f64,
    plan: Option<Plan>,
    output: PlanSample,
}

impl Planner {
    /// A planner for `config` under gravity of magnitude `gravity_m_s2` \[m/s²\] (the scenario's one
    /// gravity; ω = √(g/h) of the plans follows from it). Validates both: `InvalidParameter` for the
    /// config, `InvalidGravity` unless the gravity is finite and > 0.
    pub fn new(config: PlannerConfig, gravity_m_s2: f64) -> Result<Self, PlannerError> {
        config.validate()?;
        check_gravity(gravity_m_s2)?;
        Ok(Self {
            config,
            gravity: gravity_m_s2,
            plan: None,
            output: PlanSample::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &PlannerConfig {
        &self.config
    }

    /// The gravity magnitude the planner was built with \[m/s²\].
    pub fn gravity(&self) -> f64 {
        self.gravity
    }

    /// The current plan, if any.
    pub fn plan(&self) -> Option<&Plan> {
        self.plan.as_ref()
    }

    /// Starts a new plan from standing at `t0` (plan time `seconds(t0)`, see [`plan_from_standing`]);
    /// replaces any previous plan.
    pub fn start(
        &mut self,
        t0: Duration,
        left: &Isometry3<f64>,
        right: &Isometry3<f64>,
        goal: &Goal,
    ) -> Result<&Plan, PlannerError> {
        let t0 = seconds(t0);
        let plan = plan_from_standing(&self.config, self.gravity, t0, left, right, goal)?;
        self.verify(&plan)?;
        Ok(self.plan.insert(plan))
    }

    /// Writes the references at `t` (plan time `seconds(t)`, [`Plan::sample`]) into `out` (no allocation).
    pub fn sample(&self, t: Duration, out: &mut PlanSample) -> Result<(), PlannerError> {
        let plan = self.plan.as_ref().ok_or(PlannerError::NoPlan)?;
        plan.sample(seconds(t), out);
        Ok(())
    }

    /// The merge point a replan requested at `t` would use: the first double support whose merge point
    /// (`merge_point_fraction` into it) is at or after `t` and leaves some double support after it; in the
    /// final double support (or standing) any time works. Returns the merge point in plan time \[s\].
    pub fn merge_time(&self, t: Duration) -> Result<f64, PlannerError> {
        let plan = self.plan.as_ref().ok_or(PlannerError::NoPlan)?;
        merge_point(&self.config, plan, seconds(t))
    }

    /// Merges a plan towards `goal` into the current one at the first merge point after `t`. Feet planned
    /// before the merge point do not move; DCM position/velocity, CoM and feet are continuous across it.
    /// Returns the merge time in plan time \[s\]. On error the current plan is unchanged.
    pub fn replan(&mut self, t: Duration, goal: &Goal) -> Result<f64, PlannerError> {
        goal.validate()?;
        let plan = self.plan.as_ref().ok_or(PlannerError::NoPlan)?;
        let t = seconds(t);
        let cfg = &self.config;
        let m = merge_point(cfg, plan, t)?;
        let mut s = PlanSample::default();
        plan.sample(m, &mut s);
        let lc = plan.left_contacts.active_at(m).cloned();
        let rc = plan.right_contacts.active_at(m).cloned();
        let (Some(lc), Some(rc)) = (lc, rc) else {
            return Err(PlannerError::NoMergePoint { time: t });
        };
        // next single support in the old plan decides who swings first
        let next_ss = plan
            .phases
            .iter()
            .find(|p| p.start >= m && matches!(p.kind, PhaseKind::SingleSupport { .. }));
        let current_ds = plan
            .phases
            .iter()
            .rev()
            .find(|p| p.start <= m && p.kind == PhaseKind::DoubleSupport);
        let f = cfg.double_support_fraction;
        let min_remaining = 0.5 * (1.0 - cfg.merge_point_fraction) * f * cfg.step_duration_min;
        let (first_swing, anchor, anchor_time, min_init) = match next_ss {
            Some(Phase {
                kind: PhaseKind::SingleSupport { stance },
                ..
            }) => {
                let swing = stance.other();
                // re-anchor the unicycle on the most recently landed foot, if it landed in this plan
                let landed = if lc.activation_time >= rc.activation_time {
                    &lc
                } else {
                    &rc
                };
                let ds_start = current_ds.map_or(plan.start_time, |p| p.start);
                let ds_end = current_ds.map_or(m, |p| p.end);
                if landed.activation_time > plan.start_time
                    && landed.activation_time >= ds_start - 1e-12
                {
                    let p = Pose2::from_isometry(&landed.pose);
                    let c = p.transform_point(Vector2::new(
                        0.0,
                        -landed.foot.side() * 0.5 * cfg.nominal_width,
                    ));
                    (
                        Some(swing),
                        Pose2 {
                            x: c.x,
                            y: c.y,
                            yaw: p.yaw,
                        },
                        landed.activation_time,
                        min_remaining,
                    )
                } else {
                    (
                        Some(swing),
                        mid_pose(&lc.pose, &rc.pose),
                        m,
                        (ds_end - m).max(min_remaining),
                    )
                }
            }
            _ => (
                None,
                mid_pose(&lc.pose, &rc.pose),
                m,
                cfg.initial_double_support_duration,
            ),
        };
        let start = StartState {
            t_start: m,
            anchor_time,
            anchor,
            min_initial_ds: min_init,
            left: lc.pose,
            right: rc.pose,
            left_since: lc.activation_time,
            right_since: rc.activation_time,
            zmp0: Vector2::new(s.zmp.x, s.zmp.y),
            dcm0: Vector2::new(s.dcm_position.x, s.dcm_position.y),
            com0: Vector2::new(s.com_position.x, s.com_position.y),
            ground: plan.ground_height,
            first_swing,
        };
        let new = build_plan(cfg, cfg.omega(self.gravity), &start, goal)?;
        let merged = merge(plan, new, m);
        self.verify(&merged)?;
        self.plan = Some(merged);
        Ok(m)
    }

    /// Moves the touch-down of the swinging foot at `request.time` (inside a single support) to
    /// `request.target` at `request.land_time`, retargeting the swing mid-air and replanning everything
    /// after the new touch-down towards `goal` (see [`crate::adjust`]). Returns whether the plan changed
    /// (`false`: the swing is frozen near touch-down, or the request asks for no change). On error the
    /// current plan is unchanged.
    ///
    /// The adjusted plan is verified like every plan, except that the adjusted step itself may be longer
    /// than `feet_distance_max` and shorter than `step_duration_min` (the caller's step-adjustment box and
    /// duration limits bound it): the verification bounds are widened to exactly that step.
    pub fn adjust_step(
        &mut self,
        request: &StepAdjustmentRequest,
        goal: &Goal,
    ) -> Result<bool, PlannerError> {
        self.adjust_step_from(request, goal, None)
    }

    /// [`Planner::adjust_step`] with the rest of the single support restarted from `dcm` \[m\] when given
    /// (a measured DCM, with a push's offset: the touch-down state and the plan after it predicted from
    /// where the robot is; the plan's DCM jumps there at `request.time`, its CoM and ZMP stay continuous;
    /// see [`crate::adjust`]). `None`: [`Planner::adjust_step`]. Errors: a non-finite `dcm`, and those of
    /// [`Planner::adjust_step`].
    pub fn adjust_step_from(
        &mut self,
        request: &StepAdjustmentRequest,
        goal: &Goal,
        dcm: Option<Vector2<f64>>,
    ) -> Result<bool, PlannerError> {
        goal.validate()?;
        let plan = self.plan.as_ref().ok_or(PlannerError::NoPlan)?;
        check_time("request.land_time", request.land_time)?;
        check_time("request.min_remaining", request.min_remaining)?;
        if let Some(d) = dcm {
            check_time("dcm.x", d.x)?;
            check_time("dcm.y", d.y)?;
        }
        let t = seconds(request.time);
        let omega = self.config.omega(self.gravity);
        let Some(adjusted) = adjusted_plan(&self.config, omega, plan, request, goal, dcm)? else {
            return Ok(false);
        };
        if self.config.verify_plans.enabled() {
            let step = plan
                .current_step(t)
                .ok_or(PlannerError::NoMergePoint { time: t })?;
            let length = (request.target - xy(&step.stance_pose)).norm();
            let duration = request.land_time - step.stance_touchdown;
            let mut cfg = self.config.clone();
            cfg.feet_distance_max = cfg.feet_distance_max.max(length + 1e-9);
            cfg.step_duration_min = cfg.step_duration_min.min(duration - 1e-9);
            // a crossed touch-down: the adjustment's own width (the uncrossing step after it is the
            // unicycle's, at the nominal width; the soles still may not overlap)
            let stance = Pose2::from_isometry(&step.stance_pose);
            let landed = Pose2 {
                x: request.target.x,
                y: request.target.y,
                yaw: Pose2::from_isometry(&step.swing.end).yaw,
            };
            let width = match step.stance {
                Foot::Left => feet_lateral_separation(stance, landed),
                Foot::Right => feet_lateral_separation(landed, stance),
            };
            cfg.min_width = cfg.min_width.min(width - 1e-9);
            // the step after the adjusted touch-down: its double support may have been lengthened until
            // the ZMP stays in the support (as the first double support of any replan)
            if let Some(next) = adjusted
                .swings(step.stance)
                .iter()
                .find(|s| s.lift_time >= request.land_time)
            {
                let d = next.land_time - request.land_time;
                cfg.step_duration_max = cfg.step_duration_max.max(d + 1e-9);
            }
            adjusted.verify(&cfg, VERIFY_SAMPLING_PERIOD)?;
        }
        self.plan = Some(adjusted);
        Ok(true)
    }

    /// Verifies `plan` when [`PlannerConfig::verify_plans`] is enabled in this build.
    fn verify(&self, plan: &Plan) -> Result<(), PlannerError> {
        if self.config.verify_plans.enabled() {
            plan.verify(&self.config, VERIFY_SAMPLING_PERIOD)?;
        }
        Ok(())
    }
}

/// Sampling period of the run-time plan verification \[s\].
pub const VERIFY_SAMPLING_PERIOD: f64 = 0.01;

fn mid_pose(l: &Isometry3<f64>, r: &Isometry3<f64>) -> Pose2 {
    let (a, b) = (Pose2::from_isometry(l), Pose2::from_isometry(r));
    let mid = (a.position() + b.position()) * 0.5;
    Pose2 {
        x: mid.x,
        y: mid.y,
        yaw: b.yaw + 0.5 * wrap_angle(a.yaw - b.yaw),
    }
}

fn merge_point(cfg: &PlannerConfig, plan: &Plan, t: f64) -> Result<f64, PlannerError> {
    let t = t.max(plan.start_time);
    let r = cfg.merge_point_fraction;
    let min_remaining = 0.5 * (1.0 - r) * cfg.double_support_fraction * cfg.step_duration_min;
    let last = plan.phases.len().saturating_sub(1);
    for (i, p) in plan.phases.iter().enumerate() {
        if p.kind != PhaseKind::DoubleSupport {
            continue;
        }
        let m = (p.start + r * (p.end - p.start)).max(t);
        if i == last {
            return Ok(m);
        }
        if m <= p.end - min_remaining {
            return Ok(m);
        }
    }
    if plan.phases.is_empty() {
        return Ok(t);
    }
    Err(PlannerError::NoMergePoint { time: t })
}

fn merge(old: &Plan, mut new: Plan, m: f64) -> Plan {
    let mut segments: Vec<DcmSegment> = old
        .segments
        .iter()
        .filter(|s| s.start < m)
        .cloned()
        .collect();
    if let Some(last) = segments.last_mut() {
        last.duration = Some(m - last.start);
    }
    segments.append(&mut new.segments);
    let mut phases: Vec<Phase> = old.phases.iter().filter(|p| p.start < m).cloned().collect();
    let mut new_phases = std::mem::take(&mut new.phases).into_iter();
    match phases.last_mut() {
        Some(last) if last.kind == PhaseKind::DoubleSupport => {
            if let Some(first) = new_phases.next() {
                last.end = first.end;
            }
        }
        _ => {}
    }
    phases.extend(new_phases);
    spliced_plan(old, new, m, segments, phases, None)
}

/// The plan made of `old` up to `t` and `new` after it, given the DCM `segments` and `phases` the caller has
/// already joined: the contacts that ended by `t` and the swings that landed by `t` are kept, then `new`'s;
/// `current_swing` (a swing in progress at `t`, e.g. retargeted) goes between the two lists of its foot. Shared
/// by the merge of a replan and by a step adjustment.
pub(crate) fn spliced_plan(
    old: &Plan,
    new: Plan,
    t: f64,
    segments: Vec<DcmSegment>,
    phases: Vec<Phase>,
    current_swing: Option<SwingTrajectory>,
) -> Plan {
    let keep = |list: &ContactList, new: ContactList| {
        let mut c: Vec<PlannedContact> = list
            .contacts
            .iter()
            .filter(|c| c.deactivation_time.is_some_and(|d| d <= t))
            .cloned()
            .collect();
        c.extend(new.contacts);
        ContactList {
            foot: list.foot,
            contacts: c,
        }
    };
    let keep_swings = |foot: Foot, old: &[SwingTrajectory], new: Vec<SwingTrajectory>| {
        let mut s: Vec<SwingTrajectory> =
            old.iter().filter(|s| s.land_time <= t).cloned().collect();
        s.extend(current_swing.iter().filter(|c| c.foot == foot).cloned());
        s.extend(new);
        s
    };
    let mut merge_times = old.merge_times.clone();
    merge_times.push(t);
    Plan {
        omega: new.omega,
        com_height: new.com_height,
        ground_height: new.ground_height,
        foot_length: new.foot_length,
        foot_width: new.foot_width,
        start_time: old.start_time,
        end_time: new.end_time,
        segments,
        phases,
        left_contacts: keep(&old.left_contacts, new.left_contacts),
        right_contacts: keep(&old.right_contacts, new.right_contacts),
        left_swings: keep_swings(Foot::Left, &old.left_swings, new.left_swings),
        right_swings: keep_swings(Foot::Right, &old.right_swings, new.right_swings),
        outcome: new.outcome,
        merge_times,
        waypoint_progress: new.waypoint_progress,
    }
}

/// Input of the planner block for one tick.
#[derive(Clone, Debug, PartialEq)]
pub struct PlannerInput {
    /// Current time.
    pub time: Duration,
    /// A new goal, if one arrived this tick (a replan, or the first plan).
    pub goal: Option<Goal>,
    /// Measured left sole pose (used only to start the first plan).
    pub left_sole: Isometry3<f64>,
    /// Measured right sole pose (used only to start the first plan).
    pub right_sole: Isometry3<f64>,
}

impl Planner {
    /// First call: starts a plan from the measured soles (standing if no goal). Later calls with a goal:
    /// replan at the next merge point (this allocates; ticks without a goal do not). Then samples.
    ///
    /// Inherent, so a caller need not import [`stride_block::Block`] (the `Block` impl calls it).
    pub fn step(&mut self, input: &PlannerInput) -> Result<&PlanSample, PlannerError> {
        let t = input.time;
        if self.plan.is_none() {
            let goal = input.goal.clone().unwrap_or(Goal::Stand);
            self.start(t, &input.left_sole, &input.right_sole, &goal)?;
        } else if let Some(goal) = &input.goal {
            self.replan(t, goal)?;
        }
        let Self { plan, output, .. } = self;
        if let Some(p) = plan.as_ref() {
            p.sample(seconds(t), output);
        }
        Ok(&self.output)
    }
}

impl stride_block::Block for Planner {
    type Input = PlannerInput;
    type Output = PlanSample;
    type Error = PlannerError;

    fn step(&mut self, input: &PlannerInput) -> Result<&PlanSample, PlannerError> {
        Planner::step(self, input)
    }

    fn reset(&mut self) {
        self.plan = None;
        self.output = PlanSample::default();
    }
}
