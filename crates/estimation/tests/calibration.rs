//! In-situ force/torque sensor calibration [Traversaro 2017, ch. 5] on synthetic data from the sensor
//! model `r = C⁻¹ f + b + n` (5.1) with the simulator's default noise (docs/sim.md: σ 1.5 N and 0.05 N·m,
//! offsets up to 5 N and 0.5 N·m), the wrenches from closed forms (5.2) or from stride-model's sensor model.

mod common;

use std::sync::Arc;

use common::Gauss;
use nalgebra::{DMatrix, DVector, Matrix6, Rotation3, Vector3, Vector6};
use stride_estimation::calibration::*;
use stride_model::{KinDyn, Model, RobotState};

const G: f64 = 9.81;

/// Raw readings and the gravity in the sensor frame at each.
type Dataset = (Vec<Vector6<f64>>, Vec<Vector3<f64>>);
/// Default simulator noise σ per axis (docs/sim.md, `sensors.ft.force_noise`, `torque_noise`).
const NOISE: [f64; 6] = [1.5, 1.5, 1.5, 0.05, 0.05, 0.05];

fn noise_vector() -> Vector6<f64> {
    Vector6::from_column_slice(&NOISE)
}

fn noise(gauss: &mut Gauss, scale: f64) -> Vector6<f64> {
    Vector6::from_fn(|i, _| scale * NOISE[i] * gauss.sample())
}

/// Gravity in the sensor frame for a random orientation of the sensor.
fn random_gravity(gauss: &mut Gauss) -> Vector3<f64> {
    let axis = Vector3::new(gauss.sample(), gauss.sample(), gauss.sample());
    let r = Rotation3::new(axis * 1.5);
    r.inverse() * Vector3::new(0.0, 0.0, -G)
}

/// A true calibration: `C = (1 + E)⁻¹` with `E` uniform in ±`error` (a sensor whose factory calibration
/// is off by a few percent), offsets within the simulator's default bounds.
fn true_calibration(gauss: &mut Gauss, error: f64) -> (Matrix6<f64>, Vector6<f64>) {
    let e = Matrix6::from_fn(|_, _| error * (2.0 * uniform(gauss) - 1.0));
    let c = (Matrix6::identity() + e).try_inverse().expect("invertible");
    let b = Vector6::from_fn(|i, _| {
        let bound = if i < 3 { 5.0 } else { 0.5 };
        bound * (2.0 * uniform(gauss) - 1.0)
    });
    (c, b)
}

fn uniform(gauss: &mut Gauss) -> f64 {
    // A uniform sample from two Gaussians (the CDF of their ratio's angle): enough for test data.
    let (a, b) = (gauss.sample(), gauss.sample());
    (b.atan2(a) + std::f64::consts::PI) / std::f64::consts::TAU
}

/// Body carried by the sensor: 1.2 kg, centre 6 cm below the sensor (an iCub foot with its sole).
fn body() -> (f64, Vector3<f64>) {
    (1.2, Vector3::new(0.02, -0.01, -0.06))
}

/// `n` static readings of a body of mass `m` and first moment `h` with calibration `(c, b)`, each the mean
/// of `average` raw samples (the thesis filters the raw data before calibrating, §5.4).
fn readings(
    gauss: &mut Gauss,
    (c, b): &(Matrix6<f64>, Vector6<f64>),
    (m, h): (f64, Vector3<f64>),
    n: usize,
    noise_scale: f64,
) -> Dataset {
    let ci = c.try_inverse().expect("invertible");
    let mm = gravity_wrench_matrix(m, &h);
    let mut raw = Vec::with_capacity(n);
    let mut grav = Vec::with_capacity(n);
    for _ in 0..n {
        let g = random_gravity(gauss);
        raw.push(ci * (mm * g) + b + noise(gauss, noise_scale));
        grav.push(g);
    }
    (raw, grav)
}

#[test]
fn offsets_from_rotations_are_exact_without_noise() {
    let mut gauss = Gauss::new(1);
    let cal = true_calibration(&mut gauss, 0.05);
    let (m, c) = body();
    let (raw, grav) = readings(&mut gauss, &cal, (m, c * m), 40, 0.0);
    let fit = offset_from_rotations(&raw, &grav).expect("identifiable");
    assert!((fit.offset - cal.1).amax() < 1e-9, "{}", fit.offset - cal.1);
    // Lemma 5.1: the readings lie on a 3D affine subspace.
    assert!(fit.singular_values[3] < 1e-6 * fit.singular_values[0]);
    assert!(fit.residual_rms < 1e-9);
}

