//! The flat-footed crouch a new robot starts in: the leg joint positions that put the CoM at a target
//! height above level soles, over the centre of the feet, with the base upright.
//!
//! Solved by Gauss–Newton with a finite-difference Jacobian on the 12 conditions below (six per sole:
//! orientation, lateral position and height; two for the feet's and the CoM's fore-aft position), in the
//! leg joints only, the base held at the identity (upright) and every other joint at its given position.
//! The check is the conditions themselves: the solution is accepted only when every residual is below
//! [`CROUCH_TOLERANCE`] and the joints are inside their limits.

use std::sync::Arc;

use nalgebra::{DMatrix, DVector, Isometry3};
use stride_model::{FrameId, KinDyn, Model, RobotState};

use super::limbs::Leg;

/// Knee flexion of the default target height \[rad\]: the bundled humanoid's and iCub's crouch (40°).
pub const CROUCH_KNEE_ANGLE: f64 = 0.7;
/// Largest residual of an accepted crouch (m for positions, rad for orientations).
pub const CROUCH_TOLERANCE: f64 = 1e-7;
/// Gauss–Newton iterations before giving up.
const MAX_ITERATIONS: usize = 200;
/// Finite-difference step of the Jacobian \[rad\].
const FD_STEP: f64 = 1e-7;
/// Largest joint change per iteration \[rad\].
const MAX_STEP: f64 = 0.2;

/// Why no crouch was found.
#[derive(Debug, thiserror::Error)]
pub enum CrouchError {
    /// Gauss–Newton did not converge, or converged outside the joint limits.
    #[error("no flat-footed crouch with the CoM {height:.3} m above the soles: {reason}")]
    NotFound {
        /// Target CoM height \[m\].
        height: f64,
        /// What went wrong.
        reason: String,
    },
    /// The model could not be evaluated.
    #[error(transparent)]
    Model(#[from] stride_model::ModelError),
}

/// Fraction of the hip drop by which the CoM drops in a crouch [-]: the legs (about a third of the mass)
/// drop less than the hips. Measured on the hand-chosen 0.7 rad crouches (`stride check`): the bundled
/// humanoid's CoM drops by 0.61 of its 0.7 rad hip drop, the G1's by 0.83.
pub const COM_DROP_FRACTION: f64 = 0.75;

/// The default target CoM height: the zero posture's CoM height above the soles `h0` lowered by
/// [`COM_DROP_FRACTION`] of the hip drop of a knee bent by [`CROUCH_KNEE_ANGLE`] in a leg of length `L`
/// with equal thigh and shank, `h0 − 0.75 L (1 − cos(θ/2))` \[m\] (a two-link leg's hip-to-ankle distance
/// is `L cos(θ/2)`).
pub fn default_target_height(zero_com_height: f64, leg_length: f64) -> f64 {
    zero_com_height - COM_DROP_FRACTION * leg_length * (1.0 - (CROUCH_KNEE_ANGLE * 0.5).cos())
}

/// The residuals of the crouch conditions at joint positions `q` (base upright at the identity):
/// per sole, the rotation from its zero-posture orientation (3, rad), its lateral offset from its zero
/// posture (1, m) and the CoM height above it minus `height` (1, m); the soles' fore-aft offset and the
/// CoM's fore-aft offset from the soles' mid-point (2, m).
struct Conditions<'a> {
    model: &'a Arc<Model>,
    soles: [FrameId; 2],
    zero: [Isometry3<f64>; 2],
    height: f64,
    kd: KinDyn,
    state: RobotState,
}

