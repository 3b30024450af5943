//! Error values of the planner: [`PlannerError`] (every variant names the parameter or the input that
//! is wrong) and the [`InvariantViolation`] a plan's run-time verification reports.

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Why the planner refused to plan, replan or sample.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PlannerError {
    /// A [`crate::PlannerConfig`] field is out of its valid range (or not finite).
    #[error("invalid planner parameter `{name}` = {value}: {reason}")]
    InvalidParameter {
        /// Config field name, e.g. `feet_distance_max`.
        name: &'static str,
        /// The offending value.
        value: f64,
        /// What the valid range is.
        reason: String,
    },
    /// The gravity magnitude given to [`crate::Planner::new`] or [`crate::plan_from_standing`] is not
    /// finite and positive.
    #[error("invalid gravity magnitude {value} m/s²: must be finite and > 0")]
    InvalidGravity {
        /// The rejected value \[m/s²\].
        value: f64,
    },
    /// The goal is malformed (NaN, empty waypoint list, negative duration, ...).
    #[error("invalid goal `{name}`: {reason}")]
    InvalidGoal {
        /// Goal field, e.g. `waypoints[2].x` or `velocity.forward`.
        name: String,
        /// What is wrong with it.
        reason: String,
    },
    /// The starting feet are not a valid standing configuration.
    #[error("invalid start `{name}`: {reason}")]
    InvalidStart {
        /// Input name, e.g. `left_sole`.
        name: &'static str,
        /// What is wrong.
        reason: String,
    },
    /// The footstep search found no step satisfying the length/width/yaw/duration bounds.
    #[error(
        "no feasible footstep for step {step} (swing foot {foot}) after t = {time:.3} s: {reason}"
    )]
    NoFeasibleStep {
        /// Index of the step (0 = first step of this plan).
        step: usize,
        /// `left` or `right`.
        foot: &'static str,
        /// Plan time \[s\] of the previous touch-down.
        time: f64,
        /// The constraint(s) that could not be met.
        reason: String,
    },
    /// The DCM plan would put the ZMP outside the support polygon (only possible for the first double
    /// support of a plan, whose shape depends on the initial DCM state).
    #[error("planned ZMP leaves the support polygon at t = {time:.3} s (by {distance:.4} m)")]
    ZmpOutsideSupport {
        /// Plan time \[s\].
        time: f64,
        /// Distance outside the polygon \[m\].
        distance: f64,
    },
    /// A swing's path sweeps over the stance sole and neither detour (in front of it or behind it) clears
    /// it ([`crate::SwingTrajectory::go_round`]).
    #[error("the swing lifting off at t = {time:.3} s cannot go round the stance sole")]
    SwingOverStance {
        /// Lift-off time of the swing, or the time of the retarget \[s\].
        time: f64,
    },
    /// A time argument is not finite or out of range.
    #[error("invalid time `{name}` = {value}: {reason}")]
    InvalidTime {
        /// Argument name.
        name: &'static str,
        /// The value.
        value: f64,
        /// Why.
        reason: &'static str,
    },
    /// The closed-form DCM plan came out non-finite (an ill-conditioned combination of parameters, e.g. a
    /// huge CoM height with very short phases). Never returned as a plan with NaN in it.
    #[error("the DCM plan is not finite in the segment starting at t = {time:.3} s ({quantity}); check com_height and the phase durations")]
    NonFinitePlan {
        /// Start time \[s\] of the first non-finite segment.
        time: f64,
        /// Which quantity: `start`, `zmp`, `dcm` or `com`.
        quantity: &'static str,
    },
    /// A plan failed its run-time verification ([`crate::Plan::verify`], enabled by
    /// [`crate::PlannerConfig::verify_plans`]): a planner defect, never the user's input. The previous plan is
    /// kept.
    #[error("the new plan failed verification: {0} (a planner defect: please report it with the config and goal)")]
    InvariantViolated(#[from] InvariantViolation),
    /// `replan`/`sample` called before `start`.
    #[error("the planner has no plan yet: call `start` first")]
    NoPlan,
    /// The plan has no double-support phase left to merge a new plan into.
    #[error("no merge point available after t = {time:.3} s")]
    NoMergePoint {
        /// Requested replanning time \[s\].
        time: f64,
    },
    /// The footstep search exceeded its step budget (should not happen with valid parameters).
    #[error("footstep search exceeded {limit} steps")]
    TooManySteps {
        /// The budget.
        limit: usize,
    },
}

/// The invariants [`crate::Plan::verify`] checks (see the table of [`crate::verify`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Invariant {
    /// Every number of the plan is finite.
    Finite,
    /// Sole distance at touch-down within the step-length bounds.
    StepLength,
    /// Sole lateral distance at touch-down at least `min_width`, left foot on the left.
    StepWidth,
    /// Relative sole yaw at touch-down within `max_yaw_per_step`.
    StepYaw,
    /// The soles do not intersect at touch-down.
    FeetOverlap,
    /// Touch-down to touch-down time within the step-duration bounds.
    StepDuration,
    /// ZMP inside the support polygon.
    ZmpInSupport,
    /// DCM definition, DCM dynamics and LIPM hold.
    DcmDynamics,
    /// DCM, CoM, their velocities and the ZMP are continuous.
    Continuity,
    /// Swings start and end on their contacts with the planned velocities.
    SwingBoundary,
    /// The plan ends standing with the DCM on the ZMP.
    FinalState,
}

impl Invariant {
    /// The snake_case name used in the module table and in messages.
    pub fn name(self) -> &'static str {
        match self {
            Invariant::Finite => "finite",
            Invariant::StepLength => "step_length",
            Invariant::StepWidth => "step_width",
            Invariant::StepYaw => "step_yaw",
            Invariant::FeetOverlap => "feet_overlap",
            Invariant::StepDuration => "step_duration",
            Invariant::ZmpInSupport => "zmp_in_support",
            Invariant::DcmDynamics => "dcm_dynamics",
            Invariant::Continuity => "continuity",
            Invariant::SwingBoundary => "swing_boundary",
            Invariant::FinalState => "final_state",
        }
    }
}

impl std::fmt::Display for Invariant {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A violated plan invariant.
#[derive(Clone, Debug, PartialEq, Error)]
#[error("plan invariant `{invariant}` violated at t = {time:.4} s: {detail}")]
pub struct InvariantViolation {
    /// Which invariant.
    pub invariant: Invariant,
    /// Plan time \[s\] of the first violation found.
    pub time: f64,
    /// The numbers involved.
    pub detail: String,
}
