//! `stride identify LOG.mcap...`: physically consistent identification of the robot's inertial parameters
//! from logs of identification runs [Traversaro 2017, ch. 6–7]: a robot on a pole moving its joints through
//! exciting trajectories (`configs/identify_legs.toml`) and a robot standing on its feet
//! (`configs/identify_standing.toml`).
//!
//! Measurements, per logged sample (`/sim/state` and `/sensors/ft` at the same time):
//! * the motor torques `τ = Y_s ψ + τ_c sign(q̇) + d q̇` (joint rows of the inverse-dynamics regressor,
//!   eqs. 7.1, 7.5; Coulomb friction `τ_c` and viscous damping `d` per joint are extra unknowns; joints
//!   slower than [`IdentifyOptions::min_joint_speed`] are skipped, where the friction is a stick force);
//! * the force/torque sensor readings `r = Y_FT ψ + b` (eqs. 7.2–7.3; the offsets `b` are extra
//!   unknowns, shared by the logs), valid as long as nothing touches the sensor's child side;
//! * for a robot on its feet, the base rows of the submodel above the feet sensors,
//!   `Y_sub ψ + Σ_k A_k b_k = Σ_k A_k r_k` (eq. 7.1, Theorem 7.1): the total mass and the CoM. The rows
//!   whose submodel holds a sole are skipped there (`usable`).
//!
//! Joint accelerations are central differences of the logged velocities (the simulator logs the state at
//! the control rate; the trajectories are smooth). ψ is in the FT-split layout (see
//! `stride_model::inertial`), so the identified URDF keeps the sensors' view of each body. The identified
//! parameters come from `stride_estimation::identification::identify_on_manifold` with the logged URDF as
//! the prior; the report also has the unconstrained least squares (6.19) and, for simulated logs with
//! `[sim.model]` inertia changes, the plant's true parameters.

mod report;
mod rows;
mod urdf;
mod usable;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use nalgebra::{DVector, Vector3, Vector6};
use stride_estimation::identification::{
    identify_on_manifold, identify_unconstrained, IdentificationData, IdentificationError,
    ManifoldOptions, Prior,
};
use stride_model::inertial::{BaseParameters, InertialParameters};
use stride_model::{KinDyn, Model};

use crate::calibrate::{log_span, paired_samples, CalibrateError};
use crate::log::read_log;
use crate::replay::{logged_model, logged_scenario, ReplayError};

use rows::Rows;
pub use urdf::identified_urdf;
use usable::UsableRows;

