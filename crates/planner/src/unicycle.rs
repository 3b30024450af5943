//! Unicycle model, its feedback-linearising controller and the greedy footstep search (thesis §10.1.1–
//! §10.1.14, digest §7.1–7.2).
//!
//! The unicycle `ȯ = R(θ)[v; v_lat]`, `θ̇ = ω` (v_lat is only used by velocity commands; the thesis unicycle has
//! v_lat = 0) is driven either directly (velocity goals) or by the controller (10.1.6)
//! `u = B(θ)⁻¹ (ẋ_F* − K (x_F − x_F*))` that makes a point F rigidly attached ahead of the unicycle track a
//! reference trajectory `x_F*(t)` built from the goal (straight lines between waypoints, arcs for turning in
//! place). The commands are saturated to the speed limits derived from the step limits. Feet are the wheels
//! (10.1.7): `o_L/R = o + R(θ)[0; ±w/2]`, yaw θ. Each unicycle sample is a candidate touch-down instant; the
//! search picks, for each step, the candidate minimising `K_t/Δt² + K_x Δx²` (10.1.10) under (10.1.11)–(10.1.13).

use nalgebra::Vector2;

use crate::config::{FirstSwingFoot, PlannerConfig};
use crate::contacts::Foot;
use crate::error::PlannerError;
use crate::geometry::{wrap_angle, Pose2};
use crate::goal::Goal;

/// A piece of the reference trajectory of the controlled point F.
#[derive(Clone, Copy, Debug)]
enum Leg {
    /// F moves on a straight line at constant speed.
    Line {
        from: Vector2<f64>,
        to: Vector2<f64>,
        duration: f64,
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

/// Reference of the point F: a chain of legs.
struct Reference {
    legs: Vec<Leg>,
    offset: Vector2<f64>,
    final_pose: Pose2,
    end_point: Vector2<f64>,
}

impl Reference {
    fn build(cfg: &PlannerConfig, start: Pose2, points: &[(Vector2<f64>, Option<f64>)]) -> Self {
        let d = Vector2::new(cfg.reference_point[0], cfg.reference_point[1]);
        let v_fwd = cfg.reference_speed_fraction * cfg.max_forward_speed();
        let v_back = cfg.reference_speed_fraction * cfg.max_backward_speed();
        let w_ref = cfg.reference_speed_fraction * cfg.max_yaw_rate();
        let mut legs = Vec::new();
        let mut p = start.position();
        let mut yaw = start.yaw;
        let thr = cfg.turn_in_place_threshold;
        let turn = |legs: &mut Vec<Leg>, p: Vector2<f64>, yaw: &mut f64, target: f64| {
            let delta = wrap_angle(target - *yaw);
            if delta.abs() > 1e-9 {
                legs.push(Leg::Arc {
                    center: p,
                    yaw_from: *yaw,
                    yaw_to: *yaw + delta,
                    duration: delta.abs() / w_ref,
                });
                *yaw += delta;
            }
        };
        for &(wp, wp_yaw) in points {
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
                    turn(&mut legs, p, &mut yaw, travel_yaw);
                }
                let from = p + rot(yaw, d);
                let new_yaw = yaw + wrap_angle(travel_yaw - yaw);
                let to = wp + rot(new_yaw, d);
                let length = (to - from).norm();
                if length > 0.0 {
                    legs.push(Leg::Line {
                        from,
                        to,
                        duration: length / speed,
                    });
                }
                p = wp;
                yaw = new_yaw;
            }
            if let Some(y) = wp_yaw {
                turn(&mut legs, p, &mut yaw, y);
            }
        }
        Self {
            legs,
            offset: d,
            final_pose: Pose2 {
                x: p.x,
                y: p.y,
                yaw,
            },
            end_point: p + rot(yaw, d),
        }
    }

    fn duration(&self) -> f64 {
        self.legs.iter().map(Leg::duration).sum()
    }

    /// F*(t) and its velocity. `cursor` is the current leg index and the start time of that leg.
    fn evaluate(&self, t: f64, cursor: &mut (usize, f64)) -> (Vector2<f64>, Vector2<f64>) {
        while cursor.0 < self.legs.len() && t >= cursor.1 + self.legs[cursor.0].duration() {
            cursor.1 += self.legs[cursor.0].duration();
            cursor.0 += 1;
        }
        let Some(leg) = self.legs.get(cursor.0) else {
            return (self.end_point, Vector2::zeros());
        };
        let tau = t - cursor.1;
        match *leg {
            Leg::Line { from, to, duration } => {
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
                let rate = (yaw_to - yaw_from) / duration;
                let r = rot(yaw, self.offset);
                (center + r, Vector2::new(-r.y, r.x) * rate)
            }
        }
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
            let wanted = duration.unwrap_or(cfg.horizon);
            let n = ((wanted / dt).round() as usize).min(max_samples);
            let truncated = duration.is_some_and(|d| d > cfg.horizon + 0.5 * dt);
            let mut p = start;
            for _ in 0..n {
                p = integrate(p, v, vl, w, dt);
                samples.push(p);
            }
            let goal_pose = if truncated {
                let mut g = p;
                for _ in n..((wanted / dt).round() as usize).min(100_000_000) {
                    g = integrate(g, v, vl, w, dt);
                }
                g
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
            follow(cfg, start, &pts, max_samples, samples)
        }
        Goal::Waypoints { points } => {
            let pts: Vec<_> = points
                .iter()
                .map(|w| (Vector2::new(w.x, w.y), w.yaw))
                .collect();
            follow(cfg, start, &pts, max_samples, samples)
        }
    }
}

