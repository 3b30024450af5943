//! DCM step adjustment: the next touch-down position and the step duration chosen each tick from the
//! measured DCM [Khadiv 2020], so that a push the ankles cannot absorb is absorbed by stepping.
//!
//! # Formulation
//!
//! With the ZMP held at the stance CoP `r` until the swing foot touches down, the DCM evolves as
//! `ξ(T) = r + (ξ(t) − r) e^{ω(T−t)}` [Khadiv 2020] (`t`: time since the stance foot touched down,
//! `T`: step duration from that touch-down to the next one). Writing the touch-down DCM as the new footstep
//! `u_T` plus an offset `b` (`ξ(T) = u_T + b`) and using the timing variable `τ = e^{ωT}` the relation is
//! linear in `(u_T, τ, b)` [Khadiv 2020]:
//!
//! ```text
//! u + b − k τ = Rᵀ(r − p_s),     k = Rᵀ(ξ − r) e^{−ωt},     u = Rᵀ(u_T − p_s)
//! ```
//!
//! with `p_s`, `R = R_z(ψ_s)` the stance foot position and yaw, so `u`, `b`, `k` are in the stance-foot
//! frame. The ankle strategy enters as a CoP offset `δr` held until touch-down: it moves the touch-down DCM
//! by `−δr (e^{ω(T−t)} − 1)`, linearised at the nominal duration (`α = τ_n e^{−ωt} − 1`), as the CoP
//! feedback of [Griffin 2017] does beside the step. The QP over
//! `x = [u_x, u_y, τ, b_x, b_y, s_x, s_y, δr_x, δr_y]` (9 variables) is
//!
//! ```text
//! min  w_u ‖u − u_n‖² + (w_τ/τ_n²)(τ − τ_n)² + w_b ‖b − b_n‖² + w_s ‖s‖² + w_r ‖δr‖²
//! s.t. u + b − k τ + α δr = Rᵀ(r − p_s)                            (2 rows, the DCM dynamics)
//!      |δr_x| ≤ cop_x,  |δr_y| ≤ cop_y                               (CoP inside the stance sole)
//!      −backward_max ≤ u_x ≤ forward_max                            (reachable box, stance frame)
//!      lateral_min ≤ ±u_y ≤ lateral_max                             (+ right stance, − left stance)
//!      e^{ω max(min(T_min, T_n), t + t_rem)} ≤ τ ≤ e^{ω max(T_max, T_n)}   (duration, remaining swing)
//!      b_n − m − s ≤ b ≤ b_n + m + s,  s ≥ 0                        (DCM offset bounds, slack-softened)
//! ```
//!
//! `(u_n, T_n, b_n)` is the nominal step from the plan: `b_n = ξ_plan(T_n) − u_n` is the planned DCM offset
//! at the planned touch-down, so a DCM on the plan satisfies the equality at the nominal point and the
//! solution is the nominal step. Small DCM errors are absorbed by `δr` (the ankle, which the DCM
//! controller actually uses), so the step moves only once the CoP box is exhausted: without it a 1 cm DCM
//! error early in a swing (`e^{ω(T−t)}` ≈ 15 on the bundled humanoid) moved the step by 15 cm, and the
//! estimator's DCM noise made the nominal walk step erratically and fall. The timing weight is on the *relative* change of `τ`
//! (`δτ/τ_n ≈ ω δT`), which makes `w_τ` independent of the step duration and of ω. The box is enlarged to
//! contain the nominal step and the duration bounds to contain `T_n` (the planner's own step is admissible by
//! definition; the plan's first step counts from the plan start), and the lower `τ` bound is
//! clipped to the upper one once `t + t_rem > T_max` (then the step lands `t_rem` from now). Khadiv's
//! offset bounds come from a periodic gait [Khadiv 2020]; ours are a box of half-width `m`
//! around the planned offset, because the plan, not a periodic gait, is the reference here.
//!
//! Solved with stride-qp's dense active-set solver ([`ActiveSetSolver`], [Goldfarb 1983]); every buffer
//! is allocated in [`StepAdjuster::new`]. A solve that does not succeed returns the nominal step with
//! [`StepAdjustmentStatus::Fallback`]; the outputs are never NaN.

