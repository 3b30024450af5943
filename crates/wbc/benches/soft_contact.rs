//! The soft-ground pieces a compliant controller tick would run per foot: the Lemma 1 wrench, its rate
//! [Romualdi 2022, eq. 8.1.7, 8.2.14] and one RLS update of the ground estimate (eq. 8.2.20–8.2.22).
//!
//! `cargo bench -p stride-wbc --bench soft_contact -- --warm-up-time 1 --measurement-time 2`

#[path = "../tests/common/soft.rs"]
mod soft;

use criterion::{criterion_group, criterion_main, Criterion};
use soft::{rigid_guess_settings, stance_sample, GROUND, SOLE};
use std::hint::black_box;
use stride_wbc::GroundEstimator;

fn soft_contact(c: &mut Criterion) {
    let state = stance_sample();
    c.bench_function("lemma_1_wrench", |b| {
        b.iter(|| SOLE.wrench(black_box(&state), black_box(&GROUND)))
    });
    c.bench_function("lemma_1_wrench_rate", |b| {
        b.iter(|| SOLE.wrench_rate(black_box(&state), black_box(&GROUND)))
    });
    let mut estimator = GroundEstimator::new(&rigid_guess_settings()).expect("estimator settings");
    let wrench = SOLE.wrench(&state, &GROUND);
    c.bench_function("ground_estimator_update", |b| {
        b.iter(|| {
            let y = SOLE.regressor(black_box(&state));
            estimator.update(&y, black_box(&wrench))
        })
    });
}

criterion_group!(benches, soft_contact);
criterion_main!(benches);
