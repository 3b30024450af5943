//! A primal–dual interior-point method (Mehrotra predictor–corrector) for convex QPs whose Hessian is
//! banded and whose constraint rows each touch a few neighbouring variables:
//!
//! `min ½ xᵀPx + qᵀx  s.t.  Cx ≤ d`
//!
//! Each Newton system `(P + Cᵀ diag(λ/s) C) Δx = r` stays banded and is solved by a banded Cholesky in
//! `O(n b²)`. All memory is allocated in `new`; `solve` allocates nothing.

// Band algorithms index several arrays with the same loop counter; ranges read like the maths.
#![allow(clippy::needless_range_loop)]

/// A sparse constraint row with at most [`MAX_ROW_ENTRIES`] non-zeros (the expanded form of a
/// [`HalfPlaneRow`], for the general-purpose solvers).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct SparseRow {
    pub(crate) columns: [usize; MAX_ROW_ENTRIES],
    pub(crate) values: [f64; MAX_ROW_ENTRIES],
    pub(crate) len: usize,
    pub(crate) bound: f64,
}

/// Most non-zeros of an expanded constraint row.
pub(crate) const MAX_ROW_ENTRIES: usize = 2 * MAX_POINT_TERMS;

/// Most terms of a [`PointGroup`]'s point.
pub(crate) const MAX_POINT_TERMS: usize = 2;

/// A group of constraint rows that all constrain one 2-D point built linearly from the variables,
/// `z = Σ_t coefficients[t] · (x[columns[t]], x[columns[t] + 1])` (distinct, even-aligned pairs), with
/// rows `i = first_row..end_row` reading `normal_iᵀ z ≤ bound_i`. For the DCM MPC the point is the ZMP of
/// one stage and the rows are the edges of its support polygon: products with `C` and the Newton
/// update `Cᵀ W C` then cost 2 and 3 flops per row plus a few per group, instead of 4 and 10 per row.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct PointGroup {
    pub(crate) columns: [usize; MAX_POINT_TERMS],
    pub(crate) coefficients: [f64; MAX_POINT_TERMS],
    pub(crate) terms: usize,
    pub(crate) first_row: usize,
    pub(crate) end_row: usize,
}

impl PointGroup {
    /// The group's point for the variables `x`.
    #[inline]
    fn point(&self, x: &[f64]) -> [f64; 2] {
        let mut z = [0.0; 2];
        for t in 0..self.terms {
            let c = self.columns[t];
            z[0] += self.coefficients[t] * x[c];
            z[1] += self.coefficients[t] * x[c + 1];
        }
        z
    }

    /// `out += Jᵀ g` for the point's Jacobian `J` (scatter of a 2-D vector onto the columns).
    #[inline]
    fn add_transpose(&self, g: [f64; 2], out: &mut [f64]) {
        for t in 0..self.terms {
            let c = self.columns[t];
            out[c] += self.coefficients[t] * g[0];
            out[c + 1] += self.coefficients[t] * g[1];
        }
    }
}

/// One half-plane row `normalᵀ z ≤ bound` of a [`PointGroup`].
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct HalfPlaneRow {
    pub(crate) normal: [f64; 2],
    pub(crate) bound: f64,
}

impl HalfPlaneRow {
    #[inline]
    fn dot(&self, z: [f64; 2]) -> f64 {
        self.normal[0] * z[0] + self.normal[1] * z[1]
    }
}

/// Outcome of a solve.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum IpmOutcome {
    /// The unconstrained minimiser was feasible: it is the solution (no iteration).
    Unconstrained,
    /// Converged to the tolerances.
    Converged,
    /// Hit the iteration limit.
    MaxIterations,
    /// A Newton matrix was not positive definite or a value became non-finite.
    NumericalError,
}

/// Smallest slack of a warm start (units of the rows: metres for the DCM MPC's unit-normal polygon
/// rows). Chosen on pushed walks (docs/simplified.md): 1 mm–3 mm floors gave the fewest iterations.
pub(crate) const WARM_SLACK_FLOOR: f64 = 3e-3;

/// Smallest multiplier of a warm start (cost units per row unit; the DCM MPC's multipliers are
/// ~0.1 when active, in units of `Λ_ξ`).
pub(crate) const WARM_MULTIPLIER_FLOOR: f64 = 1e-5;

/// Half-bandwidth of every band matrix here (the DCM MPC's Newton matrices, x/y interleaved).
pub(crate) const BAND: usize = 5;

