//! Scenario configuration: the TOML schema, validation and loading.
//!
//! A scenario is one TOML file in `configs/` that may `include` shared robot and layer sections (see
//! [`load`] for the include/overlay rules). Every table rejects unknown keys; every error names the file,
//! line, column and key and says what is expected. The full key reference is `docs/configuration.md`,
//! generated from [`mod@reference`] and checked by a test so it cannot drift from the code.

pub mod load;
pub mod mujoco;
pub mod reference;
pub mod sole;
pub mod wbc;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

pub use load::{Loaded, Location, SourceFile, SourceMap};
pub use sole::{AttachedFrame, SoleFrame};
pub use wbc::{WalkingSection, WbcPreset, WbcSection};

/// Why a configuration was rejected.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// A file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
    /// A file is not valid TOML.
    #[error("{location}: TOML syntax error: {message}")]
    Syntax {
        /// Where.
        location: Location,
        /// What the parser expected.
        message: String,
    },
    /// A key is unknown, has the wrong type, or a value is out of range.
    #[error("{}key `{key}`: {message}", location.as_ref().map(|l| format!("{l}: ")).unwrap_or_default())]
    Invalid {
        /// Where the key (or its closest written parent) is written, if anywhere.
        location: Option<Location>,
        /// Dotted key path, e.g. `rates.wbc_hz`.
        key: String,
        /// What is wrong and what is expected.
        message: String,
    },
    /// A file includes itself (directly or not), or includes nest deeper than 16 levels.
    #[error("{}: include cycle (or includes nested deeper than 16 levels)", path.display())]
    IncludeCycle {
        /// The file included again.
        path: PathBuf,
    },
}

/// How the whole-body layer commands the robot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ControlMode {
    /// Kinematic QP-IK → integrated joint positions → joint position servos.
    #[default]
    Position,
    /// TSID → joint torques.
    Torque,
}

/// Which plant the loop closes on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum PlantKind {
    /// stride-sim: floating-base dynamics with compliant ground contact.
    #[default]
    Simulator,
    /// Ideal kinematic plant: joint commands applied exactly, base pose from the fixed stance foot.
    Ideal,
    /// MuJoCo 3.17 (`stride-mujoco`; needs a build with the `mujoco` feature, see docs/mujoco.md).
    Mujoco,
}

/// `[estimation]`: where the controllers' view of the robot comes from, and the estimation layer's
/// parameters (`stride_estimation::EstimatorConfig`; its sole and IMU frames are the robot's:
/// `robot.left_sole`, `robot.right_sole`, `sim.sensors.imu_frame`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EstimationSection {
    /// `ekf` (default): the estimation layer; `ground_truth`: the plant's truth, for debugging only.
    pub kind: EstimationKind,
    /// `when_read` (default): a full tick of the estimation layer only on the ticks that read the estimate,
    /// the samples in between pre-integrated; `every_sample`: a full tick on every plant sample.
    pub update: EstimationUpdate,
    /// Cut-off \[Hz\] of the first-order low-pass filter on the measured ZMP the simplified layer reads (0: unfiltered).
    pub measured_zmp_cutoff: f64,
    /// Force/torque sensor of the left foot (none: the one nearest above the sole).
    pub left_foot_ft_sensor: Option<String>,
    /// Force/torque sensor of the right foot (none: the one nearest above the sole).
    pub right_foot_ft_sensor: Option<String>,
    /// The floating-base EKF (`stride_estimation::EkfConfig`).
    pub ekf: stride_estimation::EkfConfig,
    /// Contact detection (`stride_estimation::ContactConfig`).
    pub contact: stride_estimation::ContactConfig,
    /// Force/torque offset estimation (`stride_estimation::FtOffsetConfig`).
    pub ft_offsets: stride_estimation::FtOffsetConfig,
    /// Calibration matrix `C` (6 rows of 6) of each named force/torque sensor: the estimation layer reads
    /// the wrench `C (r − b)` [Traversaro 2017, eq. (5.1)]; sensors not named keep the identity
    /// (`stride calibrate` with added-mass logs writes it).
    pub ft_calibration: std::collections::BTreeMap<String, [[f64; 6]; 6]>,
    /// Bandwidth \[Hz\] of the estimation layer's joint velocity filter on the encoder positions
    /// (`stride_estimation::JointVelocityFilter`); 0 (default): the encoders' velocities as read.
    pub joint_velocity_bandwidth: f64,
    /// The joint velocity filter predicts with the joint accelerations the TSID chose at its last tick
    /// (`stride_estimation::Estimator::set_joint_accelerations`); needs `joint_velocity_bandwidth` > 0
    /// and torque control.
    pub joint_velocity_prediction: bool,
    /// The inverse dynamics give a stance leg the joint accelerations that keep its sole still
    /// (`stride_estimation::EstimatorConfig::stance_leg_accelerations`; TSID-Flex's flexible joints stay
    /// at zero); false (default): zero joint accelerations.
    pub stance_leg_accelerations: bool,
    /// The ground the estimation layer's soles sink into (`stride_estimation::sole_sink`): `none`
    /// (default) a rigid ground; `controller_ground` the compliant TSID's (`wbc.tsid.compliant.ground_stiffness`,
    /// `ground_damping`; needs `[wbc.tsid] contact_model = "compliant"`).
    pub sole_sink: SoleSinkSource,
}

