//! Joints: posture regularization, IK `ṡ = K_p (s* − s)` [Romualdi 2022, eq. 7.1.12] (rad/s, `K_p` in
//! 1/s), TSID `s̈ = K_p (s* − s) − K_d ṡ` [Romualdi 2022, eq. 7.2.17] (rad/s², `K_p` in 1/s², `K_d` in
//! 1/s); and the joint position and velocity limits as bounds on the decision variable: IK one-step
//! look-ahead `(s⁻ − s)/T ≤ ṡ ≤ (s⁺ − s)/T` [Romualdi 2022, eq. 7.1.15], TSID
//! `2(s⁻ − s − T ṡ)/T² ≤ s̈ ≤ 2(s⁺ − s − T ṡ)/T²` [Romualdi 2022, eq. 7.2.29] and
//! `(−v_max − ṡ)/T ≤ s̈ ≤ (v_max − ṡ)/T`.

use std::collections::BTreeMap;

use nalgebra::DVector;
use stride_model::{Model, RobotState};
use stride_qp::TaskDataMut;

use super::{check_gain, Level};
use crate::config::{JointPositionLimitsTaskConfig, JointRegularizationTaskConfig, Priority};
use crate::error::WbcError;
use crate::io::WbcInput;

/// Validates a joint position limits task and returns its bounds: the model's limits `lo`/`hi` moved
/// inward by the task's margin (rad or m), and the look-ahead time (s; the control `period` by default).
pub(crate) fn position_limit_bounds(
    c: &JointPositionLimitsTaskConfig,
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
    /// Sets `K_p` (1/s in IK, 1/s² in TSID) and `K_d` (1/s, TSID).
    pub fn set_gains(&mut self, kp: f64, kd: f64) {
        self.kp = kp;
        self.kd = kd;
    }

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

/// TSID joint acceleration bounds (rad/s² or m/s², written into `lower[6..]`, `upper[6..]`): the
/// position look-ahead `2(s± − s − T ṡ)/T²` and the velocity look-ahead `(±v_max − ṡ)/T`; where they
/// conflict, the velocity bound is kept.
pub(crate) fn acceleration_bounds(
    position_limits: &Option<(Vec<f64>, Vec<f64>, f64)>,
    velocity_limits: &Option<(Vec<f64>, f64)>,
    state: &RobotState,
    lower: &mut DVector<f64>,
    upper: &mut DVector<f64>,
) {
    for i in 0..state.joint_positions.len() {
        let s = state.joint_positions[i];
        let ds = state.joint_velocities[i];
        let mut l = f64::NEG_INFINITY;
        let mut u = f64::INFINITY;
        if let Some((lo, hi, t)) = position_limits {
            l = 2.0 * (lo[i] - s - t * ds) / (t * t);
            u = 2.0 * (hi[i] - s - t * ds) / (t * t);
        }
        if let Some((v, dt)) = velocity_limits {
            l = l.max((-v[i] - ds) / dt);
            u = u.min((v[i] - ds) / dt);
        }
        if l > u {
            // conflicting position and velocity look-ahead: keep the velocity bound
            if let Some((v, dt)) = velocity_limits {
                l = (-v[i] - ds) / dt;
                u = (v[i] - ds) / dt;
            } else {
                let mid = 0.5 * (l + u);
                l = mid;
                u = mid;
            }
        }
        lower[6 + i] = l;
        upper[6 + i] = u;
    }
}

/// QP-IK joint velocity bounds (rad/s or m/s, written into `lower[6..]`, `upper[6..]`): the one-step
/// position look-ahead `(s± − s)/T` and `±v_max`; outside the position range and slower than needed to
/// come back, the joint moves back at the velocity limit (never an inconsistent bound pair).
pub(crate) fn velocity_bounds(
    position_limits: &Option<(Vec<f64>, Vec<f64>, f64)>,
    velocity_limits: &Option<Vec<f64>>,
    joint_positions: &DVector<f64>,
    lower: &mut DVector<f64>,
    upper: &mut DVector<f64>,
) {
    for i in 0..joint_positions.len() {
        let mut l = f64::NEG_INFINITY;
        let mut u = f64::INFINITY;
        if let Some((lo, hi, dt)) = position_limits {
            let s = joint_positions[i];
            l = (lo[i] - s) / dt;
            u = (hi[i] - s) / dt;
        }
        if let Some(v) = velocity_limits {
            l = l.max(-v[i]);
            u = u.min(v[i]);
        }
        if l > u {
            if let Some(v) = velocity_limits {
                if u < -v[i] {
                    l = -v[i];
                    u = -v[i];
                } else {
                    l = v[i];
                    u = v[i];
                }
            } else {
                l = u;
            }
        }
        lower[6 + i] = l;
        upper[6 + i] = u;
    }
}
