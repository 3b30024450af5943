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
use stride_qp::{ClarabelSparseSolver, SparseQp};

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

/// DCM-MPC-like sparse QP: N steps of a 2D DCM `ξ_{k+1} = F ξ_k + G z_k` (states and ZMPs as variables,
/// 4N variables), DCM tracking + ZMP-rate costs, dynamics equalities and ZMP boxes.
fn mpc_like(steps: usize, shift: f64) -> SparseQp {
    let n = 4 * steps;
    let mut qp = SparseQp::new(n, 0);
    let omega: f64 = (9.81f64 / 0.53).sqrt();
    let dt = 0.01;
    let f = (omega * dt).exp();
    let xi = |k: usize, a: usize| 4 * k + a; // state index
    let zmp = |k: usize, a: usize| 4 * k + 2 + a;
    for k in 0..steps {
        for a in 0..2 {
            // DCM tracking 7500 ‖ξ − ξ_ref‖², ZMP rate 9e4 ‖z_k − z_{k−1}‖²
            let reference = 0.05 * ((k as f64) * 0.02 + shift + a as f64).sin();
            qp.hessian.push((xi(k, a), xi(k, a), 7500.0));
            qp.gradient[xi(k, a)] = -7500.0 * reference;
            qp.hessian.push((
                zmp(k, a),
                zmp(k, a),
                if k + 1 < steps { 2.0 * 9e4 } else { 9e4 },
            ));
            if k + 1 < steps {
                qp.hessian.push((zmp(k, a), zmp(k + 1, a), -9e4));
            }
            // dynamics ξ_{k+1} − F ξ_k − (1 − F) z_k = 0 (ξ_0 fixed by the first row)
            let r = qp.lower.len();
            if k == 0 {
                qp.constraints.push((r, xi(0, a), 1.0));
                qp.lower.push(0.01);
                qp.upper.push(0.01);
            } else {
                qp.constraints.push((r, xi(k, a), 1.0));
                qp.constraints.push((r, xi(k - 1, a), -f));
                qp.constraints.push((r, zmp(k - 1, a), f - 1.0));
                qp.lower.push(0.0);
                qp.upper.push(0.0);
            }
            // ZMP box (foot: x ∈ [−0.02, 0.05], y ∈ [−0.045, 0.05])
            let r = qp.lower.len();
            qp.constraints.push((r, zmp(k, a), 1.0));
            qp.lower.push(if a == 0 { -0.02 } else { -0.045 });
            qp.upper.push(0.05);
        }
    }
    qp
}

fn run_sparse(steps: usize) {
    let mut solver = ClarabelSparseSolver::new(ClarabelSettings::default());
    let mut qp = mpc_like(steps, 0.0);
    let _ = solver.solve(&qp);
    let reps = 10;
    let c0 = cpu_ns();
    let mut iters = 0;
    let mut ok = 0;
    for r in 0..reps {
        qp = mpc_like(steps, 0.01 * r as f64);
        if let Ok(sol) = solver.solve(&qp) {
            iters += sol.iterations;
            ok += sol.status.is_success() as usize;
        }
    }
    let cpu = (cpu_ns() - c0) as f64 / reps as f64 / 1e3;
    println!(
        "{:<28} solve cpu {cpu:8.1} µs (incl. problem build)  iters {:5.1}  solved {ok}/{reps}",
        format!("mpc_like_{}vars/clarabel_sparse", 4 * steps),
        iters as f64 / reps as f64
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
    if std::env::var("STRIDE_QP_BENCH").map_or(true, |f| f.contains("mpc")) {
        run_sparse(100);
        run_sparse(200);
    }
}
