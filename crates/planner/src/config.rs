//! Planner parameters.

use serde::{Deserialize, Serialize};

use crate::error::PlannerError;

/// Which foot swings first when a plan starts from standing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FirstSwingFoot {
    /// The foot on the side the robot moves or turns to (left when going straight).
    Auto,
    /// Always the left foot.
    Left,
    /// Always the right foot.
    Right,
}

/// How the DCM is planned in double support.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DcmInterpolation {
    /// Plan the ZMP (smooth move between the stance soles) and solve the DCM exactly: the ZMP stays in the
    /// support polygon by construction (default).
    ZmpFirst,
    /// The thesis' method [Romualdi 2022, eqs. 10.1.21–10.1.23]: DCM cubics between single-support exponentials, last-step
    /// condition with `last_step_dcm_alpha`; the resulting ZMP is checked against the support polygon.
    DcmCubic,
}

/// When the [`crate::Planner`] checks the invariants of each plan it makes ([`crate::Plan::verify`]); a
/// violation is returned as [`crate::PlannerError::InvariantViolated`] and the previous plan is kept.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum PlanVerification {
    /// Never.
    Never,
    /// In builds with debug assertions (as `debug_assert!`), never in release builds.
    #[default]
    DebugBuilds,
    /// Always.
    Always,
}

impl PlanVerification {
    /// Whether plans are verified in this build.
    pub fn enabled(self) -> bool {
        match self {
            PlanVerification::Never => false,
            PlanVerification::DebugBuilds => cfg!(debug_assertions),
            PlanVerification::Always => true,
        }
    }
}

