//! DCM / ZMP / CoM plan as closed-form segments.
//!
//! Each segment `k` covers `[t0, t0 + T)` (the last one is unbounded) and has a ZMP that is a cubic
//! polynomial `Z(τ)` in local time τ = t − t0. The DCM is the exact solution of `ξ̇ = ω(ξ − Z)` [Romualdi 2022, eq. 10.1.15]:
//!
//! `ξ(τ) = P(τ) + c e^{ωτ}`, with `P = Z + Z'/ω + Z''/ω² + Z'''/ω³` (so that `P − P'/ω = Z`),
//!
//! and the CoM is the exact solution of `ẋ = −ω(x − ξ)` [Romualdi 2022, eq. 4.4.14a]:
//!
//! `x(τ) = Q(τ) + (c/2) e^{ωτ} + b e^{−ωτ}`, with `Q = Z + Z''/ω²` (so that `Q + Q'/ω = P`),
//!
//! hence `ẍ = ω²(x − Z)` holds exactly (LIPM). In single support Z is constant, `P = Z` and the DCM is the
//! thesis exponential [Romualdi 2022, eqs. 10.1.16, 10.1.18]. `c` comes from a backward pass (DCM at the segment end, as the
//! recursion [Romualdi 2022, eq. 10.1.17]), `b` from a forward pass (CoM continuity).

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};

/// Cubic polynomial coefficients (a0..a3) with 2D values.
pub type Cubic2 = [Vector2<f64>; 4];

fn eval_cubic(c: &Cubic2, t: f64) -> [Vector2<f64>; 3] {
    let p = ((c[3] * t + c[2]) * t + c[1]) * t + c[0];
    let v = (c[3] * (3.0 * t) + c[2] * 2.0) * t + c[1];
    let a = c[3] * (6.0 * t) + c[2] * 2.0;
    [p, v, a]
}

/// `P` coefficients from `Z` coefficients.
pub(crate) fn dcm_particular(z: &Cubic2, omega: f64) -> Cubic2 {
    let w = omega;
    [
        z[0] + z[1] / w + z[2] * (2.0 / (w * w)) + z[3] * (6.0 / (w * w * w)),
        z[1] + z[2] * (2.0 / w) + z[3] * (6.0 / (w * w)),
        z[2] + z[3] * (3.0 / w),
        z[3],
    ]
}

/// `Q` coefficients from `Z` coefficients.
pub(crate) fn com_particular(z: &Cubic2, omega: f64) -> Cubic2 {
    let w2 = omega * omega;
    [
        z[0] + z[2] * (2.0 / w2),
        z[1] + z[3] * (6.0 / w2),
        z[2],
        z[3],
    ]
}

/// One closed-form segment of the DCM plan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct DcmSegment {
    /// Start time \[s\].
    pub start: f64,
    /// Duration \[s\]; `None` for the final (standing) segment.
    pub duration: Option<f64>,
    /// ZMP cubic Z(τ).
    pub zmp: Cubic2,
    /// DCM particular part P(τ).
    pub dcm_poly: Cubic2,
    /// CoM particular part Q(τ).
    pub com_poly: Cubic2,
    /// Coefficient of the unstable exponential e^{ωτ} in the DCM.
    pub growth: Vector2<f64>,
    /// Coefficient of the stable exponential e^{−ωτ} in the CoM.
    pub decay: Vector2<f64>,
    /// Whether the segment restarts the DCM from a measured one (a step adjustment replanned from the
    /// measured DCM, [`crate::Planner::adjust_step_from`]): the DCM, its velocity and the CoM velocity
    /// may jump at its start (the CoM and the ZMP stay continuous).
    #[serde(default)]
    pub restart: bool,
}

/// Planar DCM/ZMP/CoM values at one instant.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct PlanarState {
    /// DCM position.
    pub dcm: Vector2<f64>,
    /// DCM velocity.
    pub dcm_velocity: Vector2<f64>,
    /// ZMP.
    pub zmp: Vector2<f64>,
    /// CoM position.
    pub com: Vector2<f64>,
    /// CoM velocity.
    pub com_velocity: Vector2<f64>,
    /// CoM acceleration.
    pub com_acceleration: Vector2<f64>,
}

impl DcmSegment {
    /// A segment starting at `start` \[s\] with ZMP cubic `zmp` (coefficients in local time); `growth` and
    /// `decay` start at zero and are set by the backward (DCM) and forward (CoM) passes.
    pub fn new(start: f64, duration: Option<f64>, zmp: Cubic2, omega: f64) -> Self {
        Self {
            start,
            duration,
            zmp,
            dcm_poly: dcm_particular(&zmp, omega),
            com_poly: com_particular(&zmp, omega),
            growth: Vector2::zeros(),
            decay: Vector2::zeros(),
            restart: false,
        }
    }

