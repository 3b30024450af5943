//! Plain-data configuration of the simulated robot ([`SimConfig`]) and its validation.
//!
//! Every struct deserialises with `#[serde(deny_unknown_fields)]` and every field has a default, so a TOML
//! section may name only what it changes. The defaults describe the bundled humanoid
//! (`models/stride_humanoid.urdf`, 32.8 kg, 0.20 m × 0.09 m soles) standing on a rigid floor.

use serde::{Deserialize, Serialize};

use crate::error::SimError;

/// Configuration of [`crate::SimRobot`]. The step period is an argument of [`crate::SimRobot::new`] and
/// gravity is the model's ([`stride_model::Model::gravity`]).
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `integrator` | – | `implicit` | [`IntegratorKind`] |
/// | `momentum_projection` | – | `false` | correct the base velocity so that the centroidal momentum balance holds exactly each step |
/// | `fixed_base` | – | `false` | hold the base where it starts, as a robot hung on a pole: the base acceleration and velocity are zero, the joints move under the fixed-base dynamics (implicit integrator only) |
/// | `ground` | – | flat floor at z = 0 | [`GroundConfig`] |
/// | `contact` | – | rigid floor, the humanoid's two soles | [`ContactConfig`] |
/// | `actuation` | – | position servos on every joint, 0.1 N·m Coulomb friction, 2-step command delay | [`ActuationConfig`] |
/// | `passive_joints` | – | none | passive visco-elastic joints, no motor: [`crate::PassiveJointConfig`] list |
/// | `joint_stops` | – | off | mechanical end stops at the URDF position limits: [`crate::JointStopsConfig`] |
/// | `sensors` | – | iCub-class encoders, IMU on `imu_frame` and force/torque sensors, 2-step delay | [`SensorConfig`] |
/// | `pushes` | – | none | [`PushConfig`] list |
/// | `fall` | – | base below 0.25 m or tilted beyond 1 rad | [`FallConfig`] |
/// | `safety` | – | see [`SafetyConfig`] | divergence thresholds |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SimConfig {
    /// Time-stepping scheme. Default [`IntegratorKind::Implicit`].
    pub integrator: IntegratorKind,
    /// After each step, correct the base velocity so that the centroidal momentum changes by exactly
    /// `dt ×` the step's external wrench (gravity, contacts, pushes; torque about the CoM at the start of the
    /// step). Makes free-flight momentum exact at any rate. Default `false`.
    pub momentum_projection: bool,
    /// Hold the base at its initial pose (a robot on a pole, for identification and calibration runs): the
    /// base rows of the step are replaced by `ν̇_b = 0` and the base velocity is kept at zero, so the joints
    /// follow the fixed-base dynamics `M_ss q̈ + h_s = τ + Σ J_sᵀ w`. Implicit integrator only; the
    /// momentum projection is skipped. Default `false`.
    pub fixed_base: bool,
    /// The ground plane.
    pub ground: GroundConfig,
    /// Contact surfaces and the contact law.
    pub contact: ContactConfig,
    /// Joint actuation (servo modes, gains, limits, passive damping).
    pub actuation: ActuationConfig,
    /// Passive visco-elastic joints `τ = −k q − b q̇`, no motor: their commands are discarded.
    pub passive_joints: Vec<crate::PassiveJointConfig>,
    /// Mechanical end stops at the joints' URDF position limits (off by default).
    pub joint_stops: crate::JointStopsConfig,
    /// Sensors and their noise.
    pub sensors: SensorConfig,
    /// Scheduled external wrenches ("pushes").
    pub pushes: Vec<PushConfig>,
    /// Fall detection thresholds.
    pub fall: FallConfig,
    /// Divergence detection thresholds.
    pub safety: SafetyConfig,
    /// The plant's own model when it differs from the controllers' (model mismatch). The simulator is
    /// built from a model; this section only says which: the runner reads it and loads that model.
    pub model: PlantModelConfig,
}

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            integrator: IntegratorKind::Implicit,
            momentum_projection: false,
            fixed_base: false,
            ground: GroundConfig::default(),
            contact: ContactConfig::default(),
            actuation: ActuationConfig::default(),
            passive_joints: Vec::new(),
            joint_stops: crate::JointStopsConfig::default(),
            sensors: SensorConfig::default(),
            pushes: Vec::new(),
            fall: FallConfig::default(),
            safety: SafetyConfig::default(),
            model: PlantModelConfig::default(),
        }
    }
}

/// `[sim.model]`: how the simulated plant differs from the model the controllers use (`robot.urdf`).
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `urdf` | – | the robot's | the plant's own URDF (relative to the scenario file that sets it) |
/// | `mass_scale` | – | 1 | scales every link's mass and rotational inertia |
/// | `links.<link>.mass_scale` | – | 1 | scales that link's mass and inertia (after `mass_scale`) |
/// | `links.<link>.com_offset` | m | `[0, 0, 0]` | moves that link's centre of mass, link frame |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlantModelConfig {
    /// The plant's URDF; `None` = the robot's.
    pub urdf: Option<std::path::PathBuf>,
    /// Scale of every link's mass and inertia (1 = as in the URDF).
    pub mass_scale: f64,
    /// Per-link changes, by URDF link name.
    pub links: std::collections::BTreeMap<String, LinkInertiaChange>,
}

/// One link's change in [`PlantModelConfig::links`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LinkInertiaChange {
    /// Scale of the link's mass and inertia.
    pub mass_scale: f64,
    /// Offset of the link's centre of mass, link frame, m.
    pub com_offset: [f64; 3],
}

impl Default for LinkInertiaChange {
    fn default() -> Self {
        Self {
            mass_scale: 1.0,
            com_offset: [0.0; 3],
        }
    }
}

