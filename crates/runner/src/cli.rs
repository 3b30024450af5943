//! The `stride` command line.
//!
//! Every subcommand returns a [`CliError`]; [`crate::commands::main`] prints it as one paragraph (the error and its causes
//! joined by `: `) and exits with status 1 (2 for usage errors, printed by clap). `--verbose` turns on
//! `tracing` diagnostics on stderr (`RUST_LOG` refines them).

use std::path::PathBuf;

use clap::{Parser, Subcommand, ValueEnum};

/// Any failure of a subcommand.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// The scenario file is invalid.
    #[error(transparent)]
    Config(#[from] crate::config::ConfigError),
    /// Anything else, with context.
    #[error("{0}")]
    Other(String),
}

impl CliError {
    /// An error from a message.
    pub fn msg(m: impl Into<String>) -> Self {
        CliError::Other(m.into())
    }
}

/// stride: a three-layer walking controller stack for humanoid robots.
#[derive(Debug, Parser)]
#[command(name = "stride", version, about, long_about = None)]
pub struct Cli {
    /// Print diagnostics (tracing, level debug; RUST_LOG overrides).
    #[arg(short, long, global = true)]
    pub verbose: bool,
    /// The subcommand.
    #[command(subcommand)]
    pub command: Command,
}

/// Velocity representation for `stride model eval`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Representation {
    /// Mixed (default): origin velocity and angular velocity in world orientation.
    Mixed,
    /// Body: both in the body frame.
    Body,
    /// Inertial: both in the world frame (right-trivialized).
    Inertial,
}

/// Plant override of `stride run`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum PlantArg {
    /// stride-sim.
    Simulator,
    /// The ideal kinematic plant.
    Ideal,
    /// MuJoCo (needs a build with `--features mujoco`).
    Mujoco,
}

/// A layer that `stride replay` can rebuild.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum LayerName {
    /// The footstep and DCM planner.
    Planner,
    /// The simplified-model (DCM/ZMP) layer.
    Simplified,
    /// The whole-body layer (QP-IK or TSID).
    Wbc,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Inspect and evaluate a URDF model.
    Model {
        /// What to do with the model.
        #[command(subcommand)]
        command: ModelCommand,
    },
    /// Derive a robot file and two walking scenarios (position and torque control, 2 m straight) from a
    /// URDF: soles, legs, knees, arms, locked hand joints, a flat-footed crouch, robot-scaled planner
    /// limits and servo gains (docs/new-robot.md).
    Init {
        /// URDF file; may hold `${VAR}` (kept as written in the robot file).
        urdf: String,
        /// Robot name: writes `DIR/robots/NAME.toml`, `DIR/walk_NAME.toml`, `DIR/walk_NAME_torque.toml`.
        #[arg(long)]
        name: String,
        /// Output directory.
        #[arg(long, default_value = "configs")]
        dir: PathBuf,
        /// CoM height of the crouch above the soles \[m\] (default: from the leg length).
        #[arg(long)]
        com_height: Option<f64>,
        /// Overwrite existing files.
        #[arg(long)]
        force: bool,
    },
    /// Validate a scenario file and its names against the model (with warnings about the posture and
    /// the ground) without running it.
    Check {
        /// Scenario TOML file.
        config: PathBuf,
    },
    /// Run only the planner of a scenario and print its plan.
    Plan {
        /// Scenario TOML file.
        config: PathBuf,
        /// Print one JSON object instead of a table.
        #[arg(long)]
        json: bool,
        /// Sampling period of the printed references \[s\] (default: the simplified layer's period).
        #[arg(long)]
        dt: Option<f64>,
    },
    /// Run a scenario in closed loop and write an MCAP log.
    Run {
        /// Scenario TOML file.
        config: PathBuf,
        /// Log file (default: `log.path` of the scenario, else `<scenario name>.mcap`).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Override the scenario duration \[s\].
        #[arg(long)]
        duration: Option<f64>,
        /// Pace the loop at 1× wall-clock time and count deadline misses.
        #[arg(long)]
        realtime: bool,
        /// Do not draw the progress bar.
        #[arg(long)]
        no_progress: bool,
        /// Override the scenario's plant (`ideal`: joint commands applied exactly, base from the stance foot, read as ground truth; `mujoco`: MuJoCo 3.17, needs `--features mujoco`).
        #[arg(long, value_enum)]
        plant: Option<PlantArg>,
    },
    /// Re-run one layer on the inputs recorded in a log.
    Replay {
        /// MCAP log written by `stride run`.
        log: PathBuf,
        /// The layer to rebuild.
        #[arg(long, value_enum)]
        layer: LayerName,
        /// Another scenario file for the layer's parameters (default: the config stored in the log).
        #[arg(long)]
        config: Option<PathBuf>,
        /// Write the replayed outputs to this MCAP file.
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Estimate the force/torque sensors' offsets from a log of a calibration run (robot on a pole, limbs
    /// swung through rotations: `configs/identify_ft_legs.toml`) and write them as a scenario overlay; with
    /// several logs of the same motion with different known added masses
    /// (`configs/identify_ft_masses_*.toml`), the calibration matrices of the sensors whose child side is
    /// one rigid body (at least three logs: Lemma 5.2).
    Calibrate {
        /// MCAP logs written by `stride run`: one for the offsets, three or more for the matrices.
        #[arg(required = true)]
        logs: Vec<PathBuf>,
        /// Calibrate only this sensor (default: every force/torque sensor of the model; with several logs,
        /// every sensor whose child side is rigid).
        #[arg(long)]
        sensor: Option<String>,
        /// With several logs: a TOML file with the masses added in each log (`[[log]] masses = [{ frame,
        /// mass, com }]`, one entry per log in order); default: each log's `[sim.model]` edits.
        #[arg(long)]
        added_masses: Option<PathBuf>,
        /// With several logs: take each sensor's offset constant over a log (Traversaro 2017, (5.10)) instead
        /// of a random walk under the logged `[sim.sensors.ft]` noise and drift rates.
        #[arg(long)]
        constant_offset: bool,
        /// Write the result to this TOML file (`estimation.ft_offsets.initial`, and with several logs
        /// `estimation.ft_calibration`).
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Identify the robot's inertial parameters from logs of identification runs (robot on a pole, joints
    /// moved: `configs/identify_legs.toml`; robot standing on its feet: `configs/identify_standing.toml`)
    /// and write a URDF with them, every body physically consistent.
    Identify {
        /// MCAP logs written by `stride run` (same robot model).
        #[arg(required = true)]
        logs: Vec<PathBuf>,
        /// The identified URDF (the logged URDF with every link's inertial replaced).
        #[arg(short, long)]
        output: PathBuf,
        /// Also write a TOML report: parameters before and after, residuals, singular values.
        #[arg(long)]
        report: Option<PathBuf>,
        /// Also write the simulated plant's parameters (`[sim.model]` applied to the logged URDF) as a URDF
        /// in the same form, for comparisons (simulated logs only).
        #[arg(long)]
        plant_urdf: Option<PathBuf>,
        /// Use only the motor torques (not the force/torque sensors).
        #[arg(long, conflicts_with = "ft_only")]
        torques_only: bool,
        /// Use only the force/torque sensors (not the motor torques).
        #[arg(long)]
        ft_only: bool,
        /// Relative weight of the pull towards the logged URDF (`ManifoldOptions::prior_weight`).
        #[arg(long, default_value_t = 1e-4)]
        prior_weight: f64,
        /// Relative weight of the pull on the rotational inertias alone; the masses and first moments keep
        /// `--prior-weight` (`ManifoldOptions::inertia_prior_weight`).
        #[arg(long, default_value_t = 1.0)]
        prior_weight_inertia: f64,
        /// Iterations of the manifold solver (`ManifoldOptions::max_iterations`).
        #[arg(long, default_value_t = 500)]
        max_iterations: usize,
    },
    /// SVG figures of a run's log (tracking, feet, forces, torques, solve times) or a sweep's survival map.
    Plot {
        /// MCAP log written by `stride run`, or a sweep's `results.json`.
        input: PathBuf,
        /// Output directory (default: `<log stem>_plots/` next to the log; the directory of `results.json`).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Survival map: the axis key across (default: the first axis of the results).
        #[arg(long)]
        x: Option<String>,
        /// Survival map: the axis key up (default: the second axis).
        #[arg(long)]
        y: Option<String>,
    },
    /// Run a scenario over a grid or random sample of parameters (docs/sweeps.md).
    Sweep(SweepArgs),
}

/// `stride sweep SWEEP.toml ...` or `stride sweep merge DIR... -o DIR`.
#[derive(Debug, clap::Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct SweepArgs {
    /// `merge`: combine shards.
    #[command(subcommand)]
    pub command: Option<SweepCommand>,
    /// Sweep TOML file.
    #[arg(required = true)]
    pub file: Option<PathBuf>,
    /// Worker threads (default: the core count).
    #[arg(short, long)]
    pub jobs: Option<usize>,
    /// Output folder for results.csv, results.json (and logs/) (default: `sweep_<file stem>`).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Run only shard I of N (variant k belongs to shard k mod N + 1).
    #[arg(long)]
    pub shard: Option<crate::sweep::Shard>,
    /// Write each variant's MCAP log into DIR/logs/.
    #[arg(long)]
    pub logs: bool,
    /// Do not draw the progress bar.
    #[arg(long)]
    pub no_progress: bool,
}

