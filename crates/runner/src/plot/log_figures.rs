//! The figures of one run, from its MCAP log: tracking (DCM, ZMP, CoM), feet, contact forces, joint
//! torques against their limits and solve times. Topics and fields: docs/logging.md.

use std::path::{Path, PathBuf};

use plotters::style::RGBColor;
use serde_json::Value;

use super::chart::{draw_time_figure, Panel, PhaseSpan, Series};
use super::PlotError;
use crate::log::LogContents;

const PLANNED: RGBColor = RGBColor(31, 119, 180);
const DESIRED: RGBColor = RGBColor(44, 160, 44);
const MEASURED: RGBColor = RGBColor(214, 39, 40);
const LEFT: RGBColor = RGBColor(31, 119, 180);
const RIGHT: RGBColor = RGBColor(255, 127, 14);
const LEFT_TRUE: RGBColor = RGBColor(23, 60, 110);
const RIGHT_TRUE: RGBColor = RGBColor(160, 70, 0);
const LIMIT: RGBColor = RGBColor(120, 120, 120);

/// Joints shown in the torque figure (the most loaded against their effort limits).
pub const TORQUE_JOINTS: usize = 6;

/// The messages of one topic parsed as JSON, with their log time \[s\].
struct Topic(Vec<(f64, Value)>);

impl Topic {
    fn read(log: &LogContents, name: &str) -> Result<Self, PlotError> {
        log.topic(name)
            .map(|m| {
                serde_json::from_slice(&m.data)
                    .map(|v| (m.time_ns as f64 * 1e-9, v))
                    .map_err(|e| PlotError::Log(format!("{name}: {e}")))
            })
            .collect::<Result<_, _>>()
            .map(Topic)
    }

    /// The number at a JSON pointer (e.g. `/dcm_position/0`) of every message that has one, scaled.
    fn series(&self, pointer: &str, scale: f64) -> Vec<(f64, f64)> {
        self.0
            .iter()
            .filter_map(|(t, v)| Some((*t, scale * v.pointer(pointer)?.as_f64()?)))
            .collect()
    }

    /// A boolean at a JSON pointer as `offset + {0, 1}`.
    fn flag(&self, pointer: &str, offset: f64) -> Vec<(f64, f64)> {
        self.0
            .iter()
            .filter_map(|(t, v)| {
                let b = v.pointer(pointer)?.as_bool()?;
                Some((*t, offset + if b { 1.0 } else { 0.0 }))
            })
            .collect()
    }
}

/// The support phases from the `phase` events; the last one ends with the log.
pub fn phases(log: &LogContents) -> Result<Vec<PhaseSpan>, PlotError> {
    let end = log.messages.iter().map(|m| m.time_ns).max().unwrap_or(0) as f64 * 1e-9;
    let events = Topic::read(log, "/events")?;
    let starts: Vec<(f64, String)> = events
        .0
        .iter()
        .filter(|(_, v)| v["kind"] == "phase")
        .filter_map(|(t, v)| Some((*t, v["detail"].as_str()?.to_string())))
        .collect();
    Ok(starts
        .iter()
        .enumerate()
        .map(|(i, (t, phase))| PhaseSpan {
            start: *t,
            end: starts.get(i + 1).map_or(end, |n| n.0),
            phase: phase.clone(),
        })
        .collect())
}

