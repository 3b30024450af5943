//! The base rows of the FT submodel above the feet sensors ([`KinDyn::ft_submodel_base_regressor`]) against
//! inverse dynamics (RNEA) and the FT sensor model with wrenches on the soles, at random states: the
//! Newton–Euler equations of the body above the feet, measured by the feet sensors [Traversaro 2017,
//! eqs. 7.1–7.4, Theorem 7.1].

mod common;

use std::sync::Arc;

use nalgebra::{DMatrix, DVector, Matrix6, Vector6};
use stride_model::{ExternalWrench, KinDyn, Model, ModelError, VelocityRepresentation};

/// The sensors just above the soles (`l_sole`, `r_sole`).
fn feet_sensors(model: &Model) -> Vec<usize> {
    ["l_sole", "r_sole"]
        .iter()
        .map(|sole| {
            let frame = model.frame_id(sole).expect("sole frame");
            model
                .innermost_ft_sensor_holding(frame)
                .expect("a sensor above the sole")
        })
        .collect()
}

fn sole_wrenches(model: &Model, seed: u64) -> Vec<ExternalWrench> {
    let w = common::random_vector(12, seed, 1.0);
    ["l_sole", "r_sole"]
        .iter()
        .enumerate()
        .map(|(i, sole)| ExternalWrench {
            frame: model.frame_id(sole).unwrap(),
            wrench: Vector6::from_fn(|a, _| w[6 * i + a] * if a < 3 { 100.0 } else { 10.0 })
                + Vector6::new(0.0, 0.0, 150.0, 0.0, 0.0, 0.0),
        })
        .collect()
}

/// `Y ψ − Σ_k A_k y_k` for the `cut` sensors, with the readings `y` of the sensor model under `wrenches`.
fn submodel_residual(
    kd: &mut KinDyn,
    split: &DVector<f64>,
    nu_dot: &DVector<f64>,
    cut: &[usize],
    wrenches: &[ExternalWrench],
) -> Vector6<f64> {
    let model = Arc::clone(kd.model());
    let ns = model.ft_sensors().len();
    let mut y = DMatrix::zeros(6, 10 * (model.body_count() + ns));
    kd.ft_submodel_base_regressor(nu_dot, cut, &mut y).unwrap();
    let mut readings = vec![Vector6::zeros(); ns];
    kd.ft_sensor_wrenches(nu_dot, wrenches, &mut readings)
        .unwrap();
    let mut out: Vector6<f64> = (&y * split).fixed_rows::<6>(0).into_owned();
    let mut a = Matrix6::zeros();
    for &k in cut {
        kd.ft_sensor_parent_side_map(k, &mut a).unwrap();
        out -= a * readings[k];
    }
    out
}

/// The base wrench of inverse dynamics about the base origin with world axes (A'): the base rows in the
/// mixed representation, the body rows turned by the base orientation in the body representation.
fn base_wrench_in_world_axes(
    kd: &mut KinDyn,
    nu_dot: &DVector<f64>,
    wrenches: &[ExternalWrench],
    rotation: &nalgebra::Matrix3<f64>,
) -> Vector6<f64> {
    let mut tau = DVector::zeros(kd.model().nv());
    kd.inverse_dynamics(nu_dot, wrenches, &mut tau).unwrap();
    match kd.representation() {
        VelocityRepresentation::Body => {
            let f = rotation * tau.fixed_rows::<3>(0);
            let t = rotation * tau.fixed_rows::<3>(3);
            Vector6::new(f.x, f.y, f.z, t.x, t.y, t.z)
        }
        _ => tau.fixed_rows::<6>(0).into_owned(),
    }
}

