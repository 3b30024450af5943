//! Swing-foot trajectories [Romualdi 2022, §10.2.2, App. D–E]: minimum-jerk quintics on R³ (with an apex knot for
//! the height) and a minimum-jerk geodesic on SO(3).

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3, Vector6};
use serde::{Deserialize, Serialize};

use std::f64::consts::FRAC_PI_2;

use nalgebra::Vector2;
use stride_block::SupportPolygon;

use crate::contacts::Foot;
use crate::geometry::{wrap_angle, Pose2};
use crate::verify::quadrilaterals_intersect;

/// Coefficients a0..a5 of a quintic in local time τ.
pub type Quintic = [f64; 6];

/// Quintic through (x0, v0, a0) at τ = 0 and (x1, v1, a1) at τ = δ [Romualdi 2022, eq. D.3.6].
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

/// Minimum and maximum of a quintic over [0, δ]: end points and the roots of its derivative (found by sign
/// changes on a 64-interval grid refined by bisection).
pub fn quintic_range(c: &Quintic, delta: f64) -> (f64, f64) {
    let mut lo = eval_quintic(c, 0.0)[0].min(eval_quintic(c, delta)[0]);
    let mut hi = eval_quintic(c, 0.0)[0].max(eval_quintic(c, delta)[0]);
    const N: usize = 64;
    let mut t0 = 0.0;
    let mut v0 = eval_quintic(c, 0.0)[1];
    for i in 1..=N {
        let t1 = delta * i as f64 / N as f64;
        let v1 = eval_quintic(c, t1)[1];
        if v0 * v1 < 0.0 {
            let (mut a, mut b, mut va) = (t0, t1, v0);
            for _ in 0..60 {
                let m = 0.5 * (a + b);
                let vm = eval_quintic(c, m)[1];
                if va * vm <= 0.0 {
                    b = m;
                } else {
                    a = m;
                    va = vm;
                }
            }
            let x = eval_quintic(c, 0.5 * (a + b))[0];
            lo = lo.min(x);
            hi = hi.max(x);
        }
        // also the grid values, in case of a double root
        let x = eval_quintic(c, t1)[0];
        lo = lo.min(x);
        hi = hi.max(x);
        t0 = t1;
        v0 = v1;
    }
    (lo, hi)
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

/// Shape parameters of a swing.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SwingShape {
    /// Apex height above the higher foothold \[m\].
    pub height: f64,
    /// Apex time as a fraction of the swing duration, in (0, 1).
    pub apex_fraction: f64,
    /// Vertical velocity at touch-down \[m/s\].
    pub landing_velocity: f64,
}

/// One swing of one foot from `start` (lift-off at `lift_time`) to `end` (touch-down at `land_time`).
///
/// Horizontal position: one minimum-jerk quintic with zero velocity and acceleration at both ends.
/// Height: two quintics joined at the apex (`apex_time`, height `apex_height`, zero vertical velocity),
/// with the apex acceleration chosen so that the jerk is continuous there; lift-off velocity 0, touch-down
/// vertical velocity `landing_velocity`, zero accelerations at both ends. Orientation: the SO(3) geodesic
/// `R(t) = Exp(s(t) Log(R_end R_startᵀ)) R_start` with the minimum-jerk blend s [Romualdi 2022, eqs. 10.2.12, 10.2.16].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SwingTrajectory {
    /// Which foot swings.
    pub foot: Foot,
    /// Pose at lift-off.
    pub start: Isometry3<f64>,
    /// Pose at touch-down.
    pub end: Isometry3<f64>,
    /// Lift-off time \[s\].
    pub lift_time: f64,
    /// Apex time \[s\].
    pub apex_time: f64,
    /// Touch-down time \[s\].
    pub land_time: f64,
    /// Apex height (world z) \[m\].
    pub apex_height: f64,
    /// Vertical velocity at touch-down \[m/s\].
    pub landing_velocity: f64,
    x: Quintic,
    y: Quintic,
    z_up: Quintic,
    z_down: Quintic,
    rotation_log: Vector3<f64>,
    /// Apex and touch-down times of the swing as first built, before any retarget \[s\].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    base_timing: Option<(f64, f64)>,
    /// Mid-swing retargets in time order ([`SwingTrajectory::retarget`]); empty for a planned swing.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    retargets: Vec<SwingRetarget>,
}

