//! Compensation of the motors' dynamics on the TSID's torques (`[wbc.tsid.actuators]`).
//!
//! The TSID chooses the joint torques `τ*` the rigid-body model needs now; a motor whose torque follows
//! its command through a first-order lag of bandwidth `f`, `τ ← τ + β (u − τ)` per control period `T`
//! (`β = 1 − e^{−2π f T}`, the exact step response of the lag over a held command), applies `τ*` one time
//! constant `1/(2π f)` late. The lead here inverts that lag on the controller's own model of the motor
//! torque `τ̂`:
//!
//! `u = τ̂ + (τ* − τ̂) / β`, bounded to `|u − τ*| ≤ max_lead`, then `τ̂ ← τ̂ + β (u − τ̂)`,
//!
//! so that, unbounded, the lagged torque equals `τ*` at the end of each period (`τ̂ = τ*` after every tick).
//! Written with the previous command it is the lead `u = τ* + (1/β − 1)(τ*ₖ − τ*ₖ₋₁)`, the continuous
//! `τ* + T_lag dτ*/dt` with `T_lag = 1/(2π f)` and its derivative from the previous command, less half a
//! period. A bounded tick leaves `τ̂` short of `τ*` (the motor really is short), and the next tick closes the
//! rest: no wind-up. The Coulomb friction feed-forward adds `τ_c sat((q̇ + T q̈*) / v_s)` to `τ*` before the lead (the
//! friction acts on the joint, so the motor torque must carry it; the velocity is the one the TSID's
//! acceleration `q̈*` asks at the end of the period, since a joint at rest sticks until its torque exceeds
//! `τ_c`).
//!
//! The model does not see the plant's command delay (a pure delay is not invertible): the lead's command
//! reaches the motor `command_delay_steps` late, and the lagged torque then equals `τ*` that much later.

use nalgebra::DVector;
use serde::{Deserialize, Serialize};
use stride_model::RobotState;

use crate::WbcError;

/// The actuator model the TSID's commanded torques compensate (`[wbc.tsid.actuators]`). Default: ideal
/// motors, no compensation (the command is the TSID's `τ*`).
///
/// | key | unit | default | meaning |
/// |---|---|---|---|
/// | `torque_bandwidth` | Hz | 0 | the motors' first-order torque lag `f` the command pre-compensates, `u = τ̂ + (τ* − τ̂)/β`, `β = 1 − e^{−2π f T}` (0: none); stride-sim's `[sim.actuation.default] torque_bandwidth` is the plant's |
/// | `max_lead` | N·m | 1 | bound on the lead, `|u − τ*| ≤ max_lead` (measured on the compliant walk with stride-sim's default actuators: 1 reaches the goal, 2 falls after 0.75 m; on the lag alone 2 reaches it, 5 falls after 0.88 m: the lead amplifies the torques' tick-to-tick changes fivefold) |
/// | `coulomb_friction` | N·m | 0 | joint Coulomb friction `τ_c` fed forward, `+ τ_c sat((q̇ + T q̈*) / friction_velocity)` on `τ*`, `q̈*` the TSID's joint acceleration, `T` the control period (0: none) |
/// | `friction_velocity` | rad/s | 0.05 | the joint speed at which the feed-forward reaches `τ_c` |
/// | `command_delay` | s | 0 | the delay between the measurement and the command reaching the motors the TSID predicts across: its input state is the estimate advanced by this time with the last tick's accelerations, `ν + d ν̇`, joint and base positions `+ d ν + d²/2 ν̇` (0: none); stride-sim's `command_delay_steps / sim_hz` is the plant's |
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ActuatorConfig {
    /// Bandwidth `f` of the motors' first-order torque lag the lead inverts, Hz (0: no lead).
    pub torque_bandwidth: f64,
    /// Bound on `|u − τ*|`, N·m (> 0; default 1, measured: docs/soft-ground.md).
    pub max_lead: f64,
    /// Coulomb friction `τ_c` fed forward, N·m (0: none).
    pub coulomb_friction: f64,
    /// Joint speed `v_s` at which the friction feed-forward saturates, rad/s (> 0).
    pub friction_velocity: f64,
    /// The command delay `d` the TSID's input state is predicted across, s (0: none).
    pub command_delay: f64,
}

impl Default for ActuatorConfig {
    fn default() -> Self {
        ActuatorConfig {
            torque_bandwidth: 0.0,
            max_lead: 1.0,
            coulomb_friction: 0.0,
            friction_velocity: 0.05,
            command_delay: 0.0,
        }
    }
}

impl ActuatorConfig {
    /// Whether the command differs from `τ*` (a lag or a friction to compensate).
    pub fn is_active(&self) -> bool {
        self.torque_bandwidth > 0.0 || self.coulomb_friction > 0.0 || self.command_delay > 0.0
    }

