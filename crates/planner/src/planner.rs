//! The planner object: start from standing, replan with merge points, sample, `Block` implementation.

use std::time::Duration;

use nalgebra::{Isometry3, Vector2};

use crate::config::{check_gravity, DcmInterpolation, PlannerConfig};
use crate::contacts::{ContactList, Foot, Phase, PhaseKind, PlannedContact};
use crate::dcm::{
    bump_coefficients, dcm_particular, dcm_particular_scalar, eval_cubic_scalar, eval_cubic_value,
    zmp_constant, zmp_transition, DcmSegment,
};
use crate::error::PlannerError;
use crate::geometry::{wrap_angle, Pose2, SupportPolygon};
use crate::goal::Goal;
use crate::plan::{Plan, PlanOutcome, PlanSample};
use crate::swing::{SwingShape, SwingTrajectory};
use crate::unicycle::{choose_first_swing, search_footsteps, unicycle_path};

/// Everything a new (partial) plan starts from.
#[derive(Clone, Debug)]
struct StartState {
    /// Plan time where the new plan starts (fresh start or merge point).
    t_start: f64,
    /// Plan time of unicycle time 0.
    anchor_time: f64,
    /// Unicycle pose at unicycle time 0.
    anchor: Pose2,
    /// Minimum duration of the first double support \[s\].
    min_initial_ds: f64,
    left: Isometry3<f64>,
    right: Isometry3<f64>,
    left_since: f64,
    right_since: f64,
    zmp0: Vector2<f64>,
    dcm0: Vector2<f64>,
    com0: Vector2<f64>,
    ground: f64,
    first_swing: Option<Foot>,
}

fn xy(h: &Isometry3<f64>) -> Vector2<f64> {
    Vector2::new(h.translation.x, h.translation.y)
}

/// Every coefficient of every segment is finite, or the plan is refused: a plan never carries NaN.
fn check_segments_finite(segments: &[DcmSegment]) -> Result<(), PlannerError> {
    match segments
        .iter()
        .find_map(|seg| seg.non_finite_quantity().map(|q| (seg.start, q)))
    {
        Some((time, quantity)) => Err(PlannerError::NonFinitePlan { time, quantity }),
        None => Ok(()),
    }
}

fn check_time(name: &'static str, t: f64) -> Result<(), PlannerError> {
    if t.is_finite() {
        Ok(())
    } else {
        Err(PlannerError::InvalidTime {
            name,
            value: t,
            reason: "must be finite",
        })
    }
}

/// Plans from standing: both feet on the ground at `left`/`right` (sole frames, world), CoM at rest above
/// their mid-point, at time `t0` \[s\], under gravity of magnitude `gravity_m_s2` \[m/s²\] (finite
/// and positive). The plan starts with `initial_double_support_duration` of weight shifting and ends standing
/// with parallel feet and the DCM on their mid-point.
pub fn plan_from_standing(
    config: &PlannerConfig,
    gravity_m_s2: f64,
    t0: f64,
    left: &Isometry3<f64>,
    right: &Isometry3<f64>,
    goal: &Goal,
) -> Result<Plan, PlannerError> {
    config.validate()?;
    check_gravity(gravity_m_s2)?;
    goal.validate()?;
    check_time("t0", t0)?;
    for (name, h) in [("left_sole", left), ("right_sole", right)] {
        let ok = h.translation.vector.iter().all(|v| v.is_finite())
            && h.rotation.coords.iter().all(|v| v.is_finite());
        if !ok {
            return Err(PlannerError::InvalidStart {
                name,
                reason: "pose is not finite".into(),
            });
        }
    }
    let (l2, r2) = (Pose2::from_isometry(left), Pose2::from_isometry(right));
    let rel = r2.inverse_transform_point(l2.position());
    let dyaw = wrap_angle(l2.yaw - r2.yaw);
    if dyaw.abs() > config.max_yaw_per_step {
        return Err(PlannerError::InvalidStart {
            name: "left_sole",
            reason: format!(
                "relative yaw of the feet {dyaw:.4} rad exceeds max_yaw_per_step {}",
                config.max_yaw_per_step
            ),
        });
    }
    if rel.y < config.foot_width
        || rel.norm() > config.step_length_max.max(config.nominal_width) * 1.5
    {
        return Err(PlannerError::InvalidStart {
            name: "left_sole",
            reason: format!(
                "left sole at ({:.4}, {:.4}) in the right sole frame: it must be to the left by at least \
                 foot_width and not farther than 1.5 step_length_max",
                rel.x, rel.y
            ),
        });
    }
    let mid = (xy(left) + xy(right)) * 0.5;
    let yaw = r2.yaw + 0.5 * dyaw;
    let start = StartState {
        t_start: t0,
        anchor_time: t0,
        anchor: Pose2 {
            x: mid.x,
            y: mid.y,
            yaw,
        },
        min_initial_ds: config.initial_double_support_duration,
        left: *left,
        right: *right,
        left_since: t0,
        right_since: t0,
        zmp0: mid,
        dcm0: mid,
        com0: mid,
        ground: 0.5 * (left.translation.z + right.translation.z),
        first_swing: None,
    };
    build_plan(config, config.omega(gravity_m_s2), &start, goal)
}

