//! The classical unconstrained least-squares estimate [Traversaro 2017, eq. (6.19)] for comparison with
//! the manifold method: `w = w⁰ + δ`, δ the minimum-norm solution of `min ‖R (w⁰ + δ) − r‖`, so the
//! directions the data leave undetermined keep the prior's values. Nothing keeps it physical.

use nalgebra::DVector;

use super::data::ReducedData;
use super::manifold::Prior;
use super::IdentificationError;

/// The unconstrained estimate and the conditioning of the problem.
#[derive(Clone, Debug)]
pub struct UnconstrainedEstimate {
    /// `w = [ψ; x]`.
    pub parameters: DVector<f64>,
    /// Numerical rank of the weighted regressor (singular values above `tolerance · σ_max`).
    pub rank: usize,
    /// `σ_max / σ_min` over the singular values counted in the rank.
    pub condition_number: f64,
    /// `√(cost / rows)` at the estimate.
    pub normalised_residual: f64,
}

/// The unconstrained least-squares estimate with relative rank tolerance `tolerance` (e.g. 1e-10).
///
/// # Errors
/// [`IdentificationError::Size`] when the prior does not match the data.
pub fn identify_unconstrained(
    data: &ReducedData,
    prior: &Prior,
    tolerance: f64,
) -> Result<UnconstrainedEstimate, IdentificationError> {
    let w0 = prior.parameters();
    if w0.len() != data.r.ncols() {
        return Err(IdentificationError::Size {
            what: "prior parameters",
            expected: data.r.ncols(),
            actual: w0.len(),
        });
    }
    let rhs = &data.rhs - &data.r * &w0;
    let svd = data.r.clone().svd(true, true);
    let s_max = svd.singular_values.max();
    let keep = |s: f64| s > tolerance * s_max && s > 0.0;
    let rank = svd.singular_values.iter().filter(|s| keep(**s)).count();
    let s_min = svd
        .singular_values
        .iter()
        .cloned()
        .filter(|s| keep(*s))
        .fold(f64::INFINITY, f64::min);
    let eps = tolerance * s_max;
    let delta = svd
        .solve(&rhs, eps.max(f64::MIN_POSITIVE))
        .map_err(|_| IdentificationError::NoData)?;
    let parameters = w0 + delta;
    Ok(UnconstrainedEstimate {
        normalised_residual: data.normalised_residual(&parameters),
        parameters,
        rank,
        condition_number: s_max / s_min,
    })
}
