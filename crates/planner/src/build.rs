//! Building a plan from a start state (a fresh start from standing or a merge point): footholds,
//! timeline, DCM segments, CoM, phases, contacts and swings.

use nalgebra::{Isometry3, Vector2};

use crate::config::{DcmInterpolation, PlannerConfig};
use crate::contacts::{ContactList, Foot, Phase, PhaseKind, PlannedContact};
use crate::dcm::{
    bump_coefficients, dcm_particular, dcm_particular_scalar, eval_cubic_scalar, eval_cubic_value,
    zmp_constant, zmp_transition, DcmSegment,
};
use crate::error::PlannerError;
use crate::geometry::{wrap_angle, Pose2};
use crate::goal::Goal;
use crate::plan::{Plan, PlanOutcome, WaypointProgress};
use crate::swing::{SwingShape, SwingTrajectory};
use crate::unicycle::{choose_first_swing, search_footsteps, unicycle_path, StepPlan};
use stride_block::SupportPolygon;

/// Everything a new (partial) plan starts from.
#[derive(Clone, Debug)]
pub(crate) struct StartState {
    /// Plan time where the new plan starts (fresh start or merge point).
    pub(crate) t_start: f64,
    /// Plan time of unicycle time 0.
    pub(crate) anchor_time: f64,
    /// Unicycle pose at unicycle time 0.
    pub(crate) anchor: Pose2,
    /// Minimum duration of the first double support \[s\].
    pub(crate) min_initial_ds: f64,
    pub(crate) left: Isometry3<f64>,
    pub(crate) right: Isometry3<f64>,
    pub(crate) left_since: f64,
    pub(crate) right_since: f64,
    pub(crate) zmp0: Vector2<f64>,
    pub(crate) dcm0: Vector2<f64>,
    pub(crate) com0: Vector2<f64>,
    pub(crate) ground: f64,
    pub(crate) first_swing: Option<Foot>,
}

pub(crate) fn xy(h: &Isometry3<f64>) -> Vector2<f64> {
    Vector2::new(h.translation.x, h.translation.y)
}

/// Every coefficient of every segment is finite, or the plan is refused: a plan never carries NaN.
pub(crate) fn check_segments_finite(segments: &[DcmSegment]) -> Result<(), PlannerError> {
    match segments
        .iter()
        .find_map(|seg| seg.non_finite_quantity().map(|q| (seg.start, q)))
    {
        Some((time, quantity)) => Err(PlannerError::NonFinitePlan { time, quantity }),
        None => Ok(()),
    }
}

/// Builds a plan from a start state (fresh or merge) towards `goal`, with the LIPM natural frequency
/// `omega` \[1/s\]: unicycle path and footsteps, then timeline, DCM segments (the first double
/// support lengthened until its ZMP stays in the support polygon), CoM, phases, contacts and swings.
pub(crate) fn build_plan(
    cfg: &PlannerConfig,
    omega: f64,
    start: &StartState,
    goal: &Goal,
) -> Result<Plan, PlannerError> {
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
    let footholds = footholds(cfg, start, &steps);
    let mut min_init = start.min_initial_ds;
    let mut attempt = 0;
    let (timeline, mut segments) = loop {
        let timeline = timeline(cfg, start, &steps, min_init);
        let segments = if cfg.dcm_interpolation == DcmInterpolation::DcmCubic && !steps.is_empty() {
            thesis_segments(omega, cfg.last_step_dcm_alpha, start, &footholds, &timeline)
        } else {
            zmp_first_segments(omega, start, &footholds, &timeline)
        };
        check_segments_finite(&segments)?;
        let worst = worst_zmp_margin(cfg, omega, &segments, &footholds, start.t_start);
        if worst.0 < 0.0 {
            attempt += 1;
            if attempt > 8 || worst.2 != 0 {
                return Err(PlannerError::ZmpOutsideSupport {
                    time: worst.1,
                    distance: -worst.0,
                });
            }
            min_init = timeline.first_double_support * 1.5;
            continue;
        }
        break (timeline, segments);
    };
    // forward pass: CoM continuity
    let mut com = start.com0;
    for seg in segments.iter_mut() {
        seg.set_com_start(com);
        if let Some(d) = seg.duration {
            com = seg.evaluate_local(d, omega).com;
        }
    }
    check_segments_finite(&segments)?;
    let phases = phases(&steps, &timeline, start.t_start);
    let ([lc, rc], [ls, rs]) = contacts_and_swings(cfg, start, &steps, &footholds, &timeline)?;
    Ok(Plan {
        omega,
        com_height: cfg.com_height,
        ground_height: start.ground,
        foot_length: cfg.foot_length,
        foot_width: cfg.foot_width,
        start_time: start.t_start,
        end_time: timeline.end_time,
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
        waypoint_progress: matches!(goal, Goal::Waypoints { .. }).then_some(WaypointProgress {
            origin: start.anchor,
            passed: 0,
        }),
    })
}

