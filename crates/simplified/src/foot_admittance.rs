//! Foot admittance for position control: foot damping control of the ankle torques and foot force
//! difference control [Kajita 2010], with the desired wrench distribution from the
//! desired ZMP [Caron 2019, wrench distribution].
//!
//! A position-controlled robot imposes its soles' poses; on a hard floor a stiff ankle servo cannot give
//! way to the ground, so a small pose error becomes a large torque error (chatter, rocking). The laws here
//! move each loaded sole's reference with the error between the measured and the desired contact wrench,
//! and leak back to the plan:
//!
//! * **damping control** (per loaded foot, roll and pitch in the sole frame):
//!   `θ̇ = K_τ (τ − τ*) − θ / T_τ`, with `τ` the measured ground torque on the foot about its sole origin
//!   and `τ* = (c* − s) × f_z e_z` the torque that puts the centre of pressure at the desired `c*` under the
//!   measured normal force `f_z` [Kajita 2010, foot damping control];
//! * **force difference control** (both feet loaded): `δ̇ = K_f ((f_L − f_R) − (f_L* − f_R*)) − δ / T_f`,
//!   the left sole raised by `δ/2` and the right one lowered by `δ/2` [Kajita 2010, foot force difference control] (written with
//!   `δ = z_L − z_R` and the sign that unloads the foot that carries too much);
//! * **sink compensation** on a compliant ground (`ground_stiffness` `k` > 0, the visco-elastic continuum of
//!   [Romualdi 2022, eq. 8.1.6]): each sole's reference is lowered by its static sink relative to the
//!   even split, `Δz_i = (F/2 − f_i*) / (k l w)`, `f_i*` its desired normal force (the distribution below,
//!   low-passed at `error_cutoff`), `F = f_L* + f_R*` and `k l w` the vertical stiffness of an `l × w`
//!   sole [Romualdi 2022, eq. 8.1.9]. The desired forces, not the measured ones: with the measured ones
//!   the compensation is a loop of gain one on the load split (a leg lengthened by its sink presses its
//!   foot in by as much) and the load swings between the feet at about 3 Hz (measured). Without it the soles' references stay level while the loaded foot sinks and the other
//!   rises: the whole robot rolls with the load (by `(f_L − f_R) / (k l w d)` over a sole distance `d`),
//!   which shifts the CoM further onto the loaded foot, a loop of gain `2 m g h / (k l w d²)` (0.86 on
//!   `k = 10⁶` N/m³ for the bundled humanoid); the kinematic QP-IK, holding the sunk sole at the planned
//!   height, shortens its leg and closes that loop even faster. The compensation sums to zero over the
//!   feet, so the planned CoM height is kept, and lifts an unloaded (swing) foot by the half-weight sink,
//!   onto the ground's surface;
//! * **sole-tilt feed-forward** on that ground (`tilt_feedforward_gain` `g` > 0): an `l × w` sole on a ground
//!   `k` has roll and pitch stiffnesses `k l w³/12` and `k w l³/12` (12 and 60 N·m/rad on `k = 10⁶` N/m³,
//!   against `m g h` ≈ 174 N·m/rad for the bundled humanoid), so its desired ankle torque `τ*` needs a tilt of
//!   `−τ*` over them; each loaded sole gets `g` times that tilt (bounded by `max_feedforward_tilt`, low-passed
//!   at `error_cutoff`) on top of the damping control's. The full tilt (`g = 1`) is tenths of a radian in a
//!   few ticks at a weight shift and kicks the robot over (measured, docs/soft-ground.md);
//! * **touch-down search** (`touchdown_search_speed` `v` > 0): a foot that the plan has put down but that
//!   carries no load yet (below [`MIN_ADMITTANCE_LOAD`] of the weight) keeps descending, its reference
//!   lowered at `v` (up to `max_touchdown_search`) until its sole carries load; the depth it reached is held
//!   while the plan keeps the foot down and leaks back to the plan with `force_leak_time` once it lifts it.
//!   The kinematic QP-IK integrates its own state with the stance sole flat, so a stance sole rolled in a
//!   soft ground turns the real robot about it and holds the landing foot over the ground (16–30 mm on
//!   `k = 10⁶` N/m³, measured, docs/soft-ground.md); the search lands it by the measured load, not by the
//!   clock;
//! * **measured sole tilt** (`measured_tilt_gain` `g_m` > 0): each loaded sole's reference is turned, on top
//!   of the tilts above, by `g_m` times its measured roll and pitch (the estimated sole attitude relative to
//!   the level frame of the same yaw, low-passed at `measured_tilt_cutoff`), so that the kinematic QP-IK,
//!   which integrates its own state from the stance sole, has that sole where the robot's is: its base and
//!   swing foot are then where it thinks. On a soft ground the stance sole rolls 12–17° in a single support
//!   and the IK's level sole turns the real robot about it (docs/soft-ground.md, "Position control: the IK
//!   on the tilted sole"). The plan's soles are level (flat ground). Measured: the ankle's command turns the
//!   light sole on its soft ground, not the heavy body, so the sole rolls further by what the reference
//!   adds (a loop of gain about one) and the robot falls sooner;
//! * **swing-foot tilt compensation** (`swing_tilt_gain` `g_s` > 0): the same fact used on the swing foot
//!   only. In single support the real robot is the IK's turned about the stance sole by `Δ`, the stance
//!   sole's measured roll and pitch minus its reference tilt (low-passed at `measured_tilt_cutoff`), so the
//!   swing foot, at `r` from the stance sole (level frame of its yaw), is `Δ_x r_y − Δ_y r_x` higher than the
//!   IK thinks and turned by `Δ`; its reference is lowered by that height and turned by `−Δ` (times `g_s`),
//!   which moves the swing leg only. Once the foot is loaded (or without a loaded stance) the offset leaks
//!   back to the plan with `force_leak_time`;
//! * **distribution** of the desired ZMP `p*`: with both feet loaded, `α` is the projection of `p*` on the
//!   segment between the sole origins (clamped to `[0, 1]`), `f_L* = (1 − α) F`, `f_R* = α F` (`F` the
//!   measured total normal force) and each desired centre of pressure is its sole origin plus the part of
//!   `p*` off the segment, `c_i* = s_i + (p* − s_L − α (s_R − s_L))`, clamped to the sole; then
//!   `Σ f_i* c_i* / F = p*` whenever no clamp is active. With one foot loaded, `c* = p*` clamped to it.
//!
//! Both first-order laws are integrated exactly over a tick for a constant error (zero-order hold):
//! `x⁺ = a x + K e T (1 − a)`, `a = e^{−dt/T}`; the state is then clamped to its bound.
//!
//! The errors (`τ − τ*` per foot, the force difference's) reach the laws through a first-order low-pass
//! filter of cut-off `error_cutoff` ([`stride_block::FirstOrderLowPass`], starting at zero), run on zero
//! while a foot (or the pair) is not loaded, so a touch-down ramps the error in rather than stepping it.
//! The rates the laws send on as velocity references (`θ̇`, `δ̇`) then move smoothly: unfiltered, a
//! contact whose wrench chatters from tick to tick (MuJoCo's four-corner box contact) steps the
//! position servos' velocity reference, and the servo damping turns each step into an ankle torque step.

use nalgebra::{Isometry3, Vector2, Vector3, Vector6};
use serde::{Deserialize, Serialize};

use stride_block::{low_pass_gain, FirstOrderLowPass};

use crate::error::{check_non_negative, check_positive, Result, SimplifiedError};

/// Default cut-off of the error filter \[Hz\] (`error_cutoff`; docs/foot-admittance.md, "MuJoCo").
pub const DEFAULT_ERROR_CUTOFF: f64 = 20.0;

/// Default foot damping gain `K_τ` \[rad/(N·m·s)\] (`torque_gain`). With [`DEFAULT_TORQUE_LEAK_TIME`] the
/// sole tilts `K_τ T_τ` = 2·10⁻³ rad per N·m of steady torque error (5·10⁻⁴ before 2026-12-06): chosen with
/// the simplified layer at 500 Hz on `walk_straight` over floors of 3·10⁷, 3·10⁸ and 10⁹ N/m³, where the
/// faster and stronger tilt brings the measured CoP onto the desired one before the chatter of a hard floor
/// builds up (docs/foot-admittance.md, "Hard floors").
pub const DEFAULT_TORQUE_GAIN: f64 = 0.01;

