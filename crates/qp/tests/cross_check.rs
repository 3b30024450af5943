//! Cross-checks of the two backends on WBC-shaped random problems, and KKT conditions.

use stride_qp::testing::RandomWbc;
use stride_qp::StartKind;
use stride_qp::{
    check_kkt, ActiveSetSettings, ActiveSetSolver, Backend, ClarabelSettings, ClarabelSolver,
    QpSettings, QpSolver, QpStatus, SolverOutput,
};

/// Clarabel as a *reference* runs at a tight tolerance: with the default 1e-10 its solution can differ by
/// ~1e-4 along the weakly weighted directions (weight 1e-3) of these problems, see docs/qp.md.
fn settings(backend: Backend) -> QpSettings {
    let clarabel = ClarabelSettings {
        tolerance: 1e-12,
        ..ClarabelSettings::default()
    };
    QpSettings {
        backend,
        fallback: false,
        clarabel,
        ..QpSettings::default()
    }
}

fn compare(mut a: RandomWbc, mut c: RandomWbc, label: &str) {
    for (step, t) in [0.0, 0.01, 0.02, 0.5].iter().enumerate() {
        a.write(*t);
        c.write(*t);
        let sa = a.problem.solve().unwrap().clone();
        let sc = c.problem.solve().unwrap().clone();
        assert_eq!(sa.status, QpStatus::Solved, "{label} step {step}");
        // at the 1e-12 reference tolerance clarabel occasionally stops at `AlmostSolved`
        assert!(
            sc.status.is_success(),
            "{label} step {step}: {:?}",
            sc.status
        );
        let scale = 1.0 + sc.x.amax();
        let diff = (&sa.x - &sc.x).amax();
        assert!(
            diff <= 1e-6 * scale,
            "{label} step {step}: |x_as - x_cl| = {diff:e}"
        );
        let obj_scale = 1.0 + sc.objective.abs();
        assert!(
            (sa.objective - sc.objective).abs() <= 1e-7 * obj_scale,
            "{label}: objectives"
        );
        let ka = a.problem.check_kkt();
        let kc = c.problem.check_kkt();
        // active set: exact up to round-off; clarabel: to its 1e-9 tolerance
        assert!(
            ka.is_satisfied(1e-10),
            "{label} step {step}: active-set KKT {ka:?}"
        );
        assert!(
            kc.is_satisfied(1e-6),
            "{label} step {step}: clarabel KKT {kc:?}"
        );
        assert!(
            sa.hard_violation <= 1e-8 * scale,
            "{label}: hard violation {}",
            sa.hard_violation
        );
    }
}

#[test]
fn tsid_like_backends_agree_and_satisfy_kkt() {
    for seed in 0..8 {
        let a = RandomWbc::tsid_like(seed, settings(Backend::ActiveSet)).unwrap();
        let c = RandomWbc::tsid_like(seed, settings(Backend::Clarabel)).unwrap();
        compare(a, c, &format!("tsid seed {seed}"));
    }
}

#[test]
fn ik_like_backends_agree_and_satisfy_kkt() {
    for seed in 0..8 {
        let a = RandomWbc::ik_like(seed, settings(Backend::ActiveSet)).unwrap();
        let c = RandomWbc::ik_like(seed, settings(Backend::Clarabel)).unwrap();
        compare(a, c, &format!("ik seed {seed}"));
    }
}

#[test]
fn warm_start_gives_the_cold_answer() {
    for seed in 0..5 {
        let mut warm = RandomWbc::tsid_like(seed, settings(Backend::ActiveSet)).unwrap();
        let mut cold_settings = settings(Backend::ActiveSet);
        cold_settings.active_set = ActiveSetSettings {
            warm_start: false,
            ..ActiveSetSettings::default()
        };
        let mut cold = RandomWbc::tsid_like(seed, cold_settings).unwrap();
        let mut warm_used = 0;
        for k in 0..30 {
            let t = 0.002 * k as f64;
            warm.write(t);
            cold.write(t);
            let sw = warm.problem.solve().unwrap().clone();
            let sc = cold.problem.solve().unwrap().clone();
            assert!(!sc.warm_started);
            warm_used += sw.warm_started as usize;
            let diff = (&sw.x - &sc.x).amax();
            assert!(
                diff <= 1e-8 * (1.0 + sc.x.amax()),
                "seed {seed} tick {k}: {diff:e}"
            );
            assert!(warm.problem.check_kkt().is_satisfied(1e-10));
        }
        assert!(
            warm_used >= 25,
            "warm start used in only {warm_used} of 30 ticks"
        );
    }
}

#[test]
fn warm_start_stages_are_all_exercised_and_exact() {
    // Large jumps in t change the active set: the guess fails and the re-imposed path must take over.
    let mut p = RandomWbc::tsid_like(3, settings(Backend::ActiveSet)).unwrap();
    p.problem.solve().unwrap();
    let mut solver = ActiveSetSolver::new(ActiveSetSettings::default());
    let mut cold = ActiveSetSolver::new(ActiveSetSettings {
        warm_start: false,
        ..ActiveSetSettings::default()
    });
    let mut seen = std::collections::HashSet::new();
    for k in 0..40 {
        let t = if k % 4 == 0 {
            0.7 * k as f64
        } else {
            0.7 * (k - k % 4) as f64 + 1e-3 * (k % 4) as f64
        };
        p.write(t);
        p.problem.solve().unwrap();
        let qp = p.problem.dense_qp().clone();
        let mut ow = SolverOutput::new(&qp);
        let mut oc = SolverOutput::new(&qp);
        solver.solve(&qp, &mut ow);
        cold.solve(&qp, &mut oc);
        assert_eq!(ow.status, QpStatus::Solved);
        seen.insert(format!("{:?}", solver.last_start()));
        assert!(
            (&ow.x - &oc.x).amax() < 1e-8 * (1.0 + oc.x.amax()),
            "tick {k}"
        );
        assert!(check_kkt(&qp, &ow).is_satisfied(1e-10));
    }
    for kind in [StartKind::Cold, StartKind::Guess, StartKind::Reimposed] {
        assert!(
            seen.contains(&format!("{kind:?}")),
            "{kind:?} never used: {seen:?}"
        );
    }
}