    /// Errors: a negative or non-finite bandwidth or friction, a non-positive bound or friction velocity.
    pub fn validate(&self) -> Result<(), WbcError> {
        let finite_at_least = |key: &'static str, value: f64, strict: bool| {
            let ok = value.is_finite() && if strict { value > 0.0 } else { value >= 0.0 };
            if ok {
                Ok(())
            } else {
                Err(WbcError::InvalidConfig {
                    task: "<actuators>".to_owned(),
                    key,
                    reason: format!(
                        "{value} must be finite and {}",
                        if strict { "> 0" } else { "≥ 0" }
                    ),
                })
            }
        };
        finite_at_least("torque_bandwidth", self.torque_bandwidth, false)?;
        // the bound may be infinite (no bound)
        let bound = if self.max_lead == f64::INFINITY {
            f64::MAX
        } else {
            self.max_lead
        };
        finite_at_least("max_lead", bound, true)?;
        finite_at_least("coulomb_friction", self.coulomb_friction, false)?;
        finite_at_least("friction_velocity", self.friction_velocity, true)?;
        finite_at_least("command_delay", self.command_delay, false)?;
        Ok(())
    }
}

/// `β = 1 − e^{−2π f T}`: the fraction of a held command's step a first-order lag of bandwidth `f` (Hz)
/// covers in `period` (s); 1 for `f = 0` (no lag).
pub fn lag_gain(bandwidth: f64, period: f64) -> f64 {
    if bandwidth > 0.0 {
        1.0 - (-std::f64::consts::TAU * bandwidth * period).exp()
    } else {
        1.0
    }
}

/// One joint's lead: the command `u` that brings a first-order lag at `modelled` (the motor torque `τ̂`)
/// to `desired` (`τ*`) in one period of gain `beta`, bounded to `|u − τ*| ≤ max_lead`.
pub fn torque_lead(desired: f64, modelled: f64, beta: f64, max_lead: f64) -> f64 {
    let lead = (desired - modelled) * (1.0 / beta - 1.0);
    desired + lead.clamp(-max_lead, max_lead)
}

/// The Coulomb friction feed-forward `τ_c sat(q̇ / v_s)` of a joint moving at `velocity`.
pub fn friction_feed_forward(velocity: f64, coulomb: f64, friction_velocity: f64) -> f64 {
    coulomb * (velocity / friction_velocity).clamp(-1.0, 1.0)
}

/// The actuator compensation of one controller: [`ActuatorConfig`] and the modelled motor torques `τ̂`.
/// Allocation-free after [`ActuatorCompensation::new`].
#[derive(Debug, Clone)]
pub struct ActuatorCompensation {
    config: ActuatorConfig,
    beta: f64,
    period: f64,
    modelled: DVector<f64>,
    /// The last tick's generalized acceleration (for the delay's prediction), `nv`.
    accelerations: DVector<f64>,
    started: bool,
}

