//! Dense dual active-set QP solver after Goldfarb & Idnani (1983), "A numerically stable dual method for
//! solving strictly convex quadratic programs", Math. Programming 27:1–33.
//!
//! Notation of the paper: `G = L Lᵀ` (Cholesky of the Hessian), `N` the normals of the active constraints,
//! `L⁻¹ N = Q [R; 0]` and `J = L⁻ᵀ Q = [J₁ J₂]`, so that `Jᵀ N = [R; 0]` and `J Jᵀ = G⁻¹`. For a violated
//! constraint `p` with normal `n⁺` (written as `n⁺ᵀx ≥ b⁺`), `d = Jᵀ n⁺`, the primal step direction is
//! `z = J₂ d₂`, the change of the active multipliers is `r = R⁻¹ d₁`; the partial (dual) step `t₁` keeps the
//! inequality multipliers non-negative and the full step `t₂ = −s(x)/zᵀn⁺` makes `p` active. Adding a
//! constraint rotates `d` into `e_q` with Givens rotations applied to the columns of `J`; dropping one
//! removes a column of `R` and restores its triangular form with Givens rotations (again applied to `J`).
//!
//! Every constraint is one *slot*: equality rows, two-sided inequality rows (the violated side is used with
//! `sign = +1` for `C_i x ≥ l_i`, `sign = −1` for `−C_i x ≥ −u_i`), and the variable bounds (unit normals,
//! handled without forming them).

use serde::{Deserialize, Serialize};

use crate::dense::DenseQp;
use crate::nullspace::kernels;
use crate::solver::{QpSolver, SolverOutput};
use crate::status::QpStatus;

/// Settings of the active-set backend.
///
/// | field | default | meaning |
/// |---|---|---|
/// | `max_iterations` | `0` (= automatic: `3·(n + n_eq + n_ineq + n) + 50`) | limit on active-set changes (adds + drops) |
/// | `feasibility_tolerance` | `1e-9` | a side is violated when `violation > tol · (1 + |rhs|)/‖row‖`-scaled (distance in `x` space) |
/// | `dependence_tolerance` | `1e-10` | a constraint is linearly dependent on the active set when `‖d₂‖ ≤ tol·‖d‖` |
/// | `warm_start` | `true` | start from the previous solve's active set (falls back to a cold start if that fails) |
/// | `reduced_guess` | `false` | the null-space path's reduced QP starts from its previous active set as a guess, a cold start when the guess is rejected: the same solution to about 1e-9, −35 / −73 M instructions per 2 s on the default / torque walk, but the round-off moves closed-loop limits that sit on a knife edge (docs/performance.md), so off by default |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ActiveSetSettings {
    /// Iteration limit (0 = automatic).
    pub max_iterations: usize,
    /// Primal feasibility tolerance (scaled distance).
    pub feasibility_tolerance: f64,
    /// Linear-dependence tolerance (relative).
    pub dependence_tolerance: f64,
    /// Warm start from the previous active set.
    pub warm_start: bool,
    /// The null-space path's reduced QP guesses its previous active set (cold start on rejection).
    pub reduced_guess: bool,
}

impl Default for ActiveSetSettings {
    fn default() -> Self {
        Self {
            max_iterations: 0,
            feasibility_tolerance: 1e-9,
            dependence_tolerance: 1e-10,
            warm_start: true,
            reduced_guess: false,
        }
    }
}

/// How the last solve of an [`ActiveSetSolver`] started.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StartKind {
    /// From the unconstrained minimum.
    Cold,
    /// The previous active set was optimal as it stood (QR guess accepted, no iteration).
    Guess,
    /// The previous active set was re-imposed (Givens), corrected, and the dual iterations continued.
    Reimposed,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Active {
    slot: usize,
    sign: f64,
}

/// Result of one active-set run.
enum Run {
    Done(QpStatus),
    /// The warm start could not be used (inconsistent skipped equality etc.): retry cold.
    WarmFailed,
}

/// The dense Goldfarb–Idnani dual active-set backend (the default for the whole-body QPs).
///
/// Needs a positive definite Hessian (use the problem's Tikhonov term for rank-deficient costs). Per solve:
/// one Cholesky factorisation of `H` (`O(n³/3)`); a cold solve then forms `J₀ = L⁻ᵀ` and costs `O(n²)` per
/// active-set change (constraint addition or drop with Givens rotations, as in the paper).
///
/// Warm start (when the previous solve had the same dimensions), in two stages:
/// 1. *guess*: the previous active set plus all equalities is taken as the optimal active set; the
///    equality-constrained QP is solved with a Householder QR of `L⁻¹ N_A`, and the result is accepted if every
///    inequality multiplier is ≥ 0 and no other constraint is violated (then the KKT conditions hold). This
///    is the common case at 1 kHz and costs about a third of a cold solve.
/// 2. otherwise the previous active set is re-imposed with Givens additions, multipliers are computed in
///    closed form, constraints with negative multipliers are dropped, and the dual iterations continue from
///    that dual-feasible point; if that fails too (e.g. the problem became infeasible) the solve restarts cold.
///
/// All workspace is allocated on the first solve of a given size: later solves allocate nothing.
pub struct ActiveSetSolver {
    settings: ActiveSetSettings,
    n: usize,
    me: usize,
    mi: usize,
    chol: Vec<f64>,
    j0: Vec<f64>,
    j: Vec<f64>,
    r: Vec<f64>,
    nt: Vec<f64>,
    norms: Vec<f64>,
    x: Vec<f64>,
    d: Vec<f64>,
    z: Vec<f64>,
    rv: Vec<f64>,
    tmp: Vec<f64>,
    u: Vec<f64>,
    active: Vec<Active>,
    is_active: Vec<bool>,
    prev: Vec<Active>,
    prev_dims: (usize, usize, usize),
    iterations: usize,
    warm_used: bool,
    qr: Vec<f64>,
    tau: Vec<f64>,
    rdiag: Vec<f64>,
    colnorm: Vec<f64>,
    y: Vec<f64>,
    hff: Vec<f64>,
    free: Vec<usize>,
    j0_ready: bool,
    /// `J` is still `J₀` (no rotation since [`Self::reset_state`]): it is read from `j0`, and the first
    /// rotation copies it into `j` ([`Self::own_j`]).
    j_is_j0: bool,
    last_start: StartKind,
    /// Whether a rejected guess re-imposes the previous active set before the cold start (stage 2 of the
    /// warm start); without it the guess is also tried from an empty previous active set.
    reimpose: bool,
}

