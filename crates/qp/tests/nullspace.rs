//! The null-space solve path ([`QpProblem::enable_null_space`]): same solutions as the full problem on
//! WBC-shaped problems whose tasks span subsets of the variables, the structure of the reduced problem,
//! and the cases that fall back to the full problem.

use stride_qp::testing::RandomWbc;
use stride_qp::{
    Backend, QpError, QpProblem, QpSettings, SolvePath, TaskSpec, VariableSet, Weight,
};

fn compare(make: fn(u64, QpSettings) -> Result<RandomWbc, QpError>, hard_rows: usize) {
    for seed in 0..8 {
        let mut full = make(seed, QpSettings::default()).unwrap();
        let mut reduced = make(seed, QpSettings::default()).unwrap();
        assert!(reduced.problem.enable_null_space().unwrap());
        let n = full.problem.n();
        for k in 0..5 {
            let t = 0.3 * k as f64;
            full.write(t);
            reduced.write(t);
            let x_full = full.problem.solve().unwrap().x.clone();
            assert_eq!(full.problem.solution().path, SolvePath::Nominal);
            let sol = reduced.problem.solve().unwrap();
            assert_eq!(sol.path, SolvePath::NullSpace, "seed {seed}, tick {k}");
            let d = (&sol.x - &x_full).amax();
            assert!(
                d < 1e-6,
                "seed {seed}, tick {k}: null-space vs full differ by {d}"
            );
            assert!(sol.hard_violation < 1e-8, "{}", sol.hard_violation);
            let last = reduced.problem.last_solved();
            assert_eq!(last.n(), n - hard_rows);
            assert!(
                last.check_kkt().max_residual() < 1e-6,
                "{:?}",
                last.check_kkt()
            );
        }
    }
}

#[test]
fn null_space_path_gives_the_full_solution_on_ik_like_problems() {
    compare(RandomWbc::ik_like, 12);
}

#[test]
fn null_space_path_gives_the_full_solution_on_tsid_like_problems() {
    compare(RandomWbc::tsid_like, 18);
}

/// `x0 + x1 = 1` hard, `x = (1, 2)` soft: the reduced problem has one variable.
/// The reduced problem's warm start (the previous active set as a guess, a cold start when it is
/// rejected): over small steps the guess is accepted on most ticks, over jumps rejected on some, and every
/// tick's solution is the one of the same reduction with the warm start off (cold starts only) and of the
/// full problem.
#[test]
fn the_reduced_problems_guess_gives_the_cold_solution_and_is_dropped_when_rejected() {
    for make in [RandomWbc::ik_like, RandomWbc::tsid_like] {
        let cold_settings = QpSettings::default();
        let mut warm_settings = QpSettings::default();
        warm_settings.active_set.reduced_guess = true;
        let mut warm = make(4, warm_settings).unwrap();
        let mut cold = make(4, cold_settings).unwrap();
        let mut full = make(4, QpSettings::default()).unwrap();
        assert!(warm.problem.enable_null_space().unwrap());
        assert!(cold.problem.enable_null_space().unwrap());
        let (mut guessed, mut ticks) = ([0; 2], [0; 2]);
        for k in 0..80 {
            // ticks 0-39: steps of 1 ms; then jumps of 0.7 (the active set changes)
            let jumps = usize::from(k >= 40);
            let t = if jumps == 0 {
                1e-3 * k as f64
            } else {
                0.7 * k as f64
            };
            for p in [&mut warm, &mut cold, &mut full] {
                p.write(t);
            }
            let x_full = full.problem.solve().unwrap().x.clone();
            let x_cold = cold.problem.solve().unwrap().x.clone();
            assert!(!cold.problem.last_solved().solution().warm_started);
            let sol = warm.problem.solve().unwrap();
            assert_eq!(sol.path, SolvePath::NullSpace, "tick {k}");
            let scale = 1.0 + x_cold.amax();
            let (dc, df) = ((&sol.x - &x_cold).amax(), (&sol.x - &x_full).amax());
            assert!(dc < 1e-9 * scale, "tick {k}: warm vs cold reduction {dc:e}");
            assert!(df < 1e-6 * scale, "tick {k}: warm reduction vs full {df:e}");
            let reduced = warm.problem.last_solved();
            assert!(reduced.check_kkt().is_satisfied(1e-10), "tick {k}");
            guessed[jumps] += usize::from(reduced.solution().warm_started);
            ticks[jumps] += 1;
        }
        // the first tick has no previous solve: a cold start
        assert!(
            guessed[0] >= 35,
            "guess accepted on {} of 40 small steps",
            guessed[0]
        );
        assert!(guessed[1] < ticks[1], "every guess accepted over the jumps");
    }
}

fn small() -> QpProblem {
    let mut vars = VariableSet::new();
    let v = vars.add("v", 2).unwrap();
    let tasks = vec![
        TaskSpec::equality("track", &[v], 2).soft(1.0),
        TaskSpec::equality("sum", &[v], 1),
    ];
    let mut qp = QpProblem::new(vars, tasks, QpSettings::default()).unwrap();
    let track = qp.task_id("track").unwrap();
    let sum = qp.task_id("sum").unwrap();
    qp.task_mut(track).a_mut().fill_with_identity();
    qp.task_mut(track).b_mut().copy_from_slice(&[1.0, 2.0]);
    let d = qp.task_mut(sum).data_mut();
    d.a.fill(1.0);
    d.b[0] = 1.0;
    qp
}

