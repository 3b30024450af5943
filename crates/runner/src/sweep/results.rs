//! The rows of a sweep: `results.csv`, `results.json`, merging shards and the terminal table.
//!
//! `results.json` is `{"variants": N, "shard": "I/N" or null, "columns": [...], "rows": [{...}]}`, rows by
//! variant index with the columns of `results.csv` in the same order. `wall_s` is the only wall-clock
//! column; [`merge`] keeps each shard's value.

use std::path::Path;

use serde::ser::{SerializeMap, Serializer};
use serde::Serialize;

use crate::run::{Outcome, RunSummary};

/// The columns after the axes, in order.
pub const METRIC_COLUMNS: [&str; 24] = [
    "outcome",
    "distance",
    "goal_distance",
    "dcm_rms",
    "max_tilt_deg",
    "wall_s",
    "est_drift_x_per_m",
    "est_drift_y_per_m",
    "est_final_position_error",
    "est_tilt_rms_deg",
    "est_tilt_max_deg",
    "step_adjustments",
    "steady_speed",
    "energy_cost",
    "fall_time",
    "fall_direction_deg",
    "fall_kind",
    "zmp_edge_time",
    "zmp_rms",
    "com_rms",
    "cop_bound_time",
    "push_holds",
    "dcm_rms_plant",
    "com_rms_plant",
];

/// One cell.
#[derive(Debug, Clone, PartialEq)]
pub enum Cell {
    /// An integer.
    Int(i64),
    /// A number.
    Float(f64),
    /// Text.
    Str(String),
    /// A boolean.
    Bool(bool),
    /// Nothing (an error row's metrics, a goal distance without a pose goal).
    Empty,
}

impl Cell {
    fn opt(x: Option<f64>) -> Self {
        x.filter(|x| x.is_finite()).map_or(Cell::Empty, Cell::Float)
    }

    /// From an axis value.
    pub fn from_toml(v: &toml::Value) -> Self {
        match v {
            toml::Value::Integer(i) => Cell::Int(*i),
            toml::Value::Float(f) => Cell::Float(*f),
            toml::Value::String(s) => Cell::Str(s.clone()),
            toml::Value::Boolean(b) => Cell::Bool(*b),
            other => Cell::Str(other.to_string()),
        }
    }

    fn from_json(v: &serde_json::Value) -> Self {
        match v {
            serde_json::Value::Null => Cell::Empty,
            serde_json::Value::Bool(b) => Cell::Bool(*b),
            serde_json::Value::Number(n) => n
                .as_i64()
                .map_or_else(|| Cell::Float(n.as_f64().unwrap_or(f64::NAN)), Cell::Int),
            serde_json::Value::String(s) => Cell::Str(s.clone()),
            other => Cell::Str(other.to_string()),
        }
    }

    /// The CSV text (shortest round-trip form of numbers; quoted when needed).
    pub fn csv(&self) -> String {
        match self {
            Cell::Int(i) => i.to_string(),
            Cell::Float(f) => f.to_string(),
            Cell::Bool(b) => b.to_string(),
            Cell::Empty => String::new(),
            Cell::Str(s) if s.contains([',', '"', '\n']) => {
                format!("\"{}\"", s.replace('"', "\"\""))
            }
            Cell::Str(s) => s.clone(),
        }
    }
}

impl Serialize for Cell {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Cell::Int(i) => s.serialize_i64(*i),
            Cell::Float(f) => s.serialize_f64(*f),
            Cell::Str(x) => s.serialize_str(x),
            Cell::Bool(b) => s.serialize_bool(*b),
            Cell::Empty => s.serialize_none(),
        }
    }
}

/// One variant's row: its index and the cells of `columns` (axes, then [`METRIC_COLUMNS`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// Variant index.
    pub variant: usize,
    /// Cells, one per column after `variant`.
    pub cells: Vec<Cell>,
}

/// The short outcome name of the results: `goal`, `fell`, `timeout` (the duration elapsed without the
/// goal, or the run was interrupted) or `error`.
pub fn outcome_name(o: &Outcome) -> &'static str {
    match o {
        Outcome::GoalReached => "goal",
        Outcome::Fell { .. } => "fell",
        Outcome::DurationReached | Outcome::Interrupted => "timeout",
        Outcome::Error { .. } => "error",
    }
}

