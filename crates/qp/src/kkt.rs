//! Independent check of the Karush–Kuhn–Tucker optimality conditions.

use crate::dense::DenseQp;
use crate::solver::SolverOutput;

/// Residuals of the KKT conditions of a [`DenseQp`] at a primal–dual point (all ∞-norms, absolute).
///
/// With the multiplier convention of [`SolverOutput`]:
///
/// | field | condition |
/// |---|---|
/// | `stationarity` | `‖H x + g + Eᵀy + Cᵀz + w‖∞` |
/// | `primal` | largest violation of `E x = f`, `l ≤ C x ≤ u`, `lb ≤ x ≤ ub` |
/// | `dual` | largest multiplier with a forbidden sign (`z_i > 0` with `u_i = +∞`, `z_i < 0` with `l_i = −∞`, same for `w`) |
/// | `complementarity` | largest `|z_i|·slack` of the side its sign selects (`z_i > 0`: `u_i − C_i x`; `z_i < 0`: `C_i x − l_i`), same for `w` |
/// | `scale` | `1 + max(‖Hx‖∞, ‖g‖∞, ‖f‖∞, finite ‖l‖∞, ‖u‖∞, ‖lb‖∞, ‖ub‖∞)` for relative tolerances |
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KktReport {
    /// Stationarity residual.
    pub stationarity: f64,
    /// Primal infeasibility.
    pub primal: f64,
    /// Dual infeasibility (multipliers of the wrong sign).
    pub dual: f64,
    /// Complementarity violation.
    pub complementarity: f64,
    /// Problem scale, for relative tolerances.
    pub scale: f64,
}

impl KktReport {
    /// Largest of the four residuals.
    pub fn max_residual(&self) -> f64 {
        self.stationarity
            .max(self.primal)
            .max(self.dual)
            .max(self.complementarity)
    }

    /// Whether every residual is below `tol · scale`.
    pub fn is_satisfied(&self, tol: f64) -> bool {
        self.max_residual() <= tol * self.scale
    }
}

/// Evaluates the KKT conditions of `qp` at the point stored in `out` (see [`KktReport`]). Allocation-free.
pub fn check_kkt(qp: &DenseQp, out: &SolverOutput) -> KktReport {
    let n = qp.n();
    let x = &out.x;
    let mut stationarity: f64 = 0.0;
    let mut scale: f64 = 0.0;
    let upd = |s: &mut f64, v: f64| {
        if v.is_finite() {
            *s = s.max(v.abs());
        }
    };
    for j in 0..n {
        let mut hx = 0.0;
        for k in 0..n {
            hx += qp.h[(j, k)] * x[k];
        }
        upd(&mut scale, hx);
        upd(&mut scale, qp.g[j]);
        let mut r = hx + qp.g[j] + out.bound_multipliers[j];
        for i in 0..qp.n_eq() {
            r += qp.e[(i, j)] * out.y[i];
        }
        for i in 0..qp.n_ineq() {
            r += qp.c[(i, j)] * out.z[i];
        }
        stationarity = stationarity.max(r.abs());
    }
    let mut primal: f64 = 0.0;
    let mut dual: f64 = 0.0;
    let mut comp: f64 = 0.0;
    for i in 0..qp.n_eq() {
        let mut ax = 0.0;
        for j in 0..n {
            ax += qp.e[(i, j)] * x[j];
        }
        upd(&mut scale, qp.f[i]);
        primal = primal.max((ax - qp.f[i]).abs());
    }
    let mut side = |v: f64, lo: f64, hi: f64, mult: f64, primal: &mut f64, scale: &mut f64| {
        upd(scale, lo);
        upd(scale, hi);
        *primal = primal.max(lo - v).max(v - hi);
        if mult > 0.0 {
            if hi.is_finite() {
                comp = comp.max(mult * (hi - v).abs());
            } else {
                dual = dual.max(mult);
            }
        } else if mult < 0.0 {
            if lo.is_finite() {
                comp = comp.max(-mult * (v - lo).abs());
            } else {
                dual = dual.max(-mult);
            }
        }
    };
    for i in 0..qp.n_ineq() {
        let mut cx = 0.0;
        for j in 0..n {
            cx += qp.c[(i, j)] * x[j];
        }
        side(cx, qp.l[i], qp.u[i], out.z[i], &mut primal, &mut scale);
    }
    for j in 0..n {
        side(
            x[j],
            qp.lb[j],
            qp.ub[j],
            out.bound_multipliers[j],
            &mut primal,
            &mut scale,
        );
    }
    KktReport {
        stationarity,
        primal: primal.max(0.0),
        dual,
        complementarity: comp,
        scale: 1.0 + scale,
    }
}
