//! `stride calibrate LOG LOG LOG...`: the calibration matrix `C` of the force/torque sensors whose child side
//! is one rigid body (the feet), from logs of the same motion with different known masses added to that
//! body [Traversaro 2017, §5.3.3, eq. (5.11), Lemma 5.2].
//!
//! Per log and sensor, each paired sample gives the raw reading `r_i` and the load acceleration `ĝ_i =
//! ±ʳR_w (g − p̈_s)` (the sensor origin's acceleration from the logged state, `±` the measurement
//! direction): for a rigid child side the reading is `C⁻¹ (M(m, m c) ĝ_i + Δ_i) + b`, `Δ_i` the rotational
//! terms of the Newton–Euler equations about the sensor origin (`−ω̇ × h − ω × (ω × h)`,
//! `−I_o ω̇ − ω × I_o ω`), computed with the child side's parameters of the logged URDF plus the added
//! masses'. `C⁻¹ Δ_i` is subtracted from the reading with the previous pass's `C` (identity first), then
//! `stride_estimation::calibration::calibration_matrix` solves (5.11) in two stages, the offset a random
//! walk under the logged sensor noise ([`OffsetChoice`]). The added masses
//! come from a TOML file ([`AddedMassFile`]) or, for simulated logs, from each log's `[sim.model]` edits
//! (the plant's child side minus the logged robot model's).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use nalgebra::{DMatrix, Isometry3, Matrix3, Matrix6, Vector3, Vector6};
use serde::Deserialize;
use stride_estimation::calibration::{
    calibration_matrix, AddedMassDataset, CalibrationMatrixFit, DriftNoise, OffsetModel,
};
use stride_model::inertial::{
    inertia_about_origin, inertial_parameters, transform_parameters, InertialParameters,
};
use stride_model::{InertiaEdits, KinDyn, Model};

use crate::calibrate::{paired_samples_with_lag, simulated_offsets, CalibrateError};
use crate::config::Scenario;
use crate::replay::{logged_model, logged_scenario, ReplayError};

/// `--added-masses FILE`: the masses added in each log, one `[[log]]` per log of the command line, in the
/// same order.
///
/// ```toml
/// [[log]]                      # the bare robot
/// [[log]]
/// masses = [{ frame = "l_foot", mass = 2.0, com = [0.15, 0.0, -0.03] }]
/// ```
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AddedMassFile {
    /// One entry per log.
    pub log: Vec<LogMasses>,
}

/// The masses added in one log.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LogMasses {
    /// The added masses (none: the bare robot).
    #[serde(default)]
    pub masses: Vec<KnownMass>,
}

/// A known mass rigidly attached to a frame of the model.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KnownMass {
    /// A frame of the model (a link or a sensor frame) on the calibrated sensor's child side.
    pub frame: String,
    /// Mass \[kg\].
    pub mass: f64,
    /// Its centre of mass in `frame` \[m\].
    #[serde(default)]
    pub com: [f64; 3],
}

/// The first stage's offset model (`stride calibrate --constant-offset` chooses [`Self::Constant`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum OffsetChoice {
    /// A random walk with the logged `[sim.sensors.ft]` noise σ and drift rates (a real robot's log: its
    /// sensors' datasheet figures written there); constant when those drift rates are zero.
    #[default]
    DriftFromLog,
    /// Constant over each log, as in Traversaro 2017 (5.1), (5.10).
    Constant,
}

/// One sensor's calibration matrix.
#[derive(Debug, Clone)]
pub struct SensorMatrix {
    /// Sensor name.
    pub name: String,
    /// The fit: `C`, the child side's mass and first moment, each log's offset, the singular values.
    pub fit: CalibrationMatrixFit,
    /// Per log: the added body's `π = [m; m c; vech(I_o)]` about the sensor origin, sensor frame.
    pub added: Vec<InertialParameters>,
    /// The simulator's `C` (simulated logs).
    pub truth: Option<Matrix6<f64>>,
    /// The simulator's offset averaged over the last log (simulated logs).
    pub truth_offset: Option<Vector6<f64>>,
}

