//! Torque whole-body QP (TSID) [Romualdi 2022, eq. 7.2.31].
//!
//! Decision vector of the QP: `x = [ν̇; f_c for every loaded contact c]`. The joint torques are
//! eliminated through the joint rows of the floating-base dynamics, `τ = M_s ν̇ + h_s − Σ J_{c,s}ᵀ f_c`,
//! so the torque limits and the torque regularization become rows over `(ν̇, f)` and only the 6 base
//! rows of the dynamics remain equality constraints. Unloaded contacts have no wrench variable at all:
//! one QP of fixed structure is built at construction for every subset of loaded contacts (and with /
//! without a hard ZMP row), each with its own warm start; a tick fills and solves only the one it needs.

use std::sync::Arc;
use std::time::{Duration, Instant};

use nalgebra::{DMatrix, DVector, Vector3, Vector6};
use stride_block::Block;
use stride_model::{KinDyn, Model, RobotState, VelocityRepresentation};
use stride_qp::{TaskDataMut, TaskKind, TaskSpec};

use crate::bridge::{check_weight, priority_weight, QpBridge, VariableLayout};
use crate::config::{check_unique_names, ContactModel, Priority, TaskConfig, TsidConfig, Weight};
use crate::error::WbcError;
use crate::ik::{check_references, check_state, find_task};
use crate::io::{InputLayout, SolveReport, TaskResidual, TsidOutput, WbcInput};
use crate::names::input_layout;
use crate::names::Resolver;
use crate::tasks::compliant::{
    add_angular_momentum_drift, add_unloaded_wrenches, derived_angular_momentum_gain,
    fill_contact_dynamics, measured_joint_torques, to_rate_rows, CompliantContacts,
    HELD_LIFT_OFF_LOAD,
};
use crate::tasks::contact::fill_wrench_regularization;
use crate::tasks::dynamics::{
    fill_base_dynamics, fill_flexible_dynamics, fill_torque_limits, fill_torque_regularization,
    joint_torques,
};
use crate::tasks::joint::acceleration_bounds;
use crate::tasks::zmp::fill_zmp;
use crate::tasks::{
    check_gain, joint_limits, position_limit_bounds, AngularMomentumRateTask, ComMomentumTask,
    Contact, FrameTask, JointMomentumReference, JointRegularizationTask, Level, TsidContext,
};

/// Model indices of the flexible joints named in `names`: each a joint of the model, none twice.
fn flexible_joints(model: &Model, names: &[String]) -> Result<Vec<usize>, WbcError> {
    let mut out = Vec::with_capacity(names.len());
    for name in names {
        let j = model
            .joint_index(name)
            .ok_or_else(|| WbcError::UnknownJoint {
                task: "flexible_joints".into(),
                joint: name.clone(),
            })?;
        if out.contains(&j) {
            return Err(WbcError::InvalidConfig {
                task: "<tsid>".into(),
                key: "flexible_joints",
                reason: format!("`{name}` is listed twice"),
            });
        }
        out.push(j);
    }
    Ok(out)
}

/// Maximum number of contacts (2^k QPs are prebuilt).
pub const MAX_CONTACTS: usize = 4;

/// What a config task became in the TSID.
#[derive(Debug, Clone, Copy)]
enum TsidTask {
    Dynamics,
    Frame(usize),
    Com(ComMomentumTask),
    AngularMomentum(AngularMomentumRateTask),
    Joint(usize),
    PositionLimits,
    VelocityLimits,
    TorqueLimits { scale: f64 },
    Contact(usize),
    WrenchRegularization,
    TorqueRegularization,
    Zmp,
}

/// The config's tasks, checked and built, before the QPs are: shared by every prebuilt QP.
struct TaskSet {
    names: Resolver,
    tasks: Vec<TsidTask>,
    /// Per config task: `Some((hard, weight))` for the equality tasks whose rows keep the config's
    /// priority and weight (the weight is unused when hard), `None` for the others.
    eq_weights: Vec<Option<(bool, Weight)>>,
    frame_tasks: Vec<FrameTask>,
    joint_tasks: Vec<JointRegularizationTask>,
    contacts: Vec<Contact>,
    position_limits: Option<(Vec<f64>, Vec<f64>, f64)>,
    velocity_limits: Option<(Vec<f64>, f64)>,
    wrench_weight: [f64; 6],
    /// The ZMP task's weight (`None`: hard).
    zmp_weight: Option<Weight>,
    zmp_hard: bool,
    has_zmp: bool,
    has_dynamics: bool,
    /// Model indices of the passive flexible joints (`TsidConfig::flexible_joints`).
    flexible: Vec<usize>,
    /// Angular momentum tasks with `reference_joints`: config task index and its reference.
    momentum_references: Vec<(usize, JointMomentumReference)>,
}

