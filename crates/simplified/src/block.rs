//! The simplified-model control layer as a [`stride_block::Block`]: a DCM controller (instantaneous or
//! predictive, chosen in the config) followed by the ZMP-CoM controller.

use std::time::{Duration, Instant};

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};

use crate::centroidal_mpc::CentroidalMpcConfig;
use crate::dcm_instantaneous::{DcmInstantaneousConfig, DcmInstantaneousController};
use crate::dcm_predictive::{
    DcmHorizon, DcmPredictiveConfig, DcmPredictiveController, MpcDiagnostics,
};
use crate::error::{check_finite, Result, SimplifiedError};
use crate::foot_admittance::FootAdmittanceConfig;
use crate::lipm::{check_omega, check_point};
use crate::push_observer::PushConfig;
use crate::step_adjustment::StepAdjustmentConfig;
use crate::zmp_com::{ZmpComConfig, ZmpComController, ZmpComGains};
use stride_block::SupportPolygon;

/// Which DCM controller the layer runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum DcmControllerKind {
    /// The PI law [Romualdi 2022, eq. 10.2.17] with projection onto the support polygon.
    #[default]
    Instantaneous,
    /// The MPC [Romualdi 2022, eq. 10.2.23].
    Predictive,
    /// The centroidal MPC with footstep adjustment [Romualdi 2022, ch. 11] ([`crate::CentroidalMpc`],
    /// run by the caller from the `centroidal_mpc` section) in front of the PI law, which then tracks the
    /// DCM of the centroidal MPC's predicted CoM instead of the plan's.
    CentroidalMpc,
}

/// Configuration of the simplified-model control layer (TOML section, every field optional).
///
/// | field | default | meaning |
/// |---|---|---|
/// | `dcm_controller` | `"instantaneous"` | `"instantaneous"`, `"predictive"` or `"centroidal_mpc"` |
/// | `instantaneous` | see [`DcmInstantaneousConfig`] | `kp` 1.2, `ki` 0, `integral_limit` 0.03 m |
/// | `predictive` | see [`DcmPredictiveConfig`] | `horizon` 2 s, `dcm_weight` 7500, `zmp_rate_weight` 9e4, … |
/// | `zmp_com` | see [`ZmpComConfig`] | walking `{k_zmp 1.5, k_com 5}`, standing `{1.0, 4.0}`, `transition_time` 0.05 s |
/// | `centroidal_mpc` | see [`CentroidalMpcConfig`] | horizon, weights, adjustment box of the centroidal MPC (used by the runner when selected) |
/// | `step_adjustment` | see [`StepAdjustmentConfig`] | `enabled` false; box, durations and weights of the step-adjustment QP (used by the runner) |
/// | `foot_admittance` | see [`FootAdmittanceConfig`] | `enabled` false; foot damping and force difference control of position control (used by the runner) |
/// | `push` | see [`PushConfig`] | `enabled` false; push estimate (momentum observer), double-support hold, push-aware step adjustment (used by the runner) |
///
/// ```toml
/// dcm_controller = "predictive"
/// \[predictive\]
/// horizon = 2.0
/// \[zmp_com\]
/// walking = { k_zmp = 1.5, k_com = 5.0 }
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct SimplifiedConfig {
    /// Which DCM controller runs.
    pub dcm_controller: DcmControllerKind,
    /// Parameters of the instantaneous controller (used when selected).
    pub instantaneous: DcmInstantaneousConfig,
    /// Parameters of the predictive controller (used when selected).
    pub predictive: DcmPredictiveConfig,
    /// Parameters of the ZMP-CoM controller (always used).
    pub zmp_com: ZmpComConfig,
    /// The centroidal MPC (the runner runs it when `dcm_controller = "centroidal_mpc"`).
    pub centroidal_mpc: CentroidalMpcConfig,
    /// Step adjustment (the runner runs it during single support when `enabled`).
    pub step_adjustment: StepAdjustmentConfig,
    /// Foot admittance of position control (the runner moves the sole references when `enabled`).
    pub foot_admittance: FootAdmittanceConfig,
    /// Push estimate and the stack's response to it (the runner runs it when `enabled`).
    pub push: PushConfig,
}

