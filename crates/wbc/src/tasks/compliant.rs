//! TSID-Compliant [Romualdi 2022, §8.2]: the TSID on visco-elastic ground, whose decision vector is
//! `x = [ν̇; ḟ_c for every loaded contact c]` (wrench **rates**, N/s and N·m/s) and whose wrenches are the
//! measured ones `f_c` (`ContactInput::measured_wrench`).
//!
//! The rigid TSID's wrench rows become rate rows by one substitution: a row `A_ν ν̇ + Σ_c A_c w_c ⋚ r`
//! over the wrenches `w_c` is asked of the wrench `w_c = f_c + T ḟ_c` a time `T` ahead, i.e.
//! `A_ν ν̇ + Σ_c T A_c ḟ_c ⋚ r − Σ_c A_c f_c` ([`to_rate_rows`]). With
//! * `T = 0`: the base dynamics and the eliminated torques with the measured wrenches
//!   [Romualdi 2022, eq. 8.2.13, 8.2.1];
//! * `T` = `feasibility_horizon`: the one-step-ahead wrench feasibility [Romualdi 2022, eq. 8.2.12] (and the
//!   ZMP of the predicted wrenches);
//! * `T = 1/k_h`: the CoM (linear momentum) task `Σ ḟ = k_h (ḣ* − ḣ)` with `ḣ = Σ f + m g` measured: the
//!   momentum second-derivative task [Romualdi 2022, eq. 8.2.2] with the PID-like reference of eq. 8.2.4,
//!   `ḧ* = k_h (ḣ^ref − ḣ) + k_h K_d (h^ref − h) + k_h K_p ∫(h^ref − h) dt` (h = m ẋ: the CoM task's
//!   `K_p`, `K_d`), exponentially stable iff `k_h K_d > K_p` [Romualdi 2022, below eq. 8.2.4]; the angular
//!   rows add the `Σ (ṗ_c − ẋ) × f_c` term of eq. 8.2.2 ([`add_angular_momentum_drift`]);
//! * `T = 1/k_f`: the wrench regularization `ḟ = k_f (f* − f)` [Romualdi 2022, eq. 8.2.9].
//!
//! The contact task of a loaded contact becomes its contact dynamics, the time derivative of Lemma 1,
//! `ḟ_c − g_c J_c ν̇ = h_c + g_c J̇_c ν` [Romualdi 2022, eq. 8.2.15] ([`fill_contact_dynamics`]).

use nalgebra::{DVector, Isometry3, Vector3, Vector6};
use stride_qp::TaskDataMut;

use super::compliant_ground::ContactGroundEstimates;
use super::{Contact, TsidContext};
use crate::config::{CompliantConfig, WrenchSource};
use crate::error::WbcError;
use crate::soft_contact::{GroundParameters, SoleGeometry, SoleState, WrenchRate};

/// What the compliant TSID keeps per contact and its settings.
#[derive(Debug, Clone)]
pub(crate) struct CompliantContacts {
    pub sole: SoleGeometry,
    /// The configured ground (`ground_stiffness`, `ground_damping`); with `estimate_ground` the prior of
    /// the per-contact estimates, which then set each contact's ground ([`Self::ground_of`]).
    pub ground: GroundParameters,
    /// `1/k_h`, s.
    pub momentum_horizon: f64,
    /// `1/k_f`, s.
    pub wrench_horizon: f64,
    /// `T` of the feasibility, s.
    pub feasibility_horizon: f64,
    /// Per contact: the wrench of this tick the rows read (mixed, about the contact frame origin), N, N·m:
    /// the measured one, or after the touch-downs and the ground estimate the `wrench_source`'s.
    pub measured: Vec<Vector6<f64>>,
    /// Per contact: the zero-force pose of the sole (its pose at touch-down).
    pub rest: Vec<Isometry3<f64>>,
    /// Per contact: the wrench-rate model of this tick [Romualdi 2022, eq. 8.2.14].
    pub rates: Vec<WrenchRate>,
    /// The online ground estimates, one per contact (`estimate_ground`).
    pub estimates: Option<ContactGroundEstimates>,
    /// `held_acceleration`: the period over which the rates are averaged (s); `None`: instantaneous.
    pub held_period: Option<f64>,
    /// `lift_off_force`: a contact whose load ramp ends stays loaded while its measured normal force
    /// exceeds this (N); `inf`: it leaves the QP when its ramp ends.
    pub lift_off_force: f64,
    /// `wrench_source`: which wrench `measured` holds once the tick's inputs are read
    /// (`tasks::compliant_wrench`).
    pub wrench_source: WrenchSource,
    /// `period / (wrench_filter_time + period)`: the `"filtered"` source's correction per tick.
    pub filter_gain: f64,
}

