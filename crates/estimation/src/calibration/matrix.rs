//! The calibration matrix of a six-axis force/torque sensor from datasets with known added masses
//! [Traversaro 2017, §5.3.3, eq. (5.11), Lemma 5.2].

use nalgebra::{DVector, Matrix3, Matrix6, Matrix6x3, Vector3, Vector6};

use super::check::{check_pairs, fit_gravity_response};
use super::drift::{gravity_response_with_drift, DriftNoise};
use super::lsq::{LeastSquaresSolution, StackedLeastSquares, RANK_TOLERANCE};
use super::CalibrationError;

/// Unknowns of (5.11): `vec(C)` (36), the body's mass and first moment `m c` (4).
pub const MATRIX_UNKNOWNS: usize = 40;

/// One dataset of (5.11): static poses of the sensor's body carrying a known added mass.
#[derive(Clone, Copy, Debug)]
pub struct AddedMassDataset<'a> {
    /// Times of the readings, s (increasing; read by [`OffsetModel::RandomWalk`] only: may be empty with
    /// [`OffsetModel::Constant`]).
    pub times: &'a [f64],
    /// Raw readings `r_i`.
    pub raw: &'a [Vector6<f64>],
    /// The load acceleration `g_i` at each reading, sensor frame (m/s²): gravity when the sensor reads the
    /// wrench its attached body exerts on it, minus gravity when it reads the opposite; the reading is then
    /// `C⁻¹ M(m, c) g_i + b` (5.2a, 5.4).
    pub gravity: &'a [Vector3<f64>],
    /// Added mass `m_a`, kg (0 for the bare body).
    pub added_mass: f64,
    /// Centre of mass of the added mass, sensor frame, m.
    pub added_com: Vector3<f64>,
}

/// How the offset `b` behaves within one dataset (stage 1 of [`calibration_matrix`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OffsetModel {
    /// Constant over the dataset, as in (5.1) and (5.10): `r_i = D g_i + b`, ordinary least squares, and
    /// stage 2 unweighted.
    Constant,
    /// A random walk under white noise ([`super::gravity_response_with_drift`]): `D` by a Kalman filter per axis, and stage 2
    /// weighted by the covariance of `D`.
    RandomWalk(DriftNoise),
}

/// The result of [`calibration_matrix`].
#[derive(Clone, Debug)]
pub struct CalibrationMatrixFit {
    /// `C` of `f = C (r − b)` (5.1).
    pub matrix: Matrix6<f64>,
    /// Mass of the body attached to the sensor, kg.
    pub mass: f64,
    /// Its first moment `m c`, sensor frame, kg·m.
    pub first_moment: Vector3<f64>,
    /// The offset `b` of each dataset (raw units): the constant one, or with [`OffsetModel::RandomWalk`]
    /// the offset at the dataset's last reading.
    pub offsets: Vec<Vector6<f64>>,
    /// Singular values of the stacked system (5.11), decreasing.
    pub singular_values: DVector<f64>,
}

/// `M(m, c) = [m 1₃; m c^]` (5.2b): the wrench `[f; τ]` about the sensor origin of a body of mass `m` and
/// first moment `h = m c` under the acceleration `g`, as `M g`.
pub fn gravity_wrench_matrix(mass: f64, first_moment: &Vector3<f64>) -> Matrix6x3<f64> {
    let mut m = Matrix6x3::zeros();
    m.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(Matrix3::identity() * mass));
    m.fixed_view_mut::<3, 3>(3, 0)
        .copy_from(&first_moment.cross_matrix());
    m
}

