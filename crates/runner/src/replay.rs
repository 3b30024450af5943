//! `stride replay`: rebuild one layer from a log's configuration (or another one) and feed it the logged
//! inputs, in order; compare its outputs with the logged ones.
//!
//! The log holds the merged scenario (`scenario.toml` attachment) and the URDF (`model.urdf`), so a log
//! replays on its own. With the log's configuration the outputs are reproduced bit-exactly (the layers are
//! deterministic, the inputs round-trip exactly through JSON); with another configuration the largest
//! difference shows how far the outputs moved, and `--output` writes them to a new log.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use stride_block::Block;
use stride_model::Model;
use stride_planner::{PlanSample, Planner};
use stride_simplified::{SimplifiedController, SimplifiedInput};
use stride_wbc::{QpIk, Tsid, WbcInput};

use crate::cli::LayerName;
use crate::config::{ControlMode, Scenario};
use crate::log::{read_log, LogContents, LogOptions, LogWriter};
use crate::records::{
    simplified_output_record, IkOutputRecord, PlanSampleRecord, PlannerInputRecord,
    TsidOutputRecord, WbcInputRecord,
};

/// Why a replay failed.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// Reading or writing a log.
    #[error(transparent)]
    Log(#[from] crate::log::LogError),
    /// The configuration.
    #[error(transparent)]
    Config(#[from] crate::config::ConfigError),
    /// The log lacks something or holds something unexpected.
    #[error("{0}")]
    Content(String),
}

/// The largest difference between replayed and logged outputs.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Difference {
    /// Largest absolute difference of a numeric field.
    pub max_abs: f64,
    /// Where (topic time and JSON path).
    pub at: String,
    /// Fields whose non-numeric values differ (flags, statuses, shapes).
    pub mismatches: usize,
}

/// Result of a replay.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReplayReport {
    /// Layer ticks replayed.
    pub ticks: usize,
    /// Difference from the logged outputs.
    pub difference: Difference,
    /// Layer errors during replay (the layer held its previous output, as in the run).
    pub layer_errors: usize,
}

fn diff(
    a: &serde_json::Value,
    b: &serde_json::Value,
    path: &mut String,
    d: &mut Difference,
    time: f64,
) {
    use serde_json::Value;
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (
                x.as_f64().unwrap_or(f64::NAN),
                y.as_f64().unwrap_or(f64::NAN),
            );
            let e = (x - y).abs();
            if e > d.max_abs || (e.is_nan() && !d.max_abs.is_nan()) {
                d.max_abs = e;
                d.at = format!("t = {time:.4} s, {path}");
            }
        }
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => {
            for (i, (p, q)) in x.iter().zip(y).enumerate() {
                let n = path.len();
                path.push_str(&format!("[{i}]"));
                diff(p, q, path, d, time);
                path.truncate(n);
            }
        }
        (Value::Object(x), Value::Object(y)) if x.len() == y.len() => {
            for (k, p) in x {
                let n = path.len();
                path.push('.');
                path.push_str(k);
                match y.get(k) {
                    Some(q) => diff(p, q, path, d, time),
                    None => d.mismatches += 1,
                }
                path.truncate(n);
            }
        }
        (x, y) => {
            if x != y {
                d.mismatches += 1;
                if d.at.is_empty() {
                    d.at = format!("t = {time:.4} s, {path}");
                }
            }
        }
    }
}

fn parse<T: serde::de::DeserializeOwned>(data: &[u8], topic: &str) -> Result<T, ReplayError> {
    serde_json::from_slice(data)
        .map_err(|e| ReplayError::Content(format!("a message on {topic} does not parse: {e}")))
}

/// The scenario stored in a log.
pub fn logged_scenario(log: &LogContents, log_path: &Path) -> Result<Scenario, ReplayError> {
    let text = log.attachments.get("scenario.toml").ok_or_else(|| {
        ReplayError::Content(format!(
            "{} holds no scenario.toml attachment",
            log_path.display()
        ))
    })?;
    let text = String::from_utf8_lossy(text).into_owned();
    Ok(Scenario::from_texts(vec![(
        log_path.join("scenario.toml"),
        text,
    )])?)
}

/// The model stored in a log.
pub fn logged_model(log: &LogContents, log_path: &Path) -> Result<Arc<Model>, ReplayError> {
    let urdf = log.attachments.get("model.urdf").ok_or_else(|| {
        ReplayError::Content(format!(
            "{} holds no model.urdf attachment",
            log_path.display()
        ))
    })?;
    Model::from_urdf_str(&String::from_utf8_lossy(urdf))
        .map(Arc::new)
        .map_err(|e| ReplayError::Content(format!("the URDF stored in the log does not load: {e}")))
}

