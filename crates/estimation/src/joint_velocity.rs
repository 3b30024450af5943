//! Joint velocities from the encoder positions: one critically damped α–β tracking filter per joint.
//!
//! Why: a robot that differentiates its encoder positions through a first-order low-pass (the default
//! encoder model: 10 Hz, the iCub walking controller's `joint_velocity_cut_frequency`) delays the joint
//! velocities by `1/(2π f_c)` ≈ 16 ms. The TSID's damping terms act on them; at the feet's K_d 40 s⁻¹
//! that delay, with the actuators' torque lag, leaves the swing foot's loop with a damping ratio of
//! 0.31 instead of 1 (docs/wbc.md, "Joint velocities"), and on a hard floor the swing feet strike the
//! ground before their touch-down. The filter here reads the positions instead: its velocity is a
//! second-order low-pass of the true velocity with group delay `2/ω` (4 ms at 80 Hz) and a velocity noise
//! that falls with frequency, where the low-passed difference's stays flat.

use nalgebra::DVector;

use crate::error::{check_positive, Result};

/// A critically damped α–β filter per joint [Kalata 1984]: with `p = exp(−ω T)` (`ω = 2π f` the
/// bandwidth, `T` the sample period) the gains `α = 1 − p²`, `β = (1 − p)²` put both poles of the
/// discrete error dynamics `z² − (2 − α − β) z + (1 − α)` at `p`. Per sample:
///
/// ```text
/// q⁻ = q̂ + T v̂,   e = q_meas − q⁻,   q̂ = q⁻ + α e,   v̂ = v̂ + (β / T) e
/// ```
///
/// Closed forms (tested): a constant velocity is tracked without error; a constant acceleration `a`
/// leaves the velocity behind by `a T (α/β − ½)` (→ `2a/ω` as `T → 0`); white position noise of
/// standard deviation `σ` gives the velocity variance `σ² 2β² / (T² α (4 − 2α − β))` [Kalata 1984].
#[derive(Debug, Clone)]
pub struct JointVelocityFilter {
    omega: f64,
    positions: DVector<f64>,
    velocities: DVector<f64>,
    /// The joint accelerations the prediction holds over a sample (zero unless set).
    accelerations: DVector<f64>,
    started: bool,
}

impl JointVelocityFilter {
    /// A filter for `dof` joints at `bandwidth` \[Hz\] (> 0; allocates here only).
    ///
    /// # Errors
    /// `InvalidParameter` when the bandwidth is not finite or not > 0.
    pub fn new(dof: usize, bandwidth: f64) -> Result<Self> {
        check_positive("joint_velocity_bandwidth", bandwidth)?;
        Ok(Self {
            omega: 2.0 * std::f64::consts::PI * bandwidth,
            positions: DVector::zeros(dof),
            velocities: DVector::zeros(dof),
            accelerations: DVector::zeros(dof),
            started: false,
        })
    }

    /// The gains `(α, β)` at sample period `dt` \[s\].
    pub fn gains(&self, dt: f64) -> (f64, f64) {
        let p = (-self.omega * dt).exp();
        (1.0 - p * p, (1.0 - p) * (1.0 - p))
    }

    /// One sample: the measured `positions` \[rad\] taken `dt` \[s\] after the previous one. The first
    /// sample after construction or [`Self::reset`] starts the filter at `positions` and `velocities`
    /// (the encoders' own, the best guess there is). Sizes are the caller's (the estimator checks them).
    pub fn step(&mut self, positions: &DVector<f64>, velocities: &DVector<f64>, dt: f64) {
        if !self.started {
            self.positions.copy_from(positions);
            self.velocities.copy_from(velocities);
            self.started = true;
            return;
        }
        let (alpha, beta) = self.gains(dt);
        let gain_v = beta / dt;
        for (((q, v), &measured), &a) in self
            .positions
            .iter_mut()
            .zip(self.velocities.iter_mut())
            .zip(positions.iter())
            .zip(self.accelerations.iter())
        {
            let predicted = *q + dt * *v + 0.5 * dt * dt * a;
            let innovation = measured - predicted;
            *q = predicted + alpha * innovation;
            *v += dt * a + gain_v * innovation;
        }
    }

    /// The joint accelerations \[rad/s²\] (model order) the next samples' prediction holds,
    /// `q⁻ = q̂ + T v̂ + T² a / 2`, `v⁻ = v̂ + T a` (a known input of the α–β filter, e.g. the accelerations
    /// a controller commanded): an acceleration that is right is then tracked without the lag `2a/ω`, so a
    /// lower bandwidth, with less noise, does not delay the velocity. Zero (the default, and after
    /// [`Self::reset`]): the plain filter. Sizes are the caller's.
    pub fn set_accelerations(&mut self, accelerations: &[f64]) {
        self.accelerations
            .as_mut_slice()
            .copy_from_slice(accelerations);
    }

    /// The filtered velocities \[rad/s\] (model order).
    pub fn velocities(&self) -> &DVector<f64> {
        &self.velocities
    }

    /// Restart at the next sample.
    pub fn reset(&mut self) {
        self.started = false;
        self.accelerations.fill(0.0);
    }
}