use nalgebra::{Rotation2, Vector2};
use serde::{Deserialize, Serialize};
use stride_block::Foot;
use stride_qp::{ActiveSetSettings, ActiveSetSolver, DenseQp, QpSolver, QpStatus, SolverOutput};

use crate::error::{
    check_finite, check_finite2, check_non_negative, check_positive, Result, SimplifiedError,
};

/// Number of decision variables `[u_x, u_y, τ, b_x, b_y, s_x, s_y, δr_x, δr_y]`.
pub const STEP_ADJUSTMENT_VARIABLES: usize = 9;
const UX: usize = 0;
const UY: usize = 1;
const TAU: usize = 2;
const BX: usize = 3;
const BY: usize = 4;
const SX: usize = 5;
const SY: usize = 6;
const RX: usize = 7;
const RY: usize = 8;

/// Parameters of the step adjustment, sized for the bundled humanoid (`configs/robots/stride_humanoid.toml`:
/// CoM height 0.54 m, ω ≈ 4.26 s⁻¹, nominal width 0.15 m, planner `feet_distance_max` 0.22 m, steps of
/// 0.8–1.2 s).
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `enabled` | – | `false` | whether the runner adjusts steps (the solver itself always works) |
/// | `forward_max` | m | 0.20 | farthest touch-down ahead of the stance foot (stance frame x); the planner allows `√(0.22² − 0.15²)` = 0.16 m in nominal walking, a recovery step may reach further |
/// | `backward_max` | m | 0.12 | farthest touch-down behind the stance foot (stance frame, −x) |
/// | `lateral_min` | m | 0.14 | no-leg-crossing distance: the touch-down is at least this far outward (stance frame, away from the stance foot); the planner's `min_width` |
/// | `lateral_max` | m | 0.30 | farthest outward touch-down (2 × the nominal width) |
/// | `step_duration_min` | s | 0.6 | shortest step (touch-down to touch-down); below the planner's 0.8 s so a step can be sped up |
/// | `step_duration_max` | s | 1.2 | longest step; the planner's `step_duration_max` |
/// | `min_remaining_time` | s | 0.15 | the swing lands at least this long after now (`τ ≥ e^{ω(t + t_rem)}`) |
/// | `offset_margin` | m | 0.05 | half-width of the box around the planned DCM offset `b_n` (per axis, softened) |
/// | `step_weight` | m⁻² | 1 | `w_u` on `‖u − u_n‖²` |
/// | `timing_weight` | – | 10 | `w_τ` on `((τ − τ_n)/τ_n)²` (≈ `(ω δT)²`) |
/// | `offset_weight` | m⁻² | 1000 | `w_b` on `‖b − b_n‖²`; `w_b/w_u` = 1000 as in [Khadiv 2020]'s Bolt parameters |
/// | `slack_weight` | m⁻² | 1e5 | `w_s` on the slacks of the offset bounds |
/// | `cop_x` | m | 0.04 | half-length of the CoP box `δr` (stance frame x): the bundled sole is 0.20 m long; the DCM controller's ZMP may use all of it, the QP counts on less than half |
/// | `cop_y` | m | 0.015 | half-width of the CoP box (stance frame y); the sole is 0.09 m wide |
/// | `cop_weight` | m⁻² | 1 | `w_r` on `‖δr‖²`; with the amplification `α` ≈ 3–15 the ankle takes `α²/(α² + w_r/w_u)` of an error first |
/// | `deadband` | m | 0.02 | the runner moves the planned touch-down only when the solution differs from it by more than this (as IHMC's 0.02 m on Atlas): DCM errors of normal walking leave the plan alone, and the plan is not rebuilt every tick |
/// | `time_deadband` | s | 0.03 | the same for the touch-down time |
/// | `dcm_error_cutoff` | Hz | 0 (off) | cut-off of a first-order low-pass on the DCM error (measured − planned) the runner gives the QP (it reads the planned DCM plus the filtered error): a transient of the measured DCM shorter than the filter's time constant, amplified by `e^{ω(T−t)}` early in a swing, does not move the step |
/// | `touchdown_force` | N | 0 (off) | early touch-down: when the swing foot's estimated vertical ground force exceeds this in the second half of its swing while the plan has the sole `touchdown_height` or more above its landing height, the runner lands the step where the foot is, `touchdown_lead` later (the plan re-anchored at the real touch-down instead of the sole dragged on to its planned one) |
/// | `touchdown_height` | m | 0.01 | planned height of the swing sole above its landing height below which a loaded sole is an ordinary (slightly early) touch-down, left to the plan |
/// | `touchdown_lead` | s | 0.08 | time from a detected early touch-down to the planned one it becomes |
/// | `crossover_min` | m | 0 (off) | crossover step: when the solution's touch-down sits at the no-crossing bound (`lateral_min`: the DCM pushed towards the stance foot's side), the QP is solved again with the touch-down on the stance foot's far side, between `crossover_min` and `crossover_max` past the stance foot (stance frame y), and the cheaper of the two solutions is kept; more than the sole's width (0.09 m on the bundled humanoid) keeps the soles apart. The planner replans from the crossed feet, the next step uncrossing them, and the swing goes round the stance sole |
/// | `crossover_max` | m | 0.25 | farthest crossover touch-down past the stance foot (stance frame y) |
/// | `closing_dcm_margin` | m | 0.02 | closing step kept: the plan's last step is not adjusted while the CoP box (`cop_x`, `cop_y`) can still bring the DCM predicted at its touch-down this far inside the hull of the stance sole and the planned landed sole (the ankle absorbs the error); 0: off (the closing step is adjusted like any other) |
///
/// `validate()` requires finite positive lengths, weights and durations, `lateral_min < lateral_max`,
/// `step_duration_min < step_duration_max`, `min_remaining_time < step_duration_max` and, with the
/// crossover on, `crossover_min < crossover_max`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StepAdjustmentConfig {
    /// Whether the runner adjusts the steps.
    pub enabled: bool,
    /// Farthest touch-down ahead of the stance foot \[m\].
    pub forward_max: f64,
    /// Farthest touch-down behind the stance foot \[m\].
    pub backward_max: f64,
    /// Smallest outward distance of the touch-down from the stance foot (no leg crossing) \[m\].
    pub lateral_min: f64,
    /// Largest outward distance of the touch-down from the stance foot \[m\].
    pub lateral_max: f64,
    /// Shortest step, touch-down to touch-down \[s\].
    pub step_duration_min: f64,
    /// Longest step, touch-down to touch-down \[s\].
    pub step_duration_max: f64,
    /// Shortest remaining swing time \[s\].
    pub min_remaining_time: f64,
    /// Half-width of the DCM-offset box around the planned offset \[m\].
    pub offset_margin: f64,
    /// Weight on the footstep change \[m⁻²\].
    pub step_weight: f64,
    /// Weight on the relative change of `τ = e^{ωT}`.
    pub timing_weight: f64,
    /// Weight on the DCM-offset change \[m⁻²\].
    pub offset_weight: f64,
    /// Weight on the slacks of the offset bounds \[m⁻²\].
    pub slack_weight: f64,
    /// Half-length of the CoP box (stance frame x) \[m\].
    pub cop_x: f64,
    /// Half-width of the CoP box (stance frame y) \[m\].
    pub cop_y: f64,
    /// Weight on the CoP offset \[m⁻²\].
    pub cop_weight: f64,
    /// Smallest change of the touch-down position the runner applies \[m\].
    pub deadband: f64,
    /// Smallest change of the touch-down time the runner applies \[s\].
    pub time_deadband: f64,
    /// Cut-off of the low-pass on the DCM error the QP reads \[Hz\]; 0: unfiltered.
    pub dcm_error_cutoff: f64,
    /// Vertical force on the swing foot above which a late swing lands where it is \[N\]; 0: off.
    pub touchdown_force: f64,
    /// Time from a detected early touch-down to the planned touch-down it becomes \[s\].
    pub touchdown_lead: f64,
    /// Planned sole height above the landing height below which a loaded sole is left to the plan \[m\].
    pub touchdown_height: f64,
    /// Smallest distance of a crossover touch-down past the stance foot \[m\]; 0: no crossover.
    pub crossover_min: f64,
    /// Largest distance of a crossover touch-down past the stance foot \[m\].
    pub crossover_max: f64,
    /// Depth inside the final double support's hull the CoP box must still bring the predicted DCM to for
    /// the plan's last step to be kept \[m\]; 0: the closing step is adjusted like any other.
    pub closing_dcm_margin: f64,
}

