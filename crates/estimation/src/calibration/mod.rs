//! In-situ calibration of six-axis force/torque sensors [Traversaro 2017, ch. 5]: the raw output `r` of a
//! sensor is affine in the wrench, `f = C (r − b)` (5.1), with an offset `b` that drifts in hours
//! (temperature) and a calibration matrix `C` that drifts in months. Both are found from data the robot
//! records while the body attached to the sensor is moved through rotations (no external wrench but
//! gravity and the body's own dynamics):
//!
//! * [`offset_from_rotations`]: `b` from static poses, knowing neither `C` nor the body (5.6)–(5.10);
//! * [`RegressorOffset`]: `b` jointly with the body's inertial parameters by least squares on the model's
//!   force/torque-sensor regressor (7.2)–(7.3), `C` taken as identity; works during motion;
//! * [`calibration_matrix`]: `C` (and the body's mass and first moment) from at least three datasets with
//!   known added masses (5.11), refusing fewer as Lemma 5.2 requires; the offset constant per dataset or a
//!   random walk ([`OffsetModel`], [`gravity_response_with_drift`]).
//!
//! `docs/identification.md`, "FT calibration", has the figures and `stride calibrate`, the command that
//! runs them on a log.

mod check;
mod drift;
mod error;
mod lsq;
mod matrix;
mod offset;
mod regressor;

pub use drift::{gravity_response_with_drift, DriftFit, DriftNoise};
pub use error::CalibrationError;
pub use lsq::{LeastSquaresSolution, StackedLeastSquares, RANK_TOLERANCE};
pub use matrix::{
    calibration_matrix, gravity_wrench_matrix, AddedMassDataset, CalibrationMatrixFit, OffsetModel,
    MATRIX_UNKNOWNS,
};
pub use offset::{offset_from_rotations, RotationOffset, MIN_POSES};
pub use regressor::{child_side_columns, RegressorOffset, RegressorOffsetFit};
