//! The ground estimate of TSID-Compliant (`[wbc.tsid.compliant] estimate_ground`): one recursive
//! least-squares estimator of `π = [k; b]` per contact [Romualdi 2022, §8.2.3, eq. 8.2.20–8.2.22], fed with
//! its sole's measured wrench and the regressor of its pose and velocity relative to its touch-down rest
//! pose, its covariance reset at each of its touch-downs [Colman 2006], its estimate the ground of that
//! contact's model. One per contact, because on a ground whose compliance changes along the path the two
//! feet stand on different patches. With `estimate_rest_height` each estimate also has the rest height's
//! error as a third parameter ([`GroundRestEstimator`]); with `estimator_open_loop` the contact models keep
//! the prior; with `estimator_accept_std` a contact's model takes each parameter of its estimate only once
//! that parameter's standard deviation (from the covariance) is below that fraction of it, and the prior
//! from each planned touch-down until then (the gate). Allocates nothing after construction.

use nalgebra::{Matrix6x3, Vector6};

use crate::config::CompliantConfig;
use crate::error::WbcError;
use crate::soft_contact::{
    EstimatorSettings, GroundEstimator, GroundParameters, GroundRestEstimator,
};

/// One contact's estimator: `[k; b]`, or `[k; b; k δ]` with the rest height's error.
#[derive(Debug, Clone)]
enum Estimator {
    Ground(GroundEstimator),
    WithRestHeight(GroundRestEstimator),
}

impl Estimator {
    fn touch_down(&mut self) {
        match self {
            Estimator::Ground(e) => e.touch_down(),
            Estimator::WithRestHeight(e) => e.touch_down(),
        }
    }

    /// One step with the regressor `[𝒴, l w |c| e₃]` (the two-parameter estimate reads `𝒴`).
    fn update(&mut self, regressor: &Matrix6x3<f64>, wrench: &Vector6<f64>) {
        match self {
            Estimator::Ground(e) => e.update(&regressor.fixed_columns::<2>(0).into_owned(), wrench),
            Estimator::WithRestHeight(e) => e.update(regressor, wrench),
        };
    }

    fn estimate(&self) -> GroundParameters {
        match self {
            Estimator::Ground(e) => e.estimate(),
            Estimator::WithRestHeight(e) => e.estimate(),
        }
    }

    /// The variances of `k̂`, `b̂` (the covariance's first two diagonal entries).
    fn variances(&self) -> [f64; 2] {
        match self {
            Estimator::Ground(e) => {
                let p = e.covariance();
                [p[(0, 0)], p[(1, 1)]]
            }
            Estimator::WithRestHeight(e) => {
                let p = e.covariance();
                [p[(0, 0)], p[(1, 1)]]
            }
        }
    }
}

/// The per-contact ground estimates and the ground each contact's model uses.
#[derive(Debug, Clone)]
pub(crate) struct ContactGroundEstimates {
    estimators: Vec<Estimator>,
    /// Per contact: the estimate's positive components over the prior (logged; the ground of its
    /// contact model unless `open_loop` or the gate).
    grounds: Vec<GroundParameters>,
    /// Per contact: the ground its contact model uses (the prior with `open_loop`; with the gate the
    /// prior from its touch-down until a parameter is accepted).
    models: Vec<GroundParameters>,
    /// `estimator_accept_std`: the relative standard deviation below which a parameter of the estimate is
    /// accepted by the contact model; `None` (infinite): every estimate is.
    accept_std: Option<f64>,
    /// The configured ground (the prior).
    prior: GroundParameters,
    /// `estimator_open_loop`: the contact models keep `prior`.
    open_loop: bool,
    /// `estimator_reset`: reset a contact's covariance at its touch-down.
    reset_at_touch_down: bool,
    /// `estimator_contact_force`: the measured normal force (N) above which a sole is on the ground.
    contact_force: f64,
    /// Per contact: touched down in the plan, not yet on the ground (its normal force below `contact_force`).
    awaiting: Vec<bool>,
}