impl TaskSet {
    /// Checks and builds every config task.
    fn parse(model: &Model, config: &TsidConfig, period: f64) -> Result<Self, WbcError> {
        let mut set = TaskSet {
            names: Resolver::new(input_layout(&config.tasks)?),
            tasks: Vec::new(),
            eq_weights: Vec::new(),
            frame_tasks: Vec::new(),
            joint_tasks: Vec::new(),
            contacts: Vec::new(),
            position_limits: None,
            velocity_limits: None,
            wrench_weight: [0.0; 6],
            zmp_weight: None,
            zmp_hard: false,
            has_zmp: false,
            has_dynamics: false,
            flexible: flexible_joints(model, &config.flexible_joints)?,
            momentum_references: Vec::new(),
        };
        check_unique_names(&config.tasks)?;
        for task in &config.tasks {
            set.add(model, task, period)?;
        }
        if !set.has_dynamics {
            return Err(WbcError::InvalidConfig {
                task: "<tsid>".into(),
                key: "tasks",
                reason: "the TSID needs a `floating_base_dynamics` task".into(),
            });
        }
        Ok(set)
    }

    /// Adds one config task.
    fn add(&mut self, model: &Model, task: &TaskConfig, period: f64) -> Result<(), WbcError> {
        let n = model.dof();
        let weights = |rows: usize, priority: Priority, w| -> Result<_, WbcError> {
            Ok(Some(
                match priority_weight(task.name(), rows, priority, w)? {
                    None => (true, Weight::default()),
                    Some(w) => (false, w),
                },
            ))
        };
        let only_one = |name: &str, what: &str| WbcError::InvalidConfig {
            task: name.to_owned(),
            key: "type",
            reason: format!("only one {what} task"),
        };
        let (entry, weight) = match task {
            TaskConfig::FloatingBaseDynamics(c) => {
                if self.has_dynamics {
                    return Err(only_one(&c.name, "floating_base_dynamics"));
                }
                self.has_dynamics = true;
                (TsidTask::Dynamics, Some((true, Weight::default())))
            }
            TaskConfig::Se3(c) => {
                let t = FrameTask::from_se3(model, &self.names, c, Level::Acceleration)?;
                let w = weights(t.row_count(), c.priority, &c.weight)?;
                self.frame_tasks.push(t);
                (TsidTask::Frame(self.frame_tasks.len() - 1), w)
            }
            TaskConfig::So3(c) | TaskConfig::R3(c) => {
                let angular = matches!(task, TaskConfig::So3(_));
                let t =
                    FrameTask::from_frame3(model, &self.names, c, angular, Level::Acceleration)?;
                let w = weights(t.row_count(), c.priority, &c.weight)?;
                self.frame_tasks.push(t);
                (TsidTask::Frame(self.frame_tasks.len() - 1), w)
            }
            TaskConfig::Com(c) => {
                let t = ComMomentumTask::new(c)?;
                (
                    TsidTask::Com(t),
                    weights(t.row_count(), c.priority, &c.weight)?,
                )
            }
            TaskConfig::AngularMomentum(c) => {
                let t = AngularMomentumRateTask::new(c)?;
                if let Some(r) = JointMomentumReference::new(model, &self.names, c)? {
                    self.momentum_references.push((self.tasks.len(), r));
                }
                (
                    TsidTask::AngularMomentum(t),
                    weights(3, c.priority, &c.weight)?,
                )
            }
            TaskConfig::JointRegularization(c) => {
                let t = JointRegularizationTask::new(model, c, Level::Acceleration)?;
                let w = Some((t.hard, Weight::PerRow(t.weights.clone())));
                self.joint_tasks.push(t);
                (TsidTask::Joint(self.joint_tasks.len() - 1), w)
            }
            TaskConfig::JointPositionLimits(c) => {
                let (lo, hi, _, _) = joint_limits(model);
                self.position_limits = Some(position_limit_bounds(c, period, &lo, &hi, model)?);
                (TsidTask::PositionLimits, None)
            }
            TaskConfig::JointVelocityLimits(c) => {
                check_gain(&c.name, "scale", c.scale)?;
                let (_, _, vmax, _) = joint_limits(model);
                self.velocity_limits = Some((vmax.iter().map(|v| v * c.scale).collect(), period));
                (TsidTask::VelocityLimits, None)
            }
            TaskConfig::JointTorqueLimits(c) => {
                check_gain(&c.name, "scale", c.scale)?;
                (TsidTask::TorqueLimits { scale: c.scale }, None)
            }
            TaskConfig::Contact(c) => {
                if self.contacts.len() == MAX_CONTACTS {
                    return Err(WbcError::InvalidConfig {
                        task: c.name.clone(),
                        key: "type",
                        reason: format!("at most {MAX_CONTACTS} contacts"),
                    });
                }
                self.contacts.push(Contact::new(model, &self.names, c)?);
                (
                    TsidTask::Contact(self.contacts.len() - 1),
                    Some((true, Weight::default())),
                )
            }
            TaskConfig::WrenchRegularization(c) => {
                check_weight(&c.name, &c.weight, 6)?;
                for (r, w) in self.wrench_weight.iter_mut().enumerate() {
                    *w = c.weight.row(r);
                }
                (TsidTask::WrenchRegularization, None)
            }
            TaskConfig::TorqueRegularization(c) => {
                check_weight(&c.name, &c.weight, n)?;
                (
                    TsidTask::TorqueRegularization,
                    Some((false, c.weight.clone())),
                )
            }
            TaskConfig::Zmp(c) => {
                if self.has_zmp {
                    return Err(only_one(&c.name, "zmp"));
                }
                self.has_zmp = true;
                self.zmp_hard = c.priority == Priority::Hard;
                self.zmp_weight = priority_weight(&c.name, 2, c.priority, &c.weight)?;
                (TsidTask::Zmp, None)
            }
        };
        self.tasks.push(entry);
        self.eq_weights.push(weight);
        Ok(())
    }