/// Default time constant `T_τ` of the tilt's return to the plan \[s\] (`torque_leak_time`).
pub const DEFAULT_TORQUE_LEAK_TIME: f64 = 0.2;

/// Default force difference gain `K_f` \[m/(N·s)\] (`force_gain`). Its loop gain is `K_f` times the
/// vertical stiffness of the two legs and the floor in series, which grows with the floor: at 10⁻⁴ (the
/// default before 2026-12-06) the double support's load split oscillates at 50–100 Hz on a 10⁹ N/m³ floor
/// (docs/foot-admittance.md, "Hard floors").
pub const DEFAULT_FORCE_GAIN: f64 = 3e-5;

/// Share of the robot's weight a foot must carry to count as loaded (below it the foot's corrections
/// leak back to the plan).
pub const MIN_ADMITTANCE_LOAD: f64 = 0.05;

/// Parameters of the foot admittance (`[simplified.foot_admittance]`; the runner uses it in position
/// control only).
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `enabled` | – | true | on in position control since 2026-12-05; false: the sole references are the plan's, bit for bit |
/// | `torque_gain` | rad/(N·m·s) | 0.01 (0.005 before 2026-12-06) | `K_τ`, the inverse of the damping `D` of [Kajita 2010, foot damping control] |
/// | `torque_leak_time` | s | 0.2 (0.1 before 2026-12-06) | `T_τ`, time constant of the return of the tilt to the plan |
/// | `max_tilt` | rad | 0.1 | bound on each tilt angle |
/// | `force_gain` | m/(N·s) | 3e-5 (1e-4 before 2026-12-06) | `K_f` of the force difference control [Kajita 2010, foot force difference control] |
/// | `force_leak_time` | s | 0.2 | `T_f`, time constant of the return of the height difference to the plan |
/// | `max_height_offset` | m | 0.02 | bound on the height difference `δ` |
/// | `error_cutoff` | Hz | 20 | cut-off of the low-pass filter on the torque and force errors (0: unfiltered) |
/// | `ground_stiffness` | N/m³ | 0 | the ground's normal stiffness density `k` for the sink compensation (0: off, a rigid ground) |
/// | `tilt_feedforward_gain` | – | 0 | with `ground_stiffness` > 0: tilt each loaded sole by this fraction of the angle that gives its desired ankle torque on the ground, `−τ*/(k l w³/12)` in roll, `−τ*/(k w l³/12)` in pitch (0: off, 1: the full static tilt) |
/// | `max_feedforward_tilt` | rad | 0.3 | bound on each feed-forward tilt angle |
/// | `touchdown_search_speed` | m/s | 0 | speed at which a foot planned in contact since its touch-down, not yet loaded, keeps descending (0: off) |
/// | `max_touchdown_search` | m | 0.05 | bound on the depth of that descent |
/// | `measured_tilt_gain` | – | 0 | fraction of each loaded sole's measured roll and pitch added to its reference tilt, so the QP-IK's stance sole is the robot's (0: off, 1: all of it) |
/// | `measured_tilt_cutoff` | Hz | 5 | cut-off of the low-pass filter on the measured sole tilt (0: unfiltered) |
/// | `swing_tilt_gain` | – | 0 | fraction of the stance sole's measured roll and pitch beyond its reference by which the swing foot's reference is turned back about the stance sole (0: off) |
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FootAdmittanceConfig {
    /// Whether the runner moves the sole references (position control only).
    pub enabled: bool,
    /// Damping-control gain `K_τ` (the inverse of the damping) \[rad/(N·m·s)\].
    pub torque_gain: f64,
    /// Time constant of the sole tilt's return to the plan \[s\].
    pub torque_leak_time: f64,
    /// Bound on each sole tilt angle (roll, pitch) \[rad\].
    pub max_tilt: f64,
    /// Force-difference gain `K_f` \[m/(N·s)\].
    pub force_gain: f64,
    /// Time constant of the soles' height difference's return to the plan \[s\].
    pub force_leak_time: f64,
    /// Bound on the soles' height difference \[m\].
    pub max_height_offset: f64,
    /// Cut-off of the first-order low-pass filter on the torque and force errors \[Hz\] (0: unfiltered).
    pub error_cutoff: f64,
    /// Normal stiffness density `k` of the ground for the sink compensation \[N/m³\] (0: off).
    pub ground_stiffness: f64,
    /// Fraction of the tilt each loaded sole needs for its desired ankle torque on the ground
    /// `ground_stiffness` (the sole-tilt feed-forward; 0: off; no effect without a ground stiffness).
    pub tilt_feedforward_gain: f64,
    /// Bound on each feed-forward tilt angle (roll, pitch) \[rad\].
    pub max_feedforward_tilt: f64,
    /// Speed at which a foot planned in contact since its touch-down but not yet loaded keeps descending
    /// (the touch-down search) \[m/s\] (0: off).
    pub touchdown_search_speed: f64,
    /// Bound on the depth of the touch-down search \[m\].
    pub max_touchdown_search: f64,
    /// Fraction of each loaded sole's measured roll and pitch added to its reference tilt (0: off).
    pub measured_tilt_gain: f64,
    /// Cut-off of the low-pass filter on the measured sole tilt \[Hz\] (0: unfiltered).
    pub measured_tilt_cutoff: f64,
    /// Fraction of the stance sole's measured roll and pitch beyond its reference by which the swing
    /// foot's reference is turned back about the stance sole (0: off).
    pub swing_tilt_gain: f64,
}

impl Default for FootAdmittanceConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            torque_gain: DEFAULT_TORQUE_GAIN,
            torque_leak_time: DEFAULT_TORQUE_LEAK_TIME,
            max_tilt: 0.1,
            force_gain: DEFAULT_FORCE_GAIN,
            force_leak_time: 0.2,
            max_height_offset: 0.02,
            error_cutoff: DEFAULT_ERROR_CUTOFF,
            ground_stiffness: 0.0,
            tilt_feedforward_gain: 0.0,
            max_feedforward_tilt: 0.3,
            touchdown_search_speed: 0.0,
            max_touchdown_search: 0.05,
            measured_tilt_gain: 0.0,
            measured_tilt_cutoff: 5.0,
            swing_tilt_gain: 0.0,
        }
    }
}

impl FootAdmittanceConfig {
    /// Checks the ranges: gains and bounds ≥ 0, leak times > 0, all finite.
    pub fn validate(&self) -> Result<()> {
        check_non_negative("foot_admittance.torque_gain", self.torque_gain)?;
        check_positive("foot_admittance.torque_leak_time", self.torque_leak_time)?;
        check_non_negative("foot_admittance.max_tilt", self.max_tilt)?;
        check_non_negative("foot_admittance.force_gain", self.force_gain)?;
        check_positive("foot_admittance.force_leak_time", self.force_leak_time)?;
        check_non_negative("foot_admittance.max_height_offset", self.max_height_offset)?;
        check_non_negative("foot_admittance.error_cutoff", self.error_cutoff)?;
        check_non_negative("foot_admittance.ground_stiffness", self.ground_stiffness)?;
        check_non_negative(
            "foot_admittance.tilt_feedforward_gain",
            self.tilt_feedforward_gain,
        )?;
        check_non_negative(
            "foot_admittance.max_feedforward_tilt",
            self.max_feedforward_tilt,
        )?;
        check_non_negative(
            "foot_admittance.touchdown_search_speed",
            self.touchdown_search_speed,
        )?;
        check_non_negative(
            "foot_admittance.max_touchdown_search",
            self.max_touchdown_search,
        )?;
        check_non_negative(
            "foot_admittance.measured_tilt_gain",
            self.measured_tilt_gain,
        )?;
        check_non_negative(
            "foot_admittance.measured_tilt_cutoff",
            self.measured_tilt_cutoff,
        )?;
        check_non_negative("foot_admittance.swing_tilt_gain", self.swing_tilt_gain)
    }
}

