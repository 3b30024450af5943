//! `stride-estimation`: the estimation layer. It turns what a robot senses (encoders, an IMU, six-axis
//! force/torque sensors) into what the controllers need: the floating-base state, the feet in contact, the
//! wrench the ground applies on each foot and the joint torques [Traversaro 2017, ch. 4].
//!
//! Like every stride layer it is a [`stride_block::Block`]: data-only [`EstimatorInput`] in,
//! [`EstimatorOutput`] out, no allocation after construction.

#![warn(missing_docs)]

mod io;

pub use io::{EstimatorInput, EstimatorOutput, ImuReading};