impl SimplifiedConfig {
    /// Validates every section (also the one of the controller that is not selected).
    pub fn validate(&self) -> Result<()> {
        self.instantaneous.validate()?;
        self.predictive.validate()?;
        self.zmp_com.validate()?;
        self.centroidal_mpc.validate()?;
        self.step_adjustment.validate()?;
        self.push.validate()?;
        if self.centroidal_mpc.push_estimate && !self.push.enabled {
            return Err(SimplifiedError::InvalidParameter {
                name: "centroidal_mpc.push_estimate",
                value: 1.0,
                reason: "needs the push response's estimate: [simplified.push] enabled = true",
            });
        }
        self.foot_admittance.validate()
    }
}

/// The `omega` of a fresh [`SimplifiedInput`] \[s⁻¹\]: a valid value (`√(9.81 / 0.5)`, a 0.5 m LIPM)
/// until the caller writes the plan's `ω`; the layer has no gravity of its own (the plan's `ω` carries
/// it).
pub const PLACEHOLDER_OMEGA: f64 = 4.429_446_918_070_020_4;

/// Everything one tick of the layer needs (plain data; 2D vectors are world x, y in metres).
///
/// Build it once with [`SimplifiedInput::new`] (which allocates the horizon buffer) and refill it every
/// tick. `horizon` is only read by the predictive controller.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SimplifiedInput {
    /// Current time (copied to the output).
    pub time: Duration,
    /// LIPM natural frequency `ω = sqrt(g/h)` \[s⁻¹\] of the plan.
    pub omega: f64,
    /// True while walking (walking ZMP-CoM gains), false while standing.
    pub walking: bool,
    /// Planned DCM at the current time \[m\].
    pub planned_dcm_position: Vector2<f64>,
    /// Planned DCM velocity at the current time \[m/s\].
    pub planned_dcm_velocity: Vector2<f64>,
    /// Planned ZMP at the current time \[m\].
    pub planned_zmp: Vector2<f64>,
    /// Planned CoM position at the current time \[m\].
    pub planned_com_position: Vector2<f64>,
    /// Planned CoM velocity at the current time \[m/s\].
    pub planned_com_velocity: Vector2<f64>,
    /// Measured (estimated) CoM position \[m\].
    pub measured_com_position: Vector2<f64>,
    /// Measured CoM velocity \[m/s\] (diagnostics only; the laws use the measured DCM).
    pub measured_com_velocity: Vector2<f64>,
    /// Measured DCM \[m\] (e.g. [`crate::dcm_from_com`] of the measured CoM).
    pub measured_dcm: Vector2<f64>,
    /// Measured ZMP \[m\] (e.g. [`crate::measured_zmp`] of the feet wrenches).
    pub measured_zmp: Vector2<f64>,
    /// Current support polygon (hull of the feet in contact, [`crate::feet_support_polygon`]).
    pub support_polygon: SupportPolygon,
    /// Plan over the MPC horizon (predictive controller only).
    pub horizon: DcmHorizon,
}

impl SimplifiedInput {
    /// An input with zero vectors, `omega` = [`PLACEHOLDER_OMEGA`], the given support polygon and a horizon
    /// buffer of `horizon_capacity` samples (use [`SimplifiedController::horizon_samples`]).
    pub fn new(horizon_capacity: usize, support_polygon: SupportPolygon) -> Self {
        Self {
            time: Duration::ZERO,
            omega: PLACEHOLDER_OMEGA,
            walking: false,
            planned_dcm_position: Vector2::zeros(),
            planned_dcm_velocity: Vector2::zeros(),
            planned_zmp: Vector2::zeros(),
            planned_com_position: Vector2::zeros(),
            planned_com_velocity: Vector2::zeros(),
            measured_com_position: Vector2::zeros(),
            measured_com_velocity: Vector2::zeros(),
            measured_dcm: Vector2::zeros(),
            measured_zmp: Vector2::zeros(),
            support_polygon,
            horizon: DcmHorizon::with_capacity(horizon_capacity),
        }
    }
}

