//! Implementations of the `stride` subcommands, and [`main`], which parses the command line ([`Cli`])
//! and dispatches to them.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Parser;

use crate::cli::{one_paragraph, Cli, CliError, Command, LayerName, ModelCommand};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use crate::config::{Goal, PlannerMode, Scenario};
use crate::run::{run_scenario, Outcome, RunOptions};

/// `stride check <CONFIG>`.
///
/// Loads the scenario and its model, checks every name it uses, builds the run's plant and layers, and
/// prints what it found, then the warnings (`warning: ...`, exit status still 0).
pub fn check(path: &Path) -> Result<ExitCode, CliError> {
    let s = Scenario::load(path)?;
    let report = crate::check::check_scenario(&s).map_err(|e| CliError::msg(one_paragraph(&e)))?;
    let c = &s.config;
    crate::outln!("{}: ok", path.display());
    crate::outln!(
        "  files: {}",
        s.sources
            .files
            .iter()
            .map(|f| f.path.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    crate::outln!(
        "  scenario: {} ({:?} control, {:?} plant, {} s)",
        c.scenario.name,
        c.scenario.control_mode,
        c.scenario.plant,
        c.scenario.duration
    );
    let m = &report.model;
    crate::outln!(
        "  model: {} ({} joints, {:.1} kg)",
        s.urdf_path.display(),
        m.dof(),
        m.total_mass()
    );
    crate::outln!(
        "  names: {} frame, joint and sensor names found in the model",
        crate::check::names::name_uses(&s).len()
    );
    let st = &report.stance;
    crate::outln!(
        "  initial posture: CoM {:.3} m above the soles, soles {:.3} m apart, m·g·h = {:.0} N·m/rad",
        st.com_height(),
        st.feet_width(),
        st.toppling_stiffness()
    );
    let planner = match c.rates.planner_mode {
        PlannerMode::Event => "event-driven".to_string(),
        PlannerMode::Periodic => format!("{} Hz", c.rates.planner_hz),
    };
    crate::outln!(
        "  rates: base {} Hz, planner {planner}, simplified {} Hz, whole-body {} Hz, simulator {} Hz",
        c.rates.base_hz, c.rates.simplified_hz, c.rates.wbc_hz, c.rates.sim_hz
    );
    let goal = match &c.goal {
        Goal::Pose(p) => format!("pose x={} m y={} m heading={}°", p.x, p.y, p.heading_deg),
        Goal::Waypoints { points } => format!("{} waypoints", points.len()),
        Goal::Velocity { segments } => format!("velocity schedule of {} segments", segments.len()),
        Goal::Stand {} => "stand".into(),
    };
    crate::outln!("  goal: {goal}");
    if !c.sim.pushes.is_empty() {
        crate::outln!("  pushes: {}", c.sim.pushes.len());
    }
    for w in &report.warnings {
        crate::outln!("warning: {w}");
    }
    Ok(ExitCode::SUCCESS)
}

/// `stride init <URDF> --name NAME`: derives the robot's configuration ([`crate::init::derive`]), writes
/// the three files and prints what it found.
pub fn init(
    urdf: &str,
    name: &str,
    dir: &Path,
    com_height: Option<f64>,
    force: bool,
) -> Result<ExitCode, CliError> {
    if name.is_empty()
        || !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        return Err(CliError::msg(format!(
            "--name `{name}`: expected letters, digits, `_` or `-` (it names the files)"
        )));
    }
    if let Some(h) = com_height {
        if !(h.is_finite() && h > 0.0) {
            return Err(CliError::msg(format!(
                "--com-height {h}: expected a positive height in metres"
            )));
        }
    }
    let run = || -> Result<_, crate::init::InitError> {
        let path = crate::init::resolve_urdf(urdf)?;
        let setup = crate::init::derive(&path, com_height)?;
        let files = crate::init::write::write(&setup, urdf, name, dir, force)?;
        Ok((setup, files))
    };
    let (s, files) = run().map_err(|e| CliError::msg(e.to_string()))?;
    crate::outln!(
        "{}: model `{}`, {:.2} kg, {} legs of {:.3} m",
        s.urdf.display(),
        s.model_name,
        s.mass,
        s.legs[0].len() + s.legs[1].len(),
        s.leg_length
    );
    crate::outln!(
        "  knees {} and {} (flexion {}), torso frame {}, {} arm joints, {} locked joint(s)",
        s.knees[0].0,
        s.knees[1].0,
        if s.knees[0].1 > 0.0 { "+" } else { "-" },
        s.torso_frame,
        s.arms[0].len() + s.arms[1].len(),
        s.locks.len()
    );
    crate::outln!(
        "  crouch: CoM {:.3} m above the soles (target {:.3}), soles {:.3} m apart, sole {:.3} m × {:.3} m",
        s.stance.com_height(),
        s.target_height,
        s.stance.feet_width(),
        s.foot[0],
        s.foot[1]
    );
    crate::outln!(
        "  servos kp {:.0} N·m/rad, kd {:.0} N·m·s/rad; feet_distance_max {:.3} m, steps {:.2}–{:.2} s",
        s.scaled.servo_kp,
        s.scaled.servo_kd,
        s.scaled.feet_distance_max,
        s.scaled.step_durations[0],
        s.scaled.step_durations[2]
    );
    for f in &files {
        crate::outln!("wrote {}", f.display());
    }
    Ok(ExitCode::SUCCESS)
}

/// `stride model info|eval`.
pub fn model(command: ModelCommand) -> Result<ExitCode, CliError> {
    crate::model_cmd::model(command)
}

/// `stride plan`: the planner alone, from the robot standing at its initial posture.
pub fn plan(path: &Path, json: bool, dt: Option<f64>) -> Result<ExitCode, CliError> {
    let scenario = Scenario::load(path)?;
    let c = &scenario.config;
    let dt = dt.unwrap_or(1.0 / f64::from(c.rates.simplified_hz));
    if !(dt.is_finite() && dt > 0.0) {
        return Err(CliError::msg(format!(
            "--dt {dt}: expected a positive number of seconds"
        )));
    }
    let model = crate::run::load_model(&scenario).map_err(err)?;
    let q0 = crate::run::initial_joint_positions(&scenario, &model).map_err(err)?;
    let frame = |name: &str, key: &str| {
        model.frame_id(name).ok_or_else(|| {
            CliError::from(scenario.invalid(key, format!("the model has no frame `{name}`")))
        })
    };
    let l = frame(&c.robot.left_sole, "robot.left_sole")?;
    let r = frame(&c.robot.right_sole, "robot.right_sole")?;
    let state = stride_model::RobotState::standing(&model, &q0, l, r).map_err(err)?;
    let mut kd = stride_model::KinDyn::new(Arc::clone(&model));
    kd.set_state(&state).map_err(err)?;
    let (lp, rp) = (kd.frame_pose(l), kd.frame_pose(r));
    let events = crate::stack::goal_events(&c.goal);
    let mut planner =
        stride_planner::Planner::new(c.planner.clone(), c.scenario.gravity).map_err(err)?;
    let first = events
        .first()
        .map_or(stride_planner::Goal::Stand, |e| e.goal.clone());
    planner
        .start(std::time::Duration::ZERO, &lp, &rp, &first)
        .map_err(err)?;
    for e in events.iter().skip(1) {
        planner
            .replan(std::time::Duration::from_nanos(e.time_ns), &e.goal)
            .map_err(err)?;
    }
    let plan = planner
        .plan()
        .ok_or_else(|| CliError::msg("the planner produced no plan"))?;
    let report = plan.report(dt).map_err(err)?;
    if json {
        crate::outln!(
            "{}",
            serde_json::to_string(&report).map_err(|e| CliError::msg(e.to_string()))?
        );
        return Ok(ExitCode::SUCCESS);
    }
    crate::outln!(
        "plan of {}: {} steps, ends at {:.2} s ({:.2} s of samples every {dt} s)",
        c.scenario.name,
        plan.step_count(),
        plan.end_time,
        plan.end_time - plan.start_time
    );
    crate::outln!(
        "  {:<6} {:>9} {:>9} {:>9} {:>10} {:>10}",
        "foot",
        "x [m]",
        "y [m]",
        "yaw [°]",
        "on [s]",
        "off [s]"
    );
    for f in plan.footsteps() {
        crate::outln!(
            "  {:<6} {:>9.3} {:>9.3} {:>9.1} {:>10.2} {:>10}",
            match f.foot {
                stride_planner::Foot::Left => "left",
                stride_planner::Foot::Right => "right",
            },
            f.pose.translation.x,
            f.pose.translation.y,
            f.pose.rotation.euler_angles().2.to_degrees(),
            f.activation_time,
            f.deactivation_time
                .map_or("-".to_string(), |t| format!("{t:.2}"))
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// `stride run`: Ctrl-C stops the loop at the next tick and the log is closed properly.
pub fn run(
    path: &Path,
    output: Option<PathBuf>,
    duration: Option<f64>,
    realtime: bool,
    no_progress: bool,
    plant: Option<crate::cli::PlantArg>,
) -> Result<ExitCode, CliError> {
    let scenario = Scenario::load(path)?;
    if let Some(d) = duration {
        if !(d.is_finite() && d > 0.0) {
            return Err(CliError::msg(format!(
                "--duration {d}: expected a positive number of seconds"
            )));
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
        plant: plant.map(|p| match p {
            crate::cli::PlantArg::Simulator => crate::config::PlantKind::Simulator,
            crate::cli::PlantArg::Ideal => crate::config::PlantKind::Ideal,
            crate::cli::PlantArg::Mujoco => crate::config::PlantKind::Mujoco,
        }),
        ..RunOptions::default()
    };
    let summary = run_scenario(&scenario, &options)
        .map_err(|e| CliError::msg(crate::cli::one_paragraph(&e)))?;
    crate::out!("{}", summary.render());
    Ok(match summary.outcome {
        Outcome::DurationReached | Outcome::GoalReached | Outcome::Interrupted => ExitCode::SUCCESS,
        Outcome::Fell { .. } => ExitCode::from(3),
        Outcome::Error { .. } => ExitCode::FAILURE,
    })
}

/// `stride replay`.
pub fn replay(
    log: &Path,
    layer: LayerName,
    config: Option<PathBuf>,
    output: Option<PathBuf>,
) -> Result<ExitCode, CliError> {
    let report = crate::replay::replay(log, layer, config.as_deref(), output.as_ref())
        .map_err(|e| CliError::msg(crate::cli::one_paragraph(&e)))?;
    let d = &report.difference;
    crate::outln!(
        "replayed {} {:?} ticks from {}{}",
        report.ticks,
        layer,
        log.display(),
        config
            .as_ref()
            .map(|c| format!(" with {}", c.display()))
            .unwrap_or_default()
    );
    crate::outln!(
        "largest difference from the logged outputs: {:e}{}; non-numeric differences: {}",
        d.max_abs,
        if d.at.is_empty() {
            String::new()
        } else {
            format!(" (at {})", d.at)
        },
        d.mismatches
    );
    if report.layer_errors > 0 {
        crate::outln!(
            "layer errors during replay (output held): {}",
            report.layer_errors
        );
    }
    if let Some(o) = output {
        crate::outln!("replayed outputs written to {}", o.display());
    }
    Ok(ExitCode::SUCCESS)
}

/// `stride plot`: the figures of a log, or the survival map of a sweep's `results.json`.
pub fn plot(
    input: &Path,
    output: Option<PathBuf>,
    x: Option<&str>,
    y: Option<&str>,
) -> Result<ExitCode, CliError> {
    use crate::plot;
    let dir = output.unwrap_or_else(|| plot::default_dir(input));
    let files = if plot::is_results(input) {
        vec![plot::plot_sweep(input, &dir, x, y).map_err(err)?]
    } else {
        if x.is_some() || y.is_some() {
            return Err(CliError::msg(
                "--x and --y apply to a sweep's results.json, not to a log",
            ));
        }
        plot::plot_log(input, &dir).map_err(err)?
    };
    for f in files {
        crate::outln!("{}", f.display());
    }
    Ok(ExitCode::SUCCESS)
}

/// `stride calibrate`: the offsets table, and the overlay file with `--output`.
pub fn calibrate(
    log: &Path,
    sensor: Option<&str>,
    output: Option<&Path>,
) -> Result<ExitCode, CliError> {
    let report = crate::calibrate::calibrate_log(log, sensor).map_err(err)?;
    crate::out!("{}", report.render());
    if let Some(o) = output {
        std::fs::write(o, report.to_toml(log))
            .map_err(|e| CliError::msg(format!("cannot write {}: {e}", o.display())))?;
        crate::outln!("offsets written to {}", o.display());
    }
    Ok(ExitCode::SUCCESS)
}

/// `stride calibrate LOG LOG LOG...`: the calibration matrices, and the overlay file with `--output`.
pub fn calibrate_matrix(
    logs: &[PathBuf],
    sensor: Option<&str>,
    added_masses: Option<&Path>,
    offsets: crate::calibrate_matrix::OffsetChoice,
    output: Option<&Path>,
) -> Result<ExitCode, CliError> {
    let masses = match added_masses {
        Some(p) => {
            let text = std::fs::read_to_string(p)
                .map_err(|e| CliError::msg(format!("cannot read {}: {e}", p.display())))?;
            Some(
                toml::from_str::<crate::calibrate_matrix::AddedMassFile>(&text)
                    .map_err(|e| CliError::msg(format!("{}: {e}", p.display())))?,
            )
        }
        None => None,
    };
    let report =
        crate::calibrate_matrix::calibrate_matrix_logs(logs, sensor, masses.as_ref(), offsets)
            .map_err(err)?;
    crate::out!("{}", report.render());
    if let Some(o) = output {
        std::fs::write(o, report.to_toml(logs))
            .map_err(|e| CliError::msg(format!("cannot write {}: {e}", o.display())))?;
        crate::outln!("calibration written to {}", o.display());
    }
    Ok(ExitCode::SUCCESS)
}

/// `stride identify`: the table, the identified URDF and, with `--report`, the TOML report.
pub fn identify(
    logs: &[PathBuf],
    output: &Path,
    report_path: Option<&Path>,
    plant_urdf: Option<&Path>,
    options: &crate::identify::IdentifyOptions,
) -> Result<ExitCode, CliError> {
    let report = crate::identify::identify_logs(logs, options).map_err(err)?;
    crate::out!("{}", report.render());
    let urdf =
        crate::identify::identified_urdf(&report.prior_urdf, &report.model, &report.identified)
            .map_err(err)?;
    let write = |path: &Path, text: &str| {
        std::fs::write(path, text)
            .map_err(|e| CliError::msg(format!("cannot write {}: {e}", path.display())))
    };
    write(output, &urdf)?;
    crate::outln!("identified URDF written to {}", output.display());
    if let Some(r) = report_path {
        write(r, &report.to_toml())?;
        crate::outln!("report written to {}", r.display());
    }
    if let Some(p) = plant_urdf {
        let truth = report.truth.as_ref().ok_or_else(|| {
            CliError::msg(
                "--plant-urdf: the logs are not simulations of the logged URDF".to_string(),
            )
        })?;
        let text = crate::identify::identified_urdf(&report.prior_urdf, &report.model, truth)
            .map_err(err)?;
        write(p, &text)?;
        crate::outln!("plant URDF written to {}", p.display());
    }
    Ok(ExitCode::SUCCESS)
}

fn err<E: std::error::Error + 'static>(e: E) -> CliError {
    CliError::msg(crate::cli::one_paragraph(&e))
}

/// Entry point of the `stride` binary.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            // clap prints help/version to stdout and usage errors to stderr.
            let _ = e.print();
            return if e.use_stderr() {
                ExitCode::from(2)
            } else {
                ExitCode::SUCCESS
            };
        }
    };
    init_tracing(cli.verbose);
    match dispatch(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {}", one_paragraph(&e));
            ExitCode::FAILURE
        }
    }
}

