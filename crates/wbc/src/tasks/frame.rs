//! SE(3) / SO(3) / R³ tracking of a frame, velocity level (QP-IK)
//! `J ν = [ṗ*; ω*] + K_p [p* − p; Log(R* Rᵀ)]` [Romualdi 2022, eq. 7.1.6–7.1.10] and acceleration level
//! (TSID) `J ν̇ = [p̈*; ω̇*] + K_d ([ṗ*; ω*] − J ν) + K_p [p* − p; Log(R* Rᵀ)] − J̇ν`
//! [Romualdi 2022, eq. 7.2.9–7.2.13]. Rows: the kept rows of `[linear (m/s, m/s²); angular (rad/s,
//! rad/s²)]`, world axes (mixed representation); gains `K_p` in 1/s (IK) or 1/s² (TSID), `K_d` in 1/s.

use nalgebra::{DMatrix, Isometry3, UnitQuaternion, Vector6};
use stride_model::{FrameId, KinDyn, Model};
use stride_qp::TaskDataMut;

use super::{check_gain, frame_id, Level};
use crate::config::{Frame3TaskConfig, ReferenceOffset, Se3TaskConfig};
use crate::error::WbcError;
use crate::io::{FrameReference, WbcInput, INITIAL};
use crate::math::orientation_error;
use crate::names::Resolver;

/// Where a frame task's reference comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Source {
    /// The controller's frame reference name `k` (see [`Resolver`]).
    Named(usize),
    /// The frame's pose at the first tick, held still.
    Initial,
}

/// SE(3) / SO(3) / R³ tracking of a frame (7.1.6–7.1.10, 7.2.9–7.2.13).
#[derive(Debug, Clone)]
pub(crate) struct FrameTask {
    pub name: String,
    pub frame: FrameId,
    source: Source,
    /// Gains per row of the 6D task `[lin; ang]`.
    kp: Vector6<f64>,
    kd: Vector6<f64>,
    /// Kept 6D rows (0..3 linear, 3..6 angular).
    rows: Vec<usize>,
    initial: Option<Isometry3<f64>>,
    /// Orientation offset mode and, once recorded, `R_off = R_refᵀ R` at the first tick.
    offset_mode: ReferenceOffset,
    offset: Option<UnitQuaternion<f64>>,
    jacobian: DMatrix<f64>,
    pub level: Level,
    /// Block index in the controller's block list.
    pub block: usize,
}

impl FrameTask {
    pub fn from_se3(
        model: &Model,
        names: &Resolver,
        c: &Se3TaskConfig,
        level: Level,
    ) -> Result<Self, WbcError> {
        for (k, v) in [
            ("kp_linear", c.kp_linear),
            ("kp_angular", c.kp_angular),
            ("kd_linear", c.kd_linear),
            ("kd_angular", c.kd_angular),
        ] {
            check_gain(&c.name, k, v)?;
        }
        let rows: Vec<usize> = (0..6).filter(|&i| c.mask[i]).collect();
        let kp = Vector6::new(
            c.kp_linear,
            c.kp_linear,
            c.kp_linear,
            c.kp_angular,
            c.kp_angular,
            c.kp_angular,
        );
        let kd = Vector6::new(
            c.kd_linear,
            c.kd_linear,
            c.kd_linear,
            c.kd_angular,
            c.kd_angular,
            c.kd_angular,
        );
        let source = source(names, &c.reference);
        Self::build(model, &c.name, &c.frame, source, kp, kd, rows, level)
    }

    pub fn from_frame3(
        model: &Model,
        names: &Resolver,
        c: &Frame3TaskConfig,
        angular: bool,
        level: Level,
    ) -> Result<Self, WbcError> {
        check_gain(&c.name, "kp", c.kp)?;
        check_gain(&c.name, "kd", c.kd)?;
        if !angular && c.reference_offset != ReferenceOffset::None {
            return Err(WbcError::InvalidConfig {
                task: c.name.clone(),
                key: "reference_offset",
                reason: "an orientation offset applies to `so3` tasks only; remove it".into(),
            });
        }
        let offset = if angular { 3 } else { 0 };
        let rows: Vec<usize> = (0..3).filter(|&i| c.mask[i]).map(|i| i + offset).collect();
        let kp = Vector6::from_element(c.kp);
        let kd = Vector6::from_element(c.kd);
        let source = source(names, &c.reference);
        let mut task = Self::build(model, &c.name, &c.frame, source, kp, kd, rows, level)?;
        task.offset_mode = c.reference_offset;
        Ok(task)
    }

