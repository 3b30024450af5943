//! The task library of both whole-body controllers, one file per task family. Every task writes rows
//! `A x = b` (equality) or `l ≤ A x ≤ u` (inequality) over the full decision vector `x` of its
//! controller straight into the storage of its stride-qp task ([`stride_qp::TaskDataMut`]), or bounds on
//! `x`. Nothing here allocates after construction.
//!
//! Velocity-level tasks (QP-IK, `x = ν`) and acceleration-level tasks (TSID, `x = [ν̇; f…]`) share the
//! same Jacobians; [`Level`] selects the right-hand side. The families:
//!
//! * [`frame`]: SE(3) / SO(3) / R³ tracking of a frame (IK and TSID);
//! * [`com`]: the CoM (IK velocity) and the linear momentum rate through the contact forces (TSID);
//! * [`momentum`]: the centroidal angular momentum (IK) and its rate through the contact wrenches (TSID);
//! * [`joint`]: posture regularization and the joint position / velocity limits as variable bounds;
//! * [`dynamics`]: the floating-base dynamics, and the joint torques (limits, regularization) eliminated
//!   through its joint rows (TSID);
//! * [`contact`]: rigid contacts — contact constraint, wrench feasibility (friction, CoP, unilateral),
//!   load ramps — and the contact wrench regularization (TSID);
//! * [`zmp`]: the global ZMP of the contact wrenches (TSID).

use nalgebra::{DMatrix, DVector, Vector3, Vector6};
use stride_model::{FrameId, Model};

use crate::error::WbcError;

pub(crate) mod com;
pub(crate) mod compliant;
pub(crate) mod compliant_ground;
pub(crate) mod compliant_wrench;
pub(crate) mod contact;
pub(crate) mod dynamics;
pub(crate) mod frame;
pub(crate) mod joint;
pub(crate) mod momentum;
pub(crate) mod zmp;

pub(crate) use com::{ComMomentumTask, ComVelocityTask};
pub(crate) use contact::Contact;
pub(crate) use frame::FrameTask;
pub(crate) use joint::{joint_limits, position_limit_bounds, JointRegularizationTask};
pub(crate) use momentum::{
    AngularMomentumRateTask, AngularMomentumVelocityTask, JointMomentumReference,
};

/// Whether a task constrains velocities (QP-IK) or accelerations (TSID).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Level {
    Velocity,
    Acceleration,
}

pub(crate) fn check_gain(task: &str, key: &'static str, value: f64) -> Result<(), WbcError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(WbcError::InvalidConfig {
            task: task.to_owned(),
            key,
            reason: format!("{value} must be finite and >= 0"),
        })
    }
}

pub(crate) fn frame_id(model: &Model, task: &str, frame: &str) -> Result<FrameId, WbcError> {
    model.frame_id(frame).ok_or_else(|| WbcError::UnknownFrame {
        task: task.to_owned(),
        frame: frame.to_owned(),
    })
}

/// What the TSID's tasks read at one tick: the dynamics and centroidal quantities at the measured state
/// (mixed representation) and the contacts with the columns of their wrenches in `x`.
pub(crate) struct TsidContext<'a> {
    /// Total mass (kg).
    pub mass: f64,
    /// Gravity (m/s², world).
    pub gravity: Vector3<f64>,
    /// Mass matrix `M` (nv × nv).
    pub mass_matrix: &'a DMatrix<f64>,
    /// Bias forces `h = C ν + g` (nv).
    pub bias_forces: &'a DVector<f64>,
    /// CoM position (m) and velocity (m/s).
    pub com_position: Vector3<f64>,
    /// CoM velocity (m/s).
    pub com_velocity: Vector3<f64>,
    /// Centroidal momentum `[linear; angular]` (kg m/s, kg m²/s).
    pub momentum: Vector6<f64>,
    /// The contacts (configuration order).
    pub contacts: &'a [Contact],
    /// Contact index → first column of its wrench in `x` (`None`: not loaded in this QP).
    pub offsets: &'a [Option<usize>],
}