impl Default for PlantModelConfig {
    fn default() -> Self {
        Self {
            urdf: None,
            mass_scale: 1.0,
            links: std::collections::BTreeMap::new(),
        }
    }
}

/// How one step advances the state.
///
/// Both are semi-implicit Euler schemes (velocity first, then the configuration with the new velocity; the base
/// orientation on SO(3)). They differ in how stiff forces are evaluated:
///
/// * `implicit` (default): the position servos, the passive joint damping and the contact spring-dampers are
///   evaluated at the end of the step, linearised (`f(q + dt ν⁺, ν⁺)`), which adds `dt·D + dt²·K` terms to the
///   mass matrix: `(M + dt Kd + dt² Kp + Σ Jᵀ(dt D + dt² K)J) ν̇ = …`. Solved with the composite-rigid-body mass
///   matrix and a Cholesky factorisation. Stable for stiff servos and a rigid floor at 1–5 kHz.
/// * `explicit`: every force is evaluated at the start of the step and the articulated-body algorithm gives ν̇.
///   Cheaper per step, but needs soft gains or a high rate; kept as an independent cross-check.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IntegratorKind {
    /// Linearly implicit servos and contacts (CRBA + Cholesky).
    Implicit,
    /// Explicit forces, articulated-body algorithm.
    Explicit,
}

/// The flat ground: a plane through `[0, 0, height]` whose normal is `R_x(roll) R_y(pitch) e_z`.
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `height` | m | 0 | height of the plane at the world origin |
/// | `inclination` | rad | `[0, 0]` | `[roll, pitch]` of the plane; a positive pitch makes the ground descend along +x |
/// | `patches` | – | none | [`GroundPatchConfig`] list: strips of ground with their own normal (and optionally tangential) stiffness and damping |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GroundConfig {
    /// Height of the plane at the world origin, m.
    pub height: f64,
    /// `[roll, pitch]` of the plane, rad.
    pub inclination: [f64; 2],
    /// Strips `x_min ≤ x < x_max` (world) whose normal stiffness and damping densities replace
    /// [`ContactConfig::normal_stiffness`] and [`ContactConfig::normal_damping`], and their tangential ones,
    /// when given, the [`ContactConfig`] tangential ones (they must not overlap).
    pub patches: Vec<GroundPatchConfig>,
}

impl Default for GroundConfig {
    fn default() -> Self {
        Self {
            height: 0.0,
            inclination: [0.0, 0.0],
            patches: Vec::new(),
        }
    }
}

/// A strip of ground `x_min ≤ x < x_max` (world x of the contact point) with its own law: a contact point
/// over the strip carries the densities below instead of the [`ContactConfig`] ones (the tangential ones only
/// when given; the friction stays the [`ContactConfig`] one). For ground whose compliance changes along the
/// path (the anisotropic ground of [Romualdi 2022, §8.3.3]).
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `x_min`, `x_max` | m | – (required) | extent along world x, `x_min < x_max` |
/// | `normal_stiffness` | N/m³ | – (required) | `k` over the strip (> 0) |
/// | `normal_damping` | N·s/m³ | – (required) | `b` over the strip (≥ 0) |
/// | `tangential_stiffness` | N/m³ | [`ContactConfig::tangential_stiffness`] | stick-spring stiffness density over the strip (> 0: the slip law divides by it) |
/// | `tangential_damping` | N·s/m³ | [`ContactConfig::tangential_damping`] | stick-spring damping density over the strip (≥ 0) |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GroundPatchConfig {
    /// Start of the strip along world x (included), m.
    pub x_min: f64,
    /// End of the strip along world x (excluded), m.
    pub x_max: f64,
    /// Normal stiffness density `k`, N/m³.
    pub normal_stiffness: f64,
    /// Normal damping density `b`, N·s/m³.
    pub normal_damping: f64,
    /// Tangential (stick) stiffness density, N/m³ (`None`: the [`ContactConfig`] one).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tangential_stiffness: Option<f64>,
    /// Tangential (stick) damping density, N·s/m³ (`None`: the [`ContactConfig`] one).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tangential_damping: Option<f64>,
}

impl GroundPatchConfig {
    /// The strip `x_min ≤ x < x_max` with normal densities `normal_stiffness`, `normal_damping` and the
    /// floor's tangential ones.
    pub fn normal(x_min: f64, x_max: f64, normal_stiffness: f64, normal_damping: f64) -> Self {
        Self {
            x_min,
            x_max,
            normal_stiffness,
            normal_damping,
            tangential_stiffness: None,
            tangential_damping: None,
        }
    }
}

/// The compliant contact law and the surfaces of the robot that touch the ground.
///
/// Each surface is a rectangle sampled by a grid of points. The parameters are **area densities** of the
/// visco-elastic contact model `ρ = k(x̄ − x) − b ẋ` [Romualdi 2022, Lemma 1]: a grid point carries the
/// stiffness `k · l · w · weight` and the damping `b · l · w · weight`, where the weights are the
/// trapezoidal-rule weights of the grid (they sum to one). So the total normal stiffness of a flat surface is
/// `k l w` whatever the grid, and a fine grid converges to the lemma's wrench. Normal forces never pull;
/// tangential forces follow Coulomb's law with a stick-slip spring anchored where the point touched down.
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `normal_stiffness` | N/m³ | 3e8 | `k` (a hard floor under a rubber sole, `k ≈ E/h`: 0.03 mm static sink for the 32.8 kg humanoid on both feet; each 0.20 × 0.09 m sole resists pitching with 27 kN·m/rad; docs/sim.md) |
/// | `normal_damping` | N·s/m³ | 9.5e5 | `b` (about critical for the humanoid bouncing on both feet) |
/// | `tangential_stiffness` | N/m³ | 3e8 | stiffness density of the stick spring |
/// | `tangential_damping` | N·s/m³ | 9.5e5 | damping density of the stick spring |
/// | `friction_coefficient` | – | 0.8 | Coulomb μ (static = kinetic) |
/// | `surfaces` | – | `l_sole`, `r_sole` | [`ContactSurfaceConfig`] list |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ContactConfig {
    /// Normal stiffness density `k`, N/m³.
    pub normal_stiffness: f64,
    /// Normal damping density `b`, N·s/m³.
    pub normal_damping: f64,
    /// Tangential (stick) stiffness density, N/m³.
    pub tangential_stiffness: f64,
    /// Tangential (stick) damping density, N·s/m³.
    pub tangential_damping: f64,
    /// Coulomb friction coefficient μ (≥ 0).
    pub friction_coefficient: f64,
    /// The contact surfaces.
    pub surfaces: Vec<ContactSurfaceConfig>,
}

