//! Independent checks of the FT sensor readings, their wrench map and the edited-inertia loader on the bundled
//! humanoid (numbers of the URDF written out by hand).

mod common;

use std::sync::Arc;

use nalgebra::{DVector, Isometry3, Matrix6, Vector3, Vector6};
use stride_model::{
    ExternalWrench, InertiaEdits, KinDyn, LinkInertiaEdit, Model, ModelError, RobotState,
};

fn humanoid() -> Arc<Model> {
    Arc::new(Model::from_urdf_file(common::humanoid_path()).unwrap())
}

fn assert_close(a: &Vector6<f64>, b: &Vector6<f64>, tol: f64, what: &str) {
    let err = (a - b).amax() / b.amax().max(1.0);
    assert!(err <= tol, "{what}: {a:?} vs {b:?} (relative {err:.2e})");
}

/// Standing still in the zero configuration (every frame aligned with the world): the foot sensor (between
/// ankle and foot, `child_to_parent`, frame = l_foot) reads the ground wrench on the sole plus the weight of
/// the foot link (0.7 kg at (0.03, 0, −0.03) in l_foot; l_sole at (0.03, 0, −0.045)), both moved to the
/// sensor origin; the other foot's sensor reads only its foot's weight.
#[test]
fn standing_foot_sensors_read_the_ground_wrench_plus_the_foot_weight() {
    let model = humanoid();
    let mut kd = KinDyn::new(Arc::clone(&model));
    let mut state = RobotState::zero(&model);
    state.base_pose = Isometry3::translation(0.0, 0.0, 0.6);
    kd.set_state(&state).unwrap();
    let ground = Vector6::new(3.0, -2.0, 180.0, 0.4, -1.5, 0.2);
    let wrenches = [ExternalWrench {
        frame: model.frame_id("l_sole").unwrap(),
        wrench: ground,
    }];
    let mut out = vec![Vector6::zeros(); model.ft_sensors().len()];
    kd.ft_sensor_wrenches(&DVector::zeros(model.nv()), &wrenches, &mut out)
        .unwrap();
    let weight = Vector3::new(0.0, 0.0, -9.81 * 0.7);
    let com = Vector3::new(0.03, 0.0, -0.03);
    let sole = Vector3::new(0.03, 0.0, -0.045);
    let f = ground.fixed_rows::<3>(0).into_owned();
    let tau = ground.fixed_rows::<3>(3).into_owned();
    let expected_l = Vector6::from_iterator(
        (f + weight)
            .iter()
            .chain((tau + sole.cross(&f) + com.cross(&weight)).iter())
            .copied(),
    );
    let expected_r =
        Vector6::from_iterator(weight.iter().chain(com.cross(&weight).iter()).copied());
    let l = model.ft_sensor_index("l_foot_ft_sensor").unwrap();
    let r = model.ft_sensor_index("r_foot_ft_sensor").unwrap();
    assert_close(&out[l], &expected_l, 1e-12, "l_foot_ft_sensor");
    assert_close(&out[r], &expected_r, 1e-12, "r_foot_ft_sensor");
}

