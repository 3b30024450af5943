//! How far a loaded sole has sunk into a compliant ground: the displacement of the sole frame's origin from
//! its zero-force position, from the foot's measured force.
//!
//! The ground is a bed of independent visco-elastic springs under the whole sole (a Winkler foundation, the
//! continuum model of [Romualdi 2022, eq. 8.1.6]): each area element pushes back with the density
//! `ρ = −k s − b ṡ` (N/m²) where `s` is its displacement from where it touched the ground. For a sole wholly
//! in contact whose origin is the centroid of its rectangle, the force is `f = −A (k s + b ṡ)` with `A` the
//! sole's area and `s` the origin's displacement, whatever the sole's tilt (a tilt adds a displacement
//! linear in the position on the sole, whose integral over the centred rectangle is zero; it gives the
//! moment, not the force; Lemma 1 of [Romualdi 2022] at small tilt). So the origin's displacement follows
//! the measured force through a first-order lag,
//!
//! `ṡ = −(f/A + k s) / b`, at rest `s = −f / (k A)`,
//!
//! the same law on every axis (an isotropic ground: the thesis's density is a vector). The bundled humanoid
//! standing on `k = 1e6` N/m³ sinks 8.9 mm per sole; on the default floor (`k = 3e8`) 0.03 mm.
//!
//! The estimator's EKF takes a stance foot's contact point as static [Hartley 2020]: on a compliant ground it
//! is the sole's zero-force point that is static, not the sole, which sinks and rises with its load and
//! slides with the tangential force. With the sink, the contact point is that zero-force point and the
//! kinematics measure it as the sole's position minus its sink.

use nalgebra::Vector3;

use crate::error::{check_non_negative, check_positive, Result};

/// The ground under the soles as the estimator models it (`EstimatorConfig::ground_stiffness`,
/// `ground_damping`, `sole_size`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SoleSink {
    /// `k A` \[N/m\]; infinite: a rigid ground (no sink).
    stiffness: f64,
    /// `b A` \[N·s/m\].
    damping: f64,
}

impl SoleSink {
    /// The sink of a sole of area `area` (m²) on a ground of stiffness density `stiffness` (N/m³) and
    /// damping density `damping` (N·s/m³). `stiffness = 0` is a rigid ground: the sink is always zero.
    ///
    /// # Errors
    /// A negative or non-finite stiffness or damping, a non-positive area.
    pub fn new(stiffness: f64, damping: f64, area: f64) -> Result<Self> {
        check_non_negative("ground_stiffness", stiffness)?;
        check_non_negative("ground_damping", damping)?;
        check_positive("sole_size", area)?;
        let stiffness = if stiffness == 0.0 {
            f64::INFINITY
        } else {
            stiffness * area
        };
        Ok(Self {
            stiffness,
            damping: damping * area,
        })
    }

    /// Whether the ground is rigid (the sink is always zero).
    pub fn rigid(&self) -> bool {
        self.stiffness.is_infinite()
    }

    /// The sink at rest under the force `force` (N, of the ground on the foot): `−f / (k A)`; zero when the
    /// ground does not push (`f_z ≤ 0`: the sole is off it, or the estimate is wrong).
    pub fn at_rest(&self, force: &Vector3<f64>) -> Vector3<f64> {
        if self.rigid() || force.z <= 0.0 {
            return Vector3::zeros();
        }
        -force / self.stiffness
    }

    /// The sink `dt` (s) after `sink` (m) under a force `force` held over the interval: the exact solution of
    /// `ṡ = −(f/A + k s)/b`, `s(dt) = s_∞ + (s − s_∞) e^{−k dt / b}` with `s_∞` [`Self::at_rest`]; without
    /// damping, `s_∞`.
    pub fn step(&self, sink: &Vector3<f64>, force: &Vector3<f64>, dt: f64) -> Vector3<f64> {
        let rest = self.at_rest(force);
        if self.rigid() || self.damping == 0.0 {
            return rest;
        }
        let decay = (-self.stiffness * dt / self.damping).exp();
        rest + (sink - rest) * decay
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_standing_sole_sinks_by_its_load_over_the_ground_stiffness() {
        // The bundled humanoid's 160.2 N per sole on k = 1e6 N/m³ under a 0.20 × 0.09 m sole: 8.9 mm down.
        let sink = SoleSink::new(1e6, 1e4, 0.2 * 0.09).unwrap();
        let s = sink.at_rest(&Vector3::new(10.0, -5.0, 160.2));
        assert!((s.z + 8.9e-3).abs() < 1e-12);
        // A tangential force pushes the sole the other way from its zero-force point.
        assert!((s.x + 10.0 / 18_000.0).abs() < 1e-15);
        assert!((s.y - 5.0 / 18_000.0).abs() < 1e-15);
    }

    #[test]
    fn the_sink_lags_the_force_by_the_ground_time_constant() {
        // τ = b/k = 10 ms: after one τ under a step of force, 1 − 1/e of the way.
        let sink = SoleSink::new(1e6, 1e4, 0.018).unwrap();
        let f = Vector3::new(0.0, 0.0, 180.0);
        let s = sink.step(&Vector3::zeros(), &f, 0.01);
        let rest = sink.at_rest(&f);
        assert!((s.z - rest.z * (1.0 - (-1.0_f64).exp())).abs() < 1e-15);
        // Two half steps are one step (exact discretisation).
        let half = sink.step(&sink.step(&Vector3::zeros(), &f, 0.005), &f, 0.005);
        assert!((half - s).norm() < 1e-15);
        // It converges to the rest sink and stays there.
        let mut x = Vector3::zeros();
        for _ in 0..1000 {
            x = sink.step(&x, &f, 0.001);
        }
        assert!((x - rest).norm() < 1e-12);
        // Without damping it is the rest sink at once.
        let undamped = SoleSink::new(1e6, 0.0, 0.018).unwrap();
        assert_eq!(undamped.step(&Vector3::zeros(), &f, 1e-3), rest);
    }

    #[test]
    fn a_rigid_ground_never_sinks_and_bad_parameters_are_refused() {
        let rigid = SoleSink::new(0.0, 1e4, 0.018).unwrap();
        assert!(rigid.rigid());
        let f = Vector3::new(3.0, 2.0, 300.0);
        assert_eq!(rigid.at_rest(&f), Vector3::zeros());
        assert_eq!(rigid.step(&Vector3::zeros(), &f, 1e-3), Vector3::zeros());
        // The ground does not pull: a sole whose estimated force pulls it has not sunk.
        let soft = SoleSink::new(1e6, 1e4, 0.018).unwrap();
        assert_eq!(
            soft.at_rest(&Vector3::new(5.0, 0.0, -2.0)),
            Vector3::zeros()
        );
        assert!(SoleSink::new(-1.0, 0.0, 0.018).is_err());
        assert!(SoleSink::new(1e6, f64::NAN, 0.018).is_err());
        assert!(SoleSink::new(1e6, 0.0, 0.0).is_err());
    }
}
