//! One step of the bundled humanoid standing on both feet, and the real-time factor of 10 s of standing.
#![allow(clippy::field_reassign_with_default)]

use std::sync::Arc;
use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::DVector;
use stride_model::Model;
use stride_model::{KinDyn, RobotState};
use stride_sim::{IntegratorKind, SimConfig, SimInput, SimRobot, TreeCholesky};

/// CPU time of the calling thread in seconds (Linux `/proc/thread-self/stat`, 10 ms resolution), so that the
/// real-time factor can also be reported without the time the thread waits for a core on a loaded machine.
fn thread_cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/stat").ok()?;
    let rest = &s[s.rfind(')')? + 2..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

fn humanoid() -> Arc<Model> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/stride_humanoid.urdf"
    );
    Arc::new(Model::from_urdf_file(path).expect("bundled model loads"))
}

fn bent_knees(model: &Model, a: f64) -> DVector<f64> {
    let mut q = DVector::zeros(model.dof());
    for (name, v) in [
        ("l_hip_pitch", a),
        ("r_hip_pitch", a),
        ("l_knee", 2.0 * a),
        ("r_knee", 2.0 * a),
        ("l_ankle_pitch", a),
        ("r_ankle_pitch", a),
    ] {
        q[model.joint_index(name).expect("joint")] = v;
    }
    q
}

/// 2 kHz, the default rate.
const PERIOD: Duration = Duration::from_micros(500);

fn standing(config: SimConfig, period: Duration) -> (SimRobot, SimInput) {
    let model = humanoid();
    let q = bent_knees(&model, 0.2);
    let mut sim = SimRobot::new(Arc::clone(&model), config, period).expect("sim");
    sim.set_standing_on_ground(&q).expect("stand");
    let input = SimInput::hold(&q);
    // Let the contacts settle so that both feet are in contact.
    for _ in 0..1000 {
        sim.step(&input).expect("step");
    }
    (sim, input)
}

fn bench_step(c: &mut Criterion) {
    let (mut sim, input) = standing(SimConfig::default(), PERIOD);
    c.bench_function("humanoid_step_two_feet_implicit", |b| {
        b.iter(|| sim.step(&input).map(|o| o.time).expect("step"))
    });
    let mut config = SimConfig::default();
    config.integrator = IntegratorKind::Explicit;
    config.actuation.default.kp = 300.0;
    config.actuation.default.kd = 3.0;
    let (mut sim, input) = standing(config, Duration::from_micros(100));
    c.bench_function("humanoid_step_two_feet_explicit_aba", |b| {
        b.iter(|| sim.step(&input).map(|o| o.time).expect("step"))
    });
}

fn bench_real_time_factor(c: &mut Criterion) {
    let mut group = c.benchmark_group("real_time_factor");
    group.sample_size(10);
    group.bench_function("humanoid_standing_10s", |b| {
        b.iter_custom(|iters| {
            let mut total = std::time::Duration::ZERO;
            for _ in 0..iters {
                let (mut sim, input) = standing(SimConfig::default(), PERIOD);
                sim.set_standing_on_ground(&input.joint_positions)
                    .expect("stand");
                let steps = (10.0 / sim.period()).round() as usize;
                let start = Instant::now();
                let cpu_start = thread_cpu_seconds();
                for _ in 0..steps {
                    sim.step(&input).expect("step");
                }
                let elapsed = start.elapsed();
                let cpu = thread_cpu_seconds().zip(cpu_start).map(|(b, a)| b - a);
                eprintln!(
                    "10 s simulated in {:.3} s wall ({:.3} s CPU): real-time factor {:.1} wall, {:.1} CPU",
                    elapsed.as_secs_f64(),
                    cpu.unwrap_or(f64::NAN),
                    10.0 / elapsed.as_secs_f64(),
                    10.0 / cpu.unwrap_or(f64::NAN)
                );
                total += elapsed;
            }
            total
        })
    });
    group.finish();
}

/// The implicit step's kernels alone: the tree factorization and solve of the bundled humanoid's mass matrix
/// (bent knees) plus a positive diagonal, as the step assembles it.
fn bench_tree_cholesky(c: &mut Criterion) {
    let model = humanoid();
    let mut tree = TreeCholesky::floating_base(&model).expect("tree");
    let mut state = RobotState::zero(&model);
    state.joint_positions = bent_knees(&model, 0.2);
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_state(&state).expect("state");
    let mut system = tree.matrix();
    let mut entries = Vec::new();
    kd.mass_matrix_lower(|row, col, v| entries.push((tree.lower_index(row, col), v)));
    for (i, v) in entries {
        system.values_mut()[i] = v;
    }
    for k in 0..tree.len() {
        system.values_mut()[tree.diagonal_index(k)] += 0.01;
    }
    c.bench_function("tree_cholesky_factor_humanoid", |b| {
        b.iter(|| assert!(tree.factor(std::hint::black_box(&system))))
    });
    let rhs = DVector::from_fn(tree.len(), |i, _| i as f64 - 10.0);
    let mut x = rhs.clone();
    c.bench_function("tree_cholesky_solve_humanoid", |b| {
        b.iter(|| {
            x.copy_from(&rhs);
            tree.solve(std::hint::black_box(&mut x));
        })
    });
}

criterion_group!(
    benches,
    bench_step,
    bench_real_time_factor,
    bench_tree_cholesky
);
criterion_main!(benches);
