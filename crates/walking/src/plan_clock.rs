//! The plan's clock: plan time that can slow to a stop and resume, to hold a gait phase (the double
//! support under a push) without rebuilding the plan.
//!
//! Plan time advances at a rate `s ∈ [0, 1]` of the controller's time, `t_plan = t − d` with the delay
//! `d = ∫ (1 − s) dt`. The rate moves linearly towards its target (1 running, 0 holding) in `ramp`
//! seconds for the full range, so plan time stays continuous and its rate does too. A sample of the plan
//! taken at `t_plan` is the time-scaled trajectory once its derivatives are scaled by the chain rule
//! ([`scale_plan_sample`]): velocities by `s`, accelerations by `s²` (the `ṡ` term, `ṡ v`, is left out:
//! `|ṡ| ≤ 1/ramp` lasts one ramp).
//!
//! While the rate is 1 the delay is exactly zero and [`PlanClock::plan_time`] returns its argument: a
//! stack that never holds runs bit for bit as without the clock.

use std::time::Duration;

use stride_planner::PlanSample;

/// Plan time with a rate that ramps between 1 and 0; no allocation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanClock {
    ramp: f64,
    rate: f64,
    target: f64,
    /// `∫ (1 − s) dt` \[s\].
    delay: f64,
    last: Duration,
}

impl PlanClock {
    /// A running clock (rate 1, no delay) whose rate takes `ramp` \[s, > 0\] to go from 1 to 0.
    pub fn new(ramp: f64) -> Self {
        Self {
            ramp: ramp.max(f64::MIN_POSITIVE),
            rate: 1.0,
            target: 1.0,
            delay: 0.0,
            last: Duration::ZERO,
        }
    }

    /// Holds (rate towards 0) or runs (rate towards 1) from now on.
    pub fn hold(&mut self, hold: bool) {
        self.target = if hold { 0.0 } else { 1.0 };
    }

    /// Whether the clock is told to hold.
    pub fn holding(&self) -> bool {
        self.target == 0.0
    }

    /// The rate `s` at the last [`PlanClock::plan_time`] call.
    pub fn rate(&self) -> f64 {
        self.rate
    }

    /// The delay `t − t_plan` \[s\] at the last [`PlanClock::plan_time`] call.
    pub fn delay(&self) -> f64 {
        self.delay
    }

    /// Advances the clock to `time` (earlier times do not move it) and returns the plan time there:
    /// the rate's linear ramp is integrated exactly.
    pub fn plan_time(&mut self, time: Duration) -> Duration {
        if time > self.last {
            let dt = (time - self.last).as_secs_f64();
            let slope = 1.0 / self.ramp;
            let ramp_time = ((self.target - self.rate).abs() / slope).min(dt);
            let rate_end = self.rate + (self.target - self.rate).signum() * slope * ramp_time;
            // ∫(1 − s): trapezoid over the ramp, then constant at the target
            self.delay += ramp_time * (1.0 - 0.5 * (self.rate + rate_end))
                + (dt - ramp_time) * (1.0 - rate_end);
            self.rate = if ramp_time < dt {
                self.target
            } else {
                rate_end
            };
            self.last = time;
        }
        if self.delay <= 0.0 {
            return time;
        }
        time.saturating_sub(Duration::from_secs_f64(self.delay))
    }
}

