//! Runs a few fixed simulations (both integrators, momentum projection, pushes, noise, saturation, an inclined
//! floor with sliding) and prints one FNV-1a digest of every output bit per scenario, so that a refactoring
//! can be checked to leave the simulator's outputs bit-identical:
//!
//! `cargo run --release -p stride-sim --example output_digest` (before and after; compare the lines).

use std::sync::Arc;
use std::time::Duration;

use nalgebra::DVector;
use stride_model::Model;
use stride_sim::{
    ActuationMode, IntegratorKind, PushConfig, SimConfig, SimInput, SimOutput, SimRobot,
};

/// FNV-1a over 64-bit words.
struct Digest(u64);

impl Digest {
    fn word(&mut self, w: u64) {
        for b in w.to_le_bytes() {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
    fn floats<'a>(&mut self, xs: impl IntoIterator<Item = &'a f64>) {
        for x in xs {
            self.word(x.to_bits());
        }
    }
    fn output(&mut self, o: &SimOutput) {
        self.word(o.time.as_nanos() as u64);
        let s = &o.state;
        self.floats(s.base_pose.translation.vector.iter());
        self.floats(s.base_pose.rotation.coords.iter());
        self.floats(s.base_velocity.iter());
        self.floats(s.joint_positions.iter());
        self.floats(s.joint_velocities.iter());
        self.floats(o.joint_positions.iter());
        self.floats(o.joint_velocities.iter());
        self.floats(o.joint_torques.iter());
        for b in &o.saturated {
            self.word(u64::from(*b));
        }
        for m in &o.surfaces {
            self.word(u64::from(m.in_contact));
            self.floats(m.wrench.iter());
            self.floats(m.sensor_wrench.iter());
            self.floats([m.normal_force].iter());
            self.floats(m.center_of_pressure.iter());
        }
        for p in &o.contact_points {
            self.word(p.surface as u64);
            self.floats(p.position.iter());
            self.floats(p.force.iter());
            self.floats([p.penetration].iter());
            self.word(p.mode as u64);
        }
        self.floats(o.imu.orientation.coords.iter());
        self.floats(o.imu.angular_velocity.iter());
        self.floats(o.imu.proper_acceleration.iter());
        self.floats(o.total_contact_wrench.iter());
        self.word(u64::from(o.fallen));
        self.word(o.fall_time.map_or(u64::MAX, |t| t.as_nanos() as u64));
        self.word(o.solves as u64);
    }
}

fn bent_knees(model: &Model, bend: f64) -> DVector<f64> {
    let mut q = DVector::zeros(model.dof());
    for (name, v) in [
        ("l_hip_pitch", bend),
        ("r_hip_pitch", bend),
        ("l_knee", 2.0 * bend),
        ("r_knee", 2.0 * bend),
        ("l_ankle_pitch", bend),
        ("r_ankle_pitch", bend),
    ] {
        if let Some(j) = model.joint_index(name) {
            q[j] = v;
        }
    }
    q
}

fn run(name: &str, model: &Arc<Model>, config: SimConfig, rate_hz: u64, steps: usize, lift: f64) {
    let mut digest = Digest(0xcbf2_9ce4_8422_2325);
    let q = bent_knees(model, 0.2);
    let mut sim = SimRobot::new(
        Arc::clone(model),
        config,
        Duration::from_nanos(1_000_000_000 / rate_hz),
    )
    .expect("config");
    let mut state = sim.set_standing_on_ground(&q).expect("placement");
    state.base_pose.translation.vector.z += lift;
    sim.set_initial_state(&state).expect("state");
    digest.output(sim.output());
    let mut input = SimInput::hold(&q);
    let elbow = model.joint_index("l_elbow").expect("l_elbow");
    let knee = model.joint_index("r_knee").expect("r_knee");
    let mut max_solves = 0;
    for k in 0..steps {
        let t = k as f64 * sim.period();
        input.joint_positions[elbow] = 1.5 * (7.0 * t).sin();
        input.joint_positions[knee] = q[knee] + 0.3 * (5.0 * t).sin();
        input.joint_torques[knee] = 40.0 * (3.0 * t).cos();
        match sim.step(&input) {
            Ok(out) => {
                max_solves = max_solves.max(out.solves);
                digest.output(out);
            }
            Err(e) => {
                println!("{name}: error at step {k}: {e}");
                break;
            }
        }
    }
    println!("{name}: {:016x} (max solves {max_solves})", digest.0);
}

fn main() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/stride_humanoid.urdf"
    );
    let model = Arc::new(Model::from_urdf_file(path).expect("bundled model"));
    let push = PushConfig {
        frame: "chest".into(),
        start: 0.1,
        duration: 0.2,
        wrench: [60.0, -20.0, 0.0, 0.0, 3.0, 0.0],
    };
    let mut c = SimConfig::default();
    c.pushes.push(push.clone());
    c.sensors.encoder.position_noise = 1e-4;
    run("implicit", &model, c.clone(), 2000, 2000, 0.0);
    let mut p = c.clone();
    p.momentum_projection = true;
    run("implicit+projection", &model, p, 2000, 2000, 0.01);
    let mut t = c.clone();
    t.actuation.default.mode = ActuationMode::Torque;
    t.ground.inclination = [0.05, 0.3];
    run("torque+incline", &model, t, 2000, 1000, 0.005);
    let mut e = c;
    e.integrator = IntegratorKind::Explicit;
    e.actuation.default.kp = 300.0;
    e.actuation.default.kd = 3.0;
    run("explicit", &model, e, 10_000, 5000, 0.0);
}