impl ActuatorCompensation {
    /// The compensation of `joints` motors of a floating-base robot (`joints + 6` velocities) commanded
    /// every `period` (s). Errors: an invalid config or period.
    pub fn new(config: ActuatorConfig, joints: usize, period: f64) -> Result<Self, WbcError> {
        config.validate()?;
        if !(period > 0.0 && period.is_finite()) {
            return Err(WbcError::InvalidConfig {
                task: "<actuators>".to_owned(),
                key: "period",
                reason: format!("{period} s must be > 0"),
            });
        }
        Ok(ActuatorCompensation {
            config,
            beta: lag_gain(config.torque_bandwidth, period),
            period,
            modelled: DVector::zeros(joints),
            accelerations: DVector::zeros(joints + 6),
            started: false,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &ActuatorConfig {
        &self.config
    }

    /// Turns the TSID's torques `torques` (`τ*`, in place) into the motor command. The friction feed-forward
    /// reads the joint velocity the TSID asks at the end of this period, `q̇ + T q̈*` (`velocities` the
    /// measured `q̇`, `accelerations` the TSID's generalized acceleration `ν̇`, base first): a joint at rest
    /// sticks until its torque exceeds `τ_c`, so the feed-forward must lead the motion the controller asks,
    /// not follow the one it measures. `accelerations` are kept for [`ActuatorCompensation::predict`]. The
    /// first tick after construction or [`ActuatorCompensation::reset`] takes the motors at `τ*` (no lead:
    /// the lag's start is unknown). Errors: lengths that differ from the joint count.
    pub fn apply(
        &mut self,
        torques: &mut DVector<f64>,
        velocities: &DVector<f64>,
        accelerations: &DVector<f64>,
    ) -> Result<(), WbcError> {
        let n = self.modelled.len();
        if torques.len() != n || velocities.len() != n || accelerations.len() != n + 6 {
            return Err(WbcError::InvalidInput(format!(
                "actuator compensation: {} torques, {} velocities and {} accelerations for {n} joints",
                torques.len(),
                velocities.len(),
                accelerations.len()
            )));
        }
        self.accelerations.copy_from(accelerations);
        let c = &self.config;
        let joints = torques
            .iter_mut()
            .zip(velocities)
            .zip(accelerations.iter().skip(6));
        for (((tau, v), a), modelled) in joints.zip(&mut self.modelled) {
            let intended = v + a * self.period;
            let friction = friction_feed_forward(intended, c.coulomb_friction, c.friction_velocity);
            let desired = *tau + friction;
            let command = if self.started {
                torque_lead(desired, *modelled, self.beta, c.max_lead)
            } else {
                desired
            };
            *modelled = if self.started {
                *modelled + self.beta * (command - *modelled)
            } else {
                desired
            };
            *tau = command;
        }
        self.started = true;
        Ok(())
    }

    /// The state the command will meet (`command_delay` > 0, after a first [`ActuatorCompensation::apply`]):
    /// `state` advanced in place by `d` with the last tick's accelerations, `ν ← ν + d ν̇`, joint positions
    /// and the base position `+ d ν + d²/2 ν̇` (the base orientation, `d ω` of a millisecond, is kept).
    /// Errors: a state of another joint count.
    pub fn predict(&self, state: &mut RobotState) -> Result<(), WbcError> {
        let d = self.config.command_delay;
        if d <= 0.0 || !self.started {
            return Ok(());
        }
        let n = self.modelled.len();
        if state.joint_positions.len() != n || state.joint_velocities.len() != n {
            return Err(WbcError::InvalidInput(format!(
                "actuator compensation: a state of {} joints for {n}",
                state.joint_positions.len()
            )));
        }
        let a = &self.accelerations;
        let base = a.fixed_rows::<6>(0);
        let linear =
            state.base_velocity.fixed_rows::<3>(0) * d + base.fixed_rows::<3>(0) * (0.5 * d * d);
        state.base_pose.translation.vector += linear;
        state.base_velocity += base * d;
        let joints = a.rows(6, n);
        for k in 0..n {
            state.joint_positions[k] += state.joint_velocities[k] * d + joints[k] * (0.5 * d * d);
            state.joint_velocities[k] += joints[k] * d;
        }
        Ok(())
    }

    /// Forgets the modelled motor torques (the next tick starts without a lead).
    pub fn reset(&mut self) {
        self.modelled.fill(0.0);
        self.started = false;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A first-order lag plant stepped `substeps` times per control period of `period` s with the
    /// command held: the torque after one period.
    fn lag(tau: f64, command: f64, bandwidth: f64, period: f64, substeps: usize) -> f64 {
        let b = lag_gain(bandwidth, period / substeps as f64);
        (0..substeps).fold(tau, |t, _| t + b * (command - t))
    }

    #[test]
    fn the_lead_brings_a_lag_to_a_step_in_one_period() {
        let period = 1e-3;
        let config = ActuatorConfig {
            torque_bandwidth: 30.0,
            max_lead: f64::INFINITY,
            ..ActuatorConfig::default()
        };
        let mut comp = ActuatorCompensation::new(config, 1, period).unwrap();
        let zero = DVector::zeros(1);
        let (mut plain, mut led) = (0.0, 0.0);
        for k in 0..20 {
            let desired = if k < 2 { 0.0 } else { 10.0 };
            let mut u = DVector::from_element(1, desired);
            comp.apply(&mut u, &zero, &DVector::zeros(7)).unwrap();
            // the plant at 2 kHz with the 1 kHz command held
            led = lag(led, u[0], 30.0, period, 2);
            plain = lag(plain, desired, 30.0, period, 2);
            if k >= 2 {
                assert!((led - 10.0).abs() < 1e-9, "tick {k}: {led}");
            }
            if k == 2 {
                // without the lead the lag covers 1 − e^{−2π·30·0.001} = 17 % of the step in that period
                assert!((plain - 1.72).abs() < 0.01, "{plain}");
            }
        }
        // and is still 3.4 % short 18 ms after the step
        assert!(plain < 9.7, "{plain}");
    }

    #[test]
    fn a_bounded_lead_reaches_the_step_within_a_few_periods() {
        let period = 1e-3;
        let config = ActuatorConfig {
            torque_bandwidth: 30.0,
            max_lead: 20.0,
            ..ActuatorConfig::default()
        };
        let mut comp = ActuatorCompensation::new(config, 1, period).unwrap();
        let zero = DVector::zeros(1);
        let mut led = 0.0;
        let mut reached = None;
        for k in 0..10 {
            let mut u = DVector::from_element(1, if k == 0 { 0.0 } else { 10.0 });
            comp.apply(&mut u, &zero, &DVector::zeros(7)).unwrap();
            assert!((u[0] - 10.0 * f64::from(k > 0)).abs() <= 20.0 + 1e-12);
            led = lag(led, u[0], 30.0, period, 2);
            if reached.is_none() && (led - 10.0).abs() < 0.1 {
                reached = Some(k);
            }
        }
        // the 48 N·m lead a 10 N·m step asks is cut to 20: the lag reaches the step two periods after
        // it (at the end of the third), then exactly
        assert_eq!(reached, Some(3));
        assert!((led - 10.0).abs() < 1e-9);
    }

    #[test]
    fn friction_is_fed_forward_with_the_intended_velocity() {
        let config = ActuatorConfig {
            coulomb_friction: 0.1,
            ..ActuatorConfig::default()
        };
        let mut comp = ActuatorCompensation::new(config, 4, 1e-3).unwrap();
        let mut tau = DVector::from_vec(vec![1.0, 1.0, 1.0, 1.0]);
        let velocities = DVector::from_vec(vec![1.0, -0.025, 0.0, 0.0]);
        // the fourth joint is at rest and asked to accelerate at 50 rad/s²: 0.05 rad/s after one period
        let mut accelerations = DVector::zeros(10);
        accelerations[9] = 50.0;
        comp.apply(&mut tau, &velocities, &accelerations).unwrap();
        assert_eq!(tau.as_slice(), &[1.1, 0.95, 1.0, 1.1]);
        let mut short = DVector::zeros(3);
        assert!(comp.apply(&mut short, &velocities, &accelerations).is_err());
    }

    #[test]
    fn the_delay_prediction_advances_the_state_with_the_last_accelerations() {
        let config = ActuatorConfig {
            command_delay: 1e-3,
            ..ActuatorConfig::default()
        };
        let mut comp = ActuatorCompensation::new(config, 2, 1e-3).unwrap();
        let mut state = RobotState {
            base_pose: nalgebra::Isometry3::identity(),
            joint_positions: DVector::zeros(2),
            base_velocity: nalgebra::Vector6::zeros(),
            joint_velocities: DVector::zeros(2),
        };
        state.joint_velocities[0] = 1.0;
        state.base_velocity[0] = 0.5;
        let before = state.clone();
        // before a first tick nothing is known of the accelerations: unchanged
        comp.predict(&mut state).unwrap();
        assert_eq!(state, before);
        let accelerations = DVector::from_vec(vec![2.0, 0.0, 0.0, 0.0, 0.0, 4.0, 10.0, -20.0]);
        let mut tau = DVector::zeros(2);
        comp.apply(&mut tau, &DVector::zeros(2), &accelerations)
            .unwrap();
        comp.predict(&mut state).unwrap();
        assert!((state.joint_velocities[0] - 1.01).abs() < 1e-12);
        assert!((state.joint_velocities[1] + 0.02).abs() < 1e-12);
        assert!((state.joint_positions[0] - (1e-3 + 5e-6)).abs() < 1e-12);
        assert!((state.base_velocity[0] - 0.502).abs() < 1e-12);
        assert!((state.base_velocity[5] - 0.004).abs() < 1e-12);
        assert!((state.base_pose.translation.vector.x - (5e-4 + 1e-6)).abs() < 1e-12);
    }

    #[test]
    fn invalid_settings_are_refused_by_key() {
        for (config, key) in [
            (
                ActuatorConfig {
                    torque_bandwidth: -1.0,
                    ..Default::default()
                },
                "torque_bandwidth",
            ),
            (
                ActuatorConfig {
                    max_lead: 0.0,
                    ..Default::default()
                },
                "max_lead",
            ),
            (
                ActuatorConfig {
                    coulomb_friction: f64::NAN,
                    ..Default::default()
                },
                "coulomb_friction",
            ),
            (
                ActuatorConfig {
                    friction_velocity: 0.0,
                    ..Default::default()
                },
                "friction_velocity",
            ),
            (
                ActuatorConfig {
                    command_delay: -1e-3,
                    ..Default::default()
                },
                "command_delay",
            ),
        ] {
            match ActuatorCompensation::new(config, 1, 1e-3) {
                Err(WbcError::InvalidConfig { key: k, .. }) => assert_eq!(k, key),
                other => panic!("{key}: {other:?}"),
            }
        }
        assert!(ActuatorConfig::default().validate().is_ok());
        assert!(!ActuatorConfig::default().is_active());
    }
}
