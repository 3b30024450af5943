//! A stance sole that spins about the vertical on the floor, told from the gyroscope and the kinematics.
//!
//! The invariant EKF's heading measurement says that a flat foot in contact does not turn ([Ramadoss 2021];
//! [`crate::ekf::InvariantEkf::update_foot`]): the estimated sole orientation `F̂` is held from touch-down, and
//! the base's heading follows whatever the leg kinematics say relative to it. When the sole does turn on the
//! floor (a creeping, low-friction contact), the whole estimate turns with it. The sole's heading as the
//! gyroscope and the kinematics see it, `ψ_seen = ψ_gyro + ψ(R̂ R_h) − ψ(R̂)` (`ψ_gyro` the base heading
//! integrated from the gyroscope alone, never corrected by the feet; `R_h` the sole's orientation in the IMU
//! frame from the encoders), moves with the sole and not with the corrections. [`SoleSpin`] compares it with
//! its value at touch-down: once it has moved by more than `threshold`, the sole is spinning until it lifts,
//! and every further change is handed to `F̂`, so that the gyroscope, not the sole, carries the heading
//! while the sole turns. The part before detection (at most `threshold`) is handed over at detection, and
//! the correction then pulls back what the base's heading took from it.

use stride_block::wrap_angle;

/// `a − b` wrapped to `(−π, π]` \[rad\].
fn angle_difference(a: f64, b: f64) -> f64 {
    wrap_angle(a - b)
}

/// The spin detector of one sole (see the module documentation). A sole is in one of three states: in
/// swing (no touch-down heading), in contact and still, in contact and spinning (latched until it lifts).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SoleSpin {
    /// Turn from touch-down past which the sole is spinning \[rad\]; 0 turns the detector off.
    threshold: f64,
    /// `ψ_seen` at touch-down \[rad\] (`None` in swing).
    touchdown: Option<f64>,
    /// The turn from touch-down already handed to the sole's estimated orientation \[rad\].
    handed: f64,
    spinning: bool,
}

impl SoleSpin {
    /// A detector in swing with the given threshold \[rad\] (0: off, [`Self::step`] always returns 0).
    pub fn new(threshold: f64) -> Self {
        Self {
            threshold,
            touchdown: None,
            handed: 0.0,
            spinning: false,
        }
    }

    /// The sole is in swing: the next [`Self::step`] is a touch-down.
    pub fn lift(&mut self) {
        self.touchdown = None;
        self.handed = 0.0;
        self.spinning = false;
    }

    /// Whether the sole has been found spinning since its touch-down.
    pub fn spinning(&self) -> bool {
        self.spinning
    }

    /// One tick of a sole in contact whose heading, as the gyroscope and the kinematics see it, is `seen`
    /// \[rad\]. Returns the heading change \[rad, about the world's vertical\] to apply to the sole's
    /// estimated orientation: 0 while the sole is still (and on the touch-down tick), the turn since the
    /// last tick once it spins, the whole turn since touch-down on the tick it is found spinning.
    pub fn step(&mut self, seen: f64) -> f64 {
        if self.threshold <= 0.0 {
            return 0.0;
        }
        let Some(touchdown) = self.touchdown else {
            self.touchdown = Some(seen);
            return 0.0;
        };
        let turn = angle_difference(seen, touchdown);
        self.spinning |= turn.abs() > self.threshold;
        if !self.spinning {
            return 0.0;
        }
        let change = turn - self.handed;
        self.handed = turn;
        change
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn a_still_sole_hands_nothing_over() {
        let mut s = SoleSpin::new(0.004);
        // Touch-down at 3.1 rad, then quantisation-sized wobble within the threshold.
        for seen in [3.1, 3.1015, 3.0985, 3.103, 3.097] {
            assert_eq!(s.step(seen), 0.0);
        }
        assert!(!s.spinning());
    }

    #[test]
    fn a_spinning_sole_hands_over_its_whole_turn_across_the_wrap() {
        let mut s = SoleSpin::new(0.004);
        let start = PI - 0.002;
        let mut handed = 0.0;
        // 0.5° per tick for 20 ticks, through +π.
        for k in 0..=20 {
            let seen = angle_difference(start + 0.5_f64.to_radians() * k as f64, 0.0);
            handed += s.step(seen);
        }
        assert!(s.spinning());
        assert!((handed - 10.0_f64.to_radians()).abs() < 1e-12, "{handed}");
        // Still latched when it stops turning; a lift forgets it.
        assert_eq!(
            s.step(angle_difference(start + 10.0_f64.to_radians(), 0.0)),
            0.0
        );
        assert!(s.spinning());
        s.lift();
        assert!(!s.spinning());
        assert_eq!(s.step(1.0), 0.0);
    }

    #[test]
    fn off_at_a_zero_threshold() {
        let mut s = SoleSpin::new(0.0);
        for seen in [0.0, 0.5, 1.0] {
            assert_eq!(s.step(seen), 0.0);
        }
        assert!(!s.spinning());
    }
}
