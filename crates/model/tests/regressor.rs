//! The inertial-parameter regressors against independent computations: the rigid-body regressor against the
//! Newton–Euler equations written out with plain matrices, the whole-robot regressor against inverse
//! dynamics (RNEA) and the FT-sensor regressor against the FT sensor model, at random states
//! [Traversaro 2017, eqs. 6.4–6.7, 7.1–7.5].

mod common;

use std::sync::Arc;

use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, Rotation3, Vector3, Vector6};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use stride_model::inertial::{
    inertial_parameters, momentum_regressor, rigid_body_regressor, sensor_regressor,
    spatial_inertia, InertialParameters,
};
use stride_model::spatial::skew;
use stride_model::{InertiaEdits, KinDyn, LinkInertiaEdit, Model, VelocityRepresentation};

fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

fn random_v6(r: &mut ChaCha8Rng, scale: f64) -> Vector6<f64> {
    Vector6::from_fn(|_, _| r.random_range(-scale..scale))
}

/// A random body: mass in [0.1, 5] kg, CoM within 0.3 m, rotational inertia about the CoM `Q diag(J) Qᵀ`.
fn random_body(r: &mut ChaCha8Rng) -> (f64, Vector3<f64>, Matrix3<f64>) {
    let m = r.random_range(0.1..5.0);
    let c = Vector3::from_fn(|_, _| r.random_range(-0.3..0.3));
    let q = Rotation3::from_scaled_axis(Vector3::from_fn(|_, _| r.random_range(-2.0..2.0)));
    let l = Vector3::from_fn(|_, _| r.random_range(0.001..0.1));
    let j = Vector3::new(l.y + l.z, l.x + l.z, l.x + l.y);
    (
        m,
        c,
        q.matrix() * Matrix3::from_diagonal(&j) * q.matrix().transpose(),
    )
}

/// `v ×̄* = [[ω^, 0], [v^, ω^]]` [Traversaro 2017, eq. 2.50], written out.
fn dual_cross(v: &Vector6<f64>) -> Matrix6<f64> {
    let lin = skew(&Vector3::new(v[0], v[1], v[2]));
    let ang = skew(&Vector3::new(v[3], v[4], v[5]));
    let mut out = Matrix6::zeros();
    out.fixed_view_mut::<3, 3>(0, 0).copy_from(&ang);
    out.fixed_view_mut::<3, 3>(3, 0).copy_from(&lin);
    out.fixed_view_mut::<3, 3>(3, 3).copy_from(&ang);
    out
}

/// The 6D inertia about the body origin from mass, CoM and inertia about the CoM (eq. 2.67 with the
/// parallel-axis theorem), written out.
fn inertia_matrix(m: f64, c: &Vector3<f64>, i_c: &Matrix3<f64>) -> Matrix6<f64> {
    let s = skew(c);
    let mut out = Matrix6::zeros();
    out.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(Matrix3::identity() * m));
    out.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-s * m));
    out.fixed_view_mut::<3, 3>(3, 0).copy_from(&(s * m));
    out.fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&(i_c - s * s * m));
    out
}

#[test]
fn rigid_body_regressor_is_the_newton_euler_equation() {
    let mut r = rng(1);
    for _ in 0..200 {
        let (m, c, i_c) = random_body(&mut r);
        let pi = inertial_parameters(m, &c, &i_c);
        let mm = inertia_matrix(m, &c, &i_c);
        assert!((spatial_inertia(&pi) - mm).amax() < 1e-14);
        let a = random_v6(&mut r, 10.0);
        let v = random_v6(&mut r, 3.0);
        // M a + v ×̄* M v (eq. 2.75).
        let phi = mm * a + dual_cross(&v) * mm * v;
        let y = rigid_body_regressor(&a, &v);
        assert!(
            (y * pi - phi).amax() <= 1e-12 * phi.amax().max(1.0),
            "{:?} vs {phi:?}",
            y * pi
        );
        assert!((momentum_regressor(&v) * pi - mm * v).amax() < 1e-12);
    }
}

/// (6.6)–(6.7): the sensor form needs only α^g and ω, and equals the body form with
/// `α^g = a + [ω × v; 0]` (Table 2.2).
#[test]
fn sensor_form_equals_the_body_form() {
    let mut r = rng(2);
    for _ in 0..100 {
        let (m, c, i_c) = random_body(&mut r);
        let pi = inertial_parameters(m, &c, &i_c);
        let a = random_v6(&mut r, 10.0);
        let v = random_v6(&mut r, 3.0);
        let w = Vector3::new(v[3], v[4], v[5]);
        let lin = w.cross(&Vector3::new(v[0], v[1], v[2]));
        let alpha = a + Vector6::new(lin.x, lin.y, lin.z, 0.0, 0.0, 0.0);
        let ys = sensor_regressor(&alpha, &w);
        let yb = rigid_body_regressor(&a, &v);
        assert!((ys * pi - yb * pi).amax() <= 1e-12 * (yb * pi).amax().max(1.0));
    }
}

