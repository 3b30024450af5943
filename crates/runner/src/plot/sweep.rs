//! The survival map of a sweep: `results.json` rows (one per variant) on a grid of two axes, each cell
//! coloured by the outcomes of its rows (the share of `goal` when the other axes vary).

use std::fmt;
use std::path::Path;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use serde::de::{Deserialize, Deserializer, MapAccess, Visitor};
use serde_json::Value;

use super::PlotError;

/// Whether a key of a row is a result (the variant index or one of `stride sweep`'s metric columns), not an
/// axis.
fn is_result(key: &str) -> bool {
    key == "variant" || crate::sweep::METRIC_COLUMNS.contains(&key)
}

/// The outcomes of a run and their colours.
pub const OUTCOMES: [(&str, RGBColor); 4] = [
    ("goal", RGBColor(44, 160, 44)),
    ("fell", RGBColor(214, 39, 40)),
    ("timeout", RGBColor(255, 127, 14)),
    ("error", RGBColor(127, 127, 127)),
];

/// One row of `results.json`, its keys in file order (the axes are the non-result keys, in order).
#[derive(Debug, Clone)]
pub struct Row(pub Vec<(String, Value)>);

impl<'de> Deserialize<'de> for Row {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Row;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("an object")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut m: A) -> Result<Row, A::Error> {
                let mut out = Vec::new();
                while let Some((k, v)) = m.next_entry::<String, Value>()? {
                    out.push((k, v));
                }
                Ok(Row(out))
            }
        }
        d.deserialize_map(V)
    }
}

impl Row {
    fn get(&self, key: &str) -> Option<&Value> {
        self.0.iter().find(|(k, _)| k == key).map(|(_, v)| v)
    }
}

/// The colour of a cell: its outcome's when all its rows agree, else between `fell` (no `goal`) and
/// `goal` (all `goal`) by the share of `goal`.
pub fn cell_color(outcomes: &[&str]) -> RGBColor {
    let first = outcomes.first().copied().unwrap_or("error");
    if outcomes.iter().all(|o| *o == first) {
        return OUTCOMES
            .iter()
            .find(|(n, _)| *n == first)
            .map_or(OUTCOMES[3].1, |c| c.1);
    }
    let share = outcomes.iter().filter(|o| **o == "goal").count() as f64 / outcomes.len() as f64;
    let (g, f) = (OUTCOMES[0].1, OUTCOMES[1].1);
    let mix = |a: u8, b: u8| (f64::from(b) + share * (f64::from(a) - f64::from(b))).round() as u8;
    RGBColor(mix(g.0, f.0), mix(g.1, f.1), mix(g.2, f.2))
}

/// The rows of a `results.json`: `stride sweep`'s object (`{"variants", "shard", "columns", "rows": [...]}`) or
/// a bare array of rows.
fn parse_rows(text: &str) -> Result<Vec<Row>, serde_json::Error> {
    #[derive(serde::Deserialize)]
    struct Results {
        rows: Vec<Row>,
    }
    #[derive(serde::Deserialize)]
    #[serde(untagged)]
    enum File {
        Sweep(Results),
        Rows(Vec<Row>),
    }
    Ok(match serde_json::from_str(text)? {
        File::Sweep(r) => r.rows,
        File::Rows(rows) => rows,
    })
}

/// The axis keys of the rows: every key of the first row that is not a result, in file order.
pub fn axes(rows: &[Row]) -> Vec<String> {
    rows.first().map_or_else(Vec::new, |r| {
        r.0.iter()
            .map(|(k, _)| k.clone())
            .filter(|k| !is_result(k))
            .collect()
    })
}

fn label(v: Option<&Value>) -> String {
    match v {
        Some(Value::String(s)) => s.clone(),
        Some(v) => v.to_string(),
        None => "-".into(),
    }
}

