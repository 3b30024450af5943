//! Hand-built cases: closed forms, degenerate and infeasible problems, the fallback, invalid data, sparse path.

use nalgebra::{DMatrix, DVector};
use stride_qp::testing::SplitMix64;
use stride_qp::{
    check_kkt, ActiveSetSolver, Backend, ClarabelSolver, ClarabelSparseSolver, DenseQp, QpError,
    QpProblem, QpSettings, QpSolver, QpStatus, SolvePath, SolverOutput, SparseQp, TaskSpec,
    VariableSet,
};

fn both() -> Vec<Box<dyn QpSolver>> {
    vec![
        Box::new(ActiveSetSolver::new(Default::default())),
        Box::new(ClarabelSolver::new(Default::default())),
    ]
}

fn spd(rng: &mut SplitMix64, n: usize) -> DMatrix<f64> {
    let m = rng.matrix(n, n, 1.0);
    &m * m.transpose() + DMatrix::identity(n, n) * 0.5
}

#[test]
fn unconstrained_matches_closed_form() {
    let mut rng = SplitMix64::new(7);
    let n = 12;
    let mut qp = DenseQp::new(n, 0, 0);
    *qp.hessian_mut() = spd(&mut rng, n);
    *qp.gradient_mut() = rng.vector(n, -3.0, 3.0);
    // closed form x = -H^{-1} g via nalgebra's LU (independent of our Cholesky)
    let x_ref = -qp.hessian().clone().lu().solve(qp.gradient()).unwrap();
    for mut s in both() {
        let mut out = SolverOutput::new(&qp);
        s.solve(&qp, &mut out);
        assert_eq!(out.status, QpStatus::Solved, "{}", s.name());
        assert!((&out.x - &x_ref).amax() < 1e-8, "{}", s.name());
        let expected = 0.5 * qp.gradient().dot(&x_ref); // ½xᵀHx + gᵀx at x = −H⁻¹g
        assert!((out.objective - expected).abs() < 1e-8 * (1.0 + expected.abs()));
    }
}

#[test]
fn equality_constrained_matches_kkt_system() {
    // min ½xᵀHx + gᵀx s.t. Ex = f  ⇔  [H Eᵀ; E 0][x; y] = [-g; f]
    let mut rng = SplitMix64::new(3);
    let (n, m) = (10, 4);
    let mut qp = DenseQp::new(n, m, 0);
    *qp.hessian_mut() = spd(&mut rng, n);
    *qp.gradient_mut() = rng.vector(n, -1.0, 1.0);
    let e = rng.matrix(m, n, 1.0);
    let f = rng.vector(m, -1.0, 1.0);
    qp.eq_matrix_mut().copy_from(&e);
    qp.eq_rhs_mut().copy_from(&f);
    let mut k = DMatrix::zeros(n + m, n + m);
    k.view_mut((0, 0), (n, n)).copy_from(qp.hessian());
    k.view_mut((0, n), (n, m)).copy_from(&e.transpose());
    k.view_mut((n, 0), (m, n)).copy_from(&e);
    let mut rhs = DVector::zeros(n + m);
    rhs.rows_mut(0, n).copy_from(&(-qp.gradient()));
    rhs.rows_mut(n, m).copy_from(&f);
    let sol = k.lu().solve(&rhs).unwrap();
    for mut s in both() {
        let mut out = SolverOutput::new(&qp);
        s.solve(&qp, &mut out);
        assert_eq!(out.status, QpStatus::Solved);
        assert!((&out.x - sol.rows(0, n)).amax() < 1e-7, "{}", s.name());
        assert!(
            (out.eq_multipliers() - sol.rows(n, m)).amax() < 1e-6,
            "{}",
            s.name()
        );
    }
}

