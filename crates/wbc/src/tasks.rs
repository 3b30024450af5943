//! The task library. Every task writes rows `A x = b` (equality) or `l ≤ A x ≤ u` (inequality) over the
//! full decision vector `x` of its controller straight into the storage of its stride-qp task
//! ([`stride_qp::TaskDataMut`]). Nothing here allocates after construction.
//!
//! Velocity-level tasks (QP-IK, `x = ν`) and acceleration-level tasks (TSID, `x = [ν̇; f…]`) share the
//! same Jacobians; [`Level`] selects the right-hand side.

use std::collections::BTreeMap;

use nalgebra::{DMatrix, DVector, Isometry3, UnitQuaternion, Vector3, Vector6};
use stride_model::{FrameId, KinDyn, Model};

use stride_qp::TaskDataMut;

use crate::config::{
    ComTaskConfig, Frame3TaskConfig, FrameReferenceSource, JointRegularizationTaskConfig, Priority,
    ReferenceOffset, Se3TaskConfig,
};
use crate::error::WbcError;
use crate::io::WbcInput;
use crate::math::orientation_error;

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

/// Validates a joint position limits task and returns its bounds: the model's limits `lo`/`hi` moved
/// inward by the task's margin (rad or m), and the look-ahead time (s; the control `period` by default).
pub(crate) fn position_limit_bounds(
    c: &crate::config::JointPositionLimitsTaskConfig,
    period: f64,
    lo: &[f64],
    hi: &[f64],
    model: &Model,
) -> Result<(Vec<f64>, Vec<f64>, f64), WbcError> {
    check_gain(&c.name, "margin", c.margin)?;
    let look_ahead = c.look_ahead.unwrap_or(period);
    if !(look_ahead.is_finite() && look_ahead > 0.0) {
        return Err(WbcError::InvalidConfig {
            task: c.name.clone(),
            key: "look_ahead",
            reason: format!("{look_ahead} must be > 0"),
        });
    }
    let l: Vec<f64> = lo.iter().map(|v| v + c.margin).collect();
    let u: Vec<f64> = hi.iter().map(|v| v - c.margin).collect();
    if let Some(i) = (0..l.len()).find(|&i| l[i] > u[i]) {
        return Err(WbcError::InvalidConfig {
            task: c.name.clone(),
            key: "margin",
            reason: format!(
                "larger than half the range of joint `{}`",
                model.joints()[i].name
            ),
        });
    }
    Ok((l, u, look_ahead))
}

pub(crate) fn frame_id(model: &Model, task: &str, frame: &str) -> Result<FrameId, WbcError> {
    model.frame_id(frame).ok_or_else(|| WbcError::UnknownFrame {
        task: task.to_owned(),
        frame: frame.to_owned(),
    })
}

/// Reference of a frame task for this tick: pose, twist, acceleration (world, mixed).
struct FrameRef {
    pose: Isometry3<f64>,
    velocity: Vector6<f64>,
    acceleration: Vector6<f64>,
}

/// SE(3) / SO(3) / R³ tracking of a frame (7.1.6–7.1.10, 7.2.9–7.2.13).
#[derive(Debug, Clone)]
pub(crate) struct FrameTask {
    pub name: String,
    pub frame: FrameId,
    source: FrameReferenceSource,
    /// Gains per row of the 6D task `[lin; ang]`.
    kp: Vector6<f64>,
    kd: Vector6<f64>,
    /// Kept 6D rows (0..3 linear, 3..6 angular).
    rows: Vec<usize>,
    initial: Option<Isometry3<f64>>,
    /// Orientation offset mode and, once recorded, `R_off = R_refᵀ R` at the first tick.
    offset_mode: ReferenceOffset,
    offset: Option<UnitQuaternion<f64>>,
    jacobian: DMatrix<f64>,
    pub level: Level,
    /// Block index in the controller's block list.
    pub block: usize,
}

impl FrameTask {
    pub fn from_se3(model: &Model, c: &Se3TaskConfig, level: Level) -> Result<Self, WbcError> {
        for (k, v) in [
            ("kp_linear", c.kp_linear),
            ("kp_angular", c.kp_angular),
            ("kd_linear", c.kd_linear),
            ("kd_angular", c.kd_angular),
        ] {
            check_gain(&c.name, k, v)?;
        }
        if c.reference == FrameReferenceSource::Torso {
            return Err(WbcError::InvalidConfig {
                task: c.name.clone(),
                key: "reference",
                reason: "`torso` gives an orientation only: use an `so3` task".into(),
            });
        }
        let rows: Vec<usize> = (0..6).filter(|&i| c.mask[i]).collect();
        let kp = Vector6::new(
            c.kp_linear,
            c.kp_linear,
            c.kp_linear,
            c.kp_angular,
            c.kp_angular,
            c.kp_angular,
        );
        let kd = Vector6::new(
            c.kd_linear,
            c.kd_linear,
            c.kd_linear,
            c.kd_angular,
            c.kd_angular,
            c.kd_angular,
        );
        Self::build(model, &c.name, &c.frame, c.reference, kp, kd, rows, level)
    }

