//! A Schmitt trigger with make/break delays: binary contact detection from a force.

/// A two-threshold, two-delay Schmitt trigger.
///
/// Semantics (iDynTree's, chosen over bipedal-locomotion-framework's): while OFF, the trigger switches ON
/// once the value has stayed `≥ make_threshold` for `make_delay`; while ON, it switches OFF once the value
/// has stayed `≤ break_threshold` for `break_delay`. The timer **restarts** whenever the value re-crosses
/// the threshold, so a chattering force does not switch (bipedal-locomotion-framework keeps the first
/// crossing time and switches on a chattering signal). A zero delay switches on the first sample past the
/// threshold. [`SchmittTrigger::edge_time_ns`] keeps the time of the crossing that led to the last switch,
/// i.e. the switch time without the detection delay.
#[derive(Debug, Clone, PartialEq)]
pub struct SchmittTrigger {
    make_threshold: f64,
    break_threshold: f64,
    make_delay_ns: u64,
    break_delay_ns: u64,
    state: bool,
    /// Time the value crossed the threshold towards the other state (and has stayed past it since).
    crossing_ns: Option<u64>,
    edge_ns: u64,
    switch_ns: u64,
}

impl SchmittTrigger {
    /// A trigger in state `initial`. Thresholds in the value's unit, delays in s (`break_threshold <
    /// make_threshold` is checked by [`crate::ContactConfig::validate`]).
    pub fn new(
        make_threshold: f64,
        break_threshold: f64,
        make_delay: f64,
        break_delay: f64,
        initial: bool,
    ) -> Self {
        Self {
            make_threshold,
            break_threshold,
            make_delay_ns: seconds_to_ns(make_delay),
            break_delay_ns: seconds_to_ns(break_delay),
            state: initial,
            crossing_ns: None,
            edge_ns: 0,
            switch_ns: 0,
        }
    }

    /// Forces the state (and forgets a pending crossing), e.g. at start-up.
    pub fn set_state(&mut self, state: bool, time_ns: u64) {
        self.state = state;
        self.crossing_ns = None;
        self.edge_ns = time_ns;
        self.switch_ns = time_ns;
    }

    /// Feeds one sample taken at `time_ns` and returns the state after it.
    pub fn update(&mut self, value: f64, time_ns: u64) -> bool {
        let past = if self.state {
            value <= self.break_threshold
        } else {
            value >= self.make_threshold
        };
        if !past {
            self.crossing_ns = None;
            return self.state;
        }
        let crossing = *self.crossing_ns.get_or_insert(time_ns);
        let delay = if self.state {
            self.break_delay_ns
        } else {
            self.make_delay_ns
        };
        if time_ns.saturating_sub(crossing) >= delay {
            self.state = !self.state;
            self.crossing_ns = None;
            self.edge_ns = crossing;
            self.switch_ns = time_ns;
        }
        self.state
    }

    /// Current state.
    pub fn state(&self) -> bool {
        self.state
    }

    /// Time of the threshold crossing that led to the last switch \[ns\].
    pub fn edge_time_ns(&self) -> u64 {
        self.edge_ns
    }

    /// Time of the last switch \[ns\].
    pub fn switch_time_ns(&self) -> u64 {
        self.switch_ns
    }
}

fn seconds_to_ns(s: f64) -> u64 {
    (s * 1e9).round() as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: u64 = 1_000_000;

    #[test]
    fn make_needs_the_delay_held_continuously() {
        let mut t = SchmittTrigger::new(100.0, 20.0, 0.02, 0.01, false);
        assert!(!t.update(150.0, 0));
        assert!(!t.update(150.0, 10 * MS));
        // Re-crossing restarts the timer: 19 ms of chatter never switches.
        assert!(!t.update(50.0, 15 * MS));
        assert!(!t.update(150.0, 16 * MS));
        assert!(!t.update(150.0, 35 * MS));
        assert!(t.update(150.0, 36 * MS));
        assert_eq!(t.edge_time_ns(), 16 * MS);
        assert_eq!(t.switch_time_ns(), 36 * MS);
    }

    #[test]
    fn thresholds_are_inclusive_and_the_band_holds() {
        let mut t = SchmittTrigger::new(100.0, 20.0, 0.0, 0.0, false);
        assert!(!t.update(99.999, 0));
        assert!(t.update(100.0, MS));
        // Inside the band nothing changes, in either state.
        assert!(t.update(20.001, 2 * MS));
        assert!(t.update(99.0, 3 * MS));
        assert!(!t.update(20.0, 4 * MS));
        assert!(!t.update(99.0, 5 * MS));
    }

    #[test]
    fn break_delay_and_edge_time() {
        let mut t = SchmittTrigger::new(100.0, 20.0, 0.02, 0.01, true);
        assert!(t.update(5.0, 100 * MS));
        assert!(t.update(5.0, 109 * MS));
        assert!(!t.update(5.0, 110 * MS));
        assert_eq!(t.edge_time_ns(), 100 * MS);
        // A spike above make shorter than the make delay does not bring the contact back.
        assert!(!t.update(500.0, 111 * MS));
        assert!(!t.update(0.0, 112 * MS));
        assert!(!t.update(500.0, 113 * MS));
        assert!(!t.update(500.0, 132 * MS));
        assert!(t.update(500.0, 133 * MS));
    }

    #[test]
    fn set_state_forgets_a_pending_crossing() {
        let mut t = SchmittTrigger::new(100.0, 20.0, 0.02, 0.02, false);
        assert!(!t.update(150.0, 0));
        t.set_state(false, 5 * MS);
        assert!(!t.update(150.0, 20 * MS));
        assert!(!t.update(150.0, 39 * MS));
        assert!(t.update(150.0, 40 * MS));
    }
}
