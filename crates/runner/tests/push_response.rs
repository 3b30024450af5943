//! The push response (`[simplified.push]`, `configs/layers/push_response.toml`) in closed loop on
//! stride-sim, torque control (`configs/walk_straight_torque.toml`): without pushes it changes nothing
//! (position control too);
//! a side push at the chest that starts at a touch-down falls without it and is walked through with it
//! (the double support is held while the momentum observer sees the push); a push beyond what the held
//! double support can take still falls (the other side of the limit, docs/push-recovery.md); with the
//! hold started at once (`layers/push_hold_at_once.toml`) the unpushed curve walk holds nothing and a push
//! in mid double support that falls with the delayed hold is walked through. Position
//! control with the step adjustment on (`configs/walk_straight_step_adjustment.toml`): the same two sides
//! of the limit on the hard default floor. Torque control with the TSID's CoP region ±35 mm across the sole
//! (`configs/layers/tsid_cop_y_35mm.toml`): the unpushed walk as good, a 40 N backward push in double
//! support walked through that falls with ±25 mm, a 40 N side push that still falls. With the TSID's
//! weights switched during a push (`configs/layers/tsid_push_weights.toml`): the unpushed walk never
//! switches, a 40 N backward-right push in single support that tips the torso without the switch is a
//! topple with the torso upright, later, and still a fall; a hard CoM task with the switch is a start-up
//! error. (The step adjustment's touch-down placed for the push, `configs/layers/push_step_offset.toml`,
//! walked a 40 N forward-right push through until the QP read the push estimate only above `hold_force`,
//! 2026-12-07; its grid is now the push weights' own, docs/push-recovery.md.)
mod common;

use common::{log_options as options, Scratch};
use stride_runner::config::Scenario;
use stride_runner::run::{run_scenario, Outcome};
use stride_runner::summary::RunSummary;

const TORQUE: &[&str] = &["walk_straight_torque.toml"];
const TORQUE_RESPONSE: &[&str] = &["walk_straight_torque.toml", "layers/push_response.toml"];
const TORQUE_RESPONSE_AT_ONCE: &[&str] = &[
    "walk_straight_torque.toml",
    "layers/push_response.toml",
    "layers/push_hold_at_once.toml",
];
const TORQUE_STEPS_RESPONSE: &[&str] = &["walk_straight_step_adjustment_push_response_torque.toml"];
const TORQUE_STEPS_RESPONSE_COP_35: &[&str] =
    &["walk_straight_step_adjustment_push_response_cop_y_35mm_torque.toml"];
const TORQUE_STEPS_RESPONSE_PUSH_WEIGHTS: &[&str] =
    &["walk_straight_step_adjustment_push_response_push_weights_torque.toml"];
const POSITION_STEPS: &[&str] = &["walk_straight_step_adjustment.toml"];
const POSITION_STEPS_RESPONSE: &[&str] = &[
    "walk_straight_step_adjustment.toml",
    "layers/push_response.toml",
    "layers/push_hold_at_once.toml",
];

/// The configs `layers` run for 9 s with one 1 s push `force` \[N, world x, y\] at the chest from
/// `start` \[s\].
fn pushed(s: &Scratch, name: &str, layers: &[&str], force: [f64; 2], start: f64) -> RunSummary {
    pushed_with(s, name, layers, "", force, start)
}

/// [`pushed`] with the TOML `keys` added to the scenario.
fn pushed_with(
    s: &Scratch,
    name: &str,
    layers: &[&str],
    keys: &str,
    force: [f64; 2],
    start: f64,
) -> RunSummary {
    let extra = format!(
        "{keys}[scenario]\nduration = 9.0\n[[sim.pushes]]\nframe = \"chest\"\nstart = {start}\n\
         duration = 1.0\nwrench = [{}, {}, 0.0, 0.0, 0.0, 0.0]\n",
        force[0], force[1]
    );
    let sc: Scenario = common::scenario_from_configs(s, name, layers, &extra);
    run_scenario(&sc, &options(s, name)).unwrap()
}

/// Asserts that `run` fell (its summary as the message otherwise).
fn assert_fell(run: &RunSummary) {
    assert!(
        matches!(run.outcome, Outcome::Fell { .. }),
        "{}",
        run.render()
    );
}

/// Without pushes the walk `base` with `layers/push_response.toml` is the same run as `base` with the
/// estimation mode that layer sets (`estimation.update = "every_sample"`, configs/layers/push_response.toml).
fn unchanged_without_pushes(test: &str, base: &str) {
    unchanged_without_pushes_with(test, &[base, "layers/push_response.toml"]);
}

