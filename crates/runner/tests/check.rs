//! `stride check`: every name against the model with where it was set, the run's layers built, and the
//! warnings about the posture, the planner's geometry and the ground, each tested on both sides of its
//! limit.
mod common;

use common::{robot_section, root, Scratch};
use stride_runner::check::names::NameKind;
use stride_runner::check::posture::{ground_rotational_stiffness, GROUND_STIFFNESS_MARGIN};
use stride_runner::check::{check_scenario, CheckError, CheckReport};
use stride_runner::config::Scenario;
use stride_runner::run::{run_scenario, Outcome, RunOptions};
use stride_sim::{ContactConfig, ContactSurfaceConfig};

const TOP: &str = "[scenario]\nname = \"x\"\nduration = 1.0\n";

/// The bundled robot file plus `extra`, checked.
fn check_with(s: &Scratch, extra: &str) -> Result<CheckReport, CheckError> {
    s.write("robot.toml", &robot_section());
    let path = s.write(
        "scenario.toml",
        &format!("include = [\"robot.toml\"]\n{TOP}{extra}"),
    );
    check_scenario(&Scenario::load(&path).unwrap())
}

fn warnings_with(s: &Scratch, extra: &str) -> Vec<String> {
    check_with(s, extra).unwrap().warnings
}

#[test]
fn the_bundled_scenarios_pass_without_warnings_and_start_running() {
    for name in ["walk_straight", "walk_straight_torque", "stand_push"] {
        let path = root().join(format!("configs/{name}.toml"));
        let scenario = Scenario::load(&path).unwrap();
        let report = check_scenario(&scenario).unwrap();
        assert!(report.warnings.is_empty(), "{name}: {:?}", report.warnings);
        // What the check accepts, the run accepts: a few ticks start without a configuration error.
        let options = RunOptions {
            duration: Some(0.05),
            no_log: true,
            ..RunOptions::default()
        };
        let summary = run_scenario(&scenario, &options).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(
            !matches!(summary.outcome, Outcome::Error { .. }),
            "{name}: {:?}",
            summary.outcome
        );
    }
}

#[test]
fn names_from_the_built_in_defaults_are_checked_and_say_so() {
    // The bundled URDF with `chest` and the joint `l_knee` renamed. The walking preset's tasks follow
    // `robot.torso_frame`, so `chest` is no problem; the built-in default posture (not written here) still
    // names `l_knee`.
    let s = Scratch::new("check-default-names");
    let urdf = std::fs::read_to_string(root().join("models/stride_humanoid.urdf"))
        .unwrap()
        .replace("\"chest\"", "\"upper_body\"")
        .replace("<joint name=\"l_knee\"", "<joint name=\"l_knee_joint\"");
    let urdf_path = s.write("robot.urdf", &urdf);
    let text = format!(
        "{TOP}[robot]\nurdf = {:?}\ntorso_frame = \"upper_body\"\n",
        urdf_path.display().to_string()
    );
    let path = s.write("scenario.toml", &text);
    let scenario = Scenario::load(&path).unwrap();
    let Err(CheckError::Names { problems }) = check_scenario(&scenario) else {
        panic!("expected missing names");
    };
    assert!(
        problems.iter().all(|p| p.name.name != "chest"),
        "{problems:?}"
    );
    assert_eq!(problems.len(), 1, "{problems:?}");
    let knee = &problems[0];
    assert_eq!(knee.name.name, "l_knee");
    assert_eq!(knee.name.kind, NameKind::Joint);
    assert_eq!(knee.name.key, "robot.initial_joint_positions.l_knee");
    assert!(
        knee.origin
            .contains("built-in default `robot.initial_joint_positions`")
            && knee.origin.contains("replaces it whole"),
        "{}",
        knee.origin
    );

    // A written posture replaces the default whole; a misspelt joint in it is located in the file, and a
    // preset task overridden in the file is checked at its key.
    let text = format!(
        "{text}\n[robot.initial_joint_positions]\nl_knee_joint = 0.7\nl_kne = 0.7\n\n[[wbc.ik.tasks]]\ntype = \"so3\"\nname = \"torso\"\nframe = \"chest\"\nreference = \"torso\"\n"
    );
    let path = s.write("scenario.toml", &text);
    let scenario = Scenario::load(&path).unwrap();
    let Err(CheckError::Names { problems }) = check_scenario(&scenario) else {
        panic!("expected missing names");
    };
    assert_eq!(problems.len(), 2, "{problems:?}");
    let typo = problems
        .iter()
        .find(|p| p.name.name == "l_kne")
        .expect("the misspelt joint");
    assert_eq!(typo.name.kind, NameKind::Joint);
    assert!(
        typo.origin.ends_with("scenario.toml:10:9"),
        "{}",
        typo.origin
    );
    let chest = problems
        .iter()
        .find(|p| p.name.name == "chest")
        .expect("the override's frame");
    assert_eq!(chest.name.key, "wbc.ik.tasks[0].frame");
    assert!(
        chest.origin.contains("scenario.toml:15:"),
        "{}",
        chest.origin
    );
    let text = CheckError::Names { problems }.to_string();
    assert!(text.contains("2 name(s) the model lacks"), "{text}");
}

