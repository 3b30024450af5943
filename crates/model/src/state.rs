//! Floating-base state, velocity representations and state integration.

use nalgebra::{DVector, Isometry3, Matrix3, Translation3, UnitQuaternion, Vector6};

use crate::error::{check_len, ModelError};
use crate::model::Model;
use crate::spatial::{ang, join, lin, skew};

/// `true` if no entry is `±∞` or NaN, `values.iter().all(|v| v.is_finite())` without a branch per entry
/// (every state the kinematics and the simulator take is checked): `v · 0` is `±0` for a finite `v` and
/// NaN otherwise, and NaN survives the sums (four lanes, which the compiler vectorizes).
fn all_finite(values: &[f64]) -> bool {
    let chunks = values.chunks_exact(4);
    let tail: f64 = chunks.remainder().iter().map(|v| v * 0.0).sum();
    let lanes = chunks.fold([0.0; 4], |a, c| {
        [
            a[0] + c[0] * 0.0,
            a[1] + c[1] * 0.0,
            a[2] + c[2] * 0.0,
            a[3] + c[3] * 0.0,
        ]
    });
    lanes.iter().sum::<f64>() + tail == 0.0
}

/// How the base velocity (and frame velocities, Jacobians, accelerations) are expressed
/// [Traversaro 2017, Table 2.1] (iDynTree semantics).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "snake_case")]
pub enum VelocityRepresentation {
    /// `[d/dt ^A o_B; ^A ω_{A,B}]`: linear velocity of the frame origin and angular velocity, both in world
    /// orientation (iDynTree's default, frame `B[A]`).
    #[default]
    Mixed,
    /// Left-trivialized `^B v_{A,B}`: both in the frame's own coordinates (Pinocchio's LOCAL).
    Body,
    /// Right-trivialized `^A v_{A,B}`: world coordinates, linear part = velocity of the body point at the world
    /// origin.
    Inertial,
}

impl VelocityRepresentation {
    /// `mixed`, `body` or `inertial`.
    pub fn as_str(&self) -> &'static str {
        match self {
            VelocityRepresentation::Mixed => "mixed",
            VelocityRepresentation::Body => "body",
            VelocityRepresentation::Inertial => "inertial",
        }
    }
}

impl std::str::FromStr for VelocityRepresentation {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "mixed" => Ok(Self::Mixed),
            "body" => Ok(Self::Body),
            "inertial" => Ok(Self::Inertial),
            other => Err(format!(
                "unknown velocity representation `{other}` (expected mixed, body or inertial)"
            )),
        }
    }
}

/// Floating-base robot state.
#[derive(Clone, Debug, PartialEq)]
pub struct RobotState {
    /// `world_H_base` (pose of the root link).
    pub base_pose: Isometry3<f64>,
    /// Joint positions (rad or m), model order, length n.
    pub joint_positions: DVector<f64>,
    /// Base velocity `[linear; angular]` in the representation of the [`crate::KinDyn`] it is given to.
    pub base_velocity: Vector6<f64>,
    /// Joint velocities (rad/s or m/s), length n.
    pub joint_velocities: DVector<f64>,
}

impl RobotState {
    /// Copies `other` into `self`, reusing `self`'s joint vectors when the sizes agree (no allocation, as
    /// in a control tick); `clone_from` would reallocate. Resizes (allocating) otherwise.
    pub fn copy_from(&mut self, other: &RobotState) {
        self.base_pose = other.base_pose;
        self.base_velocity = other.base_velocity;
        if self.joint_positions.len() == other.joint_positions.len() {
            self.joint_positions.copy_from(&other.joint_positions);
        } else {
            self.joint_positions = other.joint_positions.clone();
        }
        if self.joint_velocities.len() == other.joint_velocities.len() {
            self.joint_velocities.copy_from(&other.joint_velocities);
        } else {
            self.joint_velocities = other.joint_velocities.clone();
        }
    }

    /// Checks that the state fits `model` (one position and one velocity per joint) and holds only finite
    /// numbers. Every consumer of a user-supplied state (kinematics, controllers, simulator) calls this one
    /// check.
    pub fn validate(&self, model: &Model) -> Result<(), ModelError> {
        let n = model.dof();
        check_len("joint_positions", n, self.joint_positions.len())?;
        check_len("joint_velocities", n, self.joint_velocities.len())?;
        let pose_finite = all_finite(self.base_pose.translation.vector.as_slice())
            && all_finite(self.base_pose.rotation.coords.as_slice());
        for (what, finite) in [
            ("base_pose", pose_finite),
            (
                "joint_positions",
                all_finite(self.joint_positions.as_slice()),
            ),
            ("base_velocity", all_finite(self.base_velocity.as_slice())),
            (
                "joint_velocities",
                all_finite(self.joint_velocities.as_slice()),
            ),
        ] {
            if !finite {
                return Err(ModelError::NonFiniteInput { what });
            }
        }
        Ok(())
    }

    /// Checks that every joint position lies within its URDF limits `lower ≤ q ≤ upper` (continuous joints
    /// and joints without `<limit>` have infinite limits). Call it where joint positions enter from a user
    /// (an initial posture, a configuration file); the controllers' own states are not checked (a
    /// simulated joint may overshoot its limit slightly).
    ///
    /// # Errors
    /// [`ModelError::DimensionMismatch`] when the length is not the model's DoF,
    /// [`ModelError::JointOutOfLimits`] naming the first joint outside its limits, with its value and
    /// limits.
    pub fn check_joint_limits(&self, model: &Model) -> Result<(), ModelError> {
        check_joint_limits(model, &self.joint_positions)
    }

