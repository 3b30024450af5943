//! Test-only helpers shared by the stride crates' integration tests.
//!
//! - [`CountingAllocator`], a global allocator that counts allocations so that a test can prove a `step`
//!   allocates nothing after start-up:
//!
//! ```ignore
//! #[global_allocator]
//! static ALLOC: stride_testkit::CountingAllocator = stride_testkit::CountingAllocator::new();
//!
//! #[test]
//! fn step_does_not_allocate() {
//!     let mut block = make_block();
//!     // only this thread's allocations while the closure runs:
//!     let (_, n) = ALLOC.allocations_during(|| block.step(&input).unwrap());
//!     assert_eq!(n, 0);
//!     // or every thread's allocations between two reads:
//!     let before = ALLOC.allocations();
//!     block.step(&input).unwrap();
//!     assert_eq!(ALLOC.allocations() - before, 0);
//! }
//! ```
//!
//! - [`icub_model_urdf`] and [`icub_models_dir`], the one rule for the tests that need the official iCub
//!   URDFs (not committed; `STRIDE_ICUB_MODELS_DIR`): skipped, loudly, when the variable is unset; failed
//!   when it is set and the models are not there; a marker line when they run, which `.ci/run` counts so
//!   that CI fails when an iCub test silently did not run:
//!
//! ```ignore
//! #[test]
//! fn icub_walks() {
//!     let Some(urdf) = stride_testkit::icub_model_urdf("icub_walks", "iCubGazeboV2_7") else {
//!         return; // STRIDE_ICUB_MODELS_DIR unset: the skip is printed
//!     };
//!     // ... the test, on `urdf`; "STRIDE-ICUB-TEST-RAN icub_walks" was printed
//! }
//! ```
//!
//! - [`thread_cpu_time`], the calling thread's CPU time (`CLOCK_THREAD_CPUTIME_ID`), for timings that must
//!   hold on a loaded machine (`crates/model/examples/cpu_timings.rs`).
//!
//! - [`ft_offset_error_bound`], the error bound of an FT offset estimated from a pole log, shared by the
//!   calibration tests on stride-sim and on MuJoCo.
//!
//! This crate is a dev-dependency only; it is never published.

mod counting;
mod cpu_time;
mod ft_offsets;
mod icub;

pub use counting::CountingAllocator;
pub use cpu_time::thread_cpu_time;
pub use ft_offsets::{ft_offset_error_bound, FT_OFFSET_PIPELINE_ERROR};
pub use icub::{
    icub_model_urdf, icub_models_dir, resolve_icub_model_urdf, resolve_icub_models_dir,
    IcubModelsError, ICUB_MODELS_DIR_VAR, ICUB_TEST_RAN_MARKER, ICUB_TEST_SKIPPED_MARKER,
};
