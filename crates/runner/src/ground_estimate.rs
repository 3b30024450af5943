//! TSID-Compliant's ground estimate in closed loop, read back from a run's log: per foot, the estimate of
//! `/wbc/ground_estimate` (`[wbc.tsid.compliant] estimate_ground`, [Romualdi 2022, §8.2.3]) against the
//! ground under the foot, and per touch-down how long after it the estimate comes within a tolerance of
//! that ground for good (the thesis's Fig. 8.10 on the anisotropic ground). Touch-downs are the rising
//! edges of the contact flags of `/wbc/input` (the planned ones, at which the TSID resets the estimate's
//! covariance), the foothold its planned sole pose there; the truth the scenario's `[sim.ground]` patches
//! ([`GroundCompliance`]) when the whole sole lies on one of them.

use serde_json::Value;
use stride_sim::{GroundCompliance, NormalDensities};

use crate::log::LogContents;

/// The feet, in the order of the arrays below, as named in `/wbc/input` and `/wbc/ground_estimate`.
pub const FEET: [(&str, &str); 2] = [("left", "left_contact"), ("right", "right_contact")];

/// One foot's estimate over a run: `(time [s], k̂ [N/m³], b̂ [N·s/m³])`.
pub type EstimateSeries = Vec<(f64, f64, f64)>;

/// One touch-down of a foot and the convergence of its ground estimate.
#[derive(Debug, Clone, PartialEq)]
pub struct EstimateTouchDown {
    /// `"left"` or `"right"`.
    pub foot: &'static str,
    /// Touch-down (the contact flag's rising edge) \[s\].
    pub time: f64,
    /// The next lift-off (falling edge), or the end of the log \[s\].
    pub lift_off: f64,
    /// The planned sole's x at touch-down \[m, world\].
    pub x: f64,
    /// The ground under the whole sole; `None` when the sole spans two patches.
    pub truth: Option<NormalDensities>,
    /// Time after touch-down from which `k̂` stays within the tolerance of the truth until the end of
    /// the window (lift-off, or touch-down + the window) \[s\]; `None`: not within at the window's end.
    pub stiffness_within: Option<f64>,
    /// The same for `b̂` \[s\].
    pub damping_within: Option<f64>,
    /// `k̂`, `b̂` at the end of the window.
    pub last: (f64, f64),
}

/// `(time, value)` of every message of `topic` (JSON) in the log.
fn messages(log: &LogContents, topic: &str) -> Result<Vec<(f64, Value)>, String> {
    log.topic(topic)
        .map(|m| {
            serde_json::from_slice(&m.data)
                .map(|v| (m.time_ns as f64 * 1e-9, v))
                .map_err(|e| format!("{topic}: {e}"))
        })
        .collect()
}

/// Per foot ([`FEET`]), the estimate of `/wbc/ground_estimate`. Errors: the topic is missing (a run
/// without `estimate_ground`) or a message lacks the foot's contact.
pub fn estimate_series(log: &LogContents) -> Result<[EstimateSeries; 2], String> {
    let msgs = messages(log, "/wbc/ground_estimate")?;
    if msgs.is_empty() {
        return Err("the log has no /wbc/ground_estimate (run with estimate_ground = true)".into());
    }
    let mut out: [EstimateSeries; 2] = Default::default();
    for (t, v) in &msgs {
        for (f, (_, contact)) in FEET.iter().enumerate() {
            let i = v["contacts"]
                .as_array()
                .and_then(|c| c.iter().position(|n| n == contact))
                .ok_or_else(|| format!("/wbc/ground_estimate at {t} s has no {contact}"))?;
            let k = v["stiffness"][i].as_f64().unwrap_or(f64::NAN);
            let b = v["damping"][i].as_f64().unwrap_or(f64::NAN);
            out[f].push((*t, k, b));
        }
    }
    Ok(out)
}

