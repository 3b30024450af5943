//! The key reference of scenario files (docs/configuration.md), generated from the code.
//!
//! Every key of the default [`super::ScenarioConfig`] (serialized) is listed with its TOML type and
//! default. Keys of the runner's own sections carry unit and meaning from [`RUNNER_KEYS`]; keys of the
//! embedded layer configurations take their meaning from the layer crates' field documentation (looked
//! up by the caller, see the `configuration_reference` test, which regenerates the file and fails when
//! docs/configuration.md differs). A key in the code without a description, or a description without a
//! key, fails the test too.

use std::collections::BTreeMap;

/// Unit and meaning of a runner-owned key.
#[derive(Debug, Clone, Copy)]
pub struct KeyDoc {
    /// Dotted key.
    pub key: &'static str,
    /// Unit (`-` when none).
    pub unit: &'static str,
    /// Meaning, with allowed values or ranges.
    pub meaning: &'static str,
}

/// Keys that may be absent from the default configuration (optional or alternative shapes).
pub const OPTIONAL_KEYS: &[KeyDoc] = &[
    KeyDoc { key: "include", unit: "-", meaning: "Files merged before this one (paths relative to this file), in order; later files and this file override earlier ones (tables merge key by key, other values are replaced)." },
    KeyDoc { key: "sim.passive_joints[].joints", unit: "-", meaning: "`[[sim.passive_joints]]`: joints with no motor that are springs `τ = −k q − b q̇` in stride-sim (commands discarded); each joint in one entry (docs/flexible-joints.md)." },
    KeyDoc { key: "sim.passive_joints[].stiffness", unit: "N·m/rad", meaning: "The entry's stiffness `k` (> 0)." },
    KeyDoc { key: "sim.passive_joints[].damping", unit: "N·m·s/rad", meaning: "The entry's damping `b` (≥ 0); absent: `2√k` [Romualdi 2022, §9.4]." },
    KeyDoc { key: "sim.passive_joints[].encoder", unit: "-", meaning: "The joints have encoders (default `false`: they read 0 and the deflection is unmeasured; TSID-Flex then estimates it)." },
    KeyDoc { key: "goal.waypoints.points[].x", unit: "m", meaning: "`[goal.waypoints]`: waypoint x; `[[goal.waypoints.points]]` entries are visited in order, the robot stops at the last." },
    KeyDoc { key: "goal.waypoints.points[].y", unit: "m", meaning: "Waypoint y." },
    KeyDoc { key: "goal.waypoints.points[].heading_deg", unit: "deg", meaning: "Waypoint heading about world z." },
    KeyDoc { key: "goal.velocity.segments[].start", unit: "s", meaning: "`[goal.velocity]`: start of a velocity-command segment (sorted); each segment replans at its start." },
    KeyDoc { key: "goal.velocity.segments[].forward", unit: "m/s", meaning: "Forward speed of the segment." },
    KeyDoc { key: "goal.velocity.segments[].lateral", unit: "m/s", meaning: "Lateral speed of the segment." },
    KeyDoc { key: "goal.velocity.segments[].yaw_rate_deg", unit: "deg/s", meaning: "Yaw rate of the segment." },
    KeyDoc { key: "goal.stand", unit: "-", meaning: "`[goal.stand]` (empty table): stand still (push scenarios)." },
    KeyDoc { key: "sim.ground.patches[].x_min", unit: "m", meaning: "`[[sim.ground.patches]]`: start of a strip of ground along world x (included); a contact point over the strip uses its normal law (and its tangential one when given). Patches must not overlap." },
    KeyDoc { key: "sim.ground.patches[].x_max", unit: "m", meaning: "End of the strip along world x (excluded), > `x_min`." },
    KeyDoc { key: "sim.ground.patches[].normal_stiffness", unit: "N/m³", meaning: "Normal stiffness density `k` over the strip (> 0), replacing `sim.contact.normal_stiffness` there." },
    KeyDoc { key: "sim.ground.patches[].normal_damping", unit: "N·s/m³", meaning: "Normal damping density `b` over the strip (≥ 0), replacing `sim.contact.normal_damping` there." },
    KeyDoc { key: "sim.ground.patches[].tangential_stiffness", unit: "N/m³", meaning: "Optional: tangential (stick-spring) stiffness density over the strip (> 0), replacing `sim.contact.tangential_stiffness` there (absent: that one)." },
    KeyDoc { key: "sim.ground.patches[].tangential_damping", unit: "N·s/m³", meaning: "Optional: tangential (stick-spring) damping density over the strip (≥ 0), replacing `sim.contact.tangential_damping` there (absent: that one)." },
    KeyDoc { key: "robot.left_sole.parent", unit: "-", meaning: "`robot.left_sole = { parent = \"<link>\", xyz = [..], rpy = [..] }` instead of a frame name: a sole frame the URDF lacks, added to the model on this frame (usually the foot link); `stride model feet <URDF>` proposes it." },
    KeyDoc { key: "robot.left_sole.xyz", unit: "m", meaning: "Origin of the added left sole frame in `parent` (default `[0, 0, 0]`)." },
    KeyDoc { key: "robot.left_sole.rpy", unit: "rad", meaning: "Roll, pitch, yaw of the added left sole frame in `parent`, URDF convention `R = Rz(y) Ry(p) Rx(r)` (default `[0, 0, 0]`); the sole frame has z up (out of the sole) and x forward." },
    KeyDoc { key: "robot.left_sole.name", unit: "-", meaning: "Name of the added frame in the model (default `left_sole`); must not be a frame the model already has." },
    KeyDoc { key: "robot.right_sole.parent", unit: "-", meaning: "As `robot.left_sole.parent`, for the right sole." },
    KeyDoc { key: "robot.right_sole.xyz", unit: "m", meaning: "As `robot.left_sole.xyz`." },
    KeyDoc { key: "robot.right_sole.rpy", unit: "rad", meaning: "As `robot.left_sole.rpy`." },
    KeyDoc { key: "robot.right_sole.name", unit: "-", meaning: "Name of the added frame (default `right_sole`)." },
    KeyDoc { key: "robot.base_frame", unit: "-", meaning: "Floating-base frame the walking preset's `pelvis` tasks hold upright (absent: the model's root link)." },
    KeyDoc { key: "mujoco.solref", unit: "s, -", meaning: "MuJoCo plant only (docs/mujoco.md): `[time constant, damping ratio]` of the floor–sole contact constraint; the time constant ≥ 2 plant periods, the ratio > 0. Absent: derived from `sim.contact.normal_stiffness`/`normal_damping`, the soles' area (`sim.contact.surfaces`) and the robot's mass so that both plants give the robot standing on its soles the same vertical frequency and damping ratio (`stride_runner::config::mujoco::ground_solref`; the default floor under the bundled humanoid: `[0.0019, 0.91]`)." },
    KeyDoc { key: "sim.actuation.default.effort_limit", unit: "N·m (N)", meaning: "Motor torque bound of every joint not overridden (absent: each joint's URDF `effort`, unbounded if the URDF has none); at the bound the torque saturates (`effort_limit_policy`). Per joint: `[[sim.actuation.joints]]` `effort_limit`." },
];

