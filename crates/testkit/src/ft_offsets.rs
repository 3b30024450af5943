//! The error bound that the FT offset calibration tests share (`stride calibrate` on a log of a robot on a
//! pole, on stride-sim and on MuJoCo).

/// The calibration pipeline's own error on each axis of an offset estimated from a 100 Hz log without
/// sensor noise or drift (N for the forces, N·m for the torques): accelerations computed from 100 Hz
/// states leave at most 0.014 N and 0.020 N·m on the leg sensors, 0.006 N and 0.002 N·m on the feet
/// (docs/identification.md); rounded up.
pub const FT_OFFSET_PIPELINE_ERROR: [f64; 6] = [0.02, 0.02, 0.02, 0.03, 0.03, 0.03];

/// Bound on the error of axis `axis` (0–2 force \[N\], 3–5 torque \[N·m\]) of an FT sensor offset estimated
/// as a mean over a log of `duration` \[s\] with standard deviation `estimate_std`, when the simulated
/// offset drifts as a random walk of `force_drift` \[N/√s\] / `torque_drift` \[N·m/√s\] and the truth is
/// the simulator's mean offset over the run: 4 σ of the estimate, plus the walk's spread about its mean
/// over the run (`rate √(T/3)`), plus [`FT_OFFSET_PIPELINE_ERROR`].
pub fn ft_offset_error_bound(
    axis: usize,
    estimate_std: f64,
    force_drift: f64,
    torque_drift: f64,
    duration: f64,
) -> f64 {
    let rate = if axis < 3 { force_drift } else { torque_drift };
    4.0 * estimate_std + rate * (duration / 3.0).sqrt() + FT_OFFSET_PIPELINE_ERROR[axis]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bound_adds_four_sigma_the_walks_spread_and_the_pipeline() {
        // 30 s: the walk's spread is rate · √10.
        let force = ft_offset_error_bound(1, 0.01, 0.0645, 6.45e-3, 30.0);
        assert!((force - (0.04 + 0.0645 * 10f64.sqrt() + 0.02)).abs() < 1e-15);
        let torque = ft_offset_error_bound(4, 0.001, 0.0645, 6.45e-3, 30.0);
        assert!((torque - (0.004 + 6.45e-3 * 10f64.sqrt() + 0.03)).abs() < 1e-15);
    }
}
