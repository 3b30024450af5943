//! Support polygons: fixed-capacity convex polygons, convex hulls of feet rectangles, point-in-polygon tests,
//! projection onto the polygon and the half-plane (H-) representation used by the MPC [Romualdi 2022, eq. 10.2.22].
//!
//! Nothing here allocates: hulls are built in stack arrays. This is the one support-polygon type of
//! stride: the planner's plan samples and the simplified layer's inputs both carry it.

use nalgebra::{Isometry3, Vector2, Vector3};
use serde::{Deserialize, Serialize};

/// Why a [`SupportPolygon`] cannot be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("invalid support polygon `{name}`: {reason}")]
pub struct PolygonError {
    /// Which polygon (input field name or helper name).
    pub name: &'static str,
    /// What is wrong with it.
    pub reason: &'static str,
}

type Result<T> = std::result::Result<T, PolygonError>;

/// Largest number of vertices a [`SupportPolygon`] stores (the hull of two rectangles has at most 8).
pub const MAX_POLYGON_VERTICES: usize = 8;

/// Largest number of points [`SupportPolygon::convex_hull`] accepts.
pub const MAX_HULL_POINTS: usize = 32;

/// Polygons with a smaller area \[m²\] are rejected as degenerate.
pub const MIN_POLYGON_AREA: f64 = 1e-10;

/// A convex polygon in the ground plane (world x, y), vertices counter-clockwise, no collinear vertices,
/// at least 3 and at most [`MAX_POLYGON_VERTICES`] vertices, area ≥ [`MIN_POLYGON_AREA`].
///
/// Every constructor validates these invariants, so a `SupportPolygon` value is always usable.
/// In serde form it is a list of `[x, y]` vertices (any order; the convex hull is taken).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(try_from = "Vec<[f64; 2]>")]
pub struct SupportPolygon {
    vertices: [Vector2<f64>; MAX_POLYGON_VERTICES],
    len: usize,
}

impl TryFrom<Vec<[f64; 2]>> for SupportPolygon {
    type Error = PolygonError;
    fn try_from(points: Vec<[f64; 2]>) -> Result<Self> {
        if points.len() > MAX_HULL_POINTS {
            return Err(PolygonError {
                name: "vertices",
                reason: "more than MAX_HULL_POINTS points",
            });
        }
        let mut buffer = [Vector2::zeros(); MAX_HULL_POINTS];
        for (slot, p) in buffer.iter_mut().zip(points.iter()) {
            *slot = Vector2::new(p[0], p[1]);
        }
        Self::convex_hull(&buffer[..points.len()])
    }
}

impl From<SupportPolygon> for Vec<[f64; 2]> {
    fn from(polygon: SupportPolygon) -> Self {
        polygon.vertices().iter().map(|v| [v.x, v.y]).collect()
    }
}

/// The serde form: the list of `[x, y]` vertices, written without building a `Vec` (logging a polygon
/// every control tick must not allocate).
impl Serialize for SupportPolygon {
    fn serialize<S: serde::Serializer>(
        &self,
        serializer: S,
    ) -> std::result::Result<S::Ok, S::Error> {
        serializer.collect_seq(self.vertices().iter().map(|v| [v.x, v.y]))
    }
}

fn cross(a: Vector2<f64>, b: Vector2<f64>) -> f64 {
    a.x * b.y - a.y * b.x
}

impl SupportPolygon {
    /// Convex hull of `points` (any order, duplicates and interior points allowed), Andrew's monotone chain.
    ///
    /// Errors (`InvalidPolygon`) when a point is not finite, when there are more than
    /// [`MAX_HULL_POINTS`] points, when the hull has fewer than 3 vertices or an area below
    /// [`MIN_POLYGON_AREA`] (degenerate), or more than [`MAX_POLYGON_VERTICES`] vertices.
    pub fn convex_hull(points: &[Vector2<f64>]) -> Result<Self> {
        const NAME: &str = "convex_hull";
        if points.len() > MAX_HULL_POINTS {
            return Err(PolygonError {
                name: NAME,
                reason: "more than MAX_HULL_POINTS points",
            });
        }
        if points.iter().any(|p| !(p.x.is_finite() && p.y.is_finite())) {
            return Err(PolygonError {
                name: NAME,
                reason: "a point is not finite",
            });
        }
        if points.len() < 3 {
            return Err(PolygonError {
                name: NAME,
                reason: "fewer than 3 points",
            });
        }
        let mut sorted = [Vector2::zeros(); MAX_HULL_POINTS];
        let sorted = &mut sorted[..points.len()];
        sorted.copy_from_slice(points);
        sorted.sort_unstable_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
        // Scale-aware tolerance for collinearity.
        let extent = (sorted[sorted.len() - 1] - sorted[0]).norm().max(1e-300);
        let tolerance = 1e-12 * extent * extent;
        let mut hull = [Vector2::zeros(); 2 * MAX_HULL_POINTS];
        let mut k = 0usize;
        for &p in sorted.iter() {
            while k >= 2 && cross(hull[k - 1] - hull[k - 2], p - hull[k - 2]) <= tolerance {
                k -= 1;
            }
            hull[k] = p;
            k += 1;
        }
        let lower_len = k + 1;
        for &p in sorted.iter().rev().skip(1) {
            while k >= lower_len && cross(hull[k - 1] - hull[k - 2], p - hull[k - 2]) <= tolerance {
                k -= 1;
            }
            hull[k] = p;
            k += 1;
        }
        // The last point equals the first one.
        let count = k.saturating_sub(1);
        if count < 3 {
            return Err(PolygonError {
                name: NAME,
                reason: "degenerate: the points are collinear or coincident",
            });
        }
        if count > MAX_POLYGON_VERTICES {
            return Err(PolygonError {
                name: NAME,
                reason: "the hull has more than MAX_POLYGON_VERTICES vertices",
            });
        }
        let mut vertices = [Vector2::zeros(); MAX_POLYGON_VERTICES];
        vertices[..count].copy_from_slice(&hull[..count]);
        let polygon = Self {
            vertices,
            len: count,
        };
        if polygon.area() < MIN_POLYGON_AREA {
            return Err(PolygonError {
                name: NAME,
                reason: "degenerate: area below MIN_POLYGON_AREA",
            });
        }
        Ok(polygon)
    }

