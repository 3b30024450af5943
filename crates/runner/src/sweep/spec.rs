//! The sweep file (`[sweep]`), its variants, and each variant's scenario.
//!
//! A variant is the base scenario with one setting per axis (and one push, with `[sweep.push]`). Its
//! scenario is built by overlaying a generated TOML file on the scenario's files and loading the result
//! exactly as a scenario file is loaded ([`Scenario::from_texts`]): a key the scenario schema does not know,
//! a value of the wrong type or out of range is rejected by the same code. Errors located in the generated
//! overlay are moved to the line of the sweep file that wrote the key or the value.
//!
//! | key | unit | default | meaning |
//! |---|---|---|---|
//! | `sweep.scenario` | – | required | scenario file, relative to the sweep file |
//! | `sweep.mode` | – | `grid` | `grid` (every combination) or `random` (`samples` draws) |
//! | `sweep.samples` | – | required with `random` | number of variants |
//! | `sweep.seed` | – | 0 | seed of the random draws (ChaCha8) |
//! | `sweep.axes[].key` | – | required | dotted scenario key, array entries as `key[i]` |
//! | `sweep.axes[].values` | key's | – | the values (grid; random picks one uniformly) |
//! | `sweep.axes[].min`, `max` | key's | – | random only: uniform draw in `[min, max]` |
//! | `sweep.push.frame` | – | required | model frame the push acts at |
//! | `sweep.push.duration` | s | required | push duration |
//! | `sweep.push.magnitudes` | N | required | horizontal force magnitudes |
//! | `sweep.push.directions_deg` | deg | `[0]` | force direction, 0 = +x of the initial heading, 90 = +y |
//! | `sweep.push.starts` | s | required | push start times |

use std::ops::Range;
use std::path::{Path, PathBuf};

use rand::{Rng, SeedableRng};
use serde::Deserialize;
use toml::Spanned;

use crate::config::{ConfigError, Location, Scenario};

/// How the variants are chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Mode {
    /// Every combination of the axes' values (the last axis varies fastest).
    #[default]
    Grid,
    /// `samples` independent draws from the seeded generator.
    Random,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SweepFile {
    sweep: SweepSection,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SweepSection {
    scenario: Spanned<String>,
    #[serde(default)]
    mode: Mode,
    samples: Option<Spanned<usize>>,
    #[serde(default)]
    seed: u64,
    #[serde(default)]
    axes: Vec<Spanned<AxisSpec>>,
    push: Option<Spanned<PushSpec>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct AxisSpec {
    key: Spanned<String>,
    values: Option<Vec<Spanned<toml::Value>>>,
    min: Option<Spanned<f64>>,
    max: Option<Spanned<f64>>,
}

/// `[sweep.push]`: one horizontal push per variant.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PushSpec {
    /// Model frame the push acts at.
    pub frame: String,
    /// Duration \[s\].
    pub duration: f64,
    /// Horizontal force magnitudes \[N\].
    pub magnitudes: Vec<f64>,
    /// Directions \[deg\], 0 = +x of the initial heading (runs start facing +x), 90 = +y.
    #[serde(default = "zero_direction")]
    pub directions_deg: Vec<f64>,
    /// Start times \[s\].
    pub starts: Vec<f64>,
}

fn zero_direction() -> Vec<f64> {
    vec![0.0]
}

/// The push of one variant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PushSetting {
    /// Force magnitude \[N\].
    pub magnitude: f64,
    /// Direction \[deg\] from +x towards +y.
    pub direction_deg: f64,
    /// Start \[s\].
    pub start: f64,
}

/// One axis: a key and what it takes.
#[derive(Debug, Clone)]
struct Axis {
    key: String,
    key_span: Range<usize>,
    values: Vec<(toml::Value, Range<usize>)>,
    range: Option<(f64, f64)>,
}

/// One run of the sweep: its index and settings.
#[derive(Debug, Clone)]
pub struct Variant {
    /// Index in the whole sweep (0-based; shards and result rows use it).
    pub index: usize,
    /// One value per axis, in the order of `[[sweep.axes]]`.
    pub values: Vec<toml::Value>,
    /// The push, with `[sweep.push]`.
    pub push: Option<PushSetting>,
}

