//! The log's message format: every logged vector a plain JSON array, the format version in the metadata,
//! and `stride replay` refusing a log of another format.
mod common;

use std::collections::BTreeMap;

use common::Scratch;
use stride_runner::cli::LayerName;
use stride_runner::config::{PlantKind, Scenario};
use stride_runner::log::{read_log, LogOptions, LogWriter};
use stride_runner::records::LOG_FORMAT;
use stride_runner::replay::{replay, ReplayError};
use stride_runner::run::{run_scenario, RunOptions};

fn short_walk(s: &Scratch, control_mode: &str) -> Scenario {
    s.write("robots/r.toml", &common::robot_section());
    let top = s.write(
        "walk.toml",
        &format!(
            "include = [\"robots/r.toml\"]\n[scenario]\nname = \"f\"\nduration = 0.2\nplant = \"ideal\"\n\
             control_mode = \"{control_mode}\"\n[estimation]\nkind = \"ground_truth\"\n[goal.pose]\nx = 1.0\n"
        ),
    );
    Scenario::load(&top).unwrap()
}

fn json(data: &[u8]) -> serde_json::Value {
    serde_json::from_slice(data).unwrap()
}

/// A plain array of `len` numbers.
fn assert_numbers(v: &serde_json::Value, len: usize, what: &str) {
    let a = v
        .as_array()
        .unwrap_or_else(|| panic!("{what} is not an array: {v}"));
    assert_eq!(a.len(), len, "{what}: {v}");
    assert!(
        a.iter().all(|x| x.is_f64() || x.is_i64() || x.is_u64()),
        "{what}: {v}"
    );
}

/// Where `v` holds serde's form of a dynamic nalgebra vector, `[[numbers], n, null]`.
fn find_nalgebra_shape(v: &serde_json::Value, path: &str) -> Option<String> {
    use serde_json::Value;
    match v {
        Value::Array(a) => {
            let dynamic = a.len() == 3 && a[0].is_array() && a[1].is_u64() && a[2].is_null();
            if dynamic {
                return Some(path.to_string());
            }
            a.iter()
                .enumerate()
                .find_map(|(i, x)| find_nalgebra_shape(x, &format!("{path}[{i}]")))
        }
        Value::Object(m) => m
            .iter()
            .find_map(|(k, x)| find_nalgebra_shape(x, &format!("{path}.{k}"))),
        _ => None,
    }
}

#[test]
fn logged_vectors_are_plain_arrays_in_both_control_modes() {
    for mode in ["position", "torque"] {
        let s = Scratch::new(&format!("format-{mode}"));
        let path = s.path("a.mcap");
        let options = RunOptions {
            output: Some(path.clone()),
            plant: Some(PlantKind::Ideal),
            ..RunOptions::default()
        };
        run_scenario(&short_walk(&s, mode), &options).unwrap();
        let log = read_log(&path).unwrap();
        assert_eq!(
            log.metadata["stride"]["log_format"],
            LOG_FORMAT.to_string(),
            "{mode}"
        );
        let description = json(&log.topic("/robot/description").next().unwrap().data);
        let dof = description["joint_names"].as_array().unwrap().len();
        assert!(dof > 10, "{dof} joints");
        let outputs: Vec<_> = log.topic("/wbc/output").map(|m| json(&m.data)).collect();
        assert!(outputs.len() > 10, "{mode}: {} outputs", outputs.len());
        for o in &outputs {
            if mode == "position" {
                assert_numbers(&o["joint_positions"], dof, "joint_positions");
                assert_numbers(&o["joint_velocities"], dof, "joint_velocities");
                assert_numbers(&o["base_velocity"], 6, "base_velocity");
                assert_numbers(&o["base_pose"]["position"], 3, "base_pose.position");
                assert_numbers(
                    &o["base_pose"]["orientation_xyzw"],
                    4,
                    "base_pose.orientation_xyzw",
                );
            } else {
                assert_numbers(&o["joint_torques"], dof, "joint_torques");
                assert_numbers(&o["accelerations"], dof + 6, "accelerations");
                for w in o["contact_wrenches"].as_array().unwrap() {
                    assert_numbers(w, 6, "contact_wrenches[]");
                }
            }
        }
        for m in &log.messages {
            if let Some(at) = find_nalgebra_shape(&json(&m.data), "") {
                panic!(
                    "{mode}: {} at {} ns holds {at} as [data, n, null]",
                    m.topic, m.time_ns
                );
            }
        }
    }
}

/// The shape finder does flag the old form (the check above would not pass vacuously).
#[test]
fn the_old_dynamic_vector_form_is_recognised() {
    let old = serde_json::to_value(nalgebra::DVector::from_vec(vec![1.0, 2.0])).unwrap();
    assert_eq!(old, serde_json::json!([[1.0, 2.0], 2, null]));
    let message = serde_json::json!({"report": {"x": 1}, "joint_positions": old});
    assert_eq!(
        find_nalgebra_shape(&message, "").as_deref(),
        Some(".joint_positions")
    );
    assert_eq!(
        find_nalgebra_shape(&serde_json::json!({"v": [1.0, 2, null]}), ""),
        None
    );
}

/// A log holding only what replay reads before its format check, with the given `log_format` entry.
fn log_with_format(path: &std::path::Path, format: Option<&str>) {
    let mut w = LogWriter::create(path, &LogOptions::default()).unwrap();
    let mut meta = BTreeMap::from([("stride_version".to_string(), "0".to_string())]);
    if let Some(f) = format {
        meta.insert("log_format".into(), f.into());
    }
    w.metadata("stride", meta).unwrap();
    w.finish().unwrap();
}

#[test]
fn replay_refuses_a_log_of_another_format() {
    let s = Scratch::new("format-refused");
    for (format, found) in [(None, "1"), (Some("1"), "1"), (Some("3"), "3")] {
        let path = s.path("old.mcap");
        log_with_format(&path, format);
        let e = replay(&path, LayerName::Wbc, None, None).unwrap_err();
        let ReplayError::Format {
            found: f, expected, ..
        } = &e
        else {
            panic!("{format:?}: not a format error: {e}");
        };
        assert_eq!((f.as_str(), *expected), (found, LOG_FORMAT));
        let message = e.to_string();
        assert!(
            message.contains(&format!("log format {found}"))
                && message.contains(&format!("log format {LOG_FORMAT}"))
                && message.contains("old.mcap"),
            "{message}"
        );
    }
    // The current format passes the check (and then fails on the missing scenario, not on the format).
    let path = s.path("current.mcap");
    log_with_format(&path, Some(&LOG_FORMAT.to_string()));
    let e = replay(&path, LayerName::Wbc, None, None).unwrap_err();
    assert!(matches!(e, ReplayError::Content(_)), "{e}");
}