/// The `(d1, d2)`, `0 ≤ d2 ≤ d1 < BAND`, of the trailing window a Cholesky column updates (a constant
/// list, so the update loop unrolls fully).
const WINDOW_PAIRS: [(usize, usize); BAND * (BAND + 1) / 2] = {
    let mut pairs = [(0, 0); BAND * (BAND + 1) / 2];
    let mut k = 0;
    let mut d1 = 0;
    while d1 < BAND {
        let mut d2 = 0;
        while d2 <= d1 {
            pairs[k] = (d1, d2);
            k += 1;
            d2 += 1;
        }
        d1 += 1;
    }
    pairs
};

/// Banded symmetric matrix (lower band, row-major, fixed half-bandwidth [`BAND`]): row `i` is an array
/// `R_i` with `R_i[c] = A(i, i − BAND + c)`, `c = 0..=BAND` (so `R_i[BAND]` is the diagonal). Entries
/// with a negative column stay zero, which lets the kernels run fixed-length loops.
#[derive(Debug, Clone)]
pub(crate) struct BandMatrix {
    pub(crate) n: usize,
    rows: Vec<[f64; BAND + 1]>,
    /// `1 / L(i,i)` after `cholesky_in_place` (divisions are the slow operation here).
    inverse_diagonal: Vec<f64>,
}

impl BandMatrix {
    pub(crate) fn new(n: usize) -> Self {
        Self {
            n,
            rows: vec![[0.0; BAND + 1]; n],
            inverse_diagonal: vec![0.0; n],
        }
    }

    /// Half-bandwidth.
    pub(crate) fn bandwidth(&self) -> usize {
        BAND
    }

    /// Adds `v` to the symmetric entry `(i, j)`, `|i − j| ≤ BAND` (stored once, in the lower band).
    #[inline]
    pub(crate) fn add(&mut self, i: usize, j: usize, v: f64) {
        let (r, c) = if i >= j { (i, j) } else { (j, i) };
        debug_assert!(r - c <= BAND);
        self.rows[r][BAND + c - r] += v;
    }

    /// Entry `(i, j)` of the symmetric matrix (zero outside the band).
    #[inline]
    pub(crate) fn get(&self, i: usize, j: usize) -> f64 {
        let (r, c) = if i >= j { (i, j) } else { (j, i) };
        if r - c > BAND {
            0.0
        } else {
            self.rows[r][BAND + c - r]
        }
    }

    /// Diagonal entry `(i, i)`.
    #[inline]
    pub(crate) fn diagonal(&self, i: usize) -> f64 {
        self.rows[i][BAND]
    }

    /// Adds `v` to the diagonal entry `(i, i)`.
    #[inline]
    pub(crate) fn add_diagonal(&mut self, i: usize, v: f64) {
        self.rows[i][BAND] += v;
    }

    pub(crate) fn fill_zero(&mut self) {
        self.rows.iter_mut().for_each(|r| *r = [0.0; BAND + 1]);
    }

    pub(crate) fn copy_from(&mut self, other: &BandMatrix) {
        self.rows.copy_from_slice(&other.rows);
    }

    /// `y = A x` for the symmetric matrix (row by row: the lower band of row `i` and the column
    /// below the diagonal, read from the next `BAND` rows; no read-modify-write chains).
    pub(crate) fn mul_vec(&self, x: &[f64], y: &mut [f64]) {
        let n = self.n.min(x.len()).min(y.len());
        for i in 0..n {
            let row = &self.rows[i];
            let mut sum = row[BAND] * x[i];
            if i >= BAND && i + BAND < n {
                let before = &x[i - BAND..i];
                for c in 0..BAND {
                    sum += row[c] * before[c];
                }
                let below = &self.rows[i + 1..=i + BAND];
                let after = &x[i + 1..=i + BAND];
                for d in 0..BAND {
                    sum += below[d][BAND - 1 - d] * after[d];
                }
            } else {
                for j in i.saturating_sub(BAND)..i {
                    sum += row[BAND + j - i] * x[j];
                }
                for k in i + 1..n.min(i + BAND + 1) {
                    sum += self.rows[k][BAND + i - k] * x[k];
                }
            }
            y[i] = sum;
        }
    }