/// The load of a contact held in the QP after its ramp ended (`lift_off_force`): not zero, so that the
/// contact keeps its wrench-rate columns; its normal-force bound is then `Contact::held_upper`.
pub(crate) const HELD_LIFT_OFF_LOAD: f64 = 1e-9;

fn positive(key: &'static str, value: f64) -> Result<f64, WbcError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(WbcError::InvalidConfig {
            task: "<tsid>".into(),
            key,
            reason: format!("compliant.{key} = {value} must be finite and > 0"),
        })
    }
}

impl CompliantContacts {
    /// Checked settings for `contacts` contacts of a controller running every `period` (s). Errors: a
    /// value that is not finite and > 0.
    pub fn new(c: &CompliantConfig, contacts: usize, period: f64) -> Result<Self, WbcError> {
        let estimates = match c.estimate_ground {
            true => Some(ContactGroundEstimates::new(c, contacts)?),
            false => None,
        };
        Ok(CompliantContacts {
            estimates,
            held_period: c.held_acceleration.then_some(period),
            wrench_source: c.wrench_source,
            filter_gain: period / (positive("wrench_filter_time", c.wrench_filter_time)? + period),
            lift_off_force: match c.lift_off_force {
                f if f.is_nan() || f < 0.0 => {
                    return Err(WbcError::InvalidConfig {
                        task: "<tsid>".into(),
                        key: "lift_off_force",
                        reason: format!("compliant.lift_off_force = {f} must be >= 0 (inf: off)"),
                    })
                }
                f => f,
            },
            sole: SoleGeometry {
                length: positive("sole_length", c.sole_length)?,
                width: positive("sole_width", c.sole_width)?,
            },
            ground: GroundParameters {
                stiffness: positive("ground_stiffness", c.ground_stiffness)?,
                damping: positive("ground_damping", c.ground_damping)?,
            },
            momentum_horizon: 1.0 / positive("momentum_rate_gain", c.momentum_rate_gain)?,
            wrench_horizon: 1.0 / positive("wrench_rate_gain", c.wrench_rate_gain)?,
            feasibility_horizon: positive("feasibility_horizon", c.feasibility_horizon)?,
            measured: vec![Vector6::zeros(); contacts],
            rest: vec![Isometry3::identity(); contacts],
            rates: vec![
                WrenchRate {
                    drift: Vector6::zeros(),
                    gain: nalgebra::Matrix6::zeros(),
                };
                contacts
            ],
        })
    }

    /// The rest pose of contact `c` touching down at `pose` with the measured wrench: `pose` raised by the
    /// static sink `f / (k l w |e₃ᵀRe₃|)` of Lemma 1 (eq. 8.1.7a at zero velocity), so that a contact
    /// already loaded (at start-up) starts where the model gives its measured force.
    /// With `estimate_ground`, the contact's estimate waits for the sole to meet the ground
    /// ([`Self::estimate_ground`]).
    pub fn touch_down(&mut self, c: usize, pose: &Isometry3<f64>) {
        if let Some(e) = &mut self.estimates {
            e.touch_down(c);
        }
        self.rest[c] = self.rest_at(c, pose);
    }

    /// `pose` raised by the static sink of contact `c`'s measured force on its ground (see [`Self::touch_down`]).
    fn rest_at(&self, c: usize, pose: &Isometry3<f64>) -> Isometry3<f64> {
        let scale = self.ground_of(c).stiffness
            * self.sole.area()
            * pose.rotation.to_rotation_matrix()[(2, 2)].abs();
        let mut rest = *pose;
        if scale > 0.0 {
            rest.translation.vector += self.measured[c].fixed_rows::<3>(0) / scale;
        }
        rest
    }