#[test]
fn offsets_from_rotations_at_the_default_noise() {
    let mut gauss = Gauss::new(2);
    let cal = true_calibration(&mut gauss, 0.05);
    let (m, c) = body();
    // 60 s at 100 Hz, as one of the thesis's datasets.
    let n = 6000;
    let (raw, grav) = readings(&mut gauss, &cal, (m, c * m), n, 1.0);
    let fit = offset_from_rotations(&raw, &grav).expect("identifiable");
    // The noise level of an offset estimated from n samples: σ √(k / n) with k ≈ 4 unknowns per axis
    // (the gravity gains and the offset); asserted within 4 of those.
    for (i, sigma) in NOISE.iter().enumerate() {
        let level = sigma * (4.0 / n as f64).sqrt();
        let err = (fit.offset[i] - cal.1[i]).abs();
        assert!(
            err < 4.0 * level,
            "axis {i}: error {err:.3e}, noise level {level:.3e}"
        );
    }
}

#[test]
fn one_rotation_axis_does_not_determine_the_offset() {
    let mut gauss = Gauss::new(3);
    let cal = true_calibration(&mut gauss, 0.05);
    let (m, c) = body();
    let ci = cal.0.try_inverse().expect("invertible");
    let mm = gravity_wrench_matrix(m, &(c * m));
    // Rotations about the sensor's x axis only: gravity stays in the y–z plane.
    let grav: Vec<Vector3<f64>> = (0..50)
        .map(|k| Rotation3::new(Vector3::x() * (0.1 * k as f64)) * Vector3::new(0.0, 0.0, -G))
        .collect();
    let raw: Vec<Vector6<f64>> = grav.iter().map(|g| ci * (mm * g) + cal.1).collect();
    assert!(matches!(
        offset_from_rotations(&raw, &grav),
        Err(CalibrationError::NotIdentifiable { .. })
    ));
    // Two axes: determined.
    let grav2: Vec<Vector3<f64>> = (0..50)
        .map(|k| {
            Rotation3::new(Vector3::x() * (0.1 * k as f64))
                * Rotation3::new(Vector3::y() * (0.3 * (0.7 * k as f64).sin()))
                * Vector3::new(0.0, 0.0, -G)
        })
        .collect();
    let raw2: Vec<Vector6<f64>> = grav2.iter().map(|g| ci * (mm * g) + cal.1).collect();
    let fit = offset_from_rotations(&raw2, &grav2).expect("two axes");
    assert!((fit.offset - cal.1).amax() < 1e-9);
}

/// Three datasets with added masses (the bare body and two masses of 1 kg at different places).
fn added_masses() -> [(f64, Vector3<f64>); 3] {
    [
        (0.0, Vector3::zeros()),
        (1.0, Vector3::new(0.35, -0.03, 0.03)),
        (1.0, Vector3::new(-0.04, 0.30, 0.06)),
    ]
}

fn datasets(
    gauss: &mut Gauss,
    cal: &(Matrix6<f64>, Vector6<f64>),
    n: usize,
    noise_scale: f64,
) -> Vec<Dataset> {
    let (m, c) = body();
    added_masses()
        .iter()
        .map(|(ma, ca)| {
            let mass = m + ma;
            let first_moment = c * m + ca * *ma;
            readings(gauss, cal, (mass, first_moment), n, noise_scale)
        })
        .collect()
}

fn as_datasets(data: &[Dataset]) -> Vec<AddedMassDataset<'_>> {
    data.iter()
        .zip(added_masses())
        .map(|((raw, grav), (ma, ca))| AddedMassDataset {
            times: &[],
            raw,
            gravity: grav,
            added_mass: ma,
            added_com: ca,
        })
        .collect()
}

