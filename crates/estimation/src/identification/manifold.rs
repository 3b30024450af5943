//! Physically consistent identification on the manifold 𝔓ⁿ [Traversaro 2017, eqs. (6.24)–(6.28),
//! Theorem 6.1]: a Levenberg–Marquardt iteration on θ = (m, c, Q, L) per body, each step taken in the
//! local chart of [`super::chart`] (rotation updated on SO(3) through the exponential map, `m ≥ 0` and
//! `L ≥ 0` kept by clamping), so every iterate is a set of physical bodies. A weak quadratic pull towards
//! a prior fixes the directions the data do not excite (structurally or numerically non-identifiable).

use nalgebra::{DMatrix, DVector};

use stride_model::inertial::{InertialParameters, PhysicalParameters};

use super::chart::{chart_jacobian, nearest_physical, retract};
use super::data::ReducedData;
use super::IdentificationError;

/// Options of [`identify_on_manifold`].
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `prior_weight` | – | 1e-4 | `ρ ≥ 0`: parameter `j` is pulled towards the prior with weight `ρ (‖R_j‖² + 10⁻⁶ · mean_k ‖R_k‖²)`, `R_j` the column of the (noise-weighted) regressor: relative to what the data say about it |
/// | `inertia_prior_weight` | – | `None` | `ρ_I ≥ 0` in place of `ρ` for the six rotational-inertia entries `vech(I_B)` of every body (masses, first moments and extras keep `ρ`): the rotational inertias are the parameters motions excite least, and a stronger pull keeps them near the prior while the masses and CoMs follow the data; `None` = `ρ` |
/// | `max_iterations` | – | 200 | Levenberg–Marquardt iterations |
/// | `tolerance` | – | 1e-9 | stop when an accepted step lowers the cost by less than this fraction |
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ManifoldOptions {
    /// Relative weight `ρ` of the prior (see the table).
    pub prior_weight: f64,
    /// Relative weight `ρ_I` of the prior on the rotational inertias (`None`: `prior_weight`).
    pub inertia_prior_weight: Option<f64>,
    /// Maximum number of iterations.
    pub max_iterations: usize,
    /// Relative cost decrease that ends the iteration.
    pub tolerance: f64,
}

impl Default for ManifoldOptions {
    fn default() -> Self {
        Self {
            prior_weight: 1e-4,
            inertia_prior_weight: None,
            max_iterations: 200,
            tolerance: 1e-9,
        }
    }
}

/// The prior: one `π` per body (need not be consistent: it is moved to the nearest θ of 𝔓 to start) and
/// the extra unknowns.
#[derive(Clone, Debug)]
pub struct Prior {
    /// `π = [m; m c; vech(I_B)]` per body [Traversaro 2017, eq. (6.3)].
    pub bodies: Vec<InertialParameters>,
    /// Extra linear unknowns (friction, offsets, ...).
    pub extras: DVector<f64>,
}

/// The result of [`identify_on_manifold`].
#[derive(Clone, Debug)]
pub struct ManifoldEstimate {
    /// θ per body: every one a physical body (Theorem 6.1).
    pub bodies: Vec<PhysicalParameters>,
    /// `w = [π_p(θ_1); …; π_p(θ_n); x]`.
    pub parameters: DVector<f64>,
    /// Iterations taken.
    pub iterations: usize,
    /// Whether the relative cost decrease fell below the tolerance (or no step could lower it).
    pub converged: bool,
    /// `√(data cost / rows)` at the estimate (≈ 1 when the residuals match the noise).
    pub normalised_residual: f64,
    /// The minimised objective `‖R w − r‖² + ρ² + Σ_j λ_j (w_j − w⁰_j)²` at the estimate.
    pub objective: f64,
}

impl Prior {
    /// `w` of the prior: `[π_1; …; π_n; x]`.
    pub fn parameters(&self) -> DVector<f64> {
        let n = 10 * self.bodies.len();
        let mut w = DVector::zeros(n + self.extras.len());
        for (b, pi) in self.bodies.iter().enumerate() {
            w.fixed_rows_mut::<10>(10 * b).copy_from(pi);
        }
        w.rows_mut(n, self.extras.len()).copy_from(&self.extras);
        w
    }
}

/// `w` of θ and the extras.
fn stack(theta: &[PhysicalParameters], extras: &DVector<f64>) -> DVector<f64> {
    let n = 10 * theta.len();
    let mut w = DVector::zeros(n + extras.len());
    for (b, t) in theta.iter().enumerate() {
        w.fixed_rows_mut::<10>(10 * b)
            .copy_from(&t.to_inertial_parameters());
    }
    w.rows_mut(n, extras.len()).copy_from(extras);
    w
}

