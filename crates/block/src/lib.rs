//! `stride-block`: the one interface every stride layer implements, and the vocabulary the layers
//! share: [`Foot`], [`SupportPolygon`] (with [`FootRectangle`] and [`feet_support_polygon`]).
//!
//! A layer (planner, simplified-model controller, whole-body controller, simulated robot) is a *block*:
//! it is built once from a validated configuration (`new`, where all allocation happens), then stepped
//! with plain-data inputs, returning a reference to its plain-data output. Blocks own no threads, do no
//! I/O and keep no hidden globals; the caller (usually `stride-runner`) owns clocks, scheduling and logs.
//!
//! ```
//! use stride_block::Block;
//!
//! /// A block that integrates its input with a fixed period.
//! struct Integrator { period: f64, out: f64 }
//!
//! impl Block for Integrator {
//!     type Input = f64;
//!     type Output = f64;
//!     type Error = std::convert::Infallible;
//!     fn step(&mut self, input: &f64) -> Result<&f64, Self::Error> {
//!         self.out += self.period * input;
//!         Ok(&self.out)
//!     }
//!     fn reset(&mut self) { self.out = 0.0; }
//! }
//!
//! let mut block = Integrator { period: 0.01, out: 0.0 };
//! assert_eq!(*block.step(&2.0).unwrap(), 0.02);
//! block.reset();
//! assert_eq!(*block.step(&1.0).unwrap(), 0.01);
//! ```

mod angle;
mod filter;
mod foot;
mod polygon;
mod time;

pub use angle::wrap_angle;
pub use filter::{low_pass_gain, FirstOrderLowPass};
pub use foot::Foot;
pub use polygon::{
    feet_support_polygon, FootRectangle, PolygonError, SupportPolygon, MAX_HULL_POINTS,
    MAX_POLYGON_VERTICES, MIN_POLYGON_AREA,
};
pub use time::seconds;

/// What a user of a layer needs in scope: `use stride_block::prelude::*;`.
pub mod prelude {
    pub use crate::{
        feet_support_polygon, seconds, Block, FirstOrderLowPass, Foot, FootRectangle, PolygonError,
        SupportPolygon,
    };
    pub use nalgebra;
}

/// A layer of the stack: plain data in, plain data out, no allocation after construction.
pub trait Block {
    /// Everything the block needs for one tick (measurements, references from the layer above).
    type Input;
    /// What one tick produces. Returned by reference so stepping allocates nothing.
    type Output;
    /// Why a tick failed. Errors carry context; a failed tick leaves the block in its previous state
    /// unless the block documents otherwise.
    type Error: std::error::Error;

    /// Advances the block by one tick.
    fn step(&mut self, input: &Self::Input) -> Result<&Self::Output, Self::Error>;

    /// Returns the block to the state it had right after construction.
    fn reset(&mut self);
}