/// The ground the estimation layer's soles sink into (`estimation.sole_sink`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum SoleSinkSource {
    /// A rigid ground: a stance sole's origin is the EKF's static contact point.
    #[default]
    None,
    /// The compliant TSID's ground model (`wbc.tsid.compliant.ground_stiffness`, `ground_damping`): the
    /// EKF's contact point is the sole's zero-force point, the sole's origin less its sink under the
    /// foot's estimated force (docs/estimation.md, "A sole sinking into a compliant ground").
    ControllerGround,
}

/// Default of `estimation.measured_zmp_cutoff` \[Hz\]: the middle of the band that walks on both plants
/// (docs/estimation.md, "The measured ZMP").
pub const DEFAULT_MEASURED_ZMP_CUTOFF: f64 = stride_walking::MEASURED_ZMP_CUTOFF;

impl Default for EstimationSection {
    fn default() -> Self {
        Self {
            kind: EstimationKind::default(),
            update: EstimationUpdate::default(),
            measured_zmp_cutoff: DEFAULT_MEASURED_ZMP_CUTOFF,
            left_foot_ft_sensor: None,
            right_foot_ft_sensor: None,
            ekf: Default::default(),
            contact: Default::default(),
            ft_offsets: Default::default(),
            ft_calibration: Default::default(),
            joint_velocity_bandwidth: 0.0,
            joint_velocity_prediction: false,
            stance_leg_accelerations: false,
            sole_sink: SoleSinkSource::None,
        }
    }
}

impl EstimationSection {
    /// The estimation layer's configuration with the robot's frames.
    /// `sole_size`: the soles' `[length, width]` (`planner.foot_length`, `foot_width`); `ground`: the
    /// `[stiffness, damping]` densities of the ground the soles sink into (`estimation.sole_sink`; zeros: rigid).
    pub fn estimator_config(
        &self,
        robot: &RobotSection,
        imu_frame: &str,
        sole_size: [f64; 2],
        ground: [f64; 2],
    ) -> stride_estimation::EstimatorConfig {
        stride_estimation::EstimatorConfig {
            left_sole: robot.left_sole.name().to_string(),
            right_sole: robot.right_sole.name().to_string(),
            imu_frame: imu_frame.into(),
            left_foot_ft_sensor: self.left_foot_ft_sensor.clone(),
            right_foot_ft_sensor: self.right_foot_ft_sensor.clone(),
            ekf: self.ekf.clone(),
            contact: self.contact.clone(),
            ft_offsets: self.ft_offsets.clone(),
            ft_calibration: self.ft_calibration.clone(),
            joint_velocity_bandwidth: self.joint_velocity_bandwidth,
            ground_stiffness: ground[0],
            ground_damping: ground[1],
            sole_size,
            stance_leg_accelerations: self.stance_leg_accelerations,
            passive_joints: Vec::new(),
        }
    }
}

/// Which estimation the loop runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum EstimationKind {
    /// The estimation layer: contact-aided invariant EKF, foot wrenches and contacts from the FT sensors.
    #[default]
    Ekf,
    /// The plant's truth read directly (a simulator's privilege; debugging only).
    GroundTruth,
}

/// When the estimation layer runs its full tick (`estimation.update`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum EstimationUpdate {
    /// On every plant sample (2 kHz with the default rates).
    EverySample,
    /// On the ticks whose layers read the estimate (the whole-body, simplified and planner ticks: 500 Hz with
    /// the default rates); the IMU samples in between are pre-integrated into the EKF's mean
    /// (`stride_estimation::Estimator::preintegrate`) and the covariance is propagated over the whole
    /// interval at the next full tick. The state log records the estimate the layers last read: its rate
    /// does not change the closed loop.
    #[default]
    WhenRead,
}

/// `[scenario]`: what this run is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ScenarioSection {
    /// Short name, used for the default log file name.
    pub name: String,
    /// One line saying what the scenario shows.
    pub description: String,
    /// Simulated duration \[s\]; the run ends here at the latest.
    pub duration: f64,
    /// Position or torque control.
    pub control_mode: ControlMode,
    /// Simulator, ideal kinematic plant or MuJoCo.
    pub plant: PlantKind,
    /// Gravity acceleration \[m/s²\] along −z of the world: the one gravity of the run, set on the model
    /// and handed to the planner, the controllers and the simulator.
    pub gravity: f64,
}