impl ActiveSetSolver {
    /// A solver with the given settings; workspace is sized at the first solve.
    pub fn new(settings: ActiveSetSettings) -> Self {
        Self {
            settings,
            n: 0,
            me: 0,
            mi: 0,
            chol: Vec::new(),
            j0: Vec::new(),
            j: Vec::new(),
            r: Vec::new(),
            nt: Vec::new(),
            norms: Vec::new(),
            x: Vec::new(),
            d: Vec::new(),
            z: Vec::new(),
            rv: Vec::new(),
            tmp: Vec::new(),
            u: Vec::new(),
            active: Vec::new(),
            is_active: Vec::new(),
            prev: Vec::new(),
            prev_dims: (usize::MAX, 0, 0),
            iterations: 0,
            warm_used: false,
            qr: Vec::new(),
            tau: Vec::new(),
            rdiag: Vec::new(),
            colnorm: Vec::new(),
            y: Vec::new(),
            hff: Vec::new(),
            free: Vec::new(),
            j0_ready: false,
            j_is_j0: false,
            last_start: StartKind::Cold,
            reimpose: true,
        }
    }

    /// This solver with the warm start reduced to its first stage: the previous active set (empty
    /// included: the unconstrained minimum) is tried as a guess, and a rejected guess goes straight to
    /// the cold start. For the null-space path's reduced problems, whose optimum usually keeps the
    /// previous tick's few active inequalities (none on the position walk), and where re-imposing an
    /// active set was measured slower than a cold start (docs/performance.md): an accepted guess needs
    /// neither `J₀ = L⁻ᵀ` nor any Givens rotation.
    pub(crate) fn guess_or_cold(mut self) -> Self {
        self.reimpose = false;
        self
    }

    /// How the last solve started (cold, accepted guess, or re-imposed active set).
    pub fn last_start(&self) -> StartKind {
        self.last_start
    }

    /// Settings in use.
    pub fn settings(&self) -> &ActiveSetSettings {
        &self.settings
    }

    /// Mutable settings (take effect at the next solve).
    pub fn settings_mut(&mut self) -> &mut ActiveSetSettings {
        &mut self.settings
    }

    /// Number of constraints in the active set of the last successful solve.
    pub fn active_set_size(&self) -> usize {
        self.prev.len()
    }

    fn ensure_workspace(&mut self, n: usize, me: usize, mi: usize) {
        let grow = |v: &mut Vec<f64>, len: usize| {
            if v.len() < len {
                v.resize(len, 0.0);
            }
        };
        grow(&mut self.chol, n * n);
        grow(&mut self.j0, n * n);
        grow(&mut self.j, n * n);
        grow(&mut self.r, n * n);
        grow(&mut self.nt, n * (me + mi));
        grow(&mut self.norms, me + mi);
        grow(&mut self.x, n);
        grow(&mut self.d, n);
        grow(&mut self.z, n.max(me + mi));
        grow(&mut self.rv, n);
        grow(&mut self.tmp, n.max(me + mi + n));
        grow(&mut self.u, n);
        grow(&mut self.qr, n * n);
        grow(&mut self.tau, n);
        grow(&mut self.rdiag, n);
        grow(&mut self.colnorm, n);
        grow(&mut self.y, n);
        grow(&mut self.hff, n * n);
        if self.free.capacity() < n {
            self.free.reserve(n - self.free.len());
        }
        if self.is_active.len() < me + mi + n {
            self.is_active.resize(me + mi + n, false);
        }
        if self.active.capacity() < n {
            self.active.reserve(n - self.active.len());
        }
        if self.prev.capacity() < n {
            self.prev.reserve(n - self.prev.len());
        }
        self.n = n;
        self.me = me;
        self.mi = mi;
    }

    /// Copies the rows in use of `E` and `C` into `nt` (constraint `i`'s normal contiguous at `i·n`) and
    /// their norms into `norms`, reading the column-major matrices column by column.
    #[inline(never)]
    fn load_rows(&mut self, qp: &DenseQp) {
        let (n, me, mi) = (self.n, self.me, self.mi);
        for (first, rows, used) in [(0, &qp.e, me), (me, &qp.c, mi)] {
            let ld = rows.nrows();
            let src = rows.as_slice();
            for jdx in 0..n {
                for (i, v) in src[jdx * ld..jdx * ld + used].iter().enumerate() {
                    self.nt[(first + i) * n + jdx] = *v;
                }
            }
        }
        for i in 0..me + mi {
            let row = &self.nt[i * n..(i + 1) * n];
            self.norms[i] = row.iter().map(|v| v * v).sum::<f64>().sqrt();
        }
    }

    /// Cholesky `H = L Lᵀ` (lower, column-major, [`cholesky_lower`]); `J₀ = L⁻ᵀ` is formed later, when
    /// dual iterations need it. False if `H` is not PD.
    #[inline(never)]
    fn factorize(&mut self, qp: &DenseQp) -> bool {
        let n = self.n;
        let l = &mut self.chol[..n * n];
        let h = qp.h.as_slice();
        let mut max_diag: f64 = 0.0;
        // the lower triangle (diagonal included) of (H + Hᵀ)/2: the only part any use of the factor reads
        for c in 0..n {
            for r in c..n {
                l[r + c * n] = 0.5 * (h[r + c * n] + h[c + r * n]);
            }
            max_diag = max_diag.max(h[c + c * n].abs());
        }
        let pivot_min = 1e-14 * max_diag.max(f64::MIN_POSITIVE);
        self.j0_ready = false;
        cholesky_lower(l, n, pivot_min)
    }

    /// `J₀ = L⁻ᵀ`: column `jj` solves `Lᵀ y = e_jj` (upper triangular back substitution).
    fn compute_j0(&mut self) {
        if self.j0_ready {
            return;
        }
        let n = self.n;
        let l = &self.chol[..n * n];
        let j0 = &mut self.j0[..n * n];
        j0.fill(0.0);
        for jj in 0..n {
            for i in (0..=jj).rev() {
                let mut s = if i == jj { 1.0 } else { 0.0 };
                let lcol = &l[i * n + i + 1..i * n + jj + 1];
                let ycol = &j0[jj * n + i + 1..jj * n + jj + 1];
                for (a, b) in lcol.iter().zip(ycol) {
                    s -= a * b;
                }
                j0[jj * n + i] = s / l[i + i * n];
            }
        }
        self.j0_ready = true;
    }

    /// `y ← L⁻¹ y` (forward substitution, column-oriented), starting at row `first` (entries above are 0).
    fn forward_l(l: &[f64], n: usize, y: &mut [f64], first: usize) {
        for jj in first..n {
            let v = y[jj] / l[jj + jj * n];
            y[jj] = v;
            if v != 0.0 {
                for (a, b) in y[jj + 1..n]
                    .iter_mut()
                    .zip(&l[jj * n + jj + 1..(jj + 1) * n])
                {
                    *a -= v * b;
                }
            }
        }
    }

