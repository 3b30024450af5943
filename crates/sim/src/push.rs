//! Scheduled external wrenches ("pushes") on frames of the robot.

use nalgebra::Vector6;
use stride_model::{FrameId, Model};

use crate::config::PushConfig;
use crate::error::{find_frame, SimError};

/// A push resolved against the model: a wrench on a frame during `[start, end)` (simulated time, ns).
#[derive(Clone, Debug)]
pub(crate) struct Push {
    pub(crate) frame: FrameId,
    start_ns: u64,
    end_ns: u64,
    /// `[f; τ]` on the robot, world orientation, torque about the frame origin (N, N·m).
    pub(crate) wrench: Vector6<f64>,
}

impl Push {
    /// Resolves `p`'s frame in `model`; `parameter` names the config entry in the error.
    pub(crate) fn new(model: &Model, p: &PushConfig, parameter: &str) -> Result<Self, SimError> {
        let frame = find_frame(model, parameter, &p.frame)?;
        let start_ns = secs_to_ns(p.start);
        Ok(Self {
            frame,
            start_ns,
            end_ns: start_ns + secs_to_ns(p.duration),
            wrench: Vector6::from_row_slice(&p.wrench),
        })
    }

    /// The push acts at the simulated time `t_ns`.
    pub(crate) fn is_active(&self, t_ns: u64) -> bool {
        t_ns >= self.start_ns && t_ns < self.end_ns
    }
}

/// Seconds to whole nanoseconds (rounded, negative values clamped to zero).
fn secs_to_ns(s: f64) -> u64 {
    (s * 1e9).round().max(0.0) as u64
}
