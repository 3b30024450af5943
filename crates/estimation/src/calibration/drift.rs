//! The gravity response of a force/torque sensor whose offset drifts as a random walk: stage 1 of the
//! calibration matrix (5.11) with the offset as a function of time, by a Kalman filter per axis.
//!
//! Traversaro 2017 takes the offset constant over a dataset ((5.1), (5.10)); with the drift of a real
//! sensor (`b` a random walk: temperature) a constant offset reads the walk as gravity response wherever it
//! correlates with the slow rotations, and (5.11) amplifies that. The model here is ours: per raw axis `a`,
//!
//! `r_a(t_i) = d_aᵀ g_i + b_a(t_i) + n_i`, `b_a(t_i) = b_a(t_{i−1}) + w_i`,
//! `n_i ~ N(0, σ_a²)`, `w_i ~ N(0, q_a (t_i − t_{i−1}))`,
//!
//! with `d_a` (row `a` of `D = C⁻¹ M`, constant) and `b_a` in the state `x = (d_a, b_a)` of a linear
//! Kalman filter. `d_a` has no process noise, so the filter's final estimate of it is conditioned on every
//! sample: it is the generalised least-squares estimate of `d_a` under the noise covariance
//! `σ_a² 1 + q_a min(t_i − t_0, t_j − t_0)` (white noise plus a Wiener process), with its covariance
//! `P_dd`. The initial state is diffuse ([`DIFFUSE_STD`]).

use nalgebra::{Matrix3, Matrix4, Matrix6x3, Vector3, Vector4, Vector6};

use super::check::check_pairs;
use super::lsq::RANK_TOLERANCE;
use super::CalibrationError;

/// The sensor's noise model, per raw axis `[f; τ]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DriftNoise {
    /// White-noise σ of one reading, raw units (N, N·m for a sensor near identity).
    pub white: Vector6<f64>,
    /// Random-walk rate of the offset, raw units/√s (the walk's σ after one second).
    pub walk: Vector6<f64>,
}

/// The gravity response of one dataset with a drifting offset.
#[derive(Clone, Debug)]
pub struct DriftFit {
    /// `D` of `r = D g + b(t)`, 6 × 3.
    pub response: Matrix6x3<f64>,
    /// Covariance of each row `d_a` of `D` (3 × 3 per raw axis).
    pub row_covariance: [Matrix3<f64>; 6],
    /// The offset at the last sample (filtered: conditioned on every sample), raw units.
    pub final_offset: Vector6<f64>,
    /// Its standard deviation, raw units.
    pub final_offset_std: Vector6<f64>,
    /// `√(Σ ν²/S / samples)` per axis over the innovations `ν` and their predicted variances `S` (the first
    /// 50 samples, which do not determine the state yet, left out): about 1 when the noise model fits the
    /// data.
    pub normalised_innovation: Vector6<f64>,
}

