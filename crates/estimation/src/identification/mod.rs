//! Inertial-parameter identification with physical consistency [Traversaro 2017, ch. 6–7].
//!
//! The measurements are linear in the inertial parameters: each row is `y ψ + e x = z` with `y` a row of a
//! regressor of stride-model (the rigid-body regressor (6.6)–(6.7), the inverse-dynamics regressor (7.1),
//! (7.5) or the FT-sensor regressor (7.2)–(7.3)), ψ the `π = [m; m c; vech(I_B)]` of every body and `x`
//! extra linear unknowns (joint friction, sensor offsets). [`IdentificationData`] folds the rows into a
//! triangular factor; then
//!
//! * [`identify_on_manifold`]: the fully consistent estimate (6.24)–(6.27), optimised over
//!   θ = (m, c, Q, L) ∈ 𝔓 per body so that every iterate is a physical body (Theorem 6.1), pulled weakly
//!   towards a prior (the URDF) in the directions the data do not determine;
//! * [`identify_unconstrained`]: the classical least squares (6.19) for comparison, which on poorly
//!   exciting data gives non-physical bodies (the thesis's Table 6.1).
//!
//! This lives in stride-estimation rather than a crate of its own because it shares the batched least
//! squares of [`crate::calibration`] and is, like the calibration, estimation from logged data; it only
//! needs stride-model's regressors and parametrisation. `docs/identification.md` has the figures and
//! `stride identify`, the command that runs it on logs.

mod chart;
mod data;
mod error;
mod manifold;
mod unconstrained;

pub use chart::{chart_jacobian, nearest_physical, retract, ChartJacobian};
pub use data::{IdentificationData, ReducedData};
pub use error::IdentificationError;
pub use manifold::{identify_on_manifold, ManifoldEstimate, ManifoldOptions, Prior};
pub use unconstrained::{identify_unconstrained, UnconstrainedEstimate};
