//! Example 1: the dynamics model alone (stride-model).
//!
//! Loads the bundled humanoid, stands it on the ground, and evaluates the CoM, a frame pose, the mass
//! matrix (CRBA) and the inverse dynamics (RNEA). Each figure is checked against another path: the
//! gravity torques of the RNEA at rest must equal `−J_comᵀ m g` built from the CoM Jacobian.
//!
//! Run: `cargo run --release --bin model` (in the `examples` folder).

use std::process::ExitCode;
use std::sync::Arc;

use stride_model::prelude::*;
// nalgebra comes with stride (the prelude re-exports it): no version to keep in step.
use stride_model::prelude::nalgebra::{DMatrix, DVector, Vector3};

fn main() -> ExitCode {
    stride_examples::run(|checks| {
        // The bundled URDF is compiled into the library: no file to find at run time.
        let model = Arc::new(bundled::model()?);
        println!(
            "bundled humanoid: {} joints, {:.2} kg",
            model.dof(),
            model.total_mass()
        );

        // Standing: the bundled posture, the soles flat on the ground plane z = 0.
        // (`bundled::standing_state(&model)` does the same in one call.)
        let [left, right] = bundled::soles(&model)?;
        let q = bundled::posture(&model)?;
        let state = RobotState::standing(&model, &q, left, right)?;

        // One kinematics/dynamics workspace per thread; it allocates here and never again.
        let mut kd = KinDyn::new(Arc::clone(&model));
        kd.set_state(&state)?;

        // Frame pose and CoM.
        let sole = kd.frame_pose(left);
        checks.at_most(
            "left sole on the ground",
            sole.translation.z.abs(),
            1e-12,
            "m",
        );
        let com = kd.com_position();
        println!("CoM at [{:.4}, {:.4}, {:.4}] m", com.x, com.y, com.z);
        checks.at_most(
            "CoM height is the bundled COM_HEIGHT",
            (com.z - bundled::COM_HEIGHT).abs(),
            1e-3,
            "m",
        );

        // Mass matrix (nv × nv, mixed representation): symmetric, its linear block is m·I.
        let nv = model.nv();
        let mut mass = DMatrix::zeros(nv, nv);
        kd.mass_matrix(&mut mass)?;
        let asymmetry = (&mass - mass.transpose()).amax();
        checks.at_most("mass matrix symmetric", asymmetry, 1e-12, "kg m²");
        let linear = mass.view((0, 0), (3, 3)).into_owned();
        let m = model.total_mass();
        checks.at_most(
            "mass matrix linear block = m I",
            (linear - DMatrix::identity(3, 3) * m).amax(),
            1e-12,
            "kg",
        );

        // RNEA at rest (ν = 0, ν̇ = 0, no contact wrench): the generalized gravity forces.
        let mut rnea = DVector::zeros(nv);
        kd.inverse_dynamics(&DVector::zeros(nv), &[], &mut rnea)?;
        // The same from the CoM Jacobian: gravity acts at the CoM, so G = −J_comᵀ (m g).
        let mut j_com = DMatrix::zeros(3, nv);
        kd.com_jacobian(&mut j_com)?;
        let weight: Vector3<f64> = model.gravity() * m;
        let from_com = -(j_com.transpose() * weight);
        checks.at_most(
            "RNEA at rest = −J_comᵀ m g",
            (&rnea - &from_com).amax(),
            1e-9,
            "N, N m",
        );
        // The base force carries the weight: [0, 0, m g].
        checks.at_most(
            "base force of the RNEA = weight",
            (rnea.fixed_rows::<3>(0) + weight).amax(),
            1e-9,
            "N",
        );
        println!(
            "gravity torque at the left knee: {:.3} N m",
            rnea[6 + model.joint_index("l_knee").ok_or("l_knee")?]
        );
        Ok(())
    })
}
