//! Small planar geometry helpers: planar poses, foot rectangles and a fixed-capacity convex polygon.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector2, Vector3};
use serde::{Deserialize, Serialize};

/// Wraps an angle to (−π, π].
pub fn wrap_angle(a: f64) -> f64 {
    let two_pi = 2.0 * std::f64::consts::PI;
    let mut r = a % two_pi;
    if r > std::f64::consts::PI {
        r -= two_pi;
    } else if r <= -std::f64::consts::PI {
        r += two_pi;
    }
    r
}

/// Yaw (rotation about world z) of a 3D orientation, from its x axis projected on the ground.
pub fn yaw_of(rotation: &UnitQuaternion<f64>) -> f64 {
    let x = rotation * Vector3::x();
    x.y.atan2(x.x)
}

/// A pose on the ground plane: position \[m\] and yaw \[rad\].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pose2 {
    /// x \[m\].
    pub x: f64,
    /// y \[m\].
    pub y: f64,
    /// Yaw \[rad\].
    pub yaw: f64,
}

impl Pose2 {
    /// Planar projection of a 3D pose.
    pub fn from_isometry(h: &Isometry3<f64>) -> Self {
        Self {
            x: h.translation.x,
            y: h.translation.y,
            yaw: yaw_of(&h.rotation),
        }
    }

    /// Flat 3D pose at height `z`.
    pub fn to_isometry(&self, z: f64) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(self.x, self.y, z),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), self.yaw),
        )
    }

    /// Position as a vector.
    pub fn position(&self) -> Vector2<f64> {
        Vector2::new(self.x, self.y)
    }

    /// The point `local` (expressed in this pose's frame) in the world.
    pub fn transform_point(&self, local: Vector2<f64>) -> Vector2<f64> {
        let (s, c) = self.yaw.sin_cos();
        Vector2::new(
            self.x + c * local.x - s * local.y,
            self.y + s * local.x + c * local.y,
        )
    }

    /// The world point `p` expressed in this pose's frame.
    pub fn inverse_transform_point(&self, p: Vector2<f64>) -> Vector2<f64> {
        let (s, c) = self.yaw.sin_cos();
        let d = p - self.position();
        Vector2::new(c * d.x + s * d.y, -s * d.x + c * d.y)
    }
}

/// How far the left sole is to the left of the right one \[m\], the quantity bounded below by `min_width`
/// [Romualdi 2022, eq. 10.1.13]: the left sole's lateral position in the right-sole frame or, mirrored, the
/// right sole's lateral position (negated) in the left-sole frame, whichever is larger.
///
/// Measuring in the right-sole frame only is not mirror-symmetric when the soles have different yaws: a
/// left foot landing ahead of a right foot turned by ψ to the left loses `Δx·sin ψ` of width, while the
/// mirrored step (right foot ahead of a left foot turned right) loses nothing. With `min_width ==
/// nominal_width` every right-turning step of the left foot was infeasible, so a start yawed by +1e-6 rad
/// crawled while −1e-6 rad walked. Either frame keeps the feet apart: if one sole's centre is at least
/// `min_width` (> the overlap bound checked by validation) off the other sole's axis, the sole outlines are
/// separated along that axis.
pub fn feet_lateral_separation(left: Pose2, right: Pose2) -> f64 {
    let left_in_right = right.inverse_transform_point(left.position()).y;
    let right_in_left = -left.inverse_transform_point(right.position()).y;
    left_in_right.max(right_in_left)
}

/// Maximum number of vertices of a support polygon (convex hull of two rectangles).
pub const MAX_POLYGON_VERTICES: usize = 8;

/// A convex polygon on the ground with at most [`MAX_POLYGON_VERTICES`] vertices, counter-clockwise.
/// Fixed capacity: building and querying it never allocates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SupportPolygon {
    /// Vertices; only the first `len` are meaningful.
    pub vertices: [Vector2<f64>; MAX_POLYGON_VERTICES],
    /// Number of vertices.
    pub len: usize,
}

impl Default for SupportPolygon {
    fn default() -> Self {
        Self {
            vertices: [Vector2::zeros(); MAX_POLYGON_VERTICES],
            len: 0,
        }
    }
}

impl SupportPolygon {
    /// The vertices (counter-clockwise).
    pub fn as_slice(&self) -> &[Vector2<f64>] {
        &self.vertices[..self.len]
    }

    /// Corners of a foot sole (rectangle `length` × `width` centred on the sole frame), CCW.
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

    /// Convex hull of up to 8 points (Andrew's monotone chain), without allocation.
    pub fn hull_of(points: &[Vector2<f64>]) -> Self {
        let n = points.len().min(MAX_POLYGON_VERTICES);
        let mut pts = [Vector2::zeros(); MAX_POLYGON_VERTICES];
        pts[..n].copy_from_slice(&points[..n]);
        // insertion sort by (x, y)
        for i in 1..n {
            let mut j = i;
            while j > 0
                && (pts[j - 1].x > pts[j].x
                    || (pts[j - 1].x == pts[j].x && pts[j - 1].y > pts[j].y))
            {
                pts.swap(j - 1, j);
                j -= 1;
            }
        }
        let cross = |o: Vector2<f64>, a: Vector2<f64>, b: Vector2<f64>| {
            (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x)
        };
        let mut hull = [Vector2::zeros(); 2 * MAX_POLYGON_VERTICES];
        let mut k = 0usize;
        for p in pts.iter().take(n) {
            while k >= 2 && cross(hull[k - 2], hull[k - 1], *p) <= 0.0 {
                k -= 1;
            }
            hull[k] = *p;
            k += 1;
        }
        let lower = k + 1;
        for i in (0..n.saturating_sub(1)).rev() {
            let p = pts[i];
            while k >= lower && cross(hull[k - 2], hull[k - 1], p) <= 0.0 {
                k -= 1;
            }
            hull[k] = p;
            k += 1;
        }
        let len = if n <= 1 {
            n
        } else {
            (k - 1).min(MAX_POLYGON_VERTICES)
        };
        let mut out = Self::default();
        out.vertices[..len].copy_from_slice(&hull[..len]);
        out.len = len;
        out
    }

    /// Signed distance of `p` from the polygon boundary: positive inside, negative outside (for points
    /// outside, the value is the most violated edge distance, a lower bound of the true distance).
    pub fn signed_distance(&self, p: Vector2<f64>) -> f64 {
        if self.len < 3 {
            return f64::NEG_INFINITY;
        }
        let mut d = f64::INFINITY;
        for i in 0..self.len {
            let a = self.vertices[i];
            let b = self.vertices[(i + 1) % self.len];
            let e = b - a;
            let n = e.norm();
            if n == 0.0 {
                continue;
            }
            // inward normal for CCW polygon: (-e.y, e.x)
            let dist = ((p.x - a.x) * (-e.y) + (p.y - a.y) * e.x) / n;
            d = d.min(dist);
        }
        d
    }

    /// Whether `p` is inside (or within `tolerance` \[m\] of) the polygon.
    pub fn contains(&self, p: Vector2<f64>, tolerance: f64) -> bool {
        self.signed_distance(p) >= -tolerance
    }
}
