//! `[mujoco]`: the MuJoCo plant's own contact and solver parameters (`stride_mujoco::MujocoConfig`, which
//! documents each one and why its default is MuJoCo's). Read only with `scenario.plant = "mujoco"` (or
//! `--plant mujoco`) in a build with the `mujoco` feature, and range-checked there (an out-of-range value is
//! a configuration error at its key); the rest of the plant is the `[sim]` section shared with stride-sim,
//! including the ground: without `solref` the contact's time constant and damping ratio are derived from
//! `sim.contact` ([`ground_solref`]), so both plants stand on the same floor.

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

/// Where a position or velocity servo's effort limit is applied on the MuJoCo plant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum MujocoServoSaturation {
    /// On the force the step applies, the damping implicit (stride-sim's rule).
    #[default]
    AppliedForce,
    /// MuJoCo's own clamp of the start-of-step force.
    StartOfStep,
}

/// `[mujoco]`: the fields of `stride_mujoco::MujocoConfig`, with its defaults (MuJoCo's own, a minimum
/// joint armature of 0.01 kg·m², and `solref` derived from the scenario's ground when not written).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MujocoSection {
    /// `solref`: contact time constant \[s\] (≥ 2 plant periods) and damping ratio (> 0); absent: the
    /// scenario's ground ([`ground_solref`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub solref: Option<[f64; 2]>,
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
    /// Where a position or velocity servo's effort limit is applied.
    pub servo_saturation: MujocoServoSaturation,
}

impl Default for MujocoSection {
    /// `stride_mujoco::MujocoConfig::default()` (a test of the `mujoco` build checks they agree).
    fn default() -> Self {
        Self {
            solref: None,
            solimp: [0.9, 0.95, 0.001, 0.5, 2.0],
            condim: 3,
            cone: MujocoCone::Pyramidal,
            impratio: 1.0,
            torsional_friction: 0.005,
            rolling_friction: 0.0001,
            min_armature: 0.01,
            joint_limits: true,
            servo_saturation: MujocoServoSaturation::AppliedForce,
        }
    }
}

/// Lowest damping ratio [`ground_solref`] returns (an undamped floor would need an infinite time constant).
pub const MIN_GROUND_DAMPING_RATIO: f64 = 0.01;

/// MuJoCo's contact `solref = [time constant (s), damping ratio]` for the floor stride-sim models with the
/// area densities `normal_stiffness` \[N/m³\] and `normal_damping` \[N·s/m³\] (`sim.contact`): the robot of
/// `mass` \[kg\] standing on soles of total area `sole_area` \[m²\] gets the same vertical mode on both
/// plants.
///
/// On stride-sim the soles carry the stiffness `K = k A` and the damping `C = b A` [Romualdi 2022, Lemma 1],
/// so the robot bounces at `ω = √(K/m)` with the damping ratio `ζ = C / (2√(K m))`. MuJoCo's soft contact
/// drives a violated constraint towards the mass-normalised reference `a = −(2/τ) v − 1/(τ ζ)² r` (impedance
/// at its plateau) [MuJoCo 3.17 documentation, "Solver parameters"]: frequency `1/(τ ζ)` and damping
/// ratio `ζ`. Equal modes: `τ = 1/(ω ζ)`. The time constant is raised to two plant periods (`period` \[s\]),
/// the floor MuJoCo itself clamps to, and `ζ` to [`MIN_GROUND_DAMPING_RATIO`]. The static sink is set by
/// `solimp`, not by this. The default floor under the 32.8 kg humanoid (k 3·10⁸, b 9.5·10⁵, two 0.20 × 0.09 m
/// soles): ω 574 rad/s, ζ 0.91, τ 1.9 ms, where MuJoCo's own default (τ 20 ms, ζ 1) is a floor 132× less
/// stiff (the former default, k 3·10⁷, b 3·10⁵: ω 181 rad/s, τ 6.1 ms).
pub fn ground_solref(
    normal_stiffness: f64,
    normal_damping: f64,
    sole_area: f64,
    mass: f64,
    period: f64,
) -> [f64; 2] {
    let stiffness = normal_stiffness * sole_area;
    let damping = normal_damping * sole_area;
    let omega = (stiffness / mass).sqrt();
    let zeta = (damping / (2.0 * (stiffness * mass).sqrt())).max(MIN_GROUND_DAMPING_RATIO);
    [(1.0 / (omega * zeta)).max(2.0 * period), zeta]
}