impl SensorMatrix {
    /// `‖Ĉ − C‖_F / ‖C‖_F` against the simulator's `C`.
    pub fn relative_error(&self) -> Option<f64> {
        self.truth.map(|c| (self.fit.matrix - c).norm() / c.norm())
    }
}

/// The result of [`calibrate_matrix_logs`].
#[derive(Debug, Clone)]
pub struct MatrixReport {
    /// Calibrated sensors.
    pub sensors: Vec<SensorMatrix>,
    /// Every sensor of the model, in order.
    pub all_sensors: Vec<String>,
    /// Paired samples per log.
    pub samples: Vec<usize>,
    /// The first stage's offset model.
    pub offsets: OffsetModel,
}

/// One log read for the calibration.
struct LoggedRun {
    scenario: Scenario,
    urdf: String,
    model: Arc<Model>,
    samples: Vec<crate::calibrate::Sample>,
    duration: f64,
}

fn read_run(path: &Path) -> Result<LoggedRun, CalibrateError> {
    let log = crate::calibrate::read_calibration_log(path).map_err(ReplayError::from)?;
    let scenario = logged_scenario(&log, path)?;
    let mut model = (*logged_model(&log, path, &scenario)?).clone();
    model.set_gravity(Vector3::new(0.0, 0.0, -scenario.config.scenario.gravity))?;
    let model = Arc::new(model);
    let names: Vec<String> = model.ft_sensors().iter().map(|s| s.name.clone()).collect();
    // A reading describes the robot of the sensors' latency before it (`[sim.sensors] delay_steps`
    // simulator steps, and the step the transmitted wrench is computed over).
    let sim = &scenario.config.sim.sensors;
    let lag = (sim.delay_steps as f64 + 1.0) / f64::from(scenario.config.rates.sim_hz);
    let samples = paired_samples_with_lag(&log, &model, &names, lag)?;
    if samples.is_empty() {
        return Err(CalibrateError::Content(format!(
            "{} has no /sim/state and /sensors/ft messages at the same times",
            path.display()
        )));
    }
    let urdf = String::from_utf8_lossy(&log.attachments["model.urdf"]).into_owned();
    Ok(LoggedRun {
        scenario,
        urdf,
        model,
        samples,
        duration: crate::calibrate::log_span(&log),
    })
}

/// The calibration matrix of `sensor` (or of every sensor whose child side is one rigid body) from `logs`
/// taken with different added masses: from `masses` when given, else from each log's `[sim.model]` edits.
/// Fewer than three logs are refused by the rank check of (5.11) (Lemma 5.2). `offsets` chooses the first
/// stage's offset model. ([`MatrixLogs`] reads the logs once for several calibrations.)
pub fn calibrate_matrix_logs(
    logs: &[PathBuf],
    sensor: Option<&str>,
    masses: Option<&AddedMassFile>,
    offsets: OffsetChoice,
) -> Result<MatrixReport, CalibrateError> {
    MatrixLogs::read(logs)?.calibrate(sensor, masses, offsets)
}

/// The logs of [`calibrate_matrix_logs`], read once (e.g. to compare offset models on the same logs).
pub struct MatrixLogs {
    paths: Vec<PathBuf>,
    runs: Vec<LoggedRun>,
}

impl MatrixLogs {
    /// Reads `logs` (at least one) and checks that they hold one robot model.
    pub fn read(logs: &[PathBuf]) -> Result<Self, CalibrateError> {
        let runs = logs
            .iter()
            .map(|p| read_run(p))
            .collect::<Result<Vec<_>, _>>()?;
        let Some(first) = runs.first() else {
            return Err(CalibrateError::Content(
                "no log given: the calibration matrix needs at least three (Lemma 5.2)".into(),
            ));
        };
        let model = &first.model;
        for (run, path) in runs.iter().zip(logs) {
            if run.model.ft_sensors().len() != model.ft_sensors().len()
                || run.model.dof() != model.dof()
            {
                return Err(CalibrateError::Content(format!(
                    "{} holds another robot model than {}",
                    path.display(),
                    logs[0].display()
                )));
            }
        }
        Ok(Self {
            paths: logs.to_vec(),
            runs,
        })
    }

