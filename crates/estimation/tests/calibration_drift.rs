//! Stage 1 of the calibration matrix (5.11) with a drifting offset (`gravity_response_with_drift`): the
//! Kalman filter against the generalised least-squares estimate written out densely, and on synthetic
//! readings with a known random walk (the simulator's default noise and drift, docs/sim.md) the errors
//! match the filter's covariance, while a constant offset (5.10) on the same data is farther off.

mod common;

use common::Gauss;
use nalgebra::{DMatrix, DVector, Matrix6x3, Rotation3, Vector3, Vector6};
use stride_estimation::calibration::*;

const G: f64 = 9.81;

/// The simulator's default force/torque noise σ and drift rates (`[sim.sensors.ft]`).
fn default_noise() -> DriftNoise {
    DriftNoise {
        white: Vector6::new(1.5, 1.5, 1.5, 0.05, 0.05, 0.05),
        walk: Vector6::new(0.0645, 0.0645, 0.0645, 6.45e-3, 6.45e-3, 6.45e-3),
    }
}

/// Gravity in the frame of a sensor swung slowly about three axes (periods 7–19 s, as the pole runs).
fn swung_gravity(t: f64, phase: f64) -> Vector3<f64> {
    let w = |period: f64| std::f64::consts::TAU * t / period + phase;
    let r = Rotation3::new(Vector3::z() * 0.8 * w(13.0).sin())
        * Rotation3::new(Vector3::x() * 0.6 * w(11.0).sin())
        * Rotation3::new(Vector3::y() * (0.3 + 1.0 * w(17.0).sin()));
    r.inverse() * Vector3::new(0.0, 0.0, -G)
}

/// Readings `r = D g + b(t) + n`, `b` starting at `b0` and walking; returns times, readings, gravity and
/// the offset at each sample.
struct Drifting {
    times: Vec<f64>,
    raw: Vec<Vector6<f64>>,
    gravity: Vec<Vector3<f64>>,
    offset: Vec<Vector6<f64>>,
}

fn drifting_readings(
    gauss: &mut Gauss,
    d: &Matrix6x3<f64>,
    noise: &DriftNoise,
    rate: f64,
    duration: f64,
) -> Drifting {
    let n = (duration * rate) as usize;
    let dt = 1.0 / rate;
    let mut b = Vector6::new(3.0, -2.0, 4.0, 0.3, -0.2, 0.1);
    let phase = gauss.sample();
    let mut out = Drifting {
        times: Vec::with_capacity(n),
        raw: Vec::with_capacity(n),
        gravity: Vec::with_capacity(n),
        offset: Vec::with_capacity(n),
    };
    for i in 0..n {
        let t = i as f64 * dt;
        if i > 0 {
            b += Vector6::from_fn(|a, _| noise.walk[a] * dt.sqrt() * gauss.sample());
        }
        let g = swung_gravity(t, phase);
        let n = Vector6::from_fn(|a, _| noise.white[a] * gauss.sample());
        out.times.push(t);
        out.raw.push(d * g + b + n);
        out.gravity.push(g);
        out.offset.push(b);
    }
    out
}

/// `D = C⁻¹ M(m, h)` of a foot-like body (0.7 kg + 2.1 kg, first moment 0.5 kg·m) seen through a sensor
/// whose gains are off identity by a few percent.
fn response() -> Matrix6x3<f64> {
    let m = gravity_wrench_matrix(2.8, &Vector3::new(0.45, 0.05, -0.08));
    let gains = nalgebra::Matrix6::from_fn(|i, j| {
        if i == j {
            1.02
        } else {
            0.01 * ((i + 2 * j) as f64).sin()
        }
    });
    gains * m
}

/// The generalised least-squares estimate of `(d_a, b_0)` and the offset at the last sample (its best
/// linear unbiased prediction), written out densely: covariance `σ² 1 + q min(t_i, t_j)` (`t_0 = 0`).
fn dense_gls(
    data: &Drifting,
    a: usize,
    white: f64,
    walk: f64,
) -> (Vector3<f64>, f64, DMatrix<f64>) {
    let n = data.times.len();
    let q = walk * walk;
    let sigma = DMatrix::from_fn(n, n, |i, j| {
        q * data.times[i].min(data.times[j]) + if i == j { white * white } else { 0.0 }
    });
    let x = DMatrix::from_fn(n, 4, |i, c| if c < 3 { data.gravity[i][c] } else { 1.0 });
    let y = DVector::from_fn(n, |i, _| data.raw[i][a]);
    let chol = sigma.cholesky().expect("positive definite");
    let si_x = chol.solve(&x);
    let si_y = chol.solve(&y);
    let normal = x.transpose() * &si_x;
    let cov = normal.clone().try_inverse().expect("identifiable");
    let beta = &cov * (x.transpose() * &si_y);
    // BLUP of the walk at the last sample: k_Nᵀ Σ⁻¹ (y − X β), k_N[i] = q t_i.
    let resid = &y - &x * &beta;
    let k = DVector::from_fn(n, |i, _| q * data.times[i]);
    let walk_n = k.dot(&chol.solve(&resid));
    (
        Vector3::new(beta[0], beta[1], beta[2]),
        beta[3] + walk_n,
        cov.view((0, 0), (3, 3)).into_owned(),
    )
}

