//! Online estimation of the ground's `k` and `b` by recursive least squares [Romualdi 2022, §8.2.3,
//! eq. 8.2.20–8.2.22; Ljung 1999, §11.2] (a Kalman filter on `π_{t+1} = π_t`, eq. 8.2.23–8.2.24), with the covariance reset
//! at every touch-down for grounds whose parameters change along the path [Colman 2006]; and the same RLS
//! with a third parameter, the rest (zero-force) height's error ([`GroundRestEstimator`]).

use nalgebra::{Matrix6, Matrix6x2, Matrix6x3, SMatrix, SVector, Vector2, Vector3, Vector6};

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

/// The RLS state of `N` parameters: estimate, covariance, the covariance a touch-down resets to and the
/// noise information `Γ⁻¹` (diagonal). Allocates nothing.
#[derive(Clone, Debug)]
struct Rls<const N: usize> {
    estimate: SVector<f64, N>,
    covariance: SMatrix<f64, N, N>,
    reset_covariance: SMatrix<f64, N, N>,
    noise_information: Vector6<f64>,
}

impl<const N: usize> Rls<N> {
    /// One RLS step with regressor `𝒴` (6 × N) and measured wrench `f` [Romualdi 2022, eq. 8.2.20–8.2.22]
    /// (see [`GroundEstimator::update`]); `false` (and no change) for a non-finite sample or a singular
    /// information matrix.
    fn update(&mut self, regressor: &SMatrix<f64, 6, N>, wrench: &Vector6<f64>) -> bool {
        if !regressor.iter().chain(wrench.iter()).all(|x| x.is_finite()) {
            return false;
        }
        let weighted: SMatrix<f64, 6, N> =
            Matrix6::from_diagonal(&self.noise_information) * regressor;
        let Some(p_inv) = self.covariance.try_inverse() else {
            return false;
        };
        let Some(posterior) = (p_inv + regressor.transpose() * weighted).try_inverse() else {
            return false;
        };
        let gain = posterior * weighted.transpose();
        let innovation = wrench - regressor * self.estimate;
        self.estimate += gain * innovation;
        let a = SMatrix::<f64, N, N>::identity() - gain * regressor;
        let noise = Matrix6::from_diagonal(&self.noise_information.map(|x| 1.0 / x));
        self.covariance = a * self.covariance * a.transpose() + gain * noise * gain.transpose();
        true
    }

    /// `k̂`, `b̂`: the first two parameters.
    fn ground(&self) -> GroundParameters {
        GroundParameters {
            stiffness: self.estimate[0],
            damping: self.estimate[1],
        }
    }
}

/// `P₀` and `Γ⁻¹` of `settings`, checked. Errors: [`WbcError::InvalidConfig`] for a non-finite guess or a
/// non-positive standard deviation.
fn checked_prior(settings: &EstimatorSettings) -> Result<(Vector2<f64>, Vector6<f64>), WbcError> {
    let bad = |key: &'static str, reason: &str| WbcError::InvalidConfig {
        task: "<ground estimator>".into(),
        key,
        reason: reason.into(),
    };
    let guess = settings.initial.vector();
    if !guess.iter().all(|x| x.is_finite()) {
        return Err(bad("initial", "must be finite"));
    }
    let positive = |s: &[f64]| s.iter().all(|s| s.is_finite() && *s > 0.0);
    if !positive(&settings.initial_std) {
        return Err(bad("initial_std", "must be finite and > 0"));
    }
    if !positive(&settings.wrench_std) {
        return Err(bad("wrench_std", "must be finite and > 0"));
    }
    let [sf, st] = settings.wrench_std;
    let (inf_f, inf_t) = (1.0 / (sf * sf), 1.0 / (st * st));
    Ok((
        guess,
        Vector6::new(inf_f, inf_f, inf_f, inf_t, inf_t, inf_t),
    ))
}

/// Recursive least-squares estimate of `π = [k; b]` from measured sole wrenches and the regressor
/// [`crate::SoleGeometry::regressor`]. Allocates nothing.
#[derive(Clone, Debug)]
pub struct GroundEstimator {
    rls: Rls<2>,
}

impl GroundEstimator {
    /// An estimator at `settings.initial` with covariance `P₀`.
    ///
    /// # Errors
    /// [`WbcError::InvalidConfig`] for a non-finite guess or a non-positive standard deviation.
    pub fn new(settings: &EstimatorSettings) -> Result<Self, WbcError> {
        let (guess, noise_information) = checked_prior(settings)?;
        let [sk, sb] = settings.initial_std;
        let p0 = SMatrix::<f64, 2, 2>::new(sk * sk, 0.0, 0.0, sb * sb);
        Ok(Self {
            rls: Rls {
                estimate: guess,
                covariance: p0,
                reset_covariance: p0,
                noise_information,
            },
        })
    }

    /// The current estimate.
    pub fn estimate(&self) -> GroundParameters {
        self.rls.ground()
    }

    /// The covariance `P` of the estimate, `[(N/m³)², …]`.
    pub fn covariance(&self) -> SMatrix<f64, 2, 2> {
        self.rls.covariance
    }

