//! The push response (`[simplified.push]`, `configs/layers/push_response.toml`) in closed loop on
//! stride-sim, torque control (`configs/walk_straight_torque.toml`): without pushes it changes nothing;
//! a side push at the chest that starts at a touch-down falls without it and is walked through with it
//! (the double support is held while the momentum observer sees the push); a push beyond what the held
//! double support can take still falls (the other side of the limit, docs/push-recovery.md).
mod common;

use common::{log_options as options, Scratch};
use stride_runner::config::Scenario;
use stride_runner::run::{run_scenario, Outcome};
use stride_runner::summary::RunSummary;

/// `configs/walk_straight_torque.toml` with the push response when `respond`, run for `duration` s
/// with one 1 s push `force` \[N, world x, y\] at the chest from `start` \[s\].
fn pushed(s: &Scratch, name: &str, respond: bool, force: [f64; 2], start: f64) -> RunSummary {
    let layers: &[&str] = if respond {
        &["walk_straight_torque.toml", "layers/push_response.toml"]
    } else {
        &["walk_straight_torque.toml"]
    };
    let extra = format!(
        "[scenario]\nduration = 9.0\n[[sim.pushes]]\nframe = \"chest\"\nstart = {start}\n\
         duration = 1.0\nwrench = [{}, {}, 0.0, 0.0, 0.0, 0.0]\n",
        force[0], force[1]
    );
    let sc: Scenario = common::scenario_from_configs(s, name, layers, &extra);
    run_scenario(&sc, &options(s, name)).unwrap()
}

#[test]
fn without_pushes_the_torque_walk_is_unchanged() {
    let s = Scratch::new("push_response_nominal");
    let sc = |name: &str, layers: &[&str]| common::scenario_from_configs(&s, name, layers, "");
    // the push response's layer sets `estimation.update = "every_sample"` (configs/layers/push_response.toml):
    // the reference run ticks the estimation layer the same way
    let every_sample = "[estimation]\nupdate = \"every_sample\"\n";
    let reference =
        common::scenario_from_configs(&s, "off", &["walk_straight_torque.toml"], every_sample);
    let off = run_scenario(&reference, &options(&s, "off")).unwrap();
    let on = run_scenario(
        &sc(
            "on",
            &["walk_straight_torque.toml", "layers/push_response.toml"],
        ),
        &options(&s, "on"),
    )
    .unwrap();
    assert_eq!(off.outcome, Outcome::GoalReached, "{}", off.render());
    assert_eq!(on.outcome, Outcome::GoalReached, "{}", on.render());
    // the observer's estimate of an unpushed walk stays below the hold force: the same run
    assert_eq!(on.push_holds, (0, 0.0), "{}", on.render());
    assert_eq!(on.dcm_error.rms, off.dcm_error.rms);
    assert_eq!(on.goal_distance, off.goal_distance);
}

#[test]
fn a_side_push_at_a_touch_down_is_walked_through_with_the_double_support_held() {
    let s = Scratch::new("push_response_side");
    // 20 N to the left for 1 s from 5.5 s (the right foot lands at 5.557 s): without the response the
    // left foot lifts at 5.90 s into the push and the torso tips (docs/push-recovery.md)
    let off = pushed(&s, "off", false, [0.0, 20.0], 5.5);
    let on = pushed(&s, "on", true, [0.0, 20.0], 5.5);
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
    let on = pushed(&s, "on", true, [60.0, 0.0], 5.5);
    assert!(
        matches!(on.outcome, Outcome::Fell { .. }),
        "{}",
        on.render()
    );
    assert!(on.push_holds.0 >= 1, "{}", on.render());
}