/// The cost function, with the data's normal matrix `H = RᵀR` and `Rᵀr` formed once: each iteration then
/// costs `O(n²)` products with the block-diagonal chart Jacobian plus one Cholesky factorisation.
struct Problem<'a> {
    data: &'a ReducedData,
    h: DMatrix<f64>,
    rt_rhs: DVector<f64>,
    prior: DVector<f64>,
    prior_weights: DVector<f64>,
}

impl<'a> Problem<'a> {
    fn new(data: &'a ReducedData, prior: DVector<f64>, prior_weights: DVector<f64>) -> Self {
        Self {
            h: data.r.tr_mul(&data.r),
            rt_rhs: data.r.tr_mul(&data.rhs),
            data,
            prior,
            prior_weights,
        }
    }

    /// Data cost plus prior term at `w`.
    fn cost(&self, w: &DVector<f64>) -> f64 {
        let d = w - &self.prior;
        self.data.cost(w) + d.component_mul(&d).dot(&self.prior_weights)
    }

    /// Gauss–Newton normal matrix `Jᵀ(H + Λ)J` and gradient `Jᵀ(H w − Rᵀr + Λ(w − w⁰))` in the chart at
    /// θ, `J` block-diagonal (one [`chart_jacobian`] per body, identity on the extras).
    fn normal_equations(
        &self,
        theta: &[PhysicalParameters],
        w: &DVector<f64>,
    ) -> (DMatrix<f64>, DVector<f64>) {
        let blocks: Vec<_> = theta.iter().map(chart_jacobian).collect();
        let mut hl = self.h.clone();
        for i in 0..w.len() {
            hl[(i, i)] += self.prior_weights[i];
        }
        // (H + Λ) J, column blocks.
        for (b, jb) in blocks.iter().enumerate() {
            let cols = hl.columns(10 * b, 10) * jb;
            hl.columns_mut(10 * b, 10).copy_from(&cols);
        }
        // Jᵀ (H + Λ) J, row blocks.
        for (b, jb) in blocks.iter().enumerate() {
            let rows = jb.tr_mul(&hl.rows(10 * b, 10));
            hl.rows_mut(10 * b, 10).copy_from(&rows);
        }
        let mut g =
            &self.h * w - &self.rt_rhs + self.prior_weights.component_mul(&(w - &self.prior));
        for (b, jb) in blocks.iter().enumerate() {
            let gb = jb.tr_mul(&g.fixed_rows::<10>(10 * b));
            g.fixed_rows_mut::<10>(10 * b).copy_from(&gb);
        }
        (hl, g)
    }
}

/// The fully consistent identification (6.24)–(6.27) with a prior: minimises
/// `‖R w(θ, x) − r‖² + Σ_j λ_j (w_j − w⁰_j)²` over θ ∈ 𝔓ⁿ and the extras x, starting from the prior.
///
/// # Errors
/// [`IdentificationError::Size`] when the prior does not match the data, [`IdentificationError::Invalid`]
/// for a negative or non-finite option or a non-finite prior.
pub fn identify_on_manifold(
    data: &ReducedData,
    prior: &Prior,
    options: &ManifoldOptions,
) -> Result<ManifoldEstimate, IdentificationError> {
    check(data, prior, options)?;
    let problem = Problem::new(data, prior.parameters(), prior_weights(data, options));
    let mut theta: Vec<PhysicalParameters> = prior.bodies.iter().map(nearest_physical).collect();
    let mut extras = prior.extras.clone();
    let mut w = stack(&theta, &extras);
    let mut cost = problem.cost(&w);
    let mut mu = 1e-3;
    let mut converged = false;
    let mut iterations = 0;
    let n10 = 10 * theta.len();
    while iterations < options.max_iterations && !converged {
        iterations += 1;
        let (mut normal, mut gradient) = problem.normal_equations(&theta, &w);
        hold_active_bounds(&theta, &mut normal, &mut gradient);
        let scale = normal.diagonal().max().max(f64::MIN_POSITIVE);
        loop {
            let mut damped = normal.clone();
            for i in 0..damped.nrows() {
                damped[(i, i)] += mu * (normal[(i, i)] + 1e-9 * scale);
            }
            let Some(step) = damped.cholesky().map(|c| c.solve(&(-&gradient))) else {
                mu *= 4.0;
                continue;
            };
            let trial: Vec<PhysicalParameters> = theta
                .iter()
                .enumerate()
                .map(|(b, t)| retract(t, step.rows(10 * b, 10).as_slice()))
                .collect();
            let trial_extras = &extras + step.rows(n10, extras.len());
            let trial_w = stack(&trial, &trial_extras);
            let trial_cost = problem.cost(&trial_w);
            if trial_cost < cost {
                converged = cost - trial_cost <= options.tolerance * cost;
                (theta, extras, w, cost) = (trial, trial_extras, trial_w, trial_cost);
                mu = (mu / 3.0).max(1e-12);
                break;
            }
            mu *= 4.0;
            if mu > 1e12 {
                converged = true;
                break;
            }
        }
    }
    Ok(ManifoldEstimate {
        normalised_residual: data.normalised_residual(&w),
        bodies: theta,
        parameters: w,
        iterations,
        converged,
        objective: cost,
    })
}

