//! `stride-simplified`: the simplified-model control layer [Romualdi 2022, ch. 4 and §10.2.3].
//!
//! It keeps the robot's divergent component of motion (DCM) on the plan by choosing a desired ZMP, and
//! turns that into CoM references for the whole-body layer:
//!
//! ```text
//! plan (DCM, ZMP, CoM) + measured (DCM, ZMP, CoM) ─► DCM controller ─► desired ZMP ─► ZMP-CoM ─► CoM refs
//!                                                   (instantaneous PI      (gains scheduled
//!                                                    or predictive MPC)     walk/stand)
//! ```
//!
//! The instantaneous PI law is [Romualdi 2022, eq. 10.2.17], the predictive MPC
//! [Romualdi 2022, eq. 10.2.23], the ZMP-CoM controller [Romualdi 2022, eq. 10.2.25].
//!
//! # What the runner uses
//!
//! * [`SimplifiedConfig`] (serde, `deny_unknown_fields`, every field optional with iCub-like defaults):
//!   `dcm_controller = "instantaneous" | "predictive"`, sections `[instantaneous]` (`kp`, `ki`,
//!   `integral_limit`), `[predictive]` (`horizon` = 2 s, `dcm_weight`, `zmp_rate_weight`,
//!   `zmp_rate_reference`, `solver`, `tolerance`, `max_iterations`), `[zmp_com]` (`walking`/`standing`
//!   `{k_zmp, k_com}`, `transition_time` of the minimum-jerk gain blend).
//! * [`SimplifiedController::new`]`(&config, period)` builds the layer for its tick period (the MPC stage
//!   length is that period). It implements [`stride_block::Block`] with
//!   * `Input` = [`SimplifiedInput`]: time, `omega` (= [`natural_frequency`] of the plan's CoM height),
//!     `walking` flag, planned DCM position/velocity, ZMP, CoM position/velocity at the current time,
//!     measured CoM position/velocity, DCM ([`dcm_from_com`]) and ZMP ([`measured_zmp`]), the current
//!     [`SupportPolygon`] ([`feet_support_polygon`]: hull of the feet in contact) and, for the MPC only,
//!     a [`DcmHorizon`]: `clear()` then `push(HorizonSample { dcm_position, zmp, support })` for
//!     `k = 0..=N` at times `t + k·period` ([`SimplifiedController::horizon_samples`] = `N + 1`; build the
//!     input with [`SimplifiedInput::new`]`(controller.horizon_samples(), polygon)`, no allocation after).
//!   * `Output` = [`SimplifiedOutput`]: desired ZMP (always inside the support polygon), CoM position,
//!     velocity and acceleration references, and [`SimplifiedDiagnostics`] (DCM error, integral term,
//!     projection flag, gains, MPC status/iterations/solve time, and `solve_time`: the wall-clock time
//!     of the tick of whichever DCM controller runs, PI or MPC, plus the ZMP-CoM controller).
//! * **Bad input**: a non-finite input or an empty horizon returns an error and changes nothing; [`SimplifiedController::output`] keeps the last valid references (hold them). Support
//!   polygons are validated when built ([`SupportPolygon::convex_hull`] rejects empty/degenerate sets),
//!   so an invalid polygon cannot reach `step`. A horizon shorter than `N + 1` samples (plan ending) is
//!   padded by holding its last sample (reported as `held_samples`). If the MPC's QP fails (seen only
//!   once the DCM has left the support polygon, i.e. the robot cannot be captured any more) the desired
//!   ZMP comes from a documented fallback law and `diagnostics.mpc.fallback` is set (or, with
//!   `predictive.fallback = false`, `SolverFailed` is returned). No output is ever NaN.
//!
//! # Helpers
//!
//! [`natural_frequency`], [`dcm_from_com`], [`zmp_from_dcm`] (`p = ξ − ξ̇/ω`; the thesis prints `ξ − ω ξ̇`, see [`zmp_from_dcm`]),
//! [`dcm_velocity`], [`LipmDiscretization`] (exact ZOH LIPM/DCM transition for any `dt`),
//! [`measured_zmp`] (global ZMP from the feet wrenches), [`SupportPolygon`] (hull, point-in-polygon,
//! projection, half-planes), [`FootRectangle`] and [`feet_support_polygon`].
//!
//! # Step adjustment
//!
//! [`StepAdjuster`] (config [`StepAdjustmentConfig`], section `[step_adjustment]`, off by default): the
//! next touch-down position and the step duration from the measured DCM, a 7-variable QP after
//! [Khadiv 2020] solved by stride-qp's active-set solver without allocation. The runner calls it during
//! single support and retargets the swing foot.
//!
//! # Push estimate
//!
//! [`PushObserver`] (config [`PushConfig`], section `[push]`, off by default): the horizontal external
//! force from a linear-momentum observer (measured contact forces against the measured CoM velocity);
//! [`push_zmp_offset`] is its LIPM ZMP offset `F/(m ω²)`. The runner holds the double support while it is
//! large and gives it to the step adjustment.
//!
//! # Centroidal MPC
//!
//! [`CentroidalMpc`] (config [`CentroidalMpcConfig`]): the reduced-model layer of [Romualdi 2022, ch. 11]
//! — centroidal dynamics with forces at the sole corners, linearised friction cones, the positions of the
//! contacts that start inside the horizon as decision variables in a box around the planned ones — as a
//! real-time iteration (one active-set QP per tick, linearised about the previous solution). A
//! [`stride_block::Block`] with [`CentroidalMpcInput`] (measured centroidal state, contact schedule,
//! nominal CoM per stage) and [`CentroidalMpcOutput`] (predicted centroidal states, adjusted contacts,
//! first-stage forces and ZMP).
//!
//! The individual controllers are usable alone: [`DcmInstantaneousController`],
//! [`DcmPredictiveController`], [`ZmpComController`]; the bare laws [`dcm_instantaneous_law`] and
//! [`zmp_com_law`] are exposed for analysis.

