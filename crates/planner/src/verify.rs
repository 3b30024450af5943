//! Run-time verification of a plan's invariants.
//!
//! The planner builds plans that satisfy these invariants by construction, and the property tests check
//! them on thousands of random plans with independent code. [`Plan::verify`] makes the same promises
//! checkable at run time, on the plan a robot is about to execute: the [`crate::Planner`] calls it after
//! every plan and replan when [`crate::PlannerConfig::verify_plans`] says so (by default in debug builds, as
//! `debug_assert!` would), and a user embedding the planner can call it on any plan, e.g. one read back from a
//! log. A violated invariant is an error value naming the invariant, the time and the numbers; it is never a
//! panic.
//!
//! | invariant | what is checked | tolerance |
//! |---|---|---|
//! | `finite` | every number of the plan (segments, contacts, swings, times) | – |
//! | `step_length` | at every touch-down: distance between the soles in `[feet_distance_min, feet_distance_max]` | 1e-9 m |
//! | `step_width` | at every touch-down: left sole at least `min_width` to the left of the right one (in the right-sole frame or, mirrored, the left-sole frame: `geometry::feet_lateral_separation`) | 1e-9 m |
//! | `step_yaw` | at every touch-down: relative yaw of the soles within `max_yaw_per_step` | 1e-9 rad |
//! | `feet_overlap` | at every touch-down: the two sole rectangles do not intersect | – |
//! | `step_duration` | touch-down to touch-down in `[step_duration_min, step_duration_max]` (after the last merge: a merge may shorten the step it falls in) | 1e-9 s |
//! | `zmp_in_support` | ZMP inside the support polygon, sampled every `dt` and at every segment start | 1e-9 m |
//! | `dcm_dynamics` | `ξ = x + ẋ/ω`, `ξ̇ = ω(ξ − ZMP)` and `ẍ = ω²(x − ZMP)` at every sample | 1e-9 (relative to 1 m) |
//! | `continuity` | DCM, CoM, their velocities and the ZMP continuous at every segment boundary (at a segment that restarts from a measured DCM, `DcmSegment::restart`, only the CoM and the ZMP) | 1e-8 |
//! | `swing_boundary` | each swing leaves its contact pose at rest and lands on the next contact pose with the planned landing velocity | 1e-9 |
//! | `final_state` | after `end_time` both feet are in contact and the DCM rests on the ZMP within 1 mm | 1e-3 m |

use nalgebra::{Vector2, Vector6};
use serde::{Deserialize, Serialize};

use crate::config::PlannerConfig;
use crate::contacts::Foot;
use crate::geometry::{feet_lateral_separation, wrap_angle, Pose2};
use crate::plan::{Plan, PlanSample};
use stride_block::SupportPolygon;

pub use crate::error::{Invariant, InvariantViolation};

/// Tolerance on lengths and angles of the step checks \[m, rad, s\].
const STEP_TOLERANCE: f64 = 1e-9;
/// Tolerance on the sampled LIPM identities and the ZMP-in-polygon test \[m\].
const DYNAMICS_TOLERANCE: f64 = 1e-9;
/// Tolerance on the continuity at segment boundaries.
const CONTINUITY_TOLERANCE: f64 = 1e-8;
/// Largest distance of the final DCM from the final ZMP \[m\].
const FINAL_DCM_TOLERANCE: f64 = 1e-3;
/// Largest number of samples [`Plan::verify`] takes (the sampling period is widened beyond it).
const MAX_SAMPLES: f64 = 1.0e6;

/// What a successful [`Plan::verify`] measured: margins, for logs and tuning.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct VerifyReport {
    /// Instants sampled.
    pub samples: usize,
    /// Touch-downs checked.
    pub touch_downs: usize,
    /// Smallest distance of the ZMP from the support-polygon boundary over the samples \[m\].
    pub min_zmp_margin: f64,
    /// Smallest lateral sole distance at a touch-down minus `min_width` \[m\] (∞ without steps).
    pub min_width_margin: f64,
    /// Largest DCM distance from the final ZMP at the end of the plan \[m\].
    pub final_dcm_error: f64,
}

fn violation(invariant: Invariant, time: f64, detail: String) -> InvariantViolation {
    InvariantViolation {
        invariant,
        time,
        detail,
    }
}

/// `value > limit`, with NaN counting as exceeding.
fn exceeds(value: f64, limit: f64) -> bool {
    value.is_nan() || value > limit
}

fn all_finite<'a>(values: impl IntoIterator<Item = &'a f64>) -> bool {
    values.into_iter().all(|v| v.is_finite())
}

