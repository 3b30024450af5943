//! Torque whole-body QP (TSID, thesis 7.2.31).
//!
//! Decision vector of the QP: `x = [ν̇; f_c for every loaded contact c]`. The joint torques are
//! eliminated through the joint rows of the floating-base dynamics, `τ = M_s ν̇ + h_s − Σ J_{c,s}ᵀ f_c`,
//! so the torque limits and the torque regularization become rows over `(ν̇, f)` and only the 6 base
//! rows of the dynamics remain equality constraints. Unloaded contacts have no wrench variable at all:
//! one QP of fixed structure is built at construction for every subset of loaded contacts (and with /
//! without a hard ZMP row), each with its own warm start; a tick fills and solves only the one it needs.

use std::sync::Arc;
use std::time::{Duration, Instant};

use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, Vector3, Vector6};
use stride_block::Block;
use stride_model::{FrameId, KinDyn, Model, VelocityRepresentation};

use crate::bridge::{check_weight, priority_weight, residual, QpBridge, VariableLayout};
use crate::config::{ContactTaskConfig, Foot, Priority, TaskConfig, TsidConfig, Weight};
use crate::error::WbcError;
use crate::ik::{check_references, check_state};
use crate::io::{SolveReport, TaskResidual, TsidOutput, WbcInput};
use crate::math::skew;
use crate::tasks::{
    check_gain, frame_id, joint_limits, position_limit_bounds, FrameTask, JointRegularizationTask,
    Level,
};
use stride_qp::{TaskDataMut, TaskKind, TaskSpec};

/// Maximum number of contacts (2^k QPs are prebuilt).
pub const MAX_CONTACTS: usize = 4;

/// Rows of the contact wrench feasibility in the contact frame: friction pyramid (4S), CoP (4),
/// torsional friction (2), all `≤ 0`; the normal force row is separate.
#[derive(Debug, Clone)]
struct Contact {
    name: String,
    frame: FrameId,
    foot: Foot,
    /// Homogeneous rows on the local wrench `[f; τ]`, all `A w ≤ 0`.
    local_rows: DMatrix<f64>,
    min_normal_force: f64,
    max_normal_force: f64,
    ramp_time: f64,
    kp: f64,
    kd: f64,
    // run-time
    load: f64,
    unload_from: f64,
    unloading: bool,
    jacobian: DMatrix<f64>,
    bias: Vector6<f64>,
    velocity: Vector6<f64>,
    pose: nalgebra::Isometry3<f64>,
    reference: nalgebra::Isometry3<f64>,
    last_fz: f64,
}

impl Contact {
    fn new(model: &Model, c: &ContactTaskConfig) -> Result<Self, WbcError> {
        let bad = |key: &'static str, reason: String| WbcError::InvalidConfig {
            task: c.name.clone(),
            key,
            reason,
        };
        if !(c.friction.is_finite() && c.friction > 0.0) {
            return Err(bad("friction", format!("{} must be > 0", c.friction)));
        }
        if c.facets == 0 || c.facets > 16 {
            return Err(bad("facets", format!("{} must be in 1..=16", c.facets)));
        }
        if !c.foot_x.iter().all(|v| v.is_finite()) || c.foot_x[0] >= c.foot_x[1] {
            return Err(bad("foot_x", "needs lower < upper".into()));
        }
        if !c.foot_y.iter().all(|v| v.is_finite()) || c.foot_y[0] >= c.foot_y[1] {
            return Err(bad("foot_y", "needs lower < upper".into()));
        }
        check_gain(&c.name, "torsional_friction", c.torsional_friction)?;
        check_gain(&c.name, "min_normal_force", c.min_normal_force)?;
        check_gain(&c.name, "ramp_time", c.ramp_time)?;
        check_gain(&c.name, "kp", c.kp)?;
        check_gain(&c.name, "kd", c.kd)?;
        if !(c.max_normal_force.is_finite() && c.max_normal_force > c.min_normal_force) {
            return Err(bad(
                "max_normal_force",
                format!(
                    "{} must be finite and > min_normal_force",
                    c.max_normal_force
                ),
            ));
        }
        let s = c.facets;
        let rows = 4 * s + 6;
        let mut a = DMatrix::zeros(rows, 6);
        let mu_eff = c.friction * (std::f64::consts::PI / (4.0 * s as f64)).cos();
        for k in 0..4 * s {
            let phi = (k as f64 + 0.5) * std::f64::consts::PI / (2.0 * s as f64);
            a[(k, 0)] = phi.cos();
            a[(k, 1)] = phi.sin();
            a[(k, 2)] = -mu_eff;
        }
        let r = 4 * s;
        // CoP x = −τ_y / f_z ∈ [x_lo, x_hi];  CoP y = τ_x / f_z ∈ [y_lo, y_hi]
        a[(r, 2)] = c.foot_x[0];
        a[(r, 4)] = 1.0;
        a[(r + 1, 2)] = -c.foot_x[1];
        a[(r + 1, 4)] = -1.0;
        a[(r + 2, 2)] = c.foot_y[0];
        a[(r + 2, 3)] = -1.0;
        a[(r + 3, 2)] = -c.foot_y[1];
        a[(r + 3, 3)] = 1.0;
        // |τ_z| ≤ γ f_z
        a[(r + 4, 5)] = 1.0;
        a[(r + 4, 2)] = -c.torsional_friction;
        a[(r + 5, 5)] = -1.0;
        a[(r + 5, 2)] = -c.torsional_friction;
        Ok(Contact {
            name: c.name.clone(),
            frame: frame_id(model, &c.name, &c.frame)?,
            foot: c.foot,
            local_rows: a,
            min_normal_force: c.min_normal_force,
            max_normal_force: c.max_normal_force,
            ramp_time: c.ramp_time,
            kp: c.kp,
            kd: c.kd,
            load: 0.0,
            unload_from: 0.0,
            unloading: false,
            jacobian: DMatrix::zeros(6, model.nv()),
            bias: Vector6::zeros(),
            velocity: Vector6::zeros(),
            pose: nalgebra::Isometry3::identity(),
            reference: nalgebra::Isometry3::identity(),
            last_fz: 0.0,
        })
    }

    /// Feasibility rows + 1 normal-force row.
    fn feasibility_rows(&self) -> usize {
        self.local_rows.nrows() + 1
    }

    /// Upper bound of f_z this tick.
    fn normal_upper(&self) -> f64 {
        if self.unloading {
            self.unload_from * self.load
        } else {
            self.max_normal_force * self.load
        }
    }

    /// Advances the load ramp for one period.
    fn advance_load(&mut self, in_contact: bool, period: f64) {
        let step = if self.ramp_time > 0.0 {
            period / self.ramp_time
        } else {
            1.0
        };
        if in_contact {
            if self.unloading {
                // re-loading during an unload ramp: continue from the current bound
                let current = self.normal_upper();
                self.unloading = false;
                self.load = (current / self.max_normal_force).clamp(0.0, 1.0);
            }
            if self.load == 0.0 {
                self.reference = self.pose;
            }
            self.load = (self.load + step).min(1.0);
        } else if self.load > 0.0 {
            if !self.unloading {
                self.unloading = true;
                self.unload_from =
                    (self.last_fz / self.load.max(1e-12)).clamp(0.0, self.max_normal_force);
            }
            self.load = (self.load - step).max(0.0);
            if self.load <= 0.0 {
                self.load = 0.0;
                self.unloading = false;
            }
        }
    }
}

