//! Why an identification was refused.

/// Everything that can stop an inertial-parameter identification.
#[derive(Debug, thiserror::Error)]
pub enum IdentificationError {
    /// Inputs of different lengths or a regressor block of the wrong shape.
    #[error("{what}: expected {expected}, got {actual}")]
    Size {
        /// Which input.
        what: &'static str,
        /// Expected size.
        expected: usize,
        /// Actual size.
        actual: usize,
    },
    /// A sample, a weight or an option is NaN, infinite or out of range.
    #[error("{what} is not valid (entry {index}): {reason}")]
    Invalid {
        /// Which input.
        what: &'static str,
        /// Index of the offending row or entry.
        index: usize,
        /// What is wrong.
        reason: &'static str,
    },
    /// No rows were added.
    #[error("no measurements: add regressor rows before solving")]
    NoData,
}
