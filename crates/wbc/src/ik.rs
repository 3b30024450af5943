//! Kinematic whole-body QP (QP-IK) [Romualdi 2022, eq. 7.1.16]: decision variable `ν = [base twist (mixed); ṡ]`.

use std::sync::Arc;
use std::time::{Duration, Instant};

use nalgebra::{DVector, Vector6};
use stride_block::Block;
use stride_model::{KinDyn, Model, RobotState, VelocityRepresentation};

use crate::bridge::{QpBridge, VariableLayout};
use crate::config::{check_unique_names, IkConfig, IkFeedback, Priority, TaskConfig, Weight};
use crate::error::WbcError;
use crate::io::{IkOutput, InputLayout, SolveReport, TaskResidual, WbcInput};
use crate::names::{input_layout, Resolver};
use crate::tasks::joint::velocity_bounds;
use crate::tasks::{
    check_gain, joint_limits, position_limit_bounds, AngularMomentumVelocityTask, ComVelocityTask,
    FrameTask, JointRegularizationTask, Level,
};

/// What a config entry became.
#[derive(Debug, Clone, Copy)]
enum Slot {
    /// A stride-qp task (its index in the bridge).
    Block(usize),
    /// Joint position limits (variable bounds).
    PositionLimits,
    /// Joint velocity limits (variable bounds).
    VelocityLimits,
}

/// The kinematic QP-IK block. See the crate docs and docs/wbc.md.
///
/// Each [`Block::step`]: evaluates the task errors at the integrated state (position control,
/// [Romualdi 2022, §7.1.3]) or at the measured one, solves for ν, integrates the internal state on SE(3) × Rⁿ with
/// [`RobotState::integrate`] (mixed representation) and returns the integrated joint positions. A failed
/// solve falls back to the relaxed problem (hard tasks as heavily weighted soft ones, as stride-qp
/// documents); if that fails too the last valid joint positions are held with zero velocity, the
/// internal state is not advanced and `report.held` is set.
///
/// ```
/// use std::{sync::Arc, time::Duration};
/// use stride_wbc::prelude::*;
/// use stride_model::{bundled, KinDyn, RobotState, VelocityRepresentation};
///
/// let model = Arc::new(bundled::model()?);
/// let config = IkConfig::builder()
///     .se3_hard(bundled::LEFT_SOLE, 7.0)
///     .se3_hard(bundled::RIGHT_SOLE, 7.0)
///     .se3("l_hand_palm", 5.0)
///     .com(2.0)
///     .posture(5.0, &bundled::POSTURE)
///     .build()?;
/// let mut ik = QpIk::new(model.clone(), config, Duration::from_millis(2))?;
/// let mut state = RobotState::zero(&model);
/// for (joint, q) in bundled::POSTURE {
///     state.joint_positions[model.joint_index(joint).unwrap()] = q;
/// }
/// let mut kd = KinDyn::new(model.clone());
/// kd.set_representation(VelocityRepresentation::Mixed);
/// kd.set_state(&state)?;
/// let pose = |name: &str| kd.frame_pose(model.frame_id(name).unwrap());
/// let mut input = ik.input(&state);
/// input.com_position = kd.com_position();
/// for frame in [bundled::LEFT_SOLE, bundled::RIGHT_SOLE] {
///     input.set_frame_reference(frame, FrameReference::still(pose(frame)))?;
/// }
/// // the left palm 5 cm up
/// let mut hand = pose("l_hand_palm");
/// hand.translation.vector.z += 0.05;
/// input.set_frame_reference("l_hand_palm", FrameReference::still(hand))?;
/// let out = ik.step(&input)?;
/// assert!(out.report.is_nominal());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct QpIk {
    model: Arc<Model>,
    config: IkConfig,
    /// Control period (s).
    period: f64,
    /// Control period as given to [`QpIk::new`] (for [`QpIk::add_task`]).
    period_duration: Duration,
    names: Resolver,
    kd: KinDyn,
    frame_tasks: Vec<FrameTask>,
    com_tasks: Vec<ComVelocityTask>,
    momentum_tasks: Vec<AngularMomentumVelocityTask>,
    joint_tasks: Vec<JointRegularizationTask>,
    slots: Vec<Slot>,
    position_limits: Option<(Vec<f64>, Vec<f64>, f64)>,
    velocity_limits: Option<Vec<f64>>,
    lower: DVector<f64>,
    upper: DVector<f64>,
    x: DVector<f64>,
    bridge: QpBridge,
    state: RobotState,
    initialized: bool,
    output: IkOutput,
}