impl Default for ContactConfig {
    fn default() -> Self {
        Self {
            normal_stiffness: 3.0e8,
            normal_damping: 9.5e5,
            tangential_stiffness: 3.0e8,
            tangential_damping: 9.5e5,
            friction_coefficient: 0.8,
            surfaces: vec![
                ContactSurfaceConfig::foot("left", "l_sole", "l_foot_ft_sensor"),
                ContactSurfaceConfig::foot("right", "r_sole", "r_foot_ft_sensor"),
            ],
        }
    }
}

/// A rectangular contact surface rigidly attached to a frame of the model.
///
/// The rectangle lies in the frame's x-y plane, centred at `offset` (frame coordinates), `length` along the
/// frame's x axis and `width` along y; it is sampled by `grid[0] × grid[1]` points that include the corners.
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `name` | – | – | name used in outputs and errors |
/// | `frame` | – | – | model frame the surface is attached to (e.g. `l_sole`) |
/// | `length`, `width` | m | 0.20, 0.09 | rectangle size along the frame's x and y |
/// | `grid` | – | `[3, 3]` | points along x and y (each ≥ 2) |
/// | `offset` | m | `[0, 0, 0]` | rectangle centre in the frame |
/// | `ft_sensor` | – | none | frame in which the surface's measured wrench is expressed (e.g. `l_foot_ft_sensor`) |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSurfaceConfig {
    /// Name used in outputs and errors.
    pub name: String,
    /// Model frame the surface is attached to.
    pub frame: String,
    /// Size along the frame's x axis, m.
    #[serde(default = "default_length")]
    pub length: f64,
    /// Size along the frame's y axis, m.
    #[serde(default = "default_width")]
    pub width: f64,
    /// Number of grid points along x and y (each ≥ 2, corners included).
    #[serde(default = "default_grid")]
    pub grid: [usize; 2],
    /// Centre of the rectangle in the frame, m.
    #[serde(default)]
    pub offset: [f64; 3],
    /// Frame of the six-axis force/torque sensor that measures this surface's wrench (optional).
    #[serde(default)]
    pub ft_sensor: Option<String>,
}

fn default_length() -> f64 {
    0.20
}
fn default_width() -> f64 {
    0.09
}
fn default_grid() -> [usize; 2] {
    [3, 3]
}

impl ContactSurfaceConfig {
    /// A sole of the bundled humanoid (0.20 m × 0.09 m, 3 × 3 points) with its force/torque sensor.
    pub fn foot(name: &str, frame: &str, ft_sensor: &str) -> Self {
        Self {
            name: name.to_string(),
            frame: frame.to_string(),
            length: default_length(),
            width: default_width(),
            grid: default_grid(),
            offset: [0.0; 3],
            ft_sensor: Some(ft_sensor.to_string()),
        }
    }
}

/// How a joint is driven.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ActuationMode {
    /// PD servo on the commanded position and velocity plus the feed-forward torque:
    /// `τ = kp (q_ref − q) + kd (q̇_ref − q̇) + τ_ff` (a robot's motor board in position mode).
    Position,
    /// Velocity servo: `τ = kd (q̇_ref − q̇) + τ_ff` (the position command is ignored).
    Velocity,
    /// Torque: `τ = τ_ff` (position and velocity commands are ignored).
    Torque,
}

/// What to do when a joint's motor torque exceeds its effort limit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EffortLimitPolicy {
    /// Saturate the torque at the limit and report the joint in the output (like a motor driver).
    Saturate,
    /// Fail the step with [`SimError::EffortLimit`] (only for a commanded feed-forward torque beyond the limit;
    /// servo torques are always saturated).
    Error,
}

/// Joint actuation: a default actuator for every joint and per-joint overrides.
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `default` | – | position servo, kp 1000 N·m/rad, kd 60 N·m·s/rad | [`JointActuatorConfig`] of every joint |
/// | `joints` | – | none | [`JointActuatorOverride`] list by joint name |
/// | `effort_limit_policy` | – | `saturate` | [`EffortLimitPolicy`] |
/// | `command_delay_steps` | steps | 2 | every command reaches the motors this many simulator steps late (0 = none; 1 ms at 2 kHz) |
///
/// [`ActuationConfig::ideal`] gives the same servos with no friction, no torque lag and no command delay.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ActuationConfig {
    /// Actuator of every joint not overridden.
    pub default: JointActuatorConfig,
    /// Per-joint overrides (applied in order).
    pub joints: Vec<JointActuatorOverride>,
    /// Behaviour at the effort limit.
    pub effort_limit_policy: EffortLimitPolicy,
    /// Command latency in simulator steps: the commands of a step are applied this many steps later (0 =
    /// none; until then the motors hold the initial joint positions).
    pub command_delay_steps: usize,
}

impl Default for ActuationConfig {
    fn default() -> Self {
        Self {
            default: JointActuatorConfig::default(),
            joints: Vec::new(),
            effort_limit_policy: EffortLimitPolicy::Saturate,
            command_delay_steps: 2,
        }
    }
}