impl Default for ScenarioSection {
    fn default() -> Self {
        Self {
            name: "scenario".into(),
            description: String::new(),
            duration: 20.0,
            control_mode: ControlMode::Position,
            plant: PlantKind::Simulator,
            gravity: stride_model::STANDARD_GRAVITY,
        }
    }
}

/// `[robot]`: the model and how the runner names its parts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RobotSection {
    /// URDF path, relative to the file that sets this key; `${NAME}` is replaced by the environment
    /// variable `NAME` (an unset variable is a configuration error), e.g.
    /// `"${STRIDE_ICUB_MODELS_DIR}/iCubGazeboV2_7/model.urdf"` for a model that is not in the repository.
    pub urdf: PathBuf,
    /// Frame at the centre of the left sole (z up, x forward): a frame of the model, or one attached to a
    /// link (`{ parent, xyz, rpy }`, added to the model as `left_sole`).
    pub left_sole: SoleFrame,
    /// Frame at the centre of the right sole (added as `right_sole` when attached).
    pub right_sole: SoleFrame,
    /// Frame whose tilt is checked for falls (torso or base link), held upright by the walking preset's
    /// `torso` tasks.
    pub torso_frame: String,
    /// Floating-base frame held upright by the walking preset's `pelvis` tasks (none: the model's root
    /// link).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub base_frame: Option<String>,
    /// Initial joint positions [rad or m] by joint name; joints not listed start at 0. Also the posture of
    /// the walking preset. Replaced whole by a file that writes it (not merged with the default).
    pub initial_joint_positions: BTreeMap<String, f64>,
    /// Locked joints: joint name or glob (`*`, `?`) → position [rad or m]. The model every layer and the
    /// simulator use is reduced: each locked joint becomes a fixed joint at its position
    /// (`stride_model::Model::from_urdf_file_reduced`).
    pub locked_joints: BTreeMap<String, f64>,
    /// Effort limits [N·m or N] by joint name or glob (`*`, `?`), replacing the URDF's `effort` in the model
    /// every layer and the plant use (the TSID's torque bounds, stride-sim's and MuJoCo's saturation), for
    /// a URDF whose `effort` is a placeholder (an entry that matches no joint is an error).
    pub effort_limits: BTreeMap<String, f64>,
    /// Velocity limits [rad/s or m/s] by joint name or glob, replacing the URDF's `velocity` the same way
    /// (the QP-IK's and TSID's joint velocity limits).
    pub velocity_limits: BTreeMap<String, f64>,
}

impl Default for RobotSection {
    fn default() -> Self {
        Self {
            urdf: PathBuf::from("../models/stride_humanoid.urdf"),
            left_sole: SoleFrame::from(stride_model::bundled::LEFT_SOLE),
            right_sole: SoleFrame::from(stride_model::bundled::RIGHT_SOLE),
            torso_frame: stride_model::bundled::TORSO.into(),
            base_frame: None,
            initial_joint_positions: stride_wbc::bundled_posture(),
            locked_joints: BTreeMap::new(),
            effort_limits: BTreeMap::new(),
            velocity_limits: BTreeMap::new(),
        }
    }
}

/// When the planner runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum PlannerMode {
    /// On a new goal and at merge points of the current plan.
    #[default]
    Event,
    /// At `rates.planner_hz`, plus on a new goal.
    Periodic,
}

/// `[rates]`: the multi-rate schedule. Every rate must divide `base_hz` exactly, and `base_hz` must divide
/// 1 000 000 000 so the base period is an integer number of nanoseconds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RatesSection {
    /// Base clock rate \[Hz\]; every other rate divides it.
    pub base_hz: u32,
    /// Planner scheduling.
    pub planner_mode: PlannerMode,
    /// Planner rate \[Hz\] when `planner_mode = "periodic"`.
    pub planner_hz: u32,
    /// Simplified-model layer rate \[Hz\].
    pub simplified_hz: u32,
    /// Whole-body layer rate \[Hz\].
    pub wbc_hz: u32,
    /// Simulator (plant) rate \[Hz\].
    pub sim_hz: u32,
}

impl Default for RatesSection {
    fn default() -> Self {
        Self {
            base_hz: 4000,
            planner_mode: PlannerMode::Event,
            planner_hz: 10,
            simplified_hz: 100,
            wbc_hz: 500,
            sim_hz: 4000,
        }
    }
}

/// A planar pose goal.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct PlanarPose {
    /// x \[m\] in the world frame.
    pub x: f64,
    /// y \[m\] in the world frame.
    pub y: f64,
    /// Heading \[deg\] about world z.
    pub heading_deg: f64,
}

/// One segment of a velocity command schedule.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct VelocitySegment {
    /// Start time of this segment \[s\]; segments are sorted by start.
    pub start: f64,
    /// Forward speed [m/s] (in the robot's heading frame).
    pub forward: f64,
    /// Lateral speed [m/s].
    pub lateral: f64,
    /// Yaw rate [deg/s].
    pub yaw_rate_deg: f64,
}

