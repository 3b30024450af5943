//! Benchmarks: DCM PI step, ZMP-CoM step, whole block tick, DCM MPC with a 2 s horizon at 100 Hz.
use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, Criterion};
use nalgebra::Vector2;
use stride_simplified::*;

const OMEGA: f64 = 4.302_325_511_579_751;

fn foot() -> SupportPolygon {
    SupportPolygon::rectangle(-0.05, 0.07, -0.03, 0.03).unwrap()
}

fn horizon(samples: usize, transfer: bool) -> DcmHorizon {
    let foot = foot();
    let both = SupportPolygon::rectangle(-0.05, 0.07, -0.03, 0.19).unwrap();
    let mut horizon = DcmHorizon::with_capacity(samples);
    let center = Vector2::new(0.01, 0.0);
    for k in 0..samples {
        let (support, zmp) = if k < 30 || !transfer {
            (foot, center)
        } else {
            let s = ((k - 30) as f64 / 20.0).min(1.0);
            (both, center + Vector2::new(0.0, 0.08 * s))
        };
        horizon
            .push(HorizonSample {
                dcm_position: zmp,
                zmp,
                support,
            })
            .unwrap();
    }
    horizon
}

fn benches(c: &mut Criterion) {
    let support = foot();
    let mut pi = DcmInstantaneousController::new(DcmInstantaneousConfig {
        ki: 0.5,
        ..Default::default()
    })
    .unwrap();
    c.bench_function("dcm_pi_step", |b| {
        b.iter(|| {
            pi.step(
                black_box(Vector2::new(0.01, 0.0)),
                black_box(Vector2::new(0.05, 0.01)),
                black_box(Vector2::new(0.012, 0.001)),
                OMEGA,
                &support,
                0.01,
            )
            .unwrap()
        })
    });
    let mut zc = ZmpComController::new(ZmpComConfig::default()).unwrap();
    c.bench_function("zmp_com_step", |b| {
        b.iter(|| {
            zc.step(
                true,
                OMEGA,
                black_box(Vector2::new(0.01, 0.0)),
                black_box(Vector2::new(0.012, 0.001)),
                black_box(Vector2::new(0.0, 0.0)),
                black_box(Vector2::new(0.1, 0.0)),
                black_box(Vector2::new(0.001, 0.0)),
                0.01,
            )
            .unwrap()
        })
    });
    let config = SimplifiedConfig::default();
    let mut block = SimplifiedController::new(&config, Duration::from_millis(10)).unwrap();
    let mut input = SimplifiedInput::new(0, support);
    input.omega = OMEGA;
    input.walking = true;
    input.measured_dcm = Vector2::new(0.003, 0.0);
    c.bench_function("block_step_instantaneous", |b| {
        b.iter(|| *block.step(black_box(&input)).unwrap())
    });

    for (name, transfer, push) in [
        ("dcm_mpc_2s_100hz_nominal", false, Vector2::new(0.003, 0.0)),
        (
            "dcm_mpc_2s_100hz_constrained",
            true,
            Vector2::new(0.05, 0.0),
        ),
    ] {
        let mut mpc = DcmPredictiveController::new(DcmPredictiveConfig::default(), 0.01).unwrap();
        let h = horizon(mpc.horizon_samples(), transfer);
        let dcm = Vector2::new(0.01, 0.0) + push;
        let out = mpc.step(OMEGA, dcm, &h, &support).unwrap();
        eprintln!(
            "{name}: status {:?}, iterations {}",
            out.diagnostics.status, out.diagnostics.iterations
        );
        c.bench_function(name, |b| {
            b.iter(|| {
                mpc.reset();
                mpc.step(OMEGA, black_box(dcm), &h, &support).unwrap()
            })
        });
    }
    for (name, solver) in [
        (
            "dcm_mpc_2s_100hz_constrained_clarabel",
            MpcSolverKind::Clarabel,
        ),
        (
            "dcm_mpc_2s_100hz_constrained_stride_qp",
            MpcSolverKind::StrideQp,
        ),
    ] {
        let mut mpc = DcmPredictiveController::new(
            DcmPredictiveConfig {
                solver,
                ..Default::default()
            },
            0.01,
        )
        .unwrap();
        let h = horizon(mpc.horizon_samples(), true);
        let dcm = Vector2::new(0.06, 0.0);
        c.bench_function(name, |b| {
            b.iter(|| {
                mpc.reset();
                mpc.step(OMEGA, black_box(dcm), &h, &support).unwrap()
            })
        });
    }
}

/// CPU time of this thread [s] from /proc (user + system, clock ticks of 10 ms): unlike wall time it
/// excludes the time the thread waits for a core on a loaded machine.
fn thread_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/thread-self/stat").ok()?;
    let after = stat.rsplit_once(')')?.1;
    let fields: Vec<&str> = after.split_whitespace().collect();
    let utime: f64 = fields.get(11)?.parse().ok()?;
    let stime: f64 = fields.get(12)?.parse().ok()?;
    Some((utime + stime) / 100.0)
}

fn cpu_time_report() {
    let support = foot();
    for (name, transfer, push) in [
        ("dcm_mpc_2s_100hz_nominal", false, Vector2::new(0.003, 0.0)),
        (
            "dcm_mpc_2s_100hz_constrained",
            true,
            Vector2::new(0.05, 0.0),
        ),
    ] {
        let mut mpc = DcmPredictiveController::new(DcmPredictiveConfig::default(), 0.01).unwrap();
        let h = horizon(mpc.horizon_samples(), transfer);
        let dcm = Vector2::new(0.01, 0.0) + push;
        let count = if transfer { 2000 } else { 20000 };
        let (Some(t0), w0) = (thread_cpu_seconds(), std::time::Instant::now()) else {
            return;
        };
        for _ in 0..count {
            mpc.reset();
            black_box(mpc.step(OMEGA, black_box(dcm), &h, &support).unwrap());
        }
        let wall = w0.elapsed().as_secs_f64() / count as f64;
        if let Some(t1) = thread_cpu_seconds() {
            eprintln!(
                "{name}: thread CPU time {:.1} µs per solve (wall {:.1} µs)",
                (t1 - t0) / count as f64 * 1e6,
                wall * 1e6
            );
        }
    }
}

/// The step-adjustment QP: the nominal case (no bound active) and a push that activates the box and the
/// timing bounds, each solved cold (a fresh solver's first solve is not measured: the solver is reused).
fn step_adjustment(c: &mut Criterion) {
    let base = StepAdjustmentInput {
        dcm: Vector2::new(0.33, 0.0912),
        omega: OMEGA,
        stance: Foot::Left,
        stance_position: Vector2::new(0.3, 0.075),
        stance_yaw: 0.0,
        stance_cop: Vector2::new(0.31, 0.075),
        nominal_step: Vector2::new(0.4, -0.075),
        nominal_offset: Vector2::new(0.0, 0.05),
        time_since_touchdown: 0.5,
        nominal_duration: 1.0,
    };
    for (name, push) in [
        ("step_adjustment_small_error", 0.005),
        ("step_adjustment_large_push", -0.15),
    ] {
        let mut adj = StepAdjuster::new(&StepAdjustmentConfig::default()).unwrap();
        let mut input = base;
        input.dcm.y += push;
        c.bench_function(name, |b| {
            b.iter(|| *adj.solve(black_box(&input)).unwrap());
        });
    }
}

criterion_group!(group, benches, step_adjustment);

fn main() {
    cpu_time_report();
    group();
    Criterion::default().configure_from_args().final_summary();
}