/// Controller diagnostics of one tick.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct SimplifiedDiagnostics {
    /// DCM controller that produced the tick.
    pub controller: DcmControllerKind,
    /// DCM error `ξ − ξ_ref` \[m\].
    pub dcm_error: Vector2<f64>,
    /// Integral term `K_i ∫e dt` \[m\] (instantaneous controller; zero for the predictive one).
    pub integral_term: Vector2<f64>,
    /// The DCM controller's ZMP before projection onto the support polygon \[m\].
    pub unprojected_zmp: Vector2<f64>,
    /// True when the projection onto the support polygon changed the ZMP.
    pub projection_active: bool,
    /// ZMP tracking error `p* − p` (desired minus measured) \[m\].
    pub zmp_error: Vector2<f64>,
    /// CoM error `x_ref − x` (planned minus measured) \[m\].
    pub com_error: Vector2<f64>,
    /// CoM velocity error `ẋ_ref − ẋ` \[m/s\].
    pub com_velocity_error: Vector2<f64>,
    /// ZMP-CoM gains applied.
    pub zmp_com_gains: Option<ZmpComGains>,
    /// Progress of the ZMP-CoM gain blend in \[0, 1\].
    pub gain_blend_progress: f64,
    /// True when `K_CoM > ω > K_ZMP > 0` (the thesis' conditions) held.
    pub thesis_gain_conditions_met: bool,
    /// MPC diagnostics (status `not_run` with the instantaneous controller).
    pub mpc: MpcDiagnostics,
    /// Wall-clock time of this tick of the running controllers \[s\]: the DCM controller (PI or MPC,
    /// whichever runs) plus the ZMP-CoM controller, with the input checks.
    pub solve_time: f64,
}

/// What one tick of the layer produces: references for the whole-body controller.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct SimplifiedOutput {
    /// Time of the input that produced this output.
    pub time: Duration,
    /// False until the first successful tick (then all fields below are meaningful).
    pub valid: bool,
    /// Desired ZMP \[m\], always inside the support polygon of the tick.
    pub desired_zmp: Vector2<f64>,
    /// CoM position reference \[m\].
    pub com_position: Vector2<f64>,
    /// CoM velocity reference \[m/s\].
    pub com_velocity: Vector2<f64>,
    /// LIPM-consistent CoM acceleration reference `ω² (x* − p*)` \[m/s²\].
    pub com_acceleration: Vector2<f64>,
    /// Diagnostics.
    pub diagnostics: SimplifiedDiagnostics,
}

/// The simplified-model control layer. See the crate documentation for the runner-facing contract.
///
/// ```
/// use std::time::Duration;
/// use stride_simplified::prelude::*;
/// use nalgebra::Vector2;
///
/// let mut layer = SimplifiedController::new(&SimplifiedConfig::default(), Duration::from_millis(10))?;
/// let foot = SupportPolygon::rectangle(-0.1, 0.1, -0.12, 0.12)?;
/// let mut input = SimplifiedInput::new(layer.horizon_samples(), foot);
/// input.omega = (9.81_f64 / 0.54).sqrt();
/// input.measured_dcm = Vector2::new(0.01, 0.0); // 1 cm ahead of the planned DCM (at the origin)
/// let out = layer.step(&input)?; // inherent: no need to import `Block`
/// assert!(out.valid && out.desired_zmp.x > 0.0); // the ZMP moves ahead to push the DCM back
/// # Ok::<(), SimplifiedError>(())
/// ```
#[derive(Debug, Clone)]
pub struct SimplifiedController {
    config: SimplifiedConfig,
    period: f64,
    instantaneous: DcmInstantaneousController,
    predictive: Option<DcmPredictiveController>,
    zmp_com: ZmpComController,
    output: SimplifiedOutput,
}

