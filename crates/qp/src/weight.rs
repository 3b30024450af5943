//! The weight of a soft task, one type from the configuration file to the QP.

use serde::{Deserialize, Serialize};

use crate::error::QpError;

/// Weight `W = diag(w)` of a soft equality task `½‖W^{1/2}(A x − b)‖²`: one number for every row, or one
/// per row. Dimensionless relative to the task's residual units squared; every entry finite and ≥ 0.
///
/// Deserialized from TOML as a number (`weight = 5.0`) or an array (`weight = [1.0, 1.0, 10.0]`). Hard
/// tasks carry no weight (a weight given to one is a configuration error, [`QpError::WeightOnHardTask`]).
///
/// ```
/// use stride_qp::Weight;
/// assert_eq!(Weight::Scalar(2.0).row(3), 2.0);
/// assert_eq!(Weight::PerRow(vec![1.0, 4.0]).row(1), 4.0);
/// assert!(Weight::PerRow(vec![1.0, 4.0]).validate("t", 3).is_err());
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Weight {
    /// The same weight on every row.
    Scalar(f64),
    /// One weight per row.
    PerRow(Vec<f64>),
}

impl Default for Weight {
    fn default() -> Self {
        Weight::Scalar(1.0)
    }
}

impl Weight {
    /// The entries as given: one (scalar) or one per row.
    pub fn as_slice(&self) -> &[f64] {
        match self {
            Weight::Scalar(w) => std::slice::from_ref(w),
            Weight::PerRow(v) => v,
        }
    }

    /// Weight of row `i` (a per-row list must be long enough: see [`Weight::validate`]).
    pub fn row(&self, i: usize) -> f64 {
        match self {
            Weight::Scalar(w) => *w,
            Weight::PerRow(v) => v[i],
        }
    }

    /// The weights of a task with `rows` rows; `None` when a per-row list has the wrong length.
    pub fn expand(&self, rows: usize) -> Option<Vec<f64>> {
        match self {
            Weight::Scalar(w) => Some(vec![*w; rows]),
            Weight::PerRow(v) if v.len() == rows => Some(v.clone()),
            Weight::PerRow(_) => None,
        }
    }

    /// Checks the weight of task `task` with `rows` rows: one entry or `rows` entries
    /// ([`QpError::WeightSize`]), each finite and ≥ 0 ([`QpError::InvalidWeight`]).
    pub fn validate(&self, task: &str, rows: usize) -> Result<(), QpError> {
        check_weights(task, self.as_slice(), rows)
    }
}

/// Checks a weight given as a slice (one entry or `rows` entries, each finite and ≥ 0). Allocation-free
/// unless it fails.
pub(crate) fn check_weights(task: &str, weights: &[f64], rows: usize) -> Result<(), QpError> {
    if weights.len() != 1 && weights.len() != rows {
        return Err(QpError::WeightSize {
            task: task.to_owned(),
            expected: rows,
            got: weights.len(),
        });
    }
    for (row, &w) in weights.iter().enumerate() {
        if !(w >= 0.0 && w.is_finite()) {
            return Err(QpError::InvalidWeight {
                task: task.to_owned(),
                row,
                value: w,
            });
        }
    }
    Ok(())
}
