//! External-force (push) estimate from a linear-momentum observer, and the push's place in the LIPM.
//!
//! The robot's linear momentum obeys `ṗ = Σ f_feet + m g + F_ext` (Newton's law for the whole body,
//! [Romualdi 2022, eq. 11.2.1] with the push as the unknown force). A difference quotient of the measured
//! momentum amplifies the CoM velocity's noise; the momentum observer [De Luca 2006], restricted to the
//! linear momentum, integrates instead:
//!
//! ```text
//! r(t) = K ( p(t) − p(0) − ∫₀ᵗ (Σ f_feet + m g + r) ds )      ⇒      ṙ = K (F_ext − r)
//! ```
//!
//! so the residual `r` is the push seen through a first-order low-pass of bandwidth `K` \[s⁻¹\]: for a
//! constant force switched on at `t = 0`, `r(t) = F (1 − e^{−K t})`. Discretised with the integral
//! updated by the previous residual (`I_{k+1} = I_k + dt (Σf + m g + r_k)`), the error obeys
//! `F − r_{k+1} = (1 − K dt)(F − r_k)`: stable for `K dt < 2`, monotone for `K dt < 1`.
//!
//! In the LIPM a horizontal force `F` acts as a ZMP offset: `ẍ = ω² (x − p) + F/m = ω² (x − p_eff)`
//! with `p_eff = p − F/(m ω²)` ([`push_zmp_offset`]).

use nalgebra::{Vector2, Vector3};
use serde::{Deserialize, Serialize};

use crate::error::{check_finite, check_non_negative, check_positive, Result, SimplifiedError};

