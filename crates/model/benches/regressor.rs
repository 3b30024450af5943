//! Criterion timings of the whole-robot inertial-parameter regressor against inverse dynamics (RNEA) in one
//! group, on the bundled humanoid and, when `STRIDE_ICUB_MODELS_DIR` is set, on iCubGazeboV2_7. Both calls
//! include `set_state`; the ratio regressor / RNEA is the cost of the (6 + n) × 10·N matrix over the
//! (6 + n) vector.

use std::hint::black_box;
use std::path::PathBuf;
use std::sync::Arc;

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::{DMatrix, DVector, Isometry3, Translation3, UnitQuaternion, Vector3, Vector6};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use stride_model::{KinDyn, Model, RobotState};

fn random_states(model: &Model, count: usize) -> Vec<RobotState> {
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let n = model.dof();
    (0..count)
        .map(|_| RobotState {
            base_pose: Isometry3::from_parts(
                Translation3::new(rng.random_range(-1.0..1.0), 0.0, 0.6),
                UnitQuaternion::from_scaled_axis(Vector3::from_fn(|_, _| {
                    rng.random_range(-1.0..1.0)
                })),
            ),
            joint_positions: DVector::from_fn(n, |_, _| rng.random_range(-1.0..1.0)),
            base_velocity: Vector6::from_fn(|_, _| rng.random_range(-1.0..1.0)),
            joint_velocities: DVector::from_fn(n, |_, _| rng.random_range(-1.0..1.0)),
        })
        .collect()
}

fn bench_model(c: &mut Criterion, label: &str, model: Arc<Model>) {
    let nv = model.nv();
    let states = random_states(&model, 100);
    let mut kd = KinDyn::new(Arc::clone(&model));
    let nu_dot = DVector::from_fn(nv, |k, _| ((k * 7919) % 13) as f64 * 0.1 - 0.6);
    let mut out = DVector::zeros(nv);
    let mut y = DMatrix::zeros(nv, 10 * model.body_count());
    let ns = model.ft_sensors().len();
    let mut y_ft = DMatrix::zeros(6 * ns, 10 * (model.body_count() + ns));
    let mut k = 0usize;
    let mut next = move || {
        k = (k + 1) % 100;
        k
    };
    let mut group = c.benchmark_group(format!("{label} regressor vs RNEA"));
    group.bench_function("RNEA (inverse_dynamics)", |b| {
        b.iter(|| {
            kd.set_state(&states[next()]).unwrap();
            kd.inverse_dynamics(black_box(&nu_dot), &[], &mut out)
                .unwrap();
        })
    });
    group.bench_function("inverse_dynamics_regressor", |b| {
        b.iter(|| {
            kd.set_state(&states[next()]).unwrap();
            kd.inverse_dynamics_regressor(black_box(&nu_dot), &mut y)
                .unwrap();
        })
    });
    if ns > 0 {
        group.bench_function("ft_sensor_regressor", |b| {
            b.iter(|| {
                kd.set_state(&states[next()]).unwrap();
                kd.ft_sensor_regressor(black_box(&nu_dot), &mut y_ft)
                    .unwrap();
            })
        });
    }
    group.finish();
}

fn benches(c: &mut Criterion) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let humanoid = Model::from_urdf_file(root.join("models/stride_humanoid.urdf")).unwrap();
    bench_model(c, "stride_humanoid", Arc::new(humanoid));
    if let Ok(dir) = std::env::var("STRIDE_ICUB_MODELS_DIR") {
        let path = PathBuf::from(dir).join("iCubGazeboV2_7/model.urdf");
        if let Ok(model) = Model::from_urdf_file(path) {
            bench_model(c, "iCubGazeboV2_7", Arc::new(model));
        }
    }
}

criterion_group! {
    name = regressor;
    config = Criterion::default().sample_size(30).measurement_time(std::time::Duration::from_secs(2));
    targets = benches
}
criterion_main!(regressor);
