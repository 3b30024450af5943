//! Configuration of the centroidal MPC (TOML section `[centroidal_mpc]` of `[simplified]`).

use serde::{Deserialize, Serialize};

use crate::error::{
    check_non_negative as non_negative, check_positive as positive, Result, SimplifiedError,
};

/// Largest horizon the MPC accepts (stages).
pub const MAX_CENTROIDAL_STAGES: usize = 30;

/// An interval `[lower, upper]` \[m\].
pub type Interval = [f64; 2];

/// Configuration of the centroidal MPC [Romualdi 2022, §11.1]. Every field is optional; the defaults are
/// the thesis's stage length and friction, a 1.2 s horizon and weights tuned on the bundled humanoid (the
/// thesis's weights belong to another scaling of the variables and do not carry over).
///
/// | field | default | meaning |
/// |---|---|---|
/// | `stage_duration` | 0.1 s | forward-Euler step `dt` of (11.1.15b–d) |
/// | `stages` | 12 | horizon length `N` |
/// | `force_hold_stages` | 2 | move blocking: each corner force is one variable over this many consecutive stages |
/// | `update_period` | 0.05 s | the runner re-solves every this long and interpolates the prediction in between |
/// | `friction` | 0.33 | static friction `μ` of the linearised cone (11.1.13) |
/// | `com_weight` | \[1e4, 1e4, 1e5\] | `Λ_CoM` of (11.1.11) \[1/m²\] |
/// | `angular_momentum_weight` | 10 | `Λ_h` of (11.1.11) \[1/(kg m²/s)²\] |
/// | `force_average_weight` | 1e-4 | `Λ_f` of (11.1.6) \[1/N²\] |
/// | `force_rate_weight` | 1e-6 | `Λ_ḟ` of (11.1.8) \[1/(N/s)²\] |
/// | `contact_position_weight` | 2e3 | `Λ_p` of (11.1.12) \[1/m²\] |
/// | `force_regularization` | 1e-7 | Tikhonov term on the cone coordinates \[1/N²\] (keeps the QP strictly convex) |
/// | `forward` | \[−0.10, 0.10\] | box (11.1.14) along the sole x axis \[m\] |
/// | `outward` | \[0, 0.10\] | box (11.1.14) across the sole, positive away from the other foot \[m\] |
/// | `external_force` | false | the runner estimates the horizontal external force (`m ẍ − Σ f_feet`) and passes it to the MPC [Romualdi 2022, eq. 11.2.1] |
/// | `external_force_threshold` | 30 N | smaller estimates are ignored (the thesis's code: 30 N) |
/// | `external_force_stages` | 1 | stages over which the external force acts in the prediction (the thesis: the first only) |
/// | `push_estimate` | false | the runner passes the push response's momentum-observer estimate (`[simplified.push] enabled = true` needed; not with `external_force`) as the external force, held constant over the whole horizon (all `stages`; `external_force_stages` is not used); `external_force_threshold` applies |
/// | `deadband` | 0.02 m | the runner retargets the swing only when the adjusted touch-down differs from the plan's by more |
/// | `track_prediction` | false | the DCM PI tracks the MPC's predicted CoM (false: the plan's, and the MPC only moves the footsteps) |
/// | `warm_start_active_set` | false | start the active-set solver from the previous active set of the same QP size (the RTI itself always linearises about the previous solution); off: not faster in two measurements on a loaded machine (docs/simplified.md) |
/// | `min_remaining_time` | 0.15 s | a contact that starts sooner than this is no longer moved |
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CentroidalMpcConfig {
    /// Stage length `dt` \[s\].
    pub stage_duration: f64,
    /// Number of stages `N`.
    pub stages: usize,
    /// Stages over which a corner force is held constant (move blocking; 1 = one force per stage).
    pub force_hold_stages: usize,
    /// Re-solve period used by the runner \[s\].
    pub update_period: f64,
    /// Friction coefficient `μ`.
    pub friction: f64,
    /// CoM tracking weight per axis \[1/m²\].
    pub com_weight: [f64; 3],
    /// Angular momentum weight \[1/(kg m²/s)²\].
    pub angular_momentum_weight: f64,
    /// Weight of each corner force's distance to the contact's corner average \[1/N²\].
    pub force_average_weight: f64,
    /// Weight of the corner-force rate \[1/(N/s)²\].
    pub force_rate_weight: f64,
    /// Weight of the contact displacement \[1/m²\].
    pub contact_position_weight: f64,
    /// Tikhonov weight on the cone coordinates \[1/N²\].
    pub force_regularization: f64,
    /// Displacement box along the sole x axis \[m\].
    pub forward: Interval,
    /// Displacement box across the sole, positive away from the other foot \[m\].
    pub outward: Interval,
    /// Contacts starting sooner than this are not moved \[s\].
    pub min_remaining_time: f64,
    /// Whether the runner estimates the external force and passes it on.
    pub external_force: bool,
    /// Estimates below this magnitude are ignored \[N\].
    pub external_force_threshold: f64,
    /// Stages over which the external force acts in the prediction.
    pub external_force_stages: usize,
    /// Whether the runner passes the push response's estimate as the external force, over the whole
    /// horizon.
    pub push_estimate: bool,
    /// Dead band of the runner's swing retargeting \[m\].
    pub deadband: f64,
    /// Whether the DCM PI tracks the MPC's prediction (else the plan's CoM).
    pub track_prediction: bool,
    /// Warm start of the active-set solver from its previous active set.
    pub warm_start_active_set: bool,
}