/// One tick of a leaky integrator `ẋ = K e − x / T` over `dt` \[s\] with `e` held constant (exact
/// zero-order-hold solution), the result clamped to `[−bound, bound]`.
pub fn leaky_admittance(x: f64, gain: f64, error: f64, leak_time: f64, dt: f64, bound: f64) -> f64 {
    let a = (-dt / leak_time).exp();
    (a * x + gain * error * leak_time * (1.0 - a)).clamp(-bound, bound)
}

/// What one tick of [`FootAdmittance`] reads (plain data, world frame).
///
/// | field | unit | meaning |
/// |---|---|---|
/// | `desired_zmp` | m | the simplified layer's desired ZMP (world xy) |
/// | `soles` | m, – | measured `[left, right]` sole poses |
/// | `wrenches` | N, N·m | measured `[f; τ]` the ground applies on each foot, world orientation, torque about its sole origin |
/// | `contacts` | – | feet in contact (planned and measured) |
/// | `planned` | – | feet the plan has in contact (the touch-down search) |
/// | `dt` | s | time since the last tick (> 0) |
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FootAdmittanceInput {
    /// Desired ZMP \[m\].
    pub desired_zmp: Vector2<f64>,
    /// Measured sole poses `[left, right]`.
    pub soles: [Isometry3<f64>; 2],
    /// Measured ground wrenches on the feet `[f; τ]` \[N, N·m\] (world orientation, about the sole).
    pub wrenches: [Vector6<f64>; 2],
    /// Feet in contact.
    pub contacts: [bool; 2],
    /// Feet in contact in the plan.
    pub planned: [bool; 2],
    /// Tick period \[s\].
    pub dt: f64,
}

/// The correction of one sole's reference.
///
/// | field | unit | meaning |
/// |---|---|---|
/// | `tilt` | rad | roll and pitch about the sole frame's x and y axes, applied after the planned orientation |
/// | `tilt_rate` | rad/s | their rates `K_τ (τ − τ*) − θ/T_τ` |
/// | `height` | m | world z offset (`±δ/2`, plus the sink compensation `Δz_i`, minus the touch-down search's depth) |
/// | `height_rate` | m/s | its rate |
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FootCorrection {
    /// Roll and pitch in the sole frame \[rad\].
    pub tilt: Vector2<f64>,
    /// Their rates \[rad/s\].
    pub tilt_rate: Vector2<f64>,
    /// World z offset \[m\].
    pub height: f64,
    /// Its rate \[m/s\].
    pub height_rate: f64,
}

/// The output of a tick: the sole corrections and the wrench distribution they aimed at.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FootAdmittanceOutput {
    /// Corrections `[left, right]`.
    pub feet: [FootCorrection; 2],
    /// Desired centres of pressure (world xy) \[m\]; the sole origin of an unloaded foot.
    pub desired_cop: [Vector2<f64>; 2],
    /// Desired normal forces \[N\] (0 on an unloaded foot).
    pub desired_force: [f64; 2],
}

/// Foot damping and force difference control (see the module documentation). Allocation-free.
#[derive(Debug, Clone)]
pub struct FootAdmittance {
    config: FootAdmittanceConfig,
    half_size: Vector2<f64>,
    min_force: f64,
    /// Vertical compliance of one sole on the ground, `1 / (k l w)` \[m/N\] (0: no sink compensation).
    sole_compliance: f64,
    /// Roll and pitch compliance of one sole on the ground, `[12 / (k l w³), 12 / (k w l³)]` \[rad/(N·m)\],
    /// times `tilt_feedforward_gain` (zero without the tilt feed-forward).
    tilt_compliance: Vector2<f64>,
    /// The damping control's tilts `[left, right]` (roll, pitch in the sole frame) \[rad\].
    feedback_tilts: [Vector2<f64>; 2],
    /// Low-pass filters of the feed-forward tilts `[left, right]` (roll, pitch in the sole frame) \[rad\].
    feedforward_tilts: [FirstOrderLowPass<Vector2<f64>>; 2],
    /// Low-pass filters of the measured sole tilts `[left, right]` (roll, pitch) \[rad\].
    measured_tilts: [FirstOrderLowPass<Vector2<f64>>; 2],
    /// Swing-foot tilt compensations `[left, right]`: height \[m\], roll and pitch \[rad\].
    swing_offsets: [Vector3<f64>; 2],
    /// Half the robot's weight, the even split the normal-force filter starts from \[N\].
    half_weight: f64,
    /// Height difference `δ = z_L − z_R` \[m\].
    height_difference: f64,
    /// Low-pass filters of the torque errors `[left, right]` (roll, pitch in the sole frame) \[N·m\].
    torque_errors: [FirstOrderLowPass<Vector2<f64>>; 2],
    /// Low-pass filter of the force difference error \[N\].
    force_error: FirstOrderLowPass<f64>,
    /// Low-pass filter of the desired normal forces `[f_L*, f_R*]` of the sink compensation \[N\].
    normal_forces: FirstOrderLowPass<Vector2<f64>>,
    /// Depths of the touch-down search `[left, right]` \[m\] (≥ 0, below the plan).
    search_depths: [f64; 2],
    /// Feet searching for the ground: planned in contact since their touch-down, not loaded since.
    searching: [bool; 2],
    /// The planned contacts of the last tick.
    planned_before: [bool; 2],
    output: FootAdmittanceOutput,
}

impl FootAdmittance {
    /// A foot admittance for rectangular soles of `foot_length` × `foot_width` \[m\] centred on the sole
    /// frames, on a robot of weight `weight` \[N\].
    ///
    /// # Errors
    /// An invalid config or a non-positive size or weight.
    pub fn new(
        config: &FootAdmittanceConfig,
        foot_length: f64,
        foot_width: f64,
        weight: f64,
    ) -> Result<Self> {
        config.validate()?;
        check_positive("foot_length", foot_length)?;
        check_positive("foot_width", foot_width)?;
        check_positive("weight", weight)?;
        Ok(Self {
            config: *config,
            half_size: Vector2::new(foot_length, foot_width) * 0.5,
            min_force: MIN_ADMITTANCE_LOAD * weight,
            sole_compliance: if config.ground_stiffness > 0.0 {
                1.0 / (config.ground_stiffness * foot_length * foot_width)
            } else {
                0.0
            },
            tilt_compliance: if config.ground_stiffness > 0.0 {
                let k = config.ground_stiffness;
                Vector2::new(
                    12.0 / (k * foot_length * foot_width.powi(3)),
                    12.0 / (k * foot_width * foot_length.powi(3)),
                ) * config.tilt_feedforward_gain
            } else {
                Vector2::zeros()
            },
            feedback_tilts: [Vector2::zeros(); 2],
            feedforward_tilts: [FirstOrderLowPass::starting_at(
                config.error_cutoff,
                Vector2::zeros(),
            ); 2],
            measured_tilts: [FirstOrderLowPass::starting_at(
                config.measured_tilt_cutoff,
                Vector2::zeros(),
            ); 2],
            swing_offsets: [Vector3::zeros(); 2],
            half_weight: weight * 0.5,
            height_difference: 0.0,
            torque_errors: [FirstOrderLowPass::starting_at(config.error_cutoff, Vector2::zeros());
                2],
            force_error: FirstOrderLowPass::starting_at(config.error_cutoff, 0.0),
            normal_forces: FirstOrderLowPass::starting_at(
                config.error_cutoff,
                Vector2::repeat(weight * 0.5),
            ),
            search_depths: [0.0; 2],
            searching: [false; 2],
            planned_before: [true; 2],
            output: FootAdmittanceOutput::default(),
        })
    }

    /// The last output.
    pub fn output(&self) -> &FootAdmittanceOutput {
        &self.output
    }

    /// Back to the plan (no correction).
    pub fn reset(&mut self) {
        self.height_difference = 0.0;
        for filter in &mut self.torque_errors {
            filter.reset_to(Vector2::zeros());
        }
        self.force_error.reset_to(0.0);
        self.feedback_tilts = [Vector2::zeros(); 2];
        for filter in self
            .feedforward_tilts
            .iter_mut()
            .chain(&mut self.measured_tilts)
        {
            filter.reset_to(Vector2::zeros());
        }
        self.normal_forces
            .reset_to(Vector2::repeat(self.half_weight));
        self.search_depths = [0.0; 2];
        self.searching = [false; 2];
        self.planned_before = [true; 2];
        self.swing_offsets = [Vector3::zeros(); 2];
        self.output = FootAdmittanceOutput::default();
    }

