//! The runner's response to a push (`[simplified.push] enabled = true`, issue 13): the momentum
//! observer's estimate of the horizontal external force ([`stride_simplified::PushObserver`]) at every
//! simplified tick, the double-support hold it drives (the plan's clock, [`stride_walking::PlanClock`],
//! slows to a stop while the estimate exceeds `hold_force` in a double support of a walk, for at most
//! `max_hold` per double support) and the push-aware step adjustment (the effective ZMP
//! `p − F̂/(m ω²)` given to the step-adjustment QP as its stance CoP).

use nalgebra::{Vector2, Vector3};
use stride_block::SupportPolygon;
use stride_planner::{Phase, PhaseKind, Plan, PlanSample};
use stride_simplified::{push_zmp_offset, PushConfig, PushObserver, SimplifiedError};
use stride_walking::PlanClock;

/// The push estimate and the hold decision; no allocation.
#[derive(Debug, Clone)]
pub struct PushResponse {
    config: PushConfig,
    observer: PushObserver,
    mass: f64,
    /// The horizontal estimate of the last tick \[N\].
    estimate: Vector2<f64>,
    /// How long the estimate has been above `hold_force` \[s\].
    pushed_for: f64,
    /// The clock's delay when the current double support began (`None` outside double support) \[s\].
    double_support_start: Option<f64>,
    /// Time since the last planned touch-down (the first tick of a double support; `None` before the
    /// first) \[s\].
    since_touch_down: Option<f64>,
    /// Whether the estimate's current rise above `hold_force` came within `impact_window` of a planned
    /// touch-down (then it must last `hold_delay` before a hold starts).
    near_impact: bool,
    /// How far the DCM with the push, `ξ + F̂/(m ω²)`, is outside the support polygon (the last
    /// [`PushResponse::capture`]; −∞ before the first) \[m\].
    outside: f64,
    /// Whether `step_out` ended the hold of the current double support (it is not held again).
    stepped_out: bool,
    /// Double supports held so far.
    pub holds: u64,
    /// Holds ended by `step_out` so far.
    pub step_outs: u64,
}

impl PushResponse {
    /// The response of `config` for a robot of `mass` \[kg\] under `gravity` \[m/s²\].
    pub fn new(
        config: &PushConfig,
        mass: f64,
        gravity: Vector3<f64>,
    ) -> Result<Self, SimplifiedError> {
        Ok(Self {
            config: *config,
            observer: PushObserver::new(config, mass, gravity)?,
            mass,
            estimate: Vector2::zeros(),
            pushed_for: 0.0,
            double_support_start: None,
            since_touch_down: None,
            near_impact: false,
            outside: f64::NEG_INFINITY,
            stepped_out: false,
            holds: 0,
            step_outs: 0,
        })
    }

    /// The horizontal push estimate of the last tick \[N\].
    pub fn estimate(&self) -> Vector2<f64> {
        self.estimate
    }

    /// One observer step of `dt` \[s\] (every whole-body tick: the contact forces change within a
    /// simplified period at a touch-down, and sampling them at 100 Hz aliases the impact into a ±20 N
    /// false push) from the measured CoM velocity and the contact forces. Errors: non-finite
    /// measurements (the estimate is kept).
    pub fn observe(
        &mut self,
        dt: f64,
        com_velocity: &Vector3<f64>,
        contact_force: &Vector3<f64>,
    ) -> Result<(), SimplifiedError> {
        self.estimate = self.observer.update(dt, com_velocity, contact_force)?;
        Ok(())
    }

    /// Notes where the measured DCM `dcm` \[m\] stands with the push for the next [`PushResponse::decide`]:
    /// the capture point of the pushed LIPM, `ξ + F̂/(m ω²)` (the DCM a CoP inside `support` can stop
    /// only if that point is inside it), and its distance outside `support` (half-plane test; ≤ 0
    /// inside). Returns that distance \[m\]. No allocation.
    pub fn capture(&mut self, dcm: Vector2<f64>, omega: f64, support: &SupportPolygon) -> f64 {
        self.outside = if omega > 0.0 {
            support.max_violation(dcm + push_zmp_offset(&self.estimate, self.mass, omega))
        } else {
            f64::NEG_INFINITY
        };
        self.outside
    }

