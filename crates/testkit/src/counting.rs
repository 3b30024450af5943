//! [`CountingAllocator`]: a global allocator that counts allocations, so that a test can prove a `step`
//! allocates nothing after start-up (see the crate documentation for its use).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

thread_local! {
    /// Allocations (and reallocations) made by this thread through a [`CountingAllocator`] installed as
    /// the global allocator. `const`-initialised and without `Drop`, so reading it from inside the
    /// allocator never allocates and never registers a destructor.
    static THREAD_ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

/// A global allocator that forwards to [`std::alloc::System`] and counts every `alloc` and `realloc`
/// (zeroed allocations go through `alloc` and count too; deallocations are not counted).
///
/// It keeps two counts:
/// - a process-wide count over all threads, read with [`CountingAllocator::allocations`];
/// - a per-thread count, used by [`CountingAllocator::allocations_during`] to count only what the
///   calling thread allocates while a closure runs (the test harness's other threads may allocate at
///   any time without disturbing it).
///
/// Install it once per test binary with `#[global_allocator]`; the counts are meaningful only then
/// ([`CountingAllocator::allocations_during`] panics if it finds it is not installed).
#[derive(Debug)]
pub struct CountingAllocator {
    /// Allocations and reallocations by all threads since the process started.
    total: AtomicUsize,
}

impl CountingAllocator {
    /// A counting allocator with both counts at zero (`const`, for a `static`).
    pub const fn new() -> Self {
        Self {
            total: AtomicUsize::new(0),
        }
    }

    /// Number of allocations and reallocations made by all threads since the process started.
    ///
    /// Take the difference of two reads around the code under test. Other threads running at the
    /// same time are counted too: keep such a test the only `#[test]` of its binary, or use
    /// [`CountingAllocator::allocations_during`].
    pub fn allocations(&self) -> usize {
        self.total.load(Ordering::SeqCst)
    }

    /// Runs `f` and returns its result with the number of allocations and reallocations the calling
    /// thread made while `f` ran (threads spawned by `f` are not counted).
    ///
    /// # Panics
    /// If no [`CountingAllocator`] is the global allocator (a probe allocation made before `f` runs is
    /// not seen), since every count would then be a vacuous zero.
    pub fn allocations_during<R>(&self, f: impl FnOnce() -> R) -> (R, usize) {
        let probe_before = thread_allocations();
        drop(std::hint::black_box(Box::new(0_u8)));
        assert!(
            thread_allocations() > probe_before,
            "stride_testkit::CountingAllocator is not the #[global_allocator] of this test binary"
        );
        let before = thread_allocations();
        let result = f();
        let after = thread_allocations();
        (result, after - before)
    }

    fn record(&self) {
        self.total.fetch_add(1, Ordering::SeqCst);
        // `try_with` fails only while this thread's locals are being torn down: nothing to count then.
        let _ = THREAD_ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
    }
}

impl Default for CountingAllocator {
    fn default() -> Self {
        Self::new()
    }
}

/// The calling thread's count (0 if its thread locals are already torn down).
fn thread_allocations() -> usize {
    THREAD_ALLOCATIONS.try_with(Cell::get).unwrap_or(0)
}

// SAFETY: every method forwards its arguments unchanged to `System`, which upholds the `GlobalAlloc`
// contract; the bookkeeping touches only an atomic and a const-initialised, drop-free thread local, so
// it neither allocates nor unwinds.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        self.record();
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` was allocated by `System` (every allocation above forwards to it).
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        self.record();
        // SAFETY: `ptr` was allocated by `System`; the layout and size are the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}