/// A loaded, checked sweep: the base scenario, the variants and their scenarios.
#[derive(Debug)]
pub struct Sweep {
    /// The sweep file.
    pub path: PathBuf,
    /// The base scenario.
    pub base: Scenario,
    /// Axis keys as written, then `push.magnitude`, `push.direction_deg`, `push.start` with a push grid.
    pub columns: Vec<String>,
    /// Every variant, by index.
    pub variants: Vec<Variant>,
    push: Option<PushSpec>,
}

/// Column names of the push grid.
pub const PUSH_COLUMNS: [&str; 3] = ["push.magnitude", "push.direction_deg", "push.start"];

impl Sweep {
    /// Reads the sweep file and its scenario, and checks every axis value against the scenario schema
    /// (see the module doc); nothing runs.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|e| ConfigError::Io {
            path: path.to_path_buf(),
            source: e,
        })?;
        let at = |span: &Range<usize>| locate(path, &text, span.start);
        let file: SweepFile = toml::from_str(&text).map_err(|e| {
            let message = e.message().to_string();
            let key = message
                .strip_prefix("unknown field `")
                .and_then(|r| r.split('`').next())
                .map_or_else(|| "sweep".to_string(), |f| format!("sweep.{f}"));
            ConfigError::Invalid {
                location: Some(locate(path, &text, e.span().map_or(0, |s| s.start))),
                key,
                message,
            }
        })?;
        let s = file.sweep;
        let invalid = |span: &Range<usize>, key: &str, message: String| ConfigError::Invalid {
            location: Some(at(span)),
            key: key.into(),
            message,
        };
        let dir = path.parent().map_or_else(PathBuf::new, Path::to_path_buf);
        let base = Scenario::load(&dir.join(s.scenario.get_ref()))?;
        let mut axes = Vec::new();
        for a in &s.axes {
            axes.push(axis(a, s.mode, &invalid)?);
        }
        let push = s.push.as_ref().map(|p| p.get_ref().clone());
        if let Some(p) = &s.push {
            check_push(p.get_ref()).map_err(|m| invalid(&p.span(), "sweep.push", m))?;
        }
        let mut columns: Vec<String> = axes.iter().map(|a| a.key.clone()).collect();
        if push.is_some() {
            columns.extend(PUSH_COLUMNS.iter().map(|c| c.to_string()));
        }
        let variants = match s.mode {
            Mode::Grid => {
                if s.samples.is_some() {
                    let sp = s.samples.as_ref().map(|x| x.span()).unwrap_or_default();
                    return Err(invalid(
                        &sp,
                        "sweep.samples",
                        "only with mode = \"random\"".into(),
                    ));
                }
                grid(&axes, push.as_ref())
            }
            Mode::Random => {
                let n = s.samples.as_ref().map(|x| *x.get_ref()).ok_or_else(|| {
                    invalid(
                        &(0..0),
                        "sweep.samples",
                        "mode = \"random\" needs `samples = N`".into(),
                    )
                })?;
                random(&axes, push.as_ref(), n, s.seed)
            }
        };
        let sweep = Self {
            path: path.to_path_buf(),
            base,
            columns,
            variants,
            push,
        };
        sweep.check_axes(&axes, &text)?;
        Ok(sweep)
    }

    /// Applies each axis value alone to the scenario; an error in the overlay names the sweep file's line.
    fn check_axes(&self, axes: &[Axis], text: &str) -> Result<(), ConfigError> {
        for a in axes {
            let mut probes: Vec<(toml::Value, Range<usize>)> = a.values.clone();
            if let Some((lo, hi)) = a.range {
                probes.push((toml::Value::Float(lo), a.key_span.clone()));
                probes.push((toml::Value::Float(hi), a.key_span.clone()));
            }
            for (v, span) in probes {
                let overlay =
                    overlay(&self.base.merged, &[(a.key.as_str(), v)], None).map_err(|m| {
                        ConfigError::Invalid {
                            location: Some(locate(&self.path, text, a.key_span.start)),
                            key: a.key.clone(),
                            message: m,
                        }
                    })?;
                self.load_overlay(overlay).map_err(|e| {
                    relocate(e, &self.overlay_path(), |unknown| {
                        let s = if unknown { &a.key_span } else { &span };
                        locate(&self.path, text, s.start)
                    })
                })?;
            }
        }
        Ok(())
    }

    /// The scenario of variant `v`.
    pub fn scenario(&self, v: &Variant) -> Result<Scenario, ConfigError> {
        let settings: Vec<(&str, toml::Value)> = self
            .columns
            .iter()
            .zip(&v.values)
            .map(|(k, x)| (k.as_str(), x.clone()))
            .collect();
        let push = v
            .push
            .map(|p| (self.push.as_ref().expect("push variants have a spec"), p));
        let text =
            overlay(&self.base.merged, &settings, push).map_err(|m| ConfigError::Invalid {
                location: None,
                key: format!("variant {}", v.index),
                message: m,
            })?;
        self.load_overlay(text).map_err(|e| ConfigError::Invalid {
            location: None,
            key: format!("variant {} ({})", v.index, self.describe(v)),
            message: crate::cli::one_paragraph(&e),
        })
    }

    /// `key = value, ...` of a variant (push columns included).
    pub fn describe(&self, v: &Variant) -> String {
        self.columns
            .iter()
            .zip(&v.values)
            .map(|(k, x)| format!("{k} = {x}"))
            .collect::<Vec<_>>()
            .join(", ")
    }

    fn overlay_path(&self) -> PathBuf {
        self.path
            .parent()
            .map_or_else(PathBuf::new, Path::to_path_buf)
            .join("<sweep variant>")
    }

    fn load_overlay(&self, overlay: String) -> Result<Scenario, ConfigError> {
        let mut files: Vec<(PathBuf, String)> = self
            .base
            .sources
            .files
            .iter()
            .filter(|f| f.path != Path::new(crate::config::load::DEFAULTS_PATH))
            .map(|f| (f.path.clone(), f.text.clone()))
            .collect();
        files.push((self.overlay_path(), overlay));
        Scenario::from_texts(files)
    }
}