impl Default for StepAdjustmentConfig {
    fn default() -> Self {
        Self {
            enabled: false,
            forward_max: 0.20,
            backward_max: 0.12,
            lateral_min: 0.14,
            lateral_max: 0.30,
            step_duration_min: 0.6,
            step_duration_max: 1.2,
            min_remaining_time: 0.15,
            offset_margin: 0.05,
            step_weight: 1.0,
            timing_weight: 10.0,
            offset_weight: 1000.0,
            slack_weight: 1e5,
            cop_x: 0.04,
            cop_y: 0.015,
            cop_weight: 1.0,
            deadband: 0.02,
            time_deadband: 0.03,
            dcm_error_cutoff: 0.0,
            touchdown_force: 0.0,
            touchdown_lead: 0.08,
            touchdown_height: 0.01,
            crossover_min: 0.0,
            crossover_max: 0.25,
            closing_dcm_margin: 0.02,
        }
    }
}

impl StepAdjustmentConfig {
    /// Checks the ranges documented on the struct.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("step_adjustment.forward_max", self.forward_max),
            ("step_adjustment.backward_max", self.backward_max),
            ("step_adjustment.lateral_min", self.lateral_min),
            ("step_adjustment.lateral_max", self.lateral_max),
            ("step_adjustment.step_duration_min", self.step_duration_min),
            ("step_adjustment.step_duration_max", self.step_duration_max),
            (
                "step_adjustment.min_remaining_time",
                self.min_remaining_time,
            ),
            ("step_adjustment.offset_margin", self.offset_margin),
            ("step_adjustment.step_weight", self.step_weight),
            ("step_adjustment.timing_weight", self.timing_weight),
            ("step_adjustment.offset_weight", self.offset_weight),
            ("step_adjustment.slack_weight", self.slack_weight),
            ("step_adjustment.cop_weight", self.cop_weight),
        ] {
            check_positive(name, v)?;
        }
        check_non_negative("step_adjustment.cop_x", self.cop_x)?;
        check_non_negative("step_adjustment.cop_y", self.cop_y)?;
        check_non_negative("step_adjustment.deadband", self.deadband)?;
        check_non_negative("step_adjustment.time_deadband", self.time_deadband)?;
        check_non_negative("step_adjustment.dcm_error_cutoff", self.dcm_error_cutoff)?;
        check_non_negative("step_adjustment.touchdown_force", self.touchdown_force)?;
        check_positive("step_adjustment.touchdown_lead", self.touchdown_lead)?;
        check_non_negative("step_adjustment.touchdown_height", self.touchdown_height)?;
        check_non_negative("step_adjustment.crossover_min", self.crossover_min)?;
        check_positive("step_adjustment.crossover_max", self.crossover_max)?;
        check_non_negative(
            "step_adjustment.closing_dcm_margin",
            self.closing_dcm_margin,
        )?;
        let order = |name, value, ok, reason| {
            if ok {
                Ok(())
            } else {
                Err(SimplifiedError::InvalidParameter {
                    name,
                    value,
                    reason,
                })
            }
        };
        order(
            "step_adjustment.lateral_max",
            self.lateral_max,
            self.lateral_max > self.lateral_min,
            "must be > lateral_min (the reachable lateral interval is empty)",
        )?;
        order(
            "step_adjustment.step_duration_max",
            self.step_duration_max,
            self.step_duration_max > self.step_duration_min,
            "must be > step_duration_min",
        )?;
        order(
            "step_adjustment.min_remaining_time",
            self.min_remaining_time,
            self.min_remaining_time < self.step_duration_max,
            "must be < step_duration_max",
        )?;
        order(
            "step_adjustment.crossover_max",
            self.crossover_max,
            self.crossover_min == 0.0 || self.crossover_max > self.crossover_min,
            "must be > crossover_min (the crossover interval is empty)",
        )
    }
}

