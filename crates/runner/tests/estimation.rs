//! The estimation layer in the loop: the controllers read only what the robot senses, the ground-truth
//! bypass says so, `/estimation/state` carries its documented keys, and `[sim.model]` builds the plant
//! from another model than the controllers'.
mod common;

use std::sync::{Arc, Mutex};

use common::Scratch;
use stride_runner::config::{PlantKind, Scenario};
use stride_runner::log::read_log;
use stride_runner::robot::{JointCommand, Measurement, Robot, RobotError};
use stride_runner::run::{build_robot, load_model, run_with_robot, RunError, RunOptions};

/// A short walk on the simulator with `extra` TOML appended.
fn walk(s: &Scratch, extra: &str) -> Scenario {
    s.write("r.toml", &common::robot_section());
    s.write(
        "layers/rates.toml",
        &std::fs::read_to_string(common::root().join("configs/layers/rates.toml")).unwrap(),
    );
    let top = s.write(
        "w.toml",
        &format!(
            "include = [\"r.toml\", \"layers/rates.toml\"]\n[scenario]\nname = \"w\"\nduration = 1.6\n\
             [goal.pose]\nx = 1.0\n{extra}\n"
        ),
    );
    Scenario::load(&top).unwrap()
}

/// A robot whose reported truth is wrong (base 10 m away, wrenches tripled, contacts swapped, torques
/// offset) and that records every command it receives.
struct LyingTruth {
    inner: Box<dyn Robot>,
    meas: Measurement,
    commands: Arc<Mutex<Vec<JointCommand>>>,
    lie: bool,
}

impl LyingTruth {
    fn new(inner: Box<dyn Robot>, commands: Arc<Mutex<Vec<JointCommand>>>, lie: bool) -> Self {
        let mut robot = Self {
            meas: inner.measurement().clone(),
            inner,
            commands,
            lie,
        };
        robot.refresh();
        robot
    }

    /// The inner robot's measurement, its truth corrupted when lying.
    fn refresh(&mut self) {
        self.meas.clone_from(self.inner.measurement());
        if !self.lie {
            return;
        }
        let t = &mut self.meas.truth;
        t.state.base_pose.translation.x += 10.0;
        t.state.base_velocity[1] += 0.5;
        t.foot_wrenches[0] *= 3.0;
        t.foot_wrenches[1] *= 3.0;
        t.feet_in_contact.swap(0, 1);
        t.joint_torques.add_scalar_mut(100.0);
    }
}

impl Robot for LyingTruth {
    fn name(&self) -> &str {
        "lying"
    }
    fn model(&self) -> &Arc<stride_model::Model> {
        self.inner.model()
    }
    fn period_ns(&self) -> u64 {
        self.inner.period_ns()
    }
    fn measurement(&self) -> &Measurement {
        &self.meas
    }
    fn command(&mut self, c: &JointCommand) -> Result<(), RobotError> {
        self.commands.lock().unwrap().push(c.clone());
        self.inner.command(c)
    }
    fn advance(&mut self) -> Result<(), RobotError> {
        self.inner.advance()?;
        self.refresh();
        Ok(())
    }
}

/// The commands of a run of `sc`, with the robot's truth corrupted or not.
fn commands(s: &Scratch, sc: &Scenario, lie: bool) -> Vec<JointCommand> {
    let model = load_model(sc).unwrap();
    let robot = build_robot(sc, &model, PlantKind::Simulator).unwrap();
    let log = Arc::new(Mutex::new(Vec::new()));
    let robot: Box<dyn Robot> = Box::new(LyingTruth::new(robot, Arc::clone(&log), lie));
    let options = RunOptions {
        output: Some(s.path(if lie { "lie.mcap" } else { "true.mcap" })),
        ..RunOptions::default()
    };
    let summary = run_with_robot(sc, &options, robot).unwrap();
    assert!(
        !matches!(summary.outcome, stride_runner::run::Outcome::Error { .. }),
        "{}",
        summary.render()
    );
    let commands = log.lock().unwrap().clone();
    commands
}

#[test]
fn the_controllers_never_read_the_plants_truth() {
    let s = Scratch::new("no-truth");
    let sc = walk(&s, "");
    let honest = commands(&s, &sc, false);
    let lied_to = commands(&s, &sc, true);
    assert!(honest.len() > 500, "{} commands", honest.len());
    assert_eq!(honest.len(), lied_to.len());
    for (k, (a, b)) in honest.iter().zip(&lied_to).enumerate() {
        assert_eq!(a, b, "command {k} differs: the controllers read the truth");
    }
    // The other side: with the ground-truth bypass the same corruption reaches the commands.
    let s2 = Scratch::new("truth-bypass");
    let gt = walk(&s2, "[estimation]\nkind = \"ground_truth\"");
    let honest = commands(&s2, &gt, false);
    let lied_to = commands(&s2, &gt, true);
    assert!(
        honest.iter().zip(&lied_to).any(|(a, b)| a != b),
        "the corrupted truth should change the commands of the ground-truth bypass"
    );
}

