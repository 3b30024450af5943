//! Time points and periods: `Duration` in every layer API, seconds where a formula wants them.

use std::time::Duration;

/// `d` in seconds, `t = n · 10⁻⁹` with `n` the whole nanoseconds of `d` \[s\].
///
/// The one conversion stride's layers and runner use (a tick at `n` ns samples the plan at exactly the
/// same `f64` whichever layer converts it). It differs from [`Duration::as_secs_f64`] in the last bit for
/// some values.
///
/// ```
/// use std::time::Duration;
/// assert_eq!(stride_block::seconds(Duration::from_millis(1500)), 1.5);
/// ```
pub fn seconds(d: Duration) -> f64 {
    d.as_nanos() as f64 * 1e-9
}