#[test]
fn bound_heavy_ik_guess_path_is_exact() {
    // IK-like: ~20 active bounds, so the guess path eliminates the fixed variables.
    let mut p = RandomWbc::ik_like(9, settings(Backend::ActiveSet)).unwrap();
    let mut warm = ActiveSetSolver::new(ActiveSetSettings::default());
    let mut cold = ActiveSetSolver::new(ActiveSetSettings {
        warm_start: false,
        ..ActiveSetSettings::default()
    });
    let mut guesses = 0;
    for k in 0..50 {
        p.write(1e-3 * k as f64);
        p.problem.solve().unwrap();
        let qp = p.problem.dense_qp().clone();
        let mut ow = SolverOutput::new(&qp);
        let mut oc = SolverOutput::new(&qp);
        warm.solve(&qp, &mut ow);
        cold.solve(&qp, &mut oc);
        assert_eq!(ow.status, QpStatus::Solved);
        guesses += (warm.last_start() == StartKind::Guess) as usize;
        assert!(
            (&ow.x - &oc.x).amax() < 1e-9 * (1.0 + oc.x.amax()),
            "tick {k}"
        );
        let kkt = check_kkt(&qp, &ow);
        assert!(kkt.is_satisfied(1e-10), "tick {k}: {kkt:?}");
        // multipliers of the bounds agree with the cold solve (unique under LICQ)
        let dw = (&ow.bound_multipliers - &oc.bound_multipliers).amax();
        assert!(
            dw < 1e-7 * (1.0 + oc.bound_multipliers.amax()),
            "tick {k}: {dw:e}"
        );
    }
    assert!(warm.active_set_size() > 12, "bounds should be active");
    assert!(guesses >= 45, "guess accepted on {guesses} of 50 ticks");
}

#[test]
fn iteration_limit_is_reported() {
    let mut s = settings(Backend::ActiveSet);
    s.active_set.max_iterations = 3;
    s.active_set.warm_start = false;
    let mut p = RandomWbc::tsid_like(0, s).unwrap();
    let err = p.problem.solve().unwrap_err();
    assert_eq!(
        err,
        stride_qp::QpError::SolveFailed {
            nominal: QpStatus::MaxIterations,
            relaxed: None
        }
    );
    assert!(p.problem.solution().x.iter().all(|v| *v == 0.0));
}

#[test]
fn raw_backends_on_dense_qp() {
    let mut p = RandomWbc::ik_like(42, settings(Backend::ActiveSet)).unwrap();
    p.problem.solve().unwrap();
    let qp = p.problem.dense_qp().clone();
    let mut a = ActiveSetSolver::new(ActiveSetSettings::default());
    let mut c = ClarabelSolver::new(Default::default());
    let mut oa = SolverOutput::new(&qp);
    let mut oc = SolverOutput::new(&qp);
    a.solve(&qp, &mut oa);
    c.solve(&qp, &mut oc);
    assert_eq!(oa.status, QpStatus::Solved);
    assert_eq!(oc.status, QpStatus::Solved);
    assert!((&oa.x - &oc.x).amax() < 1e-6);
    assert!(check_kkt(&qp, &oa).is_satisfied(1e-10));
    // multipliers agree too (unique here: LICQ holds for random data)
    assert!(
        (oa.bound_multipliers.clone() - oc.bound_multipliers.clone()).amax()
            < 1e-5 * (1.0 + oa.bound_multipliers.amax())
    );
    // clarabel re-solve through update_* (same layout) gives the same answer without a rebuild
    c.solve(&qp, &mut oc);
    assert_eq!(c.rebuilds(), 1);
    assert!((&oa.x - &oc.x).amax() < 1e-6);
}

/// Without the regularisation task the TSID-like Hessian is positive definite only through the default
/// Tikhonov term ρ = 1e-8 (3 base directions plus the null space of the posture/torso tasks): the active-set
/// solver must still agree with clarabel and satisfy KKT.
#[test]
fn weakly_regularised_tsid_still_agrees() {
    for weight in [1e-5, 0.0] {
        for seed in 0..4 {
            let make = |backend| {
                let mut r = RandomWbc::tsid_like(seed, settings(backend)).unwrap();
                let id = r.problem.task_id("regularization").unwrap();
                r.problem.task_mut(id).set_weight(weight).unwrap();
                r
            };
            let mut a = make(Backend::ActiveSet);
            let mut c = make(Backend::Clarabel);
            let sa = a.problem.solve().unwrap().clone();
            let sc = c.problem.solve().unwrap().clone();
            let diff = (&sa.x - &sc.x).amax();
            assert!(
                diff <= 1e-6 * (1.0 + sc.x.amax()),
                "weight {weight} seed {seed}: {diff:e}"
            );
            let k = a.problem.check_kkt();
            assert!(k.is_satisfied(1e-10), "weight {weight} seed {seed}: {k:?}");
        }
    }
}