#[test]
fn rank_deficient_or_switched_hard_rows_and_infeasible_reductions_take_the_full_path() {
    let mut qp = small();
    assert!(qp.enable_null_space().unwrap());
    let sol = qp.solve().unwrap();
    assert_eq!(sol.path, SolvePath::NullSpace);
    assert!((sol.x[0] - 0.0).abs() < 1e-6 && (sol.x[1] - 1.0).abs() < 1e-6);
    assert_eq!(qp.last_solved().n(), 1);
    // a zero hard row is rank deficient: the full problem (infeasible 0 = 1, relaxed fallback) solves it
    let sum = qp.task_id("sum").unwrap();
    qp.task_mut(sum).a_mut().fill(0.0);
    let sol = qp.solve().unwrap();
    assert_eq!(sol.path, SolvePath::Relaxed);
    assert_eq!(qp.last_solved().n(), 2);
    // back to full rank, then the hard task made soft: the reduction no longer matches
    qp.task_mut(sum).a_mut().fill(1.0);
    assert_eq!(qp.solve().unwrap().path, SolvePath::NullSpace);
    qp.task_mut(sum).set_hard(false).unwrap();
    assert_eq!(qp.solve().unwrap().path, SolvePath::Nominal);
    qp.task_mut(sum).set_hard(true).unwrap();
    // bounds that exclude the hard line's solutions: the reduced problem is infeasible, so is the full one,
    // whose relaxed fallback answers
    let v = qp.variables().id("v").unwrap();
    qp.upper_bounds_mut(v).fill(0.0);
    let sol = qp.solve().unwrap();
    assert_eq!(sol.path, SolvePath::Relaxed);
}

#[test]
fn null_space_path_is_only_for_the_active_set_backend_and_needs_hard_rows() {
    let mut vars = VariableSet::new();
    let v = vars.add("v", 2).unwrap();
    let settings = QpSettings {
        backend: Backend::Clarabel,
        ..QpSettings::default()
    };
    let tasks = vec![TaskSpec::equality("sum", &[v], 1)];
    let mut qp = QpProblem::new(vars.clone(), tasks.clone(), settings).unwrap();
    assert!(!qp.enable_null_space().unwrap());
    let soft_only = vec![TaskSpec::equality("track", &[v], 2).soft(1.0)];
    let mut qp = QpProblem::new(vars.clone(), soft_only, QpSettings::default()).unwrap();
    assert!(!qp.enable_null_space().unwrap());
    let too_many = vec![TaskSpec::equality("pin", &[v], 2)];
    let mut qp = QpProblem::new(vars, too_many, QpSettings::default()).unwrap();
    assert!(!qp.enable_null_space().unwrap());
}

#[test]
fn a_weight_on_a_hard_task_is_an_error_naming_it() {
    let mut vars = VariableSet::new();
    let v = vars.add("v", 2).unwrap();
    let hard_with_weight = TaskSpec::equality("feet", &[v], 2).soft(3.0).hard();
    let err = QpProblem::new(vars.clone(), vec![hard_with_weight], QpSettings::default())
        .err()
        .unwrap();
    assert_eq!(
        err,
        QpError::WeightOnHardTask {
            task: "feet".into()
        }
    );
    // soft tasks take the configuration's type, scalar or per row
    let per_row = TaskSpec::equality("track", &[v], 2).soft_weight(Weight::PerRow(vec![1.0, 4.0]));
    let qp = QpProblem::new(vars.clone(), vec![per_row], QpSettings::default()).unwrap();
    assert_eq!(qp.tasks()[0].weights().as_slice(), &[1.0, 4.0]);
    let scalar = TaskSpec::equality("track", &[v], 2).soft_weight(Weight::Scalar(2.0));
    let qp = QpProblem::new(vars, vec![scalar], QpSettings::default()).unwrap();
    assert_eq!(qp.tasks()[0].weights().as_slice(), &[2.0, 2.0]);
}

#[test]
fn weights_parse_from_a_scalar_or_a_list() {
    #[derive(serde::Deserialize)]
    struct T {
        weight: Weight,
    }
    let s: T = toml::from_str("weight = 5.0").unwrap();
    assert_eq!(s.weight, Weight::Scalar(5.0));
    let l: T = toml::from_str("weight = [1.0, 2.0]").unwrap();
    assert_eq!(l.weight, Weight::PerRow(vec![1.0, 2.0]));
    assert!(toml::from_str::<T>("weight = \"heavy\"").is_err());
    assert!(Weight::Scalar(-1.0).validate("t", 3).is_err());
    assert!(Weight::PerRow(vec![1.0; 2]).validate("t", 3).is_err());
    assert!(Weight::PerRow(vec![1.0; 3]).validate("t", 3).is_ok());
}