/// `[goal]`: where the robot should go. Exactly one of the sub-tables.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum Goal {
    /// `[goal.pose]`: walk to a planar pose and stop.
    Pose(PlanarPose),
    /// `[goal.waypoints]`: walk through planar poses in order, stop at the last.
    Waypoints {
        /// The poses.
        points: Vec<PlanarPose>,
    },
    /// `[goal.velocity]`: follow a velocity command over time.
    Velocity {
        /// The schedule.
        segments: Vec<VelocitySegment>,
    },
    /// `[goal.stand]`: stand still (push tests).
    Stand {},
}

impl Default for Goal {
    fn default() -> Self {
        Goal::Pose(PlanarPose {
            x: 2.0,
            y: 0.0,
            heading_deg: 0.0,
        })
    }
}

/// MCAP chunk compression.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Compression {
    /// zstd (smallest files).
    #[default]
    Zstd,
    /// lz4 (fastest).
    Lz4,
    /// No compression.
    None,
}

/// `[log]`: the MCAP log.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LogSection {
    /// Write a log at all.
    pub enabled: bool,
    /// Output path (relative to the working directory); empty = `<scenario.name>.mcap`. `--output` wins.
    pub path: PathBuf,
    /// Rate of `/tf`, `/sim/state` and `/sensors/*` \[Hz\]; must divide `rates.sim_hz`.
    pub state_hz: u32,
    /// Chunk compression.
    pub compression: Compression,
    /// Target chunk size \[bytes\] before compression.
    pub chunk_size: u64,
    /// Messages the loop may queue ahead of the writer thread before it waits.
    pub queue_capacity: usize,
}

impl Default for LogSection {
    fn default() -> Self {
        Self {
            enabled: true,
            path: PathBuf::new(),
            state_hz: 100,
            compression: Compression::Zstd,
            chunk_size: crate::log::DEFAULT_CHUNK_BYTES,
            queue_capacity: 1024,
        }
    }
}

/// `[end]`: when a run stops before its duration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EndSection {
    /// Fall when the base height drops below this fraction of its initial height [-], in (0, 1).
    pub fall_height_fraction: f64,
    /// Fall when the torso tilts more than this from vertical \[deg\].
    pub fall_tilt_deg: f64,
    /// Stop when the goal is reached and the robot stands still.
    pub stop_at_goal: bool,
    /// Goal reached: planar distance from the goal \[m\].
    pub goal_position_tolerance: f64,
    /// Goal reached: heading error \[deg\].
    pub goal_heading_tolerance_deg: f64,
    /// Standing still: CoM speed below this [m/s] ...
    pub standstill_speed: f64,
    /// ... for this long \[s\].
    pub standstill_time: f64,
}

impl Default for EndSection {
    fn default() -> Self {
        Self {
            fall_height_fraction: 0.8,
            fall_tilt_deg: 20.0,
            stop_at_goal: true,
            goal_position_tolerance: 0.1,
            goal_heading_tolerance_deg: 10.0,
            standstill_speed: 0.01,
            standstill_time: 0.5,
        }
    }
}

/// A whole scenario. The file may also hold `include = [...]` (see [`load`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct ScenarioConfig {
    /// What this run is.
    pub scenario: ScenarioSection,
    /// The robot model.
    pub robot: RobotSection,
    /// The schedule.
    pub rates: RatesSection,
    /// The goal.
    pub goal: Goal,
    /// Planner parameters (`stride_planner::PlannerConfig`).
    pub planner: stride_planner::PlannerConfig,
    /// Simplified-model layer parameters (`stride_simplified::SimplifiedConfig`).
    pub simplified: stride_simplified::SimplifiedConfig,
    /// Whole-body layer parameters.
    pub wbc: WbcSection,
    /// Simulator parameters (`stride_sim::SimConfig`), pushes included (`[[sim.pushes]]`).
    pub sim: stride_sim::SimConfig,
    /// The estimation layer.
    pub estimation: EstimationSection,
    /// The MuJoCo plant's contact and solver parameters (`scenario.plant = "mujoco"`).
    pub mujoco: mujoco::MujocoSection,
    /// The log.
    pub log: LogSection,
    /// Run endings.
    pub end: EndSection,
    /// Joint sinusoids played instead of the whole-body command (calibration and identification runs).
    pub joint_trajectory: crate::joint_trajectory::JointTrajectorySection,
}

/// Sections that choose one alternative (`[goal.pose]`, `[goal.stand]`, ...): not pre-filled from the
/// defaults, so writing another alternative replaces the default one instead of merging with it.
/// `robot.initial_joint_positions` is the bundled humanoid's posture by default and names its joints: a
/// file that writes the table replaces it whole.
const EXCLUSIVE_SECTIONS: &[&str] = &["goal", "robot.initial_joint_positions"];