/// The metric cells of a run (`wall_s` measured by the caller); `None`: the run did not start.
pub fn metric_cells(summary: Option<&RunSummary>, wall_s: f64) -> Vec<Cell> {
    let Some(s) = summary else {
        let mut cells = vec![Cell::Str("error".into())];
        cells.extend(std::iter::repeat_n(Cell::Empty, METRIC_COLUMNS.len() - 1));
        cells[5] = Cell::Float(wall_s);
        return cells;
    };
    let e = &s.estimation;
    let drift = e.drift_per_metre;
    let [px, py] = e.final_position_error;
    vec![
        Cell::Str(outcome_name(&s.outcome).into()),
        Cell::Float(s.distance),
        Cell::opt(s.goal_distance),
        Cell::Float(s.dcm_error.rms),
        Cell::Float(s.max_tilt_deg),
        Cell::Float(wall_s),
        Cell::opt(drift.map(|d| d[0])),
        Cell::opt(drift.map(|d| d[1])),
        Cell::Float(px.hypot(py)),
        Cell::Float(e.tilt_error.rms.to_degrees()),
        Cell::Float(e.tilt_error.max.to_degrees()),
        Cell::Int(i64::try_from(s.step_adjustments.0).unwrap_or(i64::MAX)),
        Cell::opt(s.gait.steady_speed),
        Cell::opt(s.gait.energy_cost),
        Cell::opt(s.diagnosis.fall.map(|f| f.time)),
        Cell::opt(s.diagnosis.fall.map(|f| f.direction_deg)),
        s.diagnosis
            .fall
            .map_or(Cell::Empty, |f| Cell::Str(f.kind.into())),
        Cell::Float(s.diagnosis.zmp_edge.at_edge),
        Cell::Float(s.zmp_error.rms),
        Cell::Float(s.com_error.rms),
        Cell::Float(s.diagnosis.cop_bound.at_edge),
        Cell::Int(i64::try_from(s.push_holds.0).unwrap_or(i64::MAX)),
        Cell::opt(s.plant_tracking.as_ref().map(|p| p.dcm_error.rms)),
        Cell::opt(s.plant_tracking.as_ref().map(|p| p.com_error.rms)),
    ]
}

/// A results table: all columns (`variant` first), the total number of variants of the sweep, the shard.
#[derive(Debug, Clone, PartialEq)]
pub struct Results {
    /// Column names, `variant` first.
    pub columns: Vec<String>,
    /// Variants in the whole sweep.
    pub variants: usize,
    /// `I/N` when these are one shard's rows.
    pub shard: Option<String>,
    /// Rows by variant index.
    pub rows: Vec<Row>,
}

struct JsonRow<'a>(&'a [String], &'a Row);

impl Serialize for JsonRow<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        m.serialize_entry("variant", &self.1.variant)?;
        for (c, v) in self.0[1..].iter().zip(&self.1.cells) {
            m.serialize_entry(c, v)?;
        }
        m.end()
    }
}

#[derive(Serialize)]
struct JsonDoc<'a> {
    variants: usize,
    shard: Option<&'a str>,
    columns: &'a [String],
    rows: Vec<JsonRow<'a>>,
}

impl Results {
    /// Writes `results.csv` and `results.json` into `dir`.
    pub fn write(&self, dir: &Path) -> std::io::Result<()> {
        std::fs::create_dir_all(dir)?;
        let mut csv = self.columns.join(",");
        csv.push('\n');
        for r in &self.rows {
            csv.push_str(&r.variant.to_string());
            for c in &r.cells {
                csv.push(',');
                csv.push_str(&c.csv());
            }
            csv.push('\n');
        }
        std::fs::write(dir.join("results.csv"), csv)?;
        let rows: Vec<JsonRow<'_>> = self
            .rows
            .iter()
            .map(|r| JsonRow(&self.columns, r))
            .collect();
        let doc = JsonDoc {
            variants: self.variants,
            shard: self.shard.as_deref(),
            columns: &self.columns,
            rows,
        };
        let text = serde_json::to_string_pretty(&doc).map_err(std::io::Error::other)?;
        std::fs::write(dir.join("results.json"), text + "\n")
    }

    /// Reads `dir/results.json`.
    pub fn read(dir: &Path) -> Result<Self, String> {
        let path = dir.join("results.json");
        let text =
            std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let bad = |what: &str| format!("{}: {what}", path.display());
        let doc: serde_json::Value =
            serde_json::from_str(&text).map_err(|e| bad(&e.to_string()))?;
        let columns: Vec<String> = serde_json::from_value(doc["columns"].clone())
            .map_err(|_| bad("expected `columns`, an array of names"))?;
        let variants = doc["variants"]
            .as_u64()
            .ok_or_else(|| bad("expected `variants`, a count"))? as usize;
        let shard = doc["shard"].as_str().map(str::to_string);
        let mut rows = Vec::new();
        for r in doc["rows"]
            .as_array()
            .ok_or_else(|| bad("expected `rows`"))?
        {
            let variant = r["variant"]
                .as_u64()
                .ok_or_else(|| bad("a row without `variant`"))? as usize;
            let cells = columns[1..]
                .iter()
                .map(|c| Cell::from_json(&r[c.as_str()]))
                .collect();
            rows.push(Row { variant, cells });
        }
        Ok(Self {
            columns,
            variants,
            shard,
            rows,
        })
    }
}