fn init_tracing(verbose: bool) {
    use tracing_subscriber::EnvFilter;
    let default = if verbose { "debug" } else { "warn" };
    let filter = EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(default));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_target(false)
        .try_init();
}

/// Runs a parsed command line.
pub fn dispatch(cli: Cli) -> Result<ExitCode, CliError> {
    match cli.command {
        Command::Model { command } => model(command),
        Command::Check { config } => check(&config),
        Command::Init {
            urdf,
            name,
            dir,
            com_height,
            force,
        } => init(&urdf, &name, &dir, com_height, force),
        Command::Plan { config, json, dt } => plan(&config, json, dt),
        Command::Run {
            config,
            output,
            duration,
            realtime,
            no_progress,
            plant,
        } => run(&config, output, duration, realtime, no_progress, plant),
        Command::Replay {
            log,
            layer,
            config,
            output,
        } => replay(&log, layer, config, output),
        Command::Calibrate {
            logs,
            sensor,
            added_masses,
            constant_offset,
            output,
        } => match logs.as_slice() {
            [log] if added_masses.is_none() => calibrate(log, sensor.as_deref(), output.as_deref()),
            _ => calibrate_matrix(
                &logs,
                sensor.as_deref(),
                added_masses.as_deref(),
                if constant_offset {
                    crate::calibrate_matrix::OffsetChoice::Constant
                } else {
                    crate::calibrate_matrix::OffsetChoice::DriftFromLog
                },
                output.as_deref(),
            ),
        },
        Command::Identify {
            logs,
            output,
            report,
            plant_urdf,
            torques_only,
            ft_only,
            prior_weight,
            prior_weight_inertia,
            max_iterations,
        } => identify(
            &logs,
            &output,
            report.as_deref(),
            plant_urdf.as_deref(),
            &crate::identify::IdentifyOptions {
                use_torques: !ft_only,
                use_ft: !torques_only,
                prior_weight,
                inertia_prior_weight: Some(prior_weight_inertia),
                max_iterations,
                ..Default::default()
            },
        ),
        Command::Sweep(args) => crate::sweep_cmd::sweep(args),
        Command::Plot {
            input,
            output,
            x,
            y,
        } => plot(&input, output, x.as_deref(), y.as_deref()),
    }
}
