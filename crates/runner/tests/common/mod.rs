//! Test helpers: scratch directories and the repository's paths.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// The workspace root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A fresh scratch directory under the target dir (removed when dropped).
pub struct Scratch(pub PathBuf);

impl Scratch {
    pub fn new(name: &str) -> Self {
        let base =
            std::env::temp_dir().join(format!("stride-runner-test-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&base);
        std::fs::create_dir_all(&base).unwrap();
        Scratch(base)
    }
    pub fn write(&self, rel: &str, text: &str) -> PathBuf {
        let p = self.0.join(rel);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(&p, text).unwrap();
        p
    }
    pub fn path(&self, rel: &str) -> PathBuf {
        self.0.join(rel)
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A scenario text that uses the bundled model through an absolute URDF path.
pub fn robot_section() -> String {
    let urdf = root().join("models/stride_humanoid.urdf");
    let robot =
        std::fs::read_to_string(root().join("configs/robots/stride_humanoid.toml")).unwrap();
    robot.replace(
        "\"../../models/stride_humanoid.urdf\"",
        &format!("{:?}", urdf.display().to_string()),
    )
}

/// The files `configs/<includes>` (in order) with `extra` appended, written to `<scratch>/<name>.toml`
/// and loaded.
pub fn scenario_from_configs(
    s: &Scratch,
    name: &str,
    includes: &[&str],
    extra: &str,
) -> stride_runner::config::Scenario {
    let configs = root().join("configs");
    let include: Vec<String> = includes
        .iter()
        .map(|p| format!("{:?}", configs.join(p).display().to_string()))
        .collect();
    let text = format!("include = [{}]\n{extra}", include.join(", "));
    stride_runner::config::Scenario::load(&s.write(&format!("{name}.toml"), &text)).unwrap()
}

/// Run options that write the log to `<scratch>/<name>.mcap`.
pub fn log_options(s: &Scratch, name: &str) -> stride_runner::run::RunOptions {
    stride_runner::run::RunOptions {
        output: Some(s.path(&format!("{name}.mcap"))),
        ..stride_runner::run::RunOptions::default()
    }
}

/// Runs `scenario` for `duration` s with its log at `<scratch>/<name>.mcap`, asserts that it ran to the
/// end (a robot on a pole neither falls nor reaches a goal), and returns the log's path.
pub fn run_to_the_end(
    s: &Scratch,
    scenario: &stride_runner::config::Scenario,
    name: &str,
    duration: f64,
) -> PathBuf {
    let options = stride_runner::run::RunOptions {
        duration: Some(duration),
        ..log_options(s, name)
    };
    let summary = stride_runner::run::run_scenario(scenario, &options).unwrap();
    assert!(
        matches!(
            summary.outcome,
            stride_runner::summary::Outcome::DurationReached
        ),
        "{:?}",
        summary.outcome
    );
    s.path(&format!("{name}.mcap"))
}

/// The `/planner/adjusted_footsteps` records of a log, as JSON.
pub fn adjusted_footsteps(path: &Path) -> Vec<serde_json::Value> {
    stride_runner::log::read_log(path)
        .unwrap()
        .messages
        .into_iter()
        .filter(|m| m.topic == "/planner/adjusted_footsteps")
        .map(|m| serde_json::from_slice(&m.data).unwrap())
        .collect()
}

/// Whether `example-robot-data` is available (STRIDE_EXAMPLE_ROBOT_DATA_DIR set), saying so straight to
/// the process's stderr, past the harness's capture (`.ci/run` counts the names that ran):
/// `STRIDE-ERD-TEST-RAN <test>` or `STRIDE-ERD-TEST-SKIPPED <test>: <why>`.
pub fn example_robot_data(test: &str) -> bool {
    use std::io::Write;
    let set = std::env::var_os("STRIDE_EXAMPLE_ROBOT_DATA_DIR").is_some();
    let line = if set {
        format!("STRIDE-ERD-TEST-RAN {test}\n")
    } else {
        format!(
            "STRIDE-ERD-TEST-SKIPPED {test}: STRIDE_EXAMPLE_ROBOT_DATA_DIR is not set \
             (export STRIDE_EXAMPLE_ROBOT_DATA_DIR=$(bash tools/reference/example-robot-data-dir.sh))\n"
        )
    };
    let _ = std::io::stderr().lock().write_all(line.as_bytes());
    set
}