/// Why an identification failed.
#[derive(Debug, thiserror::Error)]
pub enum IdentifyError {
    /// Reading a log, its scenario or its model.
    #[error(transparent)]
    Log(#[from] ReplayError),
    /// Pairing the logged messages.
    #[error(transparent)]
    Samples(#[from] CalibrateError),
    /// The model could not evaluate a regressor or hold the parameters.
    #[error(transparent)]
    Model(#[from] stride_model::ModelError),
    /// The identification refused the data.
    #[error(transparent)]
    Identification(#[from] IdentificationError),
    /// The logs lack something or disagree.
    #[error("{0}")]
    Content(String),
}

/// Options of [`identify_logs`].
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `torque_noise` | N·m | 0.05 | σ of a motor-torque row (the FT rows use the logged scenario's sensor noise) |
/// | `prior_weight` | – | 1e-4 | pull towards the logged URDF (`ManifoldOptions::prior_weight`) |
/// | `inertia_prior_weight` | – | 1 | pull on the rotational inertias alone (`ManifoldOptions::inertia_prior_weight`; `None`: `prior_weight`): the inertias of the wrists, forearms, shoulders and torso are poorly excited, and left to the data they land on the bound `L = 0` and make TSID fall (docs/identification.md, "Payoff") |
/// | `max_iterations` | – | 500 | manifold solver iterations (`ManifoldOptions::max_iterations`) |
/// | `max_samples` | – | 1500 | samples used per log, evenly spaced |
/// | `min_joint_speed` | rad/s | 0.05 | torque rows of slower joints are skipped (sticking friction) |
/// | `use_torques`, `use_ft` | – | true | which measurements to use |
#[derive(Clone, Debug)]
pub struct IdentifyOptions {
    /// σ of a motor-torque row (N·m).
    pub torque_noise: f64,
    /// Relative weight of the prior.
    pub prior_weight: f64,
    /// Relative weight of the prior on the rotational inertias (`None`: `prior_weight`).
    pub inertia_prior_weight: Option<f64>,
    /// Manifold solver iterations.
    pub max_iterations: usize,
    /// Samples used per log.
    pub max_samples: usize,
    /// Joint speed below which a torque row is skipped (rad/s).
    pub min_joint_speed: f64,
    /// Use the motor torques.
    pub use_torques: bool,
    /// Use the force/torque sensors.
    pub use_ft: bool,
}

impl Default for IdentifyOptions {
    fn default() -> Self {
        Self {
            torque_noise: 0.05,
            prior_weight: 1e-4,
            inertia_prior_weight: Some(1.0),
            max_iterations: 500,
            max_samples: 1500,
            min_joint_speed: 0.05,
            use_torques: true,
            use_ft: true,
        }
    }
}

/// Relative singular-value threshold of the identifiable combinations the report compares: the right
/// singular vectors of the noise-weighted regressor of ψ with `σ_i > 10⁻² σ_max`, i.e. the combinations
/// the data determine at most 100 times worse than the best one (eqs. 7.6–7.10 with a numerical rather
/// than structural rank). On a 20 s `configs/identify_legs.toml` log the structural rank is 252 of 370
/// and this keeps about 230 (docs/identification.md).
pub const IDENTIFIABLE_TOLERANCE: f64 = 1e-2;

/// The result of [`identify_logs`].
#[derive(Debug, Clone)]
pub struct IdentificationReport {
    /// The logged (prior) model.
    pub model: Arc<Model>,
    /// The logged URDF text.
    pub prior_urdf: String,
    /// Logs used.
    pub logs: Vec<PathBuf>,
    /// Samples and measurement rows used.
    pub samples: usize,
    /// Measurement rows.
    pub rows: usize,
    /// Of which base rows of the submodel above the feet sensors (logs of a robot on its feet).
    pub base_rows: usize,
    /// ψ of the prior, FT-split layout.
    pub prior: DVector<f64>,
    /// ψ identified on the manifold (every body fully consistent).
    pub identified: DVector<f64>,
    /// ψ of the unconstrained least squares (6.19).
    pub unconstrained: DVector<f64>,
    /// ψ of the simulated plant, when the logs are simulations (with or without `[sim.model]`).
    pub truth: Option<DVector<f64>>,
    /// Identified extras: Coulomb friction per joint (N·m), viscous damping per joint (N·m·s/rad), offsets
    /// `[f; τ]` per sensor (N, N·m), in that order (empty parts when a measurement kind is off).
    pub extras: DVector<f64>,
    /// Identifiable subspace of the weighted regressor (relative tolerance [`IDENTIFIABLE_TOLERANCE`]).
    pub base: BaseParameters,
    /// `σ_max / σ_min` of the weighted regressor of ψ over the identifiable combinations.
    pub condition_number: f64,
    /// Normalised residuals (√(χ²/rows)) of the prior (extras at their identified values), of the manifold
    /// estimate and of the unconstrained one.
    pub residuals: [f64; 3],
    /// Manifold iterations, and whether they converged.
    pub iterations: (usize, bool),
    /// The manifold solver's objective (data and prior terms) at the estimate.
    pub objective: f64,
    /// Bodies (model order; FT child sides as `sensor`) whose unconstrained estimate is not fully consistent.
    pub unconstrained_violations: Vec<String>,
    /// The options used.
    pub options: IdentifyOptions,
}

/// Layout of the unknowns `w = [ψ; τ_c; d; b]`.
struct Layout {
    psi: usize,
    friction: usize,
    offsets: usize,
}

impl Layout {
    fn extras(&self) -> usize {
        2 * self.friction + self.offsets
    }
}

/// Identifies the inertial parameters from the logs at `paths` (same robot model).
///
/// # Errors
/// [`IdentifyError`] naming the log or what the data lack.
pub fn identify_logs(
    paths: &[PathBuf],
    options: &IdentifyOptions,
) -> Result<IdentificationReport, IdentifyError> {
    let Some(first) = paths.first() else {
        return Err(IdentifyError::Content("no log given".into()));
    };
    let valid = |w: f64| w.is_finite() && w >= 0.0;
    if !valid(options.prior_weight) || !options.inertia_prior_weight.is_none_or(valid) {
        return Err(IdentifyError::Content(format!(
            "the prior weights must be finite and ≥ 0, not {} (inertias: {:?})",
            options.prior_weight, options.inertia_prior_weight
        )));
    }
    let logged = load_model(first)?;
    let model = Arc::clone(&logged.model);
    let ns = model.ft_sensors().len();
    let layout = Layout {
        psi: 10 * (model.body_count() + ns),
        friction: if options.use_torques { model.dof() } else { 0 },
        offsets: if options.use_ft { 6 * ns } else { 0 },
    };
    let mut data = IdentificationData::new(model.body_count() + ns, layout.extras());
    let mut kd = KinDyn::new(Arc::clone(&model));
    let mut used = LogRows::default();
    for path in paths {
        if load_model(path)?.urdf != logged.urdf {
            return Err(IdentifyError::Content(format!(
                "{} holds another robot model than {}",
                path.display(),
                first.display()
            )));
        }
        let added = add_log(path, &mut kd, &layout, options, &mut data)?;
        used.samples += added.samples;
        used.base_rows += added.base_rows;
    }
    solve(logged, paths, &used, &layout, &data, options)
}

/// The model a log holds.
struct LoggedModel {
    /// The controllers' model, with the scenario's gravity.
    model: Arc<Model>,
    /// Its URDF text.
    urdf: String,
    /// The simulated plant's ψ (FT-split layout), for simulator logs of that URDF.
    truth: Option<DVector<f64>>,
}

/// The logged model (gravity of the scenario), its URDF text and, for simulated logs, the plant's ψ.
fn load_model(path: &Path) -> Result<LoggedModel, IdentifyError> {
    let log = read_log(path).map_err(ReplayError::from)?;
    let scenario = logged_scenario(&log, path)?;
    let mut model = (*logged_model(&log, path, &scenario)?).clone();
    let gravity = Vector3::new(0.0, 0.0, -scenario.config.scenario.gravity);
    model.set_gravity(gravity)?;
    let urdf = log
        .attachments
        .get("model.urdf")
        .map(|u| String::from_utf8_lossy(u).into_owned())
        .unwrap_or_default();
    let plant = &scenario.config.sim.model;
    let truth = if scenario.config.scenario.plant == crate::config::PlantKind::Ideal
        || plant.urdf.is_some()
    {
        None
    } else {
        let edits = crate::setup::plant_inertia_edits(&scenario);
        let locks = crate::setup::joint_locks(&scenario);
        let plant = Model::from_urdf_str_reduced(&urdf, &edits, &locks)?;
        Some(plant.ft_split_inertial_parameters()?)
    };
    Ok(LoggedModel {
        model: Arc::new(model),
        urdf,
        truth,
    })
}

/// What one log added.
#[derive(Default)]
struct LogRows {
    samples: usize,
    base_rows: usize,
}

/// Adds the rows of one log; returns the number of samples and of base rows used.
fn add_log(
    path: &Path,
    kd: &mut KinDyn,
    layout: &Layout,
    options: &IdentifyOptions,
    data: &mut IdentificationData,
) -> Result<LogRows, IdentifyError> {
    let log = read_log(path).map_err(ReplayError::from)?;
    let scenario = logged_scenario(&log, path)?;
    let model = Arc::clone(kd.model());
    let names: Vec<String> = model.ft_sensors().iter().map(|s| s.name.clone()).collect();
    let samples = paired_samples(&log, &model, &names)?;
    if samples.is_empty() {
        return Err(IdentifyError::Content(format!(
            "{} has no /sim/state and /sensors/ft messages at the same times ({:.1} s logged)",
            path.display(),
            log_span(&log)
        )));
    }
    let ft = &scenario.config.sim.sensors.ft;
    let positive = |v: f64, default: f64| if v > 0.0 { v } else { default };
    let ft_noise = Vector6::from_fn(|i, _| {
        if i < 3 {
            positive(ft.force_noise, 1.0)
        } else {
            positive(ft.torque_noise, 0.1)
        }
    });
    let usable = UsableRows::of_log(&scenario, kd, &samples[0].state, path)?;
    let every = samples.len().div_ceil(options.max_samples.max(1));
    let mut rows = Rows::new(&model, layout);
    let mut used = LogRows::default();
    for s in samples.iter().step_by(every) {
        kd.set_state(&s.state)?;
        if options.use_torques {
            rows.add_torques(kd, s, layout, options, &usable, data)?;
        }
        if options.use_ft {
            rows.add_ft(kd, s, layout, &ft_noise, &usable, data)?;
            if !usable.cut.is_empty() {
                rows.add_base(kd, s, layout, &ft_noise, &usable.cut, data)?;
                used.base_rows += 6;
            }
        }
        used.samples += 1;
    }
    Ok(used)
}

/// Solves the manifold and the unconstrained problems and collects the report.
fn solve(
    logged: LoggedModel,
    paths: &[PathBuf],
    used: &LogRows,
    layout: &Layout,
    data: &IdentificationData,
    options: &IdentifyOptions,
) -> Result<IdentificationReport, IdentifyError> {
    let LoggedModel {
        model,
        urdf: prior_urdf,
        truth,
    } = logged;
    let reduced = data.reduce()?;
    let prior_psi = model.ft_split_inertial_parameters()?;
    let prior = Prior {
        bodies: (0..layout.psi / 10)
            .map(|b| {
                InertialParameters::from_column_slice(&prior_psi.as_slice()[10 * b..10 * b + 10])
            })
            .collect(),
        extras: DVector::zeros(layout.extras()),
    };
    let manifold = ManifoldOptions {
        prior_weight: options.prior_weight,
        inertia_prior_weight: options.inertia_prior_weight,
        max_iterations: options.max_iterations,
        ..ManifoldOptions::default()
    };
    let est = identify_on_manifold(&reduced, &prior, &manifold)?;
    let ls = identify_unconstrained(&reduced, &prior, 1e-10)?;
    let psi_columns = reduced.r.columns(0, layout.psi).into_owned();
    let base = BaseParameters::from_stacked(psi_columns, IDENTIFIABLE_TOLERANCE)?;
    let sigma = &base.singular_values;
    let condition_number = sigma[0] / sigma[base.rank().max(1) - 1];
    let extras = est
        .parameters
        .rows(layout.psi, layout.extras())
        .into_owned();
    let mut prior_w = est.parameters.clone();
    prior_w.rows_mut(0, layout.psi).copy_from(&prior_psi);
    let identified = est.parameters.rows(0, layout.psi).into_owned();
    let unconstrained = ls.parameters.rows(0, layout.psi).into_owned();
    let unconstrained_violations = report::violations(&model, &unconstrained);
    Ok(IdentificationReport {
        prior_urdf,
        logs: paths.to_vec(),
        samples: used.samples,
        rows: reduced.rows,
        base_rows: used.base_rows,
        prior: prior_psi,
        identified,
        unconstrained,
        truth,
        extras,
        base,
        condition_number,
        residuals: [
            reduced.normalised_residual(&prior_w),
            est.normalised_residual,
            ls.normalised_residual,
        ],
        iterations: (est.iterations, est.converged),
        objective: est.objective,
        unconstrained_violations,
        model,
        options: options.clone(),
    })
}