/// The separating-axis test for two convex quadrilaterals.
pub(crate) fn quadrilaterals_intersect(a: &[Vector2<f64>; 4], b: &[Vector2<f64>; 4]) -> bool {
    for poly in [a, b] {
        for i in 0..4 {
            let e = poly[(i + 1) % 4] - poly[i];
            let axis = Vector2::new(-e.y, e.x);
            let range = |p: &[Vector2<f64>; 4]| {
                p.iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), q| {
                        let d = axis.dot(q);
                        (lo.min(d), hi.max(d))
                    })
            };
            let (a_lo, a_hi) = range(a);
            let (b_lo, b_hi) = range(b);
            if a_hi < b_lo || b_hi < a_lo {
                return false;
            }
        }
    }
    true
}

impl Plan {
    /// Checks every invariant of the module table, sampling the DCM/ZMP/CoM every `dt` seconds \[s\] (and at
    /// every segment start); `config` gives the step bounds (the configuration the plan was made with).
    /// Allocates nothing per sample; about 0.3 µs per sample (2.2 ms for a 68 s, 68-step plan at `dt` = 10 ms,
    /// 3.5× the time to make that plan). Returns the margins it measured, or
    /// the first violation found.
    pub fn verify(
        &self,
        config: &PlannerConfig,
        dt: f64,
    ) -> Result<VerifyReport, InvariantViolation> {
        self.verify_finite()?;
        if !(dt.is_finite() && dt > 0.0) {
            return Err(violation(
                Invariant::Finite,
                self.start_time,
                format!("sampling period dt = {dt} must be finite and > 0"),
            ));
        }
        let mut report = VerifyReport {
            samples: 0,
            touch_downs: 0,
            min_zmp_margin: f64::INFINITY,
            min_width_margin: f64::INFINITY,
            final_dcm_error: 0.0,
        };
        self.verify_steps(config, &mut report)?;
        self.verify_swings()?;
        self.verify_samples(dt, &mut report)?;
        self.verify_continuity()?;
        self.verify_final_state(&mut report)?;
        Ok(report)
    }

    fn verify_finite(&self) -> Result<(), InvariantViolation> {
        let scalars = [
            self.omega,
            self.com_height,
            self.ground_height,
            self.foot_length,
            self.foot_width,
            self.start_time,
            self.end_time,
        ];
        if !all_finite(&scalars) || self.omega <= 0.0 {
            return Err(violation(
                Invariant::Finite,
                self.start_time,
                format!("plan constants {scalars:?} (ω must be > 0)"),
            ));
        }
        for seg in &self.segments {
            if let Some(quantity) = seg.non_finite_quantity() {
                return Err(violation(
                    Invariant::Finite,
                    seg.start,
                    format!("a DCM segment has a non-finite {quantity} coefficient"),
                ));
            }
        }
        for foot in [Foot::Left, Foot::Right] {
            for c in &self.contacts(foot).contacts {
                let pose = c.pose.to_homogeneous();
                if !c.activation_time.is_finite()
                    || c.deactivation_time.is_some_and(|t| !t.is_finite())
                    || !all_finite(pose.iter())
                {
                    return Err(violation(
                        Invariant::Finite,
                        c.activation_time,
                        format!("a {} contact is not finite", foot.name()),
                    ));
                }
            }
            for sw in self.swings(foot) {
                let times = [sw.lift_time, sw.apex_time, sw.land_time, sw.apex_height];
                if !all_finite(&times) {
                    return Err(violation(
                        Invariant::Finite,
                        sw.lift_time,
                        format!("a {} swing is not finite: {times:?}", foot.name()),
                    ));
                }
            }
        }
        Ok(())
    }