    /// `y ← L⁻ᵀ y` (back substitution on `Lᵀ`).
    fn backward_lt(l: &[f64], n: usize, y: &mut [f64]) {
        for i in (0..n).rev() {
            let s: f64 = l[i * n + i + 1..(i + 1) * n]
                .iter()
                .zip(&y[i + 1..n])
                .map(|(a, b)| a * b)
                .sum();
            y[i] = (y[i] - s) / l[i + i * n];
        }
    }

    /// Fast warm path: take the previous active set (plus all equalities) as a guess and solve the
    /// equality-constrained QP it defines. Active bounds fix their variables, so the QP is reduced to the free
    /// variables `F` (Cholesky of `H_FF`, or the full factor when no bound is active); the remaining active
    /// rows are handled with a Householder QR of `M = L_F⁻¹ N_F`: `x_F = x₀ + L_F⁻ᵀ Q v`, `Rᵀ v = b − N_Fᵀx₀`,
    /// `u = R⁻¹ v`; bound multipliers follow from stationarity. The guess is accepted when every inequality
    /// multiplier is ≥ 0 and no inactive constraint is violated — the KKT conditions then hold — and no
    /// J/R factors are needed.
    fn try_guess(&mut self, qp: &DenseQp) -> bool {
        if !self.guess_active_set(qp) {
            return false;
        }
        let reduced = self.guess_free_variables(qp);
        if reduced && !self.factor_free_hessian(qp) {
            return false;
        }
        self.guess_primal(qp, reduced) && self.guess_multipliers(qp)
    }

    /// The guess's active set: every equality, then the previous active set's entries that still apply;
    /// false when it has more than `n` entries.
    fn guess_active_set(&mut self, qp: &DenseQp) -> bool {
        let n = self.n;
        let nrow = self.me + self.mi;
        let nslots = nrow + n;
        self.active.clear();
        for v in &mut self.is_active {
            *v = false;
        }
        for i in 0..self.me {
            self.active.push(Active { slot: i, sign: 1.0 });
            self.is_active[i] = true;
        }
        for idx in 0..self.prev.len() {
            let Active { slot, sign } = self.prev[idx];
            if slot < self.me || slot >= nslots || self.is_active[slot] {
                continue;
            }
            if !self.signed_rhs(qp, slot, sign).is_finite() {
                continue;
            }
            if self.active.len() >= n {
                return false;
            }
            self.active.push(Active { slot, sign });
            self.is_active[slot] = true;
        }
        true
    }

    /// Fixes the variables whose bound is active at that bound (in `x`), lists the others in `free`;
    /// returns whether any is fixed.
    fn guess_free_variables(&mut self, qp: &DenseQp) -> bool {
        let n = self.n;
        let nrow = self.me + self.mi;
        // x starts with the fixed (bound) values; free variables are listed in `free`
        self.free.clear();
        for jdx in 0..n {
            if self.is_active[nrow + jdx] {
                let sign = self
                    .active
                    .iter()
                    .find(|a| a.slot == nrow + jdx)
                    .map_or(1.0, |a| a.sign);
                self.x[jdx] = if sign > 0.0 { qp.lb[jdx] } else { qp.ub[jdx] };
            } else {
                self.x[jdx] = 0.0;
                self.free.push(jdx);
            }
        }
        self.free.len() < n
    }

    /// Cholesky factor of `H_FF` (the free variables' Hessian) into `hff`; false when not positive
    /// definite.
    fn factor_free_hessian(&mut self, qp: &DenseQp) -> bool {
        let n = self.n;
        let nf = self.free.len();
        // Cholesky of H_FF (right-looking, column-major nf × nf in `hff`)
        let max_diag = (0..n).fold(0.0f64, |m, j| m.max(qp.h[(j, j)].abs()));
        let pivot_min = 1e-14 * max_diag.max(f64::MIN_POSITIVE);
        for (c, &jc) in self.free.iter().enumerate() {
            for (r, &jr) in self.free.iter().enumerate() {
                self.hff[r + c * nf] = 0.5 * (qp.h[(jr, jc)] + qp.h[(jc, jr)]);
            }
        }
        cholesky_lower(&mut self.hff[..nf * nf], nf, pivot_min)
    }