/// A tracking figure: planned (and desired) against measured, x and y.
fn tracking(log: &LogContents, what: &str) -> Result<Vec<Panel>, PlotError> {
    let plan = Topic::read(log, "/planner/references")?;
    let out = Topic::read(log, "/simplified/output")?;
    let track = Topic::read(log, "/runner/tracking")?;
    let (plan_key, desired_key, measured_key) = match what {
        "DCM" => ("dcm_position", None, "measured_dcm"),
        "ZMP" => ("zmp", Some(("desired_zmp", "desired ZMP")), "measured_zmp"),
        _ => (
            "com_position",
            Some(("com_position", "CoM reference")),
            "measured_com",
        ),
    };
    Ok(["x", "y"]
        .iter()
        .enumerate()
        .map(|(i, axis)| {
            let mut series = vec![Series::new(
                format!("planned {what}"),
                PLANNED,
                plan.series(&format!("/{plan_key}/{i}"), 1.0),
            )];
            if let Some((key, label)) = desired_key {
                series.push(Series::new(
                    label,
                    DESIRED,
                    out.series(&format!("/{key}/{i}"), 1.0),
                ));
            }
            series.push(Series::new(
                format!("measured {what}"),
                MEASURED,
                track.series(&format!("/{measured_key}/{i}"), 1.0),
            ));
            Panel {
                title: format!("{what} {axis}"),
                y_label: format!("{what} {axis} [m]"),
                series,
            }
        })
        .collect())
}

/// Feet heights (planned, true) and contact flags (planned, estimated, true; offset to be read apart).
fn feet(log: &LogContents) -> Result<Vec<Panel>, PlotError> {
    let plan = Topic::read(log, "/planner/references")?;
    let est = Topic::read(log, "/estimation/state")?;
    let truth = Topic::read(log, "/sensors/feet")?;
    let mut heights = Vec::new();
    let mut contacts = Vec::new();
    for (side, color, dark) in [("left", LEFT, LEFT_TRUE), ("right", RIGHT, RIGHT_TRUE)] {
        heights.push(Panel {
            title: format!("{side} sole height"),
            y_label: "height [m]".into(),
            series: vec![
                Series::new(
                    "planned",
                    color,
                    plan.series(&format!("/{side}/pose/position/2"), 1.0),
                ),
                Series::new("true", dark, truth.series(&format!("/{side}/point/2"), 1.0)),
            ],
        });
        contacts.push(Panel {
            title: format!("{side} contact (planned +2.4, estimated +1.2, true +0)"),
            y_label: "in contact (0/1, offset)".into(),
            series: vec![
                Series::new(
                    "planned",
                    PLANNED,
                    plan.flag(&format!("/{side}/in_contact"), 2.4),
                ),
                Series::new(
                    "estimated",
                    DESIRED,
                    est.flag(&format!("/contacts/{side}"), 1.2),
                ),
                Series::new(
                    "true",
                    MEASURED,
                    truth.flag(&format!("/{side}/in_contact"), 0.0),
                ),
            ],
        });
    }
    heights.extend(contacts);
    Ok(heights)
}

/// Normal contact forces, estimated and true.
fn wrenches(log: &LogContents) -> Result<Vec<Panel>, PlotError> {
    let est = Topic::read(log, "/estimation/state")?;
    let truth = Topic::read(log, "/sensors/feet")?;
    Ok(["left", "right"]
        .iter()
        .map(|side| Panel {
            title: format!("{side} foot normal force"),
            y_label: "f_z [N]".into(),
            series: vec![
                Series::new(
                    "estimated",
                    DESIRED,
                    est.series(&format!("/{side}_foot_wrench/2"), 1.0),
                ),
                Series::new(
                    "true",
                    MEASURED,
                    truth.series(&format!("/{side}/force/2"), 1.0),
                ),
            ],
        })
        .collect())
}

/// Joint names (from `/robot/description`) and effort limits (from the `model.urdf` attachment).
fn joints(log: &LogContents) -> Result<Vec<(String, f64)>, PlotError> {
    let urdf = log
        .attachments
        .get("model.urdf")
        .ok_or_else(|| PlotError::Log("no `model.urdf` attachment".into()))?;
    let model = stride_model::Model::from_urdf_str(&String::from_utf8_lossy(urdf))
        .map_err(|e| PlotError::Log(format!("model.urdf: {e}")))?;
    let desc = Topic::read(log, "/robot/description")?;
    let names: Vec<String> = desc
        .0
        .first()
        .and_then(|(_, v)| v["joint_names"].as_array().cloned())
        .ok_or_else(|| PlotError::Log("no `/robot/description` joint names".into()))?
        .iter()
        .filter_map(|n| n.as_str().map(str::to_string))
        .collect();
    names
        .into_iter()
        .map(|n| {
            let i = model
                .joint_index(&n)
                .ok_or_else(|| PlotError::Log(format!("model.urdf has no joint `{n}`")))?;
            Ok((n, model.joints()[i].effort_limit))
        })
        .collect()
}

