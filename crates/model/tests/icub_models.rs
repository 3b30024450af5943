//! Every official URDF of the `icub-models` package loads (including those with `<texture/>` elements that
//! urdf-rs rejects as they stand) and gives a consistent model. The URDFs are not committed: set
//! `STRIDE_ICUB_MODELS_DIR` to the package's `share/iCub/robots` directory. The rule of
//! [`stride_testkit::icub_models_dir`] applies: without the variable the test is skipped with a printed
//! reason (an error under CI, `CI` set); with it, a folder without the models is an error.

mod common;

use std::sync::Arc;

use nalgebra::{DMatrix, DVector};
use stride_model::{KinDyn, Model};

/// Total masses (kg) of icub-models 3.2.0: the sum of each URDF's `<inertial><mass>` values, computed
/// independently of this crate.
const EXPECTED_MASS: &[(&str, f64)] = &[
    ("iCubGazeboV2_7", 33.062),
    ("iCubGazeboV2_5", 33.062),
    ("iCubGenova02", 33.058),
    ("iCubGenova03", 27.647),
    ("iCubLisboa01", 25.945),
    ("iCubNancy01", 28.465),
    ("left_hand_mk3", 0.259),
    ("left_wrist_mk2", 1.144),
];

#[test]
fn every_icub_model_loads() {
    let Some(dir) = stride_testkit::icub_models_dir("every_icub_model_loads") else {
        return;
    };
    let mut entries: Vec<_> = std::fs::read_dir(&dir)
        .expect("STRIDE_ICUB_MODELS_DIR is readable")
        .map(|e| e.unwrap().path())
        .filter(|p| p.join("model.urdf").is_file())
        .collect();
    entries.sort();
    assert!(
        entries.len() >= 10,
        "expected the icub-models robots in {dir:?}, found {}",
        entries.len()
    );
    for path in entries {
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let model = Model::from_urdf_file(path.join("model.urdf"))
            .unwrap_or_else(|e| panic!("{name} does not load: {e}"));
        let model = Arc::new(model);
        assert!(model.total_mass() > 0.0, "{name}");
        if let Some((_, m)) = EXPECTED_MASS.iter().find(|(n, _)| *n == name) {
            assert!(
                (model.total_mass() - m).abs() < 1.5e-3,
                "{name}: mass {} vs {m}",
                model.total_mass()
            );
        }
        if name.starts_with("iCub") {
            assert_eq!(model.dof(), 32, "{name}: 32 revolute joints");
            assert!(
                ["root_link", "base_link"].contains(&model.root_link()),
                "{name}: root {}",
                model.root_link()
            );
            for frame in ["l_sole", "r_sole"] {
                assert!(model.frame_id(frame).is_some(), "{name}: frame {frame}");
            }
            assert!(
                model.ft_sensors().len() >= 4,
                "{name}: FT sensors {:?}",
                model.ft_sensors()
            );
            for joint in model.joints() {
                assert!(
                    joint.lower < joint.upper,
                    "{name}: limits of {}",
                    joint.name
                );
            }
        }
        // Dynamics are well defined at a random state.
        let nv = model.nv();
        let state = common::random_state(&model, 1);
        let mut kd = KinDyn::new(Arc::clone(&model));
        kd.set_state(&state).unwrap();
        let mut mm = DMatrix::zeros(nv, nv);
        kd.mass_matrix(&mut mm).unwrap();
        assert!(
            mm.clone().symmetric_eigenvalues().min() > 0.0,
            "{name}: M positive definite"
        );
        let tau = common::random_vector(model.dof(), 2, 1.0);
        let mut acc = DVector::zeros(nv);
        kd.forward_dynamics(&tau, &[], &mut acc).unwrap();
        let mut h = DVector::zeros(nv);
        kd.bias_forces(&mut h).unwrap();
        let residual = &mm * &acc + &h;
        assert!(
            residual.rows(0, 6).amax() < 1e-8 * (1.0 + h.amax()),
            "{name}: free-floating base"
        );
        assert!(
            (residual.rows(6, nv - 6) - &tau).amax() < 1e-8 * (1.0 + h.amax()),
            "{name}: joint torques"
        );
        println!(
            "{name}: {} DoF, {:.4} kg, {} frames, {} FT sensors, {} warnings",
            model.dof(),
            model.total_mass(),
            model.frames().len(),
            model.ft_sensors().len(),
            model.warnings().len()
        );
    }
}