impl ActuationConfig {
    /// The default servos with ideal actuators: no Coulomb friction, ideal torque tracking, no command delay.
    pub fn ideal() -> Self {
        Self {
            default: JointActuatorConfig::ideal(),
            command_delay_steps: 0,
            ..Self::default()
        }
    }
}

/// One joint's actuator and passive dynamics.
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `mode` | – | `position` | [`ActuationMode`] |
/// | `kp` | N·m/rad (N/m) | 1000 | position gain |
/// | `kd` | N·m·s/rad (N·s/m) | 60 | velocity gain (position and velocity modes) |
/// | `effort_limit` | N·m (N) | model's limit | motor torque bound; `None` uses the URDF `effort` (unbounded if absent) |
/// | `damping` | N·m·s/rad | 0 | passive viscous joint damping (not limited by the effort limit) |
/// | `armature` | kg·m² | 0 | reflected rotor inertia added to the joint's diagonal of the mass matrix |
/// | `coulomb_friction` | N·m (N) | 0.1 | joint Coulomb friction `τ_c`: the joint sticks while the other torques on it stay within `±τ_c`, else it slides against `∓τ_c` (implicit law, see `docs/sim.md`) |
/// | `torque_bandwidth` | Hz | 30 | torque mode: first-order lag `f` of the motor torque on the command (time constant `1/(2π f)`); 0 = ideal |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct JointActuatorConfig {
    /// Servo mode.
    pub mode: ActuationMode,
    /// Position gain (N/m for prismatic joints), N·m/rad.
    pub kp: f64,
    /// Velocity gain (N·s/m for prismatic joints), N·m·s/rad.
    pub kd: f64,
    /// Motor torque bound (`None`: the model's effort limit).
    pub effort_limit: Option<f64>,
    /// Passive viscous joint damping, N·m·s/rad.
    pub damping: f64,
    /// Reflected rotor inertia added to the joint's diagonal of the mass matrix, kg·m².
    pub armature: f64,
    /// Joint Coulomb friction torque (N for prismatic joints), N·m.
    pub coulomb_friction: f64,
    /// Torque-mode tracking bandwidth (first-order lag of the motor torque on the command), Hz; 0 = ideal.
    pub torque_bandwidth: f64,
}

impl Default for JointActuatorConfig {
    fn default() -> Self {
        Self {
            mode: ActuationMode::Position,
            kp: 1000.0,
            kd: 60.0,
            effort_limit: None,
            damping: 0.0,
            armature: 0.0,
            coulomb_friction: 0.1,
            torque_bandwidth: 30.0,
        }
    }
}

impl JointActuatorConfig {
    /// The default servo with no Coulomb friction and ideal torque tracking.
    pub fn ideal() -> Self {
        Self {
            coulomb_friction: 0.0,
            torque_bandwidth: 0.0,
            ..Self::default()
        }
    }
}

/// Override of some fields of one joint's actuator (unset fields keep the default actuator's value).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointActuatorOverride {
    /// Joint name (must exist in the model).
    pub name: String,
    /// Servo mode.
    #[serde(default)]
    pub mode: Option<ActuationMode>,
    /// Position gain.
    #[serde(default)]
    pub kp: Option<f64>,
    /// Velocity gain.
    #[serde(default)]
    pub kd: Option<f64>,
    /// Motor torque bound.
    #[serde(default)]
    pub effort_limit: Option<f64>,
    /// Passive viscous damping.
    #[serde(default)]
    pub damping: Option<f64>,
    /// Reflected rotor inertia.
    #[serde(default)]
    pub armature: Option<f64>,
    /// Coulomb friction torque.
    #[serde(default)]
    pub coulomb_friction: Option<f64>,
    /// Torque-mode tracking bandwidth.
    #[serde(default)]
    pub torque_bandwidth: Option<f64>,
}

/// Sensors: what the robot's own sensors report (the ground truth in [`crate::SimOutput::state`] is never
/// altered). The defaults model an iCub-class robot (sources in `docs/sim.md`, "Sensors");
/// [`SensorConfig::ideal`] gives exact, undelayed sensors.
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `imu_frame` | – | `imu_frame` | frame of the IMU; if absent from the model, the root link |
/// | `seed` | – | 0 | seed of the one ChaCha8 generator every sensor draws from (a run is reproducible from it) |
/// | `delay_steps` | steps | 2 | every sensor reading is reported this many simulator steps late (0 = none; 1 ms at 2 kHz) |
/// | `encoder` | – | 4096 counts/rev, velocity differenced and low-passed at 10 Hz | [`EncoderConfig`] |
/// | `imu` | – | Xsens MTi-1 class | [`ImuConfig`] |
/// | `ft` | – | iCub-class six-axis sensors | [`FtSensorConfig`] |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SensorConfig {
    /// IMU frame name (falls back to the root link when the model has no frame of that name).
    pub imu_frame: String,
    /// Seed of the ChaCha8 generator of every sensor's noise, offsets and biases.
    pub seed: u64,
    /// Sensor latency in simulator steps: encoders, IMU and force/torque readings are reported this many steps
    /// after they were taken (0 = none).
    pub delay_steps: usize,
    /// Joint encoders.
    pub encoder: EncoderConfig,
    /// Inertial measurement unit.
    pub imu: ImuConfig,
    /// Six-axis force/torque sensors (the model's, at their URDF frames).
    pub ft: FtSensorConfig,
}

impl Default for SensorConfig {
    fn default() -> Self {
        Self {
            imu_frame: "imu_frame".to_string(),
            seed: 0,
            delay_steps: 2,
            encoder: EncoderConfig::default(),
            imu: ImuConfig::default(),
            ft: FtSensorConfig::default(),
        }
    }
}

