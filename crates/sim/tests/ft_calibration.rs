//! `sensors.ft.calibration_error`: the force/torque sensors' raw output `(1 + E) w + b` with a calibration
//! matrix `C = (1 + E)⁻¹` to recover [Traversaro 2017, eq. (5.1)].

mod common;

use std::sync::Arc;

use nalgebra::Matrix6;
use stride_model::RobotState;
use stride_sim::{SimInput, SimRobot};

fn run(calibration_error: f64) -> SimRobot {
    let model = common::humanoid();
    let mut config = common::ideal_config();
    config.fixed_base = true;
    config.contact.surfaces.clear();
    config.sensors.ft.force_offset = 5.0;
    config.sensors.ft.torque_offset = 0.5;
    config.sensors.ft.calibration_error = calibration_error;
    let mut sim = SimRobot::new(Arc::clone(&model), config, common::PERIOD).unwrap();
    let mut state = RobotState::zero(&model);
    state.base_pose.translation.vector.z = 1.0;
    state.joint_positions = common::bent_knees(&model, 0.4);
    sim.set_initial_state(&state).unwrap();
    let input = SimInput::hold(&state.joint_positions);
    for _ in 0..20 {
        sim.step(&input).unwrap();
    }
    sim
}

#[test]
fn the_raw_output_is_affine_in_the_wrench_with_the_drawn_matrix() {
    let sim = run(0.05);
    let (offsets, matrices) = sim.ft_calibration_truth();
    let out = sim.output();
    assert_eq!(matrices.len(), out.ft_wrenches.len());
    for (k, c) in matrices.iter().enumerate() {
        // C (r − b) = w (5.1), no noise or drift.
        let w = c * (out.ft_wrenches[k] - offsets[k]);
        let err = (w - out.ft_wrenches_truth[k]).amax();
        assert!(err < 1e-9, "sensor {k}: {err:.2e}");
        // E within its bound, and not zero.
        let e = c.try_inverse().unwrap() - Matrix6::identity();
        assert!(e.amax() <= 0.05 && e.amax() > 0.01, "{e}");
    }
}

#[test]
fn no_calibration_error_leaves_the_readings_as_they_were() {
    let sim = run(0.0);
    let (offsets, matrices) = sim.ft_calibration_truth();
    let out = sim.output();
    for (k, c) in matrices.iter().enumerate() {
        assert_eq!(*c, Matrix6::identity());
        assert_eq!(out.ft_wrenches[k], out.ft_wrenches_truth[k] + offsets[k]);
    }
}

#[test]
fn a_calibration_error_of_one_sixth_is_refused() {
    let mut config = common::ideal_config();
    config.sensors.ft.calibration_error = 1.0 / 6.0;
    let err = config.validate().unwrap_err().to_string();
    assert!(err.contains("calibration_error"), "{err}");
}
