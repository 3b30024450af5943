//! `KinDyn::joint_jacobians` (all joint columns in one pass) against the per-frame Jacobians and velocities.

mod common;

use nalgebra::{DMatrix, DVector, Vector6};
use stride_model::{convert_velocity, KinDyn, VelocityRepresentation};

/// In the inertial representation, every body's frame Jacobian is the one-pass matrix restricted to the
/// body's ancestors (the other columns exactly zero); in every representation, the one-pass matrix applied
/// to ν restricted to the ancestors gives the body's inertial twist.
#[test]
fn joint_jacobians_agree_with_frame_jacobians_and_velocities() {
    let model =
        common::humanoid_model().expect("models/stride_humanoid.urdf is part of the repository");
    let nv = model.nv();
    let bodies: Vec<String> = model.bodies().iter().map(|b| b.name.clone()).collect();
    let mut all = DMatrix::zeros(6, nv);
    let mut frame_j = DMatrix::zeros(6, nv);
    for seed in 0..8u64 {
        let state = common::random_state(&model, seed);
        // Ancestor columns of each body, and its inertial twist, from the inertial representation.
        let mut kd = KinDyn::new(model.clone());
        kd.set_representation(VelocityRepresentation::Inertial);
        kd.set_state(&state).expect("state");
        kd.joint_jacobians(&mut all).expect("shape");
        let mut ancestors = Vec::new();
        let mut twists = Vec::new();
        for name in &bodies {
            let id = model.frame_id(name).expect("every body is a frame");
            kd.frame_jacobian(id, &mut frame_j).expect("shape");
            let mut mask = vec![false; nv];
            for (c, is_ancestor) in mask.iter_mut().enumerate() {
                let col = frame_j.column(c);
                if col.iter().all(|v| *v == 0.0) {
                    continue;
                }
                *is_ancestor = true;
                let diff = (col - all.column(c)).amax();
                assert!(
                    diff <= 1e-12 * (1.0 + col.amax()),
                    "{name}, column {c}: {diff:e}"
                );
            }
            assert!(
                mask[..6].iter().all(|m| *m),
                "{name}: base columns are always ancestors"
            );
            ancestors.push(mask);
            twists.push(kd.frame_velocity(id));
        }
        // Every degree of freedom moves some body.
        for c in 0..nv {
            assert!(
                ancestors.iter().any(|m| m[c]),
                "column {c} belongs to no body"
            );
        }
        // Mixed and body: same twists from the base velocity expressed in that representation.
        for repr in [VelocityRepresentation::Mixed, VelocityRepresentation::Body] {
            let mut state_r = state.clone();
            state_r.base_velocity = convert_velocity(
                &state.base_pose,
                &state.base_velocity,
                VelocityRepresentation::Inertial,
                repr,
            );
            let mut kd_r = KinDyn::new(model.clone());
            kd_r.set_representation(repr);
            kd_r.set_state(&state_r).expect("state");
            kd_r.joint_jacobians(&mut all).expect("shape");
            let nu = DVector::from_iterator(
                nv,
                state_r
                    .base_velocity
                    .iter()
                    .copied()
                    .chain(state_r.joint_velocities.iter().copied()),
            );
            for (b, mask) in ancestors.iter().enumerate() {
                let masked = DVector::from_fn(nv, |k, _| if mask[k] { nu[k] } else { 0.0 });
                let twist: Vector6<f64> = Vector6::from_iterator((&all * masked).iter().copied());
                let diff = (twist - twists[b]).amax();
                assert!(
                    diff <= 1e-10 * (1.0 + twists[b].amax()),
                    "{repr:?}, {}: {diff:e}",
                    bodies[b]
                );
            }
        }
    }
}
