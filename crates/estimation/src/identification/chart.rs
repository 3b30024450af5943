//! The local chart of the fully consistent parametrisation θ = (m, c, Q, L) used by the manifold solver
//! [Traversaro 2017, §6.3.2, eq. (6.28)]: a step `z = (δm, δc, δQ, δL) ∈ R¹⁰` moves θ to
//! `(m + δm, c + δc, Q exp(δQ^), L + δL)` with `m` and `L` kept non-negative, so every iterate is a
//! physical body (Theorem 6.1); the Jacobian of `π_p` in that chart drives the Gauss–Newton steps.

use nalgebra::{Matrix3, Rotation3, SMatrix, SymmetricEigen, Vector3};
use stride_model::inertial::{mass_com_inertia, vech, InertialParameters, PhysicalParameters};

/// `∂π_p / ∂z` at `z = 0`: 10 × 10, columns `(δm, δc_x, δc_y, δc_z, δQ_x, δQ_y, δQ_z, δL_x, δL_y, δL_z)`.
pub type ChartJacobian = SMatrix<f64, 10, 10>;

fn hat(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// The Jacobian of `π_p(θ) = [m; m c; vech(Q diag(P L) Qᵀ − m S(c) S(c))]` [Traversaro 2017, §6.3.2] with
/// respect to the chart step `z` (rotation perturbed on the right, `Q exp(δQ^)`):
/// `∂/∂m = [1; c; vech(−S(c)²)]`, `∂/∂c_k = [0; m e_k; vech(−m (S(e_k) S(c) + S(c) S(e_k)))]`,
/// `∂/∂δQ_k = [0; 0; vech(Q (S(e_k) D − D S(e_k)) Qᵀ)]` with `D = diag(P L)`,
/// `∂/∂L_k = [0; 0; vech(Q diag(P e_k) Qᵀ)]`.
pub fn chart_jacobian(theta: &PhysicalParameters) -> ChartJacobian {
    let (m, c) = (theta.mass, theta.com);
    let q = *theta.principal_axes.matrix();
    let d = Matrix3::from_diagonal(&theta.principal_moments());
    let sc = hat(&c);
    let mut jac = ChartJacobian::zeros();
    let mut set = |col: usize, head: [f64; 4], inertia: &Matrix3<f64>| {
        for (r, v) in head.iter().chain(vech(inertia).iter()).enumerate() {
            jac[(r, col)] = *v;
        }
    };
    set(0, [1.0, c.x, c.y, c.z], &(-sc * sc));
    for k in 0..3 {
        let e = Vector3::ith(k, 1.0);
        let se = hat(&e);
        let mut head = [0.0; 4];
        head[1 + k] = m;
        set(1 + k, head, &(-(se * sc + sc * se) * m));
        set(4 + k, [0.0; 4], &(q * (se * d - d * se) * q.transpose()));
        let p_col = Vector3::new(1.0, 1.0, 1.0) - e;
        set(
            7 + k,
            [0.0; 4],
            &(q * Matrix3::from_diagonal(&p_col) * q.transpose()),
        );
    }
    jac
}

/// θ moved by the chart step `z` (see [`chart_jacobian`]), with `m` and `L` clamped at zero: always in
/// 𝔓, so always a physical body.
pub fn retract(theta: &PhysicalParameters, z: &[f64]) -> PhysicalParameters {
    let rot = Rotation3::new(Vector3::new(z[4], z[5], z[6]));
    PhysicalParameters {
        mass: (theta.mass + z[0]).max(0.0),
        com: theta.com + Vector3::new(z[1], z[2], z[3]),
        principal_axes: Rotation3::from_matrix(&(theta.principal_axes * rot).into_inner()),
        second_moments: (theta.second_moments + Vector3::new(z[7], z[8], z[9])).map(|l| l.max(0.0)),
    }
}

/// The θ closest to any `π` in the sense of the parametrisation: mass clamped at zero, CoM `mc/m` (zero
/// without mass), principal axes of `I_C` (right-handed) and the central second moments `L = P⁻¹ J`
/// clamped at zero. Equal to [`PhysicalParameters::from_inertial_parameters`] up to the axes' order and
/// signs when `π` is fully consistent; the start (and prior) of the manifold solver for URDF links that
/// are not (zero masses, triangle inequalities violated).
pub fn nearest_physical(pi: &InertialParameters) -> PhysicalParameters {
    let (mass, com, i_c) = mass_com_inertia(pi);
    let eig = SymmetricEigen::new(i_c);
    let mut q = eig.eigenvectors;
    if q.determinant() < 0.0 {
        q.set_column(2, &(-q.column(2)));
    }
    let j = eig.eigenvalues;
    let l = Vector3::new(j.y + j.z - j.x, j.x + j.z - j.y, j.x + j.y - j.z) / 2.0;
    PhysicalParameters {
        mass: mass.max(0.0),
        com: if mass > 0.0 { com } else { Vector3::zeros() },
        principal_axes: Rotation3::from_matrix(&q),
        second_moments: l.map(|v| v.max(0.0)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use stride_model::inertial::check_full_consistency;

    fn theta() -> PhysicalParameters {
        PhysicalParameters {
            mass: 1.7,
            com: Vector3::new(0.03, -0.12, 0.2),
            principal_axes: Rotation3::from_euler_angles(0.4, -0.7, 1.9),
            second_moments: Vector3::new(0.011, 0.004, 0.027),
        }
    }

    /// Central differences of `π_p(retract(θ, h e_k))` against [`chart_jacobian`], column by column.
    #[test]
    fn chart_jacobian_matches_finite_differences() {
        let t = theta();
        let jac = chart_jacobian(&t);
        let h = 1e-6;
        for k in 0..10 {
            let mut z = [0.0; 10];
            z[k] = h;
            let plus = retract(&t, &z).to_inertial_parameters();
            z[k] = -h;
            let minus = retract(&t, &z).to_inertial_parameters();
            let fd = (plus - minus) / (2.0 * h);
            let err = (fd - jac.column(k)).amax();
            assert!(err < 1e-7 * (1.0 + fd.amax()), "column {k}: error {err:e}");
        }
    }

    /// Retraction stays in 𝔓 (full consistency) even for steps that would make m or L negative, and the
    /// nearest θ of a consistent π gives it back.
    #[test]
    fn retraction_stays_physical_and_nearest_inverts() {
        let t = theta();
        let wild = [-5.0, 1.0, -2.0, 3.0, 2.0, -1.0, 0.5, -1.0, 0.3, -0.5];
        let moved = retract(&t, &wild);
        assert_eq!(moved.mass, 0.0);
        assert!(moved.second_moments.iter().all(|l| *l >= 0.0));
        let small = [0.1, 0.01, 0.0, 0.02, 0.3, -0.2, 0.1, -0.001, 0.002, 0.0];
        let pi = retract(&t, &small).to_inertial_parameters();
        assert!(check_full_consistency(&pi).is_ok());
        let back = nearest_physical(&pi).to_inertial_parameters();
        assert!((back - pi).amax() < 1e-12);
        // A π violating the triangle inequality is clamped onto the boundary of 𝔓.
        let mut bad = pi;
        bad[9] += 1.0;
        assert!(check_full_consistency(&bad).is_err());
        assert!(check_full_consistency(&nearest_physical(&bad).to_inertial_parameters()).is_ok());
    }
}
