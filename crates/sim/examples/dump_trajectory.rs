//! Drops the bundled humanoid (PD servos holding a knee-bent posture) on the ground and prints the trajectory
//! as JSON on stdout (used by `tools/sim/mujoco_compare.py`).
//!
//! `cargo run --release -p stride-sim --example dump_trajectory -- [DROP_HEIGHT_M] [DURATION_S] [BEND_RAD] [CONFIG.toml] [RATE_HZ]`
//! (rate 2000 Hz by default).

use std::sync::Arc;
use std::time::Duration;

use nalgebra::DVector;
use serde_json::json;
use stride_model::{KinDyn, Model};
use stride_sim::{SimConfig, SimInput, SimRobot};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let arg = |i: usize, default: f64| -> Result<f64, Box<dyn std::error::Error>> {
        Ok(match args.get(i) {
            Some(s) => s.parse()?,
            None => default,
        })
    };
    let drop = arg(1, 0.02)?;
    let duration = arg(2, 2.0)?;
    let bend = arg(3, 0.2)?;
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/stride_humanoid.urdf"
    );
    let model = Arc::new(Model::from_urdf_file(path)?);
    let mut q = DVector::zeros(model.dof());
    for (name, v) in [
        ("l_hip_pitch", bend),
        ("r_hip_pitch", bend),
        ("l_knee", 2.0 * bend),
        ("r_knee", 2.0 * bend),
        ("l_ankle_pitch", bend),
        ("r_ankle_pitch", bend),
    ] {
        q[model.joint_index(name).ok_or("missing joint")?] = v;
    }
    // Ideal sensors and actuators: the MuJoCo scene has neither friction, lag, delay nor sensor errors.
    let mut config = SimConfig {
        sensors: stride_sim::SensorConfig::ideal(),
        actuation: stride_sim::ActuationConfig::ideal(),
        ..SimConfig::default()
    };
    if let Some(path) = args.get(4) {
        // Optional TOML file with SimConfig overrides.
        config = toml::from_str(&std::fs::read_to_string(path)?)?;
    }
    let rate_hz: u64 = match args.get(5) {
        Some(s) => s.parse()?,
        None => 2000,
    };
    if rate_hz == 0 {
        return Err("the rate must be positive".into());
    }
    let period = Duration::from_nanos(1_000_000_000 / rate_hz);
    let mut sim = SimRobot::new(Arc::clone(&model), config.clone(), period)?;
    let mut state = sim.set_standing_on_ground(&q)?;
    // Lift so that the soles start `drop` above the ground (undo the static sink too).
    let sink = model.total_mass() * -model.gravity().z
        / (2.0 * config.contact.normal_stiffness * 0.20 * 0.09);
    state.base_pose.translation.vector.z += drop + sink;
    sim.set_initial_state(&state)?;
    let input = SimInput::hold(&q);
    let mut kd = KinDyn::new(Arc::clone(&model));
    let every = (0.005 / sim.period()).round() as usize;
    let steps = (duration / sim.period()).round() as usize;
    let mut samples = Vec::new();
    let names: Vec<String> = model.joints().iter().map(|j| j.name.clone()).collect();
    for k in 0..=steps {
        let out = if k == 0 {
            sim.output().clone()
        } else {
            sim.step(&input)?.clone()
        };
        if k % every != 0 {
            continue;
        }
        kd.set_state(&out.state)?;
        let p = out.state.base_pose.translation.vector;
        let r = out.state.base_pose.rotation;
        let feet: Vec<_> = out
            .surfaces
            .iter()
            .map(|s| {
                json!({"name": s.name, "normal_force": s.normal_force, "cop": [s.center_of_pressure.x, s.center_of_pressure.y, s.center_of_pressure.z],
                       "force": [s.wrench[0], s.wrench[1], s.wrench[2]]})
            })
            .collect();
        let joints: serde_json::Map<String, serde_json::Value> = names
            .iter()
            .zip(out.state.joint_positions.iter())
            .map(|(n, v)| (n.clone(), json!(v)))
            .collect();
        let com = kd.com_position();
        samples.push(json!({
            "time": out.time.as_secs_f64(),
            "base_position": [p.x, p.y, p.z],
            "base_orientation_xyzw": [r.i, r.j, r.k, r.w],
            "com_position": [com.x, com.y, com.z],
            "joint_positions": joints,
            "feet": feet,
        }));
    }
    let doc = json!({
        "simulator": "stride-sim",
        "rate_hz": rate_hz,
        "kp": config.actuation.default.kp,
        "kd": config.actuation.default.kd,
        "friction": config.contact.friction_coefficient,
        "drop_height": drop,
        "bend": bend,
        "initial_base_position": [state.base_pose.translation.vector.x, state.base_pose.translation.vector.y, state.base_pose.translation.vector.z],
        "initial_joint_positions": names.iter().zip(q.iter()).map(|(n, v)| (n.clone(), json!(v))).collect::<serde_json::Map<_, _>>(),
        "samples": samples,
    });
    println!("{}", serde_json::to_string(&doc)?);
    Ok(())
}
