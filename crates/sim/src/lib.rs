//! `stride-sim`: the simulated robot that closes stride's loop with no external simulator.
//!
//! A [`SimRobot`] integrates the floating-base dynamics of a [`stride_model::Model`] standing on a flat,
//! possibly inclined, compliant ground:
//!
//! * **Dynamics.** Semi-implicit Euler (velocity first, then the configuration with the new velocity; the base
//!   orientation on SO(3) with [`stride_model::RobotState::integrate`]). With the default
//!   [`IntegratorKind::Implicit`] scheme the joint servos, passive damping and contact spring-dampers are
//!   evaluated at the end of the step (linearly implicit), which keeps high-gain position servos and a rigid
//!   floor stable at 2 kHz; [`IntegratorKind::Explicit`] uses the articulated-body algorithm with every force
//!   explicit.
//! * **Contact.** Each contact surface (a foot sole) is a rectangle sampled by a grid of points; each point is
//!   a spring-damper along the ground normal that never pulls and a tangential stick spring anchored where
//!   the point touched down, limited by Coulomb's cone (it slides when the cone is reached). The stiffness
//!   and damping are area densities (N/m³, N·s/m³) of the visco-elastic contact model
//!   [Romualdi 2022, Lemma 1], so a fine grid reproduces that lemma's wrench.
//! * **Actuation** per joint: position PD servo, velocity servo or torque, with effort limits, passive
//!   damping, armature, Coulomb friction, a torque-tracking lag and a command delay; passive visco-elastic
//!   joints with no motor, `τ = −k q − b q̇` ([`PassiveJointConfig`], [Romualdi 2022, eq. (9.1.1)]).
//! * **Sensors** as an iCub-class robot has them: quantised encoders with differenced, low-passed
//!   velocities; an IMU with biases, noise and a filter-like orientation; the six-axis force/torque sensors
//!   of the URDF with offsets, drift, noise and saturation; a sensor delay; all from one seeded generator.
//!   Ground truth beside them. **Pushes** and **fall detection** from the config.
//!
//! See `docs/sim.md` for the choices, the checks and the measured numbers.

#![warn(missing_docs)]

mod actuator;
mod config;
mod contact;
mod error;
mod io;
mod linalg;
mod noise;
mod passive;
mod patches;
mod push;
mod robot;
mod sensors;
mod stops;

pub use config::{
    ActuationConfig, ActuationMode, ContactConfig, ContactSurfaceConfig, EffortLimitPolicy,
    EncoderConfig, FallConfig, FtSensorConfig, GroundConfig, GroundPatchConfig, ImuConfig,
    IntegratorKind, JointActuatorConfig, JointActuatorOverride, LinkInertiaChange,
    PlantModelConfig, PushConfig, SafetyConfig, SensorConfig, SimConfig, VelocitySource,
};
pub use contact::{surface_points, trapezoid_nodes, ContactMode, GroundPlane, PointLaw, PointSpec};
pub use error::SimError;
pub use io::{ContactPointState, ImuMeasurement, SimInput, SimOutput, SurfaceMeasurement};
pub use linalg::{cholesky_in_place, cholesky_solve_in_place, TreeCholesky, TreeMatrix};
pub use noise::GaussianNoise;
pub use passive::PassiveJointConfig;
pub use patches::{GroundCompliance, NormalDensities, TangentialDensities};
pub use robot::SimRobot;
/// The sensor models of [`SimRobot`] for another plant (stride-mujoco): fill a [`SensorTruth`] each step and
/// [`SensorModels::record`] returns the delayed [`SensorReading`].
pub use sensors::{Reading as SensorReading, Sensors as SensorModels, Truth as SensorTruth};
pub use stops::JointStopsConfig;

/// What a user of the simulator needs in scope: `use stride_sim::prelude::*;`.
pub mod prelude {
    pub use crate::{
        ActuationMode, ImuMeasurement, SimConfig, SimError, SimInput, SimOutput, SimRobot,
    };
    pub use nalgebra;
    pub use stride_block::Block;
}