/// [Traversaro 2017, Theorem 4.1] split at a sensor: the net wrench of the whole robot minus the external
/// wrenches (the base wrench of inverse dynamics, mixed representation, about the base origin) is the sum of
/// the child side's and the parent side's. The parent side's is computed by inverse dynamics of the same
/// robot with the child-side links made (almost) massless and the child-side wrench removed, so
/// `reading (child_to_parent) = − child side = parent side − whole`, moved to the sensor frame.
#[test]
fn a_sensor_splits_the_inverse_dynamics_base_wrench() {
    let model = humanoid();
    let child_side = ["l_thigh", "l_lower_leg", "l_ankle_1", "l_ankle_2", "l_foot"];
    let edits = InertiaEdits {
        mass_scale: 1.0,
        links: child_side
            .iter()
            .map(|l| LinkInertiaEdit {
                link: l.to_string(),
                mass_scale: 1e-13,
                com_offset: Vector3::zeros(),
            })
            .collect(),
    };
    let parent_only =
        Arc::new(Model::from_urdf_file_edited(common::humanoid_path(), &edits).unwrap());
    let state = common::random_state(&model, 11);
    let nu_dot = common::random_vector(model.nv(), 12, 2.0);
    let w = |name: &str, k: f64| ExternalWrench {
        frame: model.frame_id(name).unwrap(),
        wrench: Vector6::new(10.0 * k, -20.0, 150.0 + k, 1.0, -2.0 * k, 0.5),
    };
    let all = [w("l_sole", 1.0), w("r_sole", -1.5), w("l_hand", 0.3)];
    let parent_side = [w("r_sole", -1.5), w("l_hand", 0.3)];
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_state(&state).unwrap();
    let mut whole = DVector::zeros(model.nv());
    kd.inverse_dynamics(&nu_dot, &all, &mut whole).unwrap();
    let mut kd_p = KinDyn::new(Arc::clone(&parent_only));
    kd_p.set_state(&state).unwrap();
    let mut part = DVector::zeros(model.nv());
    kd_p.inverse_dynamics(&nu_dot, &parent_side, &mut part)
        .unwrap();
    let diff = Vector6::from_iterator((0..6).map(|r| part[r] - whole[r]));
    // about the base origin, world orientation → sensor frame
    let s = model.ft_sensor_index("l_leg_ft_sensor").unwrap();
    let frame = model.ft_sensors()[s].frame;
    let x_s = kd.frame_pose(frame);
    let r = x_s.rotation.to_rotation_matrix();
    let d = x_s.translation.vector - state.base_pose.translation.vector;
    let f = diff.fixed_rows::<3>(0).into_owned();
    let tau = diff.fixed_rows::<3>(3).into_owned() - d.cross(&f);
    let expected = Vector6::from_iterator(
        (r.inverse() * f)
            .iter()
            .chain((r.inverse() * tau).iter())
            .copied(),
    );
    let mut out = vec![Vector6::zeros(); model.ft_sensors().len()];
    kd.ft_sensor_wrenches(&nu_dot, &all, &mut out).unwrap();
    // the 1e-13 residual masses leave ~1e-13 of the child-side wrench in `part`
    assert_close(
        &out[s],
        &expected,
        1e-9,
        "l_leg_ft_sensor vs inverse dynamics",
    );
    assert!(out[s].amax() > 10.0, "a non-trivial reading");
}

/// The wrench map reproduces the change of every reading when a wrench is added on a frame (exact: the
/// readings are affine in the external wrenches), and is zero for frames on the parent side.
#[test]
fn wrench_map_reproduces_finite_changes() {
    let model = humanoid();
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_state(&common::random_state(&model, 3)).unwrap();
    let nu_dot = common::random_vector(model.nv(), 4, 2.0);
    let base = [ExternalWrench {
        frame: model.frame_id("r_sole").unwrap(),
        wrench: Vector6::new(1.0, 2.0, 100.0, 0.1, -0.2, 0.3),
    }];
    let n = model.ft_sensors().len();
    let mut y0 = vec![Vector6::zeros(); n];
    let mut y1 = vec![Vector6::zeros(); n];
    kd.ft_sensor_wrenches(&nu_dot, &base, &mut y0).unwrap();
    let mut nonzero = 0;
    for name in [
        "l_sole",
        "r_sole",
        "l_foot",
        "l_ankle_2",
        "l_thigh",
        "l_upper_thigh",
        "l_hand",
    ] {
        let frame = model.frame_id(name).unwrap();
        let dw = Vector6::new(-7.0, 5.0, 40.0, 2.0, 1.0, -3.0);
        let with = [base[0], ExternalWrench { frame, wrench: dw }];
        kd.ft_sensor_wrenches(&nu_dot, &with, &mut y1).unwrap();
        for s in 0..n {
            let mut a = Matrix6::zeros();
            kd.ft_sensor_wrench_map(s, frame, &mut a).unwrap();
            let predicted = a * dw;
            let actual = y1[s] - y0[s];
            let err = (predicted - actual).amax();
            assert!(
                err <= 1e-9 * actual.amax().max(1.0),
                "{name} on {}: {predicted:?} vs {actual:?}",
                model.ft_sensors()[s].name
            );
            if a.amax() > 0.0 {
                nonzero += 1;
            }
        }
    }
    // l_sole, l_foot: both left sensors; l_ankle_2, l_thigh: the leg sensor only; r_sole: r_foot, r_leg
    assert_eq!(nonzero, 2 + 2 + 1 + 1 + 2);
    let mut a = Matrix6::zeros();
    assert!(matches!(
        kd.ft_sensor_wrench_map(n, model.frame_id("l_sole").unwrap(), &mut a),
        Err(ModelError::FtSensorOutOfRange { .. })
    ));
}

