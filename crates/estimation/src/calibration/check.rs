//! Input checks and the gravity-response fit shared by the calibration methods.

use nalgebra::{SVector, Vector3, Vector6};

use super::lsq::{LeastSquaresSolution, StackedLeastSquares, RANK_TOLERANCE};
use super::offset::MIN_POSES;
use super::CalibrationError;

/// Readings paired with gravity samples: same count, at least [`MIN_POSES`], all finite.
pub(crate) fn check_pairs(
    what: &'static str,
    raw: &[Vector6<f64>],
    gravity: &[Vector3<f64>],
) -> Result<(), CalibrationError> {
    if raw.len() != gravity.len() {
        return Err(CalibrationError::Size {
            what: "gravity samples (one per raw reading)",
            expected: raw.len(),
            actual: gravity.len(),
        });
    }
    if raw.len() < MIN_POSES {
        return Err(CalibrationError::TooFewSamples {
            what,
            needed: MIN_POSES,
            got: raw.len(),
        });
    }
    check_finite6("raw reading", raw)?;
    check_finite3("gravity", gravity)
}

/// Least squares of `y_i = K g_i + λ` over the samples (`K` D × 3, `λ` D), stacked with
/// `vec(K g) = (gᵀ ⊗ 1_D) vec(K)` [Traversaro 2017, eq. (2.9)]: unknowns `(vec K, λ)`, `4 D`. Refused
/// ([`CalibrationError::NotIdentifiable`]) when the gravity samples do not span an affine 3D set.
pub(crate) fn fit_gravity_response<const D: usize>(
    what: &'static str,
    samples: impl Iterator<Item = (SVector<f64, D>, Vector3<f64>)>,
) -> Result<LeastSquaresSolution, CalibrationError> {
    let unknowns = 4 * D;
    let mut ls = StackedLeastSquares::new(unknowns);
    let mut row = vec![0.0; unknowns];
    for (y, g) in samples {
        for a in 0..D {
            row.fill(0.0);
            for c in 0..3 {
                row[D * c + a] = g[c];
            }
            row[3 * D + a] = 1.0;
            ls.add_row(&row, y[a]);
        }
    }
    let sol = ls.solve(RANK_TOLERANCE);
    if sol.rank < unknowns {
        return Err(CalibrationError::NotIdentifiable {
            what,
            rank: sol.rank,
            unknowns,
            hint: "rotate the sensor so that gravity takes directions off one plane (two axes)",
        });
    }
    Ok(sol)
}

/// Every sample finite, or the index of the first that is not.
fn check_finite6(what: &'static str, v: &[Vector6<f64>]) -> Result<(), CalibrationError> {
    match v.iter().position(|x| !x.iter().all(|e| e.is_finite())) {
        Some(index) => Err(CalibrationError::NonFinite { what, index }),
        None => Ok(()),
    }
}

/// Every sample finite, or the index of the first that is not.
fn check_finite3(what: &'static str, v: &[Vector3<f64>]) -> Result<(), CalibrationError> {
    match v.iter().position(|x| !x.iter().all(|e| e.is_finite())) {
        Some(index) => Err(CalibrationError::NonFinite { what, index }),
        None => Ok(()),
    }
}
