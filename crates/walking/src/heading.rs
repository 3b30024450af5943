//! The heading of a stance, the one rule for the torso's yaw reference.

use nalgebra::Isometry3;
use stride_planner::geometry::wrap_angle;

/// Heading of a stance: the mean of the two soles' yaws (about world z), taken the shorter way round,
/// `ψ = ψ_l + ½·wrap(ψ_r − ψ_l)` \[rad\].
///
/// The walking stack uses it as the torso's yaw reference (the torso upright, facing the mean of the
/// feet yaws).
///
/// ```
/// use nalgebra::{Isometry3, Vector3};
/// let left = Isometry3::new(Vector3::zeros(), Vector3::z() * 0.2);
/// let right = Isometry3::new(Vector3::zeros(), Vector3::z() * 0.4);
/// assert!((stride_walking::soles_heading(&left, &right) - 0.3).abs() < 1e-12);
/// ```
pub fn soles_heading(left: &Isometry3<f64>, right: &Isometry3<f64>) -> f64 {
    let yl = left.rotation.euler_angles().2;
    let yr = right.rotation.euler_angles().2;
    yl + 0.5 * wrap_angle(yr - yl)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;
    use std::f64::consts::PI;

    #[test]
    fn heading_takes_the_shorter_way_round() {
        let left = Isometry3::new(Vector3::zeros(), Vector3::z() * (PI - 0.1));
        let right = Isometry3::new(Vector3::zeros(), Vector3::z() * (-PI + 0.1));
        let h = wrap_angle(soles_heading(&left, &right));
        assert!((h.abs() - PI).abs() < 1e-12, "heading {h}");
    }
}
