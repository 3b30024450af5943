//! stride-model's (edited) inertias written over the compiled MuJoCo model: unedited they reproduce
//! MuJoCo's own compilation of the URDF; edited (mass scale, a link's CoM offset) MuJoCo's total mass,
//! centre of mass and ground force are the edited model's.
#![cfg(feature = "mujoco")]

mod common;

use std::sync::Arc;
use std::time::Duration;

use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use stride_model::{InertiaEdits, KinDyn, LinkInertiaEdit, Model};
use stride_mujoco::{principal_inertia, MujocoConfig, MujocoRobot, PlantSetup};

use common::{crouch, humanoid_urdf, ideal_sim, standing, stands_with_its_weight};

fn plant_with_model_inertias(model: &Arc<Model>) -> MujocoRobot {
    MujocoRobot::new(
        Arc::clone(model),
        &PlantSetup {
            urdf: &humanoid_urdf(),
            sim: &ideal_sim(10000.0, 200.0),
            mujoco: &MujocoConfig::default(),
            soles: ["l_sole", "r_sole"],
            period: Duration::from_micros(500),
            inertias_from_model: true,
        },
    )
    .expect("MuJoCo plant")
}

/// Rotational inertia about the CoM in the body frame from MuJoCo's `body_inertia` / `body_iquat`.
fn full_inertia(moments: [f64; 3], quat: [f64; 4]) -> Matrix3<f64> {
    let r = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
        quat[0], quat[1], quat[2], quat[3],
    ))
    .to_rotation_matrix();
    r.matrix() * Matrix3::from_diagonal(&Vector3::from(moments)) * r.matrix().transpose()
}

#[test]
fn principal_axes_reconstruct_the_inertia_with_a_proper_rotation() {
    let a = Matrix3::new(0.3, 0.02, -0.01, 0.02, 0.2, 0.03, -0.01, 0.03, 0.1);
    let (d, q) = principal_inertia(&a);
    let back = full_inertia(d, [q.w, q.i, q.j, q.k]);
    assert!((back - a).norm() < 1e-14, "{back} vs {a}");
    assert!((q.to_rotation_matrix().matrix().determinant() - 1.0).abs() < 1e-12);
}

/// Unedited, writing stride's inertias reproduces MuJoCo's own compilation (mass, CoM, inertia tensor of
/// every body within 1e-12), which checks that body frames and lumping agree.
#[test]
fn the_unedited_model_inertias_are_mujocos_own() {
    let urdf = humanoid_urdf();
    let model = Arc::new(Model::from_urdf_file(&urdf).expect("humanoid"));
    let own = common::plant(
        &model,
        &urdf,
        &ideal_sim(1000.0, 60.0),
        ["l_sole", "r_sole"],
    );
    let written = plant_with_model_inertias(&model);
    let (a, b) = (own.mj_model(), written.mj_model());
    for (body, &id) in model.bodies().iter().zip(own.body_ids()) {
        assert!(
            (a.body_mass()[id] - b.body_mass()[id]).abs() < 1e-12,
            "{}",
            body.name
        );
        let ipos = Vector3::from(a.body_ipos()[id]) - Vector3::from(b.body_ipos()[id]);
        assert!(ipos.norm() < 1e-12, "{}: CoM {ipos}", body.name);
        let ia = full_inertia(a.body_inertia()[id], a.body_iquat()[id]);
        let ib = full_inertia(b.body_inertia()[id], b.body_iquat()[id]);
        assert!((ia - ib).norm() < 1e-12, "{}: {ia} vs {ib}", body.name);
    }
}

/// Edited (every mass × 1.2, the chest's CoM 3 cm forward): MuJoCo's total mass = the edited model's
/// (1e-12), its centre of mass = stride-model's at the same state (1e-12 m), and standing 2 s the soles
/// carry the edited weight (0.1 %).
#[test]
fn edited_inertias_give_mujoco_the_edited_mass_and_centre_of_mass() {
    let urdf = humanoid_urdf();
    let edits = InertiaEdits {
        mass_scale: 1.2,
        links: vec![LinkInertiaEdit {
            link: "chest".into(),
            mass_scale: 1.0,
            com_offset: Vector3::new(0.03, 0.0, 0.0),
        }],
    };
    let model = Arc::new(Model::from_urdf_file_edited(&urdf, &edits).expect("edited"));
    let unedited = Model::from_urdf_file(&urdf).expect("humanoid");
    assert!((model.total_mass() - 1.2 * unedited.total_mass()).abs() < 1e-9);
    let mut plant = plant_with_model_inertias(&model);
    let mass: f64 = plant.mj_model().body_mass().iter().sum();
    assert!(
        (mass - model.total_mass()).abs() < 1e-12 * mass,
        "{mass} vs {}",
        model.total_mass()
    );
    let q = crouch(&model);
    let state = standing(&model, &q);
    plant.set_initial_state(&state).expect("state");
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_state(&state).expect("state");
    let com = Vector3::from(plant.mj_data().subtree_com()[0]);
    assert!(
        (com - kd.com_position()).norm() < 1e-12,
        "MuJoCo {com} vs stride {}",
        kd.com_position()
    );
    stands_with_its_weight(&mut plant, &model, &q);
}
