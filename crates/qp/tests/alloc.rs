//! A tick (write task numbers + assemble + solve + residuals) allocates nothing with the active-set backend,
//! on the nominal path, with warm starts, and on the relaxed fallback path.

use stride_qp::testing::RandomWbc;
use stride_qp::{QpProblem, QpSettings, SolvePath, TaskSpec, VariableSet};

#[global_allocator]
static ALLOC: stride_testkit::CountingAllocator = stride_testkit::CountingAllocator::new();

#[test]
fn ticks_do_not_allocate() {
    // one test function so that no other test thread allocates concurrently
    let mut tsid = RandomWbc::tsid_like(1, QpSettings::default()).unwrap();
    let mut ik = RandomWbc::ik_like(1, QpSettings::default()).unwrap();
    // Only this thread's allocations count (the test harness may allocate on its own threads, e.g. to
    // report a slow test: a global count made this test fail on a loaded CI machine).
    // Even the very first solve is allocation-free (workspaces are reserved in QpProblem::new).
    let (_, first) = ALLOC.allocations_during(|| {
        tsid.problem.solve().unwrap();
        ik.problem.solve().unwrap();
    });
    assert_eq!(first, 0, "allocations in the first solve");
    let mut warm = 0;
    let (_, nominal) = ALLOC.allocations_during(|| {
        for k in 1..100 {
            let t = 0.001 * k as f64;
            tsid.write(t);
            warm += tsid
                .problem
                .solve()
                .map(|s| s.warm_started as usize)
                .unwrap_or(0);
            ik.write(t);
            ik.problem.solve().unwrap();
        }
    });
    assert_eq!(nominal, 0, "allocations during nominal ticks");
    assert!(warm > 90);

    // fallback path: a hard equality alternately feasible and infeasible
    let mut vars = VariableSet::new();
    let f = vars.add("forces", 2).unwrap();
    let specs = vec![
        TaskSpec::equality("com", &[f], 1),
        TaskSpec::equality("reg", &[f], 2).soft(1.0),
    ];
    let mut p = QpProblem::new(vars, specs, QpSettings::default()).unwrap();
    let com = p.task_id("com").unwrap();
    let reg = p.task_id("reg").unwrap();
    p.task_mut(com).a_mut().fill(1.0);
    p.task_mut(reg).a_mut().fill_with_identity();
    p.upper_bounds_mut(f).fill(100.0);
    let (_, fallback) = ALLOC.allocations_during(|| {
        for k in 0..20 {
            let target = if k % 2 == 0 { 50.0 } else { 300.0 };
            p.task_mut(com).b_mut()[0] = target;
            let path = p.solve().unwrap().path;
            assert_eq!(
                path,
                if k % 2 == 0 {
                    SolvePath::Nominal
                } else {
                    SolvePath::Relaxed
                }
            );
        }
    });
    assert_eq!(fallback, 0, "allocations on the fallback path");
}