    /// The primal point of the guess: the minimum of the cost on the free variables subject to the active
    /// rows (range-space method on `L_F`, Householder QR of `L_F⁻¹ N_F`); false on a dependent or
    /// non-finite system.
    fn guess_primal(&mut self, qp: &DenseQp, reduced: bool) -> bool {
        let n = self.n;
        let nrow = self.me + self.mi;
        let nf = self.free.len();
        let l: &[f64] = if reduced {
            &self.hff[..nf * nf]
        } else {
            &self.chol[..n * n]
        };
        // reduced gradient g_F + H_FB x_B (into y), then x0_F = -H_FF^{-1} (.) into tmp
        for (r, &jr) in self.free.iter().enumerate() {
            let mut s = qp.g[jr];
            if reduced {
                for jdx in 0..n {
                    if self.is_active[nrow + jdx] {
                        s += qp.h[(jr, jdx)] * self.x[jdx];
                    }
                }
            }
            self.tmp[r] = -s;
        }
        Self::forward_l(l, nf, &mut self.tmp[..nf], 0);
        Self::backward_lt(l, nf, &mut self.tmp[..nf]);
        // active rows (not bounds): M = L_F^{-1} N_F, column by column; rhs w = b' - n_F·x0_F
        let mut qr_cols = 0;
        for k in 0..self.active.len() {
            let Active { slot, sign } = self.active[k];
            if slot >= nrow {
                continue;
            }
            let rhs = self.signed_rhs(qp, slot, sign);
            let normal = &self.nt[slot * n..(slot + 1) * n];
            let col = &mut self.qr[qr_cols * nf..(qr_cols + 1) * nf];
            let mut fixed_part = 0.0;
            if reduced {
                for (jdx, nv) in normal.iter().enumerate() {
                    if self.is_active[nrow + jdx] {
                        fixed_part += nv * self.x[jdx];
                    }
                }
            }
            let mut dot_x0 = 0.0;
            for (r, &jr) in self.free.iter().enumerate() {
                col[r] = sign * normal[jr];
                dot_x0 += col[r] * self.tmp[r];
            }
            self.rv[qr_cols] = rhs - sign * fixed_part - dot_x0;
            Self::forward_l(l, nf, col, 0);
            self.colnorm[qr_cols] = col.iter().map(|v| v * v).sum::<f64>().sqrt();
            qr_cols += 1;
        }
        let q = qr_cols;
        if q > nf {
            return false;
        }
        // Householder QR in place (nf × q)
        let dep = self.settings.dependence_tolerance;
        for k in 0..q {
            let (head, tail) = self.qr.split_at_mut((k + 1) * nf);
            let vk = &mut head[k * nf + k..(k + 1) * nf];
            let normx = vk.iter().map(|v| v * v).sum::<f64>().sqrt();
            if normx.is_nan() || normx == 0.0 || normx <= dep * self.colnorm[k] {
                return false;
            }
            let alpha = if vk[0] > 0.0 { -normx } else { normx };
            vk[0] -= alpha;
            let vtv: f64 = vk.iter().map(|v| v * v).sum();
            let beta = 2.0 / vtv;
            self.tau[k] = beta;
            self.rdiag[k] = alpha;
            for jcol in 0..q - k - 1 {
                let cj = &mut tail[jcol * nf + k..(jcol + 1) * nf];
                let s: f64 = vk.iter().zip(cj.iter()).map(|(a, b)| a * b).sum();
                let f = beta * s;
                for (c, v) in cj.iter_mut().zip(vk.iter()) {
                    *c -= f * v;
                }
            }
        }
        // Rᵀ v = w (in place in rv), then u_rows = R^{-1} v (into z scratch)
        for k in 0..q {
            let s: f64 = self.qr[k * nf..k * nf + k]
                .iter()
                .zip(&self.rv[..k])
                .map(|(a, b)| a * b)
                .sum();
            self.rv[k] = (self.rv[k] - s) / self.rdiag[k];
        }
        for i in (0..q).rev() {
            let mut s = self.rv[i];
            for k in i + 1..q {
                s -= self.qr[i + k * nf] * self.z[k];
            }
            self.z[i] = s / self.rdiag[i];
        }
        // y = Q [v; 0]; x_F = x0_F + L_F^{-T} y
        self.y[..nf].fill(0.0);
        self.y[..q].copy_from_slice(&self.rv[..q]);
        for k in (0..q).rev() {
            let vk = &self.qr[k * nf + k..(k + 1) * nf];
            let yk = &mut self.y[k..nf];
            let s: f64 = vk.iter().zip(yk.iter()).map(|(a, b)| a * b).sum();
            let f = self.tau[k] * s;
            for (yv, v) in yk.iter_mut().zip(vk) {
                *yv -= f * v;
            }
        }
        Self::backward_lt(l, nf, &mut self.y[..nf]);
        for (r, &jr) in self.free.iter().enumerate() {
            self.x[jr] = self.tmp[r] + self.y[r];
        }
        if !self.x[..n].iter().all(|v| v.is_finite()) {
            return false;
        }
        true
    }

    /// The multipliers of the guess (rows from the QR solve, bounds from stationarity); true when they
    /// are dual feasible and no constraint is violated.
    fn guess_multipliers(&mut self, qp: &DenseQp) -> bool {
        let n = self.n;
        let nrow = self.me + self.mi;
        // multipliers in active order: rows from z, bounds from stationarity
        // (H x + g − Σ_rows u_k n⁺_k)_j = u_j · sign_j
        let mut row_k = 0;
        for k in 0..self.active.len() {
            if self.active[k].slot < nrow {
                self.u[k] = self.z[row_k];
                row_k += 1;
            }
        }
        for k in 0..self.active.len() {
            let Active { slot, sign } = self.active[k];
            if slot < nrow {
                continue;
            }
            let jdx = slot - nrow;
            let mut s = qp.g[jdx];
            for c in 0..n {
                s += qp.h[(jdx, c)] * self.x[c];
            }
            for kk in 0..self.active.len() {
                let a = self.active[kk];
                if a.slot < nrow {
                    s -= self.u[kk] * a.sign * self.nt[a.slot * n + jdx];
                }
            }
            self.u[k] = sign * s;
        }
        let umax = self.u[..self.active.len()]
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        for k in 0..self.active.len() {
            if self.active[k].slot >= self.me
                && (self.u[k] < -1e-10 * (1.0 + umax) || self.u[k].is_nan())
            {
                return false;
            }
        }
        self.most_violated(qp).is_none()
    }

    /// `d = sign · Jᵀ n(slot)`.
    fn compute_d(&mut self, slot: usize, sign: f64) {
        let n = self.n;
        let nrow = self.me + self.mi;
        if slot < nrow {
            let col = &self.nt[slot * n..(slot + 1) * n];
            let j = if self.j_is_j0 { &self.j0 } else { &self.j };
            for k in 0..n {
                let jc = &j[k * n..(k + 1) * n];
                let mut s = 0.0;
                for (a, b) in jc.iter().zip(col) {
                    s += a * b;
                }
                self.d[k] = sign * s;
            }
        } else {
            let row = slot - nrow;
            let j = if self.j_is_j0 { &self.j0 } else { &self.j };
            for k in 0..n {
                self.d[k] = sign * j[row + k * n];
            }
        }
    }

    /// `n(slot) · x` (without sign).
    fn normal_dot(&self, slot: usize, x: &[f64]) -> f64 {
        let n = self.n;
        let nrow = self.me + self.mi;
        if slot < nrow {
            self.nt[slot * n..(slot + 1) * n]
                .iter()
                .zip(&x[..n])
                .map(|(a, b)| a * b)
                .sum()
        } else {
            x[slot - nrow]
        }
    }

    /// Right-hand side `b` of slot in the `sign · n·x ≥ sign · b` form, i.e. returns `sign · rhs`.
    fn signed_rhs(&self, qp: &DenseQp, slot: usize, sign: f64) -> f64 {
        let nrow = self.me + self.mi;
        if slot < self.me {
            sign * qp.f[slot]
        } else if slot < nrow {
            let i = slot - self.me;
            if sign > 0.0 {
                qp.l[i]
            } else {
                -qp.u[i]
            }
        } else {
            let jdx = slot - nrow;
            if sign > 0.0 {
                qp.lb[jdx]
            } else {
                -qp.ub[jdx]
            }
        }
    }

    /// `z = J₂ d₂` (columns q..n); returns `‖d₂‖²` (= zᵀn⁺) and `‖d‖²`.
    fn compute_z(&mut self, q: usize) -> (f64, f64) {
        let n = self.n;
        let z = &mut self.z[..n];
        let j = if self.j_is_j0 { &self.j0 } else { &self.j };
        z.fill(0.0);
        let mut zn = 0.0;
        let mut dn = 0.0;
        for k in 0..n {
            let dk = self.d[k];
            dn += dk * dk;
            if k >= q {
                zn += dk * dk;
                if dk != 0.0 {
                    for (a, b) in z.iter_mut().zip(&j[k * n..(k + 1) * n]) {
                        *a += dk * b;
                    }
                }
            }
        }
        (zn, dn)
    }

