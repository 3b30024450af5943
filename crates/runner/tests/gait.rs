//! The summary's steady forward speed and specific energetic cost (issue 15) recomputed from the MCAP log of
//! a simulated walk logged at every plant period: touch-downs from `/sensors/feet`, the forward progress from
//! the base poses of `/sim/state`, the positive actuator work from its joint torques and velocities.
mod common;

use common::Scratch;
use stride_runner::config::Scenario;
use stride_runner::log::read_log;
use stride_runner::run::{run_scenario, Outcome, RunOptions};

const PLANT_PERIOD: f64 = 1.0 / 2000.0;

struct Sample {
    time: f64,
    base: [f64; 2],
    /// The soles' mean yaw \[rad\].
    heading: f64,
    base_velocity: [f64; 2],
    power: f64,
    contacts: [bool; 2],
}

fn mean_yaw(left: f64, right: f64) -> f64 {
    let d = (right - left + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
        - std::f64::consts::PI;
    left + 0.5 * d
}

fn samples(path: &std::path::Path) -> Vec<Sample> {
    let log = read_log(path).unwrap();
    let states: Vec<serde_json::Value> = log
        .topic("/sim/state")
        .map(|m| serde_json::from_slice(&m.data).unwrap())
        .collect();
    let feet: Vec<serde_json::Value> = log
        .topic("/sensors/feet")
        .map(|m| serde_json::from_slice(&m.data).unwrap())
        .collect();
    assert_eq!(states.len(), feet.len());
    let f = |v: &serde_json::Value| v.as_f64().unwrap();
    let list =
        |v: &serde_json::Value| -> Vec<f64> { v.as_array().unwrap().iter().map(f).collect() };
    states
        .iter()
        .zip(&feet)
        .map(|(s, ft)| {
            assert_eq!(s["time"], ft["time"]);
            let p = list(&s["base"]["position"]);
            let v = list(&s["base_velocity"]);
            let tau = list(&s["joint_torques"]);
            let qd = list(&s["joint_velocities"]);
            Sample {
                time: f(&s["time"]),
                base: [p[0], p[1]],
                heading: mean_yaw(f(&ft["left"]["yaw"]), f(&ft["right"]["yaw"])),
                base_velocity: [v[0], v[1]],
                power: tau.iter().zip(&qd).map(|(t, w)| (t * w).max(0.0)).sum(),
                contacts: [
                    ft["left"]["in_contact"].as_bool().unwrap(),
                    ft["right"]["in_contact"].as_bool().unwrap(),
                ],
            }
        })
        .collect()
}

/// Touch-downs (time, forward progress): a contact flag rising after ≥ 0.1 s off the ground; progress along
/// the soles' heading of the earlier sample (the tracker's: measured before the plant period).
fn touchdowns(samples: &[Sample]) -> Vec<(f64, f64)> {
    let mut progress = 0.0;
    let mut lifted: [Option<f64>; 2] = [None, None];
    let mut out = Vec::new();
    for w in samples.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        let h = a.heading;
        progress += (b.base[0] - a.base[0]) * h.cos() + (b.base[1] - a.base[1]) * h.sin();
        for ((before, after), lift) in a.contacts.iter().zip(b.contacts).zip(&mut lifted) {
            if *before && !after {
                *lift = Some(b.time);
            }
            if !before && after && lift.is_some_and(|t| b.time - t >= 0.1) {
                out.push((b.time, progress));
            }
        }
    }
    out
}

#[test]
fn steady_speed_and_energy_cost_agree_with_the_log() {
    let s = Scratch::new("gait");
    let walk = common::root().join("configs/walk_straight_torque.toml");
    let top = s.write(
        "walk.toml",
        &format!(
            "include = [{:?}]\n[scenario]\nname = \"gait\"\nduration = 14.0\n[log]\nstate_hz = 2000\n\
             [goal.pose]\nx = 1.0\n",
            walk.display().to_string()
        ),
    );
    let scenario = Scenario::load(&top).unwrap();
    let options = RunOptions {
        output: Some(s.path("run.mcap")),
        ..RunOptions::default()
    };
    let summary = run_scenario(&scenario, &options).unwrap();
    let text = summary.render();
    assert!(
        !matches!(
            summary.outcome,
            Outcome::Fell { .. } | Outcome::Error { .. }
        ),
        "{text}"
    );
    let g = summary.gait;
    let samples = samples(&s.path("run.mcap"));

    // Touch-downs and the steady speed.
    let td = touchdowns(&samples);
    assert_eq!(td.len(), g.touchdowns, "{text}");
    assert!(td.len() >= 7, "{text}");
    let (a, b) = (td[2], td[td.len() - 4]);
    let speed = (b.1 - a.1) / (b.0 - a.0);
    let v = g.steady_speed.expect("a steady speed");
    assert!((v - speed).abs() < 1e-9, "summary {v} m/s, log {speed} m/s");
    assert_eq!(g.steady_window, Some([a.0, b.0]));
    // Independently, the mean of the logged base velocity along +x over the window (trapezoid rule).
    let window: Vec<&Sample> = samples
        .iter()
        .filter(|x| x.time >= a.0 && x.time <= b.0)
        .collect();
    let integral: f64 = window
        .windows(2)
        .map(|w| 0.5 * (w[0].base_velocity[0] + w[1].base_velocity[0]) * (w[1].time - w[0].time))
        .sum();
    let mean_velocity = integral / (b.0 - a.0);
    assert!(
        (mean_velocity - v).abs() < 0.01 * v,
        "mean velocity {mean_velocity}, speed {v}"
    );
    assert!(v > 0.05 && v < 0.5, "{text}");

    // Positive work (the first sample is the initial state, before any plant period) and c_et.
    let work: f64 = samples[1..].iter().map(|x| x.power * PLANT_PERIOD).sum();
    let last = samples.last().unwrap().power * PLANT_PERIOD;
    assert!(
        (g.positive_work - work).abs() <= last + 1e-9,
        "summary {} J, log {work} J",
        g.positive_work
    );
    assert!(work > 0.0);
    let mass = stride_runner::run::load_model(&scenario)
        .unwrap()
        .total_mass();
    assert!((g.mass - mass).abs() < 1e-12);
    let cost = g.energy_cost.expect("an energy cost");
    assert!((cost - g.positive_work / (mass * summary.distance)).abs() < 1e-12);
    assert!(
        text.contains(&format!("steady forward speed {v:.3} m/s")),
        "{text}"
    );
    assert!(text.contains(&format!("c_et {cost:.2} J/kg/m")), "{text}");

    // The log's diagnosis message carries the same figures.
    let log = read_log(&s.path("run.mcap")).unwrap();
    let d: serde_json::Value =
        serde_json::from_slice(&log.topic("/runner/diagnosis").next().unwrap().data).unwrap();
    assert_eq!(d["steady_speed"].as_f64(), Some(v));
    assert_eq!(d["energy_cost"].as_f64(), Some(cost));
    assert_eq!(d["positive_work"].as_f64(), Some(g.positive_work));
}
