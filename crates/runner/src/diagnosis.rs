//! Fall diagnosis: which way the robot fell and when, how long the measured ZMP sat at a sole edge and at the
//! bound of the whole-body layer's CoP region, and the largest DCM error and when (issues 13, 17). Accumulated while the loop runs without allocating; printed by the
//! summary ([`crate::summary::RunSummary::render`]) and written to `/runner/diagnosis` (docs/logging.md).
//!
//! **At a sole edge.** The measured ZMP (the plant's truth, from the wrenches of the feet in contact carrying
//! a vertical force) is *at a sole edge* when it is outside the support polygon or inside it but within
//! [`ZMP_EDGE_MARGIN`] of its boundary: `max_i (n_iᵀ p − b_i) ≥ −ZMP_EDGE_MARGIN`, the polygon being the
//! convex hull of the sole rectangles (`planner.foot_length` × `planner.foot_width`, centred on the sole
//! frames) of those feet, `{p | n_iᵀ p ≤ b_i}`. The ZMP of rigid contacts cannot leave the support polygon
//! [Vukobratović 2004]; one that reaches its boundary means the foot is about to roll about that edge.
//!
//! **At the CoP bound.** The same test against the hull of the *CoP regions* of the loaded feet
//! (`wbc.walking.cop_x` × `cop_y` in each sole frame, the region the TSID keeps every contact's CoP in) with
//! the margin [`COP_BOUND_MARGIN`]. In torque control the ankles can give no more than that region: a ZMP
//! held at its bound while the sole edge is still centimetres away means the ankle strategy is spent, and
//! whatever the whole-body layer's hard tasks still ask of the contact wrenches comes out of the angular
//! momentum (docs/push-recovery.md, "Torque control: why the torso tips").

use nalgebra::{Isometry3, Vector2};
use serde::Serialize;
use stride_planner::PlanSample;
use stride_simplified::{feet_support_polygon, FootRectangle, SupportPolygon};

use crate::stack::{soles_heading, Measured};

/// Distance \[m\] from the support polygon's boundary within which the measured ZMP counts as at a sole
/// edge (5 % of the bundled humanoid's 0.20 m sole, 11 % of its 0.09 m width).
pub const ZMP_EDGE_MARGIN: f64 = 0.01;

/// Distance \[m\] from the boundary of the CoP regions' hull within which the measured ZMP counts as at the
/// CoP bound (12 % of the bundled humanoid's 25 mm lateral half-width of the region).
pub const COP_BOUND_MARGIN: f64 = 0.003;

/// Edge directions in the robot's heading frame, in the order of [`ZmpEdgeTime::by_edge`].
pub const EDGE_NAMES: [&str; 4] = ["front", "left", "back", "right"];

/// Time the measured ZMP spent at a sole edge.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct ZmpEdgeTime {
    /// Time with a measurable ZMP (some foot in contact carrying load) \[s\].
    pub measured: f64,
    /// Time at a sole edge (see the module documentation) \[s\].
    pub at_edge: f64,
    /// The same split by the edge the ZMP was nearest to, by its outward normal in the robot's heading frame:
    /// front, left, back, right (the normal within ±45° of forward, left, ...) \[s\].
    pub by_edge: [f64; 4],
}

impl ZmpEdgeTime {
    /// Adds `dt` \[s\] of the ZMP `zmp` \[m\] over `polygon` with the robot heading `heading` \[rad\],
    /// at an edge within [`ZMP_EDGE_MARGIN`]; returns the signed distance `max_i (n_iᵀ p − b_i)` \[m\]
    /// (≤ 0 inside).
    pub fn add(
        &mut self,
        zmp: Vector2<f64>,
        polygon: &SupportPolygon,
        heading: f64,
        dt: f64,
    ) -> f64 {
        self.add_within(zmp, polygon, heading, dt, ZMP_EDGE_MARGIN)
    }