    /// `rv = R⁻¹ d₁` (q × q upper triangular).
    fn compute_r(&mut self, q: usize) {
        let n = self.n;
        for i in (0..q).rev() {
            let mut s = self.d[i];
            for k in i + 1..q {
                s -= self.r[i + k * n] * self.rv[k];
            }
            self.rv[i] = s / self.r[i + i * n];
        }
    }

    /// Appends the constraint whose `d` is current as column `q` of R. False if it is dependent.
    fn add_constraint(&mut self, q: usize) -> bool {
        let n = self.n;
        let dnorm: f64 = self.d[..n].iter().map(|v| v * v).sum::<f64>().sqrt();
        for i in (q + 1..n).rev() {
            let a = self.d[i - 1];
            let b = self.d[i];
            if b == 0.0 {
                continue;
            }
            let h = (a * a + b * b).sqrt();
            let (c, s) = (a / h, b / h);
            self.d[i - 1] = h;
            self.d[i] = 0.0;
            self.own_j();
            let (left, right) = self.j.split_at_mut(i * n);
            let col_a = &mut left[(i - 1) * n..i * n];
            let col_b = &mut right[..n];
            for (ja, jb) in col_a.iter_mut().zip(col_b.iter_mut()) {
                let (va, vb) = (*ja, *jb);
                *ja = c * va + s * vb;
                *jb = -s * va + c * vb;
            }
        }
        if self.d[q].is_nan() || self.d[q].abs() <= self.settings.dependence_tolerance * dnorm {
            return false;
        }
        for i in 0..=q {
            self.r[i + q * n] = self.d[i];
        }
        true
    }

    /// Removes active constraint `k` (of `q`), restoring R triangular with Givens rotations on J.
    fn drop_constraint(&mut self, k: usize, q: usize) {
        let n = self.n;
        // shift columns k+1..q of R one to the left
        for col in k + 1..q {
            for i in 0..=col {
                self.r[i + (col - 1) * n] = self.r[i + col * n];
            }
        }
        for jcol in k..q - 1 {
            let a = self.r[jcol + jcol * n];
            let b = self.r[jcol + 1 + jcol * n];
            if b != 0.0 {
                let h = (a * a + b * b).sqrt();
                let (c, s) = (a / h, b / h);
                self.r[jcol + jcol * n] = h;
                self.r[jcol + 1 + jcol * n] = 0.0;
                for col in jcol + 1..q - 1 {
                    let va = self.r[jcol + col * n];
                    let vb = self.r[jcol + 1 + col * n];
                    self.r[jcol + col * n] = c * va + s * vb;
                    self.r[jcol + 1 + col * n] = -s * va + c * vb;
                }
                self.own_j();
                let (left, right) = self.j.split_at_mut((jcol + 1) * n);
                let col_a = &mut left[jcol * n..(jcol + 1) * n];
                let col_b = &mut right[..n];
                for (ja, jb) in col_a.iter_mut().zip(col_b.iter_mut()) {
                    let (va, vb) = (*ja, *jb);
                    *ja = c * va + s * vb;
                    *jb = -s * va + c * vb;
                }
            }
        }
        let removed = self.active.remove(k);
        self.is_active[removed.slot] = false;
        for i in k..q - 1 {
            self.u[i] = self.u[i + 1];
        }
        self.u[q - 1] = 0.0;
    }

    /// Unconstrained minimiser into `x`: `x = −J Jᵀ g` (any J with J Jᵀ = H⁻¹).
    fn unconstrained(&mut self, qp: &DenseQp) {
        let n = self.n;
        let j = if self.j_is_j0 { &self.j0 } else { &self.j };
        for k in 0..n {
            let jc = &j[k * n..(k + 1) * n];
            self.tmp[k] = jc.iter().zip(qp.g.iter()).map(|(a, b)| a * b).sum();
        }
        let x = &mut self.x[..n];
        x.fill(0.0);
        for k in 0..n {
            let t = self.tmp[k];
            for (a, b) in x.iter_mut().zip(&j[k * n..(k + 1) * n]) {
                *a -= t * b;
            }
        }
    }

    /// [`Self::unconstrained`] right after [`Self::reset_state`], when `J = J₀ = L⁻ᵀ` is upper triangular:
    /// column `k` of `J` is zero below row `k`, so the sums and updates stop at row `k`. With a finite `g`
    /// and finite `Jᵀ g` that is the full form bit for bit: a dropped term `0 · g_r` is `±0`, which leaves a
    /// nonzero sum as it is and can only change the sign of a zero `(Jᵀ g)_k`; the dropped updates
    /// `x_r −= (Jᵀ g)_k · 0` subtract `±0`, which leaves every `x_r` as it is (`x` starts at `+0` and an
    /// update never makes it `−0`), and so does a zero `(Jᵀ g)_k` of either sign. Otherwise (a NaN or
    /// infinity, which `0 · ∞` would spread) the full form.
    fn unconstrained_cold(&mut self, qp: &DenseQp) {
        let n = self.n;
        let g = &qp.g.as_slice()[..n];
        if !g.iter().all(|v| v.is_finite()) {
            return self.unconstrained(qp);
        }
        let j = &self.j0;
        for k in 0..n {
            let jc = &j[k * n..k * n + k + 1];
            self.tmp[k] = jc.iter().zip(g).map(|(a, b)| a * b).sum();
        }
        if !self.tmp[..n].iter().all(|v| v.is_finite()) {
            return self.unconstrained(qp);
        }
        let x = &mut self.x[..n];
        x.fill(0.0);
        for k in 0..n {
            let t = self.tmp[k];
            for (a, b) in x[..=k].iter_mut().zip(&j[k * n..k * n + k + 1]) {
                *a -= t * b;
            }
        }
    }

    /// The most violated inactive inequality side or bound: `(slot, sign, signed slack < 0)`.
    fn most_violated(&self, qp: &DenseQp) -> Option<(usize, f64, f64)> {
        let tol = self.settings.feasibility_tolerance;
        let mut best: Option<(usize, f64, f64)> = None;
        let mut best_measure = 0.0;
        let mut consider = |slot: usize, sign: f64, slack: f64, rhs: f64, norm: f64| {
            let measure = -slack / norm;
            if measure > tol * (1.0 + rhs.abs() / norm) && measure > best_measure {
                best_measure = measure;
                best = Some((slot, sign, slack));
            }
        };
        let n = self.n;
        for i in 0..self.mi {
            let slot = self.me + i;
            if self.is_active[slot] {
                continue;
            }
            let norm = self.norms[slot];
            if norm == 0.0 {
                continue;
            }
            let v = self.normal_dot(slot, &self.x);
            if qp.l[i].is_finite() {
                consider(slot, 1.0, v - qp.l[i], qp.l[i], norm);
            }
            if qp.u[i].is_finite() {
                consider(slot, -1.0, qp.u[i] - v, qp.u[i], norm);
            }
        }
        let nrow = self.me + self.mi;
        for jdx in 0..n {
            let slot = nrow + jdx;
            if self.is_active[slot] {
                continue;
            }
            let v = self.x[jdx];
            if qp.lb[jdx].is_finite() {
                consider(slot, 1.0, v - qp.lb[jdx], qp.lb[jdx], 1.0);
            }
            if qp.ub[jdx].is_finite() {
                consider(slot, -1.0, qp.ub[jdx] - v, qp.ub[jdx], 1.0);
            }
        }
        best
    }