/// Box-constrained diagonal QP: the solution is the clamped unconstrained minimiser.
#[test]
fn diagonal_box_qp_is_clamped() {
    let mut rng = SplitMix64::new(11);
    let n = 20;
    let mut qp = DenseQp::new(n, 0, 0);
    let mut expected = DVector::zeros(n);
    for i in 0..n {
        let h = rng.uniform(0.5, 3.0);
        let g = rng.uniform(-5.0, 5.0);
        qp.hessian_mut()[(i, i)] = h;
        qp.gradient_mut()[i] = g;
        qp.lower_bounds_mut()[i] = -1.0;
        qp.upper_bounds_mut()[i] = 1.0;
        expected[i] = (-g / h).clamp(-1.0, 1.0);
    }
    for mut s in both() {
        let mut out = SolverOutput::new(&qp);
        s.solve(&qp, &mut out);
        assert_eq!(out.status, QpStatus::Solved);
        assert!((&out.x - &expected).amax() < 1e-7, "{}", s.name());
        assert!(check_kkt(&qp, &out).is_satisfied(1e-7));
    }
}

fn redundant_problem() -> DenseQp {
    // x ∈ R³, min ½‖x − (2, 2, 2)‖², x0 + x1 = 1 given twice (and scaled), x0 ≤ 0.2 given twice,
    // x2 ≤ 0.5 as a row and as a bound.
    let mut qp = DenseQp::new(3, 3, 3);
    qp.hessian_mut().fill_with_identity();
    qp.gradient_mut().fill(-2.0);
    qp.eq_matrix_mut().copy_from(&DMatrix::from_row_slice(
        3,
        3,
        &[1.0, 1.0, 0.0, 1.0, 1.0, 0.0, 2.0, 2.0, 0.0],
    ));
    qp.eq_rhs_mut()
        .copy_from(&DVector::from_row_slice(&[1.0, 1.0, 2.0]));
    qp.ineq_matrix_mut().copy_from(&DMatrix::from_row_slice(
        3,
        3,
        &[1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0],
    ));
    qp.ineq_upper_mut()
        .copy_from(&DVector::from_row_slice(&[0.2, 0.2, 0.5]));
    qp.upper_bounds_mut()[2] = 0.5;
    qp
}

#[test]
fn redundant_constraints_solved_by_both() {
    let qp = redundant_problem();
    let expected = DVector::from_row_slice(&[0.2, 0.8, 0.5]);
    for mut s in both() {
        let mut out = SolverOutput::new(&qp);
        s.solve(&qp, &mut out);
        assert_eq!(out.status, QpStatus::Solved, "{}", s.name());
        assert!(
            (&out.x - &expected).amax() < 1e-7,
            "{}: {}",
            s.name(),
            out.x
        );
        // multipliers are not unique here, but KKT must hold
        assert!(
            check_kkt(&qp, &out).is_satisfied(1e-7),
            "{}: {:?}",
            s.name(),
            check_kkt(&qp, &out)
        );
    }
}

#[test]
fn inconsistent_equalities_are_infeasible_in_both() {
    let mut qp = redundant_problem();
    qp.eq_rhs_mut()[1] = 1.5; // x0 + x1 = 1 and = 1.5
    for mut s in both() {
        let mut out = SolverOutput::new(&qp);
        s.solve(&qp, &mut out);
        assert_eq!(out.status, QpStatus::Infeasible, "{}", s.name());
        assert!(out.x.iter().all(|v| v.is_finite()));
    }
}

#[test]
fn infeasible_bounds_with_equality_detected_by_both() {
    // x0 + x1 = 10 with 0 ≤ x ≤ 1
    let mut qp = DenseQp::new(2, 1, 0);
    qp.hessian_mut().fill_with_identity();
    qp.eq_matrix_mut().fill(1.0);
    qp.eq_rhs_mut()[0] = 10.0;
    qp.lower_bounds_mut().fill(0.0);
    qp.upper_bounds_mut().fill(1.0);
    for mut s in both() {
        let mut out = SolverOutput::new(&qp);
        s.solve(&qp, &mut out);
        assert_eq!(out.status, QpStatus::Infeasible, "{}", s.name());
    }
    // contradictory inequalities only: x0 + x1 ≥ 3 and x0 ≤ 1, x1 ≤ 1
    let mut qp = DenseQp::new(2, 0, 1);
    qp.hessian_mut().fill_with_identity();
    qp.ineq_matrix_mut().fill(1.0);
    qp.ineq_lower_mut()[0] = 3.0;
    qp.upper_bounds_mut().fill(1.0);
    for mut s in both() {
        let mut out = SolverOutput::new(&qp);
        s.solve(&qp, &mut out);
        assert_eq!(out.status, QpStatus::Infeasible, "{}", s.name());
    }
}

