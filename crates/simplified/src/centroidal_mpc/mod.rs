//! The centroidal MPC with footstep adjustment [Romualdi 2022, ch. 11; Romualdi et al. 2022].
//!
//! Prediction model: the centroidal dynamics with the contact wrenches as pure forces at the four sole
//! corners (11.1.4), forward Euler over `N` stages of `dt` (11.1.15b–c); the contact schedule Γ_i comes
//! from the plan; the positions of the contacts that start inside the horizon are decision variables in
//! a box around the planned ones (11.1.14); friction cones (11.1.13) are linearised as the square
//! pyramid inscribed in the Coulomb cone, written as a conic combination of four generators per corner
//! (so the cone is a simple bound `λ ⪰ 0`). Objective (11.1.15a): CoM tracking of the plan's CoM, zero
//! angular momentum, corner forces close to their contact's average (11.1.6, the average form — the
//! printed (11.1.7) contradicts it), force rate (11.1.8), contact displacement (11.1.12).
//!
//! Solver: a real-time iteration [Diehl 2005] — one QP per tick, the bilinear torque term linearised
//! about the previous solution shifted in time, states condensed out, solved by stride-qp's
//! Goldfarb–Idnani active-set solver warm-started from the previous active set of the same size.
//! The thesis solved the full NLP with IPOPT (§11.1.4).

#[path = "../centroidal_mpc_config.rs"]
mod config;
mod cost;
mod dynamics;
mod io;
mod layout;
mod linearization;
mod mpc;
mod step;
#[cfg(test)]
mod tests;

pub use config::{CentroidalMpcConfig, Interval, MAX_CENTROIDAL_STAGES};
pub use io::{
    AdjustedContact, CentroidalMpcDiagnostics, CentroidalMpcInput, CentroidalMpcOutput,
    CentroidalState, ComReference, MpcContact, MAX_MPC_CONTACTS,
};
pub use mpc::{CentroidalMpc, FootCornerForces};
