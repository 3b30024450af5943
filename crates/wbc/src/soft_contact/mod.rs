//! What the compliant TSID knows of soft ground [Romualdi 2022, ch. 8]: the closed-form contact wrench of a
//! rectangular sole on visco-elastic ground and its rate ([`model`]) and the online estimate of the ground's
//! stiffness and damping ([`estimator`]).

pub mod estimator;
pub mod model;

pub use estimator::{EstimatorSettings, GroundEstimator};
pub use model::{GroundParameters, SoleAcceleration, SoleGeometry, SoleState, WrenchRate};