/// Scales the derivatives of a plan sample taken at a plan time running at `rate` (see the module
/// documentation): DCM, CoM and feet velocities by `rate`, CoM and feet accelerations by `rate²`, and the
/// ZMP recomputed as `ξ − rate ξ̇/ω` (the LIPM's `p = ξ − ξ̇/ω` of the scaled trajectory). A rate of 1
/// leaves the sample untouched.
pub fn scale_plan_sample(sample: &mut PlanSample, rate: f64) {
    if rate == 1.0 {
        return;
    }
    let r2 = rate * rate;
    if sample.omega > 0.0 {
        let shift = sample.dcm_velocity.xy() * ((1.0 - rate) / sample.omega);
        sample.zmp.x += shift.x;
        sample.zmp.y += shift.y;
    }
    sample.dcm_velocity *= rate;
    sample.com_velocity *= rate;
    sample.com_acceleration *= r2;
    for foot in [&mut sample.left, &mut sample.right] {
        foot.twist *= rate;
        foot.acceleration *= r2;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn ms(n: u64) -> Duration {
        Duration::from_millis(n)
    }

    #[test]
    fn a_running_clock_is_the_identity() {
        let mut c = PlanClock::new(0.1);
        for k in 0..1000 {
            let t = Duration::from_nanos(k * 1_234_567);
            assert_eq!(c.plan_time(t), t);
        }
        assert_eq!(c.delay(), 0.0);
    }

    /// Held at 1 s with a 0.1 s ramp, released at 2 s: the rate falls linearly to 0 in 0.1 s (plan time
    /// gains 0.05 s over the ramp), stays 0 until 2 s, rises in 0.1 s; the delay is the area above the
    /// rate curve, 0.05 + 0.9 + 0.05 = 1.0 s: `t_plan(3 s) = 2 s`.
    #[test]
    fn a_hold_delays_plan_time_by_the_area_above_the_rate() {
        let mut c = PlanClock::new(0.1);
        assert_eq!(c.plan_time(ms(1000)), ms(1000));
        c.hold(true);
        let t = c.plan_time(ms(1050));
        assert!((t.as_secs_f64() - (1.05 - 0.5 * 0.05 * 0.5)).abs() < 1e-12);
        assert!((c.rate() - 0.5).abs() < 1e-12);
        let frozen = c.plan_time(ms(1500));
        assert!((frozen.as_secs_f64() - 1.05).abs() < 1e-9, "{frozen:?}");
        assert_eq!(c.rate(), 0.0);
        assert_eq!(
            c.plan_time(ms(2000)),
            frozen,
            "held: plan time stands still"
        );
        c.hold(false);
        let t = c.plan_time(ms(3000));
        assert!((t.as_secs_f64() - 2.0).abs() < 1e-9, "{t:?}");
        assert_eq!(c.rate(), 1.0);
        // fine and coarse steps integrate the same ramp
        let mut fine = PlanClock::new(0.1);
        fine.plan_time(ms(1000));
        fine.hold(true);
        for k in 1001..=1500 {
            fine.plan_time(ms(k));
        }
        assert!((fine.delay() - 0.45).abs() < 1e-9);
    }

    #[test]
    fn scaling_a_sample_scales_its_derivatives_and_keeps_the_lipm_zmp() {
        let mut s = PlanSample {
            omega: 4.0,
            dcm_position: Vector3::new(0.1, 0.02, 0.5),
            dcm_velocity: Vector3::new(0.2, -0.4, 0.0),
            com_velocity: Vector3::new(0.1, 0.3, 0.0),
            com_acceleration: Vector3::new(1.0, 2.0, 0.0),
            ..PlanSample::default()
        };
        s.zmp = s.dcm_position - s.dcm_velocity / 4.0;
        s.zmp.z = 0.0;
        let unscaled = s;
        scale_plan_sample(&mut s, 1.0);
        assert_eq!(s, unscaled);
        scale_plan_sample(&mut s, 0.0);
        assert_eq!(s.dcm_velocity, Vector3::zeros());
        assert_eq!(s.com_acceleration, Vector3::zeros());
        assert!(
            (s.zmp.xy() - s.dcm_position.xy()).norm() < 1e-15,
            "frozen: p = ξ"
        );
        let mut h = unscaled;
        scale_plan_sample(&mut h, 0.5);
        assert!((h.zmp.xy() - (h.dcm_position.xy() - h.dcm_velocity.xy() / 4.0)).norm() < 1e-15);
        assert!((h.com_acceleration - unscaled.com_acceleration * 0.25).norm() < 1e-15);
    }
}