#[test]
fn the_estimation_topic_has_its_documented_keys() {
    let s = Scratch::new("est-topic");
    let sc = walk(&s, "");
    commands(&s, &sc, false);
    let log = read_log(&s.path("true.mcap")).unwrap();
    let msgs: Vec<_> = log.topic("/estimation/state").collect();
    assert!(msgs.len() > 100, "{} messages", msgs.len());
    let v: serde_json::Value = serde_json::from_slice(&msgs[msgs.len() / 2].data).unwrap();
    for (key, len) in [
        ("base_position", 3),
        ("base_orientation_xyzw", 4),
        ("base_linear_velocity", 3),
        ("base_angular_velocity", 3),
        ("left_foot_wrench", 6),
        ("right_foot_wrench", 6),
    ] {
        let a = v[key]
            .as_array()
            .unwrap_or_else(|| panic!("{key} missing: {v}"));
        assert_eq!(a.len(), len, "{key}");
        assert!(
            a.iter().all(|x| x.as_f64().is_some_and(f64::is_finite)),
            "{key}"
        );
    }
    assert!(v["contacts"]["left"].is_boolean() && v["contacts"]["right"].is_boolean());
    // Standing at the start: both feet carry about half the weight (the estimate, not the truth).
    let first: serde_json::Value = serde_json::from_slice(&msgs[0].data).unwrap();
    let fz = |k: &str| first[k][2].as_f64().unwrap();
    let weight = 32.8 * 9.81;
    assert!(
        (fz("left_foot_wrench") + fz("right_foot_wrench") - weight).abs() < 0.05 * weight,
        "{first}"
    );
    let ft = log.topic("/sensors/ft").next().unwrap();
    let ft: serde_json::Value = serde_json::from_slice(&ft.data).unwrap();
    assert_eq!(ft["names"].as_array().unwrap().len(), 4, "{ft}");
}

#[test]
fn the_summary_says_ground_truth_in_capitals_only_when_used() {
    let s = Scratch::new("gt-summary");
    let options = RunOptions {
        duration: Some(0.3),
        no_log: true,
        ..RunOptions::default()
    };
    let run = |extra: &str| {
        let sc = walk(&s, extra);
        stride_runner::run::run_scenario(&sc, &options)
            .unwrap()
            .render()
    };
    let gt = run("[estimation]\nkind = \"ground_truth\"");
    assert!(gt.contains("GROUND TRUTH"), "{gt}");
    let ekf = run("");
    assert!(!ekf.contains("GROUND TRUTH"), "{ekf}");
    assert!(ekf.contains("estimation (ekf)"), "{ekf}");
}

#[test]
fn the_plant_model_can_differ_from_the_controllers() {
    let s = Scratch::new("plant-model");
    let sc = walk(
        &s,
        "[sim.model]\nmass_scale = 1.1\n[sim.model.links.chest]\ncom_offset = [0.02, 0.0, 0.0]",
    );
    let model = load_model(&sc).unwrap();
    let robot = build_robot(&sc, &model, PlantKind::Simulator).unwrap();
    let ratio = robot.model().total_mass() / model.total_mass();
    assert!((ratio - 1.1).abs() < 1e-12, "plant/model mass {ratio}");
    // An unknown link is an error that names it.
    let bad = walk(&s, "[sim.model.links.no_such_link]\nmass_scale = 2.0");
    let model = load_model(&bad).unwrap();
    match build_robot(&bad, &model, PlantKind::Simulator) {
        Err(RunError::ModelLoad { source, .. }) => {
            assert!(source.to_string().contains("no_such_link"), "{source}")
        }
        Err(e) => panic!("unexpected error {e}"),
        Ok(_) => panic!("an unknown link was accepted"),
    }
}