    #[allow(clippy::too_many_arguments)]
    fn build(
        model: &Model,
        name: &str,
        frame: &str,
        source: Source,
        kp: Vector6<f64>,
        kd: Vector6<f64>,
        rows: Vec<usize>,
        level: Level,
    ) -> Result<Self, WbcError> {
        if rows.is_empty() {
            return Err(WbcError::InvalidConfig {
                task: name.to_owned(),
                key: "mask",
                reason: "masks every row".into(),
            });
        }
        Ok(FrameTask {
            name: name.to_owned(),
            frame: frame_id(model, name, frame)?,
            source,
            kp,
            kd,
            rows,
            initial: None,
            offset_mode: ReferenceOffset::None,
            offset: None,
            jacobian: DMatrix::zeros(6, model.nv()),
            level,
            block: usize::MAX,
        })
    }

    pub fn row_count(&self) -> usize {
        self.rows.len()
    }

    pub fn reset(&mut self) {
        self.initial = None;
        self.offset = None;
    }

    fn reference(&mut self, kd: &KinDyn, names: &Resolver, input: &WbcInput) -> FrameReference {
        let mut r = match self.source {
            Source::Named(k) => *names.frame(input, k),
            Source::Initial => FrameReference::still(
                *self
                    .initial
                    .get_or_insert_with(|| kd.frame_pose(self.frame)),
            ),
        };
        if self.offset_mode == ReferenceOffset::Initial {
            let frame = self.frame;
            let reference = r.pose.rotation;
            let offset = *self
                .offset
                .get_or_insert_with(|| reference.inverse() * kd.frame_pose(frame).rotation);
            r.pose.rotation = reference * offset;
        }
        r
    }

    /// Sets the gains of every row: `K_p` (1/s in IK, 1/s² in TSID), `K_d` (1/s, TSID).
    pub fn set_gains(&mut self, kp: f64, kd: f64) {
        self.kp.fill(kp);
        self.kd.fill(kd);
    }

    /// Fills the block's columns `0..nv` (the ν / ν̇ part) and its right-hand side.
    pub fn update(
        &mut self,
        kd: &KinDyn,
        names: &Resolver,
        input: &WbcInput,
        block: TaskDataMut<'_>,
    ) -> Result<(), WbcError> {
        let r = self.reference(kd, names, input);
        kd.frame_jacobian(self.frame, &mut self.jacobian)?;
        let pose = kd.frame_pose(self.frame);
        let mut error = Vector6::zeros();
        error
            .fixed_rows_mut::<3>(0)
            .copy_from(&(r.pose.translation.vector - pose.translation.vector));
        error
            .fixed_rows_mut::<3>(3)
            .copy_from(&orientation_error(&r.pose.rotation, &pose.rotation));
        let mut rhs = Vector6::zeros();
        match self.level {
            Level::Velocity => {
                for i in 0..6 {
                    rhs[i] = r.velocity[i] + self.kp[i] * error[i];
                }
            }
            Level::Acceleration => {
                let v = kd.frame_velocity(self.frame);
                let bias = kd.frame_bias_acceleration(self.frame);
                for i in 0..6 {
                    rhs[i] = r.acceleration[i]
                        + self.kd[i] * (r.velocity[i] - v[i])
                        + self.kp[i] * error[i]
                        - bias[i];
                }
            }
        }
        let nv = self.jacobian.ncols();
        for (k, &row) in self.rows.iter().enumerate() {
            for j in 0..nv {
                block.a[(k, j)] = self.jacobian[(row, j)];
            }
            block.b[k] = rhs[row];
        }
        Ok(())
    }

    /// Current task error `[p_ref − p; Log(R_ref Rᵀ)]` on the kept rows, norm (for tests and logs).
    pub fn pose_error_norm(&mut self, kd: &KinDyn, names: &Resolver, input: &WbcInput) -> f64 {
        let r = self.reference(kd, names, input);
        let pose = kd.frame_pose(self.frame);
        let mut e = Vector6::zeros();
        e.fixed_rows_mut::<3>(0)
            .copy_from(&(r.pose.translation.vector - pose.translation.vector));
        e.fixed_rows_mut::<3>(3)
            .copy_from(&orientation_error(&r.pose.rotation, &pose.rotation));
        self.rows.iter().map(|&i| e[i] * e[i]).sum::<f64>().sqrt()
    }
}

/// The source of reference name `name`: `initial`, or its index in the controller's names (which hold
/// every frame task's reference by construction).
fn source(names: &Resolver, name: &str) -> Source {
    match names.frame_index(name) {
        Some(k) if name != INITIAL => Source::Named(k),
        _ => Source::Initial,
    }
}
