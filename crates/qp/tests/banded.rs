//! The banded interior-point solver through its public interface: agreement with the dense clarabel
//! backend on constrained chain problems shaped like the DCM MPC, the unconstrained shortcut, the
//! refactorisation after a Hessian change, warm starts, structure errors, and allocation-free solves.

use nalgebra::{DMatrix, DVector};
use stride_qp::{
    BandedOutcome, BandedQp, BandedQpError, BandedSettings, ClarabelSettings, ClarabelSolver,
    DenseQp, QpSolver, QpStatus, SolverOutput,
};

#[global_allocator]
static ALLOC: stride_testkit::CountingAllocator = stride_testkit::CountingAllocator::new();

const SETTINGS: BandedSettings = BandedSettings {
    tolerance: 1e-9,
    max_iterations: 50,
};

/// A chain problem like the DCM MPC's: `stages` 2-D variables `ξ_k` (x/y interleaved), cost
/// `½ Σ ‖ξ_k − r_k‖² + ½ w Σ ‖ξ_{k+1} − 2ξ_k + ξ_{k−1}‖²`, and per stage the point
/// `z_k = a ξ_k + c ξ_{k−1}` kept in the square `|z| ≤ half_width` (four rows). The references
/// `r_k` step sideways by `jump` halfway, which makes rows active when `jump > half_width`.
struct Chain {
    qp: BandedQp,
    rows: Vec<Row>,
}

/// One row `normalᵀ Σ_t c_t (x[j_t], x[j_t + 1]) ≤ bound` as `(point [(j_t, c_t)], normal, bound)`.
type Row = (Vec<(usize, f64)>, [f64; 2], f64);

fn chain(stages: usize, jump: f64, half_width: f64) -> Chain {
    let n = 2 * stages;
    let (a, c, w) = (25.0, -24.0, 0.3);
    let mut qp = BandedQp::new(n, stages, 4 * stages);
    for k in 0..stages {
        let reference = [if k >= stages / 2 { jump } else { 0.0 }, 0.5 * jump];
        for (axis, r) in reference.iter().enumerate() {
            let i = 2 * k + axis;
            qp.hessian_mut().add(i, i, 1.0).unwrap();
            qp.gradient_mut()[i] = -r;
        }
    }
    for k in 1..stages.saturating_sub(1) {
        let terms = [(k + 1, 1.0), (k, -2.0), (k - 1, 1.0)];
        for &(si, ci) in &terms {
            for &(sj, cj) in &terms {
                if sj <= si {
                    for axis in 0..2 {
                        qp.hessian_mut()
                            .add(2 * si + axis, 2 * sj + axis, w * ci * cj)
                            .unwrap();
                    }
                }
            }
        }
    }
    let mut rows = Vec::new();
    for k in 0..stages {
        let point: Vec<(usize, f64)> = if k == 0 {
            vec![(0, a)]
        } else {
            vec![(2 * (k - 1), c), (2 * k, a)]
        };
        qp.push_group(&point).unwrap();
        for normal in [[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]] {
            qp.push_row(normal, half_width).unwrap();
            rows.push((point.clone(), normal, half_width));
        }
    }
    Chain { qp, rows }
}

/// The same problem as a dense QP, solved by the clarabel backend.
fn dense_solution(chain: &Chain) -> DVector<f64> {
    let n = chain.qp.n();
    let mut dense = DenseQp::new(n, 0, chain.rows.len());
    *dense.hessian_mut() = DMatrix::from_fn(n, n, |i, j| chain.qp.hessian().get(i, j));
    dense
        .gradient_mut()
        .copy_from(&DVector::from_column_slice(chain.qp.gradient()));
    for (r, (point, normal, bound)) in chain.rows.iter().enumerate() {
        for &(column, coefficient) in point {
            for (axis, n) in normal.iter().enumerate() {
                dense.ineq_matrix_mut()[(r, column + axis)] += coefficient * n;
            }
        }
        dense.ineq_upper_mut()[r] = *bound;
    }
    let mut solver = ClarabelSolver::new(ClarabelSettings {
        tolerance: 1e-12,
        max_iterations: 300,
    });
    let mut out = SolverOutput::new(&dense);
    solver.solve(&dense, &mut out);
    assert!(out.status.is_success(), "{:?}", out.status);
    out.x
}