mod block;
mod centroidal_mpc;
mod dcm_instantaneous;
mod dcm_predictive;
mod error;
mod foot_admittance;
mod lipm;
mod push_observer;
mod step_adjustment;
mod wrench;
mod zmp_com;

pub use block::{
    DcmControllerKind, SimplifiedConfig, SimplifiedController, SimplifiedDiagnostics,
    SimplifiedInput, SimplifiedOutput, PLACEHOLDER_OMEGA,
};
pub use centroidal_mpc::{
    AdjustedContact, CentroidalMpc, CentroidalMpcConfig, CentroidalMpcDiagnostics,
    CentroidalMpcInput, CentroidalMpcOutput, CentroidalState, ComReference, FootCornerForces,
    Interval, MpcContact, MAX_CENTROIDAL_STAGES, MAX_MPC_CONTACTS,
};
pub use dcm_instantaneous::{
    dcm_instantaneous_law, DcmInstantaneousConfig, DcmInstantaneousController,
    DcmInstantaneousOutput,
};
pub use dcm_predictive::{
    DcmHorizon, DcmPredictiveConfig, DcmPredictiveController, DcmPredictiveOutput, HorizonSample,
    MpcDiagnostics, MpcProblemView, MpcSolverKind, MpcStatus, ZmpRateReference,
};
pub use error::{Result, SimplifiedError};
pub use foot_admittance::{
    ankle_torque_error, distribute_zmp, leaky_admittance, right_foot_share, FootAdmittance,
    FootAdmittanceConfig, FootAdmittanceInput, FootAdmittanceOutput, FootCorrection,
    MIN_ADMITTANCE_LOAD,
};
pub use lipm::{dcm_from_com, dcm_velocity, natural_frequency, zmp_from_dcm, LipmDiscretization};
pub use push_observer::{push_zmp_offset, PushConfig, PushObserver};
pub use step_adjustment::{
    StepAdjuster, StepAdjustment, StepAdjustmentConfig, StepAdjustmentDiagnostics,
    StepAdjustmentInput, StepAdjustmentStatus, STEP_ADJUSTMENT_VARIABLES,
};
pub use stride_block::{
    feet_support_polygon, Block, Foot, FootRectangle, PolygonError, SupportPolygon,
    MAX_HULL_POINTS, MAX_POLYGON_VERTICES, MIN_POLYGON_AREA,
};
pub use wrench::{measured_zmp, FootWrench};
pub use zmp_com::{
    minimum_jerk_blend, zmp_com_law, ZmpComConfig, ZmpComController, ZmpComGains, ZmpComOutput,
};

/// What a user of the simplified layer needs in scope: `use stride_simplified::prelude::*;`.
pub mod prelude {
    pub use crate::{
        feet_support_polygon, Block, CentroidalMpc, CentroidalMpcInput, CentroidalMpcOutput,
        DcmControllerKind, Foot, FootRectangle, HorizonSample, MpcStatus, SimplifiedConfig,
        SimplifiedController, SimplifiedDiagnostics, SimplifiedError, SimplifiedInput,
        SimplifiedOutput, StepAdjuster, StepAdjustmentInput, StepAdjustmentStatus, SupportPolygon,
    };
    pub use nalgebra;
    pub use stride_qp::QpStatus;
}
