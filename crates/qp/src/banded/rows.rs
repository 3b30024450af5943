//! Constraint rows grouped by the 2-D point they constrain.

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
    pub(crate) fn point(&self, x: &[f64]) -> [f64; 2] {
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
    pub(crate) fn add_transpose(&self, g: [f64; 2], out: &mut [f64]) {
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
    pub(crate) fn dot(&self, z: [f64; 2]) -> f64 {
        self.normal[0] * z[0] + self.normal[1] * z[1]
    }
}