    /// Resets the covariance to `P₀` (keeps the estimate): call at every touch-down.
    pub fn touch_down(&mut self) {
        self.rls.covariance = self.rls.reset_covariance;
    }

    /// One RLS step with regressor `𝒴` and measured wrench `f` (force, torque about the sole centre):
    /// `L = P 𝒴ᵀ (Γ + 𝒴 P 𝒴ᵀ)⁻¹`, `π̂ ← π̂ + L (f − 𝒴 π̂)`, `P ← (I − L𝒴) P (I − L𝒴)ᵀ + L Γ Lᵀ`
    /// [Romualdi 2022, eq. 8.2.20–8.2.22]. The gain is computed in the equal information form
    /// `L = (P⁻¹ + 𝒴ᵀΓ⁻¹𝒴)⁻¹ 𝒴ᵀ Γ⁻¹` (matrix inversion lemma; 2 × 2 instead of 6 × 6). A non-finite sample
    /// is skipped (returns `false`).
    pub fn update(&mut self, regressor: &Matrix6x2<f64>, wrench: &Vector6<f64>) -> bool {
        self.rls.update(regressor, wrench)
    }
}

/// Recursive least-squares estimate of `[k; b; k δ]`: the ground's densities and the error `δ` (m, up) of
/// the rest (zero-force) height the regressor measures the sole's sink from. A rest plane `δ` below the true
/// one adds `k l w |c| δ e₃` to Lemma 1's force (eq. 8.1.7a with `ō + δ e₃`) and nothing to its torque (a
/// uniform density has no moment about the sole's centre), so the regressor of eq. 8.2.17 gains the column
/// `l w |c| e₃` ([`crate::SoleGeometry::rest_height_column`]) and stays linear in `θ = k δ` (N/m²). Without
/// it a rest plane that is off by `δ` is absorbed by `k` and `b` (docs/soft-ground.md, "The ground estimate:
/// `b̂` and the rest height"). `δ` is a property of the landing, not of the ground: a touch-down resets
/// `θ̂` to zero with the covariance, and keeps `k̂`, `b̂`. Allocates nothing.
#[derive(Clone, Debug)]
pub struct GroundRestEstimator {
    rls: Rls<3>,
}

impl GroundRestEstimator {
    /// An estimator at `settings.initial` and `δ = 0`, with covariance
    /// `P₀ = diag(σ_k², σ_b², (k₀ σ_δ)²)`, `σ_δ` = `rest_height_std` (m).
    ///
    /// # Errors
    /// [`WbcError::InvalidConfig`] for a non-finite guess or a non-positive standard deviation.
    pub fn new(settings: &EstimatorSettings, rest_height_std: f64) -> Result<Self, WbcError> {
        let (guess, noise_information) = checked_prior(settings)?;
        let theta_std = settings.initial.stiffness.abs() * rest_height_std;
        if !(theta_std.is_finite() && theta_std > 0.0) {
            return Err(WbcError::InvalidConfig {
                task: "<ground estimator>".into(),
                key: "rest_height_std",
                reason: format!(
                    "rest_height_std = {rest_height_std} m must be finite and > 0 (with k > 0)"
                ),
            });
        }
        let [sk, sb] = settings.initial_std;
        let p0 = SMatrix::<f64, 3, 3>::from_diagonal(&Vector3::new(
            sk * sk,
            sb * sb,
            theta_std * theta_std,
        ));
        Ok(Self {
            rls: Rls {
                estimate: Vector3::new(guess[0], guess[1], 0.0),
                covariance: p0,
                reset_covariance: p0,
                noise_information,
            },
        })
    }

    /// The current estimate of `k` and `b`.
    pub fn estimate(&self) -> GroundParameters {
        self.rls.ground()
    }

    /// The estimated error of the rest height, `δ̂ = θ̂ / k̂` (m, up: the true zero-force plane is `δ̂` above
    /// the assumed one); zero while `k̂ ≤ 0`.
    pub fn rest_height(&self) -> f64 {
        match self.rls.estimate[0] > 0.0 {
            true => self.rls.estimate[2] / self.rls.estimate[0],
            false => 0.0,
        }
    }

    /// The covariance `P` of `[k; b; k δ]`.
    pub fn covariance(&self) -> SMatrix<f64, 3, 3> {
        self.rls.covariance
    }

    /// A new landing: the covariance back to `P₀`, `θ̂ = k δ` back to zero; `k̂`, `b̂` kept.
    pub fn touch_down(&mut self) {
        self.rls.covariance = self.rls.reset_covariance;
        self.rls.estimate[2] = 0.0;
    }

    /// One RLS step (as [`GroundEstimator::update`]) with the regressor `[𝒴, l w |c| e₃]` (6 × 3:
    /// [`crate::SoleGeometry::regressor`] and [`crate::SoleGeometry::rest_height_column`]).
    pub fn update(&mut self, regressor: &Matrix6x3<f64>, wrench: &Vector6<f64>) -> bool {
        self.rls.update(regressor, wrench)
    }
}
