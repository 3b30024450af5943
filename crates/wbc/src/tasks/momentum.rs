//! The centroidal angular momentum about the CoM. QP-IK: `J_CMM,ω ν = h*` [Romualdi 2022, eq. 7.1.5]
//! (rows in kg m²/s). TSID: its rate through the contact wrenches,
//! `Σ_c (p_c − x_com) × f_c + μ_c = ḣ* + K_p (h* − h)` with `ḣ* = 0` [Romualdi 2022, eq. 7.2.5, 7.2.8]
//! (rows in N m, `K_p` in 1/s). The reference `h*` is `input.angular_momentum`, or with `reference_joints`
//! the momentum of those joints' motion ([`JointMomentumReference`]).

use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, Vector3};
use stride_model::{FrameId, KinDyn, Model, RobotState};
use stride_qp::TaskDataMut;

use super::{check_gain, frame_id, TsidContext};
use crate::config::AngularMomentumTaskConfig;
use crate::error::WbcError;
use crate::io::WbcInput;
use crate::math::skew;
use crate::names::Resolver;

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
    /// `h*` (kg m²/s) of this tick when set by a [`JointMomentumReference`]; `None`:
    /// `input.angular_momentum`.
    pub reference: Option<Vector3<f64>>,
}

impl AngularMomentumRateTask {
    /// Sets `K_p` (1/s).
    pub fn set_gains(&mut self, kp: f64) {
        self.kp = kp;
    }

    pub fn new(c: &AngularMomentumTaskConfig) -> Result<Self, WbcError> {
        check_gain(&c.name, "kp", c.kp)?;
        Ok(AngularMomentumRateTask {
            kp: c.kp,
            reference: None,
        })
    }

    /// Fills the 3 rows over the wrench columns of the loaded contacts.
    pub fn fill(&self, input: &WbcInput, s: &TsidContext, b: &mut TaskDataMut) {
        let h = s.momentum.fixed_rows::<3>(3).into_owned();
        let target = self.reference.unwrap_or(input.angular_momentum);
        let rhs = self.kp * (target - h);
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

/// The reference of a TSID angular momentum task with `reference_joints` or `reference_frames`: the
/// centroidal angular momentum of the listed joints' motion with the base translating but not rotating,
/// `h* = A_ω(q) [v_B; 0; ṡ]` (`A_ω`: the angular rows of the centroidal momentum matrix, mixed velocity
/// [Orin 2013]), with `ḣ* = 0`: its change over the control period as `ḣ*` made the hard rows infeasible
/// within 0.02 s on the soft-ground walk (a 500 Hz difference of measured velocities). `ṡ` is the measured
/// velocity of the `reference_joints`, and on the chain of each `reference_frames` frame the velocity that
/// makes the frame follow its reference's velocity (damped least squares, see
/// [`crate::AngularMomentumTaskConfig`]); every other joint is still.
#[derive(Debug, Clone)]
pub(crate) struct JointMomentumReference {
    /// Velocity indices `6 + j` of the listed joints.
    columns: Vec<usize>,
    /// `reference_frames`: the frame and its reference's index in the controller's frame names.
    frames: Vec<(FrameId, usize)>,
    cmm: DMatrix<f64>,
    /// Scratch: a frame's Jacobian (6 × nv) and the reference velocity `[v_B; 0; ṡ]` (nv).
    jacobian: DMatrix<f64>,
    velocity: DVector<f64>,
}

/// The damping `λ` of the chains' least squares (`reference_frames`), m and rad.
const CHAIN_DAMPING: f64 = 1e-3;

impl JointMomentumReference {
    /// The reference of `c` (`None` when it lists no joints and no frames). Errors: an unknown joint or
    /// frame name, a reference name that is not in `names`.
    pub fn new(
        model: &Model,
        names: &Resolver,
        c: &AngularMomentumTaskConfig,
    ) -> Result<Option<Self>, WbcError> {
        if c.reference_joints.is_empty() && c.reference_frames.is_empty() {
            return Ok(None);
        }
        let columns = c
            .reference_joints
            .iter()
            .map(|name| {
                model
                    .joint_index(name)
                    .map(|j| 6 + j)
                    .ok_or_else(|| WbcError::UnknownJoint {
                        task: c.name.clone(),
                        joint: name.clone(),
                    })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let frames = c
            .reference_frames
            .iter()
            .map(|f| {
                let reference =
                    names
                        .frame_index(&f.reference)
                        .ok_or_else(|| WbcError::InvalidConfig {
                            task: c.name.clone(),
                            key: "reference_frames",
                            reason: format!("no reference named `{}`", f.reference),
                        })?;
                Ok((frame_id(model, &c.name, &f.frame)?, reference))
            })
            .collect::<Result<Vec<_>, WbcError>>()?;
        Ok(Some(JointMomentumReference {
            columns,
            frames,
            cmm: DMatrix::zeros(6, model.nv()),
            jacobian: DMatrix::zeros(6, model.nv()),
            velocity: DVector::zeros(model.nv()),
        }))
    }

    /// `h*` (kg m²/s) at the state `kd` holds (`state`: its velocities, mixed representation), the
    /// references of `reference_frames` read from `input`.
    pub fn update(
        &mut self,
        kd: &mut KinDyn,
        state: &RobotState,
        names: &Resolver,
        input: &WbcInput,
    ) -> Result<Vector3<f64>, WbcError> {
        kd.centroidal_momentum_matrix(&mut self.cmm)?;
        let v = &mut self.velocity;
        v.fill(0.0);
        for c in 0..3 {
            v[c] = state.base_velocity[c];
        }
        for &c in &self.columns {
            v[c] = state.joint_velocities[c - 6];
        }
        for &(frame, reference) in &self.frames {
            kd.frame_jacobian(frame, &mut self.jacobian)?;
            let j = &self.jacobian;
            let nv = j.ncols();
            // the chain: the joints that move the frame (a revolute joint's column has its axis in the
            // angular rows)
            let on_chain = |c: usize| j.fixed_view::<3, 1>(3, c).norm_squared() > 0.0;
            let mut target = names.frame(input, reference).velocity;
            for c in 0..3 {
                target -= j.fixed_view::<6, 1>(0, c) * v[c];
            }
            let mut gram = Matrix6::identity() * (CHAIN_DAMPING * CHAIN_DAMPING);
            for c in (6..nv).filter(|&c| on_chain(c)) {
                let col = j.fixed_view::<6, 1>(0, c);
                gram += col * col.transpose();
            }
            let Some(y) = gram.cholesky().map(|ch| ch.solve(&target)) else {
                continue;
            };
            for c in (6..nv).filter(|&c| on_chain(c)) {
                v[c] = j.fixed_view::<6, 1>(0, c).dot(&y);
            }
        }
        let mut h = Vector3::zeros();
        for k in 0..3 {
            h[k] = (0..v.len()).map(|c| self.cmm[(3 + k, c)] * v[c]).sum();
        }
        Ok(h)
    }
}
