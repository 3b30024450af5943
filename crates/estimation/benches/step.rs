//! One `Estimator::step` on the bundled model: kinematics, EKF propagation and update with both feet in
//! contact (flat ground on), foot wrenches, contact detection, offsets, joint torques; and one
//! `Estimator::preintegrate` (a sample between two full ticks: input checks and the EKF's mean).
//!
//! `cargo bench -p stride-estimation --bench step -- --warm-up-time 1 --measurement-time 3`

use std::sync::Arc;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::{DVector, Isometry3, Translation3, UnitQuaternion, Vector3, Vector6};
use stride_estimation::{Estimator, EstimatorConfig, EstimatorInput, ImuReading};
use stride_model::{ExternalWrench, KinDyn, Model, RobotState};

fn bench_step(c: &mut Criterion) {
    let path = format!(
        "{}/../../models/stride_humanoid.urdf",
        env!("CARGO_MANIFEST_DIR")
    );
    let model = Arc::new(Model::from_urdf_file(path).expect("bundled model"));
    let mut state = RobotState::zero(&model);
    state.base_pose =
        Isometry3::from_parts(Translation3::new(0.0, 0.0, 0.6), UnitQuaternion::identity());
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_state(&state).expect("state");
    let soles = ["l_sole", "r_sole"].map(|s| model.frame_id(s).expect("sole"));
    let weight = model.total_mass() * 9.81;
    let external = soles.map(|frame| ExternalWrench {
        frame,
        wrench: Vector6::new(0.0, 0.0, 0.5 * weight, 0.0, 0.0, 0.0),
    });
    let mut readings = vec![Vector6::zeros(); model.ft_sensors().len()];
    kd.ft_sensor_wrenches(&DVector::zeros(model.nv()), &external, &mut readings)
        .expect("readings");
    let mut input = EstimatorInput {
        time_ns: 0,
        joint_positions: state.joint_positions.clone(),
        joint_velocities: state.joint_velocities.clone(),
        imu: ImuReading {
            orientation: UnitQuaternion::identity(),
            angular_velocity: Vector3::new(1e-3, -2e-3, 5e-4),
            proper_acceleration: Vector3::new(0.01, -0.02, 9.81),
        },
        ft_wrenches: readings,
    };
    let mut est = Estimator::new(model, &EstimatorConfig::default(), Duration::from_millis(2))
        .expect("estimator");
    est.set_initial_state(&state).expect("initial state");
    c.bench_function("estimator_step_bundled", |b| {
        b.iter(|| {
            input.time_ns += 2_000_000;
            est.step(std::hint::black_box(&input)).expect("step");
        })
    });
    c.bench_function("estimator_preintegrate_bundled", |b| {
        b.iter(|| {
            input.time_ns += 500_000;
            est.preintegrate(std::hint::black_box(&input))
                .expect("preintegrate");
        })
    });
}

criterion_group!(benches, bench_step);
criterion_main!(benches);