/// The [`TORQUE_JOINTS`] joints with the largest peak |τ| / effort limit: true and estimated torques and
/// the ± limits.
fn torques(log: &LogContents) -> Result<Vec<Panel>, PlotError> {
    let sim = Topic::read(log, "/sim/state")?;
    let est = Topic::read(log, "/estimation/state")?;
    let joints = joints(log)?;
    let mut load: Vec<(usize, f64)> = joints
        .iter()
        .enumerate()
        .map(|(i, (_, limit))| {
            let peak = sim
                .series(&format!("/joint_torques/{i}"), 1.0)
                .iter()
                .fold(0.0_f64, |m, p| m.max(p.1.abs()));
            (i, if limit.is_finite() { peak / limit } else { 0.0 })
        })
        .collect();
    load.sort_by(|a, b| b.1.total_cmp(&a.1));
    let (t0, t1) = (
        sim.0.first().map_or(0.0, |p| p.0),
        sim.0.last().map_or(1.0, |p| p.0),
    );
    Ok(load
        .iter()
        .take(TORQUE_JOINTS)
        .map(|&(i, ratio)| {
            let (name, limit) = &joints[i];
            let mut series = vec![
                Series::new(
                    "true (actuator)",
                    MEASURED,
                    sim.series(&format!("/joint_torques/{i}"), 1.0),
                ),
                Series::new(
                    "estimated",
                    DESIRED,
                    est.series(&format!("/joint_torques/{i}"), 1.0),
                ),
            ];
            if limit.is_finite() {
                for (sign, label) in [(1.0, Some("effort limit ±".to_string())), (-1.0, None)] {
                    series.push(Series {
                        label,
                        color: LIMIT,
                        width: 1,
                        points: vec![(t0, sign * limit), (t1, sign * limit)],
                    });
                }
            }
            Panel {
                title: format!("{name} (peak {:.0} % of limit)", 100.0 * ratio),
                y_label: "torque [N m]".into(),
                series,
            }
        })
        .collect())
}

/// Wall-clock solve and tick times of the simplified and whole-body layers.
fn timing(log: &LogContents) -> Result<Vec<Panel>, PlotError> {
    let simplified = Topic::read(log, "/simplified/timing")?;
    let wbc = Topic::read(log, "/wbc/timing")?;
    Ok(["solve_time", "tick_time"]
        .iter()
        .map(|key| Panel {
            title: format!("{} per tick (wall clock)", key.replace('_', " ")),
            y_label: format!("{} [ms]", key.replace('_', " ")),
            series: vec![
                Series::new(
                    "simplified",
                    PLANNED,
                    simplified.series(&format!("/{key}"), 1e3),
                ),
                Series::new("whole-body", MEASURED, wbc.series(&format!("/{key}"), 1e3)),
            ],
        })
        .collect())
}

/// The figure files of a log plot, in the order they are written.
pub const LOG_FIGURES: [&str; 7] = [
    "dcm.svg",
    "zmp.svg",
    "com.svg",
    "feet.svg",
    "wrenches.svg",
    "torques.svg",
    "timing.svg",
];