/// All parameters of the trajectory layer. Defaults are iCub-v2.7-like (the values of the iCub walking
/// experiments of [Romualdi 2022, ch. 10] and of the robotology walking-controllers).
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `com_height` | m | 0.54 (`stride_model::bundled::COM_HEIGHT`) | constant CoM height above the ground (LIPM), gives ω = √(g/h); in (0, 10] |
/// | `step_duration_min` | s | 0.8 | min time between two touch-downs [Romualdi 2022, eq. 10.1.11] |
/// | `step_duration_nominal` | s | 1.0 | duration of the closing steps once the unicycle stopped |
/// | `step_duration_max` | s | 1.2 | max time between two touch-downs [Romualdi 2022, eq. 10.1.11] |
/// | `double_support_fraction` | – | 0.35 | share of each step spent in double support, in (0, 1) |
/// | `initial_double_support_duration` | s | 1.0 | first double support of a plan started from standing |
/// | `final_double_support_duration` | s | 1.0 | last double support, ZMP/DCM move to the feet mid-point |
/// | `feet_distance_min` | m | 0.0 | min straight-line distance between the two sole origins at touch-down [Romualdi 2022, eq. 10.1.12] (was `step_length_min`) |
/// | `feet_distance_max` | m | 0.22 | max straight-line distance between the two sole origins at touch-down [Romualdi 2022, eq. 10.1.12], the lateral width included: a forward step `s` at width `w` needs `√(s² + w²)` (was `step_length_max`) |
/// | `nominal_width` | m | 0.15 (`stride_model::bundled::NOMINAL_WIDTH`) | lateral distance of the feet from each other on the unicycle axle |
/// | `min_width` | m | 0.14 | min lateral distance of the left foot in the right-foot frame (or of the right foot in the left-foot frame, see `geometry::feet_lateral_separation`) |
/// | `max_yaw_per_step` | rad | 0.26 | max relative yaw between the feet [Romualdi 2022, eq. 10.1.13], ≈ 15° |
/// | `swing_height` | m | 0.03 | apex height of the swing foot above the higher of its two footholds |
/// | `swing_apex_fraction` | – | 0.5 | apex time as a fraction of the swing, in (0, 1) |
/// | `landing_velocity` | m/s | 0.0 | vertical swing-foot velocity at touch-down (≤ 0) |
/// | `foot_length` | m | 0.20 | sole rectangle length (x of the sole frame), centred on the sole frame |
/// | `foot_width` | m | 0.09 | sole rectangle width (y of the sole frame) |
/// | `backward_speed_factor` | – | 0.5 | backward speed limit as a fraction of the forward one, in (0, 1] |
/// | `sideways_speed_factor` | – | 0.3 | lateral speed limit as a fraction of the forward one, in [0, 1] |
/// | `linear_saturation_factor` | – | 0.9 | forward speed limit = factor · √(l_max² − w²)/t_min |
/// | `angular_saturation_factor` | – | 0.7 | yaw-rate limit = factor · max_yaw_per_step / t_min |
/// | `reference_speed_fraction` | – | 0.9 | speed of the reference point along a path, fraction of the limits |
/// | `unicycle_gain` | 1/s | 10.0 | K of the feedback-linearising unicycle controller [Romualdi 2022, eq. 10.1.6] |
/// | `reference_point` | m | [0.1, 0.0] | controlled point F in the unicycle frame (x must be > 0) |
/// | `time_weight` | s² | 2.5 | K_t of the step cost K_t/Δt² + K_x Δx² [Romualdi 2022, eq. 10.1.10] |
/// | `position_weight` | 1/m² | 1.0 | K_x of the step cost |
/// | `unicycle_dt` | s | 0.01 | integration and impact-time sampling period of the unicycle |
/// | `horizon` | s | 120.0 | longest unicycle motion planned at once; beyond it the plan is a prefix |
/// | `turn_in_place_threshold` | rad | 0.8 | heading error to a waypoint above which the robot turns in place first |
/// | `backward_max_distance` | m | 0.5 | a waypoint behind the robot closer than this is reached walking backwards |
/// | `merge_point_fraction` | – | 0.4 | where inside a double support a new plan is merged, in [0, 1) |
/// | `verify_plans` | – | `"debug_builds"` | when the [`crate::Planner`] checks each new or merged plan with [`crate::Plan::verify`]: `"never"`, `"debug_builds"` (like `debug_assert!`) or `"always"` (sampled every 10 ms: about 2 ms for a 68-step plan, 3.5× the planning time) |
/// | `first_swing_foot` | – | `auto` | `auto`, `left` or `right` |
/// | `dcm_interpolation` | – | `zmp_first` | `zmp_first` or `dcm_cubic` [Romualdi 2022, eq. 10.1.23] |
/// | `last_step_dcm_alpha` | – | 0.2 | α_LS of [Romualdi 2022, eq. 10.2.3], in [0, 1] (only for `dcm_cubic`) |
/// | `stop_deceleration` | m/s² | 0 | deceleration of the reference point F on its way to the goal: it slows down uniformly over the last `v²/(2a)` of the path instead of stopping there at full speed (0: full speed to the goal) |
/// | `arrival_tolerance` | m | 0.05 | a step adjustment ([`crate::Planner::adjust_step`]) whose new touch-down puts the feet's mid-point this close to the goal's position closes the walk there (the other foot steps beside it, the goal's heading kept) instead of replanning a turn, a walk and a turn back to the goal (0: never) |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlannerConfig {
    /// Constant CoM height above the ground \[m\], in (0, 10].
    pub com_height: f64,
    /// Minimum step duration (touch-down to touch-down) \[s\].
    pub step_duration_min: f64,
    /// Duration of the closing steps placed after the unicycle stopped \[s\].
    pub step_duration_nominal: f64,
    /// Maximum step duration \[s\].
    pub step_duration_max: f64,
    /// Fraction of each step spent in double support, in (0, 1).
    pub double_support_fraction: f64,
    /// Duration of the first double support when starting from standing \[s\].
    pub initial_double_support_duration: f64,
    /// Duration of the final double support \[s\].
    pub final_double_support_duration: f64,
    /// Minimum straight-line distance between the two sole origins at touch-down \[m\] (formerly
    /// `step_length_min`).
    pub feet_distance_min: f64,
    /// Maximum straight-line distance between the two sole origins at touch-down \[m\], the lateral width
    /// included: a forward step `s` at width `w` needs `√(s² + w²)` (formerly `step_length_max`).
    pub feet_distance_max: f64,
    /// Nominal lateral distance between the feet \[m\].
    pub nominal_width: f64,
    /// Minimum lateral separation of the feet: the larger of the left sole's lateral position in the right-sole frame and the right sole's (negated) in the left-sole frame \[m\].
    pub min_width: f64,
    /// Maximum relative yaw between the feet \[rad\].
    pub max_yaw_per_step: f64,
    /// Swing apex height above the higher foothold \[m\].
    pub swing_height: f64,
    /// Apex time as a fraction of the swing duration, in (0, 1).
    pub swing_apex_fraction: f64,
    /// Vertical velocity of the swing foot at touch-down \[m/s\], ≤ 0.
    pub landing_velocity: f64,
    /// Sole length \[m\].
    pub foot_length: f64,
    /// Sole width \[m\].
    pub foot_width: f64,
    /// Backward speed limit as a fraction of the forward speed limit, in (0, 1].
    pub backward_speed_factor: f64,
    /// Lateral speed limit as a fraction of the forward speed limit, in [0, 1].
    pub sideways_speed_factor: f64,
    /// Forward speed limit factor (see the table above), in (0, 1].
    pub linear_saturation_factor: f64,
    /// Yaw-rate limit factor (see the table above), in (0, 1].
    pub angular_saturation_factor: f64,
    /// Reference-point speed along a path as a fraction of the limits, in (0, 1].
    pub reference_speed_fraction: f64,
    /// Unicycle feedback gain K \[1/s\].
    pub unicycle_gain: f64,
    /// Controlled point F in the unicycle frame \[m\] (x > 0).
    pub reference_point: [f64; 2],
    /// K_t of the footstep cost \[s²\].
    pub time_weight: f64,
    /// K_x of the footstep cost \[1/m²\].
    pub position_weight: f64,
    /// Unicycle integration period \[s\].
    pub unicycle_dt: f64,
    /// Planning horizon of the unicycle \[s\].
    pub horizon: f64,
    /// Heading error above which the robot turns in place before walking to a waypoint \[rad\].
    pub turn_in_place_threshold: f64,
    /// Waypoints behind the robot closer than this are reached walking backwards \[m\].
    pub backward_max_distance: f64,
    /// Merge point position inside a double support, in [0, 1).
    pub merge_point_fraction: f64,
    /// When the planner checks each new or merged plan (`Plan::verify`): `never`, `debug_builds` or `always`.
    pub verify_plans: PlanVerification,
    /// Which foot swings first from standing.
    pub first_swing_foot: FirstSwingFoot,
    /// Double-support DCM method.
    pub dcm_interpolation: DcmInterpolation,
    /// Last-step DCM weight α_LS [Romualdi 2022, eq. 10.2.3], in [0, 1].
    pub last_step_dcm_alpha: f64,
    /// Deceleration of the reference point on the last straight line to the goal \[m/s²\] (≥ 0; 0: none).
    pub stop_deceleration: f64,
    /// Distance to the goal's position within which a step adjustment's replan closes the walk where the
    /// adjusted step put the feet \[m\] (≥ 0; 0: never).
    pub arrival_tolerance: f64,
}