#[test]
fn rank_deficient_soft_tasks_same_answer() {
    // Two soft tasks that only see x0 + x1; the Tikhonov term picks the minimum-norm split.
    for backend in [Backend::ActiveSet, Backend::Clarabel] {
        let mut vars = VariableSet::new();
        let v = vars.add("v", 2).unwrap();
        let specs = vec![
            TaskSpec::equality("sum", &[v], 1).soft(1.0),
            TaskSpec::equality("sum2", &[v], 1).soft(1.0),
        ];
        let settings = QpSettings {
            backend,
            regularization: 1e-6,
            ..QpSettings::default()
        };
        let mut p = QpProblem::new(vars, specs, settings).unwrap();
        for name in ["sum", "sum2"] {
            let id = p.task_id(name).unwrap();
            p.task_mut(id).a_mut().fill(1.0);
            p.task_mut(id).b_mut()[0] = 2.0;
        }
        let sol = p.solve().unwrap();
        assert_eq!(sol.status, QpStatus::Solved);
        // closed form: min (s − 2)² + ρ/2 (x0² + x1²) with s = x0 + x1 ⇒ x0 = x1 = 2/(2 + ρ/2)
        let expected = 2.0 / (2.0 + 0.5e-6);
        assert!(
            (sol.x[0] - expected).abs() < 1e-7 && (sol.x[1] - expected).abs() < 1e-7,
            "{backend:?} {}",
            sol.x
        );
    }
    // Without regularisation the active-set solver refuses a singular Hessian explicitly.
    let mut qp = DenseQp::new(2, 0, 0);
    qp.hessian_mut().fill(1.0);
    let mut out = SolverOutput::new(&qp);
    ActiveSetSolver::new(Default::default()).solve(&qp, &mut out);
    assert_eq!(out.status, QpStatus::HessianNotPositiveDefinite);
}

fn com_problem(backend: Backend, fallback: bool) -> QpProblem {
    // Two "forces" f ∈ [0, 100]², hard "com" task f0 + f1 = target, soft regularisation.
    let mut vars = VariableSet::new();
    let f = vars.add("forces", 2).unwrap();
    let specs = vec![
        TaskSpec::equality("com", &[f], 1),
        TaskSpec::equality("regularization", &[f], 2).soft(1.0),
        TaskSpec::inequality("unilateral", &[f], 2),
    ];
    let settings = QpSettings {
        backend,
        fallback,
        ..QpSettings::default()
    };
    let mut p = QpProblem::new(vars, specs, settings).unwrap();
    let com = p.task_id("com").unwrap();
    p.task_mut(com).a_mut().fill(1.0);
    let reg = p.task_id("regularization").unwrap();
    p.task_mut(reg).a_mut().fill_with_identity();
    let uni = p.task_id("unilateral").unwrap();
    p.task_mut(uni).a_mut().fill_with_identity();
    p.task_mut(uni).lower_mut().fill(0.0);
    p.upper_bounds_mut(f).fill(100.0);
    p
}

#[test]
fn fallback_relaxes_hard_equalities() {
    for backend in [Backend::ActiveSet, Backend::Clarabel] {
        let mut p = com_problem(backend, true);
        let com = p.task_id("com").unwrap();
        // feasible: nominal path
        p.task_mut(com).b_mut()[0] = 50.0;
        let sol = p.solve().unwrap();
        assert_eq!(sol.path, SolvePath::Nominal);
        assert!((sol.x[0] - 25.0).abs() < 1e-6);
        // infeasible target (needs 300 > 2·100): relaxed path, forces saturate, residual reported
        p.task_mut(com).b_mut()[0] = 300.0;
        let sol = p.solve().unwrap().clone();
        assert_eq!(sol.nominal_status, QpStatus::Infeasible, "{backend:?}");
        assert_eq!(sol.path, SolvePath::Relaxed);
        assert_eq!(sol.status, QpStatus::Solved);
        assert!(
            (sol.x[0] - 100.0).abs() < 1e-6 && (sol.x[1] - 100.0).abs() < 1e-6,
            "{}",
            sol.x
        );
        assert!((sol.task_residuals[com.0] - 100.0).abs() < 1e-6);
        assert!((sol.hard_violation - 100.0).abs() < 1e-6);
        // back to feasible: nominal again
        p.task_mut(com).b_mut()[0] = 50.0;
        assert_eq!(p.solve().unwrap().path, SolvePath::Nominal);
    }
}