/// The summary's `DCM plant` and `CoM plant` rows and `/runner/tracking.plant`: absent when the plant's
/// inertias are the controllers' (also from another copy of the same URDF); with every mass scaled (the
/// CoM does not move) equal to the controllers'-model rows; with the chest's CoM 2 cm forward, the plant's
/// CoM is ahead of the controllers' view of it.
#[test]
fn the_plant_models_tracking_errors_are_reported_with_a_plant_model() {
    let s = Scratch::new("plant-tracking");
    let urdf = common::root().join("models/stride_humanoid.urdf");
    let run = |name: &str, extra: &str| {
        let sc = walk(&s, extra);
        let options = common::log_options(&s, name);
        let summary = stride_runner::run::run_scenario(&sc, &options).unwrap();
        let log = read_log(&s.path(&format!("{name}.mcap"))).unwrap();
        let msg = log.topic("/runner/tracking").last().unwrap();
        let msg: serde_json::Value = serde_json::from_slice(&msg.data).unwrap();
        (summary, msg)
    };
    let x = |v: &serde_json::Value| v.as_f64().unwrap();
    let same = format!("[sim.model]\nurdf = {:?}", urdf.display().to_string());
    for (name, extra) in [("own", ""), ("copy", same.as_str())] {
        let (summary, msg) = run(name, extra);
        assert!(summary.plant_tracking.is_none(), "{name}");
        assert!(
            !summary.render().contains("DCM plant"),
            "{}",
            summary.render()
        );
        assert!(msg.get("plant").is_none(), "{name}: {msg}");
    }

    let (scaled, msg) = run("scaled", &format!("{same}\nmass_scale = 1.1"));
    let p = scaled.plant_tracking.expect("a plant model of its own");
    assert!(scaled.render().contains("DCM plant"), "{}", scaled.render());
    assert!(
        (p.dcm_error.rms - scaled.dcm_error.rms).abs() < 1e-9,
        "{p:?}"
    );
    assert!(
        (p.com_error.rms - scaled.com_error.rms).abs() < 1e-9,
        "{p:?}"
    );
    assert!(
        (x(&msg["plant"]["dcm_error"]) - x(&msg["dcm_error"])).abs() < 1e-9,
        "{msg}"
    );

    let (moved, msg) = run(
        "moved",
        &format!("{same}\n[sim.model.links.chest]\ncom_offset = [0.02, 0.0, 0.0]"),
    );
    let p = moved.plant_tracking.expect("a plant model of its own");
    let forward = x(&msg["plant"]["com"][0]) - x(&msg["measured_com"][0]);
    // The chest (5.0 of 32.8 kg) carries its 2 cm offset to the plant's CoM: about 3 mm forward.
    assert!(
        (forward - 0.02 * 5.0 / 32.8).abs() < 5e-4,
        "{forward} m, {msg}"
    );
    assert!(p.dcm_error.rms != moved.dcm_error.rms, "{}", moved.render());
}

#[test]
fn scenario_checks_of_estimation_and_the_plant_model() {
    let s = Scratch::new("est-config");
    s.write("r.toml", &common::robot_section());
    let check = |extra: &str| {
        let top = s.write(
            "c.toml",
            &format!("include = [\"r.toml\"]\n[goal.pose]\nx = 1.0\n{extra}\n"),
        );
        Scenario::load(&top).map(|_| ()).map_err(|e| e.to_string())
    };
    let e = check("[scenario]\nplant = \"ideal\"").unwrap_err();
    assert!(
        e.contains("estimation.kind") && e.contains("ground_truth"),
        "{e}"
    );
    assert!(check("[scenario]\nplant = \"ideal\"\n[estimation]\nkind = \"ground_truth\"").is_ok());
    let e = check("[sim.model]\nmass_scale = 0.0").unwrap_err();
    assert!(
        e.contains("sim.model.mass_scale") && e.contains("c.toml"),
        "{e}"
    );
    let e = check("[sim.model.links.chest]\nmass_scale = -1.0").unwrap_err();
    assert!(e.contains("sim.model.links.chest.mass_scale"), "{e}");
    let e = check("[estimation]\nkind = \"magic\"").unwrap_err();
    assert!(e.contains("estimation.kind") || e.contains("magic"), "{e}");
    let e = check("[estimation.contact]\nno_such_key = 1").unwrap_err();
    assert!(e.contains("no_such_key"), "{e}");
}

/// RMS of `est − truth` over the messages of two topics, with `pick` giving the compared vectors.
fn rms_error(
    log: &stride_runner::log::LogContents,
    est_topic: &str,
    truth_topic: &str,
    pick: impl Fn(&serde_json::Value, &serde_json::Value) -> Vec<(f64, f64)>,
) -> (f64, f64) {
    let est: Vec<serde_json::Value> = log
        .topic(est_topic)
        .map(|m| serde_json::from_slice(&m.data).unwrap())
        .collect();
    let truth: Vec<serde_json::Value> = log
        .topic(truth_topic)
        .map(|m| serde_json::from_slice(&m.data).unwrap())
        .collect();
    assert_eq!(est.len(), truth.len());
    let (mut err, mut norm, mut n) = (0.0, 0.0, 0.0);
    for (e, t) in est.iter().zip(&truth) {
        for (a, b) in pick(e, t) {
            err += (a - b) * (a - b);
            norm += b * b;
            n += 1.0;
        }
    }
    ((err / n).sqrt(), (norm / n).sqrt())
}

