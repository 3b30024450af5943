//! The foot admittance of position control (`[simplified.foot_admittance]`, docs/foot-admittance.md) in
//! closed loop on stride-sim: off is today's behaviour bit for bit; on a hard floor (k = 10⁹ N/m³, a
//! rubber sole on concrete) the fast walk rocks at its goal without it and stands still with it, and on a
//! 3·10⁸ N/m³ floor it brings the default walk's ZMP error from 47 to 16 mm RMS.
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
/// The fast walk these figures were measured on: 0.22 m steps every 0.5–0.8 s (`configs/walk_fast.toml`
/// until 2026-12-06, which sets no admittance gains of its own).
const FAST: &str = "layers/walk_fast_base";

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
    // fell; with the defaults since it rocks on its soles until the duration runs out (measured ZMP 99.1 mm
    // RMS, DCM 24.3 mm; 79.4 / 10.7 mm with the hard-floor defaults of 2026-12-06).
    let without = run(&s, "without", FAST, &format!("{hard}{OFF}"), None);
    assert!(
        matches!(
            without.outcome,
            Outcome::Fell { .. } | Outcome::DurationReached
        ),
        "{}",
        without.render()
    );
    assert!(without.zmp_error.rms > 0.07, "{}", without.render());
    let with = run(&s, "with", FAST, &format!("{hard}{ON}"), None);
    assert_eq!(with.outcome, Outcome::GoalReached, "{}", with.render());
    // measured 22.2 / 61.1 mm RMS with the 20 Hz error filter (12.2 / 54.5 unfiltered, which rocks on
    // MuJoCo; docs/foot-admittance.md, "MuJoCo"); 13.4 / 38.0 (13.5 / 54.9 unfiltered) with the gains and
    // the 500 Hz simplified layer of 2026-12-06
    assert!(with.dcm_error.rms < 0.025, "{}", with.render());
    assert!(with.zmp_error.rms < 0.07, "{}", with.render());
    // the unfiltered law (error_cutoff 0) keeps its own figures: measured 12.2 / 54.5 mm RMS
    let raw = format!("{hard}{ON}error_cutoff = 0.0\n");
    let unfiltered = run(&s, "unfiltered", FAST, &raw, None);
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
fn on_a_stiffer_floor_the_admittance_brings_the_default_walks_zmp_error_to_a_third() {
    let s = Scratch::new("foot_admittance_hard_straight");
    let hard = floor(3e8, 9.5e5);
    let without = run(
        &s,
        "without",
        "walk_straight",
        &format!("{hard}{OFF}"),
        None,
    );
    // With the simplified layer at 100 Hz (before 2026-12-06) it rocked on its soles until the scenario's
    // duration ran out (ZMP 76.7 mm RMS); at 500 Hz it stands still at the goal, with 47.2 mm RMS.
    assert!(without.zmp_error.rms > 0.04, "{}", without.render());
    let with = run(&s, "with", "walk_straight", &format!("{hard}{ON}"), None);
    assert_eq!(with.outcome, Outcome::GoalReached, "{}", with.render());
    // measured 15.7 / 8.0 mm RMS (ZMP / DCM) with the gains of 2026-12-06 (crates/runner/tests/hard_floor.rs)
    assert!(with.zmp_error.rms < 0.02, "{}", with.render());
    assert!(with.dcm_error.rms < 0.01, "{}", with.render());
}
