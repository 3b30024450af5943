//! Scenario files: include/overlay, error locations, rate checks, the shipped scenarios.
mod common;

use common::Scratch;
use stride_runner::config::{ConfigError, ControlMode, Goal, Scenario};

fn invalid(e: ConfigError) -> (String, usize, usize, String, String) {
    match e {
        ConfigError::Invalid {
            location,
            key,
            message,
        } => {
            let l = location.expect("a location");
            (l.path.display().to_string(), l.line, l.column, key, message)
        }
        other => panic!("expected an Invalid error, got {other}"),
    }
}

#[test]
fn typo_in_included_file_names_that_file_line_column_and_key() {
    let s = Scratch::new("typo");
    s.write(
        "robots/r.toml",
        "[robot]\nleft_sole = \"l_sole\"\nright_sol = \"r_sole\"\n",
    );
    let top = s.write(
        "scenario.toml",
        "include = [\"robots/r.toml\"]\n[scenario]\nname = \"x\"\n",
    );
    let err = Scenario::load(&top).unwrap_err();
    let text = err.to_string();
    let (path, line, column, key, message) = invalid(err);
    assert!(path.ends_with("robots/r.toml"), "{path}");
    assert_eq!((line, column), (3, 1), "{text}");
    assert_eq!(key, "robot.right_sol");
    assert!(message.contains("unknown field `right_sol`"), "{message}");
    assert!(
        message.contains("right_sole"),
        "the allowed keys are listed: {message}"
    );
    assert!(
        text.contains("r.toml:3:1") && text.contains("robot.right_sol"),
        "{text}"
    );
}

#[test]
fn wrong_type_names_key_and_expected_type() {
    let s = Scratch::new("type");
    let top = s.write(
        "scenario.toml",
        "[scenario]\nname = \"x\"\n\nduration = \"long\"\n",
    );
    let (path, line, column, key, message) = invalid(Scenario::load(&top).unwrap_err());
    assert!(path.ends_with("scenario.toml"));
    assert_eq!((line, column), (4, 12));
    assert_eq!(key, "scenario.duration");
    assert!(
        message.contains("expected") && message.contains("f64"),
        "{message}"
    );
}

#[test]
fn unknown_enum_value_lists_allowed_values() {
    let s = Scratch::new("enum");
    let top = s.write("scenario.toml", "[scenario]\ncontrol_mode = \"velocity\"\n");
    let (_, line, _, key, message) = invalid(Scenario::load(&top).unwrap_err());
    assert_eq!(line, 2);
    assert_eq!(key, "scenario.control_mode");
    assert!(
        message.contains("position") && message.contains("torque"),
        "{message}"
    );
}

#[test]
fn rates_must_divide_the_base_rate() {
    let s = Scratch::new("rates");
    let text = format!(
        "{}\n[rates]\nbase_hz = 2000\nsim_hz = 2000\nwbc_hz = 300\n",
        common::robot_section()
    );
    let top = s.write("scenario.toml", &text);
    let err = Scenario::load(&top).unwrap_err();
    let (path, line, _, key, message) = invalid(err);
    assert!(path.ends_with("scenario.toml"));
    assert_eq!(key, "rates.wbc_hz");
    let expected_line = text.lines().position(|l| l.starts_with("wbc_hz")).unwrap() + 1;
    assert_eq!(line, expected_line);
    assert!(
        message.contains("does not divide") && message.contains("500"),
        "{message}"
    );

    // A base rate whose period is not a whole number of nanoseconds.
    let top = s.write(
        "b.toml",
        "[rates]\nbase_hz = 3000\nsim_hz = 3000\nwbc_hz = 500\n",
    );
    let (_, _, _, key, message) = invalid(Scenario::load(&top).unwrap_err());
    assert_eq!(key, "rates.base_hz");
    assert!(message.contains("1 000 000 000"), "{message}");

    // Exact divisors are accepted.
    let top = s.write(
        "c.toml",
        &format!(
            "{}\n[rates]\nbase_hz = 4000\nsim_hz = 4000\nwbc_hz = 1000\nsimplified_hz = 100\n",
            common::robot_section()
        ),
    );
    Scenario::load(&top).unwrap();
}

