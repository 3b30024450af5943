//! ZMP-CoM controller [Romualdi 2022, eq. 10.2.25], after [Choi 2007], with standing/walking gain
//! scheduling.
//!
//! `ẋ* = ẋ_ref − K_ZMP (p* − p) + K_CoM (x_ref − x)` with `p*` the desired ZMP (output of the DCM
//! controller), `p` the measured ZMP, `x_ref, ẋ_ref` the planned CoM and `x` the measured CoM.
//!
//! **Stability.** With ideal CoM-velocity tracking and the LIPM ZMP `p = x − ẍ/ω²`, the CoM error
//! `e = x_ref − x` obeys `(K_ZMP/ω²) ë + ė + (K_CoM − K_ZMP) e = 0`, stable iff `K_CoM > K_ZMP > 0`.
//! The thesis' sufficient conditions `K_CoM > ω > K_ZMP > 0` imply it. The configuration rejects gains
//! that violate `K_CoM > K_ZMP > 0`; [`ZmpComOutput::thesis_conditions_met`] reports the thesis' form.
//!
//! **Position reference.** The CoM position reference integrates `ẋ*`; it is kept as the plan plus an
//! integrated correction, `x* = x_ref + δ`, `δ̇ = ẋ* − ẋ_ref` (forward Euler at the layer period). This is
//! the same integral in continuous time, but with perfect tracking `δ ≡ 0` and the plan is reproduced
//! exactly whatever the period (a plain Euler integral of `ẋ*` drifts by O(dt) from the plan).

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};

use crate::error::{check_non_negative, Result, SimplifiedError};
use crate::lipm::{check_omega, check_point};

/// One pair of ZMP-CoM gains (isotropic, s⁻¹).
///
/// | field | unit | meaning |
/// |---|---|---|
/// | `k_zmp` | s⁻¹ | ZMP error gain `K_ZMP` > 0 |
/// | `k_com` | s⁻¹ | CoM error gain `K_CoM` (the thesis' `K_LIP`) > `k_zmp` |
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ZmpComGains {
    /// ZMP gain `K_ZMP` \[s⁻¹\].
    pub k_zmp: f64,
    /// CoM gain `K_CoM` \[s⁻¹\].
    pub k_com: f64,
}

impl ZmpComGains {
    /// Checks `k_com > k_zmp > 0` (the stability condition of the closed loop).
    pub fn validate(&self, name: &'static str) -> Result<()> {
        if !(self.k_zmp.is_finite() && self.k_zmp > 0.0) {
            return Err(SimplifiedError::InvalidParameter {
                name,
                value: self.k_zmp,
                reason: "k_zmp must be finite and > 0",
            });
        }
        if !(self.k_com.is_finite() && self.k_com > self.k_zmp) {
            return Err(SimplifiedError::InvalidParameter {
                name,
                value: self.k_com,
                reason: "k_com must be finite and > k_zmp (otherwise the CoM error diverges)",
            });
        }
        Ok(())
    }

    fn lerp(&self, other: &Self, s: f64) -> Self {
        Self {
            k_zmp: self.k_zmp + s * (other.k_zmp - self.k_zmp),
            k_com: self.k_com + s * (other.k_com - self.k_com),
        }
    }
}

/// Parameters of the ZMP-CoM controller.
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `walking` | s⁻¹ | `{ k_zmp = 1.5, k_com = 5.0 }` | gains while walking (iCub: K_ZMP 1.3–3, K_CoM 5–10) |
/// | `standing` | s⁻¹ | `{ k_zmp = 1.0, k_com = 4.0 }` | gains while standing |
/// | `transition_time` | s | 0.05 | duration of the minimum-jerk blend between the two gain sets (0 = switch) |
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ZmpComConfig {
    /// Gains used while walking.
    pub walking: ZmpComGains,
    /// Gains used while standing.
    pub standing: ZmpComGains,
    /// Duration of the gain blend \[s\].
    pub transition_time: f64,
}

impl Default for ZmpComConfig {
    fn default() -> Self {
        Self {
            walking: ZmpComGains {
                k_zmp: 1.5,
                k_com: 5.0,
            },
            standing: ZmpComGains {
                k_zmp: 1.0,
                k_com: 4.0,
            },
            transition_time: 0.05,
        }
    }
}

impl ZmpComConfig {
    /// Checks the ranges documented on the struct.
    pub fn validate(&self) -> Result<()> {
        self.walking.validate("zmp_com.walking")?;
        self.standing.validate("zmp_com.standing")?;
        check_non_negative("zmp_com.transition_time", self.transition_time)
    }
}

/// The law [Romualdi 2022, eq. 10.2.25]: `ẋ* = ẋ_ref − K_ZMP (p* − p) + K_CoM (x_ref − x)` \[m/s\].
///
/// Exposed (without gain checks) so that tests can show that violating the gain bound diverges.
pub fn zmp_com_law(
    gains: &ZmpComGains,
    planned_com_velocity: Vector2<f64>,
    desired_zmp: Vector2<f64>,
    measured_zmp: Vector2<f64>,
    planned_com_position: Vector2<f64>,
    measured_com_position: Vector2<f64>,
) -> Vector2<f64> {
    planned_com_velocity - (desired_zmp - measured_zmp) * gains.k_zmp
        + (planned_com_position - measured_com_position) * gains.k_com
}