/// Parameters of the push estimate and of the stack's response to it (section `[simplified.push]`).
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `enabled` | – | `false` | whether the runner estimates the push and responds to it |
/// | `observer_gain` | s⁻¹ | 10 | bandwidth `K` of the momentum observer (time constant `1/K`); `K dt` must stay below 1 at the simplified rate |
/// | `threshold` | N | 6 | dead zone: the estimate's horizontal norm is reduced by this (smaller estimates are zero); above the observer's noise on an unpushed walk |
/// | `hold_double_support` | – | `true` | hold the double support (the plan's clock slows to a stop) while the estimate exceeds `hold_force` |
/// | `hold_force` | N | 8 | horizontal push (after the dead zone) above which the double support is held |
/// | `hold_delay` | s | 0.1 | the estimate must stay above `hold_force` this long before a hold starts (with `hold_at_once`, only when it rose within `impact_window` of a planned touch-down): a touch-down's impact shows in the observer as a ±20 N pulse of under 0.1 s on the fast walks (the CoM velocity estimate and the contact forces disagree for a few milliseconds) |
/// | `hold_at_once` | – | `false` | a rise of the estimate farther than `impact_window` from a planned touch-down, outside the walk's start-up and stopping double supports (before the first lift-off, after the last touch-down), holds the double support at once (without it every rise waits `hold_delay`) |
/// | `impact_window` | s | 0.2 | with `hold_at_once`: time on either side of a planned touch-down (the start of a double support) within which a rise of the estimate is treated as a possible impact pulse and waits `hold_delay` |
/// | `max_hold` | s | 2 | longest hold of one double support (an estimate that never decays cannot stop the walk) |
/// | `hold_ramp` | s | 0.1 | time for the plan's clock rate to go from 1 to 0 and back (linear ramp) |
/// | `step_adjustment` | – | `true` | the step-adjustment QP predicts the DCM with the push: its stance CoP is moved by `−F̂/(m ω²)` |
/// | `step_adjustment_delay` | s | 0 (off) | with `step_adjustment`: the QP predicts with the estimate only once it has stayed above `hold_force` this long (0: at once; never while it is not above `hold_force`, since 2026-12-07). On the iCub the estimated CoM velocity jumps for 20–30 ms about 0.2 s into each single support (the base rolls), a 40–115 N pulse of the observer (at most 56 ms) that moves the QP's CoP by 7–19 cm and shortens the steps |
/// | `lean` | – | 0 | fraction in \[0, 1\] of the push's LIPM offset by which the planned CoM and DCM the simplified layer tracks move against the push, `−lean F̂/(m ω²)`: with 1 the pushed LIPM's ZMP stays on the plan's |
/// | `step_offset` | – | 0 | fraction in \[0, 1\] of the push's LIPM offset by which the step-adjustment QP's nominal DCM offset at touch-down moves against the push, `b_n − step_offset F̂/(m ω²)`: the push is taken to last past the touch-down, so the foot lands that much further along it (under the CoP the pushed LIPM needs) |
/// | `replan_from_dcm` | – | `false` | once the estimate has stayed above `hold_force` for `hold_delay`, a step adjustment the planner refuses from the plan's own DCM is replanned from the measured DCM moved by `replan_push_offset F̂/(m ω²)` (the plan's DCM jumps to it; `stride_planner::Planner::adjust_step_from`): the touch-down state and the steps after it are planned from where the pushed robot is (replanning every adjustment of a push from it loses cells: docs/push-recovery.md) |
/// | `replan_push_offset` | – | 1 | with `replan_from_dcm`: fraction in \[0, 1\] of the push's LIPM offset added to the measured DCM (with 1 the pushed LIPM's capture point `ξ + F̂/(m ω²)`, where the DCM goes if the push lasts) |
/// | `wbc_force` | N | 20 | push (after the dead zone) above which the TSID's weights switch to `wbc_com_weight` / `wbc_upright_weight` (back below it); above the touch-down pulses of the unpushed torque walks |
/// | `wbc_com_weight` | – | 0 (off) | weight of the TSID's `com` task while the push exceeds `wbc_force` (the task must be soft; its configured weight otherwise): the CoM gives way to the push instead of the torso |
/// | `wbc_nominal_in_hold` | – | `false` | the TSID's configured weights while the push response holds a double support (the push weights only outside the hold) |
/// | `wbc_upright_weight` | – | 0 (off) | weight of the TSID's `torso` and `pelvis` orientation tasks while the push exceeds `wbc_force` (soft tasks; their configured weight otherwise) |
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PushConfig {
    /// Whether the runner estimates the push and responds to it.
    pub enabled: bool,
    /// Bandwidth of the momentum observer \[s⁻¹\].
    pub observer_gain: f64,
    /// Dead zone on the estimate's horizontal norm \[N\].
    pub threshold: f64,
    /// Whether the double support is held while the push exceeds `hold_force`.
    pub hold_double_support: bool,
    /// Push (after the dead zone) above which the double support is held \[N\].
    pub hold_force: f64,
    /// Time the estimate must stay above `hold_force` before a hold starts \[s\].
    pub hold_delay: f64,
    /// Whether a rise away from the touch-downs (farther than `impact_window`) and from the walk's
    /// start-up and stopping double supports holds at once.
    pub hold_at_once: bool,
    /// Time on either side of a planned touch-down within which a rise of the estimate waits `hold_delay` \[s\].
    pub impact_window: f64,
    /// Longest hold of one double support \[s\].
    pub max_hold: f64,
    /// Ramp time of the plan's clock rate between 1 and 0 \[s\].
    pub hold_ramp: f64,
    /// Whether the step-adjustment QP predicts the DCM with the estimated push.
    pub step_adjustment: bool,
    /// Time the estimate must stay above `hold_force` before the step adjustment predicts with it \[s\];
    /// 0: at once.
    pub step_adjustment_delay: f64,
    /// Fraction of the push's LIPM offset the tracked CoM and DCM lean against the push, in \[0, 1\].
    pub lean: f64,
    /// Whether a hold ends early (the plan's clock runs on into the next single support, whose step the
    /// step adjustment moves) once the DCM with the push, `ξ + F̂/(m ω²)`, is more than
    /// `step_out_margin` outside the measured support polygon: no CoP of the held double support can
    /// capture it any more.
    pub step_out: bool,
    /// Distance outside the support polygon of `ξ + F̂/(m ω²)` at which `step_out` ends a hold \[m\].
    pub step_out_margin: f64,
    /// Fraction of the push's LIPM offset by which the step QP's nominal touch-down DCM offset moves, in \[0, 1\].
    pub step_offset: f64,
    /// Whether a step adjustment refused during a push is replanned from the measured DCM (with the
    /// push's offset).
    pub replan_from_dcm: bool,
    /// Fraction of the push's LIPM offset added to the measured DCM of `replan_from_dcm`, in \[0, 1\].
    pub replan_push_offset: f64,
    /// Push above which the TSID's weights switch \[N\].
    pub wbc_force: f64,
    /// Weight of the TSID's `com` task during a push; 0: unchanged.
    pub wbc_com_weight: f64,
    /// Weight of the TSID's `torso` and `pelvis` tasks during a push; 0: unchanged.
    pub wbc_upright_weight: f64,
    /// Whether the TSID keeps its configured weights while a double support is held.
    pub wbc_nominal_in_hold: bool,
}