impl ContactGroundEstimates {
    /// `contacts` estimators at the prior `ground_stiffness`, `ground_damping` of `c` (their own size as
    /// standard deviation). Errors: the estimator's settings ([`GroundEstimator::new`]).
    pub fn new(c: &CompliantConfig, contacts: usize) -> Result<Self, WbcError> {
        let prior = GroundParameters {
            stiffness: c.ground_stiffness,
            damping: c.ground_damping,
        };
        let settings = EstimatorSettings {
            initial: prior,
            initial_std: [c.ground_stiffness, c.ground_damping],
            wrench_std: c.estimator_wrench_std,
        };
        let estimator = match c.estimate_rest_height {
            false => Estimator::Ground(GroundEstimator::new(&settings)?),
            true => Estimator::WithRestHeight(
                GroundRestEstimator::new(&settings, c.estimator_rest_height_std).map_err(|_| {
                    WbcError::InvalidConfig {
                        task: "<tsid>".into(),
                        key: "estimator_rest_height_std",
                        reason: format!(
                            "compliant.estimator_rest_height_std = {} must be finite and > 0",
                            c.estimator_rest_height_std
                        ),
                    }
                })?,
            ),
        };
        Ok(Self {
            estimators: vec![estimator; contacts],
            grounds: vec![prior; contacts],
            models: vec![prior; contacts],
            accept_std: match c.estimator_accept_std {
                f if f == f64::INFINITY => None,
                f if f.is_finite() && f > 0.0 => Some(f),
                f => {
                    return Err(WbcError::InvalidConfig {
                        task: "<tsid>".into(),
                        key: "estimator_accept_std",
                        reason: format!(
                            "compliant.estimator_accept_std = {f} must be > 0 (inf: off)"
                        ),
                    })
                }
            },
            prior,
            open_loop: c.estimator_open_loop,
            reset_at_touch_down: c.estimator_reset,
            contact_force: match c.estimator_contact_force {
                f if f.is_finite() && f >= 0.0 => f,
                f => {
                    return Err(WbcError::InvalidConfig {
                        task: "<tsid>".into(),
                        key: "estimator_contact_force",
                        reason: format!(
                            "compliant.estimator_contact_force = {f} must be finite and >= 0"
                        ),
                    })
                }
            },
            awaiting: vec![false; contacts],
        })
    }

    /// Contact `c` touched down in the plan: its estimate waits for the sole to meet the ground; with the
    /// gate (`estimator_accept_std`) its model returns to the prior until the new landing's estimate is
    /// accepted.
    pub fn touch_down(&mut self, c: usize) {
        self.awaiting[c] = true;
        if self.accept_std.is_some() && !self.open_loop {
            self.models[c] = self.prior;
        }
    }

    /// The measured normal force above which a sole is on the ground, N.
    pub fn contact_force(&self) -> f64 {
        self.contact_force
    }

    /// Whether contact `c` touched down in the plan and its sole has not met the ground yet.
    pub fn awaiting(&self, c: usize) -> bool {
        self.awaiting[c]
    }

    /// One RLS step of contact `c` with its sole's regressor and measured wrench (its sole on the ground);
    /// its model's ground takes the estimate's positive components (with the gate, each one whose standard
    /// deviation is below `estimator_accept_std` of it). The first step after a touch-down resets the
    /// covariance to `P₀` (with `estimator_reset`), keeping the estimate [Colman 2006].
    pub fn update(&mut self, c: usize, regressor: &Matrix6x3<f64>, wrench: &Vector6<f64>) {
        if std::mem::take(&mut self.awaiting[c]) && self.reset_at_touch_down {
            self.estimators[c].touch_down();
        }
        let e = &mut self.estimators[c];
        e.update(regressor, wrench);
        let estimate = e.estimate();
        let g = &mut self.grounds[c];
        if estimate.stiffness > 0.0 {
            g.stiffness = estimate.stiffness;
        }
        if estimate.damping > 0.0 {
            g.damping = estimate.damping;
        }
        if self.open_loop {
            return;
        }
        let model = &mut self.models[c];
        match self.accept_std {
            None => *model = *g,
            Some(bound) => {
                let [var_k, var_b] = e.variances();
                if estimate.stiffness > 0.0 && var_k.sqrt() <= bound * estimate.stiffness {
                    model.stiffness = estimate.stiffness;
                }
                if estimate.damping > 0.0 && var_b.sqrt() <= bound * estimate.damping {
                    model.damping = estimate.damping;
                }
            }
        }
    }

    /// The ground of contact `c`'s model: its estimate, the prior with `estimator_open_loop`, or with the
    /// gate (`estimator_accept_std`) the estimate's parameters accepted since its touch-down (the prior
    /// until then).
    pub fn ground(&self, c: usize) -> GroundParameters {
        self.models[c]
    }

    /// The grounds of every contact's model ([`Self::ground`]), in contact order.
    pub fn models(&self) -> &[GroundParameters] {
        &self.models
    }

    /// The estimates of every contact (their positive components over the prior), in contact order.
    pub fn grounds(&self) -> &[GroundParameters] {
        &self.grounds
    }
}