#[test]
fn a_sensor_name_written_in_a_file_is_located() {
    let s = Scratch::new("check-sensor");
    let err = check_with(&s, "[estimation]\nleft_foot_ft_sensor = \"l_foot_ft\"\n").unwrap_err();
    let CheckError::Names { problems } = err else {
        panic!("expected missing names, got {err}");
    };
    assert_eq!(problems.len(), 1, "{problems:?}");
    assert_eq!(problems[0].name.kind, NameKind::FtSensor);
    assert_eq!(problems[0].name.key, "estimation.left_foot_ft_sensor");
    assert!(
        problems[0].origin.contains("scenario.toml:"),
        "{}",
        problems[0].origin
    );
}

#[test]
fn a_sole_above_the_ground_or_tilted_is_warned_about() {
    let s = Scratch::new("check-soles");
    let sole = |xyz: &str, rpy: &str| {
        format!("[robot.right_sole]\nparent = \"r_sole\"\nname = \"r_sole_2\"\nxyz = {xyz}\nrpy = {rpy}\n")
    };
    let above = warnings_with(&s, &sole("[0.0, 0.0, 0.035]", "[0.0, 0.0, 0.0]"));
    assert!(
        above
            .iter()
            .any(|w| w.contains("robot.right_sole") && w.contains("35.0 mm above")),
        "{above:?}"
    );
    let tilted = warnings_with(&s, &sole("[0.0, 0.0, 0.0]", "[0.03, 0.0, 0.0]"));
    assert!(
        tilted
            .iter()
            .any(|w| w.contains("robot.right_sole") && w.contains("1.7°")),
        "{tilted:?}"
    );
    // Inside the limits (1 mm, 0.6°): no warning.
    let fine = warnings_with(&s, &sole("[0.0, 0.0, 0.001]", "[0.01, 0.0, 0.0]"));
    assert!(fine.is_empty(), "{fine:?}");
}

#[test]
fn planner_geometry_far_from_the_posture_is_warned_about() {
    let s = Scratch::new("check-planner");
    // The posture: CoM 0.540 m above the soles, soles 0.150 m apart (the robot file's own numbers).
    let far = warnings_with(&s, "[planner]\ncom_height = 0.60\nnominal_width = 0.20\n");
    assert!(
        far.iter().any(|w| w.contains("planner.com_height")),
        "{far:?}"
    );
    assert!(
        far.iter().any(|w| w.contains("planner.nominal_width")),
        "{far:?}"
    );
    let near = warnings_with(&s, "[planner]\ncom_height = 0.56\nnominal_width = 0.16\n");
    assert!(near.is_empty(), "{near:?}");
}

#[test]
fn a_ground_softer_than_twice_the_toppling_stiffness_is_warned_about() {
    let s = Scratch::new("check-ground");
    let report = check_with(&s, "").unwrap();
    let mgh = report.stance.toppling_stiffness();
    let surface = ContactSurfaceConfig::foot("left", "l_sole", "l_foot_ft_sensor");
    let per_unit_k = ground_rotational_stiffness(
        &surface,
        &ContactConfig {
            normal_stiffness: 1.0,
            ..ContactConfig::default()
        },
    )
    .0;
    for (ratio, warned) in [(0.95, true), (1.05, false)] {
        let k = ratio * GROUND_STIFFNESS_MARGIN * mgh / per_unit_k;
        let w = warnings_with(&s, &format!("[sim.contact]\nnormal_stiffness = {k}\n"));
        let roll = w.iter().filter(|w| w.contains("roll stiffness")).count();
        assert_eq!(roll, if warned { 2 } else { 0 }, "ratio {ratio}: {w:?}");
    }
}

