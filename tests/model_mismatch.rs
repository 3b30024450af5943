//! The plant is not the model (`[sim.model]`): the controllers keep `robot.urdf` while the simulated robot
//! is heavier, or carries its torso's mass off its nominal centre. Every limit in docs/estimation.md is
//! checked on both sides (the last mismatch that reaches the goal, the first that falls), so a change that
//! moves a limit fails here. Controllers on the estimated state with the realistic sensor defaults.

use std::path::Path;

use stride_runner::config::Scenario;
use stride_runner::run::{run_scenario, Outcome, RunOptions, RunSummary};
use stride_sim::LinkInertiaChange;

/// A plant change: every link's mass scaled, or the chest's CoM moved forward \[m\].
#[derive(Clone, Copy, Debug)]
enum Mismatch {
    MassScale(f64),
    ChestComForward(f64),
}

fn run(name: &str, mismatch: Mismatch) -> RunSummary {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("configs")
        .join(name);
    let mut scenario = Scenario::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
    let model = &mut scenario.config.sim.model;
    match mismatch {
        Mismatch::MassScale(s) => model.mass_scale = s,
        Mismatch::ChestComForward(x) => {
            model.links.insert(
                "chest".into(),
                LinkInertiaChange {
                    mass_scale: 1.0,
                    com_offset: [x, 0.0, 0.0],
                },
            );
        }
    }
    let options = RunOptions {
        no_log: true,
        ..RunOptions::default()
    };
    let summary = run_scenario(&scenario, &options).unwrap_or_else(|e| panic!("{name}: {e}"));
    eprintln!("{name} {mismatch:?}\n{}", summary.render());
    summary
}

fn assert_walks(name: &str, mismatch: Mismatch) {
    let s = run(name, mismatch);
    assert_eq!(s.outcome, Outcome::GoalReached, "{name} with {mismatch:?}");
}

fn assert_falls(name: &str, mismatch: Mismatch) {
    let s = run(name, mismatch);
    assert!(
        matches!(s.outcome, Outcome::Fell { .. }),
        "{name} with {mismatch:?} should fall; outcome {}",
        s.outcome
    );
}

#[test]
fn ten_percent_heavier_plant_walks_in_both_modes() {
    assert_walks("walk_straight.toml", Mismatch::MassScale(1.1));
    assert_walks("walk_straight_torque.toml", Mismatch::MassScale(1.1));
}

#[test]
fn position_control_mass_limit() {
    // On the hard default floor (k 3·10⁸ N/m³, since 2026-12-06). On the former 3·10⁷ floor: 1.95 / 2.0 with
    // the position-control defaults of 2026-12-06 (the simplified layer at 500 Hz, K_ZMP 2.0, the foot
    // admittance's gains), 2.1 / 2.2 before them (docs/estimation.md).
    assert_walks("walk_straight.toml", Mismatch::MassScale(2.4));
    assert_falls("walk_straight.toml", Mismatch::MassScale(2.45));
}

#[test]
fn torque_control_mass_limit() {
    // 1.2 / 1.25 before the CoM task's own vertical gains of 2026-12-07 (docs/estimation.md).
    assert_walks("walk_straight_torque.toml", Mismatch::MassScale(1.35));
    assert_falls("walk_straight_torque.toml", Mismatch::MassScale(1.4));
}

#[test]
fn position_control_torso_com_limit() {
    // On the hard default floor (k 3·10⁸ N/m³, since 2026-12-06). On the former 3·10⁷ floor: 0.26 / 0.27 m
    // with the position-control defaults of 2026-12-06, 0.25 / 0.26 m before them.
    assert_walks("walk_straight.toml", Mismatch::ChestComForward(0.28));
    assert_falls("walk_straight.toml", Mismatch::ChestComForward(0.29));
}

#[test]
fn torque_control_torso_com_limit() {
    assert_walks(
        "walk_straight_torque.toml",
        Mismatch::ChestComForward(0.125),
    );
    assert_falls("walk_straight_torque.toml", Mismatch::ChestComForward(0.15));
}
