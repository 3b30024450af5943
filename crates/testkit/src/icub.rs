//! The one rule for tests that need the official iCub URDFs of the `icub-models` package, which are not
//! committed: the tests find them in `$STRIDE_ICUB_MODELS_DIR/<model>/model.urdf`
//! (`export STRIDE_ICUB_MODELS_DIR=$(bash tools/reference/icub-models-dir.sh)`).
//!
//! | `STRIDE_ICUB_MODELS_DIR` | the test |
//! |---|---|
//! | unset | is skipped: returns early after printing `STRIDE-ICUB-TEST-SKIPPED <test>: <why>` (fails instead when `CI` is set) |
//! | set, the folder or `<model>/model.urdf` missing | fails (panics, naming the missing path) |
//! | set, the model there | runs, after printing `STRIDE-ICUB-TEST-RAN <test>` |
//!
//! Both lines are written straight to the process's standard error, past the test harness's output
//! capture, so they show in a plain `cargo test` run. `.ci/run` counts the distinct `STRIDE-ICUB-TEST-RAN`
//! names in its test output and fails when fewer than the expected number of iCub tests ran.

use std::ffi::OsStr;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The environment variable naming the `share/iCub/robots` folder of the `icub-models` package.
pub const ICUB_MODELS_DIR_VAR: &str = "STRIDE_ICUB_MODELS_DIR";

/// First word of the line an iCub test prints when it runs (followed by the test's name).
pub const ICUB_TEST_RAN_MARKER: &str = "STRIDE-ICUB-TEST-RAN";

/// First word of the line an iCub test prints when it is skipped (followed by the test's name and why).
pub const ICUB_TEST_SKIPPED_MARKER: &str = "STRIDE-ICUB-TEST-SKIPPED";

/// The model whose URDF proves that a folder is the `icub-models` robots folder (the one every stride
/// iCub test uses; `tools/reference/icub-models-dir.sh` checks the same file).
const PROBE_MODEL: &str = "iCubGazeboV2_7";

/// Why a set `STRIDE_ICUB_MODELS_DIR` does not give the requested model.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum IcubModelsError {
    /// The variable names something that is not a folder.
    #[error("STRIDE_ICUB_MODELS_DIR is set to {0:?}, which is not a folder")]
    NotAFolder(PathBuf),
    /// The folder has no `<model>/model.urdf`.
    #[error("STRIDE_ICUB_MODELS_DIR is set but {0:?} does not exist (is it the share/iCub/robots folder of icub-models?)")]
    MissingUrdf(PathBuf),
}

/// The folder of the official iCub models for the test named `test`, or `None` when
/// `STRIDE_ICUB_MODELS_DIR` is unset (the test then returns early; see the module documentation).
///
/// # Panics
/// When the variable is set but is not a folder holding `iCubGazeboV2_7/model.urdf`, when it is unset
/// and `CI` is set, and when `test` is empty or contains white space (it is the marker's second word).
pub fn icub_models_dir(test: &str) -> Option<PathBuf> {
    located(test, resolve_icub_models_dir(env_dir().as_deref()))
}

/// The URDF of the official iCub model `model` (e.g. `"iCubGazeboV2_7"`) for the test named `test`, or
/// `None` when `STRIDE_ICUB_MODELS_DIR` is unset (the test then returns early; see the module
/// documentation).
///
/// # Panics
/// As [`icub_models_dir`], and when the folder has no `<model>/model.urdf`.
pub fn icub_model_urdf(test: &str, model: &str) -> Option<PathBuf> {
    located(test, resolve_icub_model_urdf(env_dir().as_deref(), model))
}

/// The rule of [`icub_models_dir`] on a given value of the variable, without printing: `Ok(None)` when
/// unset, the folder when it holds `iCubGazeboV2_7/model.urdf`, an error otherwise.
pub fn resolve_icub_models_dir(var: Option<&OsStr>) -> Result<Option<PathBuf>, IcubModelsError> {
    let Some(dir) = var else {
        return Ok(None);
    };
    let dir = PathBuf::from(dir);
    if !dir.is_dir() {
        return Err(IcubModelsError::NotAFolder(dir));
    }
    urdf_in(&dir, PROBE_MODEL)?;
    Ok(Some(dir))
}

/// The rule of [`icub_model_urdf`] on a given value of the variable, without printing: `Ok(None)` when
/// unset, `<dir>/<model>/model.urdf` when the folder passes [`resolve_icub_models_dir`] and holds that
/// file, an error otherwise.
pub fn resolve_icub_model_urdf(
    var: Option<&OsStr>,
    model: &str,
) -> Result<Option<PathBuf>, IcubModelsError> {
    match resolve_icub_models_dir(var)? {
        Some(dir) => urdf_in(&dir, model).map(Some),
        None => Ok(None),
    }
}

fn urdf_in(dir: &Path, model: &str) -> Result<PathBuf, IcubModelsError> {
    let urdf = dir.join(model).join("model.urdf");
    if urdf.is_file() {
        Ok(urdf)
    } else {
        Err(IcubModelsError::MissingUrdf(urdf))
    }
}

fn env_dir() -> Option<std::ffi::OsString> {
    std::env::var_os(ICUB_MODELS_DIR_VAR)
}

/// Applies the rule's outcome for `test`: prints the marker and returns the path, prints the skip and
/// returns `None`, or panics.
fn located(test: &str, outcome: Result<Option<PathBuf>, IcubModelsError>) -> Option<PathBuf> {
    assert!(
        !test.is_empty() && !test.contains(char::is_whitespace),
        "an iCub test's name is one word (it is counted by .ci/run), got {test:?}"
    );
    match outcome {
        Ok(Some(path)) => {
            print_uncaptured(&format!("{ICUB_TEST_RAN_MARKER} {test}\n"));
            Some(path)
        }
        Ok(None) => {
            let why = format!(
                "{ICUB_MODELS_DIR_VAR} is not set (the official iCub URDFs are not committed; \
                 export {ICUB_MODELS_DIR_VAR}=$(bash tools/reference/icub-models-dir.sh))"
            );
            if std::env::var_os("CI").is_some() {
                panic!("{test}: {why}; CI must run it");
            }
            print_uncaptured(&format!("{ICUB_TEST_SKIPPED_MARKER} {test}: {why}\n"));
            None
        }
        Err(e) => panic!("{test}: {e}"),
    }
}

/// Writes `line` to the process's standard error in one call: `eprintln!` would be captured by the test
/// harness (and shown only for a failing test); a direct write is not, and one `write_all` of a short line
/// keeps it whole among the harness's own output.
fn print_uncaptured(line: &str) {
    // Nothing useful to do if standard error is closed.
    let _ = std::io::stderr().lock().write_all(line.as_bytes());
}