    /// The first quantity with a non-finite coefficient (`"start"`, `"zmp"`, `"dcm"` or `"com"`), if any.
    pub fn non_finite_quantity(&self) -> Option<&'static str> {
        let finite = |c: &[Vector2<f64>]| c.iter().all(|v| v.iter().all(|x| x.is_finite()));
        if !self.start.is_finite() {
            Some("start")
        } else if !finite(&self.zmp) {
            Some("zmp")
        } else if !finite(&self.dcm_poly) || !finite(&[self.growth]) {
            Some("dcm")
        } else if !finite(&self.com_poly) || !finite(&[self.decay]) {
            Some("com")
        } else {
            None
        }
    }

    /// End time (infinite for the last segment).
    pub fn end(&self) -> f64 {
        self.duration.map_or(f64::INFINITY, |d| self.start + d)
    }

    /// Evaluates at local time τ (clamped to \[0, duration\]; NaN is read as 0).
    pub fn evaluate_local(&self, tau: f64, omega: f64) -> PlanarState {
        let tau = if tau.is_nan() { 0.0 } else { tau };
        let tau = match self.duration {
            Some(d) => tau.clamp(0.0, d),
            // (the unbounded segment is constant after a few 1/ω; clamping keeps 0·∞ out of the polynomials)
            None => tau.clamp(0.0, 1.0e9),
        };
        let [z, _, _] = eval_cubic(&self.zmp, tau);
        let [p, dp, _] = eval_cubic(&self.dcm_poly, tau);
        let [q, dq, ddq] = eval_cubic(&self.com_poly, tau);
        // e^{ωτ} only multiplies `growth`, which is exactly zero on the unbounded last segment.
        let grow = if self.growth == Vector2::zeros() {
            0.0
        } else {
            (omega * tau).exp()
        };
        let decay = (-omega * tau).exp();
        let g = self.growth * grow;
        let b = self.decay * decay;
        PlanarState {
            dcm: p + g,
            dcm_velocity: dp + g * omega,
            zmp: z,
            com: q + g * 0.5 + b,
            com_velocity: dq + g * (0.5 * omega) - b * omega,
            com_acceleration: ddq + g * (0.5 * omega * omega) + b * (omega * omega),
        }
    }

    /// The `growth` coefficient that makes the DCM reach `dcm_end` at the end of the segment (zero for the
    /// unbounded segment): the backward recursion [Romualdi 2022, eq. 10.1.17].
    pub fn growth_for_end_dcm(&self, dcm_end: Vector2<f64>, omega: f64) -> Vector2<f64> {
        match self.duration {
            Some(d) => {
                let [p_end, _, _] = eval_cubic(&self.dcm_poly, d);
                (dcm_end - p_end) * (-omega * d).exp()
            }
            None => Vector2::zeros(),
        }
    }

    /// DCM at τ = 0 given the growth coefficient.
    pub fn dcm_start(&self) -> Vector2<f64> {
        self.dcm_poly[0] + self.growth
    }

    /// Sets `decay` so that the CoM at τ = 0 equals `com_start`.
    pub fn set_com_start(&mut self, com_start: Vector2<f64>) {
        self.decay = com_start - self.com_poly[0] - self.growth * 0.5;
    }
}

/// ZMP cubic moving from `a` to `b` over `duration` with the smooth step 3u² − 2u³ (zero ZMP velocity at both
/// ends), plus `bump` times u(1 − u)² (zero at both ends, used to meet an initial DCM condition).
pub(crate) fn zmp_transition(
    a: Vector2<f64>,
    b: Vector2<f64>,
    bump: Vector2<f64>,
    duration: f64,
) -> Cubic2 {
    let t = duration;
    let d = b - a;
    [
        a,
        bump / t,
        d * (3.0 / (t * t)) - bump * (2.0 / (t * t)),
        d * (-2.0 / (t * t * t)) + bump / (t * t * t),
    ]
}

/// Constant ZMP.
pub(crate) fn zmp_constant(a: Vector2<f64>) -> Cubic2 {
    [a, Vector2::zeros(), Vector2::zeros(), Vector2::zeros()]
}

/// Scalar cubic helpers for the bump u(1 − u)²: coefficient vector in τ.
pub(crate) fn bump_coefficients(duration: f64) -> [f64; 4] {
    let t = duration;
    [0.0, 1.0 / t, -2.0 / (t * t), 1.0 / (t * t * t)]
}

/// Scalar version of [`dcm_particular`].
pub(crate) fn dcm_particular_scalar(z: &[f64; 4], omega: f64) -> [f64; 4] {
    let w = omega;
    [
        z[0] + z[1] / w + 2.0 * z[2] / (w * w) + 6.0 * z[3] / (w * w * w),
        z[1] + 2.0 * z[2] / w + 6.0 * z[3] / (w * w),
        z[2] + 3.0 * z[3] / w,
        z[3],
    ]
}

/// Scalar cubic value.
pub(crate) fn eval_cubic_scalar(c: &[f64; 4], t: f64) -> f64 {
    ((c[3] * t + c[2]) * t + c[1]) * t + c[0]
}

/// Planar value of a cubic at τ (used by the planner).
pub(crate) fn eval_cubic_value(c: &Cubic2, t: f64) -> Vector2<f64> {
    eval_cubic(c, t)[0]
}