/// `stride sweep merge`.
#[derive(Debug, Subcommand)]
pub enum SweepCommand {
    /// Combine the results of `--shard` runs into those of the whole sweep.
    Merge {
        /// Shard output folders.
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
        /// Output folder.
        #[arg(short, long)]
        output: PathBuf,
    },
}

/// `stride model ...`
#[derive(Debug, Subcommand)]
pub enum ModelCommand {
    /// Degrees of freedom, joints, links, frames, sensors, mass and CoM of a URDF.
    Info {
        /// URDF file.
        urdf: PathBuf,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
    },
    /// Propose each foot's sole frame and rectangle from the lowest flat patch of its collision geometry
    /// (boxes, cylinders, spheres, STL and OBJ meshes), and compare it with the visual geometry.
    Feet {
        /// URDF file.
        urdf: PathBuf,
    },
    /// Evaluate kinematics and dynamics at a state given as JSON; prints one JSON object.
    Eval {
        /// URDF file.
        urdf: PathBuf,
        /// State JSON file (see docs/cli.md).
        #[arg(long)]
        state: PathBuf,
        /// Velocity representation.
        #[arg(long, value_enum, default_value_t = Representation::Mixed)]
        representation: Representation,
    },
}

/// Writes to stdout; a closed pipe (reader gone) is not an error worth a panic.
pub fn write_stdout(args: std::fmt::Arguments<'_>) {
    use std::io::Write;
    let _ = std::io::stdout().lock().write_fmt(args);
}

/// The error and its chain of causes as one line.
pub fn one_paragraph(e: &(dyn std::error::Error + 'static)) -> String {
    let mut s = e.to_string();
    let mut cur = e.source();
    while let Some(c) = cur {
        let cs = c.to_string();
        if !s.contains(&cs) {
            s.push_str(": ");
            s.push_str(&cs);
        }
        cur = c.source();
    }
    s
}
