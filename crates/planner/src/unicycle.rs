//! Unicycle model, its feedback-linearising controller and the greedy footstep search
//! [Romualdi 2022, eqs. 10.1.1–10.1.14].
//!
//! The unicycle `ȯ = R(θ)[v; v_lat]`, `θ̇ = ω` (v_lat is only used by velocity commands; the thesis unicycle has
//! v_lat = 0) is driven either directly (velocity goals) or by the controller [Romualdi 2022, eq. 10.1.6]
//! `u = B(θ)⁻¹ (ẋ_F* − K (x_F − x_F*))` that makes a point F rigidly attached ahead of the unicycle track a
//! reference trajectory `x_F*(t)` built from the goal (straight lines between waypoints, arcs for turning in
//! place). The commands are saturated to the speed limits derived from the step limits. Feet are the wheels
//! [Romualdi 2022, eq. 10.1.7]: `o_L/R = o + R(θ)[0; ±w/2]`, yaw θ. Each unicycle sample is a candidate touch-down instant; the
//! search picks, for each step, the candidate minimising `K_t/Δt² + K_x Δx²` [Romualdi 2022, eq. 10.1.10] under [Romualdi 2022, eqs. 10.1.11–10.1.13].

use nalgebra::Vector2;

use crate::config::{FirstSwingFoot, PlannerConfig};
use crate::contacts::Foot;
use crate::error::PlannerError;
use crate::geometry::{feet_lateral_separation, wrap_angle, Pose2};
use crate::goal::Goal;

/// A piece of the reference trajectory of the controlled point F.
#[derive(Clone, Copy, Debug)]
enum Leg {
    /// F moves on a straight line at constant speed.
    Line {
        from: Vector2<f64>,
        to: Vector2<f64>,
        duration: f64,
        /// Uniform deceleration over the end of the line \[m/s²\] (0: constant speed to `to`).
        deceleration: f64,
        /// Speed before the braking \[m/s\] (with a deceleration).
        cruise: f64,
    },
    /// The unicycle turns in place about `center`: F = center + R(θ) d.
    Arc {
        center: Vector2<f64>,
        yaw_from: f64,
        yaw_to: f64,
        duration: f64,
    },
}

impl Leg {
    fn duration(&self) -> f64 {
        match self {
            Leg::Line { duration, .. } | Leg::Arc { duration, .. } => *duration,
        }
    }
}

fn rot(yaw: f64, v: Vector2<f64>) -> Vector2<f64> {
    let (s, c) = yaw.sin_cos();
    Vector2::new(c * v.x - s * v.y, s * v.x + c * v.y)
}

/// What the reference does next; instantiated into a [`Leg`] from the actual unicycle state when the
/// previous leg is done (so that turning in place happens about where the unicycle really is).
#[derive(Clone, Copy, Debug)]
enum LegSpec {
    /// Move F to `point + R(travel_yaw) d` on a straight line at `speed`, slowing down at `deceleration`
    /// (m/s², 0: none) over its end.
    Line {
        point: Vector2<f64>,
        travel_yaw: f64,
        speed: f64,
        deceleration: f64,
    },
    /// Turn in place to `yaw` at `rate`.
    Turn { yaw: f64, rate: f64 },
}

/// Reference of the point F: a chain of legs decided from the goal.
struct Reference {
    specs: Vec<LegSpec>,
    /// Index of the waypoint each spec leads to (parallel to `specs`).
    owners: Vec<usize>,
    offset: Vector2<f64>,
    final_pose: Pose2,
}

