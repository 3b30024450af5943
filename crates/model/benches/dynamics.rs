//! Criterion timings (wall clock) of the main algorithms on the bundled humanoid and, when
//! `STRIDE_ICUB_MODELS_DIR` is set, on iCubGazeboV2_7 (free flyer + 32 joints).
//!
//! Every timed call includes `set_state` (forward kinematics, velocities, world inertias), like Pinocchio's
//! algorithms include their own forward pass. States cycle through 100 random states. The comparison with
//! Pinocchio does not use this bench: `tools/bench/vs-pinocchio` times `examples/cpu_timings.rs`, which
//! reads the same fixture states as the Pinocchio side and applies the same statistic.

use std::hint::black_box;
use std::path::PathBuf;
use std::sync::Arc;

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::{DMatrix, DVector, Isometry3, Translation3, UnitQuaternion, Vector3, Vector6};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use stride_model::{ExternalWrench, FrameId, KinDyn, Model, RobotState};

fn random_states(model: &Model, count: usize) -> Vec<RobotState> {
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let n = model.dof();
    (0..count)
        .map(|_| {
            let pos = Vector3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                0.6,
            );
            let axis = Vector3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            RobotState {
                base_pose: Isometry3::from_parts(
                    Translation3::from(pos),
                    UnitQuaternion::from_scaled_axis(axis),
                ),
                joint_positions: DVector::from_fn(n, |_, _| rng.random_range(-1.0..1.0)),
                base_velocity: Vector6::from_fn(|_, _| rng.random_range(-1.0..1.0)),
                joint_velocities: DVector::from_fn(n, |_, _| rng.random_range(-1.0..1.0)),
            }
        })
        .collect()
}

fn bench_model(c: &mut Criterion, label: &str, model: Arc<Model>) {
    let nv = model.nv();
    let n = model.dof();
    let states = random_states(&model, 100);
    let mut kd = KinDyn::new(Arc::clone(&model));
    let frames: Vec<FrameId> = (0..model.frames().len())
        .map(|k| model.frame_id(&model.frames()[k].name).expect("frame"))
        .collect();
    let links: Vec<FrameId> = model
        .bodies()
        .iter()
        .map(|b| model.frame_id(&b.name).expect("body frame"))
        .collect();
    let mut jac = DMatrix::zeros(6, nv);
    let mut mass = DMatrix::zeros(nv, nv);
    let mut cmm = DMatrix::zeros(6, nv);
    let mut out = DVector::zeros(nv);
    let nu_dot = DVector::from_fn(nv, |k, _| ((k * 7919) % 13) as f64 * 0.1 - 0.6);
    let tau = DVector::from_fn(n, |k, _| ((k * 104729) % 17) as f64 * 0.5 - 4.0);
    let mut k = 0usize;
    let mut next = move || {
        k = (k + 1) % 100;
        k
    };

    let mut group = c.benchmark_group(label);
    group.bench_function("set_state (FK + velocities)", |b| {
        b.iter(|| kd.set_state(black_box(&states[next()])).unwrap())
    });
    // the joints at the same positions in every state (base pose and velocities change): each joint's
    // rotation is reused, as for encoder readings that did not change since the last tick
    let held: Vec<RobotState> = states
        .iter()
        .map(|s| RobotState {
            joint_positions: states[0].joint_positions.clone(),
            ..s.clone()
        })
        .collect();
    group.bench_function("set_state, joints held", |b| {
        b.iter(|| kd.set_state(black_box(&held[next()])).unwrap())
    });
    group.bench_function("forward kinematics, all frames", |b| {
        b.iter(|| {
            kd.set_state(&states[next()]).unwrap();
            let mut acc = 0.0;
            for &f in &frames {
                acc += kd.frame_rotation_translation(f).1.x;
            }
            black_box(acc)
        })
    });
    group.bench_function("all link Jacobians", |b| {
        b.iter(|| {
            kd.set_state(&states[next()]).unwrap();
            for &f in &links {
                kd.frame_jacobian(f, &mut jac).unwrap();
                black_box(&jac);
            }
        })
    });
    group.bench_function("joint Jacobians (one pass)", |b| {
        b.iter(|| {
            kd.set_state(&states[next()]).unwrap();
            kd.joint_jacobians(&mut jac).unwrap();
            black_box(&jac);
        })
    });
    group.bench_function("CRBA (mass matrix)", |b| {
        b.iter(|| {
            kd.set_state(&states[next()]).unwrap();
            kd.mass_matrix(&mut mass).unwrap();
            black_box(&mass);
        })
    });
    group.bench_function("RNEA (inverse dynamics)", |b| {
        b.iter(|| {
            kd.set_state(&states[next()]).unwrap();
            kd.inverse_dynamics(&nu_dot, &[], &mut out).unwrap();
            black_box(&out);
        })
    });
    group.bench_function("ABA (forward dynamics)", |b| {
        b.iter(|| {
            kd.set_state(&states[next()]).unwrap();
            kd.forward_dynamics(&tau, &[], &mut out).unwrap();
            black_box(&out);
        })
    });
    group.bench_function("CMM (centroidal momentum matrix)", |b| {
        b.iter(|| {
            kd.set_state(&states[next()]).unwrap();
            kd.centroidal_momentum_matrix(&mut cmm).unwrap();
            black_box(&cmm);
        })
    });
    // The readings of every FT sensor with a wrench on each sole (what a simulator's sensor model calls).
    let soles: Vec<ExternalWrench> = ["l_sole", "r_sole"]
        .iter()
        .filter_map(|n| model.frame_id(n))
        .map(|frame| ExternalWrench {
            frame,
            wrench: Vector6::new(5.0, -3.0, 150.0, 0.5, -1.0, 0.2),
        })
        .collect();
    let mut ft = vec![Vector6::zeros(); model.ft_sensors().len()];
    group.bench_function("FT sensor wrenches (all sensors, 2 sole wrenches)", |b| {
        b.iter(|| {
            kd.set_state(&states[next()]).unwrap();
            kd.ft_sensor_wrenches(&nu_dot, black_box(&soles), &mut ft)
                .unwrap();
            black_box(&ft);
        })
    });
    group.finish();
}

fn benches(c: &mut Criterion) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    match Model::from_urdf_file(root.join("models/stride_humanoid.urdf")) {
        Ok(model) => bench_model(c, "stride_humanoid", Arc::new(model)),
        Err(e) => eprintln!("bundled model not benchmarked: {e}"),
    }
    match std::env::var_os("STRIDE_ICUB_MODELS_DIR") {
        Some(dir) => {
            let path = PathBuf::from(dir).join("iCubGazeboV2_7").join("model.urdf");
            match Model::from_urdf_file(&path) {
                Ok(model) => bench_model(c, "iCubGazeboV2_7", Arc::new(model)),
                Err(e) => eprintln!("{} not benchmarked: {e}", path.display()),
            }
        }
        None => eprintln!("STRIDE_ICUB_MODELS_DIR not set: iCubGazeboV2_7 not benchmarked"),
    }
}

criterion_group!(dynamics, benches);
criterion_main!(dynamics);