    /// [`calibrate_matrix_logs`] on the logs read.
    pub fn calibrate(
        &self,
        sensor: Option<&str>,
        masses: Option<&AddedMassFile>,
        offsets: OffsetChoice,
    ) -> Result<MatrixReport, CalibrateError> {
        let (runs, logs) = (&self.runs, &self.paths);
        if let Some(f) = masses {
            if f.log.len() != logs.len() {
                return Err(CalibrateError::Content(format!(
                    "the added-mass file has {} [[log]] entries for {} logs; give one per log, in order",
                    f.log.len(),
                    logs.len()
                )));
            }
        }
        let model = Arc::clone(&runs[0].model);
        let all_sensors: Vec<String> = model.ft_sensors().iter().map(|s| s.name.clone()).collect();
        let chosen = chosen_sensors(&model, sensor)?;
        let offsets = offset_model(&runs[0].scenario, offsets);
        let mut sensors = Vec::new();
        for k in chosen {
            let mut added = Vec::new();
            for (j, run) in runs.iter().enumerate() {
                added.push(match masses {
                    Some(f) => masses_on_sensor(&model, k, &f.log[j].masses)?,
                    None => edits_on_sensor(run, k, &logs[j])?,
                });
            }
            sensors.push(fit_sensor(runs, k, added, &offsets)?);
        }
        Ok(MatrixReport {
            sensors,
            all_sensors,
            samples: runs.iter().map(|r| r.samples.len()).collect(),
            offsets,
        })
    }
}

/// The offset model of `choice` for the logged sensors: a random walk under the logged `[sim.sensors.ft]`
/// white noise and drift rates (each σ at least [`MIN_NOISE`]); constant when asked or when the log's
/// sensors do not drift.
fn offset_model(scenario: &Scenario, choice: OffsetChoice) -> OffsetModel {
    let ft = &scenario.config.sim.sensors.ft;
    if choice == OffsetChoice::Constant || (ft.force_drift <= 0.0 && ft.torque_drift <= 0.0) {
        return OffsetModel::Constant;
    }
    let per_axis = |f: f64, t: f64| nalgebra::Vector6::new(f, f, f, t, t, t);
    OffsetModel::RandomWalk(DriftNoise {
        white: per_axis(
            ft.force_noise.max(MIN_NOISE),
            ft.torque_noise.max(MIN_NOISE),
        ),
        walk: per_axis(ft.force_drift, ft.torque_drift),
    })
}

/// Floor of the white-noise σ given to the drift filter, raw units (a noise-free log still has the
/// pipeline's own errors).
const MIN_NOISE: f64 = 1e-3;

/// The named sensor (its child side must be rigid), or every sensor whose child side is.
fn chosen_sensors(model: &Model, sensor: Option<&str>) -> Result<Vec<usize>, CalibrateError> {
    let names: Vec<&str> = model.ft_sensors().iter().map(|s| s.name.as_str()).collect();
    match sensor {
        Some(name) => {
            let k = model.ft_sensor_index(name).ok_or_else(|| {
                CalibrateError::Content(format!(
                    "the model has no force/torque sensor `{name}`; it has: {}",
                    names.join(", ")
                ))
            })?;
            if !rigid_child_side(model, k)? {
                return Err(CalibrateError::Content(format!(
                    "`{name}` has moving joints on its child side: the calibration matrix (5.11) needs a \
                     sensor whose child side is one rigid body (e.g. a foot sensor)"
                )));
            }
            Ok(vec![k])
        }
        None => {
            let mut out = Vec::new();
            for k in 0..names.len() {
                if rigid_child_side(model, k)? {
                    out.push(k);
                }
            }
            if out.is_empty() {
                return Err(CalibrateError::Content(
                    "no force/torque sensor of the model has a rigid child side".into(),
                ));
            }
            Ok(out)
        }
    }
}