#[test]
fn fallback_failure_is_an_error() {
    for backend in [Backend::ActiveSet, Backend::Clarabel] {
        let mut p = com_problem(backend, true);
        let com = p.task_id("com").unwrap();
        p.task_mut(com).b_mut()[0] = 50.0;
        // inequalities contradict the bounds: relaxing equalities cannot help
        let uni = p.task_id("unilateral").unwrap();
        p.task_mut(uni).lower_mut().fill(150.0);
        let err = p.solve().unwrap_err();
        assert_eq!(
            err,
            QpError::SolveFailed {
                nominal: QpStatus::Infeasible,
                relaxed: Some(QpStatus::Infeasible)
            },
            "{backend:?}"
        );
        let sol = p.solution();
        assert!(!sol.is_success());
        assert!(sol.x.iter().all(|v| *v == 0.0));
        // without fallback: only the nominal status
        let mut p = com_problem(backend, false);
        p.task_mut(com).b_mut()[0] = 300.0;
        assert_eq!(
            p.solve().unwrap_err(),
            QpError::SolveFailed {
                nominal: QpStatus::Infeasible,
                relaxed: None
            }
        );
    }
}

#[test]
fn nan_input_is_reported_never_returned() {
    for backend in [Backend::ActiveSet, Backend::Clarabel] {
        let mut p = com_problem(backend, true);
        let com = p.task_id("com").unwrap();
        p.task_mut(com).b_mut()[0] = f64::NAN;
        let err = p.solve().unwrap_err();
        assert_eq!(
            err,
            QpError::SolveFailed {
                nominal: QpStatus::InvalidData,
                relaxed: None
            }
        );
        assert!(p.solution().x.iter().all(|v| v.is_finite()));
    }
}

#[test]
fn construction_errors_name_the_culprit() {
    let mut vars = VariableSet::new();
    let v = vars.add("v", 2).unwrap();
    assert!(matches!(
        vars.add("v", 3),
        Err(QpError::DuplicateVariable { .. })
    ));
    assert!(matches!(
        vars.add("w", 0),
        Err(QpError::EmptyVariable { .. })
    ));
    let err = QpProblem::new(
        vars.clone(),
        vec![TaskSpec::inequality("lim", &[v], 1).soft(1.0)],
        QpSettings::default(),
    );
    assert!(matches!(err, Err(QpError::SoftInequality { task }) if task == "lim"));
    let err = QpProblem::new(
        vars.clone(),
        vec![TaskSpec::equality("t", &[v, v], 1)],
        QpSettings::default(),
    );
    assert!(matches!(err, Err(QpError::RepeatedVariable { .. })));
    let err = QpProblem::new(
        vars.clone(),
        vec![TaskSpec::equality("t", &[v], 2).soft_weights(&[1.0, 2.0, 3.0])],
        QpSettings::default(),
    );
    assert!(matches!(
        err,
        Err(QpError::WeightSize {
            expected: 2,
            got: 3,
            ..
        })
    ));
    let mut p = QpProblem::new(
        vars,
        vec![TaskSpec::equality("t", &[v], 2).soft(1.0)],
        QpSettings::default(),
    )
    .unwrap();
    let t = p.task_id("t").unwrap();
    assert!(matches!(
        p.task_mut(t).set_weight(-1.0),
        Err(QpError::InvalidWeight { .. })
    ));
    assert!(p.task_mut(t).set_weights(&[1.0, 4.0]).is_ok());
    let bad: QpSettings = QpSettings {
        regularization: -1.0,
        ..QpSettings::default()
    };
    assert!(bad.validate().is_err());
}