/// Writes every figure of the log into `dir` (created if needed); returns the files written.
pub fn plot_log(log_path: &Path, dir: &Path) -> Result<Vec<PathBuf>, PlotError> {
    let log = crate::log::read_log(log_path).map_err(|e| PlotError::Log(e.to_string()))?;
    std::fs::create_dir_all(dir).map_err(|e| PlotError::Io {
        path: dir.to_path_buf(),
        source: e,
    })?;
    let phases = phases(&log)?;
    let name = log_path
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    let figures: [(&str, String, Vec<Panel>, usize); 7] = [
        (
            LOG_FIGURES[0],
            format!("{name}: DCM, planned vs measured"),
            tracking(&log, "DCM")?,
            1,
        ),
        (
            LOG_FIGURES[1],
            format!("{name}: ZMP, planned, desired and measured"),
            tracking(&log, "ZMP")?,
            1,
        ),
        (
            LOG_FIGURES[2],
            format!("{name}: CoM, planned, reference and measured"),
            tracking(&log, "CoM")?,
            1,
        ),
        (
            LOG_FIGURES[3],
            format!("{name}: feet heights and contact states"),
            feet(&log)?,
            2,
        ),
        (
            LOG_FIGURES[4],
            format!("{name}: normal contact forces"),
            wrenches(&log)?,
            1,
        ),
        (
            LOG_FIGURES[5],
            format!("{name}: most loaded joints against their effort limits"),
            torques(&log)?,
            2,
        ),
        (
            LOG_FIGURES[6],
            format!("{name}: solve times per layer"),
            timing(&log)?,
            1,
        ),
    ];
    let mut written = Vec::new();
    for (file, title, panels, cols) in figures {
        let path = dir.join(file);
        draw_time_figure(&path, &title, &panels, cols, &phases)?;
        written.push(path);
    }
    if log.topic("/wbc/ground_estimate").next().is_some() {
        let path = dir.join(GROUND_ESTIMATE_FIGURE);
        let title = format!("{name}: ground estimate per foot against the ground under it");
        draw_time_figure(&path, &title, &ground_estimate(&log, log_path)?, 2, &phases)?;
        written.push(path);
    }
    Ok(written)
}

/// The figure of TSID-Compliant's ground estimate, written besides [`LOG_FIGURES`] when the log has
/// `/wbc/ground_estimate` (`estimate_ground = true`).
pub const GROUND_ESTIMATE_FIGURE: &str = "ground_estimate.svg";

/// Per foot, `k̂` and `b̂` of `/wbc/ground_estimate` against the scenario's ground under the planned sole
/// while the foot's contact flag is set (where one patch holds under the whole sole).
fn ground_estimate(log: &LogContents, log_path: &Path) -> Result<Vec<Panel>, PlotError> {
    use crate::ground_estimate::{estimate_series, ground_under, FEET};
    let scenario =
        crate::replay::logged_scenario(log, log_path).map_err(|e| PlotError::Log(e.to_string()))?;
    let sim = &scenario.config.sim;
    let ground = stride_sim::GroundCompliance::from_config(&sim.ground, &sim.contact);
    let sole = scenario.config.wbc.tsid.compliant.sole_length;
    let estimates = estimate_series(log).map_err(PlotError::Log)?;
    let input = Topic::read(log, "/wbc/input")?;
    let mut panels = Vec::new();
    for (what, unit, scale) in [("k", "k [1e6 N/m³]", 1e-6), ("b", "b [1e4 N·s/m³]", 1e-4)] {
        for (f, (foot, _)) in FEET.iter().enumerate() {
            let pick = |&(t, k, b): &(f64, f64, f64)| (t, scale * if what == "k" { k } else { b });
            let truth = input
                .0
                .iter()
                .filter(|(_, v)| v[format!("{foot}_in_contact")].as_bool() == Some(true))
                .filter_map(|(t, v)| {
                    let x = v[format!("{foot}_foot")]["pose"]["position"][0].as_f64()?;
                    let g = ground_under(&ground, x, sole)?;
                    Some((
                        *t,
                        scale * if what == "k" { g.stiffness } else { g.damping },
                    ))
                })
                .collect();
            panels.push(Panel {
                title: format!("{foot} foot: {what}"),
                y_label: unit.into(),
                series: vec![
                    Series::new(
                        "estimate",
                        MEASURED,
                        estimates[f].iter().map(pick).collect(),
                    ),
                    Series::new("ground under the sole (in contact)", PLANNED, truth),
                ],
            });
        }
    }
    Ok(panels)
}
