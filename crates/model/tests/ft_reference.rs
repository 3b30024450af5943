//! `KinDyn::ft_sensor_wrenches` against iDynTree 15.1.
//!
//! The fixtures `tests/fixtures/ft_*.json` are written by `tools/reference/generate_ft_fixtures.py`: the wrench
//! transmitted through each FT sensor's fixed joint from iDynTree's
//! `KinDynComputations::inverseDynamicsWithInternalJointForceTorques` on the un-lumped model, signed and
//! expressed as iDynTree's `SixAxisForceTorqueSensor` defines the measurement (the wrench applied on the
//! parent link by the child link for `child_to_parent`, in the sensor frame), at random states,
//! accelerations and known wrenches on both soles. Every reading must match with
//! `max |stride − reference| ≤ 1e-9 · max(1, ‖reference‖∞)`.
//!
//! The iCub case runs only with `STRIDE_ICUB_MODELS_DIR` set ([`stride_testkit::icub_model_urdf`]).

use std::path::PathBuf;
use std::sync::Arc;

use nalgebra::{DVector, Isometry3, Quaternion, Translation3, UnitQuaternion, Vector6};
use serde_json::Value;
use stride_model::{ExternalWrench, KinDyn, Model, RobotState};

const TOL: f64 = 1e-9;

fn manifest_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn load_fixture(name: &str) -> Value {
    let path = manifest_dir().join("tests/fixtures").join(name);
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("cannot parse {}: {e}", path.display()))
}

fn vec_of(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap_or_else(|| panic!("expected an array, got {v}"))
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

fn v6(v: &[f64]) -> Vector6<f64> {
    Vector6::from_column_slice(v)
}

/// Checks every state of the fixture; returns the worst relative error.
fn check_fixture(model: &Arc<Model>, fx: &Value) -> f64 {
    let names: Vec<&str> = fx["joint_names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(names.len(), model.dof(), "joint count");
    let dof: Vec<usize> = names
        .iter()
        .map(|n| {
            model
                .joint_index(n)
                .unwrap_or_else(|| panic!("no joint `{n}`"))
        })
        .collect();
    let sensors: Vec<usize> = fx["ft_sensors"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| {
            let name = v.as_str().unwrap();
            model
                .ft_sensor_index(name)
                .unwrap_or_else(|| panic!("stride model has no FT sensor `{name}`"))
        })
        .collect();
    assert_eq!(sensors.len(), model.ft_sensors().len(), "FT sensor count");
    let mut kd = KinDyn::new(Arc::clone(model));
    let mut out = vec![Vector6::zeros(); model.ft_sensors().len()];
    let mut worst: f64 = 0.0;
    for (k, st) in fx["states"].as_array().unwrap().iter().enumerate() {
        let p = vec_of(&st["base_position"]);
        let q = vec_of(&st["base_orientation_xyzw"]);
        let base_pose = Isometry3::from_parts(
            Translation3::new(p[0], p[1], p[2]),
            UnitQuaternion::from_quaternion(Quaternion::new(q[3], q[0], q[1], q[2])),
        );
        let mut joint_positions = DVector::zeros(model.dof());
        let mut joint_velocities = DVector::zeros(model.dof());
        let mut nu_dot = DVector::zeros(model.nv());
        let (s, sd, nd) = (
            vec_of(&st["joint_positions"]),
            vec_of(&st["joint_velocities"]),
            vec_of(&st["nu_dot_mixed"]),
        );
        for (i, &j) in dof.iter().enumerate() {
            joint_positions[j] = s[i];
            joint_velocities[j] = sd[i];
            nu_dot[6 + j] = nd[6 + i];
        }
        for r in 0..6 {
            nu_dot[r] = nd[r];
        }
        let state = RobotState {
            base_pose,
            joint_positions,
            base_velocity: v6(&vec_of(&st["base_velocity_mixed"])),
            joint_velocities,
        };
        kd.set_state(&state).unwrap();
        let wrenches: Vec<ExternalWrench> = st["external_wrenches"]
            .as_array()
            .unwrap()
            .iter()
            .map(|w| ExternalWrench {
                frame: model.frame_id(w["frame"].as_str().unwrap()).unwrap(),
                wrench: v6(&vec_of(&w["wrench"])),
            })
            .collect();
        kd.ft_sensor_wrenches(&nu_dot, &wrenches, &mut out).unwrap();
        for (i, r) in st["ft_readings"].as_array().unwrap().iter().enumerate() {
            let reference = v6(&vec_of(r));
            let got = out[sensors[i]];
            let scale = reference.amax().max(1.0);
            let err = (got - reference).amax() / scale;
            assert!(
                err <= TOL,
                "state {k}, sensor {}: stride {got:?} vs iDynTree {reference:?} (relative error {err:.3e})",
                model.ft_sensors()[sensors[i]].name
            );
            worst = worst.max(err);
        }
    }
    worst
}

#[test]
fn ft_readings_match_idyntree_on_the_bundled_humanoid() {
    let fx = load_fixture("ft_stride_humanoid.json");
    let path = manifest_dir()
        .join("../..")
        .join(fx["urdf"].as_str().unwrap());
    let model = Arc::new(Model::from_urdf_file(path).unwrap());
    let worst = check_fixture(&model, &fx);
    println!("stride_humanoid FT readings: worst relative error {worst:.2e}");
}

#[test]
fn ft_readings_match_idyntree_on_icub_gazebo_v2_7() {
    let fx = load_fixture("ft_iCubGazeboV2_7.json");
    let Some(path) = stride_testkit::icub_model_urdf(
        "ft_readings_match_idyntree_on_icub_gazebo_v2_7",
        fx["icub_model"].as_str().unwrap(),
    ) else {
        return;
    };
    let model = Arc::new(Model::from_urdf_file(path).unwrap());
    let worst = check_fixture(&model, &fx);
    println!("iCubGazeboV2_7 FT readings: worst relative error {worst:.2e}");
}