#[test]
fn vector_weights_and_runtime_priority_switch() {
    // min w0 (x − 1)² + w1 (x − 3)²  ⇒ x = (w0 + 3 w1)/(w0 + w1)
    let mut vars = VariableSet::new();
    let v = vars.add("v", 1).unwrap();
    let specs = vec![TaskSpec::equality("two_targets", &[v], 2).soft_weights(&[1.0, 3.0])];
    let mut p = QpProblem::new(
        vars,
        specs,
        QpSettings {
            regularization: 0.0,
            ..QpSettings::default()
        },
    )
    .unwrap();
    let t = p.task_id("two_targets").unwrap();
    p.task_mut(t).a_mut().fill(1.0);
    p.task_mut(t).b_mut().copy_from_slice(&[1.0, 3.0]);
    assert!((p.solve().unwrap().x[0] - 2.5).abs() < 1e-12);
    p.task_mut(t).set_weights(&[3.0, 1.0]).unwrap();
    assert!((p.solve().unwrap().x[0] - 1.5).abs() < 1e-12);
    // hard: the two rows contradict ⇒ infeasible ⇒ relaxed path (equal weights) gives the mean
    p.task_mut(t).set_hard(true).unwrap();
    let sol = p.solve().unwrap();
    assert_eq!(sol.path, SolvePath::Relaxed);
    assert!((sol.x[0] - 2.0).abs() < 1e-9);
}

#[test]
fn sparse_clarabel_matches_dense_active_set() {
    // A banded problem like the DCM MPC: chain x_{k+1} − a x_k = c, tracking costs, box on x.
    let n = 200;
    let mut qp = SparseQp::new(n, 0);
    let mut rng = SplitMix64::new(5);
    for k in 0..n {
        qp.hessian.push((k, k, 2.0));
        if k + 1 < n {
            qp.hessian.push((k, k + 1, -0.5));
        }
        qp.gradient[k] = rng.uniform(-3.0, 3.0);
    }
    for k in 0..n - 1 {
        let r = qp.lower.len();
        qp.constraints.push((r, k + 1, 1.0));
        qp.constraints.push((r, k, -0.9));
        qp.lower.push(-0.3);
        qp.upper.push(0.3);
    }
    let r = qp.lower.len();
    qp.constraints.push((r, 0, 1.0));
    qp.lower.push(0.1);
    qp.upper.push(0.1); // equality x0 = 0.1
    let mut sparse = ClarabelSparseSolver::new(Default::default());
    let sol = sparse.solve(&qp).unwrap().clone();
    assert_eq!(sol.status, QpStatus::Solved);
    let dense = qp.to_dense().unwrap();
    let mut out = SolverOutput::new(&dense);
    ActiveSetSolver::new(Default::default()).solve(&dense, &mut out);
    assert_eq!(out.status, QpStatus::Solved);
    let xs = DVector::from_vec(sol.x.clone());
    assert!((&xs - &out.x).amax() < 1e-6);
    assert!(check_kkt(&dense, &out).is_satisfied(1e-10));
    let ms = DVector::from_vec(sol.multipliers.clone());
    assert!((&ms - out.ineq_multipliers()).amax() < 1e-5);
    // second solve with new numbers reuses the pattern
    qp.gradient[3] += 1.0;
    let sol2 = sparse.solve(&qp).unwrap();
    assert_eq!(sol2.status, QpStatus::Solved);
    // helpers: the same kind of problem written with add_hessian / add_row gives the same rows
    let mut small = SparseQp::new(2, 0);
    small.add_hessian(1, 0, 0.5); // lower-triangle input is mirrored into the upper triangle
    small.add_hessian(0, 0, 2.0);
    small.add_hessian(1, 1, 2.0);
    small.gradient.copy_from_slice(&[-1.0, -1.0]);
    let r = small.add_row(&[(0, 1.0), (1, 1.0)], f64::NEG_INFINITY, 0.4);
    assert_eq!(r, 0);
    let d = small.to_dense().unwrap();
    assert_eq!(d.hessian()[(0, 1)], 0.5);
    assert_eq!(d.hessian()[(1, 0)], 0.5);
    let s2 = ClarabelSparseSolver::new(Default::default())
        .solve(&small)
        .unwrap()
        .clone();
    // symmetric optimum on the active row: x0 = x1 = 0.2
    assert!(
        (s2.x[0] - 0.2).abs() < 1e-7 && (s2.x[1] - 0.2).abs() < 1e-7,
        "{:?}",
        s2.x
    );
    // bad triplet rejected
    qp.hessian.push((5, 2, 1.0));
    assert!(matches!(sparse.solve(&qp), Err(QpError::BadTriplet { .. })));
}