    /// [`ZmpEdgeTime::add`] with the margin `margin` \[m\] instead of [`ZMP_EDGE_MARGIN`].
    pub fn add_within(
        &mut self,
        zmp: Vector2<f64>,
        polygon: &SupportPolygon,
        heading: f64,
        dt: f64,
        margin: f64,
    ) -> f64 {
        self.measured += dt;
        let (mut worst, mut normal) = (f64::NEG_INFINITY, Vector2::zeros());
        for i in 0..polygon.len() {
            let (n, b) = polygon.half_plane(i);
            let v = n.dot(&zmp) - b;
            if v > worst {
                (worst, normal) = (v, n);
            }
        }
        if worst >= -margin {
            self.at_edge += dt;
            self.by_edge[quadrant(normal.y.atan2(normal.x) - heading)] += dt;
        }
        worst
    }
}

impl ZmpEdgeTime {
    /// ` (left 0.20 s, …)`: the edges with some time, or nothing.
    fn sides(&self) -> String {
        let sides: Vec<String> = EDGE_NAMES
            .iter()
            .zip(self.by_edge)
            .filter(|(_, t)| *t > 0.0)
            .map(|(name, t)| format!("{name} {t:.2} s"))
            .collect();
        if sides.is_empty() {
            String::new()
        } else {
            format!(" ({})", sides.join(", "))
        }
    }
}

/// Index of the direction `angle` \[rad\] (0 forward, π/2 left) in [`EDGE_NAMES`]: the nearest of the four.
fn quadrant(angle: f64) -> usize {
    let q = (angle / std::f64::consts::FRAC_PI_2).round() as i64;
    q.rem_euclid(4) as usize
}

/// The support polygon of the feet in contact that carry a vertical force (`loaded`), from the sole poses and
/// the half length and width \[m\] of the sole rectangle; `None` without such a foot.
pub fn loaded_support(
    soles: &[Isometry3<f64>; 2],
    loaded: [bool; 2],
    half_length: f64,
    half_width: f64,
) -> Option<SupportPolygon> {
    loaded_region(
        soles,
        loaded,
        [-half_length, half_length],
        [-half_width, half_width],
    )
}

/// The hull of the rectangles `x = [min, max]` × `y = [min, max]` \[m\] in the sole frames of the feet in
/// contact that carry a vertical force (`loaded`); `None` without such a foot.
pub fn loaded_region(
    soles: &[Isometry3<f64>; 2],
    loaded: [bool; 2],
    x: [f64; 2],
    y: [f64; 2],
) -> Option<SupportPolygon> {
    let mut feet = [FootRectangle {
        position: Vector2::zeros(),
        yaw: 0.0,
        x_min: x[0],
        x_max: x[1],
        y_min: y[0],
        y_max: y[1],
    }; 2];
    let mut n = 0;
    for (sole, _) in soles.iter().zip(loaded).filter(|(_, l)| *l) {
        feet[n].position = sole.translation.vector.xy();
        feet[n].yaw = sole.rotation.euler_angles().2;
        n += 1;
    }
    feet_support_polygon(&feet[..n]).ok()
}

/// The largest value of an error and when it happened.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Peak {
    /// Largest value.
    pub value: f64,
    /// Simulated time of the first tick that reached it \[s\].
    pub time: f64,
}

impl Peak {
    /// Keeps `value` at `time` \[s\] if it is the largest so far.
    pub fn add(&mut self, value: f64, time: f64) {
        if value > self.value {
            *self = Self { value, time };
        }
    }
}

/// DCM errors \[m\] above which a fall is the robot toppling the way its DCM diverges (4–6 times the DCM
/// error RMS of the default walks, docs/runner.md); below, the torso fell over legs that kept their balance.
pub const TOPPLING_DCM_ERROR: f64 = 0.05;

/// Which way and when the robot fell.
///
/// When the DCM error (measured − planned) exceeds [`TOPPLING_DCM_ERROR`], the direction is the DCM error's:
/// where the robot diverges from its plan, the way it topples [Romualdi 2022, eq. 4.4.2] (on a pushed walk
/// the torso may lean elsewhere than the CoM goes). Below it, the direction is the torso's lean: a torso that
/// pitches over legs that stand trips the tilt check with the DCM on its plan. Both directions are in the
/// heading frame of the *planned* soles (their mean yaw), which the feet's own twisting in a fall does not
/// move.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FallDiagnosis {
    /// Simulated time of the fall check that fired \[s\].
    pub time: f64,
    /// Direction of the fall in the heading frame \[deg\]: 0 forward, 90 left, ±180 backward, −90 right.
    pub direction_deg: f64,
    /// `forward`, `left`, `backward` or `right`: the nearest of the four.
    pub direction: &'static str,
    /// What the direction is of: `dcm_error` (the robot toppled) or `torso_lean` (the torso fell over
    /// balanced legs).
    pub kind: &'static str,
    /// Direction of the DCM error in the heading frame \[deg\].
    pub dcm_error_deg: f64,
    /// The DCM error's magnitude \[m\].
    pub dcm_error: f64,
    /// Direction of the torso's lean (the horizontal part of its up axis) in the heading frame \[deg\].
    pub lean_deg: f64,
    /// Torso tilt \[deg\].
    pub tilt_deg: f64,
    /// Gait phase of the plan then (`double_support`, `left_stance`, `right_stance`).
    pub phase: &'static str,
}

