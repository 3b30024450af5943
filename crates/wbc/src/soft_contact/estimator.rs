//! Online estimation of the ground's `k` and `b` by recursive least squares [Romualdi 2022, §8.2.3,
//! eq. 8.2.20–8.2.22; Ljung 1999, §11.2] (a Kalman filter on `π_{t+1} = π_t`, eq. 8.2.23–8.2.24), with the covariance reset
//! at every touch-down for grounds whose parameters change along the path [Colman 2006].

use nalgebra::{Matrix2, Matrix6, Matrix6x2, Vector2, Vector6};

use crate::error::WbcError;
use crate::soft_contact::model::GroundParameters;

/// Settings of a [`GroundEstimator`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EstimatorSettings {
    /// First guess `π̂₀ = [k; b]`.
    pub initial: GroundParameters,
    /// Standard deviations of the first guess `[σ_k (N/m³), σ_b (N·s/m³)]`: `P₀ = diag(σ²)`, also the
    /// covariance a touch-down resets to.
    pub initial_std: [f64; 2],
    /// Standard deviations of the measured wrench, `[force (N), torque (N·m)]`: `Γ = diag(σ_f² I₃, σ_μ² I₃)`.
    pub wrench_std: [f64; 2],
}

/// Recursive least-squares estimate of `π = [k; b]` from measured sole wrenches and the regressor
/// [`crate::SoleGeometry::regressor`]. Allocates nothing.
#[derive(Clone, Debug)]
pub struct GroundEstimator {
    estimate: Vector2<f64>,
    covariance: Matrix2<f64>,
    reset_covariance: Matrix2<f64>,
    /// `Γ⁻¹` diagonal (the information form of the update never inverts a 6 × 6 matrix).
    noise_information: Vector6<f64>,
}

impl GroundEstimator {
    /// An estimator at `settings.initial` with covariance `P₀`.
    ///
    /// # Errors
    /// [`WbcError::InvalidConfig`] for a non-finite guess or a non-positive standard deviation.
    pub fn new(settings: &EstimatorSettings) -> Result<Self, WbcError> {
        let bad = |key: &'static str, reason: &str| WbcError::InvalidConfig {
            task: "<ground estimator>".into(),
            key,
            reason: reason.into(),
        };
        let guess = settings.initial.vector();
        if !guess.iter().all(|x| x.is_finite()) {
            return Err(bad("initial", "must be finite"));
        }
        if !settings
            .initial_std
            .iter()
            .all(|s| s.is_finite() && *s > 0.0)
        {
            return Err(bad("initial_std", "must be finite and > 0"));
        }
        if !settings
            .wrench_std
            .iter()
            .all(|s| s.is_finite() && *s > 0.0)
        {
            return Err(bad("wrench_std", "must be finite and > 0"));
        }
        let [sk, sb] = settings.initial_std;
        let [sf, st] = settings.wrench_std;
        let p0 = Matrix2::new(sk * sk, 0.0, 0.0, sb * sb);
        let (inf_f, inf_t) = (1.0 / (sf * sf), 1.0 / (st * st));
        Ok(Self {
            estimate: guess,
            covariance: p0,
            reset_covariance: p0,
            noise_information: Vector6::new(inf_f, inf_f, inf_f, inf_t, inf_t, inf_t),
        })
    }

    /// The current estimate.
    pub fn estimate(&self) -> GroundParameters {
        GroundParameters {
            stiffness: self.estimate[0],
            damping: self.estimate[1],
        }
    }

    /// The covariance `P` of the estimate, `[(N/m³)², …]`.
    pub fn covariance(&self) -> Matrix2<f64> {
        self.covariance
    }

    /// Resets the covariance to `P₀` (keeps the estimate): call at every touch-down.
    pub fn touch_down(&mut self) {
        self.covariance = self.reset_covariance;
    }

    /// One RLS step with regressor `𝒴` and measured wrench `f` (force, torque about the sole centre):
    /// `L = P 𝒴ᵀ (Γ + 𝒴 P 𝒴ᵀ)⁻¹`, `π̂ ← π̂ + L (f − 𝒴 π̂)`, `P ← (I − L𝒴) P (I − L𝒴)ᵀ + L Γ Lᵀ`
    /// [Romualdi 2022, eq. 8.2.20–8.2.22]. The gain is computed in the equal information form
    /// `L = (P⁻¹ + 𝒴ᵀΓ⁻¹𝒴)⁻¹ 𝒴ᵀ Γ⁻¹` (matrix inversion lemma; 2 × 2 instead of 6 × 6). A non-finite sample
    /// is skipped (returns `false`).
    pub fn update(&mut self, regressor: &Matrix6x2<f64>, wrench: &Vector6<f64>) -> bool {
        if !regressor.iter().chain(wrench.iter()).all(|x| x.is_finite()) {
            return false;
        }
        let weighted: Matrix6x2<f64> = Matrix6::from_diagonal(&self.noise_information) * regressor;
        let Some(p_inv) = self.covariance.try_inverse() else {
            return false;
        };
        let Some(posterior) = (p_inv + regressor.transpose() * weighted).try_inverse() else {
            return false;
        };
        let gain = posterior * weighted.transpose();
        let innovation = wrench - regressor * self.estimate;
        self.estimate += gain * innovation;
        let a = Matrix2::identity() - gain * regressor;
        let noise = Matrix6::from_diagonal(&self.noise_information.map(|x| 1.0 / x));
        self.covariance = a * self.covariance * a.transpose() + gain * noise * gain.transpose();
        true
    }
}