/// TOML type of an [`OPTIONAL_KEYS`] entry.
fn optional_key_type(key: &str) -> &'static str {
    let array = ["include", "mujoco.solref"].contains(&key);
    if array || key.ends_with(".xyz") || key.ends_with(".rpy") {
        "array"
    } else if key == "goal.stand" {
        "table"
    } else if key.ends_with(".parent") || key.ends_with(".name") || key == "robot.base_frame" {
        "string"
    } else {
        "float"
    }
}

/// Runner-owned keys present in the default configuration.
pub const RUNNER_KEYS: &[KeyDoc] = &[
    KeyDoc { key: "scenario.name", unit: "-", meaning: "Short name; the default log file is `<name>.mcap`." },
    KeyDoc { key: "joint_trajectory.enabled", unit: "-", meaning: "Send joint sinusoids to the position servos instead of the whole-body layer's command (the other layers still run and are logged); position control only. For calibration and identification runs, e.g. with `sim.fixed_base = true` (`configs/identify_ft_legs.toml`)." },
    KeyDoc { key: "joint_trajectory.ramp", unit: "s", meaning: "The amplitudes grow linearly from 0 over this time, ≥ 0." },
    KeyDoc { key: "estimation.ft_calibration", unit: "-", meaning: "Table force/torque sensor name → its calibration matrix `C` (6 rows of 6): the estimation layer reads each raw reading `r` of that sensor as the wrench `C (r − b)`, `b` the offset (`estimation.ft_offsets`, raw units) [Traversaro 2017, eq. (5.1)]; sensors not listed keep the identity. Unknown sensors and singular or non-finite matrices are rejected. `stride calibrate LOG LOG LOG` writes it from pole runs with added masses (docs/identification.md, \"Calibration matrix from logs\")." },
    KeyDoc { key: "joint_trajectory.joints", unit: "rad or m, s, deg", meaning: "Table joint name → `{ amplitude, period, phase_deg }`: `q(t) = q₀ + A sin(2π t / T + φ)` about the initial position (clamped to the joint limits); joints not listed hold `q₀`. Unknown joints are rejected." },
    KeyDoc { key: "scenario.description", unit: "-", meaning: "One line saying what the scenario shows." },
    KeyDoc { key: "scenario.duration", unit: "s", meaning: "Simulated duration, 0 < value ≤ 3600; the run ends here at the latest (`--duration` overrides)." },
    KeyDoc { key: "scenario.control_mode", unit: "-", meaning: "`position` (QP-IK → joint position servos) or `torque` (TSID → joint torques)." },
    KeyDoc { key: "scenario.gravity", unit: "m/s²", meaning: "Gravity acceleration along −z of the world, > 0: the run's one gravity, set on the model and handed to the planner, the controllers and the simulator." },
    KeyDoc { key: "estimation.kind", unit: "-", meaning: "`ekf` (default): the controllers read only the estimation layer's output (stride-estimation: invariant EKF, contacts and foot wrenches from the force/torque sensors). `ground_truth`: they read the simulator's truth, for debugging only (the summary says GROUND TRUTH; required with `scenario.plant = \"ideal\"`)." },
    KeyDoc { key: "estimation.update", unit: "-", meaning: "`every_sample`: the estimation layer's full tick (kinematics, foot wrenches, contacts, EKF propagation and updates, offsets, joint torques) on every plant sample. `when_read` (default since 2026-12-05): the full tick only on the ticks whose layers read the estimate (whole-body, simplified and planner ticks: 500 Hz with the default rates; the state log records the estimate they last read, so `log.state_hz` never changes the closed loop); the IMU samples in between move the EKF's mean only (pre-integration) and the next full tick propagates the covariance over the whole interval. The estimation layer's instructions fall by three quarters, the whole process's by 10–13 % on the default walks (docs/performance.md); on the default walks the base pose and velocity errors are as good or better, the detected contacts disagree with the plant's slightly more often (docs/estimation.md). An observer of flexible joints (`wbc.tsid.flexible_joints` without encoders) needs every sample: such a scenario must set `every_sample` (refused otherwise, at this key)." },
    KeyDoc { key: "estimation.joint_velocity_bandwidth", unit: "Hz", meaning: "0 (default): the joint velocities as the encoders report them (`sim.sensors.encoder.velocity_source`; the default low-passed difference lags 16 ms). > 0: the estimation layer's critically damped α–β filter of that bandwidth on the encoder positions gives them (`stride_estimation::JointVelocityFilter`, group delay 2/(2π f)), on every sample; the TSID's damping reads them. `walk_curve_fast_torque` sets 150, which takes it to its goal on hard floors and on MuJoCo; on the other torque walks it trades DCM for ZMP tracking (docs/wbc.md, \"Joint velocities\")." },
    KeyDoc { key: "estimation.joint_velocity_prediction", unit: "–", meaning: "false (default). true (torque control, `joint_velocity_bandwidth` > 0): the α–β filter predicts each sample with the joint accelerations the TSID chose at its last tick (`stride_estimation::Estimator::set_joint_accelerations`), so a low bandwidth tracks an acceleration the TSID got right without its lag 2a/ω (docs/soft-ground.md, \"Stage 3 on the estimated state\")." },
    KeyDoc { key: "estimation.stance_leg_accelerations", unit: "–", meaning: "false (default): the estimation layer's inverse dynamics (foot wrenches, joint torques) take the joint accelerations as zero, every link moving with the base. true: a foot in contact (last tick's) has its leg's six actuated joints accelerate so that its sole stays still under the base's acceleration (`stride_estimation::EstimatorConfig::stance_leg_accelerations`; TSID-Flex's `flexible_joints` stay at zero), so the deflection observer's hip torques carry the stance leg's inertia [Romualdi 2022, §9.3] (docs/flexible-joints.md, \"The 3 mm goal: where the estimate's error comes from\")." },
    KeyDoc { key: "estimation.sole_sink", unit: "–", meaning: "\"none\" (default): the EKF takes a stance sole's origin as its static contact point (a rigid ground). \"controller_ground\": the contact point is the sole's zero-force point on the compliant TSID's ground (`wbc.tsid.compliant.ground_stiffness`, `ground_damping`; needs `[wbc.tsid] contact_model = \"compliant\"`), the sole's origin less its sink under the foot's estimated force (`stride_estimation::sole_sink`; docs/estimation.md, \"A sole sinking into a compliant ground\")." },
    KeyDoc { key: "estimation.measured_zmp_cutoff", unit: "Hz", meaning: "Cut-off of the first-order low-pass filter on the measured ZMP (from the estimated foot wrenches) that the simplified layer's ZMP-CoM controller reads, applied at every simplified and whole-body tick (0: unfiltered; ≥ 0). 5 Hz walks in position control on stride-sim and MuJoCo; unfiltered, the ZMP noise reaches the joint servos through the CoM velocity reference and the position walk falls on MuJoCo (docs/estimation.md, \"The measured ZMP\")." },
    KeyDoc { key: "scenario.plant", unit: "-", meaning: "`simulator` (stride-sim), `ideal` (joint commands applied exactly, base from the fixed stance foot) or `mujoco` (MuJoCo 3.17 on the soles of the URDF, configured by the same `[sim]` section; needs a build with `--features mujoco`, see docs/mujoco.md)." },
    KeyDoc { key: "robot.urdf", unit: "-", meaning: "URDF of the robot, relative to the file that sets this key; `${NAME}` is replaced by the environment variable `NAME` (unset: a configuration error), e.g. `\"${STRIDE_ICUB_MODELS_DIR}/iCubGazeboV2_7/model.urdf\"`." },
    KeyDoc { key: "robot.left_sole", unit: "-", meaning: "Frame at the centre of the left sole, z up and x forward: a link or frame of the model, or a table `{ parent, xyz, rpy }` that adds one (see `robot.left_sole.parent`). `stride check` warns when it is not on the ground or not level in the initial posture." },
    KeyDoc { key: "robot.right_sole", unit: "-", meaning: "Frame at the centre of the right sole (a frame name or a `{ parent, xyz, rpy }` table)." },
    KeyDoc { key: "robot.torso_frame", unit: "-", meaning: "Frame whose tilt is checked for falls, measured from its orientation in the initial posture (so any frame convention works)." },
    KeyDoc { key: "robot.initial_joint_positions", unit: "rad or m", meaning: "Table joint name → initial position; joints not listed start at 0. Unknown joint names are rejected. Also the posture of the walking preset's posture tasks (`wbc.preset`). The default is the bundled humanoid's crouch; a file that writes the table replaces it whole (no merge with the default)." },
    KeyDoc { key: "robot.locked_joints", unit: "rad or m", meaning: "Table joint name or glob (`*` any run of characters, `?` one) → position: every movable joint matched is locked there, and the model every layer and the simulator use is reduced (the joint becomes fixed, its child link merged into the parent body: `stride_model::Model::from_urdf_file_reduced`, docs/model.md). An entry that matches no movable joint, a non-finite position or a joint locked at two positions is an error; locked joints cannot be named elsewhere (posture, tasks, actuators). Not with the MuJoCo plant." },
    KeyDoc { key: "robot.effort_limits", unit: "N·m or N", meaning: "Table joint name or glob (`*` any run of characters, `?` one) → effort limit, > 0: replaces the URDF's `effort` of every joint matched in the model every layer and the plant use (the TSID's torque bounds, stride-sim's and MuJoCo's saturation unless `sim.actuation` overrides it), for a URDF whose `effort` is a placeholder (the iCub's 50 000 N·m on the torso, neck and arms, docs/push-recovery.md). Entries apply in name order, so a later one wins on a joint two match. An entry that matches no joint, or a limit not positive and finite, is an error." },
    KeyDoc { key: "robot.velocity_limits", unit: "rad/s or m/s", meaning: "Table joint name or glob → velocity limit, > 0: replaces the URDF's `velocity` of every joint matched in the model every layer uses (the QP-IK's and the TSID's `joint_velocity_limits`), for a URDF whose `velocity` is a placeholder (the iCub's 50 000 rad/s on the torso, neck and arms). The same rules as `robot.effort_limits`." },
    KeyDoc { key: "wbc.preset", unit: "-", meaning: "`walking` (default): the QP-IK and TSID task lists are stride-wbc's walking presets (`stride_wbc::presets::walking_ik`, `walking_tsid`) built from `robot.left_sole`, `robot.right_sole`, `robot.torso_frame`, `robot.base_frame`, `robot.initial_joint_positions` and `[wbc.walking]`; each `[[wbc.ik.tasks]]` / `[[wbc.tsid.tasks]]` entry replaces the preset's task of the same name in place, or is added at the end (docs/wbc.md, \"Task presets\"). `none`: the written lists are the whole lists." },
    KeyDoc { key: "wbc.position_command", unit: "-", meaning: "Position control: the joint set-points between two QP-IK ticks. `hold` (default): the QP-IK's command (the positions it integrated to the end of its period) held over the period, a staircase at `rates.wbc_hz`. `interpolate`: the QP-IK's joint trajectory at the end of every plant step, `q_ref − q̇_ref (t_next − t − h)`, which removes the `kp q̇ T` sawtooth of the servo torques (`stride_runner::position_command`; docs/mujoco.md, \"The fast position walks\")." },
    KeyDoc { key: "wbc.walking.posture_joint_weights", unit: "-", meaning: "Walking preset: weights of the posture tasks' joints, by joint name or glob (`*`, `?`), matched against the model's joints (joints matched by none: 1; a glob matching no joint is ignored). Table entries merge with the default's globs (set one to 1.0 to neutralise it)." },
    KeyDoc { key: "wbc.walking.upright_offset", unit: "-", meaning: "Walking preset: `reference_offset` of the torso and pelvis orientation tasks, `none` (the frames are x forward, z up when upright) or `initial` (they keep their initial orientation relative to the upright reference; e.g. iCub)." },
    KeyDoc { key: "wbc.walking.cop_x", unit: "m", meaning: "Walking preset: `[min, max]` of the TSID contacts' CoP region along the sole frame's x (the part of the sole that stays loaded; default `stride_wbc::BUNDLED_COP_X`)." },
    KeyDoc { key: "wbc.walking.cop_y", unit: "m", meaning: "Walking preset: `[min, max]` of the CoP region along the sole frame's y (default `stride_wbc::BUNDLED_COP_Y`)." },
    KeyDoc { key: "wbc.walking.ik_without", unit: "-", meaning: "Walking preset: names of the QP-IK preset's tasks to leave out (`left_foot`, `right_foot`, `com`, `torso`, `pelvis`, `posture`, `joint_position_limits`, `joint_velocity_limits`); a name the preset lacks is an error." },
    KeyDoc { key: "wbc.walking.tsid_without", unit: "-", meaning: "Walking preset: names of the TSID preset's tasks to leave out (`dynamics`, `left_contact`, `right_contact`, `left_foot`, `right_foot`, `com`, `torso`, `pelvis`, `posture`, `wrench_regularization`, `torque_regularization`, `zmp`, `joint_torque_limits`, `joint_position_limits`, `joint_velocity_limits`)." },
    KeyDoc { key: "rates.base_hz", unit: "Hz", meaning: "Base clock rate; must divide 1 000 000 000 (integer-nanosecond period). Every other rate divides it." },
    KeyDoc { key: "rates.planner_mode", unit: "-", meaning: "`event` (plan at start and on each new goal segment) or `periodic` (also at `planner_hz`)." },
    KeyDoc { key: "rates.planner_hz", unit: "Hz", meaning: "Planner rate in `periodic` mode; divides `base_hz`." },
    KeyDoc { key: "rates.simplified_hz", unit: "Hz", meaning: "Simplified-layer rate (about 100 Hz); divides `base_hz`, ≤ `wbc_hz`." },
    KeyDoc { key: "rates.wbc_hz", unit: "Hz", meaning: "Whole-body layer rate (500–1000 Hz); divides `base_hz`, ≤ `sim_hz`. Sets the period of the QP-IK and the TSID." },
    KeyDoc { key: "rates.sim_hz", unit: "Hz", meaning: "Plant rate (2–5 kHz for the simulator); divides `base_hz`. The simulator's step period is `1 / sim_hz`." },
    KeyDoc { key: "goal.pose.x", unit: "m", meaning: "`[goal.pose]`: goal x in the world frame (the robot starts near the origin, facing +x)." },
    KeyDoc { key: "goal.pose.y", unit: "m", meaning: "Goal y." },
    KeyDoc { key: "goal.pose.heading_deg", unit: "deg", meaning: "Goal heading about world z." },
    KeyDoc { key: "mujoco.solimp", unit: "-, -, m, -, -", meaning: "MuJoCo plant: contact impedance `[d0, d_width, width, midpoint, power]`, 0 ≤ d0, d_width < 1, width > 0, 0 ≤ midpoint ≤ 1, power ≥ 1. Default MuJoCo's `[0.9, 0.95, 0.001, 0.5, 2]`." },
    KeyDoc { key: "mujoco.condim", unit: "-", meaning: "MuJoCo plant: contact dimensionality, 1 (frictionless), 3 (sliding friction, default), 4 (+ torsional) or 6 (+ rolling)." },
    KeyDoc { key: "mujoco.cone", unit: "-", meaning: "MuJoCo plant: friction cone, `pyramidal` (default) or `elliptic`." },
    KeyDoc { key: "mujoco.impratio", unit: "-", meaning: "MuJoCo plant: ratio of frictional to normal constraint impedance, ≥ 1 (default 1)." },
    KeyDoc { key: "mujoco.torsional_friction", unit: "m", meaning: "MuJoCo plant: torsional friction coefficient (used with `condim` ≥ 4), ≥ 0." },
    KeyDoc { key: "mujoco.rolling_friction", unit: "m", meaning: "MuJoCo plant: rolling friction coefficient (used with `condim` 6), ≥ 0." },
    KeyDoc { key: "mujoco.min_armature", unit: "kg·m²", meaning: "MuJoCo plant: lower bound of every joint's armature (`sim.actuation` armature if larger), ≥ 0; 0.01 keeps the stiff position servos consistent with MuJoCo's contact solver (docs/mujoco.md)." },
    KeyDoc { key: "mujoco.servo_saturation", unit: "-", meaning: "MuJoCo plant: where a position or velocity servo's effort limit is applied. `applied_force` (default): on the force the step applies with the servo's damping implicit, the step taken again with a servo beyond its limit pinned at it (stride-sim's rule; `stride_mujoco`'s `limits` module). `start_of_step`: MuJoCo's own `forcerange` clamp of the start-of-step force, which makes a clamped servo's damping explicit: on a light link (kd dt / I > 2) the torque flips between its limits at every step (docs/mujoco.md, \"Servos at their limits\")." },
    KeyDoc { key: "mujoco.joint_limits", unit: "-", meaning: "MuJoCo plant: enforce the URDF's joint position limits (stride-sim enforces none)." },
    KeyDoc { key: "log.enabled", unit: "-", meaning: "Write an MCAP log." },
    KeyDoc { key: "log.path", unit: "-", meaning: "Log path (relative to the working directory); empty: `<scenario.name>.mcap`. `--output` overrides." },
    KeyDoc { key: "log.state_hz", unit: "Hz", meaning: "Rate of `/sim/state`, `/sensors/*`, `/estimation/state`, `/tf`, `/runner/timing`; divides `rates.sim_hz`." },
    KeyDoc { key: "log.compression", unit: "-", meaning: "Chunk compression: `zstd`, `lz4` or `none`." },
    KeyDoc { key: "log.chunk_size", unit: "bytes", meaning: "Target uncompressed chunk size." },
    KeyDoc { key: "log.queue_capacity", unit: "messages", meaning: "Messages the loop may queue ahead of the writer thread (≥ 1); beyond it the loop waits (counted in the summary as writer waits). Each owns a preallocated 16 KB buffer (16 MB by default), so the loop never allocates for logging." },
    KeyDoc { key: "end.fall_height_fraction", unit: "-", meaning: "Fall when the base height drops below this fraction of its initial height; 0 < value < 1." },
    KeyDoc { key: "end.fall_tilt_deg", unit: "deg", meaning: "Fall when `robot.torso_frame` tilts more than this from its initial (upright) orientation; 1 ≤ value ≤ 90." },
    KeyDoc { key: "end.stop_at_goal", unit: "-", meaning: "End the run when the plan is finished, the goal is reached within tolerance and the CoM stands still." },
    KeyDoc { key: "end.goal_position_tolerance", unit: "m", meaning: "Goal reached: planar distance of the soles' mid-point from the goal (> 0)." },
    KeyDoc { key: "end.goal_heading_tolerance_deg", unit: "deg", meaning: "Goal reached: heading error (> 0)." },
    KeyDoc { key: "end.standstill_speed", unit: "m/s", meaning: "Standing still: planar CoM speed below this (> 0) ..." },
    KeyDoc { key: "end.standstill_time", unit: "s", meaning: "... for this long (> 0)." },
];