fn axis(
    a: &Spanned<AxisSpec>,
    mode: Mode,
    invalid: &impl Fn(&Range<usize>, &str, String) -> ConfigError,
) -> Result<Axis, ConfigError> {
    let spec = a.get_ref();
    let key = spec.key.get_ref().clone();
    let values: Vec<(toml::Value, Range<usize>)> = spec
        .values
        .iter()
        .flatten()
        .map(|v| (v.get_ref().clone(), v.span()))
        .collect();
    let range = match (&spec.min, &spec.max) {
        (None, None) => None,
        (Some(lo), Some(hi)) => {
            let (l, h) = (*lo.get_ref(), *hi.get_ref());
            if mode == Mode::Grid {
                return Err(invalid(
                    &lo.span(),
                    &key,
                    "`min`/`max` need mode = \"random\"; a grid takes `values`".into(),
                ));
            }
            if !(l.is_finite() && h.is_finite() && l <= h) {
                return Err(invalid(
                    &lo.span(),
                    &key,
                    format!("min {l}, max {h}: expected finite min ≤ max"),
                ));
            }
            Some((l, h))
        }
        _ => return Err(invalid(&a.span(), &key, "give both `min` and `max`".into())),
    };
    if values.is_empty() == range.is_none() {
        return Err(invalid(
            &spec.key.span(),
            &key,
            "expected either `values = [...]` or (random mode) `min` and `max`".into(),
        ));
    }
    Ok(Axis {
        key,
        key_span: spec.key.span(),
        values,
        range,
    })
}

fn check_push(p: &PushSpec) -> Result<(), String> {
    let all = p
        .magnitudes
        .iter()
        .chain(&p.directions_deg)
        .chain(&p.starts)
        .chain([&p.duration]);
    if all.into_iter().any(|x| !x.is_finite()) {
        return Err("every number must be finite".into());
    }
    if p.magnitudes.is_empty() || p.directions_deg.is_empty() || p.starts.is_empty() {
        return Err("`magnitudes`, `directions_deg` and `starts` need at least one value".into());
    }
    Ok(())
}