/// The defaults fit the bundled humanoid: `com_height`, `nominal_width`, `foot_length` and `foot_width`
/// come from [`stride_model::bundled`]; set them for another robot.
impl Default for PlannerConfig {
    fn default() -> Self {
        Self {
            com_height: stride_model::bundled::COM_HEIGHT,
            step_duration_min: 0.8,
            step_duration_nominal: 1.0,
            step_duration_max: 1.2,
            double_support_fraction: 0.35,
            initial_double_support_duration: 1.0,
            final_double_support_duration: 1.0,
            feet_distance_min: 0.0,
            feet_distance_max: 0.22,
            nominal_width: stride_model::bundled::NOMINAL_WIDTH,
            min_width: 0.14,
            max_yaw_per_step: 0.26,
            swing_height: 0.03,
            swing_apex_fraction: 0.5,
            landing_velocity: 0.0,
            foot_length: stride_model::bundled::FOOT_LENGTH,
            foot_width: stride_model::bundled::FOOT_WIDTH,
            backward_speed_factor: 0.5,
            sideways_speed_factor: 0.3,
            linear_saturation_factor: 0.9,
            angular_saturation_factor: 0.7,
            reference_speed_fraction: 0.9,
            unicycle_gain: 10.0,
            reference_point: [0.1, 0.0],
            time_weight: 2.5,
            position_weight: 1.0,
            unicycle_dt: 0.01,
            horizon: 120.0,
            turn_in_place_threshold: 0.8,
            backward_max_distance: 0.5,
            merge_point_fraction: 0.4,
            verify_plans: PlanVerification::DebugBuilds,
            first_swing_foot: FirstSwingFoot::Auto,
            dcm_interpolation: DcmInterpolation::ZmpFirst,
            last_step_dcm_alpha: 0.2,
            stop_deceleration: 0.0,
            arrival_tolerance: 0.05,
        }
    }
}