    fn verify_steps(
        &self,
        config: &PlannerConfig,
        report: &mut VerifyReport,
    ) -> Result<(), InvariantViolation> {
        let last_merge = self
            .merge_times
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        let mut previous_touch_down: Option<f64> = None;
        // touch-downs of both feet in time order (the swings of each foot are sorted)
        let (mut i, mut j) = (0, 0);
        let (left, right) = (&self.left_swings, &self.right_swings);
        while i < left.len() || j < right.len() {
            let take_left =
                j >= right.len() || (i < left.len() && left[i].land_time <= right[j].land_time);
            let t = if take_left {
                i += 1;
                left[i - 1].land_time
            } else {
                j += 1;
                right[j - 1].land_time
            };
            report.touch_downs += 1;
            if let Some(t0) = previous_touch_down.filter(|&t0| t0 >= last_merge) {
                let d = t - t0;
                if d < config.step_duration_min - STEP_TOLERANCE
                    || d > config.step_duration_max + STEP_TOLERANCE
                {
                    return Err(violation(
                        Invariant::StepDuration,
                        t,
                        format!(
                            "{d:.6} s since the previous touch-down, outside [{}, {}] s",
                            config.step_duration_min, config.step_duration_max
                        ),
                    ));
                }
            }
            previous_touch_down = Some(t);
            let (Some(l), Some(r)) = (
                self.left_contacts.active_at(t),
                self.right_contacts.active_at(t),
            ) else {
                return Err(violation(
                    Invariant::SwingBoundary,
                    t,
                    "a foot is not in contact at a touch-down".into(),
                ));
            };
            // left sole in the right sole's frame (planar)
            let (left, right) = (Pose2::from_isometry(&l.pose), Pose2::from_isometry(&r.pose));
            let relative = right.inverse_transform_point(left.position());
            let relative_yaw = wrap_angle(left.yaw - right.yaw);
            let length = relative.norm();
            if length > config.feet_distance_max + STEP_TOLERANCE
                || length < config.feet_distance_min - STEP_TOLERANCE
            {
                return Err(violation(
                    Invariant::StepLength,
                    t,
                    format!(
                        "soles {length:.6} m apart, outside [{}, {}] m",
                        config.feet_distance_min, config.feet_distance_max
                    ),
                ));
            }
            let width = feet_lateral_separation(left, right);
            if width < config.min_width - STEP_TOLERANCE {
                return Err(violation(
                    Invariant::StepWidth,
                    t,
                    format!(
                        "left sole {:.6} m left of the right one, below min_width {} m",
                        width, config.min_width
                    ),
                ));
            }
            report.min_width_margin = report.min_width_margin.min(width - config.min_width);
            if relative_yaw.abs() > config.max_yaw_per_step + STEP_TOLERANCE {
                return Err(violation(
                    Invariant::StepYaw,
                    t,
                    format!(
                        "relative yaw {relative_yaw:.6} rad beyond max_yaw_per_step {} rad",
                        config.max_yaw_per_step
                    ),
                ));
            }
            let corners =
                |pose| SupportPolygon::foot_corners(pose, self.foot_length, self.foot_width);
            if quadrilaterals_intersect(&corners(&l.pose), &corners(&r.pose)) {
                return Err(violation(
                    Invariant::FeetOverlap,
                    t,
                    "the sole rectangles intersect".into(),
                ));
            }
        }
        Ok(())
    }

    fn verify_swings(&self) -> Result<(), InvariantViolation> {
        for foot in [Foot::Left, Foot::Right] {
            let contacts = &self.contacts(foot).contacts;
            for sw in self.swings(foot) {
                let fail =
                    |detail: String| Err(violation(Invariant::SwingBoundary, sw.lift_time, detail));
                let Some(before) = contacts
                    .iter()
                    .find(|c| c.deactivation_time == Some(sw.lift_time))
                else {
                    return fail(format!("no {} contact ends at lift-off", foot.name()));
                };
                let Some(after) = contacts.iter().find(|c| c.activation_time == sw.land_time)
                else {
                    return fail(format!("no {} contact starts at touch-down", foot.name()));
                };
                let lift = sw.evaluate(sw.lift_time);
                let land = sw.evaluate(sw.land_time);
                let pose_error = |a: &nalgebra::Isometry3<f64>, b: &nalgebra::Isometry3<f64>| {
                    (a.translation.vector - b.translation.vector)
                        .norm()
                        .max(a.rotation.angle_to(&b.rotation))
                };
                let landing = Vector6::new(0.0, 0.0, sw.landing_velocity, 0.0, 0.0, 0.0);
                let errors = [
                    pose_error(&lift.pose, &before.pose),
                    pose_error(&land.pose, &after.pose),
                    lift.twist.norm(),
                    (land.twist - landing).norm(),
                ];
                if errors.iter().any(|&e| exceeds(e, STEP_TOLERANCE)) {
                    return fail(format!(
                        "{} swing: lift-off pose error {:.3e}, touch-down pose error {:.3e}, lift-off speed \
                         {:.3e}, landing velocity error {:.3e}",
                        foot.name(),
                        errors[0],
                        errors[1],
                        errors[2],
                        errors[3]
                    ));
                }
            }
        }
        Ok(())
    }

