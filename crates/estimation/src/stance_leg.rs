//! The accelerations of a stance leg's joints for the estimation layer's inverse dynamics.
//!
//! The estimator's `ν̇` (step 3 of [`crate::Estimator`]) has the base's linear acceleration and zero joint
//! accelerations: every link moves as if welded to the base. A leg whose sole stands still does not: its
//! links pivot about the sole while the base accelerates over it (the LIP's `ω² (x − x_zmp)`, about
//! 1 m/s² on the bundled robot), and the joint torques at its top, a passive hip's torque among them
//! (the deflection observer's input, [`crate::FlexibleJointObserver`]), miss that inertia. The thesis's
//! observer starts from the sole instead [Romualdi 2022, §9.3, Algorithm 1]. Here, for a foot in contact,
//! the six actuated joints between the base and the sole get the accelerations that keep the sole still
//! given the base's: `J_q q̈ = −(J_b ν̇_b + J̇ ν)`, `J = [J_b J_q]` the sole's Jacobian (mixed velocity).
//! The passive joints of the chain keep zero (their own acceleration is the observer's unknown).

use nalgebra::{DMatrix, DVector, Matrix6, Vector6};
use stride_model::{FrameId, KinDyn, Model};

use crate::error::{EstimatorError, Result};

/// The stance legs' joint chains and the Jacobian workspace. Allocation-free after [`StanceLegs::new`].
#[derive(Debug, Clone)]
pub(crate) struct StanceLegs {
    /// Per foot, the model indices of the six actuated joints between the base and the sole.
    chains: [[usize; 6]; 2],
    jacobian: DMatrix<f64>,
}

impl StanceLegs {
    /// The chains of `soles` (left, right) in `model`, skipping the joints named in `passive`.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidParameter`] (`stance_leg_accelerations`) when a chain has other than six
    /// actuated joints (the solve is square), [`EstimatorError::UnknownJoint`] for a name of `passive` the
    /// model lacks.
    pub(crate) fn new(model: &Model, soles: [FrameId; 2], passive: &[String]) -> Result<Self> {
        let mut skip = Vec::with_capacity(passive.len());
        for name in passive {
            skip.push(
                model
                    .joint_index(name)
                    .ok_or_else(|| EstimatorError::UnknownJoint {
                        key: "passive_joints",
                        name: name.clone(),
                    })?,
            );
        }
        let mut chains = [[0; 6]; 2];
        for (chain, sole) in chains.iter_mut().zip(soles) {
            let mut joints = Vec::new();
            let mut body = Some(model.frames()[sole.index()].link);
            while let Some(b) = body {
                let node = &model.bodies()[b];
                if let Some(j) = node.joint.filter(|j| !skip.contains(j)) {
                    joints.push(j);
                }
                body = node.parent;
            }
            if joints.len() != 6 {
                return Err(EstimatorError::InvalidParameter {
                    name: "stance_leg_accelerations",
                    value: joints.len() as f64,
                    reason:
                        "needs six actuated joints between the base and each sole (the value is \
                             the count found)",
                });
            }
            chain.copy_from_slice(&joints);
        }
        Ok(Self {
            chains,
            jacobian: DMatrix::zeros(6, model.nv()),
        })
    }