    /// One tick. With `enabled = false` the output stays zero.
    ///
    /// # Errors
    /// `NonFiniteInput` for a non-finite input, `InvalidParameter` for `dt ≤ 0`; the state is unchanged.
    pub fn step(&mut self, input: &FootAdmittanceInput) -> Result<&FootAdmittanceOutput> {
        check_input(input)?;
        if !self.config.enabled {
            return Ok(&self.output);
        }
        let loaded: [bool; 2] =
            std::array::from_fn(|k| input.contacts[k] && input.wrenches[k][2] >= self.min_force);
        let (cops, forces) = distribute_zmp(
            &input.desired_zmp,
            &input.soles,
            &input.wrenches,
            loaded,
            &self.half_size,
        );
        let c = self.config;
        for k in 0..2 {
            let raw = if loaded[k] {
                ankle_torque_error(&input.soles[k], &input.wrenches[k], &cops[k])
            } else {
                Vector2::zeros()
            };
            let error = self.torque_errors[k].update(raw, input.dt);
            let (feedforward, feedforward_rate) =
                self.feedforward_tilt(k, loaded[k], &input.soles[k], &cops[k], forces[k], input.dt);
            let foot = &mut self.output.feet[k];
            for axis in 0..2 {
                let e = error[axis];
                let tilt = &mut self.feedback_tilts[k][axis];
                *tilt = leaky_admittance(
                    *tilt,
                    c.torque_gain,
                    e,
                    c.torque_leak_time,
                    input.dt,
                    c.max_tilt,
                );
                foot.tilt_rate[axis] =
                    c.torque_gain * e - *tilt / c.torque_leak_time + feedforward_rate[axis];
            }
            foot.tilt = self.feedback_tilts[k] + feedforward;
            if c.measured_tilt_gain > 0.0 {
                let (measured, measured_rate) =
                    self.measured_tilt(k, loaded[k], &input.soles[k], input.dt);
                let foot = &mut self.output.feet[k];
                foot.tilt += measured;
                foot.tilt_rate += measured_rate;
            }
        }
        let raw_force_error = if loaded[0] && loaded[1] {
            (input.wrenches[0][2] - input.wrenches[1][2]) - (forces[0] - forces[1])
        } else {
            0.0
        };
        let force_error = self.force_error.update(raw_force_error, input.dt);
        let d = leaky_admittance(
            self.height_difference,
            c.force_gain,
            force_error,
            c.force_leak_time,
            input.dt,
            c.max_height_offset,
        );
        self.height_difference = d;
        let rate = c.force_gain * force_error - d / c.force_leak_time;
        let (sink, sink_rate) = self.sink_compensation(&forces, input.dt);
        let (depth, depth_rate) = self.touchdown_search(input);
        for (k, (foot, sign)) in self.output.feet.iter_mut().zip([0.5, -0.5]).enumerate() {
            foot.height = sign * d + sink[k] - depth[k];
            foot.height_rate = sign * rate + sink_rate[k] - depth_rate[k];
        }
        if c.swing_tilt_gain > 0.0 {
            self.compensate_swing(input, loaded);
        }
        self.output.desired_cop = cops;
        self.output.desired_force = forces;
        Ok(&self.output)
    }
}

impl FootAdmittance {
    /// The sole-tilt feed-forward of foot `k` and its rate over the tick \[rad, rad/s\]: `g` =
    /// `tilt_feedforward_gain` times the roll and pitch that give the desired ankle torque
    /// `τ* = (c* − s) × f* e_z` (sole frame) on a ground of stiffness density `k`, `θ = −g τ* / (k l w³/12)`
    /// in roll and `−g τ* / (k w l³/12)` in pitch (a sole rolled by `θ` about its x axis presses its −y edge
    /// in: `τ_x = −k l w³/12 θ`), bounded by `max_feedforward_tilt` and low-passed at `error_cutoff`; it goes
    /// back to zero on an unloaded foot.
    fn feedforward_tilt(
        &mut self,
        k: usize,
        loaded: bool,
        sole: &Isometry3<f64>,
        cop: &Vector2<f64>,
        force: f64,
        dt: f64,
    ) -> (Vector2<f64>, Vector2<f64>) {
        if self.tilt_compliance == Vector2::zeros() {
            return (Vector2::zeros(), Vector2::zeros());
        }
        let target = if loaded {
            let torque = desired_ankle_torque(sole, cop, force);
            let bound = self.config.max_feedforward_tilt;
            (-torque.component_mul(&self.tilt_compliance)).map(|v| v.clamp(-bound, bound))
        } else {
            Vector2::zeros()
        };
        filter_with_rate(&mut self.feedforward_tilts[k], target, dt)
    }

    /// The measured sole tilt of foot `k` and its rate over the tick \[rad, rad/s\]: `measured_tilt_gain`
    /// times the roll and pitch of the measured sole ([`sole_tilt`]) while the foot is loaded, zero
    /// otherwise, low-passed at `measured_tilt_cutoff`.
    fn measured_tilt(
        &mut self,
        k: usize,
        loaded: bool,
        sole: &Isometry3<f64>,
        dt: f64,
    ) -> (Vector2<f64>, Vector2<f64>) {
        let target = if loaded {
            sole_tilt(sole) * self.config.measured_tilt_gain
        } else {
            Vector2::zeros()
        };
        filter_with_rate(&mut self.measured_tilts[k], target, dt)
    }

    /// The swing-foot tilt compensation, added to the output's corrections: an unloaded foot `k` while the
    /// other foot `j` is loaded moves towards `g_s` times [`swing_offset`] of `j`'s measured sole over its
    /// reference tilt (first-order, `measured_tilt_cutoff`); otherwise its offset leaks back to zero with
    /// `force_leak_time`.
    fn compensate_swing(&mut self, input: &FootAdmittanceInput, loaded: [bool; 2]) {
        let c = self.config;
        let alpha = low_pass_gain(input.dt, c.measured_tilt_cutoff);
        let leak = (-input.dt / c.force_leak_time).exp();
        let commanded: [Vector2<f64>; 2] =
            std::array::from_fn(|k| self.output.feet[k].tilt + self.swing_offsets[k].yz());
        for k in 0..2 {
            let j = 1 - k;
            let before = self.swing_offsets[k];
            let after = if loaded[j] && !loaded[k] {
                let target = swing_offset(&input.soles[j], &commanded[j], &input.soles[k])
                    * c.swing_tilt_gain;
                before + (target - before) * alpha
            } else {
                before * leak
            };
            self.swing_offsets[k] = after;
            let rate = (after - before) / input.dt;
            let foot = &mut self.output.feet[k];
            foot.height += after.x;
            foot.height_rate += rate.x;
            foot.tilt += after.yz();
            foot.tilt_rate += rate.yz();
        }
    }

    /// The touch-down search's depths `[left, right]` and their rates over the tick \[m, m/s\]: a foot
    /// whose planned contact begins starts searching; while it searches and its measured normal force is
    /// below the loaded threshold its depth grows at `touchdown_search_speed` (bounded by
    /// `max_touchdown_search`); once loaded it stops searching and holds its depth while the plan keeps
    /// it in contact; once the plan lifts it the depth leaks back to zero with `force_leak_time` (zero
    /// without the search). Holding only through the double support and leaking in the single support
    /// was measured too and walked less far (docs/soft-ground.md, "the touch-down search").
    fn touchdown_search(&mut self, input: &FootAdmittanceInput) -> ([f64; 2], [f64; 2]) {
        let c = self.config;
        if c.touchdown_search_speed == 0.0 {
            return ([0.0; 2], [0.0; 2]);
        }
        let rates = std::array::from_fn(|k| {
            let planned = input.planned[k];
            if planned && !self.planned_before[k] {
                self.searching[k] = true;
            }
            if !planned || input.wrenches[k][2] >= self.min_force {
                self.searching[k] = false;
            }
            let before = self.search_depths[k];
            self.search_depths[k] = if self.searching[k] {
                (before + c.touchdown_search_speed * input.dt).min(c.max_touchdown_search)
            } else if planned {
                before
            } else {
                leaky_admittance(before, 0.0, 0.0, c.force_leak_time, input.dt, f64::INFINITY)
            };
            (self.search_depths[k] - before) / input.dt
        });
        self.planned_before = input.planned;
        (self.search_depths, rates)
    }