    pub fn from_frame3(
        model: &Model,
        c: &Frame3TaskConfig,
        angular: bool,
        level: Level,
    ) -> Result<Self, WbcError> {
        check_gain(&c.name, "kp", c.kp)?;
        check_gain(&c.name, "kd", c.kd)?;
        if !angular && c.reference == FrameReferenceSource::Torso {
            return Err(WbcError::InvalidConfig {
                task: c.name.clone(),
                key: "reference",
                reason: "`torso` gives an orientation only: use an `so3` task".into(),
            });
        }
        if !angular && c.reference_offset != ReferenceOffset::None {
            return Err(WbcError::InvalidConfig {
                task: c.name.clone(),
                key: "reference_offset",
                reason: "an orientation offset applies to `so3` tasks only; remove it".into(),
            });
        }
        let offset = if angular { 3 } else { 0 };
        let rows: Vec<usize> = (0..3).filter(|&i| c.mask[i]).map(|i| i + offset).collect();
        let kp = Vector6::from_element(c.kp);
        let kd = Vector6::from_element(c.kd);
        let mut task = Self::build(model, &c.name, &c.frame, c.reference, kp, kd, rows, level)?;
        task.offset_mode = c.reference_offset;
        Ok(task)
    }

    #[allow(clippy::too_many_arguments)]
    fn build(
        model: &Model,
        name: &str,
        frame: &str,
        source: FrameReferenceSource,
        kp: Vector6<f64>,
        kd: Vector6<f64>,
        rows: Vec<usize>,
        level: Level,
    ) -> Result<Self, WbcError> {
        if rows.is_empty() {
            return Err(WbcError::InvalidConfig {
                task: name.to_owned(),
                key: "mask",
                reason: "masks every row".into(),
            });
        }
        Ok(FrameTask {
            name: name.to_owned(),
            frame: frame_id(model, name, frame)?,
            source,
            kp,
            kd,
            rows,
            initial: None,
            offset_mode: ReferenceOffset::None,
            offset: None,
            jacobian: DMatrix::zeros(6, model.nv()),
            level,
            block: usize::MAX,
        })
    }

    pub fn row_count(&self) -> usize {
        self.rows.len()
    }

    pub fn reset(&mut self) {
        self.initial = None;
        self.offset = None;
    }

    fn reference(&mut self, kd: &KinDyn, input: &WbcInput) -> FrameRef {
        let mut r = self.source_reference(kd, input);
        if self.offset_mode == ReferenceOffset::Initial {
            let frame = self.frame;
            let reference = r.pose.rotation;
            let offset = *self
                .offset
                .get_or_insert_with(|| reference.inverse() * kd.frame_pose(frame).rotation);
            r.pose.rotation = reference * offset;
        }
        r
    }

    fn source_reference(&mut self, kd: &KinDyn, input: &WbcInput) -> FrameRef {
        match self.source {
            FrameReferenceSource::LeftFoot => FrameRef {
                pose: input.left_foot.pose,
                velocity: input.left_foot.velocity,
                acceleration: input.left_foot.acceleration,
            },
            FrameReferenceSource::RightFoot => FrameRef {
                pose: input.right_foot.pose,
                velocity: input.right_foot.velocity,
                acceleration: input.right_foot.acceleration,
            },
            FrameReferenceSource::Torso => {
                let mut velocity = Vector6::zeros();
                velocity
                    .fixed_rows_mut::<3>(3)
                    .copy_from(&input.torso.angular_velocity);
                let mut acceleration = Vector6::zeros();
                acceleration
                    .fixed_rows_mut::<3>(3)
                    .copy_from(&input.torso.angular_acceleration);
                FrameRef {
                    pose: Isometry3::from_parts(
                        nalgebra::Translation3::identity(),
                        input.torso.orientation,
                    ),
                    velocity,
                    acceleration,
                }
            }
            FrameReferenceSource::Initial => {
                let pose = *self
                    .initial
                    .get_or_insert_with(|| kd.frame_pose(self.frame));
                FrameRef {
                    pose,
                    velocity: Vector6::zeros(),
                    acceleration: Vector6::zeros(),
                }
            }
        }
    }