/// Sections embedded from layer crates: (section prefix, crate, where its docs are).
pub const LAYER_SECTIONS: &[(&str, &str)] = &[
    ("planner", "stride_planner::PlannerConfig"),
    ("simplified", "stride_simplified::SimplifiedConfig"),
    ("wbc.ik", "stride_wbc::IkConfig"),
    ("wbc.tsid", "stride_wbc::TsidConfig"),
    ("sim", "stride_sim::SimConfig"),
    ("estimation", "stride_estimation::EstimatorConfig"),
];

/// One row of the reference.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// Dotted key (`[]` marks array-of-tables entries).
    pub key: String,
    /// TOML type.
    pub ty: String,
    /// Default (TOML literal), or `–`.
    pub default: String,
}

fn type_of(v: &toml::Value) -> &'static str {
    match v {
        toml::Value::String(_) => "string",
        toml::Value::Integer(_) => "integer",
        toml::Value::Float(_) => "float",
        toml::Value::Boolean(_) => "bool",
        toml::Value::Datetime(_) => "datetime",
        toml::Value::Array(_) => "array",
        toml::Value::Table(_) => "table",
    }
}

fn literal(v: &toml::Value) -> String {
    let s = v.to_string();
    if s.len() > 60 {
        format!(
            "{}…",
            &s[..s.char_indices().nth(57).map_or(s.len(), |(i, _)| i)]
        )
    } else {
        s
    }
}