/// [`unchanged_without_pushes`] for the configs `layers` (the walk first, then the push response's).
fn unchanged_without_pushes_with(test: &str, layers: &[&str]) {
    let s = Scratch::new(test);
    let every_sample = "[estimation]\nupdate = \"every_sample\"\n";
    let reference = common::scenario_from_configs(&s, "off", &layers[..1], every_sample);
    let off = run_scenario(&reference, &options(&s, "off")).unwrap();
    let with_response = common::scenario_from_configs(&s, "on", layers, "");
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

/// The position-control fast walk (0.36 m/s, double supports of 0.12–0.16 s) shows the observer's
/// touch-down pulses (docs/push-recovery.md, "Why `hold_delay`"): with the hold at once away from the
/// touch-downs (`layers/push_hold_at_once.toml`) and the delay kept for the estimate's rises within
/// `impact_window` of a planned touch-down, no double support is held and the run is the walk's own;
/// without that window (`impact_window = 0`: every hold starts at once) the pulses hold double supports.
#[test]
fn without_pushes_the_fast_walk_holds_no_double_support_and_would_without_the_impact_window() {
    let layers = &[
        "walk_fast.toml",
        "layers/push_response.toml",
        "layers/push_hold_at_once.toml",
    ];
    unchanged_without_pushes_with("push_response_fast_nominal", layers);
    let s = Scratch::new("push_response_fast_no_window");
    let no_window = "[simplified.push]\nimpact_window = 0.0\n";
    let sc = common::scenario_from_configs(&s, "no_window", layers, no_window);
    let run = run_scenario(&sc, &options(&s, "no_window")).unwrap();
    assert!(run.push_holds.0 >= 1, "{}", run.render());
}

/// The torque-control walk whose observer is not quiet in its start-up and stopping double supports
/// (docs/push-recovery.md, "The hold at once in torque control"): `walk_curve_fast_torque` with the
/// hold at once (`layers/push_hold_at_once.toml`) held 13 double supports there, unpushed, before those
/// two double supports waited `hold_delay` too; now it holds none and is the walk's own run.
#[test]
fn without_pushes_the_torque_curve_walk_with_the_hold_at_once_holds_no_double_support() {
    unchanged_without_pushes_with(
        "push_response_torque_curve_nominal",
        &[
            "walk_curve_fast_torque.toml",
            "layers/push_response.toml",
            "layers/push_hold_at_once.toml",
        ],
    );
}

#[test]
fn a_side_push_at_a_touch_down_is_walked_through_with_the_double_support_held() {
    let s = Scratch::new("push_response_side");
    // 20 N to the left for 1 s from 5.5 s (the right foot lands at 5.557 s): without the response the
    // left foot lifts at 5.90 s into the push and the torso tips (docs/push-recovery.md)
    let off = pushed(&s, "off", TORQUE, [0.0, 20.0], 5.5);
    let on = pushed(&s, "on", TORQUE_RESPONSE, [0.0, 20.0], 5.5);
    assert_fell(&off);
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
    assert_fell(&on);
    assert!(on.push_holds.0 >= 1, "{}", on.render());
}

/// Torque control, a push that starts in the middle of a double support (5.75 s; the right foot landed
/// at 5.557 s and lifts at 5.90 s): 40 N backward and to the left (135°) for 1 s is walked through with
/// the hold started at once (`layers/push_hold_at_once.toml`: the rise is outside the touch-down's
/// `impact_window`), and falls by torso tilt when the hold waits `hold_delay` (`hold_at_once = false`,
/// the default: the plan is 0.01 s behind when the right foot lifts). 40 N to the left from the same
/// instant still falls with it (the other side of the limit; docs/push-recovery.md, "The hold at once in
/// torque control").
#[test]
fn torque_control_a_push_in_mid_double_support_is_held_at_once_and_walked_through() {
    let s = Scratch::new("push_response_torque_mid_double_support");
    let force = [-40.0 * 0.5f64.sqrt(), 40.0 * 0.5f64.sqrt()];
    let on = pushed(&s, "on", TORQUE_RESPONSE_AT_ONCE, force, 5.75);
    assert_eq!(on.outcome, Outcome::DurationReached, "{}", on.render());
    assert!(on.push_holds.0 >= 1, "{}", on.render());
    let always_delayed = "[simplified.push]\nhold_at_once = false\n";
    let late = pushed_with(
        &s,
        "late",
        TORQUE_RESPONSE_AT_ONCE,
        always_delayed,
        force,
        5.75,
    );
    assert_fell(&late);
    let left = pushed(&s, "left", TORQUE_RESPONSE_AT_ONCE, [0.0, 40.0], 5.75);
    assert_fell(&left);
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
    assert_fell(&off);
    assert!(off.step_adjustments.0 > 0, "{}", off.render());
    assert_eq!(on.outcome, Outcome::DurationReached, "{}", on.render());
    assert!(on.push_holds.0 >= 1, "{}", on.render());
    let strong = pushed(&s, "strong", POSITION_STEPS_RESPONSE, [0.0, -40.0], 5.5);
    assert_fell(&strong);
}

/// Position control with the step adjustment and the push response, a push that starts in the middle of
/// a double support (5.75 s; the right foot landed at 5.557 s): its estimate rises outside the
/// `impact_window` of the touch-down, the hold starts at once (`layers/push_hold_at_once.toml`) and 40 N
/// backward is walked through; with `hold_delay` waited at every rise (`hold_at_once = false`, the
/// default) the hold comes too late and the walk falls. 40 N to the right from the same instant still falls (the
/// other side of the limit; docs/push-recovery.md, "The hold without delay").
#[test]
fn position_control_a_push_in_mid_double_support_is_held_at_once_and_walked_through() {
    let s = Scratch::new("push_response_position_mid_double_support");
    let on = pushed(&s, "on", POSITION_STEPS_RESPONSE, [-40.0, 0.0], 5.75);
    assert_eq!(on.outcome, Outcome::DurationReached, "{}", on.render());
    assert!(on.push_holds.0 >= 1, "{}", on.render());
    let always_delayed = "[simplified.push]\nhold_at_once = false\n";
    let late = pushed_with(
        &s,
        "late",
        POSITION_STEPS_RESPONSE,
        always_delayed,
        [-40.0, 0.0],
        5.75,
    );
    assert_fell(&late);
    let right = pushed(&s, "right", POSITION_STEPS_RESPONSE, [0.0, -40.0], 5.75);
    assert_fell(&right);
}

/// Position control with the step adjustment and the push response, 20 N to the right for 1 s from 5.0 s
/// (the right foot swinging towards the push's side): the body rolls under the push, the swinging sole
/// strikes the ground before its touch-down and the walk falls at once (5.5 s); with the early touch-down
/// (`configs/layers/early_touchdown.toml`) the strike becomes the touch-down and the walk goes on past the
/// push (the full scenario still falls at its last steps, 15.3 s: docs/push-recovery.md). 40 N to the
/// right from 5.25 s falls with it (the other side).
#[test]
fn position_control_an_early_strike_of_the_swing_foot_becomes_a_touch_down() {
    let s = Scratch::new("push_response_position_early_touchdown");
    let early = "[simplified.step_adjustment]\ntouchdown_force = 150.0\ntouchdown_lead = 0.08\n";
    let off = pushed(&s, "off", POSITION_STEPS_RESPONSE, [0.0, -20.0], 5.0);
    assert_fell(&off);
    assert_eq!(off.early_touchdowns, 0);
    let on = pushed_with(&s, "on", POSITION_STEPS_RESPONSE, early, [0.0, -20.0], 5.0);
    assert_eq!(on.outcome, Outcome::DurationReached, "{}", on.render());
    assert!(on.early_touchdowns >= 1, "{}", on.render());
    let strong = pushed_with(
        &s,
        "strong",
        POSITION_STEPS_RESPONSE,
        early,
        [0.0, -40.0],
        5.25,
    );
    assert_fell(&strong);
}

/// Torque control with the push response (hold at once) and the step adjustment
/// (`configs/walk_straight_step_adjustment_push_response_torque.toml`): 40 N backward for 1 s from
/// 5.75 s (mid double support) falls by torso tilt with the TSID's CoP region ±25 mm across the sole (the
/// default) and is walked through with ±35 mm (`configs/layers/tsid_cop_y_35mm.toml`); 40 N to the left
/// from the same instant still falls with ±35 mm (the other side of the limit; docs/push-recovery.md,
/// "40 N in eight directions in torque control and on the iCub").
#[test]
fn torque_control_a_backward_push_in_double_support_is_walked_through_with_the_wider_cop_region() {
    let s = Scratch::new("push_response_torque_cop_y_35mm");
    let backward = [-40.0, 0.0];
    let wide = pushed(&s, "wide", TORQUE_STEPS_RESPONSE_COP_35, backward, 5.75);
    assert_eq!(wide.outcome, Outcome::DurationReached, "{}", wide.render());
    let narrow = pushed(&s, "narrow", TORQUE_STEPS_RESPONSE, backward, 5.75);
    assert_fell(&narrow);
    let left = pushed(&s, "left", TORQUE_STEPS_RESPONSE_COP_35, [0.0, 40.0], 5.75);
    assert_fell(&left);
}

/// Without pushes the torque walk reaches its goal with the TSID's CoP region ±35 mm across the sole
/// (`configs/layers/tsid_cop_y_35mm.toml`) as with the default ±25 mm, its DCM error RMS within 0.5 mm
/// of the default's (6.5 mm both on main 40e7e29, docs/push-recovery.md).
#[test]
fn without_pushes_the_torque_walk_with_the_wider_cop_region_reaches_its_goal_as_well() {
    let s = Scratch::new("push_response_torque_cop_y_35mm_nominal");
    let base = common::scenario_from_configs(&s, "base", TORQUE, "");
    let base = run_scenario(&base, &options(&s, "base")).unwrap();
    let layers = ["walk_straight_torque.toml", "layers/tsid_cop_y_35mm.toml"];
    let wide = common::scenario_from_configs(&s, "wide", &layers, "");
    let wide = run_scenario(&wide, &options(&s, "wide")).unwrap();
    assert_eq!(base.outcome, Outcome::GoalReached, "{}", base.render());
    assert_eq!(wide.outcome, Outcome::GoalReached, "{}", wide.render());
    assert!(
        wide.dcm_error.rms <= base.dcm_error.rms + 5e-4,
        "{} against {}",
        wide.dcm_error.rms,
        base.dcm_error.rms
    );
}

/// 40 N backward and to the right (225°) from 5.25 s (the left foot alone, the right swinging): without
/// the push weights the torso tips within 0.45 s (fall by torso tilt, the DCM error small); with them
/// (`configs/layers/tsid_push_weights.toml`) the torso stays upright and the walk topples (DCM error)
/// more than 0.3 s later (measured 2026-12-07: 5.68 s against 6.12 s, the torso within 7.6°): the switch
/// moves the fall from the torso to the CoM but saves nothing (the limit, docs/push-recovery.md, "A step
/// during the push in torque control"). The forward push from 5.25 s showed the same until the QP read the
/// push estimate only above `hold_force` (2026-12-07); it now topples with the torso at 20°.
#[test]
fn torque_control_the_push_weights_keep_the_torso_upright_but_a_40_n_push_still_falls() {
    let s = Scratch::new("push_response_torque_push_weights");
    let f = 40.0 * std::f64::consts::FRAC_1_SQRT_2;
    let backward_right = [-f, -f];
    let tips = pushed(
        &s,
        "tips",
        TORQUE_STEPS_RESPONSE_COP_35,
        backward_right,
        5.25,
    );
    assert_fell(&tips);
    let tip = tips.diagnosis.fall.expect("a fall diagnosis");
    assert_eq!(tip.kind, "torso_lean", "{}", tips.render());
    assert_eq!(tips.push_weight_ticks, 0);
    let upright = pushed(
        &s,
        "upright",
        TORQUE_STEPS_RESPONSE_PUSH_WEIGHTS,
        backward_right,
        5.25,
    );
    assert_fell(&upright);
    let topple = upright.diagnosis.fall.expect("a fall diagnosis");
    assert!(upright.push_weight_ticks > 0, "{}", upright.render());
    assert!(topple.tilt_deg < 10.0, "{}", upright.render());
    assert!(
        topple.time > tip.time + 0.3,
        "{} against {}",
        topple.time,
        tip.time
    );
}

/// Without pushes the torque walk with the push weights (`configs/layers/tsid_push_weights.toml`, on the
/// layers of `walk_straight_step_adjustment_push_response_cop_y_35mm_torque.toml`) never switches and
/// reaches its goal, its DCM error RMS within 1 mm of the walk's without the layer; the switch on a
/// hard CoM task is a start-up error naming the task.
#[test]
fn without_pushes_the_torque_walk_with_the_push_weights_never_switches_and_reaches_its_goal() {
    let s = Scratch::new("push_response_torque_push_weights_nominal");
    let mut layers = vec![
        "walk_straight_torque.toml",
        "layers/step_adjustment.toml",
        "layers/push_response.toml",
        "layers/push_hold_at_once.toml",
        "layers/tsid_cop_y_35mm.toml",
    ];
    let base = common::scenario_from_configs(&s, "base", &layers, "");
    let base = run_scenario(&base, &options(&s, "base")).unwrap();
    layers.push("layers/tsid_push_weights.toml");
    let switched = common::scenario_from_configs(&s, "switched", &layers, "");
    let switched = run_scenario(&switched, &options(&s, "switched")).unwrap();
    assert_eq!(base.outcome, Outcome::GoalReached, "{}", base.render());
    assert_eq!(
        switched.outcome,
        Outcome::GoalReached,
        "{}",
        switched.render()
    );
    assert_eq!(switched.push_weight_ticks, 0, "{}", switched.render());
    assert!(
        switched.dcm_error.rms <= base.dcm_error.rms + 1e-3,
        "{} against {}",
        switched.dcm_error.rms,
        base.dcm_error.rms
    );
    let hard = "[simplified.push]\nwbc_com_weight = 10.0\n";
    let hard = common::scenario_from_configs(&s, "hard", &layers[..5], hard);
    let err = run_scenario(&hard, &options(&s, "hard")).unwrap_err();
    assert!(err.to_string().contains("`com`"), "{err}");
}