/// The distinct values of an axis, numbers in increasing order, else in order of appearance.
fn categories(rows: &[Row], key: &str) -> Vec<String> {
    let mut vals: Vec<(String, Option<f64>)> = Vec::new();
    for r in rows {
        let v = r.get(key);
        let l = label(v);
        if !vals.iter().any(|(x, _)| *x == l) {
            vals.push((l, v.and_then(Value::as_f64)));
        }
    }
    if vals.iter().all(|(_, n)| n.is_some()) {
        vals.sort_by(|a, b| a.1.unwrap_or(0.0).total_cmp(&b.1.unwrap_or(0.0)));
    }
    vals.into_iter().map(|(l, _)| l).collect()
}

fn err<E: std::fmt::Display>(e: E) -> PlotError {
    PlotError::Draw(e.to_string())
}

/// Reads `results.json` and writes `survival_<x>_<y>.svg` into `dir`; returns the file.
pub fn plot_sweep(
    results: &Path,
    dir: &Path,
    x: Option<&str>,
    y: Option<&str>,
) -> Result<std::path::PathBuf, PlotError> {
    let text = std::fs::read_to_string(results).map_err(|e| PlotError::Io {
        path: results.into(),
        source: e,
    })?;
    let rows =
        parse_rows(&text).map_err(|e| PlotError::Log(format!("{}: {e}", results.display())))?;
    let axes = axes(&rows);
    let pick = |chosen: Option<&str>, default: usize, flag: &str| -> Result<String, PlotError> {
        match chosen {
            Some(a) if axes.iter().any(|k| k == a) => Ok(a.to_string()),
            Some(a) => Err(PlotError::Usage(format!(
                "{flag} {a}: not an axis of {}; its axes are: {}",
                results.display(),
                axes.join(", ")
            ))),
            None => axes.get(default).cloned().ok_or_else(|| {
                PlotError::Usage(format!(
                    "{}: {} axis(es) ({}); a survival map needs two",
                    results.display(),
                    axes.len(),
                    axes.join(", ")
                ))
            }),
        }
    };
    let xk = pick(x, 0, "--x")?;
    let yk = pick(y, 1, "--y")?;
    std::fs::create_dir_all(dir).map_err(|e| PlotError::Io {
        path: dir.to_path_buf(),
        source: e,
    })?;
    let file = dir.join(format!("survival_{xk}_{yk}.svg"));
    draw_map(&file, &rows, &xk, &yk)?;
    Ok(file)
}

fn draw_map(file: &Path, rows: &[Row], xk: &str, yk: &str) -> Result<(), PlotError> {
    let (xs, ys) = (categories(rows, xk), categories(rows, yk));
    let root = SVGBackend::new(file, (900, 640)).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let (nx, ny) = (xs.len() as f64, ys.len() as f64);
    let (left, right) = root.split_horizontally(700);
    let mut chart = ChartBuilder::on(&left)
        .caption(
            format!(
                "survival map: {} runs, share of `goal` per cell",
                rows.len()
            ),
            ("sans-serif", 20),
        )
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(-0.5..nx - 0.5, -0.5..ny - 0.5)
        .map_err(err)?;
    let at = |v: &[String], f: f64| {
        let i = f.round();
        if (f - i).abs() < 1e-6 && i >= 0.0 {
            v.get(i as usize).cloned().unwrap_or_default()
        } else {
            String::new()
        }
    };
    chart
        .configure_mesh()
        .disable_mesh()
        .x_labels(xs.len() * 2 + 1)
        .y_labels(ys.len() * 2 + 1)
        .x_label_formatter(&|f| at(&xs, *f))
        .y_label_formatter(&|f| at(&ys, *f))
        .x_desc(xk)
        .y_desc(yk)
        .draw()
        .map_err(err)?;
    for (i, xv) in xs.iter().enumerate() {
        for (j, yv) in ys.iter().enumerate() {
            let outcomes: Vec<&str> = rows
                .iter()
                .filter(|r| label(r.get(xk)) == *xv && label(r.get(yk)) == *yv)
                .map(|r| r.get("outcome").and_then(Value::as_str).unwrap_or("error"))
                .collect();
            if outcomes.is_empty() {
                continue;
            }
            let (x, y) = (i as f64, j as f64);
            let goals = outcomes.iter().filter(|o| **o == "goal").count();
            let text = if outcomes.len() == 1 {
                outcomes[0].to_string()
            } else {
                format!("{goals}/{} goal", outcomes.len())
            };
            let style = ("sans-serif", 14)
                .into_font()
                .color(&BLACK)
                .pos(Pos::new(HPos::Center, VPos::Center));
            chart
                .draw_series([Rectangle::new(
                    [(x - 0.48, y - 0.48), (x + 0.48, y + 0.48)],
                    cell_color(&outcomes).filled(),
                )])
                .map_err(err)?;
            chart
                .draw_series([Text::new(text, (x, y), style)])
                .map_err(err)?;
        }
    }
    draw_legend(&right)?;
    root.present().map_err(err)
}

