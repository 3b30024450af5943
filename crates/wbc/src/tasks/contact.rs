//! Rigid planar contacts on any frame (TSID): the contact constraint, the wrench feasibility (linearized
//! friction cone, CoP inside the sole rectangle, torsional friction, unilateral and bounded normal force,
//! in the contact frame), the load ramps of contact changes, and the regularization of the contact
//! wrenches `‖w − w*‖²_W` [Romualdi 2022, eq. 7.2.25]. Wrenches are mixed: force (N) and torque (N m)
//! about the contact frame origin, world axes.

use nalgebra::{DMatrix, Isometry3, Matrix6, Vector6};
use stride_model::{FrameId, Model};
use stride_qp::TaskDataMut;

use super::{check_gain, frame_id, TsidContext};
use crate::config::ContactTaskConfig;
use crate::error::WbcError;
use crate::io::WbcInput;
use crate::math::orientation_error;
use crate::names::Resolver;

/// Rows of the contact wrench feasibility in the contact frame: friction pyramid (4S), CoP (4),
/// torsional friction (2), all `≤ 0`; the normal force row is separate.
#[derive(Debug, Clone)]
pub(crate) struct Contact {
    pub(crate) name: String,
    pub(crate) frame: FrameId,
    /// Index of its contact flag in the controller's names ([`Resolver`]).
    pub(crate) flag: usize,
    /// Homogeneous rows on the local wrench `[f; τ]`, all `A w ≤ 0`.
    pub(crate) local_rows: DMatrix<f64>,
    pub(crate) min_normal_force: f64,
    pub(crate) max_normal_force: f64,
    pub(crate) ramp_time: f64,
    pub(crate) kp: f64,
    pub(crate) kd: f64,
    // run-time
    pub(crate) load: f64,
    pub(crate) unload_from: f64,
    pub(crate) unloading: bool,
    pub(crate) jacobian: DMatrix<f64>,
    pub(crate) bias: Vector6<f64>,
    pub(crate) velocity: Vector6<f64>,
    pub(crate) pose: Isometry3<f64>,
    pub(crate) reference: Isometry3<f64>,
    pub(crate) last_fz: f64,
    /// TSID-Compliant's `lift_off_force`: the normal-force bound of a contact held in the QP after its
    /// ramp ended (N); `None`: the ramp's bound.
    pub(crate) held_upper: Option<f64>,
}

