//! A tick of the QP-IK and of the TSID allocates nothing (counting global allocator).

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

use common::*;
use nalgebra::Vector2;
use stride_block::Block;
use stride_qp::Backend;
use stride_wbc::{IkConfig, QpIk, Tsid, TsidConfig};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);
thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.with(|c| c.get()) {
            ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if COUNTING.with(|c| c.get()) {
            ALLOCATIONS.fetch_add(1, Ordering::SeqCst);
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn count<R>(f: impl FnOnce() -> R) -> (R, usize) {
    let before = ALLOCATIONS.load(Ordering::SeqCst);
    COUNTING.with(|c| c.set(true));
    let r = f();
    COUNTING.with(|c| c.set(false));
    (r, ALLOCATIONS.load(Ordering::SeqCst) - before)
}

#[test]
fn ik_and_tsid_ticks_allocate_nothing() {
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let mut input = references_at(&model, &state);
    input.com_position.x += 0.01;

    let mut ik = QpIk::new(Arc::clone(&model), IkConfig::default_for_bundled_model()).unwrap();
    ik.step(&input).unwrap();
    let (_, n) = count(|| {
        for _ in 0..20 {
            assert!(ik.step(&input).unwrap().report.status.is_success());
        }
    });
    assert_eq!(n, 0, "QP-IK ticks allocated {n} times");

    let mut tsid = Tsid::new(Arc::clone(&model), TsidConfig::default_for_bundled_model()).unwrap();
    tsid.step(&input).unwrap();
    let (_, n) = count(|| {
        for _ in 0..20 {
            assert!(tsid.step(&input).unwrap().report.status.is_success());
        }
    });
    assert_eq!(n, 0, "TSID ticks allocated {n} times");
    // a contact change (another prebuilt QP, first solve of that QP included) and a ZMP task
    input.right_in_contact = false;
    input.desired_zmp = Some(Vector2::new(input.com_position.x, input.com_position.y));
    let (_, n) = count(|| {
        for _ in 0..100 {
            assert!(tsid.step(&input).unwrap().report.status.is_success());
        }
    });
    assert_eq!(n, 0, "TSID ticks across a lift-off allocated {n} times");
}

#[test]
fn clarabel_ticks_are_reported_not_asserted() {
    // clarabel builds its solver per solve (allocates); only check the ticks work with it
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let input = references_at(&model, &state);
    let mut c = IkConfig::default_for_bundled_model();
    c.qp.backend = Backend::Clarabel;
    let mut ik = QpIk::new(Arc::clone(&model), c).unwrap();
    assert!(ik.step(&input).unwrap().report.status.is_success());
}