    /// In-place Cholesky `A = L Lᵀ` (L kept in the band). Returns false if not positive definite.
    ///
    /// Right-looking (column by column): once column `j` is known, its outer product is subtracted from
    /// the trailing `BAND × BAND` window at once, written as `A(k,l) −= A(k,j) A(l,j) / A(j,j)` with the
    /// unscaled column, so the serial chain from one pivot to the next is one division, one product and
    /// one subtraction; the square root and the scaling of the column to `L(·, j)` are off that chain,
    /// and the fifteen window updates are independent of each other.
    pub(crate) fn cholesky_in_place(&mut self) -> bool {
        let n = self.n;
        for j in 0..n {
            let pivot = self.rows[j][BAND];
            if !(pivot > 0.0 && pivot.is_finite()) {
                return false;
            }
            let inverse_pivot = 1.0 / pivot;
            let root = pivot.sqrt();
            let inverse_root = root * inverse_pivot;
            self.rows[j][BAND] = root;
            self.inverse_diagonal[j] = inverse_root;
            if j + BAND < n {
                let below = &mut self.rows[j + 1..=j + BAND];
                // column[d − 1] = A(j+d, j), scaled[d − 1] = A(j+d, j) / A(j,j)
                let mut column = [0.0; BAND];
                let mut scaled = [0.0; BAND];
                for d in 0..BAND {
                    let v = below[d][BAND - 1 - d];
                    column[d] = v;
                    scaled[d] = v * inverse_pivot;
                    below[d][BAND - 1 - d] = v * inverse_root;
                }
                // A(j+1+d1, j+1+d2) −= A(j+1+d1, j) A(j+1+d2, j) / A(j,j), 0 ≤ d2 ≤ d1 < BAND
                for &(d1, d2) in &WINDOW_PAIRS {
                    below[d1][BAND - d1 + d2] -= column[d1] * scaled[d2];
                }
            } else {
                let reach = n - 1 - j;
                let mut column = [0.0; BAND];
                let mut scaled = [0.0; BAND];
                for d in 0..reach {
                    let v = self.rows[j + 1 + d][BAND - 1 - d];
                    column[d] = v;
                    scaled[d] = v * inverse_pivot;
                    self.rows[j + 1 + d][BAND - 1 - d] = v * inverse_root;
                }
                for d1 in 0..reach {
                    let row = &mut self.rows[j + 1 + d1];
                    for d2 in 0..=d1 {
                        row[BAND - d1 + d2] -= column[d1] * scaled[d2];
                    }
                }
            }
        }
        true
    }

    /// Solves `L Lᵀ x = b` in place (after `cholesky_in_place`).
    ///
    /// Both substitutions keep the `BAND` values in flight in a local window (registers once the
    /// fixed-length loops are unrolled), so the serial chain has no store-to-load round trip; the last
    /// `BAND` rows, where the band is cut by the end of the matrix, run a general loop.
    pub(crate) fn cholesky_solve(&self, b: &mut [f64]) {
        let n = self.n.min(b.len());
        let body = n.saturating_sub(BAND);
        // L y = b, column-oriented: window[d] holds b[j + d] minus the updates of the columns done.
        let mut window = [0.0; BAND];
        for (d, w) in window.iter_mut().enumerate() {
            if d < n {
                *w = b[d];
            }
        }
        for j in 0..body {
            let yj = window[0] * self.inverse_diagonal[j];
            b[j] = yj;
            let below = &self.rows[j + 1..=j + BAND];
            for d in 0..BAND - 1 {
                window[d] = window[d + 1] - below[d][BAND - 1 - d] * yj;
            }
            window[BAND - 1] = b[j + BAND] - below[BAND - 1][0] * yj;
        }
        for j in body..n {
            let yj = window[0] * self.inverse_diagonal[j];
            b[j] = yj;
            for d in 0..BAND - 1 {
                window[d] = window[d + 1];
            }
            window[BAND - 1] = 0.0;
            for d in 1..n - j {
                window[d - 1] -= self.rows[j + d][BAND - d] * yj;
            }
        }
        // Lᵀ x = y, row-oriented over Lᵀ: x_i = (y_i − Σ_d L(i+d, i) x_{i+d}) / L(i,i), with the last
        // BAND solutions kept locally (solved[d − 1] = x_{i+d}) and the newest term added last.
        let mut solved = [0.0; BAND];
        for i in (body..n).rev() {
            let mut dot = 0.0;
            for d in (1..n - i).rev() {
                dot += self.rows[i + d][BAND - d] * solved[d - 1];
            }
            let xi = (b[i] - dot) * self.inverse_diagonal[i];
            b[i] = xi;
            for d in (1..BAND).rev() {
                solved[d] = solved[d - 1];
            }
            solved[0] = xi;
        }
        for i in (0..body).rev() {
            let below = &self.rows[i + 1..=i + BAND];
            let mut dot = 0.0;
            for d in (1..=BAND).rev() {
                dot += below[d - 1][BAND - d] * solved[d - 1];
            }
            let xi = (b[i] - dot) * self.inverse_diagonal[i];
            b[i] = xi;
            for d in (1..BAND).rev() {
                solved[d] = solved[d - 1];
            }
            solved[0] = xi;
        }
    }
}