impl Default for PushConfig {
    fn default() -> Self {
        Self {
            enabled: false,
            observer_gain: 10.0,
            threshold: 6.0,
            hold_double_support: true,
            hold_force: 8.0,
            hold_delay: 0.1,
            hold_at_once: false,
            impact_window: 0.2,
            max_hold: 2.0,
            hold_ramp: 0.1,
            step_adjustment: true,
            step_adjustment_delay: 0.0,
            lean: 0.0,
            step_out: false,
            step_out_margin: 0.0,
            step_offset: 0.0,
            replan_from_dcm: false,
            replan_push_offset: 1.0,
            wbc_force: 20.0,
            wbc_com_weight: 0.0,
            wbc_upright_weight: 0.0,
            wbc_nominal_in_hold: false,
        }
    }
}

impl PushConfig {
    /// Checks the ranges documented on the struct.
    pub fn validate(&self) -> Result<()> {
        check_positive("push.observer_gain", self.observer_gain)?;
        check_non_negative("push.threshold", self.threshold)?;
        check_non_negative("push.hold_force", self.hold_force)?;
        check_non_negative("push.hold_delay", self.hold_delay)?;
        check_non_negative("push.impact_window", self.impact_window)?;
        check_non_negative("push.max_hold", self.max_hold)?;
        check_non_negative("push.step_adjustment_delay", self.step_adjustment_delay)?;
        check_positive("push.hold_ramp", self.hold_ramp)?;
        check_non_negative("push.step_out_margin", self.step_out_margin)?;
        check_non_negative("push.wbc_force", self.wbc_force)?;
        check_non_negative("push.wbc_com_weight", self.wbc_com_weight)?;
        check_non_negative("push.wbc_upright_weight", self.wbc_upright_weight)?;
        for (name, value) in [
            ("push.lean", self.lean),
            ("push.step_offset", self.step_offset),
            ("push.replan_push_offset", self.replan_push_offset),
        ] {
            if !(0.0..=1.0).contains(&value) {
                return Err(SimplifiedError::InvalidParameter {
                    name,
                    value,
                    reason: "must be in [0, 1]",
                });
            }
        }
        Ok(())
    }
}

/// The horizontal ZMP offset `F/(m ω²)` \[m\] of a horizontal force `F` \[N\] on a LIPM of mass `m` \[kg\]
/// and natural frequency `ω` \[s⁻¹\]: the effective ZMP of the pushed LIPM is `p − F/(m ω²)`.
pub fn push_zmp_offset(force: &Vector2<f64>, mass: f64, omega: f64) -> Vector2<f64> {
    force / (mass * omega * omega)
}

