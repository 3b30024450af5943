//! Independent checks of a plan's invariants, shared by the scenario and property tests.
#![allow(dead_code)]

use std::time::Duration;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector2, Vector3};
use stride_planner::{Foot, Plan, PlanSample, PlannerConfig};

/// The instant `t` \[s\] rounded to whole nanoseconds: the `Duration` the planner's API takes and the plan
/// time \[s\] it stands for (`stride_block::seconds`).
pub fn instant(t: f64) -> (Duration, f64) {
    let d = Duration::from_secs_f64(t);
    (d, stride_block::seconds(d))
}

/// Gravity magnitude the tests plan with \[m/s²\] (the runner passes the scenario's).
pub const GRAVITY: f64 = 9.81;

pub fn sole(x: f64, y: f64, yaw: f64) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(x, y, 0.0),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw),
    )
}

/// Feet standing parallel around (x, y) with heading yaw, `width` apart.
pub fn standing(x: f64, y: f64, yaw: f64, width: f64) -> (Isometry3<f64>, Isometry3<f64>) {
    let (s, c) = yaw.sin_cos();
    let h = 0.5 * width;
    (
        sole(x - s * h, y + c * h, yaw),
        sole(x + s * h, y - c * h, yaw),
    )
}

pub fn yaw_of(h: &Isometry3<f64>) -> f64 {
    let x = h.rotation * Vector3::x();
    x.y.atan2(x.x)
}

/// Left sole position in the right sole frame (planar) and relative yaw.
pub fn left_in_right(l: &Isometry3<f64>, r: &Isometry3<f64>) -> (Vector2<f64>, f64) {
    let ry = yaw_of(r);
    let d = l.translation.vector - r.translation.vector;
    let (s, c) = ry.sin_cos();
    (
        Vector2::new(c * d.x + s * d.y, -s * d.x + c * d.y),
        stride_planner::geometry::wrap_angle(yaw_of(l) - ry),
    )
}

pub fn corners(h: &Isometry3<f64>, cfg: &PlannerConfig) -> Vec<Vector2<f64>> {
    let (a, b) = (cfg.foot_length / 2.0, cfg.foot_width / 2.0);
    [(a, b), (-a, b), (-a, -b), (a, -b)]
        .iter()
        .map(|&(x, y)| {
            let p = h * nalgebra::Point3::new(x, y, 0.0);
            Vector2::new(p.x, p.y)
        })
        .collect()
}

/// Brute-force "inside the convex hull": for every pair of points that has all points on its left, p must be
/// on its left as well (tolerance `eps`).
pub fn in_hull(points: &[Vector2<f64>], p: Vector2<f64>, eps: f64) -> bool {
    let cross = |o: Vector2<f64>, a: Vector2<f64>, b: Vector2<f64>| {
        (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x)
    };
    for (i, a) in points.iter().enumerate() {
        for (j, b) in points.iter().enumerate() {
            if i == j || (a - b).norm() < 1e-12 {
                continue;
            }
            if points.iter().all(|q| cross(*a, *b, *q) >= -1e-12) {
                let d = cross(*a, *b, p) / (b - a).norm();
                if d < -eps {
                    return false;
                }
            }
        }
    }
    true
}

/// Separating-axis test: do two sole rectangles overlap?
pub fn rectangles_overlap(a: &[Vector2<f64>], b: &[Vector2<f64>]) -> bool {
    for poly in [a, b] {
        for i in 0..4 {
            let e = poly[(i + 1) % 4] - poly[i];
            let n = Vector2::new(-e.y, e.x);
            let (amin, amax) = a.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| {
                (lo.min(n.dot(p)), hi.max(n.dot(p)))
            });
            let (bmin, bmax) = b.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| {
                (lo.min(n.dot(p)), hi.max(n.dot(p)))
            });
            if amax < bmin || bmax < amin {
                return false;
            }
        }
    }
    true
}

pub fn sample(plan: &Plan, t: f64) -> PlanSample {
    let mut s = PlanSample::default();
    plan.sample(t, &mut s);
    s
}