/// Replaces every `${NAME}` in `text` by the value `lookup(NAME)` (the process environment for
/// `robot.urdf`). `$` not followed by `{` is kept as written. Errors (as a message for
/// [`ConfigError::Invalid`]): an unset or empty variable, an unterminated `${`, or an empty or invalid name
/// (names are ASCII letters, digits and `_`).
pub fn expand_env_vars(
    text: &str,
    lookup: impl Fn(&str) -> Option<String>,
) -> Result<String, String> {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find("${") {
        out.push_str(&rest[..start]);
        let after = &rest[start + 2..];
        let end = after
            .find('}')
            .ok_or_else(|| format!("unterminated `${{` in \"{text}\"; expected `${{NAME}}`"))?;
        let name = &after[..end];
        if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
            return Err(format!(
                "`${{{name}}}` in \"{text}\" is not a valid environment variable name (letters, digits, `_`)"
            ));
        }
        match lookup(name) {
            Some(v) if !v.is_empty() => out.push_str(&v),
            _ => {
                return Err(format!(
                    "environment variable `{name}` (used in \"{text}\") is not set; set it (e.g. `export \
                     {name}=...`) or write the path without it"
                ))
            }
        }
        rest = &after[end + 1..];
    }
    out.push_str(rest);
    Ok(out)
}

impl ScenarioConfig {
    /// The estimation layer's configuration ([`EstimationSection::estimator_config`]) with the robot's
    /// frames, the planner's sole size, the ground of `estimation.sole_sink` and TSID-Flex's flexible
    /// joints as the passive ones.
    pub fn estimator_config(&self) -> stride_estimation::EstimatorConfig {
        let ground = match self.estimation.sole_sink {
            SoleSinkSource::None => [0.0; 2],
            SoleSinkSource::ControllerGround => {
                let g = &self.wbc.tsid.compliant;
                [g.ground_stiffness, g.ground_damping]
            }
        };
        stride_estimation::EstimatorConfig {
            passive_joints: self.wbc.tsid.flexible_joints.clone(),
            ..self.estimation.estimator_config(
                &self.robot,
                &self.sim.sensors.imu_frame,
                [self.planner.foot_length, self.planner.foot_width],
                ground,
            )
        }
    }
}

/// A loaded, validated scenario with its sources (for error locations and relative paths).
#[derive(Debug, Clone)]
pub struct Scenario {
    /// The configuration.
    pub config: ScenarioConfig,
    /// Where each key came from.
    pub sources: SourceMap,
    /// The merged document (stored in logs).
    pub merged: toml::Table,
    /// Resolved URDF path.
    pub urdf_path: PathBuf,
    /// Resolved `sim.model.urdf` (the plant's own URDF), if set.
    pub plant_urdf_path: Option<PathBuf>,
}

/// The path `written` at `key` with `${NAME}` expanded, relative to the file that sets the key (the
/// top-level scenario file when only the built-in defaults do).
fn resolve_path(sources: &SourceMap, key: &str, written: &str) -> Result<PathBuf, ConfigError> {
    let dir = sources.value_dir(key).unwrap_or_else(|| {
        sources
            .files
            .last()
            .filter(|f| f.path != Path::new(load::DEFAULTS_PATH))
            .and_then(|f| f.path.parent().map(Path::to_path_buf))
            .unwrap_or_default()
    });
    let expanded =
        expand_env_vars(written, |name| std::env::var(name).ok()).map_err(|message| {
            ConfigError::Invalid {
                location: sources.value_location(key),
                key: key.into(),
                message,
            }
        })?;
    let expanded = PathBuf::from(expanded);
    Ok(if expanded.is_absolute() {
        expanded
    } else {
        dir.join(&expanded)
    })
}

