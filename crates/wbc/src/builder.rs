//! Builders of [`TsidConfig`] and [`IkConfig`]: the task list written in code, one call per task, with
//! the config types' defaults; `build` checks the names the way the controllers do.
//!
//! ```
//! use stride_wbc::prelude::*;
//!
//! let tsid = TsidConfig::builder()
//!     .contact("l_sole", 0.5)
//!     .contact("r_sole", 0.5)
//!     .se3("l_hand_palm", 100.0, 20.0)
//!     .com(25.0, 5.0)
//!     .posture(100.0, 20.0, &[("l_knee", 0.7), ("r_knee", 0.7)])
//!     .build()?;
//! assert_eq!(tsid.tasks.len(), 8); // dynamics, 2 contacts, hand, CoM, posture, 2 regularizations
//! # Ok::<(), stride_wbc::WbcError>(())
//! ```

use crate::config::{
    check_unique_names, ComTaskConfig, CompliantConfig, ContactModel, ContactTaskConfig,
    FloatingBaseDynamicsTaskConfig, Frame3TaskConfig, IkConfig, IkFeedback,
    JointPositionLimitsTaskConfig, JointRegularizationTaskConfig, JointTorqueLimitsTaskConfig,
    JointVelocityLimitsTaskConfig, Priority, QpSettings, ReferenceOffset, Se3TaskConfig,
    TaskConfig, TorqueRegularizationTaskConfig, TsidConfig, Weight, WrenchRegularizationTaskConfig,
};
use crate::error::WbcError;

/// An SE(3) task named after `frame` that follows the input reference `frame`, soft (weight 1), with
/// the same gains on the linear and angular rows (`kp`: 1/s in IK, 1/s² in TSID; `kd`: 1/s, TSID).
fn se3(frame: &str, kp: f64, kd: f64) -> TaskConfig {
    TaskConfig::Se3(Se3TaskConfig {
        name: frame.to_owned(),
        frame: frame.to_owned(),
        reference: frame.to_owned(),
        kp_linear: kp,
        kp_angular: kp,
        kd_linear: kd,
        kd_angular: kd,
        mask: [true; 6],
        priority: Priority::Soft,
        weight: None,
    })
}

/// An SO(3) task on `frame` named after it, following the input reference `reference`, soft with
/// weight `weight`.
fn so3(frame: &str, reference: &str, kp: f64, kd: f64, weight: f64) -> TaskConfig {
    TaskConfig::So3(Frame3TaskConfig {
        name: frame.to_owned(),
        frame: frame.to_owned(),
        reference: reference.to_owned(),
        reference_offset: ReferenceOffset::None,
        kp,
        kd,
        mask: [true; 3],
        priority: Priority::Soft,
        weight: Some(Weight::Scalar(weight)),
    })
}

/// A hard CoM task named `com`.
pub(crate) fn com(kp: f64, kd: f64) -> TaskConfig {
    TaskConfig::Com(com_config(kp, kd))
}

/// The hard CoM task `com` on every row with gains `kp`, `kd` (the same on the vertical row).
pub(crate) fn com_config(kp: f64, kd: f64) -> ComTaskConfig {
    ComTaskConfig {
        name: "com".into(),
        kp,
        kd,
        kp_z: None,
        kd_z: None,
        mask: [true; 3],
        priority: Priority::Hard,
        weight: None,
    }
}

fn posture_task(kp: f64, kd: f64, posture: &[(&str, f64)]) -> TaskConfig {
    TaskConfig::JointRegularization(JointRegularizationTaskConfig {
        name: "posture".into(),
        kp,
        kd,
        posture: posture.iter().map(|&(j, q)| (j.to_owned(), q)).collect(),
        weight: None,
        joint_weights: Default::default(),
        priority: Priority::Soft,
    })
}

