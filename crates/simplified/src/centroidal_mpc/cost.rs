//! The QP of one real-time iteration: the objective (11.1.15a) as `½ zᵀ H z + gᵀ z` over the condensed
//! states, the cone coordinates `λ ⪰ 0` (11.1.13) and the displacement box (11.1.14) as bounds.

use nalgebra::{DMatrix, DVector, SMatrix, Vector3};

use super::config::CentroidalMpcConfig;
use super::dynamics::{Condensed, STATE};
use super::io::CentroidalMpcInput;
use super::layout::{ContactGeometry, Layout, CONTACT_VARIABLES, CORNERS, GENERATORS};
use super::linearization::Linearization;
use stride_qp::DenseQp;

/// Adds `½ w ‖A z_cols + c‖²` to the objective.
fn add_least_squares<const M: usize>(
    qp: &mut DenseQp,
    cols: &[usize; M],
    a: &SMatrix<f64, 3, M>,
    c: &Vector3<f64>,
    w: f64,
) {
    let ata = a.transpose() * a * w;
    let atc = a.transpose() * c * w;
    let h = qp.hessian_mut();
    for (p, &i) in cols.iter().enumerate() {
        for (q, &j) in cols.iter().enumerate() {
            h[(i, j)] += ata[(p, q)];
        }
    }
    let g = qp.gradient_mut();
    for (p, &i) in cols.iter().enumerate() {
        g[i] += atc[p];
    }
}

/// The tracking rows (11.1.11) stacked with their square-root weights: `J z + r`.
pub(crate) struct Tracking {
    pub j: DMatrix<f64>,
    pub r: DVector<f64>,
}

impl Tracking {
    pub fn new(stages: usize, max_variables: usize) -> Self {
        Self {
            j: DMatrix::zeros(6 * stages, max_variables),
            r: DVector::zeros(6 * stages),
        }
    }

    /// CoM rows `√Λ_CoM (x[k] − x_CoMⁿ[k])` and angular-momentum rows `√Λ_h h^ω[k]` for `k = 1..=N`
    /// (the nominal angular momentum is zero); `H = JᵀJ`, `g = Jᵀr`.
    fn fill(
        &mut self,
        qp: &mut DenseQp,
        input: &CentroidalMpcInput,
        states: &Condensed,
        stages: usize,
        config: &CentroidalMpcConfig,
    ) {
        let n = qp.n();
        let w_h = config.angular_momentum_weight.sqrt();
        for k in 1..=stages {
            let reference = input.reference(k);
            for a in 0..3 {
                let (row, w) = (6 * (k - 1) + a, config.com_weight[a].sqrt());
                let src = STATE * k + a;
                for j in 0..n {
                    self.j[(row, j)] = w * states.s[(src, j)];
                    self.j[(row + 3, j)] = w_h * states.s[(src + 6, j)];
                }
                self.r[row] = w * (states.c[src] - reference[a]);
                self.r[row + 3] = w_h * states.c[src + 6];
            }
        }
        let rows = 6 * stages;
        let j = self.j.view((0, 0), (rows, n));
        qp.hessian_mut().gemm_tr(1.0, &j, &j, 0.0);
        qp.gradient_mut()
            .gemv_tr(1.0, &j, &self.r.rows(0, rows), 0.0);
    }
}

/// Column indices of the cone coordinates of one corner.
fn corner_cols(offset: usize, corner: usize) -> [usize; GENERATORS] {
    std::array::from_fn(|g| offset + corner * GENERATORS + g)
}

/// (11.1.6): each corner force close to the contact's corner average.
fn add_force_average(qp: &mut DenseQp, offset: usize, geo: &ContactGeometry, w: f64) {
    let cols: [usize; CONTACT_VARIABLES] = std::array::from_fn(|v| offset + v);
    for j in 0..CORNERS {
        let mut a = SMatrix::<f64, 3, CONTACT_VARIABLES>::zeros();
        for w_corner in 0..CORNERS {
            let coef = if w_corner == j { 0.75 } else { -0.25 };
            a.fixed_view_mut::<3, GENERATORS>(0, w_corner * GENERATORS)
                .copy_from(&(geo.generators * coef));
        }
        add_least_squares(qp, &cols, &a, &Vector3::zeros(), w);
    }
}