/// The linear-momentum observer (see the module documentation); no allocation.
#[derive(Debug, Clone, PartialEq)]
pub struct PushObserver {
    gain: f64,
    threshold: f64,
    mass: f64,
    /// Gravity vector \[m/s²\].
    gravity: Vector3<f64>,
    /// `p(0) + ∫ (Σf + m g + r) ds` \[N s\]; `None` before the first update.
    predicted: Option<Vector3<f64>>,
    /// Residual `r` \[N\].
    residual: Vector3<f64>,
}

impl PushObserver {
    /// The observer of `config` for a robot of `mass` \[kg\] under `gravity` \[m/s², e.g. (0, 0, −9.81)\].
    pub fn new(config: &PushConfig, mass: f64, gravity: Vector3<f64>) -> Result<Self> {
        config.validate()?;
        check_positive("mass", mass)?;
        if !gravity.iter().all(|g| g.is_finite()) {
            return Err(SimplifiedError::NonFiniteInput { name: "gravity" });
        }
        Ok(Self {
            gain: config.observer_gain,
            threshold: config.threshold,
            mass,
            gravity,
            predicted: None,
            residual: Vector3::zeros(),
        })
    }

    /// One observer step of `dt` \[s\] with the measured CoM velocity \[m/s\] and the sum of the contact
    /// forces on the robot \[N\] (world frame) over the step; returns the horizontal push estimate after
    /// the dead zone ([`PushObserver::horizontal`]). The first call only records the momentum.
    ///
    /// Errors: non-finite input, `dt` not > 0.
    pub fn update(
        &mut self,
        dt: f64,
        com_velocity: &Vector3<f64>,
        contact_force: &Vector3<f64>,
    ) -> Result<Vector2<f64>> {
        check_positive("dt", dt)?;
        for (name, v) in [
            ("com_velocity", com_velocity),
            ("contact_force", contact_force),
        ] {
            if !v.iter().all(|x| x.is_finite()) {
                return Err(SimplifiedError::NonFiniteInput { name });
            }
        }
        check_finite("dt", dt)?;
        let momentum = com_velocity * self.mass;
        match self.predicted.as_mut() {
            None => self.predicted = Some(momentum),
            Some(predicted) => {
                *predicted += (contact_force + self.gravity * self.mass + self.residual) * dt;
                self.residual = (momentum - *predicted) * self.gain;
            }
        }
        Ok(self.horizontal())
    }

    /// The raw residual `r` \[N\] (all three axes, no dead zone).
    pub fn residual(&self) -> Vector3<f64> {
        self.residual
    }

    /// The horizontal estimate \[N\] with the dead zone: `r_h (1 − threshold/‖r_h‖)` when `‖r_h‖ >
    /// threshold`, else zero (continuous in `r`).
    pub fn horizontal(&self) -> Vector2<f64> {
        let r = self.residual.xy();
        let n = r.norm();
        if n <= self.threshold {
            Vector2::zeros()
        } else {
            r * (1.0 - self.threshold / n)
        }
    }

