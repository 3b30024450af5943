//! Implementations of the `stride` subcommands.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use crate::cli::{CliError, LayerName, ModelCommand};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use crate::config::{Goal, PlannerMode, Scenario};
use crate::run::{run_scenario, Outcome, RunOptions};

/// `stride check <CONFIG>`.
pub fn check(path: &Path) -> Result<ExitCode, CliError> {
    let s = Scenario::load(path)?;
    let c = &s.config;
    println!("{}: ok", path.display());
    println!(
        "  files: {}",
        s.sources
            .files
            .iter()
            .map(|f| f.path.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    println!("  scenario: {} ({:?} control, {:?} plant, {} s)", c.scenario.name, c.scenario.control_mode, c.scenario.plant, c.scenario.duration);
    println!("  model: {}", s.urdf_path.display());
    let planner = match c.rates.planner_mode {
        PlannerMode::Event => "event-driven".to_string(),
        PlannerMode::Periodic => format!("{} Hz", c.rates.planner_hz),
    };
    println!(
        "  rates: base {} Hz, planner {planner}, simplified {} Hz, whole-body {} Hz, simulator {} Hz",
        c.rates.base_hz, c.rates.simplified_hz, c.rates.wbc_hz, c.rates.sim_hz
    );
    let goal = match &c.goal {
        Goal::Pose(p) => format!("pose x={} m y={} m heading={}°", p.x, p.y, p.heading_deg),
        Goal::Waypoints { points } => format!("{} waypoints", points.len()),
        Goal::Velocity { segments } => format!("velocity schedule of {} segments", segments.len()),
        Goal::Stand {} => "stand".into(),
    };
    println!("  goal: {goal}");
    if !c.sim.pushes.is_empty() {
        println!("  pushes: {}", c.sim.pushes.len());
    }
    Ok(ExitCode::SUCCESS)
}

/// `stride model info|eval`.
pub fn model(command: ModelCommand) -> Result<ExitCode, CliError> {
    crate::model_cmd::model(command)
}

/// `stride plan`.
pub fn plan(_path: &Path, _json: bool, _dt: Option<f64>) -> Result<ExitCode, CliError> {
    Err(CliError::msg("`stride plan`: the planner is not wired into the runner yet"))
}

/// `stride run`: Ctrl-C stops the loop at the next tick and the log is closed properly.
pub fn run(
    path: &Path,
    output: Option<PathBuf>,
    duration: Option<f64>,
    realtime: bool,
    no_progress: bool,
) -> Result<ExitCode, CliError> {
    let scenario = Scenario::load(path)?;
    if let Some(d) = duration {
        if !(d.is_finite() && d > 0.0) {
            return Err(CliError::msg(format!("--duration {d}: expected a positive number of seconds")));
        }
    }
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = Arc::clone(&stop);
        // A second Ctrl-C while stopping is ignored; the first one ends the run at the next tick.
        let _ = ctrlc::set_handler(move || stop.store(true, Ordering::SeqCst));
    }
    let options = RunOptions {
        output,
        duration,
        realtime,
        progress: !no_progress,
        stop: Some(stop),
        ..RunOptions::default()
    };
    let summary = run_scenario(&scenario, &options).map_err(|e| CliError::msg(crate::cli::one_paragraph(&e)))?;
    print!("{}", summary.render());
    Ok(match summary.outcome {
        Outcome::DurationReached | Outcome::GoalReached | Outcome::Interrupted => ExitCode::SUCCESS,
        Outcome::Fell { .. } => ExitCode::from(3),
        Outcome::Error { .. } => ExitCode::FAILURE,
    })
}

/// `stride replay`.
pub fn replay(
    _log: &Path,
    _layer: LayerName,
    _config: Option<PathBuf>,
    _output: Option<PathBuf>,
) -> Result<ExitCode, CliError> {
    Err(CliError::msg("`stride replay`: not wired yet"))
}