/// Whether every frame on sensor `k`'s child side lies in the sensor's own body (no joint below it).
fn rigid_child_side(model: &Model, k: usize) -> Result<bool, CalibrateError> {
    let host = model.frames()[model.ft_sensors()[k].frame.index()].link;
    for frame in model.frames() {
        let Some(id) = model.frame_id(&frame.name) else {
            continue;
        };
        if model.ft_child_side_holds(k, id)? && frame.link != host {
            return Ok(false);
        }
    }
    Ok(true)
}

/// `sensor_H_body` of sensor `k` (its frame's placement in its body, inverted).
fn sensor_from_body(model: &Model, k: usize) -> Isometry3<f64> {
    model.frames()[model.ft_sensors()[k].frame.index()]
        .placement
        .inverse()
}

/// `π` of sensor `k`'s child side in `host` layout (host body frame, block `N + k` of the FT-split layout)
/// moved to the sensor frame, about the sensor origin.
fn child_side_in_sensor_frame(
    model: &Model,
    k: usize,
) -> Result<InertialParameters, CalibrateError> {
    let p = model.ft_split_inertial_parameters()?;
    let i = 10 * (model.body_count() + k);
    let pi = InertialParameters::from_column_slice(&p.as_slice()[i..i + 10]);
    let s_h_b = sensor_from_body(model, k);
    Ok(transform_parameters(
        &pi,
        s_h_b.rotation.to_rotation_matrix().matrix(),
        &s_h_b.translation.vector,
    ))
}

/// The known masses on sensor `k`'s child side as one body: `π` (point masses) about the sensor origin,
/// sensor frame.
fn masses_on_sensor(
    model: &Model,
    k: usize,
    masses: &[KnownMass],
) -> Result<InertialParameters, CalibrateError> {
    let s_h_b = sensor_from_body(model, k);
    let mut pi = InertialParameters::zeros();
    for mass in masses {
        let id = model.frame_id(&mass.frame).ok_or_else(|| {
            CalibrateError::Content(format!(
                "added mass: the model has no frame `{}`",
                mass.frame
            ))
        })?;
        if !(mass.mass.is_finite() && mass.mass > 0.0 && mass.com.iter().all(|v| v.is_finite())) {
            return Err(CalibrateError::Content(format!(
                "added mass on `{}`: mass {} kg and com {:?} must be finite, the mass positive",
                mass.frame, mass.mass, mass.com
            )));
        }
        if !model.ft_child_side_holds(k, id)? {
            continue;
        }
        let placement = model.frames()[id.index()].placement;
        let c = s_h_b * placement * nalgebra::Point3::from(Vector3::from(mass.com));
        pi += inertial_parameters(mass.mass, &c.coords, &Matrix3::zeros());
    }
    Ok(pi)
}

/// The body the log's `[sim.model]` edits add on sensor `k`'s child side: the plant's child side minus the
/// logged robot model's, about the sensor origin, sensor frame.
fn edits_on_sensor(
    run: &LoggedRun,
    k: usize,
    path: &Path,
) -> Result<InertialParameters, CalibrateError> {
    if run.scenario.config.sim.model.urdf.is_some() {
        return Err(CalibrateError::Content(format!(
            "{}: the plant has its own URDF ([sim.model] urdf); give the added masses with --added-masses",
            path.display()
        )));
    }
    let edits: InertiaEdits = crate::setup::plant_inertia_edits(&run.scenario);
    let locks = crate::setup::joint_locks(&run.scenario);
    let plant = Model::from_urdf_str_reduced(&run.urdf, &edits, &locks)?;
    let bare = Model::from_urdf_str_reduced(&run.urdf, &InertiaEdits::default(), &locks)?;
    Ok(child_side_in_sensor_frame(&plant, k)? - child_side_in_sensor_frame(&bare, k)?)
}

/// Passes of (5.11) with the rotational terms read through the previous pass's `C⁻¹`.
const ROTATIONAL_PASSES: usize = 3;