fn random_nu_dot(nv: usize, seed: u64) -> DVector<f64> {
    common::random_vector(nv, seed, 4.0)
}

fn relative(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).amax() / b.amax().max(1.0)
}

/// `Y ψ` = inverse dynamics (no external wrench) at random states, in every representation.
fn check_regressor_is_rnea(model: &Arc<Model>, seeds: std::ops::Range<u64>) -> f64 {
    let nv = model.nv();
    let psi = model.inertial_parameters();
    let mut kd = KinDyn::new(Arc::clone(model));
    let mut y = DMatrix::zeros(nv, 10 * model.body_count());
    let mut tau = DVector::zeros(nv);
    let mut worst: f64 = 0.0;
    for repr in [
        VelocityRepresentation::Mixed,
        VelocityRepresentation::Body,
        VelocityRepresentation::Inertial,
    ] {
        kd.set_representation(repr);
        for seed in seeds.clone() {
            kd.set_state(&common::random_state(model, seed)).unwrap();
            let nu_dot = random_nu_dot(nv, seed + 1000);
            kd.inverse_dynamics(&nu_dot, &[], &mut tau).unwrap();
            kd.inverse_dynamics_regressor(&nu_dot, &mut y).unwrap();
            let err = relative(&(&y * &psi), &tau);
            assert!(
                err <= 1e-10,
                "{repr:?} seed {seed}: relative error {err:.2e}"
            );
            worst = worst.max(err);
        }
    }
    worst
}

#[test]
fn whole_body_regressor_is_rnea_on_the_test_tree() {
    check_regressor_is_rnea(&common::test_model(), 0..20);
}

#[test]
fn whole_body_regressor_is_rnea_on_the_bundled_humanoid() {
    let model = common::humanoid_model().expect("bundled humanoid");
    let worst = check_regressor_is_rnea(&model, 0..20);
    assert!(worst < 1e-10);
    println!("stride_humanoid: Y ψ vs RNEA, worst relative error {worst:.2e}");
}

#[test]
fn whole_body_regressor_is_rnea_on_icub() {
    let test = "whole_body_regressor_is_rnea_on_icub";
    let Some(path) = stride_testkit::icub_model_urdf(test, "iCubGazeboV2_7") else {
        return;
    };
    let model = Arc::new(Model::from_urdf_file(path).unwrap());
    let worst = check_regressor_is_rnea(&model, 0..10);
    println!("iCubGazeboV2_7: Y ψ vs RNEA, worst relative error {worst:.2e}");
}

/// The regressor does not depend on the parameters: the regressor of the bundled humanoid times the
/// parameters of an edited humanoid (every link's mass scaled, CoMs moved) is the edited robot's inverse
/// dynamics.
#[test]
fn the_regressor_predicts_other_parameters() {
    let path = common::humanoid_path();
    let model = Arc::new(Model::from_urdf_file(&path).unwrap());
    let text = std::fs::read_to_string(&path).unwrap();
    let mut r = rng(3);
    let links: Vec<String> = model.frames().iter().map(|f| f.name.clone()).collect();
    let edits = InertiaEdits {
        mass_scale: 1.1,
        links: links
            .iter()
            .filter(|l| text.contains(&format!("<link name=\"{l}\"")))
            .map(|l| LinkInertiaEdit {
                link: l.clone(),
                mass_scale: r.random_range(0.5..1.5),
                com_offset: Vector3::from_fn(|_, _| r.random_range(-0.05..0.05)),
            })
            .collect(),
    };
    let edited = Arc::new(Model::from_urdf_file_edited(&path, &edits).unwrap());
    let psi = edited.inertial_parameters();
    assert!((&psi - model.inertial_parameters()).amax() > 0.1);
    let nv = model.nv();
    let mut kd = KinDyn::new(Arc::clone(&model));
    let mut kd_edited = KinDyn::new(Arc::clone(&edited));
    let mut y = DMatrix::zeros(nv, 10 * model.body_count());
    let mut tau = DVector::zeros(nv);
    for seed in 0..10 {
        let state = common::random_state(&model, seed);
        let nu_dot = random_nu_dot(nv, seed + 50);
        kd.set_state(&state).unwrap();
        kd_edited.set_state(&state).unwrap();
        kd.inverse_dynamics_regressor(&nu_dot, &mut y).unwrap();
        kd_edited.inverse_dynamics(&nu_dot, &[], &mut tau).unwrap();
        let err = relative(&(&y * &psi), &tau);
        assert!(err <= 1e-10, "seed {seed}: {err:.2e}");
    }
}