/// Settings of the interior-point method.
#[derive(Debug, Clone, Copy)]
pub(crate) struct IpmSettings {
    pub(crate) tolerance: f64,
    pub(crate) max_iterations: u32,
}

/// Workspace and problem data of the banded QP.
#[derive(Debug, Clone)]
pub(crate) struct BandedQp {
    /// `P`. Whoever changes it must call [`BandedQp::hessian_changed`].
    pub(crate) hessian: BandMatrix,
    /// Cholesky factor of `P` (for the unconstrained minimiser), reused while `P` is unchanged.
    hessian_factor: BandMatrix,
    hessian_factor_current: bool,
    /// Warm start: when `warm_start` is set, `solve` starts from `start_x` and
    /// `start_multiplier[..row_count]` (pushed into the interior) instead of the cold start. Reset by
    /// every solve.
    pub(crate) warm_start: bool,
    pub(crate) start_x: Vec<f64>,
    pub(crate) start_multiplier: Vec<f64>,
    pub(crate) gradient: Vec<f64>,
    /// Constraint rows, grouped by the point they constrain (`groups[..group_count]`, whose row ranges
    /// tile `rows[..row_count]` in order).
    pub(crate) groups: Vec<PointGroup>,
    pub(crate) group_count: usize,
    pub(crate) rows: Vec<HalfPlaneRow>,
    pub(crate) row_count: usize,
    // iterates
    pub(crate) x: Vec<f64>,
    pub(crate) slack: Vec<f64>,
    pub(crate) multiplier: Vec<f64>,
    // scratch
    newton: BandMatrix,
    residual_dual: Vec<f64>,
    residual_primal: Vec<f64>,
    dx: Vec<f64>,
    ds: Vec<f64>,
    dl: Vec<f64>,
    ds_aff: Vec<f64>,
    dl_aff: Vec<f64>,
    rhs_rows: Vec<f64>,
    transpose_product: Vec<f64>,
    inverse_slack: Vec<f64>,
}

impl BandedQp {
    /// Workspace for `n` variables (half-bandwidth [`BAND`]), at most `max_groups` row groups and at
    /// most `max_rows` constraint rows.
    pub(crate) fn new(n: usize, max_groups: usize, max_rows: usize) -> Self {
        Self {
            hessian: BandMatrix::new(n),
            hessian_factor: BandMatrix::new(n),
            hessian_factor_current: false,
            warm_start: false,
            start_x: vec![0.0; n],
            start_multiplier: vec![0.0; max_rows],
            gradient: vec![0.0; n],
            groups: vec![PointGroup::default(); max_groups],
            group_count: 0,
            rows: vec![HalfPlaneRow::default(); max_rows],
            row_count: 0,
            x: vec![0.0; n],
            slack: vec![0.0; max_rows],
            multiplier: vec![0.0; max_rows],
            newton: BandMatrix::new(n),
            residual_dual: vec![0.0; n],
            residual_primal: vec![0.0; max_rows],
            dx: vec![0.0; n],
            ds: vec![0.0; max_rows],
            dl: vec![0.0; max_rows],
            ds_aff: vec![0.0; max_rows],
            dl_aff: vec![0.0; max_rows],
            rhs_rows: vec![0.0; max_rows],
            transpose_product: vec![0.0; n],
            inverse_slack: vec![0.0; max_rows],
        }
    }

    fn n(&self) -> usize {
        self.hessian.n
    }

    /// Marks `P` as changed: the next solve refactorises it (otherwise its factor is reused).
    pub(crate) fn hessian_changed(&mut self) {
        self.hessian_factor_current = false;
    }