    /// Fills the block's columns `0..nv` (the ν / ν̇ part) and its right-hand side.
    pub fn update(
        &mut self,
        kd: &KinDyn,
        input: &WbcInput,
        block: TaskDataMut<'_>,
    ) -> Result<(), WbcError> {
        let r = self.reference(kd, input);
        kd.frame_jacobian(self.frame, &mut self.jacobian)?;
        let pose = kd.frame_pose(self.frame);
        let mut error = Vector6::zeros();
        error
            .fixed_rows_mut::<3>(0)
            .copy_from(&(r.pose.translation.vector - pose.translation.vector));
        error
            .fixed_rows_mut::<3>(3)
            .copy_from(&orientation_error(&r.pose.rotation, &pose.rotation));
        let mut rhs = Vector6::zeros();
        match self.level {
            Level::Velocity => {
                for i in 0..6 {
                    rhs[i] = r.velocity[i] + self.kp[i] * error[i];
                }
            }
            Level::Acceleration => {
                let v = kd.frame_velocity(self.frame);
                let bias = kd.frame_bias_acceleration(self.frame);
                for i in 0..6 {
                    rhs[i] = r.acceleration[i]
                        + self.kd[i] * (r.velocity[i] - v[i])
                        + self.kp[i] * error[i]
                        - bias[i];
                }
            }
        }
        let nv = self.jacobian.ncols();
        for (k, &row) in self.rows.iter().enumerate() {
            for j in 0..nv {
                block.a[(k, j)] = self.jacobian[(row, j)];
            }
            block.b[k] = rhs[row];
        }
        Ok(())
    }

    /// Current task error `[p_ref − p; Log(R_ref Rᵀ)]` on the kept rows, norm (for tests and logs).
    pub fn pose_error_norm(&mut self, kd: &KinDyn, input: &WbcInput) -> f64 {
        let r = self.reference(kd, input);
        let pose = kd.frame_pose(self.frame);
        let mut e = Vector6::zeros();
        e.fixed_rows_mut::<3>(0)
            .copy_from(&(r.pose.translation.vector - pose.translation.vector));
        e.fixed_rows_mut::<3>(3)
            .copy_from(&orientation_error(&r.pose.rotation, &pose.rotation));
        self.rows.iter().map(|&i| e[i] * e[i]).sum::<f64>().sqrt()
    }
}

/// CoM tracking (velocity level: `J_com ν = ẋ_ref + K_p (x_ref − x)`).
#[derive(Debug, Clone)]
pub(crate) struct ComVelocityTask {
    pub name: String,
    kp: f64,
    rows: Vec<usize>,
    jacobian: DMatrix<f64>,
    pub block: usize,
}

impl ComVelocityTask {
    pub fn new(model: &Model, c: &ComTaskConfig) -> Result<Self, WbcError> {
        check_gain(&c.name, "kp", c.kp)?;
        let rows: Vec<usize> = (0..3).filter(|&i| c.mask[i]).collect();
        if rows.is_empty() {
            return Err(WbcError::InvalidConfig {
                task: c.name.clone(),
                key: "mask",
                reason: "masks every row".into(),
            });
        }
        Ok(ComVelocityTask {
            name: c.name.clone(),
            kp: c.kp,
            rows,
            jacobian: DMatrix::zeros(3, model.nv()),
            block: usize::MAX,
        })
    }

    pub fn row_count(&self) -> usize {
        self.rows.len()
    }

    pub fn update(
        &mut self,
        kd: &mut KinDyn,
        input: &WbcInput,
        block: TaskDataMut<'_>,
    ) -> Result<(), WbcError> {
        kd.com_jacobian(&mut self.jacobian)?;
        let com = kd.com_position();
        let rhs: Vector3<f64> = input.com_velocity + self.kp * (input.com_position - com);
        let nv = self.jacobian.ncols();
        for (k, &row) in self.rows.iter().enumerate() {
            for j in 0..nv {
                block.a[(k, j)] = self.jacobian[(row, j)];
            }
            block.b[k] = rhs[row];
        }
        Ok(())
    }

    /// `‖(x_ref − x)[mask]‖`.
    pub fn error_norm(&self, kd: &KinDyn, input: &WbcInput) -> f64 {
        let e = input.com_position - kd.com_position();
        self.rows.iter().map(|&i| e[i] * e[i]).sum::<f64>().sqrt()
    }
}

/// Centroidal angular momentum, velocity level: `J_CMM,ω ν = h_ref`.
#[derive(Debug, Clone)]
pub(crate) struct AngularMomentumVelocityTask {
    cmm: DMatrix<f64>,
    pub block: usize,
}

