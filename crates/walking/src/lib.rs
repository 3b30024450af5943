//! # stride-walking
//!
//! The walking stack as a library: the functions that connect stride's layers, used by `stride-runner`
//! and by any controller that embeds the layers without it. Each layer stays usable on its own; this
//! crate holds only the rules that chain them (plan sample → simplified-layer input, simplified output +
//! plan → whole-body input).

mod heading;
mod simplified_input;
pub mod wbc_input;

pub use heading::soles_heading;
pub use simplified_input::{
    is_walking, support_polygon, MeasuredCentroidal, SimplifiedInputBuilder, SimplifiedInputError,
};
pub use wbc_input::{fill_wbc_input, walking_input, walking_layout, WalkingHandles};