impl FallDiagnosis {
    /// The diagnosis at time `t` \[s\] of the plant's truth `m` (its DCM from the last simplified tick)
    /// against the plan sample `plan`.
    pub fn new(t: f64, m: &Measured, plan: &PlanSample) -> Self {
        let heading = soles_heading(&plan.left.pose, &plan.right.pose);
        let in_heading_frame =
            |v: Vector2<f64>| stride_planner::geometry::wrap_angle(v.y.atan2(v.x) - heading);
        let error = m.dcm - plan.dcm_position.xy();
        let dcm_angle = in_heading_frame(error);
        let lean = in_heading_frame(m.torso_up.xy());
        let toppled = error.norm() > TOPPLING_DCM_ERROR;
        let angle = if toppled { dcm_angle } else { lean };
        Self {
            time: t,
            direction_deg: angle.to_degrees(),
            direction: DIRECTION_NAMES[quadrant(angle)],
            kind: if toppled { "dcm_error" } else { "torso_lean" },
            dcm_error_deg: dcm_angle.to_degrees(),
            dcm_error: error.norm(),
            lean_deg: lean.to_degrees(),
            tilt_deg: m.tilt.to_degrees(),
            phase: crate::records::phase_name(&plan.phase),
        }
    }
}

/// Fall directions in the robot's heading frame, counter-clockwise from forward.
const DIRECTION_NAMES: [&str; 4] = ["forward", "left", "backward", "right"];

/// The diagnosis figures of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Diagnosis {
    /// The fall, if the robot fell.
    pub fall: Option<FallDiagnosis>,
    /// Time the measured ZMP spent at a sole edge.
    pub zmp_edge: ZmpEdgeTime,
    /// Time the measured ZMP spent at the bound of the CoP regions (`wbc.walking.cop_x`, `cop_y`) of the
    /// loaded feet, within [`COP_BOUND_MARGIN`] or outside.
    pub cop_bound: ZmpEdgeTime,
    /// Largest DCM error (measured vs planned, planar) \[m\] and when.
    pub dcm_error_peak: Peak,
}

impl Diagnosis {
    /// The fall block of the summary (only when the robot fell); `saturation` is the summary's per-joint
    /// saturation time, longest first.
    pub fn render(&self, s: &mut String, saturation: &[(String, f64)]) {
        use std::fmt::Write as _;
        let Some(f) = &self.fall else {
            return;
        };
        let _ = writeln!(
            s,
            "  fall diagnosis: fell {} ({}) at {:.2} s, in {}: DCM error {:.0} mm towards {:.0}° from the \
             heading, torso tilt {:.1}° towards {:.0}°",
            f.direction,
            if f.kind == "dcm_error" {
                "toppled"
            } else {
                "the torso over balanced legs"
            },
            f.time,
            f.phase,
            f.dcm_error * 1e3,
            f.dcm_error_deg,
            f.tilt_deg,
            f.lean_deg
        );
        let z = &self.zmp_edge;
        let _ = writeln!(
            s,
            "    measured ZMP at a sole edge (within {:.0} mm of the support polygon's boundary or outside): \
             {:.2} s of {:.2} s{}",
            ZMP_EDGE_MARGIN * 1e3,
            z.at_edge,
            z.measured,
            z.sides()
        );
        let c = &self.cop_bound;
        let _ = writeln!(
            s,
            "    measured ZMP at the CoP bound (within {:.0} mm of the hull of the loaded feet's \
             wbc.walking.cop_x × cop_y or outside): {:.2} s of {:.2} s{}",
            COP_BOUND_MARGIN * 1e3,
            c.at_edge,
            c.measured,
            c.sides()
        );
        let _ = writeln!(
            s,
            "    joints at their effort limit: {}",
            crate::summary::longest_saturations(saturation, 5)
        );
        let p = &self.dcm_error_peak;
        let _ = writeln!(
            s,
            "    largest DCM error {:.1} mm at {:.2} s",
            p.value * 1e3,
            p.time
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion, Vector3};

    fn sole(x: f64, y: f64, yaw: f64) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(x, y, 0.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
        )
    }