impl QpIk {
    /// Builds the controller running every `period` (the integration step and the default look-ahead of
    /// the joint position limits). All allocation happens here.
    ///
    /// Errors: a zero period, unknown frames/joints, invalid gains or weights (a weight on a hard task),
    /// task types the QP-IK does not support (TSID-only tasks), or a QP that stride-qp rejects.
    pub fn new(model: Arc<Model>, config: IkConfig, period: Duration) -> Result<Self, WbcError> {
        let period_duration = period;
        let period = period.as_secs_f64();
        if period <= 0.0 {
            return Err(WbcError::InvalidConfig {
                task: "<qp-ik>".into(),
                key: "period",
                reason: format!("{period} s must be > 0"),
            });
        }
        let n = model.dof();
        let nv = model.nv();
        let layout = VariableLayout::new(&[("base_velocity", 6), ("joint_velocities", n)])?;
        let mut frame_tasks = Vec::new();
        let mut com_tasks = Vec::new();
        let mut momentum_tasks = Vec::new();
        let mut joint_tasks = Vec::new();
        let mut slots = Vec::new();
        let mut blocks = Vec::new();
        let mut position_limits = None;
        let mut velocity_limits = None;
        let (lo, hi, vmax, _) = joint_limits(&model);
        check_unique_names(&config.tasks)?;
        let names = Resolver::new(input_layout(&config.tasks)?);
        for task in &config.tasks {
            let eq_block = |rows: usize, priority: Priority, weight| {
                layout.equality(task.name(), rows, priority, weight)
            };
            match task {
                TaskConfig::Se3(c) => {
                    let mut t = FrameTask::from_se3(&model, &names, c, Level::Velocity)?;
                    t.block = blocks.len();
                    slots.push(Slot::Block(blocks.len()));
                    blocks.push(eq_block(t.row_count(), c.priority, &c.weight)?);
                    frame_tasks.push(t);
                }
                TaskConfig::So3(c) | TaskConfig::R3(c) => {
                    let angular = matches!(task, TaskConfig::So3(_));
                    let mut t =
                        FrameTask::from_frame3(&model, &names, c, angular, Level::Velocity)?;
                    t.block = blocks.len();
                    slots.push(Slot::Block(blocks.len()));
                    blocks.push(eq_block(t.row_count(), c.priority, &c.weight)?);
                    frame_tasks.push(t);
                }
                TaskConfig::Com(c) => {
                    let mut t = ComVelocityTask::new(&model, c)?;
                    t.block = blocks.len();
                    slots.push(Slot::Block(blocks.len()));
                    blocks.push(eq_block(t.row_count(), c.priority, &c.weight)?);
                    com_tasks.push(t);
                }
                TaskConfig::AngularMomentum(c) => {
                    if !c.reference_joints.is_empty() || !c.reference_frames.is_empty() {
                        return Err(WbcError::InvalidConfig {
                            task: c.name.clone(),
                            key: if c.reference_joints.is_empty() {
                                "reference_frames"
                            } else {
                                "reference_joints"
                            },
                            reason: "the QP-IK's angular momentum task takes its reference from the input"
                                .into(),
                        });
                    }
                    let mut t = AngularMomentumVelocityTask::new(&model);
                    t.block = blocks.len();
                    slots.push(Slot::Block(blocks.len()));
                    blocks.push(eq_block(3, c.priority, &c.weight)?);
                    momentum_tasks.push(t);
                }
                TaskConfig::JointRegularization(c) => {
                    let mut t = JointRegularizationTask::new(&model, c, Level::Velocity)?;
                    t.block = blocks.len();
                    slots.push(Slot::Block(blocks.len()));
                    blocks.push(if t.hard {
                        layout.hard(&c.name, n)
                    } else {
                        layout.soft(&c.name, n, Weight::PerRow(t.weights.clone()))
                    });
                    joint_tasks.push(t);
                }
                TaskConfig::JointPositionLimits(c) => {
                    position_limits = Some(position_limit_bounds(c, period, &lo, &hi, &model)?);
                    slots.push(Slot::PositionLimits);
                }
                TaskConfig::JointVelocityLimits(c) => {
                    check_gain(&c.name, "scale", c.scale)?;
                    velocity_limits = Some(vmax.iter().map(|v| v * c.scale).collect());
                    slots.push(Slot::VelocityLimits);
                }
                other => {
                    return Err(WbcError::UnsupportedTask {
                        task: other.name().to_owned(),
                        task_type: other.type_name(),
                        controller: "QP-IK",
                    })
                }
            }
        }
        let bridge = QpBridge::new(layout, blocks, &config.qp, config.eliminate_equalities)?;
        let residuals = config
            .tasks
            .iter()
            .map(|t| TaskResidual {
                name: t.name().to_owned(),
                hard: match t {
                    TaskConfig::Se3(c) => c.priority == Priority::Hard,
                    TaskConfig::So3(c) | TaskConfig::R3(c) => c.priority == Priority::Hard,
                    TaskConfig::Com(c) => c.priority == Priority::Hard,
                    TaskConfig::AngularMomentum(c) => c.priority == Priority::Hard,
                    TaskConfig::JointRegularization(c) => c.priority == Priority::Hard,
                    _ => true,
                },
                residual: 0.0,
            })
            .collect();
        let state = RobotState::zero(&model);
        let output = IkOutput {
            joint_positions: DVector::zeros(n),
            joint_velocities: DVector::zeros(n),
            base_velocity: Vector6::zeros(),
            base_pose: state.base_pose,
            report: SolveReport::default(),
            residuals,
        };
        let mut kd = KinDyn::new(Arc::clone(&model));
        kd.set_representation(VelocityRepresentation::Mixed);
        Ok(QpIk {
            period_duration,
            names,
            kd,
            frame_tasks,
            com_tasks,
            momentum_tasks,
            joint_tasks,
            slots,
            position_limits,
            velocity_limits,
            lower: DVector::from_element(nv, f64::NEG_INFINITY),
            upper: DVector::from_element(nv, f64::INFINITY),
            x: DVector::zeros(nv),
            bridge,
            state,
            initialized: false,
            output,
            model,
            config,
            period,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &IkConfig {
        &self.config
    }

    /// The model.
    pub fn model(&self) -> &Arc<Model> {
        &self.model
    }

    /// The names of the frame references this controller reads from its input (no contacts).
    pub fn input_layout(&self) -> &Arc<InputLayout> {
        self.names.layout()
    }

    /// An input holding the robot at `state` with this controller's reference names (see
    /// [`WbcInput::new`]).
    pub fn input(&self, state: &RobotState) -> WbcInput {
        WbcInput::new(state.clone(), Arc::clone(self.names.layout()))
    }

    /// One tick (the same as [`Block::step`], without importing the trait).
    pub fn step(&mut self, input: &WbcInput) -> Result<&IkOutput, WbcError> {
        self.tick(input)
    }

    /// Takes an equality task (frame, CoM, angular momentum, posture) out of the problem (`false`) or
    /// puts it back with its priority and weight (`true`), at run time, allocation-free (a hard task
    /// taken out makes the QP use stride-qp's full solve path until it is back). Errors: unknown name, a
    /// limit.
    pub fn set_task_enabled(&mut self, task: &str, enabled: bool) -> Result<(), WbcError> {
        let k = find_task(&self.config.tasks, task)?;
        match self.slots[k] {
            Slot::Block(b) => self.bridge.set_enabled(b, enabled),
            _ => Err(WbcError::InvalidInput(format!(
                "task `{task}` is a limit: it cannot be disabled"
            ))),
        }
    }

    /// Whether a task takes part in the problem. Errors: unknown name.
    pub fn is_task_enabled(&self, task: &str) -> Result<bool, WbcError> {
        Ok(match self.slots[find_task(&self.config.tasks, task)?] {
            Slot::Block(b) => self.bridge.is_enabled(b),
            _ => true,
        })
    }

    /// Changes `K_p` (1/s) of a frame, CoM or posture task at run time (every row), allocation-free.
    /// Errors: unknown name, a task without gain, a negative or non-finite gain.
    pub fn set_task_gain(&mut self, task: &str, kp: f64) -> Result<(), WbcError> {
        let k = find_task(&self.config.tasks, task)?;
        check_gain(task, "kp", kp)?;
        let Slot::Block(b) = self.slots[k] else {
            return Err(WbcError::InvalidInput(format!("task `{task}` has no gain")));
        };
        if let Some(t) = self.frame_tasks.iter_mut().find(|t| t.block == b) {
            t.set_gains(kp, 0.0);
        } else if let Some(t) = self.com_tasks.iter_mut().find(|t| t.block == b) {
            t.set_gains(kp);
        } else if let Some(t) = self.joint_tasks.iter_mut().find(|t| t.block == b) {
            t.set_gains(kp, 0.0);
        } else {
            return Err(WbcError::InvalidInput(format!("task `{task}` has no gain")));
        }
        Ok(())
    }

    /// Adds a task: a **reconfiguration**, not a run-time edit. The controller is rebuilt from its
    /// configuration plus `task` (this allocates) and restarts as after [`Block::reset`] (the next tick
    /// re-initializes the integrated state from the measured one); run-time edits (weights, gains,
    /// disabled tasks) are not carried over. Call it before the first tick or where a restart is
    /// acceptable; a new reference name also needs a new input ([`QpIk::input`]). Errors: those of
    /// [`QpIk::new`] (on error the controller is unchanged).
    pub fn add_task(&mut self, task: TaskConfig) -> Result<(), WbcError> {
        let mut config = self.config.clone();
        config.tasks.push(task);
        *self = QpIk::new(Arc::clone(&self.model), config, self.period_duration)?;
        Ok(())
    }

    /// The internal (integrated) state: the state the task errors were evaluated at in
    /// [`IkFeedback::Integrated`] mode, advanced by the last solution.
    pub fn integrated_state(&self) -> &RobotState {
        &self.state
    }

    /// Replaces the internal state (e.g. to restart the integration from a known posture).
    pub fn set_integrated_state(&mut self, state: &RobotState) -> Result<(), WbcError> {
        check_state(&self.model, state)?;
        copy_state(&mut self.state, state);
        self.initialized = true;
        Ok(())
    }

    /// Changes the weight of a soft task at run time (e.g. walking vs standing): one value for every
    /// row or one per row. Allocation-free.
    ///
    /// Errors: unknown task name, a hard task or a limit (no weight), wrong length, negative or
    /// non-finite weight.
    pub fn set_task_weight(&mut self, task: &str, weights: &[f64]) -> Result<(), WbcError> {
        let k = find_task(&self.config.tasks, task)?;
        let b = match self.slots[k] {
            Slot::Block(b) if !self.bridge.task(b).is_hard() => b,
            _ => {
                return Err(WbcError::InvalidInput(format!(
                    "task `{task}` is not a soft task"
                )))
            }
        };
        self.bridge.set_weights(b, weights)
    }

    /// The control period given to [`QpIk::new`] (s).
    pub fn period(&self) -> f64 {
        self.period
    }

    /// The last output.
    pub fn output(&self) -> &IkOutput {
        &self.output
    }

    /// The stride-qp problem of the last tick: data, solution, KKT check (for fixtures and
    /// cross-solver checks).
    pub fn qp_problem(&self) -> &stride_qp::QpProblem {
        self.bridge.problem()
    }

    /// Norms of the current pose errors of the frame tasks `(name, error)` at the state the tasks are
    /// evaluated at (m and rad mixed: `‖[p_ref − p; Log(R_ref Rᵀ)]‖` on the kept rows), and of the CoM
    /// tasks. Evaluated for `input` at the internal state. For tests and diagnostics (allocates).
    pub fn task_errors(&mut self, input: &WbcInput) -> Result<Vec<(String, f64)>, WbcError> {
        self.names.resolve(input)?;
        self.kd.set_state(&self.state)?;
        let mut out = Vec::new();
        for t in &mut self.frame_tasks {
            out.push((
                t.name.clone(),
                t.pose_error_norm(&self.kd, &self.names, input),
            ));
        }
        for t in &self.com_tasks {
            out.push((t.name.clone(), t.error_norm(&self.kd, input)));
        }
        Ok(out)
    }

    fn fill(&mut self, input: &WbcInput) -> Result<(), WbcError> {
        self.kd.set_state(&self.state)?;
        let bridge = &mut self.bridge;
        for t in &mut self.frame_tasks {
            if bridge.is_enabled(t.block) {
                t.update(&self.kd, &self.names, input, bridge.rows_mut(t.block))?;
            }
        }
        for t in &mut self.com_tasks {
            if bridge.is_enabled(t.block) {
                t.update(&mut self.kd, input, bridge.rows_mut(t.block))?;
            }
        }
        for t in &mut self.momentum_tasks {
            if bridge.is_enabled(t.block) {
                t.update(&mut self.kd, input, bridge.rows_mut(t.block))?;
            }
        }
        for t in &self.joint_tasks {
            if !self.bridge.is_enabled(t.block) {
                continue;
            }
            t.update(
                input,
                &self.state.joint_positions,
                &self.state.joint_velocities,
                self.bridge.rows_mut(t.block),
            );
        }
        velocity_bounds(
            &self.position_limits,
            &self.velocity_limits,
            &self.state.joint_positions,
            &mut self.lower,
            &mut self.upper,
        );
        Ok(())
    }

    fn write_residuals(&mut self) {
        let n = self.model.dof();
        for (k, slot) in self.slots.iter().enumerate() {
            let r = match slot {
                Slot::Block(b) if !self.bridge.is_enabled(*b) => 0.0,
                Slot::Block(b) => self.bridge.residual(*b, &self.x),
                Slot::PositionLimits | Slot::VelocityLimits => {
                    let mut s = 0.0;
                    for i in 0..n {
                        let v = self.x[6 + i];
                        let e = (self.lower[6 + i] - v).max(0.0) + (v - self.upper[6 + i]).max(0.0);
                        s += e * e;
                    }
                    s.sqrt()
                }
            };
            self.output.residuals[k].residual = r;
        }
    }
}

/// Index of task `name` in a task list. Errors: no such task.
pub(crate) fn find_task(tasks: &[TaskConfig], name: &str) -> Result<usize, WbcError> {
    tasks
        .iter()
        .position(|t| t.name() == name)
        .ok_or_else(|| WbcError::UnknownName {
            what: "task".into(),
            name: name.to_owned(),
            known: tasks
                .iter()
                .map(|t| t.name())
                .collect::<Vec<_>>()
                .join(", "),
        })
}

pub(crate) fn check_state(model: &Model, state: &RobotState) -> Result<(), WbcError> {
    Ok(state.validate(model)?)
}

pub(crate) fn copy_state(dst: &mut RobotState, src: &RobotState) {
    dst.base_pose = src.base_pose;
    dst.base_velocity = src.base_velocity;
    dst.joint_positions.copy_from(&src.joint_positions);
    dst.joint_velocities.copy_from(&src.joint_velocities);
}

pub(crate) fn check_references(model: &Model, input: &WbcInput) -> Result<(), WbcError> {
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    let frames_ok = input.frames().iter().all(|r| {
        finite(r.pose.translation.vector.as_slice())
            && finite(r.pose.rotation.coords.as_slice())
            && finite(r.velocity.as_slice())
            && finite(r.acceleration.as_slice())
    });
    let ok = finite(input.com_position.as_slice())
        && finite(input.com_velocity.as_slice())
        && finite(input.com_acceleration.as_slice())
        && finite(input.angular_momentum.as_slice())
        && input.desired_zmp.is_none_or(|z| finite(z.as_slice()))
        && frames_ok
        && input
            .contacts()
            .iter()
            .all(|c| finite(c.desired_wrench.as_slice()));
    if !ok {
        return Err(WbcError::InvalidInput("non-finite reference".into()));
    }
    if let Some(p) = &input.posture {
        if p.len() != model.dof() || !p.iter().all(|v| v.is_finite()) {
            return Err(WbcError::InvalidInput(format!(
                "posture reference must have {} finite entries",
                model.dof()
            )));
        }
    }
    Ok(())
}

impl Block for QpIk {
    type Input = WbcInput;
    type Output = IkOutput;
    type Error = WbcError;

    fn step(&mut self, input: &WbcInput) -> Result<&IkOutput, WbcError> {
        self.tick(input)
    }

    fn reset(&mut self) {
        self.reset_state();
    }
}

impl QpIk {
    fn tick(&mut self, input: &WbcInput) -> Result<&IkOutput, WbcError> {
        let start = Instant::now();
        check_state(&self.model, &input.state)?;
        check_references(&self.model, input)?;
        self.names.resolve(input)?;
        if !self.initialized || self.config.feedback == IkFeedback::Measured {
            copy_state(&mut self.state, &input.state);
            if !self.initialized {
                self.output
                    .joint_positions
                    .copy_from(&input.state.joint_positions);
                self.output.base_pose = input.state.base_pose;
            }
            self.initialized = true;
        }
        self.fill(input)?;
        let report = self.bridge.solve(&self.lower, &self.upper, &mut self.x);
        let n = self.model.dof();
        self.output.report = report;
        if report.held {
            // keep the last valid joint positions, command zero velocity
            self.output.joint_velocities.fill(0.0);
            self.output.base_velocity.fill(0.0);
        } else {
            self.state
                .base_velocity
                .copy_from(&self.x.fixed_rows::<6>(0));
            for i in 0..n {
                self.state.joint_velocities[i] = self.x[6 + i];
            }
            self.state
                .integrate(&self.model, VelocityRepresentation::Mixed, self.period)?;
            self.output
                .joint_positions
                .copy_from(&self.state.joint_positions);
            self.output
                .joint_velocities
                .copy_from(&self.state.joint_velocities);
            self.output.base_velocity = self.state.base_velocity;
            self.output.base_pose = self.state.base_pose;
        }
        self.write_residuals();
        self.output.report.tick_time = start.elapsed().as_secs_f64();
        Ok(&self.output)
    }

    fn reset_state(&mut self) {
        self.initialized = false;
        self.bridge.reset();
        for t in &mut self.frame_tasks {
            t.reset();
        }
        self.x.fill(0.0);
        self.output.report = SolveReport::default();
        self.output.joint_velocities.fill(0.0);
        self.output.base_velocity.fill(0.0);
        for r in &mut self.output.residuals {
            r.residual = 0.0;
        }
    }
}