/// `Y_ft ψ_split` = the FT sensor model's readings (no external wrench), and the split layout sums back to
/// the body layout.
fn check_ft_regressor(model: &Arc<Model>, seeds: std::ops::Range<u64>) {
    let nv = model.nv();
    let ns = model.ft_sensors().len();
    assert!(ns > 0);
    let split = model.ft_split_inertial_parameters().unwrap();
    let merged = model.merge_ft_split_parameters(&split).unwrap();
    assert!((merged - model.inertial_parameters()).amax() < 1e-12);
    let mut kd = KinDyn::new(Arc::clone(model));
    let mut y = DMatrix::zeros(6 * ns, 10 * (model.body_count() + ns));
    let mut readings = vec![Vector6::zeros(); ns];
    for repr in [VelocityRepresentation::Mixed, VelocityRepresentation::Body] {
        kd.set_representation(repr);
        for seed in seeds.clone() {
            kd.set_state(&common::random_state(model, seed)).unwrap();
            let nu_dot = random_nu_dot(nv, seed + 2000);
            kd.ft_sensor_wrenches(&nu_dot, &[], &mut readings).unwrap();
            kd.ft_sensor_regressor(&nu_dot, &mut y).unwrap();
            let expected =
                DVector::from_iterator(6 * ns, readings.iter().flat_map(|w| w.iter().copied()));
            let err = relative(&(&y * &split), &expected);
            assert!(
                err <= 1e-10,
                "{repr:?} seed {seed}: relative error {err:.2e}"
            );
        }
    }
}

#[test]
fn ft_regressor_is_the_sensor_model_on_the_test_tree() {
    check_ft_regressor(&common::test_model(), 0..20);
}

#[test]
fn ft_regressor_is_the_sensor_model_on_the_bundled_humanoid() {
    check_ft_regressor(&common::humanoid_model().expect("bundled humanoid"), 0..20);
}

#[test]
fn ft_regressor_is_the_sensor_model_on_icub() {
    let test = "ft_regressor_is_the_sensor_model_on_icub";
    let Some(path) = stride_testkit::icub_model_urdf(test, "iCubGazeboV2_7") else {
        return;
    };
    check_ft_regressor(&Arc::new(Model::from_urdf_file(path).unwrap()), 0..10);
}

#[test]
fn regressors_report_wrong_sizes() {
    let model = common::test_model();
    let mut kd = KinDyn::new(Arc::clone(&model));
    let nv = model.nv();
    let mut y = DMatrix::zeros(nv, 10);
    assert!(kd
        .inverse_dynamics_regressor(&DVector::zeros(nv), &mut y)
        .is_err());
    let mut y = DMatrix::zeros(nv, 10 * model.body_count());
    assert!(kd
        .inverse_dynamics_regressor(&DVector::zeros(nv + 1), &mut y)
        .is_err());
    let mut bad = DVector::zeros(nv);
    bad[0] = f64::NAN;
    assert!(kd.inverse_dynamics_regressor(&bad, &mut y).is_err());
    assert!(model.merge_ft_split_parameters(&DVector::zeros(3)).is_err());
}

/// The parameter vector's first block is the root body's: mass, first moment and inertia about its origin.
#[test]
fn body_layout_holds_each_body_in_its_frame() {
    let model = common::test_model();
    let psi = model.inertial_parameters();
    for (b, body) in model.bodies().iter().enumerate() {
        let pi: InertialParameters = psi.fixed_rows::<10>(10 * b).into_owned();
        let expected = inertial_parameters(body.mass, &body.com, &body.inertia_at_com);
        assert!((pi - expected).amax() < 1e-12, "{}", body.name);
    }
}

