//! The payoff of issue 19, end to end: a plant 10 % heavier than the URDF with the chest's CoM 2 cm forward
//! (`[sim.model]`); two short identification runs on it (on a pole, `configs/identify_legs.toml`, and
//! standing on the feet, `configs/identify_standing.toml`, whose feet sensors give the base rows of the
//! submodel above them, Traversaro 2017 eq. 7.1 and Theorem 7.1); then `configs/walk_straight.toml` on the
//! same plant with the controllers' URDF set to the prior, the identified and the plant's: the identified
//! one tracks the plant's DCM (its true state with its own model, the summary's `DCM plant`) better than
//! the prior and within 10 % of the plant's (means over three sensor seeds, on the default hard floor;
//! docs/identification.md, "Payoff"). In torque control (`configs/walk_straight_torque.toml`, TSID: the
//! whole mass matrix) the rotational inertias matter: the identification pulled towards the prior's
//! inertias (`IdentifyOptions::inertia_prior_weight`) tracks the DCM within 10 % of the plant's and the
//! CoM far better than the prior; with the inertias weighted like the masses the identified URDF falls or
//! tracks the DCM worse.

mod common;

use std::path::{Path, PathBuf};

use common::{root, run_to_the_end, Scratch};
use stride_runner::config::Scenario;
use stride_runner::identify::{identified_urdf, identify_logs, IdentifyOptions};
use stride_runner::run::{run_scenario, Outcome};
use stride_runner::summary::PlantTracking;

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

/// Mean tracking errors (m) of a set of walks: the plant's DCM and CoM (its true state with its own model:
/// the summary's `DCM plant` and `CoM plant`, or `DCM` and `CoM` when the controllers' URDF is the plant's) and the same with the controllers' model (`DCM`, `CoM`: what
/// the controllers regulate).
#[derive(Clone, Copy, Debug)]
struct Rms {
    dcm: f64,
    com: f64,
    controllers_dcm: f64,
    controllers_com: f64,
}

/// Mean [`Rms`] of `configs/{config}` on the mismatched plant (the bundled URDF edited) with the
/// controllers' URDF `urdf`, over sensor seeds `seeds`; every walk reaches the goal.
fn walk_rms(
    s: &Scratch,
    config: &str,
    urdf: &Path,
    name: &str,
    seeds: std::ops::Range<u64>,
) -> Rms {
    let n = (seeds.end - seeds.start) as f64;
    let mut sum = [0.0; 4];
    for seed in seeds {
        let summary = walk(s, config, urdf, &format!("{name}_{seed}"), seed);
        assert_eq!(
            summary.outcome,
            Outcome::GoalReached,
            "{name} seed {seed}: {}",
            summary.render()
        );
        // Without the rows the controllers' model is the plant's (the plant's URDF): the rows are its own.
        let plant = summary.plant_tracking.unwrap_or(PlantTracking {
            dcm_error: summary.dcm_error,
            com_error: summary.com_error,
        });
        let figures = [
            plant.dcm_error.rms,
            plant.com_error.rms,
            summary.dcm_error.rms,
            summary.com_error.rms,
        ];
        for (total, x) in sum.iter_mut().zip(figures) {
            *total += x / n;
        }
    }
    let [dcm, com, controllers_dcm, controllers_com] = sum;
    Rms {
        dcm,
        com,
        controllers_dcm,
        controllers_com,
    }
}

/// One walk of `configs/{config}` on the mismatched plant with the controllers' URDF `urdf`.
fn walk(
    s: &Scratch,
    config: &str,
    urdf: &Path,
    name: &str,
    seed: u64,
) -> stride_runner::summary::RunSummary {
    walk_with(s, config, urdf, name, seed, "")
}

