//! Without `#[global_allocator]`, `allocations_during` refuses to report a vacuous zero.

use stride_testkit::CountingAllocator;

#[test]
#[should_panic(expected = "is not the #[global_allocator]")]
fn uninstalled_allocator_panics() {
    let alloc = CountingAllocator::new();
    let _ = alloc.allocations_during(|| 0);
}