    /// Axis-aligned rectangle `[x_min, x_max] × [y_min, y_max]` \[m\].
    pub fn rectangle(x_min: f64, x_max: f64, y_min: f64, y_max: f64) -> Result<Self> {
        Self::convex_hull(&[
            Vector2::new(x_min, y_min),
            Vector2::new(x_max, y_min),
            Vector2::new(x_max, y_max),
            Vector2::new(x_min, y_max),
        ])
    }

    /// Corners of a sole (rectangle `length` × `width` \[m\] centred on the sole frame `pose`), projected
    /// on the ground plane, counter-clockwise for a flat sole. Unlike [`FootRectangle`] this keeps the
    /// sole's full 3D orientation (a tilted sole's outline projects shorter).
    pub fn foot_corners(pose: &Isometry3<f64>, length: f64, width: f64) -> [Vector2<f64>; 4] {
        let (hl, hw) = (0.5 * length, 0.5 * width);
        let local = [
            Vector3::new(hl, hw, 0.0),
            Vector3::new(-hl, hw, 0.0),
            Vector3::new(-hl, -hw, 0.0),
            Vector3::new(hl, -hw, 0.0),
        ];
        let mut out = [Vector2::zeros(); 4];
        for (o, l) in out.iter_mut().zip(local.iter()) {
            let w = pose.transform_point(&(*l).into());
            *o = Vector2::new(w.x, w.y);
        }
        out
    }

    /// The vertices, counter-clockwise.
    pub fn vertices(&self) -> &[Vector2<f64>] {
        &self.vertices[..self.len]
    }

    /// Number of vertices (= number of edges = number of half-planes).
    pub fn len(&self) -> usize {
        self.len
    }

    /// Always false: a valid polygon has at least 3 vertices (provided for API completeness).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Area \[m²\] (shoelace formula).
    pub fn area(&self) -> f64 {
        let v = self.vertices();
        let mut twice = 0.0;
        for i in 0..v.len() {
            twice += cross(v[i], v[(i + 1) % v.len()]);
        }
        0.5 * twice
    }

    /// Mean of the vertices \[m\] (inside the polygon because it is convex).
    pub fn vertex_mean(&self) -> Vector2<f64> {
        self.vertices().iter().sum::<Vector2<f64>>() / self.len as f64
    }

    /// Half-plane `i` of the H-representation: `(n, b)` with `n` the unit outward normal of edge
    /// `v_i → v_{i+1}` and the polygon being `{p | nᵀ p ≤ b for every edge}`.
    pub fn half_plane(&self, i: usize) -> (Vector2<f64>, f64) {
        let a = self.vertices[i];
        let b = self.vertices[(i + 1) % self.len];
        let e = b - a;
        let n = Vector2::new(e.y, -e.x) / e.norm();
        (n, n.dot(&a))
    }

    /// Signed distance \[m\] from `p` to the polygon's boundary lines taken as half-planes: the largest
    /// `nᵀp − b` over the edges. ≤ 0 inside (minus the distance to the nearest edge line), > 0 outside
    /// (a lower bound of the Euclidean distance to the polygon).
    pub fn max_violation(&self, p: Vector2<f64>) -> f64 {
        (0..self.len)
            .map(|i| {
                let (n, b) = self.half_plane(i);
                n.dot(&p) - b
            })
            .fold(f64::NEG_INFINITY, f64::max)
    }

