//! The data of a banded QP and the workspace of its solvers: [`BandedQp`].

use std::ops::Range;

use super::band::BandMatrix;
use super::rows::{HalfPlaneRow, PointGroup, SparseRow, MAX_POINT_TERMS};
use super::BandedQpError;

/// A convex QP `min ½ xᵀPx + qᵀx  s.t.  Cx ≤ d` with a banded `P` (half-bandwidth 5) and constraint
/// rows grouped by the 2-D point they constrain, with the workspace of its solvers.
///
/// Every tick the caller
/// 1. changes `P` through [`BandedQp::hessian_mut`] only when it changes (its Cholesky factor is kept
///    otherwise), writes `q` into [`BandedQp::gradient_mut`];
/// 2. rebuilds the rows: [`BandedQp::clear_constraints`], then per point [`BandedQp::push_group`]
///    followed by its half-planes [`BandedQp::push_row`];
/// 3. optionally arms a warm start ([`BandedQp::warm_start_mut`]), then calls [`BandedQp::solve`] and
///    reads [`BandedQp::x`] and [`BandedQp::multipliers`].
///
/// All memory is allocated in [`BandedQp::new`]; none of the above allocates.
#[derive(Debug, Clone)]
pub struct BandedQp {
    /// `P`.
    pub(super) hessian: BandMatrix,
    /// Cholesky factor of `P` (for the unconstrained minimiser), reused while `P` is unchanged.
    pub(super) hessian_factor: BandMatrix,
    pub(super) hessian_factor_current: bool,
    /// Warm start: when `warm_start` is set, `solve` starts from `start_x` and
    /// `start_multiplier[..row_count]` (pushed into the interior) instead of the cold start. Reset by
    /// every solve.
    pub(super) warm_start: bool,
    pub(super) start_x: Vec<f64>,
    pub(super) start_multiplier: Vec<f64>,
    pub(super) gradient: Vec<f64>,
    /// Constraint rows, grouped by the point they constrain (`groups[..group_count]`, whose row ranges
    /// tile `rows[..row_count]` in order).
    pub(super) groups: Vec<PointGroup>,
    pub(super) group_count: usize,
    pub(super) rows: Vec<HalfPlaneRow>,
    pub(super) row_count: usize,
    // iterates
    pub(super) x: Vec<f64>,
    pub(super) slack: Vec<f64>,
    pub(super) multiplier: Vec<f64>,
    // scratch
    pub(super) newton: BandMatrix,
    pub(super) residual_dual: Vec<f64>,
    pub(super) residual_primal: Vec<f64>,
    pub(super) dx: Vec<f64>,
    pub(super) ds: Vec<f64>,
    pub(super) dl: Vec<f64>,
    pub(super) ds_aff: Vec<f64>,
    pub(super) dl_aff: Vec<f64>,
    pub(super) rhs_rows: Vec<f64>,
    pub(super) transpose_product: Vec<f64>,
    pub(super) inverse_slack: Vec<f64>,
}

