//! Every frame, joint and sensor name a scenario uses, with the key that sets it and where that key was
//! written (a file and line, or the built-in defaults), checked against the model.

use stride_model::Model;
use stride_wbc::TaskConfig;

use crate::config::{EstimationKind, Scenario};

/// What a name must be in the model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NameKind {
    /// A frame (a link, a merged link or a sensor frame).
    Frame,
    /// A movable joint.
    Joint,
    /// A six-axis force/torque sensor (by sensor name).
    FtSensor,
}

impl NameKind {
    fn noun(self) -> &'static str {
        match self {
            NameKind::Frame => "frame",
            NameKind::Joint => "joint",
            NameKind::FtSensor => "force/torque sensor",
        }
    }
}

/// One name the scenario uses.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NameUse {
    /// Dotted key that sets it, e.g. `wbc.ik.tasks[2].frame`.
    pub key: String,
    /// The name.
    pub name: String,
    /// What it must be.
    pub kind: NameKind,
}

/// A name the model lacks, with where it was set.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NameProblem {
    /// The use.
    pub name: NameUse,
    /// `file:line:col`, or `built-in default ...` saying which default set it came from.
    pub origin: String,
}

impl NameProblem {
    /// What is missing, without the origin.
    pub fn what(&self) -> String {
        format!(
            "key `{}`: the model has no {} `{}`",
            self.name.key,
            self.name.kind.noun(),
            self.name.name
        )
    }
}

impl std::fmt::Display for NameProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.origin, self.what())
    }
}

/// Every name the scenario uses (the robot's parts, the whole-body tasks of the control mode's
/// controller and of the other one, the simulator's surfaces, actuators, pushes and inertia edits, the
/// estimation layer's sensors).
pub fn name_uses(scenario: &Scenario) -> Vec<NameUse> {
    let c = &scenario.config;
    let mut out = Vec::new();
    let mut push = |key: String, name: &str, kind: NameKind| {
        out.push(NameUse {
            key,
            name: name.to_string(),
            kind,
        })
    };
    for (side, sole) in [("left", &c.robot.left_sole), ("right", &c.robot.right_sole)] {
        match sole.attached() {
            Some(a) => push(
                format!("robot.{side}_sole.parent"),
                &a.parent,
                NameKind::Frame,
            ),
            None => push(format!("robot.{side}_sole"), sole.name(), NameKind::Frame),
        }
    }
    push(
        "robot.torso_frame".into(),
        &c.robot.torso_frame,
        NameKind::Frame,
    );
    if let Some(base) = &c.robot.base_frame {
        push("robot.base_frame".into(), base, NameKind::Frame);
    }
    for j in c.robot.initial_joint_positions.keys() {
        push(
            format!("robot.initial_joint_positions.{j}"),
            j,
            NameKind::Joint,
        );
    }
    for (section, tasks) in [("wbc.ik", &c.wbc.ik.tasks), ("wbc.tsid", &c.wbc.tsid.tasks)] {
        for (i, task) in tasks.iter().enumerate() {
            task_names(&format!("{section}.tasks[{i}]"), task, &mut push);
        }
    }
    for (i, s) in c.sim.contact.surfaces.iter().enumerate() {
        let key = format!("sim.contact.surfaces[{i}]");
        push(format!("{key}.frame"), &s.frame, NameKind::Frame);
        if let Some(ft) = &s.ft_sensor {
            push(format!("{key}.ft_sensor"), ft, NameKind::Frame);
        }
    }
    for (i, j) in c.sim.actuation.joints.iter().enumerate() {
        push(
            format!("sim.actuation.joints[{i}].name"),
            &j.name,
            NameKind::Joint,
        );
    }
    for (i, p) in c.sim.pushes.iter().enumerate() {
        push(format!("sim.pushes[{i}].frame"), &p.frame, NameKind::Frame);
    }
    for link in c.sim.model.links.keys() {
        push(format!("sim.model.links.{link}"), link, NameKind::Frame);
    }
    if c.estimation.kind == EstimationKind::Ekf {
        push(
            "sim.sensors.imu_frame".into(),
            &c.sim.sensors.imu_frame,
            NameKind::Frame,
        );
        let sensors = [
            ("left", &c.estimation.left_foot_ft_sensor),
            ("right", &c.estimation.right_foot_ft_sensor),
        ];
        for (side, sensor) in sensors {
            if let Some(s) = sensor {
                push(
                    format!("estimation.{side}_foot_ft_sensor"),
                    s,
                    NameKind::FtSensor,
                );
            }
        }
    }
    out
}

/// The names one whole-body task uses.
fn task_names(key: &str, task: &TaskConfig, push: &mut impl FnMut(String, &str, NameKind)) {
    match task {
        TaskConfig::Se3(t) => push(format!("{key}.frame"), &t.frame, NameKind::Frame),
        TaskConfig::So3(t) | TaskConfig::R3(t) => {
            push(format!("{key}.frame"), &t.frame, NameKind::Frame)
        }
        TaskConfig::Contact(t) => push(format!("{key}.frame"), &t.frame, NameKind::Frame),
        TaskConfig::JointRegularization(t) => {
            for j in t.posture.keys() {
                push(format!("{key}.posture.{j}"), j, NameKind::Joint);
            }
            for j in t.joint_weights.keys() {
                push(format!("{key}.joint_weights.{j}"), j, NameKind::Joint);
            }
        }
        _ => {}
    }
}

/// Where `key` was set: its file location, or the built-in default set it belongs to.
pub fn origin(scenario: &Scenario, key: &str) -> String {
    let posture = "robot.initial_joint_positions";
    if key.starts_with(posture) && scenario.sources.key_location(posture).is_none() {
        return "built-in default `robot.initial_joint_positions` (the bundled humanoid's posture, also the \
                walking preset's; a written table replaces it whole, so write this robot's posture)"
            .to_string();
    }
    if let Some(loc) = scenario.sources.value_location(key) {
        return loc.to_string();
    }
    let list = ["sim.contact.surfaces"]
        .into_iter()
        .find(|l| key.starts_with(l));
    match list {
        Some(l) => format!(
            "built-in default `{l}` (the bundled humanoid's; a list is replaced whole, so restate the \
             whole `{l}` list for this robot)"
        ),
        None => "built-in default".to_string(),
    }
}

/// The names the model lacks, each with its origin.
pub fn missing_names(scenario: &Scenario, model: &Model) -> Vec<NameProblem> {
    name_uses(scenario)
        .into_iter()
        .filter(|u| !has_name(model, u))
        .map(|u| NameProblem {
            origin: origin(scenario, &u.key),
            name: u,
        })
        .collect()
}

fn has_name(model: &Model, u: &NameUse) -> bool {
    match u.kind {
        NameKind::Frame => model.frame_id(&u.name).is_some(),
        NameKind::Joint => model.joint_index(&u.name).is_some(),
        NameKind::FtSensor => model.ft_sensor_index(&u.name).is_some(),
    }
}

/// The problems, one a line; those from one built-in default set under one heading.
pub fn render_problems(problems: &[NameProblem]) -> String {
    let mut out = String::new();
    let mut heading = "";
    for p in problems {
        let what = p.what();
        if p.origin.starts_with("built-in default") {
            if p.origin != heading {
                out.push_str(&format!("\n  {}:", p.origin));
                heading = &p.origin;
            }
            out.push_str(&format!("\n    {what}"));
        } else {
            heading = "";
            out.push_str(&format!("\n  {}: {what}", p.origin));
        }
    }
    out
}
