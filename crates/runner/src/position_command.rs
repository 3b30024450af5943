//! `wbc.position_command`: what the position servos get between two whole-body ticks.
//!
//! The QP-IK runs at `rates.wbc_hz` (500 Hz) and the plant at `rates.sim_hz` (2 kHz). Its command is the
//! joint position it integrated to the *end* of its period, `q_ref = q_k + q̇_ref T`, with the velocity
//! `q̇_ref` [Romualdi 2022, eq. 7.1.16 integrated over T]. Held for the whole period (a zero-order hold),
//! that set-point is a staircase: a joint that follows the IK's trajectory starts each period `q̇_ref T`
//! behind it, so the servo adds a 500 Hz sawtooth of `kp q̇_ref T` to the torque the motion needs (10⁴ ·
//! 1 rad/s · 2 ms = 20 N·m on a stance ankle, ≈ 100 N·m on a swinging knee), which saturates the joints and
//! shakes the soles on a stiff floor. Interpolated (a first-order hold), the set-point of each plant step is
//! the IK's trajectory at the end of that step, `q_ref − q̇_ref (t_next − t − h)`, and the servo torque is
//! the one the motion needs. `[joint_trajectory]` plays its sinusoids at the plant rate for the same reason.
//!
//! The default stays `hold`: the scenarios were tuned with it. With `interpolate` everywhere (stride-sim,
//! defaults of 2026-12-05) the walks track the DCM as before within 2 mm RMS and do 20–25 % less positive
//! actuator work, but `walk_fast_icub` falls while stopping and `walk_fast`'s 0.30 m steps fall (their
//! margins were tuned on the staircase, 2026-12-05). `walk_fast_upright` sets `interpolate` (docs/mujoco.md,
//! "The fast position walks"), and so does `walk_fast_icub` since its retuning on the URDF's sole boxes
//! (docs/gait.md, "On the URDF's sole").

use serde::{Deserialize, Serialize};

use crate::config::ControlMode;
use crate::robot::JointCommand;

/// `wbc.position_command`: the position set-point between two whole-body ticks (position control only;
/// a torque command is held).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum PositionCommand {
    /// The whole-body command held over its period (a zero-order hold: a staircase at `rates.wbc_hz`).
    #[default]
    Hold,
    /// The QP-IK's joint trajectory sampled at every plant step (a first-order hold).
    Interpolate,
}

/// Writes into `out` the command of one plant step that ends `remaining` seconds before the next
/// whole-body tick: `q = q_ref − remaining · q̇_ref` for a position command (the velocity and torque
/// feed-forwards and the contacts as they are), `wbc` as it is otherwise. Allocates nothing (`out` has
/// `wbc`'s sizes).
pub fn interpolate(wbc: &JointCommand, remaining: f64, out: &mut JointCommand) {
    out.mode = wbc.mode;
    out.contacts = wbc.contacts;
    out.joint_velocities.copy_from(&wbc.joint_velocities);
    out.joint_torques.copy_from(&wbc.joint_torques);
    out.joint_positions.copy_from(&wbc.joint_positions);
    if wbc.mode == ControlMode::Position {
        out.joint_positions
            .axpy(-remaining, &wbc.joint_velocities, 1.0);
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::DVector;

    use super::*;

    fn command(mode: ControlMode) -> JointCommand {
        JointCommand {
            mode,
            joint_positions: DVector::from_vec(vec![0.5, -1.0, 2.0]),
            joint_velocities: DVector::from_vec(vec![1.0, -2.0, 0.0]),
            joint_torques: DVector::from_vec(vec![0.1, 0.2, 0.3]),
            contacts: [true, false],
        }
    }

    #[test]
    fn a_position_command_moves_back_along_its_velocity_and_reaches_the_set_point_at_the_tick() {
        let wbc = command(ControlMode::Position);
        let mut out = JointCommand::hold(ControlMode::Torque, &DVector::zeros(3));
        interpolate(&wbc, 1.5e-3, &mut out);
        let expected = [0.5 - 1.5e-3, -1.0 + 3.0e-3, 2.0];
        for (q, e) in out.joint_positions.iter().zip(expected) {
            assert!((q - e).abs() < 1e-15, "{q} vs {e}");
        }
        assert_eq!(out.joint_velocities, wbc.joint_velocities);
        assert_eq!(out.joint_torques, wbc.joint_torques);
        assert_eq!(out.mode, ControlMode::Position);
        assert_eq!(out.contacts, [true, false]);
        interpolate(&wbc, 0.0, &mut out);
        assert_eq!(out.joint_positions, wbc.joint_positions);
    }

    #[test]
    fn a_torque_command_is_held() {
        let wbc = command(ControlMode::Torque);
        let mut out = JointCommand::hold(ControlMode::Position, &DVector::zeros(3));
        interpolate(&wbc, 1.5e-3, &mut out);
        assert_eq!(out.joint_positions, wbc.joint_positions);
        assert_eq!(out.joint_torques, wbc.joint_torques);
        assert_eq!(out.mode, ControlMode::Torque);
    }
}
