//! The centre of mass. QP-IK: `J_com ν = ẋ* + K_p (x* − x)` [Romualdi 2022, eq. 7.1.4] (rows in m/s,
//! `K_p` in 1/s). TSID: the linear momentum rate through the contact forces,
//! `Σ_c f_c = m (ẍ* + K_d (ẋ* − ẋ) + K_p (x* − x)) − m g` [Romualdi 2022, eq. 7.2.4, 7.2.7] (rows in N,
//! `K_p` in 1/s², `K_d` in 1/s).

use nalgebra::{DMatrix, Vector3};
use stride_model::{KinDyn, Model};
use stride_qp::TaskDataMut;

use super::{check_gain, TsidContext};
use crate::config::ComTaskConfig;
use crate::error::WbcError;
use crate::io::WbcInput;

/// The per-row gains `[x, y, z]` of a CoM task: `kp`, `kd`, the vertical row's `kp_z`, `kd_z` when given.
fn row_gains(c: &ComTaskConfig) -> Result<(Vector3<f64>, Vector3<f64>), WbcError> {
    check_gain(&c.name, "kp", c.kp)?;
    check_gain(&c.name, "kd", c.kd)?;
    let kp_z = c.kp_z.unwrap_or(c.kp);
    let kd_z = c.kd_z.unwrap_or(c.kd);
    check_gain(&c.name, "kp_z", kp_z)?;
    check_gain(&c.name, "kd_z", kd_z)?;
    Ok((
        Vector3::new(c.kp, c.kp, kp_z),
        Vector3::new(c.kd, c.kd, kd_z),
    ))
}

/// CoM tracking (velocity level: `J_com ν = ẋ_ref + K_p (x_ref − x)`, `K_p` per row).
#[derive(Debug, Clone)]
pub(crate) struct ComVelocityTask {
    pub name: String,
    kp: Vector3<f64>,
    rows: Vec<usize>,
    jacobian: DMatrix<f64>,
    pub block: usize,
}

impl ComVelocityTask {
    /// Sets `K_p` (1/s) of every row, the vertical one's included; the velocity-level task has no `K_d`.
    pub fn set_gains(&mut self, kp: f64) {
        self.kp = Vector3::repeat(kp);
    }

    pub fn new(model: &Model, c: &ComTaskConfig) -> Result<Self, WbcError> {
        let (kp, _) = row_gains(c)?;
        let rows: Vec<usize> = (0..3).filter(|&i| c.mask[i]).collect();
        if rows.is_empty() {
            return Err(WbcError::InvalidConfig {
                task: c.name.clone(),
                key: "mask",
                reason: "masks every row".into(),
            });
        }
        Ok(ComVelocityTask {
            name: c.name.clone(),
            kp,
            rows,
            jacobian: DMatrix::zeros(3, model.nv()),
            block: usize::MAX,
        })
    }

    pub fn row_count(&self) -> usize {
        self.rows.len()
    }

    pub fn update(
        &mut self,
        kd: &mut KinDyn,
        input: &WbcInput,
        block: TaskDataMut<'_>,
    ) -> Result<(), WbcError> {
        kd.com_jacobian(&mut self.jacobian)?;
        let com = kd.com_position();
        let rhs: Vector3<f64> =
            input.com_velocity + self.kp.component_mul(&(input.com_position - com));
        let nv = self.jacobian.ncols();
        for (k, &row) in self.rows.iter().enumerate() {
            for j in 0..nv {
                block.a[(k, j)] = self.jacobian[(row, j)];
            }
            block.b[k] = rhs[row];
        }
        Ok(())
    }

    /// `‖(x_ref − x)[mask]‖`.
    pub fn error_norm(&self, kd: &KinDyn, input: &WbcInput) -> f64 {
        let e = input.com_position - kd.com_position();
        self.rows.iter().map(|&i| e[i] * e[i]).sum::<f64>().sqrt()
    }
}

/// TSID linear momentum rate (the CoM task of the TSID): one row per kept axis `r`,
/// `Σ_c f_{c,r} = m (ẍ*_r + K_{d,r} (ẋ*_r − ẋ_r) + K_{p,r} (x*_r − x_r)) − m g_r` (N).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ComMomentumTask {
    kp: Vector3<f64>,
    kd: Vector3<f64>,
    rows: [bool; 3],
}

impl ComMomentumTask {
    /// Sets `K_p` (1/s²) and `K_d` (1/s) of every row, the vertical one's included.
    pub fn set_gains(&mut self, kp: f64, kd: f64) {
        self.kp = Vector3::repeat(kp);
        self.kd = Vector3::repeat(kd);
    }

    pub fn new(c: &ComTaskConfig) -> Result<Self, WbcError> {
        let (kp, kd) = row_gains(c)?;
        if !c.mask.iter().any(|m| *m) {
            return Err(WbcError::InvalidConfig {
                task: c.name.clone(),
                key: "mask",
                reason: "masks every row".into(),
            });
        }
        Ok(ComMomentumTask {
            kp,
            kd,
            rows: c.mask,
        })
    }

    pub fn row_count(&self) -> usize {
        self.rows.iter().filter(|m| **m).count()
    }

    /// Fills the rows over the force columns of the loaded contacts.
    pub fn fill(&self, input: &WbcInput, s: &TsidContext, b: &mut TaskDataMut) {
        let m = s.mass;
        let acc = input.com_acceleration
            + self
                .kd
                .component_mul(&(input.com_velocity - s.com_velocity))
            + self
                .kp
                .component_mul(&(input.com_position - s.com_position));
        let rhs = m * acc - m * s.gravity;
        let mut k = 0;
        for r in 0..3 {
            if !self.rows[r] {
                continue;
            }
            for c in 0..s.contacts.len() {
                if let Some(off) = s.offsets[c] {
                    b.a[(k, off + r)] = 1.0;
                }
            }
            b.b[k] = rhs[r];
            k += 1;
        }
    }
}
