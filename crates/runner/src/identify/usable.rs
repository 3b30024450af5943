//! Which rows a log can give. A robot held by its base (`sim.fixed_base`) feels no contact: every motor
//! torque and every force/torque sensor row holds, and the base rows do not (the holder's wrench is not
//! measured). A robot on its feet is touched only at the soles: the rows whose submodel holds a sole
//! (the torques of the joints on the way to a sole, the sensors whose child side holds one) would need the
//! contact wrench and are skipped, and the submodel above the feet sensors gives the base rows
//! [Traversaro 2017, eq. 7.1, Theorem 7.1].

use std::path::Path;

use nalgebra::DMatrix;
use stride_model::{KinDyn, RobotState};

use super::IdentifyError;
use crate::config::Scenario;

/// The rows of one log that hold.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct UsableRows {
    /// Per joint: its motor-torque row holds.
    pub joints: Vec<bool>,
    /// Per force/torque sensor: its FT-submodel rows (7.2)–(7.3) hold.
    pub sensors: Vec<bool>,
    /// The sensors that bound the submodel of the base rows (the feet sensors); empty: no base rows.
    pub cut: Vec<usize>,
}

impl UsableRows {
    /// The rows of a log of `scenario` (the robot's kinematic structure evaluated at `state`).
    ///
    /// # Errors
    /// [`IdentifyError::Content`] for a floating-base log with pushes (a wrench nothing measures), or
    /// without a force/torque sensor above each sole.
    pub(super) fn of_log(
        scenario: &Scenario,
        kd: &mut KinDyn,
        state: &RobotState,
        path: &Path,
    ) -> Result<Self, IdentifyError> {
        let model = std::sync::Arc::clone(kd.model());
        let (n, ns) = (model.dof(), model.ft_sensors().len());
        let mut usable = Self {
            joints: vec![true; n],
            sensors: vec![true; ns],
            cut: Vec::new(),
        };
        if scenario.config.sim.fixed_base {
            return Ok(usable);
        }
        if !scenario.config.sim.pushes.is_empty() {
            return Err(IdentifyError::Content(format!(
                "{}: the robot is pushed ([[sim.pushes]]); the base rows need every external wrench measured",
                path.display()
            )));
        }
        kd.set_state(state)?;
        let mut jacobian = DMatrix::zeros(6, model.nv());
        let robot = &scenario.config.robot;
        for sole in [robot.left_sole.name(), robot.right_sole.name()] {
            let frame = model.frame_id(sole).ok_or_else(|| {
                IdentifyError::Content(format!("{}: no frame {sole} in the model", path.display()))
            })?;
            let sensor = model.innermost_ft_sensor_holding(frame).ok_or_else(|| {
                IdentifyError::Content(format!(
                    "{}: no force/torque sensor above {sole}; a robot on its feet needs the feet sensors \
                     (or `sim.fixed_base = true`)",
                    path.display()
                ))
            })?;
            usable.cut.push(sensor);
            for (k, ok) in usable.sensors.iter_mut().enumerate() {
                *ok &= !model.ft_child_side_holds(k, frame)?;
            }
            // A joint is on the way to the sole when the sole's Jacobian has a non-zero column for it.
            kd.frame_jacobian(frame, &mut jacobian)?;
            for (j, ok) in usable.joints.iter_mut().enumerate() {
                *ok &= jacobian.column(6 + j).amax() == 0.0;
            }
        }
        Ok(usable)
    }
}