    /// Whether config task `ti` is a hard constraint (for the residual reports).
    fn is_hard(&self, ti: usize) -> bool {
        match &self.eq_weights[ti] {
            Some((hard, _)) => *hard,
            None => match self.tasks[ti] {
                TsidTask::WrenchRegularization => false,
                TsidTask::Zmp => self.zmp_hard,
                _ => true,
            },
        }
    }

    /// The stride-qp tasks of config task `ti` in the QP with the loaded contacts `mask` (bit c: contact
    /// c) and, when `zmp`, the ZMP rows; pushed onto `specs`, their indices onto `slots`.
    #[allow(clippy::too_many_arguments)]
    fn specs_of(
        &self,
        ti: usize,
        name: &str,
        layout: &VariableLayout,
        mask: usize,
        zmp: bool,
        n: usize,
        specs: &mut Vec<TaskSpec>,
        slots: &mut Vec<usize>,
    ) {
        let loaded = mask != 0;
        let mut push = |spec: TaskSpec| {
            slots.push(specs.len());
            specs.push(spec);
        };
        // the equality tasks (all have `eq_weights[ti]`) with their priority and weight
        let eq = |rows: usize| match &self.eq_weights[ti] {
            Some((false, w)) => layout.soft(name, rows, w.clone()),
            _ => layout.hard(name, rows),
        };
        match self.tasks[ti] {
            TsidTask::Dynamics => push(eq(6 + self.flexible.len())),
            TsidTask::Frame(f) => {
                // the contact constraint of a loaded contact replaces a frame task on its frame
                let frame = self.frame_tasks[f].frame;
                let replaced = self
                    .contacts
                    .iter()
                    .enumerate()
                    .any(|(c, ct)| mask & (1 << c) != 0 && ct.frame == frame);
                if !replaced {
                    push(eq(self.frame_tasks[f].row_count()));
                }
            }
            TsidTask::Com(t) if loaded => push(eq(t.row_count())),
            TsidTask::AngularMomentum(_) if loaded => push(eq(3)),
            TsidTask::Com(_) | TsidTask::AngularMomentum(_) => {}
            TsidTask::Joint(_) | TsidTask::TorqueRegularization => push(eq(n)),
            TsidTask::PositionLimits | TsidTask::VelocityLimits => {}
            TsidTask::TorqueLimits { .. } => push(layout.inequality(name, n)),
            TsidTask::Contact(c) => {
                if mask & (1 << c) != 0 {
                    push(eq(6));
                    push(layout.inequality(
                        &format!("{name}_feasibility"),
                        self.contacts[c].feasibility_rows(),
                    ));
                }
            }
            TsidTask::WrenchRegularization => {
                if loaded {
                    let rows = 6 * mask.count_ones() as usize;
                    let w: Vec<f64> = (0..rows).map(|r| self.wrench_weight[r % 6]).collect();
                    push(layout.soft(name, rows, Weight::PerRow(w)));
                }
            }
            TsidTask::Zmp => {
                if zmp && loaded {
                    push(match &self.zmp_weight {
                        None => layout.hard(name, 2),
                        Some(w) => layout.soft(name, 2, w.clone()),
                    });
                }
            }
        }
    }