impl Default for CentroidalMpcConfig {
    fn default() -> Self {
        Self {
            stage_duration: 0.1,
            stages: 12,
            force_hold_stages: 2,
            update_period: 0.05,
            friction: 0.33,
            com_weight: [1e4, 1e4, 1e5],
            angular_momentum_weight: 10.0,
            force_average_weight: 1e-4,
            force_rate_weight: 1e-6,
            contact_position_weight: 2e3,
            force_regularization: 1e-7,
            forward: [-0.10, 0.10],
            outward: [0.0, 0.10],
            min_remaining_time: 0.15,
            external_force: false,
            external_force_threshold: 30.0,
            external_force_stages: 1,
            push_estimate: false,
            deadband: 0.02,
            track_prediction: false,
            warm_start_active_set: false,
        }
    }
}

fn invalid(name: &'static str, value: f64, reason: &'static str) -> SimplifiedError {
    SimplifiedError::InvalidParameter {
        name,
        value,
        reason,
    }
}

fn interval(name: &'static str, [lower, upper]: Interval) -> Result<()> {
    if !(lower.is_finite() && upper.is_finite()) {
        return Err(invalid(name, f64::NAN, "bounds must be finite"));
    }
    if lower > 0.0 || upper < 0.0 {
        return Err(invalid(name, lower, "must contain 0 (lower <= 0 <= upper)"));
    }
    Ok(())
}

impl CentroidalMpcConfig {
    /// Checks every field (ranges above; the box intervals must contain 0 so that the planned contact
    /// is feasible).
    pub fn validate(&self) -> Result<()> {
        positive("centroidal_mpc.stage_duration", self.stage_duration)?;
        positive("centroidal_mpc.update_period", self.update_period)?;
        if self.stages < 2 || self.stages > MAX_CENTROIDAL_STAGES {
            return Err(invalid(
                "centroidal_mpc.stages",
                self.stages as f64,
                "must be in [2, 30]",
            ));
        }
        if self.force_hold_stages == 0 || self.force_hold_stages > self.stages {
            return Err(invalid(
                "centroidal_mpc.force_hold_stages",
                self.force_hold_stages as f64,
                "must be in [1, stages]",
            ));
        }
        positive("centroidal_mpc.friction", self.friction)?;
        for w in self.com_weight {
            non_negative("centroidal_mpc.com_weight", w)?;
        }
        non_negative(
            "centroidal_mpc.angular_momentum_weight",
            self.angular_momentum_weight,
        )?;
        non_negative(
            "centroidal_mpc.force_average_weight",
            self.force_average_weight,
        )?;
        non_negative("centroidal_mpc.force_rate_weight", self.force_rate_weight)?;
        positive(
            "centroidal_mpc.contact_position_weight",
            self.contact_position_weight,
        )?;
        positive(
            "centroidal_mpc.force_regularization",
            self.force_regularization,
        )?;
        interval("centroidal_mpc.forward", self.forward)?;
        interval("centroidal_mpc.outward", self.outward)?;
        non_negative("centroidal_mpc.deadband", self.deadband)?;
        non_negative(
            "centroidal_mpc.external_force_threshold",
            self.external_force_threshold,
        )?;
        if self.external_force_stages > self.stages {
            return Err(invalid(
                "centroidal_mpc.external_force_stages",
                self.external_force_stages as f64,
                "must be <= stages",
            ));
        }
        if self.push_estimate && self.external_force {
            return Err(invalid(
                "centroidal_mpc.push_estimate",
                1.0,
                "one source of the external force: not with `external_force`",
            ));
        }
        non_negative("centroidal_mpc.min_remaining_time", self.min_remaining_time)
    }

    /// Stages over which the input's external force acts in the prediction: all of them with
    /// `push_estimate` (the estimate held over the horizon), else `external_force_stages`.
    pub fn external_stages(&self) -> usize {
        if self.push_estimate {
            self.stages
        } else {
            self.external_force_stages
        }
    }
}