    /// Writes into `nu_dot` (its base rows set, its joint rows of foot `foot`'s chain overwritten) the
    /// chain's joint accelerations that keep sole `sole` still, with `kd` at the robot's state (mixed
    /// velocity). A singular chain (a stretched knee) leaves the rows as they are.
    pub(crate) fn hold_sole(
        &mut self,
        kd: &KinDyn,
        foot: usize,
        sole: FrameId,
        nu_dot: &mut DVector<f64>,
    ) -> Result<()> {
        let chain = &self.chains[foot];
        for &j in chain {
            nu_dot[6 + j] = 0.0;
        }
        kd.frame_jacobian(sole, &mut self.jacobian)?;
        let mut drift = kd.frame_bias_acceleration(sole);
        for c in 0..self.jacobian.ncols() {
            let a = nu_dot[c];
            if a != 0.0 {
                drift += self.jacobian.fixed_view::<6, 1>(0, c) * a;
            }
        }
        let j_q = Matrix6::from_fn(|r, c| self.jacobian[(r, 6 + chain[c])]);
        if let Some(qdd) = j_q.lu().solve(&(-drift)) {
            let qdd: Vector6<f64> = qdd;
            for (c, &j) in chain.iter().enumerate() {
                nu_dot[6 + j] = qdd[c];
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use nalgebra::{DMatrix, DVector, Vector3};
    use stride_model::{KinDyn, Model, RobotState, VelocityRepresentation};

    use super::StanceLegs;

    const FLEX: [&str; 4] = [
        "l_hip_flex_pitch",
        "l_hip_flex_roll",
        "r_hip_flex_pitch",
        "r_hip_flex_roll",
    ];

    fn model() -> Arc<Model> {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../models/stride_humanoid_flex.urdf"
        );
        Arc::new(Model::from_urdf_file(path).expect("bundled flexible humanoid"))
    }

    /// With bent knees, moving joints and a base accelerating over the left sole, the left leg's solved
    /// accelerations leave that sole's acceleration `J ν̇ + J̇ ν` at zero; the passive joints keep zero.
    #[test]
    fn the_solved_leg_accelerations_hold_the_sole_still() {
        let model = model();
        let mut kd = KinDyn::new(Arc::clone(&model));
        kd.set_representation(VelocityRepresentation::Mixed);
        let mut state = RobotState::zero(&model);
        for (name, q) in [
            ("l_hip_pitch", 0.3),
            ("l_knee", 0.6),
            ("l_ankle_pitch", 0.3),
            ("r_hip_pitch", 0.35),
            ("r_knee", 0.7),
            ("r_ankle_pitch", 0.35),
            ("l_hip_flex_pitch", 0.02),
            ("l_hip_flex_roll", -0.03),
        ] {
            state.joint_positions[model.joint_index(name).expect(name)] = q;
        }
        for (i, v) in state.joint_velocities.iter_mut().enumerate() {
            *v = 0.1 * ((i as f64) * 0.7).sin();
        }
        state.base_velocity = nalgebra::Vector6::new(0.3, -0.05, 0.02, 0.1, -0.2, 0.05);
        kd.set_state(&state).expect("state");
        let soles = ["l_sole", "r_sole"].map(|s| model.frame_id(s).expect(s));
        let passive: Vec<String> = FLEX.iter().map(|s| (*s).to_owned()).collect();
        let mut legs =
            StanceLegs::new(&model, soles, &passive).expect("six actuated joints per leg");
        let mut nu_dot = DVector::zeros(model.nv());
        nu_dot
            .fixed_rows_mut::<3>(0)
            .copy_from(&Vector3::new(0.9, -0.4, 0.2));
        legs.hold_sole(&kd, 0, soles[0], &mut nu_dot)
            .expect("solve");
        let mut j = DMatrix::zeros(6, model.nv());
        kd.frame_jacobian(soles[0], &mut j).expect("jacobian");
        let sole_acc = &j * &nu_dot + kd.frame_bias_acceleration(soles[0]);
        assert!(sole_acc.norm() < 1e-9, "sole acceleration {sole_acc}");
        for name in FLEX {
            assert_eq!(nu_dot[6 + model.joint_index(name).expect(name)], 0.0);
        }
        let knee = nu_dot[6 + model.joint_index("l_knee").expect("l_knee")];
        assert!(
            knee.abs() > 0.1,
            "the base's acceleration bends the knee: {knee}"
        );
        // The right leg, not solved, keeps zero.
        assert_eq!(
            nu_dot[6 + model.joint_index("r_knee").expect("r_knee")],
            0.0
        );
    }

    /// Without the passive joints named, a leg has eight joints between the base and its sole: refused.
    #[test]
    fn a_chain_of_other_than_six_actuated_joints_is_refused() {
        let model = model();
        let soles = ["l_sole", "r_sole"].map(|s| model.frame_id(s).expect(s));
        let err = StanceLegs::new(&model, soles, &[]).expect_err("eight joints per leg");
        assert!(
            err.to_string().contains("stance_leg_accelerations"),
            "{err}"
        );
    }
}