/// Every planned step respects the bounds; feet never cross or overlap.
pub fn check_steps(cfg: &PlannerConfig, plan: &Plan, check_durations: bool) {
    let tol = 1e-9;
    let f = cfg.double_support_fraction;
    let mut landings = Vec::new();
    for foot in [Foot::Left, Foot::Right] {
        for sw in plan.swings(foot) {
            let d = sw.land_time - sw.lift_time;
            if check_durations {
                assert!(
                    d >= (1.0 - f) * cfg.step_duration_min - tol
                        && d <= (1.0 - f) * cfg.step_duration_max + tol,
                    "swing duration {d}"
                );
            }
            landings.push((sw.land_time, foot));
        }
    }
    landings.sort_by(|a, b| a.0.total_cmp(&b.0));
    if check_durations {
        for w in landings.windows(2) {
            let d = w[1].0 - w[0].0;
            assert!(
                d >= cfg.step_duration_min - 1e-9 && d <= cfg.step_duration_max + 1e-9,
                "touch-down to touch-down {d} outside [{}, {}]",
                cfg.step_duration_min,
                cfg.step_duration_max
            );
        }
    }
    for &(t, _) in &landings {
        let l = plan
            .left_contacts
            .active_at(t)
            .expect("left in contact at touch-down");
        let r = plan
            .right_contacts
            .active_at(t)
            .expect("right in contact at touch-down");
        let (rel, dyaw) = left_in_right(&l.pose, &r.pose);
        assert!(
            rel.norm() <= cfg.feet_distance_max + tol,
            "step length {} at {t}",
            rel.norm()
        );
        assert!(
            rel.norm() >= cfg.feet_distance_min - tol,
            "step length {} at {t}",
            rel.norm()
        );
        // width: left sole left of the right one in the right-sole frame or, mirrored, right sole right of
        // the left one in the left-sole frame (the constraint must not depend on which foot is "right")
        let (rel_mirror, _) = left_in_right(&r.pose, &l.pose);
        let width = rel.y.max(-rel_mirror.y);
        assert!(width >= cfg.min_width - tol, "width {width} at {t}");
        assert!(
            dyaw.abs() <= cfg.max_yaw_per_step + tol,
            "yaw {dyaw} at {t}"
        );
        assert!(
            !rectangles_overlap(&corners(&l.pose, cfg), &corners(&r.pose, cfg)),
            "feet overlap at {t}"
        );
    }
    // the final stance: parallel at the nominal width
    let l = plan.left_contacts.contacts.last().unwrap();
    let r = plan.right_contacts.contacts.last().unwrap();
    assert!(l.deactivation_time.is_none() && r.deactivation_time.is_none());
    if plan.step_count() > 0 {
        let (rel, dyaw) = left_in_right(&l.pose, &r.pose);
        assert!(dyaw.abs() <= 1e-3, "final feet not parallel: {dyaw}");
        assert!(
            (rel.y - cfg.nominal_width).abs() <= 1e-3 && rel.x.abs() <= 1e-3,
            "final feet {rel:?}"
        );
    }
}