#[derive(Debug, Clone, Copy)]
enum TsidTask {
    Dynamics,
    Frame(usize),
    Com { kp: f64, kd: f64, rows: [bool; 3] },
    AngularMomentum { kp: f64 },
    Joint(usize),
    PositionLimits,
    VelocityLimits,
    TorqueLimits { scale: f64 },
    Contact(usize),
    WrenchRegularization,
    TorqueRegularization,
    Zmp,
}

/// One prebuilt QP: the loaded contacts it has wrench variables for, its blocks and bridge.
struct Variant {
    /// Contact index → column offset of its wrench in x.
    offsets: [Option<usize>; MAX_CONTACTS],
    /// Config task index → stride-qp task indices (a contact task has two: constraint and feasibility).
    slots: Vec<Vec<usize>>,
    bridge: QpBridge,
    lower: DVector<f64>,
    upper: DVector<f64>,
    x: DVector<f64>,
}

/// The torque TSID block. See the module docs and docs/wbc.md.
pub struct Tsid {
    model: Arc<Model>,
    config: TsidConfig,
    /// Control period (s).
    period: f64,
    kd: KinDyn,
    tasks: Vec<TsidTask>,
    frame_tasks: Vec<FrameTask>,
    joint_tasks: Vec<JointRegularizationTask>,
    contacts: Vec<Contact>,
    variants: Vec<Variant>,
    position_limits: Option<(Vec<f64>, Vec<f64>, f64)>,
    velocity_limits: Option<(Vec<f64>, f64)>,
    effort: Vec<f64>,
    has_zmp: bool,
    mass: f64,
    gravity: Vector3<f64>,
    mass_matrix: DMatrix<f64>,
    bias_forces: DVector<f64>,
    com_position: Vector3<f64>,
    com_velocity: Vector3<f64>,
    momentum: Vector6<f64>,
    output: TsidOutput,
    last_valid: bool,
    last_variant: Option<usize>,
    initialized: bool,
}