    /// Single support on a 0.2 × 0.1 m sole at the origin: the signed distance is minus the distance to the
    /// nearest edge inside and the distance to the edge line outside, counted against the margin.
    #[test]
    fn edge_time_counts_points_near_or_outside_the_boundary() {
        let soles = [sole(0.0, 0.0, 0.0), sole(0.0, -0.2, 0.0)];
        let poly = loaded_support(&soles, [true, false], 0.1, 0.05).unwrap();
        let mut e = ZmpEdgeTime::default();
        // Centre: 50 mm from the side edges, not at an edge.
        assert!((e.add(Vector2::new(0.0, 0.0), &poly, 0.0, 0.01) + 0.05).abs() < 1e-12);
        // 9 mm inside the left edge (y = 0.05): at the left edge.
        assert!((e.add(Vector2::new(0.0, 0.041), &poly, 0.0, 0.01) + 0.009).abs() < 1e-12);
        // 11 mm inside the front edge: not at an edge (the other side of the margin).
        assert!((e.add(Vector2::new(0.089, 0.0), &poly, 0.0, 0.01) + 0.011).abs() < 1e-12);
        // 3 mm outside the back edge.
        assert!((e.add(Vector2::new(-0.103, 0.0), &poly, 0.0, 0.01) - 0.003).abs() < 1e-12);
        assert!((e.measured - 0.04).abs() < 1e-12);
        assert!((e.at_edge - 0.02).abs() < 1e-12);
        assert_eq!(e.by_edge, [0.0, 0.01, 0.01, 0.0]);
        // The same edge (outward normal +y) seen by a robot heading +y: its front edge.
        let mut turned = ZmpEdgeTime::default();
        turned.add(
            Vector2::new(0.0, 0.045),
            &poly,
            std::f64::consts::FRAC_PI_2,
            0.01,
        );
        assert_eq!(turned.by_edge, [0.01, 0.0, 0.0, 0.0]);
    }

    /// The CoP bound: an asymmetric region (x in [−0.05, 0.07], y in [−0.025, 0.025] m) in the frame of a
    /// sole at (1, 0.1) turned by 90°, so that the sole's x is world +y and its y world −x. Distances are the
    /// ones to the rotated rectangle's edges, counted against the 3 mm margin, and the region is not the
    /// sole's rectangle (a ZMP 20 mm from the sole edge is at the CoP bound).
    #[test]
    fn cop_bound_uses_the_cop_region_in_the_sole_frame() {
        let soles = [
            sole(1.0, 0.1, std::f64::consts::FRAC_PI_2),
            sole(1.0, -0.3, 0.0),
        ];
        let region = loaded_region(&soles, [true, false], [-0.05, 0.07], [-0.025, 0.025]).unwrap();
        let mut e = ZmpEdgeTime::default();
        // sole x = 0.068 (2 mm inside the front bound): world (1, 0.168)
        let d = e.add_within(
            Vector2::new(1.0, 0.168),
            &region,
            0.0,
            0.01,
            COP_BOUND_MARGIN,
        );
        assert!((d + 0.002).abs() < 1e-12, "{d}");
        // sole y = 0.021 (4 mm inside the left bound): world (0.979, 0.1), not at the bound
        let d = e.add_within(
            Vector2::new(0.979, 0.1),
            &region,
            0.0,
            0.01,
            COP_BOUND_MARGIN,
        );
        assert!((d + 0.004).abs() < 1e-12, "{d}");
        // sole x = −0.052 (2 mm behind the back bound): world (1, 0.048)
        let d = e.add_within(
            Vector2::new(1.0, 0.048),
            &region,
            0.0,
            0.01,
            COP_BOUND_MARGIN,
        );
        assert!((d - 0.002).abs() < 1e-12, "{d}");
        assert!((e.measured - 0.03).abs() < 1e-12);
        assert!((e.at_edge - 0.02).abs() < 1e-12);
        // outward normals: sole +x = world +y (left of a robot heading +x), sole −x = world −y (right)
        assert_eq!(e.by_edge, [0.0, 0.01, 0.0, 0.01]);
        // the symmetric sole rectangle of `loaded_support` is the same function
        let a = loaded_support(&soles, [true, true], 0.1, 0.045).unwrap();
        let b = loaded_region(&soles, [true, true], [-0.1, 0.1], [-0.045, 0.045]).unwrap();
        assert_eq!(a, b);
    }

