//! The `stride plan --json` shape (the contract in docs/cli.md) and plan logging/replay through serde.

mod common;

use common::*;
use serde_json::Value;
use stride_planner::{plan_from_standing, Goal, Plan, PlannerConfig};

fn keys(v: &Value) -> Vec<String> {
    let mut k: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
    k.sort();
    k
}

#[test]
fn report_matches_the_json_contract() {
    let cfg = PlannerConfig::default();
    let (l, r) = standing(0.0, 0.0, 0.0, cfg.nominal_width);
    let plan = plan_from_standing(
        &cfg,
        GRAVITY,
        0.0,
        &l,
        &r,
        &Goal::Pose {
            x: 0.5,
            y: 0.0,
            yaw: 0.0,
        },
    )
    .unwrap();
    let report = plan.report(0.01).unwrap();
    let v: Value = serde_json::from_str(&serde_json::to_string(&report).unwrap()).unwrap();
    assert_eq!(keys(&v), ["foot_size", "footsteps", "samples"]);
    let fs = &v["footsteps"][0];
    assert_eq!(
        keys(fs),
        [
            "activation_time",
            "deactivation_time",
            "foot",
            "orientation_xyzw",
            "position"
        ]
    );
    assert!(fs["foot"] == "left" || fs["foot"] == "right");
    assert_eq!(fs["position"].as_array().unwrap().len(), 3);
    assert_eq!(fs["orientation_xyzw"].as_array().unwrap().len(), 4);
    let s = &v["samples"][0];
    assert_eq!(
        keys(s),
        [
            "com_position",
            "com_velocity",
            "dcm_position",
            "dcm_velocity",
            "left_foot",
            "omega",
            "right_foot",
            "time",
            "zmp"
        ]
    );
    assert_eq!(
        keys(&s["left_foot"]),
        [
            "angular_velocity",
            "in_contact",
            "linear_velocity",
            "orientation_xyzw",
            "position"
        ]
    );
    assert_eq!(v["foot_size"]["length"], 0.2);
    // samples every dt from start to end (inclusive)
    let n = v["samples"].as_array().unwrap().len();
    assert_eq!(
        n,
        ((plan.end_time - plan.start_time) / 0.01 + 1e-9).floor() as usize + 1
    );
    // quaternion order x, y, z, w for a 90° yaw
    let (l, r) = standing(0.0, 0.0, std::f64::consts::FRAC_PI_2, cfg.nominal_width);
    let p2 = plan_from_standing(&cfg, GRAVITY, 0.0, &l, &r, &Goal::Stand).unwrap();
    let q = p2.report(0.5).unwrap().footsteps[0].orientation_xyzw;
    let h = std::f64::consts::FRAC_1_SQRT_2;
    assert!(
        (q[0]).abs() < 1e-12
            && q[1].abs() < 1e-12
            && (q[2] - h).abs() < 1e-12
            && (q[3] - h).abs() < 1e-12
    );
    assert!(plan.report(0.0).is_err() && plan.report(f64::NAN).is_err());
}

#[test]
fn plans_round_trip_through_json_bit_identically() {
    let cfg = PlannerConfig::default();
    let (l, r) = standing(0.3, -0.2, 0.4, cfg.nominal_width);
    let plan = plan_from_standing(
        &cfg,
        GRAVITY,
        1.5,
        &l,
        &r,
        &Goal::Pose {
            x: 1.0,
            y: 0.5,
            yaw: 1.0,
        },
    )
    .unwrap();
    let text = serde_json::to_string(&plan).unwrap();
    let back: Plan = serde_json::from_str(&text).unwrap();
    assert_eq!(back, plan);
    let mut t = plan.start_time;
    while t < plan.end_time {
        assert_eq!(sample(&plan, t), sample(&back, t));
        t += 0.037;
    }
}

#[test]
fn config_round_trips_through_toml() {
    let cfg = PlannerConfig {
        dcm_interpolation: stride_planner::DcmInterpolation::DcmCubic,
        first_swing_foot: stride_planner::FirstSwingFoot::Right,
        ..PlannerConfig::default()
    };
    let text = toml::to_string(&cfg).unwrap();
    assert!(
        text.contains("dcm_interpolation = \"dcm_cubic\"")
            && text.contains("first_swing_foot = \"right\"")
    );
    let back: PlannerConfig = toml::from_str(&text).unwrap();
    assert_eq!(back, cfg);
    back.validate().unwrap();
}
