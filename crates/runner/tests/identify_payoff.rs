//! The payoff of issue 19, end to end: a plant 10 % heavier than the URDF with the chest's CoM 2 cm forward
//! (`[sim.model]`); two short identification runs on it (on a pole, `configs/identify_legs.toml`, and
//! standing on the feet, `configs/identify_standing.toml`, whose feet sensors give the base rows of the
//! submodel above them, Traversaro 2017 eq. 7.1 and Theorem 7.1); then `configs/walk_straight.toml` on the
//! same plant with the controllers' URDF set to the prior, the identified and the plant's: the identified
//! one tracks the DCM better than the prior and within 10 % of the plant's (means over three sensor seeds;
//! docs/identification.md, "Payoff").

mod common;

use std::path::Path;

use common::{root, run_to_the_end, Scratch};
use stride_runner::config::Scenario;
use stride_runner::identify::{identified_urdf, identify_logs, IdentifyOptions};
use stride_runner::run::{run_scenario, Outcome};

const MISMATCH: &str =
    "[sim.model]\nmass_scale = 1.1\n[sim.model.links.chest]\ncom_offset = [0.02, 0.0, 0.0]\n";

/// `config` (under configs/) on the mismatched plant, run for 20 s; the log's path.
fn identification_log(s: &Scratch, config: &str, name: &str) -> std::path::PathBuf {
    let text = format!(
        "include = [{:?}]\n{MISMATCH}",
        root().join("configs").join(config).display().to_string()
    );
    let scenario = Scenario::load(&s.write(&format!("{name}.toml"), &text)).unwrap();
    run_to_the_end(s, &scenario, name, 20.0)
}

/// Mean DCM RMS (m) of `configs/walk_straight.toml` on the mismatched plant (the bundled URDF edited) with
/// the controllers' URDF `urdf`, over sensor seeds 0–2; every walk reaches the goal.
fn walk_dcm_rms(s: &Scratch, urdf: &Path, name: &str) -> f64 {
    let bundled = root().join("models/stride_humanoid.urdf");
    let mut sum = 0.0;
    for seed in 0..3 {
        let text = format!(
            "include = [{:?}]\n[robot]\nurdf = {:?}\n[sim.sensors]\nseed = {seed}\n{}",
            root()
                .join("configs/walk_straight.toml")
                .display()
                .to_string(),
            urdf.display().to_string(),
            MISMATCH.replace(
                "[sim.model]\n",
                &format!("[sim.model]\nurdf = {:?}\n", bundled.display().to_string())
            )
        );
        let path = s.write(&format!("walk_{name}_{seed}.toml"), &text);
        let summary = run_scenario(&Scenario::load(&path).unwrap(), &Default::default()).unwrap();
        assert_eq!(
            summary.outcome,
            Outcome::GoalReached,
            "{}",
            summary.render()
        );
        sum += summary.dcm_error.rms;
    }
    sum / 3.0
}

#[test]
fn the_identified_urdf_walks_better_than_the_prior_and_within_ten_percent_of_the_plant() {
    let s = Scratch::new("identify_payoff");
    let legs = identification_log(&s, "identify_legs.toml", "legs");
    let standing = identification_log(&s, "identify_standing.toml", "standing");
    let report = identify_logs(&[legs, standing], &IdentifyOptions::default()).unwrap();
    assert!(report.base_rows > 0, "the standing log gives base rows");
    let truth = report.truth.clone().expect("a simulated plant");
    let mass = |psi: &nalgebra::DVector<f64>| psi.iter().step_by(10).sum::<f64>();
    let (identified_mass, plant_mass) = (mass(&report.identified), mass(&truth));
    assert!(
        (identified_mass - plant_mass).abs() < 0.01 * plant_mass,
        "identified {identified_mass} kg, plant {plant_mass} kg"
    );

    let id_urdf = s.write(
        "identified.urdf",
        &identified_urdf(&report.prior_urdf, &report.model, &report.identified).unwrap(),
    );
    let plant_urdf = s.write(
        "plant.urdf",
        &identified_urdf(&report.prior_urdf, &report.model, &truth).unwrap(),
    );
    let prior = walk_dcm_rms(&s, &root().join("models/stride_humanoid.urdf"), "prior");
    let identified = walk_dcm_rms(&s, &id_urdf, "identified");
    let plant = walk_dcm_rms(&s, &plant_urdf, "plant");
    println!(
        "DCM RMS [mm]: prior {:.2}, identified {:.2}, plant {:.2}",
        1e3 * prior,
        1e3 * identified,
        1e3 * plant
    );
    assert!(
        identified < prior,
        "identified {identified} vs prior {prior}"
    );
    assert!(
        identified <= 1.1 * plant,
        "identified {identified} vs plant {plant}"
    );
}
