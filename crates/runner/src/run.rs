//! The scheduler: the deterministic multi-rate loop that ticks the layers and the plant.
//!
//! # Clock and order
//! Simulated time is an integer count of nanoseconds. The base tick is `1e9 / rates.base_hz` ns; every
//! layer runs on the ticks that are multiples of `base_hz / layer_hz`. Within tick `k` at time
//! `t = k · T_base` the order is fixed:
//!
//! 1. **sense and measure**: on a fresh measurement (every `base/sim` ticks) step the estimation layer
//!    ([`Stack::sense`]); if any layer runs or the state is logged this tick, compute the measured CoM,
//!    ZMP, sole poses and tilt from the estimate, and the same from the plant's truth for the summary
//!    ([`Stack::measure`]). No layer reads the truth (unless `estimation.kind = "ground_truth"`);
//! 2. **planner**: on events only (first tick; start of a new goal segment), replan from the measured
//!    soles (or at `rates.planner_hz` in `periodic` mode);
//! 3. **simplified layer** (every `base/simplified` ticks): plan sampled at `t`, measured DCM with the
//!    plan's ω, DCM controller and ZMP-CoM controller;
//! 4. **whole-body layer** (every `base/wbc` ticks): plan feet and CoM height at `t`, simplified CoM and
//!    ZMP references → joint command, handed to the robot;
//! 5. **log** the state topics (every `base/log.state_hz` ticks, at least a plant period apart);
//! 6. **end checks** (fall, goal reached and standing still) on layer ticks;
//! 7. **plant**: the robot advances one period (every `base/sim` ticks) from `t` to `t + T_sim`.
//!
//! Each layer therefore sees the measurement of its own tick time and the latest outputs of the layers
//! above it (computed in the same tick when their ticks coincide). Nothing depends on wall-clock time
//! except the `*/timing` topics, the progress bar and, with `realtime`, the pacing itself. Logging is
//! [`crate::sink`], the summary [`crate::summary`], the wiring of the layers [`crate::stack`].

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use crate::config::{
    ControlMode, EstimationKind, PlannerMode, PlantKind, Scenario, ScenarioConfig,
};
use crate::position_command::{interpolate, PositionCommand};
use crate::records::{RunnerTimingMsg, TimingRecord};
use crate::robot::{JointCommand, Robot};
use crate::setup::{check_same_joints, frame_of};
use crate::sink::LogSink;
use crate::stack::{Stack, Wbc};
use crate::summary::mid_pose;
use crate::tracking::{end_check, Tracker};

pub use crate::error::RunError;
pub use crate::setup::{build_robot, default_log_path, initial_joint_positions, load_model};
pub use crate::sink::{git_commit, WALL_CLOCK_TOPICS};
pub use crate::summary::{goal_pose, ErrorStats, Outcome, RunSummary, SolveTimes};

/// Options of one run (the command line's).
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Log path (overrides the scenario's).
    pub output: Option<PathBuf>,
    /// Duration override \[s\].
    pub duration: Option<f64>,
    /// Pace at 1× wall-clock time.
    pub realtime: bool,
    /// Draw a progress bar (only when stderr is a terminal).
    pub progress: bool,
    /// Plant override.
    pub plant: Option<PlantKind>,
    /// Set from outside (Ctrl-C handler, tests) to stop the run; the log is closed properly.
    pub stop: Option<Arc<AtomicBool>>,
    /// Stop after this many base ticks (tests of interrupted runs).
    pub stop_after_ticks: Option<u64>,
    /// Do not write a log.
    pub no_log: bool,
}

/// Which base ticks run what: periods as multiples of the base tick.
struct Schedule {
    base_ns: u64,
    sim_every: u64,
    wbc_every: u64,
    simplified_every: u64,
    planner_every: Option<u64>,
    state_every: u64,
    total_ticks: u64,
}

impl Schedule {
    fn new(c: &ScenarioConfig, duration: f64) -> Self {
        let r = &c.rates;
        let base_ns = 1_000_000_000 / u64::from(r.base_hz);
        let every = |hz: u32| u64::from(r.base_hz / hz);
        let sim_every = every(r.sim_hz);
        Self {
            base_ns,
            sim_every,
            wbc_every: every(r.wbc_hz),
            simplified_every: every(r.simplified_hz),
            planner_every: (r.planner_mode == PlannerMode::Periodic).then(|| every(r.planner_hz)),
            state_every: u64::from(r.base_hz / c.log.state_hz.max(1)).max(sim_every),
            total_ticks: (duration * 1e9 / base_ns as f64).round() as u64,
        }
    }