impl BandedQp {
    /// Workspace for `n` variables, at most `max_groups` row groups and at most `max_rows` constraint
    /// rows; `P = 0`, `q = 0`, no row.
    pub fn new(n: usize, max_groups: usize, max_rows: usize) -> Self {
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

    /// Number of variables `n`.
    #[inline]
    pub fn n(&self) -> usize {
        self.hessian.n()
    }

    /// The Hessian `P`.
    #[inline]
    pub fn hessian(&self) -> &BandMatrix {
        &self.hessian
    }

    /// The Hessian `P` for writing; marks it changed, so the next solve refactorises it (otherwise its
    /// factor is reused).
    #[inline]
    pub fn hessian_mut(&mut self) -> &mut BandMatrix {
        self.hessian_factor_current = false;
        &mut self.hessian
    }

    /// The linear term `q` (length `n`).
    #[inline]
    pub fn gradient(&self) -> &[f64] {
        &self.gradient
    }

    /// The linear term `q` for writing.
    #[inline]
    pub fn gradient_mut(&mut self) -> &mut [f64] {
        &mut self.gradient
    }

    /// Removes every constraint row and group (keeps the memory).
    #[inline]
    pub fn clear_constraints(&mut self) {
        self.group_count = 0;
        self.row_count = 0;
    }

    /// Starts a group of rows on the point `z = Σ_t c_t · (x[j_t], x[j_t + 1])` given as `(j_t, c_t)`
    /// pairs: at most 2 terms, distinct even columns `j_t` with `j_t + 1 < n`. The rows pushed next
    /// ([`BandedQp::push_row`]) constrain this point.
    #[inline]
    pub fn push_group(&mut self, point: &[(usize, f64)]) -> Result<(), BandedQpError> {
        if self.group_count >= self.groups.len() {
            return Err(BandedQpError::CapacityExceeded {
                what: "groups",
                capacity: self.groups.len(),
            });
        }
        if point.len() > MAX_POINT_TERMS {
            return Err(BandedQpError::InvalidPoint {
                reason: "more than 2 terms",
            });
        }
        let mut group = PointGroup {
            first_row: self.row_count,
            end_row: self.row_count,
            ..PointGroup::default()
        };
        for (t, &(column, coefficient)) in point.iter().enumerate() {
            if column % 2 != 0 || column + 1 >= self.n() {
                return Err(BandedQpError::InvalidPoint {
                    reason: "a column is odd or beyond the variables",
                });
            }
            if group.columns[..t].contains(&column) {
                return Err(BandedQpError::InvalidPoint {
                    reason: "a column is repeated",
                });
            }
            if (group.columns[..t].iter()).any(|&c| c.abs_diff(column) + 1 > super::band::BAND) {
                return Err(BandedQpError::InvalidPoint {
                    reason: "the columns are farther apart than the band",
                });
            }
            group.columns[t] = column;
            group.coefficients[t] = coefficient;
            group.terms = t + 1;
        }
        self.groups[self.group_count] = group;
        self.group_count += 1;
        Ok(())
    }

    /// Adds the row `normalᵀ z ≤ bound` on the point of the last group.
    #[inline]
    pub fn push_row(&mut self, normal: [f64; 2], bound: f64) -> Result<(), BandedQpError> {
        let Some(group) = self.group_count.checked_sub(1) else {
            return Err(BandedQpError::NoGroup);
        };
        if self.row_count >= self.rows.len() {
            return Err(BandedQpError::CapacityExceeded {
                what: "rows",
                capacity: self.rows.len(),
            });
        }
        self.rows[self.row_count] = HalfPlaneRow { normal, bound };
        self.row_count += 1;
        self.groups[group].end_row = self.row_count;
        Ok(())
    }

    /// Number of groups.
    #[inline]
    pub fn group_count(&self) -> usize {
        self.group_count
    }

    /// Number of constraint rows.
    #[inline]
    pub fn row_count(&self) -> usize {
        self.row_count
    }

    /// The rows of group `group` (indices into [`BandedQp::multipliers`]); empty for a group that does
    /// not exist.
    #[inline]
    pub fn group_rows(&self, group: usize) -> Range<usize> {
        if group < self.group_count {
            let g = &self.groups[group];
            g.first_row..g.end_row
        } else {
            0..0
        }
    }

    /// Arms a warm start and returns its buffers to fill: the start point `x` (length `n`) and the
    /// start multipliers of the rows (length [`BandedQp::row_count`]); slacks and multipliers are
    /// pushed into the interior by the solve. The next solve that iterates consumes it; a solve whose
    /// unconstrained minimiser is feasible returns before reading it and leaves it armed.
    #[inline]
    pub fn warm_start_mut(&mut self) -> (&mut [f64], &mut [f64]) {
        self.warm_start = true;
        (
            &mut self.start_x,
            &mut self.start_multiplier[..self.row_count],
        )
    }

    /// The solution of the last solve (length `n`).
    #[inline]
    pub fn x(&self) -> &[f64] {
        &self.x
    }

    /// The multipliers `λ ≥ 0` of the rows at the last solve (length [`BandedQp::row_count`]), in the
    /// units of the cost per unit of the row.
    #[inline]
    pub fn multipliers(&self) -> &[f64] {
        &self.multiplier[..self.row_count]
    }

    /// The slacks `s = d − Cx ≥ 0` of the rows at the last solve (length [`BandedQp::row_count`]).
    #[inline]
    pub fn slacks(&self) -> &[f64] {
        &self.slack[..self.row_count]
    }

    /// The constraint rows expanded to sparse rows over the variables, in row order (for the
    /// general-purpose solvers).
    pub(super) fn sparse_rows(&self) -> impl Iterator<Item = SparseRow> + '_ {
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
}