impl Scenario {
    /// Reads, merges, deserializes and validates a scenario file.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let loaded: Loaded<ScenarioConfig> = load::load(path, EXCLUSIVE_SECTIONS)?;
        Self::from_loaded(loaded)
    }

    /// Parses a scenario from in-memory texts (merge order), e.g. the config stored in a log.
    pub fn from_texts(files: Vec<(PathBuf, String)>) -> Result<Self, ConfigError> {
        let files = files
            .into_iter()
            .map(|(path, text)| SourceFile {
                path,
                text,
                offset: 0,
            })
            .collect();
        Self::from_loaded(load::load_files(files, EXCLUSIVE_SECTIONS)?)
    }

    fn from_loaded(loaded: Loaded<ScenarioConfig>) -> Result<Self, ConfigError> {
        let Loaded {
            value,
            sources,
            merged,
        } = loaded;
        let written = value.robot.urdf.to_string_lossy().into_owned();
        let urdf_path = resolve_path(&sources, "robot.urdf", &written)?;
        let plant_urdf_path = match &value.sim.model.urdf {
            Some(p) => Some(resolve_path(
                &sources,
                "sim.model.urdf",
                &p.to_string_lossy(),
            )?),
            None => None,
        };
        let mut merged = merged;
        if written.contains('$') {
            // Store the resolved path in the merged document (what logs keep), so a log replays without the
            // environment variables of the machine that wrote it.
            if let Some(toml::Value::Table(r)) = merged.get_mut("robot") {
                r.insert(
                    "urdf".into(),
                    toml::Value::String(urdf_path.to_string_lossy().into_owned()),
                );
            }
        }
        let mut value = value;
        for (sole, default) in [
            (&mut value.robot.left_sole, "left_sole"),
            (&mut value.robot.right_sole, "right_sole"),
        ] {
            if let SoleFrame::Attached(a) = sole {
                if a.name.is_empty() {
                    a.name = default.to_string();
                }
            }
        }
        let scenario = Self {
            config: value,
            sources,
            merged,
            urdf_path,
            plant_urdf_path,
        };
        scenario.validate()?;
        Ok(scenario)
    }

    /// An error about `key`, located where it was written; when no file writes it (the value is a
    /// built-in default), without a location and the message says so.
    pub fn invalid(&self, key: &str, message: impl Into<String>) -> ConfigError {
        let location = self.sources.value_location(key);
        let mut message = message.into();
        if location.is_none() {
            message.push_str(" (the value is a built-in default: no file sets this key)");
        }
        ConfigError::Invalid {
            location,
            key: key.into(),
            message,
        }
    }

    /// A layer's validation error, located at the key its `InvalidParameter` names: `name` is a path
    /// inside `section` (`feet_distance_max`, `dcm_pi.gain`) or the leaf of one; the section when the
    /// error names no parameter or no written key matches.
    fn layer_invalid(&self, section: &str, name: Option<&str>, message: String) -> ConfigError {
        let key = name.map_or_else(|| section.to_string(), |n| self.layer_key(section, n));
        self.invalid(&key, message)
    }

    /// The dotted key of parameter `name` of the layer configured in `section`.
    fn layer_key(&self, section: &str, name: &str) -> String {
        let full = format!("{section}.{name}");
        if self.sources.key_location(&full).is_some() {
            return full;
        }
        let leaf = format!(".{name}");
        self.sources
            .key_spans
            .iter()
            .map(|(k, _)| k)
            .find(|k| k.starts_with(section) && k.ends_with(&leaf))
            .cloned()
            .unwrap_or(full)
    }

    /// `Ok` when `v` is finite and > 0; else an error at `key` with the unit.
    fn positive(&self, key: &str, v: f64, unit: &str) -> Result<(), ConfigError> {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(self.invalid(
                key,
                format!("{v} is not allowed; expected a finite number > 0 {unit}"),
            ))
        }
    }

    /// `Ok` when `lo ≤ v ≤ hi`; else an error at `key` with the unit.
    fn within(
        &self,
        key: &str,
        v: f64,
        (lo, hi): (f64, f64),
        unit: &str,
    ) -> Result<(), ConfigError> {
        if v.is_finite() && v >= lo && v <= hi {
            Ok(())
        } else {
            Err(self.invalid(
                key,
                format!("{v} is out of range; expected {lo} ≤ value ≤ {hi} {unit}"),
            ))
        }
    }

    /// Range, rate and consistency checks that serde cannot express.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let c = &self.config;
        self.positive("scenario.duration", c.scenario.duration, "[s]")?;
        self.within(
            "scenario.duration",
            c.scenario.duration,
            (0.0, 3600.0),
            "[s]",
        )?;
        self.positive("scenario.gravity", c.scenario.gravity, "[m/s²]")?;
        self.validate_rates()?;
        self.validate_goal()?;
        self.validate_end()?;
        for (name, q) in &c.robot.initial_joint_positions {
            if !q.is_finite() {
                return Err(self.invalid(
                    &format!("robot.initial_joint_positions.{name}"),
                    format!("{q}: expected a finite joint position [rad or m]"),
                ));
            }
        }
        self.validate_soles()?;
        self.validate_plant()?;
        self.validate_layers()
    }

    /// Attached sole frames: finite placements, distinct names.
    fn validate_soles(&self) -> Result<(), ConfigError> {
        let r = &self.config.robot;
        for (side, sole) in [("left", &r.left_sole), ("right", &r.right_sole)] {
            if let Some(a) = sole.attached() {
                let key = format!("robot.{side}_sole");
                if !a.xyz.iter().chain(&a.rpy).all(|v| v.is_finite()) {
                    return Err(self.invalid(&key, "expected finite `xyz` [m] and `rpy` [rad]"));
                }
            }
        }
        if r.left_sole.name() == r.right_sole.name() {
            return Err(self.invalid(
                "robot.right_sole",
                format!(
                    "the same frame `{}` as robot.left_sole; expected one frame per foot",
                    r.left_sole.name()
                ),
            ));
        }
        Ok(())
    }

    /// `[estimation]` against the plant, and `[sim.model]`'s scales.
    fn validate_plant(&self) -> Result<(), ConfigError> {
        let c = &self.config;
        if c.scenario.plant == PlantKind::Mujoco && !c.robot.locked_joints.is_empty() {
            return Err(self.invalid(
                "robot.locked_joints",
                "the MuJoCo plant compiles the URDF itself and does not lock joints; expected no \
                 locked joints with `scenario.plant = \"mujoco\"` (or the simulator plant)",
            ));
        }
        if c.scenario.plant != PlantKind::Simulator && !c.sim.passive_joints.is_empty() {
            return Err(self.invalid(
                "sim.passive_joints",
                "passive visco-elastic joints are modelled by stride-sim only; expected no passive \
                 joints unless `scenario.plant = \"simulator\"`",
            ));
        }
        if c.scenario.plant == PlantKind::Ideal && c.estimation.kind != EstimationKind::GroundTruth
        {
            return Err(self.invalid(
                "estimation.kind",
                "the ideal plant has no IMU and no force/torque sensors to estimate from; expected \
                 `ground_truth` with `scenario.plant = \"ideal\"`",
            ));
        }
        self.within(
            "estimation.measured_zmp_cutoff",
            c.estimation.measured_zmp_cutoff,
            (0.0, 1000.0),
            "Hz",
        )?;
        self.positive("sim.model.mass_scale", c.sim.model.mass_scale, "")?;
        for (link, change) in &c.sim.model.links {
            let key = format!("sim.model.links.{link}");
            self.positive(&format!("{key}.mass_scale"), change.mass_scale, "")?;
            if !change.com_offset.iter().all(|v| v.is_finite()) {
                return Err(
                    self.invalid(&format!("{key}.com_offset"), "expected finite numbers [m]")
                );
            }
        }
        Ok(())
    }

    /// `[rates]` and `[log]`: every rate divides the base rate, the base period is whole nanoseconds.
    fn validate_rates(&self) -> Result<(), ConfigError> {
        let c = &self.config;
        let r = &c.rates;
        if r.base_hz == 0 || 1_000_000_000 % r.base_hz != 0 {
            return Err(self.invalid(
                "rates.base_hz",
                format!(
                    "{} Hz gives a base period that is not a whole number of nanoseconds; expected a rate \
                     that divides 1 000 000 000 (e.g. 1000, 2000, 4000, 5000, 8000, 10000) [Hz]",
                    r.base_hz
                ),
            ));
        }
        let divides = |key: &str, hz: u32, base: u32, base_key: &str| -> Result<(), ConfigError> {
            if hz == 0 || base % hz != 0 {
                let divisors: Vec<String> = (1..=base)
                    .filter(|d| base % d == 0 && *d >= base / 100)
                    .map(|d| d.to_string())
                    .collect();
                Err(self.invalid(
                    key,
                    format!(
                        "{hz} Hz does not divide {base_key} = {base} Hz exactly; expected one of its divisors \
                         (e.g. {}) [Hz]",
                        divisors.join(", ")
                    ),
                ))
            } else {
                Ok(())
            }
        };
        divides("rates.sim_hz", r.sim_hz, r.base_hz, "rates.base_hz")?;
        divides("rates.wbc_hz", r.wbc_hz, r.base_hz, "rates.base_hz")?;
        divides(
            "rates.simplified_hz",
            r.simplified_hz,
            r.base_hz,
            "rates.base_hz",
        )?;
        if r.planner_mode == PlannerMode::Periodic {
            divides("rates.planner_hz", r.planner_hz, r.base_hz, "rates.base_hz")?;
        }
        if r.wbc_hz > r.sim_hz {
            return Err(self.invalid(
                "rates.wbc_hz",
                format!(
                    "{} Hz is faster than the simulator ({} Hz); expected wbc_hz ≤ sim_hz",
                    r.wbc_hz, r.sim_hz
                ),
            ));
        }
        if r.simplified_hz > r.wbc_hz {
            return Err(self.invalid(
                "rates.simplified_hz",
                format!(
                    "{} Hz is faster than the whole-body layer ({} Hz); expected simplified_hz ≤ wbc_hz",
                    r.simplified_hz, r.wbc_hz
                ),
            ));
        }
        if c.log.enabled {
            divides("log.state_hz", c.log.state_hz, r.sim_hz, "rates.sim_hz")?;
        }
        if c.log.queue_capacity == 0 {
            return Err(self.invalid(
                "log.queue_capacity",
                "0 is not allowed; expected ≥ 1 [messages]",
            ));
        }

        Ok(())
    }

    /// `[goal]`: finite poses, sorted velocity segments.
    fn validate_goal(&self) -> Result<(), ConfigError> {
        let c = &self.config;
        match &c.goal {
            Goal::Pose(p) => self.check_pose("goal.pose", p)?,
            Goal::Waypoints { points } => {
                if points.is_empty() {
                    return Err(
                        self.invalid("goal.waypoints.points", "empty; expected at least one pose")
                    );
                }
                for (i, p) in points.iter().enumerate() {
                    self.check_pose(&format!("goal.waypoints.points[{i}]"), p)?;
                }
            }
            Goal::Velocity { segments } => {
                let mut last = f64::NEG_INFINITY;
                for (i, s) in segments.iter().enumerate() {
                    let k = format!("goal.velocity.segments[{i}]");
                    for (name, v) in [
                        ("start", s.start),
                        ("forward", s.forward),
                        ("lateral", s.lateral),
                        ("yaw_rate_deg", s.yaw_rate_deg),
                    ] {
                        if !v.is_finite() {
                            return Err(self.invalid(
                                &format!("{k}.{name}"),
                                format!("{v}: expected a finite number"),
                            ));
                        }
                    }
                    if s.start < last {
                        return Err(self.invalid(
                            &format!("{k}.start"),
                            "segments must be sorted by start time [s]",
                        ));
                    }
                    last = s.start;
                }
            }
            Goal::Stand {} => {}
        }

        Ok(())
    }

    /// `[end]`: fall and goal criteria.
    fn validate_end(&self) -> Result<(), ConfigError> {
        let c = &self.config;
        let e = &c.end;
        if !(e.fall_height_fraction > 0.0 && e.fall_height_fraction < 1.0) {
            return Err(self.invalid(
                "end.fall_height_fraction",
                format!(
                    "{} is out of range; expected 0 < value < 1 [-]",
                    e.fall_height_fraction
                ),
            ));
        }
        self.within("end.fall_tilt_deg", e.fall_tilt_deg, (1.0, 90.0), "[deg]")?;
        self.positive(
            "end.goal_position_tolerance",
            e.goal_position_tolerance,
            "[m]",
        )?;
        self.positive(
            "end.goal_heading_tolerance_deg",
            e.goal_heading_tolerance_deg,
            "[deg]",
        )?;
        self.positive("end.standstill_speed", e.standstill_speed, "[m/s]")?;
        self.positive("end.standstill_time", e.standstill_time, "[s]")?;
        Ok(())
    }

    /// The layers' own checks, located at the key their `InvalidParameter` names.
    fn validate_layers(&self) -> Result<(), ConfigError> {
        let c = &self.config;
        c.planner.validate().map_err(|e| {
            let name = match &e {
                stride_planner::PlannerError::InvalidParameter { name, .. } => Some(*name),
                _ => None,
            };
            self.layer_invalid("planner", name, e.to_string())
        })?;
        c.simplified.validate().map_err(|e| {
            let name = match &e {
                stride_simplified::SimplifiedError::InvalidParameter { name, .. } => Some(*name),
                _ => None,
            };
            self.layer_invalid("simplified", name, e.to_string())
        })?;
        if c.estimation.sole_sink == SoleSinkSource::ControllerGround
            && c.wbc.tsid.contact_model != stride_wbc::ContactModel::Compliant
        {
            return Err(self.invalid(
                "estimation.sole_sink",
                "\"controller_ground\" needs the compliant TSID ([wbc.tsid] contact_model = \"compliant\"), whose ground it reads",
            ));
        }
        c.estimator_config().validate().map_err(|e| {
            let name = match &e {
                stride_estimation::EstimatorError::InvalidParameter { name, .. } => Some(*name),
                _ => None,
            };
            self.layer_invalid("estimation", name, e.to_string())
        })?;
        c.sim.validate().map_err(|e| {
            let name = match &e {
                stride_sim::SimError::InvalidConfig { parameter, .. } => Some(parameter.as_str()),
                _ => None,
            };
            self.layer_invalid("sim", name, e.to_string())
        })?;
        Ok(())
    }

    fn check_pose(&self, key: &str, p: &PlanarPose) -> Result<(), ConfigError> {
        for (name, v) in [("x", p.x), ("y", p.y), ("heading_deg", p.heading_deg)] {
            if !v.is_finite() {
                return Err(self.invalid(
                    &format!("{key}.{name}"),
                    format!("{v}: expected a finite number"),
                ));
            }
        }
        Ok(())
    }

    /// The simulator's step period, `1 / rates.sim_hz` (a whole number of nanoseconds: validated).
    pub fn sim_period(&self) -> std::time::Duration {
        std::time::Duration::from_nanos(1_000_000_000 / u64::from(self.config.rates.sim_hz))
    }

    /// The merged configuration as TOML text (what logs store).
    pub fn merged_toml(&self) -> String {
        toml::to_string(&self.merged).unwrap_or_default()
    }
}