    /// The active constraint rows expanded to sparse rows over the variables, in row order (for the
    /// general-purpose solvers).
    pub(crate) fn sparse_rows(&self) -> impl Iterator<Item = SparseRow> + '_ {
        self.groups[..self.group_count].iter().flat_map(move |g| {
            self.rows[g.first_row..g.end_row].iter().map(move |r| {
                let mut row = SparseRow {
                    bound: r.bound,
                    ..SparseRow::default()
                };
                for t in 0..g.terms {
                    for axis in 0..2 {
                        row.columns[row.len] = g.columns[t] + axis;
                        row.values[row.len] = g.coefficients[t] * r.normal[axis];
                        row.len += 1;
                    }
                }
                row
            })
        })
    }

    /// Residuals `rd = Px + q + Cᵀλ`, `rp = Cx + s − d` at the current iterate, with the quantities
    /// the stopping rules and the step need (one pass over the rows).
    fn compute_residuals(&mut self) -> ResidualSummary {
        let mut summary = ResidualSummary::default();
        self.hessian.mul_vec(&self.x, &mut self.residual_dual);
        self.transpose_product.iter_mut().for_each(|v| *v = 0.0);
        for g in &self.groups[..self.group_count] {
            let z = g.point(&self.x);
            let mut weighted_normals = [0.0; 2];
            for i in g.first_row..g.end_row {
                let row = &self.rows[i];
                let (s, l) = (self.slack[i], self.multiplier[i]);
                let cx = row.dot(z);
                let rp = cx + s - row.bound;
                self.residual_primal[i] = rp;
                weighted_normals[0] += row.normal[0] * l;
                weighted_normals[1] += row.normal[1] * l;
                summary.row_term = summary.row_term.max(cx.abs());
                summary.primal_inf = summary.primal_inf.max(rp.abs());
                let product = s * l;
                summary.product_sum += product;
                summary.largest_product = summary.largest_product.max(product.abs());
                summary.largest_multiplier = summary.largest_multiplier.max(l);
            }
            g.add_transpose(weighted_normals, &mut self.transpose_product);
        }
        for ((r, g), t) in self
            .residual_dual
            .iter_mut()
            .zip(self.gradient.iter())
            .zip(self.transpose_product.iter())
        {
            summary.hessian_term = summary.hessian_term.max(r.abs());
            summary.transpose_term = summary.transpose_term.max(t.abs());
            *r += g + t;
            summary.dual_inf = summary.dual_inf.max(r.abs());
        }
        summary
    }

    /// Solves the Newton system for the complementarity right-hand side `rc = s∘λ` (predictor,
    /// `centering = None`) or `rc = s∘λ + Δs_aff∘Δλ_aff − σμ` (corrector, `centering = Some(σμ)`),
    /// writing `dx`, `ds`, `dl`; returns the largest step in (0, 1] keeping `s` and `λ` non-negative.
    /// The factorization must be current.
    fn newton_direction(&mut self, centering: Option<f64>) -> f64 {
        // KΔx = −rd + Cᵀ((rc − λ∘rp)/s)
        for (d, r) in self.dx.iter_mut().zip(self.residual_dual.iter()) {
            *d = -r;
        }
        for g in &self.groups[..self.group_count] {
            let mut sum = [0.0; 2];
            for i in g.first_row..g.end_row {
                let mut rc = self.slack[i] * self.multiplier[i];
                if let Some(sigma_mu) = centering {
                    rc += self.ds_aff[i] * self.dl_aff[i] - sigma_mu;
                }
                self.rhs_rows[i] = rc;
                let v = (rc - self.multiplier[i] * self.residual_primal[i]) * self.inverse_slack[i];
                sum[0] += self.rows[i].normal[0] * v;
                sum[1] += self.rows[i].normal[1] * v;
            }
            g.add_transpose(sum, &mut self.dx);
        }
        self.newton.cholesky_solve(&mut self.dx);
        let mut alpha: f64 = 1.0;
        for g in &self.groups[..self.group_count] {
            let dz = g.point(&self.dx);
            for i in g.first_row..g.end_row {
                let c_dx = self.rows[i].dot(dz);
                let ds = -self.residual_primal[i] - c_dx;
                let (s, l) = (self.slack[i], self.multiplier[i]);
                let dl = (-self.rhs_rows[i] - l * ds) * self.inverse_slack[i];
                self.ds[i] = ds;
                self.dl[i] = dl;
                // divide only when this entry limits the step further
                if ds < 0.0 && s < alpha * -ds {
                    alpha = -s / ds;
                }
                if dl < 0.0 && l < alpha * -dl {
                    alpha = -l / dl;
                }
            }
        }
        alpha
    }

    /// Factorises the Newton matrix assembled in `newton`; when round-off makes it numerically
    /// indefinite (multipliers/slacks ratios near 1e16 at the end of a degenerate solve), retries with a
    /// growing diagonal shift relative to its largest diagonal entry (a primal regularisation that only
    /// damps the step). Returns false when even the largest shift fails.
    fn factor_newton_regularized(&mut self) -> bool {
        let n = self.n();
        let largest = (0..n).fold(0.0_f64, |a, i| a.max(self.newton.diagonal(i).abs()));
        for shift in [0.0, 1e-14, 1e-12, 1e-10, 1e-8] {
            if shift > 0.0 {
                // the failed factorization overwrote the band: reassemble, then shift the diagonal
                self.assemble_newton();
                for i in 0..n {
                    self.newton.add_diagonal(i, shift * largest);
                }
            }
            if self.newton.cholesky_in_place() {
                return true;
            }
        }
        false
    }

    /// Newton matrix `K = P + Cᵀ diag(λ/s) C` into `newton`: per group, `Jᵀ (Σ_rows w n nᵀ) J`.
    fn assemble_newton(&mut self) {
        self.newton.copy_from(&self.hessian);
        for g in &self.groups[..self.group_count] {
            // M = Σ w n nᵀ (symmetric 2×2: xx, yx, yy)
            let mut m = [0.0; 3];
            for i in g.first_row..g.end_row {
                let inverse = 1.0 / self.slack[i];
                self.inverse_slack[i] = inverse;
                let w = self.multiplier[i] * inverse;
                let [nx, ny] = self.rows[i].normal;
                let (wx, wy) = (w * nx, w * ny);
                m[0] += wx * nx;
                m[1] += wy * nx;
                m[2] += wy * ny;
            }
            for t in 0..g.terms {
                let (ct, at) = (g.columns[t], g.coefficients[t]);
                for u in 0..g.terms {
                    let (cu, au) = (g.columns[u], g.coefficients[u]);
                    let f = at * au;
                    if cu < ct {
                        // a full 2×2 block below the diagonal
                        self.newton.add(ct, cu, f * m[0]);
                        self.newton.add(ct, cu + 1, f * m[1]);
                        self.newton.add(ct + 1, cu, f * m[1]);
                        self.newton.add(ct + 1, cu + 1, f * m[2]);
                    } else if cu == ct {
                        self.newton.add_diagonal(ct, f * m[0]);
                        self.newton.add(ct + 1, ct, f * m[1]);
                        self.newton.add_diagonal(ct + 1, f * m[2]);
                    }
                }
            }
        }
    }

    /// Solves the QP; on return `x`, `slack`, `multiplier` hold the solution. Returns the outcome and
    /// the number of iterations.
    pub(crate) fn solve(&mut self, settings: &IpmSettings) -> (IpmOutcome, u32) {
        let n = self.n();
        let m = self.row_count;
        // Unconstrained minimiser, with the factor of P kept while P does not change.
        if !self.hessian_factor_current {
            self.hessian_factor.copy_from(&self.hessian);
            if !self.hessian_factor.cholesky_in_place() {
                return (IpmOutcome::NumericalError, 0);
            }
            self.hessian_factor_current = true;
        }
        for (x, g) in self.x.iter_mut().zip(self.gradient.iter()) {
            *x = -g;
        }
        self.hessian_factor.cholesky_solve(&mut self.x);
        if self.x.iter().any(|v| !v.is_finite()) {
            return (IpmOutcome::NumericalError, 0);
        }
        let mut min_slack = f64::INFINITY;
        for g in &self.groups[..self.group_count] {
            let z = g.point(&self.x);
            for i in g.first_row..g.end_row {
                let s = self.rows[i].bound - self.rows[i].dot(z);
                self.slack[i] = s;
                min_slack = min_slack.min(s);
            }
        }
        if m == 0 || min_slack >= 0.0 {
            self.multiplier[..m].iter_mut().for_each(|v| *v = 0.0);
            return (IpmOutcome::Unconstrained, 0);
        }
        if std::mem::take(&mut self.warm_start) {
            // Warm start: the given point, slacks and multipliers pushed into the interior.
            self.x.copy_from_slice(&self.start_x);
            for g in &self.groups[..self.group_count] {
                let z = g.point(&self.x);
                for i in g.first_row..g.end_row {
                    let s = self.rows[i].bound - self.rows[i].dot(z);
                    self.slack[i] = s.max(WARM_SLACK_FLOOR);
                    self.multiplier[i] = self.start_multiplier[i].max(WARM_MULTIPLIER_FLOOR);
                }
            }
        } else {
            // Infeasible start: positive slacks and multipliers (Mehrotra-style shift).
            let shift = (-1.5 * min_slack).max(0.0);
            let floor = 1e-4;
            for i in 0..m {
                self.slack[i] = (self.slack[i] + shift).max(floor);
                self.multiplier[i] = 1.0;
            }
        }
        let scale_gradient = self
            .gradient
            .iter()
            .fold(0.0_f64, |a, v| a.max(v.abs()))
            .max(1.0);
        let scale_bound = self.rows[..m]
            .iter()
            .fold(0.0_f64, |a, r| a.max(r.bound.abs()))
            .max(1.0);
        let tol = settings.tolerance;
        let mut iterations = 0u32;
        let mut initial_mu = None;
        loop {
            let r = self.compute_residuals();
            let mu = r.product_sum / m as f64;
            if !(mu.is_finite()
                && r.largest_product.is_finite()
                && r.dual_inf.is_finite()
                && r.primal_inf.is_finite())
            {
                return (IpmOutcome::NumericalError, iterations);
            }
            let initial_mu = *initial_mu.get_or_insert(mu);
            // Scale-invariant stopping rules: residuals relative to the largest term of their
            // equation; complementarity: no product above tol × 1 mm × the largest multiplier, i.e. a
            // row either has a slack below ~tol mm or a multiplier below tol × 1e-3 of the largest.
            let dual_scale = scale_gradient.max(r.hessian_term).max(r.transpose_term);
            let primal_scale = scale_bound.max(r.row_term);
            if r.dual_inf <= tol * dual_scale
                && r.primal_inf <= tol * primal_scale
                && r.largest_product <= tol * 1e-3 * r.largest_multiplier.max(tol * dual_scale)
            {
                return (IpmOutcome::Converged, iterations);
            }
            if iterations >= settings.max_iterations {
                return (IpmOutcome::MaxIterations, iterations);
            }
            iterations += 1;
            self.assemble_newton();
            if !self.factor_newton_regularized() {
                return (IpmOutcome::NumericalError, iterations);
            }
            // Predictor (affine scaling).
            let alpha_aff = self.newton_direction(None);
            let mut mu_aff = 0.0;
            for i in 0..m {
                mu_aff += (self.slack[i] + alpha_aff * self.ds[i])
                    * (self.multiplier[i] + alpha_aff * self.dl[i]);
            }
            mu_aff /= m as f64;
            let sigma = (mu_aff / mu).clamp(0.0, 1.0).powi(3);
            std::mem::swap(&mut self.ds, &mut self.ds_aff);
            std::mem::swap(&mut self.dl, &mut self.dl_aff);
            // Corrector.
            let alpha_max = self.newton_direction(Some(sigma * mu));
            // Fraction to the boundary: 0.99 at the start, tending to 1 as μ falls (the last
            // iterations then take full steps: quadratic-rate endgame instead of ×100 per iteration).
            let eta = 1.0 - 0.01 * (mu / initial_mu).sqrt().min(1.0);
            let alpha = (eta * alpha_max).min(1.0);
            for j in 0..n {
                self.x[j] += alpha * self.dx[j];
            }
            for i in 0..m {
                self.slack[i] += alpha * self.ds[i];
                self.multiplier[i] += alpha * self.dl[i];
            }
        }
    }
}

