use std::time::Instant;
use stride_qp::testing::RandomWbc;
use stride_qp::*;
#[test]
#[ignore]
fn probe() {
    for (label, make) in [
        (
            "tsid",
            RandomWbc::tsid_like as fn(u64, QpSettings) -> Result<RandomWbc, QpError>,
        ),
        ("ik", RandomWbc::ik_like),
    ] {
        for warm in [false, true] {
            let s = QpSettings {
                active_set: ActiveSetSettings {
                    warm_start: warm,
                    ..Default::default()
                },
                ..Default::default()
            };
            let mut p = make(1, s).unwrap();
            let (mut tw, mut ts, mut it, mut na) = (0.0, 0.0, 0, 0);
            let k = 300;
            for i in 0..k {
                let t0 = Instant::now();
                p.write(1e-3 * i as f64);
                let t1 = Instant::now();
                let sol = p.problem.solve().unwrap();
                let t2 = Instant::now();
                it += sol.iterations;
                tw += (t1 - t0).as_secs_f64();
                ts += (t2 - t1).as_secs_f64();
                na += p.problem.dense_qp().n_eq();
            }
            let qp = p.problem.dense_qp().clone();
            let mut a = ActiveSetSolver::new(ActiveSetSettings {
                warm_start: warm,
                ..Default::default()
            });
            let mut out = SolverOutput::new(&qp);
            let t0 = Instant::now();
            for _ in 0..k {
                a.solve(&qp, &mut out);
            }
            let tb = t0.elapsed().as_secs_f64();
            println!("{label} warm={warm}: write {:.1} us, solve {:.1} us, backend-only {:.1} us, iters {:.1}, active {}, neq {}", tw / k as f64 * 1e6, ts / k as f64 * 1e6, tb / k as f64 * 1e6, it as f64 / k as f64, a.active_set_size(), na / k);
        }
    }
}
