//! Building a run from its scenario: the model, the initial posture, the plant, the log path.

use std::path::PathBuf;
use std::sync::Arc;

use nalgebra::{DVector, Vector3};
use stride_model::{
    FrameId, InertiaEdits, JointLock, LinkInertiaEdit, Model, ModelError, RobotState,
};

use crate::config::{PlantKind, Scenario};
use crate::error::RunError;
use crate::robot::{IdealPlant, Robot};
use crate::sim_plant::SimPlant;

/// Initial joint positions from the scenario (unknown joint names are configuration errors).
pub fn initial_joint_positions(
    scenario: &Scenario,
    model: &Model,
) -> Result<DVector<f64>, RunError> {
    let mut q = DVector::zeros(model.dof());
    for (name, v) in &scenario.config.robot.initial_joint_positions {
        let i = model.joint_index(name).ok_or_else(|| {
            scenario.invalid(
                &format!("robot.initial_joint_positions.{name}"),
                format!(
                    "the model has no joint `{name}`; expected one of: {}",
                    joint_list(model)
                ),
            )
        })?;
        q[i] = *v;
    }
    stride_model::check_joint_limits(model, &q)
        .map_err(|e| scenario.invalid("robot.initial_joint_positions", e.to_string()))?;
    Ok(q)
}