/// One step-adjustment problem (plain data; 2D vectors are world x, y in metres).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct StepAdjustmentInput {
    /// Measured DCM `ξ` \[m\].
    pub dcm: Vector2<f64>,
    /// LIPM natural frequency ω \[s⁻¹\].
    pub omega: f64,
    /// Which foot stands.
    pub stance: Foot,
    /// Stance foot (sole) position `p_s` \[m\].
    pub stance_position: Vector2<f64>,
    /// Stance foot yaw `ψ_s` \[rad\].
    pub stance_yaw: f64,
    /// The CoP `r` held until touch-down (the planned single-support ZMP) \[m\].
    pub stance_cop: Vector2<f64>,
    /// Nominal next touch-down position `u_n` (world) \[m\].
    pub nominal_step: Vector2<f64>,
    /// Nominal DCM offset at touch-down `b_n = ξ_plan(T_n) − u_n` (world) \[m\].
    pub nominal_offset: Vector2<f64>,
    /// Time since the stance foot touched down `t` \[s\].
    pub time_since_touchdown: f64,
    /// Nominal step duration `T_n` (stance touch-down to the next touch-down) \[s\].
    pub nominal_duration: f64,
}

/// How a solve ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum StepAdjustmentStatus {
    /// No solve yet.
    #[default]
    NotSolved,
    /// The QP was solved; the step is its solution.
    Solved,
    /// The QP failed; the step is the nominal one.
    Fallback,
}

