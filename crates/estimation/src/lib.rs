//! `stride-estimation`: the estimation layer. It turns what a robot senses (encoders, an IMU, six-axis
//! force/torque sensors) into what the controllers need: the floating-base state, the feet in contact, the
//! wrench the ground applies on each foot and the joint torques [Traversaro 2017, ch. 4].
//!
//! Like every stride layer it is a [`stride_block::Block`]: data-only [`EstimatorInput`] in,
//! [`EstimatorOutput`] out, no allocation after construction. The pipeline of one tick is in
//! [`Estimator`]; `docs/estimation.md` describes it with every configuration key.

#![warn(missing_docs)]

pub mod calibration;
mod config;
pub mod ekf;
mod error;
mod estimator;
mod flexible;
pub mod identification;
mod io;
mod joint_velocity;
mod schmitt;
pub mod sole_sink;
pub mod sole_spin;
mod stance_leg;
mod standing;

pub use config::{ContactConfig, EkfConfig, EkfPrior, EstimatorConfig, FtOffsetConfig};
pub use ekf::{EkfState, InvariantEkf};
pub use error::{EstimatorError, Result};
pub use estimator::Estimator;
pub use flexible::{FlexibleJoint, FlexibleJointObserver};
pub use io::{EstimatorInput, EstimatorOutput, ImuReading};
pub use joint_velocity::JointVelocityFilter;
pub use schmitt::SchmittTrigger;
pub use standing::standing_foot_wrenches;

/// What a user of the estimation layer needs in scope: `use stride_estimation::prelude::*;`.
pub mod prelude {
    pub use crate::{
        Estimator, EstimatorConfig, EstimatorError, EstimatorInput, EstimatorOutput, ImuReading,
    };
    pub use nalgebra;
    pub use stride_block::Block;
}
