//! The MuJoCo-specific parameters of the plant: contact and solver. Everything else (actuators, sensors,
//! pushes, ground, fall detection) is the scenario's `[sim]` section, shared with stride-sim.

/// Friction cone of MuJoCo's contact solver.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cone {
    /// MuJoCo's default: a pyramid with `2 (condim − 1)` edges.
    Pyramidal,
    /// The exact cone (pair it with `impratio` > 1 to reduce slip).
    Elliptic,
}

/// How a position or velocity servo's effort limit is applied (`crate::limits`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ServoSaturation {
    /// On the force the step applies, the servo's damping implicit, as stride-sim decides it (default).
    AppliedForce,
    /// MuJoCo's own `forcerange` clamp of the start-of-step force: a clamped servo's damping is explicit
    /// and flips the torque between its limits at every step on a light link (kept to show that).
    StartOfStep,
}

/// Contact and solver parameters of the floor–sole contacts. The floor geom carries them with a higher
/// `priority` than the robot's geoms, so MuJoCo uses them as written for every contact (no mixing)
/// [MuJoCo 3.17 documentation, "Contact parameters"].
///
/// | field | unit | default | meaning |
/// |---|---|---|---|
/// | `solref` | s, – | `[0.02, 1]` | MuJoCo's default (time constant, damping ratio) of the contact constraint; the time constant must be ≥ 2 timesteps (it is 40 steps at 2 kHz) |
/// | `solimp` | –, –, m, –, – | `[0.9, 0.95, 0.001, 0.5, 2]` | MuJoCo's default impedance (`d0`, `d_width`, `width`, `midpoint`, `power`) |
/// | `condim` | – | 3 | MuJoCo's default: normal and two-dimensional sliding friction; a sole box touches at its four corners, which resists yaw |
/// | `cone` | – | `pyramidal` | MuJoCo's default |
/// | `impratio` | – | 1 | MuJoCo's default ratio of frictional to normal impedance |
/// | `torsional_friction`, `rolling_friction` | m | 0.005, 0.0001 | MuJoCo's defaults (used with `condim` 4 and 6) |
/// | `min_armature` | kg·m² | 0.01 | lower bound of every joint's armature (reflected rotor inertia); see below |
/// | `joint_limits` | – | true | MuJoCo enforces the URDF's joint position limits (stride-sim does not) |
/// | `servo_saturation` | – | `applied_force` | [`ServoSaturation`]: where a servo's effort limit is applied |
///
/// **Why a minimum armature.** MuJoCo integrates the servos' velocity gain implicitly (`implicitfast`) but
/// its constraint solver computes the contact forces with the plain mass matrix, so a damping `kd dt` much
/// larger than a joint's own inertia makes the two inconsistent. Measured on the bundled humanoid standing
/// in its crouch with the position-control servos of the scenarios (kp 10000 N·m/rad, kd 200 N·m·s/rad,
/// 2 kHz, constant command, no armature): a 4 Hz fore-aft rocking that does not decay, ±5 mm at the base,
/// with both feet nearly leaving the ground (Σ f_z down to 4 N); kd 20 or kp 1000 / kd 60 settle; the
/// Euler and RK4 integrators diverge (explicit damping). With 0.01 kg·m² on every joint it settles within
/// 1 s (Σ f_z = m g). Real actuators have more: a rotor of 1e-5 kg·m² behind a 100:1 harmonic drive
/// reflects 0.1 kg·m², and MuJoCo Menagerie's humanoids carry 0.01–0.1 kg·m². stride-sim's implicit
/// scheme needs none (it solves servos and contacts in one linear system).
/// The sliding friction coefficient is the scenario's `sim.contact.friction_coefficient`.
#[derive(Clone, Debug, PartialEq)]
pub struct MujocoConfig {
    /// `solref`: time constant \[s\] and damping ratio.
    pub solref: [f64; 2],
    /// `solimp`: `[d0, d_width, width (m), midpoint, power]`.
    pub solimp: [f64; 5],
    /// Contact dimensionality: 1, 3, 4 or 6.
    pub condim: i32,
    /// Friction cone.
    pub cone: Cone,
    /// Ratio of frictional to normal constraint impedance (≥ 1 with the elliptic cone).
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
    pub servo_saturation: ServoSaturation,
}

impl Default for MujocoConfig {
    fn default() -> Self {
        Self {
            solref: [0.02, 1.0],
            solimp: [0.9, 0.95, 0.001, 0.5, 2.0],
            condim: 3,
            cone: Cone::Pyramidal,
            impratio: 1.0,
            torsional_friction: 0.005,
            rolling_friction: 0.0001,
            min_armature: 0.01,
            joint_limits: true,
            servo_saturation: ServoSaturation::AppliedForce,
        }
    }
}

impl MujocoConfig {
    /// Range checks; `period` is the plant timestep \[s\].
    pub fn validate(&self, period: f64) -> Result<(), crate::MujocoError> {
        let bad = |parameter: &str, value: String, reason: &str| {
            Err(crate::MujocoError::InvalidConfig {
                parameter: parameter.into(),
                value,
                reason: reason.into(),
            })
        };
        if !(self.solref[0].is_finite() && self.solref[0] >= 2.0 * period) {
            return bad(
                "solref[0]",
                self.solref[0].to_string(),
                "expected a time constant ≥ 2 timesteps [s] (MuJoCo clamps it otherwise)",
            );
        }
        if !(self.solref[1].is_finite() && self.solref[1] > 0.0) {
            return bad(
                "solref[1]",
                self.solref[1].to_string(),
                "expected a damping ratio > 0",
            );
        }
        let [d0, dw, width, mid, power] = self.solimp;
        let impedance_ok = (0.0..1.0).contains(&d0) && (0.0..1.0).contains(&dw);
        if !(impedance_ok && width > 0.0 && (0.0..=1.0).contains(&mid) && power >= 1.0) {
            return bad(
                "solimp",
                format!("{:?}", self.solimp),
                "expected 0 ≤ d0, d_width < 1, width > 0 m, 0 ≤ midpoint ≤ 1, power ≥ 1",
            );
        }
        if ![1, 3, 4, 6].contains(&self.condim) {
            return bad("condim", self.condim.to_string(), "expected 1, 3, 4 or 6");
        }
        if !(self.impratio.is_finite() && self.impratio >= 1.0) {
            return bad(
                "impratio",
                self.impratio.to_string(),
                "expected a finite ratio ≥ 1",
            );
        }
        for (name, v) in [
            ("torsional_friction", self.torsional_friction),
            ("rolling_friction", self.rolling_friction),
            ("min_armature", self.min_armature),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(
                    name,
                    v.to_string(),
                    "expected a finite value ≥ 0 [m or kg·m²]",
                );
            }
        }
        Ok(())
    }
}
