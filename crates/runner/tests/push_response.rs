//! The push response (`[simplified.push]`, `configs/layers/push_response.toml`) in closed loop on
//! stride-sim, torque control (`configs/walk_straight_torque.toml`): without pushes it changes nothing
//! (position control too);
//! a side push at the chest that starts at a touch-down falls without it and is walked through with it
//! (the double support is held while the momentum observer sees the push); a push beyond what the held
//! double support can take still falls (the other side of the limit, docs/push-recovery.md). Position
//! control with the step adjustment on (`configs/walk_straight_step_adjustment.toml`): the same two sides
//! of the limit on the hard default floor.
mod common;

use common::{log_options as options, Scratch};
use stride_runner::config::Scenario;
use stride_runner::run::{run_scenario, Outcome};
use stride_runner::summary::RunSummary;

const TORQUE: &[&str] = &["walk_straight_torque.toml"];
const TORQUE_RESPONSE: &[&str] = &["walk_straight_torque.toml", "layers/push_response.toml"];
const POSITION_STEPS: &[&str] = &["walk_straight_step_adjustment.toml"];
const POSITION_STEPS_RESPONSE: &[&str] = &[
    "walk_straight_step_adjustment.toml",
    "layers/push_response.toml",
];

/// The configs `layers` run for 9 s with one 1 s push `force` \[N, world x, y\] at the chest from
/// `start` \[s\].
fn pushed(s: &Scratch, name: &str, layers: &[&str], force: [f64; 2], start: f64) -> RunSummary {
    let extra = format!(
        "[scenario]\nduration = 9.0\n[[sim.pushes]]\nframe = \"chest\"\nstart = {start}\n\
         duration = 1.0\nwrench = [{}, {}, 0.0, 0.0, 0.0, 0.0]\n",
        force[0], force[1]
    );
    let sc: Scenario = common::scenario_from_configs(s, name, layers, &extra);
    run_scenario(&sc, &options(s, name)).unwrap()
}

/// Without pushes the walk `base` with `layers/push_response.toml` is the same run as `base` with the
/// estimation mode that layer sets (`estimation.update = "every_sample"`, configs/layers/push_response.toml).
fn unchanged_without_pushes(test: &str, base: &str) {
    let s = Scratch::new(test);
    let every_sample = "[estimation]\nupdate = \"every_sample\"\n";
    let reference = common::scenario_from_configs(&s, "off", &[base], every_sample);
    let off = run_scenario(&reference, &options(&s, "off")).unwrap();
    let with_response =
        common::scenario_from_configs(&s, "on", &[base, "layers/push_response.toml"], "");
    let on = run_scenario(&with_response, &options(&s, "on")).unwrap();
    assert_eq!(off.outcome, Outcome::GoalReached, "{}", off.render());
    assert_eq!(on.outcome, Outcome::GoalReached, "{}", on.render());
    // the observer's estimate of an unpushed walk stays below the hold force: the same run
    assert_eq!(on.push_holds, (0, 0.0), "{}", on.render());
    assert_eq!(on.dcm_error.rms, off.dcm_error.rms);
    assert_eq!(on.goal_distance, off.goal_distance);
}

#[test]
fn without_pushes_the_torque_walk_is_unchanged() {
    unchanged_without_pushes("push_response_nominal", "walk_straight_torque.toml");
}

#[test]
fn without_pushes_the_position_walk_with_step_adjustment_is_unchanged() {
    unchanged_without_pushes(
        "push_response_position_nominal",
        "walk_straight_step_adjustment.toml",
    );
}

#[test]
fn a_side_push_at_a_touch_down_is_walked_through_with_the_double_support_held() {
    let s = Scratch::new("push_response_side");
    // 20 N to the left for 1 s from 5.5 s (the right foot lands at 5.557 s): without the response the
    // left foot lifts at 5.90 s into the push and the torso tips (docs/push-recovery.md)
    let off = pushed(&s, "off", TORQUE, [0.0, 20.0], 5.5);
    let on = pushed(&s, "on", TORQUE_RESPONSE, [0.0, 20.0], 5.5);
    assert!(
        matches!(off.outcome, Outcome::Fell { .. }),
        "{}",
        off.render()
    );
    assert_eq!(on.outcome, Outcome::DurationReached, "{}", on.render());
    let (holds, delay) = on.push_holds;
    assert_eq!(holds, 1, "{}", on.render());
    // held about as long as the push lasts after the touch-down
    assert!(delay > 0.3 && delay < 1.5, "{}", on.render());
}

#[test]
fn a_forward_push_beyond_the_soles_still_falls_with_the_double_support_held() {
    let s = Scratch::new("push_response_front");
    // 60 N forward: F h/(m g) = 60 · 0.65 / 321.8 = 0.12 m of CoP, twice the sole's half length
    let on = pushed(&s, "on", TORQUE_RESPONSE, [60.0, 0.0], 5.5);
    assert!(
        matches!(on.outcome, Outcome::Fell { .. }),
        "{}",
        on.render()
    );
    assert!(on.push_holds.0 >= 1, "{}", on.render());
}

/// Position control with the step adjustment, on the hard default floor (docs/push-recovery.md, "Position
/// control with the push response"): 20 N to the right for 1 s from 5.5 s (the right foot lands at 5.557 s
/// and stands alone from 5.90 s, pushed outward over its sole) falls with the step adjustment alone, whose
/// left step is held at the no-crossing bound and lands early; with the push response the double support
/// is held while the push lasts and the walk goes on. 40 N the same way still falls with both (the other
/// side of the limit).
#[test]
fn position_control_a_side_push_at_a_touch_down_is_walked_through_with_the_double_support_held() {
    let s = Scratch::new("push_response_position_side");
    let off = pushed(&s, "off", POSITION_STEPS, [0.0, -20.0], 5.5);
    let on = pushed(&s, "on", POSITION_STEPS_RESPONSE, [0.0, -20.0], 5.5);
    assert!(
        matches!(off.outcome, Outcome::Fell { .. }),
        "{}",
        off.render()
    );
    assert!(off.step_adjustments.0 > 0, "{}", off.render());
    assert_eq!(on.outcome, Outcome::DurationReached, "{}", on.render());
    assert!(on.push_holds.0 >= 1, "{}", on.render());
    let strong = pushed(&s, "strong", POSITION_STEPS_RESPONSE, [0.0, -40.0], 5.5);
    assert!(
        matches!(strong.outcome, Outcome::Fell { .. }),
        "{}",
        strong.render()
    );
}