/// Replays `layer` of the log at `log_path`; `config` replaces the logged scenario for the layer's
/// parameters; `output` receives the replayed outputs.
pub fn replay(
    log_path: &Path,
    layer: LayerName,
    config: Option<&Path>,
    output: Option<&PathBuf>,
) -> Result<ReplayReport, ReplayError> {
    let log = read_log(log_path)?;
    let logged = logged_scenario(&log, log_path)?;
    let scenario = match config {
        Some(p) => Scenario::load(p)?,
        None => logged.clone(),
    };
    let model = logged_model(&log, log_path)?;
    let c = &scenario.config;
    let mut writer = match output {
        Some(p) => {
            let mut w = LogWriter::create(p, &LogOptions::default())?;
            w.attach(
                "scenario.toml",
                "application/toml",
                scenario.merged_toml().into_bytes(),
            )?;
            if let Some(u) = log.attachments.get("model.urdf") {
                w.attach("model.urdf", "application/xml", u.clone())?;
            }
            Some(w)
        }
        None => None,
    };
    let mut report = ReplayReport::default();
    let mut path = String::new();
    let mut compare = |report: &mut ReplayReport,
                       writer: &mut Option<LogWriter>,
                       topic: &str,
                       t: u64,
                       replayed: serde_json::Value,
                       logged: &[u8]|
     -> Result<(), ReplayError> {
        let logged: serde_json::Value = parse(logged, topic)?;
        path.clear();
        diff(
            &replayed,
            &logged,
            &mut path,
            &mut report.difference,
            t as f64 * 1e-9,
        );
        report.ticks += 1;
        if let Some(w) = writer.as_mut() {
            let id = w.topic_id(topic)?;
            w.write(id, t, &replayed)?;
        }
        Ok(())
    };
    let to_value = |v: &dyn erased::Ser| v.value();
    match layer {
        LayerName::Planner => {
            let mut planner = Planner::new(c.planner.clone(), stride_model::STANDARD_GRAVITY)
                .map_err(|e| ReplayError::Content(format!("planner: {e}")))?;
            let mut sample = PlanSample::default();
            for m in &log.messages {
                match m.topic.as_str() {
                    "/planner/input" => {
                        let rec: PlannerInputRecord = parse(&m.data, &m.topic)?;
                        if planner.step(&rec.to_input()).is_err() {
                            report.layer_errors += 1;
                        }
                    }
                    "/planner/references" => {
                        planner
                            .sample(m.time_ns as f64 * 1e-9, &mut sample)
                            .map_err(|e| ReplayError::Content(format!("planner: {e}")))?;
                        let v = to_value(&PlanSampleRecord::from_sample(&sample));
                        compare(
                            &mut report,
                            &mut writer,
                            "/planner/references",
                            m.time_ns,
                            v,
                            &m.data,
                        )?;
                    }
                    _ => {}
                }
            }
        }
        LayerName::Simplified => {
            let period = Duration::from_nanos(1_000_000_000 / u64::from(c.rates.simplified_hz));
            let mut ctl = SimplifiedController::new(&c.simplified, period)
                .map_err(|e| ReplayError::Content(format!("simplified layer: {e}")))?;
            let outputs: Vec<_> = log.topic("/simplified/output").collect();
            for (i, m) in log.topic("/simplified/input").enumerate() {
                // With another configuration whose MPC horizon is longer, the layer pads the logged horizon.
                let input: SimplifiedInput = parse(&m.data, &m.topic)?;
                if ctl.step(&input).is_err() {
                    report.layer_errors += 1;
                }
                let out = simplified_output_record(ctl.output());
                let logged = outputs.get(i).ok_or_else(|| {
                    ReplayError::Content("fewer /simplified/output than inputs".into())
                })?;
                compare(
                    &mut report,
                    &mut writer,
                    "/simplified/output",
                    m.time_ns,
                    to_value(&out),
                    &logged.data,
                )?;
            }
        }
        LayerName::Wbc => {
            let period = 1.0 / f64::from(c.rates.wbc_hz);
            let outputs: Vec<_> = log.topic("/wbc/output").collect();
            let mut input = WbcInput::new(&model);
            let mode = c.scenario.control_mode;
            let mut ik = None;
            let mut tsid = None;
            match mode {
                ControlMode::Position => {
                    let mut cfg = c.wbc.ik.clone();
                    cfg.period = period;
                    ik = Some(
                        QpIk::new(Arc::clone(&model), cfg)
                            .map_err(|e| ReplayError::Content(format!("QP-IK: {e}")))?,
                    );
                }
                ControlMode::Torque => {
                    let mut cfg = c.wbc.tsid.clone();
                    cfg.period = period;
                    tsid = Some(
                        Tsid::new(Arc::clone(&model), cfg)
                            .map_err(|e| ReplayError::Content(format!("TSID: {e}")))?,
                    );
                }
            }
            for (i, m) in log.topic("/wbc/input").enumerate() {
                let rec: WbcInputRecord = parse(&m.data, &m.topic)?;
                rec.to_input(&mut input).map_err(ReplayError::Content)?;
                let v = if let Some(ik) = ik.as_mut() {
                    if ik.step(&input).is_err() {
                        report.layer_errors += 1;
                    }
                    to_value(&IkOutputRecord::new(ik.output()))
                } else if let Some(ts) = tsid.as_mut() {
                    if ts.step(&input).is_err() {
                        report.layer_errors += 1;
                    }
                    to_value(&TsidOutputRecord::new(ts.output()))
                } else {
                    return Err(ReplayError::Content("no whole-body controller".into()));
                };
                let logged = outputs
                    .get(i)
                    .ok_or_else(|| ReplayError::Content("fewer /wbc/output than inputs".into()))?;
                compare(
                    &mut report,
                    &mut writer,
                    "/wbc/output",
                    m.time_ns,
                    v,
                    &logged.data,
                )?;
            }
        }
    }
    if let Some(mut w) = writer {
        w.finish()?;
    }
    if report.ticks == 0 {
        return Err(ReplayError::Content(format!(
            "{} holds no logged outputs for that layer",
            log_path.display()
        )));
    }
    Ok(report)
}

/// Type-erased serialization to a JSON value.
mod erased {
    /// Anything serializable, as a JSON value.
    pub trait Ser {
        fn value(&self) -> serde_json::Value;
    }
    impl<T: serde::Serialize> Ser for T {
        fn value(&self) -> serde_json::Value {
            serde_json::to_value(self).unwrap_or(serde_json::Value::Null)
        }
    }
}
