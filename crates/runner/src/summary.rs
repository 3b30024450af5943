//! The end-of-run summary: what the scheduler accumulates while the loop runs, and its rendering.

use std::path::PathBuf;

use serde::Serialize;

use crate::config::Goal;
use crate::diagnosis::Diagnosis;
use crate::estimation_summary::EstimationSummary;
use crate::gait::GaitFigures;
use crate::log::LogStats;
use stride_planner::geometry::wrap_angle;

use crate::stack::soles_heading;

/// How a run ended.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Outcome {
    /// The scenario duration elapsed.
    DurationReached,
    /// The goal was reached and the robot stood still.
    GoalReached,
    /// The robot fell.
    Fell {
        /// Why (height, tilt, simulator).
        reason: String,
    },
    /// Ctrl-C (or the stop flag).
    Interrupted,
    /// A layer or the robot failed, or panicked.
    Error {
        /// The error.
        message: String,
    },
}

impl std::fmt::Display for Outcome {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Outcome::DurationReached => write!(f, "duration reached"),
            Outcome::GoalReached => write!(f, "goal reached, standing still"),
            Outcome::Fell { reason } => write!(f, "FELL ({reason})"),
            Outcome::Interrupted => write!(f, "interrupted"),
            Outcome::Error { message } => write!(f, "ERROR: {message}"),
        }
    }
}

/// Root-mean-square and maximum of a tracking error.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct ErrorStats {
    /// RMS \[m\].
    pub rms: f64,
    /// Max \[m\].
    pub max: f64,
    #[serde(skip)]
    sum_sq: f64,
    #[serde(skip)]
    n: u64,
}

impl ErrorStats {
    pub(crate) fn add(&mut self, e: f64) {
        self.sum_sq += e * e;
        self.n += 1;
        self.max = self.max.max(e);
        self.rms = (self.sum_sq / self.n as f64).sqrt();
    }
}

/// Tracking errors of the plant's own CoM and DCM (the plant's model on its true state), against the same
/// references as [`RunSummary::dcm_error`] and [`RunSummary::com_error`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct PlantTracking {
    /// DCM tracking error (planar) \[m\].
    pub dcm_error: ErrorStats,
    /// CoM tracking error (3D) \[m\].
    pub com_error: ErrorStats,
}

/// Percentiles of a layer's solve times \[s\].
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct SolveTimes {
    /// Median.
    pub p50: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Maximum.
    pub max: f64,
    /// Number of solves.
    pub count: usize,
}

impl SolveTimes {
    pub(crate) fn from(samples: &mut [f64]) -> Self {
        if samples.is_empty() {
            return Self::default();
        }
        samples.sort_by(f64::total_cmp);
        let q = |p: f64| samples[((samples.len() - 1) as f64 * p).round() as usize];
        Self {
            p50: q(0.5),
            p99: q(0.99),
            max: samples[samples.len() - 1],
            count: samples.len(),
        }
    }
}

/// The end-of-run summary.
#[derive(Debug, Clone, Serialize)]
pub struct RunSummary {
    /// Scenario name.
    pub scenario: String,
    /// Plant used.
    pub plant: String,
    /// How the run ended.
    pub outcome: Outcome,
    /// Simulated time \[s\].
    pub simulated_time: f64,
    /// Wall-clock time of the loop \[s\].
    pub wall_time: f64,
    /// Simulated / wall-clock time.
    pub real_time_factor: f64,
    /// Planar distance of the soles' mid-point from its start \[m\].
    pub distance: f64,
    /// Forward displacement (along the initial heading) / simulated time [m/s].
    pub mean_forward_speed: f64,
    /// Final planar position of the soles' mid-point \[m\] and heading \[deg\].
    pub final_pose: [f64; 3],
    /// Planar distance to the goal at the end \[m\] (pose/waypoint goals).
    pub goal_distance: Option<f64>,
    /// Heading error to the goal at the end \[deg\].
    pub goal_heading_error_deg: Option<f64>,
    /// Lowest base height relative to the initial one [-].
    pub min_base_height_fraction: f64,
    /// Largest torso tilt \[deg\].
    pub max_tilt_deg: f64,
    /// DCM tracking error (measured vs planned, planar) \[m\]: the plant's true state with the
    /// controllers' model (their view of the truth; the plant's own model in
    /// [`RunSummary::plant_tracking`]).
    pub dcm_error: ErrorStats,
    /// CoM tracking error (measured vs simplified-layer reference, 3D) \[m\], as `dcm_error`.
    pub com_error: ErrorStats,
    /// The DCM and CoM tracking errors of the plant's true state with the plant's own model, when it
    /// differs from the controllers' (`[sim.model]`); `None` otherwise (then `dcm_error` and `com_error`
    /// are the plant's).
    pub plant_tracking: Option<PlantTracking>,
    /// ZMP tracking error (measured vs desired) \[m\], over ticks with a measurable ZMP.
    pub zmp_error: ErrorStats,
    /// Feet tracking error (measured vs planned sole positions, worst foot) \[m\].
    pub feet_error: ErrorStats,
    /// Whole-body QP solve times \[s\].
    pub wbc_solve_time: SolveTimes,
    /// Simplified-layer solve times \[s\] of the running controller.
    pub simplified_solve_time: SolveTimes,
    /// Joints whose motor torque sat at its effort limit, with the simulated time spent there \[s\],
    /// longest first (empty when no joint saturated, or the plant does not report it).
    pub joint_saturation: Vec<(String, f64)>,
    /// Fall diagnosis: the fall's direction and time, ZMP at the sole edges, the DCM error's peak.
    pub diagnosis: Diagnosis,
    /// Steady forward speed and specific energetic cost.
    pub gait: GaitFigures,
    /// Whole-body ticks solved by the relaxed fallback QP.
    pub wbc_fallbacks: u64,
    /// Whole-body ticks that held the previous command.
    pub wbc_holds: u64,
    /// Simplified-layer ticks that held the previous references.
    pub simplified_holds: u64,
    /// Planner replans.
    pub replans: u64,
    /// Footsteps moved by the step adjustment (`simplified.step_adjustment`), and the adjustments the planner
    /// refused (the plan kept).
    pub step_adjustments: (u64, u64),
    /// Late swings landed where the foot struck the ground (`simplified.step_adjustment.touchdown_force`).
    pub early_touchdowns: u64,
    /// Double supports held by a push (`simplified.push`), and the plan's delay behind the run's time at
    /// the end \[s\].
    pub push_holds: (u64, f64),
    /// Whole-body ticks with the TSID's push weights (`simplified.push.wbc_com_weight`,
    /// `wbc_upright_weight`).
    pub push_weight_ticks: u64,
    /// Realtime mode: whole-body ticks that started late.
    pub deadline_misses: u64,
    /// Estimation errors (estimate − plant truth).
    pub estimation: EstimationSummary,
    /// Log file and counters.
    pub log: Option<(PathBuf, LogStats)>,
}