impl Conditions<'_> {
    fn residual(&mut self, q: &DVector<f64>) -> Result<DVector<f64>, stride_model::ModelError> {
        self.state.joint_positions.copy_from(q);
        self.kd.set_state(&self.state)?;
        let com = self.kd.com_position();
        let mut r = DVector::zeros(12);
        let mut xs = [0.0; 2];
        for (i, sole) in self.soles.iter().enumerate() {
            let pose = self.kd.frame_pose(*sole);
            let rot = (self.zero[i].rotation.inverse() * pose.rotation).scaled_axis();
            r.fixed_rows_mut::<3>(5 * i).copy_from(&rot);
            r[5 * i + 3] = pose.translation.y - self.zero[i].translation.y;
            r[5 * i + 4] = com.z - pose.translation.z - self.height;
            xs[i] = pose.translation.x;
        }
        r[10] = xs[0] - xs[1];
        r[11] = com.x - 0.5 * (xs[0] + xs[1]);
        Ok(r)
    }
}

/// Joint positions (model order) of the flat-footed crouch with the CoM `height` above the soles, from
/// `start` (the legs' joints are solved; the others keep their values). The knees start flexed by a
/// quarter of [`CROUCH_KNEE_ANGLE`] in their flexion direction so the solution bends them forwards.
pub fn crouch(
    model: &Arc<Model>,
    soles: [FrameId; 2],
    legs: [&Leg; 2],
    start: &DVector<f64>,
    height: f64,
) -> Result<DVector<f64>, CrouchError> {
    let not_found = |reason: String| CrouchError::NotFound { height, reason };
    let unknowns: Vec<usize> = legs.iter().flat_map(|l| l.joints.clone()).collect();
    let mut q = start.clone();
    for leg in legs {
        q[leg.knee] = leg.knee_flexion_sign * CROUCH_KNEE_ANGLE * 0.25;
    }
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_state(&RobotState::zero(model))?;
    let zero = [kd.frame_pose(soles[0]), kd.frame_pose(soles[1])];
    let mut c = Conditions {
        model,
        soles,
        zero,
        height,
        kd,
        state: RobotState::zero(model),
    };
    let mut jac = DMatrix::zeros(12, unknowns.len());
    for _ in 0..MAX_ITERATIONS {
        let r = c.residual(&q)?;
        if r.amax() < CROUCH_TOLERANCE {
            return accept(c.model, q, legs, not_found);
        }
        for (k, &j) in unknowns.iter().enumerate() {
            let mut qp = q.clone();
            qp[j] += FD_STEP;
            let rp = c.residual(&qp)?;
            jac.set_column(k, &((rp - &r) / FD_STEP));
        }
        let jt = jac.transpose();
        let damped = &jt * &jac + DMatrix::identity(unknowns.len(), unknowns.len()) * 1e-9;
        let step = damped
            .cholesky()
            .ok_or_else(|| not_found("the legs' Jacobian is singular".into()))?
            .solve(&(jt * r));
        let scale = (MAX_STEP / step.amax().max(MAX_STEP)).min(1.0);
        for (k, &j) in unknowns.iter().enumerate() {
            let joint = &c.model.joints()[j];
            q[j] = (q[j] - scale * step[k]).clamp(joint.lower, joint.upper);
        }
    }
    let r = c.residual(&q)?;
    Err(not_found(format!(
        "Gauss–Newton stopped after {MAX_ITERATIONS} iterations with a residual of {:.2e}",
        r.amax()
    )))
}

/// The converged `q` if its knees are flexed (not hyper-extended) and every joint is inside its limits.
fn accept(
    model: &Model,
    q: DVector<f64>,
    legs: [&Leg; 2],
    not_found: impl Fn(String) -> CrouchError,
) -> Result<DVector<f64>, CrouchError> {
    for leg in legs {
        if q[leg.knee] * leg.knee_flexion_sign <= 0.0 {
            return Err(not_found(format!(
                "the solution bends the knee `{}` backwards ({:.3} rad)",
                model.joints()[leg.knee].name,
                q[leg.knee]
            )));
        }
    }
    stride_model::check_joint_limits(model, &q).map_err(|e| not_found(e.to_string()))?;
    Ok(q)
}
