//! Reduced models (locked joints): the reduced model's mass matrix, inverse dynamics, CoM and frame poses
//! equal the full model's evaluated with the locked joints held still at their positions, on random
//! states; lock lists that cannot be applied are errors naming the entry.

mod common;

use std::sync::Arc;

use common::{humanoid_path, random_state, random_vector, TEST_URDF};
use nalgebra::{DMatrix, DVector};
use stride_model::{InertiaEdits, JointLock, KinDyn, Model, ModelError, RobotState};

/// Relative agreement: `|a − b| ≤ 1e-12 (1 + |b|)`.
fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * (1.0 + b.abs())
}

/// The full model's state with the reduced state's base and free joints, the locked joints at their
/// positions and still; also the indices (in ν of the full model) of the reduced model's ν.
fn full_state(
    full: &Model,
    reduced: &Model,
    locks: &[(String, f64)],
    s: &RobotState,
) -> (RobotState, Vec<usize>) {
    let mut state = RobotState::zero(full);
    state.base_pose = s.base_pose;
    state.base_velocity = s.base_velocity;
    let mut rows: Vec<usize> = (0..6).collect();
    for (i, j) in full.joints().iter().enumerate() {
        match reduced.joint_index(&j.name) {
            Some(r) => {
                state.joint_positions[i] = s.joint_positions[r];
                state.joint_velocities[i] = s.joint_velocities[r];
                rows.push(6 + i);
            }
            None => {
                let q = locks.iter().find(|(n, _)| *n == j.name).map(|l| l.1);
                state.joint_positions[i] =
                    q.expect("every joint missing from the reduced model is locked");
            }
        }
    }
    (state, rows)
}

fn check_reduction(
    urdf: &str,
    locks: &[JointLock],
    locked: &[(String, f64)],
    seeds: std::ops::Range<u64>,
) {
    let full = Arc::new(Model::from_urdf_str(urdf).expect("full model"));
    let reduced = Arc::new(
        Model::from_urdf_str_reduced(urdf, &InertiaEdits::default(), locks).expect("reduced model"),
    );
    assert_eq!(reduced.dof() + locked.len(), full.dof());
    assert!(close(reduced.total_mass(), full.total_mass()));
    let (nf, nr) = (full.nv(), reduced.nv());
    for seed in seeds {
        let s = random_state(&reduced, seed);
        let (fs, rows) = full_state(&full, &reduced, locked, &s);
        let mut kr = KinDyn::new(Arc::clone(&reduced));
        let mut kf = KinDyn::new(Arc::clone(&full));
        kr.set_state(&s).unwrap();
        kf.set_state(&fs).unwrap();

        let (mut mr, mut mf) = (DMatrix::zeros(nr, nr), DMatrix::zeros(nf, nf));
        kr.mass_matrix(&mut mr).unwrap();
        kf.mass_matrix(&mut mf).unwrap();
        for (a, &fa) in rows.iter().enumerate() {
            for (b, &fb) in rows.iter().enumerate() {
                assert!(
                    close(mr[(a, b)], mf[(fa, fb)]),
                    "M[{a},{b}] seed {seed}: {} vs {}",
                    mr[(a, b)],
                    mf[(fa, fb)]
                );
            }
        }

        let acc = random_vector(nr, seed + 1000, 3.0);
        let mut acc_full = DVector::zeros(nf);
        for (a, &fa) in rows.iter().enumerate() {
            acc_full[fa] = acc[a];
        }
        let (mut tr, mut tf) = (DVector::zeros(nr), DVector::zeros(nf));
        kr.inverse_dynamics(&acc, &[], &mut tr).unwrap();
        kf.inverse_dynamics(&acc_full, &[], &mut tf).unwrap();
        for (a, &fa) in rows.iter().enumerate() {
            assert!(
                close(tr[a], tf[fa]),
                "RNEA row {a} seed {seed}: {} vs {}",
                tr[a],
                tf[fa]
            );
        }

        let (cr, cf) = (kr.com_position(), kf.com_position());
        assert!(
            (0..3).all(|k| close(cr[k], cf[k])),
            "CoM seed {seed}: {cr} vs {cf}"
        );
        for frame in reduced.frames() {
            let fid = full
                .frame_id(&frame.name)
                .expect("every frame of the reduced model is in the full one");
            let rid = reduced.frame_id(&frame.name).unwrap();
            let (pr, pf) = (
                kr.frame_pose(rid).to_homogeneous(),
                kf.frame_pose(fid).to_homogeneous(),
            );
            assert!(
                pr.iter().zip(pf.iter()).all(|(a, b)| close(*a, *b)),
                "frame {} seed {seed}",
                frame.name
            );
        }
    }
}

