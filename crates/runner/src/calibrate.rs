//! `stride calibrate LOG.mcap`: the in-situ offset calibration of the force/torque sensors from a log
//! [Traversaro 2017, ch. 5], e.g. of `configs/identify_ft_legs.toml` (robot on a pole, legs swung through
//! rotations). Each sensor's offset is estimated jointly with the inertial parameters of its child side by
//! least squares on the model's FT-sensor regressor (`stride_estimation::calibration::RegressorOffset`),
//! from the logged readings (`/sensors/ft`) and joint states (`/sim/state`, accelerations by central
//! differences), over the samples where the sensor's child side touches nothing (the run must have no
//! contact on it: a robot on a pole). The static method of the thesis (5.6)–(5.10) is run as a cross-check.
//! The result is a scenario overlay that sets `estimation.ft_offsets.initial`.

use std::fmt::Write as _;
use std::path::Path;
use std::sync::Arc;

use nalgebra::{DMatrix, DVector, Vector3, Vector6};
use stride_estimation::calibration::{
    child_side_columns, offset_from_rotations, CalibrationError, RegressorOffset,
};
use stride_model::{KinDyn, Model, RobotState};

use crate::log::{read_log_topics, LogContents, LogError};
use crate::records::StateRecord;
use crate::replay::{logged_model, logged_scenario, ReplayError};

