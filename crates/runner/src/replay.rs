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

use stride_model::{Model, RobotState};
use stride_planner::{PlanSample, Planner};
use stride_simplified::{SimplifiedController, SimplifiedInput};

use crate::cli::LayerName;
use crate::config::Scenario;
use crate::log::{read_log, LogContents, LogOptions, LogWriter};
use crate::records::{
    simplified_output_record, IkOutputRecord, PlanSampleRecord, PlannerInputRecord,
    TsidOutputRecord, WbcInputRecord, LOG_FORMAT,
};
use crate::stack::Wbc;

/// Why a replay failed.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// Reading or writing a log.
    #[error(transparent)]
    Log(#[from] crate::log::LogError),
    /// The configuration.
    #[error(transparent)]
    Config(#[from] crate::config::ConfigError),
    /// A layer could not be built.
    #[error(transparent)]
    Layer(#[from] crate::error::RunError),
    /// The planner failed to sample its plan.
    #[error("planner: {0}")]
    Planner(#[from] stride_planner::PlannerError),
    /// The simplified layer could not be built.
    #[error("simplified layer: {0}")]
    Simplified(#[from] stride_simplified::SimplifiedError),
    /// The URDF stored in the log does not load.
    #[error("the URDF stored in the log does not load: {0}")]
    Model(#[from] stride_model::ModelError),
    /// The log was written in another message format than this version reads.
    #[error(
        "{}: log format {found}, this stride replays log format {expected} only (run the scenario again to \
         record a log in the current format)",
        path.display()
    )]
    Format {
        /// The log file.
        path: PathBuf,
        /// The `log_format` of its `stride` metadata (`1` when it has none: logs older than the entry).
        found: String,
        /// [`LOG_FORMAT`].
        expected: u32,
    },
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

/// The `log_format` entry of a log's `stride` metadata record; `"1"` when it has none (the logs written
/// before the entry existed).
pub fn logged_format(log: &LogContents) -> &str {
    log.metadata
        .get("stride")
        .and_then(|m| m.get("log_format"))
        .map_or("1", String::as_str)
}

/// `Ok` when the log at `log_path` is in the message format this version replays ([`LOG_FORMAT`]).
pub fn check_format(log: &LogContents, log_path: &Path) -> Result<(), ReplayError> {
    let found = logged_format(log);
    if found == LOG_FORMAT.to_string() {
        return Ok(());
    }
    Err(ReplayError::Format {
        path: log_path.to_path_buf(),
        found: found.to_string(),
        expected: LOG_FORMAT,
    })
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
    Ok(Arc::new(Model::from_urdf_str(&String::from_utf8_lossy(
        urdf,
    ))?))
}

/// Compares replayed outputs with logged ones and writes them to the output log, if any.
struct Comparison {
    report: ReplayReport,
    writer: Option<LogWriter>,
    path: String,
}

impl Comparison {
    fn add(
        &mut self,
        topic: &str,
        t: u64,
        replayed: &dyn erased::Ser,
        logged: &[u8],
    ) -> Result<(), ReplayError> {
        let replayed = replayed.value();
        let logged: serde_json::Value = parse(logged, topic)?;
        self.path.clear();
        diff(
            &replayed,
            &logged,
            &mut self.path,
            &mut self.report.difference,
            t as f64 * 1e-9,
        );
        self.report.ticks += 1;
        if let Some(w) = self.writer.as_mut() {
            let id = w.topic_id(topic)?;
            w.write(id, t, &replayed)?;
        }
        Ok(())
    }
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
    check_format(&log, log_path)?;
    let scenario = match config {
        Some(p) => Scenario::load(p)?,
        None => logged_scenario(&log, log_path)?,
    };
    let model = logged_model(&log, log_path)?;
    let writer = match output {
        Some(p) => Some(output_log(p, &scenario, &log)?),
        None => None,
    };
    let mut cmp = Comparison {
        report: ReplayReport::default(),
        writer,
        path: String::new(),
    };
    match layer {
        LayerName::Planner => replay_planner(&scenario, &log, &mut cmp)?,
        LayerName::Simplified => replay_simplified(&scenario, &log, &mut cmp)?,
        LayerName::Wbc => replay_wbc(&scenario, &model, &log, &mut cmp)?,
    }
    if let Some(mut w) = cmp.writer {
        w.finish()?;
    }
    if cmp.report.ticks == 0 {
        return Err(ReplayError::Content(format!(
            "{} holds no logged outputs for that layer",
            log_path.display()
        )));
    }
    Ok(cmp.report)
}

/// The log replayed outputs go to: the scenario used and the logged URDF attached, the logged `stride`
/// metadata (with its `log_format`) copied.
fn output_log(
    path: &Path,
    scenario: &Scenario,
    log: &LogContents,
) -> Result<LogWriter, ReplayError> {
    let mut w = LogWriter::create(path, &LogOptions::default())?;
    w.attach(
        "scenario.toml",
        "application/toml",
        scenario.merged_toml().into_bytes(),
    )?;
    if let Some(u) = log.attachments.get("model.urdf") {
        w.attach("model.urdf", "application/xml", u.clone())?;
    }
    let mut metadata = log.metadata.get("stride").cloned().unwrap_or_default();
    metadata.insert("log_format".into(), LOG_FORMAT.to_string());
    w.metadata("stride", metadata)?;
    Ok(w)
}

/// The planner: every logged `/planner/input` replans, every `/planner/references` samples.
fn replay_planner(
    scenario: &Scenario,
    log: &LogContents,
    cmp: &mut Comparison,
) -> Result<(), ReplayError> {
    let c = &scenario.config;
    let mut planner = Planner::new(c.planner.clone(), c.scenario.gravity)?;
    let mut sample = PlanSample::default();
    for m in &log.messages {
        match m.topic.as_str() {
            "/planner/input" => {
                let rec: PlannerInputRecord = parse(&m.data, &m.topic)?;
                if planner.step(&rec.to_input()).is_err() {
                    cmp.report.layer_errors += 1;
                }
            }
            "/planner/references" => {
                planner.sample(Duration::from_nanos(m.time_ns), &mut sample)?;
                let replayed = PlanSampleRecord::from_sample(&sample);
                cmp.add("/planner/references", m.time_ns, &replayed, &m.data)?;
            }
            _ => {}
        }
    }
    Ok(())
}

/// The simplified layer on the logged `/simplified/input`s.
fn replay_simplified(
    scenario: &Scenario,
    log: &LogContents,
    cmp: &mut Comparison,
) -> Result<(), ReplayError> {
    let c = &scenario.config;
    let period = Duration::from_nanos(1_000_000_000 / u64::from(c.rates.simplified_hz));
    let mut ctl = SimplifiedController::new(&c.simplified, period)?;
    let outputs: Vec<_> = log.topic("/simplified/output").collect();
    for (i, m) in log.topic("/simplified/input").enumerate() {
        // With another configuration whose MPC horizon is longer, the layer pads the logged horizon.
        let input: SimplifiedInput = parse(&m.data, &m.topic)?;
        if ctl.step(&input).is_err() {
            cmp.report.layer_errors += 1;
        }
        let logged = outputs
            .get(i)
            .ok_or_else(|| ReplayError::Content("fewer /simplified/output than inputs".into()))?;
        let replayed = simplified_output_record(ctl.output());
        cmp.add("/simplified/output", m.time_ns, &replayed, &logged.data)?;
    }
    Ok(())
}

/// The whole-body layer of the scenario's control mode on the logged `/wbc/input`s.
fn replay_wbc(
    scenario: &Scenario,
    model: &Arc<Model>,
    log: &LogContents,
    cmp: &mut Comparison,
) -> Result<(), ReplayError> {
    let mut wbc = Wbc::new(scenario, model)?;
    let outputs: Vec<_> = log.topic("/wbc/output").collect();
    let mut input = wbc.input(&RobotState::zero(model));
    for (i, m) in log.topic("/wbc/input").enumerate() {
        let rec: WbcInputRecord = parse(&m.data, &m.topic)?;
        rec.to_input(&mut input).map_err(ReplayError::Content)?;
        let logged = outputs
            .get(i)
            .ok_or_else(|| ReplayError::Content("fewer /wbc/output than inputs".into()))?;
        match &mut wbc {
            Wbc::Ik(ik) => {
                if ik.step(&input).is_err() {
                    cmp.report.layer_errors += 1;
                }
                let replayed = IkOutputRecord::new(ik.output());
                cmp.add("/wbc/output", m.time_ns, &replayed, &logged.data)?;
            }
            Wbc::Tsid(ts) => {
                if ts.step(&input).is_err() {
                    cmp.report.layer_errors += 1;
                }
                let replayed = TsidOutputRecord::new(ts.output());
                cmp.add("/wbc/output", m.time_ns, &replayed, &logged.data)?;
            }
        }
    }
    Ok(())
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
