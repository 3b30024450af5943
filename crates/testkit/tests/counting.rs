//! The counts of an installed `CountingAllocator` match allocations whose number is known by
//! construction: exact per-thread counts, other threads excluded from them, included in the total.

use std::hint::black_box;
use std::sync::{Arc, Barrier};

use stride_testkit::CountingAllocator;

#[global_allocator]
static ALLOC: CountingAllocator = CountingAllocator::new();

#[test]
fn counts_are_exact_and_per_thread() {
    // nothing allocated: zero
    let (sum, n) = ALLOC.allocations_during(|| black_box(2_u64) + 3);
    assert_eq!((sum, n), (5, 0));

    // ten boxes: ten allocations (their frees are not counted)
    let ((), n) = ALLOC.allocations_during(|| {
        for k in 0..10_u64 {
            drop(black_box(Box::new(k)));
        }
    });
    assert_eq!(n, 10);

    // one allocation, then growth beyond the capacity is one reallocation
    let (v, n) = ALLOC.allocations_during(|| {
        let mut v: Vec<u64> = Vec::with_capacity(1);
        v.push(1);
        v.reserve_exact(7);
        black_box(v)
    });
    assert_eq!((v.capacity() >= 8, n), (true, 2));

    // another thread's 100 allocations are in the process-wide total, not in this thread's count
    let start = Arc::new(Barrier::new(2));
    let done = Arc::new(Barrier::new(2));
    let worker = {
        let (start, done) = (Arc::clone(&start), Arc::clone(&done));
        std::thread::spawn(move || {
            start.wait();
            for k in 0..100_u64 {
                drop(black_box(Box::new(k)));
            }
            done.wait();
        })
    };
    let total_before = ALLOC.allocations();
    let ((), n) = ALLOC.allocations_during(|| {
        start.wait();
        done.wait();
    });
    let total_after = ALLOC.allocations();
    worker.join().unwrap();
    assert_eq!(n, 0);
    assert!(total_after - total_before >= 100);
}
