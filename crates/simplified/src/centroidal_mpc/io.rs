//! Data-only input and output of the centroidal MPC.

use std::time::Duration;

use nalgebra::{Vector2, Vector3};
use serde::{Deserialize, Serialize};

use crate::error::{Result, SimplifiedError};
use stride_block::Foot;

/// Most contacts one input can list (both feet's current and next contacts over a horizon).
pub const MAX_MPC_CONTACTS: usize = 8;

/// One planned contact of the schedule (plain data; world frame, SI units).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MpcContact {
    /// Which foot makes the contact.
    pub foot: Foot,
    /// Planned sole position `p_iⁿ` (centre of the adjustment box) \[m\].
    pub position: Vector3<f64>,
    /// Sole yaw about world z \[rad\] (the feet are flat on the ground).
    pub yaw: f64,
    /// Activation time \[s\].
    pub activation: f64,
    /// Deactivation time \[s\] (`f64::INFINITY` for the last contact).
    pub deactivation: f64,
}

impl MpcContact {
    /// A sole at `(x, y)` on the ground plane `z = 0`, heading along world x (yaw 0), active over
    /// `[activation, deactivation)` \[m, s\].
    pub fn level(foot: Foot, x: f64, y: f64, activation: f64, deactivation: f64) -> Self {
        Self {
            foot,
            position: Vector3::new(x, y, 0.0),
            yaw: 0.0,
            activation,
            deactivation,
        }
    }
}

/// Everything one MPC tick needs (plain data; build once with [`CentroidalMpcInput::new`] and refill).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CentroidalMpcInput {
    /// Current time; `t₀ = stride_block::seconds(time)` in the plan time of the contact times \[s\].
    pub time: Duration,
    /// Measured CoM \[m\].
    pub com_position: Vector3<f64>,
    /// Measured CoM velocity `h^p/m` \[m/s\].
    pub com_velocity: Vector3<f64>,
    /// Measured angular momentum about the CoM `h^ω` \[kg m²/s\].
    pub angular_momentum: Vector3<f64>,
    /// Known external force on the robot during the first `external_force_stages` stages
    /// [Romualdi 2022, eq. 11.2.1] \[N\].
    pub external_force: Vector3<f64>,
    /// Half length of the sole rectangle (corners at `±a` along the sole x axis) \[m\].
    pub foot_half_length: f64,
    /// Half width of the sole rectangle (corners at `±b` along the sole y axis) \[m\].
    pub foot_half_width: f64,
    /// The contact schedule over the horizon: [`CentroidalMpcInput::push_contact`].
    pub contacts: Vec<MpcContact>,
    /// Nominal CoM `x_CoMⁿ` at `t₀ + k·dt`, `k = 0..=N` (missing samples hold the last one) \[m\].
    pub com_reference: Vec<Vector3<f64>>,
}

impl CentroidalMpcInput {
    /// An input with room for `stages + 1` CoM samples and [`MAX_MPC_CONTACTS`] contacts.
    pub fn new(stages: usize) -> Self {
        Self {
            time: Duration::ZERO,
            com_position: Vector3::zeros(),
            com_velocity: Vector3::zeros(),
            angular_momentum: Vector3::zeros(),
            external_force: Vector3::zeros(),
            foot_half_length: 0.05,
            foot_half_width: 0.025,
            contacts: Vec::with_capacity(MAX_MPC_CONTACTS),
            com_reference: Vec::with_capacity(stages + 1),
        }
    }

    /// Appends a contact; an error when [`MAX_MPC_CONTACTS`] are already listed.
    pub fn push_contact(&mut self, contact: MpcContact) -> Result<()> {
        if self.contacts.len() >= MAX_MPC_CONTACTS {
            return Err(SimplifiedError::TooManyContacts {
                count: self.contacts.len() + 1,
                reason: "more than MAX_MPC_CONTACTS listed",
            });
        }
        self.contacts.push(contact);
        Ok(())
    }

    /// `t₀`, the input's time in seconds \[s\].
    pub(crate) fn t0(&self) -> f64 {
        stride_block::seconds(self.time)
    }

    /// The nominal CoM of stage `k` (the last sample held past the end).
    pub(crate) fn reference(&self, k: usize) -> Vector3<f64> {
        self.com_reference
            .get(k)
            .or(self.com_reference.last())
            .copied()
            .unwrap_or(self.com_position)
    }