#[cfg(feature = "mujoco")]
impl MujocoSection {
    /// The plant's configuration; `ground` is the `solref` used when the section does not set one
    /// ([`ground_solref`]).
    pub fn plant_config(&self, ground: [f64; 2]) -> stride_mujoco::MujocoConfig {
        stride_mujoco::MujocoConfig {
            solref: self.solref.unwrap_or(ground),
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
            servo_saturation: match self.servo_saturation {
                MujocoServoSaturation::AppliedForce => stride_mujoco::ServoSaturation::AppliedForce,
                MujocoServoSaturation::StartOfStep => stride_mujoco::ServoSaturation::StartOfStep,
            },
        }
    }
}

#[cfg(all(test, feature = "mujoco"))]
mod tests {
    use super::*;

    #[test]
    fn the_section_defaults_are_the_plant_defaults() {
        let ground = stride_mujoco::MujocoConfig::default().solref;
        assert_eq!(
            MujocoSection::default().plant_config(ground),
            stride_mujoco::MujocoConfig::default()
        );
    }

    #[test]
    fn every_field_reaches_the_plant() {
        let s = MujocoSection {
            solref: Some([0.005, 0.9]),
            solimp: [0.8, 0.9, 0.002, 0.4, 3.0],
            condim: 4,
            cone: MujocoCone::Elliptic,
            impratio: 2.0,
            torsional_friction: 0.01,
            rolling_friction: 0.001,
            min_armature: 0.1,
            joint_limits: false,
            servo_saturation: MujocoServoSaturation::StartOfStep,
        };
        let c = s.plant_config([0.02, 1.0]);
        assert_eq!(
            (c.solref, c.solimp, c.condim, c.cone, c.impratio),
            (
                [0.005, 0.9],
                s.solimp,
                4,
                stride_mujoco::Cone::Elliptic,
                2.0
            )
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
        assert_eq!(
            c.servo_saturation,
            stride_mujoco::ServoSaturation::StartOfStep
        );
    }
}

#[cfg(test)]
mod ground_tests {
    use super::*;

    /// The reference acceleration MuJoCo builds from `solref` (impedance at its plateau), as a
    /// mass-normalised spring and damper: `(stiffness, damping)` in 1/s² and 1/s.
    fn mujoco_spring(solref: [f64; 2]) -> (f64, f64) {
        let [tau, zeta] = solref;
        (1.0 / (tau * zeta).powi(2), 2.0 / tau)
    }

    #[test]
    fn the_derived_contact_has_the_floors_frequency_and_damping_per_unit_mass() {
        for (k, b, area, mass) in [
            (3e7, 3e5, 0.036, 32.8),
            (8e5, 1e4, 0.036, 32.8),
            (2e6, 1e3, 0.0285, 33.0),
            (3e7, 3e5, 0.05, 95.0),
        ] {
            let solref = ground_solref(k, b, area, mass, 5e-4);
            let (stiffness, damping) = mujoco_spring(solref);
            assert!(
                (stiffness - k * area / mass).abs() < 1e-9 * stiffness,
                "{solref:?}"
            );
            assert!(
                (damping - b * area / mass).abs() < 1e-9 * damping,
                "{solref:?}"
            );
        }
    }

    #[test]
    fn the_default_floor_under_the_bundled_humanoid_is_a_two_millisecond_contact() {
        let ground = stride_sim::ContactConfig::default();
        let [tau, zeta] = ground_solref(
            ground.normal_stiffness,
            ground.normal_damping,
            2.0 * 0.20 * 0.09,
            32.8,
            5e-4,
        );
        assert!((tau - 1.918e-3).abs() < 0.001e-3, "{tau}");
        assert!((zeta - 0.9085).abs() < 1e-4, "{zeta}");
        // The former default floor (k 3·10⁷, b 3·10⁵): 6.1 ms.
        let [tau, zeta] = ground_solref(3e7, 3e5, 2.0 * 0.20 * 0.09, 32.8, 5e-4);
        assert!((tau - 6.07e-3).abs() < 0.01e-3, "{tau}");
        assert!((zeta - 0.907).abs() < 1e-3, "{zeta}");
    }

    #[test]
    fn a_floor_stiffer_than_two_plant_periods_allow_is_clamped_and_an_undamped_one_gets_the_least_damping(
    ) {
        let [tau, _] = ground_solref(1e12, 1e10, 0.036, 32.8, 5e-4);
        assert_eq!(tau, 1e-3);
        let [tau, zeta] = ground_solref(3e7, 0.0, 0.036, 32.8, 5e-4);
        assert_eq!(zeta, MIN_GROUND_DAMPING_RATIO);
        assert!(tau.is_finite() && tau > 0.1);
    }
}
