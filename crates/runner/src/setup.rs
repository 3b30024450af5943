//! Building a run from its scenario: the model, the initial posture, the plant, the log path.

use std::path::PathBuf;
use std::sync::Arc;

use nalgebra::{DVector, Vector3};
use stride_model::{FrameId, Model};

use crate::config::{PlantKind, Scenario};
use crate::error::RunError;
use crate::robot::{standing_state, IdealPlant, Robot};
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
    let mut model = Model::from_urdf_file(&scenario.urdf_path).map_err(load_error)?;
    let g = scenario.config.scenario.gravity;
    model
        .set_gravity(Vector3::new(0.0, 0.0, -g))
        .map_err(load_error)?;
    Ok(Arc::new(model))
}

/// Builds the plant of the scenario (or of the override).
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
        PlantKind::Simulator => Box::new(SimPlant::new(
            Arc::clone(model),
            c.sim.clone(),
            scenario.sim_period(),
            c.scenario.control_mode,
            &q0,
            soles,
        )?),
        PlantKind::Ideal => {
            let state = standing_state(model, &q0, soles[0], soles[1])?;
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
