//! The calibration matrix of a six-axis force/torque sensor from datasets with known added masses
//! [Traversaro 2017, §5.3.3, eq. (5.11), Lemma 5.2].

use nalgebra::{DVector, Matrix3, Matrix6, Matrix6x3, Vector3, Vector6};

use super::check::{check_pairs, fit_gravity_response};
use super::lsq::{StackedLeastSquares, RANK_TOLERANCE};
use super::CalibrationError;

/// Unknowns of (5.11): `vec(C)` (36), the body's mass and first moment `m c` (4).
pub const MATRIX_UNKNOWNS: usize = 40;

/// One dataset of (5.11): static poses of the sensor's body carrying a known added mass.
#[derive(Clone, Copy, Debug)]
pub struct AddedMassDataset<'a> {
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

/// The result of [`calibration_matrix`].
#[derive(Clone, Debug)]
pub struct CalibrationMatrixFit {
    /// `C` of `f = C (r − b)` (5.1).
    pub matrix: Matrix6<f64>,
    /// Mass of the body attached to the sensor, kg.
    pub mass: f64,
    /// Its first moment `m c`, sensor frame, kg·m.
    pub first_moment: Vector3<f64>,
    /// The offset `b` of each dataset (raw units).
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
pub fn calibration_matrix(
    datasets: &[AddedMassDataset<'_>],
) -> Result<CalibrationMatrixFit, CalibrationError> {
    let mut fits = Vec::with_capacity(datasets.len());
    for d in datasets {
        fits.push(fit_dataset(d)?);
    }
    let mut ls = StackedLeastSquares::new(MATRIX_UNKNOWNS);
    let mut row = [0.0; MATRIX_UNKNOWNS];
    for (d, (dj, _)) in datasets.iter().zip(&fits) {
        let ma = gravity_wrench_matrix(d.added_mass, &(d.added_com * d.added_mass));
        for c in 0..3 {
            for a in 0..6 {
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
                ls.add_row(&row, ma[(a, c)]);
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
    Ok(CalibrationMatrixFit {
        matrix: Matrix6::from_column_slice(&sol.x.as_slice()[0..36]),
        mass: sol.x[36],
        first_moment: Vector3::new(sol.x[37], sol.x[38], sol.x[39]),
        offsets: fits.into_iter().map(|(_, b)| b).collect(),
        singular_values: sol.singular_values,
    })
}

/// `∂ h^ / ∂ h_i`: the skew matrix of the unit vector `e_i`.
fn skew_derivative(i: usize) -> Matrix3<f64> {
    let mut e = Vector3::zeros();
    e[i] = 1.0;
    e.cross_matrix()
}

/// Stage 1: `r_i = D g_i + b` by least squares (24 unknowns).
fn fit_dataset(
    d: &AddedMassDataset<'_>,
) -> Result<(Matrix6x3<f64>, Vector6<f64>), CalibrationError> {
    check_pairs("calibration dataset", d.raw, d.gravity)?;
    if !d.added_mass.is_finite() || !d.added_com.iter().all(|v| v.is_finite()) {
        return Err(CalibrationError::NonFinite {
            what: "added mass or its centre",
            index: 0,
        });
    }
    let sol = fit_gravity_response(
        "a dataset's gravity response",
        d.raw.iter().copied().zip(d.gravity.iter().copied()),
    )?;
    let dj = Matrix6x3::from_column_slice(&sol.x.as_slice()[0..18]);
    let b = Vector6::from_column_slice(&sol.x.as_slice()[18..24]);
    Ok((dj, b))
}
