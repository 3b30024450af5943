//! The banded interior-point solver alone, on a chain shaped like the DCM MPC with a 2 s horizon at
//! 100 Hz (200 stages, 400 variables, 800 rows): the band kernels (Cholesky and solve of the 400 × 400
//! Newton-sized band) and whole solves (unconstrained: one banded solve with the factor reused;
//! constrained: the interior-point iterations). The MPC's own step, with assembly, is benchmarked in
//! stride-simplified (`dcm_mpc_2s_100hz_*`).

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use stride_qp::{BandMatrix, BandedOutcome, BandedQp, BandedSettings};

const STAGES: usize = 200;

/// `½ Σ ‖ξ_k − r_k‖² + ½ Σ ‖z_k − z_{k−1}‖²`-like chain: unit diagonal plus a coupling to the previous
/// stage, `z_k = 25 ξ_k − 24 ξ_{k−1}` kept in `|z| ≤ half_width`; the references step by `jump`.
fn chain(jump: f64, half_width: f64) -> BandedQp {
    let n = 2 * STAGES;
    let mut qp = BandedQp::new(n, STAGES, 4 * STAGES);
    for i in 0..n {
        qp.hessian_mut().add(i, i, 1.5).unwrap();
        if i >= 2 {
            qp.hessian_mut().add(i, i - 2, -0.25).unwrap();
        }
        qp.gradient_mut()[i] = if i >= STAGES { -jump } else { 0.0 };
    }
    for k in 0..STAGES {
        if k == 0 {
            qp.push_group(&[(0, 25.0)]).unwrap();
        } else {
            qp.push_group(&[(2 * (k - 1), -24.0), (2 * k, 25.0)])
                .unwrap();
        }
        for normal in [[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]] {
            qp.push_row(normal, half_width).unwrap();
        }
    }
    qp
}

fn benches(c: &mut Criterion) {
    let settings = BandedSettings {
        tolerance: 1e-9,
        max_iterations: 50,
    };
    let mut band = BandMatrix::new(2 * STAGES);
    for i in 0..2 * STAGES {
        for j in i.saturating_sub(5)..i {
            band.add(i, j, 0.1).unwrap();
        }
        band.add(i, i, 4.0).unwrap();
    }
    let rhs = vec![1.0; 2 * STAGES];
    c.bench_function("banded_cholesky_and_solve_400", |b| {
        b.iter(|| {
            let mut factor = band.clone();
            assert!(factor.cholesky_in_place());
            let mut x = rhs.clone();
            factor.cholesky_solve(black_box(&mut x));
            x
        })
    });
    for (name, half_width, expected) in [
        (
            "banded_qp_200_stages_unconstrained",
            1.0,
            BandedOutcome::Unconstrained,
        ),
        (
            "banded_qp_200_stages_constrained",
            0.01,
            BandedOutcome::Converged,
        ),
    ] {
        let mut qp = chain(0.02, half_width);
        let (outcome, iterations) = qp.solve(&settings);
        assert_eq!(outcome, expected, "{name}");
        eprintln!("{name}: {outcome:?}, {iterations} iterations");
        c.bench_function(name, |b| b.iter(|| black_box(qp.solve(&settings))));
    }
}

criterion_group!(banded, benches);
criterion_main!(banded);
