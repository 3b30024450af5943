//! Why a calibration was refused.

use stride_model::ModelError;

/// Everything that can stop an in-situ force/torque calibration [Traversaro 2017, ch. 5]. The data-driven
/// refusals ([`CalibrationError::NotIdentifiable`], [`CalibrationError::TooFewDatasets`]) are checked before
/// solving, so a calibration never returns numbers the data cannot determine.
#[derive(Debug, thiserror::Error)]
pub enum CalibrationError {
    /// Fewer samples than unknowns.
    #[error("{what}: {got} samples, at least {needed} needed")]
    TooFewSamples {
        /// What was being estimated.
        what: &'static str,
        /// Minimum number of samples.
        needed: usize,
        /// Samples given.
        got: usize,
    },
    /// A sample or an argument is NaN or infinite.
    #[error("non-finite {what} (sample {index})")]
    NonFinite {
        /// Which input.
        what: &'static str,
        /// Index of the sample.
        index: usize,
    },
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
    /// The data leave some of the sought quantities undetermined (the stacked regressor is rank deficient
    /// in their directions): e.g. the sensor was not rotated about two independent axes.
    #[error(
        "{what} is not determined by the data: the regressor has rank {rank} of {unknowns} ({hint})"
    )]
    NotIdentifiable {
        /// What cannot be determined.
        what: &'static str,
        /// Numerical rank of the stacked regressor.
        rank: usize,
        /// Number of unknowns.
        unknowns: usize,
        /// What would help.
        hint: &'static str,
    },
    /// The calibration matrix needs at least three datasets with different added masses
    /// [Traversaro 2017, Lemma 5.2].
    #[error(
        "the calibration matrix is not determined by {datasets} dataset(s): the stacked system (5.11) has \
         rank {rank} of {unknowns}; Lemma 5.2 needs at least 3 datasets with different added masses"
    )]
    TooFewDatasets {
        /// Datasets given.
        datasets: usize,
        /// Numerical rank of the stacked system.
        rank: usize,
        /// Number of unknowns (36 + 4).
        unknowns: usize,
    },
    /// The model could not evaluate a regressor.
    #[error(transparent)]
    Model(#[from] ModelError),
}