/// Builds a plan from a start state (fresh or merge).
fn build_plan(
    cfg: &PlannerConfig,
    omega: f64,
    start: &StartState,
    goal: &Goal,
) -> Result<Plan, PlannerError> {
    let f = cfg.double_support_fraction;
    let path = unicycle_path(cfg, start.anchor, goal)?;
    let (l2, r2) = (
        Pose2::from_isometry(&start.left),
        Pose2::from_isometry(&start.right),
    );
    let steps = if matches!(goal, Goal::Stand) {
        Vec::new()
    } else {
        let first = start
            .first_swing
            .unwrap_or_else(|| choose_first_swing(cfg, &path));
        search_footsteps(cfg, &path, l2, r2, first)?
    };
    let outcome = if path.truncated {
        let last = path.samples[path.samples.len() - 1];
        PlanOutcome::HorizonReached {
            remaining_distance: (path.goal_pose.position() - last.position()).norm(),
            remaining_yaw: wrap_angle(path.goal_pose.yaw - last.yaw),
        }
    } else {
        PlanOutcome::Complete
    };

    // foot poses along the steps and the stance ZMP of each step
    let mut cur = [start.left, start.right];
    let idx = |f: Foot| match f {
        Foot::Left => 0,
        Foot::Right => 1,
    };
    let mut stance_zmp = Vec::with_capacity(steps.len());
    let mut step_poses = Vec::with_capacity(steps.len());
    let mut step_from = Vec::with_capacity(steps.len());
    for s in &steps {
        stance_zmp.push(xy(&cur[idx(s.foot.other())]));
        let pose = s.pose.to_isometry(start.ground);
        step_from.push(cur[idx(s.foot)]);
        step_poses.push(pose);
        cur[idx(s.foot)] = pose;
    }
    let final_mid = (xy(&cur[0]) + xy(&cur[1])) * 0.5;
    let initial_polygon = {
        let a = SupportPolygon::foot_corners(&start.left, cfg.foot_length, cfg.foot_width);
        let b = SupportPolygon::foot_corners(&start.right, cfg.foot_length, cfg.foot_width);
        SupportPolygon::hull_of(&[a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]])
    };

    // support polygon of each double support after a touch-down
    let ds_polygons: Vec<SupportPolygon> = {
        let mut feet = [start.left, start.right];
        steps
            .iter()
            .zip(step_poses.iter())
            .map(|(s, pose)| {
                feet[idx(s.foot)] = *pose;
                let a = SupportPolygon::foot_corners(&feet[0], cfg.foot_length, cfg.foot_width);
                let b = SupportPolygon::foot_corners(&feet[1], cfg.foot_length, cfg.foot_width);
                SupportPolygon::hull_of(&[a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]])
            })
            .collect()
    };
    let mut min_init = start.min_initial_ds;
    let mut attempt = 0;
    loop {
        // timeline
        let n = steps.len();
        let mut lift = Vec::with_capacity(n);
        let mut land = Vec::with_capacity(n);
        for (k, s) in steps.iter().enumerate() {
            let l = if k == 0 {
                (start.anchor_time + f * s.duration).max(start.t_start + min_init)
            } else {
                land[k - 1] + f * s.duration
            };
            lift.push(l);
            land.push(l + (1.0 - f) * s.duration);
        }
        let end_time = if n > 0 {
            land[n - 1] + cfg.final_double_support_duration
        } else {
            start.t_start + min_init
        };
        let d0 = if n > 0 { lift[0] } else { end_time } - start.t_start;
        let first_target = if n > 0 { stance_zmp[0] } else { final_mid };

        let mut segments = if cfg.dcm_interpolation == DcmInterpolation::DcmCubic && n > 0 {
            let last_landed = xy(&step_poses[n - 1]);
            thesis_segments(
                omega,
                cfg.last_step_dcm_alpha,
                start,
                &lift,
                &land,
                end_time,
                &stance_zmp,
                last_landed,
                final_mid,
            )
        } else {
            // segments (the first one is filled after the backward pass)
            let mut segments = Vec::with_capacity(2 * n + 2);
            segments.push(DcmSegment::new(
                start.t_start,
                Some(d0),
                zmp_transition(start.zmp0, first_target, Vector2::zeros(), d0),
                omega,
            ));
            for k in 0..n {
                segments.push(DcmSegment::new(
                    lift[k],
                    Some(land[k] - lift[k]),
                    zmp_constant(stance_zmp[k]),
                    omega,
                ));
                let (next_t, next_z) = if k + 1 < n {
                    (lift[k + 1], stance_zmp[k + 1])
                } else {
                    (end_time, final_mid)
                };
                segments.push(DcmSegment::new(
                    land[k],
                    Some(next_t - land[k]),
                    zmp_transition(stance_zmp[k], next_z, Vector2::zeros(), next_t - land[k]),
                    omega,
                ));
            }
            segments.push(DcmSegment::new(
                end_time,
                None,
                zmp_constant(final_mid),
                omega,
            ));

            // backward pass: DCM at each segment end (10.1.17), the final DCM on the final ZMP
            let mut dcm_end = final_mid;
            for seg in segments.iter_mut().skip(1).rev() {
                seg.growth = seg.growth_for_end_dcm(dcm_end, omega);
                dcm_end = seg.dcm_start();
            }
            // first segment: ZMP bump so that the DCM starts at dcm0
            let base = zmp_transition(start.zmp0, first_target, Vector2::zeros(), d0);
            let pb = dcm_particular(&base, omega);
            let gb = dcm_particular_scalar(&bump_coefficients(d0), omega);
            let e = (-omega * d0).exp();
            let coef = eval_cubic_scalar(&gb, 0.0) - eval_cubic_scalar(&gb, d0) * e;
            let rhs = start.dcm0 - pb[0] - (dcm_end - eval_cubic_value(&pb, d0)) * e;
            let bump = rhs / coef;
            segments[0] = DcmSegment::new(
                start.t_start,
                Some(d0),
                zmp_transition(start.zmp0, first_target, bump, d0),
                omega,
            );
            segments[0].growth = segments[0].growth_for_end_dcm(dcm_end, omega);
            segments
        };

        check_segments_finite(&segments)?;
        // The ZMP of every double support whose shape depends on the DCM boundary conditions (the first one;
        // all of them for the thesis DCM cubic) is checked against the support polygon, 1e-4 m inside at 64
        // points (the ZMP cubic cannot move more than ~3e-5 m away from its chords between those points).
        let mut worst = (f64::INFINITY, start.t_start, 0usize);
        let checked = if cfg.dcm_interpolation == DcmInterpolation::DcmCubic {
            segments.len() - 1
        } else {
            1
        };
        for (i, seg) in segments.iter().enumerate().take(checked) {
            let Some(d) = seg.duration else { continue };
            if i % 2 == 1 {
                continue; // single supports: ZMP on the stance sole by construction
            }
            let polygon = if i == 0 {
                &initial_polygon
            } else {
                &ds_polygons[i / 2 - 1]
            };
            const CHECKS: usize = 64;
            for k in 0..=CHECKS {
                let tau = d * k as f64 / CHECKS as f64;
                let z = seg.evaluate_local(tau, omega).zmp;
                // (a NaN distance counts as outside: it must never pass the check)
                let dist = polygon.signed_distance(z) - 1e-4;
                let dist = if dist.is_nan() { -f64::INFINITY } else { dist };
                if dist < worst.0 {
                    worst = (dist, seg.start + tau, i);
                }
            }
        }
        if worst.0 < 0.0 {
            attempt += 1;
            if attempt > 8 || worst.2 != 0 {
                return Err(PlannerError::ZmpOutsideSupport {
                    time: worst.1,
                    distance: -worst.0,
                });
            }
            min_init = d0 * 1.5;
            continue;
        }

        // forward pass: CoM continuity
        let mut com = start.com0;
        for seg in segments.iter_mut() {
            seg.set_com_start(com);
            if let Some(d) = seg.duration {
                com = seg.evaluate_local(d, omega).com;
            }
        }
        check_segments_finite(&segments)?;

        // phases, contacts and swings
        let mut phases = Vec::with_capacity(2 * n + 1);
        phases.push(Phase {
            kind: PhaseKind::DoubleSupport,
            start: start.t_start,
            end: if n > 0 { lift[0] } else { end_time },
        });
        for k in 0..n {
            phases.push(Phase {
                kind: PhaseKind::SingleSupport {
                    stance: steps[k].foot.other(),
                },
                start: lift[k],
                end: land[k],
            });
            phases.push(Phase {
                kind: PhaseKind::DoubleSupport,
                start: land[k],
                end: if k + 1 < n { lift[k + 1] } else { end_time },
            });
        }
        let mut contacts = [
            vec![PlannedContact {
                foot: Foot::Left,
                pose: start.left,
                activation_time: start.left_since,
                deactivation_time: None,
            }],
            vec![PlannedContact {
                foot: Foot::Right,
                pose: start.right,
                activation_time: start.right_since,
                deactivation_time: None,
            }],
        ];
        let mut swings: [Vec<SwingTrajectory>; 2] = [Vec::new(), Vec::new()];
        for k in 0..n {
            let foot = steps[k].foot;
            let list = &mut contacts[idx(foot)];
            if let Some(last) = list.last_mut() {
                last.deactivation_time = Some(lift[k]);
            }
            list.push(PlannedContact {
                foot,
                pose: step_poses[k],
                activation_time: land[k],
                deactivation_time: None,
            });
            swings[idx(foot)].push(SwingTrajectory::new(
                foot,
                step_from[k],
                step_poses[k],
                lift[k],
                land[k],
                SwingShape {
                    height: cfg.swing_height,
                    apex_fraction: cfg.swing_apex_fraction,
                    landing_velocity: cfg.landing_velocity,
                },
            ));
        }
        let [lc, rc] = contacts;
        let [ls, rs] = swings;
        return Ok(Plan {
            omega,
            com_height: cfg.com_height,
            ground_height: start.ground,
            foot_length: cfg.foot_length,
            foot_width: cfg.foot_width,
            start_time: start.t_start,
            end_time,
            segments,
            phases,
            left_contacts: ContactList {
                foot: Foot::Left,
                contacts: lc,
            },
            right_contacts: ContactList {
                foot: Foot::Right,
                contacts: rc,
            },
            left_swings: ls,
            right_swings: rs,
            outcome,
            merge_times: Vec::new(),
        });
    }
}

