//! Small 6D (spatial) algebra helpers [Featherstone 2008] in the linear-first ordering `[linear; angular]` of
//! [Traversaro 2017, ch. 2].
//!
//! Internal to the crate: motions and forces are plain `Vector6<f64>`, rigid-body inertias are stored with the
//! ten inertial parameters about a frame origin (mass, first moment of mass, 3D inertia about the origin), which
//! makes change of coordinates and accumulation cheap.

use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

/// The skew-symmetric matrix of `w` (`skew(w) u = w × u`).
#[inline]
pub fn skew(w: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -w.z, w.y, w.z, 0.0, -w.x, -w.y, w.x, 0.0)
}

#[inline]
pub(crate) fn lin(v: &Vector6<f64>) -> Vector3<f64> {
    Vector3::new(v[0], v[1], v[2])
}

#[inline]
pub(crate) fn ang(v: &Vector6<f64>) -> Vector3<f64> {
    Vector3::new(v[3], v[4], v[5])
}

#[inline]
pub(crate) fn join(l: &Vector3<f64>, a: &Vector3<f64>) -> Vector6<f64> {
    Vector6::new(l.x, l.y, l.z, a.x, a.y, a.z)
}

/// Motion cross product `a × b` (= ad_a b): `[ωa × vb + va × ωb; ωa × ωb]` [Traversaro 2017, eq. 2.37].
#[inline]
pub(crate) fn cross_motion(a: &Vector6<f64>, b: &Vector6<f64>) -> Vector6<f64> {
    let (va, wa) = (lin(a), ang(a));
    let (vb, wb) = (lin(b), ang(b));
    join(&(wa.cross(&vb) + va.cross(&wb)), &wa.cross(&wb))
}

/// Dual cross product `v ×̄* f` = `[ω × f; v × f + ω × τ]` [Traversaro 2017, eq. 2.50].
#[inline]
pub(crate) fn cross_force(v: &Vector6<f64>, f: &Vector6<f64>) -> Vector6<f64> {
    let (vl, w) = (lin(v), ang(v));
    let (fl, t) = (lin(f), ang(f));
    join(&w.cross(&fl), &(vl.cross(&fl) + w.cross(&t)))
}

/// Moves the reference point of a motion vector by `p` (new origin = old origin + p), same orientation:
/// `[v + ω × p; ω]` (the linear part becomes the velocity of the point at the new origin).
#[inline]
pub(crate) fn shift_motion(v: &Vector6<f64>, p: &Vector3<f64>) -> Vector6<f64> {
    let w = ang(v);
    join(&(lin(v) + w.cross(p)), &w)
}

/// Rigid-body inertia about the origin of a frame: mass `m`, first moment `h = m c` and 3D inertia `i` about
/// the origin (not about the centre of mass), all in that frame's coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Inertia {
    pub m: f64,
    pub h: Vector3<f64>,
    pub i: Matrix3<f64>,
}

impl Inertia {
    pub fn zero() -> Self {
        Self {
            m: 0.0,
            h: Vector3::zeros(),
            i: Matrix3::zeros(),
        }
    }

    /// From mass, centre of mass `c` and the 3D inertia `i_com` about the CoM (same orientation).
    pub fn from_com(m: f64, c: &Vector3<f64>, i_com: &Matrix3<f64>) -> Self {
        let s = skew(c);
        Self {
            m,
            h: c * m,
            i: i_com - s * s * m,
        }
    }

    /// Expresses the inertia in a parent frame where this frame has orientation `r` and origin `p`.
    #[inline]
    pub fn transformed(&self, r: &Matrix3<f64>, p: &Vector3<f64>) -> Self {
        let rh = r * self.h;
        let sp = skew(p);
        let srh = skew(&rh);
        let ri = r * self.i * r.transpose();
        Self {
            m: self.m,
            h: rh + p * self.m,
            i: ri - srh * sp - sp * srh - sp * sp * self.m,
        }
    }

    /// World (parent) inertia of a body with mass `m`, CoM `c` and rotational inertia `i_com` about the CoM in
    /// body coordinates, the body having orientation `r` and origin `p`. Cheaper than
    /// [`Inertia::transformed`] (no 3×3 products beyond `R I Rᵀ`).
    #[inline]
    pub fn from_body_com(
        m: f64,
        c: &Vector3<f64>,
        i_com: &Matrix3<f64>,
        r: &Matrix3<f64>,
        p: &Vector3<f64>,
    ) -> Self {
        let cw = r * c + p;
        let mut i = r * i_com * r.transpose();
        // Parallel axis: I_o = I_c + m (|c|² 1 − c cᵀ).
        let c2 = cw.norm_squared();
        for a in 0..3 {
            for b in 0..3 {
                let d = if a == b { c2 } else { 0.0 };
                i[(a, b)] += m * (d - cw[a] * cw[b]);
            }
        }
        Self { m, h: cw * m, i }
    }