/// What a solve reports beside the step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct StepAdjustmentDiagnostics {
    /// How the solve ended.
    pub status: StepAdjustmentStatus,
    /// The QP backend's status.
    pub qp_status: QpStatus,
    /// Active-set iterations.
    pub iterations: usize,
    /// Slacks of the offset bounds `s` (stance frame) \[m\]; > 0 when the offset box is violated.
    pub offset_slack: Vector2<f64>,
    /// DCM offset at touch-down `b` (world) \[m\].
    pub offset: Vector2<f64>,
    /// Whether a box or duration bound is active at the solution.
    pub bound_active: bool,
    /// CoP offset `δr` the solution counts on (world) \[m\].
    pub cop_offset: Vector2<f64>,
    /// Whether the touch-down is a crossover (past the stance foot, `crossover_min`).
    pub crossover: bool,
}

/// The adjusted step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct StepAdjustment {
    /// Adjusted touch-down position `u_T` (world) \[m\].
    pub touchdown: Vector2<f64>,
    /// Adjusted step duration `T = ln(τ)/ω` (from the stance touch-down) \[s\].
    pub duration: f64,
    /// Remaining swing time `T − t` \[s\].
    pub remaining: f64,
    /// `u_T − u_n` (world) \[m\].
    pub displacement: Vector2<f64>,
    /// Diagnostics.
    pub diagnostics: StepAdjustmentDiagnostics,
}

/// The step-adjustment solver: a 7-variable QP (module documentation) on preallocated buffers.
pub struct StepAdjuster {
    config: StepAdjustmentConfig,
    qp: DenseQp,
    solver: ActiveSetSolver,
    out: SolverOutput,
    /// The crossover's solver and output (`crossover_min` > 0): its own, so that the main solve's warm
    /// start is the same with the crossover on or off.
    cross_solver: ActiveSetSolver,
    cross_out: SolverOutput,
    /// Stance position of the step whose touch-down crossed over: the rest of that step stays crossed.
    crossed_step: Option<Vector2<f64>>,
    result: StepAdjustment,
}

