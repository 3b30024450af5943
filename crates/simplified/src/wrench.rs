//! Measured ZMP from the feet contact wrenches ([Romualdi 2022, eq. 4.2.4] generalised to several feet).

use nalgebra::{Vector2, Vector3, Vector6};
use serde::{Deserialize, Serialize};

use crate::error::{Result, SimplifiedError};

/// The contact wrench the ground applies on one foot.
///
/// | field | unit | meaning |
/// |---|---|---|
/// | `wrench` | N, N·m | `[f; τ]` in world orientation, the torque taken about `point` |
/// | `point` | m | world position of the point the torque is expressed about (e.g. the sole or the F/T sensor) |
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FootWrench {
    /// `[force; torque]` \[N; N·m\], world orientation, torque about `point`.
    pub wrench: Vector6<f64>,
    /// World position \[m\] the torque is taken about.
    pub point: Vector3<f64>,
}

/// Global ZMP \[m\] on the plane `z = ground_height` from the wrenches of the feet in contact.
///
/// The total wrench about the world origin is `F = Σ fᵢ`, `T = Σ (τᵢ + rᵢ × fᵢ)`. The ZMP is the point
/// `p = (pₓ, p_y, h)` about which the horizontal torque vanishes: `pₓ = (h Fₓ − T_y) / F_z`,
/// `p_y = (h F_y + Tₓ) / F_z` — for one foot and `h = 0` this is [Romualdi 2022, eq. 4.2.4] `[−μ_y/f_z; μ_x/f_z]`.
///
/// Errors: `NonFiniteInput` for a NaN/infinite wrench, point or height; `InvalidParameter` when
/// `min_normal_force` is not finite and > 0; `InsufficientNormalForce` when `F_z < min_normal_force`
/// (feet unloaded or in the air: the ZMP is undefined; callers usually hold the previous value).
pub fn measured_zmp(
    feet: &[FootWrench],
    ground_height: f64,
    min_normal_force: f64,
) -> Result<Vector2<f64>> {
    crate::error::check_positive("min_normal_force", min_normal_force)?;
    crate::error::check_finite("ground_height", ground_height)?;
    let mut force = Vector3::zeros();
    let mut torque = Vector3::zeros();
    for foot in feet {
        if foot.wrench.iter().any(|v| !v.is_finite()) {
            return Err(SimplifiedError::NonFiniteInput {
                name: "foot wrench",
            });
        }
        if foot.point.iter().any(|v| !v.is_finite()) {
            return Err(SimplifiedError::NonFiniteInput {
                name: "foot wrench point",
            });
        }
        let f: Vector3<f64> = foot.wrench.fixed_rows::<3>(0).into();
        let tau: Vector3<f64> = foot.wrench.fixed_rows::<3>(3).into();
        force += f;
        torque += tau + foot.point.cross(&f);
    }
    if force.z.is_nan() || force.z < min_normal_force {
        return Err(SimplifiedError::InsufficientNormalForce {
            normal_force: force.z,
            minimum: min_normal_force,
        });
    }
    let h = ground_height;
    Ok(Vector2::new(
        (h * force.x - torque.y) / force.z,
        (h * force.y + torque.x) / force.z,
    ))
}