/// The joint position limits (`look_ahead`: `None` = the controller period) and velocity limits.
pub(crate) fn limits(look_ahead: Option<f64>) -> [TaskConfig; 2] {
    [
        TaskConfig::JointPositionLimits(JointPositionLimitsTaskConfig {
            name: "joint_position_limits".into(),
            margin: 0.0,
            look_ahead,
        }),
        TaskConfig::JointVelocityLimits(JointVelocityLimitsTaskConfig {
            name: "joint_velocity_limits".into(),
            scale: 1.0,
        }),
    ]
}

/// Builder of a [`TsidConfig`] ([`TsidConfig::builder`]). Starts with the floating-base dynamics;
/// [`TsidConfigBuilder::build`] adds the wrench and torque regularizations (weight 1e-4) unless given.
#[derive(Debug, Clone)]
pub struct TsidConfigBuilder {
    config: TsidConfig,
}

impl TsidConfig {
    /// A builder with the floating-base dynamics task (`dynamics`) and default QP settings.
    pub fn builder() -> TsidConfigBuilder {
        TsidConfigBuilder {
            config: TsidConfig {
                qp: QpSettings::default(),
                eliminate_equalities: true,
                flexible_joints: Vec::new(),
                contact_model: ContactModel::Rigid,
                compliant: CompliantConfig::default(),
                actuators: crate::ActuatorConfig::default(),
                tasks: vec![TaskConfig::FloatingBaseDynamics(
                    FloatingBaseDynamicsTaskConfig {
                        name: "dynamics".into(),
                    },
                )],
            },
        }
    }
}

impl TsidConfigBuilder {
    /// Any task.
    pub fn task(mut self, task: TaskConfig) -> Self {
        self.config.tasks.push(task);
        self
    }

    /// A rigid contact on `frame` with friction coefficient `friction` ([`ContactTaskConfig::new`]:
    /// task and input contact flag named `frame`; a 0.2 m × 0.09 m CoP rectangle).
    pub fn contact(self, frame: &str, friction: f64) -> Self {
        self.task(TaskConfig::Contact(ContactTaskConfig::new(frame, friction)))
    }

    /// A soft SE(3) task on `frame` following the input reference `frame` (`kp` 1/s², `kd` 1/s on every
    /// row); replaced by the contact constraint while a contact on the same frame is loaded.
    pub fn se3(self, frame: &str, kp: f64, kd: f64) -> Self {
        self.task(se3(frame, kp, kd))
    }

    /// A soft SO(3) task on `frame` following the input reference `reference`, with weight `weight`.
    pub fn so3(self, frame: &str, reference: &str, kp: f64, kd: f64, weight: f64) -> Self {
        self.task(so3(frame, reference, kp, kd, weight))
    }

    /// The hard CoM task `com` (linear momentum rate; `kp` 1/s², `kd` 1/s).
    pub fn com(self, kp: f64, kd: f64) -> Self {
        self.task(com(kp, kd))
    }

    /// The soft posture task `posture` toward `posture` (joint name, rad; other joints 0).
    pub fn posture(self, kp: f64, kd: f64, posture: &[(&str, f64)]) -> Self {
        self.task(posture_task(kp, kd, posture))
    }

    /// Joint torque, position (look-ahead `look_ahead` s) and velocity limits.
    pub fn limits(self, look_ahead: f64) -> Self {
        let [p, v] = limits(Some(look_ahead));
        self.task(TaskConfig::JointTorqueLimits(JointTorqueLimitsTaskConfig {
            name: "joint_torque_limits".into(),
            scale: 1.0,
        }))
        .task(p)
        .task(v)
    }

    /// The QP settings.
    pub fn qp(mut self, qp: QpSettings) -> Self {
        self.config.qp = qp;
        self
    }

