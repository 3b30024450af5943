//! The one foot vocabulary of stride's walking layers.

use serde::{Deserialize, Serialize};

/// A foot of a biped. The planner's footsteps, the step adjustment's stance foot and the centroidal
/// MPC's contacts all use it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Foot {
    /// Left foot.
    Left,
    /// Right foot.
    Right,
}

impl Foot {
    /// The other foot.
    pub fn other(self) -> Foot {
        match self {
            Foot::Left => Foot::Right,
            Foot::Right => Foot::Left,
        }
    }

    /// `"left"` or `"right"`.
    pub fn name(self) -> &'static str {
        match self {
            Foot::Left => "left",
            Foot::Right => "right",
        }
    }

    /// +1 for left, −1 for right (the foot's lateral side in a frame with y to the left).
    pub fn side(self) -> f64 {
        match self {
            Foot::Left => 1.0,
            Foot::Right => -1.0,
        }
    }

    /// 0 for left, 1 for right: the index of the foot in `[left, right]` arrays.
    pub fn index(self) -> usize {
        match self {
            Foot::Left => 0,
            Foot::Right => 1,
        }
    }
}