impl Reference {
    fn build(cfg: &PlannerConfig, start: Pose2, points: &[(Vector2<f64>, Option<f64>)]) -> Self {
        let d = Vector2::new(cfg.reference_point[0], cfg.reference_point[1]);
        let v_fwd = cfg.reference_speed_fraction * cfg.max_forward_speed();
        let v_back = cfg.reference_speed_fraction * cfg.max_backward_speed();
        let w_ref = cfg.reference_speed_fraction * cfg.max_yaw_rate();
        let mut specs = Vec::new();
        let mut owners = Vec::new();
        let mut p = start.position();
        let mut yaw = start.yaw;
        let thr = cfg.turn_in_place_threshold;
        let turn = |specs: &mut Vec<LegSpec>, yaw: &mut f64, target: f64| {
            let delta = wrap_angle(target - *yaw);
            if delta.abs() > 1e-9 {
                *yaw += delta;
                specs.push(LegSpec::Turn {
                    yaw: *yaw,
                    rate: w_ref,
                });
            }
        };
        for (i, &(wp, wp_yaw)) in points.iter().enumerate() {
            let is_last = i + 1 == points.len();
            let delta = wp - p;
            let dist = delta.norm();
            if dist > 1e-6 {
                let phi = delta.y.atan2(delta.x);
                let forward_error = wrap_angle(phi - yaw).abs();
                let backward_error = wrap_angle(phi + std::f64::consts::PI - yaw).abs();
                let backward = forward_error > thr
                    && backward_error <= thr.max(1e-9)
                    && dist <= cfg.backward_max_distance;
                let (travel_yaw, speed) = if backward {
                    (phi + std::f64::consts::PI, v_back)
                } else {
                    (phi, v_fwd)
                };
                if wrap_angle(travel_yaw - yaw).abs() > thr {
                    turn(&mut specs, &mut yaw, travel_yaw);
                }
                let new_yaw = yaw + wrap_angle(travel_yaw - yaw);
                specs.push(LegSpec::Line {
                    point: wp,
                    travel_yaw: new_yaw,
                    speed,
                    deceleration: if is_last { cfg.stop_deceleration } else { 0.0 },
                });
                p = wp;
                yaw = new_yaw;
            }
            // only the final heading is enforced; the robot passes intermediate waypoints with its approach
            // heading (no stop-and-turn on the way)
            if let (true, Some(y)) = (is_last, wp_yaw) {
                turn(&mut specs, &mut yaw, y);
            }
            owners.resize(specs.len(), i);
        }
        Self {
            specs,
            owners,
            offset: d,
            final_pose: Pose2 {
                x: p.x,
                y: p.y,
                yaw,
            },
        }
    }

    /// The leg for `spec` starting from the actual unicycle pose `u` and F* end point `f_ref`.
    fn instantiate(&self, spec: LegSpec, u: Pose2, f_ref: Vector2<f64>) -> Leg {
        match spec {
            LegSpec::Line {
                point,
                travel_yaw,
                speed,
                deceleration,
            } => {
                let to = point + rot(travel_yaw, self.offset);
                let length = (to - f_ref).norm();
                let cruise = if deceleration > 0.0 {
                    cruise_speed(length, speed, deceleration)
                } else {
                    speed
                };
                Leg::Line {
                    from: f_ref,
                    to,
                    duration: line_duration(length, speed, deceleration).max(1e-9),
                    deceleration,
                    cruise,
                }
            }
            LegSpec::Turn { yaw, rate } => {
                let target = u.yaw + wrap_angle(yaw - u.yaw);
                Leg::Arc {
                    center: u.position(),
                    yaw_from: u.yaw,
                    yaw_to: target,
                    duration: ((target - u.yaw).abs() / rate).max(1e-9),
                }
            }
        }
    }

    /// F*(τ) and its velocity on `leg` at local time τ.
    fn evaluate(&self, leg: &Leg, tau: f64) -> (Vector2<f64>, Vector2<f64>) {
        match *leg {
            Leg::Line {
                from,
                to,
                duration,
                deceleration,
                cruise,
            } => {
                if tau >= duration {
                    return (to, Vector2::zeros());
                }
                if deceleration > 0.0 {
                    let length = (to - from).norm();
                    let (travelled, speed) =
                        braked_line(length, cruise, duration, deceleration, tau);
                    let direction = (to - from) / length.max(1e-12);
                    return (from + direction * travelled, direction * speed);
                }
                let s = (tau / duration).clamp(0.0, 1.0);
                (from + (to - from) * s, (to - from) / duration)
            }
            Leg::Arc {
                center,
                yaw_from,
                yaw_to,
                duration,
            } => {
                let s = (tau / duration).clamp(0.0, 1.0);
                let yaw = yaw_from + (yaw_to - yaw_from) * s;
                let rate = if tau >= duration {
                    0.0
                } else {
                    (yaw_to - yaw_from) / duration
                };
                let r = rot(yaw, self.offset);
                (center + r, Vector2::new(-r.y, r.x) * rate)
            }
        }
    }
}

