//! Base parameters: the identifiable subspace of a regressor, computed numerically [Traversaro 2017,
//! eqs. 7.6–7.10; Sheu & Walker 1991].
//!
//! A regressor `Y(q, ν, ν̇)` has a null space `N_Y = {ψ : Y ψ = 0 for every argument}` (7.7): parameter
//! changes no motion reveals (the mass of a body rigidly fixed to the world, the inertia about a joint's
//! axis of a body that can only turn about it, ...). Only the projection of ψ on `I_Y = N_Yᵀ` (7.8) is
//! identifiable. Stacking `Y` at enough generic samples (7.6) and taking its SVD gives the rank
//! (number of base parameters) and an orthonormal basis `B` of `I_Y`: `ψ = B π_b + n`, `n ∈ N_Y` (7.9).

use nalgebra::{DMatrix, DVector};

use crate::error::{check_len, ModelError};
use crate::kindyn::KinDyn;
use crate::state::RobotState;

/// Default relative threshold on the singular values (`σ_i > tol · σ_max` counts towards the rank).
pub const DEFAULT_RANK_TOLERANCE: f64 = 1e-9;

/// The identifiable subspace of a regressor, from the SVD of the regressor stacked at many samples.
#[derive(Clone, Debug)]
pub struct BaseParameters {
    /// Orthonormal basis `B` (p × r) of the identifiable subspace `I_Y`: the base parameters of ψ are
    /// `Bᵀ ψ` (7.9).
    pub basis: DMatrix<f64>,
    /// Singular values of the stacked regressor, in decreasing order.
    pub singular_values: DVector<f64>,
    /// The relative threshold the rank was decided with.
    pub tolerance: f64,
}

impl BaseParameters {
    /// The SVD of `stacked` (the regressor stacked over samples, (7.6)); the rank is the number of
    /// singular values above `relative_tolerance · σ_max`.
    ///
    /// # Errors
    /// [`ModelError::NonFiniteInput`] when `stacked` holds a non-finite value or is empty.
    pub fn from_stacked(
        stacked: DMatrix<f64>,
        relative_tolerance: f64,
    ) -> Result<BaseParameters, ModelError> {
        if stacked.is_empty() || !stacked.iter().all(|v| v.is_finite()) {
            return Err(ModelError::NonFiniteInput {
                what: "stacked regressor",
            });
        }
        let svd = stacked.svd(false, true);
        let v_t = svd.v_t.expect("v_t requested");
        let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
        order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
        let sigma =
            DVector::from_iterator(order.len(), order.iter().map(|&k| svd.singular_values[k]));
        let threshold = relative_tolerance * sigma[0];
        let rank = sigma.iter().take_while(|&&s| s > threshold).count();
        let p = v_t.ncols();
        let mut basis = DMatrix::zeros(p, rank);
        for (c, &k) in order.iter().take(rank).enumerate() {
            basis.set_column(c, &v_t.row(k).transpose());
        }
        Ok(BaseParameters {
            basis,
            singular_values: sigma,
            tolerance: relative_tolerance,
        })
    }

    /// Number of base parameters (the rank of the stacked regressor).
    pub fn rank(&self) -> usize {
        self.basis.ncols()
    }

    /// Ratio of the last singular value counted in the rank to the first one left out (∞ at full column
    /// rank): a large gap means the rank decision is clear.
    pub fn gap(&self) -> f64 {
        let r = self.rank();
        match (r, self.singular_values.get(r)) {
            (0, _) => 0.0,
            (_, Some(&next)) if next > 0.0 => self.singular_values[r - 1] / next,
            _ => f64::INFINITY,
        }
    }

    /// The base parameters `Bᵀ ψ` of a parameter vector.
    ///
    /// # Errors
    /// [`ModelError::DimensionMismatch`] for a wrong length.
    pub fn base_parameters(&self, psi: &DVector<f64>) -> Result<DVector<f64>, ModelError> {
        check_len("inertial parameters", self.basis.nrows(), psi.len())?;
        Ok(self.basis.tr_mul(psi))
    }

    /// The projection `B Bᵀ ψ` of ψ on the identifiable subspace: it gives the same regressor output
    /// `Y ψ` as ψ for every sample.
    ///
    /// # Errors
    /// [`ModelError::DimensionMismatch`] for a wrong length.
    pub fn project(&self, psi: &DVector<f64>) -> Result<DVector<f64>, ModelError> {
        Ok(&self.basis * self.base_parameters(psi)?)
    }
}

/// The inverse-dynamics regressor ([`KinDyn::inverse_dynamics_regressor`], current representation)
/// stacked over `samples` of (state, ν̇) (7.6): `samples.len() · (6 + n)` × 10·N.
///
/// # Errors
/// Those of [`KinDyn::set_state`] and [`KinDyn::inverse_dynamics_regressor`].
pub fn stacked_inverse_dynamics_regressor(
    kd: &mut KinDyn,
    samples: &[(RobotState, DVector<f64>)],
) -> Result<DMatrix<f64>, ModelError> {
    let nv = kd.model().nv();
    let cols = 10 * kd.model().body_count();
    let mut out = DMatrix::zeros(nv * samples.len(), cols);
    let mut y = DMatrix::zeros(nv, cols);
    for (k, (state, nu_dot)) in samples.iter().enumerate() {
        kd.set_state(state)?;
        kd.inverse_dynamics_regressor(nu_dot, &mut y)?;
        out.rows_mut(k * nv, nv).copy_from(&y);
    }
    Ok(out)
}
