//! End-to-end scenarios: the bundled humanoid under the full stack (planner → simplified layer →
//! whole-body QP → simulated robot), closed loop, exactly as `stride run configs/<scenario>.toml` runs it.
//!
//! These are the "Done when" checks of the runner issue. They run in release (the README test command) and
//! each takes a few seconds of wall-clock time.

use std::path::{Path, PathBuf};

use stride_runner::config::Scenario;
use stride_runner::run::{run_scenario, Outcome, RunOptions, RunSummary};

fn config_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("configs")
        .join(name)
}

fn run(name: &str) -> RunSummary {
    let scenario =
        Scenario::load(&config_path(name)).unwrap_or_else(|e| panic!("{name} does not load: {e}"));
    let dir = std::env::temp_dir().join(format!("stride-e2e-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let options = RunOptions {
        output: Some(dir.join(name.replace(".toml", ".mcap"))),
        ..RunOptions::default()
    };
    let summary = run_scenario(&scenario, &options).unwrap_or_else(|e| panic!("{name}: {e}"));
    eprintln!("{}", summary.render());
    summary
}

/// The fall criteria of the issue: base height above 80 % of nominal, torso tilt below 20°, no QP
/// fallbacks, and an outcome that is not a fall or an error.
fn assert_stayed_up(name: &str, s: &RunSummary) {
    assert!(
        !matches!(
            s.outcome,
            Outcome::Fell { .. } | Outcome::Error { .. } | Outcome::Interrupted
        ),
        "{name}: outcome {}",
        s.outcome
    );
    assert!(
        s.min_base_height_fraction > 0.8,
        "{name}: base height dropped to {:.1} % of nominal",
        100.0 * s.min_base_height_fraction
    );
    assert!(
        s.max_tilt_deg < 20.0,
        "{name}: torso tilted {:.1}°",
        s.max_tilt_deg
    );
    assert_eq!(s.wbc_fallbacks, 0, "{name}: whole-body QP fallbacks");
    assert_eq!(s.wbc_holds, 0, "{name}: whole-body commands held");
}

#[test]
fn default_scenario_walks_two_metres_to_its_goal() {
    let s = run("walk_straight.toml");
    assert_stayed_up("walk_straight", &s);
    let forward = s.final_pose[0];
    assert!(forward >= 2.0, "walked only {forward:.3} m forward");
    let goal_distance = s.goal_distance.expect("a pose goal has a distance");
    assert!(
        goal_distance <= 0.10,
        "ended {goal_distance:.3} m from the goal"
    );
    assert!(s.real_time_factor > 0.0);
}

#[test]
fn predictive_dcm_scenario_walks_two_metres_to_its_goal() {
    let s = run("walk_straight_mpc.toml");
    assert_stayed_up("walk_straight_mpc", &s);
    assert!(
        s.final_pose[0] >= 2.0,
        "walked only {:.3} m forward",
        s.final_pose[0]
    );
    let goal_distance = s.goal_distance.expect("a pose goal has a distance");
    assert!(
        goal_distance <= 0.10,
        "ended {goal_distance:.3} m from the goal"
    );
}

#[test]
fn curve_scenario_reaches_its_goal_pose() {
    let s = run("walk_curve.toml");
    assert_stayed_up("walk_curve", &s);
    let goal_distance = s.goal_distance.expect("a waypoint goal has a distance");
    assert!(
        goal_distance <= 0.10,
        "ended {goal_distance:.3} m from the goal"
    );
    let heading_error = s
        .goal_heading_error_deg
        .expect("the last waypoint has a heading");
    assert!(
        heading_error.abs() <= 10.0,
        "heading error {heading_error:.1}°"
    );
}

#[test]
fn torque_controlled_scenario_walks_one_metre() {
    let s = run("walk_straight_torque.toml");
    assert_stayed_up("walk_straight_torque", &s);
    assert!(
        s.final_pose[0] >= 1.0,
        "walked only {:.3} m forward",
        s.final_pose[0]
    );
}

#[test]
fn turning_in_place_ends_within_ten_degrees_of_the_goal_heading() {
    let s = run("turn_in_place.toml");
    assert_stayed_up("turn_in_place", &s);
    let heading_error = s.goal_heading_error_deg.expect("a pose goal has a heading");
    assert!(
        heading_error.abs() <= 10.0,
        "heading error {heading_error:.1}°"
    );
    assert!(
        s.final_pose[2].abs() > 80.0,
        "turned only to {:.1}°",
        s.final_pose[2]
    );
}

#[test]
fn standing_robot_survives_its_push() {
    let s = run("stand_push.toml");
    assert_stayed_up("stand_push", &s);
}
