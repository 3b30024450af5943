//! The fully consistent parametrisation θ = (m, c, Q, L) of a rigid body [Traversaro 2017, §6.3.2,
//! Theorem 6.1]: every θ with `m ≥ 0`, `L ≥ 0` maps to fully physically consistent parameters, so an
//! identification over θ never leaves the set of physical bodies.

use nalgebra::{Matrix3, Rotation3, Vector3};

use super::consistency::{check_full_consistency, mass_com_inertia, InertiaViolation};
use super::rigid_body::{inertial_parameters, InertialParameters};

/// θ = (m, c, Q, L) ∈ 𝔓 = R≥0 × R³ × SO(3) × R³≥0 [Traversaro 2017, §6.3.2].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhysicalParameters {
    /// Mass `m ≥ 0` (kg).
    pub mass: f64,
    /// Centre of mass `c` in the body frame (m).
    pub com: Vector3<f64>,
    /// `Q`: orientation of the principal axes in the body frame (`I_C = Q diag(J) Qᵀ`).
    pub principal_axes: Rotation3<f64>,
    /// Central second moments of mass `L ≥ 0` along the principal axes (kg·m²), `L_x = ∭ x̃² ρ̃` (6.16).
    pub second_moments: Vector3<f64>,
}

impl PhysicalParameters {
    /// Principal moments of inertia `J = P L`, `P = [[0,1,1],[1,0,1],[1,1,0]]` (6.15) (kg·m²).
    pub fn principal_moments(&self) -> Vector3<f64> {
        let l = &self.second_moments;
        Vector3::new(l.y + l.z, l.x + l.z, l.x + l.y)
    }

    /// `π_p(θ) = [m; m c; vech(Q diag(P L) Qᵀ − m S(c) S(c))]` [Traversaro 2017, §6.3.2]. Fully consistent
    /// when `m ≥ 0` and `L ≥ 0` (Theorem 6.1): it is the π of a uniform cuboid of mass `m` centred at `c`,
    /// axes `Q`, half-sides [`Self::cuboid_half_sides`].
    pub fn to_inertial_parameters(&self) -> InertialParameters {
        let q = self.principal_axes.matrix();
        let i_c = q * Matrix3::from_diagonal(&self.principal_moments()) * q.transpose();
        inertial_parameters(self.mass, &self.com, &i_c)
    }

    /// θ of fully consistent parameters (the inverse of [`Self::to_inertial_parameters`] up to the
    /// ordering and signs of the principal axes): `c = mc/m`, `I_C = Q diag(J) Qᵀ` (eigen-decomposition,
    /// `det Q = 1`), `L = P⁻¹ J` with tolerance-sized negatives set to zero.
    ///
    /// # Errors
    /// The [`InertiaViolation`] of [`check_full_consistency`].
    pub fn from_inertial_parameters(
        pi: &InertialParameters,
    ) -> Result<PhysicalParameters, InertiaViolation> {
        check_full_consistency(pi)?;
        let (mass, com, i_c) = mass_com_inertia(pi);
        let eig = nalgebra::SymmetricEigen::new(i_c);
        let mut q = eig.eigenvectors;
        if q.determinant() < 0.0 {
            q.set_column(2, &(-q.column(2)));
        }
        let j = eig.eigenvalues;
        let l = Vector3::new(
            (j.y + j.z - j.x) / 2.0,
            (j.x + j.z - j.y) / 2.0,
            (j.x + j.y - j.z) / 2.0,
        )
        .map(|v| v.max(0.0));
        Ok(PhysicalParameters {
            mass,
            com,
            principal_axes: Rotation3::from_matrix_unchecked(q),
            second_moments: l,
        })
    }

    /// Half-sides `d_i = √(3 L_i / m)` of the uniform cuboid with these parameters (6.22) (m; zero for a
    /// zero mass).
    pub fn cuboid_half_sides(&self) -> Vector3<f64> {
        if self.mass > 0.0 {
            self.second_moments
                .map(|l| (3.0 * l.max(0.0) / self.mass).sqrt())
        } else {
            Vector3::zeros()
        }
    }
}