/// Stage (5.11) for sensor `k` over every run. The reading is `C⁻¹ (M ĝ + Δ) + b`: `Δ` is subtracted
/// through the current estimate of `C⁻¹` (identity first) and (5.11) solved again, [`ROTATIONAL_PASSES`]
/// times (ours: the thesis's static poses have no `Δ`; with `Δ` of a few N in fast swings, the `(C⁻¹ − 1) Δ`
/// left by subtracting `Δ` alone is read as gravity response).
fn fit_sensor(
    runs: &[LoggedRun],
    k: usize,
    added: Vec<InertialParameters>,
    offsets: &OffsetModel,
) -> Result<SensorMatrix, CalibrateError> {
    let model = &runs[0].model;
    let name = model.ft_sensors()[k].name.clone();
    let wrap = |source| CalibrateError::Calibration {
        sensor: name.clone(),
        source,
    };
    let prior = child_side_in_sensor_frame(model, k)?;
    let mut data = Vec::new();
    for (run, a) in runs.iter().zip(&added) {
        data.push(load_accelerations(run, k, &(prior + a))?);
    }
    let mut coms = Vec::new();
    for a in &added {
        coms.push(added_com(&name, a)?);
    }
    let mut c_inv = Matrix6::identity();
    let mut fit = None;
    for _ in 0..ROTATIONAL_PASSES {
        let corrected: Vec<Vec<Vector6<f64>>> = data
            .iter()
            .map(|d| {
                d.raw
                    .iter()
                    .zip(&d.rotational)
                    .map(|(r, delta)| r - c_inv * delta)
                    .collect()
            })
            .collect();
        let datasets: Vec<AddedMassDataset<'_>> = data
            .iter()
            .zip(&corrected)
            .zip(added.iter().zip(&coms))
            .map(|((d, raw), (a, com))| AddedMassDataset {
                times: &d.times,
                raw,
                gravity: &d.load,
                added_mass: a[0],
                added_com: *com,
            })
            .collect();
        let f = calibration_matrix(&datasets, offsets).map_err(wrap)?;
        c_inv = f.matrix.try_inverse().ok_or_else(|| {
            CalibrateError::Content(format!("sensor `{name}`: the estimated C is singular"))
        })?;
        fit = Some(f);
    }
    let Some(fit) = fit else {
        unreachable!("at least one pass");
    };
    let last = runs.last().map(|r| (r, r.duration));
    let (truth, truth_offset) = match last {
        Some((run, duration)) => simulated_truth(run, k, duration),
        None => (None, None),
    };
    Ok(SensorMatrix {
        name,
        fit,
        added,
        truth,
        truth_offset,
    })
}

/// The added body's centre of mass (sensor frame) from its `π`; an edit that moves the centre without
/// adding mass is refused.
fn added_com(name: &str, a: &InertialParameters) -> Result<Vector3<f64>, CalibrateError> {
    let (m, h) = (a[0], Vector3::new(a[1], a[2], a[3]));
    if m > 1e-9 {
        Ok(h / m)
    } else if h.norm() < 1e-12 {
        Ok(Vector3::zeros())
    } else {
        Err(CalibrateError::Content(format!(
            "sensor `{name}`: a log moves the child side's centre of mass ({h:?} kg·m) without adding mass; \
             (5.11) takes added masses"
        )))
    }
}

/// A sensor's readings, the rotational terms of its child side and the load accelerations, sample by
/// sample.
struct SensorData {
    times: Vec<f64>,
    raw: Vec<Vector6<f64>>,
    rotational: Vec<Vector6<f64>>,
    load: Vec<Vector3<f64>>,
}

/// Whether a reading is at the sensor's full scale on some axis (`[sim.sensors.ft] force_range`,
/// `torque_range`; a real robot's log: its sensors' ranges written there): the wrench is then unknown.
fn saturated(reading: &Vector6<f64>, range: &Vector6<f64>) -> bool {
    reading
        .iter()
        .zip(range.iter())
        .any(|(r, full)| r.abs() >= full * (1.0 - 1e-9))
}