impl SensorConfig {
    /// Exact sensors: no noise, offset, bias, drift, quantisation, filter, saturation or delay (the joint
    /// velocity is the true one). For tests that compare the readings with the physics.
    pub fn ideal() -> Self {
        Self {
            imu_frame: "imu_frame".to_string(),
            seed: 0,
            delay_steps: 0,
            encoder: EncoderConfig::ideal(),
            imu: ImuConfig::ideal(),
            ft: FtSensorConfig::ideal(),
        }
    }
}

/// How the encoders report joint velocities.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VelocitySource {
    /// Finite difference of the reported (quantised) positions over one step, then a first-order low-pass
    /// filter `y ← y + α (x − y)`, `α = dt / (dt + 1/(2π f_c))` (as a robot's software does it).
    FilteredDifference,
    /// The true joint velocity (plus `velocity_noise`), as if a perfect velocity sensor were fitted.
    Truth,
}

/// Joint encoders. Positions are `step · round((q + n_q) / step)` with `step = 2π / counts_per_revolution`
/// (revolute joints; prismatic joints are not quantised); velocities per [`VelocitySource`], plus
/// `velocity_noise`.
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `counts_per_revolution` | counts | 4096 | resolution (12-bit absolute magnetic encoder); 0 = no quantisation |
/// | `position_noise` | rad | 0 | white noise σ added before quantisation |
/// | `velocity_source` | – | `filtered_difference` | [`VelocitySource`] |
/// | `velocity_cutoff` | Hz | 10 | cut-off `f_c` of the velocity low-pass filter (`filtered_difference`; 0 = unfiltered difference) |
/// | `velocity_noise` | rad/s | 0 | white noise σ added to the reported velocity |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EncoderConfig {
    /// Encoder resolution, counts per revolution (0 = no quantisation).
    pub counts_per_revolution: u32,
    /// White noise σ on the joint position before quantisation, rad.
    pub position_noise: f64,
    /// Where the reported joint velocity comes from.
    pub velocity_source: VelocitySource,
    /// Cut-off frequency of the first-order low-pass filter on the differenced velocity, Hz (0 = no filter).
    pub velocity_cutoff: f64,
    /// White noise σ on the reported joint velocity, rad/s.
    pub velocity_noise: f64,
}

impl Default for EncoderConfig {
    fn default() -> Self {
        Self {
            counts_per_revolution: 4096,
            position_noise: 0.0,
            velocity_source: VelocitySource::FilteredDifference,
            velocity_cutoff: 10.0,
            velocity_noise: 0.0,
        }
    }
}

impl EncoderConfig {
    /// Exact positions and velocities.
    pub fn ideal() -> Self {
        Self {
            counts_per_revolution: 0,
            position_noise: 0.0,
            velocity_source: VelocitySource::Truth,
            velocity_cutoff: 0.0,
            velocity_noise: 0.0,
        }
    }
}

/// Inertial measurement unit. Rates and accelerations are raw (`ω + b_ω + n_ω`, `a − g + b_a + n_a`, IMU frame);
/// the biases start uniformly within `±gyro_bias` / `±accel_bias` per axis and random-walk. White noise is
/// given as a density `N` and drawn per step with `σ = N / √dt`. The orientation is what an on-board filter
/// (no magnetometer) reports: `exp([δ_roll, δ_pitch, δ_yaw]^) · world_R_imu` (error about the world axes) with a
/// constant tilt error drawn within `±tilt_error`, a yaw error growing at a constant rate drawn within
/// `±yaw_drift_rate`, and white noise `orientation_noise`.
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `gyro_noise_density` | rad/s/√Hz | 1.2e-4 | gyroscope white noise (0.007 °/s/√Hz) |
/// | `gyro_bias` | rad/s | 3.5e-3 | bound of the initial gyroscope bias per axis (0.2 °/s) |
/// | `gyro_bias_random_walk` | rad/s/√s | 1e-5 | gyroscope bias random walk |
/// | `accel_noise_density` | m/s²/√Hz | 1.2e-3 | accelerometer white noise (120 µg/√Hz) |
/// | `accel_bias` | m/s² | 0.05 | bound of the initial accelerometer bias per axis (5 mg) |
/// | `accel_bias_random_walk` | m/s²/√s | 1e-4 | accelerometer bias random walk |
/// | `tilt_error` | rad | 8.7e-3 | bound of the constant roll and pitch error of the orientation (0.5°) |
/// | `yaw_drift_rate` | rad/s | 4.85e-5 | bound of the constant yaw drift rate of the orientation (10 °/h) |
/// | `orientation_noise` | rad | 1e-3 | white noise σ of the orientation (each world axis) |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ImuConfig {
    /// Gyroscope white-noise density, rad/s/√Hz (per-step σ = density / √dt).
    pub gyro_noise_density: f64,
    /// Bound of the initial gyroscope bias (uniform per axis), rad/s.
    pub gyro_bias: f64,
    /// Gyroscope bias random walk, rad/s/√s (per-step σ = value · √dt).
    pub gyro_bias_random_walk: f64,
    /// Accelerometer white-noise density, m/s²/√Hz (per-step σ = density / √dt).
    pub accel_noise_density: f64,
    /// Bound of the initial accelerometer bias (uniform per axis), m/s².
    pub accel_bias: f64,
    /// Accelerometer bias random walk, m/s²/√s (per-step σ = value · √dt).
    pub accel_bias_random_walk: f64,
    /// Bound of the constant roll and pitch error of the reported orientation (uniform), rad.
    pub tilt_error: f64,
    /// Bound of the constant yaw drift rate of the reported orientation (uniform), rad/s.
    pub yaw_drift_rate: f64,
    /// White noise σ of the reported orientation about each world axis, rad.
    pub orientation_noise: f64,
}

