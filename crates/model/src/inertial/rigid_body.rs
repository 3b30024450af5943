//! The ten inertial parameters of one rigid body and its regressor: the net wrench of the body is linear in
//! `π = [m; m c; vech(I_B)]` [Traversaro 2017, eqs. 6.3–6.7].

use nalgebra::{Matrix3, Matrix6, SMatrix, SVector, Vector3, Vector6};

use crate::spatial::{ang, cross_force, lin, skew, Inertia};

/// The inertial parameters `π = [m; m c; vech(I_B)]` of a rigid body [Traversaro 2017, eq. 6.3]: mass `m`
/// (kg), first moment of mass `m c` (kg·m, `c` the CoM in the body frame) and the six independent entries
/// of the 3D inertia `I_B` about the body-frame ORIGIN in body axes (kg·m²), in the order of (6.5):
/// `[I_xx, I_xy, I_xz, I_yy, I_yz, I_zz]`.
pub type InertialParameters = SVector<f64, 10>;

/// `vech(I)`: the six independent entries of a symmetric 3 × 3 inertia (kg·m²) in the order of
/// [Traversaro 2017, eq. 6.5], `[I_xx, I_xy, I_xz, I_yy, I_yz, I_zz]` (also the URDF's `<inertia>` order).
pub fn vech(i: &Matrix3<f64>) -> [f64; 6] {
    [
        i[(0, 0)],
        i[(0, 1)],
        i[(0, 2)],
        i[(1, 1)],
        i[(1, 2)],
        i[(2, 2)],
    ]
}

/// A 6 × 10 rigid-body regressor: `[f; τ] = Y π` (N, N·m, body frame, torque about its origin).
pub type RigidBodyRegressor = SMatrix<f64, 6, 10>;

/// `π` of a body of mass `mass` (kg), centre of mass `com` (m) and rotational inertia `inertia_at_com`
/// about the CoM (kg·m², body axes), by the parallel-axis theorem `I_B = I_C − m S(c) S(c)`
/// [Traversaro 2017, eq. 6.11].
pub fn inertial_parameters(
    mass: f64,
    com: &Vector3<f64>,
    inertia_at_com: &Matrix3<f64>,
) -> InertialParameters {
    let s = skew(com);
    let i_b = inertia_at_com - s * s * mass;
    let h = com * mass;
    let [xx, xy, xz, yy, yz, zz] = vech(&i_b);
    InertialParameters::from_column_slice(&[mass, h.x, h.y, h.z, xx, xy, xz, yy, yz, zz])
}

/// `π` of the same body in a frame `A` in which the body frame has orientation `rotation` (`^A R_B`) and
/// origin `translation` (`^A o_B`, m): `m' = m`, `(mc)' = R mc + m o`, `I' = R I Rᵀ − S(R mc) S(o) −
/// S(o) S(R mc) − m S(o) S(o)` (the inertia about A's origin, [Traversaro 2017, eqs. 2.67, 6.11]). Linear
/// in `π`; summing bodies transformed into one frame lumps them.
pub fn transform_parameters(
    pi: &InertialParameters,
    rotation: &Matrix3<f64>,
    translation: &Vector3<f64>,
) -> InertialParameters {
    parameters_of(&inertia_of(pi).transformed(rotation, translation))
}

/// The crate's [`Inertia`] of `π`.
pub(crate) fn inertia_of(pi: &InertialParameters) -> Inertia {
    Inertia {
        m: pi[0],
        h: Vector3::new(pi[1], pi[2], pi[3]),
        i: inertia_about_origin(pi),
    }
}

/// `π` of an [`Inertia`] (about a frame origin).
pub(crate) fn parameters_of(inertia: &Inertia) -> InertialParameters {
    let h = &inertia.h;
    let [xx, xy, xz, yy, yz, zz] = vech(&inertia.i);
    InertialParameters::from_column_slice(&[inertia.m, h.x, h.y, h.z, xx, xy, xz, yy, yz, zz])
}

/// The 3D inertia `I_B` about the body origin (kg·m²) held in `π` (the inverse of `vech`).
pub fn inertia_about_origin(pi: &InertialParameters) -> Matrix3<f64> {
    Matrix3::new(
        pi[4], pi[5], pi[6], //
        pi[5], pi[7], pi[8], //
        pi[6], pi[8], pi[9],
    )
}

/// The 6 × 6 spatial inertia `M = [[m 1, −(mc)^], [(mc)^, I_B]]` of `π` [Traversaro 2017, eq. 2.67].
pub fn spatial_inertia(pi: &InertialParameters) -> Matrix6<f64> {
    let sh = skew(&Vector3::new(pi[1], pi[2], pi[3]));
    let mut out = Matrix6::zeros();
    out.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(Matrix3::identity() * pi[0]));
    out.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-sh));
    out.fixed_view_mut::<3, 3>(3, 0).copy_from(&sh);
    out.fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&inertia_about_origin(pi));
    out
}

