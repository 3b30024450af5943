//! What a whole-body controller needs to know of soft ground [Romualdi 2022, ch. 8]: the closed-form wrench of a
//! rectangular sole on visco-elastic ground and its rate ([`model`]) and the online estimate of the ground's
//! stiffness and damping ([`estimator`]): the building blocks of the compliant TSID of §8.2
//! ([`crate::ContactModel::Compliant`], see docs/soft-ground.md).

pub mod estimator;
pub mod model;

pub use estimator::{EstimatorSettings, GroundEstimator, GroundRestEstimator};
pub use model::{GroundParameters, SoleAcceleration, SoleGeometry, SoleState, WrenchRate};
