//! stride-model's body inertias written into the compiled MuJoCo model: how `[sim.model]` edits (mass
//! scales, CoM offsets of links) reach the MuJoCo plant, which compiles the unedited URDF itself.

use mujoco_rs::prelude::*;
use nalgebra::{Matrix3, Rotation3, SymmetricEigen, UnitQuaternion};
use stride_model::Model;

/// Principal moments \[kg·m²\] and the orientation of the principal axes in the body frame of a symmetric
/// inertia `I = R diag(d) Rᵀ`, with `R` a proper rotation (MuJoCo's `body_inertia` and `body_iquat`).
pub fn principal_inertia(inertia: &Matrix3<f64>) -> ([f64; 3], UnitQuaternion<f64>) {
    let eigen = SymmetricEigen::new((inertia + inertia.transpose()) * 0.5);
    let mut axes = eigen.eigenvectors;
    if axes.determinant() < 0.0 {
        axes.column_mut(2).neg_mut();
    }
    let d = eigen.eigenvalues;
    let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(axes));
    ([d[0], d[1], d[2]], rotation)
}

/// Sets each MuJoCo body `body[i]` to stride body `i`'s mass, centre of mass and rotational inertia
/// (body frames agree: a test checks every body's pose). MuJoCo's derived constants (subtree masses,
/// inverse weights) must then be recomputed with `mj_setConst`.
pub fn write_model_inertias(model: &Model, body: &[usize], mj: &mut MjModel) {
    for (b, &id) in model.bodies().iter().zip(body) {
        let (moments, axes) = principal_inertia(&b.inertia_at_com);
        mj.body_mass_mut()[id] = b.mass;
        mj.body_ipos_mut()[id] = [b.com.x, b.com.y, b.com.z];
        mj.body_iquat_mut()[id] = [axes.w, axes.i, axes.j, axes.k];
        mj.body_inertia_mut()[id] = moments;
        // The inertia frame is no longer known to coincide with the body frame.
        mj.body_sameframe_mut()[id] = MjtSameFrame::mjSAMEFRAME_NONE;
    }
}