    /// Time from the end of the plant step that starts at base tick `k` to the next whole-body tick \[s\]
    /// (zero when the step ends at or after it).
    fn after_plant_step_until_wbc(&self, k: u64) -> f64 {
        let next_wbc = (k / self.wbc_every + 1) * self.wbc_every;
        next_wbc.saturating_sub(k + self.sim_every) as f64 * self.base_ns as f64 * 1e-9
    }

    /// Whether a layer reads the estimate at a tick from `k` (a plant tick) up to the next plant tick: the
    /// sample of tick `k` is then the last one it sees, so it gets the estimation layer's full tick under
    /// `estimation.update = "when_read"`. The state log is not a reader here: it records the estimate the
    /// layers last read, so the log's rate (`log.state_hz`) never changes the closed loop.
    fn reads_estimate_before_next_sample(&self, k: u64) -> bool {
        (k..k + self.sim_every).any(|j| {
            j % self.simplified_every == 0
                || j % self.wbc_every == 0
                || self.planner_every.is_some_and(|e| j % e == 0)
        })
    }
}

/// Runs a scenario to its end. The log (if any) is finished whatever happens, panics in a layer
/// included; the outcome says how the run ended.
pub fn run_scenario(scenario: &Scenario, options: &RunOptions) -> Result<RunSummary, RunError> {
    let model = load_model(scenario)?;
    let plant = options.plant.unwrap_or(scenario.config.scenario.plant);
    let robot = build_robot(scenario, &model, plant)?;
    if plant == PlantKind::Ideal && scenario.config.estimation.kind != EstimationKind::GroundTruth {
        // The ideal plant has no IMU and no force/torque sensors: the controllers read its truth.
        let mut scenario = scenario.clone();
        scenario.config.estimation.kind = EstimationKind::GroundTruth;
        return run_with_model(&scenario, options, robot, model);
    }
    run_with_model(scenario, options, robot, model)
}

/// The state the run starts from, as the controllers know it: the robot stands on flat ground at its
/// encoders' posture, which defines the world frame (left sole level on `z = 0`, the soles' mid-point at
/// the origin, heading along +x), as a real robot's start does; the ground-truth bypass reads the plant's
/// truth.
pub(crate) fn initial_state(
    scenario: &Scenario,
    model: &Arc<stride_model::Model>,
    m: &crate::robot::Measurement,
) -> Result<stride_model::RobotState, RunError> {
    if scenario.config.estimation.kind == EstimationKind::GroundTruth {
        return Ok(m.truth.state.clone());
    }
    let c = &scenario.config;
    let soles = [
        frame_of(scenario, model, "robot.left_sole", &c.robot.left_sole)?,
        frame_of(scenario, model, "robot.right_sole", &c.robot.right_sole)?,
    ];
    // Measured joints (not checked against the limits: an encoder may read a hair beyond one).
    let mut state = stride_model::RobotState::zero(model);
    state.joint_positions.copy_from(&m.sensors.joint_positions);
    state.place_on_ground(model, soles[0], soles[1])?;
    Ok(state)
}

/// Runs a scenario against any [`Robot`] (a real robot interface, another simulator, a test double).
/// The controllers use the scenario's model (`robot.urdf`); the robot's own may differ in its inertias
/// (`[sim.model]`) but must have the same joints. Its period must be `1 / rates.sim_hz`.
pub fn run_with_robot(
    scenario: &Scenario,
    options: &RunOptions,
    robot: Box<dyn Robot>,
) -> Result<RunSummary, RunError> {
    run_with_model(scenario, options, robot, load_model(scenario)?)
}