fn joint_list(model: &Model) -> String {
    model
        .joints()
        .iter()
        .map(|j| j.name.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Loads the scenario's model.
///
/// The scenario's one gravity (`scenario.gravity`, m/s² along −z) is set on the model here; the planner,
/// the controllers and the simulator all read it from the model (or receive it from the runner).
pub fn load_model(scenario: &Scenario) -> Result<Arc<Model>, RunError> {
    let load_error = |source| RunError::ModelLoad {
        path: scenario.urdf_path.clone(),
        source,
    };
    let mut model = Model::from_urdf_file_reduced(
        &scenario.urdf_path,
        &InertiaEdits::default(),
        &joint_locks(scenario),
    )
    .map_err(|e| load_failure(scenario, &scenario.urdf_path, e))?;
    let g = scenario.config.scenario.gravity;
    model
        .set_gravity(Vector3::new(0.0, 0.0, -g))
        .map_err(load_error)?;
    add_sole_frames(scenario, &mut model)?;
    apply_joint_limits(scenario, &mut model)?;
    Ok(Arc::new(model))
}

/// `robot.effort_limits` and `robot.velocity_limits` on `model`: each entry sets the limit of every joint its
/// name or glob matches (later entries, in name order, win). An entry that matches no joint, or a limit
/// that is not positive and finite, is a configuration error at its key.
fn apply_joint_limits(scenario: &Scenario, model: &mut Model) -> Result<(), RunError> {
    type Setter = fn(&mut Model, usize, f64) -> Result<(), ModelError>;
    let r = &scenario.config.robot;
    let tables: [(&str, &std::collections::BTreeMap<String, f64>, Setter); 2] = [
        (
            "robot.effort_limits",
            &r.effort_limits,
            Model::set_effort_limit,
        ),
        (
            "robot.velocity_limits",
            &r.velocity_limits,
            Model::set_velocity_limit,
        ),
    ];
    for (table, entries, set) in tables {
        for (pattern, limit) in entries {
            let key = format!("{table}.{pattern}");
            let matched: Vec<usize> = (0..model.dof())
                .filter(|&i| stride_model::glob_matches(pattern, &model.joints()[i].name))
                .collect();
            if matched.is_empty() {
                return Err(RunError::Config(scenario.invalid(
                    &key,
                    format!(
                        "`{pattern}` matches no joint of the model; expected a name or glob of: {}",
                        joint_list(model)
                    ),
                )));
            }
            for i in matched {
                set(model, i, *limit)
                    .map_err(|e| RunError::Config(scenario.invalid(&key, e.to_string())))?;
            }
        }
    }
    Ok(())
}

/// `robot.locked_joints` as the model's lock list.
pub fn joint_locks(scenario: &Scenario) -> Vec<JointLock> {
    let locks = &scenario.config.robot.locked_joints;
    locks.iter().map(|(p, q)| JointLock::new(p, *q)).collect()
}

/// A model that failed to load from `path`: a lock the model rejected is a configuration error at its
/// `robot.locked_joints` entry.
fn load_failure(scenario: &Scenario, path: &std::path::Path, e: ModelError) -> RunError {
    match e {
        ModelError::InvalidLock { pattern, reason } => RunError::Config(scenario.invalid(
            &format!("robot.locked_joints.{pattern}"),
            format!("`{pattern}` {reason}"),
        )),
        source => RunError::ModelLoad {
            path: path.to_path_buf(),
            source,
        },
    }
}

/// Adds the sole frames the configuration attaches to links (`robot.left_sole = { parent, xyz, rpy }`).
fn add_sole_frames(scenario: &Scenario, model: &mut Model) -> Result<(), RunError> {
    let r = &scenario.config.robot;
    for (key, sole) in [
        ("robot.left_sole", &r.left_sole),
        ("robot.right_sole", &r.right_sole),
    ] {
        if let Some(a) = sole.attached() {
            model
                .add_frame(&a.name, &a.parent, a.placement())
                .map_err(|e| scenario.invalid(key, e.to_string()))?;
        }
    }
    Ok(())
}

/// The simulated plant's own model: the controllers' `model` unless `[sim.model]` sets another URDF or
/// changes inertias (model mismatch), then loaded from that URDF with the changes applied to its links
/// before lumping, with the scenario's gravity.
pub fn load_plant_model(scenario: &Scenario, model: &Arc<Model>) -> Result<Arc<Model>, RunError> {
    let m = &scenario.config.sim.model;
    if m.urdf.is_none() && m.mass_scale == 1.0 && m.links.is_empty() {
        return Ok(Arc::clone(model));
    }
    let path = scenario
        .plant_urdf_path
        .clone()
        .unwrap_or_else(|| scenario.urdf_path.clone());
    let edits = plant_inertia_edits(scenario);
    let load_error = |source| RunError::ModelLoad {
        path: path.clone(),
        source,
    };
    let mut plant = Model::from_urdf_file_reduced(&path, &edits, &joint_locks(scenario))
        .map_err(|e| load_failure(scenario, &scenario.urdf_path, e))?;
    plant.set_gravity(model.gravity()).map_err(load_error)?;
    add_sole_frames(scenario, &mut plant)?;
    apply_joint_limits(scenario, &mut plant)?;
    check_same_joints(scenario, model, &plant)?;
    Ok(Arc::new(plant))
}

/// `[sim.model]`'s inertia changes (mass scale, per-link mass scales and CoM offsets) as model edits.
pub fn plant_inertia_edits(scenario: &Scenario) -> InertiaEdits {
    let m = &scenario.config.sim.model;
    InertiaEdits {
        mass_scale: m.mass_scale,
        links: m
            .links
            .iter()
            .map(|(link, change)| LinkInertiaEdit {
                link: link.clone(),
                mass_scale: change.mass_scale,
                com_offset: Vector3::from(change.com_offset),
            })
            .collect(),
    }
}

/// The plant must have the controllers' joints, in the same order.
pub(crate) fn check_same_joints(
    scenario: &Scenario,
    model: &Model,
    plant: &Model,
) -> Result<(), RunError> {
    let names = |m: &Model| {
        m.joints()
            .iter()
            .map(|j| j.name.clone())
            .collect::<Vec<_>>()
    };
    if names(model) == names(plant) {
        return Ok(());
    }
    Err(RunError::Config(scenario.invalid(
        "sim.model.urdf",
        format!(
            "the plant's joints ({}) differ from the controllers' model's ({}); expected the same joints in \
             the same order",
            joint_list(plant),
            joint_list(model)
        ),
    )))
}

/// Builds the plant of the scenario (or of the override). `model` is the controllers' model; the
/// simulator runs on [`load_plant_model`]'s.
pub fn build_robot(
    scenario: &Scenario,
    model: &Arc<Model>,
    plant: PlantKind,
) -> Result<Box<dyn Robot>, RunError> {
    let c = &scenario.config;
    let q0 = initial_joint_positions(scenario, model)?;
    let soles = [
        frame_of(scenario, model, "robot.left_sole", &c.robot.left_sole)?,
        frame_of(scenario, model, "robot.right_sole", &c.robot.right_sole)?,
    ];
    Ok(match plant {
        PlantKind::Simulator => {
            let plant = load_plant_model(scenario, model)?;
            let soles = [
                frame_of(scenario, &plant, "robot.left_sole", &c.robot.left_sole)?,
                frame_of(scenario, &plant, "robot.right_sole", &c.robot.right_sole)?,
            ];
            Box::new(SimPlant::new(
                plant,
                c.sim.clone(),
                scenario.sim_period(),
                c.scenario.control_mode,
                &q0,
                soles,
            )?)
        }
        PlantKind::Mujoco => mujoco_robot(scenario, model, &q0)?,
        PlantKind::Ideal => {
            let state = RobotState::standing(model, &q0, soles[0], soles[1])?;
            let period = 1_000_000_000 / u64::from(c.rates.sim_hz);
            Box::new(IdealPlant::new(
                Arc::clone(model),
                period,
                soles[0],
                soles[1],
                &state,
            )?)
        }
    })
}

/// The MuJoCo plant on the plant's URDF (`[sim.model] urdf`, else `robot.urdf`) with the `[mujoco]`
/// section (range-checked here, errors at its keys), the plant model's inertias written over MuJoCo's when
/// `[sim.model]` edits them.
#[cfg(feature = "mujoco")]
fn mujoco_robot(
    scenario: &Scenario,
    model: &Arc<Model>,
    q0: &DVector<f64>,
) -> Result<Box<dyn Robot>, RunError> {
    let period = scenario.sim_period().as_secs_f64();
    if let Some((key, reason)) = unsupported_by_mujoco(scenario) {
        return Err(RunError::Config(scenario.invalid(key, reason)));
    }
    let plant = load_plant_model(scenario, model)?;
    if let Err(stride_mujoco::MujocoError::InvalidConfig {
        parameter,
        value,
        reason,
    }) = crate::mujoco_plant::mujoco_config(scenario, &plant).validate(period)
    {
        let key = format!("mujoco.{}", parameter.split('[').next().unwrap_or_default());
        return Err(RunError::Config(
            scenario.invalid(&key, format!("{value}: {reason}")),
        ));
    }
    let urdf = scenario
        .plant_urdf_path
        .clone()
        .unwrap_or_else(|| scenario.urdf_path.clone());
    let c = &scenario.config;
    let soles = [
        frame_of(scenario, &plant, "robot.left_sole", &c.robot.left_sole)?,
        frame_of(scenario, &plant, "robot.right_sole", &c.robot.right_sole)?,
    ];
    Ok(Box::new(crate::mujoco_plant::MujocoPlant::new(
        scenario, plant, &urdf, q0, soles,
    )?))
}

/// What a scenario asks of the plant that the MuJoCo plant does not model, as the key and the reason:
/// ground patches of different stiffness along the path (its floor is one plane with one contact law),
/// and passive joints (`--plant mujoco` on a scenario written for stride-sim). A fixed base is modelled (the
/// root a mocap body held at the initial pose), and so is a uniform floor, soft or stiff, is modelled: its `sim.contact`
/// stiffness and damping set MuJoCo's `solref` ([`crate::config::mujoco::ground_solref`]).
#[cfg_attr(not(feature = "mujoco"), allow(dead_code))]
pub(crate) fn unsupported_by_mujoco(scenario: &Scenario) -> Option<(&'static str, &'static str)> {
    let sim = &scenario.config.sim;
    if !sim.ground.patches.is_empty() {
        Some((
            "sim.ground.patches",
            "ground patches are modelled by stride-sim only: the MuJoCo plant's floor is one plane with \
             one contact law (docs/mujoco.md); run it with `--plant simulator`, or remove the key",
        ))
    } else if !sim.passive_joints.is_empty() {
        Some((
            "sim.passive_joints",
            "passive visco-elastic joints are modelled by stride-sim only (docs/flexible-joints.md); run it \
             with `--plant simulator`",
        ))
    } else {
        None
    }
}

/// Without the `mujoco` feature the MuJoCo plant is a configuration error that names the build command.
#[cfg(not(feature = "mujoco"))]
fn mujoco_robot(
    scenario: &Scenario,
    _model: &Arc<Model>,
    _q0: &DVector<f64>,
) -> Result<Box<dyn Robot>, RunError> {
    Err(RunError::Config(scenario.invalid(
        "scenario.plant",
        "the MuJoCo plant is not in this build of stride; build it with \
         `MUJOCO_DYNAMIC_LINK_DIR=$(bash tools/mujoco/setup.sh) cargo build --release --features mujoco` \
         (see docs/mujoco.md), or choose `simulator` or `ideal`",
    )))
}

/// The model frame `name`, set by the scenario key `key`; a name the model lacks is a configuration
/// error located at the key.
pub(crate) fn frame_of(
    scenario: &Scenario,
    model: &Model,
    key: &str,
    name: &str,
) -> Result<FrameId, RunError> {
    model.frame_id(name).ok_or_else(|| {
        RunError::Config(scenario.invalid(
            key,
            format!("the model has no frame `{name}`; expected one of its links or frames"),
        ))
    })
}

/// Default log path of a scenario.
pub fn default_log_path(scenario: &Scenario) -> PathBuf {
    let p = &scenario.config.log.path;
    if p.as_os_str().is_empty() {
        PathBuf::from(format!("{}.mcap", scenario.config.scenario.name))
    } else {
        p.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scenario(name: &str) -> Scenario {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../configs")
            .join(name);
        Scenario::load(&path).expect("shipped scenario loads")
    }

    #[test]
    fn mujoco_refuses_ground_patches_and_passive_joints_and_accepts_uniform_floors_and_a_fixed_base(
    ) {
        let soft = scenario("walk_soft_ground_torque.toml");
        assert_eq!(unsupported_by_mujoco(&soft), None);
        let mut stiff = scenario("walk_straight.toml");
        assert_eq!(unsupported_by_mujoco(&stiff), None);
        stiff.config.sim.contact.normal_stiffness *= 10.0;
        assert_eq!(unsupported_by_mujoco(&stiff), None);
        let mut with_patch = scenario("walk_straight.toml");
        with_patch
            .config
            .sim
            .ground
            .patches
            .push(stride_sim::GroundPatchConfig::normal(1.0, 2.0, 1e6, 1e4));
        let (key, _) = unsupported_by_mujoco(&with_patch).expect("refused");
        assert_eq!(key, "sim.ground.patches");
        let on_a_pole = scenario("identify_ft_legs.toml");
        assert!(on_a_pole.config.sim.fixed_base);
        assert_eq!(unsupported_by_mujoco(&on_a_pole), None);
        let flexible = scenario("walk_flexible_hips_torque.toml");
        let (key, _) = unsupported_by_mujoco(&flexible).expect("refused");
        assert_eq!(key, "sim.passive_joints");
    }
}