/// The speed (m/s) a line of `length` (m) is travelled at before braking uniformly at `deceleration` (m/s²,
/// > 0) to stop at its end: `speed`, or `√(2aL)` when the braking distance `v²/(2a)` does not fit.
fn cruise_speed(length: f64, speed: f64, deceleration: f64) -> f64 {
    speed.min((2.0 * deceleration * length).sqrt())
}

/// Time (s) to cover `length` (m) at `speed` (m/s), braking at `deceleration` (m/s², 0: none) to stop at the
/// end: `L/v + v/(2a)` with `v` the [`cruise_speed`].
fn line_duration(length: f64, speed: f64, deceleration: f64) -> f64 {
    if deceleration <= 0.0 {
        return length / speed;
    }
    let v = cruise_speed(length, speed, deceleration);
    length / v + v / (2.0 * deceleration)
}

/// Distance travelled (m) and speed (m/s) at time `tau` (s) on a line of `length` travelled at `cruise`
/// (m/s) that ends at rest after `duration` (s, [`line_duration`]) braking at `deceleration` (> 0): the
/// last `cruise / a` seconds follow `v = a (T − τ)`.
fn braked_line(length: f64, cruise: f64, duration: f64, deceleration: f64, tau: f64) -> (f64, f64) {
    let remaining = (duration - tau).max(0.0);
    if deceleration * remaining >= cruise {
        (cruise * tau, cruise)
    } else {
        (
            length - 0.5 * deceleration * remaining * remaining,
            deceleration * remaining,
        )
    }
}

/// Result of integrating the unicycle: poses at `k · dt`, k = 0..len.
pub(crate) struct UnicyclePath {
    pub samples: Vec<Pose2>,
    /// Whether the horizon cut the motion before the goal was reached.
    pub truncated: bool,
    /// Final pose the goal asked for (for reporting the remaining distance).
    pub goal_pose: Pose2,
}

/// Exact integration of the unicycle over `dt` with constant commands.
fn integrate(p: Pose2, v: f64, v_lat: f64, omega: f64, dt: f64) -> Pose2 {
    let y0 = p.yaw;
    let y1 = y0 + omega * dt;
    let (s0, c0) = y0.sin_cos();
    let (s1, c1) = y1.sin_cos();
    // ∫ R(θ(s)) ds over [0, dt]
    let (a, b) = if (omega * dt).abs() < 1e-9 {
        let ym = y0 + 0.5 * omega * dt;
        (ym.cos() * dt, ym.sin() * dt)
    } else {
        ((s1 - s0) / omega, (c0 - c1) / omega)
    };
    Pose2 {
        x: p.x + a * v - b * v_lat,
        y: p.y + b * v + a * v_lat,
        yaw: y1,
    }
}

/// Whether moving with constant commands for one minimum step duration keeps the next footstep feasible for
/// either swing foot (with a small margin): steady walking places consecutive feet on unicycle poses one step
/// duration apart, and shorter steps are always easier.
fn twist_feasible(cfg: &PlannerConfig, v: f64, v_lat: f64, omega: f64) -> bool {
    let u1 = Pose2 {
        x: 0.0,
        y: 0.0,
        yaw: 0.0,
    };
    let u2 = integrate(u1, v, v_lat, omega, cfg.step_duration_min);
    // (the width margin never exceeds half the slack between the nominal and the minimum width: with
    // `nominal_width == min_width` steady walking at the nominal width must stay feasible)
    let width_margin = 0.002f64.min(0.5 * (cfg.nominal_width - cfg.min_width));
    let margin = PlannerConfig {
        feet_distance_max: cfg.feet_distance_max - 0.002,
        min_width: cfg.min_width + width_margin,
        max_yaw_per_step: cfg.max_yaw_per_step * 0.98,
        ..cfg.clone()
    };
    let w = cfg.nominal_width;
    feet_feasible(
        &margin,
        foot_on(u2, Foot::Left, w),
        foot_on(u1, Foot::Right, w),
    )
    .is_ok()
        && feet_feasible(
            &margin,
            foot_on(u1, Foot::Left, w),
            foot_on(u2, Foot::Right, w),
        )
        .is_ok()
}