impl Tsid {
    /// Builds the controller and its QPs, running every `period` (load ramps, default limit
    /// look-ahead), under the model's gravity ([`Model::gravity`]). All allocation happens here.
    ///
    /// Errors: a zero period, unknown frames/joints, invalid values (a weight on a hard task), no
    /// `floating_base_dynamics` task, more than `MAX_CONTACTS` contacts, or a QP that stride-qp rejects.
    pub fn new(model: Arc<Model>, config: TsidConfig, period: Duration) -> Result<Self, WbcError> {
        let ctl = "<tsid>";
        let period = period.as_secs_f64();
        if period <= 0.0 {
            return Err(WbcError::InvalidConfig {
                task: ctl.into(),
                key: "period",
                reason: format!("{period} s must be > 0"),
            });
        }
        let n = model.dof();
        let nv = model.nv();
        let (lo, hi, vmax, effort) = joint_limits(&model);
        let mut tasks = Vec::new();
        let mut frame_tasks = Vec::new();
        let mut joint_tasks = Vec::new();
        let mut contacts = Vec::new();
        let mut position_limits = None;
        let mut velocity_limits = None;
        let mut wrench_weight = [0.0; 6];
        let mut zmp_weight = None;
        let mut zmp_hard = false;
        let mut has_zmp = false;
        let mut has_dynamics = false;
        let mut names = std::collections::BTreeSet::new();
        // hard/soft flags per config task (for residual reports) and soft weights
        let mut eq_weights: Vec<Option<(bool, Weight)>> = Vec::new();
        for task in &config.tasks {
            if !names.insert(task.name().to_owned()) {
                return Err(WbcError::InvalidConfig {
                    task: task.name().to_owned(),
                    key: "name",
                    reason: "duplicate task name".into(),
                });
            }
            let weights = |rows: usize, priority: Priority, w| -> Result<_, WbcError> {
                Ok(Some(
                    match priority_weight(task.name(), rows, priority, w)? {
                        None => (true, Weight::default()),
                        Some(w) => (false, w),
                    },
                ))
            };
            match task {
                TaskConfig::FloatingBaseDynamics(_) => {
                    if has_dynamics {
                        return Err(WbcError::InvalidConfig {
                            task: task.name().to_owned(),
                            key: "type",
                            reason: "only one floating_base_dynamics task".into(),
                        });
                    }
                    has_dynamics = true;
                    tasks.push(TsidTask::Dynamics);
                    eq_weights.push(Some((true, Weight::default())));
                }
                TaskConfig::Se3(c) => {
                    let t = FrameTask::from_se3(&model, c, Level::Acceleration)?;
                    eq_weights.push(weights(t.row_count(), c.priority, &c.weight)?);
                    tasks.push(TsidTask::Frame(frame_tasks.len()));
                    frame_tasks.push(t);
                }
                TaskConfig::So3(c) | TaskConfig::R3(c) => {
                    let angular = matches!(task, TaskConfig::So3(_));
                    let t = FrameTask::from_frame3(&model, c, angular, Level::Acceleration)?;
                    eq_weights.push(weights(t.row_count(), c.priority, &c.weight)?);
                    tasks.push(TsidTask::Frame(frame_tasks.len()));
                    frame_tasks.push(t);
                }
                TaskConfig::Com(c) => {
                    check_gain(&c.name, "kp", c.kp)?;
                    check_gain(&c.name, "kd", c.kd)?;
                    let rows = c.mask.iter().filter(|m| **m).count();
                    if rows == 0 {
                        return Err(WbcError::InvalidConfig {
                            task: c.name.clone(),
                            key: "mask",
                            reason: "masks every row".into(),
                        });
                    }
                    eq_weights.push(weights(rows, c.priority, &c.weight)?);
                    tasks.push(TsidTask::Com {
                        kp: c.kp,
                        kd: c.kd,
                        rows: c.mask,
                    });
                }
                TaskConfig::AngularMomentum(c) => {
                    check_gain(&c.name, "kp", c.kp)?;
                    eq_weights.push(weights(3, c.priority, &c.weight)?);
                    tasks.push(TsidTask::AngularMomentum { kp: c.kp });
                }
                TaskConfig::JointRegularization(c) => {
                    let t = JointRegularizationTask::new(&model, c, Level::Acceleration)?;
                    eq_weights.push(Some((t.hard, Weight::PerRow(t.weights.clone()))));
                    tasks.push(TsidTask::Joint(joint_tasks.len()));
                    joint_tasks.push(t);
                }
                TaskConfig::JointPositionLimits(c) => {
                    position_limits = Some(position_limit_bounds(c, period, &lo, &hi, &model)?);
                    eq_weights.push(None);
                    tasks.push(TsidTask::PositionLimits);
                }
                TaskConfig::JointVelocityLimits(c) => {
                    check_gain(&c.name, "scale", c.scale)?;
                    velocity_limits = Some((vmax.iter().map(|v| v * c.scale).collect(), period));
                    eq_weights.push(None);
                    tasks.push(TsidTask::VelocityLimits);
                }
                TaskConfig::JointTorqueLimits(c) => {
                    check_gain(&c.name, "scale", c.scale)?;
                    eq_weights.push(None);
                    tasks.push(TsidTask::TorqueLimits { scale: c.scale });
                }
                TaskConfig::Contact(c) => {
                    if contacts.len() == MAX_CONTACTS {
                        return Err(WbcError::InvalidConfig {
                            task: c.name.clone(),
                            key: "type",
                            reason: format!("at most {MAX_CONTACTS} contacts"),
                        });
                    }
                    eq_weights.push(Some((true, Weight::default())));
                    tasks.push(TsidTask::Contact(contacts.len()));
                    contacts.push(Contact::new(&model, c)?);
                }
                TaskConfig::WrenchRegularization(c) => {
                    check_weight(&c.name, &c.weight, 6)?;
                    for (r, w) in wrench_weight.iter_mut().enumerate() {
                        *w = c.weight.row(r);
                    }
                    eq_weights.push(None);
                    tasks.push(TsidTask::WrenchRegularization);
                }
                TaskConfig::TorqueRegularization(c) => {
                    check_weight(&c.name, &c.weight, n)?;
                    eq_weights.push(Some((false, c.weight.clone())));
                    tasks.push(TsidTask::TorqueRegularization);
                }
                TaskConfig::Zmp(c) => {
                    if has_zmp {
                        return Err(WbcError::InvalidConfig {
                            task: c.name.clone(),
                            key: "type",
                            reason: "only one zmp task".into(),
                        });
                    }
                    has_zmp = true;
                    zmp_hard = c.priority == Priority::Hard;
                    zmp_weight = priority_weight(&c.name, 2, c.priority, &c.weight)?;
                    eq_weights.push(None);
                    tasks.push(TsidTask::Zmp);
                }
            }
        }
        if !has_dynamics {
            return Err(WbcError::InvalidConfig {
                task: ctl.into(),
                key: "tasks",
                reason: "the TSID needs a `floating_base_dynamics` task".into(),
            });
        }
        let k = contacts.len();
        let mut variants = Vec::new();
        let zmp_options: &[bool] = if has_zmp { &[false, true] } else { &[false] };
        for &zmp in zmp_options {
            for mask in 0..(1usize << k) {
                let mut offsets = [None; MAX_CONTACTS];
                let mut vars: Vec<(String, usize)> = vec![
                    ("base_acceleration".into(), 6),
                    ("joint_accelerations".into(), n),
                ];
                let mut nx = nv;
                for (c, contact) in contacts.iter().enumerate() {
                    if mask & (1 << c) != 0 {
                        offsets[c] = Some(nx);
                        nx += 6;
                        vars.push((format!("{}_wrench", contact.name), 6));
                    }
                }
                let loaded = mask != 0;
                let var_refs: Vec<(&str, usize)> =
                    vars.iter().map(|(s, z)| (s.as_str(), *z)).collect();
                let layout = VariableLayout::new(&var_refs)?;
                let mut blocks: Vec<TaskSpec> = Vec::new();
                let mut slots = Vec::new();
                for (ti, task) in tasks.iter().enumerate() {
                    let name = config.tasks[ti].name();
                    let mut s = Vec::new();
                    let eq = |blocks: &mut Vec<TaskSpec>, s: &mut Vec<usize>, rows: usize| {
                        if let Some((hard, w)) = &eq_weights[ti] {
                            s.push(blocks.len());
                            blocks.push(if *hard {
                                layout.hard(name, rows)
                            } else {
                                layout.soft(name, rows, w.clone())
                            });
                        }
                    };
                    match *task {
                        TsidTask::Dynamics => eq(&mut blocks, &mut s, 6),
                        TsidTask::Frame(f) => {
                            let replaced = contacts.iter().enumerate().any(|(c, ct)| {
                                mask & (1 << c) != 0 && ct.frame == frame_tasks[f].frame
                            });
                            if !replaced {
                                eq(&mut blocks, &mut s, frame_tasks[f].row_count());
                            }
                        }
                        TsidTask::Com { rows, .. } => {
                            if loaded {
                                eq(&mut blocks, &mut s, rows.iter().filter(|m| **m).count());
                            }
                        }
                        TsidTask::AngularMomentum { .. } => {
                            if loaded {
                                eq(&mut blocks, &mut s, 3);
                            }
                        }
                        TsidTask::Joint(_) | TsidTask::TorqueRegularization => {
                            eq(&mut blocks, &mut s, n)
                        }
                        TsidTask::PositionLimits | TsidTask::VelocityLimits => {}
                        TsidTask::TorqueLimits { .. } => {
                            s.push(blocks.len());
                            blocks.push(layout.inequality(name, n));
                        }
                        TsidTask::Contact(c) => {
                            if mask & (1 << c) != 0 {
                                eq(&mut blocks, &mut s, 6);
                                s.push(blocks.len());
                                blocks.push(layout.inequality(
                                    &format!("{name}_feasibility"),
                                    contacts[c].feasibility_rows(),
                                ));
                            }
                        }
                        TsidTask::WrenchRegularization => {
                            if loaded {
                                let rows = 6 * mask.count_ones() as usize;
                                let w: Vec<f64> = (0..rows).map(|r| wrench_weight[r % 6]).collect();
                                s.push(blocks.len());
                                blocks.push(layout.soft(name, rows, Weight::PerRow(w)));
                            }
                        }
                        TsidTask::Zmp => {
                            if zmp && loaded {
                                s.push(blocks.len());
                                blocks.push(match &zmp_weight {
                                    None => layout.hard(name, 2),
                                    Some(w) => layout.soft(name, 2, w.clone()),
                                });
                            }
                        }
                    }
                    slots.push(s);
                }
                let bridge =
                    QpBridge::new(layout, blocks, &config.qp, config.eliminate_equalities)?;
                variants.push(Variant {
                    offsets,
                    slots,
                    bridge,
                    lower: DVector::from_element(nx, f64::NEG_INFINITY),
                    upper: DVector::from_element(nx, f64::INFINITY),
                    x: DVector::zeros(nx),
                });
            }
        }
        let residuals = config
            .tasks
            .iter()
            .enumerate()
            .map(|(i, t)| TaskResidual {
                name: t.name().to_owned(),
                hard: match &eq_weights[i] {
                    Some((hard, _)) => *hard,
                    None => {
                        !matches!(tasks[i], TsidTask::WrenchRegularization | TsidTask::Zmp)
                            || (matches!(tasks[i], TsidTask::Zmp) && zmp_hard)
                    }
                },
                residual: 0.0,
            })
            .collect();
        let mut kd = KinDyn::new(Arc::clone(&model));
        kd.set_representation(VelocityRepresentation::Mixed);
        let gravity = model.gravity();
        let output = TsidOutput {
            joint_torques: DVector::zeros(n),
            accelerations: DVector::zeros(nv),
            contact_wrenches: [Vector6::zeros(); 2],
            contact_load: [0.0; 2],
            report: SolveReport::default(),
            residuals,
        };
        Ok(Tsid {
            mass: model.total_mass(),
            gravity,
            mass_matrix: DMatrix::zeros(nv, nv),
            bias_forces: DVector::zeros(nv),
            com_position: Vector3::zeros(),
            com_velocity: Vector3::zeros(),
            momentum: Vector6::zeros(),
            kd,
            tasks,
            frame_tasks,
            joint_tasks,
            contacts,
            variants,
            position_limits,
            velocity_limits,
            effort,
            has_zmp,
            output,
            last_valid: false,
            last_variant: None,
            initialized: false,
            model,
            config,
            period,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &TsidConfig {
        &self.config
    }

    /// Changes the weight of a soft task at run time (e.g. walking vs standing) in every prebuilt QP:
    /// one value for every row or one per row (per-row lists of `wrench_regularization` have 6 entries,
    /// applied to each contact). Allocation-free.
    ///
    /// Errors: unknown task name, a hard task or a constraint, wrong length, negative or non-finite weight.
    pub fn set_task_weight(&mut self, task: &str, weights: &[f64]) -> Result<(), WbcError> {
        let k = self
            .config
            .tasks
            .iter()
            .position(|t| t.name() == task)
            .ok_or_else(|| WbcError::InvalidInput(format!("no task `{task}`")))?;
        if weights.iter().any(|w| !(w.is_finite() && *w >= 0.0)) {
            return Err(WbcError::InvalidInput(format!(
                "task `{task}`: weights must be finite and >= 0"
            )));
        }
        let wrench = matches!(self.tasks[k], TsidTask::WrenchRegularization);
        if wrench && weights.len() != 1 && weights.len() != 6 {
            return Err(WbcError::InvalidInput(format!(
                "task `{task}`: 1 or 6 weights"
            )));
        }
        let mut found = false;
        for variant in &mut self.variants {
            for &b in &variant.slots[k] {
                let t = variant.bridge.task(b);
                if t.is_hard() || t.kind() != TaskKind::Equality {
                    return Err(WbcError::InvalidInput(format!(
                        "task `{task}` is not a soft task"
                    )));
                }
                let rows = t.rows();
                if !wrench && weights.len() != 1 && weights.len() != rows {
                    return Err(WbcError::InvalidInput(format!(
                        "task `{task}`: 1 or {rows} weights"
                    )));
                }
                for i in 0..rows {
                    let w = match weights.len() {
                        1 => weights[0],
                        _ if wrench => weights[i % 6],
                        _ => weights[i],
                    };
                    variant.bridge.set_row_weight(b, i, w)?;
                }
                found = true;
            }
        }
        if !found {
            return Err(WbcError::InvalidInput(format!(
                "task `{task}` has no weight"
            )));
        }
        Ok(())
    }

    /// The last output.
    pub fn output(&self) -> &TsidOutput {
        &self.output
    }

    /// The stride-qp problem solved at the last tick: data, solution, KKT check (for fixtures and
    /// cross-solver checks). `None` before the first tick.
    pub fn qp_problem(&self) -> Option<&stride_qp::QpProblem> {
        self.last_variant.map(|v| self.variants[v].bridge.problem())
    }

    fn variant_index(&self, zmp: bool) -> usize {
        let k = self.contacts.len();
        let mut mask = 0usize;
        for (c, contact) in self.contacts.iter().enumerate() {
            if contact.load > 0.0 {
                mask |= 1 << c;
            }
        }
        let base = if zmp && self.has_zmp { 1usize << k } else { 0 };
        base + mask
    }

    fn compute_dynamics(&mut self, input: &WbcInput) -> Result<(), WbcError> {
        self.kd.set_state(&input.state)?;
        self.kd.mass_matrix(&mut self.mass_matrix)?;
        self.kd.bias_forces(&mut self.bias_forces)?;
        self.com_position = self.kd.com_position();
        self.com_velocity = self.kd.com_velocity();
        self.momentum = self.kd.centroidal_momentum();
        for c in &mut self.contacts {
            self.kd.frame_jacobian(c.frame, &mut c.jacobian)?;
            c.bias = self.kd.frame_bias_acceleration(c.frame);
            c.velocity = self.kd.frame_velocity(c.frame);
            c.pose = self.kd.frame_pose(c.frame);
        }
        Ok(())
    }

    #[allow(clippy::too_many_lines)]
    fn fill(&mut self, vi: usize, input: &WbcInput) -> Result<(), WbcError> {
        let n = self.model.dof();
        let nv = n + 6;
        let m = self.mass;
        let variant = &mut self.variants[vi];
        for (ti, task) in self.tasks.iter().enumerate() {
            let slots = &variant.slots[ti];
            if slots.is_empty() {
                continue;
            }
            match *task {
                TsidTask::Dynamics => {
                    // M_b ν̇ − Σ J_{c,b}ᵀ f_c = −h_b
                    let b = &mut variant.bridge.rows_mut(slots[0]);
                    b.a.view_mut((0, 0), (6, nv))
                        .copy_from(&self.mass_matrix.view((0, 0), (6, nv)));
                    for (c, contact) in self.contacts.iter().enumerate() {
                        if let Some(off) = variant.offsets[c] {
                            for r in 0..6 {
                                for k in 0..6 {
                                    b.a[(r, off + k)] = -contact.jacobian[(k, r)];
                                }
                            }
                        }
                    }
                    for r in 0..6 {
                        b.b[r] = -self.bias_forces[r];
                    }
                }
                TsidTask::Frame(f) => {
                    let b = &mut variant.bridge.rows_mut(slots[0]);
                    self.frame_tasks[f].update(&self.kd, input, b.reborrow())?;
                }
                TsidTask::Com { kp, kd, rows } => {
                    let b = &mut variant.bridge.rows_mut(slots[0]);
                    let acc = input.com_acceleration
                        + kd * (input.com_velocity - self.com_velocity)
                        + kp * (input.com_position - self.com_position);
                    let rhs = m * acc - m * self.gravity;
                    let mut k = 0;
                    for r in 0..3 {
                        if !rows[r] {
                            continue;
                        }
                        for (c, _) in self.contacts.iter().enumerate() {
                            if let Some(off) = variant.offsets[c] {
                                b.a[(k, off + r)] = 1.0;
                            }
                        }
                        b.b[k] = rhs[r];
                        k += 1;
                    }
                }
                TsidTask::AngularMomentum { kp } => {
                    let b = &mut variant.bridge.rows_mut(slots[0]);
                    let h = self.momentum.fixed_rows::<3>(3).into_owned();
                    let rhs = kp * (input.angular_momentum - h);
                    for (c, contact) in self.contacts.iter().enumerate() {
                        if let Some(off) = variant.offsets[c] {
                            let arm: Matrix3<f64> =
                                skew(&(contact.pose.translation.vector - self.com_position));
                            b.a.view_mut((0, off), (3, 3)).copy_from(&arm);
                            b.a.view_mut((0, off + 3), (3, 3))
                                .copy_from(&Matrix3::identity());
                        }
                    }
                    for r in 0..3 {
                        b.b[r] = rhs[r];
                    }
                }
                TsidTask::Joint(j) => {
                    let b = &mut variant.bridge.rows_mut(slots[0]);
                    self.joint_tasks[j].update(
                        input,
                        &input.state.joint_positions,
                        &input.state.joint_velocities,
                        b.reborrow(),
                    );
                }
                TsidTask::PositionLimits | TsidTask::VelocityLimits => {}
                TsidTask::TorqueLimits { scale } => {
                    let b = &mut variant.bridge.rows_mut(slots[0]);
                    fill_torque_rows(&self.mass_matrix, &self.contacts, &variant.offsets, b);
                    for i in 0..n {
                        let lim = scale * self.effort[i];
                        b.lower[i] = -lim - self.bias_forces[6 + i];
                        b.upper[i] = lim - self.bias_forces[6 + i];
                    }
                }
                TsidTask::TorqueRegularization => {
                    let b = &mut variant.bridge.rows_mut(slots[0]);
                    fill_torque_rows(&self.mass_matrix, &self.contacts, &variant.offsets, b);
                    for i in 0..n {
                        b.b[i] = -self.bias_forces[6 + i];
                    }
                }
                TsidTask::Contact(c) => {
                    let contact = &self.contacts[c];
                    let off = variant.offsets[c].unwrap_or(0);
                    // contact constraint: J ν̇ = −J̇ν − K_d v − K_p e
                    let b = &mut variant.bridge.rows_mut(slots[0]);
                    b.a.view_mut((0, 0), (6, nv)).copy_from(&contact.jacobian);
                    let mut e = Vector6::zeros();
                    e.fixed_rows_mut::<3>(0).copy_from(
                        &(contact.reference.translation.vector - contact.pose.translation.vector),
                    );
                    e.fixed_rows_mut::<3>(3)
                        .copy_from(&crate::math::orientation_error(
                            &contact.reference.rotation,
                            &contact.pose.rotation,
                        ));
                    for r in 0..6 {
                        b.b[r] =
                            -contact.bias[r] - contact.kd * contact.velocity[r] + contact.kp * e[r];
                    }
                    // feasibility: A blockdiag(Rᵀ, Rᵀ) f ≤ 0, then the normal force row
                    let b = &mut variant.bridge.rows_mut(slots[1]);
                    let rt = contact
                        .pose
                        .rotation
                        .to_rotation_matrix()
                        .matrix()
                        .transpose();
                    let mut rot6 = Matrix6::zeros();
                    rot6.view_mut((0, 0), (3, 3)).copy_from(&rt);
                    rot6.view_mut((3, 3), (3, 3)).copy_from(&rt);
                    let rows = contact.local_rows.nrows();
                    for r in 0..rows {
                        for k in 0..6 {
                            let mut s = 0.0;
                            for l in 0..6 {
                                s += contact.local_rows[(r, l)] * rot6[(l, k)];
                            }
                            b.a[(r, off + k)] = s;
                        }
                        b.lower[r] = f64::NEG_INFINITY;
                        b.upper[r] = 0.0;
                    }
                    // normal force (local z): row 2 of Rᵀ on the force
                    for k in 0..3 {
                        b.a[(rows, off + k)] = rt[(2, k)];
                    }
                    let upper = contact.normal_upper();
                    b.lower[rows] = contact.min_normal_force.min(upper);
                    b.upper[rows] = upper;
                }
                TsidTask::WrenchRegularization => {
                    let b = &mut variant.bridge.rows_mut(slots[0]);
                    let mut k = 0;
                    for (c, contact) in self.contacts.iter().enumerate() {
                        if let Some(off) = variant.offsets[c] {
                            let reference = match (&input.desired_wrenches, contact.foot) {
                                (Some(w), Foot::Left) => w[0],
                                (Some(w), Foot::Right) => w[1],
                                (None, _) => Vector6::zeros(),
                            };
                            for r in 0..6 {
                                b.a[(k + r, off + r)] = 1.0;
                                b.b[k + r] = reference[r];
                            }
                            k += 6;
                        }
                    }
                }
                TsidTask::Zmp => {
                    let b = &mut variant.bridge.rows_mut(slots[0]);
                    let zmp = input.desired_zmp.unwrap_or_default();
                    // ground height: mean of the loaded contacts' heights
                    let mut z0 = 0.0;
                    let mut count: f64 = 0.0;
                    for (c, contact) in self.contacts.iter().enumerate() {
                        if variant.offsets[c].is_some() {
                            z0 += contact.pose.translation.vector.z;
                            count += 1.0;
                        }
                    }
                    z0 /= count.max(1.0);
                    for (c, contact) in self.contacts.iter().enumerate() {
                        if let Some(off) = variant.offsets[c] {
                            let p = contact.pose.translation.vector;
                            // x: (p_z − z0) f_x + (r_x − p_x) f_z + τ_y = 0 (summed)
                            b.a[(0, off)] = p.z - z0;
                            b.a[(0, off + 2)] = zmp.x - p.x;
                            b.a[(0, off + 4)] = 1.0;
                            // y: (p_z − z0) f_y + (r_y − p_y) f_z − τ_x = 0
                            b.a[(1, off + 1)] = p.z - z0;
                            b.a[(1, off + 2)] = zmp.y - p.y;
                            b.a[(1, off + 3)] = -1.0;
                        }
                    }
                    b.b[0] = 0.0;
                    b.b[1] = 0.0;
                }
            }
        }
        // joint acceleration bounds
        for i in 0..n {
            let s = input.state.joint_positions[i];
            let ds = input.state.joint_velocities[i];
            let mut l = f64::NEG_INFINITY;
            let mut u = f64::INFINITY;
            if let Some((lo, hi, t)) = &self.position_limits {
                l = 2.0 * (lo[i] - s - t * ds) / (t * t);
                u = 2.0 * (hi[i] - s - t * ds) / (t * t);
            }
            if let Some((v, dt)) = &self.velocity_limits {
                l = l.max((-v[i] - ds) / dt);
                u = u.min((v[i] - ds) / dt);
            }
            if l > u {
                // conflicting position and velocity look-ahead: keep the velocity bound
                if let Some((v, dt)) = &self.velocity_limits {
                    l = (-v[i] - ds) / dt;
                    u = (v[i] - ds) / dt;
                } else {
                    let mid = 0.5 * (l + u);
                    l = mid;
                    u = mid;
                }
            }
            variant.lower[6 + i] = l;
            variant.upper[6 + i] = u;
        }
        Ok(())
    }

    fn write_output(&mut self, vi: usize) {
        let n = self.model.dof();
        let nv = n + 6;
        let variant = &self.variants[vi];
        let x = &variant.x;
        for i in 0..nv {
            self.output.accelerations[i] = x[i];
        }
        // τ = M_s ν̇ + h_s − Σ J_{c,s}ᵀ f_c
        for i in 0..n {
            let mut t = self.bias_forces[6 + i];
            for j in 0..nv {
                t += self.mass_matrix[(6 + i, j)] * x[j];
            }
            for (c, contact) in self.contacts.iter().enumerate() {
                if let Some(off) = variant.offsets[c] {
                    for k in 0..6 {
                        t -= contact.jacobian[(k, 6 + i)] * x[off + k];
                    }
                }
            }
            self.output.joint_torques[i] = t;
        }
        self.output.contact_wrenches = [Vector6::zeros(); 2];
        for (c, contact) in self.contacts.iter_mut().enumerate() {
            let w = match variant.offsets[c] {
                Some(off) => Vector6::from_iterator((0..6).map(|k| x[off + k])),
                None => Vector6::zeros(),
            };
            let rt = contact.pose.rotation.inverse();
            contact.last_fz = (rt * w.fixed_rows::<3>(0).into_owned()).z;
            let slot = match contact.foot {
                Foot::Left => 0,
                Foot::Right => 1,
            };
            self.output.contact_wrenches[slot] += w;
        }
        for (k, slots) in variant.slots.iter().enumerate() {
            let mut s = 0.0;
            for &b in slots {
                let r = residual(variant.bridge.task(b), x);
                s += r * r;
            }
            self.output.residuals[k].residual = match self.tasks[k] {
                TsidTask::PositionLimits | TsidTask::VelocityLimits => {
                    let mut s = 0.0;
                    for i in 0..n {
                        let v = x[6 + i];
                        let e = (variant.lower[6 + i] - v).max(0.0)
                            + (v - variant.upper[6 + i]).max(0.0);
                        s += e * e;
                    }
                    s.sqrt()
                }
                _ => s.sqrt(),
            };
        }
    }
}

/// Rows `[M_s | −J_{c,s}ᵀ …]` of the eliminated torque `τ = M_s ν̇ + h_s − Σ J_{c,s}ᵀ f_c`.
fn fill_torque_rows(
    mass: &DMatrix<f64>,
    contacts: &[Contact],
    offsets: &[Option<usize>; MAX_CONTACTS],
    b: &mut TaskDataMut<'_>,
) {
    let nv = mass.ncols();
    let n = nv - 6;
    b.a.view_mut((0, 0), (n, nv))
        .copy_from(&mass.view((6, 0), (n, nv)));
    for (c, contact) in contacts.iter().enumerate() {
        if let Some(off) = offsets[c] {
            for i in 0..n {
                for k in 0..6 {
                    b.a[(i, off + k)] = -contact.jacobian[(k, 6 + i)];
                }
            }
        }
    }
}

impl Block for Tsid {
    type Input = WbcInput;
    type Output = TsidOutput;
    type Error = WbcError;

    fn step(&mut self, input: &WbcInput) -> Result<&TsidOutput, WbcError> {
        let start = Instant::now();
        check_state(&self.model, &input.state)?;
        check_references(&self.model, input)?;
        self.compute_dynamics(input)?;
        let period = self.period;
        for contact in &mut self.contacts {
            let flag = match contact.foot {
                Foot::Left => input.left_in_contact,
                Foot::Right => input.right_in_contact,
            };
            if !self.initialized {
                // start-up: contacts already closed carry load at once
                contact.reference = contact.pose;
                contact.unloading = false;
                contact.load = if flag { 1.0 } else { 0.0 };
            } else {
                contact.advance_load(flag, period);
            }
        }
        self.initialized = true;
        let vi = self.variant_index(input.desired_zmp.is_some());
        self.fill(vi, input)?;
        let variant = &mut self.variants[vi];
        let report = variant
            .bridge
            .solve(&variant.lower, &variant.upper, &mut variant.x);
        self.last_variant = Some(vi);
        self.output.report = report;
        if report.held {
            // keep the last valid torques (zero before the first valid solve)
            if !self.last_valid {
                self.output.joint_torques.fill(0.0);
            }
        } else {
            self.write_output(vi);
            self.last_valid = true;
        }
        for (c, contact) in self.contacts.iter().enumerate() {
            let slot = match contact.foot {
                Foot::Left => 0,
                Foot::Right => 1,
            };
            let _ = c;
            self.output.contact_load[slot] = contact.load;
        }
        self.output.report.tick_time = start.elapsed().as_secs_f64();
        Ok(&self.output)
    }

    fn reset(&mut self) {
        for v in &mut self.variants {
            v.bridge.reset();
            v.x.fill(0.0);
        }
        for c in &mut self.contacts {
            c.load = 0.0;
            c.unloading = false;
            c.last_fz = 0.0;
        }
        for t in &mut self.frame_tasks {
            t.reset();
        }
        self.last_valid = false;
        self.last_variant = None;
        self.initialized = false;
        self.output.joint_torques.fill(0.0);
        self.output.accelerations.fill(0.0);
        self.output.contact_wrenches = [Vector6::zeros(); 2];
        self.output.report = SolveReport::default();
    }
}