    /// Double support: the hull of both soles; a point between the feet is inside, not at an edge.
    #[test]
    fn double_support_uses_the_hull_of_both_soles() {
        let soles = [sole(0.0, 0.1, 0.0), sole(0.0, -0.1, 0.0)];
        let poly = loaded_support(&soles, [true, true], 0.1, 0.05).unwrap();
        let mut e = ZmpEdgeTime::default();
        let d = e.add(Vector2::new(0.0, 0.0), &poly, 0.0, 0.01);
        assert!((d + 0.1).abs() < 1e-12, "{d}");
        assert_eq!(e.at_edge, 0.0);
        assert!(loaded_support(&soles, [false, false], 0.1, 0.05).is_none());
    }

    /// Directions are measured from the planned soles' heading, whatever the measured soles do: a plan
    /// heading +y with the measured DCM at −x of the planned one falls to its left; a torso leaning towards −y
    /// leans backward.
    #[test]
    fn fall_direction_is_in_the_planned_heading_frame() {
        let yaw = std::f64::consts::FRAC_PI_2;
        let tilt = 0.3_f64;
        let mut plan = PlanSample::default();
        plan.left.pose = sole(-0.1, 0.0, yaw);
        plan.right.pose = sole(0.1, 0.0, yaw);
        plan.dcm_position = Vector3::new(0.5, 2.0, 0.0);
        let m = Measured {
            soles: [sole(0.1, 0.0, 0.7), sole(-0.1, 0.0, -0.4)],
            dcm: Vector2::new(0.2, 2.0),
            torso_up: Vector3::new(0.0, -tilt.sin(), tilt.cos()),
            tilt,
            ..Measured::default()
        };
        let f = FallDiagnosis::new(3.0, &m, &plan);
        assert!((f.direction_deg - 90.0).abs() < 1e-9, "{}", f.direction_deg);
        assert_eq!(f.direction, "left");
        assert!((f.dcm_error - 0.3).abs() < 1e-12);
        assert!((f.lean_deg.abs() - 180.0).abs() < 1e-9, "{}", f.lean_deg);
        assert!((f.tilt_deg - 0.3_f64.to_degrees()).abs() < 1e-12);
        // 40° to the right of the heading is nearer to right than to forward.
        let a = (yaw - 40f64.to_radians()).sin_cos();
        let m = Measured {
            dcm: plan.dcm_position.xy() + Vector2::new(a.1, a.0) * 0.1,
            ..m
        };
        let f = FallDiagnosis::new(3.0, &m, &plan);
        assert!((f.direction_deg + 40.0).abs() < 1e-9, "{}", f.direction_deg);
        assert_eq!((f.direction, f.kind), ("forward", "dcm_error"));
        // Both sides of the toppling threshold: a 49 mm DCM error leaves the direction to the torso's lean.
        let m = Measured {
            dcm: plan.dcm_position.xy() + Vector2::new(a.1, a.0) * 0.049,
            ..m
        };
        let f = FallDiagnosis::new(3.0, &m, &plan);
        assert_eq!((f.direction, f.kind), ("backward", "torso_lean"));
        assert!((f.direction_deg.abs() - 180.0).abs() < 1e-9);
        assert!((f.dcm_error_deg + 40.0).abs() < 1e-9);
    }

    #[test]
    fn peak_keeps_the_first_largest_value() {
        let mut p = Peak::default();
        for (v, t) in [(0.1, 1.0), (0.3, 2.0), (0.3, 3.0), (0.2, 4.0)] {
            p.add(v, t);
        }
        assert_eq!(
            p,
            Peak {
                value: 0.3,
                time: 2.0
            }
        );
    }
}