    /// The sink compensation `Δz_i = (F/2 − f_i*) / (k l w)` of the filtered desired normal forces `[f_L*,
    /// f_R*]` \[N\] and its rate over the tick \[m, m/s\] (zero without a ground stiffness).
    fn sink_compensation(&mut self, desired: &[f64; 2], dt: f64) -> ([f64; 2], [f64; 2]) {
        if self.sole_compliance == 0.0 {
            return ([0.0; 2], [0.0; 2]);
        }
        let desired = Vector2::new(desired[0], desired[1]);
        let before = self.normal_forces.output().unwrap_or(desired);
        let after = self.normal_forces.update(desired, dt);
        let sink = |f: Vector2<f64>| sink_offsets(&f, self.sole_compliance);
        let (z0, z1) = (sink(before), sink(after));
        (z1, [(z1[0] - z0[0]) / dt, (z1[1] - z0[1]) / dt])
    }
}

/// One tick of `filter` on `target` over `dt` \[s\]: its output and that output's rate over the tick.
fn filter_with_rate(
    filter: &mut FirstOrderLowPass<Vector2<f64>>,
    target: Vector2<f64>,
    dt: f64,
) -> (Vector2<f64>, Vector2<f64>) {
    let before = filter.output().unwrap_or(Vector2::zeros());
    let after = filter.update(target, dt);
    (after, (after - before) / dt)
}

/// The roll and pitch of a sole's orientation relative to the level frame of the same yaw \[rad\]: the
/// `(φ, θ)` of `R = R_z(ψ) R_y(θ) R_x(φ)`, the tilt a [`FootCorrection`] applies after a level planned
/// orientation of yaw `ψ`.
pub fn sole_tilt(sole: &Isometry3<f64>) -> Vector2<f64> {
    let (roll, pitch, _) = sole.rotation.euler_angles();
    Vector2::new(roll, pitch)
}

/// The swing foot's correction for a stance sole turned beyond its reference: `Δ` = the stance sole's
/// roll and pitch ([`sole_tilt`]) minus its reference tilt `commanded` \[rad\]; with `r` the swing sole's
/// position from the stance sole's in the level frame of the stance's yaw, the robot turned about the stance
/// sole by `Δ` holds the swing sole `Δ_x r_y − Δ_y r_x` higher and turned by `Δ` (small angles). Returns the
/// opposite, `(−(Δ_x r_y − Δ_y r_x), −Δ_x, −Δ_y)`: height \[m\], roll and pitch \[rad\].
pub fn swing_offset(
    stance: &Isometry3<f64>,
    commanded: &Vector2<f64>,
    swing: &Isometry3<f64>,
) -> Vector3<f64> {
    let d = sole_tilt(stance) - commanded;
    let (_, _, yaw) = stance.rotation.euler_angles();
    let r = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), -yaw)
        * (swing.translation.vector - stance.translation.vector);
    Vector3::new(-(d.x * r.y - d.y * r.x), -d.x, -d.y)
}

/// The sole height offsets `[Δz_L, Δz_R]` that put each sole at its static sink under the normal forces
/// `forces` \[N\] relative to the even split: `Δz_i = (F/2 − f_i) c`, `F = f_L + f_R`, `c = 1 / (k l w)`
/// the vertical compliance of a sole on the ground \[m/N\] [Romualdi 2022, eq. 8.1.9]. They sum to zero.
pub fn sink_offsets(forces: &Vector2<f64>, compliance: f64) -> [f64; 2] {
    let half = forces.sum() * 0.5;
    [
        (half - forces[0]) * compliance,
        (half - forces[1]) * compliance,
    ]
}

fn check_input(input: &FootAdmittanceInput) -> Result<()> {
    let finite = input.desired_zmp.iter().all(|v| v.is_finite())
        && input
            .wrenches
            .iter()
            .all(|w| w.iter().all(|v| v.is_finite()))
        && input.soles.iter().all(|s| {
            s.translation.vector.iter().all(|v| v.is_finite())
                && s.rotation.coords.iter().all(|v| v.is_finite())
        });
    if !finite {
        return Err(SimplifiedError::NonFiniteInput {
            name: "foot admittance input",
        });
    }
    check_positive("foot_admittance dt", input.dt)
}

/// The measured minus the desired ankle torque, roll and pitch in the sole frame \[N·m\]: the desired torque
/// puts the centre of pressure at `cop` (world xy) under the measured normal force,
/// `τ* = (c* − s) × f_z e_z` [Kajita 2010, foot damping control].
pub fn ankle_torque_error(
    sole: &Isometry3<f64>,
    wrench: &Vector6<f64>,
    cop: &Vector2<f64>,
) -> Vector2<f64> {
    // The difference is taken in the world frame before the rotation, as it always was: the damping
    // control's closed loops (MuJoCo's fast walk above all) are sensitive to the last bit.
    let measured = Vector3::new(wrench[3], wrench[4], wrench[5]);
    let desired = desired_ankle_torque_world(sole, cop, wrench[2]);
    (sole.rotation.inverse() * (measured - desired)).xy()
}

/// The ankle torque that puts the centre of pressure at `cop` (world xy) under the normal force `fz` \[N\],
/// `τ* = (c* − s) × f_z e_z`, roll and pitch in the sole frame \[N·m\].
pub fn desired_ankle_torque(sole: &Isometry3<f64>, cop: &Vector2<f64>, fz: f64) -> Vector2<f64> {
    (sole.rotation.inverse() * desired_ankle_torque_world(sole, cop, fz)).xy()
}

/// [`desired_ankle_torque`] in the world frame \[N·m\].
fn desired_ankle_torque_world(sole: &Isometry3<f64>, cop: &Vector2<f64>, fz: f64) -> Vector3<f64> {
    let s = sole.translation.vector;
    Vector3::new((cop.y - s.y) * fz, -(cop.x - s.x) * fz, 0.0)
}

/// The right foot's share `α ∈ [0, 1]` of a double support's normal force for the desired ZMP `zmp`: where
/// `zmp` projects on the segment from the `left` to the `right` sole origin (world xy, m), clamped to it
/// (0.5 when the origins coincide); the left foot carries `1 − α` [Kajita 2010; Caron 2019, wrench
/// distribution]. With no torque about the sole origins the feet's combined centre of pressure is then the
/// projection.
pub fn right_foot_share(zmp: &Vector2<f64>, left: &Vector2<f64>, right: &Vector2<f64>) -> f64 {
    let d = right - left;
    if d.norm_squared() > 1e-12 {
        ((zmp - left).dot(&d) / d.norm_squared()).clamp(0.0, 1.0)
    } else {
        0.5
    }
}

/// The desired centres of pressure (world xy) and normal forces \[N\] of the feet flagged `loaded` for the
/// desired ZMP `zmp` (see the module documentation); the total is the loaded feet's measured normal force.
/// An unloaded foot gets its sole origin and no force.
pub fn distribute_zmp(
    zmp: &Vector2<f64>,
    soles: &[Isometry3<f64>; 2],
    wrenches: &[Vector6<f64>; 2],
    loaded: [bool; 2],
    half_size: &Vector2<f64>,
) -> ([Vector2<f64>; 2], [f64; 2]) {
    let origin = |k: usize| soles[k].translation.vector.xy();
    let mut cops = [origin(0), origin(1)];
    let mut forces = [0.0; 2];
    let total: f64 = (0..2).filter(|&k| loaded[k]).map(|k| wrenches[k][2]).sum();
    match loaded {
        [true, true] => {
            let d = origin(1) - origin(0);
            let alpha = right_foot_share(zmp, &origin(0), &origin(1));
            let off = zmp - (origin(0) + d * alpha);
            for (k, share) in [(0, 1.0 - alpha), (1, alpha)] {
                cops[k] = clamp_to_sole(&(origin(k) + off), &soles[k], half_size);
                forces[k] = share * total;
            }
        }
        [true, false] | [false, true] => {
            let k = usize::from(loaded[1]);
            cops[k] = clamp_to_sole(zmp, &soles[k], half_size);
            forces[k] = total;
        }
        [false, false] => {}
    }
    (cops, forces)
}

