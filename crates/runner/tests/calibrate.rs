//! `stride calibrate` end to end: simulate `configs/identify_ft_legs.toml` (robot on a pole, legs swung,
//! default FT offsets, drift and noise), estimate the offsets from the log, compare with the simulator's.

mod common;

use common::{root, run_to_the_end, Scratch};
use stride_runner::calibrate::calibrate_log;
use stride_runner::config::Scenario;
use stride_testkit::ft_offset_error_bound;

#[test]
fn calibrated_offsets_match_the_simulator_and_load_as_an_overlay() {
    let s = Scratch::new("calibrate");
    let scenario = Scenario::load(&root().join("configs/identify_ft_legs.toml")).unwrap();
    let duration = 30.0;
    let log = run_to_the_end(&s, &scenario, "legs", duration);

    let report = calibrate_log(&log, None).unwrap();
    assert_eq!(report.sensors.len(), 4);
    let ft = &scenario.config.sim.sensors.ft;
    // The offset drifts during the run (a random walk): the estimate is a mean over the run, compared with
    // the simulator's mean; the bound allows for the walk's spread over the run on top of 4 σ of the
    // estimate, and for the pipeline's own error without noise or drift (stride_testkit).
    for c in &report.sensors {
        let truth = c.truth.expect("simulated");
        for i in 0..6 {
            let bound = ft_offset_error_bound(
                i,
                c.offset_std[i],
                ft.force_drift,
                ft.torque_drift,
                duration,
            );
            let err = (c.offset[i] - truth[i]).abs();
            assert!(
                err < bound,
                "{} axis {i}: error {err:.4} > {bound:.4}",
                c.name
            );
        }
        assert!(
            (c.normalised_residual - 1.0).abs() < 0.2,
            "{}: χ {}",
            c.name,
            c.normalised_residual
        );
    }

    // The overlay sets estimation.ft_offsets.initial on top of a walking scenario.
    let toml = s.write("ft_calibration.toml", &report.to_toml(&log));
    let overlay = s.write(
        "walk.toml",
        &format!(
            "include = [{:?}, {:?}]\n",
            root()
                .join("configs/walk_straight.toml")
                .display()
                .to_string(),
            toml.display().to_string()
        ),
    );
    let walk_scenario = Scenario::load(&overlay).unwrap();
    let initial = &walk_scenario.config.estimation.ft_offsets.initial;
    assert_eq!(initial.len(), 4);
    for (k, name) in report.all_sensors.iter().enumerate() {
        let c = report.sensors.iter().find(|c| &c.name == name).unwrap();
        let written: Vec<f64> = initial[k].to_vec();
        assert_eq!(written, c.offset.as_slice());
    }
}

#[test]
fn an_unknown_sensor_is_named_in_the_error() {
    let s = Scratch::new("calibrate_unknown");
    let scenario = Scenario::load(&root().join("configs/identify_ft_legs.toml")).unwrap();
    let log = run_to_the_end(&s, &scenario, "short", 0.1);
    let err = calibrate_log(&log, Some("no_such_sensor"))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("no_such_sensor") && err.contains("l_foot_ft_sensor"),
        "{err}"
    );
}

#[test]
fn a_log_of_legs_that_barely_turn_leaves_the_offset_undetermined() {
    // Joint trajectory off on a pole: the legs hang nearly still, gravity keeps about one direction in each
    // sensor frame, and the offset is hardly separable from the weight: its σ is hundreds of times that of
    // a swung run (0.03 N there).
    let s = Scratch::new("calibrate_still");
    let text = format!(
        "include = [{:?}]\n[joint_trajectory]\nenabled = false\n[sim.actuation.default]\nkp = 10000.0\n",
        root().join("configs/identify_ft_legs.toml").display().to_string()
    );
    let path = s.write("still.toml", &text);
    let scenario = Scenario::load(&path).unwrap();
    let log = run_to_the_end(&s, &scenario, "still", 1.0);
    match calibrate_log(&log, Some("l_foot_ft_sensor")) {
        Ok(r) => {
            let s = r.sensors[0].offset_std;
            assert!(
                s.max() > 1.0,
                "offset σ {s} N: the still legs determined it"
            );
        }
        Err(e) => assert!(e.to_string().contains("not determined"), "{e}"),
    }
}