/// One mid-swing retarget: from `time` on, these pieces replace the trajectory before it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct SwingRetarget {
    /// Retarget instant \[s\]; the quintics below are in local time `t − time`.
    time: f64,
    x: Quintic,
    y: Quintic,
    /// New height profile, or `None` to keep the previous one (the touch-down time did not change).
    z: Option<HeightProfile>,
    /// New orientation blend `s` (from its value at `time` to 1), or `None` to keep the previous one.
    blend: Option<Quintic>,
    /// A piece of a detour round the other sole ([`SwingTrajectory::go_round`]), not a retarget.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    detour: bool,
}

/// A height profile after a retarget: `first` over `[time, switch]`, `second` over `[switch, land]`
/// (local time of each piece from its start).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
struct HeightProfile {
    first: Quintic,
    switch: f64,
    second: Quintic,
}

/// What [`SwingTrajectory::retarget`] did.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RetargetOutcome {
    /// The rest of the swing now goes to the new target.
    Retargeted,
    /// Same target and touch-down time: nothing changed.
    Unchanged,
    /// Less than the minimum remaining time is left (or `t` is not inside the swing): nothing changed.
    Frozen,
}

impl SwingTrajectory {
    /// Builds the swing. `lift_time < land_time`, `0 < shape.apex_fraction < 1` are the caller's contract.
    pub fn new(
        foot: Foot,
        start: Isometry3<f64>,
        end: Isometry3<f64>,
        lift_time: f64,
        land_time: f64,
        shape: SwingShape,
    ) -> Self {
        let SwingShape {
            height: swing_height,
            apex_fraction,
            landing_velocity,
        } = shape;
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
        let continuous_acc = if slope.abs() > 1e-12 && (g0 / slope).is_finite() {
            -g0 / slope
        } else {
            0.0
        };
        // keep the height within [lower foothold, apex]: if the jerk-continuous apex acceleration over- or
        // undershoots, take the closest acceleration (towards 0, then more negative) that does not.
        let low = p0.z.min(p1.z);
        let within = |a: f64| {
            let up = quintic(p0.z, 0.0, 0.0, apex_height, 0.0, a, d1);
            let down = quintic(apex_height, 0.0, a, p1.z, landing_velocity, 0.0, d2);
            let (lo1, hi1) = quintic_range(&up, d1);
            let (lo2, hi2) = quintic_range(&down, d2);
            lo1.min(lo2) >= low - 1e-12 && hi1.max(hi2) <= apex_height + 1e-12
        };
        let h_up = apex_height - p0.z;
        let h_down = apex_height - p1.z;
        let a_scale = 20.0 * (h_up / (d1 * d1)).max(h_down / (d2 * d2));
        let candidates = (0..=20)
            .map(|k| continuous_acc * (1.0 - k as f64 / 20.0))
            .chain((1..=20).map(|j| -a_scale * j as f64 / 20.0));
        let mut apex_acc = 0.0;
        for a in candidates {
            if within(a) {
                apex_acc = a;
                break;
            }
        }
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
            base_timing: None,
            retargets: Vec::new(),
        }
    }

    /// Pose, twist and acceleration at time `t` (clamped to \[lift_time, land_time\]; NaN reads as lift-off).
    /// After a retarget, times before it give the trajectory as it was, times after it the retargeted one.
    pub fn evaluate(&self, t: f64) -> FootState {
        let duration = self.land_time - self.lift_time;
        let tau = (t - self.lift_time).clamp(0.0, duration);
        let tau = if tau.is_nan() { 0.0 } else { tau };
        let t = self.lift_time + tau;
        let piece = self.retargets.partition_point(|r| r.time <= t);
        let (x, y) = match piece.checked_sub(1).map(|k| &self.retargets[k]) {
            Some(r) => (
                eval_quintic(&r.x, t - r.time),
                eval_quintic(&r.y, t - r.time),
            ),
            None => (eval_quintic(&self.x, tau), eval_quintic(&self.y, tau)),
        };
        let z = self.height_at(piece, t);
        let [s, ds, dds] = self.blend_at(piece, t);
        let rotation =
            UnitQuaternion::from_scaled_axis(self.rotation_log * s) * self.start.rotation;
        let omega = self.rotation_log * ds;
        let omega_dot = self.rotation_log * dds;
        FootState {
            pose: Isometry3::from_parts(Translation3::new(x[0], y[0], z[0]), rotation),
            twist: Vector6::new(x[1], y[1], z[1], omega.x, omega.y, omega.z),
            acceleration: Vector6::new(x[2], y[2], z[2], omega_dot.x, omega_dot.y, omega_dot.z),
        }
    }

    /// Apex and touch-down times of the swing as first built \[s\].
    fn base_times(&self) -> (f64, f64) {
        self.base_timing.unwrap_or((self.apex_time, self.land_time))
    }

    /// Height, its rate and acceleration at `t` from the last height profile among the first `pieces`
    /// retargets (or the original one).
    fn height_at(&self, pieces: usize, t: f64) -> [f64; 4] {
        let latest = self.retargets[..pieces]
            .iter()
            .rev()
            .find_map(|r| r.z.map(|z| (r.time, z)));
        match latest {
            Some((start, z)) if t <= z.switch => eval_quintic(&z.first, t - start),
            Some((_, z)) => eval_quintic(&z.second, t - z.switch),
            None => {
                let (apex, _) = self.base_times();
                if t <= apex {
                    eval_quintic(&self.z_up, t - self.lift_time)
                } else {
                    eval_quintic(&self.z_down, t - apex)
                }
            }
        }
    }

    /// Orientation blend `[s, ṡ, s̈]` at `t` from the last blend among the first `pieces` retargets (or
    /// the original minimum-jerk one).
    fn blend_at(&self, pieces: usize, t: f64) -> [f64; 3] {
        let latest = self.retargets[..pieces]
            .iter()
            .rev()
            .find_map(|r| r.blend.map(|b| (r.time, b)));
        match latest {
            Some((start, b)) => {
                let v = eval_quintic(&b, t - start);
                [v[0], v[1], v[2]]
            }
            None => {
                let (_, land) = self.base_times();
                min_jerk_blend(t - self.lift_time, land - self.lift_time)
            }
        }
    }

    /// Retargets the rest of the swing at `t` \[s\] to touch down at `target` (world position of the sole;
    /// the orientation target is unchanged) at `land_time` \[s\] [Griffin 2017]. From the *desired* state at
    /// `t` (position, velocity, acceleration), one quintic per horizontal axis reaches `target` with zero
    /// velocity and acceleration [Romualdi 2022, eq. D.3.6], so position, velocity and acceleration are
    /// continuous at `t`. If the touch-down time or height changes, the height is regenerated too: before
    /// the apex a quintic to the same apex height (zero vertical velocity) at the apex time scaled with the
    /// remaining time, then a quintic to the ground landing with `landing_velocity`; after the apex one
    /// quintic down (or, if that would dip below the ground, a hold then a descent); the orientation blend goes from its current state to 1 at the new touch-down.
    /// Otherwise the height and orientation profiles are kept.
    ///
    /// Frozen (nothing changes) when `t` is not strictly inside the swing or when less than
    /// `min_remaining` \[s\] is left before the current or the new touch-down. Allocates (one retarget
    /// record); meant for planner events, not for every control tick of a long swing.
    pub fn retarget(
        &mut self,
        t: f64,
        target: Vector3<f64>,
        land_time: f64,
        min_remaining: f64,
    ) -> RetargetOutcome {
        let finite = t.is_finite() && land_time.is_finite() && target.iter().all(|v| v.is_finite());
        let inside = t > self.lift_time && t < self.land_time;
        if !finite || !inside || self.land_time - t < min_remaining || land_time - t < min_remaining
        {
            return RetargetOutcome::Frozen;
        }
        let old_target = self.end.translation.vector;
        let retime = land_time != self.land_time || target.z != old_target.z;
        if target == old_target && !retime {
            return RetargetOutcome::Unchanged;
        }
        let now = self.evaluate(t);
        let (p, v, a) = (
            now.pose.translation.vector,
            now.twist.xyz(),
            now.acceleration.xyz(),
        );
        let d = land_time - t;
        let x = quintic(p.x, v.x, a.x, target.x, 0.0, 0.0, d);
        let y = quintic(p.y, v.y, a.y, target.y, 0.0, 0.0, d);
        let (z, blend) = if retime {
            let z = self.height_retarget(t, [p.z, v.z, a.z], target.z, land_time);
            let pieces = self.retargets.partition_point(|r| r.time <= t);
            let [s, ds, dds] = self.blend_at(pieces, t);
            (Some(z), Some(quintic(s, ds, dds, 1.0, 0.0, 0.0, d)))
        } else {
            (None, None)
        };
        if self.base_timing.is_none() {
            self.base_timing = Some((self.apex_time, self.land_time));
        }
        if let Some(z) = &z {
            if t < self.apex_time {
                self.apex_time = z.switch;
            }
        }
        self.retargets.retain(|r| r.time < t);
        self.retargets.push(SwingRetarget {
            time: t,
            x,
            y,
            z,
            blend,
            detour: false,
        });
        self.end.translation.vector = target;
        self.land_time = land_time;
        RetargetOutcome::Retargeted
    }

    /// The height profile of a retarget at `t` from the vertical state `[z, ż, z̈]` to `ground` at `land`.
    fn height_retarget(&self, t: f64, z: [f64; 3], ground: f64, land: f64) -> HeightProfile {
        if t < self.apex_time {
            let scale = (land - t) / (self.land_time - t);
            let switch = t + (self.apex_time - t) * scale;
            HeightProfile {
                first: quintic(z[0], z[1], z[2], self.apex_height, 0.0, 0.0, switch - t),
                switch,
                second: quintic(
                    self.apex_height,
                    0.0,
                    0.0,
                    ground,
                    self.landing_velocity,
                    0.0,
                    land - switch,
                ),
            }
        } else {
            self.descent_retarget(t, z, ground, land)
        }
    }

    /// After the apex: one quintic down from `[z, ż, z̈]`, unless it dips below the ground (a descent
    /// stretched in time must first brake); then a hold at a height between the current one and the apex
    /// (reached with zero rate after a share of the remaining time) followed by a minimum-jerk descent,
    /// the first candidate that stays within \[ground, apex\].
    fn descent_retarget(&self, t: f64, z: [f64; 3], ground: f64, land: f64) -> HeightProfile {
        let d = land - t;
        let lv = self.landing_velocity;
        let down = quintic(z[0], z[1], z[2], ground, lv, 0.0, d);
        let inside = |q: &Quintic, len: f64| {
            let (lo, hi) = quintic_range(q, len);
            lo >= ground - 1e-12 && hi <= self.apex_height.max(z[0]) + 1e-12
        };
        if inside(&down, d) {
            return HeightProfile {
                first: down,
                switch: land,
                second: down,
            };
        }
        for share in [0.25, 0.4, 0.55] {
            for hold in [z[0], 0.5 * (z[0] + self.apex_height), self.apex_height] {
                let first = quintic(z[0], z[1], z[2], hold, 0.0, 0.0, share * d);
                let second = quintic(hold, 0.0, 0.0, ground, lv, 0.0, (1.0 - share) * d);
                if inside(&first, share * d) && inside(&second, (1.0 - share) * d) {
                    return HeightProfile {
                        first,
                        switch: t + share * d,
                        second,
                    };
                }
            }
        }
        HeightProfile {
            first: down,
            switch: land,
            second: down,
        }
    }

    /// Number of mid-swing retargets applied to this swing (the pieces of a detour not counted).
    pub fn retarget_count(&self) -> usize {
        self.retargets.iter().filter(|r| !r.detour).count()
    }

    /// Whether the sole (`length` × `width` \[m\]), swept from `from` \[s\] to the touch-down, intersects the
    /// sole at `other`: [`SWEEP_SAMPLES`] + 1 poses, exact rectangle intersection at each.
    pub fn sweeps_over(&self, from: f64, other: &Isometry3<f64>, length: f64, width: f64) -> bool {
        let fixed = SupportPolygon::foot_corners(other, length, width);
        (0..=SWEEP_SAMPLES).any(|i| {
            let t = from + (self.land_time - from) * i as f64 / SWEEP_SAMPLES as f64;
            let moving = SupportPolygon::foot_corners(&self.evaluate(t).pose, length, width);
            quadrilaterals_intersect(&moving, &fixed)
        })
    }

    /// Makes the rest of the swing from `from` \[s\] go round the sole at `other` (the stance foot, soles
    /// `length` × `width` \[m\]) when its path would sweep over it (a crossover step, or the step that
    /// uncrosses the feet after one): three pieces in `other`'s frame, from the state at `from` (position,
    /// velocity, acceleration: continuous) to a corner in front of or behind the sole, across it, then to
    /// the touch-down, each a quintic ending at rest [Romualdi 2022, eq. D.3.6], the time shared in
    /// proportion to the lengths. In front or behind, whichever path is shorter (the other if that one
    /// still touches); the corners are [`DETOUR_CLEARANCE`] past the sole, counting the swing sole turned
    /// by the larger relative yaw of its two ends. Height and orientation profiles are kept.
    ///
    /// Returns `false` when neither detour clears the sole (the swing is then left as it was); `true`
    /// when the swing clears it (unchanged if its path already did: every planned step of a walk).
    /// Allocates only when it builds a detour (a planner event).
    pub fn go_round(&mut self, from: f64, other: &Isometry3<f64>, length: f64, width: f64) -> bool {
        let frame = Pose2::from_isometry(other);
        let start_local =
            frame.inverse_transform_point(self.evaluate(from).pose.translation.vector.xy());
        let end_local = frame.inverse_transform_point(self.end.translation.vector.xy());
        let turn = |h: &Isometry3<f64>| wrap_angle(Pose2::from_isometry(h).yaw - frame.yaw).abs();
        let yaw = turn(&self.start).max(turn(&self.end)).min(FRAC_PI_2);
        let half_x = 0.5 * length * yaw.cos() + 0.5 * width * yaw.sin();
        let half_y = 0.5 * length * yaw.sin() + 0.5 * width * yaw.cos();
        // a path that never leaves one side of the sole band cannot touch it (a swing as planned)
        let band = 0.5 * width + half_y;
        let (ys, ye) = (start_local.y, end_local.y);
        let planned = self.retargets.is_empty(); // a straight path, the yaw between its ends'
        if planned && ys * ye > 0.0 && ys.abs().min(ye.abs()) >= band {
            return true;
        }
        if !self.sweeps_over(from, other, length, width) {
            return true;
        }
        let saved = self.retargets.clone();
        let reach = 0.5 * length + half_x + DETOUR_CLEARANCE;
        let cost = |x: f64| (start_local.x - x).abs() + (end_local.x - x).abs();
        let mut sides = [reach, -reach];
        if cost(-reach) < cost(reach) {
            sides.swap(0, 1);
        }
        for x in sides {
            let corners = [
                frame.transform_point(Vector2::new(x, ys)),
                frame.transform_point(Vector2::new(x, ye)),
            ];
            self.retargets.clone_from(&saved);
            self.detour(from, corners);
            if !self.sweeps_over(from, other, length, width) {
                return true;
            }
        }
        self.retargets = saved;
        false
    }

    /// Replaces the horizontal path from `from` by quintics through `corners` (at rest there) to the
    /// touch-down (see [`SwingTrajectory::go_round`]).
    fn detour(&mut self, from: f64, corners: [Vector2<f64>; 2]) {
        let now = self.evaluate(from);
        let p0 = now.pose.translation.vector.xy();
        let (v0, a0) = (now.twist.xyz().xy(), now.acceleration.xyz().xy());
        let points = [p0, corners[0], corners[1], self.end.translation.vector.xy()];
        let lengths: [f64; 3] =
            std::array::from_fn(|i| (points[i + 1] - points[i]).norm() + DETOUR_MIN_PIECE);
        let total: f64 = lengths.iter().sum();
        let duration = self.land_time - from;
        let mut t = from;
        for (i, len) in lengths.iter().enumerate() {
            let d = duration * len / total;
            let (v, a) = if i == 0 {
                (v0, a0)
            } else {
                (Vector2::zeros(), Vector2::zeros())
            };
            let (p, q) = (points[i], points[i + 1]);
            let x = quintic(p.x, v.x, a.x, q.x, 0.0, 0.0, d);
            let y = quintic(p.y, v.y, a.y, q.y, 0.0, 0.0, d);
            match self.retargets.last_mut() {
                // the retarget made at `from` keeps its height and orientation profiles
                Some(r) if i == 0 && r.time == from => {
                    r.x = x;
                    r.y = y;
                }
                _ => self.retargets.push(SwingRetarget {
                    time: t,
                    x,
                    y,
                    z: None,
                    blend: None,
                    detour: true,
                }),
            }
            t += d;
        }
    }
}

/// Poses sampled by [`SwingTrajectory::sweeps_over`] (past the first).
pub const SWEEP_SAMPLES: usize = 100;
/// Gap a detour leaves between the swing sole and the sole it goes round \[m\].
pub const DETOUR_CLEARANCE: f64 = 0.01;
/// Length added to each piece of a detour when the time is shared, so that no piece is instantaneous \[m\].
const DETOUR_MIN_PIECE: f64 = 0.02;
