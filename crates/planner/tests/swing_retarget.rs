//! Mid-swing retargeting (`SwingTrajectory::retarget`): continuity at the retarget instant, exact landing,
//! no change for the same target, freeze near touch-down, history kept, serde round trip.
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use stride_planner::{Foot, RetargetOutcome, SwingShape, SwingTrajectory};

const LIFT: f64 = 1.0;
const LAND: f64 = 1.65;

fn swing(yaw_end: f64) -> SwingTrajectory {
    let start = Isometry3::from_parts(
        Translation3::new(0.0, -0.075, 0.0),
        UnitQuaternion::identity(),
    );
    let end = Isometry3::from_parts(
        Translation3::new(0.2, -0.075, 0.0),
        UnitQuaternion::from_euler_angles(0.0, 0.0, yaw_end),
    );
    let shape = SwingShape {
        height: 0.03,
        apex_fraction: 0.5,
        landing_velocity: 0.0,
    };
    SwingTrajectory::new(Foot::Right, start, end, LIFT, LAND, shape)
}

fn assert_same_state(a: &SwingTrajectory, b: &SwingTrajectory, t: f64, what: &str) {
    let (sa, sb) = (a.evaluate(t), b.evaluate(t));
    let dp = (sa.pose.translation.vector - sb.pose.translation.vector).norm();
    let dr = sa.pose.rotation.angle_to(&sb.pose.rotation);
    let dv = (sa.twist - sb.twist).norm();
    let da = (sa.acceleration - sb.acceleration).norm();
    assert!(
        dp < 1e-12 && dr < 1e-12 && dv < 1e-12 && da < 1e-11,
        "{what} at t = {t}: position {dp:e}, rotation {dr:e}, velocity {dv:e}, acceleration {da:e}"
    );
}

/// Every retarget case: before and after the apex, earlier, unchanged and later touch-down, a turning foot.
fn cases() -> Vec<(f64, f64, f64)> {
    let mut v = Vec::new();
    for yaw in [0.0, 0.3] {
        for t in [1.1, 1.3, 1.45] {
            for land in [1.55, LAND, 1.8] {
                v.push((yaw, t, land));
            }
        }
    }
    v
}

#[test]
fn retargeting_is_continuous_and_keeps_the_past() {
    let target = Vector3::new(0.26, -0.16, 0.0);
    for (yaw, t, land) in cases() {
        let old = swing(yaw);
        let mut new = old.clone();
        assert_eq!(
            new.retarget(t, target, land, 0.05),
            RetargetOutcome::Retargeted
        );
        // position, velocity and acceleration continuous at the retarget instant
        assert_same_state(&old, &new, t, "retarget instant");
        // the past is unchanged
        for k in 0..=20 {
            let tk = LIFT + (t - LIFT) * k as f64 / 20.0;
            assert_same_state(&old, &new, tk, "before the retarget");
        }
        // continuity just after the instant: the state moves by O(dt)
        let (a, b) = (new.evaluate(t), new.evaluate(t + 1e-7));
        assert!((a.pose.translation.vector - b.pose.translation.vector).norm() < 1e-6);
        assert!((a.twist - b.twist).norm() < 1e-4);
        assert_eq!(new.land_time, land);
        assert_eq!(new.retarget_count(), 1);
    }
}

#[test]
fn retargeted_swing_lands_on_the_target_at_rest() {
    let target = Vector3::new(0.26, -0.16, 0.0);
    for (yaw, t, land) in cases() {
        let mut s = swing(yaw);
        s.retarget(t, target, land, 0.05);
        let end = s.evaluate(land);
        assert!(
            (end.pose.translation.vector - target).norm() < 1e-12,
            "{yaw} {t} {land}"
        );
        assert!(
            end.twist.norm() < 1e-10,
            "{yaw} {t} {land}: {:?}",
            end.twist
        );
        assert!(end.acceleration.norm() < 1e-9, "{:?}", end.acceleration);
        let yaw_end = UnitQuaternion::from_euler_angles(0.0, 0.0, yaw);
        assert!(end.pose.rotation.angle_to(&yaw_end) < 1e-12);
        // the height keeps its apex and stays between the ground and the apex
        for k in 0..=200 {
            let tk = LIFT + (land - LIFT) * k as f64 / 200.0;
            let z = s.evaluate(tk).pose.translation.z;
            assert!(
                z >= -1e-12 && z <= s.apex_height + 1e-12,
                "{yaw} {t} {land}: z({tk}) = {z}"
            );
        }
        if t < 1.325 {
            let apex = s.evaluate(s.apex_time);
            assert!((apex.pose.translation.z - s.apex_height).abs() < 1e-12);
            assert!(apex.twist[2].abs() < 1e-12);
        }
    }
}

#[test]
fn the_same_target_changes_nothing_and_a_late_retarget_is_frozen() {
    let old = swing(0.2);
    let mut s = old.clone();
    let end = s.end.translation.vector;
    assert_eq!(s.retarget(1.3, end, LAND, 0.05), RetargetOutcome::Unchanged);
    assert_eq!(s, old);
    let target = Vector3::new(0.3, -0.2, 0.0);
    for (t, land) in [
        (1.61, LAND),
        (1.3, 1.34),
        (LIFT, LAND),
        (LAND, 1.9),
        (f64::NAN, LAND),
    ] {
        assert_eq!(s.retarget(t, target, land, 0.05), RetargetOutcome::Frozen);
        assert_eq!(s, old);
    }
}

#[test]
fn chained_retargets_keep_each_piece_and_round_trip() {
    let old = swing(0.0);
    let mut s = old.clone();
    s.retarget(1.2, Vector3::new(0.25, -0.12, 0.0), 1.6, 0.05);
    let first = s.clone();
    s.retarget(1.4, Vector3::new(0.3, -0.2, 0.0), 1.7, 0.05);
    assert_eq!(s.retarget_count(), 2);
    assert_same_state(&old, &s, 1.15, "before both");
    assert_same_state(&first, &s, 1.3, "between the retargets");
    assert_same_state(&first, &s, 1.4, "second retarget instant");
    let end = s.evaluate(1.7);
    assert!((end.pose.translation.vector - Vector3::new(0.3, -0.2, 0.0)).norm() < 1e-12);
    let json = serde_json::to_string(&s).unwrap();
    let back: SwingTrajectory = serde_json::from_str(&json).unwrap();
    assert_eq!(back, s);
    // a planned swing serializes as before (no retarget keys)
    let plain = serde_json::to_string(&old).unwrap();
    assert!(!plain.contains("retargets") && !plain.contains("base_timing"));
}
