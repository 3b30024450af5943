//! The soft-ground pieces a compliant controller tick would run per foot: the Lemma 1 wrench, its rate
//! [Romualdi 2022, eq. 8.1.7, 8.2.14] and one RLS update of the ground estimate (eq. 8.2.20–8.2.22).
//!
//! `cargo bench -p stride-wbc --bench soft_contact -- --warm-up-time 1 --measurement-time 2`

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::{Rotation3, Vector3};
use std::hint::black_box;
use stride_wbc::{EstimatorSettings, GroundEstimator, GroundParameters, SoleGeometry, SoleState};

fn soft_contact(c: &mut Criterion) {
    let sole = SoleGeometry {
        length: 0.2,
        width: 0.09,
    };
    let ground = GroundParameters {
        stiffness: 1e6,
        damping: 1e4,
    };
    let state = SoleState {
        position: Vector3::new(0.01, 0.0, -0.01),
        rotation: Rotation3::new(Vector3::new(0.02, -0.03, 0.1)),
        linear_velocity: Vector3::new(0.01, 0.0, -0.02),
        angular_velocity: Vector3::new(0.1, 0.2, 0.0),
        rest_position: Vector3::zeros(),
        rest_rotation: Rotation3::identity(),
    };
    c.bench_function("lemma_1_wrench", |b| {
        b.iter(|| sole.wrench(black_box(&state), black_box(&ground)))
    });
    c.bench_function("lemma_1_wrench_rate", |b| {
        b.iter(|| sole.wrench_rate(black_box(&state), black_box(&ground)))
    });
    let mut estimator = GroundEstimator::new(&EstimatorSettings {
        initial: GroundParameters {
            stiffness: 3e7,
            damping: 3e5,
        },
        initial_std: [3e7, 3e5],
        wrench_std: [2.0, 0.2],
    })
    .expect("estimator settings");
    let wrench = sole.wrench(&state, &ground);
    c.bench_function("ground_estimator_update", |b| {
        b.iter(|| {
            let y = sole.regressor(black_box(&state));
            estimator.update(&y, black_box(&wrench))
        })
    });
}

criterion_group!(benches, soft_contact);
criterion_main!(benches);
