//! Gait figures of a run (issue 15): the steady forward speed and the specific energetic cost, accumulated
//! every plant period from the plant's truth without allocating (the touch-down list is pre-sized).
//!
//! **Steady forward speed.** Touch-downs are the instants a foot's contact flag rises after the foot was off
//! the ground for at least [`MIN_SWING_TIME`] (shorter gaps are contact chatter, not steps). The forward
//! progress is `F(t) = ∫ h(t)ᵀ dp`, `p` the base position (x, y) and `h` the unit heading: the soles' mean
//! yaw, measured at the last layer tick (not the base yaw: the pelvis yaws with the steps, and a base
//! frame's x may point backwards, as iCub's `root_link`). The steady forward speed is the mean forward base
//! speed from the third touch-down to the third before the last, `(F(t_b) − F(t_a)) / (t_b − t_a)`; with
//! fewer than 7 touch-downs it is not available.
//!
//! **Specific energetic cost** `c_et = E / (m D)` [Romualdi 2022, eq. 7.3.1] [Torricelli 2015]: `E` the
//! positive mechanical work of the actuators `Σ_k Σ_j max(τ_j q̇_j, 0) Δt` (`τ` the motor torques the plant
//! applied during the period, after saturation, `q̇` the joint velocities at its end, `Δt` the plant
//! period), `m` the plant model's mass, `D` the planar distance of the soles' mid-point from its start
//! ([`crate::summary::RunSummary::distance`]); not available below [`MIN_COST_DISTANCE`].

use nalgebra::Vector2;
use serde::Serialize;

use crate::robot::PlantTruth;

/// A foot must be off the ground this long \[s\] before its next contact counts as a touch-down.
pub const MIN_SWING_TIME: f64 = 0.1;

/// Touch-downs skipped at each end of the walk for the steady speed: from the third to the third before
/// the last.
pub const STEADY_SKIP: usize = 3;

/// Shortest distance \[m\] for which the energetic cost is given.
pub const MIN_COST_DISTANCE: f64 = 0.1;

/// The gait figures of the summary.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct GaitFigures {
    /// Touch-downs detected.
    pub touchdowns: usize,
    /// Steady forward speed \[m/s\] (`None`: fewer than 7 touch-downs).
    pub steady_speed: Option<f64>,
    /// The window of the steady speed: the third touch-down and the third before the last \[s\].
    pub steady_window: Option<[f64; 2]>,
    /// Positive mechanical work of the actuators `E` \[J\].
    pub positive_work: f64,
    /// Robot mass `m` \[kg\].
    pub mass: f64,
    /// Specific energetic cost `c_et = E / (m D)` \[J/(kg m)\] (`None` below [`MIN_COST_DISTANCE`]).
    pub energy_cost: Option<f64>,
}

/// Positive actuator power `Σ_j max(τ_j q̇_j, 0)` \[W\] of torques `tau` \[N m\] and velocities `qd` \[rad/s\].
pub fn positive_power(tau: &[f64], qd: &[f64]) -> f64 {
    tau.iter().zip(qd).map(|(t, v)| (t * v).max(0.0)).sum()
}

/// The steady forward speed \[m/s\] and its window from touch-downs `(time [s], forward progress [m])` in
/// time order (see the module documentation).
pub fn steady_speed(touchdowns: &[(f64, f64)]) -> Option<(f64, [f64; 2])> {
    let n = touchdowns.len();
    if n < 2 * STEADY_SKIP + 1 {
        return None;
    }
    let (ta, fa) = touchdowns[STEADY_SKIP - 1];
    let (tb, fb) = touchdowns[n - 1 - STEADY_SKIP];
    (tb > ta).then(|| ((fb - fa) / (tb - ta), [ta, tb]))
}

/// The running gait figures.
pub(crate) struct GaitTracker {
    work: f64,
    progress: f64,
    last_base: Vector2<f64>,
    in_contact: [bool; 2],
    /// Lift-off time of each foot \[s\] (`None` while in contact or before its first lift-off).
    lifted_at: [Option<f64>; 2],
    touchdowns: Vec<(f64, f64)>,
    mass: f64,
}