/// Slows the translation (and, if that is not enough, the rotation) down until [`twist_feasible`] holds
/// ("slow down when turning").
fn feasible_twist(cfg: &PlannerConfig, v: f64, v_lat: f64, omega: f64) -> (f64, f64, f64) {
    if twist_feasible(cfg, v, v_lat, omega) {
        return (v, v_lat, omega);
    }
    let mut w = omega;
    if !twist_feasible(cfg, 0.0, 0.0, w) {
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..30 {
            let mid = 0.5 * (lo + hi);
            if twist_feasible(cfg, 0.0, 0.0, omega * mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        w = omega * lo;
    }
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..30 {
        let mid = 0.5 * (lo + hi);
        if twist_feasible(cfg, v * mid, v_lat * mid, w) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (v * lo, v_lat * lo, w)
}

/// Integrates the unicycle for `goal` from `start`.
pub(crate) fn unicycle_path(
    cfg: &PlannerConfig,
    start: Pose2,
    goal: &Goal,
) -> Result<UnicyclePath, PlannerError> {
    let dt = cfg.unicycle_dt;
    let max_samples = (cfg.horizon / dt).floor() as usize;
    let v_fwd = cfg.max_forward_speed();
    let v_back = cfg.max_backward_speed();
    let v_lat_max = cfg.max_lateral_speed();
    let w_max = cfg.max_yaw_rate();
    let mut samples = Vec::with_capacity(1024);
    samples.push(start);
    match goal {
        Goal::Stand => Ok(UnicyclePath {
            samples,
            truncated: false,
            goal_pose: start,
        }),
        Goal::Velocity {
            forward,
            lateral,
            yaw_rate,
            duration,
        } => {
            let v = forward.clamp(-v_back, v_fwd);
            let vl = lateral.clamp(-v_lat_max, v_lat_max);
            let w = yaw_rate.clamp(-w_max, w_max);
            let (v, vl, w) = feasible_twist(cfg, v, vl, w);
            let wanted = duration.unwrap_or(cfg.horizon);
            let n = ((wanted / dt).round() as usize).min(max_samples);
            let truncated = duration.is_some_and(|d| d > cfg.horizon + 0.5 * dt);
            let mut p = start;
            for _ in 0..n {
                p = integrate(p, v, vl, w, dt);
                samples.push(p);
            }
            // constant commands integrate exactly over any duration
            let goal_pose = if truncated {
                integrate(p, v, vl, w, wanted - n as f64 * dt)
            } else {
                p
            };
            Ok(UnicyclePath {
                samples,
                truncated,
                goal_pose,
            })
        }
        Goal::Pose { x, y, yaw } => {
            let pts = [(Vector2::new(*x, *y), Some(*yaw))];
            follow(cfg, start, &pts, max_samples, samples, None)
        }
        Goal::Waypoints { points } => {
            let pts: Vec<_> = points
                .iter()
                .map(|w| (Vector2::new(w.x, w.y), w.yaw))
                .collect();
            follow(cfg, start, &pts, max_samples, samples, None)
        }
    }
}

/// How many of `points` (a waypoint goal followed from `origin`) the unicycle path has passed where it comes
/// closest to `position`: the waypoints of the legs completed at that sample, at most all but the last. A step
/// adjustment replans from its new touch-down towards the waypoints not yet passed instead of from the
/// first one.
pub(crate) fn waypoints_passed(
    cfg: &PlannerConfig,
    origin: Pose2,
    points: &[crate::goal::Waypoint],
    position: Vector2<f64>,
) -> Result<usize, PlannerError> {
    let pts: Vec<_> = points
        .iter()
        .map(|w| (Vector2::new(w.x, w.y), w.yaw))
        .collect();
    let max_samples = (cfg.horizon / cfg.unicycle_dt).floor() as usize;
    let mut passed = vec![0];
    let path = follow(
        cfg,
        origin,
        &pts,
        max_samples,
        vec![origin],
        Some(&mut passed),
    )?;
    let nearest = path
        .samples
        .iter()
        .map(|s| (s.position() - position).norm_squared())
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(0, |(i, _)| i);
    Ok(passed
        .get(nearest)
        .copied()
        .unwrap_or(0)
        .min(points.len().saturating_sub(1)))
}

fn follow(
    cfg: &PlannerConfig,
    start: Pose2,
    points: &[(Vector2<f64>, Option<f64>)],
    max_samples: usize,
    mut samples: Vec<Pose2>,
    mut passed: Option<&mut Vec<usize>>,
) -> Result<UnicyclePath, PlannerError> {
    let dt = cfg.unicycle_dt;
    let reference = Reference::build(cfg, start, points);
    // waypoints passed at each sample (parallel to `samples`, when asked): those before the current leg's,
    // all but the last once every leg is done
    let last = points.len().saturating_sub(1);
    let d = reference.offset;
    let k = cfg.unicycle_gain;
    let (v_fwd, v_back, w_max) = (
        cfg.max_forward_speed(),
        cfg.max_backward_speed(),
        cfg.max_yaw_rate(),
    );
    // a leg ends when its time is over and F has converged to its end (or after this extra wait)
    let max_wait = 2.0;
    let mut p = start;
    let mut next_spec = 0usize;
    let mut f_end = p.position() + rot(p.yaw, d);
    let mut leg: Option<(Leg, f64)> = None;
    let mut truncated = true;
    for i in 0..max_samples {
        let t = i as f64 * dt;
        let f = p.position() + rot(p.yaw, d);
        // advance to the next leg when the current one is done (legs are checked again at the next sample)
        let done = match &leg {
            None => true,
            Some((l, t0)) => {
                let tau = t - t0;
                let dur = l.duration();
                tau >= dur && ((f - f_end).norm() < 1e-5 || tau >= dur + max_wait)
            }
        };
        if done {
            match reference.specs.get(next_spec) {
                Some(spec) => {
                    let l = reference.instantiate(*spec, p, f_end);
                    f_end = reference.evaluate(&l, l.duration()).0;
                    leg = Some((l, t));
                    next_spec += 1;
                }
                None => leg = None,
            }
        }
        let Some((l, t0)) = &leg else {
            if (f - f_end).norm() < 1e-5 {
                truncated = false;
                break;
            }
            // no leg left but not converged yet: hold the last point
            let err = f - f_end;
            let local = rot(-p.yaw, -err * k);
            let v = (local.x + d.y / d.x * local.y).clamp(-v_back, v_fwd);
            let w = (local.y / d.x).clamp(-w_max, w_max);
            p = integrate(p, v, 0.0, w, dt);
            samples.push(p);
            if let Some(passed) = passed.as_deref_mut() {
                passed.push(last);
            }
            continue;
        };
        let (f_ref, df_ref) = reference.evaluate(l, t - t0);
        let err = f - f_ref;
        // u = B⁻¹ (ẋ_F* − K e),  B⁻¹ = [[1, dy/dx], [0, 1/dx]] R(θ)ᵀ
        let q = df_ref - err * k;
        let local = rot(-p.yaw, q);
        let v = (local.x + d.y / d.x * local.y).clamp(-v_back, v_fwd);
        let w = (local.y / d.x).clamp(-w_max, w_max);
        let (v, _, w) = feasible_twist(cfg, v, 0.0, w);
        p = integrate(p, v, 0.0, w, dt);
        samples.push(p);
        if let Some(passed) = passed.as_deref_mut() {
            let owner = next_spec
                .checked_sub(1)
                .and_then(|j| reference.owners.get(j));
            passed.push(owner.copied().unwrap_or(0));
        }
    }
    if !samples
        .iter()
        .all(|s| s.x.is_finite() && s.y.is_finite() && s.yaw.is_finite())
    {
        return Err(PlannerError::InvalidGoal {
            name: "goal".into(),
            reason: "the unicycle integration diverged".into(),
        });
    }
    Ok(UnicyclePath {
        samples,
        truncated,
        goal_pose: reference.final_pose,
    })
}

/// One planned step: the swing foot, where it lands, and the step duration in unicycle samples.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct StepPlan {
    pub foot: Foot,
    pub pose: Pose2,
    pub duration: f64,
}

/// Whether a pair of feet satisfies the step constraints [Romualdi 2022, eqs. 10.1.12–10.1.13] plus the width constraint.
/// Which step constraints a pair of feet violates (no allocation; formatted only for error messages).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Violation {
    length: f64,
    lateral: f64,
    yaw: f64,
    too_long: bool,
    too_short: bool,
    too_narrow: bool,
    too_twisted: bool,
}

impl Violation {
    fn describe(&self) -> String {
        let mut why = Vec::new();
        if self.too_long {
            why.push(format!(
                "feet distance {:.4} > feet_distance_max",
                self.length
            ));
        }
        if self.too_short {
            why.push(format!(
                "feet distance {:.4} < feet_distance_min",
                self.length
            ));
        }
        if self.too_narrow {
            why.push(format!("lateral distance {:.4} < min_width", self.lateral));
        }
        if self.too_twisted {
            why.push(format!("relative yaw {:.4} > max_yaw_per_step", self.yaw));
        }
        why.join(", ")
    }
}

/// Rounding allowance on the step bounds \[m, rad\]: a step exactly at a bound (e.g. at `min_width` when it
/// equals `nominal_width`) is feasible even when its computed value is off by a few ulps. The same 1e-9 as
/// [`crate::Plan::verify`].
const BOUND_TOLERANCE: f64 = 1e-9;

pub(crate) fn feet_feasible(
    cfg: &PlannerConfig,
    left: Pose2,
    right: Pose2,
) -> Result<(), Violation> {
    let rel = right.inverse_transform_point(left.position());
    let len = rel.norm();
    let lateral = feet_lateral_separation(left, right);
    let dyaw = wrap_angle(left.yaw - right.yaw);
    let v = Violation {
        length: len,
        lateral,
        yaw: dyaw,
        too_long: len > cfg.feet_distance_max + BOUND_TOLERANCE,
        too_short: len < cfg.feet_distance_min - BOUND_TOLERANCE,
        too_narrow: lateral < cfg.min_width - BOUND_TOLERANCE,
        too_twisted: dyaw.abs() > cfg.max_yaw_per_step + BOUND_TOLERANCE,
    };
    if v.too_long || v.too_short || v.too_narrow || v.too_twisted {
        Err(v)
    } else {
        Ok(())
    }
}

fn foot_on(u: Pose2, foot: Foot, width: f64) -> Pose2 {
    let p = u.transform_point(Vector2::new(0.0, foot.side() * 0.5 * width));
    Pose2 {
        x: p.x,
        y: p.y,
        yaw: u.yaw,
    }
}

fn close(a: Pose2, b: Pose2) -> bool {
    (a.position() - b.position()).norm() <= 2e-4 && wrap_angle(a.yaw - b.yaw).abs() <= 4e-4
}

/// The candidate on unicycle pose `u` for `swing`, moved outward along the unicycle's axle until it is
/// `min_width` away from `stance`, when the candidate at the nominal width violates only `min_width`
/// (`None` otherwise, or when the wider candidate breaks another bound).
///
/// The lateral separation is measured across the feet's own headings
/// ([`feet_lateral_separation`]), so with `nominal_width == min_width` a candidate at the nominal width is
/// narrower than `min_width` (by cos of the relative yaw, and by the stance foot's offset from the axle)
/// whenever the stance foot does not sit exactly on the unicycle's axle: e.g. the closing step at the goal
/// after a replan that left the stance foot turned by 1° (0.13998 m across it on the iCub, whose
/// `nominal_width` is its `min_width`). Without this, no candidate was feasible, the fallback set the foot
/// parallel to the stance foot, and the search swapped the feet in place until its step budget.
fn widened(
    cfg: &PlannerConfig,
    u: Pose2,
    swing: Foot,
    stance: Pose2,
    reason: Violation,
) -> Option<Pose2> {
    let mut reason = reason;
    let mut width = cfg.nominal_width;
    // the separation grows by about half the width's growth (× the cosine of the relative yaw): two
    // corrections with a 1 µm allowance land above `min_width` for the relative yaws a step allows
    for _ in 0..3 {
        if reason.too_long || reason.too_short || reason.too_twisted || !reason.too_narrow {
            return None;
        }
        width += 2.0 * (cfg.min_width - reason.lateral) + 1e-6;
        let cand = foot_on(u, swing, width);
        let result = match swing {
            Foot::Left => feet_feasible(cfg, cand, stance),
            Foot::Right => feet_feasible(cfg, stance, cand),
        };
        match result {
            Ok(()) => return Some(cand),
            Err(r) => reason = r,
        }
    }
    None
}

/// Picks the first swing foot: explicit, or the side the unicycle moves/turns to.
pub(crate) fn choose_first_swing(cfg: &PlannerConfig, path: &UnicyclePath) -> Foot {
    match cfg.first_swing_foot {
        FirstSwingFoot::Left => Foot::Left,
        FirstSwingFoot::Right => Foot::Right,
        FirstSwingFoot::Auto => {
            let (n_min, _) = cfg.step_sample_window();
            let s0 = path.samples[0];
            let u = path.samples[n_min.min(path.samples.len() - 1)];
            let rel = s0.inverse_transform_point(u.position());
            let score = rel.y + 0.1 * wrap_angle(u.yaw - s0.yaw);
            if score < -1e-9 {
                Foot::Right
            } else {
                Foot::Left
            }
        }
    }
}

/// Greedy footstep search along the unicycle path [Romualdi 2022, eqs. 10.1.10–10.1.13]: for each
/// step, the cheapest feasible unicycle sample.
pub(crate) fn search_footsteps(
    cfg: &PlannerConfig,
    path: &UnicyclePath,
    left: Pose2,
    right: Pose2,
    first_swing: Foot,
) -> Result<Vec<StepPlan>, PlannerError> {
    let samples = &path.samples;
    let last = samples.len() - 1;
    let final_pose = samples[last];
    let target = |f: Foot| foot_on(final_pose, f, cfg.nominal_width);
    let (n_min, n_max) = cfg.step_sample_window();
    let n_nom =
        ((cfg.step_duration_nominal / cfg.unicycle_dt).round() as usize).clamp(n_min, n_max);
    let dt = cfg.unicycle_dt;
    let limit = 2 * (samples.len() / n_min.max(1)) + 8;
    let mut feet = [left, right];
    let idx = |f: Foot| match f {
        Foot::Left => 0,
        Foot::Right => 1,
    };
    let mut swing = first_swing;
    let mut prev = 0usize;
    let mut steps = Vec::new();
    let mut skipped = false;
    loop {
        if close(feet[0], target(Foot::Left)) && close(feet[1], target(Foot::Right)) {
            break;
        }
        if steps.len() >= limit {
            return Err(PlannerError::TooManySteps { limit });
        }
        let all_final = prev + n_min >= last;
        if all_final && close(feet[idx(swing)], target(swing)) && !skipped {
            // the unicycle stopped and this foot is already in place: let the other foot close the stance.
            swing = swing.other();
            skipped = true;
            continue;
        }
        skipped = false;
        let stance = feet[idx(swing.other())];
        let mut best: Option<(f64, usize, Pose2)> = None;
        // the cheapest candidate that is feasible only once set wider than the nominal width (see
        // [`widened`]); taken when no candidate at the nominal width is feasible
        let mut best_widened: Option<(f64, usize, Pose2)> = None;
        let mut last_reason = Violation::default();
        for n in n_min..=n_max {
            let sample = samples[(prev + n).min(last)];
            let cand = foot_on(sample, swing, cfg.nominal_width);
            let (l, r) = match swing {
                Foot::Left => (cand, stance),
                Foot::Right => (stance, cand),
            };
            let feasible = match feet_feasible(cfg, l, r) {
                Ok(()) => Ok((cand, false)),
                Err(reason) => widened(cfg, sample, swing, stance, reason)
                    .map(|wide| (wide, true))
                    .ok_or(reason),
            };
            match feasible {
                Ok((cand, is_widened)) => {
                    let (l, r) = match swing {
                        Foot::Left => (cand, stance),
                        Foot::Right => (stance, cand),
                    };
                    let duration = n as f64 * dt;
                    let dx = (l.position() - r.position()).norm();
                    let cost =
                        cfg.time_weight / (duration * duration) + cfg.position_weight * dx * dx;
                    let cost = if all_final {
                        // all candidates are the same pose: take the nominal duration
                        (n as f64 - n_nom as f64).abs()
                    } else {
                        cost
                    };
                    let slot = if is_widened {
                        &mut best_widened
                    } else {
                        &mut best
                    };
                    if slot.is_none_or(|(c, _, _)| cost < c) {
                        *slot = Some((cost, n, cand));
                    }
                }
                Err(reason) => last_reason = reason,
            }
        }
        let best = best.or(best_widened).or_else(|| {
            // No candidate on the unicycle path is feasible (the feet lag behind the unicycle, e.g. after a
            // start from feet that are not at the nominal width): take the step from the pose parallel to the
            // stance foot towards the nominal-duration candidate, as far as the constraints allow.
            let n = n_nom;
            let cand = foot_on(samples[(prev + n).min(last)], swing, cfg.nominal_width);
            let par_pos =
                stance.transform_point(Vector2::new(0.0, swing.side() * cfg.nominal_width));
            let parallel = Pose2 {
                x: par_pos.x,
                y: par_pos.y,
                yaw: stance.yaw,
            };
            let at = |lambda: f64| Pose2 {
                x: parallel.x + lambda * (cand.x - parallel.x),
                y: parallel.y + lambda * (cand.y - parallel.y),
                yaw: parallel.yaw + lambda * wrap_angle(cand.yaw - parallel.yaw),
            };
            let ok = |p: Pose2| match swing {
                Foot::Left => feet_feasible(cfg, p, stance).is_ok(),
                Foot::Right => feet_feasible(cfg, stance, p).is_ok(),
            };
            if !ok(parallel) {
                return None;
            }
            let (mut lo, mut hi) = (0.0, 1.0);
            for _ in 0..40 {
                let mid = 0.5 * (lo + hi);
                if ok(at(mid)) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            Some((0.0, n, at(lo)))
        });
        let Some((_, n, pose)) = best else {
            return Err(PlannerError::NoFeasibleStep {
                step: steps.len(),
                foot: swing.name(),
                time: prev as f64 * dt,
                reason: last_reason.describe(),
            });
        };
        steps.push(StepPlan {
            foot: swing,
            pose,
            duration: n as f64 * dt,
        });
        feet[idx(swing)] = pose;
        prev += n;
        swing = swing.other();
    }
    Ok(steps)
}

#[cfg(test)]
mod braking_tests {
    use super::{braked_line, cruise_speed, line_duration};

    /// The braked line against its closed form: it starts at 0, ends at rest at `L` after `T`, its speed
    /// is the derivative of its position (central differences), and the braking phase is `v = a (T − τ)`.
    #[test]
    fn the_braked_line_ends_at_rest_and_its_speed_is_its_derivative() {
        for (length, speed, a) in [(2.0, 0.4, 0.3), (0.1, 0.4, 0.3), (1.0, 0.2, 5.0)] {
            let cruise = cruise_speed(length, speed, a);
            let duration = line_duration(length, speed, a);
            // `L/v + v/(2a)`, and the braking distance v²/(2a) ≤ L
            assert!((duration - (length / cruise + cruise / (2.0 * a))).abs() < 1e-15);
            assert!(cruise * cruise / (2.0 * a) <= length * (1.0 + 1e-12));
            assert_eq!(braked_line(length, cruise, duration, a, 0.0), (0.0, cruise));
            let (end, v_end) = braked_line(length, cruise, duration, a, duration);
            assert!(
                (end - length).abs() < 1e-12 && v_end == 0.0,
                "{end} {v_end}"
            );
            let h = 1e-6;
            for k in 1..50 {
                let tau = duration * k as f64 / 50.0;
                let (p, v) = braked_line(length, cruise, duration, a, tau);
                let (p1, _) = braked_line(length, cruise, duration, a, tau + h);
                let (p0, _) = braked_line(length, cruise, duration, a, tau - h);
                assert!(((p1 - p0) / (2.0 * h) - v).abs() < 1e-6, "τ {tau}");
                assert!(v <= cruise && p <= length);
            }
        }
        // a short line is braked all the way from √(2aL)
        assert!((cruise_speed(0.1, 0.4, 0.3) - (2.0f64 * 0.3 * 0.1).sqrt()).abs() < 1e-15);
        // no deceleration: L / v
        assert_eq!(line_duration(2.0, 0.4, 0.0), 5.0);
    }
}
