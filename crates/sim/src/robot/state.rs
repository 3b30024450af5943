//! Setting and placing the state of [`SimRobot`], and the kinematics every step and output start from.

use nalgebra::{DVector, Point3, Vector3};
use stride_model::{ModelError, RobotState};

use super::SimRobot;
use crate::error::SimError;
use crate::linalg::lin;

impl SimRobot {
    /// Replaces the current state (time and contact memory are kept/reinitialised: penetrating points stick
    /// where they are). The base velocity is read in the mixed representation.
    pub fn set_state(&mut self, state: &RobotState) -> Result<(), SimError> {
        self.check_state(state)?;
        self.state.base_pose = state.base_pose;
        self.state.base_velocity = state.base_velocity;
        self.state.joint_positions.copy_from(&state.joint_positions);
        self.state
            .joint_velocities
            .copy_from(&state.joint_velocities);
        for p in &mut self.points {
            p.anchor = None;
        }
        self.refresh_after_state_change()
    }

    /// Sets the state and makes it the one [`Block::reset`](stride_block::Block::reset) returns to; the time
    /// restarts at zero and the fall flag, the re-solve cap counter and the noise sequence are reset.
    pub fn set_initial_state(&mut self, state: &RobotState) -> Result<(), SimError> {
        self.check_state(state)?;
        self.initial_state.clone_from(state);
        self.time_ns = 0;
        self.fall_time_ns = None;
        self.solve_cap_hits = 0;
        self.sensors.reset();
        // Until the first delayed command arrives the motors hold the initial posture.
        for c in &mut self.commands {
            c.joint_positions.copy_from(&state.joint_positions);
            c.joint_velocities.fill(0.0);
            c.joint_torques.fill(0.0);
        }
        self.command_head = 0;
        self.lagged_torques.fill(0.0);
        self.set_state(state)
    }

    /// Places the robot at rest with the given joint positions and an upright base (identity orientation, base
    /// at x = y = 0) so that its lowest contact points sink into the ground by the static penetration expected
    /// under the robot's weight (`m g / Σ k` over the lowest points, within 0.1 mm of the lowest). Makes this the
    /// initial state and returns it.
    pub fn set_standing_on_ground(
        &mut self,
        joint_positions: &DVector<f64>,
    ) -> Result<RobotState, SimError> {
        let mut state = RobotState::zero(&self.model);
        if joint_positions.len() != state.joint_positions.len() {
            return Err(SimError::Dimension {
                what: "joint_positions",
                expected: state.joint_positions.len(),
                actual: joint_positions.len(),
            });
        }
        state.joint_positions.copy_from(joint_positions);
        self.check_state(&state)?;
        self.kd.set_state(&state)?;
        let lowest = self
            .point_heights()
            .fold(f64::INFINITY, |lowest, (_, h)| lowest.min(h));
        if lowest.is_finite() {
            let stiffness: f64 = self
                .point_heights()
                .filter(|(_, h)| *h < lowest + 1e-4)
                .fold(0.0, |k, (i, _)| {
                    let x = self.point_position(i).x;
                    k + self.compliance.at(x).stiffness * self.points[i].area
                });
            let weight =
                self.model.total_mass() * (-self.gravity.dot(&self.ground.normal)).max(0.0);
            let sink = if stiffness > 0.0 {
                weight / stiffness
            } else {
                0.0
            };
            let shift = self.ground.normal * (-(lowest + sink));
            state.base_pose.translation.vector += shift;
        }
        self.set_initial_state(&state)?;
        Ok(state)
    }

    /// `(index, height above the ground)` of every contact point at the configuration of the dynamics
    /// workspace, m.
    fn point_heights(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        (0..self.points.len()).map(|i| (i, self.ground.height_of(&self.point_position(i))))
    }

    /// World position of contact point `i` at the configuration of the dynamics workspace, m.
    fn point_position(&self, i: usize) -> Vector3<f64> {
        let p = &self.points[i];
        let pose = self.kd.frame_pose(self.surfaces[p.surface].frame);
        (pose * Point3::from(p.local)).coords
    }

    /// Validates a state given by the caller (dimensions, finiteness).
    pub(super) fn check_state(&self, state: &RobotState) -> Result<(), SimError> {
        state.validate(&self.model).map_err(|e| match e {
            ModelError::NonFiniteInput { what } => SimError::NonFiniteState { what },
            ModelError::DimensionMismatch {
                what,
                expected_rows,
                rows,
                ..
            } => SimError::Dimension {
                what,
                expected: expected_rows,
                actual: rows,
            },
            other => SimError::Model(other),
        })
    }

    /// Recomputes the kinematics, initialises contact anchors and the output after a state change.
    fn refresh_after_state_change(&mut self) -> Result<(), SimError> {
        self.update_kinematics()?;
        for p in &mut self.points {
            p.restart(&self.ground);
        }
        self.imu_velocity = lin(&self.kd.frame_velocity(self.imu_frame));
        self.motor_torques.fill(0.0);
        self.saturated.fill(false);
        self.friction.fill(crate::actuator::Friction::Stick);
        // Until the first step the force/torque sensors read the wrench of the robot at rest with no contact force.
        self.acceleration.fill(0.0);
        self.compute_ft_truth()?;
        self.update_output(
            &Vector3::zeros(),
            super::integrator::Solve {
                solves: 0,
                cap_hit: false,
            },
            true,
        );
        Ok(())
    }

    /// Sets the dynamics workspace to the current state and updates surface poses/twists and point positions,
    /// velocities and penetrations.
    pub(super) fn update_kinematics(&mut self) -> Result<(), SimError> {
        self.kd.set_state(&self.state)?;
        for s in &mut self.surfaces {
            s.pose = self.kd.frame_pose(s.frame);
            s.twist = self.kd.frame_velocity(s.frame);
            s.ft_pose = match s.ft_frame {
                Some(f) => self.kd.frame_pose(f),
                None => s.pose,
            };
        }
        for p in &mut self.points {
            let s = &self.surfaces[p.surface];
            p.place(&s.pose, &s.twist, &self.ground);
            p.set_densities(self.compliance.densities_at(p.position.x));
        }
        Ok(())
    }
}