    fn max_iterations(&self) -> usize {
        if self.settings.max_iterations > 0 {
            self.settings.max_iterations
        } else {
            3 * (2 * self.n + self.me + self.mi) + 50
        }
    }

    /// `J = J₀`, no active constraint, `u = 0`. `J` is not copied: it is read from `j0` until a rotation
    /// needs its own copy ([`Self::own_j`]); most cold solves of the whole-body problems add no constraint.
    fn reset_state(&mut self) {
        self.compute_j0();
        let n = self.n;
        self.j_is_j0 = true;
        self.active.clear();
        for v in &mut self.is_active {
            *v = false;
        }
        self.u[..n].fill(0.0);
    }

    /// Makes `j` hold `J` before a rotation changes it (a copy of `J₀` after [`Self::reset_state`]).
    fn own_j(&mut self) {
        if self.j_is_j0 {
            let n = self.n;
            self.j[..n * n].copy_from_slice(&self.j0[..n * n]);
            self.j_is_j0 = false;
        }
    }

    /// Checks an equality row that was skipped as dependent: true if it holds at `x`.
    fn equality_holds(&self, qp: &DenseQp, i: usize) -> bool {
        let v = self.normal_dot(i, &self.x);
        let norm = self.norms[i].max(f64::MIN_POSITIVE);
        (v - qp.f[i]).abs() / norm
            <= 10.0 * self.settings.feasibility_tolerance * (1.0 + qp.f[i].abs() / norm)
    }

    /// Cold start: unconstrained minimum, then equalities with full steps, then the dual iterations.
    fn run_cold(&mut self, qp: &DenseQp) -> Run {
        self.reset_state();
        self.unconstrained_cold(qp);
        let tol = self.settings.feasibility_tolerance;
        let dep = self.settings.dependence_tolerance;
        for i in 0..self.me {
            let q = self.active.len();
            let s_raw = self.normal_dot(i, &self.x) - qp.f[i];
            let sign = if s_raw > 0.0 { -1.0 } else { 1.0 };
            let s = sign * s_raw;
            self.compute_d(i, sign);
            let (zn, dn) = self.compute_z(q);
            if zn <= dep * dep * dn {
                let norm = self.norms[i].max(f64::MIN_POSITIVE);
                if -s / norm <= 10.0 * tol * (1.0 + qp.f[i].abs() / norm) {
                    continue; // redundant and consistent
                }
                return Run::Done(QpStatus::Infeasible);
            }
            let t = -s / zn;
            for (xv, zv) in self.x[..self.n].iter_mut().zip(&self.z[..self.n]) {
                *xv += t * zv;
            }
            if q > 0 {
                self.compute_r(q);
                for k in 0..q {
                    self.u[k] -= t * self.rv[k];
                }
            }
            if !self.add_constraint(q) {
                return Run::Done(QpStatus::NumericalError);
            }
            self.u[q] = t;
            self.active.push(Active { slot: i, sign });
            self.is_active[i] = true;
            self.iterations += 1;
        }
        Run::Done(self.dual_iterations(qp))
    }

    /// Warm start: re-impose equalities and the previous active set, closed-form x/u, drop negative
    /// multipliers, then the dual iterations.
    fn run_warm(&mut self, qp: &DenseQp) -> Run {
        self.reset_state();
        let dep = self.settings.dependence_tolerance;
        for i in 0..self.me {
            let q = self.active.len();
            self.compute_d(i, 1.0);
            let (zn, dn) = self.compute_z(q);
            if zn <= dep * dep * dn {
                continue;
            }
            if !self.add_constraint(q) {
                return Run::WarmFailed;
            }
            self.active.push(Active { slot: i, sign: 1.0 });
            self.is_active[i] = true;
        }
        let nslots = self.me + self.mi + self.n;
        for idx in 0..self.prev.len() {
            let Active { slot, sign } = self.prev[idx];
            if slot < self.me || slot >= nslots || self.is_active[slot] {
                continue;
            }
            if !self.signed_rhs(qp, slot, sign).is_finite() {
                continue;
            }
            let q = self.active.len();
            if q >= self.n {
                break;
            }
            self.compute_d(slot, sign);
            let (zn, dn) = self.compute_z(q);
            if zn <= dep * dep * dn {
                continue;
            }
            if !self.add_constraint(q) {
                return Run::WarmFailed;
            }
            self.active.push(Active { slot, sign });
            self.is_active[slot] = true;
        }
        loop {
            self.closed_form(qp);
            let mut worst: Option<usize> = None;
            let mut worst_u = 0.0;
            for k in 0..self.active.len() {
                if self.active[k].slot >= self.me && self.u[k] < worst_u {
                    worst_u = self.u[k];
                    worst = Some(k);
                }
            }
            match worst {
                Some(k) => {
                    let q = self.active.len();
                    self.drop_constraint(k, q);
                }
                None => break,
            }
        }
        for i in 0..self.me {
            if !self.is_active[i] && !self.equality_holds(qp, i) {
                return Run::WarmFailed;
            }
        }
        match self.dual_iterations(qp) {
            QpStatus::Solved => Run::Done(QpStatus::Solved),
            _ => Run::WarmFailed,
        }
    }

    /// Given J, R of the active set: `x = x₀ + J₁ v`, `u = R⁻¹ v` with `Rᵀ v = b_A − N_Aᵀ x₀`.
    fn closed_form(&mut self, qp: &DenseQp) {
        let n = self.n;
        let q = self.active.len();
        self.unconstrained(qp);
        // w_k = b_k - n_k·x0 (signed), then forward substitution Rᵀ v = w (v stored in rv)
        for k in 0..q {
            let Active { slot, sign } = self.active[k];
            let w = self.signed_rhs(qp, slot, sign) - sign * self.normal_dot(slot, &self.x);
            let mut s = w;
            for i in 0..k {
                s -= self.r[i + k * n] * self.rv[i];
            }
            self.rv[k] = s / self.r[k + k * n];
        }
        let j = if self.j_is_j0 { &self.j0 } else { &self.j };
        for k in 0..q {
            let vk = self.rv[k];
            for (a, b) in self.x[..n].iter_mut().zip(&j[k * n..(k + 1) * n]) {
                *a += vk * b;
            }
        }
        // u = R^{-1} v
        for i in (0..q).rev() {
            let mut s = self.rv[i];
            for k in i + 1..q {
                s -= self.r[i + k * n] * self.u[k];
            }
            self.u[i] = s / self.r[i + i * n];
        }
    }