fn f(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap()
}

/// Foot wrenches and joint torques estimated from the force/torque sensors [Traversaro 2017, §4.5–4.6]
/// against the simulator's contact wrenches and actuator torques, on a recorded walk with the realistic
/// sensors (offsets, noise, delays, quantised encoders). The bounds were measured on the former 3·10⁷ N/m³
/// default ground, which the walk keeps here (an explicit overlay). On the hard default floor (k 3·10⁸,
/// since 2026-12-06) the same walk measures force 5.13 of 111.3 N (4.6 %), torque 0.446 of 3.60 N·m
/// (12.4 %) and joints 1.04 of 4.11 N·m (25.4 %): the torque and joint bounds (10 %, 25 %) do not hold
/// there (why is not diagnosed; the estimator neglects some accelerations and has a 1 ms sensor delay, which
/// a harder contact may weigh more); re-measured 2026-12-06, open.
#[test]
fn foot_wrenches_and_joint_torques_match_the_simulator_on_a_walk() {
    let s = Scratch::new("wrench-torque");
    // The foot admittance (on by default since 2026-12-05) is off here: it shrinks the sole torques the
    // bound below is relative to (2.9 → 2.3 N m RMS) while the estimator's error stays at its noise and
    // delay floor (0.19 → 0.24 N m, the tilting soles adding accelerations it neglects), so the ratio
    // would measure the controller, not the sensor models.
    let sc = walk(
        &s,
        "[simplified.foot_admittance]\nenabled = false\n[sim.contact]\nnormal_stiffness = 3.0e7\n\
         normal_damping = 3.0e5\ntangential_stiffness = 3.0e7\ntangential_damping = 3.0e5",
    );
    commands(&s, &sc, false);
    let log = read_log(&s.path("true.mcap")).unwrap();
    let force = |e: &serde_json::Value, t: &serde_json::Value| {
        let mut out = Vec::new();
        for (side, key) in [("left", "left_foot_wrench"), ("right", "right_foot_wrench")] {
            for j in 0..3 {
                out.push((f(&e[key][j]), f(&t[side]["force"][j])));
            }
        }
        out
    };
    let torque = |e: &serde_json::Value, t: &serde_json::Value| {
        let mut out = Vec::new();
        for (side, key) in [("left", "left_foot_wrench"), ("right", "right_foot_wrench")] {
            for j in 0..3 {
                out.push((f(&e[key][3 + j]), f(&t[side]["torque"][j])));
            }
        }
        out
    };
    let joints = |e: &serde_json::Value, t: &serde_json::Value| {
        let a = e["joint_torques"].as_array().unwrap();
        let b = t["joint_torques"].as_array().unwrap();
        a.iter().zip(b).map(|(x, y)| (f(x), f(y))).collect()
    };
    let (fe, fn_) = rms_error(&log, "/estimation/state", "/sensors/feet", force);
    let (te, tn) = rms_error(&log, "/estimation/state", "/sensors/feet", torque);
    let (je, jn) = rms_error(&log, "/estimation/state", "/sim/state", joints);
    eprintln!(
        "force {fe:.2} of {fn_:.2} N, torque {te:.3} of {tn:.3} N m, joints {je:.3} of {jn:.3} N m"
    );
    // Measured (2026-12-05, when_read): 3.3 N of 111 N, 0.19 of 2.91 N m, 0.70 of 4.06 N m. The errors come from the
    // sensor noise and offsets (learnt in the first swings), the 1 ms sensor delay and the accelerations the
    // estimator neglects (joints, base rotation); a wrong sign, frame or submodel is off by the signal.
    assert!(fe <= 0.05 * fn_, "foot force error {fe} N RMS of {fn_} N");
    assert!(
        te <= 0.10 * tn,
        "foot torque error {te} N m RMS of {tn} N m"
    );
    assert!(
        je <= 0.25 * jn,
        "joint torque error {je} N m RMS of {jn} N m"
    );
}