/// Projected Newton [Bertsekas 1982]: a chart coordinate at its bound (`m = 0` or `L_k = 0`) whose
/// gradient points out of 𝔓 (descent would make it negative) is held for this step: its row and column of
/// the normal matrix become the unit's and its gradient zero, so the step is the Levenberg–Marquardt step
/// of the free coordinates. Without it the retraction clamps the unconstrained step, which then is not a
/// descent step of the free coordinates, and the iteration crawls along the boundary.
fn hold_active_bounds(
    theta: &[PhysicalParameters],
    normal: &mut DMatrix<f64>,
    gradient: &mut DVector<f64>,
) {
    for (b, t) in theta.iter().enumerate() {
        let bounded = [
            (0, t.mass),
            (7, t.second_moments.x),
            (8, t.second_moments.y),
            (9, t.second_moments.z),
        ];
        for (k, value) in bounded {
            let i = 10 * b + k;
            if value <= 0.0 && gradient[i] > 0.0 {
                normal.row_mut(i).fill(0.0);
                normal.column_mut(i).fill(0.0);
                normal[(i, i)] = 1.0;
                gradient[i] = 0.0;
            }
        }
    }
}

/// `λ_j = ρ_j (‖R_j‖² + 10⁻⁶ · mean_k ‖R_k‖²)`, `ρ_j` the inertia weight `ρ_I` for the entries
/// `vech(I_B)` (4–9 of each body's 10) and `ρ` otherwise (see [`ManifoldOptions`]).
fn prior_weights(data: &ReducedData, options: &ManifoldOptions) -> DVector<f64> {
    let norms = DVector::from_iterator(
        data.r.ncols(),
        data.r.column_iter().map(|c| c.norm_squared()),
    );
    let floor = 1e-6 * norms.mean();
    let rho = options.prior_weight;
    let rho_inertia = options.inertia_prior_weight.unwrap_or(rho);
    DVector::from_iterator(
        norms.len(),
        norms.iter().enumerate().map(|(j, v)| {
            let inertia = j < 10 * data.bodies && j % 10 >= 4;
            (if inertia { rho_inertia } else { rho }) * (v + floor)
        }),
    )
}

fn check(
    data: &ReducedData,
    prior: &Prior,
    options: &ManifoldOptions,
) -> Result<(), IdentificationError> {
    if prior.bodies.len() != data.bodies {
        return Err(IdentificationError::Size {
            what: "prior bodies",
            expected: data.bodies,
            actual: prior.bodies.len(),
        });
    }
    let n = data.r.ncols();
    if 10 * prior.bodies.len() + prior.extras.len() != n {
        return Err(IdentificationError::Size {
            what: "prior extra unknowns",
            expected: n - 10 * data.bodies,
            actual: prior.extras.len(),
        });
    }
    if let Some(index) = prior.parameters().iter().position(|v| !v.is_finite()) {
        return Err(IdentificationError::Invalid {
            what: "prior",
            index,
            reason: "non-finite",
        });
    }
    let non_negative = |v: f64| v.is_finite() && v >= 0.0;
    if !non_negative(options.prior_weight)
        || !non_negative(options.tolerance)
        || !options.inertia_prior_weight.is_none_or(non_negative)
    {
        return Err(IdentificationError::Invalid {
            what: "manifold options",
            index: 0,
            reason:
                "prior_weight, inertia_prior_weight and tolerance must be finite and non-negative",
        });
    }
    Ok(())
}
