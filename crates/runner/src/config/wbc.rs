//! `[wbc]`: the whole-body controllers' task lists, from the walking preset of stride-wbc
//! ([`stride_wbc::presets`]) built from the robot section, overridden task by task, or written whole.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use stride_model::{glob_matches, Model};
use stride_wbc::presets::{walking_ik, walking_tsid, with_overrides, WalkingFrames, WalkingPreset};
use stride_wbc::{ContactModel, IkConfig, ReferenceOffset, TaskConfig, TsidConfig};

use super::{RobotSection, Scenario};
use crate::config::ConfigError;

/// Where the whole-body task lists come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum WbcPreset {
    /// `stride_wbc::presets::walking_ik` / `walking_tsid` built from `robot.left_sole`, `robot.right_sole`,
    /// `robot.torso_frame`, `robot.base_frame`, `robot.initial_joint_positions` and `[wbc.walking]`; each
    /// entry of `wbc.ik.tasks` / `wbc.tsid.tasks` replaces the preset's task of the same name, or is added.
    #[default]
    Walking,
    /// No preset: `wbc.ik.tasks` and `wbc.tsid.tasks` are the whole lists.
    None,
}

/// `[wbc.walking]`: what the walking preset takes besides the robot section's frames and posture.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WalkingSection {
    /// Weights of the posture task by joint name or glob (`*`, `?`), resolved against the model; joints
    /// matched by none: 1. A glob that matches no joint is ignored (the default's names fit many robots).
    pub posture_joint_weights: BTreeMap<String, f64>,
    /// `reference_offset` of the torso and pelvis orientation tasks: `none` (the frames are x forward,
    /// z up when upright) or `initial` (they keep their initial orientation relative to the upright
    /// reference).
    pub upright_offset: ReferenceOffset,
    /// CoP region of the TSID contacts along the sole's x \[m\].
    pub cop_x: [f64; 2],
    /// CoP region of the TSID contacts along the sole's y \[m\].
    pub cop_y: [f64; 2],
    /// Names of preset tasks the QP-IK leaves out.
    pub ik_without: Vec<String>,
    /// Names of preset tasks the TSID leaves out.
    pub tsid_without: Vec<String>,
}

/// Default posture weights of the walking preset: 2 on every shoulder, elbow and wrist joint (the bundled
/// humanoid's arm weight, `stride_wbc::presets::BUNDLED_ARM_POSTURE_WEIGHT`).
pub fn default_posture_joint_weights() -> BTreeMap<String, f64> {
    ["*shoulder*", "*elbow*", "*wrist*"]
        .into_iter()
        .map(|g| {
            (
                g.to_string(),
                stride_wbc::presets::BUNDLED_ARM_POSTURE_WEIGHT,
            )
        })
        .collect()
}

impl Default for WalkingSection {
    fn default() -> Self {
        Self {
            posture_joint_weights: default_posture_joint_weights(),
            upright_offset: ReferenceOffset::None,
            cop_x: stride_wbc::BUNDLED_COP_X,
            cop_y: stride_wbc::BUNDLED_COP_Y,
            ik_without: Vec::new(),
            tsid_without: Vec::new(),
        }
    }
}

/// `[wbc]`: the whole-body controllers; `ik` is used in position mode, `tsid` in torque mode. Their
/// period is `1 / rates.wbc_hz`, given to their constructors by the runner.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct WbcSection {
    /// Where the task lists come from.
    pub preset: WbcPreset,
    /// The walking preset's parameters.
    pub walking: WalkingSection,
    /// Kinematic QP-IK (`stride_wbc::IkConfig`); with a preset, `tasks` are overrides.
    pub ik: IkConfig,
    /// TSID (`stride_wbc::TsidConfig`); with a preset, `tasks` are overrides.
    pub tsid: TsidConfig,
    /// The position set-point between two QP-IK ticks: `interpolate` (the IK's joint trajectory at every
    /// plant step) or `hold` (its command held over the period). See `crate::position_command`.
    pub position_command: crate::position_command::PositionCommand,
}

impl Default for WbcSection {
    fn default() -> Self {
        Self {
            preset: WbcPreset::Walking,
            walking: WalkingSection::default(),
            ik: empty_ik(),
            tsid: empty_tsid(),
            position_command: crate::position_command::PositionCommand::default(),
        }
    }
}

