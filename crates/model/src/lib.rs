//! # stride-model
//!
//! Floating-base rigid-body kinematics and dynamics for stride: URDF loading (urdf-rs), forward kinematics,
//! frame Jacobians and `J̇ν`, centre of mass, centroidal momentum, mass matrix (CRBA), bias/gravity forces and
//! inverse dynamics (RNEA), forward dynamics (ABA), in the mixed (default), body and inertial velocity
//! representations with iDynTree semantics.
//!
//! ```no_run
//! use std::sync::Arc;
//! use stride_model::{KinDyn, Model, RobotState};
//! let model = Arc::new(Model::from_urdf_file("models/stride_humanoid.urdf")?);
//! let mut kd = KinDyn::new(Arc::clone(&model));
//! kd.set_state(&RobotState::zero(&model))?;
//! let sole = model.frame_id("l_sole").expect("frame");
//! let pose = kd.frame_pose(sole);
//! # let _ = pose;
//! # Ok::<(), stride_model::ModelError>(())
//! ```
//!
//! Conventions: 6D vectors are `[linear; angular]`; generalized velocity `ν = [base linear; base angular;
//! joints]`; the base part of generalized forces is the wrench dual to the base velocity of the selected
//! representation. See `docs/model.md`.

#![warn(missing_docs)]

pub mod bundled;
mod edits;
mod error;
pub mod inertial;
mod kindyn;
mod locks;
mod model;
pub mod spatial;
mod standing;
mod state;
mod urdf;

pub use edits::{InertiaEdits, LinkInertiaEdit};
pub use error::ModelError;
pub use kindyn::{ExternalWrench, KinDyn};
pub use locks::{glob_matches, JointLock};
pub use model::{
    Body, Frame, FrameId, FrameKind, FtSensor, Joint, JointKind, Mimic, Model, STANDARD_GRAVITY,
};
pub use state::{
    check_joint_limits, convert_velocity, se3_exp, RobotState, VelocityRepresentation,
};

/// What a user of the model needs in scope: `use stride_model::prelude::*;` (the model is not a layer, so
/// no `Block` here).
pub mod prelude {
    pub use crate::{
        bundled, ExternalWrench, FrameId, KinDyn, Model, ModelError, RobotState,
        VelocityRepresentation, STANDARD_GRAVITY,
    };
    pub use nalgebra;
}

impl Model {
    /// Loads a model from a URDF file. Fixed joints are merged (inertias lumped, child links kept as frames);
    /// see [`Model::from_urdf_str`].
    pub fn from_urdf_file(path: impl AsRef<std::path::Path>) -> Result<Model, ModelError> {
        urdf::load_file(path.as_ref())
    }

    /// Loads a model from URDF text. Revolute, continuous and prismatic joints are degrees of freedom; fixed
    /// joints are merged; floating and planar joints are rejected. Warnings (inconsistent inertias, missing
    /// limits, massless bodies) are in [`Model::warnings`] and are also emitted with `tracing::warn!`.
    pub fn from_urdf_str(urdf: &str) -> Result<Model, ModelError> {
        urdf::load_str(urdf)
    }

    /// Loads a model from a URDF file with its inertial parameters edited (a plant that differs from the
    /// controllers' model); see [`Model::from_urdf_str_edited`].
    pub fn from_urdf_file_edited(
        path: impl AsRef<std::path::Path>,
        edits: &InertiaEdits,
    ) -> Result<Model, ModelError> {
        urdf::load_file_edited(path.as_ref(), edits)
    }

    /// Loads a model from URDF text with the inertial parameters of its links edited before fixed joints are
    /// merged: every link's mass and rotational inertia (about its CoM) are scaled by `edits.mass_scale`,
    /// then each listed link's by its own `mass_scale`, and its CoM is moved by its `com_offset` (m, link
    /// frame). Moving link `l`'s CoM by `d` moves the robot's CoM by `m_l d / M` (world orientation of the
    /// link frame).
    ///
    /// # Errors
    /// Those of [`Model::from_urdf_str`], and [`ModelError::InvalidInertiaEdit`] for an unknown link, a
    /// non-positive or non-finite scale or a non-finite offset.
    pub fn from_urdf_str_edited(urdf: &str, edits: &InertiaEdits) -> Result<Model, ModelError> {
        urdf::load_str_edited(urdf, edits)
    }

    /// Loads a reduced model from URDF text: the inertial parameters edited as in
    /// [`Model::from_urdf_str_edited`], and every movable joint matched by `locks` turned into a fixed
    /// joint at its locked position (Pinocchio's `buildReducedModel`): its child link is placed at the
    /// joint's origin moved by the locked position, merged into the parent body (inertia lumped, the link
    /// and its frames kept as frames). The reduced model's mass matrix, bias forces, CoM and frame poses
    /// equal the full model's with the locked joints held still at their positions (rows and columns of
    /// the remaining degrees of freedom).
    ///
    /// # Errors
    /// Those of [`Model::from_urdf_str_edited`], and [`ModelError::InvalidLock`] for a non-finite position,
    /// a name or glob that matches no movable joint, or a joint locked at two positions.
    pub fn from_urdf_str_reduced(
        urdf: &str,
        edits: &InertiaEdits,
        locks: &[JointLock],
    ) -> Result<Model, ModelError> {
        urdf::load_str_reduced(urdf, edits, locks)
    }

    /// [`Model::from_urdf_str_reduced`] on a file.
    pub fn from_urdf_file_reduced(
        path: impl AsRef<std::path::Path>,
        edits: &InertiaEdits,
        locks: &[JointLock],
    ) -> Result<Model, ModelError> {
        urdf::load_file_reduced(path.as_ref(), edits, locks)
    }
}