/// Minimum-jerk blend `s(τ) = 10τ³ − 15τ⁴ + 6τ⁵`, τ clamped to \[0, 1\]: zero velocity and acceleration
/// at both ends.
pub fn minimum_jerk_blend(tau: f64) -> f64 {
    let t = tau.clamp(0.0, 1.0);
    t * t * t * (10.0 + t * (-15.0 + 6.0 * t))
}

/// What one tick of the ZMP-CoM controller produces.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ZmpComOutput {
    /// CoM position reference `x* = x_ref + δ` \[m\].
    pub com_position: Vector2<f64>,
    /// CoM velocity reference `ẋ*` \[m/s\].
    pub com_velocity: Vector2<f64>,
    /// LIPM-consistent CoM acceleration reference `ω² (x* − p*)` \[m/s²\].
    pub com_acceleration: Vector2<f64>,
    /// Gains used this tick.
    pub gains: ZmpComGains,
    /// Progress of the gain blend in \[0, 1\] (1 = settled on the target gains).
    pub blend_progress: f64,
    /// True when the thesis' conditions `K_CoM > ω > K_ZMP > 0` hold for this tick's gains.
    pub thesis_conditions_met: bool,
}

/// The ZMP-CoM controller with its gain-schedule and position-integration state.
/// A failed step (error returned) changes nothing.
#[derive(Debug, Clone)]
pub struct ZmpComController {
    config: ZmpComConfig,
    walking: Option<bool>,
    blend_from: ZmpComGains,
    blend_elapsed: f64,
    correction: Vector2<f64>,
}

impl ZmpComController {
    /// Builds the controller from a validated configuration. It starts on the gains of the first
    /// step's walking flag (no blend on the first tick).
    pub fn new(config: ZmpComConfig) -> Result<Self> {
        config.validate()?;
        Ok(Self {
            config,
            walking: None,
            blend_from: config.standing,
            blend_elapsed: 0.0,
            correction: Vector2::zeros(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &ZmpComConfig {
        &self.config
    }

    /// Back to the state right after `new`.
    pub fn reset(&mut self) {
        self.walking = None;
        self.blend_from = self.config.standing;
        self.blend_elapsed = 0.0;
        self.correction = Vector2::zeros();
    }

    /// Integrated correction `δ = x* − x_ref` \[m\].
    pub fn correction(&self) -> Vector2<f64> {
        self.correction
    }

    fn target(&self, walking: bool) -> ZmpComGains {
        if walking {
            self.config.walking
        } else {
            self.config.standing
        }
    }

    fn blend(&self, walking: bool, elapsed: f64) -> (ZmpComGains, f64) {
        let target = self.target(walking);
        let progress = if self.config.transition_time > 0.0 {
            (elapsed / self.config.transition_time).clamp(0.0, 1.0)
        } else {
            1.0
        };
        (
            self.blend_from.lerp(&target, minimum_jerk_blend(progress)),
            progress,
        )
    }

    /// Gains currently applied (the blend evaluated at the current time).
    pub fn current_gains(&self) -> ZmpComGains {
        match self.walking {
            Some(w) => self.blend(w, self.blend_elapsed).0,
            None => self.config.standing,
        }
    }

    /// One tick of length `dt` \[s\].
    ///
    /// | argument | unit | meaning |
    /// |---|---|---|
    /// | `walking` | – | selects the walking (true) or standing gains; a change starts a blend |
    /// | `omega` | s⁻¹ | LIPM natural frequency (for the acceleration reference and the diagnostics) |
    /// | `desired_zmp` | m | output of the DCM controller |
    /// | `measured_zmp` | m | ZMP from the feet wrenches |
    /// | `planned_com_position`, `planned_com_velocity` | m, m/s | plan at the current time |
    /// | `measured_com_position` | m | estimated CoM |
    #[allow(clippy::too_many_arguments)]
    pub fn step(
        &mut self,
        walking: bool,
        omega: f64,
        desired_zmp: Vector2<f64>,
        measured_zmp: Vector2<f64>,
        planned_com_position: Vector2<f64>,
        planned_com_velocity: Vector2<f64>,
        measured_com_position: Vector2<f64>,
        dt: f64,
    ) -> Result<ZmpComOutput> {
        check_omega(omega)?;
        check_point("desired_zmp", &desired_zmp)?;
        check_point("measured_zmp", &measured_zmp)?;
        check_point("planned_com_position", &planned_com_position)?;
        check_point("planned_com_velocity", &planned_com_velocity)?;
        check_point("measured_com_position", &measured_com_position)?;
        check_non_negative("dt", dt)?;
        match self.walking {
            None => {
                self.blend_from = self.target(walking);
                self.blend_elapsed = self.config.transition_time;
            }
            Some(previous) if previous != walking => {
                self.blend_from = self.blend(previous, self.blend_elapsed).0;
                self.blend_elapsed = 0.0;
            }
            Some(_) => {}
        }
        self.walking = Some(walking);
        let (gains, progress) = self.blend(walking, self.blend_elapsed);
        let velocity = zmp_com_law(
            &gains,
            planned_com_velocity,
            desired_zmp,
            measured_zmp,
            planned_com_position,
            measured_com_position,
        );
        let position = planned_com_position + self.correction;
        self.correction += (velocity - planned_com_velocity) * dt;
        self.blend_elapsed += dt;
        Ok(ZmpComOutput {
            com_position: position,
            com_velocity: velocity,
            com_acceleration: (position - desired_zmp) * (omega * omega),
            gains,
            blend_progress: progress,
            thesis_conditions_met: gains.k_com > omega && omega > gains.k_zmp && gains.k_zmp > 0.0,
        })
    }
}
