//! Input checks shared by the calibration methods.

use nalgebra::{Vector3, Vector6};

use super::CalibrationError;

/// Every sample finite, or the index of the first that is not.
pub(crate) fn check_finite6(
    what: &'static str,
    v: &[Vector6<f64>],
) -> Result<(), CalibrationError> {
    match v.iter().position(|x| !x.iter().all(|e| e.is_finite())) {
        Some(index) => Err(CalibrationError::NonFinite { what, index }),
        None => Ok(()),
    }
}

/// Every sample finite, or the index of the first that is not.
pub(crate) fn check_finite3(
    what: &'static str,
    v: &[Vector3<f64>],
) -> Result<(), CalibrationError> {
    match v.iter().position(|x| !x.iter().all(|e| e.is_finite())) {
        Some(index) => Err(CalibrationError::NonFinite { what, index }),
        None => Ok(()),
    }
}