/// Leaf keys of a serialized configuration with their types and defaults. Maps whose keys are data
/// (joint names) are listed as one `table` key; arrays of tables list the union of their entries' keys.
pub fn rows(root: &toml::Table) -> Vec<Row> {
    let mut out = BTreeMap::new();
    walk(root, "", &mut out);
    out.into_values().collect()
}

/// Keys whose table holds data (names → values), not fields.
const DATA_TABLES: &[&str] = &[
    "robot.initial_joint_positions",
    "robot.locked_joints",
    "robot.effort_limits",
    "robot.velocity_limits",
    "wbc.walking.posture_joint_weights",
    "joint_trajectory.joints",
    "estimation.ft_calibration",
];

fn is_data_table(key: &str) -> bool {
    DATA_TABLES.contains(&key) || key.ends_with(".posture") || key.ends_with(".joint_weights")
}

fn walk(t: &toml::Table, prefix: &str, out: &mut BTreeMap<String, Row>) {
    for (k, v) in t {
        let key = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        match v {
            toml::Value::Table(inner) if !is_data_table(&key) => walk(inner, &key, out),
            toml::Value::Array(items)
                if !items.is_empty() && items.iter().all(|i| i.is_table()) =>
            {
                let key = format!("{key}[]");
                for item in items {
                    if let toml::Value::Table(inner) = item {
                        let mut sub = BTreeMap::new();
                        walk(inner, &key, &mut sub);
                        for (sk, mut row) in sub {
                            row.default = "per entry".into();
                            out.entry(sk).or_insert(row);
                        }
                    }
                }
            }
            _ => {
                out.insert(
                    key.clone(),
                    Row {
                        key,
                        ty: type_of(v).into(),
                        default: literal(v),
                    },
                );
            }
        }
    }
}