/// [`walk`] with `extra` TOML appended.
fn walk_with(
    s: &Scratch,
    config: &str,
    urdf: &Path,
    name: &str,
    seed: u64,
    extra: &str,
) -> stride_runner::summary::RunSummary {
    let bundled = root().join("models/stride_humanoid.urdf");
    let text = format!(
        "include = [{:?}]\n[robot]\nurdf = {:?}\n[sim.sensors]\nseed = {seed}\n{extra}\n{}",
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
fn prior_identified_plant(s: &Scratch, config: &str, identified: &Path, plant: &Path) -> [Rms; 3] {
    let bundled = root().join("models/stride_humanoid.urdf");
    [
        (bundled.as_path(), "prior"),
        (identified, "identified"),
        (plant, "plant"),
    ]
    .map(|(urdf, name)| walk_rms(s, config, urdf, name, 0..3))
}

/// Position control on the default (hard) floor, judged on the plant's own DCM: the identified URDF tracks
/// it better than the prior and within 10 % of the plant's URDF. Seen through the controllers' model (the
/// summary's `DCM` row) the prior looks better than it is: it regulates its own CoM, which the chest's
/// 2 cm offset moves away from the plant's, so its controllers'-model DCM RMS is below its plant DCM RMS
/// (7.38 against 8.13 mm over seeds 0–5); the identified URDF's two figures agree.
#[test]
fn the_identified_urdf_walks_better_than_the_prior_and_within_ten_percent_of_the_plant() {
    let s = Scratch::new("identify_payoff");
    let (id_urdf, plant_urdf) = identified_and_plant(&s, &IdentifyOptions::default());
    let [prior, identified, plant] =
        prior_identified_plant(&s, "walk_straight.toml", &id_urdf, &plant_urdf);
    println!("prior {prior:?}\nidentified {identified:?}\nplant {plant:?}");
    assert!(
        identified.dcm < prior.dcm,
        "plant DCM RMS: identified {} vs prior {}",
        identified.dcm,
        prior.dcm
    );
    assert!(
        identified.dcm <= 1.1 * plant.dcm,
        "plant DCM RMS: identified {} vs plant {}",
        identified.dcm,
        plant.dcm
    );
    assert!(
        prior.controllers_dcm < prior.dcm,
        "the prior's own view {} vs the plant's DCM {}",
        prior.controllers_dcm,
        prior.dcm
    );
}

/// Torque control: with the rotational inertias pulled towards the prior's (the default
/// `inertia_prior_weight` 1, masses and first moments at `prior_weight` 1e-4) the identified URDF tracks
/// the plant's DCM within 10 % of the plant's URDF and closes at least 90 % of the gap between the prior's
/// plant CoM error and the plant URDF's (TSID's model is 3.3 kg light and the CoM task sags: 32.8 mm RMS
/// with the CoM task's single gain, 9.3 mm since its own vertical gains of 2026-12-07, identified 2.5,
/// plant 2.2 mm: 96 % closed; the former "at least fourfold" held only on the 32.8 mm sag); TSID tracks its own CoM within 10 %
/// of the plant URDF's (the controllers' view; the plant's CoM error is 12.6 % above the plant URDF's
/// over seeds 0–5, 2.95 against 2.62 mm: the identified CoM is a little off). The prior's plant DCM RMS is not above the identified or the plant
/// URDF's in this scenario (6.37 against 6.47 and 6.43 mm over seeds 0–5: a light TSID model tracks the
/// DCM a little better, docs/identification.md, "Payoff"), so "better than the prior" is asserted on the
/// CoM. With the inertias weighted like the masses (poorly excited inertias on the bound `L = 0`) the
/// identified URDF falls or tracks the DCM more than 10 % worse than the plant. With the controllers on
/// the plant's exact state (`estimation.kind = "ground_truth"`) the identified URDF tracks the plant's
/// DCM better than the prior (4.5 against 4.9 mm) and like the plant's (4.5 mm).
#[test]
fn in_torque_control_the_identified_urdf_walks_like_the_plant() {
    let s = Scratch::new("identify_payoff_torque");
    let (id_urdf, plant_urdf) = identified_and_plant(&s, &IdentifyOptions::default());
    let config = "walk_straight_torque.toml";
    let [prior, identified, plant] = prior_identified_plant(&s, config, &id_urdf, &plant_urdf);
    println!("prior {prior:?}\nidentified {identified:?}\nplant {plant:?}");
    assert!(
        identified.dcm <= 1.1 * plant.dcm,
        "plant DCM RMS: identified {} vs plant {}",
        identified.dcm,
        plant.dcm
    );
    assert!(
        identified.controllers_com <= 1.1 * plant.controllers_com,
        "controllers' CoM RMS: identified {} vs plant {}",
        identified.controllers_com,
        plant.controllers_com
    );
    assert!(
        prior.com - identified.com >= 0.9 * (prior.com - plant.com),
        "plant CoM RMS: identified {} vs prior {} and plant {}",
        identified.com,
        prior.com,
        plant.com
    );

    // The controllers on the plant's exact state (the estimation layer bypassed; deterministic, one
    // walk each): the identified URDF tracks the plant's DCM better than the prior, like the plant's.
    let exact = |urdf: &Path, name: &str| {
        let summary = walk_with(
            &s,
            config,
            urdf,
            &format!("exact_{name}"),
            0,
            "[estimation]\nkind = \"ground_truth\"",
        );
        assert_eq!(
            summary.outcome,
            Outcome::GoalReached,
            "{}",
            summary.render()
        );
        summary
            .plant_tracking
            .map_or(summary.dcm_error.rms, |p| p.dcm_error.rms)
    };
    let bundled = root().join("models/stride_humanoid.urdf");
    let [prior_exact, identified_exact, plant_exact] = [
        exact(&bundled, "prior"),
        exact(&id_urdf, "identified"),
        exact(&plant_urdf, "plant"),
    ];
    println!(
        "exact state, plant DCM RMS: prior {prior_exact}, identified {identified_exact}, plant {plant_exact}"
    );
    assert!(
        identified_exact < prior_exact && identified_exact <= 1.1 * plant_exact,
        "exact state: identified {identified_exact}, prior {prior_exact}, plant {plant_exact}"
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
    let dcm = walks
        .iter()
        .map(|w| w.plant_tracking.map_or(f64::INFINITY, |p| p.dcm_error.rms))
        .sum::<f64>()
        / 3.0;
    println!(
        "inertias weighted like the masses: {} of 3 at the goal, DCM RMS {:.2} mm",
        walks
            .iter()
            .filter(|w| w.outcome == Outcome::GoalReached)
            .count(),
        1e3 * dcm
    );
    assert!(
        !all_at_goal || dcm > 1.1 * plant.dcm,
        "plant DCM RMS {dcm} vs plant URDF {}",
        plant.dcm
    );
}
