//! Load-robust companion to the criterion benchmark: per-tick *thread CPU time* (from
//! `/proc/thread-self/schedstat`, so time spent preempted by other processes is not counted) for the same
//! TSID-like and IK-like problem sequences, plus iteration counts and warm-start hit rates. A "tick" is
//! `write` (new task numbers) + `QpProblem::solve` (assembly, backend, residuals).
//! Run: `cargo bench -p stride-qp --bench cpu_time`.

use std::time::Instant;

use stride_qp::testing::RandomWbc;
use stride_qp::{
    ActiveSetSettings, ActiveSetSolver, Backend, ClarabelSettings, QpError, QpSettings, QpSolver,
    SolverOutput,
};

fn cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next().and_then(|v| v.parse().ok()))
        .unwrap_or(0)
}

type Make = fn(u64, QpSettings) -> Result<RandomWbc, QpError>;

fn settings(backend: Backend, warm: bool) -> QpSettings {
    QpSettings {
        backend,
        active_set: ActiveSetSettings {
            warm_start: warm,
            ..ActiveSetSettings::default()
        },
        clarabel: ClarabelSettings::default(),
        ..QpSettings::default()
    }
}

fn run(label: &str, make: Make, backend: Backend, warm: bool, ticks: usize, seeds: u64) {
    // optional filter for profiling: STRIDE_QP_BENCH=ik_like/active_set_warm
    if let Ok(filter) = std::env::var("STRIDE_QP_BENCH") {
        if !label.contains(&filter) {
            return;
        }
    }
    let (mut cpu, mut wall, mut iters, mut warm_hits, mut n) = (0u64, 0.0, 0usize, 0usize, 0usize);
    let mut backend_cpu = 0u64;
    for seed in 0..seeds {
        let Ok(mut p) = make(seed, settings(backend, warm)) else {
            return;
        };
        let _ = p.problem.solve();
        // CPU time is read once per batch (the /proc read itself costs a few µs)
        let c0 = cpu_ns();
        let w0 = Instant::now();
        for k in 1..=ticks {
            p.write(1e-3 * k as f64);
            let ok = p
                .problem
                .solve()
                .map(|s| (s.iterations, s.warm_started))
                .ok();
            if let Some((it, w)) = ok {
                iters += it;
                warm_hits += w as usize;
            }
            n += 1;
        }
        wall += w0.elapsed().as_secs_f64();
        cpu += cpu_ns() - c0;
        if backend == Backend::ActiveSet {
            // backend alone on the last QP of the sequence (no assembly), repeated
            let qp = p.problem.dense_qp().clone();
            let mut s = ActiveSetSolver::new(ActiveSetSettings {
                warm_start: warm,
                ..ActiveSetSettings::default()
            });
            let mut out = SolverOutput::new(&qp);
            s.solve(&qp, &mut out);
            let c0 = cpu_ns();
            for _ in 0..ticks {
                s.solve(&qp, &mut out);
            }
            backend_cpu += cpu_ns() - c0;
        }
    }
    let per = |v: f64| v / n as f64;
    let backend_only = if backend == Backend::ActiveSet {
        format!("{:8.1}", backend_cpu as f64 / n as f64 / 1e3)
    } else {
        "       -".to_string()
    };
    println!(
        "{label:<28} tick cpu {:8.1} µs  wall {:8.1} µs  backend-only cpu {backend_only} µs  iters {:5.1}  warm hits {:5.1} %",
        per(cpu as f64) / 1e3,
        per(wall) * 1e6,
        per(iters as f64),
        100.0 * per(warm_hits as f64)
    );
}

fn main() {
    let ticks = 200;
    let seeds = 5;
    for (shape, make) in [
        ("tsid_like", RandomWbc::tsid_like as Make),
        ("ik_like", RandomWbc::ik_like as Make),
    ] {
        run(
            &format!("{shape}/active_set_cold"),
            make,
            Backend::ActiveSet,
            false,
            ticks,
            seeds,
        );
        run(
            &format!("{shape}/active_set_warm"),
            make,
            Backend::ActiveSet,
            true,
            ticks,
            seeds,
        );
        run(
            &format!("{shape}/clarabel"),
            make,
            Backend::Clarabel,
            false,
            ticks / 10,
            seeds,
        );
    }
}
