//! Closed-loop runs on the ideal plant: determinism, interrupted runs, panics, replay exactness.
mod common;

use std::sync::Arc;

use common::Scratch;
use stride_runner::cli::LayerName;
use stride_runner::config::{PlantKind, Scenario};
use stride_runner::log::read_log;
use stride_runner::robot::{JointCommand, Measurement, Robot, RobotError};
use stride_runner::run::{
    build_robot, load_model, run_scenario, run_with_robot, Outcome, RunOptions, WALL_CLOCK_TOPICS,
};

fn scenario(s: &Scratch) -> Scenario {
    s.write("robots/r.toml", &common::robot_section());
    s.write(
        "layers/rates.toml",
        &std::fs::read_to_string(common::root().join("configs/layers/rates.toml")).unwrap(),
    );
    let top = s.write(
        "walk.toml",
        "include = [\"robots/r.toml\", \"layers/rates.toml\"]\n[scenario]\nname = \"t\"\nduration = 1.5\nplant = \"ideal\"\n[estimation]\nkind = \"ground_truth\"\n\
         [goal.pose]\nx = 1.0\n",
    );
    Scenario::load(&top).unwrap()
}

fn options(path: std::path::PathBuf) -> RunOptions {
    RunOptions {
        output: Some(path),
        plant: Some(PlantKind::Ideal),
        ..RunOptions::default()
    }
}

fn deterministic_messages(path: &std::path::Path) -> Vec<(String, u64, Vec<u8>)> {
    read_log(path)
        .unwrap()
        .messages
        .into_iter()
        .filter(|m| !WALL_CLOCK_TOPICS.contains(&m.topic.as_str()))
        .map(|m| (m.topic, m.time_ns, m.data))
        .collect()
}

#[test]
fn two_runs_give_identical_logs_and_replay_is_exact() {
    let s = Scratch::new("determinism");
    let sc = scenario(&s);
    let a = run_scenario(&sc, &options(s.path("a.mcap"))).unwrap();
    let b = run_scenario(&sc, &options(s.path("b.mcap"))).unwrap();
    assert_eq!(a.outcome, b.outcome);
    assert_eq!(a.outcome, Outcome::DurationReached, "{}", a.render());
    let ma = deterministic_messages(&s.path("a.mcap"));
    let mb = deterministic_messages(&s.path("b.mcap"));
    assert!(ma.len() > 1000, "{} messages", ma.len());
    assert_eq!(ma.len(), mb.len());
    for (x, y) in ma.iter().zip(&mb) {
        assert_eq!(x, y, "first difference on {} at {} ns", x.0, x.1);
    }
    let log = read_log(&s.path("a.mcap")).unwrap();
    for topic in [
        "/planner/input",
        "/planner/references",
        "/simplified/input",
        "/wbc/input",
        "/wbc/output",
        "/tf",
        "/sim/state",
        "/events",
    ] {
        assert!(log.topic(topic).count() > 0, "no messages on {topic}");
    }
    assert!(
        log.attachments.contains_key("model.urdf") && log.attachments.contains_key("scenario.toml")
    );
    assert!(log.metadata["stride"].contains_key("git_commit"));

    // Replay of each layer with the logged configuration reproduces its outputs exactly.
    for layer in [LayerName::Planner, LayerName::Simplified, LayerName::Wbc] {
        let r = stride_runner::replay::replay(&s.path("a.mcap"), layer, None, None).unwrap();
        assert!(r.ticks > 10, "{layer:?}: {} ticks", r.ticks);
        assert_eq!(r.difference.max_abs, 0.0, "{layer:?}: {:?}", r.difference);
        assert_eq!(r.difference.mismatches, 0, "{layer:?}: {:?}", r.difference);
    }
    // With another configuration the outputs move, and the new log holds them.
    let other = s.write(
        "other.toml",
        "include = [\"walk.toml\"]\n[simplified.instantaneous]\nkp = 2.0\n",
    );
    let out = s.path("replayed.mcap");
    let r = stride_runner::replay::replay(
        &s.path("a.mcap"),
        LayerName::Simplified,
        Some(&other),
        Some(&out),
    )
    .unwrap();
    assert!(r.difference.max_abs > 0.0, "{:?}", r.difference);
    assert_eq!(
        read_log(&out).unwrap().topic("/simplified/output").count(),
        r.ticks
    );
}

#[test]
fn interrupted_run_leaves_a_readable_log() {
    let s = Scratch::new("interrupt");
    let sc = scenario(&s);
    let mut o = options(s.path("i.mcap"));
    o.stop_after_ticks = Some(1234);
    let summary = run_scenario(&sc, &o).unwrap();
    assert_eq!(summary.outcome, Outcome::Interrupted);
    let log = read_log(&s.path("i.mcap")).unwrap();
    let last = log.messages.last().unwrap();
    assert_eq!(last.topic, "/events");
    let e: serde_json::Value = serde_json::from_slice(&last.data).unwrap();
    assert_eq!(e["kind"], "end");
    // The stop flag (what Ctrl-C sets) ends the run the same way.
    let flag = Arc::new(std::sync::atomic::AtomicBool::new(true));
    let mut o = options(s.path("j.mcap"));
    o.stop = Some(flag);
    assert_eq!(run_scenario(&sc, &o).unwrap().outcome, Outcome::Interrupted);
    assert!(!read_log(&s.path("j.mcap")).unwrap().messages.is_empty());
}

/// A robot that panics after some steps (a crashing driver or layer).
struct Panicking {
    inner: Box<dyn Robot>,
    steps: usize,
}

