//! Offset of a six-axis force/torque sensor from rotations of the body attached to it, without knowing
//! that body's inertial parameters or the calibration matrix [Traversaro 2017, §5.3.2, eqs. (5.6)–(5.10)].

use nalgebra::{Matrix3, Matrix6, SymmetricEigen, Vector3, Vector6};

use super::check::{check_pairs, fit_gravity_response};
use super::CalibrationError;

/// Minimum number of static poses: the 12 unknowns of (5.10) need 4 gravity directions.
pub const MIN_POSES: usize = 4;

/// The offset found by [`offset_from_rotations`].
#[derive(Clone, Debug, PartialEq)]
pub struct RotationOffset {
    /// Offset `b` of the raw readings, `[f; τ]` (the raw space's units; N, N·m for a sensor whose
    /// calibration is near identity).
    pub offset: Vector6<f64>,
    /// Singular values of the centred readings, decreasing (5.7): three large ones, the other three at the
    /// noise level when the readings lie on the 3D ellipsoid of Lemma 5.1.
    pub singular_values: Vector6<f64>,
    /// `K = U₁ᵀ C⁻¹ M(m, c)` of (5.10): how the gravity maps to the readings' 3D subspace.
    pub k: Matrix3<f64>,
    /// RMS residual of (5.10) per sample, raw units.
    pub residual_rms: f64,
}

/// The offset `b` of the affine sensor model `f = C (r − b)` (5.1) from raw readings `raw[i]` taken at
/// static poses where only gravity loads the body attached to the sensor, with `gravity[i]` the gravity
/// acceleration in the sensor frame at that pose (an accelerometer on the body, or the kinematics) [Traversaro
/// 2017, §5.3.2]:
///
/// 1. the mean `r_m` (5.6) and the three principal directions `U₁` of the centred readings (5.7) (from the
///    6 × 6 scatter matrix, which has the left singular vectors of (5.7));
/// 2. `U₁ᵀ (r_i − r_m) = K g_i + λ_b` (5.10), stacked as `(g_iᵀ ⊗ 1₃) vec(K) + λ_b` (2.9) and solved by
///    least squares for `(vec K, λ_b)`;
/// 3. `b = r_m + U₁ λ_b` (5.8).
///
/// Needs neither `C` nor the body's mass: only that gravity takes at least four directions that do not lie
/// on one plane of the sensor frame (the body rotated about two axes); otherwise
/// [`CalibrationError::NotIdentifiable`].
pub fn offset_from_rotations(
    raw: &[Vector6<f64>],
    gravity: &[Vector3<f64>],
) -> Result<RotationOffset, CalibrationError> {
    check_pairs("offset from rotations", raw, gravity)?;
    let n = raw.len() as f64;
    let mean = raw.iter().sum::<Vector6<f64>>() / n;
    let mut scatter = Matrix6::zeros();
    for r in raw {
        let d = r - mean;
        scatter += d * d.transpose();
    }
    let (u1, singular_values) = principal_directions(&scatter);
    // (5.10): U₁ᵀ (r_i − r_m) = K g_i + λ_b.
    let projected = raw.iter().map(|r| u1.transpose() * (r - mean));
    let sol = fit_gravity_response("the offset", projected.zip(gravity.iter().copied()))?;
    let k = Matrix3::from_column_slice(&sol.x.as_slice()[0..9]);
    let lambda = Vector3::new(sol.x[9], sol.x[10], sol.x[11]);
    Ok(RotationOffset {
        offset: mean + u1 * lambda,
        singular_values,
        k,
        residual_rms: (sol.residual_squared / n).sqrt(),
    })
}

/// The three leading eigenvectors of the symmetric scatter matrix (the first three left singular vectors of
/// the centred readings) and the six singular values `√λ`, decreasing.
fn principal_directions(scatter: &Matrix6<f64>) -> (nalgebra::Matrix6x3<f64>, Vector6<f64>) {
    let eig = SymmetricEigen::new(*scatter);
    let mut order: Vec<usize> = (0..6).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let mut u1 = nalgebra::Matrix6x3::zeros();
    for (c, &i) in order.iter().take(3).enumerate() {
        u1.set_column(c, &eig.eigenvectors.column(i));
    }
    let s = Vector6::from_iterator(order.iter().map(|&i| eig.eigenvalues[i].max(0.0).sqrt()));
    (u1, s)
}
