//! `stride-mujoco`: MuJoCo 3.17 as a plant of stride, a physics engine nobody on the team wrote.
//!
//! With the `mujoco` feature (it needs MuJoCo's library: `MUJOCO_DYNAMIC_LINK_DIR=$(bash
//! tools/mujoco/setup.sh)`), `MujocoRobot` builds a MuJoCo model from the scenario's URDF (compiled by
//! MuJoCo's own URDF parser, a free joint on the root link, a ground plane, the robot's collision geometry
//! restricted to the soles, `implicitfast`, timestep = the plant period), drives it with position servos or
//! torque motors per the scenario's `[sim.actuation]`, applies `[[sim.pushes]]` through `xfrc_applied`, and
//! reports the true state in stride's representation, the ground wrench on each sole, and the same sensors
//! as stride-sim (its sensor models, fed with MuJoCo's motion). Without the feature the crate is empty, so
//! the workspace builds without MuJoCo.
//!
//! See `docs/mujoco.md` for the choices and the measured figures.

#![warn(missing_docs)]

#[cfg(feature = "mujoco")]
mod actuators;
#[cfg(feature = "mujoco")]
mod config;
#[cfg(feature = "mujoco")]
mod error;
#[cfg(feature = "mujoco")]
mod inertia;
#[cfg(feature = "mujoco")]
mod limits;
#[cfg(feature = "mujoco")]
mod measure;
#[cfg(feature = "mujoco")]
mod robot;
#[cfg(feature = "mujoco")]
mod scene;
#[cfg(feature = "mujoco")]
mod state;
#[cfg(feature = "mujoco")]
mod urdf;

#[cfg(feature = "mujoco")]
pub use actuators::{resolve as resolve_servos, Servo};
#[cfg(feature = "mujoco")]
pub use config::{Cone, MujocoConfig, ServoSaturation};
#[cfg(feature = "mujoco")]
pub use error::MujocoError;
#[cfg(feature = "mujoco")]
pub use inertia::principal_inertia;
#[cfg(feature = "mujoco")]
pub use robot::{MujocoOutput, MujocoRobot, PlantSetup};
#[cfg(feature = "mujoco")]
pub use state::{state_from_mujoco, state_to_mujoco};
#[cfg(feature = "mujoco")]
pub use urdf::{prepare as prepare_urdf, resolve_package, UrdfEdit, UrdfStats};