impl Robot for Panicking {
    fn name(&self) -> &str {
        "panicking"
    }
    fn model(&self) -> &Arc<stride_model::Model> {
        self.inner.model()
    }
    fn period_ns(&self) -> u64 {
        self.inner.period_ns()
    }
    fn measurement(&self) -> &Measurement {
        self.inner.measurement()
    }
    fn command(&mut self, c: &JointCommand) -> Result<(), RobotError> {
        self.inner.command(c)
    }
    fn advance(&mut self) -> Result<(), RobotError> {
        self.steps += 1;
        if self.steps == 500 {
            panic!("driver crashed");
        }
        self.inner.advance()
    }
}

#[test]
fn panic_in_the_loop_is_reported_and_the_log_closed() {
    let s = Scratch::new("panic");
    let sc = scenario(&s);
    let model = load_model(&sc).unwrap();
    let inner = build_robot(&sc, &model, PlantKind::Ideal).unwrap();
    let summary = run_with_robot(
        &sc,
        &options(s.path("p.mcap")),
        Box::new(Panicking { inner, steps: 0 }),
    )
    .unwrap();
    match &summary.outcome {
        Outcome::Error { message } => assert!(message.contains("driver crashed"), "{message}"),
        other => panic!("expected an error outcome, got {other:?}"),
    }
    let log = read_log(&s.path("p.mcap")).unwrap();
    assert!(log.topic("/wbc/output").count() > 10);
}

#[test]
fn simulator_runs_are_deterministic_too() {
    let s = Scratch::new("simdet");
    s.write("r.toml", &common::robot_section());
    let top = s.write(
        "s.toml",
        "include = [\"r.toml\"]\n[scenario]\nduration = 0.5\n[goal.stand]\n[end]\nstop_at_goal = false\n",
    );
    let sc = Scenario::load(&top).unwrap();
    let o = |p: &str| RunOptions {
        output: Some(s.path(p)),
        plant: Some(PlantKind::Simulator),
        ..RunOptions::default()
    };
    let a = run_scenario(&sc, &o("a.mcap")).unwrap();
    run_scenario(&sc, &o("b.mcap")).unwrap();
    assert_eq!(a.outcome, Outcome::DurationReached, "{}", a.render());
    assert_eq!(a.plant, "simulator");
    let ma = deterministic_messages(&s.path("a.mcap"));
    assert!(ma.len() > 100);
    assert_eq!(ma, deterministic_messages(&s.path("b.mcap")));
}

/// `/tf` (world → every body, at each state tick) composed with `/tf_static` (body → each rigidly attached
/// frame, once a second) gives every frame of the model at the logged state, as stride-model computes it.
#[test]
fn tf_and_tf_static_reconstruct_every_frame() {
    use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
    use std::collections::BTreeMap;
    use stride_model::{KinDyn, RobotState};
    use stride_runner::records::StateRecord;

    let s = Scratch::new("tf");
    let sc = scenario(&s);
    run_scenario(&sc, &options(s.path("tf.mcap"))).unwrap();
    let log = read_log(&s.path("tf.mcap")).unwrap();
    let model = load_model(&sc).unwrap();
    let pose = |t: &serde_json::Value| {
        let (p, q) = (&t["translation"], &t["rotation"]);
        let f = |v: &serde_json::Value| v.as_f64().unwrap();
        Isometry3::from_parts(
            Translation3::new(f(&p["x"]), f(&p["y"]), f(&p["z"])),
            UnitQuaternion::from_quaternion(Quaternion::new(
                f(&q["w"]),
                f(&q["x"]),
                f(&q["y"]),
                f(&q["z"]),
            )),
        )
    };
    let parse = |data: &[u8]| -> Vec<(String, String, Isometry3<f64>)> {
        let v: serde_json::Value = serde_json::from_slice(data).unwrap();
        v["transforms"]
            .as_array()
            .unwrap()
            .iter()
            .map(|t| {
                (
                    t["parent_frame_id"].as_str().unwrap().to_string(),
                    t["child_frame_id"].as_str().unwrap().to_string(),
                    pose(t),
                )
            })
            .collect()
    };
    let statics: Vec<_> = log.topic("/tf_static").collect();
    let tfs: Vec<_> = log.topic("/tf").collect();
    // once at the start and then once a second (the scenario lasts 1.5 s)
    assert_eq!(statics.len(), 2);
    assert_eq!(statics[0].time_ns, tfs[0].time_ns);
    let attached: BTreeMap<String, (String, Isometry3<f64>)> = parse(&statics[0].data)
        .into_iter()
        .map(|(parent, child, p)| (child, (parent, p)))
        .collect();
    let mut kd = KinDyn::new(model.clone());
    let mut state = RobotState::zero(&model);
    let states: Vec<_> = log.topic("/sim/state").collect();
    assert_eq!(states.len(), tfs.len());
    for (st, tf) in states.iter().zip(&tfs).step_by(37) {
        assert_eq!(st.time_ns, tf.time_ns);
        let record: StateRecord = serde_json::from_slice(&st.data).unwrap();
        record.to_state(&mut state).unwrap();
        kd.set_state(&state).unwrap();
        let bodies: BTreeMap<String, Isometry3<f64>> = parse(&tf.data)
            .into_iter()
            .map(|(parent, child, p)| {
                assert_eq!(parent, "world");
                (child, p)
            })
            .collect();
        assert_eq!(bodies.len() + attached.len(), model.frames().len());
        for frame in model.frames() {
            let expected = kd.frame_pose(model.frame_id(&frame.name).unwrap());
            let got = match bodies.get(&frame.name) {
                Some(p) => *p,
                None => {
                    let (parent, local) = &attached[&frame.name];
                    bodies[parent] * local
                }
            };
            let error = (got.translation.vector - expected.translation.vector)
                .norm()
                .max(got.rotation.angle_to(&expected.rotation));
            assert!(error < 1e-12, "{}: {error:e}", frame.name);
        }
    }
}