impl GaitTracker {
    /// Starts at the plant's initial truth, with the robot's `mass` \[kg\] and room for the touch-downs of
    /// `duration` \[s\].
    pub(crate) fn new(truth: &PlantTruth, mass: f64, duration: f64) -> Self {
        let base = &truth.state.base_pose;
        let per_foot = (duration.max(0.0) / MIN_SWING_TIME).ceil() as usize + 1;
        Self {
            work: 0.0,
            progress: 0.0,
            last_base: base.translation.vector.xy(),
            in_contact: truth.feet_in_contact,
            lifted_at: [None; 2],
            touchdowns: Vec::with_capacity(2 * per_foot),
            mass,
        }
    }

    /// After a plant period of `dt` \[s\] ending at `time` \[s\] with the truth `truth`, the robot heading
    /// `heading` \[rad\] (the soles' mean yaw).
    pub(crate) fn add(&mut self, time: f64, dt: f64, truth: &PlantTruth, heading: f64) {
        let s = &truth.state;
        self.work += dt
            * positive_power(
                truth.joint_torques.as_slice(),
                s.joint_velocities.as_slice(),
            );
        let base = s.base_pose.translation.vector.xy();
        self.progress += (base - self.last_base).dot(&Vector2::new(heading.cos(), heading.sin()));
        self.last_base = base;
        for k in 0..2 {
            let now = truth.feet_in_contact[k];
            match (self.in_contact[k], now) {
                (true, false) => self.lifted_at[k] = Some(time),
                (false, true) => {
                    let swung = self.lifted_at[k].is_some_and(|t0| time - t0 >= MIN_SWING_TIME);
                    // Pre-sized for the most touch-downs the duration allows: pushing never allocates.
                    if swung && self.touchdowns.len() < self.touchdowns.capacity() {
                        self.touchdowns.push((time, self.progress));
                    }
                }
                _ => {}
            }
            self.in_contact[k] = now;
        }
    }

    /// The figures, with the distance walked `distance` \[m\].
    pub(crate) fn finish(&self, distance: f64) -> GaitFigures {
        let steady = steady_speed(&self.touchdowns);
        GaitFigures {
            touchdowns: self.touchdowns.len(),
            steady_speed: steady.map(|s| s.0),
            steady_window: steady.map(|s| s.1),
            positive_work: self.work,
            mass: self.mass,
            energy_cost: (distance >= MIN_COST_DISTANCE && self.mass > 0.0)
                .then(|| self.work / (self.mass * distance)),
        }
    }
}