    /// Tells `clock` to hold or run for the plan `sample` (taken at the clock's plan time) while
    /// `walking` (every simplified tick, `dt` \[s\] apart; `start_or_stop`: the sample is in the walk's
    /// first or last double support, [`in_start_or_stop`]). A hold starts in a double support once the
    /// estimate has stayed above `hold_force` for `hold_delay`, and lasts while it stays above, at most
    /// `max_hold`. With `hold_at_once` only an estimate that rose within `impact_window` of a planned
    /// touch-down (before or after it), or in the start-up or stopping double support, waits
    /// `hold_delay` (a touch-down's impact, and the torque walks' weight shift before the first lift-off
    /// and after the last touch-down, show in the observer as short pulses); any other rise holds at
    /// once. With `step_out`, a hold ends for the rest of the double support once the last
    /// [`PushResponse::capture`] is more than `step_out_margin` outside the support polygon (counted in
    /// `step_outs`): the clock runs on to the next lift-off and the step adjustment places that step.
    /// Returns whether a hold started.
    pub fn decide(
        &mut self,
        dt: f64,
        sample: &PlanSample,
        walking: bool,
        start_or_stop: bool,
        clock: &mut PlanClock,
    ) -> bool {
        let double_support = walking && sample.phase == PhaseKind::DoubleSupport;
        let touch_down = double_support && self.double_support_start.is_none();
        self.note_rise(dt, touch_down);
        if !double_support {
            self.double_support_start = None;
            self.stepped_out = false;
            clock.hold(false);
            return false;
        }
        let start = *self.double_support_start.get_or_insert(clock.delay());
        let pushed = self.pushed_for > 0.0;
        let delay = if self.config.hold_at_once && !self.near_impact && !start_or_stop {
            0.0
        } else {
            self.config.hold_delay
        };
        let persistent = self.pushed_for >= delay - 1e-9;
        let hold = self.config.hold_double_support
            && pushed
            && (clock.holding() || persistent)
            && clock.delay() - start < self.config.max_hold;
        if self.config.step_out
            && hold
            && !self.stepped_out
            && self.outside > self.config.step_out_margin
        {
            self.stepped_out = true;
            self.step_outs += 1;
        }
        let hold = hold && !self.stepped_out;
        let started = hold && !clock.holding();
        if started {
            self.holds += 1;
        }
        clock.hold(hold);
        started
    }

    /// Bookkeeping of one tick of `dt` \[s\] (`touch_down`: the first tick of a double support): how long
    /// the estimate has been above `hold_force`, the time since the last touch-down, and whether the
    /// current rise came within `impact_window` of a touch-down (a rise after it, or a rise at most
    /// `impact_window` before it, seen at the touch-down).
    fn note_rise(&mut self, dt: f64, touch_down: bool) {
        let pushed = self.estimate.norm() > self.config.hold_force;
        let rose = pushed && self.pushed_for == 0.0;
        self.pushed_for = if pushed { self.pushed_for + dt } else { 0.0 };
        self.since_touch_down = if touch_down {
            Some(0.0)
        } else {
            self.since_touch_down.map(|s| s + dt)
        };
        let window = self.config.impact_window + 1e-9;
        if rose {
            self.near_impact = self.since_touch_down.is_some_and(|s| s <= window);
        }
        if touch_down && pushed && self.pushed_for <= window + dt {
            self.near_impact = true;
        }
    }

    /// Moves the planned CoM and DCM of `sample` against the push by `lean F̂/(m ω²)` (the pushed
    /// LIPM `ẍ = ω² (x − p) + F/m` then keeps the plan's ZMP at the shifted CoM); the ZMP stays.
    pub fn lean(&self, sample: &mut PlanSample) {
        if self.config.lean == 0.0 || sample.omega <= 0.0 {
            return;
        }
        let shift = -push_zmp_offset(&self.estimate, self.mass, sample.omega) * self.config.lean;
        for p in [&mut sample.com_position, &mut sample.dcm_position] {
            p.x += shift.x;
            p.y += shift.y;
        }
    }