/// [`run_with_robot`] with the controllers' model already loaded (`load_model(scenario)`): `run_scenario`
/// loaded it to build the plant, and loading it again would parse the URDF a second time.
fn run_with_model(
    scenario: &Scenario,
    options: &RunOptions,
    robot: Box<dyn Robot>,
    model: Arc<stride_model::Model>,
) -> Result<RunSummary, RunError> {
    let c = &scenario.config;
    check_same_joints(scenario, &model, robot.model())?;
    let duration = options.duration.unwrap_or(c.scenario.duration);
    let schedule = Schedule::new(c, duration);
    let expected_ns = schedule.sim_every * schedule.base_ns;
    if robot.period_ns() != expected_ns {
        return Err(crate::robot::RobotError::Period {
            robot_ns: robot.period_ns(),
            expected_ns,
        }
        .into());
    }
    let initial = initial_state(scenario, &model, robot.measurement())?;
    let stack = Stack::new(scenario, Arc::clone(&model), &initial)?;
    let log = if c.log.enabled && !options.no_log {
        let path = options
            .output
            .clone()
            .unwrap_or_else(|| default_log_path(scenario));
        Some(LogSink::open(&path, scenario, &model, robot.name())?)
    } else {
        None
    };
    let mut lp = Loop::new(scenario, schedule, robot, stack, log, options)?;
    let progress = progress_bar(options.progress, duration);
    // The loop proper, inside catch_unwind: a panic in a layer ends the run with an error outcome and the
    // log is still finished below (the sink lives outside the closure's unwinding).
    let result = catch_unwind(AssertUnwindSafe(|| lp.run(options, progress.as_ref())));
    let outcome = match result {
        Ok(Ok(o)) => o,
        Ok(Err(e)) => Outcome::Error {
            message: e.to_string(),
        },
        Err(panic) => Outcome::Error {
            message: format!("panic in the loop: {}", panic_message(panic.as_ref())),
        },
    };
    if let Some(pb) = progress {
        pb.finish_and_clear();
    }
    lp.finish(outcome)
}

fn panic_message(panic: &(dyn std::any::Any + Send)) -> String {
    panic
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_else(|| "unknown payload".into())
}

struct Loop<'a> {
    scenario: &'a Scenario,
    schedule: Schedule,
    robot: Box<dyn Robot>,
    stack: Stack,
    log: Option<LogSink>,
    tracker: Tracker,
    realtime: bool,
    wall_start: Instant,
    last_phase: &'static str,
    /// `[joint_trajectory]`: replaces the whole-body command when enabled.
    trajectory: Option<crate::joint_trajectory::JointTrajectory>,
    /// `wbc.position_command = "interpolate"`: the command of each plant step (allocated at start-up).
    plant_command: Option<JointCommand>,
}

impl<'a> Loop<'a> {
    fn new(
        scenario: &'a Scenario,
        schedule: Schedule,
        robot: Box<dyn Robot>,
        mut stack: Stack,
        log: Option<LogSink>,
        options: &RunOptions,
    ) -> Result<Self, RunError> {
        stack.sense(robot.measurement())?;
        stack.measure(robot.measurement(), robot.kinematics())?;
        let tracker = Tracker::new(
            scenario,
            robot.as_ref(),
            &stack,
            schedule.total_ticks / schedule.wbc_every + 2,
            schedule.total_ticks / schedule.simplified_every + 2,
            schedule.total_ticks as f64 * schedule.base_ns as f64 * 1e-9,
        );
        let q0 = crate::setup::initial_joint_positions(scenario, stack.model())?;
        let trajectory =
            crate::joint_trajectory::JointTrajectory::from_scenario(scenario, stack.model(), &q0)?;
        let c = &scenario.config;
        let plant_command = (c.scenario.control_mode == ControlMode::Position
            && c.wbc.position_command == PositionCommand::Interpolate)
            .then(|| stack.command.clone());
        Ok(Self {
            scenario,
            schedule,
            robot,
            stack,
            log,
            tracker,
            realtime: options.realtime,
            wall_start: Instant::now(),
            last_phase: "",
            trajectory,
            plant_command,
        })
    }

    /// Ticks until an outcome (duration, goal, fall, stop) or an error.
    fn run(
        &mut self,
        options: &RunOptions,
        progress: Option<&indicatif::ProgressBar>,
    ) -> Result<Outcome, RunError> {
        self.wall_start = Instant::now();
        let mut k: u64 = 0;
        loop {
            if k >= self.schedule.total_ticks {
                return Ok(Outcome::DurationReached);
            }
            let stopped = options
                .stop
                .as_ref()
                .is_some_and(|s| s.load(Ordering::Relaxed));
            if stopped || options.stop_after_ticks.is_some_and(|n| k >= n) {
                return Ok(Outcome::Interrupted);
            }
            if let Some(outcome) = self.tick(k, progress)? {
                return Ok(outcome);
            }
            k += 1;
            self.tracker.summary.simulated_time = k as f64 * self.schedule.base_ns as f64 * 1e-9;
        }
    }

