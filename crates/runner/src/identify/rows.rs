//! The measurement rows of `stride identify`, one sample at a time: motor torques, force/torque sensor
//! readings and the base rows of the submodel above the feet sensors.

use nalgebra::{DMatrix, DVector, Matrix6, Vector6};
use stride_estimation::identification::IdentificationData;
use stride_model::{KinDyn, Model};

use super::usable::UsableRows;
use super::{IdentifyError, IdentifyOptions, Layout};
use crate::calibrate::Sample;

/// Regressor workspaces and the row being assembled.
pub(super) struct Rows {
    id: DMatrix<f64>,
    ft: DMatrix<f64>,
    sub: DMatrix<f64>,
    row: DVector<f64>,
    hosts: Vec<usize>,
}

impl Rows {
    pub(super) fn new(model: &Model, layout: &Layout) -> Self {
        let (nb, ns) = (model.body_count(), model.ft_sensors().len());
        Self {
            id: DMatrix::zeros(model.nv(), 10 * nb),
            ft: DMatrix::zeros(6 * ns, 10 * (nb + ns)),
            sub: DMatrix::zeros(6, 10 * (nb + ns)),
            row: DVector::zeros(layout.psi + layout.extras()),
            hosts: model
                .ft_sensors()
                .iter()
                .map(|s| model.frames()[s.frame.index()].link)
                .collect(),
        }
    }

    /// Motor-torque rows: the inverse-dynamics regressor's joint rows in the FT-split layout (a sensor's
    /// child-side block moves with its host), friction columns `sign(q̇)` and `q̇`.
    pub(super) fn add_torques(
        &mut self,
        kd: &mut KinDyn,
        s: &Sample,
        layout: &Layout,
        options: &IdentifyOptions,
        usable: &UsableRows,
        data: &mut IdentificationData,
    ) -> Result<(), IdentifyError> {
        let dof = layout.friction;
        if s.joint_torques.len() != dof {
            return Err(IdentifyError::Content(format!(
                "/sim/state has {} joint torques for {dof} joints",
                s.joint_torques.len()
            )));
        }
        kd.inverse_dynamics_regressor(&s.nu_dot, &mut self.id)?;
        let nb10 = self.id.ncols();
        for j in 0..dof {
            let speed = s.state.joint_velocities[j];
            if speed.abs() < options.min_joint_speed || !usable.joints[j] {
                continue;
            }
            self.row.fill(0.0);
            let r = 6 + j;
            for c in 0..nb10 {
                self.row[c] = self.id[(r, c)];
            }
            for (k, &h) in self.hosts.iter().enumerate() {
                for c in 0..10 {
                    self.row[nb10 + 10 * k + c] = self.id[(r, 10 * h + c)];
                }
            }
            self.row[layout.psi + j] = speed.signum();
            self.row[layout.psi + dof + j] = speed;
            data.add_row(self.row.as_view(), s.joint_torques[j], options.torque_noise)?;
        }
        Ok(())
    }

    /// Force/torque rows: the FT-sensor regressor and the sensor's offset columns.
    pub(super) fn add_ft(
        &mut self,
        kd: &mut KinDyn,
        s: &Sample,
        layout: &Layout,
        noise: &Vector6<f64>,
        usable: &UsableRows,
        data: &mut IdentificationData,
    ) -> Result<(), IdentifyError> {
        kd.ft_sensor_regressor(&s.nu_dot, &mut self.ft)?;
        let offsets = layout.psi + 2 * layout.friction;
        for (k, reading) in s.readings.iter().enumerate() {
            if !usable.sensors[k] {
                continue;
            }
            for a in 0..6 {
                self.row.fill(0.0);
                let r = 6 * k + a;
                for c in 0..layout.psi {
                    self.row[c] = self.ft[(r, c)];
                }
                self.row[offsets + r] = 1.0;
                data.add_row(self.row.as_view(), reading[a], noise[a])?;
            }
        }
        Ok(())
    }

    /// Base rows: the Newton–Euler equations of the submodel above the `cut` sensors,
    /// `Y_sub ψ + Σ_k A_k b_k = Σ_k A_k r_k` (`r_k` the raw readings, `b_k` their offsets, `A_k` the map to
    /// the wrench on the parent side in frame A'; [`KinDyn::ft_submodel_base_regressor`], Traversaro 2017
    /// eq. 7.1 with the feet sensors' wrenches). The six rows share the readings' noise: they are whitened
    /// by the Cholesky factor of `Σ_k A_k diag(σ²) A_kᵀ` and added with unit σ.
    pub(super) fn add_base(
        &mut self,
        kd: &mut KinDyn,
        s: &Sample,
        layout: &Layout,
        noise: &Vector6<f64>,
        cut: &[usize],
        data: &mut IdentificationData,
    ) -> Result<(), IdentifyError> {
        kd.ft_submodel_base_regressor(&s.nu_dot, cut, &mut self.sub)?;
        let offsets = layout.psi + 2 * layout.friction;
        let mut rhs = Vector6::zeros();
        let mut cov = Matrix6::zeros();
        let mut a = Matrix6::zeros();
        let mut rows = DMatrix::zeros(6, layout.psi + layout.extras());
        rows.columns_mut(0, layout.psi).copy_from(&self.sub);
        for &k in cut {
            kd.ft_sensor_parent_side_map(k, &mut a)?;
            rhs += a * s.readings[k];
            cov += a * Matrix6::from_diagonal(&noise.component_mul(noise)) * a.transpose();
            rows.view_mut((0, offsets + 6 * k), (6, 6)).copy_from(&a);
        }
        let chol = cov.cholesky().ok_or_else(|| {
            IdentifyError::Content("the feet sensors' noise covariance is singular".into())
        })?;
        let white_rows = chol.l().solve_lower_triangular(&rows).ok_or_else(|| {
            IdentifyError::Content("the feet sensors' noise covariance is singular".into())
        })?;
        let white_rhs = chol.l().solve_lower_triangular(&rhs).ok_or_else(|| {
            IdentifyError::Content("the feet sensors' noise covariance is singular".into())
        })?;
        for r in 0..6 {
            self.row.copy_from(&white_rows.row(r).transpose());
            data.add_row(self.row.as_view(), white_rhs[r], 1.0)?;
        }
        Ok(())
    }
}
