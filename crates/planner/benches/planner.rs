//! Planner benchmarks: planning 10 steps, a 10 m walk, replanning mid-walk, sampling one instant.

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use std::hint::black_box;
use std::time::Duration;
use stride_planner::{plan_from_standing, Goal, PlanSample, Planner, PlannerConfig};

/// Gravity magnitude \[m/s²\].
const GRAVITY: f64 = 9.81;

fn feet(width: f64) -> (Isometry3<f64>, Isometry3<f64>) {
    let s =
        |y: f64| Isometry3::from_parts(Translation3::new(0.0, y, 0.0), UnitQuaternion::identity());
    (s(0.5 * width), s(-0.5 * width))
}

fn benches(c: &mut Criterion) {
    let cfg = PlannerConfig::default();
    let (l, r) = feet(cfg.nominal_width);
    // about 10 steps: 1.2 m straight
    let ten = Goal::Pose {
        x: 1.2,
        y: 0.0,
        yaw: 0.0,
    };
    let steps = plan_from_standing(&cfg, GRAVITY, 0.0, &l, &r, &ten)
        .unwrap()
        .step_count();
    eprintln!("'plan 10 steps' plans {steps} steps");
    c.bench_function("plan_10_steps", |b| {
        b.iter(|| {
            plan_from_standing(&cfg, GRAVITY, 0.0, black_box(&l), &r, black_box(&ten)).unwrap()
        })
    });
    let walk = Goal::Pose {
        x: 10.0,
        y: 0.0,
        yaw: 0.0,
    };
    let p = plan_from_standing(&cfg, GRAVITY, 0.0, &l, &r, &walk).unwrap();
    eprintln!(
        "'plan 10 m' plans {} steps over {:.1} s",
        p.step_count(),
        p.end_time
    );
    c.bench_function("plan_10m_walk", |b| {
        b.iter(|| {
            plan_from_standing(&cfg, GRAVITY, 0.0, black_box(&l), &r, black_box(&walk)).unwrap()
        })
    });
    let mut planner = Planner::new(cfg.clone(), GRAVITY).unwrap();
    planner
        .start(
            Duration::ZERO,
            &l,
            &r,
            &Goal::Pose {
                x: 3.0,
                y: 0.0,
                yaw: 0.0,
            },
        )
        .unwrap();
    let base = planner.clone();
    let turn = Goal::Pose {
        x: 2.0,
        y: 1.0,
        yaw: 1.0,
    };
    c.bench_function("replan_mid_walk", |b| {
        b.iter_batched(
            || base.clone(),
            |mut p| p.replan(black_box(Duration::from_secs(6)), &turn).unwrap(),
            criterion::BatchSize::SmallInput,
        )
    });
    let plan = p;
    let mut out = PlanSample::default();
    let mut t = 0.0;
    c.bench_function("sample_one_instant", |b| {
        b.iter(|| {
            t = (t + 0.0137) % plan.end_time;
            plan.sample(black_box(t), &mut out);
            out.dcm_position.x
        })
    });
    // run-time verification of the 10 m plan, sampled every 10 ms (the Planner's setting)
    let samples = plan
        .verify(&cfg, 0.01)
        .expect("the 10 m plan verifies")
        .samples;
    eprintln!("'verify 10 m plan' checks {samples} samples");
    c.bench_function("verify_10m_plan", |b| {
        b.iter(|| plan.verify(black_box(&cfg), 0.01).map(|r| r.samples))
    });
    let _ = Vector3::<f64>::zeros();
}

criterion_group!(planner_benches, benches);
criterion_main!(planner_benches);