#[test]
fn include_overlay_deep_merges_and_later_wins() {
    let s = Scratch::new("overlay");
    s.write(
        "layers/a.toml",
        "[rates]\nwbc_hz = 1000\nsimplified_hz = 50\n[scenario]\nduration = 10.0\n",
    );
    s.write("layers/b.toml", "[rates]\nsimplified_hz = 100\n");
    let robot = common::robot_section();
    s.write("robots/r.toml", &robot);
    let top = s.write(
        "scenario.toml",
        "include = [\"robots/r.toml\", \"layers/a.toml\", \"layers/b.toml\"]\n[scenario]\nname = \"o\"\n\
         control_mode = \"torque\"\n[rates]\nbase_hz = 4000\nsim_hz = 4000\n",
    );
    let sc = Scenario::load(&top).unwrap();
    let c = &sc.config;
    assert_eq!(c.rates.wbc_hz, 1000, "from a.toml, not overridden");
    assert_eq!(c.rates.simplified_hz, 100, "b.toml overrides a.toml");
    assert_eq!(
        c.rates.base_hz, 4000,
        "the scenario file overrides its includes"
    );
    assert_eq!(
        c.scenario.duration, 10.0,
        "sibling keys of merged tables survive"
    );
    assert_eq!(c.scenario.control_mode, ControlMode::Torque);
    assert_eq!(c.robot.left_sole, "l_sole");
    assert_eq!(sc.sources.files.len(), 5, "built-in defaults + 4 files");
    assert_eq!(
        sc.sources.files[0].path,
        std::path::Path::new(stride_runner::config::load::DEFAULTS_PATH)
    );
    // The merged document stored in logs parses back to the same configuration.
    let again = Scenario::from_texts(vec![(s.path("merged.toml"), sc.merged_toml())]).unwrap();
    assert_eq!(again.config, sc.config);
    // Locations point to the file that wrote the winning value.
    let loc = sc.sources.value_location("rates.simplified_hz").unwrap();
    assert!(loc.path.ends_with("layers/b.toml"));
    assert_eq!(loc.line, 2);
}

#[test]
fn one_key_of_a_layer_section_can_be_overridden() {
    // The built-in defaults fill `wbc.ik` (no overrides: the walking preset of the default robot, the
    // bundled humanoid), the file changes one key.
    let s = Scratch::new("partial");
    let top = s.write(
        "s.toml",
        "[wbc.ik]\nfeedback = \"measured\"\n[goal.stand]\n",
    );
    let sc = Scenario::load(&top).unwrap();
    assert_eq!(sc.config.wbc.ik.feedback, stride_wbc::IkFeedback::Measured);
    assert!(sc.config.wbc.ik.tasks.is_empty());
    let model = stride_model::bundled::model().unwrap();
    let ik = sc.ik_config(&model).unwrap();
    assert_eq!(ik.feedback, stride_wbc::IkFeedback::Measured);
    assert_eq!(
        ik.tasks,
        stride_wbc::IkConfig::default_for_bundled_model().tasks
    );
    assert!(matches!(sc.config.goal, Goal::Stand {}));
}

/// The whole-body task lists configs/robots/stride_humanoid.toml stated before the walking preset.
fn explicit_bundled_lists() -> (stride_wbc::IkConfig, stride_wbc::TsidConfig) {
    #[derive(serde::Deserialize)]
    struct Wbc {
        ik: stride_wbc::IkConfig,
        tsid: stride_wbc::TsidConfig,
    }
    #[derive(serde::Deserialize)]
    struct Fixture {
        wbc: Wbc,
    }
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let path = root.join("crates/wbc/tests/fixtures/stride_humanoid_tasks.toml");
    let f: Fixture = toml::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    (f.wbc.ik, f.wbc.tsid)
}

