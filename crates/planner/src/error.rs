//! Error values of the planner. Every variant names the parameter or the input that is wrong.

use thiserror::Error;

/// Why the planner refused to plan, replan or sample.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum PlannerError {
    /// A [`crate::PlannerConfig`] field is out of its valid range (or not finite).
    #[error("invalid planner parameter `{name}` = {value}: {reason}")]
    InvalidParameter {
        /// Config field name, e.g. `step_length_max`.
        name: &'static str,
        /// The offending value.
        value: f64,
        /// What the valid range is.
        reason: String,
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
    InvariantViolated(#[from] crate::verify::InvariantViolation),
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