/// `D(v)` with `M v = D(v) π` for a motion `v = [v; ω]` [Traversaro 2017, eqs. 6.4–6.5]:
/// `D = [[v, ω^, 0₃ₓ₆], [0₃ₓ₁, −v^, ω•]]`, `ω• vech(I) = I ω`.
pub fn momentum_regressor(v: &Vector6<f64>) -> RigidBodyRegressor {
    let (l, w) = (lin(v), ang(v));
    let mut d = RigidBodyRegressor::zeros();
    d.fixed_view_mut::<3, 1>(0, 0).copy_from(&l);
    d.fixed_view_mut::<3, 3>(0, 1).copy_from(&skew(&w));
    d.fixed_view_mut::<3, 3>(3, 1).copy_from(&(-skew(&l)));
    // ω• (6.5): rows of I ω in terms of [I_xx, I_xy, I_xz, I_yy, I_yz, I_zz].
    let dot = [
        [w.x, w.y, w.z, 0.0, 0.0, 0.0],
        [0.0, w.x, 0.0, w.y, w.z, 0.0],
        [0.0, 0.0, w.x, 0.0, w.y, w.z],
    ];
    for (r, row) in dot.iter().enumerate() {
        for (c, value) in row.iter().enumerate() {
            d[(3 + r, 4 + c)] = *value;
        }
    }
    d
}

/// The rigid-body regressor `Y(a, v) = D(a) + v ×̄* D(v)`: the net wrench `φ = M a + v ×̄* M v = Y π` of a
/// body (N, N·m; body frame, torque about its origin) whose left-trivialized (body) velocity is `v` and
/// whose left-trivialized proper acceleration is `a = ^B v̇ − [^B R_A g; 0]` (gravity subtracted)
/// [Traversaro 2017, eqs. 2.75, 6.4].
pub fn rigid_body_regressor(a: &Vector6<f64>, v: &Vector6<f64>) -> RigidBodyRegressor {
    let mut y = momentum_regressor(a);
    let dv = momentum_regressor(v);
    for k in 0..10 {
        let col: Vector6<f64> = dv.column(k).into_owned();
        let cross = cross_force(v, &col);
        let mut out = y.column_mut(k);
        out += cross;
    }
    y
}

/// The regressor in the sensor form `Y(α^g, ω) = D(α^g) + [0; ω] ×̄* D([0; ω])` [Traversaro 2017,
/// eqs. 6.6–6.7], for the proper sensor acceleration `α^g = [^B R_A (ö_B − g); ^B ω̇]` (what an IMU at the
/// body origin measures, plus the angular acceleration) and the angular velocity `ω` (rad/s), both in body
/// coordinates. Equal to [`rigid_body_regressor`] with `a = α^g − [ω × v; 0]` (Table 2.2): the linear
/// velocity is not needed.
pub fn sensor_regressor(alpha_g: &Vector6<f64>, omega: &Vector3<f64>) -> RigidBodyRegressor {
    let w6 = Vector6::new(0.0, 0.0, 0.0, omega.x, omega.y, omega.z);
    rigid_body_regressor(alpha_g, &w6)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against the crate's spatial algebra: `φ = I a + v ×̄* (I v)` with [`Inertia::mul_motion`] and
    /// [`cross_force`] (the RNEA's per-body line).
    #[test]
    fn regressor_matches_the_spatial_algebra() {
        let i_com = Matrix3::new(0.3, 0.01, 0.02, 0.01, 0.4, 0.03, 0.02, 0.03, 0.5);
        let c = Vector3::new(0.1, -0.2, 0.3);
        let inertia = Inertia::from_com(2.5, &c, &i_com);
        let pi = inertial_parameters(2.5, &c, &i_com);
        assert!((spatial_inertia(&pi) - inertia.matrix()).amax() < 1e-15);
        for k in 0..20 {
            let t = k as f64;
            let a = Vector6::new(
                t.sin(),
                2.0 * t.cos(),
                -9.81,
                0.3 * t,
                -0.5,
                1.0 / (1.0 + t),
            );
            let v = Vector6::new(0.2, -t.cos(), 0.7, (0.3 * t).sin(), 1.5, -0.4 * t);
            let phi = inertia.mul_motion(&a) + cross_force(&v, &inertia.mul_motion(&v));
            let y = rigid_body_regressor(&a, &v);
            assert!((y * pi - phi).amax() <= 1e-12 * phi.amax().max(1.0));
        }
        // Moving π to another frame is the spatial inertia's change of frame.
        let r = *nalgebra::Rotation3::from_euler_angles(0.3, -0.4, 1.1).matrix();
        let p = Vector3::new(0.5, 1.0, -0.7);
        let moved = spatial_inertia(&transform_parameters(&pi, &r, &p));
        assert!((moved - inertia.transformed(&r, &p).matrix()).amax() < 1e-14);
    }
}
