//! Settings are data: TOML in, defaults documented, unknown keys rejected; clarabel rebuild logic.

use stride_qp::{
    ActiveSetSettings, Backend, ClarabelSolver, DenseQp, QpSettings, QpSolver, QpStatus,
    SolverOutput,
};

#[test]
fn settings_from_toml() {
    let s: QpSettings = toml::from_str(
        "backend = \"clarabel\"\nregularization = 1e-6\n[active_set]\nwarm_start = false\n[clarabel]\ntolerance = 1e-9\n",
    )
    .unwrap();
    assert_eq!(s.backend, Backend::Clarabel);
    assert_eq!(s.regularization, 1e-6);
    assert!(!s.active_set.warm_start);
    assert_eq!(
        s.active_set.feasibility_tolerance,
        ActiveSetSettings::default().feasibility_tolerance
    );
    assert_eq!(s.clarabel.tolerance, 1e-9);
    assert!(s.fallback);
    assert_eq!(s.relaxation_weight, 1e4);
    let empty: QpSettings = toml::from_str("").unwrap();
    assert_eq!(empty, QpSettings::default());
    assert!(toml::from_str::<QpSettings>("regularisation = 1.0").is_err());
    assert!(toml::from_str::<QpSettings>("[active_set]\nwarm = true").is_err());
    assert!(toml::from_str::<QpSettings>("backend = \"osqp\"").is_err());
}

#[test]
fn clarabel_rebuilds_only_when_the_finite_sides_change() {
    let mut qp = DenseQp::new(3, 1, 2);
    qp.hessian_mut().fill_with_identity();
    qp.gradient_mut().fill(-1.0);
    qp.eq_matrix_mut().fill(1.0);
    qp.eq_rhs_mut()[0] = 1.0;
    qp.ineq_matrix_mut()[(0, 0)] = 1.0;
    qp.ineq_matrix_mut()[(1, 1)] = 1.0;
    qp.ineq_upper_mut()[0] = 0.1;
    let mut c = ClarabelSolver::new(Default::default());
    let mut out = SolverOutput::new(&qp);
    c.solve(&qp, &mut out);
    assert_eq!(out.status, QpStatus::Solved);
    assert!((out.x[0] - 0.1).abs() < 1e-7);
    // new numbers, same layout: update path
    qp.ineq_upper_mut()[0] = 0.2;
    c.solve(&qp, &mut out);
    assert!((out.x[0] - 0.2).abs() < 1e-7);
    assert_eq!(c.rebuilds(), 1);
    // a side becomes finite: rebuild
    qp.ineq_lower_mut()[1] = 0.5;
    c.solve(&qp, &mut out);
    assert_eq!(c.rebuilds(), 2);
    assert!((out.x[1] - 0.5).abs() < 1e-7);
    // no constraint at all
    let mut free = DenseQp::new(2, 0, 0);
    free.hessian_mut().fill_with_identity();
    free.gradient_mut().fill(-2.0);
    let mut out = SolverOutput::new(&free);
    c.solve(&free, &mut out);
    assert_eq!(out.status, QpStatus::Solved);
    assert!((out.x[0] - 2.0).abs() < 1e-7);
}