/// (7.3) holds per sensor whenever its child side carries no external wrench: with a wrench on the right
/// sole, the left sensors still read `Y_ft ψ_split`, the right ones do not.
#[test]
fn ft_regressor_rows_hold_for_contact_free_child_sides() {
    let model = common::humanoid_model().expect("bundled humanoid");
    let nv = model.nv();
    let ns = model.ft_sensors().len();
    let split = model.ft_split_inertial_parameters().unwrap();
    let mut kd = KinDyn::new(Arc::clone(&model));
    let mut y = DMatrix::zeros(6 * ns, 10 * (model.body_count() + ns));
    let mut readings = vec![Vector6::zeros(); ns];
    let wrench = [stride_model::ExternalWrench {
        frame: model.frame_id("r_sole").unwrap(),
        wrench: Vector6::new(5.0, -3.0, 150.0, 1.0, -2.0, 0.5),
    }];
    for seed in 0..5 {
        kd.set_state(&common::random_state(&model, seed)).unwrap();
        let nu_dot = random_nu_dot(nv, seed + 3000);
        kd.ft_sensor_wrenches(&nu_dot, &wrench, &mut readings)
            .unwrap();
        kd.ft_sensor_regressor(&nu_dot, &mut y).unwrap();
        let predicted = &y * &split;
        for (k, sensor) in model.ft_sensors().iter().enumerate() {
            let err = (predicted.fixed_rows::<6>(6 * k) - readings[k]).amax();
            if sensor.name.starts_with("l_") {
                assert!(
                    err <= 1e-10 * readings[k].amax().max(1.0),
                    "{}: {err:.2e}",
                    sensor.name
                );
            } else {
                assert!(err > 1.0, "{} feels the right sole's wrench", sensor.name);
            }
        }
    }
}

/// Random parameters (the humanoid's, perturbed by up to 20 % plus a constant, not physically consistent in
/// general): a model built from them ([`Model::with_ft_split_inertial_parameters`]) holds them, and its inverse
/// dynamics and FT readings are the regressors times them.
#[test]
fn regressors_times_random_parameters_are_the_dynamics_of_the_model_holding_them() {
    let model = common::humanoid_model().expect("bundled humanoid");
    let nv = model.nv();
    let ns = model.ft_sensors().len();
    let mut r = rng(4);
    let mut split = model.ft_split_inertial_parameters().unwrap();
    for (i, v) in split.iter_mut().enumerate() {
        let size = v.abs() + 0.01;
        *v += if i % 10 == 0 {
            r.random_range(0.0..0.2) * size
        } else {
            r.random_range(-0.2..0.2) * size
        };
    }
    let edited = Arc::new(model.with_ft_split_inertial_parameters(&split).unwrap());
    let back = edited.ft_split_inertial_parameters().unwrap();
    assert!(
        (&back - &split).amax() < 1e-12,
        "{:.2e}",
        (&back - &split).amax()
    );
    let psi = edited.inertial_parameters();
    let mut kd = KinDyn::new(Arc::clone(&model));
    let mut kd_edited = KinDyn::new(Arc::clone(&edited));
    let mut y = DMatrix::zeros(nv, 10 * model.body_count());
    let mut y_ft = DMatrix::zeros(6 * ns, 10 * (model.body_count() + ns));
    let mut tau = DVector::zeros(nv);
    let mut readings = vec![Vector6::zeros(); ns];
    for seed in 0..10 {
        let state = common::random_state(&model, seed);
        let nu_dot = random_nu_dot(nv, seed + 4000);
        kd.set_state(&state).unwrap();
        kd_edited.set_state(&state).unwrap();
        kd.inverse_dynamics_regressor(&nu_dot, &mut y).unwrap();
        kd.ft_sensor_regressor(&nu_dot, &mut y_ft).unwrap();
        kd_edited.inverse_dynamics(&nu_dot, &[], &mut tau).unwrap();
        kd_edited
            .ft_sensor_wrenches(&nu_dot, &[], &mut readings)
            .unwrap();
        let expected =
            DVector::from_iterator(6 * ns, readings.iter().flat_map(|w| w.iter().copied()));
        assert!(relative(&(&y * &psi), &tau) <= 1e-10, "seed {seed}");
        assert!(
            relative(&(&y_ft * &split), &expected) <= 1e-10,
            "seed {seed}"
        );
    }
    // A model cannot hold a negative mass, nor a first moment without mass.
    let mut bad = split.clone();
    bad[0] = -1.0;
    assert!(model.with_ft_split_inertial_parameters(&bad).is_err());
    let mut bad = split.clone();
    bad[0] = 0.0;
    bad[1] = 0.1;
    assert!(model.with_ft_split_inertial_parameters(&bad).is_err());
    bad[0] = f64::NAN;
    assert!(model.with_ft_split_inertial_parameters(&bad).is_err());
}