    /// The Goldfarb–Idnani iterations from a dual-feasible (x, active set, u).
    fn dual_iterations(&mut self, qp: &DenseQp) -> QpStatus {
        let max_iter = self.max_iterations();
        let dep = self.settings.dependence_tolerance;
        let n = self.n;
        loop {
            if self.iterations >= max_iter {
                return QpStatus::MaxIterations;
            }
            let Some((slot, sign, mut slack)) = self.most_violated(qp) else {
                return QpStatus::Solved;
            };
            let mut u_new = 0.0;
            self.compute_d(slot, sign);
            loop {
                let q = self.active.len();
                let (zn, dn) = self.compute_z(q);
                self.compute_r(q);
                let mut t1 = f64::INFINITY;
                let mut kdrop = usize::MAX;
                for k in 0..q {
                    if self.active[k].slot >= self.me && self.rv[k] > 0.0 {
                        let ratio = self.u[k] / self.rv[k];
                        if ratio < t1 {
                            t1 = ratio;
                            kdrop = k;
                        }
                    }
                }
                let t2 = if zn > dep * dep * dn {
                    -slack / zn
                } else {
                    f64::INFINITY
                };
                if t1.is_infinite() && t2.is_infinite() {
                    return QpStatus::Infeasible;
                }
                self.iterations += 1;
                if self.iterations > max_iter {
                    return QpStatus::MaxIterations;
                }
                let t = t1.min(t2);
                for k in 0..q {
                    self.u[k] -= t * self.rv[k];
                }
                u_new += t;
                if t2.is_finite() {
                    for (xv, zv) in self.x[..n].iter_mut().zip(&self.z[..n]) {
                        *xv += t * zv;
                    }
                }
                if t2 <= t1 {
                    if q >= n || !self.add_constraint(q) {
                        return QpStatus::NumericalError;
                    }
                    self.u[q] = u_new;
                    self.active.push(Active { slot, sign });
                    self.is_active[slot] = true;
                    break;
                }
                self.u[kdrop] = 0.0;
                self.drop_constraint(kdrop, q);
                slack = sign * self.normal_dot(slot, &self.x) - self.signed_rhs(qp, slot, sign);
                if slack > 0.0 {
                    // Round-off made p (just) satisfied by the partial steps. It still carries the multiplier
                    // u_new in stationarity, so it must become active: continue with a zero full step.
                    slack = 0.0;
                }
                self.compute_d(slot, sign);
            }
            if !self.x[..n].iter().all(|v| v.is_finite()) {
                return QpStatus::NumericalError;
            }
        }
    }
}

impl QpSolver for ActiveSetSolver {
    fn name(&self) -> &'static str {
        "active_set"
    }

    fn solve(&mut self, qp: &DenseQp, out: &mut SolverOutput) {
        out.prepare(qp);
        if !qp.is_valid() {
            out.status = QpStatus::InvalidData;
            self.prev.clear();
            return;
        }
        let (n, me, mi) = (qp.n(), qp.n_eq(), qp.n_ineq());
        self.ensure_workspace(n, me, mi);
        self.load_rows(qp);
        if !self.factorize(qp) {
            out.status = QpStatus::HessianNotPositiveDefinite;
            self.prev.clear();
            return;
        }
        self.iterations = 0;
        self.warm_used = false;
        let can_warm = self.settings.warm_start
            && self.prev_dims == (n, me, mi)
            && (!self.prev.is_empty() || !self.reimpose);
        let mut status = None;
        self.last_start = StartKind::Cold;
        if can_warm {
            if self.try_guess(qp) {
                self.warm_used = true;
                self.last_start = StartKind::Guess;
                status = Some(QpStatus::Solved);
            } else if !self.reimpose {
                self.iterations = 0;
            } else if let Run::Done(s) = self.run_warm(qp) {
                self.warm_used = true;
                self.last_start = StartKind::Reimposed;
                status = Some(s);
            } else {
                self.iterations = 0;
            }
        }
        let status = match status {
            Some(s) => s,
            None => match self.run_cold(qp) {
                Run::Done(s) => s,
                Run::WarmFailed => QpStatus::NumericalError,
            },
        };
        out.status = status;
        out.iterations = self.iterations;
        out.warm_started = self.warm_used;
        self.prev.clear();
        if status == QpStatus::Solved {
            for jdx in 0..n {
                out.x[jdx] = self.x[jdx];
            }
            let nrow = me + mi;
            for (k, a) in self.active.iter().enumerate() {
                let m = -a.sign * self.u[k];
                if a.slot < me {
                    out.y[a.slot] = m;
                } else if a.slot < nrow {
                    out.z[a.slot - me] = m;
                } else {
                    out.bound_multipliers[a.slot - nrow] = m;
                }
            }
            out.objective = qp.objective_noalloc(&out.x);
            self.prev.extend_from_slice(&self.active);
            self.prev_dims = (n, me, mi);
        }
        out.sanitize();
        if !out.status.is_success() {
            self.prev.clear();
        }
    }

    fn reset(&mut self) {
        self.prev.clear();
        // the next solve starts cold, as the first one did (without this a guess-or-cold solver would
        // try the empty active set)
        self.prev_dims = (usize::MAX, 0, 0);
    }

    fn reserve(&mut self, n: usize, n_eq: usize, n_ineq: usize) {
        self.ensure_workspace(n, n_eq, n_ineq);
    }
}

/// Cholesky factor in place of the lower triangle of the `n × n` column-major `l` (the strict upper
/// triangle is neither read nor written); false at the first pivot that is NaN or `≤ pivot_min`.
///
/// Left-looking and register-tiled: column `k` is `l[k.., k] − Σ_{c<k} l[k, c] l[k.., c]` (the terms with
/// `l[k, c] = 0` skipped), summed over `c` in ascending order, then divided by the square root of its
/// pivot, tile by tile of [`kernels::TILE`] rows held in registers. That is every entry's sequence of
/// operations in the right-looking rank-one form (`l[k.., k] −= l[k, c] l[k.., c]` after column `c` is
/// final), so the factor is the same bit for bit, with a fraction of the loads and stores (the test
/// below keeps the rank-one form as the reference).
fn cholesky_lower(l: &mut [f64], n: usize, pivot_min: f64) -> bool {
    for k in 0..n {
        let (done, rest) = l.split_at_mut(k * n);
        let col = &mut rest[..n];
        let mut s = 1.0;
        for (r0, width) in kernels::tiles(k..n) {
            match width {
                kernels::TILE => cholesky_tile::<{ kernels::TILE }>(done, n, k, r0, col),
                4 => cholesky_tile::<4>(done, n, k, r0, col),
                2 => cholesky_tile::<2>(done, n, k, r0, col),
                _ => cholesky_tile::<1>(done, n, k, r0, col),
            }
            if r0 == k {
                let piv = col[k];
                if piv.is_nan() || piv <= pivot_min {
                    return false;
                }
                s = piv.sqrt();
            }
            for v in &mut col[r0..r0 + width] {
                *v /= s;
            }
        }
    }
    true
}