#[test]
fn ground_rotational_stiffness_matches_the_closed_forms() {
    let contact = ContactConfig {
        normal_stiffness: 3.0e7,
        ..ContactConfig::default()
    };
    let (k, l, w): (f64, f64, f64) = (3.0e7, 0.2, 0.09);
    let mut surface = ContactSurfaceConfig::foot("left", "l_sole", "l_foot_ft_sensor");
    // Trapezoidal weights across the width: 2 points give Σ w y² = W²/4, 3 points W²/8, many W²/12.
    for (n, divisor, tol) in [(2, 4.0, 1e-9), (3, 8.0, 1e-9), (401, 12.0, 1e-4)] {
        surface.grid = [3, n];
        let roll = ground_rotational_stiffness(&surface, &contact).0;
        let expected = k * l * w.powi(3) / divisor;
        assert!(
            (roll / expected - 1.0).abs() < tol,
            "{n}: {roll} vs {expected}"
        );
    }
    // About the centre of stiffness: an offset rectangle has the same stiffness.
    surface.grid = [3, 3];
    let centred = ground_rotational_stiffness(&surface, &contact);
    surface.offset = [0.02, -0.01, 0.0];
    let offset = ground_rotational_stiffness(&surface, &contact);
    assert!((centred.0 - offset.0).abs() < 1e-9 * centred.0);
    assert!((centred.1 - offset.1).abs() < 1e-9 * centred.1);
    // Pitch: the same law along the length.
    assert!((centred.1 / (k * w * l.powi(3) / 8.0) - 1.0).abs() < 1e-9);
}

#[test]
fn an_attached_sole_frame_equals_the_urdf_frame_it_copies() {
    // l_sole is `l_foot` + (0.03, 0, −0.045) in the bundled URDF: the same frame from the configuration
    // gives the same stance.
    let s = Scratch::new("check-attached");
    let by_name = check_with(&s, "").unwrap().stance;
    let attached = check_with(
        &s,
        "[robot.left_sole]\nparent = \"l_foot\"\nxyz = [0.03, 0.0, -0.045]\n\
         [robot.right_sole]\nparent = \"r_foot\"\nxyz = [0.03, 0.0, -0.045]\n\
         [[sim.contact.surfaces]]\nname = \"left\"\nframe = \"left_sole\"\nft_sensor = \"l_foot_ft_sensor\"\n\
         [[sim.contact.surfaces]]\nname = \"right\"\nframe = \"right_sole\"\nft_sensor = \"r_foot_ft_sensor\"\n",
    )
    .unwrap()
    .stance;
    for i in 0..2 {
        let d = by_name.soles[i].inverse() * attached.soles[i];
        assert!(d.translation.vector.norm() < 1e-12 && d.rotation.angle() < 1e-12);
    }
    assert!((by_name.com - attached.com).norm() < 1e-12);
    // A parent the model lacks is an error at the key.
    let text = format!("include = [\"robot.toml\"]\n{TOP}[robot.left_sole]\nparent = \"l_fot\"\n");
    let path = s.write("bad.toml", &text);
    let e = check_scenario(&Scenario::load(&path).unwrap())
        .unwrap_err()
        .to_string();
    assert!(e.contains("robot.left_sole") && e.contains("l_fot"), "{e}");
}

#[test]
fn a_sole_frame_above_the_foot_geometry_is_warned_about() {
    // Both soles raised by the same height: level and on the ground, but above the foot's collision box.
    let s = Scratch::new("check-sole-geometry");
    let raised = |dz: f64| {
        format!(
            "[robot.left_sole]\nparent = \"l_sole\"\nname = \"l2\"\nxyz = [0.0, 0.0, {dz}]\n\
             [robot.right_sole]\nparent = \"r_sole\"\nname = \"r2\"\nxyz = [0.0, 0.0, {dz}]\n"
        )
    };
    let above = warnings_with(&s, &raised(0.006));
    assert_eq!(
        above
            .iter()
            .filter(|w| w.contains("6.0 mm below the sole frame"))
            .count(),
        2,
        "{above:?}"
    );
    let within = warnings_with(&s, &raised(0.004));
    assert!(within.is_empty(), "{within:?}");
}
