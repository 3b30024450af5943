//! Goals the planner accepts. Serde-tagged so they can be written in TOML scenarios:
//!
//! ```toml
//! [goal]
//! type = "pose"
//! x = 2.0
//! y = 0.0
//! yaw = 0.0
//! ```
//! ```toml
//! [goal]
//! type = "waypoints"
//! points = [{ x = 1.0, y = 0.0 }, { x = 1.5, y = 0.5, yaw = 1.57 }]
//! ```
//! ```toml
//! [goal]
//! type = "velocity"
//! forward = 0.1
//! lateral = 0.0
//! yaw_rate = 0.1
//! duration = 10.0
//! ```

use serde::{Deserialize, Serialize};

use crate::error::PlannerError;

/// A waypoint of the robot's mid-feet point (world frame).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Waypoint {
    /// x \[m\].
    pub x: f64,
    /// y \[m\].
    pub y: f64,
    /// Heading \[rad\]. Only the last waypoint's heading is enforced (by turning in place at the end); the robot
    /// passes intermediate waypoints with its approach heading. `None` = keep the approach heading.
    #[serde(default)]
    pub yaw: Option<f64>,
}

/// What the robot should do.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Goal {
    /// Stand on the current feet: no step; the ZMP/DCM/CoM move to the feet mid-point and stay. Mid-walk this
    /// stops in the current stance; to stop with the feet closed parallel, send a zero velocity command.
    Stand,
    /// Walk so that the feet mid-point ends at (x, y) with heading `yaw` (world frame, m and rad).
    Pose {
        /// x \[m\].
        x: f64,
        /// y \[m\].
        y: f64,
        /// Final heading \[rad\].
        yaw: f64,
    },
    /// Walk through the waypoints in order (world frame).
    Waypoints {
        /// The waypoints (at least one).
        points: Vec<Waypoint>,
    },
    /// Walk with a constant velocity command of the unicycle (robot frame), then stop.
    Velocity {
        /// Forward speed \[m/s\] (negative = backwards); saturated to the configured limits.
        forward: f64,
        /// Lateral speed \[m/s\] (positive = left); saturated to the configured limits.
        lateral: f64,
        /// Yaw rate \[rad/s\]; saturated to the configured limit.
        yaw_rate: f64,
        /// How long to walk \[s\]; `None` = the planning horizon.
        #[serde(default)]
        duration: Option<f64>,
    },
}

fn finite(name: String, v: f64) -> Result<(), PlannerError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(PlannerError::InvalidGoal {
            name,
            reason: format!("must be finite, got {v}"),
        })
    }
}

impl Goal {
    /// Checks the goal for NaN/infinite values, empty lists and negative durations.
    pub fn validate(&self) -> Result<(), PlannerError> {
        match self {
            Goal::Stand => Ok(()),
            Goal::Pose { x, y, yaw } => {
                finite("pose.x".into(), *x)?;
                finite("pose.y".into(), *y)?;
                finite("pose.yaw".into(), *yaw)
            }
            Goal::Waypoints { points } => {
                if points.is_empty() {
                    return Err(PlannerError::InvalidGoal {
                        name: "waypoints.points".into(),
                        reason: "needs at least one waypoint".into(),
                    });
                }
                for (i, p) in points.iter().enumerate() {
                    finite(format!("waypoints.points[{i}].x"), p.x)?;
                    finite(format!("waypoints.points[{i}].y"), p.y)?;
                    if let Some(yaw) = p.yaw {
                        finite(format!("waypoints.points[{i}].yaw"), yaw)?;
                    }
                }
                Ok(())
            }
            Goal::Velocity {
                forward,
                lateral,
                yaw_rate,
                duration,
            } => {
                finite("velocity.forward".into(), *forward)?;
                finite("velocity.lateral".into(), *lateral)?;
                finite("velocity.yaw_rate".into(), *yaw_rate)?;
                if let Some(d) = duration {
                    finite("velocity.duration".into(), *d)?;
                    if *d < 0.0 {
                        return Err(PlannerError::InvalidGoal {
                            name: "velocity.duration".into(),
                            reason: format!("must be >= 0, got {d}"),
                        });
                    }
                }
                Ok(())
            }
        }
    }
}