    /// Identity base pose, zero joint positions and velocities.
    pub fn zero(model: &Model) -> Self {
        Self {
            base_pose: Isometry3::identity(),
            joint_positions: DVector::zeros(model.dof()),
            base_velocity: Vector6::zeros(),
            joint_velocities: DVector::zeros(model.dof()),
        }
    }

    /// Advances the state by `dt` seconds at constant velocity: joints `q += dt q̇`; base on SE(3) with the
    /// base velocity read in `representation` and held constant in that representation:
    /// body `H ← H exp(dt ^B v^)`, inertial `H ← exp(dt ^A v^) H`, mixed `o ← o + dt ȯ`, `R ← exp(dt ω^) R`.
    /// Velocities are unchanged.
    pub fn integrate(
        &mut self,
        model: &Model,
        representation: VelocityRepresentation,
        dt: f64,
    ) -> Result<(), ModelError> {
        check_len("joint_positions", model.dof(), self.joint_positions.len())?;
        check_len("joint_velocities", model.dof(), self.joint_velocities.len())?;
        if !dt.is_finite() {
            return Err(ModelError::NonFiniteInput { what: "dt" });
        }
        if !self.base_velocity.iter().all(|v| v.is_finite())
            || !self.joint_velocities.iter().all(|v| v.is_finite())
        {
            return Err(ModelError::NonFiniteInput { what: "velocities" });
        }
        self.joint_positions.axpy(dt, &self.joint_velocities, 1.0);
        let v = self.base_velocity;
        self.base_pose = match representation {
            VelocityRepresentation::Body => self.base_pose * se3_exp(&(v * dt)),
            VelocityRepresentation::Inertial => se3_exp(&(v * dt)) * self.base_pose,
            VelocityRepresentation::Mixed => {
                let rot = UnitQuaternion::from_scaled_axis(ang(&v) * dt) * self.base_pose.rotation;
                let pos = self.base_pose.translation.vector + lin(&v) * dt;
                Isometry3::from_parts(
                    Translation3::from(pos),
                    UnitQuaternion::new_normalize(rot.into_inner()),
                )
            }
        };
        Ok(())
    }
}

/// Exponential map of SE(3): the pose reached after a unit time at constant body twist `xi = [v; ω]`.
pub fn se3_exp(xi: &Vector6<f64>) -> Isometry3<f64> {
    let v = lin(xi);
    let w = ang(xi);
    let theta = w.norm();
    let s = skew(&w);
    let (a, b) = if theta < 1e-6 {
        // Series of (1 − cos θ)/θ² and (θ − sin θ)/θ³.
        let t2 = theta * theta;
        (0.5 - t2 / 24.0, 1.0 / 6.0 - t2 / 120.0)
    } else {
        (
            (1.0 - theta.cos()) / (theta * theta),
            (theta - theta.sin()) / (theta * theta * theta),
        )
    };
    let jac = Matrix3::identity() + s * a + s * s * b;
    Isometry3::from_parts(
        Translation3::from(jac * v),
        UnitQuaternion::from_scaled_axis(w),
    )
}

/// Converts a base (or any frame) velocity of a frame with world pose `pose` between representations.
pub fn convert_velocity(
    pose: &Isometry3<f64>,
    velocity: &Vector6<f64>,
    from: VelocityRepresentation,
    to: VelocityRepresentation,
) -> Vector6<f64> {
    let r: Matrix3<f64> = *pose.rotation.to_rotation_matrix().matrix();
    let o = pose.translation.vector;
    // To mixed [ȯ; ω].
    let (od, w) = match from {
        VelocityRepresentation::Mixed => (lin(velocity), ang(velocity)),
        VelocityRepresentation::Body => (r * lin(velocity), r * ang(velocity)),
        VelocityRepresentation::Inertial => {
            let w = ang(velocity);
            (lin(velocity) + w.cross(&o), w)
        }
    };
    match to {
        VelocityRepresentation::Mixed => join(&od, &w),
        VelocityRepresentation::Body => join(&(r.transpose() * od), &(r.transpose() * w)),
        VelocityRepresentation::Inertial => join(&(od - w.cross(&o)), &w),
    }
}

/// [`RobotState::check_joint_limits`] on bare joint positions `q` (model order, rad or m).
///
/// # Errors
/// As [`RobotState::check_joint_limits`]; NaN is outside every limit.
pub fn check_joint_limits(model: &Model, q: &DVector<f64>) -> Result<(), ModelError> {
    check_len("joint_positions", model.dof(), q.len())?;
    for (joint, &value) in model.joints().iter().zip(q.iter()) {
        if !(joint.lower <= value && value <= joint.upper) {
            return Err(ModelError::JointOutOfLimits {
                joint: joint.name.clone(),
                value,
                lower: joint.lower,
                upper: joint.upper,
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod finite_tests {
    use super::all_finite;

    /// The entrywise answer for every length up to a few lanes past a multiple of four and every
    /// position of one non-finite entry, among finite entries of extreme magnitudes and both zeros.
    #[test]
    fn all_finite_is_the_entrywise_check() {
        let finite = [1.0, -2.5, f64::MAX, -f64::MAX, 5e-324, -0.0, 0.0, -3.0e300];
        for len in 0..=13 {
            let values: Vec<f64> = (0..len).map(|k| finite[k % finite.len()]).collect();
            assert!(all_finite(&values), "len {len}");
            for bad in [f64::INFINITY, f64::NEG_INFINITY, f64::NAN] {
                for at in 0..len {
                    let mut v = values.clone();
                    v[at] = bad;
                    assert!(!all_finite(&v), "len {len}, {bad} at {at}");
                }
            }
        }
        // +∞ and −∞ in different lanes do not cancel
        let mut v = vec![0.0; 9];
        v[0] = f64::INFINITY;
        v[5] = f64::NEG_INFINITY;
        assert!(!all_finite(&v));
    }
}