    /// One base tick: steps 1-7 of the module documentation.
    fn tick(
        &mut self,
        k: u64,
        progress: Option<&indicatif::ProgressBar>,
    ) -> Result<Option<Outcome>, RunError> {
        let s = &self.schedule;
        let t = k * s.base_ns;
        let run_simplified = k % s.simplified_every == 0;
        let run_wbc = k % s.wbc_every == 0;
        let run_planner = self.stack.planner_due(t) || s.planner_every.is_some_and(|e| k % e == 0);
        let log_state = k % s.state_every == 0;
        let run_plant = k % s.sim_every == 0;
        if run_plant && k > 0 {
            // A fresh measurement (the plant advanced at the end of the previous tick; the initial one was
            // sensed when the loop started); pre-integrated when nothing reads the estimate at this tick and
            // `estimation.update = "when_read"`.
            let read = run_planner || s.reads_estimate_before_next_sample(k);
            if read || !self.stack.preintegrate_unread {
                self.stack.sense(self.robot.measurement())?;
            } else {
                self.stack.preintegrate(self.robot.measurement())?;
            }
        }
        if run_simplified || run_wbc || run_planner || log_state {
            self.stack
                .measure(self.robot.measurement(), self.robot.kinematics())?;
        }
        if run_simplified || run_wbc {
            self.stack.filter_measured_zmp(t);
        }
        if run_planner && self.stack.planner_tick(t)? {
            self.planned(t, k == 0)?;
        }
        if run_simplified {
            self.simplified(t)?;
        }
        if run_wbc {
            self.wbc(t)?;
        }
        if log_state {
            self.state(t, progress)?;
        }
        if run_wbc || run_simplified {
            let fallen = self.robot.measurement().fallen;
            let ending = end_check(&mut self.tracker, self.scenario, &self.stack, t, fallen);
            if ending.is_some() {
                return Ok(ending);
            }
        }
        if run_plant {
            if let Some(trajectory) = &self.trajectory {
                // At the plant rate: a staircase at the whole-body rate would shake stiff servos.
                trajectory.command(t as f64 * 1e-9, &mut self.stack.command);
                self.robot.command(&self.stack.command)?;
            } else if let Some(command) = self.plant_command.as_mut() {
                let remaining = self.schedule.after_plant_step_until_wbc(k);
                interpolate(&self.stack.command, remaining, command);
                self.robot.command(command)?;
            }
            self.robot.advance()?;
            self.tracker
                .plant_period(self.robot.measurement(), &self.stack);
        }
        Ok(None)
    }

    fn event(&mut self, t: u64, kind: &str, detail: String) -> Result<(), RunError> {
        tracing::info!(time = t as f64 * 1e-9, kind, "{detail}");
        if let Some(log) = self.log.as_mut() {
            log.event(t, kind, detail)?;
        }
        Ok(())
    }

    /// After the planner ran: its topics and a `start` / `replan` event.
    fn planned(&mut self, t: u64, first: bool) -> Result<(), RunError> {
        if let Some(log) = self.log.as_mut() {
            log.plan(t, &self.stack)?;
        }
        if let Some(plan) = self.stack.planner.plan() {
            let (contacts, end) = (plan.footsteps().len(), plan.end_time);
            let kind = if first { "start" } else { "replan" };
            self.event(
                t,
                kind,
                format!("plan with {contacts} contacts, ends at {end:.2} s"),
            )?;
        }
        Ok(())
    }

    fn simplified(&mut self, t: u64) -> Result<(), RunError> {
        let held = self.stack.simplified_tick(t)?;
        let time = self.stack.simplified_output.diagnostics.solve_time;
        self.tracker.simplified_times.push(time);
        if let Some(log) = self.log.as_mut() {
            log.simplified(t, &self.stack, time)?;
        }
        if let Some(adjusted) = self.stack.adjusted_footstep.take() {
            if let Some(log) = self.log.as_mut() {
                log.adjusted_footstep(t, &adjusted)?;
            }
            let [dx, dy] = adjusted.displacement;
            let detail = format!(
                "{} footstep moved by ({dx:.3}, {dy:.3}) m, touch-down {:.3} s (planned {:.3} s)",
                adjusted.foot, adjusted.touchdown_time, adjusted.nominal_touchdown_time
            );
            let kind = if std::mem::take(&mut self.stack.early_touchdown) {
                "early_touchdown"
            } else {
                "step_adjustment"
            };
            self.event(t, kind, detail)?;
        }
        if let Some(f) = self.stack.push_hold_started.take() {
            let detail = format!(
                "double support held: push estimate ({:.1}, {:.1}) N, plan {:.2} s behind",
                f.x,
                f.y,
                self.stack.plan_clock.delay()
            );
            self.event(t, "push_hold", detail)?;
        }
        if let Some(outside) = self.stack.push_step_out.take() {
            let detail = format!(
                "hold ended for a step: DCM with the push {:.1} mm outside the support polygon",
                outside * 1e3
            );
            self.event(t, "push_step_out", detail)?;
        }
        if let Some(message) = held {
            let detail = format!("simplified layer held its references: {message}");
            self.event(t, "hold", detail)?;
        }
        let msg = self.tracker.track(t, &self.stack, self.robot.measurement());
        if let Some(log) = self.log.as_mut() {
            log.tracking(t, &msg)?;
        }
        Ok(())
    }

