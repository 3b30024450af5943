//! Implementations of the `stride` subcommands.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use crate::cli::{CliError, LayerName, ModelCommand};
use crate::config::{Goal, PlannerMode, Scenario};

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
    if !c.pushes.is_empty() {
        println!("  pushes: {}", c.pushes.len());
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

/// `stride run`.
pub fn run(
    _path: &Path,
    _output: Option<PathBuf>,
    _duration: Option<f64>,
    _realtime: bool,
    _no_progress: bool,
) -> Result<ExitCode, CliError> {
    Err(CliError::msg("`stride run`: not wired yet"))
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
