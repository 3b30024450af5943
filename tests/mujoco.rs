//! The scenarios on MuJoCo (`--features mujoco`, see docs/mujoco.md), and the error a build without MuJoCo
//! gives when asked for it.

use std::path::{Path, PathBuf};

use stride_runner::config::{PlantKind, Scenario};
#[cfg(feature = "mujoco")]
use stride_runner::run::Outcome;
use stride_runner::run::{run_scenario, RunOptions};

fn config_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("configs")
        .join(name)
}

/// A build without the `mujoco` feature rejects the MuJoCo plant with a configuration error that names
/// the command that builds it.
#[cfg(not(feature = "mujoco"))]
#[test]
fn the_mujoco_plant_without_the_feature_names_the_build_command() {
    let scenario = Scenario::load(&config_path("walk_straight.toml")).expect("scenario");
    let options = RunOptions {
        plant: Some(PlantKind::Mujoco),
        no_log: true,
        ..RunOptions::default()
    };
    let message = match run_scenario(&scenario, &options) {
        Err(e) => e.to_string(),
        Ok(s) => panic!("expected an error, the run ended with {}", s.outcome),
    };
    assert!(message.contains("scenario.plant"), "{message}");
    assert!(
        message.contains("cargo build --release --features mujoco"),
        "{message}"
    );
}

#[cfg(feature = "mujoco")]
fn run_on_mujoco(name: &str) -> stride_runner::run::RunSummary {
    let scenario = Scenario::load(&config_path(name)).expect("scenario");
    let options = RunOptions {
        plant: Some(PlantKind::Mujoco),
        no_log: true,
        ..RunOptions::default()
    };
    let summary = run_scenario(&scenario, &options).unwrap_or_else(|e| panic!("{name}: {e}"));
    eprintln!("{}", summary.render());
    summary
}

/// Torque control (TSID) on MuJoCo: the default walk's goal is reached and the robot stands still, with
/// the DCM tracked as on stride-sim (measured 9.2 mm RMS on MuJoCo, 8.2 mm on stride-sim).
#[cfg(feature = "mujoco")]
#[test]
fn the_torque_walk_reaches_its_goal_on_mujoco() {
    let s = run_on_mujoco("walk_straight_torque.toml");
    assert_eq!(s.outcome, Outcome::GoalReached, "{}", s.outcome);
    assert!(s.max_tilt_deg < 20.0 && s.min_base_height_fraction > 0.8);
    assert!(s.dcm_error.rms < 0.02, "DCM RMS {} m", s.dcm_error.rms);
}

/// Position control (QP-IK) on MuJoCo stands through `stand_push`'s 40 N × 0.2 s push at the chest (measured:
/// largest tilt 1.7°, DCM 10.2 mm RMS).
#[cfg(feature = "mujoco")]
#[test]
fn position_control_stands_through_the_push_on_mujoco() {
    let s = run_on_mujoco("stand_push.toml");
    assert_eq!(s.outcome, Outcome::DurationReached, "{}", s.outcome);
    assert!(s.max_tilt_deg < 5.0, "largest tilt {}°", s.max_tilt_deg);
    assert!(s.min_base_height_fraction > 0.95);
    assert!(s.dcm_error.rms < 0.02, "DCM RMS {} m", s.dcm_error.rms);
}

/// The default walk, position control (QP-IK), on MuJoCo: its goal is reached with the measured ZMP
/// low-passed at the default 5 Hz, and the same walk falls with the ZMP unfiltered (measured: goal at
/// 2.03 m, DCM 31 mm RMS; unfiltered, a fall at 6.7 s with the ankles saturated by the servos' damping
/// of the CoM velocity reference's jumps; docs/mujoco.md, "Position control").
#[cfg(feature = "mujoco")]
#[test]
fn the_position_walk_reaches_its_goal_on_mujoco_only_with_the_zmp_filter() {
    let s = run_on_mujoco("walk_straight.toml");
    assert_eq!(s.outcome, Outcome::GoalReached, "{}", s.outcome);
    assert!(s.max_tilt_deg < 20.0 && s.min_base_height_fraction > 0.8);
    let mut scenario = Scenario::load(&config_path("walk_straight.toml")).expect("scenario");
    scenario.config.estimation.measured_zmp_cutoff = 0.0;
    let options = RunOptions {
        plant: Some(PlantKind::Mujoco),
        no_log: true,
        ..RunOptions::default()
    };
    let unfiltered = run_scenario(&scenario, &options).expect("run");
    assert!(
        matches!(unfiltered.outcome, Outcome::Fell { .. }),
        "unfiltered: {}",
        unfiltered.outcome
    );
}