/// The estimation layer's full tick on the ticks that read the estimate only (`estimation.update =
/// "when_read"`, the samples in between pre-integrated): the commands differ from those of the full tick
/// on every sample (it is in use), are the same in two runs (deterministic), still never depend on the
/// plant's truth, and the estimate stays within the every-sample run's error bounds (base velocity error
/// and tilt error RMS at most 1.5× and 0.1° above them).
#[test]
fn the_estimation_layer_can_tick_only_when_read() {
    let s = Scratch::new("when-read");
    let every = walk(&s, "[estimation]\nupdate = \"every_sample\"");
    let when_read = walk(&s, "[estimation]\nupdate = \"when_read\"");
    let first = commands(&s, &when_read, false);
    assert_eq!(first, commands(&s, &when_read, false), "not deterministic");
    assert_eq!(
        first,
        commands(&s, &when_read, true),
        "the controllers read the truth"
    );
    assert_ne!(first, commands(&s, &every, false), "pre-integration unused");
    let summary = |sc: &Scenario| {
        let options = RunOptions {
            output: Some(s.path("summary.mcap")),
            ..RunOptions::default()
        };
        let summary = stride_runner::run::run_scenario(sc, &options).unwrap();
        assert_eq!(summary.wbc_holds, 0, "{}", summary.render());
        summary.estimation
    };
    let (a, b) = (summary(&every), summary(&when_read));
    assert!(
        b.velocity_error.rms <= 1.5 * a.velocity_error.rms,
        "velocity error RMS {} against {}",
        b.velocity_error.rms,
        a.velocity_error.rms
    );
    assert!(
        b.tilt_error.rms <= a.tilt_error.rms + 0.1f64.to_radians(),
        "tilt error RMS {} against {}",
        b.tilt_error.rms,
        a.tilt_error.rms
    );
}

/// The log's rate never changes the closed loop: under `estimation.update = "when_read"` the state log
/// records the estimate the layers last read and does not tick the estimation layer itself, so a state
/// log at 1 kHz or 200 Hz (ticks between the whole-body layer's 500 Hz ones) gives the commands of the
/// default 100 Hz bit for bit. (Until 2026-12-06 a state-log tick ran the estimation layer's full tick
/// and changed them.)
#[test]
fn the_state_logs_rate_does_not_change_the_commands() {
    let s = Scratch::new("log-rate");
    let at = |hz: u32| {
        let sc = walk(
            &s,
            &format!("[estimation]\nupdate = \"when_read\"\n[log]\nstate_hz = {hz}"),
        );
        commands(&s, &sc, false)
    };
    let default_rate = at(100);
    assert!(default_rate.len() > 500, "{} commands", default_rate.len());
    assert_eq!(
        default_rate,
        at(1000),
        "a 1 kHz state log changed the commands"
    );
    assert_eq!(
        default_rate,
        at(200),
        "a 200 Hz state log changed the commands"
    );
}

/// The observer of flexible joints without encoders needs every sample: `when_read` is refused with it.
#[test]
fn ticking_only_when_read_is_refused_with_the_flexible_joints_observer() {
    let s = Scratch::new("when-read-flex");
    let sc = common::scenario_from_configs(
        &s,
        "flex",
        &["walk_flexible_hips_tsid_flex_torque.toml"],
        "[estimation]\nupdate = \"when_read\"",
    );
    let options = RunOptions {
        output: Some(s.path("flex.mcap")),
        duration: Some(0.01),
        ..RunOptions::default()
    };
    let e = stride_runner::run::run_scenario(&sc, &options)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        e.contains("estimation.update") && e.contains("every_sample"),
        "{e}"
    );
}

/// `estimation.stance_leg_accelerations` on the flexible-hip robot: the runner names TSID-Flex's flexible
/// joints as the passive ones, so each leg has six actuated joints to solve and the run starts; on the same
/// robot with the rigid TSID (no flexible joints named) the legs have eight and the scenario is refused at
/// the key.
#[test]
fn stance_leg_accelerations_take_tsid_flex_passive_joints() {
    let s = Scratch::new("stance-leg-flex");
    let options = |name: &str| RunOptions {
        output: Some(s.path(name)),
        duration: Some(0.05),
        ..RunOptions::default()
    };
    let flex = common::scenario_from_configs(
        &s,
        "flex",
        &["walk_flexible_hips_tsid_flex_torque.toml"],
        "[estimation]\nstance_leg_accelerations = true",
    );
    let out = stride_runner::run::run_scenario(&flex, &options("flex.mcap"));
    assert!(out.is_ok(), "{:?}", out.err().map(|e| e.to_string()));
    let rigid = common::scenario_from_configs(
        &s,
        "rigid",
        &["walk_flexible_hips_torque.toml"],
        "[estimation]\nstance_leg_accelerations = true",
    );
    let e = stride_runner::run::run_scenario(&rigid, &options("rigid.mcap"))
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(e.contains("stance_leg_accelerations"), "{e}");
}
