//! A robot standing on flat ground: the base pose that puts the soles on the ground plane.

use std::sync::Arc;

use nalgebra::{DVector, Isometry3, Translation3, Vector3};

use crate::error::ModelError;
use crate::kindyn::KinDyn;
use crate::model::{FrameId, Model};
use crate::state::RobotState;

impl RobotState {
    /// The robot standing still at `joint_positions` (model order, rad or m): the base pose levels the left
    /// sole (`world_R_left_sole = I`, heading along world x), puts the lower sole on the ground plane
    /// `z = 0` and the soles' mid-point at the world origin (x, y). Velocities are zero.
    ///
    /// ```
    /// use std::sync::Arc;
    /// use stride_model::{bundled, KinDyn, RobotState};
    /// let model = Arc::new(bundled::model()?);
    /// let mut q = nalgebra::DVector::zeros(model.dof());
    /// for (name, value) in bundled::POSTURE {
    ///     q[model.joint_index(name).expect("joint")] = value;
    /// }
    /// let (l, r) = (model.frame_id(bundled::LEFT_SOLE).unwrap(), model.frame_id(bundled::RIGHT_SOLE).unwrap());
    /// let state = RobotState::standing(&model, &q, l, r)?;
    /// let mut kd = KinDyn::new(Arc::clone(&model));
    /// kd.set_state(&state)?;
    /// assert!(kd.frame_pose(l).translation.z.abs() < 1e-12);
    /// # Ok::<(), stride_model::ModelError>(())
    /// ```
    ///
    /// # Errors
    /// [`ModelError::DimensionMismatch`] when `joint_positions` is not `model.dof()` long,
    /// [`ModelError::JointOutOfLimits`] for a joint outside its URDF limits (NaN included: the limits are
    /// checked first), [`ModelError::NonFiniteInput`] for an infinite continuous joint, [`ModelError::FrameOutOfRange`] for a sole frame of another model.
    pub fn standing(
        model: &Arc<Model>,
        joint_positions: &DVector<f64>,
        left_sole: FrameId,
        right_sole: FrameId,
    ) -> Result<RobotState, ModelError> {
        crate::state::check_joint_limits(model, joint_positions)?;
        let mut state = RobotState::zero(model);
        state.joint_positions.copy_from(joint_positions);
        state.place_on_ground(model, left_sole, right_sole)?;
        Ok(state)
    }

    /// Sets the base pose (keeping the joint positions and velocities) as [`RobotState::standing`] does: left sole level
    /// and heading along world x, the lower sole on `z = 0`, the soles' mid-point at the origin (x, y).
    /// Joint limits are not checked: this is for measured postures (encoders at start-up) that may sit a
    /// hair beyond a limit; user postures go through [`RobotState::standing`].
    ///
    /// # Errors
    /// [`ModelError::DimensionMismatch`], [`ModelError::NonFiniteInput`] for a state that does not fit
    /// `model`, [`ModelError::FrameOutOfRange`] for a sole frame of another model.
    pub fn place_on_ground(
        &mut self,
        model: &Arc<Model>,
        left_sole: FrameId,
        right_sole: FrameId,
    ) -> Result<(), ModelError> {
        self.validate(model)?;
        for sole in [left_sole, right_sole] {
            if sole.index() >= model.frames().len() {
                return Err(ModelError::FrameOutOfRange {
                    index: sole.index(),
                    count: model.frames().len(),
                });
            }
        }
        self.base_pose = Isometry3::identity();
        let mut kd = KinDyn::new(Arc::clone(model));
        kd.set_state(self)?;
        let l = kd.frame_pose(left_sole);
        // Level the left sole: world_R_sole = identity (yaw 0).
        self.base_pose = Isometry3::from_parts(Translation3::identity(), l.rotation.inverse());
        kd.set_state(self)?;
        let l = kd.frame_pose(left_sole).translation.vector;
        let r = kd.frame_pose(right_sole).translation.vector;
        let mid = (l + r) * 0.5;
        let lowest = l.z.min(r.z);
        self.base_pose.translation.vector -= Vector3::new(mid.x, mid.y, lowest);
        Ok(())
    }
}
