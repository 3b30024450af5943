//! Property tests: random small feasible QPs solved by both backends agree and satisfy KKT; warm = cold.

use nalgebra::{DMatrix, DVector};
use proptest::prelude::*;
use stride_qp::testing::SplitMix64;
use stride_qp::{
    check_kkt, ActiveSetSettings, ActiveSetSolver, ClarabelSettings, ClarabelSolver, DenseQp,
    QpSolver, QpStatus, SolverOutput,
};

/// A random strictly convex QP with a known feasible point (equalities through it, sides around it, some
/// sides tight, some infinite).
fn random_qp(seed: u64, n: usize, me: usize, mi: usize) -> DenseQp {
    let mut rng = SplitMix64::new(seed);
    let mut qp = DenseQp::new(n, me, mi);
    let m = rng.matrix(n, n, 1.0);
    *qp.hessian_mut() = &m * m.transpose() + DMatrix::identity(n, n) * rng.uniform(0.01, 1.0);
    *qp.gradient_mut() = rng.vector(n, -10.0, 10.0);
    let xf = rng.vector(n, -1.0, 1.0);
    let e = rng.matrix(me, n, 1.0);
    let f = &e * &xf;
    qp.eq_matrix_mut().copy_from(&e);
    qp.eq_rhs_mut().copy_from(&f);
    let c = rng.matrix(mi, n, 1.0);
    let cx = &c * &xf;
    qp.ineq_matrix_mut().copy_from(&c);
    for i in 0..mi {
        let kind = rng.next_u64() % 4;
        let lo = cx[i] - rng.uniform(0.0, 0.5);
        let hi = cx[i] + rng.uniform(0.0, 0.5);
        let (l, u) = match kind {
            0 => (lo, f64::INFINITY),
            1 => (f64::NEG_INFINITY, hi),
            2 => (lo, hi),
            _ => (cx[i], cx[i]), // equality written as an inequality row
        };
        qp.ineq_lower_mut()[i] = l;
        qp.ineq_upper_mut()[i] = u;
    }
    for j in 0..n {
        if rng.next_u64() % 2 == 0 {
            qp.lower_bounds_mut()[j] = xf[j] - rng.uniform(0.0, 1.0);
            qp.upper_bounds_mut()[j] = xf[j] + rng.uniform(0.0, 1.0);
        }
    }
    qp
}

/// `base` (one equality row) with its equality row repeated scaled by `scale` and every inequality row
/// repeated once.
fn with_duplicated_rows(base: &DenseQp, scale: f64) -> DenseQp {
    let (n, mi) = (base.n(), base.n_ineq());
    let mut dup = DenseQp::new(n, 2, 2 * mi);
    *dup.hessian_mut() = base.hessian().clone();
    *dup.gradient_mut() = base.gradient().clone();
    for r in 0..2 {
        let f = if r == 0 { 1.0 } else { scale };
        dup.eq_matrix_mut()
            .row_mut(r)
            .copy_from(&(base.eq_matrix().row(0) * f));
        dup.eq_rhs_mut()[r] = base.eq_rhs()[0] * f;
    }
    for i in 0..mi {
        for r in [i, mi + i] {
            dup.ineq_matrix_mut()
                .row_mut(r)
                .copy_from(&base.ineq_matrix().row(i));
            dup.ineq_lower_mut()[r] = base.ineq_lower()[i];
            dup.ineq_upper_mut()[r] = base.ineq_upper()[i];
        }
    }
    *dup.lower_bounds_mut() = base.lower_bounds().clone();
    *dup.upper_bounds_mut() = base.upper_bounds().clone();
    dup
}

