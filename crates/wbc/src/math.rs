//! Small SO(3) helpers shared by the tasks.

use nalgebra::{UnitQuaternion, Vector3};

/// Logarithm of a rotation, `Log(R) ∈ R³` (axis times angle, angle in [0, π]).
///
/// Uses the quaternion with non-negative scalar part so the shortest rotation is returned.
pub fn so3_log(rotation: &UnitQuaternion<f64>) -> Vector3<f64> {
    let q = rotation.quaternion();
    let (w, v) = if q.w < 0.0 {
        (-q.w, -q.imag())
    } else {
        (q.w, q.imag())
    };
    let s = v.norm();
    if s < 1e-12 {
        // angle ≈ 2 s, axis·angle ≈ 2 v (first order), exact to O(s³)
        return v * 2.0;
    }
    let angle = 2.0 * s.atan2(w);
    v * (angle / s)
}

/// Orientation error `Log(R_ref Rᵀ)` expressed in the world frame [Romualdi 2022, eq. 7.1.8].
pub fn orientation_error(
    reference: &UnitQuaternion<f64>,
    current: &UnitQuaternion<f64>,
) -> Vector3<f64> {
    so3_log(&(reference * current.inverse()))
}

/// Skew-symmetric matrix with `skew(a) b = a × b` (stride-model's).
pub use stride_model::spatial::skew;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_inverts_exp() {
        for v in [
            Vector3::new(0.1, -0.2, 0.3),
            Vector3::new(3.0, 0.1, 0.0),
            Vector3::new(1e-9, 0.0, 2e-9),
            Vector3::zeros(),
        ] {
            let r = UnitQuaternion::from_scaled_axis(v);
            assert!((so3_log(&r) - v).norm() < 1e-12, "{v:?}");
        }
    }

    #[test]
    fn skew_is_cross_product() {
        let a = Vector3::new(1.0, -2.0, 0.5);
        let b = Vector3::new(0.3, 0.7, -1.1);
        assert!((skew(&a) * b - a.cross(&b)).norm() < 1e-15);
    }
}