/// The bundled robot's file states only its frames and posture; the walking preset built from them is
/// exactly the task lists the file stated before presets, and the Rust defaults a user embedding stride-wbc
/// gets.
#[test]
fn bundled_robot_file_builds_the_explicit_task_lists() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let sc = Scenario::load(&root.join("configs/robots/stride_humanoid.toml")).unwrap();
    assert!(sc.config.wbc.ik.tasks.is_empty() && sc.config.wbc.tsid.tasks.is_empty());
    let model = stride_model::bundled::model().unwrap();
    let (ik, tsid) = explicit_bundled_lists();
    let built_ik = sc.ik_config(&model).unwrap();
    assert_eq!(built_ik.tasks, ik.tasks);
    assert_eq!(built_ik.feedback, ik.feedback);
    assert_eq!(sc.tsid_config(&model).unwrap().tasks, tsid.tasks);
    assert_eq!(ik, stride_wbc::IkConfig::default_for_bundled_model());
    assert_eq!(tsid, stride_wbc::TsidConfig::default_for_bundled_model());
    let posture = stride_wbc::bundled_posture();
    assert_eq!(sc.config.robot.initial_joint_positions, posture);
}

/// `wbc.ik.tasks` entries replace the preset's task of the same name in place or are added;
/// `wbc.walking.ik_without` drops preset tasks; `wbc.preset = "none"` takes the written list whole; the
/// posture weights' globs are matched against the model's joints.
#[test]
fn preset_tasks_are_overridden_by_name_removed_or_replaced_whole() {
    let s = Scratch::new("preset_overrides");
    let model = stride_model::bundled::model().unwrap();
    let com = "[[wbc.ik.tasks]]\ntype = \"com\"\nname = \"com\"\nkp = 1.0\npriority = \"hard\"\n";
    let head = "[[wbc.ik.tasks]]\ntype = \"so3\"\nname = \"head\"\nframe = \"head\"\nreference = \"torso\"\n";
    let top = s.write(
        "s.toml",
        &format!(
            "[goal.stand]\n[wbc.walking]\nik_without = [\"pelvis\"]\nposture_joint_weights = {{ \"l_hip_*\" = 3.0 }}\n{com}{head}"
        ),
    );
    let sc = Scenario::load(&top).unwrap();
    let ik = sc.ik_config(&model).unwrap();
    let names: Vec<&str> = ik.tasks.iter().map(|t| t.name()).collect();
    assert_eq!(
        names,
        [
            "left_foot",
            "right_foot",
            "com",
            "torso",
            "posture",
            "joint_position_limits",
            "joint_velocity_limits",
            "head"
        ]
    );
    match &ik.tasks[2] {
        stride_wbc::TaskConfig::Com(c) => assert_eq!(c.kp, 1.0),
        other => panic!("{other:?}"),
    }
    match &ik.tasks[4] {
        stride_wbc::TaskConfig::JointRegularization(p) => {
            assert_eq!(p.joint_weights.get("l_hip_pitch"), Some(&3.0));
            assert_eq!(p.joint_weights.get("l_elbow"), Some(&2.0));
            assert_eq!(p.joint_weights.get("l_knee"), None);
        }
        other => panic!("{other:?}"),
    }
    // The TSID keeps its preset's tasks (the overrides and removals were the QP-IK's).
    let tsid = sc.tsid_config(&model).unwrap().tasks;
    let preset = stride_wbc::TsidConfig::default_for_bundled_model().tasks;
    let names =
        |t: &[stride_wbc::TaskConfig]| t.iter().map(|t| t.name().to_owned()).collect::<Vec<_>>();
    assert_eq!(names(&tsid), names(&preset));
    assert_eq!(tsid[5], preset[5]);

    let none = s.write(
        "none.toml",
        &format!("[goal.stand]\n[wbc]\npreset = \"none\"\n{com}"),
    );
    let sc = Scenario::load(&none).unwrap();
    assert_eq!(sc.ik_config(&model).unwrap().tasks.len(), 1);

    let bad = s.write(
        "bad.toml",
        "[goal.stand]\n[wbc.walking]\ntsid_without = [\"pelvic\"]\n",
    );
    let err = Scenario::load(&bad)
        .unwrap()
        .tsid_config(&model)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("bad.toml:3")
            && err.contains("wbc.walking.tsid_without")
            && err.contains("pelvic"),
        "{err}"
    );
}

