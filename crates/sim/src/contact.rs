//! The ground plane and the point-contact law (normal spring-damper that never pulls, Coulomb friction with a
//! stick-slip tangential spring).

use nalgebra::{Matrix3, Rotation3, Vector3};
use serde::{Deserialize, Serialize};

use crate::config::{ContactConfig, ContactSurfaceConfig, GroundConfig};

/// The ground: the plane through `origin` with unit `normal` (pointing out of the ground).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroundPlane {
    /// A point of the plane (world), m.
    pub origin: Vector3<f64>,
    /// Unit normal (world), pointing up out of the ground.
    pub normal: Vector3<f64>,
}

impl GroundPlane {
    /// The plane described by a [`GroundConfig`]: through `[0, 0, height]`, normal `R_x(roll) R_y(pitch) e_z`.
    pub fn from_config(config: &GroundConfig) -> Self {
        let [roll, pitch] = config.inclination;
        let rotation = Rotation3::from_axis_angle(&Vector3::x_axis(), roll)
            * Rotation3::from_axis_angle(&Vector3::y_axis(), pitch);
        Self {
            origin: Vector3::new(0.0, 0.0, config.height),
            normal: rotation * Vector3::z(),
        }
    }

    /// Signed height of `p` above the plane (negative: below, i.e. penetrating), m.
    pub fn height_of(&self, p: &Vector3<f64>) -> f64 {
        self.normal.dot(&(p - self.origin))
    }

    /// Orthogonal projection of `p` on the plane.
    pub fn project(&self, p: &Vector3<f64>) -> Vector3<f64> {
        p - self.normal * self.height_of(p)
    }

    /// Tangential part of a vector (`x − n nᵀ x`).
    pub fn tangential(&self, x: &Vector3<f64>) -> Vector3<f64> {
        x - self.normal * self.normal.dot(x)
    }
}

/// What a contact point is doing during a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ContactMode {
    /// Above the ground, or leaving it (no force).
    #[default]
    Separated,
    /// In contact, held by the tangential stick spring (inside the friction cone).
    Sticking,
    /// In contact and slipping: tangential force on the friction cone.
    Sliding,
}

/// Per-point contact parameters (already multiplied by the point's share of the surface area).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLaw {
    /// Normal stiffness, N/m.
    pub normal_stiffness: f64,
    /// Normal damping, N·s/m.
    pub normal_damping: f64,
    /// Tangential (stick) stiffness, N/m.
    pub tangential_stiffness: f64,
    /// Tangential (stick) damping, N·s/m.
    pub tangential_damping: f64,
    /// Coulomb coefficient.
    pub friction: f64,
}

impl PointLaw {
    /// The 3×3 stiffness (`K`) and damping (`D`) of the point in a given mode (`f = −K Δx − D v`).
    pub fn matrices(
        &self,
        mode: ContactMode,
        normal: &Vector3<f64>,
    ) -> (Matrix3<f64>, Matrix3<f64>) {
        let nn = normal * normal.transpose();
        match mode {
            ContactMode::Separated => (Matrix3::zeros(), Matrix3::zeros()),
            ContactMode::Sticking => (
                Matrix3::identity() * self.tangential_stiffness
                    + nn * (self.normal_stiffness - self.tangential_stiffness),
                Matrix3::identity() * self.tangential_damping
                    + nn * (self.normal_damping - self.tangential_damping),
            ),
            ContactMode::Sliding => (nn * self.normal_stiffness, nn * self.normal_damping),
        }
    }
}

/// A contact point of a surface: where it sits in the surface frame and its law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointSpec {
    /// Position in the surface's frame, m.
    pub local: Vector3<f64>,
    /// Its share of the surface (trapezoidal-rule weight; the weights of a surface sum to one).
    pub weight: f64,
    /// The point's law.
    pub law: PointLaw,
}

/// Trapezoidal-rule abscissae and weights of `n` points on `[-size/2, size/2]` (corners included; one point:
/// the centre with weight one). The weights sum to one.
pub fn trapezoid_nodes(n: usize, size: f64) -> impl Iterator<Item = (f64, f64)> {
    (0..n).map(move |i| {
        if n == 1 {
            (0.0, 1.0)
        } else {
            let s = -0.5 * size + size * i as f64 / (n - 1) as f64;
            let w = if i == 0 || i == n - 1 { 0.5 } else { 1.0 } / (n - 1) as f64;
            (s, w)
        }
    })
}

/// The grid points of a rectangular surface with the per-area law of `contact`.
pub fn surface_points(surface: &ContactSurfaceConfig, contact: &ContactConfig) -> Vec<PointSpec> {
    let area = surface.length * surface.width;
    // A degenerate (zero-area) surface still carries the densities over a unit "area" so it is not inert.
    let area = if area > 0.0 { area } else { 1.0 };
    let mut points = Vec::with_capacity(surface.grid[0] * surface.grid[1]);
    for (x, wx) in trapezoid_nodes(surface.grid[0], surface.length) {
        for (y, wy) in trapezoid_nodes(surface.grid[1], surface.width) {
            let weight = wx * wy;
            let share = area * weight;
            points.push(PointSpec {
                local: Vector3::new(
                    surface.offset[0] + x,
                    surface.offset[1] + y,
                    surface.offset[2],
                ),
                weight,
                law: PointLaw {
                    normal_stiffness: contact.normal_stiffness * share,
                    normal_damping: contact.normal_damping * share,
                    tangential_stiffness: contact.tangential_stiffness * share,
                    tangential_damping: contact.tangential_damping * share,
                    friction: contact.friction_coefficient,
                },
            });
        }
    }
    points
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trapezoid_weights_sum_to_one_and_integrate_quadratics_in_the_limit() {
        for n in [1, 2, 3, 5, 9] {
            let s: f64 = trapezoid_nodes(n, 0.2).map(|(_, w)| w).sum();
            assert!((s - 1.0).abs() < 1e-15);
        }
        // Second moment → l²/12 as the grid refines.
        let l = 0.2;
        let m: f64 = trapezoid_nodes(2001, l).map(|(x, w)| w * x * x).sum();
        assert!((m - l * l / 12.0).abs() < 1e-6 * l * l);
    }

    #[test]
    fn inclined_plane_descends_along_x_for_positive_pitch() {
        let g = GroundPlane::from_config(&GroundConfig {
            height: 0.0,
            inclination: [0.0, 0.1],
        });
        assert!(g.height_of(&Vector3::new(1.0, 0.0, 0.0)) > 0.0);
        assert!((g.normal.norm() - 1.0).abs() < 1e-15);
        let p = Vector3::new(0.3, 0.2, 0.5);
        assert!(g.height_of(&g.project(&p)).abs() < 1e-15);
    }
}