/// (11.1.8)–(11.1.10): `(f[b] − f[b−1]) / (hold·dt)` per corner between consecutive force blocks of the
/// same contact (at the first block against the force applied at the previous tick).
fn add_force_rate(
    qp: &mut DenseQp,
    layout: &Layout,
    geometry: &[ContactGeometry],
    lin: &Linearization,
    block_duration: f64,
    w: f64,
) {
    for (b, slots) in layout.blocks.iter().enumerate() {
        for (q, slot) in slots.iter().enumerate() {
            let Some(slot) = slot else { continue };
            let g = geometry[slot.contact].generators / block_duration;
            if b == 0 {
                let Some(applied) = lin.applied[q] else {
                    continue;
                };
                for (j, f_prev) in applied.iter().enumerate() {
                    let c = -f_prev / block_duration;
                    add_least_squares(qp, &corner_cols(slot.offset, j), &g, &c, w);
                }
                continue;
            }
            let Some(prev) = layout.blocks[b - 1]
                .iter()
                .flatten()
                .find(|p| p.contact == slot.contact)
            else {
                continue;
            };
            let mut a = SMatrix::<f64, 3, 8>::zeros();
            a.fixed_view_mut::<3, 4>(0, 0).copy_from(&g);
            a.fixed_view_mut::<3, 4>(0, 4).copy_from(&(-g));
            for j in 0..CORNERS {
                let (now, before) = (corner_cols(slot.offset, j), corner_cols(prev.offset, j));
                let cols: [usize; 8] =
                    std::array::from_fn(|v| if v < 4 { now[v] } else { before[v - 4] });
                add_least_squares(qp, &cols, &a, &Vector3::zeros(), w);
            }
        }
    }
}

/// Writes the whole QP of the tick into `qp` (sized `layout.n`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn assemble(
    qp: &mut DenseQp,
    tracking: &mut Tracking,
    input: &CentroidalMpcInput,
    layout: &Layout,
    geometry: &[ContactGeometry],
    states: &Condensed,
    lin: &Linearization,
    config: &CentroidalMpcConfig,
) {
    tracking.fill(qp, input, states, layout.stages.len(), config);
    for slots in &layout.blocks {
        for slot in slots.iter().flatten() {
            add_force_average(
                qp,
                slot.offset,
                &geometry[slot.contact],
                config.force_average_weight,
            );
        }
    }
    add_force_rate(
        qp,
        layout,
        geometry,
        lin,
        config.stage_duration * config.force_hold_stages as f64,
        config.force_rate_weight,
    );
    let cone = layout.n - 2 * layout.displacement.iter().flatten().count();
    for v in 0..cone {
        qp.hessian_mut()[(v, v)] += config.force_regularization;
        qp.lower_bounds_mut()[v] = 0.0;
        qp.upper_bounds_mut()[v] = f64::INFINITY;
    }
    for (i, od) in layout.displacement.iter().enumerate() {
        let Some(od) = *od else { continue };
        let side = match input.contacts[i].foot {
            crate::Foot::Left => 1.0,
            crate::Foot::Right => -1.0,
        };
        let [out_lo, out_hi] = config.outward;
        let (y_lo, y_hi) = if side > 0.0 {
            (out_lo, out_hi)
        } else {
            (-out_hi, -out_lo)
        };
        let bounds = [(config.forward[0], config.forward[1]), (y_lo, y_hi)];
        for (b, (lo, hi)) in bounds.iter().enumerate() {
            qp.hessian_mut()[(od + b, od + b)] += config.contact_position_weight;
            qp.lower_bounds_mut()[od + b] = *lo;
            qp.upper_bounds_mut()[od + b] = *hi;
        }
    }
}