impl Default for ImuConfig {
    fn default() -> Self {
        Self {
            gyro_noise_density: 1.2e-4,
            gyro_bias: 3.5e-3,
            gyro_bias_random_walk: 1e-5,
            accel_noise_density: 1.2e-3,
            accel_bias: 0.05,
            accel_bias_random_walk: 1e-4,
            tilt_error: 8.7e-3,
            yaw_drift_rate: 4.85e-5,
            orientation_noise: 1e-3,
        }
    }
}

impl ImuConfig {
    /// An exact IMU.
    pub fn ideal() -> Self {
        Self {
            gyro_noise_density: 0.0,
            gyro_bias: 0.0,
            gyro_bias_random_walk: 0.0,
            accel_noise_density: 0.0,
            accel_bias: 0.0,
            accel_bias_random_walk: 0.0,
            tilt_error: 0.0,
            yaw_drift_rate: 0.0,
            orientation_noise: 0.0,
        }
    }
}

/// The six-axis force/torque sensors of the model ([`stride_model::Model::ft_sensors`]), all alike. Each reads
/// the wrench transmitted through its fixed joint, in its frame, with its measurement direction, plus a constant
/// offset drawn uniformly within `±offset` per axis at start, a random-walk drift and white noise, clamped at
/// the full scale per axis.
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `force_offset` | N | 5 | bound of the initial force offset per axis |
/// | `torque_offset` | N·m | 0.5 | bound of the initial torque offset per axis |
/// | `force_drift` | N/√s | 0.0645 | force drift random walk (0.5 N after one minute) |
/// | `torque_drift` | N·m/√s | 6.45e-3 | torque drift random walk (0.05 N·m after one minute) |
/// | `force_noise` | N | 1.5 | force white noise σ per step |
/// | `torque_noise` | N·m | 0.05 | torque white noise σ per step |
/// | `force_range` | N | `[580, 580, 1160]` | full scale per force axis (clamped); 0 = unbounded |
/// | `torque_range` | N·m | `[20, 20, 20]` | full scale per torque axis (clamped); 0 = unbounded |
/// | `calibration_error` | – | 0 | bound of the entries of `E`, uniform, in the raw output `(1 + E) w + offset + …`: the sensor's calibration matrix `C = (1 + E)⁻¹` is that far from identity [Traversaro 2017, eq. (5.1)]; drawn per sensor after the other start-up errors, only when > 0; below 1/6 |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FtSensorConfig {
    /// Bound of the initial force offset (uniform per axis), N.
    pub force_offset: f64,
    /// Bound of the initial torque offset (uniform per axis), N·m.
    pub torque_offset: f64,
    /// Force drift random walk, N/√s (per-step σ = value · √dt).
    pub force_drift: f64,
    /// Torque drift random walk, N·m/√s (per-step σ = value · √dt).
    pub torque_drift: f64,
    /// Force white noise σ per step, N.
    pub force_noise: f64,
    /// Torque white noise σ per step, N·m.
    pub torque_noise: f64,
    /// Full scale of each force axis (the reading is clamped to ±range; 0 = unbounded), N.
    pub force_range: [f64; 3],
    /// Full scale of each torque axis (the reading is clamped to ±range; 0 = unbounded), N·m.
    pub torque_range: [f64; 3],
    /// Bound of the entries of the calibration error `E` (uniform per entry): the raw output is
    /// `(1 + E) w + offset + drift + noise`, i.e. `w = C (r − b)` with `C = (1 + E)⁻¹` (5.1). 0 (default):
    /// exact gains, nothing drawn. Must be below 1/6 so that `1 + E` is invertible.
    pub calibration_error: f64,
}

impl Default for FtSensorConfig {
    fn default() -> Self {
        Self {
            force_offset: 5.0,
            torque_offset: 0.5,
            force_drift: 0.0645,
            torque_drift: 6.45e-3,
            force_noise: 1.5,
            torque_noise: 0.05,
            force_range: [580.0, 580.0, 1160.0],
            torque_range: [20.0, 20.0, 20.0],
            calibration_error: 0.0,
        }
    }
}

impl FtSensorConfig {
    /// Exact, unbounded sensors.
    pub fn ideal() -> Self {
        Self {
            force_offset: 0.0,
            torque_offset: 0.0,
            force_drift: 0.0,
            torque_drift: 0.0,
            force_noise: 0.0,
            torque_noise: 0.0,
            force_range: [0.0; 3],
            torque_range: [0.0; 3],
            calibration_error: 0.0,
        }
    }
}

/// An external wrench applied on a frame of the robot during a time window.
///
/// | field | unit | meaning |
/// |---|---|---|
/// | `frame` | – | model frame the wrench is applied at |
/// | `start` | s | simulated time at which the push starts |
/// | `duration` | s | how long it lasts |
/// | `wrench` | N, N·m | `[fx, fy, fz, τx, τy, τz]` applied on the robot, world orientation, torque about the frame origin |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PushConfig {
    /// Model frame the wrench acts at.
    pub frame: String,
    /// Start time, s.
    pub start: f64,
    /// Duration, s.
    pub duration: f64,
    /// `[force; torque]` on the robot, world orientation, torque about the frame origin.
    pub wrench: [f64; 6],
}

/// Fall detection. A fall is reported (and latched until reset) when the root link origin is closer to the
/// ground plane than `min_base_height` or its z axis is tilted from the ground normal by more than `max_tilt`.
///
/// | field | unit | default |
/// |---|---|---|
/// | `min_base_height` | m | 0.25 |
/// | `max_tilt` | rad | 1.0 |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FallConfig {
    /// Minimum height of the root link origin above the ground plane, m.
    pub min_base_height: f64,
    /// Maximum angle between the root link z axis and the ground normal, rad.
    pub max_tilt: f64,
}

impl Default for FallConfig {
    fn default() -> Self {
        Self {
            min_base_height: 0.25,
            max_tilt: 1.0,
        }
    }
}