/// The test tree: a locked knee (a body with a movable child and a force/torque sensor below it), a locked
/// prismatic arm and a mimic pair locked together by a glob.
#[test]
fn the_reduced_test_tree_is_the_full_one_with_locked_joints_held_still() {
    let locks = [
        JointLock::new("l_knee", 0.4),
        JointLock::new("arm_slide", 0.05),
        JointLock::new("finger_?_joint", 0.01),
    ];
    let locked = [
        ("l_knee".to_string(), 0.4),
        ("arm_slide".to_string(), 0.05),
        ("finger_a_joint".to_string(), 0.01),
        ("finger_b_joint".to_string(), 0.01),
    ];
    check_reduction(TEST_URDF, &locks, &locked, 0..20);
}

/// The bundled humanoid with its wrists (a glob over six joints) and one elbow locked.
#[test]
fn the_reduced_humanoid_is_the_full_one_with_locked_joints_held_still() {
    let urdf = std::fs::read_to_string(humanoid_path()).unwrap();
    let locks = [
        JointLock::new("*_wrist_*", 0.3),
        JointLock::new("l_elbow", 0.5),
    ];
    let full = Model::from_urdf_str(&urdf).unwrap();
    let mut locked: Vec<(String, f64)> = full
        .joints()
        .iter()
        .filter(|j| j.name.contains("_wrist_"))
        .map(|j| (j.name.clone(), 0.3))
        .collect();
    assert_eq!(locked.len(), 6);
    locked.push(("l_elbow".into(), 0.5));
    check_reduction(&urdf, &locks, &locked, 0..20);
}

#[test]
fn lock_lists_that_cannot_be_applied_are_errors_naming_the_entry() {
    let reduce = |locks: &[JointLock]| {
        Model::from_urdf_str_reduced(TEST_URDF, &InertiaEdits::default(), locks)
    };
    let cases = [
        (
            vec![JointLock::new("thumb*", 0.0)],
            "thumb*",
            "matches no movable joint",
        ),
        (
            vec![JointLock::new("neck_fixed", 0.0)],
            "neck_fixed",
            "matches no movable joint",
        ),
        (
            vec![JointLock::new("l_hip", f64::NAN)],
            "l_hip",
            "not finite",
        ),
        (
            vec![JointLock::new("l_*", 0.1), JointLock::new("l_knee", 0.2)],
            "l_knee",
            "also locked by `l_*`",
        ),
    ];
    for (locks, pattern, reason) in cases {
        match reduce(&locks) {
            Err(e @ ModelError::InvalidLock { .. }) => {
                let text = e.to_string();
                assert!(text.contains(pattern) && text.contains(reason), "{text}");
            }
            other => panic!("{locks:?}: expected InvalidLock, got {other:?}"),
        }
    }
    // A mimic joint whose target is locked names a joint the reduced model lacks.
    assert!(matches!(
        reduce(&[JointLock::new("finger_a_joint", 0.0)]),
        Err(ModelError::MimicTarget { .. })
    ));
    // The same position twice is one lock, not a conflict; an empty list is the full model.
    let twice = reduce(&[JointLock::new("l_*", 0.1), JointLock::new("l_knee", 0.1)]).unwrap();
    assert!(twice.joint_index("l_knee").is_none() && twice.joint_index("l_hip").is_none());
    assert_eq!(
        reduce(&[]).unwrap().dof(),
        Model::from_urdf_str(TEST_URDF).unwrap().dof()
    );
}