/// The thesis's stacked system (5.11c–f) written literally with Kronecker products, offsets removed with the
/// true offset: `Θ = [R_jᵀ ⊗ 1₆, −(G_jᵀ ⊗ 1₆) H]`, `β = vec(M_a^j G_j)`, solved densely.
fn thesis_system(data: &[Dataset], offset: &Vector6<f64>) -> DVector<f64> {
    let rows: usize = data.iter().map(|(r, _)| 6 * r.len()).sum();
    let mut theta = DMatrix::zeros(rows, 40);
    let mut beta = DVector::zeros(rows);
    // H: vec(M(m, h)) = H (m; h), M column-major 6 × 3.
    let mut hmat = DMatrix::zeros(18, 4);
    for p in 0..4 {
        let mut x = [0.0; 4];
        x[p] = 1.0;
        let m = gravity_wrench_matrix(x[0], &Vector3::new(x[1], x[2], x[3]));
        for (i, v) in m.iter().enumerate() {
            hmat[(i, p)] = *v;
        }
    }
    let i6 = DMatrix::<f64>::identity(6, 6);
    let mut row = 0;
    for ((raw, grav), (ma, ca)) in data.iter().zip(added_masses()) {
        let n = raw.len();
        let r = DMatrix::from_fn(6, n, |a, i| raw[i][a] - offset[a]);
        let g = DMatrix::from_fn(3, n, |a, i| grav[i][a]);
        let block_c = r.transpose().kronecker(&i6);
        let block_b = -(g.transpose().kronecker(&i6)) * &hmat;
        theta.view_mut((row, 0), (6 * n, 36)).copy_from(&block_c);
        theta.view_mut((row, 36), (6 * n, 4)).copy_from(&block_b);
        let ma_mat = gravity_wrench_matrix(ma, &(ca * ma));
        let mag = DMatrix::from_fn(6, 3, |a, c| ma_mat[(a, c)]) * g;
        beta.rows_mut(row, 6 * n)
            .copy_from(&DVector::from_column_slice(mag.as_slice()));
        row += 6 * n;
    }
    let svd = theta.svd(true, true);
    svd.solve(&beta, 1e-12).expect("solvable")
}

#[test]
fn calibration_matrix_is_exact_without_noise_and_equals_the_thesis_system() {
    let mut gauss = Gauss::new(4);
    let cal = true_calibration(&mut gauss, 0.05);
    let data = datasets(&mut gauss, &cal, 30, 0.0);
    let fit =
        calibration_matrix(&as_datasets(&data), &OffsetModel::Constant).expect("three datasets");
    assert!((fit.matrix - cal.0).amax() < 1e-9, "{}", fit.matrix - cal.0);
    let (m, c) = body();
    assert!((fit.mass - m).abs() < 1e-9);
    assert!((fit.first_moment - c * m).amax() < 1e-9);
    for b in &fit.offsets {
        assert!((b - cal.1).amax() < 1e-9);
    }
    // Independent: the thesis's Θ x = β with the raw readings.
    let x = thesis_system(&data, &cal.1);
    let c_thesis = Matrix6::from_column_slice(&x.as_slice()[0..36]);
    assert!((c_thesis - fit.matrix).amax() < 1e-9);
    assert!((x[36] - fit.mass).abs() < 1e-9);
}

#[test]
fn calibration_matrix_at_the_default_noise_is_within_one_percent() {
    let mut gauss = Gauss::new(5);
    let cal = true_calibration(&mut gauss, 0.05);
    // Three datasets of 100 s at 1 kHz (an iCub FT sensor's rate), raw readings at the simulator's
    // default noise. The error falls as 1/√n (docs/identification.md, "FT calibration").
    let data = datasets(&mut gauss, &cal, 100_000, 1.0);
    let fit =
        calibration_matrix(&as_datasets(&data), &OffsetModel::Constant).expect("three datasets");
    let err = (fit.matrix - cal.0).norm() / cal.0.norm();
    eprintln!(
        "calibration matrix, 3 × 100 000 samples at the default noise: Frobenius error {:.2} %",
        100.0 * err
    );
    assert!(err < 0.01, "Frobenius error {:.3} %", 100.0 * err);
    let (m, _) = body();
    assert!((fit.mass - m).abs() < 0.05 * m, "mass {}", fit.mass);
}

#[test]
fn two_datasets_are_refused_by_the_rank_check() {
    let mut gauss = Gauss::new(6);
    let cal = true_calibration(&mut gauss, 0.05);
    for scale in [0.0, 1.0] {
        let data = datasets(&mut gauss, &cal, 500, scale);
        let all = as_datasets(&data);
        match calibration_matrix(&all[..2], &OffsetModel::Constant) {
            Err(CalibrationError::TooFewDatasets {
                datasets,
                rank,
                unknowns,
            }) => {
                assert_eq!((datasets, unknowns), (2, 40));
                assert!(rank <= 36, "rank {rank}");
            }
            other => panic!("two datasets accepted: {other:?}"),
        }
        assert!(calibration_matrix(&all, &OffsetModel::Constant).is_ok());
    }
}

// ---- The model-based method: offset and child-side parameters on the FT-sensor regressor. ----

fn humanoid() -> (Arc<Model>, KinDyn) {
    let model = Arc::new(stride_model::bundled::model().expect("bundled model"));
    let kd = KinDyn::new(Arc::clone(&model));
    (model, kd)
}

