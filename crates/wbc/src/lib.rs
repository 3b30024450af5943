//! `stride-wbc`: the whole-body QP layer of stride — a task library, the kinematic QP-IK
//! [Romualdi 2022, eq. 7.1.16] and the torque TSID [Romualdi 2022, eq. 7.2.31], both on stride-qp.
//!
//! * [`QpIk`]: decision variable ν (mixed base twist + joint velocities); hard feet SE(3) and CoM, soft
//!   torso orientation and posture, joint position/velocity limits as bounds; integrates its own state
//!   on SE(3) × Rⁿ and outputs joint position commands (position-controlled robots) and velocities.
//! * [`Tsid`]: decision variables ν̇ and the contact wrenches of the loaded feet (torques eliminated
//!   through the joint rows of the floating-base dynamics); outputs joint torques, accelerations and
//!   planned contact wrenches; contact changes ramp the normal-force bound.
//!
//! Both draw their rows from one task library (`tasks/`, one file per task family, written straight into
//! stride-qp's task storage) and are built from a [`IkConfig`] / [`TsidConfig`] (TOML, a list of typed
//! tasks; a soft task's [`Weight`] is stride-qp's) and the control period, and implement
//! [`stride_block::Block`] with [`WbcInput`] as input. Failed QPs fall back to the relaxed problem
//! (hard equalities as heavily weighted costs) and, if that also fails, hold the last valid command;
//! the output says which. See docs/wbc.md for the formulation choices and measured numbers.

#![warn(missing_docs)]

pub mod actuators;
mod bridge;
mod builder;
pub mod config;
mod error;
mod ik;
mod io;
pub mod math;
mod names;
pub mod presets;
pub mod soft_contact;
mod tasks;
mod tsid;

pub use actuators::{ActuatorCompensation, ActuatorConfig};
pub use builder::{IkConfigBuilder, TsidConfigBuilder};
pub use config::*;
pub use error::WbcError;
pub use ik::QpIk;
pub use io::*;
pub use soft_contact::{
    EstimatorSettings, GroundEstimator, GroundParameters, GroundRestEstimator, SoleAcceleration,
    SoleGeometry, SoleState, WrenchRate,
};
pub use stride_block::Block;
pub use stride_qp::QpStatus;
pub use tsid::Tsid;
pub use {nalgebra, stride_model};

/// Everything a controller built on stride-wbc usually needs: `use stride_wbc::prelude::*;`.
pub mod prelude {
    pub use crate::builder::{IkConfigBuilder, TsidConfigBuilder};
    pub use crate::config::{
        walking, ContactTaskConfig, IkConfig, Priority, Se3TaskConfig, TaskConfig, TsidConfig,
        Weight,
    };
    pub use crate::io::{
        ContactId, ContactInput, FrameRefId, FrameReference, IkOutput, InputLayout, SolveReport,
        TsidOutput, WbcInput,
    };
    pub use crate::{QpIk, Tsid, WbcError};
    pub use nalgebra;
    pub use stride_block::Block;
    pub use stride_qp::QpStatus;
}