/// Every combination, the last axis (then the push magnitude, direction, start) varying fastest.
fn grid(axes: &[Axis], push: Option<&PushSpec>) -> Vec<Variant> {
    let mut dims: Vec<usize> = axes.iter().map(|a| a.values.len()).collect();
    if let Some(p) = push {
        dims.extend([p.magnitudes.len(), p.directions_deg.len(), p.starts.len()]);
    }
    let total: usize = dims.iter().product();
    (0..total)
        .map(|index| {
            let mut idx = vec![0; dims.len()];
            let mut rest = index;
            for (i, d) in dims.iter().enumerate().rev() {
                idx[i] = rest % d;
                rest /= d;
            }
            let mut values: Vec<toml::Value> = axes
                .iter()
                .zip(&idx)
                .map(|(a, &i)| a.values[i].0.clone())
                .collect();
            let push = push.map(|p| {
                let n = axes.len();
                PushSetting {
                    magnitude: p.magnitudes[idx[n]],
                    direction_deg: p.directions_deg[idx[n + 1]],
                    start: p.starts[idx[n + 2]],
                }
            });
            push_columns(&mut values, push);
            Variant {
                index,
                values,
                push,
            }
        })
        .collect()
}

/// `samples` draws from ChaCha8 seeded with `seed`: per variant, the axes in order, then the push's
/// magnitude, direction and start (each picked uniformly from its list).
fn random(axes: &[Axis], push: Option<&PushSpec>, samples: usize, seed: u64) -> Vec<Variant> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    (0..samples)
        .map(|index| {
            let mut values = Vec::with_capacity(axes.len() + 3);
            for a in axes {
                values.push(match a.range {
                    Some((lo, hi)) => toml::Value::Float(rng.random_range(lo..=hi)),
                    None => a.values[rng.random_range(0..a.values.len())].0.clone(),
                });
            }
            let push = push.map(|p| {
                let mut pick = |xs: &[f64]| xs[rng.random_range(0..xs.len())];
                PushSetting {
                    magnitude: pick(&p.magnitudes),
                    direction_deg: pick(&p.directions_deg),
                    start: pick(&p.starts),
                }
            });
            push_columns(&mut values, push);
            Variant {
                index,
                values,
                push,
            }
        })
        .collect()
}

fn push_columns(values: &mut Vec<toml::Value>, push: Option<PushSetting>) {
    if let Some(p) = push {
        values.extend([p.magnitude, p.direction_deg, p.start].map(toml::Value::Float));
    }
}

/// The horizontal force `[fx, fy]` of a push of `magnitude` N towards `direction_deg` from +x (exact
/// zeros at multiples of 90°, so a 90° push has no x component).
pub fn push_force(magnitude: f64, direction_deg: f64) -> [f64; 2] {
    let (s, c) = direction_deg.to_radians().sin_cos();
    let snap = |x: f64| if x.abs() < 1e-12 { 0.0 } else { x };
    [magnitude * snap(c), magnitude * snap(s)]
}

/// The overlay file of a set of `(dotted key, value)` settings and an optional push, over the scenario's
/// merged document `merged` (arrays are replaced whole by a later file, so an entry `key[i]` or a new push
/// copies the scenario's array and changes it).
fn overlay(
    merged: &toml::Table,
    settings: &[(&str, toml::Value)],
    push: Option<(&PushSpec, PushSetting)>,
) -> Result<String, String> {
    let mut out = toml::Table::new();
    for (key, value) in settings {
        if PUSH_COLUMNS.contains(key) {
            continue;
        }
        set(&mut out, merged, &parse_key(key)?, value.clone())?;
    }
    if let Some((spec, p)) = push {
        let [fx, fy] = push_force(p.magnitude, p.direction_deg);
        let mut entry = toml::Table::new();
        entry.insert("frame".into(), spec.frame.clone().into());
        entry.insert("start".into(), p.start.into());
        entry.insert("duration".into(), spec.duration.into());
        entry.insert(
            "wrench".into(),
            toml::Value::Array(
                [fx, fy, 0.0, 0.0, 0.0, 0.0]
                    .map(toml::Value::Float)
                    .to_vec(),
            ),
        );
        let sim = table_at(&mut out, "sim")?;
        let existing = merged
            .get("sim")
            .and_then(|s| s.get("pushes"))
            .cloned()
            .unwrap_or(toml::Value::Array(Vec::new()));
        let pushes = sim.entry("pushes").or_insert(existing);
        match pushes {
            toml::Value::Array(a) => a.push(toml::Value::Table(entry)),
            _ => return Err("`sim.pushes` is not an array".into()),
        }
    }
    toml::to_string(&out).map_err(|e| e.to_string())
}