/// ZMP in the support polygon, LIPM, DCM definition and continuity, final DCM, all at many times.
pub fn check_dynamics(cfg: &PlannerConfig, plan: &Plan, dt: f64) {
    let w = (GRAVITY / cfg.com_height).sqrt();
    let mut t = plan.start_time;
    let end = plan.end_time + 2.0;
    let mut prev: Option<PlanSample> = None;
    while t <= end {
        let s = sample(plan, t);
        assert!((s.omega - w).abs() < 1e-12);
        // ZMP in the support polygon (independent hull test)
        let mut pts = Vec::new();
        for foot in [&s.left, &s.right] {
            if foot.in_contact {
                pts.extend(corners(&foot.pose, cfg));
            }
        }
        assert!(!pts.is_empty(), "no foot in contact at {t}");
        let z = Vector2::new(s.zmp.x, s.zmp.y);
        assert!(
            in_hull(&pts, z, 1e-9),
            "ZMP {z:?} outside support at t = {t}"
        );
        // DCM definition ξ = x + ẋ/ω and DCM dynamics ξ̇ = ω(ξ − ZMP)
        let xi = s.com_position + s.com_velocity / w;
        assert!(
            (xi.xy() - s.dcm_position.xy()).norm() < 1e-9,
            "DCM != x + v/ω at {t}"
        );
        assert!(
            (s.dcm_velocity.xy() - (s.dcm_position.xy() - z) * w).norm() < 1e-9,
            "DCM dynamics at {t}"
        );
        // LIPM with the planned ZMP by finite differences (Richardson-extrapolated central differences, away
        // from the plan start and merge points where the ZMP velocity may jump)
        let h = 1e-3;
        // (central differences assume a smooth function: skip 3h around the segment joints, where the ZMP's
        // second derivative jumps; continuity there is checked separately below)
        let near_merge = plan.merge_times.iter().any(|m| (t - m).abs() < 3.0 * h)
            || plan.segments.iter().any(|g| (t - g.start).abs() < 3.0 * h);
        if t - 2.0 * h >= plan.start_time && !near_merge {
            let x = |dt: f64| sample(plan, t + dt);
            let (a1, b1, a2, b2) = (x(-h), x(h), x(-2.0 * h), x(2.0 * h));
            let d2 = |a: &PlanSample, b: &PlanSample, hh: f64| {
                (b.com_position - 2.0 * s.com_position + a.com_position) / (hh * hh)
            };
            let acc = (d2(&a1, &b1, h) * 4.0 - d2(&a2, &b2, 2.0 * h)) / 3.0;
            let lipm = (s.com_position.xy() - z) * (w * w);
            assert!(
                (acc.xy() - lipm).norm() < 1e-6,
                "LIPM violated at {t}: {acc:?} vs {lipm:?}"
            );
            assert!(
                (s.com_acceleration.xy() - lipm).norm() < 1e-9,
                "reported CoM acceleration at {t}"
            );
            let d1 = |a: &PlanSample, b: &PlanSample, hh: f64| {
                (b.com_position - a.com_position) / (2.0 * hh)
            };
            let vel = (d1(&a1, &b1, h) * 4.0 - d1(&a2, &b2, 2.0 * h)) / 3.0;
            assert!((vel - s.com_velocity).norm() < 1e-7, "CoM velocity at {t}");
            let e1 = |a: &PlanSample, b: &PlanSample, hh: f64| {
                (b.dcm_position - a.dcm_position) / (2.0 * hh)
            };
            let dvel = (e1(&a1, &b1, h) * 4.0 - e1(&a2, &b2, 2.0 * h)) / 3.0;
            assert!(
                (dvel - s.dcm_velocity).norm() < 1e-6,
                "DCM velocity FD at {t}"
            );
        }
        // continuity between consecutive samples (no jumps beyond what the velocity allows)
        if let Some(p) = prev {
            let bound = (p.dcm_velocity.norm().max(s.dcm_velocity.norm()) + 1.0) * dt * 1.5;
            assert!(
                (s.dcm_position - p.dcm_position).norm() < bound,
                "DCM jump at {t}"
            );
        }
        prev = Some(s);
        t += dt;
    }
    // continuity at every segment boundary (left/right limits)
    for seg in plan.segments.iter().skip(1) {
        let tb = seg.start;
        let before = {
            let prev = plan.segments.iter().rev().find(|s| s.start < tb).unwrap();
            prev.evaluate_local(tb - prev.start, w)
        };
        let after = seg.evaluate_local(0.0, w);
        assert!(
            (before.dcm - after.dcm).norm() < 1e-9,
            "DCM discontinuous at {tb}"
        );
        assert!(
            (before.dcm_velocity - after.dcm_velocity).norm() < 1e-8,
            "DCM velocity discontinuous at {tb}"
        );
        assert!(
            (before.com - after.com).norm() < 1e-9,
            "CoM discontinuous at {tb}"
        );
        assert!(
            (before.com_velocity - after.com_velocity).norm() < 1e-8,
            "CoM vel discontinuous at {tb}"
        );
        assert!(
            (before.zmp - after.zmp).norm() < 1e-9,
            "ZMP discontinuous at {tb}"
        );
        assert!(
            (before.com_acceleration - after.com_acceleration).norm() < 1e-7,
            "CoM acceleration discontinuous at {tb}"
        );
    }
    // the DCM ends on the final ZMP (feet mid-point), standing still
    let l = plan
        .left_contacts
        .contacts
        .last()
        .unwrap()
        .pose
        .translation
        .vector;
    let r = plan
        .right_contacts
        .contacts
        .last()
        .unwrap()
        .pose
        .translation
        .vector;
    let mid = Vector2::new(0.5 * (l.x + r.x), 0.5 * (l.y + r.y));
    for t in [plan.end_time, plan.end_time + 5.0] {
        let s = sample(plan, t);
        assert!(
            (s.dcm_position.xy() - mid).norm() < 1e-3,
            "final DCM {:?} vs {mid:?}",
            s.dcm_position
        );
        assert!((s.zmp.xy() - mid).norm() < 1e-9);
        assert!(s.dcm_velocity.norm() < 1e-9);
        assert!(s.left.in_contact && s.right.in_contact);
    }
}