/// The walking preset's CoM task has its own vertical gains for the rigid TSID and the single gain for the
/// compliant contact model (docs/wbc.md, "The CoM height": the compliant walk fell sooner with them).
#[test]
fn the_compliant_tsid_keeps_the_com_tasks_single_gain() {
    let s = Scratch::new("compliant_com");
    let model = stride_model::bundled::model().unwrap();
    let com = |path: &std::path::Path| {
        let tasks = Scenario::load(path)
            .unwrap()
            .tsid_config(&model)
            .unwrap()
            .tasks;
        tasks
            .into_iter()
            .find_map(|t| match t {
                stride_wbc::TaskConfig::Com(c) => Some(c),
                _ => None,
            })
            .unwrap()
    };
    let rigid = com(&s.write("rigid.toml", "[goal.stand]\n"));
    assert_eq!(rigid.kp_z, Some(stride_wbc::BUNDLED_TSID_COM_KP_Z));
    assert_eq!(rigid.kd_z, Some(stride_wbc::BUNDLED_TSID_COM_KD_Z));
    let compliant = com(&s.write(
        "compliant.toml",
        "[goal.stand]\n[wbc.tsid]\ncontact_model = \"compliant\"\n",
    ));
    assert_eq!((compliant.kp_z, compliant.kd_z), (None, None));
    assert_eq!((compliant.kp, compliant.kd), (rigid.kp, rigid.kd));
}

#[test]
fn include_cycles_are_rejected() {
    let s = Scratch::new("cycle");
    s.write("a.toml", "include = [\"b.toml\"]\n");
    let b = s.write("b.toml", "include = [\"a.toml\"]\n");
    assert!(matches!(
        Scenario::load(&b),
        Err(ConfigError::IncludeCycle { .. })
    ));
}

#[test]
fn urdf_path_is_relative_to_the_file_that_sets_it() {
    let s = Scratch::new("urdf");
    s.write("robots/r.toml", "[robot]\nurdf = \"../models/x.urdf\"\n");
    let top = s.write("sub/scenario.toml", "include = [\"../robots/r.toml\"]\n");
    let sc = Scenario::load(&top).unwrap();
    assert!(
        sc.urdf_path.ends_with("robots/../models/x.urdf"),
        "{}",
        sc.urdf_path.display()
    );
}

#[test]
fn urdf_path_expands_environment_variables() {
    let s = Scratch::new("urdf-env");
    // CARGO_MANIFEST_DIR is set by cargo for every test process: an absolute path.
    s.write(
        "robots/r.toml",
        "[robot]\nurdf = \"${CARGO_MANIFEST_DIR}/models/x.urdf\"\n",
    );
    let top = s.write("scenario.toml", "include = [\"robots/r.toml\"]\n");
    let sc = Scenario::load(&top).unwrap();
    let expected = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("models/x.urdf");
    assert_eq!(sc.urdf_path, expected);
    // The merged document (what logs store) holds the resolved path, so a log replays without the variable.
    let again = Scenario::from_texts(vec![(s.path("merged.toml"), sc.merged_toml())]).unwrap();
    assert_eq!(again.urdf_path, expected);
    assert!(!sc.merged_toml().contains("${"), "{}", sc.merged_toml());
}

#[test]
fn unset_environment_variable_in_urdf_path_names_file_line_key_and_variable() {
    let s = Scratch::new("urdf-env-unset");
    s.write(
        "robots/r.toml",
        "# robot\n[robot]\nurdf = \"${STRIDE_TEST_VARIABLE_NEVER_SET_7F3A}/x/model.urdf\"\n",
    );
    let top = s.write("scenario.toml", "include = [\"robots/r.toml\"]\n");
    let err = Scenario::load(&top).unwrap_err();
    let text = err.to_string();
    let (path, line, column, key, message) = invalid(err);
    assert!(path.ends_with("robots/r.toml"), "{path}");
    assert_eq!((line, column), (3, 8), "{text}");
    assert_eq!(key, "robot.urdf");
    assert!(
        message.contains("STRIDE_TEST_VARIABLE_NEVER_SET_7F3A") && message.contains("not set"),
        "{message}"
    );
    assert!(text.contains("r.toml:3:8"), "{text}");
}