    /// The config. Errors: two tasks with one name, or a contact task without a contact name.
    pub fn build(mut self) -> Result<TsidConfig, WbcError> {
        let has = |tasks: &[TaskConfig], f: fn(&TaskConfig) -> bool| tasks.iter().any(f);
        if !has(&self.config.tasks, |t| {
            matches!(t, TaskConfig::WrenchRegularization(_))
        }) {
            self = self.task(TaskConfig::WrenchRegularization(
                WrenchRegularizationTaskConfig {
                    name: "wrench_regularization".into(),
                    weight: Weight::Scalar(1e-4),
                },
            ));
        }
        if !has(&self.config.tasks, |t| {
            matches!(t, TaskConfig::TorqueRegularization(_))
        }) {
            self = self.task(TaskConfig::TorqueRegularization(
                TorqueRegularizationTaskConfig {
                    name: "torque_regularization".into(),
                    weight: Weight::Scalar(1e-4),
                },
            ));
        }
        check_unique_names(&self.config.tasks)?;
        crate::names::input_layout(&self.config.tasks)?;
        Ok(self.config)
    }
}

/// Builder of an [`IkConfig`] ([`IkConfig::builder`]).
///
/// ```
/// use stride_wbc::prelude::*;
///
/// let ik = IkConfig::builder()
///     .se3_hard("l_sole", 7.0)
///     .se3_hard("r_sole", 7.0)
///     .se3("l_hand_palm", 5.0)
///     .com(2.0)
///     .posture(5.0, &[])
///     .limits()
///     .build()?;
/// assert_eq!(ik.tasks.len(), 7);
/// # Ok::<(), stride_wbc::WbcError>(())
/// ```
#[derive(Debug, Clone)]
pub struct IkConfigBuilder {
    config: IkConfig,
}

impl IkConfig {
    /// An empty builder (integrated feedback, default QP settings).
    pub fn builder() -> IkConfigBuilder {
        IkConfigBuilder {
            config: IkConfig {
                feedback: IkFeedback::Integrated,
                qp: QpSettings::default(),
                eliminate_equalities: true,
                tasks: Vec::new(),
            },
        }
    }
}

impl IkConfigBuilder {
    /// Any task.
    pub fn task(mut self, task: TaskConfig) -> Self {
        self.config.tasks.push(task);
        self
    }

    /// A soft SE(3) task on `frame` following the input reference `frame` (`kp` 1/s, every row).
    pub fn se3(self, frame: &str, kp: f64) -> Self {
        self.task(se3(frame, kp, 0.0))
    }

    /// A hard SE(3) task on `frame` following the input reference `frame` (e.g. a stance foot).
    pub fn se3_hard(self, frame: &str, kp: f64) -> Self {
        let mut task = se3(frame, kp, 0.0);
        if let TaskConfig::Se3(c) = &mut task {
            c.priority = Priority::Hard;
        }
        self.task(task)
    }

    /// A soft SO(3) task on `frame` following the input reference `reference`, with weight `weight`.
    pub fn so3(self, frame: &str, reference: &str, kp: f64, weight: f64) -> Self {
        self.task(so3(frame, reference, kp, 0.0, weight))
    }

    /// The hard CoM task `com` (`kp` 1/s).
    pub fn com(self, kp: f64) -> Self {
        self.task(com(kp, 0.0))
    }

    /// The soft posture task `posture` toward `posture` (joint name, rad; other joints 0).
    pub fn posture(self, kp: f64, posture: &[(&str, f64)]) -> Self {
        self.task(posture_task(kp, 0.0, posture))
    }

    /// Joint position (one-period look-ahead) and velocity limits.
    pub fn limits(self) -> Self {
        let [p, v] = limits(None);
        self.task(p).task(v)
    }

    /// How the task errors are evaluated.
    pub fn feedback(mut self, feedback: IkFeedback) -> Self {
        self.config.feedback = feedback;
        self
    }

    /// The config. Errors: two tasks with one name.
    pub fn build(self) -> Result<IkConfig, WbcError> {
        check_unique_names(&self.config.tasks)?;
        Ok(self.config)
    }
}
