//! `KinDyn::inverse_dynamics_regressor` against iDynTree 15.1's `inverseDynamicsInertialParametersRegressor`.
//!
//! The fixtures `tests/fixtures/regressor_*.json` are written by
//! `tools/reference/generate_regressor_fixtures.py`: iDynTree's regressor (mixed representation) at random
//! states and accelerations, and iDynTree's parameter vector, in iDynTree's layout: 10 parameters per
//! iDynTree link (`link_names`; iDynTree keeps links joined by fixed joints apart when they have mass),
//! `[m, m c, I_xx, I_xy, I_xz, I_yy, I_yz, I_zz]` in the link frame with `I` about the link origin — the
//! per-body order of stride-model ([`stride_model::inertial`]).
//!
//! The map: stride-model lumps each link into the body it is rigidly attached to, so
//! `ψ_stride = P ψ_iDynTree` with block `(body(l), l)` of `P` the change of frame of link `l`'s parameters into
//! its body's frame ([`transform_parameters`] with the link frame's placement). Hence the test checks
//! `P ψ_iDynTree = ψ_stride` (the parameter order and the lumping) and `Y_stride P = Y_iDynTree` (rows matched
//! by joint name), entry by entry, to `1e-9 · max(1, ‖Y_iDynTree‖∞)`.

use std::path::PathBuf;
use std::sync::Arc;

use nalgebra::{DMatrix, DVector, Isometry3, Quaternion, Translation3, UnitQuaternion, Vector6};
use serde_json::Value;
use stride_model::inertial::{transform_parameters, InertialParameters};
use stride_model::{KinDyn, Model, RobotState};

const TOL: f64 = 1e-9;

fn load_fixture(name: &str) -> Value {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name);
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

fn names_of(v: &Value) -> Vec<String> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap().to_string())
        .collect()
}

/// `P` (10·N × 10·L): iDynTree link blocks moved into their stride body's frame.
fn lumping_map(model: &Model, links: &[String]) -> DMatrix<f64> {
    let mut p = DMatrix::zeros(10 * model.body_count(), 10 * links.len());
    for (l, name) in links.iter().enumerate() {
        let frame = model
            .frame_id(name)
            .unwrap_or_else(|| panic!("stride model has no frame `{name}`"));
        let f = &model.frames()[frame.index()];
        let r = f.placement.rotation.to_rotation_matrix().into_inner();
        let t = f.placement.translation.vector;
        for k in 0..10 {
            let mut e = InertialParameters::zeros();
            e[k] = 1.0;
            let col = transform_parameters(&e, &r, &t);
            p.view_mut((10 * f.link, 10 * l + k), (10, 1))
                .copy_from(&col);
        }
    }
    p
}

fn state_of(model: &Model, dof: &[usize], st: &Value) -> (RobotState, DVector<f64>) {
    let p = vec_of(&st["base_position"]);
    let q = vec_of(&st["base_orientation_xyzw"]);
    let (s, sd, nd) = (
        vec_of(&st["joint_positions"]),
        vec_of(&st["joint_velocities"]),
        vec_of(&st["nu_dot_mixed"]),
    );
    let mut state = RobotState::zero(model);
    state.base_pose = Isometry3::from_parts(
        Translation3::new(p[0], p[1], p[2]),
        UnitQuaternion::from_quaternion(Quaternion::new(q[3], q[0], q[1], q[2])),
    );
    state.base_velocity = Vector6::from_column_slice(&vec_of(&st["base_velocity_mixed"]));
    let mut nu_dot = DVector::zeros(model.nv());
    nu_dot.rows_mut(0, 6).copy_from_slice(&nd[..6]);
    for (i, &j) in dof.iter().enumerate() {
        state.joint_positions[j] = s[i];
        state.joint_velocities[j] = sd[i];
        nu_dot[6 + j] = nd[6 + i];
    }
    (state, nu_dot)
}

/// Checks the parameter map and every state; returns the worst relative error of the regressor.
fn check_fixture(model: &Arc<Model>, fx: &Value) -> f64 {
    assert_eq!(fx["base_link"].as_str(), Some(model.root_link()));
    let links = names_of(&fx["link_names"]);
    let p = lumping_map(model, &links);
    let psi_idt = DVector::from_vec(vec_of(&fx["parameters"]));
    let psi = model.inertial_parameters();
    let err = (&p * &psi_idt - &psi).amax() / psi.amax();
    assert!(err <= TOL, "P ψ_iDynTree vs ψ_stride: {err:.3e}");
    let dof: Vec<usize> = names_of(&fx["joint_names"])
        .iter()
        .map(|n| {
            model
                .joint_index(n)
                .unwrap_or_else(|| panic!("no joint `{n}`"))
        })
        .collect();
    assert_eq!(dof.len(), model.dof());
    // Row r of iDynTree's regressor is row `row[r]` of stride's.
    let row: Vec<usize> = (0..6).chain(dof.iter().map(|j| 6 + j)).collect();
    let mut kd = KinDyn::new(Arc::clone(model));
    let mut y = DMatrix::zeros(model.nv(), 10 * model.body_count());
    let mut worst: f64 = 0.0;
    for (k, st) in fx["states"].as_array().unwrap().iter().enumerate() {
        let (state, nu_dot) = state_of(model, &dof, st);
        kd.set_state(&state).unwrap();
        kd.inverse_dynamics_regressor(&nu_dot, &mut y).unwrap();
        let mapped = &y * &p;
        let reference: Vec<Vec<f64>> = st["regressor"]
            .as_array()
            .unwrap()
            .iter()
            .map(vec_of)
            .collect();
        let scale = reference
            .iter()
            .flatten()
            .fold(1.0_f64, |a, v| a.max(v.abs()));
        for (r, ref_row) in reference.iter().enumerate() {
            for (c, v) in ref_row.iter().enumerate() {
                let err = (mapped[(row[r], c)] - v).abs() / scale;
                assert!(
                    err <= TOL,
                    "state {k}, row {r}, column {c} (link {}, parameter {}): stride {} vs iDynTree {v} ({err:.3e})",
                    links[c / 10],
                    c % 10,
                    mapped[(row[r], c)]
                );
                worst = worst.max(err);
            }
        }
    }
    worst
}

#[test]
fn regressor_matches_idyntree_on_the_bundled_humanoid() {
    let fx = load_fixture("regressor_stride_humanoid.json");
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(fx["urdf"].as_str().unwrap());
    let model = Arc::new(Model::from_urdf_file(path).unwrap());
    let worst = check_fixture(&model, &fx);
    assert!(worst <= TOL);
    println!("stride_humanoid regressor vs iDynTree: worst relative error {worst:.2e}");
}

#[test]
fn regressor_matches_idyntree_on_icub_gazebo_v2_7() {
    let fx = load_fixture("regressor_iCubGazeboV2_7.json");
    let Some(path) = stride_testkit::icub_model_urdf(
        "regressor_matches_idyntree_on_icub_gazebo_v2_7",
        fx["icub_model"].as_str().unwrap(),
    ) else {
        return;
    };
    let model = Arc::new(Model::from_urdf_file(path).unwrap());
    let worst = check_fixture(&model, &fx);
    assert!(worst <= TOL);
    println!("iCubGazeboV2_7 regressor vs iDynTree: worst relative error {worst:.2e}");
}