    /// The stance CoP the step-adjustment QP predicts the DCM with: the planned one moved by the push's
    /// LIPM offset, `p − F̂/(m ω²)` (unchanged when `step_adjustment` is off, while the estimate is not
    /// above `hold_force`, and with a positive `step_adjustment_delay` until it has stayed above that
    /// long: the observer's pulses of a touch-down or of a stance foot's roll last less,
    /// docs/push-recovery.md). Below `hold_force`: the unpushed fast walk's 3–6 N pulses at each
    /// lift-off, about 8 mm of CoP amplified ×15 early in the swing, moved its steps by 2–13 cm and
    /// back (docs/push-recovery.md, "Without pushes nothing gets worse").
    pub fn effective_cop(&self, planned: Vector2<f64>, omega: f64) -> Vector2<f64> {
        if !self.seen_by_step_adjustment(omega) {
            return planned;
        }
        planned - push_zmp_offset(&self.estimate, self.mass, omega)
    }

    /// The DCM a step adjustment refused from the plan's own DCM is replanned from with
    /// `replan_from_dcm`, once the estimate has stayed above `hold_force` for `hold_delay` (the
    /// observer's touch-down pulses last less: without this gate the unpushed `walk_fast` restarted its
    /// plan at them and ended 0.30 m from its goal, docs/push-recovery.md): the measured `dcm` moved by
    /// `replan_push_offset F̂/(m ω²)` (the pushed LIPM's capture point with 1). `None` otherwise (the
    /// plan's own DCM, continuous).
    pub fn replan_dcm(&self, dcm: Vector2<f64>, omega: f64) -> Option<Vector2<f64>> {
        let c = &self.config;
        let pushed = self.estimate.norm() > c.hold_force && self.pushed_for >= c.hold_delay - 1e-9;
        (c.replan_from_dcm && pushed && omega > 0.0)
            .then(|| dcm + push_zmp_offset(&self.estimate, self.mass, omega) * c.replan_push_offset)
    }

    /// Whether the step-adjustment QP reads the estimate this tick: `step_adjustment` on, the estimate
    /// above `hold_force`, and with a positive `step_adjustment_delay` once it has stayed above that long.
    fn seen_by_step_adjustment(&self, omega: f64) -> bool {
        let delay = self.config.step_adjustment_delay;
        let gated = self.pushed_for <= 0.0 || self.pushed_for < delay - 1e-9;
        self.config.step_adjustment && omega > 0.0 && !gated
    }

    /// The shift of the step-adjustment QP's nominal DCM offset at touch-down, `−step_offset F̂/(m ω²)`
    /// (zero when `step_adjustment` is off, and gated by `step_adjustment_delay` as
    /// [`PushResponse::effective_cop`]: ungated, the observer's one-tick pulses of the unpushed
    /// `walk_curve_fast_torque`, 9 N after the dead zone, moved a touch-down by 7 cm and back the next tick,
    /// docs/push-recovery.md): with the push still on after the touch-down, the new stance foot must carry
    /// the pushed LIPM's CoP, `F̂/(m ω²)` along the push from its effective ZMP.
    pub fn step_offset_shift(&self, omega: f64) -> Vector2<f64> {
        if !self.seen_by_step_adjustment(omega) || self.config.step_offset == 0.0 {
            return Vector2::zeros();
        }
        -push_zmp_offset(&self.estimate, self.mass, omega) * self.config.step_offset
    }
}

