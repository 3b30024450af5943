//! `KinDyn::set_state` reuses a joint's rotation when the joint has not moved since the previous state
//! (bit for bit the same position): everything computed after a sequence of states is bit for bit what a
//! fresh workspace computes from the last state alone.

mod common;

use std::sync::Arc;

use nalgebra::DMatrix;
use stride_model::{KinDyn, Model, RobotState};

fn models() -> Vec<Arc<Model>> {
    vec![
        common::test_model(),
        common::humanoid_model().expect("models/stride_humanoid.urdf must exist"),
    ]
}

/// The frame poses, the mass matrix and the CoM velocity of `kd`, as bits.
fn fingerprint(kd: &mut KinDyn, model: &Model) -> Vec<u64> {
    let mut bits = Vec::new();
    for f in 0..model.frames().len() {
        let id = model
            .frame_id(&model.frames()[f].name)
            .expect("a frame's own name");
        let pose = kd.frame_pose(id);
        bits.extend(pose.translation.vector.iter().map(|v| v.to_bits()));
        bits.extend(pose.rotation.coords.iter().map(|v| v.to_bits()));
    }
    let nv = model.nv();
    let mut m = DMatrix::zeros(nv, nv);
    kd.mass_matrix(&mut m).unwrap();
    bits.extend(m.iter().map(|v| v.to_bits()));
    bits.extend(kd.com_velocity().iter().map(|v| v.to_bits()));
    bits
}

/// `next` with every other joint (and, for `held_all`, every joint) at `previous`'s position.
fn partly_held(previous: &RobotState, next: &RobotState, held_all: bool) -> RobotState {
    let mut s = next.clone();
    for j in 0..s.joint_positions.len() {
        if held_all || j % 2 == 0 {
            s.joint_positions[j] = previous.joint_positions[j];
        }
    }
    s
}

#[test]
fn a_sequence_of_states_ends_where_a_fresh_workspace_starts() {
    for model in models() {
        let mut kd = KinDyn::new(Arc::clone(&model));
        let mut previous = common::random_state(&model, 0);
        kd.set_state(&previous).unwrap();
        for seed in 1..6 {
            let next = common::random_state(&model, seed);
            for held_all in [false, true] {
                let state = partly_held(&previous, &next, held_all);
                kd.set_state(&state).unwrap();
                let mut fresh = KinDyn::new(Arc::clone(&model));
                fresh.set_state(&state).unwrap();
                assert_eq!(
                    fingerprint(&mut kd, &model),
                    fingerprint(&mut fresh, &model),
                    "seed {seed}, all joints held: {held_all}"
                );
                previous = state;
            }
        }
        // back to a state whose joints were all seen before, but not in the last state
        let first = common::random_state(&model, 0);
        kd.set_state(&first).unwrap();
        let mut fresh = KinDyn::new(Arc::clone(&model));
        fresh.set_state(&first).unwrap();
        assert_eq!(
            fingerprint(&mut kd, &model),
            fingerprint(&mut fresh, &model)
        );
    }
}

/// `com_velocity` forms each body's linear momentum without its world inertia: bit for bit the linear
/// part of the centroidal momentum (the sum of the bodies' full `I v`) over the mass, before and after the
/// inertias are prepared.
#[test]
fn com_velocity_is_the_linear_momentum_over_the_mass() {
    for model in models() {
        let nv = model.nv();
        let mut m = DMatrix::zeros(nv, nv);
        let mut kd = KinDyn::new(Arc::clone(&model));
        for seed in 0..4 {
            kd.set_state(&common::random_state(&model, seed)).unwrap();
            for prepared in [false, true] {
                if prepared {
                    kd.mass_matrix(&mut m).unwrap();
                }
                let h = kd.centroidal_momentum();
                let expected = h.fixed_rows::<3>(0) / model.total_mass();
                let got = kd.com_velocity();
                for r in 0..3 {
                    assert_eq!(
                        got[r].to_bits(),
                        expected[r].to_bits(),
                        "seed {seed}, prepared {prepared}, row {r}: {} vs {}",
                        got[r],
                        expected[r]
                    );
                }
            }
        }
    }
}

/// `fingerprint` with every frame's velocity and bias acceleration and the bias forces (the velocity
/// products of the forward pass).
fn full_fingerprint(kd: &mut KinDyn, model: &Model) -> Vec<u64> {
    let mut bits = fingerprint(kd, model);
    for f in 0..model.frames().len() {
        let id = model
            .frame_id(&model.frames()[f].name)
            .expect("a frame's own name");
        bits.extend(kd.frame_velocity(id).iter().map(|v| v.to_bits()));
        bits.extend(kd.frame_bias_acceleration(id).iter().map(|v| v.to_bits()));
    }
    let mut h = nalgebra::DVector::zeros(model.nv());
    kd.bias_forces(&mut h).unwrap();
    bits.extend(h.iter().map(|v| v.to_bits()));
    bits
}

/// `KinDyn::set_state_from` copies the source's kinematics only when the source is at the same state of the
/// same model in the same representation; in every case the workspace then computes bit for bit what
/// `set_state` gives, and an invalid state is the same error.
#[test]
fn set_state_from_gives_what_set_state_gives() {
    use stride_model::VelocityRepresentation as Repr;
    for model in models() {
        let copy_of_model = Arc::new((*model).clone());
        for seed in 0..4 {
            let state = common::random_state(&model, seed);
            let other = common::random_state(&model, seed + 10);
            let mut zero_signs = state.clone();
            for v in zero_signs.joint_velocities.iter_mut().step_by(2) {
                *v = 0.0;
            }
            let mut negative_zeros = zero_signs.clone();
            for v in negative_zeros.joint_velocities.iter_mut().step_by(2) {
                *v = -0.0;
            }
            let cases = [
                (Arc::clone(&model), Repr::Mixed, &state, "the same state"),
                (Arc::clone(&model), Repr::Mixed, &other, "another state"),
                (
                    Arc::clone(&model),
                    Repr::Body,
                    &state,
                    "another representation",
                ),
                (
                    Arc::clone(&copy_of_model),
                    Repr::Mixed,
                    &state,
                    "an equal model",
                ),
                (
                    Arc::clone(&model),
                    Repr::Mixed,
                    &negative_zeros,
                    "zeros of the other sign",
                ),
            ];
            for (source_model, repr, source_state, case) in cases {
                let target_state = if case == "zeros of the other sign" {
                    &zero_signs
                } else {
                    &state
                };
                let mut source = KinDyn::new(source_model);
                source.set_representation(repr);
                source.set_state(source_state).unwrap();
                let mut kd = KinDyn::new(Arc::clone(&model));
                kd.set_state(&other).unwrap();
                kd.set_state_from(target_state, &source).unwrap();
                let mut fresh = KinDyn::new(Arc::clone(&model));
                fresh.set_state(target_state).unwrap();
                assert_eq!(
                    full_fingerprint(&mut kd, &model),
                    full_fingerprint(&mut fresh, &model),
                    "seed {seed}: {case}"
                );
            }
            let mut source = KinDyn::new(Arc::clone(&model));
            source.set_state(&state).unwrap();
            let mut bad = state.clone();
            bad.joint_positions[0] = f64::NAN;
            let mut kd = KinDyn::new(Arc::clone(&model));
            assert_eq!(
                kd.set_state_from(&bad, &source).unwrap_err().to_string(),
                kd.set_state(&bad).unwrap_err().to_string()
            );
        }
    }
}