/// The ground under a sole of length `sole_length` centred at `x`, if one density holds along it.
pub fn ground_under(
    ground: &GroundCompliance,
    x: f64,
    sole_length: f64,
) -> Option<NormalDensities> {
    let at = ground.at(x);
    (0..=8)
        .map(|i| x - 0.5 * sole_length + sole_length * f64::from(i) / 8.0)
        .all(|xi| ground.at(xi) == at)
        .then_some(at)
}

/// The time after `start` from which `value` stays within `tolerance` (relative) of `truth` until the
/// last sample in `[start, end]`; `None` if the last one is not within.
fn settled(series: &[(f64, f64)], start: f64, end: f64, truth: f64, tolerance: f64) -> Option<f64> {
    let mut from = None;
    for &(t, v) in series.iter().filter(|(t, _)| *t >= start && *t <= end) {
        let within = ((v - truth) / truth).abs() <= tolerance;
        from = match (within, from) {
            (true, None) => Some(t - start),
            (true, f) => f,
            (false, _) => None,
        };
    }
    from
}

/// Every touch-down of the log with its convergence: the window is `[touch-down, min(lift-off,
/// touch-down + window)]`, the tolerance relative (0.1: 10 %). Errors: a missing topic or field.
pub fn touch_downs(
    log: &LogContents,
    ground: &GroundCompliance,
    sole_length: f64,
    tolerance: f64,
    window: f64,
) -> Result<Vec<EstimateTouchDown>, String> {
    let estimates = estimate_series(log)?;
    let inputs = messages(log, "/wbc/input")?;
    let end = inputs.last().map_or(0.0, |(t, _)| *t);
    let mut out = Vec::new();
    for (f, (foot, _)) in FEET.iter().enumerate() {
        let flag = format!("{foot}_in_contact");
        let mut previous = true; // start-up contacts are no touch-down
        let mut open: Option<(f64, f64)> = None;
        let mut edges = Vec::new();
        for (t, v) in &inputs {
            let now = v[&flag]
                .as_bool()
                .ok_or_else(|| format!("/wbc/input: no {flag}"))?;
            if now && !previous {
                let x = v[format!("{foot}_foot")]["pose"]["position"][0]
                    .as_f64()
                    .ok_or_else(|| format!("/wbc/input: no {foot}_foot position"))?;
                open = Some((*t, x));
            }
            if !now && previous {
                if let Some((td, x)) = open.take() {
                    edges.push((td, *t, x));
                }
            }
            previous = now;
        }
        if let Some((td, x)) = open {
            edges.push((td, end, x));
        }
        let k: Vec<(f64, f64)> = estimates[f].iter().map(|&(t, k, _)| (t, k)).collect();
        let b: Vec<(f64, f64)> = estimates[f].iter().map(|&(t, _, b)| (t, b)).collect();
        for (time, lift_off, x) in edges {
            let stop = lift_off.min(time + window);
            let truth = ground_under(ground, x, sole_length);
            let last = estimates[f]
                .iter()
                .rev()
                .find(|(t, _, _)| *t <= stop)
                .map_or((f64::NAN, f64::NAN), |&(_, k, b)| (k, b));
            out.push(EstimateTouchDown {
                foot,
                time,
                lift_off,
                x,
                truth,
                stiffness_within: truth
                    .and_then(|g| settled(&k, time, stop, g.stiffness, tolerance)),
                damping_within: truth.and_then(|g| settled(&b, time, stop, g.damping, tolerance)),
                last,
            });
        }
    }
    out.sort_by(|a, b| a.time.total_cmp(&b.time));
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settling_is_the_start_of_the_last_run_within_the_tolerance() {
        let s = [
            (0.0, 2.0),
            (0.1, 1.05),
            (0.2, 1.2),
            (0.3, 1.09),
            (0.4, 0.95),
            (0.5, 3.0),
        ];
        assert_eq!(settled(&s, 0.0, 0.4, 1.0, 0.1), Some(0.3));
        assert_eq!(settled(&s, 0.0, 0.5, 1.0, 0.1), None);
        assert_eq!(settled(&s, 0.0, 0.1, 1.0, 0.1), Some(0.1));
    }
}