    /// Forgets the momentum and the estimate (the next update starts over).
    pub fn reset(&mut self) {
        self.predicted = None;
        self.residual = Vector3::zeros();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn observer(gain: f64, threshold: f64) -> PushObserver {
        let config = PushConfig {
            observer_gain: gain,
            threshold,
            ..PushConfig::default()
        };
        PushObserver::new(&config, 30.0, Vector3::new(0.0, 0.0, -9.81)).unwrap()
    }

    /// A point mass standing on a support that carries its weight, pushed by a constant horizontal force
    /// from t = 0: the velocity is `F t / m` exactly; the residual follows the discrete closed form
    /// `F (1 − (1 − K dt)^k)` and, for a small `dt`, the continuous `F (1 − e^{−K t})`.
    #[test]
    fn a_constant_force_on_a_known_mass_is_recovered_with_the_closed_form_response() {
        let (m, g, k, dt) = (30.0, 9.81, 10.0, 0.001);
        let force = Vector3::new(20.0, -12.0, 0.0);
        let mut o = observer(k, 0.0);
        let support = Vector3::new(0.0, 0.0, m * g);
        o.update(dt, &Vector3::zeros(), &support).unwrap();
        for step in 1..=500 {
            let t = step as f64 * dt;
            let v = force * (t / m);
            o.update(dt, &v, &support).unwrap();
            let discrete = force * (1.0 - (1.0 - k * dt).powi(step));
            assert!((o.residual() - discrete).norm() < 1e-9, "step {step}");
            let continuous = force * (1.0 - (-k * t).exp());
            assert!((o.residual() - continuous).norm() < 0.01 * force.norm());
        }
        // 5 time constants: within 1 % of the force
        assert!((o.horizontal() - force.xy()).norm() < 0.01 * force.norm());
    }

    /// An independent plant: a mass on a stiff damped spring (the "foot") integrated with semi-implicit
    /// Euler at a finer step; the observer sees only the spring force and the velocity.
    #[test]
    fn the_push_on_a_mass_held_by_a_spring_is_the_force_the_spring_does_not_explain() {
        let (m, k_spring, b) = (30.0, 5e4, 500.0);
        let force = 15.0;
        let mut o = observer(10.0, 0.0);
        let (mut x, mut v) = (0.0f64, 0.0f64);
        let (sub, dt) = (10, 0.01);
        let h = dt / sub as f64;
        o.update(dt, &Vector3::zeros(), &Vector3::new(0.0, 0.0, m * 9.81))
            .unwrap();
        for _ in 0..100 {
            let mut mean_spring = 0.0;
            for _ in 0..sub {
                let spring = -k_spring * x - b * v;
                v += h * (spring + force) / m;
                x += h * v;
                mean_spring += spring / sub as f64;
            }
            let contact = Vector3::new(mean_spring, 0.0, m * 9.81);
            o.update(dt, &Vector3::new(v, 0.0, 0.0), &contact).unwrap();
        }
        // the spring settles at F/k; the residual converges to F
        assert!(
            (o.horizontal().x - force).abs() < 0.05,
            "{}",
            o.horizontal()
        );
        assert!(o.horizontal().y.abs() < 1e-12);
    }

    #[test]
    fn the_dead_zone_is_continuous_and_removes_small_estimates() {
        let mut o = observer(10.0, 6.0);
        o.residual = Vector3::new(3.0, 4.0, 50.0);
        assert_eq!(o.horizontal(), Vector2::zeros());
        o.residual = Vector3::new(6.0, 8.0, 0.0);
        assert!((o.horizontal() - Vector2::new(2.4, 3.2)).norm() < 1e-12);
        o.residual = Vector3::new(6.0 + 1e-9, 0.0, 0.0);
        assert!(o.horizontal().norm() < 1e-8);
    }

    #[test]
    fn the_push_is_a_zmp_offset_of_f_over_m_omega_squared() {
        // 20 N on 32.8 kg with a 0.54 m LIPM: 0.54 · 20 / (32.8 · 9.81) = 33.6 mm
        let omega = (9.81f64 / 0.54).sqrt();
        let d = push_zmp_offset(&Vector2::new(0.0, 20.0), 32.8, omega);
        assert!((d.y - 0.54 * 20.0 / (32.8 * 9.81)).abs() < 1e-12);
    }

    #[test]
    fn bad_input_is_an_error_and_changes_nothing() {
        let mut o = observer(10.0, 0.0);
        o.update(0.01, &Vector3::zeros(), &Vector3::zeros())
            .unwrap();
        let before = o.clone();
        assert!(o
            .update(0.01, &Vector3::new(f64::NAN, 0.0, 0.0), &Vector3::zeros())
            .is_err());
        assert!(o.update(0.0, &Vector3::zeros(), &Vector3::zeros()).is_err());
        assert_eq!(o, before);
        let bad = PushConfig {
            observer_gain: 0.0,
            ..PushConfig::default()
        };
        assert!(PushObserver::new(&bad, 30.0, Vector3::zeros()).is_err());
    }
}