/// Index of a foot in `[left, right]` arrays.
fn foot_index(foot: Foot) -> usize {
    match foot {
        Foot::Left => 0,
        Foot::Right => 1,
    }
}

/// Where the feet go along the steps, and the support polygons they make.
struct Footholds {
    /// ZMP of each single support: the stance sole's origin \[m\].
    stance_zmp: Vec<Vector2<f64>>,
    /// Landing pose of each step's swing foot.
    step_poses: Vec<Isometry3<f64>>,
    /// Lift-off pose of each step's swing foot.
    step_from: Vec<Isometry3<f64>>,
    /// Mid-point of the final feet \[m\].
    final_mid: Vector2<f64>,
    /// Hull of the two starting soles (`None`: degenerate, which validated foot dimensions exclude).
    initial_polygon: Option<SupportPolygon>,
    /// Hull of the two soles in the double support after each touch-down.
    ds_polygons: Vec<Option<SupportPolygon>>,
}

/// Hull of the two soles `feet = [left, right]` (`None` when degenerate): valid whether the feet are
/// crossed or not.
pub(crate) fn double_support_polygon(
    cfg: &PlannerConfig,
    feet: &[Isometry3<f64>; 2],
) -> Option<SupportPolygon> {
    let a = SupportPolygon::foot_corners(&feet[0], cfg.foot_length, cfg.foot_width);
    let b = SupportPolygon::foot_corners(&feet[1], cfg.foot_length, cfg.foot_width);
    SupportPolygon::convex_hull(&[a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]]).ok()
}

/// Foot poses along the steps, the stance ZMP of each step and the double-support polygons.
fn footholds(cfg: &PlannerConfig, start: &StartState, steps: &[StepPlan]) -> Footholds {
    let mut cur = [start.left, start.right];
    let mut stance_zmp = Vec::with_capacity(steps.len());
    let mut step_poses = Vec::with_capacity(steps.len());
    let mut step_from = Vec::with_capacity(steps.len());
    let mut ds_polygons = Vec::with_capacity(steps.len());
    for s in steps {
        stance_zmp.push(xy(&cur[foot_index(s.foot.other())]));
        let pose = s.pose.to_isometry(start.ground);
        step_from.push(cur[foot_index(s.foot)]);
        step_poses.push(pose);
        cur[foot_index(s.foot)] = pose;
        ds_polygons.push(double_support_polygon(cfg, &cur));
    }
    Footholds {
        stance_zmp,
        step_poses,
        step_from,
        final_mid: (xy(&cur[0]) + xy(&cur[1])) * 0.5,
        initial_polygon: double_support_polygon(cfg, &[start.left, start.right]),
        ds_polygons,
    }
}

/// When each step lifts off and lands, and when the plan ends \[s, plan time\].
struct Timeline {
    lift: Vec<f64>,
    land: Vec<f64>,
    end_time: f64,
    /// Duration of the first double support \[s\].
    first_double_support: f64,
}

/// The timeline of `steps` from `start`, the first double support lasting at least `min_init` \[s\].
fn timeline(
    cfg: &PlannerConfig,
    start: &StartState,
    steps: &[StepPlan],
    min_init: f64,
) -> Timeline {
    let f = cfg.double_support_fraction;
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
    let first_double_support = if n > 0 { lift[0] } else { end_time } - start.t_start;
    Timeline {
        lift,
        land,
        end_time,
        first_double_support,
    }
}

/// The ZMP-first DCM plan: ZMP constant on the stance sole in single support, a cubic move between
/// the stance points in double support, the DCM from the backward recursion ending on the final ZMP
/// [Romualdi 2022, eq. 10.1.17], and a ZMP bump in the first double support so that the DCM starts
/// at the start state's.
fn zmp_first_segments(
    omega: f64,
    start: &StartState,
    footholds: &Footholds,
    timeline: &Timeline,
) -> Vec<DcmSegment> {
    let (lift, land, end_time) = (&timeline.lift, &timeline.land, timeline.end_time);
    let (stance_zmp, final_mid) = (&footholds.stance_zmp, footholds.final_mid);
    let n = lift.len();
    let d0 = timeline.first_double_support;
    let first_target = if n > 0 { stance_zmp[0] } else { final_mid };
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
    // backward pass: DCM at each segment end, the final DCM on the final ZMP
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
}

