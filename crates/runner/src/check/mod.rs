//! `stride check`: the scenario against its model. Every name is looked up (with where it was set), the
//! run's plant and layers are built as `stride run` builds them, and the initial posture and the
//! simulated ground are compared with the planner's geometry and the robot's toppling stiffness.

pub mod names;
pub mod posture;

use std::sync::Arc;

use stride_model::Model;

use crate::config::{PlantKind, Scenario};
use crate::error::RunError;
use crate::setup::{build_robot, frame_of, initial_joint_positions, load_model};
use names::{missing_names, NameProblem};
use posture::{ground_warnings, posture_warnings, sole_geometry_warnings, Stance};

/// Why a scenario fails its check.
#[derive(Debug, thiserror::Error)]
pub enum CheckError {
    /// Names the model lacks (every one, each with where it was set).
    #[error("{} name(s) the model lacks:{}", problems.len(), names::render_problems(problems))]
    Names {
        /// The names.
        problems: Vec<NameProblem>,
    },
    /// The model, the plant or a layer could not be built.
    #[error(transparent)]
    Run(#[from] RunError),
}

/// What a passing check found.
#[derive(Debug, Clone)]
pub struct CheckReport {
    /// The model.
    pub model: Arc<Model>,
    /// The robot standing at its initial posture.
    pub stance: Stance,
    /// Warnings (the run may still work, but probably not as intended).
    pub warnings: Vec<String>,
}

/// Loads the model, checks every name, builds the plant and the layers, and collects the warnings.
pub fn check_scenario(scenario: &Scenario) -> Result<CheckReport, CheckError> {
    let c = &scenario.config;
    let model = load_model(scenario)?;
    let problems = missing_names(scenario, &model);
    if !problems.is_empty() {
        return Err(CheckError::Names { problems });
    }
    let q0 = initial_joint_positions(scenario, &model)?;
    let soles = [
        frame_of(scenario, &model, "robot.left_sole", &c.robot.left_sole)?,
        frame_of(scenario, &model, "robot.right_sole", &c.robot.right_sole)?,
    ];
    let stance = Stance::new(&model, &q0, soles).map_err(RunError::from)?;
    build_layers(scenario, &model)?;
    let mut warnings = sole_geometry_warnings(&scenario.urdf_path, &model, soles);
    warnings.extend(posture_warnings(c, &stance));
    if c.scenario.plant == PlantKind::Simulator {
        warnings.extend(ground_warnings(c, &stance));
    }
    Ok(CheckReport {
        model,
        stance,
        warnings,
    })
}

/// Builds the plant and every layer as `stride run` does (and drops them): whatever they reject, the check
/// rejects.
fn build_layers(scenario: &Scenario, model: &Arc<Model>) -> Result<(), RunError> {
    let robot = build_robot(scenario, model, scenario.config.scenario.plant)?;
    let initial = crate::run::initial_state(scenario, model, robot.measurement())?;
    crate::stack::Stack::new(scenario, Arc::clone(model), &initial)?;
    Ok(())
}
