//! TSID-Flex's view of the passive flexible joints [Romualdi 2022, ch. 9]: the TSID's
//! `wbc.tsid.flexible_joints` take their spring-damper from `sim.passive_joints` (the robot's springs, one
//! source for the plant and the controller). A joint with an encoder is read like any other; one without
//! (the default, the thesis's case) is estimated by [`FlexibleJointObserver`] from the joint torque the
//! estimation layer computes by inverse dynamics with the measured foot wrenches [Romualdi 2022, §9.3].

use std::sync::Arc;
use std::time::Duration;

use nalgebra::DVector;
use stride_estimation::{EstimatorInput, FlexibleJointObserver};
use stride_model::{Model, RobotState};

use crate::config::Scenario;
use crate::error::RunError;

/// One flexible joint of the TSID.
#[derive(Debug, Clone)]
struct Spring {
    name: String,
    /// Model index.
    joint: usize,
    /// `k`, N·m/rad.
    stiffness: f64,
    /// `b`, N·m·s/rad.
    damping: f64,
    /// The plant measures it.
    encoder: bool,
}

/// The springs of the TSID's flexible joints.
#[derive(Debug, Clone, Default)]
pub struct FlexibleSprings {
    springs: Vec<Spring>,
}

impl FlexibleSprings {
    /// The springs of `flexible_joints` (the TSID's list) from the scenario's `sim.passive_joints`; a name
    /// with no passive-joint entry, or unknown to `model`, is an error at `wbc.tsid.flexible_joints`.
    pub fn new(
        scenario: &Scenario,
        model: &Model,
        flexible_joints: &[String],
    ) -> Result<Self, RunError> {
        let passive = &scenario.config.sim.passive_joints;
        let springs = flexible_joints
            .iter()
            .map(|name| {
                let invalid = |reason: String| {
                    RunError::Config(scenario.invalid("wbc.tsid.flexible_joints", reason))
                };
                let spring = passive
                    .iter()
                    .find(|p| p.joints.contains(name))
                    .ok_or_else(|| {
                        invalid(format!(
                            "`{name}` is not in any `[[sim.passive_joints]]` entry; expected the \
                             passive joints whose springs the controller compensates"
                        ))
                    })?;
                let joint = model
                    .joint_index(name)
                    .ok_or_else(|| invalid(format!("`{name}` is not a joint of the model")))?;
                Ok(Spring {
                    name: name.clone(),
                    joint,
                    stiffness: spring.stiffness,
                    damping: spring.damping(),
                    encoder: spring.encoder,
                })
            })
            .collect::<Result<Vec<_>, RunError>>()?;
        Ok(Self { springs })
    }

    /// `(k, b)` of each flexible joint, in the TSID's order (for [`stride_wbc::Tsid::set_flexible_springs`]).
    pub fn springs(&self) -> Vec<(f64, f64)> {
        self.springs
            .iter()
            .map(|s| (s.stiffness, s.damping))
            .collect()
    }

    /// Writes `τ^f = −k s − b ṡ` [Romualdi 2022, eq. (9.1.1)] of every flexible joint at `state` into
    /// `torques` (model order); other entries are left as they are. Allocation-free.
    pub fn fill(&self, state: &RobotState, torques: &mut DVector<f64>) {
        for s in &self.springs {
            torques[s.joint] = -s.stiffness * state.joint_positions[s.joint]
                - s.damping * state.joint_velocities[s.joint];
        }
    }

    /// The observer of the flexible joints without encoders, ticking every `period`; `None` when every
    /// flexible joint is measured (or there is none).
    pub fn observer(
        &self,
        model: &Arc<Model>,
        period: Duration,
    ) -> Result<Option<FlexibleObserver>, RunError> {
        let joints: Vec<(&str, f64, f64)> = self
            .springs
            .iter()
            .filter(|s| !s.encoder)
            .map(|s| (s.name.as_str(), s.stiffness, s.damping))
            .collect();
        if joints.is_empty() {
            return Ok(None);
        }
        Ok(Some(FlexibleObserver {
            observer: FlexibleJointObserver::new(model, &joints, period.as_secs_f64())?,
            readings: EstimatorInput::new(model),
        }))
    }
}

/// The observer in the estimation loop: the estimation layer reads the flexible joints' previous estimate
/// in place of their (absent) encoders, and its inverse-dynamics joint torques update the estimate.
#[derive(Debug, Clone)]
pub struct FlexibleObserver {
    observer: FlexibleJointObserver,
    /// The sensor sample with the flexible joints' readings replaced.
    readings: EstimatorInput,
}

impl FlexibleObserver {
    /// `sensors` with the flexible joints' encoder readings replaced by the last estimate. Allocation-free.
    pub fn readings(&mut self, sensors: &EstimatorInput) -> Result<&EstimatorInput, RunError> {
        self.readings.set_readings(
            Duration::from_nanos(sensors.time_ns),
            sensors.joint_positions.as_slice(),
            sensors.joint_velocities.as_slice(),
            sensors.imu,
            &sensors.ft_wrenches,
        )?;
        let o = &self.observer;
        for (i, f) in o.joints().iter().enumerate() {
            self.readings.joint_positions[f.joint] = o.positions()[i];
            self.readings.joint_velocities[f.joint] = o.velocities()[i];
        }
        Ok(&self.readings)
    }

    /// One observer tick on the estimated joint `torques` (model order, N·m); writes the new deflections and
    /// rates into `state`.
    pub fn update(
        &mut self,
        torques: &DVector<f64>,
        state: &mut RobotState,
    ) -> Result<(), RunError> {
        self.observer.step(torques)?;
        self.observer.write_state(state);
        Ok(())
    }
}