/// DCM cubic of (10.1.23) on [0, T] from (ξ_a, ξ̇_a) to (ξ_b, ξ̇_b), as a segment (ZMP = ξ − ξ̇/ω).
fn dcm_cubic_segment(
    start: f64,
    duration: f64,
    (xa, va): (Vector2<f64>, Vector2<f64>),
    (xb, vb): (Vector2<f64>, Vector2<f64>),
    omega: f64,
) -> DcmSegment {
    let t = duration;
    let p = [
        xa,
        va,
        ((xb - xa) * 3.0 - (va * 2.0 + vb) * t) / (t * t),
        ((xa - xb) * 2.0 + (va + vb) * t) / (t * t * t),
    ];
    let z = [
        p[0] - p[1] / omega,
        p[1] - p[2] * (2.0 / omega),
        p[2] - p[3] * (3.0 / omega),
        p[3],
    ];
    DcmSegment::new(start, Some(duration), z, omega)
}

/// The thesis' DCM plan (10.1.16)–(10.1.23), (10.2.1)–(10.2.3): single-support exponentials from the
/// backward recursion with the last-step condition `ξ_eos = α x_last + (1 − α) x_stance`, exponentials
/// switching in the middle of each double support, double supports replaced by DCM cubics matching position and
/// velocity of the neighbouring exponentials, the first from the start state, the last to the feet mid-point at
/// rest.
#[allow(clippy::too_many_arguments)]
fn thesis_segments(
    omega: f64,
    alpha: f64,
    start: &StartState,
    lift: &[f64],
    land: &[f64],
    end_time: f64,
    stance_zmp: &[Vector2<f64>],
    last_landed: Vector2<f64>,
    final_mid: Vector2<f64>,
) -> Vec<DcmSegment> {
    let n = lift.len();
    // switch times σ_k: end of the exponential of step k
    let sigma: Vec<f64> = (0..n)
        .map(|k| {
            if k + 1 < n {
                0.5 * (land[k] + lift[k + 1])
            } else {
                land[k]
            }
        })
        .collect();
    let mut xi_end = vec![Vector2::zeros(); n];
    xi_end[n - 1] = last_landed * alpha + stance_zmp[n - 1] * (1.0 - alpha);
    for k in (1..n).rev() {
        let begin = sigma[k - 1];
        xi_end[k - 1] =
            stance_zmp[k] + (xi_end[k] - stance_zmp[k]) * (-omega * (sigma[k] - begin)).exp();
    }
    let exp_at = |k: usize, t: f64| {
        let e = (xi_end[k] - stance_zmp[k]) * (omega * (t - sigma[k])).exp();
        (stance_zmp[k] + e, e * omega)
    };
    let mut segments = Vec::with_capacity(2 * n + 2);
    let dcm_vel0 = (start.dcm0 - start.zmp0) * omega;
    segments.push(dcm_cubic_segment(
        start.t_start,
        lift[0] - start.t_start,
        (start.dcm0, dcm_vel0),
        exp_at(0, lift[0]),
        omega,
    ));
    for k in 0..n {
        let mut ss = DcmSegment::new(
            lift[k],
            Some(land[k] - lift[k]),
            zmp_constant(stance_zmp[k]),
            omega,
        );
        ss.growth = (xi_end[k] - stance_zmp[k]) * (omega * (lift[k] - sigma[k])).exp();
        segments.push(ss);
        if k + 1 < n {
            segments.push(dcm_cubic_segment(
                land[k],
                lift[k + 1] - land[k],
                exp_at(k, land[k]),
                exp_at(k + 1, lift[k + 1]),
                omega,
            ));
        } else {
            segments.push(dcm_cubic_segment(
                land[k],
                end_time - land[k],
                exp_at(k, land[k]),
                (final_mid, Vector2::zeros()),
                omega,
            ));
        }
    }
    segments.push(DcmSegment::new(
        end_time,
        None,
        zmp_constant(final_mid),
        omega,
    ));
    segments
}

