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

use nalgebra::{DVector, Isometry3, Point3, Translation3, UnitQuaternion, Vector3, Vector6};
use stride_qp::TaskDataMut;

use super::compliant_ground::ContactGroundEstimates;
use super::{Contact, TsidContext};
use crate::config::{CompliantConfig, EstimatorRestPose, EstimatorRows, WrenchSource};
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
    /// `estimator_rest_pose`: the zero-force pose a sole takes where it meets the ground (with
    /// `estimate_ground`).
    pub rest_pose: EstimatorRestPose,
    /// `estimator_rows`: the rows of the wrench the ground estimate reads.
    pub estimator_rows: EstimatorRows,
    /// Per contact: its estimate may be fed (with `estimate_ground`): false for a sole loaded at start-up,
    /// whose zero-force pose is unknown (the prior's sink would be its rest), until its next touch-down.
    pub rest_known: Vec<bool>,
    /// The first tick has been run (its touch-downs are the start-up contacts).
    pub started: bool,
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

/// The angular momentum tasks' `K_p` (1/s) that `angular_momentum_damping` (`ζ`) derives from the momentum
/// rate gain `k_h`: the rows `ḧ = k_h (K_p (h* − h) − ḣ)` are the loop `s² + k_h s + k_h K_p`, whose damping
/// ratio is `ζ` for `K_p = k_h / (4 ζ²)`. `None` with `ζ = 0` (each task keeps its `kp`). Errors: `ζ` not
/// finite or negative.
pub(crate) fn derived_angular_momentum_gain(c: &CompliantConfig) -> Result<Option<f64>, WbcError> {
    let z = c.angular_momentum_damping;
    if z == 0.0 {
        return Ok(None);
    }
    if !(z.is_finite() && z > 0.0) {
        return Err(WbcError::InvalidConfig {
            task: "<tsid>".into(),
            key: "angular_momentum_damping",
            reason: format!("compliant.angular_momentum_damping = {z} must be finite and >= 0"),
        });
    }
    let kh = positive("momentum_rate_gain", c.momentum_rate_gain)?;
    Ok(Some(kh / (4.0 * z * z)))
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
            rest_pose: c.estimator_rest_pose,
            estimator_rows: c.estimator_rows,
            rest_known: vec![false; contacts],
            started: false,
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
        self.rest_known[c] = self.started;
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

    /// The rest pose of a sole meeting flat ground at `pose` (`estimator_rest_pose = "level"`): `pose`
    /// rotated about its lowest corner until its normal is the world's vertical (its roll and pitch removed
    /// by the smallest rotation, its heading kept), i.e. the horizontal plane through the lowest corner,
    /// which is where a sole that lands tilted first touches the ground.
    pub fn level_rest(&self, pose: &Isometry3<f64>) -> Isometry3<f64> {
        let normal = pose.rotation * Vector3::z();
        let level = UnitQuaternion::rotation_between(&normal, &Vector3::z())
            .unwrap_or_else(UnitQuaternion::identity);
        let rotation = level * pose.rotation;
        let lowest = self.lowest_corner(pose);
        let position = pose * lowest - rotation * lowest;
        Isometry3::from_parts(Translation3::from(position), rotation)
    }

    /// The corner of the sole (in the sole frame) lowest in the world at `pose`.
    fn lowest_corner(&self, pose: &Isometry3<f64>) -> Point3<f64> {
        let (hl, hw) = (0.5 * self.sole.length, 0.5 * self.sole.width);
        let mut lowest = Point3::new(hl, hw, 0.0);
        for (x, y) in [(hl, -hw), (-hl, hw), (-hl, -hw)] {
            let p = Point3::new(x, y, 0.0);
            if (pose * p).z < (pose * lowest).z {
                lowest = p;
            }
        }
        lowest
    }

    /// Whether all four corners of the sole at `pose` are at or below the plane of `rest` (the whole
    /// sole in the ground).
    fn whole_sole_in(&self, pose: &Isometry3<f64>, rest: &Isometry3<f64>) -> bool {
        let (hl, hw) = (0.5 * self.sole.length, 0.5 * self.sole.width);
        let normal = rest.rotation * Vector3::z();
        [(hl, hw), (hl, -hw), (-hl, hw), (-hl, -hw)]
            .iter()
            .all(|&(x, y)| {
                let corner = pose * Point3::new(x, y, 0.0);
                normal.dot(&(corner.coords - rest.translation.vector)) <= 0.0
            })
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
        self.sole_state_at(c, &contact.pose, &contact.velocity)
    }

    /// The sole state of contact `c` at `pose` moving with `velocity` (`[ȯ; ω]`, world, mixed).
    fn sole_state_at(&self, c: usize, pose: &Isometry3<f64>, velocity: &Vector6<f64>) -> SoleState {
        SoleState {
            position: pose.translation.vector,
            rotation: pose.rotation.to_rotation_matrix(),
            linear_velocity: velocity.fixed_rows::<3>(0).into_owned(),
            angular_velocity: velocity.fixed_rows::<3>(3).into_owned(),
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
    /// of the estimate is the sole's, not the plan's. With `estimator_rest_pose = "level"` that pose is
    /// levelled about its lowest corner ([`Self::level_rest`]) and the estimate is fed only while the
    /// sole's four corners are below the rest plane; a sole loaded at start-up is not estimated until its
    /// next touch-down; the rows `estimator_rows` leaves out carry no information.
    pub fn estimate_ground(&mut self, contacts: &[Contact]) {
        for (c, contact) in contacts.iter().enumerate() {
            if contact.load > 0.0 {
                self.estimate_contact_ground(c, &contact.pose, &contact.velocity);
            }
        }
        self.started = true;
    }

    /// [`Self::estimate_ground`] for the loaded contact `c`, its sole at `pose` moving with `velocity`
    /// (`[ȯ; ω]`, world, mixed) and its measured wrench in `measured[c]`.
    fn estimate_contact_ground(
        &mut self,
        c: usize,
        pose: &Isometry3<f64>,
        velocity: &Vector6<f64>,
    ) {
        let Some(threshold) = self.estimates.as_ref().map(|e| e.contact_force()) else {
            return;
        };
        let normal = (pose.rotation.inverse() * self.measured[c].fixed_rows::<3>(0)).z;
        if normal < threshold {
            if self.estimates.as_ref().is_some_and(|e| e.awaiting(c)) {
                self.rest[c] = match self.rest_pose {
                    EstimatorRestPose::Level => self.level_rest(pose),
                    EstimatorRestPose::Impact => self.rest_at(c, pose),
                };
                self.rest_known[c] = true;
            }
            return;
        }
        if !self.rest_known[c] {
            return;
        }
        if self.rest_pose == EstimatorRestPose::Level && !self.whole_sole_in(pose, &self.rest[c]) {
            return;
        }
        let mut regressor = self
            .sole
            .regressor_with_rest_height(&self.sole_state_at(c, pose, velocity));
        let mut wrench = self.measured[c];
        for row in self.estimator_rows.unread() {
            regressor.row_mut(*row).fill(0.0);
            wrench[*row] = 0.0;
        }
        if let Some(e) = &mut self.estimates {
            e.update(c, &regressor, &wrench);
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

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector2;

    /// Ground of the synthetic landing: Table 8.1's stiffest, N/m³, N·s/m³.
    const K: f64 = 2e6;
    const B: f64 = 1e4;
    const DT: f64 = 0.001;

    /// The sole's pose at `t` (s) of a heel-first landing on flat ground (surface `z = 0`): the sole,
    /// pitched 0.08 rad toe up, its heel 2 mm above the ground, rotates about its heel line until flat
    /// over 0.2 s while the heel sinks 11 mm (9 mm into the ground, about the sink of 330 N on `K`),
    /// then sinks and rises by 2 mm at 2 Hz.
    fn landing(sole: &SoleGeometry, t: f64) -> Isometry3<f64> {
        let s = (t / 0.2).min(1.0);
        let pitch = -0.08 * (1.0 - s);
        let wave = if t > 0.2 {
            0.002 * (2.0 * std::f64::consts::PI * 2.0 * (t - 0.2)).sin()
        } else {
            0.0
        };
        let heel = Vector3::new(0.0, 0.0, 0.002 - 0.011 * s - wave);
        let rotation = UnitQuaternion::from_euler_angles(0.0, pitch, 0.3);
        let centre = heel + rotation * Vector3::new(0.5 * sole.length, 0.0, 0.0);
        Isometry3::from_parts(Translation3::from(centre), rotation)
    }

    /// `[ȯ; ω]` (world) of [`landing`] at `t` by central differences.
    fn landing_velocity(sole: &SoleGeometry, t: f64) -> Vector6<f64> {
        let h = 1e-6;
        let (a, b) = (landing(sole, t - h), landing(sole, t + h));
        let v = (b.translation.vector - a.translation.vector) / (2.0 * h);
        let w = (b.rotation * a.rotation.inverse()).scaled_axis() / (2.0 * h);
        Vector6::new(v.x, v.y, v.z, w.x, w.y, w.z)
    }

    /// The wrench of flat ground on the sole at `pose` moving with `velocity` (force, torque about the
    /// sole centre; world axes): a 41 × 41 trapezoidal quadrature of the normal density
    /// `max(0, k δ − b δ̇)` over the points below the surface (depth `δ`), never pulling: the plant's law
    /// without its tangential springs.
    fn flat_ground_wrench(
        sole: &SoleGeometry,
        pose: &Isometry3<f64>,
        velocity: &Vector6<f64>,
    ) -> Vector6<f64> {
        let n = 41;
        let (v, w) = (velocity.fixed_rows::<3>(0), velocity.fixed_rows::<3>(3));
        let mut wrench = Vector6::zeros();
        for i in 0..n {
            for j in 0..n {
                let (u, s) = (i as f64 / (n - 1) as f64, j as f64 / (n - 1) as f64);
                let local = Point3::new((u - 0.5) * sole.length, (s - 0.5) * sole.width, 0.0);
                let p = pose * local;
                if p.z >= 0.0 {
                    continue;
                }
                let weight = |x: usize| if x == 0 || x == n - 1 { 0.5 } else { 1.0 };
                let area = sole.area() * weight(i) * weight(j) / ((n - 1) * (n - 1)) as f64;
                let arm = p.coords - pose.translation.vector;
                let rate = (v + w.cross(&arm)).z;
                let fz = (K * -p.z - B * rate).max(0.0) * area;
                let f = Vector3::new(0.0, 0.0, fz);
                let m = arm.cross(&f);
                wrench += Vector6::new(f.x, f.y, f.z, m.x, m.y, m.z);
            }
        }
        wrench
    }

    /// The ground estimate 1.2 s after the planned touch-down of [`landing`] (1 s after the sole is
    /// flat; prior `1e6, 1e3`), with the rest pose `rest_pose`.
    fn estimate_after_tilted_landing(rest_pose: EstimatorRestPose) -> Vector2<f64> {
        let config = CompliantConfig {
            ground_stiffness: 1e6,
            ground_damping: 1e3,
            estimate_ground: true,
            estimator_rest_pose: rest_pose,
            // noise-free data: the rest pose where the sole first carries 0.05 N (a sole landing tilted
            // by φ on the continuum sinks `sqrt(2 φ F / (k w))` before it carries F: 2.1 mm at 5 N, 0.2 mm
            // at 0.05 N)
            estimator_contact_force: 0.05,
            ..CompliantConfig::default()
        };
        let mut contacts = CompliantContacts::new(&config, 1, DT).unwrap();
        let sole = contacts.sole;
        contacts.touch_down(0, &landing(&sole, 0.0));
        for tick in 0..=1200 {
            let t = tick as f64 * DT;
            let (pose, velocity) = (landing(&sole, t), landing_velocity(&sole, t));
            contacts.measured[0] = flat_ground_wrench(&sole, &pose, &velocity);
            contacts.estimate_contact_ground(0, &pose, &velocity);
        }
        contacts.ground_of(0).vector()
    }

    /// A sole landing heel first, 0.08 rad toe up, on flat ground (`k = 2e6`, `b = 1e4`): with the level
    /// rest pose (the horizontal plane through the corner that met the ground) the estimate is within 5 %
    /// of `k` and 10 % of `b` 1 s after; with the sole's tilted pose at its impact as the rest pose the
    /// deflection it sees is millimetres too large and `k̂` is more than 10 % low.
    #[test]
    fn the_level_rest_pose_estimates_a_tilted_landing() {
        let level = estimate_after_tilted_landing(EstimatorRestPose::Level);
        assert!((level[0] / K - 1.0).abs() < 0.05, "{level:?}");
        assert!((level[1] / B - 1.0).abs() < 0.1, "{level:?}");
        let impact = estimate_after_tilted_landing(EstimatorRestPose::Impact);
        assert!(impact[0] < 0.9 * K, "{impact:?}");
        let rest = CompliantContacts::new(&CompliantConfig::default(), 1, DT).unwrap();
        let pose = landing(&rest.sole, 0.0);
        let level_pose = rest.level_rest(&pose);
        let z = level_pose.rotation * Vector3::z();
        assert!((z - Vector3::z()).norm() < 1e-12, "{z:?}");
        let heel = pose * Point3::new(-0.5 * rest.sole.length, 0.0, 0.0);
        let heel_level = level_pose * Point3::new(-0.5 * rest.sole.length, 0.0, 0.0);
        assert!((heel - heel_level).norm() < 1e-12);
    }
}