fn check(
    name: &'static str,
    value: f64,
    ok: bool,
    reason: impl Into<String>,
) -> Result<(), PlannerError> {
    if value.is_finite() && ok {
        Ok(())
    } else {
        Err(PlannerError::InvalidParameter {
            name,
            value,
            reason: reason.into(),
        })
    }
}

/// Checks the gravity magnitude the planner is built with \[m/s²\]: finite and > 0.
pub(crate) fn check_gravity(gravity_m_s2: f64) -> Result<(), PlannerError> {
    if gravity_m_s2.is_finite() && gravity_m_s2 > 0.0 {
        Ok(())
    } else {
        Err(PlannerError::InvalidGravity {
            value: gravity_m_s2,
        })
    }
}

/// Largest accepted `com_height` \[m\]: ω = √(g/h) ≈ 0.99 rad/s there; far larger heights make the DCM
/// plan's closed forms (terms in 1/ω³) lose every digit.
pub const MAX_COM_HEIGHT: f64 = 10.0;

impl PlannerConfig {
    /// Checks every field; the error names the first offending parameter.
    pub fn validate(&self) -> Result<(), PlannerError> {
        self.validate_timing()?;
        self.validate_feet()?;
        self.validate_unicycle()
    }

    /// The CoM height and the step and double-support durations.
    fn validate_timing(&self) -> Result<(), PlannerError> {
        let c = self;
        check(
            "com_height",
            c.com_height,
            c.com_height > 0.0 && c.com_height <= MAX_COM_HEIGHT,
            format!(
                "must lie in (0, {MAX_COM_HEIGHT}] m (beyond, ω·T is so small that the LIPM plan is ill-conditioned)"
            ),
        )?;
        check(
            "step_duration_min",
            c.step_duration_min,
            c.step_duration_min > 0.0,
            "must be > 0",
        )?;
        check(
            "step_duration_max",
            c.step_duration_max,
            c.step_duration_max >= c.step_duration_min,
            "must be >= step_duration_min",
        )?;
        check(
            "step_duration_nominal",
            c.step_duration_nominal,
            c.step_duration_nominal >= c.step_duration_min
                && c.step_duration_nominal <= c.step_duration_max,
            "must lie in [step_duration_min, step_duration_max]",
        )?;
        check(
            "double_support_fraction",
            c.double_support_fraction,
            c.double_support_fraction > 0.0 && c.double_support_fraction < 1.0,
            "must lie in (0, 1)",
        )?;
        check(
            "initial_double_support_duration",
            c.initial_double_support_duration,
            c.initial_double_support_duration > 0.0,
            "must be > 0",
        )?;
        check(
            "final_double_support_duration",
            c.final_double_support_duration,
            c.final_double_support_duration > 0.0,
            "must be > 0",
        )?;
        Ok(())
    }