/// With wrenches on both soles, `Y ψ − Σ A_k y_k` equals the base rows of inverse dynamics under those
/// wrenches (zero for a motion they produce) to 1e-10, in the mixed and body representations; with a wrench
/// on the chest as well, it does not (the chest is above the cut); with no sensor cut, `Y ψ` is the whole
/// robot's base rows without wrenches. Returns the worst relative error.
fn check_submodel_rows(model: &Arc<Model>, seeds: std::ops::Range<u64>) -> f64 {
    let cut = feet_sensors(model);
    let split = model.ft_split_inertial_parameters().unwrap();
    let mut kd = KinDyn::new(Arc::clone(model));
    let chest = ExternalWrench {
        frame: model.frame_id("chest").unwrap(),
        wrench: Vector6::new(20.0, -10.0, 5.0, 1.0, 2.0, -1.0),
    };
    let mut worst: f64 = 0.0;
    for representation in [VelocityRepresentation::Mixed, VelocityRepresentation::Body] {
        kd.set_representation(representation);
        for seed in seeds.clone() {
            let state = common::random_state(model, seed);
            let rotation = *state.base_pose.rotation.to_rotation_matrix().matrix();
            kd.set_state(&state).unwrap();
            let nu_dot = common::random_vector(model.nv(), seed + 9000, 4.0);
            let soles = sole_wrenches(model, seed + 500);
            let expected = base_wrench_in_world_axes(&mut kd, &nu_dot, &soles, &rotation);
            let got = submodel_residual(&mut kd, &split, &nu_dot, &cut, &soles);
            let err = (got - expected).amax() / expected.amax().max(1.0);
            assert!(err <= 1e-10, "{representation:?} seed {seed}: {err:.2e}");
            worst = worst.max(err);

            let mut pushed = soles.clone();
            pushed.push(chest);
            let expected = base_wrench_in_world_axes(&mut kd, &nu_dot, &pushed, &rotation);
            let got = submodel_residual(&mut kd, &split, &nu_dot, &cut, &pushed);
            assert!(
                (got - expected).amax() > 1.0,
                "a chest wrench is not on the feet's child sides"
            );

            let whole = base_wrench_in_world_axes(&mut kd, &nu_dot, &[], &rotation);
            let got = submodel_residual(&mut kd, &split, &nu_dot, &[], &[]);
            let err = (got - whole).amax() / whole.amax().max(1.0);
            assert!(err <= 1e-10, "no cut, seed {seed}: {err:.2e}");
            worst = worst.max(err);
        }
    }
    worst
}

#[test]
fn feet_submodel_base_rows_are_rnea_on_the_bundled_humanoid() {
    let model = common::humanoid_model().expect("bundled humanoid");
    let cut = feet_sensors(&model);
    let names: Vec<&str> = cut
        .iter()
        .map(|&k| model.ft_sensors()[k].name.as_str())
        .collect();
    assert_eq!(names, ["l_foot_ft_sensor", "r_foot_ft_sensor"]);
    let worst = check_submodel_rows(&model, 0..20);
    println!("bundled humanoid: feet submodel base rows vs RNEA, worst {worst:.2e}");
}

#[test]
fn feet_submodel_base_rows_are_rnea_on_icub() {
    let test = "feet_submodel_base_rows_are_rnea_on_icub";
    let Some(path) = stride_testkit::icub_model_urdf(test, "iCubGazeboV2_7") else {
        return;
    };
    let model = Arc::new(Model::from_urdf_file(path).unwrap());
    let worst = check_submodel_rows(&model, 0..10);
    println!("iCubGazeboV2_7: feet submodel base rows vs RNEA, worst {worst:.2e}");
}

#[test]
fn submodel_rows_refuse_an_unknown_sensor_and_a_wrong_shape() {
    let model = common::humanoid_model().expect("bundled humanoid");
    let ns = model.ft_sensors().len();
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_state(&common::random_state(&model, 1)).unwrap();
    let nu_dot = DVector::zeros(model.nv());
    let mut y = DMatrix::zeros(6, 10 * (model.body_count() + ns));
    assert!(matches!(
        kd.ft_submodel_base_regressor(&nu_dot, &[ns], &mut y),
        Err(ModelError::FtSensorOutOfRange { .. })
    ));
    let mut a = Matrix6::zeros();
    assert!(matches!(
        kd.ft_sensor_parent_side_map(ns, &mut a),
        Err(ModelError::FtSensorOutOfRange { .. })
    ));
    let mut wrong = DMatrix::zeros(6, 10);
    assert!(matches!(
        kd.ft_submodel_base_regressor(&nu_dot, &[], &mut wrong),
        Err(ModelError::DimensionMismatch { .. })
    ));
}
