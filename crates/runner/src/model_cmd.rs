//! `stride model info` and `stride model eval`: the JSON contracts documented in docs/cli.md, which other
//! tools rely on.
use std::collections::BTreeMap;
use std::path::Path;
use std::process::ExitCode;
use std::sync::Arc;

use nalgebra::{
    DMatrix, DVector, Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3, Vector6,
};
use serde::{Deserialize, Serialize};
use serde_json::json;
use stride_model::{FrameKind, KinDyn, Model, RobotState, VelocityRepresentation};

use crate::cli::{CliError, ModelCommand, Representation};

/// Runs a `stride model` subcommand.
pub fn model(command: ModelCommand) -> Result<ExitCode, CliError> {
    match command {
        ModelCommand::Info { urdf, json } => {
            let model = load(&urdf)?;
            let info = info(&model)?;
            if json {
                crate::outln!(
                    "{}",
                    serde_json::to_string_pretty(&info)
                        .map_err(|e| CliError::msg(e.to_string()))?
                );
            } else {
                print_info(&info);
            }
            Ok(ExitCode::SUCCESS)
        }
        ModelCommand::Feet { urdf } => {
            let feet = crate::feet::propose_feet(&urdf)
                .map_err(|e| CliError::msg(crate::cli::one_paragraph(&e)))?;
            print_feet(&feet);
            Ok(ExitCode::SUCCESS)
        }
        ModelCommand::Eval {
            urdf,
            state,
            representation,
        } => {
            let model = load(&urdf)?;
            let text = std::fs::read_to_string(&state).map_err(|e| {
                CliError::msg(format!("cannot read state file {}: {e}", state.display()))
            })?;
            let input: EvalInput = serde_json::from_str(&text)
                .map_err(|e| CliError::msg(format!("state file {}: {e}", state.display())))?;
            let out = eval(&model, &input, representation)?;
            crate::outln!(
                "{}",
                serde_json::to_string(&out).map_err(|e| CliError::msg(e.to_string()))?
            );
            Ok(ExitCode::SUCCESS)
        }
    }
}

fn load(path: &Path) -> Result<Arc<Model>, CliError> {
    Model::from_urdf_file(path)
        .map(Arc::new)
        .map_err(|e| CliError::msg(format!("cannot load model {}: {e}", path.display())))
}

/// One joint in `model info --json`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct JointInfo {
    /// Name.
    pub name: String,
    /// `revolute`, `continuous` or `prismatic`.
    #[serde(rename = "type")]
    pub kind: String,
    /// Axis in the child link frame.
    pub axis: [f64; 3],
    /// Lower position limit [rad or m]; `null` if unbounded.
    pub lower: Option<f64>,
    /// Upper position limit [rad or m]; `null` if unbounded.
    pub upper: Option<f64>,
    /// Velocity limit [rad/s or m/s].
    pub velocity_limit: f64,
    /// Effort limit [N m or N].
    pub effort_limit: f64,
    /// Parent link.
    pub parent_link: String,
    /// Child link.
    pub child_link: String,
    /// Joint this one mimics in the URDF (loaded as independent).
    pub mimic: Option<String>,
}

/// One frame in `model info --json`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct FrameInfo {
    /// Name.
    pub name: String,
    /// Body (link moved by a joint) it is attached to.
    pub body: String,
    /// `body`, `merged_link` or `sensor`.
    pub kind: FrameKind,
}

/// One force/torque sensor in `model info --json`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct SensorInfo {
    /// Name.
    pub name: String,
    /// `force_torque`.
    #[serde(rename = "type")]
    pub kind: String,
    /// Fixed joint it measures.
    pub joint: String,
    /// Measurement frame.
    pub frame: String,
    /// Parent link.
    pub parent_link: String,
    /// Child link.
    pub child_link: String,
}

