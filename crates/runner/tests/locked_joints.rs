//! `robot.locked_joints`: the model every layer and the simulator see is reduced, a walk with locked
//! joints reaches its goal, and entries that cannot be applied are configuration errors at their line.
mod common;

use common::{scenario_from_configs, Scratch};
use stride_runner::error::RunError;
use stride_runner::run::{load_model, run_scenario, Outcome, RunOptions};

const WRISTS: &str = "[robot.locked_joints]\n\"*_wrist_*\" = 0.0\nl_shoulder_yaw = 0.1\n";

#[test]
fn locked_joints_reduce_the_model_and_the_robot_still_walks() {
    let s = Scratch::new("locked-walk");
    let sc = scenario_from_configs(&s, "walk", &["walk_straight.toml"], WRISTS);
    let model = load_model(&sc).unwrap();
    let full = stride_model::bundled::model().unwrap();
    assert_eq!(model.dof(), full.dof() - 7);
    assert!(
        model.joint_index("l_wrist_pitch").is_none()
            && model.joint_index("l_shoulder_yaw").is_none()
    );
    assert!(
        model.frame_id("l_hand").is_some(),
        "the locked links stay frames"
    );
    assert!((model.total_mass() - full.total_mass()).abs() < 1e-12);
    let options = RunOptions {
        no_log: true,
        ..RunOptions::default()
    };
    let summary = run_scenario(&sc, &options).unwrap();
    assert_eq!(
        summary.outcome,
        Outcome::GoalReached,
        "{}",
        summary.render()
    );
}

#[test]
fn lock_entries_that_cannot_be_applied_are_errors_at_their_line() {
    let s = Scratch::new("locked-errors");
    let sc = scenario_from_configs(
        &s,
        "bad",
        &["walk_straight.toml"],
        "[robot.locked_joints]\nl_elbow = 0.2\n\"*thumb*\" = 0.0\n",
    );
    let Err(RunError::Config(e)) = load_model(&sc) else {
        panic!("expected a configuration error");
    };
    let text = e.to_string();
    assert!(
        text.contains("bad.toml:4") && text.contains("robot.locked_joints.*thumb*"),
        "{text}"
    );
    assert!(text.contains("matches no movable joint"), "{text}");

    // A locked joint is no joint of the model: naming it in the posture is an error there.
    let sc = scenario_from_configs(
        &s,
        "posture",
        &["walk_straight.toml"],
        "[robot.locked_joints]\nl_elbow = 0.5\n",
    );
    let model = load_model(&sc).unwrap();
    let err = stride_runner::setup::initial_joint_positions(&sc, &model).unwrap_err();
    assert!(
        err.to_string()
            .contains("robot.initial_joint_positions.l_elbow"),
        "{err}"
    );

    // The MuJoCo plant compiles the URDF itself: no locks there.
    let err = stride_runner::config::Scenario::load(&s.write(
        "mujoco.toml",
        &format!(
            "include = [{:?}]\n[scenario]\nplant = \"mujoco\"\n{WRISTS}",
            common::root().join("configs/walk_straight.toml").display().to_string()
        ),
    ))
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("robot.locked_joints") && err.contains("MuJoCo"),
        "{err}"
    );
}