/// Divergence detection: a step whose result exceeds one of these bounds fails with
/// [`SimError::Diverged`] and the state before the step is kept.
///
/// | field | unit | default |
/// |---|---|---|
/// | `max_joint_velocity` | rad/s (m/s) | 200 |
/// | `max_base_velocity` | m/s, rad/s | 100 |
/// | `max_penetration` | m | 0.1 |
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SafetyConfig {
    /// Largest joint speed (m/s for prismatic joints), rad/s.
    pub max_joint_velocity: f64,
    /// Largest base linear or angular speed, m/s or rad/s.
    pub max_base_velocity: f64,
    /// Largest penetration of a contact point into the ground, m.
    pub max_penetration: f64,
}

impl Default for SafetyConfig {
    fn default() -> Self {
        Self {
            max_joint_velocity: 200.0,
            max_base_velocity: 100.0,
            max_penetration: 0.1,
        }
    }
}

fn check(ok: bool, parameter: &str, message: &str) -> Result<(), SimError> {
    if ok {
        Ok(())
    } else {
        Err(SimError::InvalidConfig {
            parameter: parameter.to_string(),
            message: message.to_string(),
        })
    }
}

/// Largest sensor or command delay, simulator steps (the ring buffers are allocated at construction).
pub(crate) const MAX_DELAY_STEPS: usize = 10_000;

fn finite_nonneg(x: f64) -> bool {
    x.is_finite() && x >= 0.0
}

impl SimConfig {
    /// Checks the values that do not need the model (ranges, finiteness).
    pub fn validate(&self) -> Result<(), SimError> {
        check(
            !self.fixed_base || self.integrator == IntegratorKind::Implicit,
            "fixed_base",
            "needs integrator = \"implicit\"",
        )?;
        check(
            self.sensors.ft.calibration_error < 1.0 / 6.0,
            "sensors.ft.calibration_error",
            "must be below 1/6 (the raw gains 1 + E must stay invertible)",
        )?;
        self.validate_ground_and_contact()?;
        self.validate_actuation()?;
        self.joint_stops.validate()?;
        check(
            !self.joint_stops.enabled || self.integrator == IntegratorKind::Implicit,
            "joint_stops.enabled",
            "needs integrator = \"implicit\" (a stiff stop on a light link is unstable explicitly)",
        )?;
        self.validate_sensors_and_pushes()?;
        self.validate_fall_and_safety()
    }

    /// The ground plane, the contact law and the surfaces.
    fn validate_ground_and_contact(&self) -> Result<(), SimError> {
        check(
            self.ground.height.is_finite(),
            "ground.height",
            "must be finite",
        )?;
        check(
            self.ground
                .inclination
                .iter()
                .all(|a| a.is_finite() && a.abs() < std::f64::consts::FRAC_PI_2),
            "ground.inclination",
            "angles must be finite and within (-90°, 90°)",
        )?;
        self.validate_patches()?;
        let c = &self.contact;
        check(
            c.normal_stiffness.is_finite() && c.normal_stiffness > 0.0,
            "contact.normal_stiffness",
            "must be > 0",
        )?;
        check(
            finite_nonneg(c.normal_damping),
            "contact.normal_damping",
            "must be ≥ 0",
        )?;
        check(
            c.tangential_stiffness.is_finite() && c.tangential_stiffness > 0.0,
            "contact.tangential_stiffness",
            "must be > 0",
        )?;
        check(
            finite_nonneg(c.tangential_damping),
            "contact.tangential_damping",
            "must be ≥ 0",
        )?;
        check(
            finite_nonneg(c.friction_coefficient),
            "contact.friction_coefficient",
            "must be ≥ 0",
        )?;
        for s in &c.surfaces {
            let p = format!("contact.surfaces[{}]", s.name);
            check(
                s.length.is_finite() && s.length >= 0.0,
                &p,
                "length must be ≥ 0",
            )?;
            check(
                s.width.is_finite() && s.width >= 0.0,
                &p,
                "width must be ≥ 0",
            )?;
            check(
                s.grid[0] >= 1 && s.grid[1] >= 1,
                &p,
                "grid must have at least one point per axis",
            )?;
            check(
                s.grid[0] * s.grid[1] <= 10_000,
                &p,
                "at most 10000 points per surface",
            )?;
            check(
                s.offset.iter().all(|x| x.is_finite()),
                &p,
                "offset must be finite",
            )?;
        }
        Ok(())
    }

    /// The ground patches: finite extents with `x_min < x_max`, positive stiffnesses, non-negative dampings
    /// (normal, and tangential when given), no two overlapping.
    fn validate_patches(&self) -> Result<(), SimError> {
        let patches = &self.ground.patches;
        for (i, p) in patches.iter().enumerate() {
            let name = format!("ground.patches[{i}]");
            check(
                p.x_min.is_finite() && p.x_max.is_finite() && p.x_min < p.x_max,
                &name,
                "x_min and x_max must be finite with x_min < x_max",
            )?;
            check(
                p.normal_stiffness.is_finite() && p.normal_stiffness > 0.0,
                &format!("{name}.normal_stiffness"),
                "must be > 0",
            )?;
            check(
                finite_nonneg(p.normal_damping),
                &format!("{name}.normal_damping"),
                "must be ≥ 0",
            )?;
            if let Some(k) = p.tangential_stiffness {
                check(
                    k.is_finite() && k > 0.0,
                    &format!("{name}.tangential_stiffness"),
                    "must be > 0",
                )?;
            }
            if let Some(b) = p.tangential_damping {
                check(
                    finite_nonneg(b),
                    &format!("{name}.tangential_damping"),
                    "must be ≥ 0",
                )?;
            }
            for (j, q) in patches.iter().enumerate().take(i) {
                check(
                    p.x_max <= q.x_min || q.x_max <= p.x_min,
                    &name,
                    &format!("overlaps ground.patches[{j}]"),
                )?;
            }
        }
        Ok(())
    }