    fn verify_continuity(&self) -> Result<(), InvariantViolation> {
        for pair in self.segments.windows(2) {
            let (before, after) = (&pair[0], &pair[1]);
            let tb = after.start;
            let left = before.evaluate_local(tb - before.start, self.omega);
            let right = after.evaluate_local(0.0, self.omega);
            let jumps = [
                ("DCM", (left.dcm - right.dcm).norm()),
                (
                    "DCM velocity",
                    (left.dcm_velocity - right.dcm_velocity).norm(),
                ),
                ("CoM", (left.com - right.com).norm()),
                (
                    "CoM velocity",
                    (left.com_velocity - right.com_velocity).norm(),
                ),
                ("ZMP", (left.zmp - right.zmp).norm()),
            ];
            // a restart from the measured DCM keeps only the CoM and the ZMP continuous
            let kept = |name: &str| !after.restart || matches!(name, "CoM" | "ZMP");
            for (name, jump) in jumps {
                if kept(name) && exceeds(jump, CONTINUITY_TOLERANCE) {
                    return Err(violation(
                        Invariant::Continuity,
                        tb,
                        format!("{name} jumps by {jump:.3e} at a segment boundary"),
                    ));
                }
            }
        }
        Ok(())
    }

    fn verify_samples(&self, dt: f64, report: &mut VerifyReport) -> Result<(), InvariantViolation> {
        let span = (self.end_time - self.start_time).max(0.0);
        let dt = dt.max(span / MAX_SAMPLES);
        let count = (span / dt).floor() as usize;
        let mut sample = PlanSample::default();
        let uniform = (0..=count).map(|k| self.start_time + k as f64 * dt);
        let boundaries = self.segments.iter().map(|s| s.start);
        for t in uniform.chain(boundaries) {
            self.sample(t, &mut sample);
            report.samples += 1;
            self.check_sample(&sample, report)?;
        }
        Ok(())
    }

    fn check_sample(
        &self,
        s: &PlanSample,
        report: &mut VerifyReport,
    ) -> Result<(), InvariantViolation> {
        let t = s.time;
        let w = self.omega;
        let zmp = s.zmp.xy();
        let margin = s
            .support_polygon
            .map_or(f64::NEG_INFINITY, |p| p.signed_distance(zmp));
        if exceeds(-margin, DYNAMICS_TOLERANCE) {
            return Err(violation(
                Invariant::ZmpInSupport,
                t,
                format!(
                    "ZMP ({:.4}, {:.4}) m is {:.3e} m outside the support polygon",
                    zmp.x, zmp.y, -margin
                ),
            ));
        }
        report.min_zmp_margin = report.min_zmp_margin.min(margin);
        let definition =
            (s.com_position.xy() + s.com_velocity.xy() / w - s.dcm_position.xy()).norm();
        let dynamics = (s.dcm_velocity.xy() - (s.dcm_position.xy() - zmp) * w).norm();
        let lipm =
            (s.com_acceleration.xy() - (s.com_position.xy() - zmp) * (w * w)).norm() / (w * w);
        if [definition, dynamics / w, lipm]
            .iter()
            .any(|&e| exceeds(e, DYNAMICS_TOLERANCE))
        {
            return Err(violation(
                Invariant::DcmDynamics,
                t,
                format!(
                    "|ξ − x − ẋ/ω| = {definition:.3e} m, |ξ̇ − ω(ξ − z)|/ω = {:.3e} m, |ẍ − ω²(x − z)|/ω² = \
                     {lipm:.3e} m",
                    dynamics / w
                ),
            ));
        }
        Ok(())
    }

    fn verify_final_state(&self, report: &mut VerifyReport) -> Result<(), InvariantViolation> {
        for foot in [Foot::Left, Foot::Right] {
            let last = self.contacts(foot).contacts.last();
            if !last.is_some_and(|c| {
                c.deactivation_time.is_none() && c.activation_time <= self.end_time
            }) {
                return Err(violation(
                    Invariant::FinalState,
                    self.end_time,
                    format!(
                        "the {} foot does not end in a contact that lasts (from before end_time)",
                        foot.name()
                    ),
                ));
            }
        }
        let mut s = PlanSample::default();
        for t in [self.end_time, self.end_time + 10.0 / self.omega] {
            self.sample(t, &mut s);
            let error = (s.dcm_position.xy() - s.zmp.xy()).norm();
            report.final_dcm_error = report.final_dcm_error.max(error);
            if exceeds(error, FINAL_DCM_TOLERANCE) || exceeds(s.dcm_velocity.norm(), 1e-6) {
                return Err(violation(
                    Invariant::FinalState,
                    t,
                    format!(
                        "the DCM ends {error:.3e} m from the ZMP moving at {:.3e} m/s",
                        s.dcm_velocity.norm()
                    ),
                ));
            }
        }
        Ok(())
    }
}
