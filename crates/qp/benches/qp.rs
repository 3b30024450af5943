//! QP benchmarks on WBC-shaped random problems (see `stride_qp::testing`): TSID-like (62 variables, 18
//! equalities, 104 one-sided inequalities) and IK-like (38 variables, 12 equalities, 64 one-sided bounds).
//! Each iteration writes slowly varying numbers (t += 1 ms), assembles and solves.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use stride_qp::testing::RandomWbc;
use stride_qp::{ActiveSetSettings, ActiveSetSolver, Backend, QpSettings, QpSolver, SolverOutput};

fn settings(backend: Backend, warm: bool) -> QpSettings {
    QpSettings {
        backend,
        active_set: ActiveSetSettings {
            warm_start: warm,
            ..ActiveSetSettings::default()
        },
        ..QpSettings::default()
    }
}

type Make = fn(u64, QpSettings) -> Result<RandomWbc, stride_qp::QpError>;

fn bench_shape(c: &mut Criterion, label: &str, make: Make) {
    let mut group = c.benchmark_group(label);
    for (name, backend, warm) in [
        ("active_set_cold", Backend::ActiveSet, false),
        ("active_set_warm", Backend::ActiveSet, true),
        ("clarabel", Backend::Clarabel, false),
    ] {
        let Ok(mut p) = make(1, settings(backend, warm)) else {
            return;
        };
        let mut t = 0.0;
        group.bench_function(name, |b| {
            b.iter(|| {
                t += 1e-3;
                p.write(t);
                black_box(p.problem.solve().map(|s| s.x[0]).unwrap_or(f64::NAN))
            })
        });
    }
    // backend only (no assembly), cold, on a fixed dense QP
    let Ok(mut p) = make(1, settings(Backend::ActiveSet, false)) else {
        return;
    };
    let _ = p.problem.solve();
    let qp = p.problem.dense_qp().clone();
    let mut solver = ActiveSetSolver::new(ActiveSetSettings {
        warm_start: false,
        ..ActiveSetSettings::default()
    });
    let mut out = SolverOutput::new(&qp);
    group.bench_function("active_set_cold_backend_only", |b| {
        b.iter(|| {
            solver.solve(black_box(&qp), &mut out);
            black_box(out.x[0])
        })
    });
    // the data check every backend runs before solving
    group.bench_function("dense_qp_is_valid", |b| {
        b.iter(|| black_box(black_box(&qp).is_valid()))
    });
    group.finish();
}

fn benches(c: &mut Criterion) {
    bench_shape(c, "tsid_like", RandomWbc::tsid_like);
    bench_shape(c, "ik_like", RandomWbc::ik_like);
}

criterion_group!(qp_benches, benches);
criterion_main!(qp_benches);
