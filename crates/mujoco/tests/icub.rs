//! The official iCub (iCubGazeboV2_7 of icub-models, `STRIDE_ICUB_MODELS_DIR`) on MuJoCo: its URDF as
//! MuJoCo is given it (sole boxes kept, everything else that would load a `package://` mesh removed), the
//! compiled model, and standing on its own sole boxes. Skipped loudly without the models
//! (`stride_testkit::icub_model_urdf`).
#![cfg(feature = "mujoco")]

mod common;

use std::sync::Arc;

use mujoco_rs::prelude::*;
use stride_model::{KinDyn, Model};
use stride_mujoco::{prepare_urdf, resolve_package, UrdfEdit};

use common::{icub_crouch, ideal_sim, plant, standing, stands_with_its_weight};

/// The URDF edit keeps exactly the two sole boxes (0.16 × 0.072 × 0.001 m on `l_foot` / `r_foot`), removes
/// every visual and every other collision, and resolves the URDF's `package://iCub/...` mesh paths to the
/// files of the installed package (the ancestor `share/` folder holds `iCub/meshes`).
#[test]
fn the_icub_urdf_keeps_only_its_sole_boxes_and_its_mesh_paths_resolve() {
    let test = "the_icub_urdf_keeps_only_its_sole_boxes_and_its_mesh_paths_resolve";
    let Some(urdf) = stride_testkit::icub_model_urdf(test, "iCubGazeboV2_7") else {
        return;
    };
    let text = std::fs::read_to_string(&urdf).expect("URDF");
    let (prepared, stats) = prepare_urdf(
        &text,
        &UrdfEdit {
            path: &urdf,
            contact_links: &["l_sole".into(), "r_sole".into()],
        },
    )
    .expect("prepared");
    assert_eq!(stats.collisions_kept, 2, "{stats:?}");
    assert_eq!(
        stats.visuals_removed,
        text.matches("<visual").count(),
        "{stats:?}"
    );
    assert_eq!(
        stats.collisions_removed + 2,
        text.matches("<collision").count()
    );
    assert_eq!(stats.packages_resolved, 0, "the sole boxes need no mesh");
    assert!(!prepared.contains("package://") && !prepared.contains("<visual"));
    assert_eq!(
        prepared.matches("<box size=\"0.16 0.072 0.001\"/>").count(),
        2
    );
    // Everything else is untouched: as many joints and inertials.
    for tag in ["<joint ", "<inertial>", "<limit "] {
        assert_eq!(
            prepared.matches(tag).count(),
            text.matches(tag).count(),
            "{tag}"
        );
    }
    // The package paths the edit removed resolve to the installed meshes.
    let dir = urdf.parent().expect("folder");
    let uri = text
        .split('"')
        .find(|s| s.starts_with("package://iCub/meshes/"))
        .expect("a package path");
    let file = resolve_package(uri, dir).expect("resolved");
    assert!(file.is_file() && file.ends_with(uri.trim_start_matches("package://")));
    assert_eq!(
        resolve_package("package://iCub/no_such_mesh.stl", dir),
        None
    );
    assert_eq!(resolve_package("package://../iCub/meshes", dir), None);
}

/// iCub compiles on MuJoCo with its own inertias (no `balanceinertia`: MuJoCo's compiler accepts every
/// body, see docs/mujoco.md), every stride body maps to a MuJoCo body of the same mass, only the two sole
/// boxes collide with the floor, and standing 2 s in its crouch the soles carry its weight (Σ f_z = m g
/// within 0.1 %), both in contact, no fall.
#[test]
fn the_official_icub_compiles_and_stands_on_its_sole_boxes() {
    let test = "the_official_icub_compiles_and_stands_on_its_sole_boxes";
    let Some(urdf) = stride_testkit::icub_model_urdf(test, "iCubGazeboV2_7") else {
        return;
    };
    let model = Arc::new(Model::from_urdf_file(&urdf).expect("iCub"));
    let mut robot = plant(
        &model,
        &urdf,
        &ideal_sim(10000.0, 200.0),
        ["l_sole", "r_sole"],
    );
    let mj = robot.mj_model();
    let mass: f64 = mj.body_mass().iter().sum();
    assert!(
        (mass - model.total_mass()).abs() < 1e-9 * model.total_mass(),
        "MuJoCo {mass} kg, stride {} kg",
        model.total_mass()
    );
    for (b, &id) in model.bodies().iter().zip(robot.body_ids()) {
        assert!((mj.body_mass()[id] - b.mass).abs() < 1e-9, "{}", b.name);
    }
    let colliding: Vec<usize> = (0..mj.ngeom() as usize)
        .filter(|&g| mj.geom_contype()[g] != 0 && mj.geom_bodyid()[g] != 0)
        .collect();
    assert_eq!(colliding.len(), 2, "colliding robot geoms {colliding:?}");
    for &g in &colliding {
        assert_eq!(mj.geom_type()[g], MjtGeomBase::mjGEOM_BOX);
        let size = mj.geom_size()[g];
        for (s, half) in size.iter().zip([0.08, 0.036, 0.0005]) {
            assert!((s - half).abs() < 1e-12, "half sizes {size:?}");
        }
    }
    let q = icub_crouch(&model);
    robot
        .set_initial_state(&standing(&model, &q))
        .expect("state");
    // iCub's sole boxes reach 10.5 mm below its sole frames: with the frames on the floor they start in it.
    let depth = robot.ground_penetration();
    assert!((depth - 0.0105).abs() < 1e-4, "penetration {depth} m");
    let out = stands_with_its_weight(&mut robot, &model, &q);
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_state(&out.state).expect("state");
    assert!(kd.com_velocity().norm() < 1e-3, "CoM still moving");
}
