//! # stride-walking
//!
//! The walking stack as a library: the functions that connect stride's layers, used by `stride-runner`
//! and by any controller that embeds the layers without it. Each layer stays usable on its own; this
//! crate holds only the rules that chain them (estimated state + feet wrenches → measured CoM, DCM and
//! ZMP; plan sample → simplified-layer input; simplified output + plan → whole-body input).

mod heading;
mod measure;
mod plan_clock;
mod simplified_input;
pub mod wbc_input;

pub use heading::soles_heading;
pub use measure::{feet_zmp, CentroidalMeter, MEASURED_ZMP_CUTOFF, MIN_ZMP_LOAD};
pub use plan_clock::{scale_plan_sample, PlanClock};
pub use simplified_input::{
    is_walking, support_polygon, MeasuredCentroidal, SimplifiedInputBuilder, SimplifiedInputError,
};
pub use wbc_input::{
    apply_foot_admittance, fill_wbc_input, walking_input, walking_layout, WalkingHandles,
};

/// What a controller that chains the layers needs from this crate: `use stride_walking::prelude::*;`.
pub mod prelude {
    pub use crate::{
        apply_foot_admittance, fill_wbc_input, is_walking, soles_heading, support_polygon,
        walking_input, walking_layout, CentroidalMeter, MeasuredCentroidal, SimplifiedInputBuilder,
        SimplifiedInputError, WalkingHandles, MEASURED_ZMP_CUTOFF,
    };
    pub use stride_block::FirstOrderLowPass;
}