/// Whether plan time `t` \[s\] is in the start-up or the stopping double support of `plan`: before its
/// first lift-off or after its last touch-down (false for a plan without steps). The observer is not quiet
/// there in torque control (the unpushed `walk_curve_fast_torque` shows 8–17 N 0.2–0.9 s into its first
/// double support, while it shifts its weight, and 0.4–0.7 s into its last, docs/push-recovery.md), away
/// from any touch-down's `impact_window`. No allocation.
pub fn in_start_or_stop(plan: &Plan, t: f64) -> bool {
    let single = |p: &&Phase| matches!(p.kind, PhaseKind::SingleSupport { .. });
    let (Some(first), Some(last)) = (
        plan.phases.iter().find(single),
        plan.phases.iter().rev().find(single),
    ) else {
        return false;
    };
    t < first.start || t >= last.end
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;
    use stride_planner::{ContactList, Foot};

    fn response(config: PushConfig) -> PushResponse {
        PushResponse::new(&config, 30.0, Vector3::new(0.0, 0.0, -9.81)).unwrap()
    }

    fn sample(phase: PhaseKind) -> PlanSample {
        PlanSample {
            phase,
            ..PlanSample::default()
        }
    }

    /// A 30 kg body on a support carrying its weight, pushed by 20 N along y from 0.1 s; its velocity
    /// is the exact `F (t − 0.1)/m`.
    fn push_run(
        r: &mut PushResponse,
        clock: &mut PlanClock,
        phase: PhaseKind,
        walking: bool,
        seconds: f64,
    ) {
        let weight = Vector3::new(0.0, 0.0, 30.0 * 9.81);
        let s = sample(phase);
        for k in 0..(seconds / 0.01).round() as u64 {
            let t = k as f64 * 0.01;
            let v = Vector3::new(0.0, 20.0 * (t - 0.1).max(0.0) / 30.0, 0.0);
            clock.plan_time(Duration::from_millis(k * 10));
            r.observe(0.01, &v, &weight).unwrap();
            r.decide(0.01, &s, walking, false, clock);
        }
    }

    /// `replan_dcm`: none without the key or below `hold_force`; with it during a push, the measured DCM
    /// moved by `replan_push_offset F̂/(m ω²)` along the push (0: the measured DCM itself).
    #[test]
    fn the_replan_dcm_is_the_measured_one_with_the_push_offset_only_during_a_push() {
        let (omega, dcm) = (4.0, Vector2::new(0.3, -0.05));
        let pushed = |config: PushConfig| {
            let mut r = response(config);
            let mut clock = PlanClock::new(config.hold_ramp);
            assert_eq!(r.replan_dcm(dcm, omega), None, "before the push");
            push_run(&mut r, &mut clock, PhaseKind::DoubleSupport, true, 1.0);
            r
        };
        let off = pushed(PushConfig::default());
        assert!(off.estimate().norm() > 8.0);
        assert_eq!(off.replan_dcm(dcm, omega), None);
        for k in [0.0, 0.5, 1.0] {
            let r = pushed(PushConfig {
                replan_from_dcm: true,
                replan_push_offset: k,
                ..PushConfig::default()
            });
            let f = r.estimate();
            let from = r.replan_dcm(dcm, omega).unwrap();
            assert!((from - dcm - k * f / (30.0 * omega * omega)).norm() < 1e-12);
            assert!(k == 0.0 || (from - dcm).y > 0.0, "along the push: {from:?}");
        }
        // an estimate above `hold_force` for less than `hold_delay` (a touch-down's pulse): none
        let mut r = pushed(PushConfig {
            replan_from_dcm: true,
            ..PushConfig::default()
        });
        r.pushed_for = 0.05;
        assert_eq!(r.replan_dcm(dcm, omega), None);
        r.pushed_for = 0.1;
        assert!(r.replan_dcm(dcm, omega).is_some());
    }

    #[test]
    fn a_push_in_double_support_holds_the_clock_and_a_push_in_single_support_does_not() {
        let mut r = response(PushConfig::default());
        let mut clock = PlanClock::new(0.1);
        push_run(&mut r, &mut clock, PhaseKind::DoubleSupport, true, 1.0);
        // 20 N less the 6 N dead zone
        assert!((r.estimate().y - 14.0).abs() < 0.1, "{}", r.estimate());
        assert!(clock.holding() && r.holds == 1);
        let mut r = response(PushConfig::default());
        let mut clock = PlanClock::new(0.1);
        let ss = PhaseKind::SingleSupport {
            stance: stride_planner::Foot::Left,
        };
        push_run(&mut r, &mut clock, ss, true, 1.0);
        assert!(!clock.holding() && r.holds == 0);
        // standing (not walking) is never held
        let mut r = response(PushConfig::default());
        push_run(&mut r, &mut clock, PhaseKind::DoubleSupport, false, 1.0);
        assert!(!clock.holding());
    }

    /// A walk in single support until 0.5 s, then in double support; the estimate is set directly to
    /// 20 N along x on the ticks where `on(t)`. Returns the time of the first hold (`None`: none).
    fn first_hold(hold_at_once: bool, on: impl Fn(f64) -> bool) -> Option<f64> {
        first_hold_in(hold_at_once, false, on)
    }

    /// [`first_hold`] with the double support the walk's start-up or stopping one (`start_or_stop`).
    fn first_hold_in(
        hold_at_once: bool,
        start_or_stop: bool,
        on: impl Fn(f64) -> bool,
    ) -> Option<f64> {
        let mut r = response(PushConfig {
            hold_at_once,
            ..PushConfig::default()
        });
        let mut clock = PlanClock::new(0.1);
        let ss = sample(PhaseKind::SingleSupport {
            stance: stride_planner::Foot::Left,
        });
        let ds = sample(PhaseKind::DoubleSupport);
        for k in 0..100u64 {
            let t = k as f64 * 0.01;
            r.estimate = if on(t) {
                Vector2::new(20.0, 0.0)
            } else {
                Vector2::zeros()
            };
            clock.plan_time(Duration::from_millis(k * 10));
            let double_support = t >= 0.5 - 1e-9;
            if r.decide(
                0.01,
                if double_support { &ds } else { &ss },
                true,
                start_or_stop && double_support,
                &mut clock,
            ) {
                return Some(t);
            }
        }
        None
    }

    #[test]
    fn with_hold_at_once_a_rise_near_a_touch_down_waits_the_hold_delay_and_a_rise_away_from_it_does_not(
    ) {
        // the impact pulses of a touch-down at 0.5 s: 80 ms back, then 80 ms forth (the norm is what
        // counts), and one starting 40 ms before it: no hold
        assert_eq!(first_hold(true, |t| (0.5..0.58).contains(&t)), None);
        assert_eq!(
            first_hold(true, |t| (0.5..0.58).contains(&t)
                || (0.6..0.68).contains(&t)),
            None
        );
        assert_eq!(first_hold(true, |t| (0.46..0.54).contains(&t)), None);
        // a push rising 0.05 s after the touch-down holds once it has lasted `hold_delay` (0.1 s, ten
        // ticks counting the rise's)
        let t = first_hold(true, |t| t > 0.55 - 1e-9).unwrap();
        assert!((t - 0.64).abs() < 1e-9, "{t}");
        // a push rising 0.25 s after the touch-down (outside `impact_window`, 0.2 s) holds at once
        let t = first_hold(true, |t| t > 0.75 - 1e-9).unwrap();
        assert!((t - 0.75).abs() < 1e-9, "{t}");
        // a push rising in the single support, 0.3 s before the touch-down, holds at the touch-down
        let t = first_hold(true, |t| t > 0.2 - 1e-9).unwrap();
        assert!((t - 0.5).abs() < 1e-9, "{t}");
        // without `hold_at_once` every rise waits `hold_delay`
        let t = first_hold(false, |t| t > 0.75 - 1e-9).unwrap();
        assert!((t - 0.84).abs() < 1e-9, "{t}");
    }

    #[test]
    fn with_hold_at_once_a_rise_in_the_start_up_or_stopping_double_support_waits_the_hold_delay() {
        // the torque walks' weight-shift pulses, 80 ms long and 0.3 s from the touch-down: no hold
        assert_eq!(
            first_hold_in(true, true, |t| (0.8..0.88).contains(&t)),
            None
        );
        assert_eq!(
            first_hold_in(true, false, |t| (0.8..0.88).contains(&t)),
            Some(0.8)
        );
        // a lasting push there still holds, once it has lasted `hold_delay`
        let t = first_hold_in(true, true, |t| t > 0.75 - 1e-9).unwrap();
        assert!((t - 0.84).abs() < 1e-9, "{t}");
    }

    /// A plan of `phases` (kind, start, end) and nothing else.
    fn plan_of(phases: &[(PhaseKind, f64, f64)]) -> Plan {
        Plan {
            omega: 4.0,
            com_height: 0.6,
            ground_height: 0.0,
            foot_length: 0.2,
            foot_width: 0.1,
            start_time: 0.0,
            end_time: phases.last().map_or(0.0, |p| p.2),
            segments: Vec::new(),
            phases: phases
                .iter()
                .map(|&(kind, start, end)| Phase { kind, start, end })
                .collect(),
            left_contacts: ContactList {
                foot: Foot::Left,
                contacts: Vec::new(),
            },
            right_contacts: ContactList {
                foot: Foot::Right,
                contacts: Vec::new(),
            },
            left_swings: Vec::new(),
            right_swings: Vec::new(),
            outcome: stride_planner::PlanOutcome::Complete,
            merge_times: Vec::new(),
            waypoint_progress: None,
        }
    }

    #[test]
    fn the_start_up_and_stopping_double_supports_are_before_the_first_lift_off_and_after_the_last_touch_down(
    ) {
        let left = PhaseKind::SingleSupport {
            stance: stride_planner::Foot::Left,
        };
        let right = PhaseKind::SingleSupport {
            stance: stride_planner::Foot::Right,
        };
        let ds = PhaseKind::DoubleSupport;
        let plan = plan_of(&[
            (ds, 0.0, 1.0),
            (right, 1.0, 1.6),
            (ds, 1.6, 1.8),
            (left, 1.8, 2.4),
            (ds, 2.4, 3.0),
        ]);
        for (t, expected) in [
            (0.0, true),
            (0.99, true),
            (1.0, false),
            (1.7, false),
            (2.39, false),
            (2.4, true),
            (3.5, true),
        ] {
            assert_eq!(in_start_or_stop(&plan, t), expected, "{t}");
        }
        assert!(!in_start_or_stop(&plan_of(&[(ds, 0.0, 1.0)]), 0.5));
    }

    #[test]
    fn the_hold_ends_after_max_hold_and_when_disabled_never_starts() {
        let config = PushConfig {
            max_hold: 0.3,
            ..PushConfig::default()
        };
        let mut r = response(config);
        let mut clock = PlanClock::new(0.1);
        push_run(&mut r, &mut clock, PhaseKind::DoubleSupport, true, 2.0);
        assert!(!clock.holding());
        assert!(
            clock.delay() >= 0.3 && clock.delay() < 0.3 + 0.1 + 0.01,
            "{}",
            clock.delay()
        );
        let off = PushConfig {
            hold_double_support: false,
            ..PushConfig::default()
        };
        let mut r = response(off);
        let mut clock = PlanClock::new(0.1);
        push_run(&mut r, &mut clock, PhaseKind::DoubleSupport, true, 1.0);
        assert_eq!(clock.delay(), 0.0);
    }

    #[test]
    fn with_step_out_a_hold_ends_once_the_dcm_with_the_push_leaves_the_support_and_not_before() {
        // feet 0.2 m wide apart: the hull spans y in [-0.145, 0.145] (0.09 m wide soles)
        let support = SupportPolygon::rectangle(-0.1, 0.1, -0.145, 0.145).unwrap();
        let omega = (9.81f64 / 0.5).sqrt();
        let config = PushConfig {
            hold_at_once: true,
            step_out: true,
            step_out_margin: 0.01,
            ..PushConfig::default()
        };
        let ds = sample(PhaseKind::DoubleSupport);
        let ss = sample(PhaseKind::SingleSupport {
            stance: stride_planner::Foot::Left,
        });
        // 40 N to the right: F/(m ω²) = 40 · 0.5 / (30 · 9.81) = 68 mm; a DCM at y = -0.05 m puts the
        // pushed capture point at -0.118 m (inside), at y = -0.10 m at -0.168 m (23 mm outside)
        let run = |config: PushConfig, dcm_y: f64| {
            let mut r = response(config);
            r.estimate = Vector2::new(0.0, -40.0);
            r.pushed_for = 1.0;
            let mut clock = PlanClock::new(0.1);
            let mut held = 0;
            for k in 0..20u64 {
                clock.plan_time(Duration::from_millis(k * 10));
                let outside = r.capture(Vector2::new(0.0, dcm_y), omega, &support);
                r.decide(0.01, &ds, true, false, &mut clock);
                held += u32::from(clock.holding());
                // the capture point is still inside: held throughout
                if dcm_y > -0.06 {
                    assert!(outside < 0.0 && clock.holding(), "{outside}");
                }
            }
            (r, clock, held)
        };
        let (r, _, held) = run(config, -0.05);
        assert_eq!((r.holds, r.step_outs, held), (1, 0, 20));
        let (mut r, mut clock, held) = run(config, -0.10);
        assert_eq!((r.step_outs, held), (1, 0));
        assert!((r.capture(Vector2::new(0.0, -0.1), omega, &support) - 0.0231).abs() < 1e-3);
        // not held again in that double support, even with the capture point back inside
        r.capture(Vector2::zeros(), omega, &support);
        r.decide(0.01, &ds, true, false, &mut clock);
        assert!(!clock.holding() && r.step_outs == 1);
        // the next double support is held again
        r.decide(0.01, &ss, true, false, &mut clock);
        r.decide(0.01, &ds, true, false, &mut clock);
        assert!(clock.holding());
        // without step_out the same push is held
        let (r, _, held) = run(
            PushConfig {
                step_out: false,
                ..config
            },
            -0.10,
        );
        assert_eq!((r.holds, r.step_outs, held), (1, 0, 20));
    }

    #[test]
    fn leaning_moves_the_planned_com_and_dcm_against_the_push_and_keeps_the_zmp() {
        let mut r = response(PushConfig {
            lean: 0.5,
            ..PushConfig::default()
        });
        r.estimate = Vector2::new(-20.0, 0.0);
        let mut s = PlanSample {
            omega: 4.0,
            ..PlanSample::default()
        };
        let before = s;
        r.lean(&mut s);
        // 0.5 · 20 / (30 · 16) = 20.8 mm forward, against a backward push
        let d = 0.5 * 20.0 / (30.0 * 16.0);
        assert!((s.com_position.x - d).abs() < 1e-15 && (s.dcm_position.x - d).abs() < 1e-15);
        assert_eq!(s.zmp, before.zmp);
        assert_eq!(s.com_position.y, 0.0);
    }

    #[test]
    fn the_step_adjustment_sees_the_push_as_a_cop_moved_against_it() {
        let mut r = response(PushConfig::default());
        r.estimate = Vector2::new(0.0, 20.0);
        // above `hold_force` for one tick
        r.pushed_for = 0.002;
        let omega = (9.81f64 / 0.5).sqrt();
        let cop = r.effective_cop(Vector2::new(1.0, 0.1), omega);
        // F/(m ω²) = 20 · 0.5 / (30 · 9.81)
        assert!((cop.y - (0.1 - 20.0 * 0.5 / (30.0 * 9.81))).abs() < 1e-12);
        assert_eq!(cop.x, 1.0);
        let mut off = response(PushConfig {
            step_adjustment: false,
            ..PushConfig::default()
        });
        off.estimate = r.estimate;
        off.pushed_for = r.pushed_for;
        assert_eq!(
            off.effective_cop(Vector2::new(1.0, 0.1), omega),
            Vector2::new(1.0, 0.1)
        );
    }

    #[test]
    fn the_step_offset_moves_the_touch_down_offset_against_the_push_by_its_lipm_offset() {
        let omega = (9.81f64 / 0.5).sqrt();
        let pushed = |step_offset: f64, step_adjustment: bool| {
            let mut r = response(PushConfig {
                step_offset,
                step_adjustment,
                ..PushConfig::default()
            });
            r.estimate = Vector2::new(40.0, -20.0);
            r.pushed_for = 0.002; // one tick above `hold_force`: the QP reads the estimate
            r.step_offset_shift(omega)
        };
        // −F/(m ω²) = −(40, −20) · 0.5 / (30 · 9.81), half of it with 0.5
        let lipm = Vector2::new(40.0, -20.0) * 0.5 / (30.0 * 9.81);
        assert!((pushed(1.0, true) + lipm).norm() < 1e-12);
        assert!((pushed(0.5, true) + 0.5 * lipm).norm() < 1e-12);
        assert_eq!(pushed(0.0, true), Vector2::zeros());
        assert_eq!(pushed(1.0, false), Vector2::zeros());
        let invalid = PushConfig {
            step_offset: 1.5,
            ..PushConfig::default()
        };
        assert!(invalid.validate().is_err());
    }

    /// With `step_adjustment_delay` 0.1 s the QP's CoP stays the planned one while the estimate has been
    /// above `hold_force` for less than 0.1 s (a 56 ms pulse, the longest of the unpushed iCub walk, is
    /// never seen) and moves by the whole offset once it has lasted 0.1 s; 0 (the default) moves it at
    /// once.
    #[test]
    fn the_step_adjustment_delay_hides_a_short_pulse_and_passes_a_lasting_push() {
        let planned = Vector2::new(1.0, 0.1);
        let omega = (9.81f64 / 0.5).sqrt();
        let pushed = planned - push_zmp_offset(&Vector2::new(0.0, 20.0), 30.0, omega);
        let mut clock = PlanClock::new(0.1);
        let ss = sample(PhaseKind::SingleSupport {
            stance: stride_planner::Foot::Left,
        });
        let mut cops = |delay: f64, ticks: usize| {
            let mut r = response(PushConfig {
                step_adjustment_delay: delay,
                ..PushConfig::default()
            });
            r.estimate = Vector2::new(0.0, 20.0);
            let mut cop = Vec::new();
            for _ in 0..ticks {
                r.decide(0.002, &ss, true, false, &mut clock);
                cop.push(r.effective_cop(planned, omega));
            }
            cop
        };
        let gated = cops(0.1, 100);
        assert!(gated[..49].iter().all(|c| *c == planned));
        assert!(gated[49..].iter().all(|c| (c - pushed).norm() < 1e-15));
        assert!(cops(0.0, 1).iter().all(|c| (c - pushed).norm() < 1e-15));
    }

    /// The step offset's shift is gated as the CoP: with `step_adjustment_delay` 0.1 s zero while the
    /// estimate has been above `hold_force` for less than 0.1 s and the whole `−F̂/(m ω²)` once it has
    /// lasted 0.1 s (the unpushed torque curve's one-tick 9 N pulses are never seen); 0 passes it at once.
    #[test]
    fn the_step_adjustment_delay_gates_the_step_offset_as_the_cop() {
        let omega = (9.81f64 / 0.5).sqrt();
        let whole = -push_zmp_offset(&Vector2::new(0.0, 20.0), 30.0, omega);
        let mut clock = PlanClock::new(0.1);
        let ss = sample(PhaseKind::SingleSupport {
            stance: stride_planner::Foot::Left,
        });
        let mut shifts = |delay: f64, estimate: Vector2<f64>, ticks: usize| {
            let mut r = response(PushConfig {
                step_adjustment_delay: delay,
                step_offset: 1.0,
                ..PushConfig::default()
            });
            r.estimate = estimate;
            let mut shift = Vec::new();
            for _ in 0..ticks {
                r.decide(0.002, &ss, true, false, &mut clock);
                shift.push(r.step_offset_shift(omega));
            }
            shift
        };
        let gated = shifts(0.1, Vector2::new(0.0, 20.0), 100);
        assert!(gated[..49].iter().all(|s| *s == Vector2::zeros()));
        assert!(gated[49..].iter().all(|s| (s - whole).norm() < 1e-15));
        assert_eq!(shifts(0.1, Vector2::new(0.0, 9.0), 1), [Vector2::zeros()]);
        assert!(shifts(0.0, Vector2::new(0.0, 20.0), 1)
            .iter()
            .all(|s| (s - whole).norm() < 1e-15));
    }

    /// An estimate not above `hold_force` (8 N) leaves the QP's CoP the planned one: the unpushed fast
    /// walk's 3–6 N pulses at each lift-off moved its steps by 2–13 cm and back (docs/push-recovery.md,
    /// "Without pushes nothing gets worse"); 8.5 N moves it at the first tick.
    #[test]
    fn an_estimate_not_above_the_hold_force_leaves_the_planned_cop() {
        let planned = Vector2::new(1.0, 0.1);
        let omega = (9.81f64 / 0.5).sqrt();
        let mut clock = PlanClock::new(0.1);
        let ss = sample(PhaseKind::SingleSupport {
            stance: stride_planner::Foot::Left,
        });
        let cop = |force: f64, clock: &mut PlanClock| {
            let mut r = response(PushConfig::default());
            r.estimate = Vector2::new(force, 0.0);
            r.decide(0.002, &ss, true, false, clock);
            r.effective_cop(planned, omega)
        };
        for force in [0.0, 5.0, -6.0, 8.0] {
            assert_eq!(cop(force, &mut clock), planned, "{force} N");
        }
        let moved = planned - push_zmp_offset(&Vector2::new(8.5, 0.0), 30.0, omega);
        assert!((cop(8.5, &mut clock) - moved).norm() < 1e-15);
    }
}