/// Swing feet leave/land at the planned poses and velocities at the planned times, reach the apex.
pub fn check_swings(cfg: &PlannerConfig, plan: &Plan) {
    for foot in [Foot::Left, Foot::Right] {
        let contacts = &plan.contacts(foot).contacts;
        for sw in plan.swings(foot) {
            let before = contacts
                .iter()
                .find(|c| c.deactivation_time == Some(sw.lift_time))
                .expect("a contact ends at lift-off");
            let after = contacts
                .iter()
                .find(|c| c.activation_time == sw.land_time)
                .expect("a contact starts at touch-down");
            let a = sw.evaluate(sw.lift_time);
            let b = sw.evaluate(sw.land_time);
            assert!((a.pose.translation.vector - before.pose.translation.vector).norm() < 1e-12);
            assert!(a.pose.rotation.angle_to(&before.pose.rotation) < 1e-9);
            assert!((b.pose.translation.vector - after.pose.translation.vector).norm() < 1e-9);
            assert!(b.pose.rotation.angle_to(&after.pose.rotation) < 1e-9);
            assert!(a.twist.norm() < 1e-12, "lift-off velocity {:?}", a.twist);
            let expected = nalgebra::Vector6::new(0.0, 0.0, cfg.landing_velocity, 0.0, 0.0, 0.0);
            assert!(
                (b.twist - expected).norm() < 1e-9,
                "touch-down velocity {:?}",
                b.twist
            );
            let apex = sw.evaluate(sw.apex_time).pose.translation.z;
            let want = before.pose.translation.z.max(after.pose.translation.z) + cfg.swing_height;
            assert!((apex - want).abs() < 1e-12, "apex {apex} vs {want}");
            // the apex is the highest point; the foot never goes below the lower foothold
            let zlow = before.pose.translation.z.min(after.pose.translation.z);
            for i in 0..=200 {
                let t = sw.lift_time + (sw.land_time - sw.lift_time) * i as f64 / 200.0;
                let z = sw.evaluate(t).pose.translation.z;
                assert!(z <= want + 1e-9, "swing above apex at {t}: {z}");
                assert!(z >= zlow - 1e-9, "swing below ground at {t}: {z}");
                // sampling the plan in flight gives the swing, out of contact, never over the stance sole
                if t > sw.lift_time && t < sw.land_time {
                    let s = sample(plan, t);
                    assert!(!s.foot(foot).in_contact);
                    let stance = s.foot(foot.other());
                    assert!(stance.in_contact);
                    assert!(
                        !rectangles_overlap(
                            &corners(&s.foot(foot).pose, cfg),
                            &corners(&stance.pose, cfg)
                        ),
                        "swing foot passes over the stance sole at {t}"
                    );
                }
            }
        }
    }
}

/// The independent checks above, then the library's run-time verification, which must accept every plan
/// they accept (and report the touch-downs it checked).
pub fn check_all(cfg: &PlannerConfig, plan: &Plan, fresh: bool) {
    check_steps(cfg, plan, fresh);
    check_dynamics(cfg, plan, 0.01);
    check_swings(cfg, plan);
    let report = plan.verify(cfg, 0.01).unwrap_or_else(|e| {
        panic!("Plan::verify rejects a plan the independent checks accept: {e}")
    });
    assert_eq!(report.touch_downs, plan.step_count());
    assert!(report.min_zmp_margin >= -1e-9 && report.final_dcm_error <= 1e-3);
}
