//! A tick (write task numbers + assemble + solve + residuals) allocates nothing with the active-set backend,
//! on the nominal path, with warm starts, and on the relaxed fallback path.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use stride_qp::testing::RandomWbc;
use stride_qp::{QpProblem, QpSettings, SolvePath, TaskSpec, VariableSet};

struct Counting;
static ALLOCS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn ticks_do_not_allocate() {
    // one test function so that no other test thread allocates concurrently
    let mut tsid = RandomWbc::tsid_like(1, QpSettings::default()).unwrap();
    let mut ik = RandomWbc::ik_like(1, QpSettings::default()).unwrap();
    // even the very first solve is allocation-free (workspaces are reserved in QpProblem::new)
    let before = ALLOCS.load(Ordering::SeqCst);
    tsid.problem.solve().unwrap();
    ik.problem.solve().unwrap();
    assert_eq!(
        ALLOCS.load(Ordering::SeqCst) - before,
        0,
        "allocations in the first solve"
    );
    let before = ALLOCS.load(Ordering::SeqCst);
    let mut warm = 0;
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
    let after = ALLOCS.load(Ordering::SeqCst);
    assert_eq!(after - before, 0, "allocations during nominal ticks");
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
    let before = ALLOCS.load(Ordering::SeqCst);
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
    assert_eq!(
        ALLOCS.load(Ordering::SeqCst) - before,
        0,
        "allocations on the fallback path"
    );
}