/// `stride model info --json`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct ModelInfo {
    /// Robot name.
    pub name: String,
    /// Degrees of freedom (non-fixed joints).
    pub dof: usize,
    /// Size of ν (6 + dof).
    pub nv: usize,
    /// Root link (floating base).
    pub root_link: String,
    /// Total mass \[kg\].
    pub total_mass: f64,
    /// CoM \[m\] at the zero configuration with the base at the world origin.
    pub com_at_zero: [f64; 3],
    /// Joints in model order.
    pub joints: Vec<JointInfo>,
    /// URDF links (bodies and merged links).
    pub links: Vec<String>,
    /// Every frame.
    pub frames: Vec<FrameInfo>,
    /// Sensors.
    pub sensors: Vec<SensorInfo>,
    /// Loader warnings.
    pub warnings: Vec<String>,
}

fn finite_or_none(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

/// Collects `model info`.
pub fn info(model: &Arc<Model>) -> Result<ModelInfo, CliError> {
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_state(&RobotState::zero(model))
        .map_err(|e| CliError::msg(format!("zero state: {e}")))?;
    let com = kd.com_position();
    let bodies = model.bodies();
    Ok(ModelInfo {
        name: model.name().to_string(),
        dof: model.dof(),
        nv: model.nv(),
        root_link: model.root_link().to_string(),
        total_mass: model.total_mass(),
        com_at_zero: [com.x, com.y, com.z],
        joints: model
            .joints()
            .iter()
            .map(|j| JointInfo {
                name: j.name.clone(),
                kind: j.kind.as_str().to_string(),
                axis: [j.axis.x, j.axis.y, j.axis.z],
                lower: finite_or_none(j.lower),
                upper: finite_or_none(j.upper),
                velocity_limit: j.velocity_limit,
                effort_limit: j.effort_limit,
                parent_link: j.parent_link.clone(),
                child_link: j.child_link.clone(),
                mimic: j.mimic.as_ref().map(|m| m.joint.clone()),
            })
            .collect(),
        links: model
            .frames()
            .iter()
            .filter(|f| f.kind != FrameKind::Sensor)
            .map(|f| f.name.clone())
            .collect(),
        frames: model
            .frames()
            .iter()
            .map(|f| FrameInfo {
                name: f.name.clone(),
                body: bodies
                    .get(f.link)
                    .map(|b| b.name.clone())
                    .unwrap_or_default(),
                kind: f.kind,
            })
            .collect(),
        sensors: model
            .ft_sensors()
            .iter()
            .map(|s| SensorInfo {
                name: s.name.clone(),
                kind: "force_torque".into(),
                joint: s.joint.clone(),
                frame: model.frame_name(s.frame).to_string(),
                parent_link: s.parent_link.clone(),
                child_link: s.child_link.clone(),
            })
            .collect(),
        warnings: model.warnings().to_vec(),
    })
}

fn print_info(i: &ModelInfo) {
    crate::outln!(
        "model {}: {} DoF (nv = {}), root link {}",
        i.name,
        i.dof,
        i.nv,
        i.root_link
    );
    crate::outln!("total mass: {:.4} kg", i.total_mass);
    crate::outln!(
        "CoM at zero configuration: [{:.4}, {:.4}, {:.4}] m",
        i.com_at_zero[0],
        i.com_at_zero[1],
        i.com_at_zero[2]
    );
    crate::outln!("joints ({}), in model order:", i.joints.len());
    crate::outln!(
        "  {:>3}  {:<24} {:<10} {:<22} {:>9} {:>9} {:>8} {:>8}",
        "#",
        "name",
        "type",
        "axis",
        "lower",
        "upper",
        "vel",
        "effort"
    );
    for (k, j) in i.joints.iter().enumerate() {
        let lim = |x: Option<f64>| x.map_or("-inf/inf".to_string(), |v| format!("{v:.3}"));
        crate::outln!(
            "  {:>3}  {:<24} {:<10} [{:>5.2}, {:>5.2}, {:>5.2}]     {:>9} {:>9} {:>8.2} {:>8.2}{}",
            k,
            j.name,
            j.kind,
            j.axis[0],
            j.axis[1],
            j.axis[2],
            lim(j.lower),
            lim(j.upper),
            j.velocity_limit,
            j.effort_limit,
            j.mimic
                .as_ref()
                .map(|m| format!("  (mimics {m})"))
                .unwrap_or_default()
        );
    }
    crate::outln!("links ({}): {}", i.links.len(), i.links.join(", "));
    let extra: Vec<&str> = i
        .frames
        .iter()
        .filter(|f| f.kind != FrameKind::Body)
        .map(|f| f.name.as_str())
        .collect();
    crate::outln!(
        "frames ({} in total; besides body frames): {}",
        i.frames.len(),
        extra.join(", ")
    );
    crate::outln!("sensors ({}):", i.sensors.len());
    for s in &i.sensors {
        crate::outln!(
            "  {} ({}) on joint {}, frame {}",
            s.name,
            s.kind,
            s.joint,
            s.frame
        );
    }
    for w in &i.warnings {
        crate::outln!("warning: {w}");
    }
}

/// The input of `stride model eval` (joints missing from the maps are 0).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct EvalInput {
    /// Base position \[m\].
    #[serde(default)]
    pub base_position: [f64; 3],
    /// Base orientation, xyzw.
    #[serde(default = "identity_xyzw")]
    pub base_orientation_xyzw: [f64; 4],
    /// Joint positions by name.
    #[serde(default)]
    pub joint_positions: BTreeMap<String, f64>,
    /// Base velocity [v; ω] in the selected representation.
    #[serde(default)]
    pub base_velocity: [f64; 6],
    /// Joint velocities by name.
    #[serde(default)]
    pub joint_velocities: BTreeMap<String, f64>,
    /// Gravity [m/s²].
    #[serde(default = "default_gravity")]
    pub gravity: [f64; 3],
    /// Frames to report.
    #[serde(default)]
    pub frames: Vec<String>,
}

