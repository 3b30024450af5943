//! Linear inverted pendulum (LIPM) and divergent component of motion (DCM) utilities
//! [Romualdi 2022, ch. 4; Kajita 2001; Englsberger 2015].
//!
//! All quantities are planar (x, y in the world frame); the CoM height above the ground is constant.
//! With `ω = sqrt(g / h)` (the thesis' ζ, a natural frequency in s⁻¹):
//!
//! * CoM dynamics [Romualdi 2022, eq. 4.1.5]: `ẍ = ω² (x − p)` with `p` the ZMP;
//! * DCM [Romualdi 2022, eq. 4.4.2] with `b = 1/ω`: `ξ = x + ẋ / ω`;
//! * [Romualdi 2022, eq. 4.4.14]: `ẋ = −ω (x − ξ)` and `ξ̇ = ω (ξ − p)`, hence `p = ξ − ξ̇ / ω` (the thesis prints
//!   `ξ − ω ξ̇` in [Romualdi 2022, eq. 10.1.20]; the consistent sign and scaling is `ξ − ξ̇/ω`).

use nalgebra::{Matrix2, Vector2};

use crate::error::{check_finite, check_finite2, check_positive, Result, SimplifiedError};

/// Natural frequency `ω = sqrt(g / h)` \[s⁻¹\] of the LIPM.
///
/// | parameter | unit | meaning |
/// |---|---|---|
/// | `com_height` | m | constant CoM height above the ZMP plane, > 0 |
/// | `gravity` | m/s² | magnitude of gravity, > 0 |
///
/// Errors with `InvalidParameter` when either is not finite and positive.
pub fn natural_frequency(com_height: f64, gravity: f64) -> Result<f64> {
    check_positive("com_height", com_height)?;
    check_positive("gravity", gravity)?;
    Ok((gravity / com_height).sqrt())
}

/// DCM `ξ = x + ẋ / ω` \[m\] from the planar CoM position \[m\] and velocity \[m/s\].
pub fn dcm_from_com(
    com_position: Vector2<f64>,
    com_velocity: Vector2<f64>,
    omega: f64,
) -> Vector2<f64> {
    com_position + com_velocity / omega
}

/// ZMP `p = ξ − ξ̇ / ω` \[m\] that realises the DCM velocity `ξ̇` \[m/s\] at DCM `ξ` \[m\] (from [Romualdi 2022, eq. 4.4.14b]).
pub fn zmp_from_dcm(dcm: Vector2<f64>, dcm_velocity: Vector2<f64>, omega: f64) -> Vector2<f64> {
    dcm - dcm_velocity / omega
}

/// DCM velocity `ξ̇ = ω (ξ − p)` \[m/s\] produced by the ZMP `p` [Romualdi 2022, eq. 4.4.14b].
pub fn dcm_velocity(dcm: Vector2<f64>, zmp: Vector2<f64>, omega: f64) -> Vector2<f64> {
    omega * (dcm - zmp)
}

/// Exact discretization of the planar LIPM for a zero-order-hold ZMP over a step of any length `dt`.
///
/// Per axis, with state `[x; ẋ]` and input `p` held constant over the step:
/// `[x; ẋ]⁺ = A [x; ẋ] + B p`, `A = [[cosh ωdt, sinh ωdt / ω], [ω sinh ωdt, cosh ωdt]]`,
/// `B = [1 − cosh ωdt; −ω sinh ωdt]`; for the DCM [Romualdi 2022, eq. 10.2.19]: `ξ⁺ = F ξ + G p`, `F = e^{ω dt}`,
/// `G = 1 − e^{ω dt}`. `dt` may be zero or negative (backward propagation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LipmDiscretization {
    omega: f64,
    dt: f64,
    cosh: f64,
    sinh: f64,
    exp: f64,
}

impl LipmDiscretization {
    /// Builds the discretization for natural frequency `omega` \[s⁻¹\] (> 0) and step `dt` \[s\] (finite).
    pub fn new(omega: f64, dt: f64) -> Result<Self> {
        check_positive("omega", omega)?;
        if !dt.is_finite() {
            return Err(SimplifiedError::InvalidParameter {
                name: "dt",
                value: dt,
                reason: "must be finite",
            });
        }
        let wt = omega * dt;
        Ok(Self {
            omega,
            dt,
            cosh: wt.cosh(),
            sinh: wt.sinh(),
            exp: wt.exp(),
        })
    }

    /// Natural frequency \[s⁻¹\].
    pub fn omega(&self) -> f64 {
        self.omega
    }

    /// Step length \[s\].
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Per-axis state matrix `A` of `[x; ẋ]`.
    pub fn state_matrix(&self) -> Matrix2<f64> {
        Matrix2::new(
            self.cosh,
            self.sinh / self.omega,
            self.omega * self.sinh,
            self.cosh,
        )
    }

    /// Per-axis input vector `B` (effect of the held ZMP on `[x; ẋ]`).
    pub fn input_vector(&self) -> Vector2<f64> {
        Vector2::new(1.0 - self.cosh, -self.omega * self.sinh)
    }

    /// DCM transition `F = e^{ω dt}` (scalar, the same on both axes).
    pub fn dcm_transition(&self) -> f64 {
        self.exp
    }

    /// DCM input gain `G = 1 − e^{ω dt}`.
    pub fn dcm_input(&self) -> f64 {
        1.0 - self.exp
    }

    /// Propagates the planar CoM `(position, velocity)` over `dt` with the ZMP held at `zmp`.
    pub fn step_com(
        &self,
        position: Vector2<f64>,
        velocity: Vector2<f64>,
        zmp: Vector2<f64>,
    ) -> (Vector2<f64>, Vector2<f64>) {
        let d = position - zmp;
        let new_position = zmp + d * self.cosh + velocity * (self.sinh / self.omega);
        let new_velocity = d * (self.omega * self.sinh) + velocity * self.cosh;
        (new_position, new_velocity)
    }

    /// Propagates the DCM over `dt` with the ZMP held at `zmp`: `ξ⁺ = zmp + e^{ω dt}(ξ − zmp)`.
    pub fn step_dcm(&self, dcm: Vector2<f64>, zmp: Vector2<f64>) -> Vector2<f64> {
        zmp + (dcm - zmp) * self.exp
    }
}

/// Checks the inputs of the LIPM helpers used by the controllers; `omega` must be finite and > 0.
pub(crate) fn check_omega(omega: f64) -> Result<()> {
    check_finite("omega", omega)?;
    check_positive("omega", omega)
}

/// Checks that a planar vector is finite.
pub(crate) fn check_point(name: &'static str, v: &Vector2<f64>) -> Result<()> {
    check_finite2(name, v)
}
