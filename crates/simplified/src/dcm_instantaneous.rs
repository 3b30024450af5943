//! DCM instantaneous controller [Romualdi 2022, eq. 10.2.17]: a proportional–integral law on the DCM error giving
//! the desired ZMP, with the desired ZMP projected onto the support polygon and an anti-windup integral.

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};

use crate::error::{check_non_negative, Result, SimplifiedError};
use crate::lipm::{check_omega, check_point};
use stride_block::SupportPolygon;

/// Parameters of the DCM instantaneous (PI) controller. Gains are isotropic (the same on x and y), so
/// the law does not depend on the robot's heading.
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `kp` | – | 1.2 | proportional gain `K_p^ξ`, must be > 1 ([Romualdi 2022, eq. 10.2.17]: `K_p > I₂`); the error decays as `e^{−ω(kp−1)t}` |
/// | `ki` | s⁻¹ | 0.0 | integral gain `K_i^ξ`, ≥ 0 (iCub runs with 0; > 0 removes a constant ZMP tracking bias) |
/// | `integral_limit` | m | 0.03 | anti-windup: bound on each component of the integral term `K_i ∫e dt` |
///
/// Defaults follow the iCub walking-controllers (`kDCM` 1.1–1.2, `kIDCM` 0).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DcmInstantaneousConfig {
    /// Proportional gain (> 1).
    pub kp: f64,
    /// Integral gain \[s⁻¹\] (≥ 0).
    pub ki: f64,
    /// Bound on each component of the integral term \[m\] (≥ 0).
    pub integral_limit: f64,
}

impl Default for DcmInstantaneousConfig {
    fn default() -> Self {
        Self {
            kp: 1.2,
            ki: 0.0,
            integral_limit: 0.03,
        }
    }
}

impl DcmInstantaneousConfig {
    /// Checks the ranges documented on the struct.
    pub fn validate(&self) -> Result<()> {
        if !(self.kp.is_finite() && self.kp > 1.0) {
            return Err(SimplifiedError::InvalidParameter {
                name: "instantaneous.kp",
                value: self.kp,
                reason: "must be finite and > 1 (K_p > I2, [Romualdi 2022, eq. 10.2.17])",
            });
        }
        check_non_negative("instantaneous.ki", self.ki)?;
        check_non_negative("instantaneous.integral_limit", self.integral_limit)
    }
}

/// The control law [Romualdi 2022, eq. 10.2.17] without projection:
/// `p* = ξ_ref − ξ̇_ref/ω + kp (ξ − ξ_ref) + ki ∫(ξ − ξ_ref) dt`.
///
/// `error_integral` is `∫(ξ − ξ_ref) dt` \[m·s\]. Exposed so that tests can exercise gains the
/// controller's configuration rejects (e.g. `kp ≤ 1`, which diverges).
pub fn dcm_instantaneous_law(
    planned_dcm: Vector2<f64>,
    planned_dcm_velocity: Vector2<f64>,
    measured_dcm: Vector2<f64>,
    error_integral: Vector2<f64>,
    kp: f64,
    ki: f64,
    omega: f64,
) -> Vector2<f64> {
    planned_dcm - planned_dcm_velocity / omega
        + (measured_dcm - planned_dcm) * kp
        + error_integral * ki
}

/// What one tick of the DCM instantaneous controller produces.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct DcmInstantaneousOutput {
    /// Desired ZMP \[m\], inside the support polygon.
    pub desired_zmp: Vector2<f64>,
    /// The law's ZMP before the projection \[m\].
    pub unprojected_zmp: Vector2<f64>,
    /// DCM error `ξ − ξ_ref` \[m\].
    pub dcm_error: Vector2<f64>,
    /// Integral term `K_i ∫e dt` \[m\] used this tick.
    pub integral_term: Vector2<f64>,
    /// True when the law's ZMP was outside the polygon and was projected onto it.
    pub projection_active: bool,
}

/// The DCM instantaneous controller with its integral state.
///
/// Anti-windup: the integral term is clamped to `±integral_limit` per axis, and the integral is not
/// updated on a tick where the projection is active (conditional integration). A failed step (error
/// returned) changes nothing.
#[derive(Debug, Clone)]
pub struct DcmInstantaneousController {
    config: DcmInstantaneousConfig,
    error_integral: Vector2<f64>,
}

impl DcmInstantaneousController {
    /// Builds the controller from a validated configuration.
    pub fn new(config: DcmInstantaneousConfig) -> Result<Self> {
        config.validate()?;
        Ok(Self {
            config,
            error_integral: Vector2::zeros(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &DcmInstantaneousConfig {
        &self.config
    }

    /// Current `∫(ξ − ξ_ref) dt` \[m·s\].
    pub fn error_integral(&self) -> Vector2<f64> {
        self.error_integral
    }

    /// Zeroes the integral.
    pub fn reset(&mut self) {
        self.error_integral = Vector2::zeros();
    }

    /// One tick of length `dt` \[s\]: planned DCM \[m\] and DCM velocity \[m/s\], measured DCM \[m\], natural
    /// frequency `omega` \[s⁻¹\], current support polygon.
    ///
    /// Errors (`NonFiniteInput`, `InvalidParameter`) leave the state unchanged.
    pub fn step(
        &mut self,
        planned_dcm: Vector2<f64>,
        planned_dcm_velocity: Vector2<f64>,
        measured_dcm: Vector2<f64>,
        omega: f64,
        support: &SupportPolygon,
        dt: f64,
    ) -> Result<DcmInstantaneousOutput> {
        check_point("planned_dcm_position", &planned_dcm)?;
        check_point("planned_dcm_velocity", &planned_dcm_velocity)?;
        check_point("measured_dcm", &measured_dcm)?;
        check_omega(omega)?;
        check_non_negative("dt", dt)?;
        let error = measured_dcm - planned_dcm;
        let DcmInstantaneousConfig {
            kp,
            ki,
            integral_limit,
        } = self.config;
        let clamp_integral = |integral: Vector2<f64>| -> Vector2<f64> {
            if ki > 0.0 {
                let bound = integral_limit / ki;
                integral.map(|v| v.clamp(-bound, bound))
            } else {
                integral
            }
        };
        let mut integral = clamp_integral(self.error_integral + error * dt);
        let mut unprojected = dcm_instantaneous_law(
            planned_dcm,
            planned_dcm_velocity,
            measured_dcm,
            integral,
            kp,
            ki,
            omega,
        );
        let (mut desired, mut active) = support.project(unprojected);
        if active && ki > 0.0 {
            // Conditional integration: do not accumulate while the output saturates.
            integral = self.error_integral;
            unprojected = dcm_instantaneous_law(
                planned_dcm,
                planned_dcm_velocity,
                measured_dcm,
                integral,
                kp,
                ki,
                omega,
            );
            (desired, active) = support.project(unprojected);
        }
        self.error_integral = integral;
        Ok(DcmInstantaneousOutput {
            desired_zmp: desired,
            unprojected_zmp: unprojected,
            dcm_error: error,
            integral_term: integral * ki,
            projection_active: active,
        })
    }
}