/// The trajectory-layer object: holds the current plan, replans on new goals, samples references.
#[derive(Clone, Debug)]
pub struct Planner {
    config: PlannerConfig,
    /// Gravity magnitude \[m/s²\] (validated).
    gravity: f64,
    plan: Option<Plan>,
    output: PlanSample,
}

impl Planner {
    /// A planner for `config` under gravity of magnitude `gravity_m_s2` \[m/s²\] (the scenario's one
    /// gravity; ω = √(g/h) of the plans follows from it). Validates both: `InvalidParameter` for the
    /// config, `InvalidGravity` unless the gravity is finite and > 0.
    pub fn new(config: PlannerConfig, gravity_m_s2: f64) -> Result<Self, PlannerError> {
        config.validate()?;
        check_gravity(gravity_m_s2)?;
        Ok(Self {
            config,
            gravity: gravity_m_s2,
            plan: None,
            output: PlanSample::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &PlannerConfig {
        &self.config
    }

    /// The gravity magnitude the planner was built with \[m/s²\].
    pub fn gravity(&self) -> f64 {
        self.gravity
    }

    /// The current plan, if any.
    pub fn plan(&self) -> Option<&Plan> {
        self.plan.as_ref()
    }

    /// Starts a new plan from standing (see [`plan_from_standing`]); replaces any previous plan.
    pub fn start(
        &mut self,
        t0: f64,
        left: &Isometry3<f64>,
        right: &Isometry3<f64>,
        goal: &Goal,
    ) -> Result<&Plan, PlannerError> {
        let plan = plan_from_standing(&self.config, self.gravity, t0, left, right, goal)?;
        self.verify(&plan)?;
        Ok(self.plan.insert(plan))
    }

    /// Writes the references at `t` into `out` (no allocation).
    pub fn sample(&self, t: f64, out: &mut PlanSample) -> Result<(), PlannerError> {
        let plan = self.plan.as_ref().ok_or(PlannerError::NoPlan)?;
        plan.sample(t, out);
        Ok(())
    }

    /// The merge point a replan requested at `t` would use: the first double support whose merge point
    /// (`merge_point_fraction` into it) is at or after `t` and leaves some double support after it; in the
    /// final double support (or standing) any time works.
    pub fn merge_time(&self, t: f64) -> Result<f64, PlannerError> {
        let plan = self.plan.as_ref().ok_or(PlannerError::NoPlan)?;
        check_time("t", t)?;
        merge_point(&self.config, plan, t)
    }

    /// Merges a plan towards `goal` into the current one at the first merge point after `t`. Feet planned
    /// before the merge point do not move; DCM position/velocity, CoM and feet are continuous across it.
    /// Returns the merge time. On error the current plan is unchanged.
    pub fn replan(&mut self, t: f64, goal: &Goal) -> Result<f64, PlannerError> {
        goal.validate()?;
        let plan = self.plan.as_ref().ok_or(PlannerError::NoPlan)?;
        check_time("t", t)?;
        let cfg = &self.config;
        let m = merge_point(cfg, plan, t)?;
        let mut s = PlanSample::default();
        plan.sample(m, &mut s);
        let lc = plan.left_contacts.active_at(m).cloned();
        let rc = plan.right_contacts.active_at(m).cloned();
        let (Some(lc), Some(rc)) = (lc, rc) else {
            return Err(PlannerError::NoMergePoint { time: t });
        };
        // next single support in the old plan decides who swings first
        let next_ss = plan
            .phases
            .iter()
            .find(|p| p.start >= m && matches!(p.kind, PhaseKind::SingleSupport { .. }));
        let current_ds = plan
            .phases
            .iter()
            .rev()
            .find(|p| p.start <= m && p.kind == PhaseKind::DoubleSupport);
        let f = cfg.double_support_fraction;
        let min_remaining = 0.5 * (1.0 - cfg.merge_point_fraction) * f * cfg.step_duration_min;
        let (first_swing, anchor, anchor_time, min_init) = match next_ss {
            Some(Phase {
                kind: PhaseKind::SingleSupport { stance },
                ..
            }) => {
                let swing = stance.other();
                // re-anchor the unicycle on the most recently landed foot, if it landed in this plan
                let landed = if lc.activation_time >= rc.activation_time {
                    &lc
                } else {
                    &rc
                };
                let ds_start = current_ds.map_or(plan.start_time, |p| p.start);
                let ds_end = current_ds.map_or(m, |p| p.end);
                if landed.activation_time > plan.start_time
                    && landed.activation_time >= ds_start - 1e-12
                {
                    let p = Pose2::from_isometry(&landed.pose);
                    let c = p.transform_point(Vector2::new(
                        0.0,
                        -landed.foot.side() * 0.5 * cfg.nominal_width,
                    ));
                    (
                        Some(swing),
                        Pose2 {
                            x: c.x,
                            y: c.y,
                            yaw: p.yaw,
                        },
                        landed.activation_time,
                        min_remaining,
                    )
                } else {
                    (
                        Some(swing),
                        mid_pose(&lc.pose, &rc.pose),
                        m,
                        (ds_end - m).max(min_remaining),
                    )
                }
            }
            _ => (
                None,
                mid_pose(&lc.pose, &rc.pose),
                m,
                cfg.initial_double_support_duration,
            ),
        };
        let start = StartState {
            t_start: m,
            anchor_time,
            anchor,
            min_initial_ds: min_init,
            left: lc.pose,
            right: rc.pose,
            left_since: lc.activation_time,
            right_since: rc.activation_time,
            zmp0: Vector2::new(s.zmp.x, s.zmp.y),
            dcm0: Vector2::new(s.dcm_position.x, s.dcm_position.y),
            com0: Vector2::new(s.com_position.x, s.com_position.y),
            ground: plan.ground_height,
            first_swing,
        };
        let new = build_plan(cfg, cfg.omega(self.gravity), &start, goal)?;
        let merged = merge(plan, new, m);
        self.verify(&merged)?;
        self.plan = Some(merged);
        Ok(m)
    }

    /// Verifies `plan` when [`PlannerConfig::verify_plans`] is enabled in this build.
    fn verify(&self, plan: &Plan) -> Result<(), PlannerError> {
        if self.config.verify_plans.enabled() {
            plan.verify(&self.config, VERIFY_SAMPLING_PERIOD)?;
        }
        Ok(())
    }
}

/// Sampling period of the run-time plan verification \[s\].
pub const VERIFY_SAMPLING_PERIOD: f64 = 0.01;

fn mid_pose(l: &Isometry3<f64>, r: &Isometry3<f64>) -> Pose2 {
    let (a, b) = (Pose2::from_isometry(l), Pose2::from_isometry(r));
    let mid = (a.position() + b.position()) * 0.5;
    Pose2 {
        x: mid.x,
        y: mid.y,
        yaw: b.yaw + 0.5 * wrap_angle(a.yaw - b.yaw),
    }
}

fn merge_point(cfg: &PlannerConfig, plan: &Plan, t: f64) -> Result<f64, PlannerError> {
    let t = t.max(plan.start_time);
    let r = cfg.merge_point_fraction;
    let min_remaining = 0.5 * (1.0 - r) * cfg.double_support_fraction * cfg.step_duration_min;
    let last = plan.phases.len().saturating_sub(1);
    for (i, p) in plan.phases.iter().enumerate() {
        if p.kind != PhaseKind::DoubleSupport {
            continue;
        }
        let m = (p.start + r * (p.end - p.start)).max(t);
        if i == last {
            return Ok(m);
        }
        if m <= p.end - min_remaining {
            return Ok(m);
        }
    }
    if plan.phases.is_empty() {
        return Ok(t);
    }
    Err(PlannerError::NoMergePoint { time: t })
}

fn merge(old: &Plan, new: Plan, m: f64) -> Plan {
    let mut segments: Vec<DcmSegment> = old
        .segments
        .iter()
        .filter(|s| s.start < m)
        .cloned()
        .collect();
    if let Some(last) = segments.last_mut() {
        last.duration = Some(m - last.start);
    }
    segments.extend(new.segments);
    let mut phases: Vec<Phase> = old.phases.iter().filter(|p| p.start < m).cloned().collect();
    let mut new_phases = new.phases.into_iter();
    match phases.last_mut() {
        Some(last) if last.kind == PhaseKind::DoubleSupport => {
            if let Some(first) = new_phases.next() {
                last.end = first.end;
            }
        }
        _ => {}
    }
    phases.extend(new_phases);
    let keep = |list: &ContactList, new: ContactList| {
        let mut c: Vec<PlannedContact> = list
            .contacts
            .iter()
            .filter(|c| c.deactivation_time.is_some_and(|d| d <= m))
            .cloned()
            .collect();
        c.extend(new.contacts);
        ContactList {
            foot: list.foot,
            contacts: c,
        }
    };
    let keep_swings = |old: &[SwingTrajectory], new: Vec<SwingTrajectory>| {
        let mut s: Vec<SwingTrajectory> =
            old.iter().filter(|s| s.land_time <= m).cloned().collect();
        s.extend(new);
        s
    };
    let mut merge_times = old.merge_times.clone();
    merge_times.push(m);
    Plan {
        omega: new.omega,
        com_height: new.com_height,
        ground_height: new.ground_height,
        foot_length: new.foot_length,
        foot_width: new.foot_width,
        start_time: old.start_time,
        end_time: new.end_time,
        segments,
        phases,
        left_contacts: keep(&old.left_contacts, new.left_contacts),
        right_contacts: keep(&old.right_contacts, new.right_contacts),
        left_swings: keep_swings(&old.left_swings, new.left_swings),
        right_swings: keep_swings(&old.right_swings, new.right_swings),
        outcome: new.outcome,
        merge_times,
    }
}

/// Input of the planner block for one tick.
#[derive(Clone, Debug, PartialEq)]
pub struct PlannerInput {
    /// Current time.
    pub time: Duration,
    /// A new goal, if one arrived this tick (a replan, or the first plan).
    pub goal: Option<Goal>,
    /// Measured left sole pose (used only to start the first plan).
    pub left_sole: Isometry3<f64>,
    /// Measured right sole pose (used only to start the first plan).
    pub right_sole: Isometry3<f64>,
}

impl stride_block::Block for Planner {
    type Input = PlannerInput;
    type Output = PlanSample;
    type Error = PlannerError;

    /// First call: starts a plan from the measured soles (standing if no goal). Later calls with a goal:
    /// replan at the next merge point (this allocates; ticks without a goal do not). Then samples.
    fn step(&mut self, input: &PlannerInput) -> Result<&PlanSample, PlannerError> {
        let t = input.time.as_secs_f64();
        if self.plan.is_none() {
            let goal = input.goal.clone().unwrap_or(Goal::Stand);
            self.start(t, &input.left_sole, &input.right_sole, &goal)?;
        } else if let Some(goal) = &input.goal {
            self.replan(t, goal)?;
        }
        let Self { plan, output, .. } = self;
        if let Some(p) = plan.as_ref() {
            p.sample(t, output);
        }
        Ok(&self.output)
    }

    fn reset(&mut self) {
        self.plan = None;
        self.output = PlanSample::default();
    }
}

#[cfg(test)]
mod finiteness_tests {
    use super::*;

    #[test]
    fn non_finite_segments_are_refused_and_named() {
        let z = zmp_constant(Vector2::new(0.1, 0.0));
        let good = DcmSegment::new(0.0, Some(0.5), z, 4.0);
        assert!(check_segments_finite(std::slice::from_ref(&good)).is_ok());
        for (quantity, edit) in [
            (
                "zmp",
                (|s: &mut DcmSegment| s.zmp[1].x = f64::NAN) as fn(&mut DcmSegment),
            ),
            ("dcm", |s| s.growth.y = f64::INFINITY),
            ("com", |s| s.decay.x = f64::NAN),
        ] {
            let mut bad = good.clone();
            bad.start = 1.25;
            edit(&mut bad);
            match check_segments_finite(&[good.clone(), bad]) {
                Err(PlannerError::NonFinitePlan { time, quantity: q }) => {
                    assert_eq!(time, 1.25);
                    assert_eq!(q, quantity);
                }
                other => panic!("{quantity}: expected NonFinitePlan, got {other:?}"),
            }
        }
    }
}
