//! Inertial parameters for identification [Traversaro 2017, ch. 6–7]: the rigid-body regressor, the
//! whole-robot parameter vector ψ, base parameters (the identifiable subspace), physical-consistency checks
//! and the fully consistent parametrisation θ = (m, c, Q, L).
//!
//! The whole-robot regressors are methods of [`KinDyn`](crate::KinDyn):
//! [`inverse_dynamics_regressor`](crate::KinDyn::inverse_dynamics_regressor) (the floating-base and
//! joint-torque regressor, eqs. 7.1, 7.5) and [`ft_sensor_regressor`](crate::KinDyn::ft_sensor_regressor)
//! (what the force/torque sensors measure, eqs. 7.2–7.3). See `docs/identification.md`.
//!
//! ## Parameter layouts
//!
//! * **Body layout** (10·N, N = [`Model::body_count`](crate::Model::body_count)): block `b` (entries
//!   `10b .. 10b + 10`) is `π = [m; m c; vech(I_B)]` ([`InertialParameters`]) of model body `b`
//!   ([`Model::bodies`](crate::Model::bodies)) in its own frame. Model bodies are LUMPED: a body holds
//!   every URDF link attached to it through fixed joints, so these are the lumped body's parameters.
//! * **FT-split layout** (10·(N + S), S force/torque sensors): a sensor's fixed joint lies inside one lumped
//!   body (its host). Block `b < N` is body `b` without the child-side links of the sensor it hosts; block
//!   `N + k` is the child-side part of sensor `k`'s host (the links between the sensor's joint and the next
//!   movable joints), in the host's frame. [`Model::merge_ft_split_parameters`](crate::Model::merge_ft_split_parameters)
//!   sums them back.

mod base_parameters;
mod consistency;
mod parameters;
mod parametrisation;
mod rigid_body;

pub use base_parameters::{
    stacked_inverse_dynamics_regressor, BaseParameters, DEFAULT_RANK_TOLERANCE,
};
pub use consistency::{
    check_consistency, check_full_consistency, mass_com_inertia, principal_moments, second_moments,
    triangle_inequality_violation, BodyInertiaViolation, InertiaViolation,
};
pub use parametrisation::PhysicalParameters;
pub use rigid_body::{
    inertia_about_origin, inertial_parameters, momentum_regressor, rigid_body_regressor,
    sensor_regressor, spatial_inertia, transform_parameters, vech, InertialParameters,
    RigidBodyRegressor,
};