/// The smallest margin of the ZMP inside the support polygon, as `(margin [m], time [s], segment)`,
/// over every double support whose shape depends on the DCM boundary conditions (the first one; all
/// of them for the thesis DCM cubic): 1e-4 m inside at 64 points (the ZMP cubic cannot move more than
/// ~3e-5 m away from its chords between those points). A NaN distance counts as outside.
fn worst_zmp_margin(
    cfg: &PlannerConfig,
    omega: f64,
    segments: &[DcmSegment],
    footholds: &Footholds,
    t_start: f64,
) -> (f64, f64, usize) {
    const CHECKS: usize = 64;
    let mut worst = (f64::INFINITY, t_start, 0usize);
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
            &footholds.initial_polygon
        } else {
            &footholds.ds_polygons[i / 2 - 1]
        };
        for k in 0..=CHECKS {
            let tau = d * k as f64 / CHECKS as f64;
            let z = seg.evaluate_local(tau, omega).zmp;
            let dist = polygon.map_or(f64::NEG_INFINITY, |p| p.signed_distance(z)) - 1e-4;
            let dist = if dist.is_nan() { -f64::INFINITY } else { dist };
            if dist < worst.0 {
                worst = (dist, seg.start + tau, i);
            }
        }
    }
    worst
}

/// The gait phases: the first double support, then per step its single and double support.
fn phases(steps: &[StepPlan], timeline: &Timeline, t_start: f64) -> Vec<Phase> {
    let (lift, land, end_time) = (&timeline.lift, &timeline.land, timeline.end_time);
    let n = steps.len();
    let mut phases = Vec::with_capacity(2 * n + 1);
    phases.push(Phase {
        kind: PhaseKind::DoubleSupport,
        start: t_start,
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
    phases
}

/// Contacts and swing trajectories, `[left, right]`.
type FeetPlans = ([Vec<PlannedContact>; 2], [Vec<SwingTrajectory>; 2]);

/// The contacts of each foot (the start poses, then every landing) and its swing trajectories, each going
/// round the stance sole if its straight path would cross it ([`SwingTrajectory::go_round`]).
fn contacts_and_swings(
    cfg: &PlannerConfig,
    start: &StartState,
    steps: &[StepPlan],
    footholds: &Footholds,
    timeline: &Timeline,
) -> Result<FeetPlans, PlannerError> {
    let (lift, land) = (&timeline.lift, &timeline.land);
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
    for (k, step) in steps.iter().enumerate() {
        let foot = step.foot;
        let list = &mut contacts[foot_index(foot)];
        if let Some(last) = list.last_mut() {
            last.deactivation_time = Some(lift[k]);
        }
        list.push(PlannedContact {
            foot,
            pose: footholds.step_poses[k],
            activation_time: land[k],
            deactivation_time: None,
        });
        let mut swing = SwingTrajectory::new(
            foot,
            footholds.step_from[k],
            footholds.step_poses[k],
            lift[k],
            land[k],
            SwingShape {
                height: cfg.swing_height,
                apex_fraction: cfg.swing_apex_fraction,
                landing_velocity: cfg.landing_velocity,
            },
        );
        // the stance sole: round it when the feet start crossed (the step that uncrosses them)
        let stance = contacts[foot_index(foot.other())]
            .last()
            .map(|c| c.pose)
            .unwrap_or(footholds.step_from[k]);
        if !swing.go_round(lift[k], &stance, cfg.foot_length, cfg.foot_width) {
            return Err(PlannerError::SwingOverStance { time: lift[k] });
        }
        swings[foot_index(foot)].push(swing);
    }
    Ok((contacts, swings))
}

/// DCM cubic of [Romualdi 2022, eq. 10.1.23] on [0, T] from (ξ_a, ξ̇_a) to (ξ_b, ξ̇_b), as a segment (ZMP = ξ − ξ̇/ω).
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

/// The thesis' DCM plan [Romualdi 2022, eqs. 10.1.16–10.1.23, 10.2.1–10.2.3]: single-support exponentials from the
/// backward recursion with the last-step condition `ξ_eos = α x_last + (1 − α) x_stance`, exponentials
/// switching in the middle of each double support, double supports replaced by DCM cubics matching position and
/// velocity of the neighbouring exponentials, the first from the start state, the last to the feet mid-point at
/// rest.
fn thesis_segments(
    omega: f64,
    alpha: f64,
    start: &StartState,
    footholds: &Footholds,
    timeline: &Timeline,
) -> Vec<DcmSegment> {
    let (lift, land, end_time) = (&timeline.lift, &timeline.land, timeline.end_time);
    let (stance_zmp, final_mid) = (&footholds.stance_zmp, footholds.final_mid);
    let n = lift.len();
    let last_landed = xy(&footholds.step_poses[n - 1]);
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