    #[inline]
    pub fn add(&mut self, other: &Inertia) {
        self.m += other.m;
        self.h += other.h;
        self.i += other.i;
    }

    /// Momentum `I v` of a motion `v` (`[m v − h × ω; h × v + I ω]`).
    #[inline]
    pub fn mul_motion(&self, v: &Vector6<f64>) -> Vector6<f64> {
        let (vl, w) = (lin(v), ang(v));
        join(
            &(vl * self.m - self.h.cross(&w)),
            &(self.h.cross(&vl) + self.i * w),
        )
    }

    /// The 6×6 spatial inertia matrix `[[m 1, −h^], [h^, I]]` [Traversaro 2017, eq. 2.67].
    #[inline]
    pub fn matrix(&self) -> Matrix6<f64> {
        let sh = skew(&self.h);
        let mut out = Matrix6::zeros();
        out.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Matrix3::identity() * self.m));
        out.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-sh));
        out.fixed_view_mut::<3, 3>(3, 0).copy_from(&sh);
        out.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.i);
        out
    }

    /// Centre of mass (origin if the mass is zero).
    pub fn com(&self) -> Vector3<f64> {
        if self.m > 0.0 {
            self.h / self.m
        } else {
            Vector3::zeros()
        }
    }

    /// 3D inertia about the centre of mass.
    pub fn inertia_at_com(&self) -> Matrix3<f64> {
        let c = self.com();
        let s = skew(&c);
        self.i + s * s * self.m
    }
}

/// 6×6 velocity transform `[[R, 0], [0, R]]`.
#[inline]
pub(crate) fn blockdiag(r: &Matrix3<f64>) -> Matrix6<f64> {
    let mut out = Matrix6::zeros();
    out.fixed_view_mut::<3, 3>(0, 0).copy_from(r);
    out.fixed_view_mut::<3, 3>(3, 3).copy_from(r);
    out
}

/// 6×6 velocity transform `[[1, skew(p)], [0, 1]]`: `[v; ω] ↦ [v + p × ω; ω]`.
#[inline]
pub(crate) fn translation_x(p: &Vector3<f64>) -> Matrix6<f64> {
    let mut out = Matrix6::identity();
    out.fixed_view_mut::<3, 3>(0, 3).copy_from(&skew(p));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inertia_matrix_matches_mul_motion_and_transform() {
        let i_com = Matrix3::new(0.3, 0.01, 0.02, 0.01, 0.4, 0.03, 0.02, 0.03, 0.5);
        let inertia = Inertia::from_com(2.0, &Vector3::new(0.1, -0.2, 0.3), &i_com);
        let v = Vector6::new(0.3, -1.0, 2.0, 0.5, 0.7, -0.2);
        assert!((inertia.matrix() * v - inertia.mul_motion(&v)).norm() < 1e-14);
        // Transform consistency: kinetic energy invariant under change of coordinates.
        let r = *nalgebra::Rotation3::from_euler_angles(0.3, -0.4, 1.1).matrix();
        let p = Vector3::new(0.5, 1.0, -0.7);
        let t = inertia.transformed(&r, &p);
        // v expressed in parent: X v with X = [[R, p^R],[0,R]]
        let mut x = Matrix6::zeros();
        x.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
        x.fixed_view_mut::<3, 3>(0, 3).copy_from(&(skew(&p) * r));
        x.fixed_view_mut::<3, 3>(3, 3).copy_from(&r);
        let vp = x * v;
        let e0 = v.dot(&inertia.mul_motion(&v));
        let e1 = vp.dot(&t.mul_motion(&vp));
        assert!((e0 - e1).abs() < 1e-12);
        assert!((t.com() - (r * inertia.com() + p)).norm() < 1e-14);
        assert!((t.inertia_at_com() - r * i_com * r.transpose()).norm() < 1e-13);
        let f = Inertia::from_body_com(2.0, &Vector3::new(0.1, -0.2, 0.3), &i_com, &r, &p);
        assert!((f.matrix() - t.matrix()).norm() < 1e-13);
    }

    #[test]
    fn cross_products_are_dual() {
        let v = Vector6::new(0.3, -1.0, 2.0, 0.5, 0.7, -0.2);
        let w = Vector6::new(-0.1, 0.4, 0.2, 1.5, -0.3, 0.6);
        let f = Vector6::new(1.0, 2.0, 3.0, -0.5, 0.25, 0.75);
        // w^T (v ×* f) = −(v × w)^T f
        assert!((w.dot(&cross_force(&v, &f)) + cross_motion(&v, &w).dot(&f)).abs() < 1e-13);
        assert!(cross_motion(&v, &v).norm() < 1e-15);
    }
}