impl RunSummary {
    /// An empty summary of `scenario` on `plant`, before the loop runs.
    pub fn new(scenario: &str, plant: &str) -> Self {
        Self {
            scenario: scenario.into(),
            plant: plant.into(),
            outcome: Outcome::DurationReached,
            simulated_time: 0.0,
            wall_time: 0.0,
            real_time_factor: 0.0,
            distance: 0.0,
            mean_forward_speed: 0.0,
            final_pose: [0.0; 3],
            goal_distance: None,
            goal_heading_error_deg: None,
            min_base_height_fraction: 1.0,
            max_tilt_deg: 0.0,
            dcm_error: ErrorStats::default(),
            com_error: ErrorStats::default(),
            plant_tracking: None,
            zmp_error: ErrorStats::default(),
            feet_error: ErrorStats::default(),
            wbc_solve_time: SolveTimes::default(),
            simplified_solve_time: SolveTimes::default(),
            joint_saturation: Vec::new(),
            diagnosis: Diagnosis::default(),
            gait: GaitFigures::default(),
            wbc_fallbacks: 0,
            wbc_holds: 0,
            simplified_holds: 0,
            replans: 0,
            step_adjustments: (0, 0),
            early_touchdowns: 0,
            push_holds: (0, 0.0),
            push_weight_ticks: 0,
            deadline_misses: 0,
            estimation: EstimationSummary::default(),
            log: None,
        }
    }

    /// Fills the end-of-run figures: distance, speed and goal errors from the start and final stance
    /// poses ([`mid_pose`]), the real-time factor from the loop's wall-clock time \[s\].
    pub(crate) fn finish(&mut self, start: [f64; 3], end: [f64; 3], goal: &Goal, wall: f64) {
        self.wall_time = wall;
        self.real_time_factor = if wall > 0.0 {
            self.simulated_time / wall
        } else {
            0.0
        };
        let (dx, dy) = (end[0] - start[0], end[1] - start[1]);
        self.distance = (dx * dx + dy * dy).sqrt();
        let h = start[2];
        self.mean_forward_speed = if self.simulated_time > 0.0 {
            (dx * h.cos() + dy * h.sin()) / self.simulated_time
        } else {
            0.0
        };
        self.final_pose = [end[0], end[1], end[2].to_degrees()];
        if let Some(g) = goal_pose(goal) {
            self.goal_distance = Some(((end[0] - g[0]).powi(2) + (end[1] - g[1]).powi(2)).sqrt());
            self.goal_heading_error_deg = Some(wrap_angle(end[2] - g[2]).to_degrees());
        }
    }
}

/// Planar pose (x, y \[m\], heading \[rad\]) of the soles' mid-point: where the robot stands.
pub fn mid_pose(soles: &[nalgebra::Isometry3<f64>; 2]) -> [f64; 3] {
    let p = (soles[0].translation.vector + soles[1].translation.vector) * 0.5;
    [p.x, p.y, soles_heading(&soles[0], &soles[1])]
}