/// The unit a layer key's doc comment states: the first bracketed unit (`\\[m\\]`, `[s⁻¹]`), or the
/// trailing `, N/m³` of its first sentence (the stride-sim style). `None` when the meaning states none.
fn unit_in_meaning(meaning: &str) -> Option<&str> {
    let looks_like_unit = |u: &str| {
        !u.is_empty()
            && u.chars().count() <= 16
            && !u.contains(char::is_whitespace)
            && !u.contains('`')
            && u.chars().any(|c| c.is_alphabetic() || c == '°')
    };
    let mut rest = meaning;
    while let Some(open) = rest.find('[') {
        let after = &rest[open + 1..];
        if let Some(close) = after.find(']') {
            let unit = after[..close].trim_end_matches('\\');
            if looks_like_unit(unit) {
                return Some(unit);
            }
        }
        rest = after;
    }
    let first_sentence = meaning.split(". ").next().unwrap_or(meaning);
    if let Some(unit) = first_sentence
        .trim_end_matches('.')
        .strip_suffix(')')
        .and_then(|s| s.rsplit_once(" ("))
        .map(|(_, u)| u)
        .filter(|u| looks_like_unit(u) && u.chars().count() <= 6)
    {
        return Some(unit);
    }
    let (_, tail) = first_sentence.rsplit_once(", ")?;
    let unit = tail.trim_end_matches('.');
    looks_like_unit(unit).then_some(unit).filter(|u| {
        u.chars()
            .all(|c| !c.is_ascii_lowercase() || "msgkradz".contains(c))
            || u.contains('/')
    })
}

