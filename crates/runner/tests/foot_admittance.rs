//! The foot admittance of position control (`[simplified.foot_admittance]`, docs/foot-admittance.md) in
//! closed loop on stride-sim: off is today's behaviour bit for bit; on a hard floor (k = 10⁹ N/m³, a
//! rubber sole on concrete) the fast walk falls without it and reaches its goal with it, and the default
//! walk stands still at its goal on a 3·10⁸ N/m³ floor only with it.
mod common;

use common::Scratch;
use stride_runner::config::Scenario;
use stride_runner::run::{run_scenario, Outcome, RunOptions, RunSummary};

/// The hard floors of docs/sim.md: stiffness k and damping b (b ∝ √k keeps the default's damping ratio),
/// the same for the tangential (stick) law.
fn floor(k: f64, b: f64) -> String {
    format!(
        "[sim.contact]\nnormal_stiffness = {k:e}\nnormal_damping = {b:e}\n\
         tangential_stiffness = {k:e}\ntangential_damping = {b:e}\n"
    )
}

const ON: &str = "[simplified.foot_admittance]\nenabled = true\n";
/// The admittance off (it is on by default in position control since 2026-12-05).
const OFF: &str = "[simplified.foot_admittance]\nenabled = false\n";

/// `configs/<scenario>.toml` with `extra` appended, run for `duration` seconds (the scenario's when `None`).
fn run(s: &Scratch, name: &str, scenario: &str, extra: &str, duration: Option<f64>) -> RunSummary {
    let base = common::root().join(format!("configs/{scenario}.toml"));
    let text = format!("include = [{:?}]\n{extra}", base.display().to_string());
    let file = s.write(&format!("{name}.toml"), &text);
    let scenario = Scenario::load(&file).unwrap();
    let options = RunOptions {
        duration,
        no_log: true,
        output: Some(s.path(&format!("{name}.mcap"))),
        ..RunOptions::default()
    };
    run_scenario(&scenario, &options).unwrap()
}

/// What two runs must share bit for bit.
fn trace(s: &RunSummary) -> impl PartialEq + std::fmt::Debug {
    (
        s.final_pose,
        s.dcm_error,
        s.zmp_error,
        s.com_error,
        s.feet_error,
        s.max_tilt_deg,
    )
}

#[test]
fn disabled_or_in_torque_control_the_admittance_changes_nothing() {
    let s = Scratch::new("foot_admittance_off");
    let off = run(&s, "off", "walk_straight", OFF, Some(4.0));
    let other_gains = format!("{OFF}torque_gain = 0.5\n");
    let disabled = run(&s, "disabled", "walk_straight", &other_gains, Some(4.0));
    assert_eq!(trace(&disabled), trace(&off));
    // the other side: enabled (the default), the same walk is not the same run
    let enabled = run(&s, "enabled", "walk_straight", "", Some(4.0));
    assert_ne!(trace(&enabled), trace(&off));
    // torque control (TSID) ignores it
    let torque = run(&s, "torque", "walk_straight_torque", OFF, Some(3.0));
    let torque_on = run(&s, "torque_on", "walk_straight_torque", ON, Some(3.0));
    assert_eq!(trace(&torque_on), trace(&torque));
}

#[test]
fn on_a_hard_floor_the_fast_walk_stands_still_at_its_goal_only_with_the_admittance() {
    let s = Scratch::new("foot_admittance_hard_fast");
    let hard = floor(1e9, 1.7e6);
    // Without it: with the chest weight 5 and every-sample estimation of the defaults before 2026-12-05 it
    // fell; with today's defaults it rocks on its soles until the duration runs out (measured ZMP 99.1 mm
    // RMS, DCM 24.3 mm).
    let without = run(&s, "without", "walk_fast", &format!("{hard}{OFF}"), None);
    assert!(
        matches!(
            without.outcome,
            Outcome::Fell { .. } | Outcome::DurationReached
        ),
        "{}",
        without.render()
    );
    assert!(without.zmp_error.rms > 0.08, "{}", without.render());
    let with = run(&s, "with", "walk_fast", &format!("{hard}{ON}"), None);
    assert_eq!(with.outcome, Outcome::GoalReached, "{}", with.render());
    // measured 22.2 / 61.1 mm RMS with the 20 Hz error filter (12.2 / 54.5 unfiltered, which rocks on
    // MuJoCo; docs/foot-admittance.md, "MuJoCo")
    assert!(with.dcm_error.rms < 0.025, "{}", with.render());
    assert!(with.zmp_error.rms < 0.07, "{}", with.render());
    // the unfiltered law (error_cutoff 0) keeps its own, tighter figures: measured 12.2 / 54.5 mm RMS
    let raw = format!("{hard}{ON}error_cutoff = 0.0\n");
    let unfiltered = run(&s, "unfiltered", "walk_fast", &raw, None);
    assert_eq!(
        unfiltered.outcome,
        Outcome::GoalReached,
        "{}",
        unfiltered.render()
    );
    assert!(unfiltered.dcm_error.rms < 0.02, "{}", unfiltered.render());
    assert!(unfiltered.zmp_error.rms < 0.07, "{}", unfiltered.render());
}

#[test]
fn on_a_stiffer_floor_the_default_walk_stands_still_at_its_goal_only_with_the_admittance() {
    let s = Scratch::new("foot_admittance_hard_straight");
    let hard = floor(3e8, 9.5e5);
    let without = run(
        &s,
        "without",
        "walk_straight",
        &format!("{hard}{OFF}"),
        None,
    );
    // it reaches the goal but rocks on its soles until the scenario's duration runs out
    assert_eq!(
        without.outcome,
        Outcome::DurationReached,
        "{}",
        without.render()
    );
    assert!(without.zmp_error.rms > 0.06, "{}", without.render());
    let with = run(&s, "with", "walk_straight", &format!("{hard}{ON}"), None);
    assert_eq!(with.outcome, Outcome::GoalReached, "{}", with.render());
    // measured 11.4 / 35.4 mm RMS with the 20 Hz error filter (10.5 / 30.0 unfiltered; 76.0 mm without)
    assert!(with.zmp_error.rms < 0.04, "{}", with.render());
    assert!(with.dcm_error.rms < 0.012, "{}", with.render());
}