    /// The sole rectangle, the step geometry and the swing.
    fn validate_feet(&self) -> Result<(), PlannerError> {
        let c = self;
        check(
            "foot_length",
            c.foot_length,
            c.foot_length > 0.0,
            "must be > 0",
        )?;
        check(
            "foot_width",
            c.foot_width,
            c.foot_width > 0.0,
            "must be > 0",
        )?;
        check(
            "max_yaw_per_step",
            c.max_yaw_per_step,
            c.max_yaw_per_step > 0.0 && c.max_yaw_per_step < std::f64::consts::FRAC_PI_2,
            "must lie in (0, π/2)",
        )?;
        let no_overlap = 0.5 * c.foot_width * (1.0 + c.max_yaw_per_step.cos())
            + 0.5 * c.foot_length * c.max_yaw_per_step.sin();
        check(
            "min_width",
            c.min_width,
            c.min_width > no_overlap,
            format!(
                "must exceed {no_overlap:.4} m so that the soles cannot overlap at the maximum relative yaw"
            ),
        )?;
        check(
            "nominal_width",
            c.nominal_width,
            c.nominal_width >= c.min_width,
            "must be >= min_width",
        )?;
        check(
            "feet_distance_max",
            c.feet_distance_max,
            c.feet_distance_max > c.nominal_width,
            "must exceed nominal_width (the feet distance includes the width)",
        )?;
        check(
            "feet_distance_min",
            c.feet_distance_min,
            c.feet_distance_min >= 0.0 && c.feet_distance_min <= c.min_width,
            "must lie in [0, min_width]",
        )?;
        check(
            "swing_height",
            c.swing_height,
            c.swing_height > 0.0,
            "must be > 0",
        )?;
        check(
            "swing_apex_fraction",
            c.swing_apex_fraction,
            c.swing_apex_fraction > 0.0 && c.swing_apex_fraction < 1.0,
            "must lie in (0, 1)",
        )?;
        check(
            "landing_velocity",
            c.landing_velocity,
            c.landing_velocity <= 0.0,
            "must be <= 0 (downwards)",
        )?;
        Ok(())
    }