#[test]
fn environment_variable_expansion_rules() {
    use stride_runner::config::expand_env_vars;
    let lookup = |name: &str| match name {
        "A" => Some("/a".to_string()),
        "B_2" => Some("b".to_string()),
        "EMPTY" => Some(String::new()),
        _ => None,
    };
    assert_eq!(
        expand_env_vars("${A}/${B_2}.urdf", lookup).unwrap(),
        "/a/b.urdf"
    );
    assert_eq!(
        expand_env_vars("no/variables", lookup).unwrap(),
        "no/variables"
    );
    assert_eq!(
        expand_env_vars("$A/x", lookup).unwrap(),
        "$A/x",
        "only the braced form expands"
    );
    for (text, expected) in [
        ("${MISSING}/x", "`MISSING`"),
        ("${EMPTY}/x", "`EMPTY`"),
        ("${A", "unterminated"),
        ("${}/x", "not a valid"),
        ("${A-B}/x", "not a valid"),
    ] {
        let e = expand_env_vars(text, lookup).unwrap_err();
        assert!(e.contains(expected), "{text}: {e}");
    }
}

/// Layer periods come from `[rates]` only (one source): no layer section has a period or rate key, and
/// writing one is an unknown key located at the file, line and key.
#[test]
fn layer_periods_come_only_from_rates() {
    let s = Scratch::new("period");
    s.write("r.toml", &common::robot_section());
    for (section, key, field) in [
        ("wbc.ik", "period = 0.01", "period"),
        ("wbc.tsid", "period = 0.01", "period"),
        ("sim", "rate_hz = 1000", "rate_hz"),
    ] {
        let top = s.write(
            "s.toml",
            &format!("include = [\"r.toml\"]\n[{section}]\n{key}\n"),
        );
        let (file, line, _, found, message) = invalid(Scenario::load(&top).unwrap_err());
        assert_eq!(found, format!("{section}.{field}"));
        assert!(file.ends_with("s.toml") && line == 3, "{file}:{line}");
        assert!(
            message.contains(&format!("unknown field `{field}`")),
            "{message}"
        );
    }
}

#[test]
fn every_shipped_scenario_is_valid() {
    let dir = common::root().join("configs");
    let mut n = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let p = entry.unwrap().path();
        // Files whose name starts with `_` are scratch files, not shipped scenarios.
        let scratch = p
            .file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with('_'));
        if p.extension().is_some_and(|e| e == "toml") && !scratch {
            // The iCub scenarios find the official model through STRIDE_ICUB_MODELS_DIR (not committed).
            let icub = p.file_name().unwrap().to_string_lossy().contains("icub");
            if icub && std::env::var_os("STRIDE_ICUB_MODELS_DIR").is_none() {
                let e = Scenario::load(&p).unwrap_err().to_string();
                assert!(
                    e.contains("robot.urdf") && e.contains("STRIDE_ICUB_MODELS_DIR"),
                    "{}: {e}",
                    p.display()
                );
                eprintln!(
                    "STRIDE_ICUB_MODELS_DIR not set: {} only checked for its error",
                    p.display()
                );
                n += 1;
                continue;
            }
            let sc = Scenario::load(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
            assert!(sc.urdf_path.exists(), "{}", sc.urdf_path.display());
            let torque = p.file_name().unwrap().to_string_lossy().contains("torque");
            assert_eq!(
                sc.config.scenario.control_mode == ControlMode::Torque,
                torque,
                "{}",
                p.display()
            );
            n += 1;
        }
    }
    assert!(n >= 6, "expected at least six scenarios, found {n}");
    let default = Scenario::load(&dir.join("walk_straight.toml")).unwrap();
    assert!(matches!(default.config.goal, Goal::Pose(ref p) if p.x >= 2.0));
}