impl GaitFigures {
    /// The gait line of the summary.
    pub fn render(&self, s: &mut String) {
        use std::fmt::Write as _;
        let speed = match (self.steady_speed, self.steady_window) {
            (Some(v), Some([a, b])) => format!(
                "{v:.3} m/s (touch-downs 3 to {} of {}, {a:.2}–{b:.2} s)",
                self.touchdowns - STEADY_SKIP,
                self.touchdowns
            ),
            _ => format!("n/a ({} touch-downs, needs 7)", self.touchdowns),
        };
        let cost = match self.energy_cost {
            Some(c) => format!("{c:.2} J/kg/m"),
            None => format!("n/a (walked under {MIN_COST_DISTANCE} m)"),
        };
        let _ = writeln!(
            s,
            "  steady forward speed {speed}; energetic cost c_et {cost} (positive actuator work {:.1} J, \
             mass {:.2} kg)",
            self.positive_work, self.mass
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DVector, Isometry3, Translation3, UnitQuaternion, Vector6};
    use stride_model::RobotState;

    fn truth(n: usize) -> PlantTruth {
        PlantTruth {
            state: RobotState {
                base_pose: Isometry3::identity(),
                joint_positions: DVector::zeros(n),
                base_velocity: Vector6::zeros(),
                joint_velocities: DVector::zeros(n),
            },
            joint_torques: DVector::zeros(n),
            saturated: vec![false; n],
            foot_wrenches: [Vector6::zeros(); 2],
            feet_in_contact: [true, true],
        }
    }

    /// Standing still: large torques, zero joint velocities, no positive work, so c_et = 0 (sanity).
    #[test]
    fn standing_still_costs_nothing() {
        let mut t = truth(3);
        t.joint_torques = DVector::from_vec(vec![30.0, -12.0, 5.0]);
        let mut g = GaitTracker::new(&t, 30.0, 2.0);
        for k in 1..=2000 {
            g.add(k as f64 * 1e-3, 1e-3, &t, 0.0);
        }
        let f = g.finish(1.0);
        assert_eq!(f.positive_work, 0.0);
        assert_eq!(f.energy_cost, Some(0.0));
        assert_eq!(f.touchdowns, 0);
        assert_eq!(f.steady_speed, None);
        assert_eq!(g.finish(0.05).energy_cost, None);
    }

    /// Constant power: joint 0 does 2 N m × 3 rad/s = 6 W of positive work, joint 1 absorbs 4 W (not counted);
    /// over 2 s E = 12 J, c_et = 12 / (30 kg × 1.5 m).
    #[test]
    fn only_positive_power_is_work() {
        let mut t = truth(2);
        t.joint_torques = DVector::from_vec(vec![2.0, -2.0]);
        t.state.joint_velocities = DVector::from_vec(vec![3.0, 2.0]);
        let mut g = GaitTracker::new(&t, 30.0, 2.0);
        for k in 1..=2000 {
            g.add(k as f64 * 1e-3, 1e-3, &t, 0.0);
        }
        let f = g.finish(1.5);
        assert!((f.positive_work - 12.0).abs() < 1e-9, "{}", f.positive_work);
        assert!((f.energy_cost.unwrap() - 12.0 / 45.0).abs() < 1e-12);
    }

    /// Base moving at 0.2 m/s along +y with the soles' heading at +90° (the base yawed away by 30°: not
    /// counted), feet alternating with 0.25 s swings (a 1 ms contact chatter in each): touch-downs every
    /// 0.3 s, steady speed 0.2 m/s.
    #[test]
    fn steady_speed_of_a_uniform_walk_along_the_heading() {
        let mut t = truth(1);
        let yaw = std::f64::consts::FRAC_PI_2;
        let rotation = UnitQuaternion::from_euler_angles(0.0, 0.0, yaw + 0.5);
        t.state.base_pose = Isometry3::from_parts(Translation3::identity(), rotation);
        let mut g = GaitTracker::new(&t, 30.0, 6.0);
        let dt = 1e-3;
        for k in 1..=6000 {
            let time = k as f64 * dt;
            t.state.base_pose.translation = Translation3::new(0.0, 0.2 * time, 0.0);
            // Foot k % 2 swings in [0.3 j, 0.3 j + 0.25) for step j; the other stands.
            let step = (time / 0.3).floor() as usize;
            let phase = time - 0.3 * step as f64;
            let swinging = phase < 0.25;
            t.feet_in_contact = [true, true];
            t.feet_in_contact[step % 2] = !swinging;
            if (phase - 0.05).abs() < 0.5 * dt {
                t.feet_in_contact[step % 2] = true; // chatter: not a touch-down
            }
            g.add(time, dt, &t, yaw);
        }
        let f = g.finish(1.2);
        assert!(f.touchdowns >= 18, "{}", f.touchdowns);
        let v = f.steady_speed.unwrap();
        assert!((v - 0.2).abs() < 1e-9, "{v}");
        let [a, b] = f.steady_window.unwrap();
        assert!((a - (0.3 * 2.0 + 0.25)).abs() < 1.5 * dt, "{a}");
        assert!(b > a + 3.0, "{b}");
    }

    #[test]
    fn steady_speed_needs_seven_touchdowns() {
        let td: Vec<(f64, f64)> = (0..6).map(|k| (k as f64, 0.1 * k as f64)).collect();
        assert_eq!(steady_speed(&td), None);
        let td: Vec<(f64, f64)> = (0..7).map(|k| (k as f64, 0.1 * k as f64)).collect();
        let (v, w) = steady_speed(&td).unwrap();
        assert!((v - 0.1).abs() < 1e-12);
        assert_eq!(w, [2.0, 3.0]);
    }
}