#[test]
fn ft_sensor_wrenches_checks_its_arguments() {
    let model = humanoid();
    let mut kd = KinDyn::new(Arc::clone(&model));
    let mut out = vec![Vector6::zeros(); model.ft_sensors().len()];
    let bad = DVector::zeros(model.nv() - 1);
    assert!(matches!(
        kd.ft_sensor_wrenches(&bad, &[], &mut out),
        Err(ModelError::DimensionMismatch { .. })
    ));
    let mut nan = DVector::zeros(model.nv());
    nan[3] = f64::NAN;
    assert!(matches!(
        kd.ft_sensor_wrenches(&nan, &[], &mut out),
        Err(ModelError::NonFiniteInput { .. })
    ));
    let mut short = vec![Vector6::zeros(); 1];
    assert!(matches!(
        kd.ft_sensor_wrenches(&DVector::zeros(model.nv()), &[], &mut short),
        Err(ModelError::DimensionMismatch { .. })
    ));
    assert_eq!(model.ft_sensor_index("r_leg_ft_sensor"), Some(1));
    assert_eq!(model.ft_sensor_index("nope"), None);
}

#[test]
fn edited_loader_scales_masses_and_moves_the_com() {
    let path = common::humanoid_path();
    let model = Model::from_urdf_file(&path).unwrap();
    let scaled = Model::from_urdf_file_edited(
        &path,
        &InertiaEdits {
            mass_scale: 1.1,
            links: vec![],
        },
    )
    .unwrap();
    let m = model.total_mass();
    assert!((scaled.total_mass() - 1.1 * m).abs() <= 1e-12 * m);
    // l_foot (0.7 kg) CoM moved by d: the robot's CoM moves by 0.7 d / M (zero configuration: the link
    // frame has the world orientation).
    let d = Vector3::new(0.05, -0.02, 0.01);
    let moved = Model::from_urdf_file_edited(
        &path,
        &InertiaEdits {
            mass_scale: 1.0,
            links: vec![LinkInertiaEdit {
                link: "l_foot".into(),
                mass_scale: 1.0,
                com_offset: d,
            }],
        },
    )
    .unwrap();
    let com = |model: Model| {
        let model = Arc::new(model);
        let mut kd = KinDyn::new(Arc::clone(&model));
        kd.set_state(&RobotState::zero(&model)).unwrap();
        kd.com_position()
    };
    let shift = com(moved) - com(model);
    assert!((shift - d * (0.7 / m)).amax() <= 1e-12, "{shift:?}");
}

#[test]
fn edited_loader_rejects_bad_edits() {
    let path = common::humanoid_path();
    let edit = |link: &str, scale: f64, off: f64| InertiaEdits {
        mass_scale: 1.0,
        links: vec![LinkInertiaEdit {
            link: link.into(),
            mass_scale: scale,
            com_offset: Vector3::new(off, 0.0, 0.0),
        }],
    };
    for (edits, field) in [
        (edit("no_such_link", 1.0, 0.0), "link"),
        (edit("l_foot", 0.0, 0.0), "mass_scale"),
        (edit("l_foot", f64::NAN, 0.0), "mass_scale"),
        (edit("l_foot", 1.0, f64::INFINITY), "com_offset"),
        (
            InertiaEdits {
                mass_scale: -1.0,
                links: vec![],
            },
            "mass_scale",
        ),
    ] {
        match Model::from_urdf_file_edited(&path, &edits) {
            Err(e @ ModelError::InvalidInertiaEdit { field: f, .. }) => {
                assert_eq!(f, field, "{e}");
                if field != "mass_scale" || edits.mass_scale == 1.0 {
                    assert!(e.to_string().contains(&edits.links[0].link), "{e}");
                }
            }
            other => panic!("{edits:?}: expected InvalidInertiaEdit, got {other:?}"),
        }
    }
}