#[test]
fn the_drift_filter_equals_the_dense_generalised_least_squares() {
    let mut gauss = Gauss::new(11);
    let noise = default_noise();
    let d = response();
    // 4 s at 100 Hz: the walk (0.13 N) is comparable with the noise's share of the estimate.
    let data = drifting_readings(&mut gauss, &d, &noise, 100.0, 4.0);
    let fit = gravity_response_with_drift(&data.times, &data.raw, &data.gravity, &noise).unwrap();
    for a in 0..6 {
        let (d_gls, b_gls, cov) = dense_gls(&data, a, noise.white[a], noise.walk[a]);
        let row: Vector3<f64> = fit.response.row(a).transpose();
        let scale = cov.diagonal().map(f64::sqrt).max();
        assert!(
            (row - d_gls).amax() < 1e-6 * scale,
            "axis {a}: {row} vs {d_gls}"
        );
        assert!(
            (fit.final_offset[a] - b_gls).abs() < 1e-6 * fit.final_offset_std[a],
            "axis {a}: {} vs {b_gls}",
            fit.final_offset[a]
        );
        let cov_err = (fit.row_covariance[a] - &cov).amax();
        assert!(
            cov_err < 1e-6 * scale * scale,
            "axis {a}: covariance {cov_err}"
        );
    }
}

#[test]
fn a_known_random_walk_is_filtered_within_the_predicted_error_and_a_constant_offset_is_worse() {
    let noise = default_noise();
    let d = response();
    let mut gauss = Gauss::new(12);
    let (mut chi2, mut count) = (0.0, 0usize);
    let (mut offset_z2, mut innovation) = (0.0, 0.0);
    let (mut filter_sq, mut constant_sq) = (0.0, 0.0);
    let seeds = 12;
    for _ in 0..seeds {
        // 20 s at 500 Hz, the default noise and drift: the walk is 0.29 N over the run.
        let data = drifting_readings(&mut gauss, &d, &noise, 500.0, 20.0);
        let fit =
            gravity_response_with_drift(&data.times, &data.raw, &data.gravity, &noise).unwrap();
        let constant = offset_free_fit(&data);
        let last = data.offset.last().unwrap();
        for a in 0..6 {
            let e: Vector3<f64> = (fit.response.row(a) - d.row(a)).transpose();
            let p_inv = fit.row_covariance[a].try_inverse().unwrap();
            chi2 += e.dot(&(p_inv * e));
            count += 1;
            offset_z2 += ((fit.final_offset[a] - last[a]) / fit.final_offset_std[a]).powi(2);
            innovation += fit.normalised_innovation[a];
            // Relative to the row's own scale: force and torque rows alike.
            let scale = fit.row_covariance[a].trace().sqrt();
            filter_sq += (e.norm() / scale).powi(2);
            let ec: Vector3<f64> = (constant.row(a) - d.row(a)).transpose();
            constant_sq += (ec.norm() / scale).powi(2);
        }
    }
    let n = count as f64;
    // χ² of 3 degrees of freedom per row: its mean over 72 rows is 3 within ±0.6 (4 σ of the mean).
    let mean_chi2 = chi2 / n;
    assert!(
        (mean_chi2 - 3.0).abs() < 0.6,
        "mean χ² {mean_chi2} (3 expected)"
    );
    let offset_rms = (offset_z2 / n).sqrt();
    assert!(
        (offset_rms - 1.0).abs() < 0.35,
        "final offset error / σ RMS {offset_rms}"
    );
    let innovation = innovation / n;
    assert!(
        (innovation - 1.0).abs() < 0.02,
        "normalised innovation {innovation}"
    );
    // The constant offset reads the walk as gravity response: a larger error on the same data (1.36× the
    // filter's RMS when measured, on these swings of the pole runs' pace; the log test has the effect on C).
    let ratio = (constant_sq / filter_sq).sqrt();
    assert!(
        ratio > 1.2,
        "constant-offset error only {ratio}× the filter's"
    );
}

/// `r = D g + b` by ordinary least squares, the offset constant (the first stage of (5.11) as in Traversaro
/// 2017), written out densely.
fn offset_free_fit(data: &Drifting) -> Matrix6x3<f64> {
    let n = data.raw.len();
    let x = DMatrix::from_fn(n, 4, |i, c| if c < 3 { data.gravity[i][c] } else { 1.0 });
    let mut d = Matrix6x3::zeros();
    let xtx = x.transpose() * &x;
    let inv = xtx.try_inverse().expect("identifiable");
    for a in 0..6 {
        let y = DVector::from_fn(n, |i, _| data.raw[i][a]);
        let beta = &inv * (x.transpose() * y);
        d.set_row(a, &Vector3::new(beta[0], beta[1], beta[2]).transpose());
    }
    d
}

#[test]
fn the_drift_filter_refuses_bad_input() {
    let noise = default_noise();
    let mut gauss = Gauss::new(13);
    let data = drifting_readings(&mut gauss, &response(), &noise, 100.0, 2.0);
    // Times out of order.
    let mut times = data.times.clone();
    times.swap(10, 11);
    assert!(matches!(
        gravity_response_with_drift(&times, &data.raw, &data.gravity, &noise),
        Err(CalibrationError::NonFinite { index: 11, .. })
    ));
    // A zero white-noise σ.
    let mut zero = noise;
    zero.white[2] = 0.0;
    assert!(gravity_response_with_drift(&data.times, &data.raw, &data.gravity, &zero).is_err());
    // Gravity along one direction only: D is not determined.
    let still: Vec<Vector3<f64>> = data
        .gravity
        .iter()
        .map(|_| Vector3::new(0.0, 0.0, -G))
        .collect();
    assert!(matches!(
        gravity_response_with_drift(&data.times, &data.raw, &still, &noise),
        Err(CalibrationError::NotIdentifiable { .. })
    ));
    // One time short.
    assert!(matches!(
        gravity_response_with_drift(&data.times[1..], &data.raw, &data.gravity, &noise),
        Err(CalibrationError::Size { .. })
    ));
}
