//! The centroidal MPC (issue 13 part 2, `dcm_controller = "centroidal_mpc"`) in closed loop on
//! stride-sim with the bundled humanoid: without pushes the default walks (position and torque control)
//! reach the goal exactly as without it (no footstep moves past the dead band); with a side push it moves
//! the swing foot's touch-down outward, in the push direction, inside its box, and logs it on
//! `/planner/adjusted_footsteps`.
mod common;

use common::{adjusted_footsteps, log_options as options, Scratch};
use stride_runner::config::Scenario;
use stride_runner::run::{run_scenario, Outcome};

/// `configs/<base>`, with the centroidal-MPC layer when `mpc`, and `extra` appended.
fn walk(s: &Scratch, base: &str, name: &str, mpc: bool, extra: &str) -> Scenario {
    let layers: &[&str] = if mpc {
        &[base, "layers/centroidal_mpc.toml"]
    } else {
        &[base]
    };
    common::scenario_from_configs(s, name, layers, extra)
}

#[test]
fn without_pushes_the_walks_reach_the_goal_unchanged() {
    let s = Scratch::new("centroidal_mpc_nominal");
    for base in ["walk_straight.toml", "walk_straight_torque.toml"] {
        let off = run_scenario(&walk(&s, base, "off", false, ""), &options(&s, "off")).unwrap();
        let on = run_scenario(&walk(&s, base, "on", true, ""), &options(&s, "on")).unwrap();
        assert_eq!(off.outcome, Outcome::GoalReached, "{}", off.render());
        assert_eq!(on.outcome, Outcome::GoalReached, "{}", on.render());
        assert_eq!(on.step_adjustments, (0, 0), "{base}");
        assert!(adjusted_footsteps(&s.path("on.mcap")).is_empty());
        assert!(on.dcm_error.rms <= off.dcm_error.rms, "{base}");
        assert!(on.com_error.rms <= off.com_error.rms, "{base}");
        assert!(
            on.goal_distance.unwrap() <= off.goal_distance.unwrap(),
            "{base}"
        );
    }
}

#[test]
fn a_side_push_moves_the_swing_foot_outward_and_is_logged() {
    let s = Scratch::new("centroidal_mpc_push");
    // 30 N to the left (+y) for 1 s from 5.5 s, during the single support on the right foot that
    // ends at 6.54 s: the left foot swings and must land further left.
    let push = "[scenario]\nduration = 6.6\n[[sim.pushes]]\nframe = \"chest\"\nstart = 5.5\n\
                duration = 1.0\nwrench = [0.0, 30.0, 0.0, 0.0, 0.0, 0.0]\n";
    let base = "walk_straight.toml";
    run_scenario(&walk(&s, base, "push", true, push), &options(&s, "push")).unwrap();
    let steps = adjusted_footsteps(&s.path("push.mcap"));
    let left: Vec<_> = steps.iter().filter(|m| m["foot"] == "left").collect();
    assert!(!left.is_empty(), "{steps:?}");
    let box_outward = stride_simplified::CentroidalMpcConfig::default().outward;
    for m in &left {
        let dy = m["displacement"][1].as_f64().unwrap();
        assert!(dy > 0.02 && dy <= box_outward[1] + 1e-6, "{m}");
        assert_eq!(m["qp_status"], "solved", "{m}");
    }
}
