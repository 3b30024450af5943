//! The bundled humanoid standing on its PD servos.
#![allow(clippy::field_reassign_with_default)]

mod common;

use std::sync::Arc;

use nalgebra::Vector3;
use stride_model::KinDyn;
use stride_sim::{SimConfig, SimInput, SimRobot};

#[test]
fn humanoid_stands_for_ten_seconds_with_still_feet_and_zmp_under_the_com() {
    stand(common::ideal_config());
}

#[test]
fn humanoid_stands_with_momentum_projection() {
    let mut config = common::ideal_config();
    config.momentum_projection = true;
    stand(config);
}

fn stand(config: SimConfig) {
    let model = common::humanoid();
    let q = common::bent_knees(&model, 0.2);
    let mut sim = SimRobot::new(Arc::clone(&model), config, common::PERIOD).unwrap();
    sim.set_standing_on_ground(&q).unwrap();
    let input = SimInput::hold(&q);
    let feet_start: Vec<Vector3<f64>> = sim.contact_points().iter().map(|p| p.position).collect();
    let rate = (1.0 / sim.period()).round() as usize;
    let mut max_drift: f64 = 0.0;
    let mut solves = 0;
    for k in 0..10 * rate {
        let out = sim.step(&input).unwrap();
        solves += out.solves;
        assert!(!out.fallen, "fell at step {k}");
        for (p, p0) in out.contact_points.iter().zip(&feet_start) {
            let d = p.position - p0;
            max_drift = max_drift.max((d.x * d.x + d.y * d.y).sqrt());
        }
    }
    let out = sim.output();
    let weight = model.total_mass() * 9.81;
    let fz: f64 = out.surfaces.iter().map(|s| s.wrench[2]).sum();
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_state(&out.state).unwrap();
    let com = kd.com_position();
    // ZMP of the total contact wrench (about the world origin) on the ground z = 0.
    let w = out.total_contact_wrench;
    let zmp = Vector3::new(-w[4] / w[2], w[3] / w[2], 0.0);
    println!(
        "drift {max_drift:.3e} m, fz {fz:.4} N vs {weight:.4} N, zmp {zmp:?} com {com:?}, mean solves {}",
        solves as f64 / (10 * rate) as f64
    );
    assert!(max_drift < 1e-3, "feet drifted by {max_drift} m");
    assert!(
        (fz - weight).abs() < 1e-3 * weight,
        "vertical force {fz} N vs weight {weight} N"
    );
    assert!(
        (zmp.x - com.x).abs() < 1e-3 && (zmp.y - com.y).abs() < 1e-3,
        "zmp {zmp:?} vs com {com:?}"
    );
    // The measured wrenches in the sensor frames carry the weight upwards (the sensor frames are upright).
    let sensor_fz: f64 = out.surfaces.iter().map(|s| s.sensor_wrench[2]).sum();
    assert!(
        (sensor_fz - weight).abs() < 2e-3 * weight,
        "sensor fz {sensor_fz}"
    );
}