    /// Finite numbers, positive foot sizes, ordered contact times, at least one CoM sample.
    pub(crate) fn validate(&self) -> Result<()> {
        let vectors = [
            ("com_position", &self.com_position),
            ("com_velocity", &self.com_velocity),
            ("angular_momentum", &self.angular_momentum),
            ("external_force", &self.external_force),
        ];
        for (name, v) in vectors {
            if !v.iter().all(|x| x.is_finite()) {
                return Err(SimplifiedError::NonFiniteInput { name });
            }
        }
        crate::error::check_positive("foot_half_length", self.foot_half_length)?;
        crate::error::check_positive("foot_half_width", self.foot_half_width)?;
        for c in &self.contacts {
            if !(c.position.iter().all(|x| x.is_finite()) && c.yaw.is_finite()) {
                return Err(SimplifiedError::NonFiniteInput {
                    name: "contacts.position",
                });
            }
            if !(c.activation.is_finite() && c.deactivation > c.activation) {
                return Err(SimplifiedError::InvalidParameter {
                    name: "contacts.deactivation",
                    value: c.deactivation,
                    reason: "must be later than the activation time",
                });
            }
        }
        if self.com_reference.is_empty() {
            return Err(SimplifiedError::EmptyHorizon);
        }
        if !self
            .com_reference
            .iter()
            .all(|v| v.iter().all(|x| x.is_finite()))
        {
            return Err(SimplifiedError::NonFiniteInput {
                name: "com_reference",
            });
        }
        Ok(())
    }
}

/// The predicted centroidal state of one stage.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct CentroidalState {
    /// CoM \[m\].
    pub com_position: Vector3<f64>,
    /// CoM velocity `h^p/m` \[m/s\].
    pub com_velocity: Vector3<f64>,
    /// Angular momentum about the CoM \[kg m²/s\].
    pub angular_momentum: Vector3<f64>,
}

/// A contact of the input after the MPC: where it will be.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AdjustedContact {
    /// The input contact (planned position, times).
    pub planned: MpcContact,
    /// Adjusted sole position `p_i` \[m\] (= planned when not adjustable).
    pub position: Vector3<f64>,
    /// Whether its position was a decision variable of this tick.
    pub adjustable: bool,
    /// Whether a side of its box (11.1.14) is active at the solution.
    pub bound_active: bool,
}

/// Diagnostics of one MPC tick.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct CentroidalMpcDiagnostics {
    /// Status of the QP.
    pub status: stride_qp::QpStatus,
    /// Active-set iterations.
    pub iterations: usize,
    /// Decision variables of the QP (cone coordinates + contact displacements).
    pub variables: usize,
    /// Whether the solver reused the previous active set.
    pub warm_started: bool,
    /// Wall-clock time of the tick (assembly + solve) \[s\].
    pub solve_time: f64,
    /// Largest gap between the linearised prediction of `h^ω` and the bilinear model (11.1.4) evaluated
    /// at the solution \[kg m²/s\] (zero once the real-time iteration has converged).
    pub linearization_gap: f64,
}

/// What one MPC tick produces.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct CentroidalMpcOutput {
    /// Time `t₀` of the input \[s\].
    pub time: f64,
    /// False until the first successful tick.
    pub valid: bool,
    /// Stage length `dt` \[s\].
    pub stage_duration: f64,
    /// Predicted states at `t₀ + k·dt`, `k = 0..=N`.
    pub predicted: Vec<CentroidalState>,
    /// The input's contacts, adjusted (same order).
    pub contacts: Vec<AdjustedContact>,
    /// Total contact force of each foot (left, right) during the first stage \[N\].
    pub foot_forces: [Vector3<f64>; 2],
    /// ZMP of the first stage's corner forces (`Σ f_z p / Σ f_z` over the corners) \[m\].
    pub desired_zmp: Vector2<f64>,
    /// Diagnostics.
    pub diagnostics: CentroidalMpcDiagnostics,
}

/// CoM position, velocity and acceleration references at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ComReference {
    /// \[m\]
    pub position: Vector3<f64>,
    /// \[m/s\]
    pub velocity: Vector3<f64>,
    /// \[m/s²\]
    pub acceleration: Vector3<f64>,
    /// Angular momentum \[kg m²/s\].
    pub angular_momentum: Vector3<f64>,
}

impl CentroidalMpcOutput {
    /// The prediction at time `t` \[s\]: position and velocity interpolated linearly between the stages,
    /// acceleration the stage's `(v[k+1] − v[k])/dt` (clamped to the horizon).
    pub fn reference_at(&self, t: f64) -> ComReference {
        let n = self.predicted.len();
        if n < 2 || self.stage_duration <= 0.0 {
            return ComReference::default();
        }
        let s = ((t - self.time) / self.stage_duration).clamp(0.0, (n - 1) as f64);
        let k = (s.floor() as usize).min(n - 2);
        let a = s - k as f64;
        let (p, q) = (&self.predicted[k], &self.predicted[k + 1]);
        ComReference {
            position: p.com_position.lerp(&q.com_position, a),
            velocity: p.com_velocity.lerp(&q.com_velocity, a),
            acceleration: (q.com_velocity - p.com_velocity) / self.stage_duration,
            angular_momentum: p.angular_momentum.lerp(&q.angular_momentum, a),
        }
    }

    /// The first adjustable contact (the next touch-down), if any.
    pub fn next_adjusted(&self) -> Option<&AdjustedContact> {
        self.contacts.iter().find(|c| c.adjustable)
    }
}