    /// The normal-force bound of contact `c` held in the QP after its ramp ended (its planned lift-off):
    /// its measured normal force (along the contact frame's z), which may then only decrease, when that
    /// exceeds `lift_off_force`; `None`: the contact leaves the QP.
    pub fn held_lift_off(&self, c: usize, contact: &Contact) -> Option<f64> {
        let force = contact.pose.rotation.inverse() * self.measured[c].fixed_rows::<3>(0);
        (force.z > self.lift_off_force).then_some(force.z)
    }

    /// The sole state of `contact` (index `c`) for the contact model.
    pub fn sole_state(&self, c: usize, contact: &Contact) -> SoleState {
        SoleState {
            position: contact.pose.translation.vector,
            rotation: contact.pose.rotation.to_rotation_matrix(),
            linear_velocity: contact.velocity.fixed_rows::<3>(0).into_owned(),
            angular_velocity: contact.velocity.fixed_rows::<3>(3).into_owned(),
            rest_position: self.rest[c].translation.vector,
            rest_rotation: self.rest[c].rotation.to_rotation_matrix(),
        }
    }

    /// The ground of contact `c`'s model: its estimate with `estimate_ground`, else the configured one.
    pub fn ground_of(&self, c: usize) -> GroundParameters {
        self.estimates.as_ref().map_or(self.ground, |e| e.ground(c))
    }

    /// Updates the ground estimate of every loaded contact (when estimated) with its measured wrench and
    /// the regressor of its sole relative to its rest pose [Romualdi 2022, eq. 8.2.20–8.2.22], while its
    /// measured normal force exceeds `estimator_contact_force`. After a planned touch-down
    /// ([`Self::touch_down`]) the sole may not have met the ground yet: until its force exceeds that
    /// threshold its rest pose follows it, so the rest pose is the sole's last pose above the threshold
    /// (within one period of its impact), and the covariance is reset at its first sample: the touch-down
    /// of the estimate is the sole's, not the plan's.
    pub fn estimate_ground(&mut self, contacts: &[Contact]) {
        let Some(threshold) = self.estimates.as_ref().map(|e| e.contact_force()) else {
            return;
        };
        for (c, contact) in contacts.iter().enumerate() {
            if contact.load <= 0.0 {
                continue;
            }
            let normal = (contact.pose.rotation.inverse() * self.measured[c].fixed_rows::<3>(0)).z;
            if normal < threshold {
                if self.estimates.as_ref().is_some_and(|e| e.awaiting(c)) {
                    self.rest[c] = self.rest_at(c, &contact.pose);
                }
                continue;
            }
            let regressor = self.sole.regressor(&self.sole_state(c, contact));
            if let Some(e) = &mut self.estimates {
                e.update(c, &regressor, &self.measured[c]);
            }
        }
    }

    /// Updates the wrench-rate model of every contact at its current state (averaged over the held
    /// period with `held_acceleration`, [`WrenchRate::held_over`]).
    pub fn update_rates(&mut self, contacts: &[Contact]) {
        for (c, contact) in contacts.iter().enumerate() {
            let state = self.sole_state(c, contact);
            let ground = self.ground_of(c);
            let rate = self.sole.wrench_rate(&state, &ground);
            self.rates[c] = match self.held_period {
                Some(dt) => rate.held_over(dt, &ground),
                None => rate,
            };
        }
    }
}

/// Rewrites rows `A_ν ν̇ + Σ_c A_c w_c ⋚ r` filled for wrench columns into rate rows for `w_c = f_c + T ḟ_c`
/// (see the module docs): `r −= Σ_c A_c f_c` (the equality's `b`, or both sides of an inequality), then
/// `A_c *= T`, over the loaded contacts (`offsets`).
pub(crate) fn to_rate_rows(
    b: &mut TaskDataMut,
    equality: bool,
    offsets: &[Option<usize>],
    measured: &[Vector6<f64>],
    horizon: f64,
) {
    for r in 0..b.a.nrows() {
        let mut shift = 0.0;
        for (off, f) in offsets.iter().zip(measured) {
            if let Some(off) = *off {
                for (k, fk) in f.iter().enumerate() {
                    shift += b.a[(r, off + k)] * fk;
                    b.a[(r, off + k)] *= horizon;
                }
            }
        }
        if equality {
            b.b[r] -= shift;
        } else {
            b.lower[r] -= shift;
            b.upper[r] -= shift;
        }
    }
}

