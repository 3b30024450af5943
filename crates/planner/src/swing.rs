//! Swing-foot trajectories (thesis §10.2.2, App. D–E): minimum-jerk quintics on R³ (with an apex knot for
//! the height) and a minimum-jerk geodesic on SO(3).

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3, Vector6};
use serde::{Deserialize, Serialize};

use crate::contacts::Foot;

/// Coefficients a0..a5 of a quintic in local time τ.
pub type Quintic = [f64; 6];

/// Quintic through (x0, v0, a0) at τ = 0 and (x1, v1, a1) at τ = δ (thesis (D.3.6)).
pub fn quintic(x0: f64, v0: f64, a0: f64, x1: f64, v1: f64, a1: f64, delta: f64) -> Quintic {
    let d = delta;
    let d2 = d * d;
    let d3 = d2 * d;
    let d4 = d3 * d;
    let d5 = d4 * d;
    [
        x0,
        v0,
        0.5 * a0,
        -(20.0 * x0 - 20.0 * x1 + 12.0 * d * v0 + 8.0 * d * v1 + 3.0 * d2 * a0 - d2 * a1)
            / (2.0 * d3),
        (30.0 * x0 - 30.0 * x1 + 16.0 * d * v0 + 14.0 * d * v1 + 3.0 * d2 * a0 - 2.0 * d2 * a1)
            / (2.0 * d4),
        -(12.0 * x0 - 12.0 * x1 + 6.0 * d * v0 + 6.0 * d * v1 + d2 * a0 - d2 * a1) / (2.0 * d5),
    ]
}

/// Value, first, second and third derivative of a quintic at τ.
pub fn eval_quintic(c: &Quintic, t: f64) -> [f64; 4] {
    let p = ((((c[5] * t + c[4]) * t + c[3]) * t + c[2]) * t + c[1]) * t + c[0];
    let v = (((5.0 * c[5] * t + 4.0 * c[4]) * t + 3.0 * c[3]) * t + 2.0 * c[2]) * t + c[1];
    let a = ((20.0 * c[5] * t + 12.0 * c[4]) * t + 6.0 * c[3]) * t + 2.0 * c[2];
    let j = (60.0 * c[5] * t + 24.0 * c[4]) * t + 6.0 * c[3];
    [p, v, a, j]
}

/// Position, velocity, acceleration of the minimum-jerk blend s(u) = 10u³ − 15u⁴ + 6u⁵ with u = τ/T
/// (derivatives with respect to τ).
pub fn min_jerk_blend(tau: f64, duration: f64) -> [f64; 3] {
    let u = (tau / duration).clamp(0.0, 1.0);
    let u2 = u * u;
    let u3 = u2 * u;
    let s = u3 * (10.0 - 15.0 * u + 6.0 * u2);
    let ds = 30.0 * u2 * (1.0 - u) * (1.0 - u) / duration;
    let dds = 60.0 * u * (1.0 - u) * (1.0 - 2.0 * u) / (duration * duration);
    [s, ds, dds]
}

/// State of a foot at one instant (world frame, mixed representation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FootState {
    /// Sole pose in the world.
    pub pose: Isometry3<f64>,
    /// Mixed twist [linear velocity of the sole origin; angular velocity], world orientation.
    pub twist: Vector6<f64>,
    /// Mixed acceleration [linear; angular], world orientation.
    pub acceleration: Vector6<f64>,
}