/// The calibration matrix `C`, the body's mass and first moment, and each dataset's offset, from
/// `datasets` taken with different known added masses [Traversaro 2017, §5.3.3]. Two stages:
///
/// 1. per dataset `j`, `r_i = D_j g_i + b_j` by least squares (`D_j = C⁻¹ M_j`, 6 × 3; the 6D form of (5.10),
///    which also removes the offset): the regressor is the gravity, so the reading noise does not bias
///    `D_j`;
/// 2. `C D_j − M_b = M_a^j` for all `j` (5.11 with `R_j` replaced by its fit `D_j G_j`), `M_b = M(m, m c)`
///    the body, `M_a^j = M(m_a^j, m_a^j c_a^j)` the added mass, stacked as
///    `(D_jᵀ ⊗ 1₆) vec(C) − H (m; m c) = vec(M_a^j)` and solved by least squares for the 40 unknowns.
///
/// The rank of the stacked system is checked before solving: each dataset adds 18 equations, so two give
/// at most 36 < 40 and [`CalibrationError::TooFewDatasets`] is returned, as Lemma 5.2 states (three
/// datasets with different added masses are needed).
///
/// With [`OffsetModel::RandomWalk`], stage 1 is [`gravity_response_with_drift`] and stage 2 is weighted
/// (ours, not in the thesis): the error of equation `(a, c)` of dataset `j` is `Σ_k C[a, k] δD_j[k, c]`,
/// so the three equations `(a, ·)` get the covariance `Σ_k C[a, k]² P_{j,k}` (`P_{j,k}` the covariance
/// of row `k` of `D_j`; the rows' errors are independent) and are whitened by it; solved once with
/// `C = 1` in the weights, then again with that estimate.
pub fn calibration_matrix(
    datasets: &[AddedMassDataset<'_>],
    offsets: &OffsetModel,
) -> Result<CalibrationMatrixFit, CalibrationError> {
    let mut fits = Vec::with_capacity(datasets.len());
    for d in datasets {
        fits.push(fit_dataset(d, offsets)?);
    }
    let first = solve_stacked(datasets, &fits, None)?;
    let sol = match offsets {
        OffsetModel::Constant => first,
        OffsetModel::RandomWalk(_) => {
            let c = Matrix6::from_column_slice(&first.x.as_slice()[0..36]);
            solve_stacked(datasets, &fits, Some(&c))?
        }
    };
    Ok(CalibrationMatrixFit {
        matrix: Matrix6::from_column_slice(&sol.x.as_slice()[0..36]),
        mass: sol.x[36],
        first_moment: Vector3::new(sol.x[37], sol.x[38], sol.x[39]),
        offsets: fits.into_iter().map(|f| f.offset).collect(),
        singular_values: sol.singular_values,
    })
}

/// Stage 2: `C D_j − M_b = M_a^j` stacked over the datasets and solved after the rank check. Each block of
/// three equations `(a, ·)` is whitened by the covariance of its error when stage 1 gave one (with the
/// weights' `C` taken as `weights_c`, identity when `None`); unweighted otherwise.
fn solve_stacked(
    datasets: &[AddedMassDataset<'_>],
    fits: &[DatasetFit],
    weights_c: Option<&Matrix6<f64>>,
) -> Result<LeastSquaresSolution, CalibrationError> {
    let mut ls = StackedLeastSquares::new(MATRIX_UNKNOWNS);
    let mut rows = [[[0.0; MATRIX_UNKNOWNS]; 3]; 6];
    let mut weighted = [0.0; MATRIX_UNKNOWNS];
    for (d, fit) in datasets.iter().zip(fits) {
        let ma = gravity_wrench_matrix(d.added_mass, &(d.added_com * d.added_mass));
        fill_equations(&fit.response, &mut rows);
        let Some(p) = &fit.row_covariance else {
            for c in 0..3 {
                for (a, block) in rows.iter().enumerate() {
                    ls.add_row(&block[c], ma[(a, c)]);
                }
            }
            continue;
        };
        for (a, block) in rows.iter().enumerate() {
            let rhs = Vector3::new(ma[(a, 0)], ma[(a, 1)], ma[(a, 2)]);
            let whiten = whitening(p, a, weights_c)?;
            for w_row in whiten.row_iter() {
                weighted.fill(0.0);
                for (c, row) in block.iter().enumerate() {
                    for (out, v) in weighted.iter_mut().zip(row) {
                        *out += w_row[c] * v;
                    }
                }
                ls.add_row(&weighted, w_row.dot(&rhs.transpose()));
            }
        }
    }
    let sol = ls.solve(RANK_TOLERANCE);
    if sol.rank < MATRIX_UNKNOWNS {
        return Err(CalibrationError::TooFewDatasets {
            datasets: datasets.len(),
            rank: sol.rank,
            unknowns: MATRIX_UNKNOWNS,
        });
    }
    Ok(sol)
}

/// The equations `(C D_j − M_b)[a, c]` of one dataset as rows over the unknowns `(vec C, m, m c)`:
/// `rows[a][c]`.
fn fill_equations(dj: &Matrix6x3<f64>, rows: &mut [[[f64; MATRIX_UNKNOWNS]; 3]; 6]) {
    for (a, block) in rows.iter_mut().enumerate() {
        for (c, row) in block.iter_mut().enumerate() {
            row.fill(0.0);
            // (C D_j)[a, c] = Σ_k C[a, k] D_j[k, c]; vec(C) is column-major: C[a, k] at 6k + a.
            for k in 0..6 {
                row[6 * k + a] = dj[(k, c)];
            }
            // −M_b[a, c]: the mass on the force diagonal, the first moment in its skew block.
            if a < 3 && a == c {
                row[36] = -1.0;
            }
            if a >= 3 {
                for i in 0..3 {
                    row[37 + i] = -skew_derivative(i)[(a - 3, c)];
                }
            }
        }
    }
}

/// `W` with `Wᵀ W = Σ⁻¹`, `Σ = Σ_k C[a, k]² P_k` the covariance of equation block `a`'s error.
fn whitening(
    p: &[Matrix3<f64>; 6],
    a: usize,
    c: Option<&Matrix6<f64>>,
) -> Result<Matrix3<f64>, CalibrationError> {
    let mut sigma = Matrix3::zeros();
    for (k, pk) in p.iter().enumerate() {
        let w = match c {
            Some(c) => c[(a, k)],
            None => f64::from(u8::from(a == k)),
        };
        sigma += pk * (w * w);
    }
    let info =
        sigma
            .try_inverse()
            .and_then(|i| i.cholesky())
            .ok_or(CalibrationError::NonFinite {
                what: "covariance of the gravity response (not positive definite)",
                index: a,
            })?;
    // info = L Lᵀ: W = Lᵀ.
    Ok(info.l().transpose())
}

/// `∂ h^ / ∂ h_i`: the skew matrix of the unit vector `e_i`.
fn skew_derivative(i: usize) -> Matrix3<f64> {
    let mut e = Vector3::zeros();
    e[i] = 1.0;
    e.cross_matrix()
}

/// Stage 1's result for one dataset.
struct DatasetFit {
    response: Matrix6x3<f64>,
    offset: Vector6<f64>,
    /// Covariance of each row of `response` (random-walk model only).
    row_covariance: Option<[Matrix3<f64>; 6]>,
}

/// Stage 1: `r_i = D g_i + b` by least squares (24 unknowns), or with a drifting offset.
fn fit_dataset(
    d: &AddedMassDataset<'_>,
    offsets: &OffsetModel,
) -> Result<DatasetFit, CalibrationError> {
    check_pairs("calibration dataset", d.raw, d.gravity)?;
    if !d.added_mass.is_finite() || !d.added_com.iter().all(|v| v.is_finite()) {
        return Err(CalibrationError::NonFinite {
            what: "added mass or its centre",
            index: 0,
        });
    }
    if let OffsetModel::RandomWalk(noise) = offsets {
        let fit = gravity_response_with_drift(d.times, d.raw, d.gravity, noise)?;
        return Ok(DatasetFit {
            response: fit.response,
            offset: fit.final_offset,
            row_covariance: Some(fit.row_covariance),
        });
    }
    let sol = fit_gravity_response(
        "a dataset's gravity response",
        d.raw.iter().copied().zip(d.gravity.iter().copied()),
    )?;
    Ok(DatasetFit {
        response: Matrix6x3::from_column_slice(&sol.x.as_slice()[0..18]),
        offset: Vector6::from_column_slice(&sol.x.as_slice()[18..24]),
        row_covariance: None,
    })
}