#[test]
fn constrained_chains_agree_with_dense_clarabel() {
    for (stages, jump) in [(3, 0.05), (10, 0.03), (40, 0.02), (200, 0.02)] {
        let mut chain = chain(stages, jump, 0.01);
        let (outcome, iterations) = chain.qp.solve(&SETTINGS);
        assert_eq!(outcome, BandedOutcome::Converged, "{stages} stages");
        assert!(iterations > 0);
        let reference = dense_solution(&chain);
        let difference = (DVector::from_column_slice(chain.qp.x()) - reference).amax();
        assert!(
            difference < 1e-7,
            "{stages} stages: differs by {difference}"
        );
        // primal feasibility and complementarity of the returned iterate
        let multipliers = chain.qp.multipliers();
        let slacks = chain.qp.slacks();
        assert_eq!(multipliers.len(), 4 * stages);
        for (i, (point, normal, bound)) in chain.rows.iter().enumerate() {
            let x = chain.qp.x();
            let value: f64 = point
                .iter()
                .map(|&(j, c)| c * (normal[0] * x[j] + normal[1] * x[j + 1]))
                .sum();
            assert!(value <= bound + 1e-9, "row {i}: {value} > {bound}");
            assert!(multipliers[i] >= 0.0 && slacks[i] >= 0.0);
            assert!(multipliers[i] * slacks[i] < 1e-9, "row {i}");
        }
        assert!(multipliers.iter().any(|&l| l > 1e-6), "no active row");
        // the same problem through the clarabel reference paths
        let banded = chain.qp.x().to_vec();
        let (outcome, _) = chain.qp.solve_with_clarabel(1e-12, 300);
        assert_eq!(outcome, BandedOutcome::Converged);
        let difference =
            (DVector::from_column_slice(chain.qp.x()) - DVector::from_vec(banded)).amax();
        assert!(
            difference < 1e-7,
            "{stages} stages: clarabel differs by {difference}"
        );
    }
}

#[test]
fn a_feasible_unconstrained_minimiser_is_returned_at_once() {
    let mut chain = chain(20, 0.005, 1.0);
    assert_eq!(chain.qp.solve(&SETTINGS), (BandedOutcome::Unconstrained, 0));
    assert!(chain.qp.multipliers().iter().all(|&l| l == 0.0));
    let difference = (DVector::from_column_slice(chain.qp.x()) - dense_solution(&chain)).amax();
    assert!(difference < 1e-9, "differs by {difference}");
    assert_eq!(
        QpStatus::from(BandedOutcome::Unconstrained),
        QpStatus::Solved
    );
    assert_eq!(QpStatus::from(BandedOutcome::Converged), QpStatus::Solved);
    assert_eq!(
        QpStatus::from(BandedOutcome::MaxIterations),
        QpStatus::MaxIterations
    );
    assert_eq!(
        QpStatus::from(BandedOutcome::NumericalError),
        QpStatus::NumericalError
    );
}

#[test]
fn a_changed_hessian_is_refactorised() {
    let mut chain = chain(20, 0.005, 1.0);
    chain.qp.solve(&SETTINGS);
    let before = chain.qp.x().to_vec();
    // doubling P halves the unconstrained minimiser −P⁻¹q
    for i in 0..chain.qp.n() {
        for j in i.saturating_sub(5)..=i {
            let v = chain.qp.hessian().get(i, j);
            chain.qp.hessian_mut().add(i, j, v).unwrap();
        }
    }
    assert_eq!(chain.qp.solve(&SETTINGS).0, BandedOutcome::Unconstrained);
    for (x, b) in chain.qp.x().iter().zip(&before) {
        assert!((x - 0.5 * b).abs() < 1e-12, "{x} vs {b} / 2");
    }
}