impl StepAdjuster {
    /// Validates `config` and allocates every buffer; [`StepAdjuster::solve`] allocates nothing.
    pub fn new(config: &StepAdjustmentConfig) -> Result<Self> {
        config.validate()?;
        let mut qp = DenseQp::new(STEP_ADJUSTMENT_VARIABLES, 2, 4);
        let mut solver = ActiveSetSolver::new(ActiveSetSettings::default());
        solver.reserve(STEP_ADJUSTMENT_VARIABLES, 2, 4);
        let out = SolverOutput::new(&qp);
        let mut cross_solver = ActiveSetSolver::new(ActiveSetSettings::default());
        cross_solver.reserve(STEP_ADJUSTMENT_VARIABLES, 2, 4);
        let cross_out = SolverOutput::new(&qp);
        // The structure that never changes: the equality's unit columns and the softened offset rows.
        let mut e = qp.eq_matrix_mut();
        e[(0, UX)] = 1.0;
        e[(0, BX)] = 1.0;
        e[(1, UY)] = 1.0;
        e[(1, BY)] = 1.0;
        let mut c = qp.ineq_matrix_mut();
        c[(0, BX)] = 1.0;
        c[(0, SX)] = 1.0; //  b_x + s_x ≥ b_n,x − m
        c[(1, BX)] = 1.0;
        c[(1, SX)] = -1.0; // b_x − s_x ≤ b_n,x + m
        c[(2, BY)] = 1.0;
        c[(2, SY)] = 1.0;
        c[(3, BY)] = 1.0;
        c[(3, SY)] = -1.0;
        Ok(Self {
            config: *config,
            qp,
            solver,
            out,
            cross_solver,
            cross_out,
            crossed_step: None,
            result: StepAdjustment::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &StepAdjustmentConfig {
        &self.config
    }

    /// The QP of the last solve (for checks with another backend or [`stride_qp::check_kkt`]).
    pub fn qp(&self) -> &DenseQp {
        &self.qp
    }

    /// The active-set solver's output of the last solve (primal and multipliers).
    pub fn solver_output(&self) -> &SolverOutput {
        &self.out
    }

    /// The last result.
    pub fn result(&self) -> &StepAdjustment {
        &self.result
    }

    /// Solves the problem of `input`. Non-finite inputs, `ω ≤ 0`, a negative time or a non-positive nominal
    /// duration are errors (nothing changes); a failed QP gives the nominal step ([`StepAdjustmentStatus::Fallback`]).
    pub fn solve(&mut self, input: &StepAdjustmentInput) -> Result<&StepAdjustment> {
        check_input(input)?;
        let nominal = self.fill(input);
        self.solver.solve(&self.qp, &mut self.out);
        let crossover = self.crossover(input);
        let x = &self.out.x;
        let rot = Rotation2::new(input.stance_yaw);
        let ok = self.out.status.is_success() && x.iter().all(|v| v.is_finite()) && x[TAU] > 0.0;
        let (u, tau, b, s) = if ok {
            (
                Vector2::new(x[UX], x[UY]),
                x[TAU],
                Vector2::new(x[BX], x[BY]),
                Vector2::new(x[SX], x[SY]),
            )
        } else {
            (nominal.u, nominal.tau, nominal.b, Vector2::zeros())
        };
        let touchdown = input.stance_position + rot * u;
        let duration = tau.ln() / input.omega;
        self.result = StepAdjustment {
            touchdown,
            duration,
            remaining: duration - input.time_since_touchdown,
            displacement: touchdown - input.nominal_step,
            diagnostics: StepAdjustmentDiagnostics {
                status: if ok {
                    StepAdjustmentStatus::Solved
                } else {
                    StepAdjustmentStatus::Fallback
                },
                qp_status: self.out.status,
                iterations: self.out.iterations,
                offset_slack: s,
                offset: rot * b,
                bound_active: ok && self.bound_active(),
                cop_offset: if ok {
                    rot * Vector2::new(x[RX], x[RY])
                } else {
                    Vector2::zeros()
                },
                crossover: ok && crossover,
            },
        };
        Ok(&self.result)
    }

    /// The crossover (`crossover_min` > 0): when the main solution's touch-down is at the no-crossing bound,
    /// the same QP with the lateral bounds on the stance foot's far side (`crossover_min`..`crossover_max`
    /// past it); its solution replaces the main one in `out` when it succeeds at a lower cost. Once a step
    /// has crossed over (same stance position), the rest of its solves keep the crossed solution whenever
    /// it succeeds (no switching back and forth across the stance foot from one tick to the next). Returns
    /// whether it did. [`StepAdjuster::qp`] is then the crossover's QP (its lateral bounds), otherwise the
    /// main one.
    fn crossover(&mut self, input: &StepAdjustmentInput) -> bool {
        let c = self.config;
        if c.crossover_min <= 0.0 || !self.out.status.is_success() {
            return false;
        }
        // the swing foot's side: +1 when it steps to the left of the stance foot
        let side = input.stance.other().side();
        let inner = if side > 0.0 {
            self.qp.lower_bounds()[UY]
        } else {
            self.qp.upper_bounds()[UY]
        };
        let committed = self.crossed_step == Some(input.stance_position);
        let uy = self.out.x[UY];
        if !committed && (uy - inner).abs() > 1e-9 * (1.0 + inner.abs()) {
            return false;
        }
        let (lo, hi) = if side > 0.0 {
            (-c.crossover_max, -c.crossover_min)
        } else {
            (c.crossover_min, c.crossover_max)
        };
        let main = (self.qp.lower_bounds()[UY], self.qp.upper_bounds()[UY]);
        self.qp.lower_bounds_mut()[UY] = lo;
        self.qp.upper_bounds_mut()[UY] = hi;
        self.cross_solver.solve(&self.qp, &mut self.cross_out);
        let crossed = &self.cross_out;
        let better = crossed.status.is_success()
            && crossed.x.iter().all(|v| v.is_finite())
            && crossed.x[TAU] > 0.0
            && (committed || crossed.objective < self.out.objective);
        if better {
            self.crossed_step = Some(input.stance_position);
            std::mem::swap(&mut self.out, &mut self.cross_out);
        } else {
            self.qp.lower_bounds_mut()[UY] = main.0;
            self.qp.upper_bounds_mut()[UY] = main.1;
        }
        better
    }

    /// Whether a variable bound (box or duration) holds with equality at the solution (1e-9).
    fn bound_active(&self) -> bool {
        let x = &self.out.x;
        [UX, UY, TAU].iter().any(|&j| {
            let (lo, hi) = (self.qp.lower_bounds()[j], self.qp.upper_bounds()[j]);
            let tol = 1e-9 * (1.0 + x[j].abs());
            x[j] - lo <= tol || hi - x[j] <= tol
        })
    }

    /// Writes the QP of `input` into the preallocated buffers; returns the nominal point (stance frame).
    fn fill(&mut self, input: &StepAdjustmentInput) -> Nominal {
        let c = &self.config;
        let rot_t = Rotation2::new(-input.stance_yaw);
        let w = input.omega;
        let t = input.time_since_touchdown;
        let k = rot_t * (input.dcm - input.stance_cop) * (-w * t).exp();
        let rhs = rot_t * (input.stance_cop - input.stance_position);
        let u_n = rot_t * (input.nominal_step - input.stance_position);
        let b_n = rot_t * input.nominal_offset;
        let tau_n = (w * input.nominal_duration).exp();
        let nominal = Nominal {
            u: u_n,
            tau: tau_n,
            b: b_n,
        };
        let weights = [
            c.step_weight,
            c.step_weight,
            c.timing_weight / (tau_n * tau_n),
            c.offset_weight,
            c.offset_weight,
            c.slack_weight,
            c.slack_weight,
            c.cop_weight,
            c.cop_weight,
        ];
        let x_n = [u_n.x, u_n.y, tau_n, b_n.x, b_n.y, 0.0, 0.0, 0.0, 0.0];
        let h = self.qp.hessian_mut();
        h.fill(0.0);
        for (j, wj) in weights.iter().enumerate() {
            h[(j, j)] = 2.0 * wj;
        }
        let g = self.qp.gradient_mut();
        for j in 0..STEP_ADJUSTMENT_VARIABLES {
            g[j] = -2.0 * weights[j] * x_n[j];
        }
        let mut e = self.qp.eq_matrix_mut();
        e[(0, TAU)] = -k.x;
        e[(1, TAU)] = -k.y;
        let alpha = (tau_n * (-w * t).exp() - 1.0).max(0.0);
        e[(0, RX)] = alpha;
        e[(1, RY)] = alpha;
        let mut f = self.qp.eq_rhs_mut();
        f[0] = rhs.x;
        f[1] = rhs.y;
        let m = c.offset_margin;
        let mut l = self.qp.ineq_lower_mut();
        l[0] = b_n.x - m;
        l[1] = f64::NEG_INFINITY;
        l[2] = b_n.y - m;
        l[3] = f64::NEG_INFINITY;
        let mut u = self.qp.ineq_upper_mut();
        u[0] = f64::INFINITY;
        u[1] = b_n.x + m;
        u[2] = f64::INFINITY;
        u[3] = b_n.y + m;
        self.fill_bounds(input, &nominal);
        nominal
    }

    /// Box of the touch-down (stance frame, enlarged to contain the nominal step), duration bounds, slacks ≥ 0.
    fn fill_bounds(&mut self, input: &StepAdjustmentInput, nominal: &Nominal) {
        let c = &self.config;
        let w = input.omega;
        let side = input.stance.other().side();
        let (y_lo, y_hi) = if side > 0.0 {
            (c.lateral_min, c.lateral_max)
        } else {
            (-c.lateral_max, -c.lateral_min)
        };
        let (x_lo, x_hi) = (-c.backward_max, c.forward_max);
        // duration bounds enlarged to contain the nominal duration (the plan's first step counts from
        // the plan start); the remaining-time bound stays hard
        let t_lo = c
            .step_duration_min
            .min(input.nominal_duration)
            .max(input.time_since_touchdown + c.min_remaining_time);
        let tau_hi = (w * c.step_duration_max.max(input.nominal_duration)).exp();
        let tau_lo = (w * t_lo).exp();
        let lb = self.qp.lower_bounds_mut();
        lb[UX] = x_lo.min(nominal.u.x);
        lb[UY] = y_lo.min(nominal.u.y);
        lb[TAU] = tau_lo;
        lb[BX] = f64::NEG_INFINITY;
        lb[BY] = f64::NEG_INFINITY;
        lb[SX] = 0.0;
        lb[SY] = 0.0;
        let ub = self.qp.upper_bounds_mut();
        ub[UX] = x_hi.max(nominal.u.x);
        ub[UY] = y_hi.max(nominal.u.y);
        ub[TAU] = tau_hi.max(tau_lo);
        ub[BX] = f64::INFINITY;
        ub[BY] = f64::INFINITY;
        ub[SX] = f64::INFINITY;
        ub[SY] = f64::INFINITY;
        ub[RX] = c.cop_x;
        ub[RY] = c.cop_y;
        let lb = self.qp.lower_bounds_mut();
        lb[RX] = -c.cop_x;
        lb[RY] = -c.cop_y;
    }
}

/// The nominal point in the stance frame.
struct Nominal {
    u: Vector2<f64>,
    tau: f64,
    b: Vector2<f64>,
}

fn check_input(i: &StepAdjustmentInput) -> Result<()> {
    check_finite2("dcm", &i.dcm)?;
    check_finite2("stance_position", &i.stance_position)?;
    check_finite2("stance_cop", &i.stance_cop)?;
    check_finite2("nominal_step", &i.nominal_step)?;
    check_finite2("nominal_offset", &i.nominal_offset)?;
    check_finite("stance_yaw", i.stance_yaw)?;
    check_finite("time_since_touchdown", i.time_since_touchdown)?;
    check_positive("omega", i.omega)?;
    check_positive("nominal_duration", i.nominal_duration)?;
    if i.time_since_touchdown < 0.0 {
        return Err(SimplifiedError::InvalidParameter {
            name: "time_since_touchdown",
            value: i.time_since_touchdown,
            reason: "must be >= 0",
        });
    }
    // e^{ωT} must stay representable: T ≤ 100/ω keeps τ below e^100.
    if i.omega * (i.nominal_duration.max(i.time_since_touchdown)) > 100.0 {
        return Err(SimplifiedError::InvalidParameter {
            name: "nominal_duration",
            value: i.nominal_duration,
            reason: "ω·T above 100: e^{ωT} is not representable accurately",
        });
    }
    Ok(())
}