/// A state of the left leg: base fixed (on a pole), leg joints random within ±0.6 rad, slow or fast.
fn leg_state(model: &Model, gauss: &mut Gauss, speed: f64) -> (RobotState, DVector<f64>) {
    let mut s = RobotState::zero(model);
    for name in [
        "l_hip_pitch",
        "l_hip_roll",
        "l_hip_yaw",
        "l_knee",
        "l_ankle_pitch",
        "l_ankle_roll",
    ] {
        let j = model.joint_index(name).expect("leg joint");
        s.joint_positions[j] = 0.6 * gauss.sample().clamp(-2.0, 2.0);
        s.joint_velocities[j] = speed * gauss.sample();
    }
    let mut nu_dot = DVector::zeros(model.nv());
    for j in 0..model.dof() {
        if s.joint_velocities[j] != 0.0 {
            nu_dot[6 + j] = speed * gauss.sample();
        }
    }
    (s, nu_dot)
}

/// Fits the offsets of the left leg and foot sensors from `n` samples.
fn regressor_fits(
    speed: f64,
    n: usize,
    noise_scale: f64,
    seed: u64,
) -> Vec<(Vector6<f64>, RegressorOffsetFit)> {
    let (model, mut kd) = humanoid();
    let mut gauss = Gauss::new(seed);
    let ns = model.ft_sensors().len();
    let sensors = ["l_leg_ft_sensor", "l_foot_ft_sensor"].map(|s| {
        model
            .ft_sensors()
            .iter()
            .position(|f| f.name == s)
            .expect("sensor")
    });
    let offsets = sensors.map(|_| true_calibration(&mut gauss, 0.0).1);
    let mut fits = sensors.map(|k| {
        let cols = child_side_columns(&mut kd, k).expect("columns");
        RegressorOffset::new(cols, noise_vector()).expect("problem")
    });
    let mut y = DMatrix::zeros(6 * ns, 10 * (model.body_count() + ns));
    let mut w = vec![Vector6::zeros(); ns];
    for _ in 0..n {
        let (s, nu_dot) = leg_state(&model, &mut gauss, speed);
        kd.set_state(&s).expect("state");
        kd.ft_sensor_wrenches(&nu_dot, &[], &mut w)
            .expect("wrenches");
        kd.ft_sensor_regressor(&nu_dot, &mut y).expect("regressor");
        for ((k, fit), b) in sensors.iter().zip(&mut fits).zip(&offsets) {
            let raw = w[*k] + b + noise(&mut gauss, noise_scale);
            fit.add(&y.rows(6 * k, 6), &raw).expect("sample");
        }
    }
    offsets
        .iter()
        .zip(&fits)
        .map(|(b, f)| (*b, f.solve().expect("identifiable")))
        .collect()
}

#[test]
fn regressor_offsets_are_exact_without_noise_static_and_moving() {
    for speed in [0.0, 1.0] {
        for (truth, fit) in regressor_fits(speed, 200, 0.0, 7) {
            assert!(
                (fit.offset - truth).amax() < 1e-9,
                "speed {speed}: {}",
                fit.offset - truth
            );
        }
    }
}

#[test]
fn regressor_offsets_at_the_default_noise_are_within_the_noise_level() {
    for (truth, fit) in regressor_fits(0.3, 3000, 1.0, 8) {
        for i in 0..6 {
            let err = (fit.offset[i] - truth[i]).abs();
            assert!(
                err < 4.0 * fit.offset_std[i],
                "axis {i}: error {err:.3e} > 4 σ = {:.3e}",
                4.0 * fit.offset_std[i]
            );
            // and σ is the noise level of a mean over the samples, within a small factor.
            assert!(fit.offset_std[i] < 5.0 * NOISE[i] / (3000f64).sqrt());
        }
        assert!((fit.normalised_residual - 1.0).abs() < 0.05);
    }
}

#[test]
fn regressor_offset_refuses_a_pose_that_never_turns() {
    let (model, mut kd) = humanoid();
    let k = model.ft_sensor_index("l_foot_ft_sensor").expect("sensor");
    let ns = model.ft_sensors().len();
    let cols = child_side_columns(&mut kd, k).expect("columns");
    let mut fit = RegressorOffset::new(cols, noise_vector()).expect("problem");
    let mut y = DMatrix::zeros(6 * ns, 10 * (model.body_count() + ns));
    let s = RobotState::zero(&model);
    kd.set_state(&s).expect("state");
    let zero = DVector::zeros(model.nv());
    kd.ft_sensor_regressor(&zero, &mut y).expect("regressor");
    for _ in 0..100 {
        fit.add(&y.rows(6 * k, 6), &Vector6::zeros())
            .expect("sample");
    }
    assert!(matches!(
        fit.solve(),
        Err(CalibrationError::NotIdentifiable { .. })
    ));
}