#[test]
fn a_warm_start_from_the_solution_reaches_the_same_optimum() {
    let mut chain = chain(40, 0.03, 0.01);
    let (_, cold_iterations) = chain.qp.solve(&SETTINGS);
    let x = chain.qp.x().to_vec();
    let multipliers = chain.qp.multipliers().to_vec();
    let (start_x, start_multipliers) = chain.qp.warm_start_mut();
    start_x.copy_from_slice(&x);
    start_multipliers.copy_from_slice(&multipliers);
    let (outcome, warm_iterations) = chain.qp.solve(&SETTINGS);
    assert_eq!(outcome, BandedOutcome::Converged);
    assert!(
        warm_iterations <= cold_iterations,
        "{warm_iterations} > {cold_iterations}"
    );
    let difference = (DVector::from_column_slice(chain.qp.x()) - DVector::from_vec(x)).amax();
    assert!(difference < 1e-7, "differs by {difference}");
    assert_eq!(chain.qp.group_rows(3), 12..16);
    assert_eq!(chain.qp.group_rows(40), 0..0);
}

#[test]
fn a_structure_that_does_not_fit_is_refused() {
    let mut qp = BandedQp::new(8, 1, 2);
    assert_eq!(qp.push_row([1.0, 0.0], 1.0), Err(BandedQpError::NoGroup));
    let bad_points: [&[(usize, f64)]; 5] = [
        &[(1, 1.0)],
        &[(8, 1.0)],
        &[(2, 1.0), (2, 1.0)],
        &[(0, 1.0), (6, 1.0)],
        &[(0, 1.0), (2, 1.0), (4, 1.0)],
    ];
    for point in bad_points {
        assert!(
            matches!(
                qp.push_group(point),
                Err(BandedQpError::InvalidPoint { .. })
            ),
            "{point:?}"
        );
    }
    assert_eq!(qp.group_count(), 0);
    qp.push_group(&[(0, 1.0), (2, 1.0)]).unwrap();
    assert_eq!(
        qp.push_group(&[(2, 1.0)]),
        Err(BandedQpError::CapacityExceeded {
            what: "groups",
            capacity: 1
        })
    );
    qp.push_row([1.0, 0.0], 1.0).unwrap();
    qp.push_row([0.0, 1.0], 1.0).unwrap();
    assert_eq!(
        qp.push_row([0.0, 1.0], 1.0),
        Err(BandedQpError::CapacityExceeded {
            what: "rows",
            capacity: 2
        })
    );
    assert_eq!(qp.row_count(), 2);
    assert_eq!(
        qp.hessian_mut().add(0, 6, 1.0),
        Err(BandedQpError::OutsideBand {
            row: 0,
            column: 6,
            n: 8
        })
    );
    assert!(qp.hessian_mut().add(5, 0, 1.0).is_ok());
    assert_eq!(
        qp.hessian_mut().add(8, 8, 1.0),
        Err(BandedQpError::OutsideBand {
            row: 8,
            column: 8,
            n: 8
        })
    );
    qp.clear_constraints();
    assert_eq!((qp.group_count(), qp.row_count()), (0, 0));
    // P = 0 plus one off-diagonal entry is indefinite: reported, not a panic
    assert_eq!(qp.solve(&SETTINGS).0, BandedOutcome::NumericalError);
}

#[test]
fn solves_allocate_nothing() {
    let mut chain = chain(200, 0.02, 0.01);
    let (first, allocations) = ALLOC.allocations_during(|| chain.qp.solve(&SETTINGS));
    assert_eq!(first.0, BandedOutcome::Converged);
    assert_eq!(allocations, 0, "allocations in a constrained solve");
    let x = chain.qp.x().to_vec();
    let (_, allocations) = ALLOC.allocations_during(|| {
        let (start_x, _) = chain.qp.warm_start_mut();
        start_x.copy_from_slice(&x);
        chain.qp.solve(&SETTINGS)
    });
    assert_eq!(allocations, 0, "allocations in a warm-started solve");
}