    /// The default actuator and the per-joint overrides.
    fn validate_actuation(&self) -> Result<(), SimError> {
        let a = &self.actuation;
        check_actuator(&a.default, "actuation.default")?;
        for (i, p) in self.passive_joints.iter().enumerate() {
            p.validate(&format!("passive_joints[{i}]"))?;
        }
        for j in &a.joints {
            let p = format!("actuation.joints[{}]", j.name);
            for (v, n) in [
                (j.kp, "kp"),
                (j.kd, "kd"),
                (j.damping, "damping"),
                (j.armature, "armature"),
                (j.coulomb_friction, "coulomb_friction"),
                (j.torque_bandwidth, "torque_bandwidth"),
            ] {
                if let Some(v) = v {
                    check(
                        finite_nonneg(v),
                        &format!("{p}.{n}"),
                        "must be finite and ≥ 0",
                    )?;
                }
            }
            if let Some(e) = j.effort_limit {
                check(
                    e > 0.0 && !e.is_nan(),
                    &format!("{p}.effort_limit"),
                    "must be > 0",
                )?;
            }
        }
        Ok(())
    }

    /// Sensor parameters, delays and pushes.
    fn validate_sensors_and_pushes(&self) -> Result<(), SimError> {
        let sensors = &self.sensors;
        let (e, imu, ft) = (&sensors.encoder, &sensors.imu, &sensors.ft);
        for (v, name) in [
            (e.position_noise, "encoder.position_noise"),
            (e.velocity_cutoff, "encoder.velocity_cutoff"),
            (e.velocity_noise, "encoder.velocity_noise"),
            (imu.gyro_noise_density, "imu.gyro_noise_density"),
            (imu.gyro_bias, "imu.gyro_bias"),
            (imu.gyro_bias_random_walk, "imu.gyro_bias_random_walk"),
            (imu.accel_noise_density, "imu.accel_noise_density"),
            (imu.accel_bias, "imu.accel_bias"),
            (imu.accel_bias_random_walk, "imu.accel_bias_random_walk"),
            (imu.tilt_error, "imu.tilt_error"),
            (imu.yaw_drift_rate, "imu.yaw_drift_rate"),
            (imu.orientation_noise, "imu.orientation_noise"),
            (ft.force_offset, "ft.force_offset"),
            (ft.torque_offset, "ft.torque_offset"),
            (ft.force_drift, "ft.force_drift"),
            (ft.torque_drift, "ft.torque_drift"),
            (ft.force_noise, "ft.force_noise"),
            (ft.torque_noise, "ft.torque_noise"),
            (ft.calibration_error, "ft.calibration_error"),
        ]
        .into_iter()
        .chain(ft.force_range.iter().map(|r| (*r, "ft.force_range")))
        .chain(ft.torque_range.iter().map(|r| (*r, "ft.torque_range")))
        {
            check(
                finite_nonneg(v),
                &format!("sensors.{name}"),
                "must be finite and ≥ 0",
            )?;
        }
        for (steps, name) in [
            (sensors.delay_steps, "sensors.delay_steps"),
            (
                self.actuation.command_delay_steps,
                "actuation.command_delay_steps",
            ),
        ] {
            check(steps <= MAX_DELAY_STEPS, name, "at most 10000 steps")?;
        }
        for (i, p) in self.pushes.iter().enumerate() {
            let name = format!("pushes[{i}]");
            check(
                p.start.is_finite() && p.start >= 0.0,
                &name,
                "start must be ≥ 0",
            )?;
            check(finite_nonneg(p.duration), &name, "duration must be ≥ 0")?;
            check(
                p.wrench.iter().all(|w| w.is_finite()),
                &name,
                "wrench must be finite",
            )?;
        }
        Ok(())
    }

    /// Fall detection and divergence thresholds.
    fn validate_fall_and_safety(&self) -> Result<(), SimError> {
        check(
            self.fall.min_base_height.is_finite(),
            "fall.min_base_height",
            "must be finite",
        )?;
        check(
            self.fall.max_tilt.is_finite() && self.fall.max_tilt > 0.0,
            "fall.max_tilt",
            "must be > 0",
        )?;
        let s = &self.safety;
        check(
            s.max_joint_velocity > 0.0,
            "safety.max_joint_velocity",
            "must be > 0",
        )?;
        check(
            s.max_base_velocity > 0.0,
            "safety.max_base_velocity",
            "must be > 0",
        )?;
        check(
            s.max_penetration > 0.0,
            "safety.max_penetration",
            "must be > 0",
        )?;
        Ok(())
    }
}

fn check_actuator(a: &JointActuatorConfig, p: &str) -> Result<(), SimError> {
    check(
        finite_nonneg(a.kp),
        &format!("{p}.kp"),
        "must be finite and ≥ 0",
    )?;
    check(
        finite_nonneg(a.kd),
        &format!("{p}.kd"),
        "must be finite and ≥ 0",
    )?;
    check(
        finite_nonneg(a.damping),
        &format!("{p}.damping"),
        "must be finite and ≥ 0",
    )?;
    check(
        finite_nonneg(a.armature),
        &format!("{p}.armature"),
        "must be finite and ≥ 0",
    )?;
    check(
        finite_nonneg(a.coulomb_friction),
        &format!("{p}.coulomb_friction"),
        "must be finite and ≥ 0",
    )?;
    check(
        finite_nonneg(a.torque_bandwidth),
        &format!("{p}.torque_bandwidth"),
        "must be finite and ≥ 0",
    )?;
    if let Some(e) = a.effort_limit {
        check(
            e > 0.0 && !e.is_nan(),
            &format!("{p}.effort_limit"),
            "must be > 0",
        )?;
    }
    Ok(())
}
