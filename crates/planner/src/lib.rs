//! `stride-planner`: the trajectory layer of stride [Romualdi 2022, §10.1–§10.2, App. D–E].
//!
//! A goal becomes contacts and references that the lower layers track:
//! unicycle footstep planner → contact lists (feet poses and timings) → DCM plan (closed-form segments) → CoM,
//! ZMP → swing-foot trajectories (minimum jerk on R³ × SO(3)).
//!
//! # Public API (what the runner uses)
//!
//! * [`PlannerConfig`] (serde, `deny_unknown_fields`, iCub-v2.7-like [`Default`], [`PlannerConfig::validate`];
//!   the field table with units is on the type). [`DcmInterpolation`] selects the double-support method.
//! * [`Goal`]: `Stand`, `Pose { x, y, yaw }`, `Waypoints { points }`, `Velocity { forward, lateral, yaw_rate,
//!   duration }`; internally tagged (`type = "pose"` etc.) so it can be written in TOML. Only the last
//!   waypoint's heading is enforced.
//! * [`plan_from_standing`]`(config, gravity, t0, &left_sole, &right_sole, &goal) -> Result<Plan, PlannerError>`:
//!   a whole plan from standing (initial double support of `initial_double_support_duration`, ends standing with
//!   parallel feet, DCM on the feet mid-point).
//! * [`Planner`]: `new(config, gravity_m_s2)` (the scenario's gravity magnitude, > 0: ω = √(g/h) follows
//!   from it; it is not a config field), `start(t0, &left, &right, &goal) -> &Plan`, `replan(t, &goal) -> merge time`
//!   (merge point inside a double support; the past is kept), `sample(t, &mut PlanSample)`, `plan()`. It
//!   implements [`stride_block::Block`] with [`PlannerInput`] `{ time, goal: Option<Goal>, left_sole,
//!   right_sole }` → [`PlanSample`]: the first tick starts a plan from the measured soles, a tick carrying a
//!   goal replans, every tick samples (no allocation unless a goal arrives).
//! * [`Plan`]: serde-serialisable (log/replay). [`Plan::sample`]`(t, &mut PlanSample)` fills DCM position/
//!   velocity, ZMP, CoM position/velocity/acceleration, ω, both feet (pose, mixed twist and acceleration,
//!   contact flag), the gait phase and the support polygon (fixed capacity) — O(log n), no allocation.
//!   [`Plan::report`]`(dt) -> PlanReport` is exactly the JSON object of `stride plan --json` (docs/cli.md):
//!   `serde_json::to_string(&plan.report(dt)?)`.
//! * [`Plan::verify`]`(config, dt) -> Result<VerifyReport, InvariantViolation>`: the plan's invariants (step
//!   bounds, ZMP in the support polygon, LIPM, continuity, swing boundaries, final state) checked at run time;
//!   the [`Planner`] runs it on every new or merged plan per [`PlannerConfig::verify_plans`] (see [`verify`]).
//! * Contacts as data: [`ContactList`] per foot (`active_at(t)`, `next_after(t)`), [`PlannedContact`]
//!   `{ foot, pose, activation_time, deactivation_time: Option }`, [`Phase`] list, [`SwingTrajectory`].
//!
//! Times are `f64` seconds of plan time (the block converts its `Duration`). World frame z up, x forward;
//! twists are `[linear; angular]` in the mixed representation.
//!
//! # Method (and where it differs from the thesis)
//!
//! * Unicycle [Romualdi 2022, eq. 10.1.1] driven by the feedback-linearising controller [Romualdi 2022, eq. 10.1.6] on a point F ahead of it, tracking
//!   a reference made of straight lines (walk) and arcs (turn in place) built from the goal; velocity goals
//!   drive the unicycle directly (with an extra lateral velocity, as in the robotology walking-controllers' direct unicycle control). Speed
//!   limits come from the step limits.
//! * Greedy footstep search [Romualdi 2022, eqs. 10.1.10–10.1.13]: each unicycle sample is a candidate touch-down; the cheapest feasible
//!   candidate `K_t/Δt² + K_x Δx²` under duration, length, width and relative-yaw bounds is taken; the walk
//!   ends with both feet parallel at the nominal width.
//! * DCM: the ZMP is planned first — constant on the stance foot in single support (so the DCM is the thesis
//!   exponential [Romualdi 2022, eq. 10.1.16]), a smooth cubic move between the two stance points in double support — and the
//!   DCM/CoM are the exact closed-form solutions of ξ̇ = ω(ξ − ZMP) and ẋ = −ω(x − ξ) (see [`dcm`]). The
//!   thesis instead interpolates the DCM by a cubic in double support [Romualdi 2022, eq. 10.1.23] (available as
//!   [`DcmInterpolation::DcmCubic`], with the last-step α of [Romualdi 2022, eq. 10.2.3] and a support-polygon check); that does not
//!   keep the ZMP in the support polygon by construction, planning the ZMP does (it moves on the segment joining two points
//!   inside the two soles). The DCM is C¹ (ZMP continuous), ends exactly on the final ZMP, and the initial
//!   double support carries a ZMP bump u(1−u)² that makes the DCM start exactly at the measured/merged state
//!   (the role of [Romualdi 2022, eq. 10.2.1]); that ZMP is checked against the support polygon. In this default mode the last-step
//!   α of [Romualdi 2022, eq. 10.2.3] is implied by the final double support rather than set.
//! * Swing feet: minimum-jerk quintics [Romualdi 2022, eq. D.3.6] with an apex knot for the height, minimum-jerk geodesic on SO(3).

pub mod adjust;
mod build;
pub mod config;
pub mod contacts;
pub mod dcm;
pub mod error;
pub mod geometry;
pub mod goal;
pub mod plan;
pub mod planner;
pub mod swing;
mod unicycle;
pub mod verify;

pub use adjust::{CurrentStep, StepAdjustmentRequest};
pub use config::{DcmInterpolation, FirstSwingFoot, PlanVerification, PlannerConfig};
pub use contacts::{ContactList, Foot, Phase, PhaseKind, PlannedContact};
pub use error::PlannerError;
pub use geometry::Pose2;
pub use goal::{Goal, Waypoint};
pub use plan::{FootSample, Plan, PlanOutcome, PlanReport, PlanSample, WaypointProgress};
pub use planner::{plan_from_standing, Planner, PlannerInput};
pub use stride_block::{Block, FootRectangle, SupportPolygon};
pub use swing::{RetargetOutcome, SwingShape, SwingTrajectory};
pub use verify::{Invariant, InvariantViolation, VerifyReport};

/// What a user of the planner needs in scope: `use stride_planner::prelude::*;`.
pub mod prelude {
    pub use crate::{
        plan_from_standing, Foot, FootSample, Goal, Plan, PlanSample, Planner, PlannerConfig,
        PlannerError, PlannerInput, SupportPolygon, VerifyReport, Waypoint,
    };
    pub use nalgebra;
    pub use stride_block::Block;
}
