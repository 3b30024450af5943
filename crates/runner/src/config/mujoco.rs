//! `[mujoco]`: the MuJoCo plant's own contact and solver parameters (`stride_mujoco::MujocoConfig`, which
//! documents each one and why its default is MuJoCo's). Read only with `scenario.plant = "mujoco"` (or
//! `--plant mujoco`) in a build with the `mujoco` feature, and range-checked there (an out-of-range value is
//! a configuration error at its key); the rest of the plant is the `[sim]` section shared with stride-sim.

use serde::{Deserialize, Serialize};

/// Friction cone of MuJoCo's contact solver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum MujocoCone {
    /// MuJoCo's default: a pyramid with `2 (condim − 1)` edges.
    #[default]
    Pyramidal,
    /// The exact cone.
    Elliptic,
}

/// `[mujoco]`: the fields of `stride_mujoco::MujocoConfig`, with its defaults (MuJoCo's own, and a minimum
/// joint armature of 0.01 kg·m²).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MujocoSection {
    /// `solref`: contact time constant \[s\] (≥ 2 plant periods) and damping ratio (> 0).
    pub solref: [f64; 2],
    /// `solimp`: `[d0, d_width, width (m), midpoint, power]` of the contact impedance.
    pub solimp: [f64; 5],
    /// Contact dimensionality: 1, 3, 4 or 6.
    pub condim: i32,
    /// Friction cone.
    pub cone: MujocoCone,
    /// Ratio of frictional to normal constraint impedance (≥ 1).
    pub impratio: f64,
    /// Torsional friction \[m\] (`condim` ≥ 4).
    pub torsional_friction: f64,
    /// Rolling friction \[m\] (`condim` 6).
    pub rolling_friction: f64,
    /// Lower bound of every joint's armature \[kg·m²\].
    pub min_armature: f64,
    /// Enforce the URDF's joint position limits.
    pub joint_limits: bool,
}

impl Default for MujocoSection {
    /// `stride_mujoco::MujocoConfig::default()` (a test of the `mujoco` build checks they agree).
    fn default() -> Self {
        Self {
            solref: [0.02, 1.0],
            solimp: [0.9, 0.95, 0.001, 0.5, 2.0],
            condim: 3,
            cone: MujocoCone::Pyramidal,
            impratio: 1.0,
            torsional_friction: 0.005,
            rolling_friction: 0.0001,
            min_armature: 0.01,
            joint_limits: true,
        }
    }
}

#[cfg(feature = "mujoco")]
impl MujocoSection {
    /// The plant's configuration.
    pub fn plant_config(&self) -> stride_mujoco::MujocoConfig {
        stride_mujoco::MujocoConfig {
            solref: self.solref,
            solimp: self.solimp,
            condim: self.condim,
            cone: match self.cone {
                MujocoCone::Pyramidal => stride_mujoco::Cone::Pyramidal,
                MujocoCone::Elliptic => stride_mujoco::Cone::Elliptic,
            },
            impratio: self.impratio,
            torsional_friction: self.torsional_friction,
            rolling_friction: self.rolling_friction,
            min_armature: self.min_armature,
            joint_limits: self.joint_limits,
        }
    }
}

#[cfg(all(test, feature = "mujoco"))]
mod tests {
    use super::*;

    #[test]
    fn the_section_defaults_are_the_plant_defaults() {
        assert_eq!(
            MujocoSection::default().plant_config(),
            stride_mujoco::MujocoConfig::default()
        );
    }

    #[test]
    fn every_field_reaches_the_plant() {
        let s = MujocoSection {
            solref: [0.005, 0.9],
            solimp: [0.8, 0.9, 0.002, 0.4, 3.0],
            condim: 4,
            cone: MujocoCone::Elliptic,
            impratio: 2.0,
            torsional_friction: 0.01,
            rolling_friction: 0.001,
            min_armature: 0.1,
            joint_limits: false,
        };
        let c = s.plant_config();
        assert_eq!(
            (c.solref, c.solimp, c.condim, c.cone, c.impratio),
            (s.solref, s.solimp, 4, stride_mujoco::Cone::Elliptic, 2.0)
        );
        assert_eq!(
            (
                c.torsional_friction,
                c.rolling_friction,
                c.min_armature,
                c.joint_limits
            ),
            (0.01, 0.001, 0.1, false)
        );
    }
}