/// A problem found by `redundant_rows_do_not_change_the_answer` on which clarabel with Ruiz equilibration
/// stalls (iteration limit at tolerance 1e-8..1e-11, NumericalError at 1e-12): the backend's retry without
/// equilibration solves it, and the answer matches the active-set solution of the non-duplicated problem.
#[test]
fn clarabel_retries_a_stalled_solve_without_equilibration() {
    let base = random_qp(11442055783903989687, 8, 1, 2);
    let dup = with_duplicated_rows(&base, 0.5);
    let mut reference = SolverOutput::new(&base);
    ActiveSetSolver::new(ActiveSetSettings::default()).solve(&base, &mut reference);
    assert_eq!(reference.status, QpStatus::Solved);
    for tolerance in [1e-10, 1e-12] {
        let mut c = ClarabelSolver::new(ClarabelSettings {
            tolerance,
            ..ClarabelSettings::default()
        });
        let mut out = SolverOutput::new(&dup);
        c.solve(&dup, &mut out);
        assert_eq!(c.retries(), 1, "tolerance {tolerance:e}");
        assert!(out.status.is_success(), "{:?}", out.status);
        let diff = (&out.x - &reference.x).amax();
        assert!(diff < 1e-6 * (1.0 + reference.x.amax()), "diff {diff:e}");
        let k = check_kkt(&dup, &out);
        assert!(k.is_satisfied(1e-7), "{k:?}");
        // the next call starts from the equilibrated solver again (and the base problem needs no retry)
        let mut out_base = SolverOutput::new(&base);
        c.solve(&base, &mut out_base);
        assert_eq!(out_base.status, QpStatus::Solved);
        assert_eq!(c.retries(), 1);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn backends_agree_on_random_feasible_qps(seed in any::<u64>(), n in 1usize..10, me_frac in 0usize..3, mi in 0usize..14) {
        let me = me_frac.min(n.saturating_sub(1));
        let qp = random_qp(seed, n, me, mi);
        let mut a = ActiveSetSolver::new(ActiveSetSettings::default());
        let mut c = ClarabelSolver::new(ClarabelSettings { tolerance: 1e-12, ..ClarabelSettings::default() });
        let mut oa = SolverOutput::new(&qp);
        let mut oc = SolverOutput::new(&qp);
        a.solve(&qp, &mut oa);
        c.solve(&qp, &mut oc);
        prop_assert_eq!(oa.status, QpStatus::Solved);
        prop_assert!(oc.status.is_success(), "clarabel {:?}", oc.status);
        let diff = (&oa.x - &oc.x).amax();
        prop_assert!(diff < 1e-6 * (1.0 + oa.x.amax()), "diff {:e}", diff);
        let ka = check_kkt(&qp, &oa);
        prop_assert!(ka.is_satisfied(1e-10), "{:?}", ka);
        let kc = check_kkt(&qp, &oc);
        prop_assert!(kc.is_satisfied(1e-7), "{:?}", kc);
    }

    #[test]
    fn warm_start_equals_cold_after_perturbation(seed in any::<u64>(), n in 2usize..10, mi in 1usize..14, eps in 0.0f64..0.3) {
        let qp = random_qp(seed, n, 1, mi);
        let mut warm = ActiveSetSolver::new(ActiveSetSettings::default());
        let mut cold = ActiveSetSolver::new(ActiveSetSettings { warm_start: false, ..ActiveSetSettings::default() });
        let mut ow = SolverOutput::new(&qp);
        warm.solve(&qp, &mut ow);
        prop_assert_eq!(ow.status, QpStatus::Solved);
        // perturb the cost and the sides a little (the feasible point stays feasible for the sides we widen)
        let mut qp2 = qp.clone();
        let mut rng = SplitMix64::new(seed ^ 0xABCD);
        let dg = rng.vector(n, -eps, eps) * 10.0;
        *qp2.gradient_mut() += dg;
        let mut oc = SolverOutput::new(&qp2);
        warm.solve(&qp2, &mut ow);
        cold.solve(&qp2, &mut oc);
        prop_assert_eq!(ow.status, QpStatus::Solved);
        prop_assert_eq!(oc.status, QpStatus::Solved);
        let diff = (&ow.x - &oc.x).amax();
        prop_assert!(diff < 1e-9 * (1.0 + oc.x.amax()), "diff {:e}", diff);
        prop_assert!(check_kkt(&qp2, &ow).is_satisfied(1e-10));
    }

    /// Duplicated (and scaled) equality and inequality rows: both backends still solve and agree.
    #[test]
    fn redundant_rows_do_not_change_the_answer(seed in any::<u64>(), n in 2usize..9, mi in 1usize..8, scale in 0.5f64..3.0) {
        let base = random_qp(seed, n, 1, mi);
        let dup = with_duplicated_rows(&base, scale);
        let mut ob = SolverOutput::new(&base);
        ActiveSetSolver::new(ActiveSetSettings::default()).solve(&base, &mut ob);
        prop_assert_eq!(ob.status, QpStatus::Solved);
        let mut c = ClarabelSolver::new(ClarabelSettings { tolerance: 1e-12, ..ClarabelSettings::default() });
        for s in [&mut ActiveSetSolver::new(ActiveSetSettings::default()) as &mut dyn QpSolver, &mut c] {
            let mut od = SolverOutput::new(&dup);
            s.solve(&dup, &mut od);
            prop_assert!(od.status.is_success(), "{} {:?}", s.name(), od.status);
            let diff = (&od.x - &ob.x).amax();
            prop_assert!(diff < 1e-6 * (1.0 + ob.x.amax()), "{}: diff {:e}", s.name(), diff);
            let k = check_kkt(&dup, &od);
            prop_assert!(k.is_satisfied(1e-7), "{}: {:?}", s.name(), k);
        }
    }

    #[test]
    fn never_nan(seed in any::<u64>(), n in 1usize..6, poison in 0usize..4) {
        let mut qp = random_qp(seed, n, 0, 3);
        match poison {
            0 => qp.hessian_mut()[(0, 0)] = f64::NAN,
            1 => qp.gradient_mut()[0] = f64::INFINITY,
            2 => qp.ineq_lower_mut()[0] = f64::NAN,
            _ => { qp.ineq_lower_mut()[0] = 1.0; qp.ineq_upper_mut()[0] = 0.0; }
        }
        for mut s in [Box::new(ActiveSetSolver::new(Default::default())) as Box<dyn QpSolver>, Box::new(ClarabelSolver::new(Default::default()))] {
            let mut out = SolverOutput::new(&qp);
            s.solve(&qp, &mut out);
            prop_assert_eq!(out.status, QpStatus::InvalidData);
            prop_assert!(out.x.iter().all(|v| v.is_finite()));
        }
        let _ = DVector::<f64>::zeros(1);
    }
}