/// Combines shards' results into the results of the whole sweep: same columns and variant count, every
/// variant exactly once. Rows (their `wall_s` included) are kept as the shards wrote them.
pub fn merge(parts: Vec<Results>) -> Result<Results, String> {
    let first = parts.first().ok_or("nothing to merge")?;
    let (columns, variants) = (first.columns.clone(), first.variants);
    let mut rows: Vec<Option<Row>> = vec![None; variants];
    for p in parts {
        if p.columns != columns || p.variants != variants {
            return Err(format!(
                "shard {} is of another sweep (columns or variant count differ)",
                p.shard.as_deref().unwrap_or("-")
            ));
        }
        for r in p.rows {
            let i = r.variant;
            let slot = rows
                .get_mut(i)
                .ok_or_else(|| format!("variant {i} out of range (the sweep has {variants})"))?;
            if slot.is_some() {
                return Err(format!("variant {i} appears in two shards"));
            }
            *slot = Some(r);
        }
    }
    let missing: Vec<usize> = (0..variants).filter(|&i| rows[i].is_none()).collect();
    if !missing.is_empty() {
        return Err(format!(
            "{} of {variants} variants missing (first: {}); merge every shard",
            missing.len(),
            missing[0]
        ));
    }
    Ok(Results {
        columns,
        variants,
        shard: None,
        rows: rows.into_iter().flatten().collect(),
    })
}

/// Outcome counts per value of each axis column, as printed at the end of `stride sweep`.
pub fn outcome_table(r: &Results, axes: usize) -> String {
    use std::fmt::Write as _;
    let outcome_at = axes;
    let names = ["goal", "fell", "timeout", "error"];
    let mut s = String::new();
    let _ = writeln!(
        s,
        "  {:<34} {:>14} {:>6} {:>6} {:>8} {:>6}",
        "axis", "value", names[0], names[1], names[2], names[3]
    );
    for a in 0..axes {
        let mut values: Vec<(String, [usize; 4])> = Vec::new();
        for row in &r.rows {
            let v = row.cells[a].csv();
            let o = match &row.cells[outcome_at] {
                Cell::Str(o) => names.iter().position(|n| n == o).unwrap_or(3),
                _ => 3,
            };
            match values.iter_mut().find(|(x, _)| *x == v) {
                Some((_, c)) => c[o] += 1,
                None => {
                    let mut c = [0; 4];
                    c[o] += 1;
                    values.push((v, c));
                }
            }
        }
        for (v, c) in values {
            let _ = writeln!(
                s,
                "  {:<34} {:>14} {:>6} {:>6} {:>8} {:>6}",
                r.columns[a + 1],
                v,
                c[0],
                c[1],
                c[2],
                c[3]
            );
        }
    }
    let mut total = [0; 4];
    for row in &r.rows {
        if let Cell::Str(o) = &row.cells[outcome_at] {
            total[names.iter().position(|n| n == o).unwrap_or(3)] += 1;
        }
    }
    let _ = writeln!(
        s,
        "  {:<34} {:>14} {:>6} {:>6} {:>8} {:>6}",
        "all",
        r.rows.len(),
        total[0],
        total[1],
        total[2],
        total[3]
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::summary::PlantTracking;

    fn column(name: &str) -> usize {
        METRIC_COLUMNS
            .iter()
            .position(|c| *c == name)
            .unwrap_or_else(|| panic!("no column {name}"))
    }

    #[test]
    fn the_plant_columns_are_empty_without_a_plant_model_and_its_errors_with_one() {
        let mut summary = RunSummary::new("walk", "simulator");
        let cells = metric_cells(Some(&summary), 1.0);
        assert_eq!(cells.len(), METRIC_COLUMNS.len());
        assert_eq!(cells[column("dcm_rms_plant")], Cell::Empty);
        assert_eq!(cells[column("com_rms_plant")], Cell::Empty);

        let mut plant = PlantTracking::default();
        plant.dcm_error.add(0.003);
        plant.dcm_error.add(0.004);
        plant.com_error.add(0.002);
        summary.plant_tracking = Some(plant);
        let cells = metric_cells(Some(&summary), 1.0);
        // RMS of 3 and 4 mm: √((9 + 16) / 2) mm.
        assert_eq!(
            cells[column("dcm_rms_plant")],
            Cell::Float((12.5e-6_f64).sqrt())
        );
        assert_eq!(cells[column("com_rms_plant")], Cell::Float(0.002));
        // The controllers' view stays in `dcm_rms`.
        assert_eq!(cells[column("dcm_rms")], Cell::Float(0.0));
    }
}
