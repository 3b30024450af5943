//! Configuration errors are located at the line that sets the key, in whichever file (includes and
//! overlays), or say that the value is a built-in default when no file sets it.
mod common;

use common::Scratch;
use stride_runner::config::{ConfigError, Scenario};

fn invalid(e: ConfigError) -> (Option<(String, usize)>, String, String) {
    match e {
        ConfigError::Invalid {
            location,
            key,
            message,
        } => (
            location.map(|l| (l.path.display().to_string(), l.line)),
            key,
            message,
        ),
        other => panic!("expected an Invalid error, got {other}"),
    }
}

#[test]
fn layer_error_in_an_included_file_is_located_at_its_line() {
    let s = Scratch::new("loc-included");
    s.write(
        "robots/r.toml",
        "# robot\n[robot]\nleft_sole = \"l_sole\"\n\n[planner]\ncom_height = 0.54\nstep_duration_min = -1.0\n",
    );
    let top = s.write(
        "scenario.toml",
        "include = [\"robots/r.toml\"]\n[scenario]\nname = \"x\"\n[planner]\nnominal_width = 0.15\n",
    );
    let (loc, key, message) = invalid(Scenario::load(&top).unwrap_err());
    let (path, line) = loc.expect("a location");
    assert!(path.ends_with("robots/r.toml"), "{path}: {message}");
    assert_eq!(line, 7, "{message}");
    assert_eq!(key, "planner.step_duration_min");
}

#[test]
fn layer_error_in_an_overlay_table_is_located_at_its_line() {
    // The key is set under a table header of the top file that also appears in the included file.
    let s = Scratch::new("loc-overlay");
    s.write("robots/r.toml", "[planner]\ncom_height = 0.54\n");
    let top = s.write(
        "scenario.toml",
        "include = [\"robots/r.toml\"]\n\n[scenario]\nname = \"x\"\n\n[planner]\nswing_apex_fraction = 1.5\n",
    );
    let (loc, key, message) = invalid(Scenario::load(&top).unwrap_err());
    let (path, line) = loc.expect("a location");
    assert!(path.ends_with("scenario.toml"), "{path}: {message}");
    assert_eq!(line, 7, "{message}");
    assert_eq!(key, "planner.swing_apex_fraction");
}

#[test]
fn an_error_on_a_default_value_says_so_instead_of_pointing_at_a_file() {
    // nominal_width above the default feet distance limit: the error is about a key no file sets.
    let s = Scratch::new("loc-default");
    let top = s.write(
        "scenario.toml",
        "[scenario]\nname = \"x\"\n[planner]\nnominal_width = 0.3\nmin_width = 0.2\n",
    );
    let err = Scenario::load(&top).unwrap_err();
    let text = err.to_string();
    let (loc, key, message) = invalid(err);
    assert_eq!(key, "planner.feet_distance_max", "{text}");
    assert!(loc.is_none(), "no file sets the key: {text}");
    assert!(text.contains("built-in default"), "{text}");
    assert!(message.contains("no file sets this key"), "{message}");
}

#[test]
fn a_renamed_planner_key_names_its_replacement_at_its_line() {
    let s = Scratch::new("loc-renamed");
    let top = s.write(
        "scenario.toml",
        "[scenario]\nname = \"x\"\n[planner]\nstep_length_max = 0.25\n",
    );
    let (loc, key, message) = invalid(Scenario::load(&top).unwrap_err());
    assert_eq!(loc.expect("a location").1, 4, "{message}");
    assert_eq!(key, "planner.step_length_max");
    assert!(message.contains("renamed `feet_distance_max`"), "{message}");
}