/// Renders docs/configuration.md. `layer_doc(key)` gives the meaning of a layer key (from the layer's
/// field docs); runner keys come from [`RUNNER_KEYS`]. Returns the text and the keys without a meaning.
pub fn render(
    default: &toml::Table,
    layer_doc: &dyn Fn(&str) -> Option<String>,
) -> (String, Vec<String>) {
    let rows = rows(default);
    let mut missing = Vec::new();
    let mut s = String::new();
    s.push_str("# Scenario configuration reference\n\n");
    s.push_str(
        "<!-- Generated by `cargo test -p stride-runner --test configuration_reference` with\n",
    );
    s.push_str("     STRIDE_UPDATE_DOCS=1; the same test fails when this file and the code disagree. -->\n\n");
    s.push_str(
        "A scenario is one TOML file in `configs/`. It may start with `include = [\"robots/x.toml\", ...]`: the \
         built-in defaults (the table below) come first, then the included files (paths relative to the \
         including file), in order, then the file itself on top; tables merge key by key, every other value \
         (numbers, strings, arrays, including arrays of tables such as task lists) is replaced whole by the \
         later file, so a file can change a single key of any section. `[goal]` is the exception: its \
         alternatives (`[goal.pose]`, `[goal.waypoints]`, `[goal.velocity]`, `[goal.stand]`) are exclusive \
         and not pre-filled (the default is `[goal.pose] x = 2`). Every table rejects unknown keys. Errors name the file, line, column and key (or \
         say that the value is a built-in default when no file sets the key) and say what is expected. \
         `stride check <CONFIG>` validates a scenario without running it: it also loads the model, looks up \
         every frame, joint and sensor name the scenario uses (saying which file or built-in default set each \
         came from) and warns about the initial posture and the simulated ground (docs/new-robot.md).\n\n\
         Rates are in Hz and must divide `rates.base_hz` exactly; `base_hz` must divide 10⁹ so the base period \
         is a whole number of nanoseconds. The layers get their periods from `[rates]` (`rates.wbc_hz` for the \
         QP-IK and the TSID, `rates.sim_hz` for the simulator); no layer section has a period key.\n\n\
         Keys marked `[]` belong to the entries of an array of tables (`[[...]]`); their default is per entry \
         (see the defaults printed by the code, e.g. the tasks of `stride_wbc::IkConfig::default_for_bundled_model`).\n\n",
    );
    let mut section = String::new();
    let emit_header = |s: &mut String, title: &str| {
        s.push_str(&format!("\n## `[{title}]`\n\n| key | type | default | unit | meaning |\n|---|---|---|---|---|\n"));
    };
    let mut all: Vec<(String, String, String, String, String)> = Vec::new();
    for r in &rows {
        let (unit, meaning) = if let Some(d) = RUNNER_KEYS.iter().find(|d| d.key == r.key) {
            (d.unit.to_string(), d.meaning.to_string())
        } else if let Some(m) = layer_doc(&r.key) {
            (unit_in_meaning(&m).unwrap_or("-").to_string(), m)
        } else {
            missing.push(r.key.clone());
            ("?".into(), "(undocumented)".into())
        };
        all.push((
            r.key.clone(),
            r.ty.clone(),
            format!("`{}`", r.default.replace('|', "\\|")),
            unit,
            meaning,
        ));
    }
    for d in OPTIONAL_KEYS {
        all.push((
            d.key.to_string(),
            optional_key_type(d.key).into(),
            "–".into(),
            d.unit.into(),
            d.meaning.into(),
        ));
    }
    let top = |k: &str| -> String {
        for (p, _) in LAYER_SECTIONS {
            if k.starts_with(&format!("{p}.")) {
                return p.to_string();
            }
        }
        k.split(['.', '[']).next().unwrap_or("").to_string()
    };
    all.sort_by_key(|a| (top(&a.0) != "include", top(&a.0), a.0.clone()));
    for (key, ty, default, unit, meaning) in all {
        let sec = top(&key);
        if sec != section {
            section = sec.clone();
            emit_header(&mut s, &sec);
            if let Some((_, ty)) = LAYER_SECTIONS.iter().find(|(p, _)| *p == sec) {
                s.insert_str(
                    s.len() - "| key | type | default | unit | meaning |\n|---|---|---|---|---|\n".len(),
                    &format!("Embedded `{ty}`: meanings come from that type's documentation (units in brackets).\n\n"),
                );
            }
        }
        s.push_str(&format!(
            "| `{key}` | {ty} | {default} | {unit} | {} |\n",
            meaning.replace('|', "\\|").replace('\n', " ")
        ));
    }
    // Runner descriptions that no longer match a key.
    for d in RUNNER_KEYS {
        if !rows.iter().any(|r| r.key == d.key) {
            missing.push(format!("stale description: {}", d.key));
        }
    }
    (s, missing)
}

#[cfg(test)]
mod tests {
    use super::unit_in_meaning;

    #[test]
    fn units_are_read_from_the_layer_docs() {
        let cases = [
            (
                "Constant CoM height above the ground \\[m\\], in (0, 10].",
                Some("m"),
            ),
            ("Integral gain \\[s⁻¹\\] (≥ 0).", Some("s⁻¹")),
            ("Control period (s).", Some("s")),
            ("Normal stiffness density `k`, N/m³.", Some("N/m³")),
            (
                "Simulation rate (steps per simulated second), Hz. Default 2000.",
                Some("Hz"),
            ),
            ("Servo mode.", None),
            (
                "Fraction of each step spent in double support, in (0, 1).",
                None,
            ),
            (
                "Merge point position inside a double support, in [0, 1).",
                None,
            ),
            (
                "Variant tag of the entry (see the layer's config enum for the allowed values).",
                None,
            ),
            ("Name used in outputs and errors, a string.", None),
        ];
        for (meaning, unit) in cases {
            assert_eq!(unit_in_meaning(meaning), unit, "{meaning}");
        }
    }
}
