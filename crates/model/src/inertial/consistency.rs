//! Physical consistency of inertial parameters [Traversaro 2017, §6.2.5–6.3.1].
//!
//! * **Consistency** (Definition 6.1, Yoshida): `m > 0` and `I_C ⪰ 0` (6.20), `I_C = I_B + m S(c) S(c)` the
//!   inertia about the CoM. Enough for an invertible mass matrix, not for a physical body.
//! * **Full consistency** (Definition 6.2): some non-negative density gives π (6.21). Equivalent to
//!   consistency plus the triangle inequalities of the principal moments `J` of `I_C`,
//!   `J_i ≤ J_j + J_k` (6.18), i.e. non-negative central second moments `L = P⁻¹ J`,
//!   `L_i = (J_j + J_k − J_i)/2` (6.15)–(6.17) (the eigenvalues of the second-moment matrix
//!   `Σ_C = ½ tr(I_C) 1 − I_C`).
//!
//! A zero-mass body is reported as not consistent (`m > 0` fails) although it is harmless in a tree whose
//! other bodies carry its joint's inertia: the checks say what fails, the caller decides.

use nalgebra::{Matrix3, SymmetricEigen, Vector3};

use super::rigid_body::{inertia_about_origin, InertialParameters};
use crate::model::Model;
use crate::spatial::skew;

/// Which condition of (6.20)/(6.18) a parameter vector fails, with the numbers.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum InertiaViolation {
    /// `m > 0` fails (6.20).
    #[error("mass {mass} kg is not positive")]
    NonPositiveMass {
        /// The mass (kg).
        mass: f64,
    },
    /// `I_C ⪰ 0` fails (6.20): a principal moment about the CoM is negative.
    #[error("rotational inertia about the CoM is not positive semi-definite (principal moments {moments:?} kg·m²)")]
    NegativeMoment {
        /// Principal moments `J` about the CoM, increasing (kg·m²).
        moments: [f64; 3],
    },
    /// A triangle inequality `J_i ≤ J_j + J_k` fails (6.18): the central second moment
    /// `L_i = (J_j + J_k − J_i)/2` along principal axis `axis` is negative.
    #[error("principal moments {moments:?} kg·m² violate the triangle inequality (second moment {second_moment:e} kg·m² < 0 along principal axis {axis})")]
    TriangleInequality {
        /// Principal moments `J` about the CoM, increasing (kg·m²).
        moments: [f64; 3],
        /// Index (into `moments`) of the principal axis whose second moment is negative.
        axis: usize,
        /// That second moment `L_axis` (kg·m², negative).
        second_moment: f64,
    },
}

/// A violation found in a body of a model.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyInertiaViolation {
    /// Index into [`Model::bodies`].
    pub body: usize,
    /// Body name (the URDF link defining the body frame).
    pub name: String,
    /// What fails.
    pub violation: InertiaViolation,
}

/// Mass, CoM (m) and rotational inertia about the CoM (kg·m², body axes) of `π`; the CoM is the origin
/// when the mass is zero.
pub fn mass_com_inertia(pi: &InertialParameters) -> (f64, Vector3<f64>, Matrix3<f64>) {
    let m = pi[0];
    let c = if m != 0.0 {
        Vector3::new(pi[1], pi[2], pi[3]) / m
    } else {
        Vector3::zeros()
    };
    let s = skew(&c);
    (m, c, inertia_about_origin(pi) + s * s * m)
}

/// Principal moments of inertia about the CoM, increasing (kg·m²).
pub fn principal_moments(pi: &InertialParameters) -> [f64; 3] {
    let (_, _, i_c) = mass_com_inertia(pi);
    let e = SymmetricEigen::new(i_c).eigenvalues;
    let mut j = [e[0], e[1], e[2]];
    j.sort_by(f64::total_cmp);
    j
}

/// The absolute tolerance (kg·m²) for moments of magnitude up to `scale`: `1e-9 · scale + 1e-12` (the URDF
/// loader's).
fn tolerance(scale: f64) -> f64 {
    1e-9 * scale.abs() + 1e-12
}

/// Checks consistency (Definition 6.1, (6.20)): `m > 0` and `I_C ⪰ 0` up to a relative tolerance of 1e-9.
///
/// # Errors
/// The first condition that fails.
pub fn check_consistency(pi: &InertialParameters) -> Result<(), InertiaViolation> {
    if pi[0] <= 0.0 || pi[0].is_nan() {
        return Err(InertiaViolation::NonPositiveMass { mass: pi[0] });
    }
    let moments = principal_moments(pi);
    if moments[0] < -tolerance(moments[2]) {
        return Err(InertiaViolation::NegativeMoment { moments });
    }
    Ok(())
}

/// Checks full consistency (Definition 6.2): consistency and the triangle inequalities (6.18), up to a
/// relative tolerance of 1e-9.
///
/// # Errors
/// The first condition that fails; for the triangle inequalities, the most negative second moment.
pub fn check_full_consistency(pi: &InertialParameters) -> Result<(), InertiaViolation> {
    check_consistency(pi)?;
    let moments = principal_moments(pi);
    match triangle_inequality_violation(&moments) {
        Some((axis, second_moment)) => Err(InertiaViolation::TriangleInequality {
            moments,
            axis,
            second_moment,
        }),
        None => Ok(()),
    }
}

/// The triangle inequalities (6.18) on principal moments `J` (kg·m², increasing): the principal axis with
/// the most negative central second moment `L_i` ((6.15)–(6.17)) and that moment, when it is below the
/// relative tolerance of 1e-9; `None` when every inequality holds. The one rule of the URDF loader's
/// warning and of [`check_full_consistency`].
pub fn triangle_inequality_violation(moments: &[f64; 3]) -> Option<(usize, f64)> {
    let l = second_moments(moments);
    let (axis, second_moment) = (0..3)
        .map(|k| (k, l[k]))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or((0, 0.0));
    (second_moment < -tolerance(moments[2])).then_some((axis, second_moment))
}

/// Central second moments `L = P⁻¹ J`, `L_i = (J_j + J_k − J_i)/2` [Traversaro 2017, eqs. 6.15–6.17].
pub fn second_moments(moments: &[f64; 3]) -> [f64; 3] {
    let [a, b, c] = *moments;
    [(b + c - a) / 2.0, (a + c - b) / 2.0, (a + b - c) / 2.0]
}

impl Model {
    /// Every body (lumped, see [`crate::inertial`]) that is not consistent (`full = false`, (6.20)) or not
    /// fully consistent (`full = true`, (6.18), (6.21)), with the condition that fails.
    pub fn inertia_violations(&self, full: bool) -> Vec<BodyInertiaViolation> {
        let psi = self.inertial_parameters();
        (0..self.body_count())
            .filter_map(|b| {
                let pi: InertialParameters = psi.fixed_rows::<10>(10 * b).into_owned();
                let check = if full {
                    check_full_consistency(&pi)
                } else {
                    check_consistency(&pi)
                };
                check.err().map(|violation| BodyInertiaViolation {
                    body: b,
                    name: self.bodies[b].name.clone(),
                    violation,
                })
            })
            .collect()
    }
}