impl AngularMomentumVelocityTask {
    pub fn new(model: &Model) -> Self {
        AngularMomentumVelocityTask {
            cmm: DMatrix::zeros(6, model.nv()),
            block: usize::MAX,
        }
    }

    pub fn update(
        &mut self,
        kd: &mut KinDyn,
        input: &WbcInput,
        block: TaskDataMut<'_>,
    ) -> Result<(), WbcError> {
        kd.centroidal_momentum_matrix(&mut self.cmm)?;
        let nv = self.cmm.ncols();
        for k in 0..3 {
            for j in 0..nv {
                block.a[(k, j)] = self.cmm[(3 + k, j)];
            }
            block.b[k] = input.angular_momentum[k];
        }
        Ok(())
    }
}

/// Joint regularization: `ṡ = K_p (s_ref − s)` (velocity) or `s̈ = −K_d ṡ + K_p (s_ref − s)` (acceleration).
#[derive(Debug, Clone)]
pub(crate) struct JointRegularizationTask {
    kp: f64,
    kd: f64,
    pub posture: DVector<f64>,
    pub weights: Vec<f64>,
    pub hard: bool,
    level: Level,
    pub block: usize,
}

impl JointRegularizationTask {
    pub fn new(
        model: &Model,
        c: &JointRegularizationTaskConfig,
        level: Level,
    ) -> Result<Self, WbcError> {
        check_gain(&c.name, "kp", c.kp)?;
        check_gain(&c.name, "kd", c.kd)?;
        let hard = c.priority == Priority::Hard;
        if hard && (c.weight.is_some() || !c.joint_weights.is_empty()) {
            return Err(WbcError::InvalidConfig {
                task: c.name.clone(),
                key: "weight",
                reason: "a hard task has no weight: remove `weight`/`joint_weights` or set \
                         `priority = \"soft\"`"
                    .into(),
            });
        }
        let weight = c.weight.unwrap_or(1.0);
        check_gain(&c.name, "weight", weight)?;
        let n = model.dof();
        let posture = joint_map(model, &c.name, &c.posture, 0.0)?;
        for w in c.joint_weights.values() {
            check_gain(&c.name, "joint_weights", *w)?;
        }
        let weights = joint_map(model, &c.name, &c.joint_weights, weight)?;
        debug_assert_eq!(posture.len(), n);
        Ok(JointRegularizationTask {
            kp: c.kp,
            kd: c.kd,
            posture: DVector::from_vec(posture),
            weights,
            hard,
            level,
            block: usize::MAX,
        })
    }

    pub fn update(
        &self,
        input: &WbcInput,
        s: &DVector<f64>,
        ds: &DVector<f64>,
        block: TaskDataMut<'_>,
    ) {
        let n = s.len();
        let posture = match &input.posture {
            Some(p) if p.len() == n => p,
            _ => &self.posture,
        };
        for i in 0..n {
            block.a[(i, 6 + i)] = 1.0;
            block.b[i] = match self.level {
                Level::Velocity => self.kp * (posture[i] - s[i]),
                Level::Acceleration => self.kp * (posture[i] - s[i]) - self.kd * ds[i],
            };
        }
    }
}

/// Values by joint name → a vector in model order (`default` for joints not named).
pub(crate) fn joint_map(
    model: &Model,
    task: &str,
    map: &BTreeMap<String, f64>,
    default: f64,
) -> Result<Vec<f64>, WbcError> {
    let mut out = vec![default; model.dof()];
    for (name, value) in map {
        let i = model
            .joint_index(name)
            .ok_or_else(|| WbcError::UnknownJoint {
                task: task.to_owned(),
                joint: name.clone(),
            })?;
        if !value.is_finite() {
            return Err(WbcError::InvalidConfig {
                task: task.to_owned(),
                key: "posture",
                reason: format!("joint `{name}`: {value} is not finite"),
            });
        }
        out[i] = *value;
    }
    Ok(out)
}

/// Joint limits in model order: (lower, upper, velocity limit).
pub(crate) fn joint_limits(model: &Model) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut lo = Vec::new();
    let mut hi = Vec::new();
    let mut vel = Vec::new();
    let mut eff = Vec::new();
    for j in model.joints() {
        lo.push(j.lower);
        hi.push(j.upper);
        vel.push(if j.velocity_limit > 0.0 {
            j.velocity_limit
        } else {
            f64::INFINITY
        });
        eff.push(if j.effort_limit > 0.0 {
            j.effort_limit
        } else {
            f64::INFINITY
        });
    }
    (lo, hi, vel, eff)
}