impl SimplifiedController {
    /// Builds the layer for its tick `period` (> 0); allocates the MPC workspace when the predictive
    /// controller is selected.
    pub fn new(config: &SimplifiedConfig, period: Duration) -> Result<Self> {
        config.validate()?;
        let period_s = period.as_secs_f64();
        if period_s <= 0.0 {
            return Err(SimplifiedError::InvalidParameter {
                name: "period",
                value: period_s,
                reason: "must be > 0",
            });
        }
        let predictive = match config.dcm_controller {
            DcmControllerKind::Predictive => {
                Some(DcmPredictiveController::new(config.predictive, period_s)?)
            }
            DcmControllerKind::Instantaneous | DcmControllerKind::CentroidalMpc => None,
        };
        Ok(Self {
            config: *config,
            period: period_s,
            instantaneous: DcmInstantaneousController::new(config.instantaneous)?,
            predictive,
            zmp_com: ZmpComController::new(config.zmp_com)?,
            output: SimplifiedOutput::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &SimplifiedConfig {
        &self.config
    }

    /// Tick period \[s\].
    pub fn period(&self) -> f64 {
        self.period
    }

    /// Samples the runner must push into [`SimplifiedInput::horizon`] each tick (`N + 1` for the
    /// predictive controller, 0 for the instantaneous one).
    pub fn horizon_samples(&self) -> usize {
        self.predictive.as_ref().map_or(0, |p| p.horizon_samples())
    }

    /// The last valid output (held after a failed tick).
    pub fn output(&self) -> &SimplifiedOutput {
        &self.output
    }

    /// The instantaneous DCM controller.
    pub fn instantaneous(&self) -> &DcmInstantaneousController {
        &self.instantaneous
    }

    /// The predictive DCM controller (None when not selected).
    pub fn predictive(&self) -> Option<&DcmPredictiveController> {
        self.predictive.as_ref()
    }

    /// The ZMP-CoM controller.
    pub fn zmp_com(&self) -> &ZmpComController {
        &self.zmp_com
    }

    fn validate_input(input: &SimplifiedInput) -> Result<()> {
        check_omega(input.omega)?;
        check_point("planned_dcm_position", &input.planned_dcm_position)?;
        check_point("planned_dcm_velocity", &input.planned_dcm_velocity)?;
        check_point("planned_zmp", &input.planned_zmp)?;
        check_point("planned_com_position", &input.planned_com_position)?;
        check_point("planned_com_velocity", &input.planned_com_velocity)?;
        check_point("measured_com_position", &input.measured_com_position)?;
        check_point("measured_com_velocity", &input.measured_com_velocity)?;
        check_point("measured_dcm", &input.measured_dcm)?;
        check_point("measured_zmp", &input.measured_zmp)?;
        check_finite("omega", input.omega)
    }
}

impl SimplifiedController {
    /// One tick. On error (non-finite input, empty MPC horizon, MPC failure) nothing changes and
    /// [`SimplifiedController::output`] still holds the last valid references: callers hold them.
    ///
    /// Inherent, so a caller need not import [`stride_block::Block`] (the `Block` impl calls it).
    pub fn step(&mut self, input: &SimplifiedInput) -> Result<&SimplifiedOutput> {
        let start = Instant::now();
        Self::validate_input(input)?;
        let mut diagnostics = SimplifiedDiagnostics {
            controller: self.config.dcm_controller,
            ..SimplifiedDiagnostics::default()
        };
        let desired_zmp = match self.predictive.as_mut() {
            Some(mpc) => {
                let out = mpc.step(
                    input.omega,
                    input.measured_dcm,
                    &input.horizon,
                    &input.support_polygon,
                )?;
                diagnostics.dcm_error = out.dcm_error;
                diagnostics.unprojected_zmp = out.unprojected_zmp;
                diagnostics.projection_active = out.projection_active;
                diagnostics.mpc = out.diagnostics;
                out.desired_zmp
            }
            None => {
                let out = self.instantaneous.step(
                    input.planned_dcm_position,
                    input.planned_dcm_velocity,
                    input.measured_dcm,
                    input.omega,
                    &input.support_polygon,
                    self.period,
                )?;
                diagnostics.dcm_error = out.dcm_error;
                diagnostics.integral_term = out.integral_term;
                diagnostics.unprojected_zmp = out.unprojected_zmp;
                diagnostics.projection_active = out.projection_active;
                out.desired_zmp
            }
        };
        let com = self.zmp_com.step(
            input.walking,
            input.omega,
            desired_zmp,
            input.measured_zmp,
            input.planned_com_position,
            input.planned_com_velocity,
            input.measured_com_position,
            self.period,
        )?;
        diagnostics.zmp_error = desired_zmp - input.measured_zmp;
        diagnostics.com_error = input.planned_com_position - input.measured_com_position;
        diagnostics.com_velocity_error = input.planned_com_velocity - input.measured_com_velocity;
        diagnostics.zmp_com_gains = Some(com.gains);
        diagnostics.gain_blend_progress = com.blend_progress;
        diagnostics.thesis_gain_conditions_met = com.thesis_conditions_met;
        diagnostics.solve_time = start.elapsed().as_secs_f64();
        self.output = SimplifiedOutput {
            time: input.time,
            valid: true,
            desired_zmp,
            com_position: com.com_position,
            com_velocity: com.com_velocity,
            com_acceleration: com.com_acceleration,
            diagnostics,
        };
        Ok(&self.output)
    }
}

impl stride_block::Block for SimplifiedController {
    type Input = SimplifiedInput;
    type Output = SimplifiedOutput;
    type Error = SimplifiedError;

    fn step(&mut self, input: &SimplifiedInput) -> Result<&SimplifiedOutput> {
        SimplifiedController::step(self, input)
    }

    fn reset(&mut self) {
        self.instantaneous.reset();
        if let Some(mpc) = self.predictive.as_mut() {
            mpc.reset();
        }
        self.zmp_com.reset();
        self.output = SimplifiedOutput::default();
    }
}