fn identity_xyzw() -> [f64; 4] {
    [0.0, 0.0, 0.0, 1.0]
}
fn default_gravity() -> [f64; 3] {
    [0.0, 0.0, -stride_model::STANDARD_GRAVITY]
}

fn rows(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|r| m.row(r).iter().copied().collect())
        .collect()
}

/// Evaluates the `model eval` output object.
pub fn eval(
    model: &Arc<Model>,
    input: &EvalInput,
    representation: Representation,
) -> Result<serde_json::Value, CliError> {
    let rep = match representation {
        Representation::Mixed => VelocityRepresentation::Mixed,
        Representation::Body => VelocityRepresentation::Body,
        Representation::Inertial => VelocityRepresentation::Inertial,
    };
    let n = model.dof();
    let nv = model.nv();
    let [qx, qy, qz, qw] = input.base_orientation_xyzw;
    let norm = (qx * qx + qy * qy + qz * qz + qw * qw).sqrt();
    if !norm.is_finite() || norm < 1e-9 {
        return Err(CliError::msg(
            "base_orientation_xyzw: expected a non-zero finite quaternion [x, y, z, w]",
        ));
    }
    let mut state = RobotState::zero(model);
    state.base_pose = Isometry3::from_parts(
        Translation3::new(
            input.base_position[0],
            input.base_position[1],
            input.base_position[2],
        ),
        UnitQuaternion::from_quaternion(Quaternion::new(qw, qx, qy, qz)),
    );
    state.base_velocity = Vector6::from_column_slice(&input.base_velocity);
    let joint = |name: &str, what: &str| {
        model.joint_index(name).ok_or_else(|| {
            CliError::msg(format!(
                "{what}: unknown joint `{name}` (the model's joints are listed by `stride model info`)"
            ))
        })
    };
    for (name, v) in &input.joint_positions {
        state.joint_positions[joint(name, "joint_positions")?] = *v;
    }
    for (name, v) in &input.joint_velocities {
        state.joint_velocities[joint(name, "joint_velocities")?] = *v;
    }
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_representation(rep);
    kd.set_gravity(Vector3::from_column_slice(&input.gravity));
    let err = |e: stride_model::ModelError| CliError::msg(format!("model eval: {e}"));
    kd.set_state(&state).map_err(err)?;
    let mut m = DMatrix::zeros(nv, nv);
    kd.mass_matrix(&mut m).map_err(err)?;
    let mut h = DVector::zeros(nv);
    kd.bias_forces(&mut h).map_err(err)?;
    let mut g = DVector::zeros(nv);
    kd.gravity_forces(&mut g).map_err(err)?;
    let mut jcom = DMatrix::zeros(3, nv);
    kd.com_jacobian(&mut jcom).map_err(err)?;
    let mut cmm = DMatrix::zeros(6, nv);
    kd.centroidal_momentum_matrix(&mut cmm).map_err(err)?;
    let com = kd.com_position();
    let vcom = kd.com_velocity();
    let hc = kd.centroidal_momentum();
    let mut frames = serde_json::Map::new();
    let mut jac = DMatrix::zeros(6, nv);
    for name in &input.frames {
        let id = model.frame_id(name).ok_or_else(|| {
            CliError::msg(format!(
                "frames: unknown frame `{name}` (see `stride model info`)"
            ))
        })?;
        let pose = kd.frame_pose(id);
        kd.frame_jacobian(id, &mut jac).map_err(err)?;
        let a = kd.frame_bias_acceleration(id);
        let q = pose.rotation.coords; // [i, j, k, w]
        frames.insert(
            name.clone(),
            json!({
                "position": [pose.translation.x, pose.translation.y, pose.translation.z],
                "orientation_xyzw": [q.x, q.y, q.z, q.w],
                "jacobian": rows(&jac),
                "bias_acceleration": a.iter().copied().collect::<Vec<_>>(),
            }),
        );
    }
    let out = json!({
        "representation": rep.as_str(),
        "joint_names": model.joints().iter().map(|j| j.name.clone()).collect::<Vec<_>>(),
        "total_mass": model.total_mass(),
        "mass_matrix": rows(&m),
        "bias_forces": h.iter().copied().collect::<Vec<_>>(),
        "gravity_forces": g.iter().copied().collect::<Vec<_>>(),
        "com_position": [com.x, com.y, com.z],
        "com_velocity": [vcom.x, vcom.y, vcom.z],
        "com_jacobian": rows(&jcom),
        "centroidal_momentum": hc.iter().copied().collect::<Vec<_>>(),
        "centroidal_momentum_matrix": rows(&cmm),
        "frames": frames,
    });
    debug_assert_eq!(n + 6, nv);
    Ok(out)
}