/// Outcome colours and the mixed colour, beside the map (swatches 14 px wide).
fn draw_legend(
    area: &DrawingArea<SVGBackend<'_>, plotters::coord::Shift>,
) -> Result<(), PlotError> {
    let half = cell_color(&["goal", "fell"]);
    let entries = OUTCOMES
        .iter()
        .map(|(n, c)| (format!("all {n}"), *c))
        .chain([("mixed: fell → goal".to_string(), half)]);
    for (k, (text, color)) in entries.enumerate() {
        let y = 80 + 24 * k as i32;
        area.draw(&Rectangle::new([(10, y), (24, y + 14)], color.filled()))
            .map_err(err)?;
        area.draw(&Text::new(
            text,
            (32, y + 2),
            ("sans-serif", 14).into_font(),
        ))
        .map_err(err)?;
    }
    area.draw(&Text::new(
        "(colour by share of goal)",
        (10, 80 + 24 * 5),
        ("sans-serif", 12).into_font(),
    ))
    .map_err(err)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_stride_sweeps_results_and_bare_rows_alike() {
        let row = r#"{"variant": 0, "sim.model.mass_scale": 1.1, "push.magnitude": 20.0, "outcome": "goal",
            "distance": 2.0, "goal_distance": 0.01, "dcm_rms": 0.01, "max_tilt_deg": 5.0, "wall_s": 1.0,
            "est_drift_x_per_m": null, "est_tilt_rms_deg": 0.2}"#;
        let sweep =
            format!(r#"{{"variants": 1, "shard": null, "columns": ["variant"], "rows": [{row}]}}"#);
        for text in [sweep, format!("[{row}]")] {
            let rows = parse_rows(&text).unwrap();
            assert_eq!(rows.len(), 1);
            assert_eq!(axes(&rows), ["sim.model.mass_scale", "push.magnitude"]);
        }
        assert!(parse_rows(r#"{"rows": 3}"#).is_err());
    }

    #[test]
    fn mixed_cells_run_from_fell_to_goal() {
        assert_eq!(cell_color(&["goal"]), RGBColor(44, 160, 44));
        assert_eq!(cell_color(&["timeout", "timeout"]), RGBColor(255, 127, 14));
        assert_eq!(cell_color(&["goal", "fell"]), RGBColor(129, 100, 42));
        assert_eq!(
            cell_color(&["goal", "timeout", "timeout", "fell"]),
            RGBColor(172, 69, 41)
        );
    }

    #[test]
    fn axes_are_the_non_result_keys_in_file_order() {
        let rows: Vec<Row> = serde_json::from_str(
            r#"[{"variant": "a", "push.start": 1, "push.magnitude": 2, "outcome": "goal", "sim.friction": 0.5}]"#,
        )
        .unwrap();
        assert_eq!(
            axes(&rows),
            ["push.start", "push.magnitude", "sim.friction"]
        );
    }
}
