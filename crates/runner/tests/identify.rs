//! `stride identify` end to end: simulate `configs/identify_legs.toml` (robot on a pole, every joint
//! moved) on a plant 10 % heavier than the URDF with the chest's CoM 2 cm forward (`[sim.model]`), identify
//! the inertial parameters from the log with the URDF as prior, and compare with the plant's.

mod common;

use common::{root, run_to_the_end, Scratch};
use stride_model::inertial::{check_full_consistency, InertialParameters};
use stride_model::Model;
use stride_runner::config::Scenario;
use stride_runner::identify::{identified_urdf, identify_logs, IdentifyOptions};

#[test]
fn identified_parameters_match_a_heavier_plant_and_are_physical() {
    let s = Scratch::new("identify");
    let overlay = s.write(
        "mismatch.toml",
        &format!(
            "include = [{:?}]\n[sim.model]\nmass_scale = 1.1\n[sim.model.links.chest]\ncom_offset = [0.02, 0.0, 0.0]\n",
            root().join("configs/identify_legs.toml").display().to_string()
        ),
    );
    let scenario = Scenario::load(&overlay).unwrap();
    let log = run_to_the_end(&s, &scenario, "identify", 20.0);

    let report = identify_logs(std::slice::from_ref(&log), &IdentifyOptions::default()).unwrap();
    // A robot held by its base: no base rows (the holder's wrench is not measured).
    assert_eq!(report.base_rows, 0);
    // The identifiable combinations (numerical rank, σ > 1e-2 σ_max): the URDF is ~10 % off the plant,
    // the identified parameters within 2 %.
    let prior = report.identifiable_error(&report.prior).unwrap();
    let identified = report.identifiable_error(&report.identified).unwrap();
    assert!(prior > 0.05, "prior already within {prior}");
    assert!(
        identified < 0.02,
        "identified off by {:.2} %",
        100.0 * identified
    );
    assert!(
        report.base.rank() > 150,
        "only {} combinations",
        report.base.rank()
    );
    // Every identified body is physical; the unconstrained least squares gives non-physical ones.
    for b in 0..report.identified.len() / 10 {
        let pi = InertialParameters::from_column_slice(
            &report.identified.as_slice()[10 * b..10 * b + 10],
        );
        assert!(check_full_consistency(&pi).is_ok(), "block {b}: {pi:?}");
    }
    assert!(!report.unconstrained_violations.is_empty());
    assert!(
        report.residuals[1] < 0.3 * report.residuals[0],
        "{:?}",
        report.residuals
    );

    // The written URDF loads to exactly the identified parameters.
    let text = identified_urdf(&report.prior_urdf, &report.model, &report.identified).unwrap();
    let back = Model::from_urdf_str(&text).unwrap();
    let got = back.ft_split_inertial_parameters().unwrap();
    let err = (&got - &report.identified).amax();
    assert!(err < 1e-9, "URDF round trip off by {err:e}");
    // The report is TOML with the summary and one table per body.
    let parsed: toml::Table = toml::from_str(&report.to_toml()).unwrap();
    let bodies = parsed["body"].as_array().unwrap();
    assert_eq!(bodies.len(), report.identified.len() / 10);
    assert!(
        parsed["summary"]["identifiable_error_identified"]
            .as_float()
            .unwrap()
            < 0.02
    );
}