/// The measured wrenches of the contacts without a column (unloaded in this QP but maybe still touching)
/// in rows `M ν̇ − Σ J_{c,·}ᵀ f_c = r` of the dynamics: `r += J_{c,cols}ᵀ f_c` for the `rows` rows that
/// start at velocity index `first` (6 base rows: 0; the joint rows: 6) [Romualdi 2022, eq. 8.2.1, 8.2.13].
pub(crate) fn add_unloaded_wrenches(
    s: &TsidContext,
    measured: &[Vector6<f64>],
    first: usize,
    rows: usize,
    b: &mut TaskDataMut,
    equality: bool,
) {
    for (c, contact) in s.contacts.iter().enumerate() {
        if s.offsets[c].is_some() {
            continue;
        }
        for r in 0..rows {
            let t = contact.jacobian.column(first + r).dot(&measured[c]);
            if equality {
                b.b[r] += t;
            } else {
                b.lower[r] += t;
                b.upper[r] += t;
            }
        }
    }
}

/// The `Σ_c (ṗ_c − ẋ) × f_c` term of the angular momentum's second derivative [Romualdi 2022, eq. 8.2.2],
/// moved to the right-hand side of rows already in rate form with horizon `T`: `b −= T Σ_c (ṗ_c − ẋ) × f_c`.
pub(crate) fn add_angular_momentum_drift(
    s: &TsidContext,
    measured: &[Vector6<f64>],
    horizon: f64,
    b: &mut TaskDataMut,
) {
    let mut drift = Vector3::zeros();
    for (c, contact) in s.contacts.iter().enumerate() {
        if s.offsets[c].is_some() {
            let arm_rate = contact.velocity.fixed_rows::<3>(0) - s.com_velocity;
            drift += arm_rate.cross(&measured[c].fixed_rows::<3>(0));
        }
    }
    for r in 0..3 {
        b.b[r] -= horizon * drift[r];
    }
}

/// The contact dynamics of a loaded contact [Romualdi 2022, eq. 8.2.15]: `ḟ_c − g_c J_c ν̇ = h_c + g_c J̇_c ν`
/// (6 rows, N/s and N·m/s) with `ḟ_c` in columns `off..off + 6` and `(h_c, g_c)` the wrench rate of
/// Lemma 1 at the sole's state (eq. 8.2.14, [`SoleGeometry::wrench_rate`]).
pub(crate) fn fill_contact_dynamics(
    contact: &Contact,
    rate: &WrenchRate,
    off: usize,
    b: &mut TaskDataMut,
) {
    let nv = contact.jacobian.ncols();
    for r in 0..6 {
        for j in 0..nv {
            let mut gj = 0.0;
            for k in 0..6 {
                gj += rate.gain[(r, k)] * contact.jacobian[(k, j)];
            }
            b.a[(r, j)] = -gj;
        }
        for k in 0..6 {
            b.a[(r, off + k)] = if k == r { 1.0 } else { 0.0 };
        }
    }
    let rhs = rate.drift + rate.gain * contact.bias;
    for r in 0..6 {
        b.b[r] = rhs[r];
    }
}

/// The joint torques of the compliant TSID [Romualdi 2022, eq. 8.2.1]:
/// `τ = M_s ν̇ + h_s − Σ_c J_{c,s}ᵀ f_c` with the measured wrenches of every contact (N·m).
pub(crate) fn measured_joint_torques(
    s: &TsidContext,
    measured: &[Vector6<f64>],
    x: &DVector<f64>,
    tau: &mut DVector<f64>,
) {
    let nv = s.mass_matrix.ncols();
    for i in 0..nv - 6 {
        let mut t = s.bias_forces[6 + i];
        for j in 0..nv {
            t += s.mass_matrix[(6 + i, j)] * x[j];
        }
        for (contact, f) in s.contacts.iter().zip(measured) {
            t -= contact.jacobian.column(6 + i).dot(f);
        }
        tau[i] = t;
    }
}
