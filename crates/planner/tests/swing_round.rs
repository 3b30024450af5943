//! `SwingTrajectory::go_round`: a swing whose straight path would sweep over the stance sole (a crossover
//! retarget, or the planned step that uncrosses crossed feet) goes in front of it or behind it, the swept
//! soles never intersecting it (checked here with an independent rectangle test at 2 000 instants),
//! continuous at the detour's start, landing where and when it did; a swing that clears the sole is left
//! as it was.
mod common;

use common::*;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use stride_planner::{Foot, RetargetOutcome, SwingShape, SwingTrajectory};

const LIFT: f64 = 1.0;
const LAND: f64 = 1.65;
const LENGTH: f64 = 0.2;
const WIDTH: f64 = 0.09;

fn pose(x: f64, y: f64, yaw: f64) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(x, y, 0.0),
        UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
    )
}

fn shape() -> SwingShape {
    SwingShape {
        height: 0.03,
        apex_fraction: 0.5,
        landing_velocity: 0.0,
    }
}

fn rectangle(h: &Isometry3<f64>) -> Vec<nalgebra::Vector2<f64>> {
    [(1.0, 1.0), (1.0, -1.0), (-1.0, -1.0), (-1.0, 1.0)]
        .iter()
        .map(|(a, b)| {
            (h * nalgebra::Point3::new(0.5 * LENGTH * a, 0.5 * WIDTH * b, 0.0))
                .coords
                .xy()
        })
        .collect()
}

/// The smallest number of the 2 000 instants from `from` to the touch-down where the soles intersect
/// (0: never), and the largest horizontal speed of the swing foot \[m/s\].
fn sweep(s: &SwingTrajectory, from: f64, stance: &Isometry3<f64>) -> (usize, f64) {
    let fixed = rectangle(stance);
    let (mut hits, mut speed) = (0, 0.0_f64);
    for i in 0..=2000 {
        let t = from + (s.land_time - from) * i as f64 / 2000.0;
        let state = s.evaluate(t);
        if rectangles_overlap(&rectangle(&state.pose), &fixed) {
            hits += 1;
        }
        speed = speed.max(state.twist.xyz().xy().norm());
    }
    (hits, speed)
}

#[test]
fn a_crossover_retarget_goes_round_the_stance_sole() {
    // right foot swinging past the left (stance) sole at (0.16, 0.075), retargeted 0.10–0.25 m past it
    let stance = pose(0.16, 0.075, 0.0);
    for (t, inward, yaw) in [
        (1.3, 0.10, 0.0),
        (1.25, 0.25, 0.0),
        (1.3, 0.15, 0.2),
        (1.2, 0.20, -0.2),
    ] {
        let mut s = SwingTrajectory::new(
            Foot::Right,
            pose(0.0, -0.075, 0.0),
            pose(0.32, -0.075, yaw),
            LIFT,
            LAND,
            shape(),
        );
        let target = Vector3::new(0.32, 0.075 + inward, 0.0);
        assert_eq!(
            s.retarget(t, target, LAND, 0.05),
            RetargetOutcome::Retargeted
        );
        let straight = s.clone();
        assert!(
            sweep(&straight, t, &stance).0 > 0,
            "the straight path crosses the sole"
        );
        assert!(s.sweeps_over(t, &stance, LENGTH, WIDTH));
        assert!(s.go_round(t, &stance, LENGTH, WIDTH));
        let (hits, speed) = sweep(&s, t, &stance);
        assert_eq!(hits, 0, "{inward} m past, yaw {yaw}: the soles intersect");
        assert!(!s.sweeps_over(t, &stance, LENGTH, WIDTH));
        // the past and the retarget's state at `t` are kept: position, velocity, acceleration continuous
        for tc in [LIFT + 0.05, t - 1e-9, t] {
            let (a, b) = (straight.evaluate(tc), s.evaluate(tc));
            assert!((a.pose.translation.vector - b.pose.translation.vector).norm() < 1e-12);
            assert!(
                (a.twist - b.twist).norm() < 1e-9
                    && (a.acceleration - b.acceleration).norm() < 1e-7
            );
        }
        // lands on the target at the same time, at the planned landing velocity, height and orientation kept
        let end = s.evaluate(LAND);
        assert!((end.pose.translation.vector - target).norm() < 1e-12);
        assert!(end.twist.norm() < 1e-9);
        for k in 0..=50 {
            let tk = t + (LAND - t) * k as f64 / 50.0;
            let (a, b) = (straight.evaluate(tk), s.evaluate(tk));
            assert_eq!(a.pose.translation.z, b.pose.translation.z);
            assert!(a.pose.rotation.angle_to(&b.pose.rotation) < 1e-12);
        }
        // a detour is not a retarget; its peak speed is 2.9–3.5 m/s here, 1.5–2.0 straight (the last
        // 0.35–0.45 s of the swing)
        assert_eq!(s.retarget_count(), 1);
        assert!(speed < 4.0, "{speed}");
    }
}

#[test]
fn a_planned_step_from_crossed_feet_goes_round_and_a_normal_step_is_kept() {
    // left foot lifting from inside the crossed right foot at (0.32, 0.175), out to 0.15 left of it
    let stance = pose(0.32, 0.175, 0.0);
    for yaw in [0.0, -0.2] {
        let mut s = SwingTrajectory::new(
            Foot::Left,
            pose(0.16, 0.075, 0.0),
            pose(0.48, 0.325, yaw),
            LIFT,
            LAND,
            shape(),
        );
        assert!(sweep(&s, LIFT, &stance).0 > 0);
        assert!(s.go_round(LIFT, &stance, LENGTH, WIDTH));
        assert_eq!(sweep(&s, LIFT, &stance).0, 0, "yaw {yaw}");
        assert_eq!(s.retarget_count(), 0);
        let lift = s.evaluate(LIFT);
        assert!(lift.twist.norm() < 1e-12 && lift.acceleration.norm() < 1e-12);
    }
    // a step of a straight walk clears the stance sole: nothing changes
    let stance = pose(0.16, 0.075, 0.0);
    let planned = SwingTrajectory::new(
        Foot::Right,
        pose(0.0, -0.075, 0.0),
        pose(0.32, -0.075, 0.0),
        LIFT,
        LAND,
        shape(),
    );
    let mut s = planned.clone();
    assert!(s.go_round(LIFT, &stance, LENGTH, WIDTH));
    assert_eq!(s, planned);
}

#[test]
fn a_swing_that_cannot_go_round_is_left_as_it_was() {
    // the target overlaps the stance sole: no path clears it
    let stance = pose(0.16, 0.075, 0.0);
    let mut s = SwingTrajectory::new(
        Foot::Right,
        pose(0.0, -0.075, 0.0),
        pose(0.16, 0.03, 0.0),
        LIFT,
        LAND,
        shape(),
    );
    let before = s.clone();
    assert!(!s.go_round(LIFT, &stance, LENGTH, WIDTH));
    assert_eq!(s, before);
}
