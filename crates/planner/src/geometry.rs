//! Small planar geometry helpers: planar poses and angles (the support polygon is
//! [`stride_block::SupportPolygon`], re-exported by this crate).

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector2, Vector3};
use serde::{Deserialize, Serialize};

pub use stride_block::wrap_angle;

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