fn follow(
    cfg: &PlannerConfig,
    start: Pose2,
    points: &[(Vector2<f64>, Option<f64>)],
    max_samples: usize,
    mut samples: Vec<Pose2>,
) -> Result<UnicyclePath, PlannerError> {
    let dt = cfg.unicycle_dt;
    let reference = Reference::build(cfg, start, points);
    let t_ref = reference.duration();
    let d = reference.offset;
    let k = cfg.unicycle_gain;
    let (v_fwd, v_back, w_max) = (
        cfg.max_forward_speed(),
        cfg.max_backward_speed(),
        cfg.max_yaw_rate(),
    );
    let mut p = start;
    let mut cursor = (0usize, 0.0f64);
    let mut truncated = true;
    for i in 0..max_samples {
        let t = i as f64 * dt;
        let (f_ref, df_ref) = reference.evaluate(t, &mut cursor);
        let f = p.position() + rot(p.yaw, d);
        let err = f - f_ref;
        if t >= t_ref && err.norm() < 1e-6 {
            truncated = false;
            break;
        }
        // u = B⁻¹ (ẋ_F* − K e),  B⁻¹ = [[1, dy/dx], [0, 1/dx]] R(θ)ᵀ
        let q = df_ref - err * k;
        let local = rot(-p.yaw, q);
        let v = (local.x + d.y / d.x * local.y).clamp(-v_back, v_fwd);
        let w = (local.y / d.x).clamp(-w_max, w_max);
        p = integrate(p, v, 0.0, w, dt);
        samples.push(p);
    }
    if !samples.iter().all(|s| s.x.is_finite() && s.y.is_finite() && s.yaw.is_finite()) {
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

/// Whether a pair of feet satisfies the step constraints (10.1.12)–(10.1.13) plus the width constraint.
pub(crate) fn feet_feasible(cfg: &PlannerConfig, left: Pose2, right: Pose2) -> Result<(), String> {
    let rel = right.inverse_transform_point(left.position());
    let len = rel.norm();
    let dyaw = wrap_angle(left.yaw - right.yaw);
    let mut why = Vec::new();
    if len > cfg.step_length_max {
        why.push(format!("feet distance {len:.4} > step_length_max"));
    }
    if len < cfg.step_length_min {
        why.push(format!("feet distance {len:.4} < step_length_min"));
    }
    if rel.y < cfg.min_width {
        why.push(format!("lateral distance {:.4} < min_width", rel.y));
    }
    if dyaw.abs() > cfg.max_yaw_per_step {
        why.push(format!("relative yaw {dyaw:.4} > max_yaw_per_step"));
    }
    if why.is_empty() {
        Ok(())
    } else {
        Err(why.join(", "))
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
    (a.position() - b.position()).norm() <= 1e-3 && wrap_angle(a.yaw - b.yaw).abs() <= 1e-3
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

/// Greedy footstep search along the unicycle path (digest §7.2, steps 1–5).
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
    let n_nom = ((cfg.step_duration_nominal / cfg.unicycle_dt).round() as usize).clamp(n_min, n_max);
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
        let mut last_reason = String::new();
        for n in n_min..=n_max {
            let cand = foot_on(samples[(prev + n).min(last)], swing, cfg.nominal_width);
            let (l, r) = match swing {
                Foot::Left => (cand, stance),
                Foot::Right => (stance, cand),
            };
            match feet_feasible(cfg, l, r) {
                Ok(()) => {
                    let duration = n as f64 * dt;
                    let dx = (l.position() - r.position()).norm();
                    let cost = cfg.time_weight / (duration * duration) + cfg.position_weight * dx * dx;
                    let cost = if all_final {
                        // all candidates are the same pose: take the nominal duration
                        (n as f64 - n_nom as f64).abs()
                    } else {
                        cost
                    };
                    if best.is_none_or(|(c, _, _)| cost < c) {
                        best = Some((cost, n, cand));
                    }
                }
                Err(reason) => last_reason = reason,
            }
        }
        let Some((_, n, pose)) = best else {
            return Err(PlannerError::NoFeasibleStep {
                step: steps.len(),
                foot: swing.name(),
                time: prev as f64 * dt,
                reason: last_reason,
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
