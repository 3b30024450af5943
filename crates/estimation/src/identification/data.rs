//! Measurements for an identification: rows `y ψ + e x = z` (ψ the inertial parameters of the bodies, x
//! extra linear unknowns such as joint friction or sensor offsets) with per-row noise σ, folded into a
//! triangular factor as they arrive (memory independent of the number of samples).

use nalgebra::{DMatrix, DVector, DVectorView};

use super::IdentificationError;
use crate::calibration::StackedLeastSquares;

/// The weighted least-squares data `Σ ((y_i ψ + e_i x − z_i) / σ_i)²` of an identification over `bodies`
/// rigid bodies (10 inertial parameters each, the layout of [Traversaro 2017, eq. (6.3), Definition 7.1])
/// and `extras` extra linear unknowns.
#[derive(Clone, Debug)]
pub struct IdentificationData {
    bodies: usize,
    extras: usize,
    ls: StackedLeastSquares,
    row: Vec<f64>,
}

/// The data reduced to its triangular factor: `Σ ((a_i w − z_i)/σ_i)² = ‖R w − r‖² + ρ²`,
/// `w = [ψ; x]`.
#[derive(Clone, Debug)]
pub struct ReducedData {
    /// `R` (n × n, upper-triangular), n = 10·bodies + extras.
    pub r: DMatrix<f64>,
    /// `Qᵀ z` (n).
    pub rhs: DVector<f64>,
    /// `ρ`: the residual no `w` can explain.
    pub rho: f64,
    /// Number of rows.
    pub rows: usize,
    /// Number of bodies.
    pub bodies: usize,
}

impl IdentificationData {
    /// No rows yet, for `bodies` bodies and `extras` extra unknowns.
    pub fn new(bodies: usize, extras: usize) -> Self {
        let n = 10 * bodies + extras;
        Self {
            bodies,
            extras,
            ls: StackedLeastSquares::new(n),
            row: vec![0.0; n],
        }
    }

    /// Number of unknowns `10·bodies + extras`.
    pub fn unknowns(&self) -> usize {
        self.row.len()
    }

    /// Number of extra unknowns.
    pub fn extras(&self) -> usize {
        self.extras
    }

    /// Number of rows added.
    pub fn rows(&self) -> usize {
        self.ls.rows()
    }

    /// Adds one row `a · [ψ; x] = z` with noise σ (`a` of length [`Self::unknowns`], σ > 0; units of `z`).
    ///
    /// # Errors
    /// [`IdentificationError::Size`] for a wrong length, [`IdentificationError::Invalid`] for a
    /// non-finite entry or a non-positive σ.
    pub fn add_row(
        &mut self,
        a: DVectorView<'_, f64>,
        z: f64,
        sigma: f64,
    ) -> Result<(), IdentificationError> {
        let index = self.rows();
        if a.len() != self.row.len() {
            return Err(IdentificationError::Size {
                what: "regressor row",
                expected: self.row.len(),
                actual: a.len(),
            });
        }
        if !(sigma.is_finite() && sigma > 0.0) {
            return Err(IdentificationError::Invalid {
                what: "noise σ",
                index,
                reason: "must be positive and finite",
            });
        }
        if !z.is_finite() || !a.iter().all(|v| v.is_finite()) {
            return Err(IdentificationError::Invalid {
                what: "measurement row",
                index,
                reason: "non-finite regressor entry or measurement",
            });
        }
        for (dst, src) in self.row.iter_mut().zip(a.iter()) {
            *dst = src / sigma;
        }
        self.ls.add_row(&self.row, z / sigma);
        Ok(())
    }

    /// The triangular factor of the rows so far.
    ///
    /// # Errors
    /// [`IdentificationError::NoData`] without rows.
    pub fn reduce(&self) -> Result<ReducedData, IdentificationError> {
        if self.rows() == 0 {
            return Err(IdentificationError::NoData);
        }
        let (r, rhs, rho) = self.ls.triangular_factor();
        Ok(ReducedData {
            r,
            rhs,
            rho,
            rows: self.rows(),
            bodies: self.bodies,
        })
    }
}

impl ReducedData {
    /// `‖R w − r‖² + ρ²`: the weighted squared residual of the rows at `w = [ψ; x]`.
    pub fn cost(&self, w: &DVector<f64>) -> f64 {
        (&self.r * w - &self.rhs).norm_squared() + self.rho * self.rho
    }

    /// `√(cost / rows)`: about 1 when the residuals match the given noise.
    pub fn normalised_residual(&self, w: &DVector<f64>) -> f64 {
        (self.cost(w) / self.rows as f64).sqrt()
    }

    /// Singular values of `R` (of the weighted regressor), decreasing.
    pub fn singular_values(&self) -> DVector<f64> {
        let mut s = self.r.singular_values();
        s.as_mut_slice().sort_by(|a, b| b.total_cmp(a));
        s
    }
}