/// Final planar goal pose (x, y, heading rad) of pose and waypoint goals.
pub fn goal_pose(goal: &Goal) -> Option<[f64; 3]> {
    match goal {
        Goal::Pose(p) => Some([p.x, p.y, p.heading_deg.to_radians()]),
        Goal::Waypoints { points } => points
            .last()
            .map(|p| [p.x, p.y, p.heading_deg.to_radians()]),
        _ => None,
    }
}

impl RunSummary {
    /// The summary as printed at the end of `stride run`.
    pub fn render(&self) -> String {
        let mut s = String::new();
        use std::fmt::Write as _;
        let _ = writeln!(
            s,
            "scenario {} on the {} plant: {}",
            self.scenario, self.plant, self.outcome
        );
        self.diagnosis.render(&mut s, &self.joint_saturation);
        let _ = writeln!(
            s,
            "  simulated {:.2} s in {:.2} s wall clock: {:.1}x real time",
            self.simulated_time, self.wall_time, self.real_time_factor
        );
        let _ = writeln!(
            s,
            "  walked {:.3} m, mean forward speed {:.3} m/s, final pose x {:.3} m y {:.3} m heading {:.1}°",
            self.distance, self.mean_forward_speed, self.final_pose[0], self.final_pose[1], self.final_pose[2]
        );
        self.gait.render(&mut s);
        if let (Some(d), Some(h)) = (self.goal_distance, self.goal_heading_error_deg) {
            let _ = writeln!(s, "  goal: {:.3} m away, heading error {:.1}°", d, h);
        }
        let _ = writeln!(
            s,
            "  lowest base height {:.0} % of initial, largest torso tilt {:.1}°",
            self.min_base_height_fraction * 100.0,
            self.max_tilt_deg
        );
        let _ = writeln!(s, "  tracking        RMS [mm]   max [mm]");
        let plant = self
            .plant_tracking
            .as_ref()
            .map(|p| [("DCM plant", &p.dcm_error), ("CoM plant", &p.com_error)]);
        for (name, e) in [
            ("DCM", &self.dcm_error),
            ("CoM", &self.com_error),
            ("ZMP", &self.zmp_error),
            ("feet", &self.feet_error),
        ]
        .into_iter()
        .chain(plant.into_iter().flatten())
        {
            let _ = writeln!(
                s,
                "    {:<10} {:>10.1} {:>10.1}",
                name,
                e.rms * 1e3,
                e.max * 1e3
            );
        }
        let _ = writeln!(
            s,
            "  solve time      p50 [µs]   p99 [µs]   max [µs]   solves"
        );
        for (name, t) in [
            ("whole-body", &self.wbc_solve_time),
            ("simplified", &self.simplified_solve_time),
        ] {
            let _ = writeln!(
                s,
                "    {:<10} {:>10.1} {:>10.1} {:>10.1} {:>8}",
                name,
                t.p50 * 1e6,
                t.p99 * 1e6,
                t.max * 1e6,
                t.count
            );
        }
        render_saturation(&mut s, &self.joint_saturation);
        self.estimation.render(&mut s);
        let _ = writeln!(
            s,
            "  QP fallbacks {}, held commands {}, simplified holds {}, replans {}, deadline misses {}",
            self.wbc_fallbacks, self.wbc_holds, self.simplified_holds, self.replans, self.deadline_misses
        );
        let (applied, refused) = self.step_adjustments;
        if applied + refused > 0 {
            let _ = writeln!(
                s,
                "  step adjustments {applied} (refused by the planner {refused})"
            );
        }
        if self.early_touchdowns > 0 {
            let _ = writeln!(
                s,
                "  early touch-downs {} (swings landed where they struck the ground)",
                self.early_touchdowns
            );
        }
        let (holds, delay) = self.push_holds;
        if holds > 0 {
            let _ = writeln!(
                s,
                "  double supports held by a push {holds} (the plan {delay:.2} s behind)"
            );
        }
        if self.push_weight_ticks > 0 {
            let _ = writeln!(
                s,
                "  whole-body ticks with the push weights {}",
                self.push_weight_ticks
            );
        }
        if let Some((p, st)) = &self.log {
            let _ = writeln!(
                s,
                "  log: {} ({} messages, {:.1} MB, writer waits {})",
                p.display(),
                st.messages,
                st.bytes as f64 / 1e6,
                st.stalls
            );
        }
        s
    }
}

/// The saturation line of the summary: how many joints sat at their effort limit, the longest three.
fn render_saturation(s: &mut String, joints: &[(String, f64)]) {
    use std::fmt::Write as _;
    if joints.is_empty() {
        let _ = writeln!(s, "  joint torque saturation: none");
        return;
    }
    let _ = writeln!(
        s,
        "  joint torque saturation: {} joints at their effort limit (longest: {})",
        joints.len(),
        longest_saturations(joints, 3)
    );
}

/// The first `n` joints of a saturation list (longest first) as `name 0.12 s, ...`; `none` when empty.
pub(crate) fn longest_saturations(joints: &[(String, f64)], n: usize) -> String {
    if joints.is_empty() {
        return "none".into();
    }
    let top: Vec<String> = joints
        .iter()
        .take(n)
        .map(|(name, t)| format!("{name} {t:.2} s"))
        .collect();
    top.join(", ")
}