/// Why a calibration failed.
#[derive(Debug, thiserror::Error)]
pub enum CalibrateError {
    /// Reading the log, its scenario or its model.
    #[error(transparent)]
    Log(#[from] ReplayError),
    /// The estimation refused the data.
    #[error("sensor `{sensor}`: {source}")]
    Calibration {
        /// The sensor.
        sensor: String,
        /// Why.
        source: CalibrationError,
    },
    /// The model could not evaluate the logged states.
    #[error(transparent)]
    Model(#[from] stride_model::ModelError),
    /// The log lacks something.
    #[error("{0}")]
    Content(String),
}

/// One sensor's calibration.
#[derive(Debug, Clone)]
pub struct SensorCalibration {
    /// Sensor name.
    pub name: String,
    /// Estimated offset `[f; τ]` (N, N·m): regressor method.
    pub offset: Vector6<f64>,
    /// Its standard deviation under the configured sensor noise.
    pub offset_std: Vector6<f64>,
    /// The static method's offset (5.6)–(5.10), if the data determine it.
    pub rotation_offset: Option<Vector6<f64>>,
    /// The simulator's offset averaged over the run (drift included), when the log is a simulation.
    pub truth: Option<Vector6<f64>>,
    /// `√(χ²/rows)` of the fit (≈ 1 when the residuals match the noise model).
    pub normalised_residual: f64,
}

/// The result of [`calibrate_log`].
#[derive(Debug, Clone)]
pub struct CalibrationReport {
    /// Calibrated sensors.
    pub sensors: Vec<SensorCalibration>,
    /// Every sensor of the model, [`Model::ft_sensors`] order.
    pub all_sensors: Vec<String>,
    /// Samples used.
    pub samples: usize,
    /// Logged time span \[s\].
    pub duration: f64,
}

/// A paired sample: the state, its acceleration, the motor torques and every sensor's reading.
pub(crate) struct Sample {
    /// Time of the state, s.
    pub(crate) time: f64,
    pub(crate) state: RobotState,
    pub(crate) nu_dot: DVector<f64>,
    /// Motor torques of `/sim/state` (N·m or N; empty in logs without them).
    pub(crate) joint_torques: DVector<f64>,
    pub(crate) readings: Vec<Vector6<f64>>,
}

/// `/sim/state` message.
#[derive(serde::Deserialize)]
struct StateMsg {
    time: f64,
    #[serde(flatten)]
    state: StateRecord<'static>,
    #[serde(default)]
    joint_torques: Vec<f64>,
}

/// `/sensors/ft` message.
#[derive(serde::Deserialize)]
struct FtMsg {
    time: f64,
    names: Vec<String>,
    wrenches: Vec<[f64; 6]>,
}

/// Calibrates the offsets of `sensor` (or of every force/torque sensor) from the log at `path`.
pub fn calibrate_log(
    path: &Path,
    sensor: Option<&str>,
) -> Result<CalibrationReport, CalibrateError> {
    let log = read_calibration_log(path).map_err(ReplayError::from)?;
    let scenario = logged_scenario(&log, path)?;
    let mut model = (*logged_model(&log, path, &scenario)?).clone();
    model.set_gravity(Vector3::new(0.0, 0.0, -scenario.config.scenario.gravity))?;
    let model = Arc::new(model);
    let all_sensors: Vec<String> = model.ft_sensors().iter().map(|s| s.name.clone()).collect();
    let chosen: Vec<usize> = match sensor {
        Some(name) => vec![model.ft_sensor_index(name).ok_or_else(|| {
            CalibrateError::Content(format!(
                "the model has no force/torque sensor `{name}`; it has: {}",
                all_sensors.join(", ")
            ))
        })?],
        None => (0..all_sensors.len()).collect(),
    };
    let samples = paired_samples(&log, &model, &all_sensors)?;
    if samples.is_empty() {
        return Err(CalibrateError::Content(format!(
            "{} has no /sim/state and /sensors/ft messages at the same times",
            path.display()
        )));
    }
    let ft = &scenario.config.sim.sensors.ft;
    let sigma = |v: f64, default: f64| if v > 0.0 { v } else { default };
    let noise = Vector6::new(
        sigma(ft.force_noise, 1.0),
        sigma(ft.force_noise, 1.0),
        sigma(ft.force_noise, 1.0),
        sigma(ft.torque_noise, 0.1),
        sigma(ft.torque_noise, 0.1),
        sigma(ft.torque_noise, 0.1),
    );
    let duration = log_span(&log);
    let truth = simulated_offsets(&scenario, &model, duration);
    let mut kd = KinDyn::new(Arc::clone(&model));
    let mut sensors = Vec::new();
    for &k in &chosen {
        let mut cal = calibrate_sensor(&mut kd, k, &samples, noise)?;
        cal.truth = truth.as_ref().map(|t| t[k]);
        sensors.push(cal);
    }
    Ok(CalibrationReport {
        sensors,
        all_sensors,
        samples: samples.len(),
        duration,
    })
}

/// The two topics the calibrations read: the robot's state and the FT readings.
const CALIBRATION_TOPICS: [&str; 2] = ["/sim/state", "/sensors/ft"];

/// A log with the messages of [`CALIBRATION_TOPICS`] only (and every attachment and metadata record): a
/// 40 s pole log at 2 kHz holds ten times more on the other topics.
pub(crate) fn read_calibration_log(path: &Path) -> Result<LogContents, LogError> {
    read_log_topics(path, |topic| CALIBRATION_TOPICS.contains(&topic))
}

pub(crate) fn log_span(log: &LogContents) -> f64 {
    let mut times = log.topic("/sensors/ft").map(|m| m.time_ns);
    let first = times.next().unwrap_or(0);
    let last = times.last().unwrap_or(first);
    (last - first) as f64 * 1e-9
}

/// The regressor fit of sensor `k`, and the static method as a cross-check.
fn calibrate_sensor(
    kd: &mut KinDyn,
    k: usize,
    samples: &[Sample],
    noise: Vector6<f64>,
) -> Result<SensorCalibration, CalibrateError> {
    let model = Arc::clone(kd.model());
    let name = model.ft_sensors()[k].name.clone();
    let wrap = |source| CalibrateError::Calibration {
        sensor: name.clone(),
        source,
    };
    let columns = child_side_columns(kd, k).map_err(wrap)?;
    let mut fit = RegressorOffset::new(columns, noise).map_err(wrap)?;
    let ns = model.ft_sensors().len();
    let mut y = DMatrix::zeros(6 * ns, 10 * (model.body_count() + ns));
    let frame = model.ft_sensors()[k].frame;
    let g = model.gravity();
    let mut raw = Vec::with_capacity(samples.len());
    let mut gravity = Vec::with_capacity(samples.len());
    for s in samples {
        kd.set_state(&s.state)?;
        kd.ft_sensor_regressor(&s.nu_dot, &mut y)?;
        fit.add(&y.rows(6 * k, 6), &s.readings[k]).map_err(wrap)?;
        raw.push(s.readings[k]);
        gravity.push(kd.frame_pose(frame).rotation.inverse_transform_vector(&g));
    }
    let solved = fit.solve().map_err(wrap)?;
    Ok(SensorCalibration {
        name: name.clone(),
        offset: solved.offset,
        offset_std: solved.offset_std,
        rotation_offset: offset_from_rotations(&raw, &gravity).ok().map(|r| r.offset),
        truth: None,
        normalised_residual: solved.normalised_residual,
    })
}

/// `/sim/state` and `/sensors/ft` paired by time, with `ν̇` from central differences of the velocities
/// (the first and last states, without two neighbours, are dropped).
pub(crate) fn paired_samples(
    log: &LogContents,
    model: &Model,
    names: &[String],
) -> Result<Vec<Sample>, CalibrateError> {
    paired_samples_with_lag(log, model, names, 0.0)
}

/// [`paired_samples`] with each state paired with the reading logged `lag` seconds later (the sensors'
/// latency: a reading describes the robot of `lag` seconds before).
pub(crate) fn paired_samples_with_lag(
    log: &LogContents,
    model: &Model,
    names: &[String],
    lag: f64,
) -> Result<Vec<Sample>, CalibrateError> {
    let parse_err = |topic: &str, e: serde_json::Error| {
        CalibrateError::Content(format!("a message on {topic} does not parse: {e}"))
    };
    let mut states = Vec::new();
    for m in log.topic("/sim/state") {
        let msg: StateMsg =
            serde_json::from_slice(&m.data).map_err(|e| parse_err("/sim/state", e))?;
        let mut s = RobotState::zero(model);
        msg.state
            .to_state(&mut s)
            .map_err(|e| CalibrateError::Content(format!("/sim/state: {e}")))?;
        states.push((msg.time, s, DVector::from_vec(msg.joint_torques)));
    }
    let mut readings = std::collections::BTreeMap::new();
    for m in log.topic("/sensors/ft") {
        let msg: FtMsg =
            serde_json::from_slice(&m.data).map_err(|e| parse_err("/sensors/ft", e))?;
        if msg.names != names {
            return Err(CalibrateError::Content(format!(
                "/sensors/ft names {:?} differ from the model's sensors {names:?}",
                msg.names
            )));
        }
        let w: Vec<Vector6<f64>> = msg
            .wrenches
            .iter()
            .map(|w| Vector6::from_column_slice(w))
            .collect();
        readings.insert(time_key(msg.time), w);
    }
    let mut out = Vec::new();
    for i in 1..states.len().saturating_sub(1) {
        let (t, s, tau) = &states[i];
        let Some(r) = readings.get(&time_key(*t + lag)) else {
            continue;
        };
        let (t0, s0, _) = &states[i - 1];
        let (t1, s1, _) = &states[i + 1];
        let dt = t1 - t0;
        if dt <= 0.0 {
            continue;
        }
        let mut nu_dot = DVector::zeros(model.nv());
        for j in 0..6 {
            nu_dot[j] = (s1.base_velocity[j] - s0.base_velocity[j]) / dt;
        }
        for j in 0..model.dof() {
            nu_dot[6 + j] = (s1.joint_velocities[j] - s0.joint_velocities[j]) / dt;
        }
        out.push(Sample {
            time: *t,
            state: s.clone(),
            nu_dot,
            joint_torques: tau.clone(),
            readings: r.clone(),
        });
    }
    Ok(out)
}

/// Time in microseconds, to pair messages logged at the same tick.
fn time_key(t: f64) -> i64 {
    (t * 1e6).round() as i64
}

/// The simulator's offsets of the logged run, averaged over its `duration` (s) with the drift they
/// accumulated: its sensor models rebuilt from the logged configuration (same seed, so the same draws: the
/// draws do not depend on what the sensors read) and stepped `duration · sim_hz` times on zero wrenches;
/// the mean reading is the mean offset (the noise averages out, σ/√steps). `None` for the ideal plant (it
/// has no force/torque sensors).
pub(crate) fn simulated_offsets(
    scenario: &crate::config::Scenario,
    model: &Model,
    duration: f64,
) -> Option<Vec<Vector6<f64>>> {
    if scenario.config.scenario.plant == crate::config::PlantKind::Ideal {
        return None;
    }
    let dt = 1.0 / f64::from(scenario.config.rates.sim_hz);
    let mut sensors = stride_sim::SensorModels::new(model, &scenario.config.sim.sensors, dt);
    sensors.reset();
    let ns = model.ft_sensors().len();
    let zeros = vec![Vector6::zeros(); ns];
    let state = RobotState::zero(model);
    let steps = (duration / dt).round().max(1.0) as usize;
    let mut sum = vec![Vector6::zeros(); ns];
    for k in 0..steps {
        let truth = stride_sim::SensorTruth {
            state: &state,
            imu_pose: nalgebra::Isometry3::identity(),
            imu_twist: Vector6::zeros(),
            imu_acceleration: Vector3::zeros(),
            gravity: model.gravity(),
            time: k as f64 * dt,
            ft_wrenches: &zeros,
            fresh_start: k == 0,
        };
        let reading = sensors.record(&truth);
        for (s, r) in sum.iter_mut().zip(&reading.ft_wrenches) {
            *s += r;
        }
    }
    Some(sum.into_iter().map(|s| s / steps as f64).collect())
}

impl CalibrationReport {
    /// The table printed by `stride calibrate`.
    pub fn render(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "force/torque offsets from {} samples over {:.1} s (offset jointly with the child side's inertial \
             parameters on the FT-sensor regressor; Traversaro 2017, ch. 5)",
            self.samples, self.duration
        );
        let _ = writeln!(
            s,
            "  {:<18} {:<10} {:>9} {:>9} {:>9} {:>9} {:>9} {:>9}",
            "sensor", "", "fx [N]", "fy [N]", "fz [N]", "tx [N m]", "ty [N m]", "tz [N m]"
        );
        let row = |s: &mut String, name: &str, what: &str, v: &Vector6<f64>| {
            let _ = writeln!(
                s,
                "  {name:<18} {what:<10} {:>9.3} {:>9.3} {:>9.3} {:>9.4} {:>9.4} {:>9.4}",
                v[0], v[1], v[2], v[3], v[4], v[5]
            );
        };
        for c in &self.sensors {
            row(&mut s, &c.name, "estimate", &c.offset);
            let _ = writeln!(
                s,
                "  {:<18} {:<10} {:>9.3}",
                "", "χ/row", c.normalised_residual
            );
            row(&mut s, "", "± σ", &c.offset_std);
            if let Some(r) = &c.rotation_offset {
                row(&mut s, "", "static", r);
            }
            if let Some(t) = &c.truth {
                row(&mut s, "", "simulated", t);
                row(&mut s, "", "error", &(c.offset - t));
            }
        }
        s
    }

    /// The scenario overlay that sets `estimation.ft_offsets.initial` (uncalibrated sensors at zero).
    pub fn to_toml(&self, source: &Path) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "# Force/torque sensor offsets estimated by `stride calibrate` from {} ({} samples, {:.1} s)\n\
             # [Traversaro 2017, ch. 5]. Use it as an overlay: include = [\"<this file>\"] after the robot and layer\n\
             # files; the estimation layer starts from these offsets (estimation.ft_offsets.initial, N and N m).",
            source.display(),
            self.samples,
            self.duration
        );
        let _ = writeln!(s, "[estimation.ft_offsets]\ninitial = [");
        for name in &self.all_sensors {
            match self.sensors.iter().find(|c| &c.name == name) {
                Some(c) => {
                    let v: Vec<String> = c.offset.iter().map(|x| format!("{x:?}")).collect();
                    let _ = writeln!(s, "  [{}], # {name}", v.join(", "));
                }
                None => {
                    let _ = writeln!(
                        s,
                        "  [0.0, 0.0, 0.0, 0.0, 0.0, 0.0], # {name} (not calibrated)"
                    );
                }
            }
        }
        s.push_str("]\n");
        s
    }
}