    fn wbc(&mut self, t: u64) -> Result<(), RunError> {
        let fallbacks = self.stack.counters.wbc_fallbacks;
        self.stack.wbc_tick(t)?;
        self.tracker
            .estimation(&self.stack, self.robot.measurement());
        let report = match &self.stack.wbc {
            Wbc::Ik(ik) => ik.output().report,
            Wbc::Tsid(ts) => ts.output().report,
        };
        self.tracker.wbc_times.push(report.solve_time);
        if let Some(log) = self.log.as_mut() {
            let timing = TimingRecord {
                solve_time: report.solve_time,
                tick_time: report.tick_time,
            };
            log.wbc(t, &self.stack, timing)?;
        }
        if self.stack.counters.wbc_fallbacks > fallbacks {
            let detail = "whole-body QP solved by the relaxed fallback".to_string();
            self.event(t, "fallback", detail)?;
        }
        let phase = crate::records::phase_name(&self.stack.plan_sample.phase);
        if phase != self.last_phase {
            self.last_phase = phase;
            self.event(t, "phase", phase.to_string())?;
        }
        if self.trajectory.is_none() {
            self.robot.command(&self.stack.command)?;
        }
        if self.realtime {
            self.pace(t);
        }
        Ok(())
    }

    /// Realtime mode: sleeps until wall-clock time catches up with `t`, counts late ticks.
    fn pace(&mut self, t: u64) {
        let target = Duration::from_nanos(t);
        let now = self.wall_start.elapsed();
        let wbc_period = Duration::from_nanos(self.schedule.wbc_every * self.schedule.base_ns);
        if now < target {
            std::thread::sleep(target - now);
        } else if now > target + wbc_period {
            self.tracker.summary.deadline_misses += 1;
        }
    }

    fn state(&mut self, t: u64, progress: Option<&indicatif::ProgressBar>) -> Result<(), RunError> {
        let wall = self.wall_start.elapsed().as_secs_f64();
        let rtf = if wall > 0.0 {
            t as f64 * 1e-9 / wall
        } else {
            0.0
        };
        if let Some(log) = self.log.as_mut() {
            log.state(t, self.robot.measurement(), &self.stack)?;
            let timing = RunnerTimingMsg {
                wall_time: wall,
                real_time_factor: rtf,
                deadline_misses: self.tracker.summary.deadline_misses,
            };
            log.runner_timing(t, &timing)?;
        }
        if let Some(pb) = progress {
            let d = self.tracker.distance(&self.stack);
            pb.set_position(t / 1_000_000);
            pb.set_message(format!("{d:.2} m  {rtf:.1}x real time"));
        }
        Ok(())
    }

    /// Ends the run: the `end` event, the summary's final figures, the log closed.
    fn finish(mut self, outcome: Outcome) -> Result<RunSummary, RunError> {
        let wall = self.wall_start.elapsed().as_secs_f64();
        let t_end = (self.tracker.summary.simulated_time * 1e9).round() as u64;
        let detail = outcome.to_string();
        let _ = self
            .stack
            .measure(self.robot.measurement(), self.robot.kinematics());
        let end = mid_pose(&self.stack.truth.soles);
        let goal = &self.scenario.config.goal;
        let mut summary = self.tracker.finish(&self.stack, goal, outcome, end, wall);
        // `/runner/diagnosis` (it needs the summary), then the `end` event: the log's last message.
        tracing::info!(time = t_end as f64 * 1e-9, kind = "end", "{detail}");
        if let Some(mut log) = self.log.take() {
            log.diagnosis(t_end, &summary)?;
            let _ = log.event(t_end, "end", detail);
            summary.log = Some(log.finish()?);
        }
        Ok(summary)
    }
}

fn progress_bar(enabled: bool, duration: f64) -> Option<indicatif::ProgressBar> {
    use std::io::IsTerminal;
    if !enabled || !std::io::stderr().is_terminal() {
        return None;
    }
    let pb = indicatif::ProgressBar::new((duration * 1000.0) as u64);
    let style =
        indicatif::ProgressStyle::with_template("{bar:40} {pos:>6}/{len} ms simulated  {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar());
    pb.set_style(style);
    Some(pb)
}