    /// True when `p` is inside the polygon or within `tolerance` \[m\] of it (half-plane test).
    pub fn contains(&self, p: Vector2<f64>, tolerance: f64) -> bool {
        self.max_violation(p) <= tolerance
    }

    /// Signed distance \[m\] of `p` from the boundary lines: positive inside (the distance to the nearest
    /// edge line), negative outside (minus the most violated edge distance, a lower bound of the true
    /// distance). The planner's form of [`SupportPolygon::max_violation`], computed with the inward normal
    /// `(−e_y, e_x)/|e|` of each edge `e`.
    pub fn signed_distance(&self, p: Vector2<f64>) -> f64 {
        let mut d = f64::INFINITY;
        for i in 0..self.len {
            let a = self.vertices[i];
            let b = self.vertices[(i + 1) % self.len];
            let e = b - a;
            let n = e.norm();
            if n == 0.0 {
                continue;
            }
            d = d.min(((p.x - a.x) * (-e.y) + (p.y - a.y) * e.x) / n);
        }
        d
    }

    /// The point of the polygon closest to `p` (Euclidean projection), and whether `p` was outside.
    /// Points inside (or on the boundary) are returned unchanged.
    pub fn project(&self, p: Vector2<f64>) -> (Vector2<f64>, bool) {
        if self.max_violation(p) <= 0.0 {
            return (p, false);
        }
        let mut best = self.vertices[0];
        let mut best_distance = f64::INFINITY;
        for i in 0..self.len {
            let a = self.vertices[i];
            let b = self.vertices[(i + 1) % self.len];
            let e = b - a;
            let t = ((p - a).dot(&e) / e.norm_squared()).clamp(0.0, 1.0);
            let q = a + e * t;
            let d = (p - q).norm_squared();
            if d < best_distance {
                best_distance = d;
                best = q;
            }
        }
        (best, true)
    }
}

/// The ZMP-admissible rectangle of a foot: a rectangle in the sole frame (x forward, y left) placed at
/// the sole's planar position and yaw in the world.
///
/// | field | unit | meaning |
/// |---|---|---|
/// | `position` | m | world x, y of the sole frame origin |
/// | `yaw` | rad | rotation of the sole about world z |
/// | `x_min`, `x_max` | m | admissible extent along the sole x axis (e.g. −0.02, 0.05 on iCub) |
/// | `y_min`, `y_max` | m | admissible extent along the sole y axis (e.g. −0.045, 0.05 on iCub) |
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FootRectangle {
    /// World x, y of the sole frame \[m\].
    pub position: Vector2<f64>,
    /// Sole yaw about world z \[rad\].
    pub yaw: f64,
    /// Back edge along the sole x axis \[m\].
    pub x_min: f64,
    /// Front edge along the sole x axis \[m\].
    pub x_max: f64,
    /// Right edge along the sole y axis \[m\].
    pub y_min: f64,
    /// Left edge along the sole y axis \[m\].
    pub y_max: f64,
}

impl FootRectangle {
    /// The rectangle `length` × `width` \[m\] centred on the sole frame `pose` (its planar position and
    /// yaw about world z).
    pub fn centred(pose: &Isometry3<f64>, length: f64, width: f64) -> Self {
        let (hl, hw) = (0.5 * length, 0.5 * width);
        Self {
            position: pose.translation.vector.xy(),
            yaw: pose.rotation.euler_angles().2,
            x_min: -hl,
            x_max: hl,
            y_min: -hw,
            y_max: hw,
        }
    }

    /// The four corners in the world, counter-clockwise.
    pub fn corners(&self) -> [Vector2<f64>; 4] {
        let (s, c) = self.yaw.sin_cos();
        let place = |x: f64, y: f64| self.position + Vector2::new(c * x - s * y, s * x + c * y);
        [
            place(self.x_min, self.y_min),
            place(self.x_max, self.y_min),
            place(self.x_max, self.y_max),
            place(self.x_min, self.y_max),
        ]
    }
}

/// Support polygon of the feet in contact: the convex hull of their rectangles (one foot in single
/// support, both in double support). Errors when `feet` is empty, holds more than 8 feet, or the
/// result is degenerate (see [`SupportPolygon::convex_hull`]).
pub fn feet_support_polygon(feet: &[FootRectangle]) -> Result<SupportPolygon> {
    if feet.is_empty() {
        return Err(PolygonError {
            name: "feet_support_polygon",
            reason: "no foot in contact",
        });
    }
    if 4 * feet.len() > MAX_HULL_POINTS {
        return Err(PolygonError {
            name: "feet_support_polygon",
            reason: "more than 8 feet",
        });
    }
    let mut points = [Vector2::zeros(); MAX_HULL_POINTS];
    for (i, foot) in feet.iter().enumerate() {
        points[4 * i..4 * i + 4].copy_from_slice(&foot.corners());
    }
    SupportPolygon::convex_hull(&points[..4 * feet.len()])
}