/// Stage 1 of (5.11) with a drifting offset: `D`, its row covariances and the final offset from readings
/// `raw` at `times` (s, increasing) and the load accelerations `gravity` (sensor frame, m/s²), under
/// `noise`. [`CalibrationError::NotIdentifiable`] when the gravity samples do not determine `D` (fewer
/// than three independent directions), [`CalibrationError::NonFinite`] on a non-finite or decreasing time
/// or a non-positive noise σ.
pub fn gravity_response_with_drift(
    times: &[f64],
    raw: &[Vector6<f64>],
    gravity: &[Vector3<f64>],
    noise: &DriftNoise,
) -> Result<DriftFit, CalibrationError> {
    check_pairs("a dataset's gravity response", raw, gravity)?;
    if times.len() != raw.len() {
        return Err(CalibrationError::Size {
            what: "sample times (one per raw reading)",
            expected: raw.len(),
            actual: times.len(),
        });
    }
    if !noise.white.iter().all(|s| s.is_finite() && *s > 0.0)
        || !noise.walk.iter().all(|q| q.is_finite() && *q >= 0.0)
    {
        return Err(CalibrationError::NonFinite {
            what: "noise σ or random-walk rate (σ positive, rate non-negative)",
            index: 0,
        });
    }
    let bad_time = |i: usize| !times[i].is_finite() || (i > 0 && times[i] < times[i - 1]);
    if let Some(i) = (0..times.len()).find(|&i| bad_time(i)) {
        return Err(CalibrationError::NonFinite {
            what: "sample time (finite and increasing)",
            index: i,
        });
    }
    let mut fit = DriftFit {
        response: Matrix6x3::zeros(),
        row_covariance: [Matrix3::zeros(); 6],
        final_offset: Vector6::zeros(),
        final_offset_std: Vector6::zeros(),
        normalised_innovation: Vector6::zeros(),
    };
    for a in 0..6 {
        let axis = filter_axis(times, raw, gravity, a, noise.white[a], noise.walk[a]);
        // The gravity determines (d_a, b_a) when the information matrix is well conditioned.
        let eig = axis.information.symmetric_eigenvalues();
        let p = if eig.min() > RANK_TOLERANCE * eig.max() {
            axis.information.try_inverse()
        } else {
            None
        };
        let Some(p) = p else {
            return Err(CalibrationError::NotIdentifiable {
                what: "a dataset's gravity response (with a drifting offset)",
                rank: eig
                    .iter()
                    .filter(|e| **e > RANK_TOLERANCE * eig.max())
                    .count(),
                unknowns: 4,
                hint: "rotate the sensor so that gravity takes directions off one plane (two axes)",
            });
        };
        let x = p * axis.vector;
        let p_dd = p.fixed_view::<3, 3>(0, 0).into_owned();
        fit.response
            .set_row(a, &Vector3::new(x[0], x[1], x[2]).transpose());
        fit.row_covariance[a] = p_dd;
        fit.final_offset[a] = x[3];
        fit.final_offset_std[a] = p[(3, 3)].max(0.0).sqrt();
        fit.normalised_innovation[a] = axis.normalised_innovation;
    }
    Ok(fit)
}

/// One axis's filter after the last sample.
struct AxisFilter {
    /// Information matrix `P⁻¹` of `(d_a, b_a)` and information vector `P⁻¹ x`.
    information: Matrix4<f64>,
    vector: Vector4<f64>,
    normalised_innovation: f64,
}

/// The filter of raw axis `a` in information form (exactly diffuse at the start: zero information), state
/// `(d_a, b_a)`, measurement `r_a = (g, 1) · x + n`: the update adds `h hᵀ / σ²`; the prediction adds the
/// walk's variance `walk² Δt` to `b_a`'s, `Y ← L Y Lᵀ + c cᵀ / (walk² Δt)` with `c = Y e_b / (Y_bb +
/// 1/(walk² Δt))`, `L = 1 − c e_bᵀ` (the information filter's prediction with `F = 1`, `G = e_b`).
fn filter_axis(
    times: &[f64],
    raw: &[Vector6<f64>],
    gravity: &[Vector3<f64>],
    a: usize,
    white: f64,
    walk: f64,
) -> AxisFilter {
    let r = white * white;
    let q = walk * walk;
    let mut y = Matrix4::zeros();
    let mut v = Vector4::zeros();
    let mut chi2 = 0.0;
    let mut counted = 0usize;
    for i in 0..raw.len() {
        let dt = if i > 0 { times[i] - times[i - 1] } else { 0.0 };
        if q * dt > 0.0 {
            let yb: Vector4<f64> = y.column(3).into_owned();
            let c = yb / (y[(3, 3)] + 1.0 / (q * dt));
            let mut l = Matrix4::identity();
            for row in 0..4 {
                l[(row, 3)] -= c[row];
            }
            y = l * y * l.transpose() + c * c.transpose() / (q * dt);
            v = l * v;
        }
        let g = &gravity[i];
        let h = Vector4::new(g.x, g.y, g.z, 1.0);
        // The innovation against the prediction, once the samples so far determine the state.
        if i >= INNOVATION_WARM_UP {
            if let Some(chol) = y.cholesky() {
                let x = chol.solve(&v);
                let s = h.dot(&chol.solve(&h)) + r;
                let nu = raw[i][a] - h.dot(&x);
                chi2 += nu * nu / s;
                counted += 1;
            }
        }
        y += h * h.transpose() / r;
        v += h * (raw[i][a] / r);
    }
    AxisFilter {
        information: y,
        vector: v,
        normalised_innovation: (chi2 / counted.max(1) as f64).sqrt(),
    }
}

/// Samples before the innovations are counted (the state is not determined by the first few).
const INNOVATION_WARM_UP: usize = 50;
