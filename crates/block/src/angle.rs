//! Planar angles.

use std::f64::consts::{PI, TAU};

/// Wraps an angle \[rad\] to (−π, π].
///
/// The one implementation every layer uses (the planner's headings, the estimator's sole spin): a yaw
/// difference taken across ±π is the short way round.
pub fn wrap_angle(a: f64) -> f64 {
    let r = a % TAU;
    if r > PI {
        r - TAU
    } else if r <= -PI {
        r + TAU
    } else {
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wraps_into_the_half_open_interval() {
        assert_eq!(wrap_angle(0.25), 0.25);
        assert!((wrap_angle(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-15);
        assert!((wrap_angle(-3.0 * PI / 2.0) - PI / 2.0).abs() < 1e-15);
        assert!((wrap_angle(7.0 * TAU + 0.1) - 0.1).abs() < 1e-12);
        // −π maps to π: the interval is (−π, π].
        assert_eq!(wrap_angle(-PI), PI);
        assert_eq!(wrap_angle(PI), PI);
    }
}