/// The point of the sole's rectangle (half-sizes along the sole's x and y) nearest to `p` in the sole frame,
/// world xy \[m\].
fn clamp_to_sole(p: &Vector2<f64>, sole: &Isometry3<f64>, half: &Vector2<f64>) -> Vector2<f64> {
    let s = sole.translation.vector;
    let local = sole.rotation.inverse() * Vector3::new(p.x - s.x, p.y - s.y, 0.0);
    let clamped = Vector3::new(
        local.x.clamp(-half.x, half.x),
        local.y.clamp(-half.y, half.y),
        local.z,
    );
    (s + sole.rotation * clamped).xy()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion};

    fn sole(x: f64, y: f64, yaw: f64) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(x, y, 0.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
        )
    }

    #[test]
    fn leaky_admittance_matches_the_first_order_step_response() {
        // ẋ = K e − x/T from x = 0 with e constant: x(t) = K e T (1 − e^{−t/T}) at every tick, any dt
        let (k, e, t_leak, dt) = (0.02, 3.0, 0.2, 0.002);
        let mut x = 0.0;
        for n in 1..=500 {
            x = leaky_admittance(x, k, e, t_leak, dt, 1.0);
            let t = n as f64 * dt;
            let exact = k * e * t_leak * (1.0 - (-t / t_leak).exp());
            assert!((x - exact).abs() < 1e-14, "t {t}: {x} vs {exact}");
        }
        // the bound holds
        assert_eq!(leaky_admittance(0.0, 1.0, 100.0, 1.0, 1.0, 0.05), 0.05);
        assert_eq!(leaky_admittance(0.0, 1.0, -100.0, 1.0, 1.0, 0.05), -0.05);
    }

    #[test]
    fn distribution_reproduces_the_desired_zmp_inside_the_soles() {
        let soles = [sole(0.0, 0.07, 0.3), sole(0.1, -0.07, 0.3)];
        let w = |fz: f64| Vector6::new(0.0, 0.0, fz, 0.0, 0.0, 0.0);
        let wrenches = [w(120.0), w(200.0)];
        let half = Vector2::new(0.1, 0.045);
        for zmp in [
            Vector2::new(0.03, 0.0),
            Vector2::new(0.06, 0.01),
            Vector2::new(0.01, 0.05),
        ] {
            let (cops, forces) = distribute_zmp(&zmp, &soles, &wrenches, [true, true], &half);
            assert!((forces[0] + forces[1] - 320.0).abs() < 1e-12);
            let net = (cops[0] * forces[0] + cops[1] * forces[1]) / 320.0;
            assert!((net - zmp).norm() < 1e-12, "{net} vs {zmp}");
        }
        // on the segment between the soles: the CoPs are the sole origins
        let segment = Vector2::new(0.1, -0.14);
        let on = Vector2::new(0.0, 0.07) + segment * 0.25;
        let (cops_on, forces) = distribute_zmp(&on, &soles, &wrenches, [true, true], &half);
        assert!((cops_on[0] - Vector2::new(0.0, 0.07)).norm() < 1e-12);
        assert!((cops_on[1] - Vector2::new(0.1, -0.07)).norm() < 1e-12);
        assert!((forces[1] / 320.0 - 0.25).abs() < 1e-12);
        // one foot loaded: its CoP is the ZMP clamped to its rectangle (sole frame)
        let far = Vector2::new(0.5, 0.07);
        let (cops, forces) = distribute_zmp(&far, &soles, &wrenches, [true, false], &half);
        let local = soles[0].rotation.inverse() * Vector3::new(cops[0].x, cops[0].y - 0.07, 0.0);
        assert!((local.x - 0.1).abs() < 1e-12 && local.y.abs() <= 0.045 + 1e-12);
        assert_eq!(forces, [120.0, 0.0]);
    }

    #[test]
    fn torque_error_is_the_normal_force_times_the_cop_error_in_the_sole_frame() {
        let s = sole(0.2, -0.1, std::f64::consts::FRAC_PI_2);
        let fz = 150.0;
        // measured CoP 1 cm ahead of the sole origin along the sole's x (world +y): τ = (c − s) × f
        let wrench = Vector6::new(0.0, 0.0, fz, 0.01 * fz, 0.0, 0.0);
        let e = ankle_torque_error(&s, &wrench, &Vector2::new(0.2, -0.1));
        // the sole's pitch axis is world −x: the error is −0.01 fz about the sole's y, none about its x
        assert!((e - Vector2::new(0.0, -0.01 * fz)).norm() < 1e-12, "{e}");
    }

    /// The left foot carries 300 N with its CoP 2 cm ahead of its sole origin (τ_y = −6 N·m), where the
    /// desired ZMP is; the right foot carries nothing.
    fn left_cop_ahead(contacts: [bool; 2], dt: f64) -> FootAdmittanceInput {
        FootAdmittanceInput {
            desired_zmp: Vector2::new(0.0, 0.07),
            soles: [sole(0.0, 0.07, 0.0), sole(0.0, -0.07, 0.0)],
            wrenches: [
                Vector6::new(0.0, 0.0, 300.0, 0.0, -6.0, 0.0),
                Vector6::zeros(),
            ],
            contacts,
            planned: contacts,
            dt,
        }
    }

    #[test]
    fn disabled_stays_at_zero_and_enabled_tilts_against_the_torque_error() {
        let input = left_cop_ahead([true, true], 0.002);
        let disabled = FootAdmittanceConfig {
            enabled: false,
            ..Default::default()
        };
        let mut off = FootAdmittance::new(&disabled, 0.2, 0.09, 320.0).unwrap();
        assert_eq!(*off.step(&input).unwrap(), FootAdmittanceOutput::default());
        let config = FootAdmittanceConfig::default();
        assert!(config.enabled, "on by default");
        let mut on = FootAdmittance::new(&config, 0.2, 0.09, 320.0).unwrap();
        let out = on.step(&input).unwrap();
        // the CoP is 2 cm ahead of the desired one (the left sole origin): pitch toe up (negative), no roll
        let filtered = -6.0 * low_pass_gain(0.002, DEFAULT_ERROR_CUTOFF);
        let expected = leaky_admittance(
            0.0,
            DEFAULT_TORQUE_GAIN,
            filtered,
            DEFAULT_TORQUE_LEAK_TIME,
            0.002,
            0.1,
        );
        assert_eq!(out.feet[0].tilt, Vector2::new(0.0, expected));
        assert!(expected < 0.0);
        assert_eq!(out.feet[1], FootCorrection::default());
        let bad = FootAdmittanceInput {
            dt: f64::NAN,
            ..input
        };
        assert!(on.step(&bad).is_err());
    }

    /// The error filter in series with the leaky integrator: for a torque error stepping from 0 to `e` at
    /// load, the tilt follows the continuous cascade's closed form
    /// `θ(t) = K e T [1 − (T e^{−t/T} − τ e^{−t/τ}) / (T − τ)]`, `τ = 1/(2π f_c)` (to the discretisation's
    /// first order in `dt`); with `error_cutoff = 0` the tilt is the unfiltered law's, bit for bit.
    #[test]
    fn the_error_filter_ramps_a_step_in_and_zero_cutoff_is_the_unfiltered_law() {
        let (k, t_leak, fc, dt) = (0.005, 0.1, 5.0, 1e-4);
        let input = left_cop_ahead([true, false], dt);
        let config = |error_cutoff| FootAdmittanceConfig {
            enabled: true,
            torque_gain: k,
            torque_leak_time: t_leak,
            error_cutoff,
            ..Default::default()
        };
        let mut filtered = FootAdmittance::new(&config(fc), 0.2, 0.09, 320.0).unwrap();
        let mut raw = FootAdmittance::new(&config(0.0), 0.2, 0.09, 320.0).unwrap();
        let tau = 1.0 / (std::f64::consts::TAU * fc);
        let (mut unfiltered, e) = (0.0, -6.0);
        for n in 1..=3000 {
            let t = n as f64 * dt;
            let tilt = filtered.step(&input).unwrap().feet[0].tilt.y;
            let exact = k
                * e
                * t_leak
                * (1.0 - (t_leak * (-t / t_leak).exp() - tau * (-t / tau).exp()) / (t_leak - tau));
            assert!(
                (tilt - exact).abs() < 2e-3 * (k * e * t_leak).abs(),
                "t {t}: {tilt} vs {exact}"
            );
            unfiltered = leaky_admittance(unfiltered, k, e, t_leak, dt, 0.1);
            assert_eq!(raw.step(&input).unwrap().feet[0].tilt.y, unfiltered);
        }
        // early on the filtered tilt lags the unfiltered one (the step is ramped in)
        let mut fresh = FootAdmittance::new(&config(fc), 0.2, 0.09, 320.0).unwrap();
        let first = fresh.step(&input).unwrap().feet[0].tilt_rate.y;
        assert!(first.abs() < 0.01 * (k * e).abs(), "first rate {first}");
        // unloaded, the filtered error decays to zero and the tilt leaks back to the plan
        let lifted = FootAdmittanceInput {
            contacts: [false, false],
            ..input
        };
        for _ in 0..20000 {
            filtered.step(&lifted).unwrap();
        }
        assert!(filtered.output().feet[0].tilt.norm() < 1e-6);
    }

    /// On a ground of stiffness density `k`, a sole of `l × w` under `f` sinks `f / (k l w)`: the sink
    /// compensation puts each sole at its sink relative to the even split (the loaded foot down, the other
    /// up, summing to zero), reached through the force filter; off (`k = 0`) it adds nothing.
    #[test]
    fn the_sink_compensation_lowers_the_loaded_sole_by_its_static_sink() {
        let (k, l, w) = (1e6, 0.2, 0.09);
        let c = 1.0 / (k * l * w);
        let offsets = sink_offsets(&Vector2::new(300.0, 20.0), c);
        // 280 N more on the left: it sits 140 N · c below the even split, the right 140 N · c above
        assert!((offsets[0] + 140.0 * c).abs() < 1e-15 && (offsets[1] - 140.0 * c).abs() < 1e-15);
        assert!((140.0 * c - 7.78e-3).abs() < 1e-5, "{}", 140.0 * c);
        let config = |ground_stiffness| FootAdmittanceConfig {
            torque_gain: 0.0,
            force_gain: 0.0,
            ground_stiffness,
            ..Default::default()
        };
        // all of the weight on the left foot (the left_cop_ahead input: 300 N left, 0 right)
        let input = left_cop_ahead([true, false], 0.002);
        let mut soft = FootAdmittance::new(&config(k), l, w, 320.0).unwrap();
        let mut rigid = FootAdmittance::new(&config(0.0), l, w, 320.0).unwrap();
        let mut previous = 0.0;
        for n in 0..500 {
            let out = soft.step(&input).unwrap();
            let [left, right] = out.feet;
            assert!((left.height + right.height).abs() < 1e-15);
            assert!(
                left.height <= previous,
                "tick {n}: the left sole goes down monotonically"
            );
            assert!((left.height_rate * 0.002 - (left.height - previous)).abs() < 1e-15);
            previous = left.height;
            assert_eq!(rigid.step(&input).unwrap().feet[0].height, 0.0);
        }
        // after 1 s (20 time constants of the 20 Hz filter) the left sole is 150 N · c below the split
        assert!((previous + 150.0 * c).abs() < 1e-9, "{previous}");
        assert!(FootAdmittanceConfig {
            ground_stiffness: -1.0,
            ..Default::default()
        }
        .validate()
        .is_err());
    }

    /// The sole-tilt feed-forward: a sole of `l × w` on a ground `k` has roll and pitch stiffnesses
    /// `k l w³/12` and `k w l³/12`, so the tilt that gives the desired ankle torque `τ*` is `−τ*` over them
    /// (times the gain, within its bound), reached through the error filter; unloaded, it leaks back to
    /// zero; with the gain at 0 (the default) the corrections are those without it, bit for bit.
    #[test]
    fn the_tilt_feedforward_tilts_the_sole_by_its_desired_torque_over_the_ground_stiffness() {
        let (k, l, w): (f64, f64, f64) = (1e6, 0.2, 0.09);
        let config = |tilt_feedforward_gain, max_feedforward_tilt| FootAdmittanceConfig {
            torque_gain: 0.0,
            force_gain: 0.0,
            ground_stiffness: k,
            tilt_feedforward_gain,
            max_feedforward_tilt,
            ..Default::default()
        };
        // the left foot alone carries 300 N; the desired ZMP is 1 cm ahead of and 1 cm outside its origin
        let input = FootAdmittanceInput {
            desired_zmp: Vector2::new(0.01, 0.08),
            ..left_cop_ahead([true, false], 0.002)
        };
        // τ* = (c* − s) × f e_z = (0.01 · 300, −0.01 · 300) N·m in the sole frame
        let roll = -3.0 / (k * l * w.powi(3) / 12.0);
        let pitch = 3.0 / (k * w * l.powi(3) / 12.0);
        assert!((roll + 0.2469).abs() < 1e-4 && (pitch - 0.05).abs() < 1e-12);
        for (gain, bound, expected) in [
            (1.0, 0.3, Vector2::new(roll, pitch)),
            (0.1, 0.3, Vector2::new(roll, pitch) * 0.1),
            (1.0, 0.1, Vector2::new(-0.1, pitch)),
        ] {
            let mut on = FootAdmittance::new(&config(gain, bound), l, w, 320.0).unwrap();
            let mut previous = Vector2::zeros();
            for _ in 0..500 {
                let foot = on.step(&input).unwrap().feet[0];
                assert!((foot.tilt_rate * 0.002 - (foot.tilt - previous)).norm() < 1e-12);
                previous = foot.tilt;
            }
            assert!(
                (previous - expected).norm() < 1e-9,
                "{previous} vs {expected}"
            );
            assert_left_tilt_leaks_back(&mut on, &input);
        }
        // gain 0: the same corrections as without the key (the default admittance on the same ground)
        let plain = FootAdmittanceConfig {
            ground_stiffness: k,
            ..Default::default()
        };
        let mut off = FootAdmittance::new(&plain, l, w, 320.0).unwrap();
        let mut zero = FootAdmittance::new(
            &FootAdmittanceConfig {
                tilt_feedforward_gain: 0.0,
                max_feedforward_tilt: 0.5,
                ..plain
            },
            l,
            w,
            320.0,
        )
        .unwrap();
        for _ in 0..100 {
            assert_eq!(off.step(&input).unwrap(), zero.step(&input).unwrap());
        }
        assert!(config(-0.1, 0.3).validate().is_err());
        assert!(config(0.1, -0.3).validate().is_err());
    }

    #[test]
    fn touchdown_search_descends_until_loaded_then_leaks_back() {
        let config = FootAdmittanceConfig {
            touchdown_search_speed: 0.2,
            max_touchdown_search: 0.03,
            ..Default::default()
        };
        let dt = 0.002;
        let mut on = FootAdmittance::new(&config, 0.2, 0.09, 320.0).unwrap();
        let mut off =
            FootAdmittance::new(&FootAdmittanceConfig::default(), 0.2, 0.09, 320.0).unwrap();
        // the right foot swings (planned up), then the plan puts it down while it carries nothing
        let swing = FootAdmittanceInput {
            planned: [true, false],
            ..left_cop_ahead([true, false], dt)
        };
        on.step(&swing).unwrap();
        off.step(&swing).unwrap();
        assert_eq!(on.output(), off.output(), "no search in the swing");
        let down = FootAdmittanceInput {
            planned: [true, true],
            ..swing
        };
        for n in 1..=10 {
            on.step(&down).unwrap();
            off.step(&down).unwrap();
            let extra = off.output().feet[1].height - on.output().feet[1].height;
            assert!(
                (extra - 0.2 * dt * n as f64).abs() < 1e-12,
                "tick {n}: {extra}"
            );
            let rate = off.output().feet[1].height_rate - on.output().feet[1].height_rate;
            assert!((rate - 0.2).abs() < 1e-9, "{rate}");
            assert_eq!(
                on.output().feet[0],
                off.output().feet[0],
                "the loaded foot is left alone"
            );
        }
        for _ in 0..200 {
            on.step(&down).unwrap();
            off.step(&down).unwrap();
        }
        let extra = off.output().feet[1].height - on.output().feet[1].height;
        assert!((extra - 0.03).abs() < 1e-12, "bounded: {extra}");
        // loaded: the depth is held while the plan keeps the foot down (an unload does not restart the
        // search, nor does the other foot's lift-off), and once the plan lifts it the depth leaks back
        // with force_leak_time
        let mut loaded = down;
        let mut depths = Vec::new();
        for (w, planned) in [
            (100.0, [false, true]),
            (0.0, [true, true]),
            (0.0, [true, false]),
        ] {
            loaded.wrenches[1][2] = w;
            loaded.planned = planned;
            for _ in 0..100 {
                on.step(&loaded).unwrap();
                off.step(&loaded).unwrap();
            }
            depths.push(off.output().feet[1].height - on.output().feet[1].height);
        }
        let a = (-0.2 / config.force_leak_time).exp();
        assert!((depths[0] - 0.03).abs() < 1e-12, "{depths:?}");
        assert!((depths[1] - 0.03).abs() < 1e-12, "{depths:?}");
        assert!((depths[2] - 0.03 * a).abs() < 1e-9, "{depths:?}");
    }

    /// Both feet unloaded for 1 s: the left sole's tilt is back to the plan.
    fn assert_left_tilt_leaks_back(admittance: &mut FootAdmittance, input: &FootAdmittanceInput) {
        let lifted = FootAdmittanceInput {
            contacts: [false, false],
            ..*input
        };
        for _ in 0..500 {
            admittance.step(&lifted).unwrap();
        }
        assert!(admittance.output().feet[0].tilt.norm() < 1e-9);
    }

    /// With `measured_tilt_gain` and `swing_tilt_gain` at 0 (the defaults) another `measured_tilt_cutoff`
    /// changes nothing, bit for bit.
    fn assert_measured_tilt_off_changes_nothing(input: &FootAdmittanceInput) {
        let mut off =
            FootAdmittance::new(&FootAdmittanceConfig::default(), 0.2, 0.09, 320.0).unwrap();
        let config = FootAdmittanceConfig {
            measured_tilt_cutoff: 1.0,
            ..Default::default()
        };
        let mut zero = FootAdmittance::new(&config, 0.2, 0.09, 320.0).unwrap();
        for _ in 0..100 {
            assert_eq!(off.step(input).unwrap(), zero.step(input).unwrap());
        }
    }

    /// The measured sole tilt: a loaded sole rolled and pitched in the ground (any yaw) gets `g_m` times
    /// that roll and pitch on its reference, through the filter; unloaded, it goes back to zero; with the
    /// gain at 0 (the default) the corrections are those without it, bit for bit.
    #[test]
    fn the_measured_tilt_turns_the_loaded_sole_reference_by_its_roll_and_pitch() {
        let config = |measured_tilt_gain| FootAdmittanceConfig {
            torque_gain: 0.0,
            force_gain: 0.0,
            measured_tilt_gain,
            ..Default::default()
        };
        let (roll, pitch, yaw) = (-0.21, 0.07, 0.4);
        let base = left_cop_ahead([true, false], 0.002);
        let mut soles = base.soles;
        soles[0].rotation = UnitQuaternion::from_euler_angles(roll, pitch, yaw);
        let input = FootAdmittanceInput { soles, ..base };
        assert!((sole_tilt(&soles[0]) - Vector2::new(roll, pitch)).norm() < 1e-12);
        // the tilt a correction applies after the level planned orientation gives back the sole's
        let level = UnitQuaternion::from_euler_angles(0.0, 0.0, yaw);
        let turned = level * UnitQuaternion::from_euler_angles(roll, pitch, 0.0);
        assert!(turned.angle_to(&soles[0].rotation) < 1e-12);
        for gain in [1.0, 0.5] {
            let mut on = FootAdmittance::new(&config(gain), 0.2, 0.09, 320.0).unwrap();
            let mut previous = Vector2::zeros();
            for _ in 0..500 {
                let foot = on.step(&input).unwrap().feet[0];
                assert!((foot.tilt_rate * 0.002 - (foot.tilt - previous)).norm() < 1e-12);
                previous = foot.tilt;
            }
            let expected = Vector2::new(roll, pitch) * gain;
            assert!(
                (previous - expected).norm() < 1e-9,
                "{previous} vs {expected}"
            );
            // the right foot is not loaded: no tilt
            assert_eq!(on.output().feet[1].tilt, Vector2::zeros());
            assert_left_tilt_leaks_back(&mut on, &input);
        }
        assert_measured_tilt_off_changes_nothing(&input);
        assert!(config(-0.1).validate().is_err());
        let negative_cutoff = FootAdmittanceConfig {
            measured_tilt_cutoff: -1.0,
            ..Default::default()
        };
        assert!(negative_cutoff.validate().is_err());
    }

    /// The swing-foot tilt compensation: with the left sole loaded and rolled and pitched beyond its
    /// reference tilt, the unloaded right foot's reference goes to `g_s` times the height and tilt that undo
    /// the robot's turn about the left sole (any yaw); once loaded it leaks back with `force_leak_time`;
    /// with the gain at 0 (the default) the corrections are those without it, bit for bit.
    #[test]
    fn the_swing_foot_is_turned_back_about_the_stance_sole() {
        let (roll, pitch, yaw) = (-0.2, 0.05, 0.4);
        let level = UnitQuaternion::from_euler_angles(0.0, 0.0, yaw);
        let stance = Isometry3::from_parts(
            Translation3::new(0.1, 0.07, -0.01),
            UnitQuaternion::from_euler_angles(roll, pitch, yaw),
        );
        // the right sole 0.14 m to the right of and 0.05 m ahead of the left, in the left's heading
        let swing = Isometry3::from_parts(
            Translation3::from(stance.translation.vector + level * Vector3::new(0.05, -0.14, 0.02)),
            level,
        );
        // Δ = (−0.2, 0.05): the swing sole is −0.2 · −0.14 − 0.05 · 0.05 = 0.0255 m too high
        let offset = swing_offset(&stance, &Vector2::zeros(), &swing);
        assert!(
            (offset - Vector3::new(-0.0255, 0.2, -0.05)).norm() < 1e-12,
            "{offset}"
        );
        // a commanded stance tilt equal to the measured one: nothing to undo
        let none = swing_offset(&stance, &Vector2::new(roll, pitch), &swing);
        assert!(none.norm() < 1e-12, "{none}");
        let config = |swing_tilt_gain| FootAdmittanceConfig {
            torque_gain: 0.0,
            force_gain: 0.0,
            swing_tilt_gain,
            ..Default::default()
        };
        let input = FootAdmittanceInput {
            soles: [stance, swing],
            ..left_cop_ahead([true, false], 0.002)
        };
        let mut on = FootAdmittance::new(&config(0.5), 0.2, 0.09, 320.0).unwrap();
        let (mut height, mut tilt) = (0.0, Vector2::zeros());
        for _ in 0..500 {
            let right = on.step(&input).unwrap().feet[1];
            assert!((right.height_rate * 0.002 - (right.height - height)).abs() < 1e-12);
            assert!((right.tilt_rate * 0.002 - (right.tilt - tilt)).norm() < 1e-12);
            (height, tilt) = (right.height, right.tilt);
        }
        assert!((height + 0.5 * 0.0255).abs() < 1e-9, "{height}");
        assert!((tilt - Vector2::new(0.1, -0.025)).norm() < 1e-9, "{tilt}");
        // the stance foot itself is not turned
        assert_eq!(on.output().feet[0].tilt, Vector2::zeros());
        // loaded: back to the plan with force_leak_time (0.2 s), e^{−1} after 0.2 s
        let w = Vector6::new(0.0, 0.0, 150.0, 0.0, 0.0, 0.0);
        let landed = FootAdmittanceInput {
            wrenches: [w, w],
            contacts: [true, true],
            planned: [true, true],
            ..input
        };
        for _ in 0..100 {
            on.step(&landed).unwrap();
        }
        let left_after = on.output().feet[1].height / height;
        assert!((left_after - (-1.0_f64).exp()).abs() < 1e-9, "{left_after}");
        assert_measured_tilt_off_changes_nothing(&input);
        assert!(config(-1.0).validate().is_err());
    }
}