/// `wbc.ik`'s default: the preset's settings with no override.
pub fn empty_ik() -> IkConfig {
    IkConfig {
        tasks: Vec::new(),
        ..IkConfig::default_for_bundled_model()
    }
}

/// `wbc.tsid`'s default: the preset's settings with no override.
pub fn empty_tsid() -> TsidConfig {
    TsidConfig {
        tasks: Vec::new(),
        ..TsidConfig::default_for_bundled_model()
    }
}

/// The walking preset's input for this robot: its frames (`robot.base_frame`, else the model's root
/// link), its initial posture and `[wbc.walking]`, the posture weights' globs matched against the model's
/// joints (the last matching glob in name order wins).
pub fn walking_preset(
    robot: &RobotSection,
    walking: &WalkingSection,
    model: &Model,
) -> WalkingPreset {
    let base = robot
        .base_frame
        .clone()
        .unwrap_or_else(|| model.root_link().to_string());
    let frames = WalkingFrames::new(
        robot.left_sole.name(),
        robot.right_sole.name(),
        &robot.torso_frame,
        &base,
    );
    let mut weights = BTreeMap::new();
    for joint in model.joints() {
        for (glob, w) in &walking.posture_joint_weights {
            if glob_matches(glob, &joint.name) {
                weights.insert(joint.name.clone(), *w);
            }
        }
    }
    WalkingPreset {
        posture_joint_weights: weights,
        upright_offset: walking.upright_offset,
        cop_x: walking.cop_x,
        cop_y: walking.cop_y,
        ..WalkingPreset::new(frames, robot.initial_joint_positions.clone())
    }
}

impl Scenario {
    /// The QP-IK configuration the run uses: the preset with the overrides of `wbc.ik.tasks`, or the
    /// written list (`wbc.preset = "none"`).
    ///
    /// # Errors
    /// A name in `wbc.walking.ik_without` that is no preset task.
    pub fn ik_config(&self, model: &Model) -> Result<IkConfig, ConfigError> {
        let c = &self.config;
        let written = &c.wbc.ik;
        if c.wbc.preset == WbcPreset::None {
            return Ok(written.clone());
        }
        let preset = walking_ik(&walking_preset(&c.robot, &c.wbc.walking, model));
        let tasks = self.overridden(preset.tasks, &written.tasks, "ik")?;
        Ok(IkConfig {
            tasks,
            ..written.clone()
        })
    }

    /// The TSID configuration the run uses (as [`Scenario::ik_config`]).
    ///
    /// # Errors
    /// A name in `wbc.walking.tsid_without` that is no preset task.
    pub fn tsid_config(&self, model: &Model) -> Result<TsidConfig, ConfigError> {
        let c = &self.config;
        let written = &c.wbc.tsid;
        if c.wbc.preset == WbcPreset::None {
            return Ok(written.clone());
        }
        let mut preset = walking_tsid(&walking_preset(&c.robot, &c.wbc.walking, model));
        if written.contact_model == ContactModel::Compliant {
            // The compliant QP keeps the CoM's single gain on the vertical row: with the rigid TSID's 100 / 20
            // `walk_soft_ground_compliant_torque` falls after 0.40 m instead of 0.83 m (docs/wbc.md, "The CoM
            // height").
            for t in &mut preset.tasks {
                if let TaskConfig::Com(com) = t {
                    com.kp_z = None;
                    com.kd_z = None;
                }
            }
        }
        let tasks = self.overridden(preset.tasks, &written.tasks, "tsid")?;
        Ok(TsidConfig {
            tasks,
            ..written.clone()
        })
    }

    /// The preset's `tasks` without `wbc.walking.<controller>_without`, then overridden by `written`.
    fn overridden(
        &self,
        mut tasks: Vec<TaskConfig>,
        written: &[TaskConfig],
        controller: &str,
    ) -> Result<Vec<TaskConfig>, ConfigError> {
        let w = &self.config.wbc.walking;
        let without = if controller == "ik" {
            &w.ik_without
        } else {
            &w.tsid_without
        };
        let unknown = stride_wbc::presets::without(&mut tasks, without);
        if let Some(name) = unknown.first() {
            return Err(self.invalid(
                &format!("wbc.walking.{controller}_without"),
                format!(
                    "`{name}` is no task of the walking preset; expected one of its task names"
                ),
            ));
        }
        with_overrides(&mut tasks, written);
        Ok(tasks)
    }
}