/// One swing of one foot from `start` (lift-off at `lift_time`) to `end` (touch-down at `land_time`).
///
/// Horizontal position: one minimum-jerk quintic with zero velocity and acceleration at both ends.
/// Height: two quintics joined at the apex (`apex_time`, height `apex_height`, zero vertical velocity),
/// with the apex acceleration chosen so that the jerk is continuous there; lift-off velocity 0, touch-down
/// vertical velocity `landing_velocity`, zero accelerations at both ends. Orientation: the SO(3) geodesic
/// `R(t) = Exp(s(t) Log(R_end R_startᵀ)) R_start` with the minimum-jerk blend s (thesis (10.2.12), (10.2.16)).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SwingTrajectory {
    /// Which foot swings.
    pub foot: Foot,
    /// Pose at lift-off.
    pub start: Isometry3<f64>,
    /// Pose at touch-down.
    pub end: Isometry3<f64>,
    /// Lift-off time [s].
    pub lift_time: f64,
    /// Apex time [s].
    pub apex_time: f64,
    /// Touch-down time [s].
    pub land_time: f64,
    /// Apex height (world z) [m].
    pub apex_height: f64,
    /// Vertical velocity at touch-down [m/s].
    pub landing_velocity: f64,
    x: Quintic,
    y: Quintic,
    z_up: Quintic,
    z_down: Quintic,
    rotation_log: Vector3<f64>,
}

impl SwingTrajectory {
    /// Builds the swing. `lift_time < land_time`, `0 < apex_fraction < 1` are the caller's contract.
    pub fn new(
        foot: Foot,
        start: Isometry3<f64>,
        end: Isometry3<f64>,
        lift_time: f64,
        land_time: f64,
        swing_height: f64,
        apex_fraction: f64,
        landing_velocity: f64,
    ) -> Self {
        let duration = land_time - lift_time;
        let p0 = start.translation.vector;
        let p1 = end.translation.vector;
        let x = quintic(p0.x, 0.0, 0.0, p1.x, 0.0, 0.0, duration);
        let y = quintic(p0.y, 0.0, 0.0, p1.y, 0.0, 0.0, duration);
        let apex_height = p0.z.max(p1.z) + swing_height;
        let d1 = apex_fraction * duration;
        let d2 = duration - d1;
        // jerk continuity at the apex: jerk_end(up, a) = jerk_start(down, a), both affine in a.
        let jerk_gap = |a: f64| {
            let up = quintic(p0.z, 0.0, 0.0, apex_height, 0.0, a, d1);
            let down = quintic(apex_height, 0.0, a, p1.z, landing_velocity, 0.0, d2);
            eval_quintic(&up, d1)[3] - eval_quintic(&down, 0.0)[3]
        };
        let g0 = jerk_gap(0.0);
        let g1 = jerk_gap(1.0);
        let slope = g1 - g0;
        let apex_acc = if slope.abs() > 1e-12 && (g0 / slope).is_finite() {
            -g0 / slope
        } else {
            0.0
        };
        let z_up = quintic(p0.z, 0.0, 0.0, apex_height, 0.0, apex_acc, d1);
        let z_down = quintic(apex_height, 0.0, apex_acc, p1.z, landing_velocity, 0.0, d2);
        let rotation_log = (end.rotation * start.rotation.inverse()).scaled_axis();
        Self {
            foot,
            start,
            end,
            lift_time,
            apex_time: lift_time + d1,
            land_time,
            apex_height,
            landing_velocity,
            x,
            y,
            z_up,
            z_down,
            rotation_log,
        }
    }

    /// Pose, twist and acceleration at time `t` (clamped to [lift_time, land_time]).
    pub fn evaluate(&self, t: f64) -> FootState {
        let duration = self.land_time - self.lift_time;
        let tau = (t - self.lift_time).clamp(0.0, duration);
        let x = eval_quintic(&self.x, tau);
        let y = eval_quintic(&self.y, tau);
        let d1 = self.apex_time - self.lift_time;
        let z = if tau <= d1 {
            eval_quintic(&self.z_up, tau)
        } else {
            eval_quintic(&self.z_down, tau - d1)
        };
        let [s, ds, dds] = min_jerk_blend(tau, duration);
        let rotation = UnitQuaternion::from_scaled_axis(self.rotation_log * s) * self.start.rotation;
        let omega = self.rotation_log * ds;
        let omega_dot = self.rotation_log * dds;
        FootState {
            pose: Isometry3::from_parts(Translation3::new(x[0], y[0], z[0]), rotation),
            twist: Vector6::new(x[1], y[1], z[1], omega.x, omega.y, omega.z),
            acceleration: Vector6::new(x[2], y[2], z[2], omega_dot.x, omega_dot.y, omega_dot.z),
        }
    }
}