/// The proposal as configuration lines, then the warnings.
fn print_feet(feet: &[crate::feet::FootProposal; 2]) {
    for f in feet {
        let p = &f.patch;
        // `+ 0.0` prints −0 as 0.
        let t = f.sole_in_link.translation.vector.map(|v| v + 0.0);
        let (r, pi, y) = f.sole_in_link.rotation.euler_angles();
        let (r, pi, y) = (r + 0.0, pi + 0.0, y + 0.0);
        crate::outln!(
            "{} foot: link `{}` ({}): flat patch {:.3} m × {:.3} m (x × y) of {} points, centre [{:.4}, {:.4}, {:.4}] m at the zero posture",
            f.side, f.link, f.source, p.length, p.width, p.points, p.centre.x, p.centre.y, p.centre.z
        );
        crate::outln!(
            "  robot.{}_sole = {{ parent = \"{}\", xyz = [{:.4}, {:.4}, {:.4}], rpy = [{:.4}, {:.4}, {:.4}] }}",
            f.side, f.link, t.x, t.y, t.z, r, pi, y
        );
    }
    let [l, r] = feet;
    let length = l.patch.length.min(r.patch.length);
    let width = l.patch.width.min(r.patch.width);
    crate::outln!(
        "sole rectangle (the smaller foot): planner.foot_length = {length:.3}, planner.foot_width = {width:.3}; \
         sim.contact.surfaces[].length = {length:.3}, width = {width:.3}; wbc contact foot_x = [{:.4}, {:.4}], foot_y = [{:.4}, {:.4}]",
        -0.5 * length, 0.5 * length, -0.5 * width, 0.5 * width
    );
    for f in feet {
        for w in &f.warnings {
            crate::outln!("warning: {} foot (`{}`): {w}", f.side, f.link);
        }
    }
}