/// One segment of a dotted key: a name and an optional `[i]`.
type Segment = (String, Option<usize>);

fn parse_key(key: &str) -> Result<Vec<Segment>, String> {
    key.split('.')
        .map(|seg| {
            let (name, index) = match seg.split_once('[') {
                None => (seg, None),
                Some((n, rest)) => {
                    let i = rest
                        .strip_suffix(']')
                        .and_then(|i| i.parse::<usize>().ok())
                        .ok_or_else(|| format!("`{seg}`: expected `name` or `name[index]`"))?;
                    (n, Some(i))
                }
            };
            if name.is_empty() {
                return Err(format!("`{key}`: empty key segment"));
            }
            Ok((name.to_string(), index))
        })
        .collect()
}

fn table_at<'a>(t: &'a mut toml::Table, name: &str) -> Result<&'a mut toml::Table, String> {
    t.entry(name)
        .or_insert_with(|| toml::Value::Table(toml::Table::new()))
        .as_table_mut()
        .ok_or_else(|| format!("`{name}` is not a table"))
}

/// Sets `path` in the overlay `out`: tables are created empty (merged key by key), the first array on the
/// path is copied from `merged` (or from `out` if already copied) and changed in the copy.
fn set(
    out: &mut toml::Table,
    merged: &toml::Table,
    path: &[Segment],
    value: toml::Value,
) -> Result<(), String> {
    let ((name, index), rest) = path.split_first().ok_or("empty key")?;
    match index {
        None if rest.is_empty() => {
            out.insert(name.clone(), value);
            Ok(())
        }
        None => {
            let inner = merged
                .get(name)
                .and_then(toml::Value::as_table)
                .cloned()
                .unwrap_or_default();
            set(table_at(out, name)?, &inner, rest, value)
        }
        Some(_) => {
            let mut copy = toml::Table::new();
            let existing = out.get(name).or_else(|| merged.get(name));
            let existing = existing.ok_or_else(|| format!("the scenario has no array `{name}`"))?;
            copy.insert(name.clone(), existing.clone());
            set_value(&mut copy, path, value)?;
            out.extend(copy);
            Ok(())
        }
    }
}

/// Sets `path` inside a table copied from the scenario: every segment must exist except the last key.
fn set_value(t: &mut toml::Table, path: &[Segment], value: toml::Value) -> Result<(), String> {
    let ((name, index), rest) = path.split_first().ok_or("empty key")?;
    let slot = match index {
        None if rest.is_empty() => {
            t.insert(name.clone(), value);
            return Ok(());
        }
        None => t
            .entry(name.clone())
            .or_insert_with(|| toml::Value::Table(toml::Table::new())),
        Some(i) => {
            let a = t
                .get_mut(name)
                .and_then(toml::Value::as_array_mut)
                .ok_or_else(|| format!("`{name}` is not an array of the scenario"))?;
            let len = a.len();
            let item = a
                .get_mut(*i)
                .ok_or_else(|| format!("`{name}[{i}]`: the array has {len} entries"))?;
            if rest.is_empty() {
                *item = value;
                return Ok(());
            }
            item
        }
    };
    let inner = slot
        .as_table_mut()
        .ok_or_else(|| format!("`{name}` is not a table"))?;
    set_value(inner, rest, value)
}

/// A file location from a byte offset of `text`.
fn locate(path: &Path, text: &str, offset: usize) -> Location {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    Location {
        path: path.to_path_buf(),
        line,
        column: before[start..].chars().count() + 1,
    }
}

/// Moves an error located in the overlay file to the sweep file (`at(true)` for an unknown key: the
/// axis key's line; `at(false)` otherwise: the value's).
fn relocate(e: ConfigError, overlay: &Path, at: impl Fn(bool) -> Location) -> ConfigError {
    match e {
        ConfigError::Invalid {
            location,
            key,
            message,
        } if location.as_ref().is_none_or(|l| l.path == overlay) => {
            let unknown = message.starts_with("unknown field") || location.is_none();
            ConfigError::Invalid {
                location: Some(at(unknown)),
                key,
                message,
            }
        }
        other => other,
    }
}