    /// The QP with wrench variables for the contacts in `mask` and, when `zmp`, the ZMP rows.
    fn variant(
        &self,
        config: &TsidConfig,
        n: usize,
        mask: usize,
        zmp: bool,
    ) -> Result<Variant, WbcError> {
        let mut offsets = [None; MAX_CONTACTS];
        let mut vars: Vec<(String, usize)> = vec![
            ("base_acceleration".into(), 6),
            ("joint_accelerations".into(), n),
        ];
        let mut nx = n + 6;
        for (c, contact) in self.contacts.iter().enumerate() {
            if mask & (1 << c) != 0 {
                offsets[c] = Some(nx);
                nx += 6;
                let suffix = match config.contact_model {
                    ContactModel::Rigid => "wrench",
                    ContactModel::Compliant => "wrench_rate",
                };
                vars.push((format!("{}_{suffix}", contact.name), 6));
            }
        }
        let var_refs: Vec<(&str, usize)> = vars.iter().map(|(s, z)| (s.as_str(), *z)).collect();
        let layout = VariableLayout::new(&var_refs)?;
        let mut specs: Vec<TaskSpec> = Vec::new();
        let mut slots = Vec::new();
        for ti in 0..self.tasks.len() {
            let mut s = Vec::new();
            let name = config.tasks[ti].name();
            self.specs_of(ti, name, &layout, mask, zmp, n, &mut specs, &mut s);
            slots.push(s);
        }
        let bridge = QpBridge::new(layout, specs, &config.qp, config.eliminate_equalities)?;
        Ok(Variant {
            offsets,
            slots,
            bridge,
            lower: DVector::from_element(nx, f64::NEG_INFINITY),
            upper: DVector::from_element(nx, f64::INFINITY),
            x: DVector::zeros(nx),
        })
    }
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
///
/// ```
/// use std::{sync::Arc, time::Duration};
/// use stride_wbc::prelude::*;
/// use stride_model::{bundled, KinDyn, RobotState, VelocityRepresentation};
///
/// let model = Arc::new(bundled::model()?);
/// let mut tsid = Tsid::new(model.clone(), TsidConfig::default_for_bundled_model(), Duration::from_millis(2))?;
/// // the robot at its standing posture, soles on z = 0
/// let mut state = RobotState::zero(&model);
/// for (joint, q) in bundled::POSTURE {
///     state.joint_positions[model.joint_index(joint).unwrap()] = q;
/// }
/// let mut kd = KinDyn::new(model.clone());
/// kd.set_representation(VelocityRepresentation::Mixed);
/// kd.set_state(&state)?;
/// let left = model.frame_id(bundled::LEFT_SOLE).unwrap();
/// state.base_pose.translation.vector.z -= kd.frame_pose(left).translation.vector.z;
/// kd.set_state(&state)?;
/// let pose = |name: &str| kd.frame_pose(model.frame_id(name).unwrap());
/// // hold it there: references by name
/// let mut input = tsid.input(&state);
/// input.com_position = kd.com_position();
/// input.set_frame_reference(walking::LEFT_FOOT, FrameReference::still(pose(bundled::LEFT_SOLE)))?;
/// input.set_frame_reference(walking::RIGHT_FOOT, FrameReference::still(pose(bundled::RIGHT_SOLE)))?;
/// let torso = input.frame_id(walking::TORSO)?; // a handle: no string lookup in a loop
/// input.frame_mut(torso)?.pose.rotation = pose(bundled::TORSO).rotation;
/// let out = tsid.step(&input)?;
/// assert!(out.report.is_nominal());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct Tsid {
    model: Arc<Model>,
    config: TsidConfig,
    /// Control period (s).
    period: f64,
    /// Control period as given to [`Tsid::new`] (for [`Tsid::add_task`]).
    period_duration: Duration,
    names: Resolver,
    /// Per config task: whether it takes part (see [`Tsid::set_task_enabled`]).
    enabled: Vec<bool>,
    kd: KinDyn,
    tasks: Vec<TsidTask>,
    frame_tasks: Vec<FrameTask>,
    joint_tasks: Vec<JointRegularizationTask>,
    contacts: Vec<Contact>,
    variants: Vec<Variant>,
    position_limits: Option<(Vec<f64>, Vec<f64>, f64)>,
    velocity_limits: Option<(Vec<f64>, f64)>,
    effort: Vec<f64>,
    /// The passive flexible joints (TSID-Flex; empty: the rigid TSID): model index, `k` N·m/rad, `b`
    /// N·m·s/rad (zero until [`Tsid::set_flexible_springs`]).
    flexible: Vec<(usize, f64, f64)>,
    has_zmp: bool,
    /// TSID-Compliant's contact model and measured wrenches (`None`: the rigid TSID).
    compliant: Option<CompliantContacts>,
    /// Angular momentum tasks with `reference_joints`: config task index and its reference.
    momentum_references: Vec<(usize, JointMomentumReference)>,
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
        let period_duration = period;
        let period = period.as_secs_f64();
        if period <= 0.0 {
            return Err(WbcError::InvalidConfig {
                task: "<tsid>".into(),
                key: "period",
                reason: format!("{period} s must be > 0"),
            });
        }
        config.actuators.validate()?;
        let n = model.dof();
        let nv = model.nv();
        let mut set = TaskSet::parse(&model, &config, period)?;
        let compliant = match config.contact_model {
            ContactModel::Rigid => None,
            ContactModel::Compliant if !set.flexible.is_empty() => {
                return Err(WbcError::InvalidConfig {
                    task: "<tsid>".into(),
                    key: "contact_model",
                    reason: "the compliant contact model has no flexible joints".into(),
                })
            }
            ContactModel::Compliant => Some(CompliantContacts::new(
                &config.compliant,
                set.contacts.len(),
                period,
            )?),
        };
        if compliant.is_some() {
            if let Some(kp) = derived_angular_momentum_gain(&config.compliant)? {
                for t in &mut set.tasks {
                    if let TsidTask::AngularMomentum(t) = t {
                        t.set_gains(kp);
                    }
                }
            }
        }
        let mut variants = Vec::new();
        let zmp_options: &[bool] = if set.has_zmp {
            &[false, true]
        } else {
            &[false]
        };
        for &zmp in zmp_options {
            for mask in 0..(1usize << set.contacts.len()) {
                variants.push(set.variant(&config, n, mask, zmp)?);
            }
        }
        let residuals = config
            .tasks
            .iter()
            .enumerate()
            .map(|(i, t)| TaskResidual {
                name: t.name().to_owned(),
                hard: set.is_hard(i),
                residual: 0.0,
            })
            .collect();
        let mut kd = KinDyn::new(Arc::clone(&model));
        kd.set_representation(VelocityRepresentation::Mixed);
        let output = TsidOutput {
            joint_torques: DVector::zeros(n),
            accelerations: DVector::zeros(nv),
            contact_wrenches: vec![Vector6::zeros(); set.contacts.len()],
            contact_load: vec![0.0; set.contacts.len()],
            report: SolveReport::default(),
            residuals,
        };
        let (_, _, _, effort) = joint_limits(&model);
        Ok(Tsid {
            mass: model.total_mass(),
            gravity: model.gravity(),
            mass_matrix: DMatrix::zeros(nv, nv),
            bias_forces: DVector::zeros(nv),
            com_position: Vector3::zeros(),
            com_velocity: Vector3::zeros(),
            momentum: Vector6::zeros(),
            kd,
            period_duration,
            enabled: vec![true; set.tasks.len()],
            names: set.names,
            tasks: set.tasks,
            frame_tasks: set.frame_tasks,
            joint_tasks: set.joint_tasks,
            contacts: set.contacts,
            variants,
            position_limits: set.position_limits,
            velocity_limits: set.velocity_limits,
            effort,
            flexible: set.flexible.iter().map(|&j| (j, 0.0, 0.0)).collect(),
            has_zmp: set.has_zmp,
            compliant,
            momentum_references: set.momentum_references,
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

    /// The names of the frame references and contacts this controller reads from its input.
    pub fn input_layout(&self) -> &Arc<InputLayout> {
        self.names.layout()
    }

    /// An input holding the robot at `state` with this controller's reference and contact names (see
    /// [`WbcInput::new`]).
    pub fn input(&self, state: &RobotState) -> WbcInput {
        WbcInput::new(state.clone(), Arc::clone(self.names.layout()))
    }

    /// The contact tasks' names, in the order of [`TsidOutput::contact_wrenches`].
    pub fn contact_tasks(&self) -> impl Iterator<Item = &str> {
        self.contacts.iter().map(|c| c.name.as_str())
    }

    /// One tick (the same as [`Block::step`], without importing the trait).
    pub fn step(&mut self, input: &WbcInput) -> Result<&TsidOutput, WbcError> {
        self.tick(input)
    }

    /// Takes a task out of the problem (`false`) or puts it back with its priority, weight and gains
    /// (`true`), at run time, allocation-free (a hard task taken out makes the QP use stride-qp's full
    /// solve path rather than the null-space one until it is back). Equality tasks only: frame, CoM,
    /// angular momentum, posture, ZMP and the regularizations; contacts open and close through the input
    /// ([`WbcInput::set_contact`]). Errors: unknown name, the dynamics, a contact or a limit.
    pub fn set_task_enabled(&mut self, task: &str, enabled: bool) -> Result<(), WbcError> {
        let k = find_task(&self.config.tasks, task)?;
        if matches!(
            self.tasks[k],
            TsidTask::Dynamics
                | TsidTask::Contact(_)
                | TsidTask::PositionLimits
                | TsidTask::VelocityLimits
                | TsidTask::TorqueLimits { .. }
        ) {
            return Err(WbcError::InvalidInput(format!(
                "task `{task}` is a constraint: it cannot be disabled"
            )));
        }
        for variant in &mut self.variants {
            for &b in &variant.slots[k] {
                variant.bridge.set_enabled(b, enabled)?;
            }
        }
        self.enabled[k] = enabled;
        Ok(())
    }

    /// Whether a task takes part in the problem. Errors: unknown name.
    pub fn is_task_enabled(&self, task: &str) -> Result<bool, WbcError> {
        Ok(self.enabled[find_task(&self.config.tasks, task)?])
    }

    /// Changes the gains of a task at run time, allocation-free: `K_p` (1/s²) and `K_d` (1/s) of every
    /// row of a frame task, of the CoM and posture tasks; `K_p` of the angular momentum task (`kd`
    /// unused); the contact constraint's stabilization gains. Errors: unknown name, a task without
    /// gains, a negative or non-finite gain.
    pub fn set_task_gains(&mut self, task: &str, kp: f64, kd: f64) -> Result<(), WbcError> {
        let k = find_task(&self.config.tasks, task)?;
        check_gain(task, "kp", kp)?;
        check_gain(task, "kd", kd)?;
        match &mut self.tasks[k] {
            TsidTask::Frame(f) => self.frame_tasks[*f].set_gains(kp, kd),
            TsidTask::Com(t) => t.set_gains(kp, kd),
            TsidTask::AngularMomentum(t) => t.set_gains(kp),
            TsidTask::Joint(j) => self.joint_tasks[*j].set_gains(kp, kd),
            TsidTask::Contact(c) => {
                self.contacts[*c].kp = kp;
                self.contacts[*c].kd = kd;
            }
            _ => {
                return Err(WbcError::InvalidInput(format!(
                    "task `{task}` has no gains"
                )))
            }
        }
        Ok(())
    }

    /// Adds a task: a **reconfiguration**, not a run-time edit. The controller is rebuilt from its
    /// configuration plus `task` (every QP is rebuilt: this allocates) and restarts as after
    /// [`Block::reset`]; run-time edits (weights, gains, disabled tasks) are not carried over. Call it
    /// before the first tick, or between phases of a task where a restart is acceptable; a new reference
    /// or contact name also needs a new input ([`Tsid::input`]). Errors: those of [`Tsid::new`] (on error
    /// the controller is unchanged).
    pub fn add_task(&mut self, task: TaskConfig) -> Result<(), WbcError> {
        let mut config = self.config.clone();
        config.tasks.push(task);
        *self = Tsid::new(Arc::clone(&self.model), config, self.period_duration)?;
        Ok(())
    }

    /// Changes the weight of a soft task at run time (e.g. walking vs standing) in every prebuilt QP:
    /// one value for every row or one per row (per-row lists of `wrench_regularization` have 6 entries,
    /// applied to each contact). Allocation-free.
    ///
    /// Errors: unknown task name, a hard task or a constraint, wrong length, negative or non-finite weight.
    pub fn set_task_weight(&mut self, task: &str, weights: &[f64]) -> Result<(), WbcError> {
        let k = find_task(&self.config.tasks, task)?;
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
        if !found && self.enabled[k] {
            return Err(WbcError::InvalidInput(format!(
                "task `{task}` has no weight"
            )));
        }
        Ok(())
    }

    /// The ground the compliant contact model uses for the first contact (`contact_model = "compliant"`;
    /// its online estimate with `compliant.estimate_ground`), `None` for the rigid TSID.
    pub fn ground(&self) -> Option<crate::soft_contact::GroundParameters> {
        self.compliant.as_ref().map(|c| c.ground_of(0))
    }

    /// With `compliant.estimate_ground`: the ground estimate of every contact, in the order of
    /// [`Tsid::contact_tasks`] [Romualdi 2022, §8.2.3]; `None` otherwise.
    pub fn ground_estimates(&self) -> Option<&[crate::soft_contact::GroundParameters]> {
        self.compliant
            .as_ref()
            .and_then(|c| c.estimates.as_ref())
            .map(|e| e.grounds())
    }

    /// With `compliant.estimate_ground`: the ground every contact's model uses, in the order of
    /// [`Tsid::contact_tasks`] (the estimate, the prior with `compliant.estimator_open_loop`, or what the
    /// gate `compliant.estimator_accept_std` accepted); `None` otherwise.
    pub fn ground_models(&self) -> Option<&[crate::soft_contact::GroundParameters]> {
        self.compliant
            .as_ref()
            .and_then(|c| c.estimates.as_ref())
            .map(|e| e.models())
    }

    /// With `compliant.estimate_ground`: the ground the contact model of the contact whose flag is `flag`
    /// (e.g. [`crate::walking::LEFT_FOOT`]) uses, its estimate (the prior with
    /// `compliant.estimator_open_loop`); `None` otherwise.
    pub fn ground_estimate_of(&self, flag: &str) -> Option<crate::soft_contact::GroundParameters> {
        let k = self.names.contact_index(flag)?;
        let c = self.contacts.iter().position(|c| c.flag == k)?;
        let estimates = self.compliant.as_ref()?.estimates.as_ref()?;
        (c < estimates.grounds().len()).then(|| estimates.ground(c))
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

    /// `input.flexible_torques` has one entry per joint, finite on the flexible joints.
    fn check_flexible_torques(&self, input: &WbcInput) -> Result<(), WbcError> {
        let t = &input.flexible_torques;
        if t.len() != self.model.dof() {
            return Err(WbcError::InvalidInput(format!(
                "flexible_torques has {} entries, expected {} (one per joint)",
                t.len(),
                self.model.dof()
            )));
        }
        match self.flexible.iter().find(|&&(j, _, _)| !t[j].is_finite()) {
            Some(&(j, _, _)) => Err(WbcError::InvalidInput(format!(
                "flexible_torques: non-finite torque {} for `{}`",
                t[j],
                self.model.joints()[j].name
            ))),
            None => Ok(()),
        }
    }

    /// The passive flexible joints (TSID-Flex; empty for the rigid TSID): model index, stiffness `k`
    /// (N·m/rad), damping `b` (N·m·s/rad), in the order of `TsidConfig::flexible_joints`.
    pub fn flexible_joints(&self) -> &[(usize, f64, f64)] {
        &self.flexible
    }

    /// The springs `(k N·m/rad, b N·m·s/rad)` of the flexible joints, in the order of
    /// `TsidConfig::flexible_joints`: their rows then hold the passive torque advanced over the period by
    /// the chosen acceleration (linearly implicit, see `fill_flexible_dynamics`); without springs (the
    /// default, or zeros) the torque is held at `WbcInput::flexible_torques`. Errors: a wrong count, a
    /// negative or non-finite value.
    pub fn set_flexible_springs(&mut self, springs: &[(f64, f64)]) -> Result<(), WbcError> {
        let invalid = |reason: String| WbcError::InvalidConfig {
            task: "<tsid>".into(),
            key: "flexible_joints",
            reason,
        };
        if springs.len() != self.flexible.len() {
            return Err(invalid(format!(
                "{} springs for {} flexible joints",
                springs.len(),
                self.flexible.len()
            )));
        }
        if let Some((k, b)) = springs
            .iter()
            .find(|(k, b)| !(k.is_finite() && *k >= 0.0 && b.is_finite() && *b >= 0.0))
        {
            return Err(invalid(format!(
                "spring k = {k}, b = {b}: expected finite values ≥ 0"
            )));
        }
        for (f, &(k, b)) in self.flexible.iter_mut().zip(springs) {
            f.1 = k;
            f.2 = b;
        }
        Ok(())
    }

    /// Sets the reference of every angular momentum task with `reference_joints` at this tick's state.
    fn update_momentum_references(&mut self, input: &WbcInput) -> Result<(), WbcError> {
        for (ti, r) in &mut self.momentum_references {
            let reference = r.update(&mut self.kd, &input.state, &self.names, input)?;
            if let TsidTask::AngularMomentum(t) = &mut self.tasks[*ti] {
                t.reference = Some(reference);
            }
        }
        Ok(())
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

    /// Writes the rows of every task of QP `vi` and the joint acceleration bounds.
    fn fill(&mut self, vi: usize, input: &WbcInput) -> Result<(), WbcError> {
        let variant = &mut self.variants[vi];
        let ctx = TsidContext {
            mass: self.mass,
            gravity: self.gravity,
            mass_matrix: &self.mass_matrix,
            bias_forces: &self.bias_forces,
            com_position: self.com_position,
            com_velocity: self.com_velocity,
            momentum: self.momentum,
            contacts: &self.contacts,
            offsets: &variant.offsets,
        };
        let comp = self.compliant.as_ref();
        let n = self.model.dof();
        // the rigid rows over wrenches, in rate form (see `tasks::compliant`) for the compliant model
        let rate_form = |b: &mut TaskDataMut, equality: bool, horizon: f64| {
            if let Some(cc) = comp {
                to_rate_rows(b, equality, ctx.offsets, &cc.measured, horizon);
            }
        };
        let unloaded = |b: &mut TaskDataMut, first: usize, rows: usize, equality: bool| {
            if let Some(cc) = comp {
                add_unloaded_wrenches(&ctx, &cc.measured, first, rows, b, equality);
            }
        };
        for (ti, task) in self.tasks.iter().enumerate() {
            let slots = &variant.slots[ti];
            if slots.is_empty() || !self.enabled[ti] {
                continue;
            }
            let b = &mut variant.bridge.rows_mut(slots[0]);
            match *task {
                TsidTask::Dynamics => {
                    fill_base_dynamics(&ctx, b);
                    fill_flexible_dynamics(
                        &ctx,
                        &self.flexible,
                        self.period,
                        &input.state.joint_velocities,
                        &input.flexible_torques,
                        b,
                    );
                    rate_form(b, true, 0.0);
                    unloaded(b, 0, 6, true);
                }
                TsidTask::Frame(f) => {
                    self.frame_tasks[f].update(&self.kd, &self.names, input, b.reborrow())?
                }
                TsidTask::Com(t) => {
                    t.fill(input, &ctx, b);
                    rate_form(b, true, comp.map_or(0.0, |c| c.momentum_horizon));
                }
                TsidTask::AngularMomentum(t) => {
                    t.fill(input, &ctx, b);
                    if let Some(cc) = comp {
                        to_rate_rows(b, true, ctx.offsets, &cc.measured, cc.momentum_horizon);
                        add_angular_momentum_drift(&ctx, &cc.measured, cc.momentum_horizon, b);
                    }
                }
                TsidTask::Joint(j) => self.joint_tasks[j].update(
                    input,
                    &input.state.joint_positions,
                    &input.state.joint_velocities,
                    b.reborrow(),
                ),
                TsidTask::PositionLimits | TsidTask::VelocityLimits => {}
                TsidTask::TorqueLimits { scale } => {
                    fill_torque_limits(&ctx, scale, &self.effort, b);
                    rate_form(b, false, 0.0);
                    unloaded(b, 6, n, false);
                }
                TsidTask::TorqueRegularization => {
                    fill_torque_regularization(&ctx, b);
                    rate_form(b, true, 0.0);
                    unloaded(b, 6, n, true);
                }
                TsidTask::Contact(c) => {
                    let contact = &self.contacts[c];
                    let off = variant.offsets[c].unwrap_or(0);
                    match comp {
                        Some(cc) => fill_contact_dynamics(contact, &cc.rates[c], off, b),
                        None => contact.fill_constraint(b),
                    }
                    let f = &mut variant.bridge.rows_mut(slots[1]);
                    contact.fill_feasibility(off, f);
                    rate_form(f, false, comp.map_or(0.0, |c| c.feasibility_horizon));
                }
                TsidTask::WrenchRegularization => {
                    fill_wrench_regularization(input, &self.names, &ctx, b);
                    rate_form(b, true, comp.map_or(0.0, |c| c.wrench_horizon));
                }
                TsidTask::Zmp => {
                    fill_zmp(input, &ctx, b);
                    rate_form(b, true, comp.map_or(0.0, |c| c.feasibility_horizon));
                }
            }
        }
        acceleration_bounds(
            &self.position_limits,
            &self.velocity_limits,
            &input.state,
            &mut variant.lower,
            &mut variant.upper,
        );
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
        let ctx = TsidContext {
            mass: self.mass,
            gravity: self.gravity,
            mass_matrix: &self.mass_matrix,
            bias_forces: &self.bias_forces,
            com_position: self.com_position,
            com_velocity: self.com_velocity,
            momentum: self.momentum,
            contacts: &self.contacts,
            offsets: &variant.offsets,
        };
        match &self.compliant {
            Some(cc) => {
                measured_joint_torques(&ctx, &cc.measured, x, &mut self.output.joint_torques)
            }
            None => joint_torques(&ctx, x, &mut self.output.joint_torques),
        }
        for (c, contact) in self.contacts.iter_mut().enumerate() {
            let column = |off: usize| Vector6::from_iterator((0..6).map(|k| x[off + k]));
            let w = match (&self.compliant, variant.offsets[c]) {
                // compliant: the measured wrench advanced by the chosen rate over one period
                (Some(cc), Some(off)) => cc.measured[c] + column(off) * self.period,
                (Some(cc), None) => cc.measured[c],
                (None, Some(off)) => column(off),
                (None, None) => Vector6::zeros(),
            };
            let rt = contact.pose.rotation.inverse();
            contact.last_fz = (rt * w.fixed_rows::<3>(0).into_owned()).z;
            self.output.contact_wrenches[c] = w;
        }
        for (k, slots) in variant.slots.iter().enumerate() {
            let mut s = 0.0;
            for &b in slots {
                let r = variant.bridge.residual(b, x);
                s += r * r;
            }
            self.output.residuals[k].residual = match self.tasks[k] {
                _ if !self.enabled[k] => 0.0,
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

impl Tsid {
    fn tick(&mut self, input: &WbcInput) -> Result<&TsidOutput, WbcError> {
        let start = Instant::now();
        check_state(&self.model, &input.state)?;
        check_references(&self.model, input)?;
        self.check_flexible_torques(input)?;
        self.names.resolve(input)?;
        self.compute_dynamics(input)?;
        let period = self.period;
        if let Some(cc) = &mut self.compliant {
            read_measured_wrenches(input, &self.names, &self.contacts, &mut cc.measured)?;
            cc.filter_wrenches(&self.output.contact_wrenches, self.initialized);
        }
        for (c, contact) in self.contacts.iter_mut().enumerate() {
            let flag = self.names.contact(input, contact.flag).active;
            let was_loaded = self.initialized && contact.load > 0.0;
            if !self.initialized {
                // start-up: contacts already closed carry load at once
                contact.reference = contact.pose;
                contact.unloading = false;
                contact.load = if flag { 1.0 } else { 0.0 };
            } else {
                contact.advance_load(flag, period);
            }
            if let Some(cc) = &mut self.compliant {
                // `lift_off_force`: the ramp ended but the sole still carries load
                contact.held_upper = None;
                if !flag && was_loaded && contact.load == 0.0 {
                    contact.held_upper = cc.held_lift_off(c, contact);
                    if contact.held_upper.is_some() {
                        contact.load = HELD_LIFT_OFF_LOAD;
                    }
                }
                if !was_loaded && contact.load > 0.0 {
                    cc.touch_down(c, &contact.pose);
                }
            }
        }
        if let Some(cc) = &mut self.compliant {
            cc.estimate_ground(&self.contacts);
            cc.model_wrenches(&self.contacts);
            cc.update_rates(&self.contacts);
        }
        self.update_momentum_references(input)?;
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
            self.output.contact_load[c] = contact.load;
        }
        self.output.report.tick_time = start.elapsed().as_secs_f64();
        Ok(&self.output)
    }
}

/// The measured wrench of every contact (`ContactInput::measured_wrench`) into `measured`. Errors: a
/// non-finite wrench.
fn read_measured_wrenches(
    input: &WbcInput,
    names: &Resolver,
    contacts: &[Contact],
    measured: &mut [Vector6<f64>],
) -> Result<(), WbcError> {
    for (m, contact) in measured.iter_mut().zip(contacts) {
        let w = names.contact(input, contact.flag).measured_wrench;
        if !w.iter().all(|v| v.is_finite()) {
            return Err(WbcError::InvalidInput(format!(
                "contact `{}`: non-finite measured wrench",
                contact.name
            )));
        }
        *m = w;
    }
    Ok(())
}

impl Block for Tsid {
    type Input = WbcInput;
    type Output = TsidOutput;
    type Error = WbcError;

    fn step(&mut self, input: &WbcInput) -> Result<&TsidOutput, WbcError> {
        self.tick(input)
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
            c.held_upper = None;
        }
        for t in &mut self.frame_tasks {
            t.reset();
        }
        self.last_valid = false;
        self.last_variant = None;
        self.initialized = false;
        self.output.joint_torques.fill(0.0);
        self.output.accelerations.fill(0.0);
        self.output.contact_wrenches.fill(Vector6::zeros());
        self.output.report = SolveReport::default();
    }
}
