//! The centroidal angular momentum about the CoM. QP-IK: `J_CMM,ω ν = h*` [Romualdi 2022, eq. 7.1.5]
//! (rows in kg m²/s). TSID: its rate through the contact wrenches,
//! `Σ_c (p_c − x_com) × f_c + μ_c = ḣ* + K_p (h* − h)` with `ḣ* = 0` [Romualdi 2022, eq. 7.2.5, 7.2.8]
//! (rows in N m, `K_p` in 1/s). The reference `h*` is `input.angular_momentum`.

use nalgebra::{DMatrix, Matrix3};
use stride_model::{KinDyn, Model};
use stride_qp::TaskDataMut;

use super::{check_gain, TsidContext};
use crate::config::AngularMomentumTaskConfig;
use crate::error::WbcError;
use crate::io::WbcInput;
use crate::math::skew;

/// Centroidal angular momentum, velocity level: `J_CMM,ω ν = h_ref`.
#[derive(Debug, Clone)]
pub(crate) struct AngularMomentumVelocityTask {
    cmm: DMatrix<f64>,
    pub block: usize,
}

impl AngularMomentumVelocityTask {
    pub fn new(model: &Model) -> Self {
        AngularMomentumVelocityTask {
            cmm: DMatrix::zeros(6, model.nv()),
            block: usize::MAX,
        }
    }

    pub fn update(
        &mut self,
        kd: &mut KinDyn,
        input: &WbcInput,
        block: TaskDataMut<'_>,
    ) -> Result<(), WbcError> {
        kd.centroidal_momentum_matrix(&mut self.cmm)?;
        let nv = self.cmm.ncols();
        for k in 0..3 {
            for j in 0..nv {
                block.a[(k, j)] = self.cmm[(3 + k, j)];
            }
            block.b[k] = input.angular_momentum[k];
        }
        Ok(())
    }
}

/// TSID angular momentum rate: `Σ_c [skew(p_c − x_com) | I] w_c = K_p (h* − h)` (N m; mixed wrenches
/// `w_c = [f_c; μ_c]` about the contact frame origins `p_c`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct AngularMomentumRateTask {
    kp: f64,
}

impl AngularMomentumRateTask {
    /// Sets `K_p` (1/s).
    pub fn set_gains(&mut self, kp: f64) {
        self.kp = kp;
    }

    pub fn new(c: &AngularMomentumTaskConfig) -> Result<Self, WbcError> {
        check_gain(&c.name, "kp", c.kp)?;
        Ok(AngularMomentumRateTask { kp: c.kp })
    }

    /// Fills the 3 rows over the wrench columns of the loaded contacts.
    pub fn fill(&self, input: &WbcInput, s: &TsidContext, b: &mut TaskDataMut) {
        let h = s.momentum.fixed_rows::<3>(3).into_owned();
        let rhs = self.kp * (input.angular_momentum - h);
        for (c, contact) in s.contacts.iter().enumerate() {
            if let Some(off) = s.offsets[c] {
                let arm: Matrix3<f64> = skew(&(contact.pose.translation.vector - s.com_position));
                b.a.view_mut((0, off), (3, 3)).copy_from(&arm);
                b.a.view_mut((0, off + 3), (3, 3))
                    .copy_from(&Matrix3::identity());
            }
        }
        for r in 0..3 {
            b.b[r] = rhs[r];
        }
    }
}