impl Contact {
    pub fn new(model: &Model, names: &Resolver, c: &ContactTaskConfig) -> Result<Self, WbcError> {
        let bad = |key: &'static str, reason: String| WbcError::InvalidConfig {
            task: c.name.clone(),
            key,
            reason,
        };
        if !(c.friction.is_finite() && c.friction > 0.0) {
            return Err(bad("friction", format!("{} must be > 0", c.friction)));
        }
        if c.facets == 0 || c.facets > 16 {
            return Err(bad("facets", format!("{} must be in 1..=16", c.facets)));
        }
        if !c.foot_x.iter().all(|v| v.is_finite()) || c.foot_x[0] >= c.foot_x[1] {
            return Err(bad("foot_x", "needs lower < upper".into()));
        }
        if !c.foot_y.iter().all(|v| v.is_finite()) || c.foot_y[0] >= c.foot_y[1] {
            return Err(bad("foot_y", "needs lower < upper".into()));
        }
        check_gain(&c.name, "torsional_friction", c.torsional_friction)?;
        check_gain(&c.name, "min_normal_force", c.min_normal_force)?;
        check_gain(&c.name, "ramp_time", c.ramp_time)?;
        check_gain(&c.name, "kp", c.kp)?;
        check_gain(&c.name, "kd", c.kd)?;
        if !(c.max_normal_force.is_finite() && c.max_normal_force > c.min_normal_force) {
            return Err(bad(
                "max_normal_force",
                format!(
                    "{} must be finite and > min_normal_force",
                    c.max_normal_force
                ),
            ));
        }
        let s = c.facets;
        let rows = 4 * s + 6;
        let mut a = DMatrix::zeros(rows, 6);
        let mu_eff = c.friction * (std::f64::consts::PI / (4.0 * s as f64)).cos();
        for k in 0..4 * s {
            let phi = (k as f64 + 0.5) * std::f64::consts::PI / (2.0 * s as f64);
            a[(k, 0)] = phi.cos();
            a[(k, 1)] = phi.sin();
            a[(k, 2)] = -mu_eff;
        }
        let r = 4 * s;
        // CoP x = −τ_y / f_z ∈ [x_lo, x_hi];  CoP y = τ_x / f_z ∈ [y_lo, y_hi]
        a[(r, 2)] = c.foot_x[0];
        a[(r, 4)] = 1.0;
        a[(r + 1, 2)] = -c.foot_x[1];
        a[(r + 1, 4)] = -1.0;
        a[(r + 2, 2)] = c.foot_y[0];
        a[(r + 2, 3)] = -1.0;
        a[(r + 3, 2)] = -c.foot_y[1];
        a[(r + 3, 3)] = 1.0;
        // |τ_z| ≤ γ f_z
        a[(r + 4, 5)] = 1.0;
        a[(r + 4, 2)] = -c.torsional_friction;
        a[(r + 5, 5)] = -1.0;
        a[(r + 5, 2)] = -c.torsional_friction;
        Ok(Contact {
            name: c.name.clone(),
            frame: frame_id(model, &c.name, &c.frame)?,
            flag: names.contact_index(c.contact_name()?).ok_or_else(|| {
                WbcError::InvalidConfig {
                    task: c.name.clone(),
                    key: "contact",
                    reason: "not in the controller's contact names".into(),
                }
            })?,
            local_rows: a,
            min_normal_force: c.min_normal_force,
            max_normal_force: c.max_normal_force,
            ramp_time: c.ramp_time,
            kp: c.kp,
            kd: c.kd,
            load: 0.0,
            unload_from: 0.0,
            unloading: false,
            jacobian: DMatrix::zeros(6, model.nv()),
            bias: Vector6::zeros(),
            velocity: Vector6::zeros(),
            pose: Isometry3::identity(),
            reference: Isometry3::identity(),
            last_fz: 0.0,
            held_upper: None,
        })
    }

    /// Feasibility rows + 1 normal-force row.
    pub fn feasibility_rows(&self) -> usize {
        self.local_rows.nrows() + 1
    }

    /// Upper bound of f_z this tick.
    pub fn normal_upper(&self) -> f64 {
        if let Some(upper) = self.held_upper {
            upper
        } else if self.unloading {
            self.unload_from * self.load
        } else {
            self.max_normal_force * self.load
        }
    }

    /// Advances the load ramp for one period.
    pub fn advance_load(&mut self, in_contact: bool, period: f64) {
        let step = if self.ramp_time > 0.0 {
            period / self.ramp_time
        } else {
            1.0
        };
        if in_contact {
            if self.unloading {
                // re-loading during an unload ramp: continue from the current bound
                let current = self.normal_upper();
                self.unloading = false;
                self.load = (current / self.max_normal_force).clamp(0.0, 1.0);
            }
            if self.load == 0.0 {
                self.reference = self.pose;
            }
            self.load = (self.load + step).min(1.0);
        } else if self.load > 0.0 {
            if !self.unloading {
                self.unloading = true;
                self.unload_from =
                    (self.last_fz / self.load.max(1e-12)).clamp(0.0, self.max_normal_force);
            }
            self.load = (self.load - step).max(0.0);
            if self.load <= 0.0 {
                self.load = 0.0;
                self.unloading = false;
            }
        }
    }

    /// Contact constraint (the foot does not accelerate): `J ν̇ = −J̇ν − K_d v + K_p e` with
    /// `e = [p_ref − p; Log(R_ref Rᵀ)]` (6 rows, m/s² and rad/s²) [Romualdi 2022, §7.2].
    pub fn fill_constraint(&self, b: &mut TaskDataMut) {
        let nv = self.jacobian.ncols();
        b.a.view_mut((0, 0), (6, nv)).copy_from(&self.jacobian);
        let mut e = Vector6::zeros();
        e.fixed_rows_mut::<3>(0)
            .copy_from(&(self.reference.translation.vector - self.pose.translation.vector));
        e.fixed_rows_mut::<3>(3).copy_from(&orientation_error(
            &self.reference.rotation,
            &self.pose.rotation,
        ));
        for r in 0..6 {
            b.b[r] = -self.bias[r] - self.kd * self.velocity[r] + self.kp * e[r];
        }
    }

    /// Wrench feasibility of the wrench in columns `off..off + 6`: `A blockdiag(Rᵀ, Rᵀ) w ≤ 0` (friction
    /// pyramid, CoP in the sole rectangle, torsional friction, in the contact frame) and the bounded
    /// normal force `f_min ≤ (Rᵀ f)_z ≤ f_max · load` (N) [Romualdi 2022, §7.2].
    pub fn fill_feasibility(&self, off: usize, b: &mut TaskDataMut) {
        let rt = self.pose.rotation.to_rotation_matrix().matrix().transpose();
        let mut rot6 = Matrix6::zeros();
        rot6.view_mut((0, 0), (3, 3)).copy_from(&rt);
        rot6.view_mut((3, 3), (3, 3)).copy_from(&rt);
        let rows = self.local_rows.nrows();
        for r in 0..rows {
            for k in 0..6 {
                let mut s = 0.0;
                for l in 0..6 {
                    s += self.local_rows[(r, l)] * rot6[(l, k)];
                }
                b.a[(r, off + k)] = s;
            }
            b.lower[r] = f64::NEG_INFINITY;
            b.upper[r] = 0.0;
        }
        // normal force (local z): row 2 of Rᵀ on the force
        for k in 0..3 {
            b.a[(rows, off + k)] = rt[(2, k)];
        }
        let upper = self.normal_upper();
        b.lower[rows] = self.min_normal_force.min(upper);
        b.upper[rows] = upper;
    }
}

/// Contact wrench regularization: `w_c = w*_c` for every loaded contact (6 rows each, N and N m), with
/// `w*` the contact's `desired_wrench` in the input (zero by default).
pub(crate) fn fill_wrench_regularization(
    input: &WbcInput,
    names: &Resolver,
    s: &TsidContext,
    b: &mut TaskDataMut,
) {
    let mut k = 0;
    for (c, contact) in s.contacts.iter().enumerate() {
        if let Some(off) = s.offsets[c] {
            let reference: Vector6<f64> = names.contact(input, contact.flag).desired_wrench;
            for r in 0..6 {
                b.a[(k + r, off + r)] = 1.0;
                b.b[k + r] = reference[r];
            }
            k += 6;
        }
    }
}
