//! The centroidal MPC (issue 13 part 2, `dcm_controller = "centroidal_mpc"`) in closed loop on
//! stride-sim with the bundled humanoid: without pushes the default walks (position and torque control)
//! reach the goal exactly as without it (no footstep moves past the dead band); with a side push it moves
//! the swing foot's touch-down outward, in the push direction, inside its box, and logs it on
//! `/planner/adjusted_footsteps`. With the push response's estimate as the MPC's external force
//! (`layers/centroidal_mpc_push_estimate.toml`, position control,
//! `configs/walk_straight_centroidal_mpc_push_response.toml`): the unpushed torque walk is the same run as
//! without the estimate, and a 40 N push forward-right from mid single support that falls without it does
//! not with it, while 45 N still falls (docs/push-recovery.md, "Part 2 on the hard floor").
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

/// `configs/walk_straight_centroidal_mpc_push_response.toml` with `push_estimate` set to `estimate`, 9 s,
/// one 1 s push of `force` \[N\] towards 315° (forward and to the right) at the chest from 5.0 s (mid single
/// support on the left foot).
fn pushed_forward_right(
    s: &Scratch,
    name: &str,
    estimate: bool,
    force: f64,
) -> stride_runner::summary::RunSummary {
    let c = force / std::f64::consts::SQRT_2;
    let extra = format!(
        "[simplified.centroidal_mpc]\npush_estimate = {estimate}\n[scenario]\nduration = 9.0\n\
         [[sim.pushes]]\nframe = \"chest\"\nstart = 5.0\nduration = 1.0\n\
         wrench = [{c}, {}, 0.0, 0.0, 0.0, 0.0]\n",
        -c
    );
    let layers = ["walk_straight_centroidal_mpc_push_response.toml"];
    let sc = common::scenario_from_configs(s, name, &layers, &extra);
    run_scenario(&sc, &options(s, name)).unwrap()
}

#[test]
fn with_the_push_estimate_a_forward_right_push_is_walked_through() {
    let s = Scratch::new("centroidal_mpc_push_estimate");
    let with = pushed_forward_right(&s, "with", true, 40.0);
    assert_eq!(with.outcome, Outcome::DurationReached, "{}", with.render());
    assert!(with.step_adjustments.0 >= 1, "{}", with.render());
    let without = pushed_forward_right(&s, "without", false, 40.0);
    assert!(
        matches!(without.outcome, Outcome::Fell { .. }),
        "{}",
        without.render()
    );
    // the other side of the limit: 45 N falls with the estimate too
    let beyond = pushed_forward_right(&s, "beyond", true, 45.0);
    assert!(
        matches!(beyond.outcome, Outcome::Fell { .. }),
        "{}",
        beyond.render()
    );
}

#[test]
fn without_pushes_the_push_estimate_changes_nothing() {
    let s = Scratch::new("centroidal_mpc_push_estimate_nominal");
    let layers = [
        "walk_straight_torque.toml",
        "layers/centroidal_mpc.toml",
        "layers/push_response.toml",
        "layers/push_hold_at_once.toml",
    ];
    let run = |name: &str, estimate: bool| {
        let extra = format!("[simplified.centroidal_mpc]\npush_estimate = {estimate}\n");
        let sc = common::scenario_from_configs(&s, name, &layers, &extra);
        run_scenario(&sc, &options(&s, name)).unwrap()
    };
    let (off, on) = (run("off", false), run("on", true));
    assert_eq!(on.outcome, Outcome::GoalReached, "{}", on.render());
    assert_eq!(on.step_adjustments, off.step_adjustments);
    assert_eq!(on.push_holds, off.push_holds);
    assert_eq!(on.dcm_error.rms, off.dcm_error.rms);
    assert_eq!(on.goal_distance, off.goal_distance);
}