    /// The speed limits, the unicycle, the footstep search, replanning and the DCM options.
    fn validate_unicycle(&self) -> Result<(), PlannerError> {
        let c = self;
        check(
            "backward_speed_factor",
            c.backward_speed_factor,
            c.backward_speed_factor > 0.0 && c.backward_speed_factor <= 1.0,
            "must lie in (0, 1]",
        )?;
        check(
            "sideways_speed_factor",
            c.sideways_speed_factor,
            (0.0..=1.0).contains(&c.sideways_speed_factor),
            "must lie in [0, 1]",
        )?;
        for (name, v) in [
            ("linear_saturation_factor", c.linear_saturation_factor),
            ("angular_saturation_factor", c.angular_saturation_factor),
            ("reference_speed_fraction", c.reference_speed_fraction),
        ] {
            check(name, v, v > 0.0 && v <= 1.0, "must lie in (0, 1]")?;
        }
        check(
            "unicycle_gain",
            c.unicycle_gain,
            c.unicycle_gain > 0.0,
            "must be > 0",
        )?;
        check(
            "reference_point",
            c.reference_point[0],
            c.reference_point[0] > 0.0,
            "x must be > 0 (the unicycle controller is singular on the wheel axis)",
        )?;
        check(
            "reference_point",
            c.reference_point[1],
            true,
            "y must be finite",
        )?;
        check(
            "time_weight",
            c.time_weight,
            c.time_weight >= 0.0,
            "must be >= 0",
        )?;
        check(
            "position_weight",
            c.position_weight,
            c.position_weight >= 0.0,
            "must be >= 0",
        )?;
        check(
            "unicycle_dt",
            c.unicycle_dt,
            c.unicycle_dt > 0.0 && c.unicycle_dt <= 0.1 * c.step_duration_min,
            "must lie in (0, step_duration_min / 10]",
        )?;
        let (n_min, n_max) = c.step_sample_window();
        check(
            "step_duration_max",
            c.step_duration_max,
            n_min <= n_max,
            "the window [step_duration_min, step_duration_max] contains no multiple of unicycle_dt",
        )?;
        check(
            "horizon",
            c.horizon,
            c.horizon > 0.0 && c.horizon / c.unicycle_dt <= 1.0e7,
            "must be > 0 and at most 1e7 unicycle samples",
        )?;
        check(
            "turn_in_place_threshold",
            c.turn_in_place_threshold,
            c.turn_in_place_threshold >= 0.0 && c.turn_in_place_threshold <= std::f64::consts::PI,
            "must lie in [0, π]",
        )?;
        check(
            "backward_max_distance",
            c.backward_max_distance,
            c.backward_max_distance >= 0.0,
            "must be >= 0",
        )?;
        check(
            "merge_point_fraction",
            c.merge_point_fraction,
            (0.0..1.0).contains(&c.merge_point_fraction),
            "must lie in [0, 1)",
        )?;
        check(
            "last_step_dcm_alpha",
            c.last_step_dcm_alpha,
            (0.0..=1.0).contains(&c.last_step_dcm_alpha),
            "must lie in [0, 1]",
        )?;
        check(
            "stop_deceleration",
            c.stop_deceleration,
            c.stop_deceleration >= 0.0,
            "must be >= 0 (0: no deceleration)",
        )?;
        check(
            "arrival_tolerance",
            c.arrival_tolerance,
            c.arrival_tolerance >= 0.0,
            "must be >= 0 (0: an adjusted step always replans towards the goal's position)",
        )?;
        Ok(())
    }

    /// LIPM natural frequency ω = √(g/h) \[1/s\] for the gravity magnitude `gravity_m_s2` \[m/s²\].
    pub fn omega(&self, gravity_m_s2: f64) -> f64 {
        (gravity_m_s2 / self.com_height).sqrt()
    }

    /// Forward speed limit of the unicycle \[m/s\]: factor · √(l_max² − w²)/t_min.
    pub fn max_forward_speed(&self) -> f64 {
        let l = self.feet_distance_max;
        let w = self.nominal_width;
        self.linear_saturation_factor * (l * l - w * w).sqrt() / self.step_duration_min
    }

    /// Backward speed limit \[m/s\] (positive number).
    pub fn max_backward_speed(&self) -> f64 {
        self.backward_speed_factor * self.max_forward_speed()
    }

    /// Lateral speed limit \[m/s\]: the smaller of the configured fraction of the forward limit and the
    /// geometric limit 0.9·(nominal_width − min_width)/t_min (the trailing foot must keep `min_width`).
    pub fn max_lateral_speed(&self) -> f64 {
        let geometric = 0.9 * (self.nominal_width - self.min_width) / self.step_duration_min;
        (self.sideways_speed_factor * self.max_forward_speed()).min(geometric)
    }

    /// Yaw-rate limit \[rad/s\]: factor · max_yaw_per_step / t_min.
    pub fn max_yaw_rate(&self) -> f64 {
        self.angular_saturation_factor * self.max_yaw_per_step / self.step_duration_min
    }

    /// Step durations as numbers of unicycle samples: [ceil(t_min/dt), floor(t_max/dt)].
    pub(crate) fn step_sample_window(&self) -> (usize, usize) {
        let n_min = (self.step_duration_min / self.unicycle_dt - 1e-9)
            .ceil()
            .max(1.0);
        let n_max = (self.step_duration_max / self.unicycle_dt + 1e-9).floor();
        if !(n_min.is_finite() && n_max.is_finite()) || n_max < 0.0 || n_min > 1e9 || n_max > 1e9 {
            return (1, 0);
        }
        (n_min as usize, n_max as usize)
    }
}