/// Raw readings of sensor `k` below its full scale ([`saturated`]), the rotational terms `±Δ_i` of a child side `pi` (sensor frame, about its
/// origin) in the reading's sign, and the load accelerations `ĝ_i = ±ʳR_w (g − p̈_s)` at the paired
/// samples.
fn load_accelerations(
    run: &LoggedRun,
    k: usize,
    pi: &InertialParameters,
) -> Result<SensorData, CalibrateError> {
    let model = &run.model;
    let sensor = &model.ft_sensors()[k];
    let sign = if sensor.measure_direction == "parent_to_child" {
        -1.0
    } else {
        1.0
    };
    let mut kd = KinDyn::new(Arc::clone(model));
    let mut jac = DMatrix::zeros(6, model.nv());
    let g = model.gravity();
    let n = run.samples.len();
    let ft = &run.scenario.config.sim.sensors.ft;
    let range = Vector6::new(
        ft.force_range[0],
        ft.force_range[1],
        ft.force_range[2],
        ft.torque_range[0],
        ft.torque_range[1],
        ft.torque_range[2],
    );
    let mut out = SensorData {
        times: Vec::with_capacity(n),
        raw: Vec::with_capacity(n),
        rotational: Vec::with_capacity(n),
        load: Vec::with_capacity(n),
    };
    for s in &run.samples {
        if saturated(&s.readings[k], &range) {
            continue;
        }
        kd.set_state(&s.state)?;
        kd.frame_jacobian(sensor.frame, &mut jac)?;
        let acc: Vector6<f64> = &jac * &s.nu_dot + kd.frame_bias_acceleration(sensor.frame);
        let rotation = kd.frame_pose(sensor.frame).rotation;
        let to_sensor = |v: Vector3<f64>| rotation.inverse_transform_vector(&v);
        let omega = to_sensor(
            kd.frame_velocity(sensor.frame)
                .fixed_rows::<3>(3)
                .into_owned(),
        );
        let omega_dot = to_sensor(acc.fixed_rows::<3>(3).into_owned());
        out.load.push(sign * to_sensor(g - acc.fixed_rows::<3>(0)));
        out.times.push(s.time);
        out.raw.push(s.readings[k]);
        out.rotational
            .push(sign * rotational_terms(pi, &omega, &omega_dot));
    }
    Ok(out)
}

/// The terms of a rigid body's wrench on its sensor beyond `M(m, h) ĝ` (Newton–Euler about the sensor
/// origin `o`, sensor frame): `[−ω̇ × h − ω × (ω × h); −I_o ω̇ − ω × I_o ω]` [Traversaro 2017, (2.75)].
fn rotational_terms(
    pi: &InertialParameters,
    omega: &Vector3<f64>,
    omega_dot: &Vector3<f64>,
) -> Vector6<f64> {
    let h = Vector3::new(pi[1], pi[2], pi[3]);
    let i_o = inertia_about_origin(pi);
    let f = -omega_dot.cross(&h) - omega.cross(&omega.cross(&h));
    let t = -(i_o * omega_dot) - omega.cross(&(i_o * omega));
    Vector6::new(f.x, f.y, f.z, t.x, t.y, t.z)
}

/// The simulator's `C` of sensor `k` and its offset averaged over `duration` (the sensor models rebuilt
/// from the logged configuration: same seed, same draws).
fn simulated_truth(
    run: &LoggedRun,
    k: usize,
    duration: f64,
) -> (Option<Matrix6<f64>>, Option<Vector6<f64>>) {
    let offsets = simulated_offsets(&run.scenario, &run.model, duration);
    let Some(offsets) = offsets else {
        return (None, None);
    };
    let dt = 1.0 / f64::from(run.scenario.config.rates.sim_hz);
    let mut sensors =
        stride_sim::SensorModels::new(&run.model, &run.scenario.config.sim.sensors, dt);
    sensors.reset();
    let c = sensors.ft_calibration_matrices()[k];
    // The offsets were read through the gains on zero wrenches: exactly the offset plus drift.
    (Some(c), Some(offsets[k]))
}

fn fmt_row(v: impl Iterator<Item = f64>) -> String {
    v.map(|x| format!("{x:?}")).collect::<Vec<_>>().join(", ")
}

