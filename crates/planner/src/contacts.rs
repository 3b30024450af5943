//! Contacts as data: planned contacts per foot with time queries, and the gait phase list.

use nalgebra::Isometry3;
use serde::{Deserialize, Serialize};

pub use stride_block::Foot;

/// A planned contact: the foot stands at `pose` (sole frame, world) from `activation_time` to
/// `deactivation_time` (seconds of plan time; `None` = never lifted again within this plan).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlannedContact {
    /// Which foot.
    pub foot: Foot,
    /// Sole pose in the world.
    pub pose: Isometry3<f64>,
    /// Touch-down time \[s\].
    pub activation_time: f64,
    /// Lift-off time \[s\]; `None` = stays until the end of the plan (and after).
    pub deactivation_time: Option<f64>,
}

impl PlannedContact {
    /// Whether the contact is active at `t` (activation ≤ t < deactivation).
    pub fn is_active_at(&self, t: f64) -> bool {
        t >= self.activation_time && self.deactivation_time.is_none_or(|d| t < d)
    }
}

/// The time-ordered contacts of one foot.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ContactList {
    /// Which foot.
    pub foot: Foot,
    /// Contacts sorted by activation time, non-overlapping.
    pub contacts: Vec<PlannedContact>,
}

impl ContactList {
    /// The contact active at `t`, if the foot is on the ground then. O(log n), no allocation.
    pub fn active_at(&self, t: f64) -> Option<&PlannedContact> {
        let i = self.contacts.partition_point(|c| c.activation_time <= t);
        if i == 0 {
            return None;
        }
        let c = &self.contacts[i - 1];
        c.is_active_at(t).then_some(c)
    }

    /// The first contact activated strictly after `t`.
    pub fn next_after(&self, t: f64) -> Option<&PlannedContact> {
        let i = self.contacts.partition_point(|c| c.activation_time <= t);
        self.contacts.get(i)
    }

    /// The last contact activated at or before `t` (active or already lifted).
    pub fn last_before(&self, t: f64) -> Option<&PlannedContact> {
        let i = self.contacts.partition_point(|c| c.activation_time <= t);
        if i == 0 {
            None
        } else {
            Some(&self.contacts[i - 1])
        }
    }
}

/// Kind of gait phase.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum PhaseKind {
    /// Both feet on the ground.
    DoubleSupport,
    /// One foot on the ground.
    SingleSupport {
        /// The foot on the ground.
        stance: Foot,
    },
}

/// A gait phase over `[start, end)` (seconds of plan time).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Phase {
    /// Which phase.
    pub kind: PhaseKind,
    /// Start \[s\].
    pub start: f64,
    /// End \[s\].
    pub end: f64,
}