/// What the stopping rules need from one residual evaluation.
#[derive(Debug, Clone, Copy, Default)]
struct ResidualSummary {
    /// ‖rd‖∞ and ‖rp‖∞.
    dual_inf: f64,
    primal_inf: f64,
    /// Σ sᵢλᵢ, max |sᵢλᵢ|, max λᵢ.
    product_sum: f64,
    largest_product: f64,
    largest_multiplier: f64,
    /// Scales of the terms: ‖Px‖∞, ‖Cᵀλ‖∞, ‖Cx‖∞.
    hessian_term: f64,
    transpose_term: f64,
    row_term: f64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    /// Deterministic pseudo-random numbers in [−1, 1).
    fn numbers(seed: u64) -> impl FnMut() -> f64 {
        let mut state = seed;
        move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        }
    }

    #[test]
    fn band_kernels_match_dense_linear_algebra() {
        for n in [1, 2, 3, 5, 6, 7, 10, 11, 12, 40] {
            let mut next = numbers(n as u64);
            let mut band = BandMatrix::new(n);
            let mut dense = DMatrix::zeros(n, n);
            for i in 0..n {
                for j in i.saturating_sub(BAND)..=i {
                    let v = if i == j { 10.0 + next().abs() } else { next() };
                    band.add(i, j, v);
                    dense[(i, j)] = v;
                    dense[(j, i)] = v;
                }
            }
            let x = DVector::from_fn(n, |_, _| next());
            let mut y = vec![0.0; n];
            band.mul_vec(x.as_slice(), &mut y);
            assert!((DVector::from_vec(y) - &dense * &x).amax() < 1e-12);
            for i in 0..n {
                for j in 0..n {
                    assert_eq!(band.get(i, j), dense[(i, j)]);
                }
            }
            let b = DVector::from_fn(n, |_, _| next());
            assert!(band.cholesky_in_place());
            let mut solution = b.as_slice().to_vec();
            band.cholesky_solve(&mut solution);
            let expected = dense.cholesky().unwrap().solve(&b);
            assert!(
                (DVector::from_vec(solution) - expected).amax() < 1e-12,
                "n {n}"
            );
        }
        let mut indefinite = BandMatrix::new(3);
        indefinite.add(0, 0, 1.0);
        indefinite.add(1, 1, -1.0);
        indefinite.add(2, 2, 1.0);
        assert!(!indefinite.cholesky_in_place());
    }

    /// Grouped half-plane rows: the Newton matrix, the residuals and the transpose products equal
    /// those of the expanded sparse rows computed densely.
    #[test]
    fn grouped_rows_match_their_dense_expansion() {
        let n = 12;
        let mut next = numbers(7);
        let mut qp = BandedQp::new(n, 6, 30);
        for i in 0..n {
            qp.hessian.add(i, i, 3.0 + next().abs());
            if i >= 2 {
                qp.hessian.add(i, i - 2, 0.3 * next());
            }
            qp.gradient[i] = next();
            qp.x[i] = next();
        }
        let mut row = 0;
        for k in 0..n / 2 {
            let mut g = PointGroup {
                first_row: row,
                ..PointGroup::default()
            };
            if k > 0 {
                g.columns[0] = 2 * (k - 1);
                g.coefficients[0] = next();
                g.terms = 1;
            }
            g.columns[g.terms] = 2 * k;
            g.coefficients[g.terms] = 2.0 + next();
            g.terms += 1;
            for _ in 0..(3 + k % 3) {
                let angle = 3.0 * next();
                qp.rows[row] = HalfPlaneRow {
                    normal: [angle.cos(), angle.sin()],
                    bound: next(),
                };
                qp.slack[row] = 0.5 + next().abs();
                qp.multiplier[row] = 0.1 + next().abs();
                row += 1;
            }
            g.end_row = row;
            qp.groups[k] = g;
        }
        qp.group_count = n / 2;
        qp.row_count = row;
        let mut dense_c = DMatrix::<f64>::zeros(row, n);
        let mut bounds = DVector::<f64>::zeros(row);
        for (i, r) in qp.sparse_rows().enumerate() {
            for e in 0..r.len {
                dense_c[(i, r.columns[e])] += r.values[e];
            }
            bounds[i] = r.bound;
        }
        let dense_p = DMatrix::<f64>::from_fn(n, n, |i, j| qp.hessian.get(i, j));
        let s = DVector::from_column_slice(&qp.slack[..row]);
        let l = DVector::from_column_slice(&qp.multiplier[..row]);
        let x = DVector::from_column_slice(&qp.x);
        let w = DMatrix::from_diagonal(&l.component_div(&s));
        let newton: DMatrix<f64> = &dense_p + dense_c.transpose() * w * &dense_c;
        qp.assemble_newton();
        for i in 0..n {
            for j in 0..n {
                assert!(
                    (qp.newton.get(i, j) - newton[(i, j)]).abs() < 1e-12,
                    "({i}, {j})"
                );
            }
        }
        let summary = qp.compute_residuals();
        let dual =
            &dense_p * &x + DVector::from_column_slice(&qp.gradient) + dense_c.transpose() * &l;
        let primal = &dense_c * &x + &s - &bounds;
        assert!((DVector::from_column_slice(&qp.residual_dual) - &dual).amax() < 1e-12);
        assert!((DVector::from_column_slice(&qp.residual_primal[..row]) - &primal).amax() < 1e-12);
        assert!((summary.dual_inf - dual.amax()).abs() < 1e-12);
        assert!((summary.primal_inf - primal.amax()).abs() < 1e-12);
        assert!((summary.product_sum - s.dot(&l)).abs() < 1e-12);
    }
}
