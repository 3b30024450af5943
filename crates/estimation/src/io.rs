//! The estimation layer's data-only input and output.

use std::time::Duration;

use nalgebra::{DVector, UnitQuaternion, Vector3, Vector6};
use stride_model::{Model, RobotState};

use crate::EstimatorError;

/// One IMU sample, in the IMU frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImuReading {
    /// Orientation `world_R_imu` from the IMU's on-board filter (roll and pitch from gravity, yaw drifting).
    pub orientation: UnitQuaternion<f64>,
    /// Gyroscope: angular velocity of the IMU frame in the IMU frame, rad/s (bias and noise included).
    pub angular_velocity: Vector3<f64>,
    /// Accelerometer: proper acceleration `Rᵀ (a − g)` of the IMU origin in the IMU frame, m/s².
    pub proper_acceleration: Vector3<f64>,
}

impl Default for ImuReading {
    fn default() -> Self {
        Self {
            orientation: UnitQuaternion::identity(),
            angular_velocity: Vector3::zeros(),
            proper_acceleration: Vector3::zeros(),
        }
    }
}

/// What the robot senses at one tick.
#[derive(Clone, Debug, PartialEq)]
pub struct EstimatorInput {
    /// Sample time, ns.
    pub time_ns: u64,
    /// Encoder joint positions, rad (model joint order).
    pub joint_positions: DVector<f64>,
    /// Joint velocities as the robot provides them, rad/s (model joint order).
    pub joint_velocities: DVector<f64>,
    /// The IMU sample.
    pub imu: ImuReading,
    /// Six-axis force/torque sensor readings `[f; τ]` in [`Model::ft_sensors`] order, each in its sensor
    /// frame with its declared measure direction, N and N·m (offsets and noise included).
    pub ft_wrenches: Vec<Vector6<f64>>,
}

impl EstimatorInput {
    /// A zero input sized for `model`.
    pub fn new(model: &Model) -> Self {
        Self {
            time_ns: 0,
            joint_positions: DVector::zeros(model.dof()),
            joint_velocities: DVector::zeros(model.dof()),
            imu: ImuReading::default(),
            ft_wrenches: vec![Vector6::zeros(); model.ft_sensors().len()],
        }
    }

    /// Copies one sample of the robot's sensors into this input, allocation-free: its `time` (whole
    /// nanoseconds), encoder positions and velocities (rad, rad/s, model joint order), IMU sample and FT
    /// readings (N, N·m, [`Model::ft_sensors`] order). What a plant adapter (a simulator, a robot's driver)
    /// calls once per sample before [`Estimator::step`](crate::Estimator).
    ///
    /// # Errors
    /// [`EstimatorError::InputSize`] when a slice's length differs from this input's (built for the model);
    /// nothing is copied then.
    pub fn set_readings(
        &mut self,
        time: Duration,
        joint_positions: &[f64],
        joint_velocities: &[f64],
        imu: ImuReading,
        ft_wrenches: &[Vector6<f64>],
    ) -> Result<(), EstimatorError> {
        let size = |name, expected: usize, actual: usize| {
            if expected == actual {
                Ok(())
            } else {
                Err(EstimatorError::InputSize {
                    name,
                    expected,
                    actual,
                })
            }
        };
        size(
            "joint_positions",
            self.joint_positions.len(),
            joint_positions.len(),
        )?;
        size(
            "joint_velocities",
            self.joint_velocities.len(),
            joint_velocities.len(),
        )?;
        size("ft_wrenches", self.ft_wrenches.len(), ft_wrenches.len())?;
        self.time_ns = u64::try_from(time.as_nanos()).unwrap_or(u64::MAX);
        self.joint_positions.copy_from_slice(joint_positions);
        self.joint_velocities.copy_from_slice(joint_velocities);
        self.imu = imu;
        self.ft_wrenches.copy_from_slice(ft_wrenches);
        Ok(())
    }
}

/// What the estimation layer gives the controllers.
#[derive(Clone, Debug, PartialEq)]
pub struct EstimatorOutput {
    /// Estimated base pose and mixed twist (`[ṗ_B; ω]`, world), joint positions and velocities.
    pub state: RobotState,
    /// Left and right foot detected in contact with the ground.
    pub contacts: [bool; 2],
    /// Left and right foot: estimated wrench `[f; τ]` the ground applies on the foot, world orientation,
    /// torque about the sole frame origin, N and N·m.
    pub foot_wrenches: [Vector6<f64>; 2],
    /// Estimated joint torques, N·m (model joint order).
    pub joint_torques: DVector<f64>,
    /// Current force/torque sensor offset estimates (subtracted from the readings), [`Model::ft_sensors`] order.
    pub ft_offsets: Vec<Vector6<f64>>,
}

impl EstimatorOutput {
    /// A zero output sized for `model`.
    pub fn new(model: &Model) -> Self {
        Self {
            state: RobotState::zero(model),
            contacts: [false; 2],
            foot_wrenches: [Vector6::zeros(); 2],
            joint_torques: DVector::zeros(model.dof()),
            ft_offsets: vec![Vector6::zeros(); model.ft_sensors().len()],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn set_readings_copies_a_sample_and_refuses_wrong_sizes_untouched() {
        let model = stride_model::bundled::model().expect("bundled model");
        let mut input = EstimatorInput::new(&model);
        let (n, f) = (model.dof(), model.ft_sensors().len());
        let q: Vec<f64> = (0..n).map(|i| 0.01 * i as f64).collect();
        let qd: Vec<f64> = (0..n).map(|i| -0.02 * i as f64).collect();
        let ft = vec![Vector6::new(1.0, 2.0, 3.0, 4.0, 5.0, 6.0); f];
        let imu = ImuReading {
            angular_velocity: Vector3::new(0.1, 0.2, 0.3),
            ..ImuReading::default()
        };
        input
            .set_readings(Duration::from_micros(1500), &q, &qd, imu, &ft)
            .expect("sizes of the model");
        assert_eq!(input.time_ns, 1_500_000);
        assert_eq!(input.joint_positions.as_slice(), q.as_slice());
        assert_eq!(input.joint_velocities.as_slice(), qd.as_slice());
        assert_eq!(input.imu, imu);
        assert_eq!(input.ft_wrenches, ft);

        let before = input.clone();
        let short = &q[..n - 1];
        let err = input
            .set_readings(Duration::from_secs(1), &q, short, imu, &ft)
            .expect_err("one joint velocity short");
        assert!(matches!(
            err,
            EstimatorError::InputSize { name: "joint_velocities", expected, actual } if expected == n && actual == n - 1
        ));
        assert_eq!(input, before);
    }
}
