//! The soles' zero-force poses on soft ground, the footholds the planner starts from when the TSID models
//! the ground as visco-elastic (`[wbc.tsid] contact_model = "compliant"`).
//!
//! A loaded sole sinks into a soft ground by `f_z / (k l w |e₃ᵀRe₃|)` (Lemma 1 at zero velocity,
//! [Romualdi 2022, eq. 8.1.7a]): 9 mm per foot for the bundled humanoid standing on `k = 1e6` N/m³. Planning
//! from the sunk soles puts every later foothold that much below the ground's surface, so each swing foot
//! strikes the ground before its planned touch-down while the controller still tracks it as a swing foot.
//! Planning from the zero-force poses (the sole raised by its sink, the rest pose the compliant TSID gives a
//! loaded contact) lands the swing foot on the surface.

use nalgebra::{Isometry3, Vector6};

/// `sole` raised by the static sink of its measured wrench `wrench` (world force, N) on a ground of
/// stiffness density `stiffness` (N/m³) under a sole of area `area` (m²): the zero-force pose of
/// [Romualdi 2022, eq. 8.1.7a] at zero velocity. An unloaded sole (f_z ≤ 0), a non-positive stiffness or
/// area, or a sole on its edge (e₃ᵀRe₃ = 0) is returned unchanged.
pub fn zero_force_sole(
    sole: &Isometry3<f64>,
    wrench: &Vector6<f64>,
    stiffness: f64,
    area: f64,
) -> Isometry3<f64> {
    let tilt = sole.rotation.to_rotation_matrix()[(2, 2)].abs();
    let scale = stiffness * area * tilt;
    let mut raised = *sole;
    if wrench.z > 0.0 && scale > 0.0 && scale.is_finite() {
        raised.translation.vector.z += wrench.z / scale;
    }
    raised
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Translation3, UnitQuaternion, Vector3};

    #[test]
    fn a_loaded_flat_sole_rises_by_its_static_sink() {
        let sole = Isometry3::from_parts(
            Translation3::new(0.1, 0.075, -0.0089),
            UnitQuaternion::identity(),
        );
        let w = Vector6::new(0.0, 0.0, 160.2, 0.0, 0.0, 0.0);
        let raised = zero_force_sole(&sole, &w, 1e6, 0.2 * 0.09);
        // 160.2 N / (1e6 N/m³ · 0.018 m²) = 8.9 mm: back on the surface z = 0
        assert!((raised.translation.z - 0.0).abs() < 1e-12);
        assert_eq!(raised.translation.x, 0.1);
        assert_eq!(raised.rotation, sole.rotation);
    }

    #[test]
    fn a_tilted_sole_sinks_by_the_projected_area_and_an_unloaded_one_stays() {
        let tilt = 0.3_f64;
        let sole = Isometry3::from_parts(
            Translation3::new(0.0, 0.0, -0.01),
            UnitQuaternion::from_axis_angle(&Vector3::y_axis(), tilt),
        );
        let w = Vector6::new(0.0, 0.0, 100.0, 0.0, 0.0, 0.0);
        let raised = zero_force_sole(&sole, &w, 2e6, 0.01);
        let expected = -0.01 + 100.0 / (2e6 * 0.01 * tilt.cos());
        assert!((raised.translation.z - expected).abs() < 1e-12);
        let pulled = Vector6::new(0.0, 0.0, -5.0, 0.0, 0.0, 0.0);
        assert_eq!(zero_force_sole(&sole, &pulled, 2e6, 0.01), sole);
        assert_eq!(zero_force_sole(&sole, &w, 0.0, 0.01), sole);
    }
}