impl MatrixReport {
    /// The table printed by `stride calibrate` with several logs.
    pub fn render(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "force/torque calibration matrices from {} logs ({} paired samples; Traversaro 2017, (5.11))",
            self.samples.len(),
            self.samples
                .iter()
                .map(|n| n.to_string())
                .collect::<Vec<_>>()
                .join(" + ")
        );
        let _ = match &self.offsets {
            OffsetModel::Constant => writeln!(s, "  offsets: constant over each log ((5.10))"),
            OffsetModel::RandomWalk(n) => writeln!(
                s,
                "  offsets: random walks (white noise σ {:.3} N / {:.4} N m, drift {:.4} N/√s / {:.5} N m/√s), \
                 stage 2 weighted",
                n.white[0], n.white[3], n.walk[0], n.walk[3]
            ),
        };
        for c in &self.sensors {
            let _ = writeln!(s, "  {}", c.name);
            for (j, a) in c.added.iter().enumerate() {
                let _ = writeln!(
                    s,
                    "    log {j}: added {:.3} kg, first moment [{:.4}, {:.4}, {:.4}] kg m (sensor frame)",
                    a[0], a[1], a[2], a[3]
                );
            }
            let _ = writeln!(
                s,
                "    child side: mass {:.4} kg, first moment [{:.5}, {:.5}, {:.5}] kg m",
                c.fit.mass, c.fit.first_moment.x, c.fit.first_moment.y, c.fit.first_moment.z
            );
            let sv = &c.fit.singular_values;
            let _ = writeln!(
                s,
                "    singular values of (5.11): {:.3e} … {:.3e}",
                sv.max(),
                sv.min()
            );
            for i in 0..6 {
                let row: Vec<String> = (0..6)
                    .map(|j| format!("{:>9.5}", c.fit.matrix[(i, j)]))
                    .collect();
                let _ = writeln!(s, "    C [{}]", row.join(" "));
            }
            if let Some(e) = c.relative_error() {
                let _ = writeln!(s, "    simulated C: ‖Ĉ − C‖_F / ‖C‖_F = {:.3} %", 100.0 * e);
            }
        }
        s
    }

    /// `[estimation.ft_offsets] initial`: the calibrated sensors' offsets fitted on the last log (the most
    /// recent session; with the random-walk model, the offset at its end), the others at zero.
    pub fn offsets_toml(&self) -> String {
        let mut s = String::from("[estimation.ft_offsets]\ninitial = [\n");
        for name in &self.all_sensors {
            match self.sensors.iter().find(|c| &c.name == name) {
                Some(c) => {
                    let b = c.fit.offsets.last().copied().unwrap_or_else(Vector6::zeros);
                    let _ = writeln!(s, "  [{}], # {name}", fmt_row(b.iter().copied()));
                }
                None => {
                    let _ = writeln!(
                        s,
                        "  [0.0, 0.0, 0.0, 0.0, 0.0, 0.0], # {name} (not calibrated here: `stride calibrate LOG`)"
                    );
                }
            }
        }
        s.push_str("]\n");
        s
    }

    /// `[estimation.ft_calibration]`: each calibrated sensor's `C`, by rows.
    pub fn matrices_toml(&self) -> String {
        let mut s = String::from("[estimation.ft_calibration]\n");
        for c in &self.sensors {
            let _ = writeln!(s, "{} = [", c.name);
            for i in 0..6 {
                let _ = writeln!(s, "  [{}],", fmt_row((0..6).map(|j| c.fit.matrix[(i, j)])));
            }
            s.push_str("]\n");
        }
        s
    }

    /// The scenario overlay: the calibration matrices and the offsets.
    pub fn to_toml(&self, sources: &[PathBuf]) -> String {
        let names: Vec<String> = sources.iter().map(|p| p.display().to_string()).collect();
        format!(
            "# Force/torque calibration matrices and offsets estimated by `stride calibrate` from {}\n\
             # [Traversaro 2017, (5.11)]. Use it as an overlay: include = [\"<this file>\"] after the robot and layer\n\
             # files; the estimation layer reads each wrench as C (r - b).\n{}{}",
            names.join(", "),
            self.matrices_toml(),
            self.offsets_toml()
        )
    }
}
