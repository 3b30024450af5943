//! The centroidal prediction model, condensed: every state of the horizon as an affine function of the
//! decision vector `z` (cone coordinates and contact displacements).
//!
//! Forward Euler [Romualdi 2022, eq. 11.1.15b–c] with the corner-force dynamics (11.1.4, with the linear
//! `I₃` block the printed (11.1.4a) drops):
//!
//! ```text
//! h^p[k+1] = h^p[k] + dt (Σ_ij f_ij + m g + f_ext[k])   (f_ext over the first `external_force_stages`)
//! x[k+1]   = x[k]   + dt h^p[k] / m
//! h^ω[k+1] = h^ω[k] + dt Σ_ij (p_i + R_i c_j − x[k]) × f_ij
//! ```
//!
//! `f_ij = G_i λ_ij` (cone generators, [`super::layout::ContactGeometry`]) and `p_i = p_iⁿ + E_i d_i`
//! are linear in `z`; the bilinear `r × f` is replaced by its first-order expansion about the
//! linearisation point `(r̄, f̄)`: `r × f ≈ r̄ × f + r × f̄ − r̄ × f̄` (one real-time iteration).
//! The contact-location dynamics (11.1.15d) is folded in: a contact's position is one variable `d_i`,
//! frozen while it is active.

use nalgebra::{DMatrix, DVector, DVectorView, Matrix3, Vector3};

use super::io::CentroidalMpcInput;
use super::layout::{ContactGeometry, Layout, GENERATORS};
use super::linearization::Linearization;

/// Rows of one stage's state: CoM (3), linear momentum (3), angular momentum (3).
pub(crate) const STATE: usize = 9;
const X: usize = 0;
const HP: usize = 3;
const HW: usize = 6;

/// The condensed states `s_k = S_k z + c_k`, `k = 0..=N`, stacked (9 rows per stage).
#[derive(Debug, Clone)]
pub(crate) struct Condensed {
    pub s: DMatrix<f64>,
    pub c: DVector<f64>,
}

/// Physical constants of the model.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Body {
    pub mass: f64,
    pub gravity: f64,
    pub dt: f64,
    /// Stages over which the input's external force acts.
    pub external_stages: usize,
}

fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    v.cross_matrix()
}

impl Condensed {
    pub fn new(stages: usize, max_variables: usize) -> Self {
        Self {
            s: DMatrix::zeros(STATE * (stages + 1), max_variables),
            c: DVector::zeros(STATE * (stages + 1)),
        }
    }

    /// `rows[dst + a] += m[a][b] · rows[src + b]` over the first `n` columns and the constants.
    fn add_mapped(&mut self, dst: usize, src: usize, m: &Matrix3<f64>, n: usize) {
        for a in 0..3 {
            for b in 0..3 {
                let w = m[(a, b)];
                if w == 0.0 {
                    continue;
                }
                for j in 0..n {
                    self.s[(dst + a, j)] += w * self.s[(src + b, j)];
                }
                self.c[dst + a] += w * self.c[src + b];
            }
        }
    }

    /// Fills the maps for the tick (see the module documentation).
    pub fn propagate(
        &mut self,
        input: &CentroidalMpcInput,
        layout: &Layout,
        geometry: &[ContactGeometry],
        lin: &Linearization,
        body: Body,
    ) {
        let (n, dt, m) = (layout.n, body.dt, body.mass);
        let rows = STATE * (layout.stages.len() + 1);
        self.s.view_mut((0, 0), (rows, n)).fill(0.0);
        self.c.fill(0.0);
        for a in 0..3 {
            self.c[X + a] = input.com_position[a];
            self.c[HP + a] = m * input.com_velocity[a];
            self.c[HW + a] = input.angular_momentum[a];
        }
        for (k, slots) in layout.stages.iter().enumerate() {
            let (r0, r1) = (STATE * k, STATE * (k + 1));
            for a in 0..STATE {
                for j in 0..n {
                    self.s[(r1 + a, j)] = self.s[(r0 + a, j)];
                }
                self.c[r1 + a] = self.c[r0 + a];
            }
            self.add_mapped(r1 + X, r0 + HP, &(Matrix3::identity() * (dt / m)), n);
            self.c[r1 + HP + 2] -= dt * m * body.gravity;
            if k < body.external_stages {
                for a in 0..3 {
                    self.c[r1 + HP + a] += dt * input.external_force[a];
                }
            }
            let x_bar = lin.com_bar[k];
            let mut total = Vector3::zeros();
            for (q, slot) in slots.iter().enumerate() {
                let Some(slot) = slot else { continue };
                let (i, geo) = (slot.contact, &geometry[slot.contact]);
                let d_bar = geo.axes * lin.displacement_bar[i];
                let p = input.contacts[i].position + d_bar;
                let mut contact_total = Vector3::zeros();
                for (j, corner) in geo.corners.iter().enumerate() {
                    let f_bar = lin.force_bar[k][q][j];
                    let r_bar = p + corner - x_bar;
                    for g in 0..GENERATORS {
                        let col = slot.offset + j * GENERATORS + g;
                        let gen = geo.generators.column(g).into_owned();
                        let torque = r_bar.cross(&gen);
                        for a in 0..3 {
                            self.s[(r1 + HP + a, col)] += dt * gen[a];
                            self.s[(r1 + HW + a, col)] += dt * torque[a];
                        }
                    }
                    let constant = (x_bar - d_bar).cross(&f_bar) * dt;
                    for a in 0..3 {
                        self.c[r1 + HW + a] += constant[a];
                    }
                    contact_total += f_bar;
                }
                if let Some(od) = layout.displacement[i] {
                    let block = -skew(&contact_total) * geo.axes * dt;
                    for a in 0..3 {
                        for b in 0..2 {
                            self.s[(r1 + HW + a, od + b)] += block[(a, b)];
                        }
                    }
                }
                total += contact_total;
            }
            self.add_mapped(r1 + HW, r0 + X, &(skew(&total) * dt), n);
        }
    }

    /// State rows of stage `k` at `z`: (CoM, linear momentum, angular momentum).
    pub fn state(&self, k: usize, z: &DVectorView<'_, f64>) -> [Vector3<f64>; 3] {
        let n = z.len();
        let mut out = [Vector3::zeros(); 3];
        for (part, o) in out.iter_mut().enumerate() {
            for a in 0..3 {
                let r = STATE * k + 3 * part + a;
                o[a] = self.c[r] + (0..n).map(|j| self.s[(r, j)] * z[j]).sum::<f64>();
            }
        }
        out
    }
}
