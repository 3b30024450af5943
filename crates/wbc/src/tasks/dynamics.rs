//! The floating-base dynamics `M ν̇ + h = [0; τ] + Σ_c J_cᵀ w_c` [Romualdi 2022, eq. 7.2.14–7.2.15] in
//! the TSID, whose decision vector has no torque: the 6 base rows are an equality task (N, N m), and the
//! joint rows define `τ = M_s ν̇ + h_s − Σ_c J_{c,s}ᵀ w_c`, through which the joint torque limits
//! `−τ_max ≤ τ ≤ τ_max` [Romualdi 2022, eq. 7.2.30] and the torque regularization `τ = 0`
//! [Romualdi 2022, eq. 7.2.25] are rows over `(ν̇, w)` (N m).

use nalgebra::{DMatrix, DVector};
use stride_qp::TaskDataMut;

use super::{Contact, TsidContext};

/// Base rows: `M_b ν̇ − Σ_c J_{c,b}ᵀ w_c = −h_b` (6 rows).
pub(crate) fn fill_base_dynamics(s: &TsidContext, b: &mut TaskDataMut) {
    let nv = s.mass_matrix.ncols();
    b.a.view_mut((0, 0), (6, nv))
        .copy_from(&s.mass_matrix.view((0, 0), (6, nv)));
    for (c, contact) in s.contacts.iter().enumerate() {
        if let Some(off) = s.offsets[c] {
            for r in 0..6 {
                for k in 0..6 {
                    b.a[(r, off + k)] = -contact.jacobian[(k, r)];
                }
            }
        }
    }
    for r in 0..6 {
        b.b[r] = -s.bias_forces[r];
    }
}

/// Flexible-joint rows of TSID-Flex [Romualdi 2022, eq. (9.2.6), last n_f rows]: the torque of a passive
/// joint is its spring-damper's, not a decision. One row per entry of `flexible` (model joint index, `k`
/// N·m/rad, `b` N·m·s/rad), after the 6 base rows (N m):
///
/// `M_{s,j} ν̇ + (b h + k h²) s̈_j − Σ_c J_{c,s,j}ᵀ w_c = τ^f_j − k h ṡ_j − h_{s,j}`,
///
/// i.e. the joint torque equals the passive torque `τ^f = −k s − b ṡ` (`torques`, measured) advanced over the
/// controller's period `h` by the chosen acceleration (`s⁺ = s + h ṡ + h² s̈`, `ṡ⁺ = ṡ + h s̈`), the linearly
/// implicit form a simulator uses for a stiff spring-damper: with `k = b = 0` it is the explicit
/// `τ_j = τ^f_j`. The implicit form keeps the loop stable when `b h` exceeds the inertia the joint moves.
pub(crate) fn fill_flexible_dynamics(
    s: &TsidContext,
    flexible: &[(usize, f64, f64)],
    period: f64,
    state_velocities: &DVector<f64>,
    torques: &DVector<f64>,
    b: &mut TaskDataMut,
) {
    let nv = s.mass_matrix.ncols();
    for (r, &(j, k, d)) in flexible.iter().enumerate() {
        let row = 6 + r;
        b.a.view_mut((row, 0), (1, nv))
            .copy_from(&s.mass_matrix.view((6 + j, 0), (1, nv)));
        b.a[(row, 6 + j)] += d * period + k * period * period;
        for (c, contact) in s.contacts.iter().enumerate() {
            if let Some(off) = s.offsets[c] {
                for kk in 0..6 {
                    b.a[(row, off + kk)] = -contact.jacobian[(kk, 6 + j)];
                }
            }
        }
        b.b[row] = torques[j] - k * period * state_velocities[j] - s.bias_forces[6 + j];
    }
}

/// Joint torque limits: `−scale τ_max − h_s ≤ M_s ν̇ − Σ_c J_{c,s}ᵀ w_c ≤ scale τ_max − h_s` (n rows; `effort`
/// is `τ_max` per joint, N m).
pub(crate) fn fill_torque_limits(s: &TsidContext, scale: f64, effort: &[f64], b: &mut TaskDataMut) {
    fill_torque_rows(s.mass_matrix, s.contacts, s.offsets, b);
    for (i, e) in effort.iter().enumerate() {
        let lim = scale * e;
        b.lower[i] = -lim - s.bias_forces[6 + i];
        b.upper[i] = lim - s.bias_forces[6 + i];
    }
}

/// Torque regularization: `M_s ν̇ − Σ_c J_{c,s}ᵀ w_c = −h_s` (n rows, i.e. `τ = 0`).
pub(crate) fn fill_torque_regularization(s: &TsidContext, b: &mut TaskDataMut) {
    fill_torque_rows(s.mass_matrix, s.contacts, s.offsets, b);
    let n = s.mass_matrix.ncols() - 6;
    for i in 0..n {
        b.b[i] = -s.bias_forces[6 + i];
    }
}

/// The joint torques of a solution `x = [ν̇; w…]`: `τ = M_s ν̇ + h_s − Σ_c J_{c,s}ᵀ w_c` (N m).
pub(crate) fn joint_torques(s: &TsidContext, x: &DVector<f64>, tau: &mut DVector<f64>) {
    let nv = s.mass_matrix.ncols();
    let n = nv - 6;
    for i in 0..n {
        let mut t = s.bias_forces[6 + i];
        for j in 0..nv {
            t += s.mass_matrix[(6 + i, j)] * x[j];
        }
        for (c, contact) in s.contacts.iter().enumerate() {
            if let Some(off) = s.offsets[c] {
                for k in 0..6 {
                    t -= contact.jacobian[(k, 6 + i)] * x[off + k];
                }
            }
        }
        tau[i] = t;
    }
}

/// Rows `[M_s | −J_{c,s}ᵀ …]` of the eliminated torque `τ = M_s ν̇ + h_s − Σ J_{c,s}ᵀ f_c`.
fn fill_torque_rows(
    mass: &DMatrix<f64>,
    contacts: &[Contact],
    offsets: &[Option<usize>],
    b: &mut TaskDataMut<'_>,
) {
    let nv = mass.ncols();
    let n = nv - 6;
    b.a.view_mut((0, 0), (n, nv))
        .copy_from(&mass.view((6, 0), (n, nv)));
    for (c, contact) in contacts.iter().enumerate() {
        if let Some(off) = offsets[c] {
            for i in 0..n {
                for k in 0..6 {
                    b.a[(i, off + k)] = -contact.jacobian[(k, 6 + i)];
                }
            }
        }
    }
}