/// Rows `r0..r0 + W` of column `k` (`col`): minus the products with the final columns `0..k` (`done`).
fn cholesky_tile<const W: usize>(done: &[f64], n: usize, k: usize, r0: usize, col: &mut [f64]) {
    let mut acc = [0.0; W];
    acc.copy_from_slice(&col[r0..r0 + W]);
    for c in 0..k {
        let f = done[c * n + k];
        if f == 0.0 {
            continue;
        }
        let src = &done[c * n + r0..c * n + r0 + W];
        for t in 0..W {
            acc[t] -= f * src[t];
        }
    }
    col[r0..r0 + W].copy_from_slice(&acc);
}

#[cfg(test)]
mod tests {
    use super::cholesky_lower;

    /// A reproducible stream of uniform numbers in `[0, 1)` (a linear congruential generator).
    fn uniform_stream(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// The cold start's unconstrained minimum over the triangular `J₀` is the full `x = −J Jᵀ g` bit for
    /// bit, with zeros of either sign in `g` and a gradient orthogonal to columns of `J₀`; and a
    /// non-finite `g` gives the full form's non-finite `x`.
    #[test]
    fn the_cold_unconstrained_minimum_is_the_full_form_bit_for_bit() {
        use super::{ActiveSetSettings, ActiveSetSolver};
        use crate::dense::DenseQp;
        let mut next = uniform_stream(5);
        for n in [1, 2, 3, 8, 9, 25, 31] {
            let b: Vec<f64> = (0..n * n)
                .map(|_| {
                    let u = next();
                    if u < 0.3 {
                        0.0
                    } else {
                        2.0 * u - 1.0
                    }
                })
                .collect();
            let mut qp = DenseQp::new(n, 0, 0);
            for c in 0..n {
                for r in 0..n {
                    qp.h[(r, c)] = (0..n).map(|i| b[r + i * n] * b[c + i * n]).sum::<f64>();
                }
                qp.h[(c, c)] += 1e-2;
            }
            let gradients: Vec<Vec<f64>> = vec![
                (0..n).map(|_| 2.0 * next() - 1.0).collect(),
                (0..n)
                    .map(|i| match i % 3 {
                        0 => 0.0,
                        1 => -0.0,
                        _ => 2.0 * next() - 1.0,
                    })
                    .collect(),
                (0..n)
                    .map(|i| if i + 1 == n { 1.0 } else { -0.0 })
                    .collect(),
                (0..n).map(|_| 0.0).collect(),
                (0..n)
                    .map(|i| if i == 0 { f64::INFINITY } else { 1.0 })
                    .collect(),
                (0..n)
                    .map(|i| if i + 1 == n { f64::NAN } else { 1.0 })
                    .collect(),
            ];
            for g in gradients {
                qp.g.copy_from_slice(&g);
                let mut solver = ActiveSetSolver::new(ActiveSetSettings::default());
                solver.ensure_workspace(n, 0, 0);
                assert!(solver.factorize(&qp), "n {n}");
                solver.reset_state();
                solver.unconstrained(&qp);
                let full = solver.x[..n].to_vec();
                solver.x[..n].fill(7.0);
                solver.unconstrained_cold(&qp);
                for (k, (x, y)) in solver.x[..n].iter().zip(&full).enumerate() {
                    if y.is_nan() {
                        assert!(x.is_nan(), "n {n}, entry {k}: {x}");
                    } else {
                        assert_eq!(x.to_bits(), y.to_bits(), "n {n}, entry {k}: {x} vs {y}");
                    }
                }
            }
        }
    }

    /// The right-looking rank-one form the tiled factorization replaced.
    fn cholesky_reference(l: &mut [f64], n: usize, pivot_min: f64) -> bool {
        for c in 0..n {
            let piv = l[c + c * n];
            if piv.is_nan() || piv <= pivot_min {
                return false;
            }
            let s = piv.sqrt();
            for v in &mut l[c + c * n..(c + 1) * n] {
                *v /= s;
            }
            for k in c + 1..n {
                let f = l[k + c * n];
                if f != 0.0 {
                    let (left, right) = l.split_at_mut(k * n);
                    for (a, b) in right[k..n].iter_mut().zip(&left[c * n + k..c * n + n]) {
                        *a -= f * b;
                    }
                }
            }
        }
        true
    }

    /// `B Bᵀ + δ I` with a third of `B`'s entries zero (sizes across the tile widths), and one matrix
    /// that is not positive definite: same factor bit for bit (lower triangle), same verdict.
    #[test]
    fn the_tiled_cholesky_is_the_rank_one_form_bit_for_bit() {
        let mut uniform = uniform_stream(7);
        let mut next = || {
            let u = uniform();
            if u < 1.0 / 3.0 {
                0.0
            } else {
                2.0 * u - 1.0
            }
        };
        for n in [1, 2, 3, 5, 8, 9, 17, 26, 32, 41] {
            let b: Vec<f64> = (0..n * n).map(|_| next()).collect();
            let mut h = vec![0.0; n * n];
            for c in 0..n {
                for r in 0..n {
                    h[r + c * n] = (0..n).map(|i| b[r + i * n] * b[c + i * n]).sum::<f64>();
                }
                h[c + c * n] += 1e-3;
            }
            for indefinite in [false, true] {
                let mut a = h.clone();
                if indefinite {
                    a[(n - 1) * (n + 1)] = -1.0;
                }
                let mut expected = a.clone();
                let ok = cholesky_reference(&mut expected, n, 1e-14);
                let got = cholesky_lower(&mut a, n, 1e-14);
                assert_eq!(got, ok, "n {n}, indefinite {indefinite}");
                assert_eq!(got, !indefinite, "n {n}");
                if ok {
                    for c in 0..n {
                        for r in c..n {
                            let (x, y) = (a[r + c * n], expected[r + c * n]);
                            assert_eq!(x.to_bits(), y.to_bits(), "n {n}, entry ({r}, {c})");
                        }
                    }
                }
            }
        }
    }
}
