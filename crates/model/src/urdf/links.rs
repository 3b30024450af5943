//! Links: validation of every `<inertial>` and its spatial inertia in the link frame.

use std::collections::HashMap;

use nalgebra::{Matrix3, SymmetricEigen};

use super::{check_finite, pose};
use crate::edits::InertiaEdits;
use crate::error::ModelError;
use crate::inertial::triangle_inequality_violation;
use crate::spatial::Inertia;

/// The links of the URDF, in file order.
pub(super) struct Links {
    /// Link name → index in file order.
    pub(super) index: HashMap<String, usize>,
    /// Spatial inertia of each link about its own frame.
    pub(super) inertia: Vec<Inertia>,
}

/// Validates every link in file order (unique name, finite numbers, non-negative mass, positive
/// semi-definite rotational inertia) and builds its inertia; physically doubtful inertias are warnings.
/// The inertias are then edited by `edits` ([`InertiaEdits::apply`], checked first).
pub(super) fn read_links(
    robot: &urdf_rs::Robot,
    edits: &InertiaEdits,
    warnings: &mut Vec<String>,
) -> Result<Links, ModelError> {
    let mut index: HashMap<String, usize> = HashMap::new();
    let mut inertia: Vec<Inertia> = Vec::with_capacity(robot.links.len());
    for (k, link) in robot.links.iter().enumerate() {
        if index.insert(link.name.clone(), k).is_some() {
            return Err(ModelError::DuplicateLink {
                link: link.name.clone(),
            });
        }
        inertia.push(link_inertia(link, warnings)?);
    }
    if !edits.is_identity() {
        edits.validate(|name| index.contains_key(name))?;
        for (link, i) in robot.links.iter().zip(inertia.iter_mut()) {
            let (m, c, i_com) = edits.apply(&link.name, i.m, i.com(), i.inertia_at_com());
            *i = Inertia::from_com(m, &c, &i_com);
        }
    }
    Ok(Links { index, inertia })
}

/// The spatial inertia of one link about the link frame, from its `<inertial>`: the rotational inertia
/// `I_C = R I R^T` about the CoM (`R` the rotation of the inertial `<origin>`), then [`Inertia::from_com`].
fn link_inertia(link: &urdf_rs::Link, warnings: &mut Vec<String>) -> Result<Inertia, ModelError> {
    let element = format!("link `{}`", link.name);
    let inertial = &link.inertial;
    let m = inertial.mass.value;
    check_finite(&[m], &element, "mass")?;
    check_finite(&inertial.origin.xyz.0, &element, "inertial origin xyz")?;
    check_finite(&inertial.origin.rpy.0, &element, "inertial origin rpy")?;
    let i = &inertial.inertia;
    let iv = [i.ixx, i.ixy, i.ixz, i.iyy, i.iyz, i.izz];
    check_finite(&iv, &element, "inertia")?;
    if m < 0.0 {
        return Err(ModelError::NegativeMass {
            link: link.name.clone(),
            mass: m,
        });
    }
    let i_frame = Matrix3::new(
        i.ixx, i.ixy, i.ixz, i.ixy, i.iyy, i.iyz, i.ixz, i.iyz, i.izz,
    );
    check_principal_moments(&link.name, m, &i_frame, warnings)?;
    let origin = pose(inertial.origin.xyz.0, inertial.origin.rpy.0);
    let r = origin.rotation.to_rotation_matrix().into_inner();
    let i_com = r * i_frame * r.transpose();
    Ok(Inertia::from_com(m, &origin.translation.vector, &i_com))
}

/// Checks the principal moments of a rotational inertia (kg·m²): a negative eigenvalue (below
/// `−(1e-9 |λ_max| + 1e-12)`) is an error; moments violating the triangle inequality
/// `λ₁ + λ₂ ≥ λ₃` ([`triangle_inequality_violation`], Traversaro 2017, eq. 6.18), a zero mass with a non-zero inertia, or a positive mass with a zero inertia are warnings.
fn check_principal_moments(
    name: &str,
    m: f64,
    i_frame: &Matrix3<f64>,
    warnings: &mut Vec<String>,
) -> Result<(), ModelError> {
    let eig = SymmetricEigen::new(*i_frame).eigenvalues;
    let (mut lo, mut hi) = (eig[0], eig[0]);
    for e in eig.iter() {
        lo = lo.min(*e);
        hi = hi.max(*e);
    }
    let tol = 1e-9 * hi.abs() + 1e-12;
    if lo < -tol {
        return Err(ModelError::NegativeInertia {
            link: name.to_string(),
            eigenvalue: lo,
        });
    }
    if hi > 0.0 {
        let mut sorted = [eig[0], eig[1], eig[2]];
        sorted.sort_by(f64::total_cmp);
        if triangle_inequality_violation(&sorted).is_some() {
            warnings.push(format!(
                "link `{}`: inertia is not physically consistent (principal moments {:.6e}, {:.6e}, {:.6e} violate the triangle inequality)",
                name, sorted[0], sorted[1], sorted[2]
            ));
        }
        if m == 0.0 {
            warnings.push(format!(
                "link `{name}`: zero mass but non-zero rotational inertia"
            ));
        }
    } else if m > 0.0 {
        warnings.push(format!(
            "link `{name}`: point mass ({m} kg with zero rotational inertia)"
        ));
    }
    Ok(())
}
