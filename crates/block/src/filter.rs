//! The discrete first-order low-pass filter the layers and the plants share (sensor velocity filtering in
//! the simulator, the measured ZMP the simplified layer reads).

use std::ops::{Add, Mul, Sub};

/// Gain `α = dt / (dt + 1/(2π f_c))` of the discrete first-order low-pass filter `y ← y + α (x − y)` with
/// cut-off `cutoff` Hz sampled every `dt` s: the backward-Euler discretisation of `τ ẏ = x − y`,
/// `τ = 1/(2π f_c)`. It is 1 (no filtering) when `cutoff` is 0 (or not positive). The delay at low
/// frequency is about `τ`: 32 ms at 5 Hz.
pub fn low_pass_gain(dt: f64, cutoff: f64) -> f64 {
    if cutoff > 0.0 {
        dt / (dt + 1.0 / (std::f64::consts::TAU * cutoff))
    } else {
        1.0
    }
}

/// A first-order low-pass filter on any value with `+`, `−` and scaling by `f64` (`f64`, nalgebra vectors).
///
/// Sampled at irregular instants if need be: each [`FirstOrderLowPass::update`] takes the time elapsed
/// since the previous one. The first sample initialises the output (no start-up transient from zero).
///
/// ```
/// use stride_block::FirstOrderLowPass;
///
/// let mut f = FirstOrderLowPass::new(5.0); // Hz
/// assert_eq!(f.update(1.0, 0.002), 1.0); // the first sample passes through
/// let y = f.update(0.0, 0.002);
/// assert!(y < 1.0 && y > 0.9);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FirstOrderLowPass<T> {
    cutoff: f64,
    output: Option<T>,
}

impl<T> FirstOrderLowPass<T>
where
    T: Copy + Add<Output = T> + Sub<Output = T> + Mul<f64, Output = T>,
{
    /// A filter with cut-off `cutoff` Hz (0: the output is the input, bit for bit).
    pub fn new(cutoff: f64) -> Self {
        Self {
            cutoff,
            output: None,
        }
    }

    /// A filter with cut-off `cutoff` Hz whose output starts at `output` (the first sample is filtered
    /// from it instead of passing through).
    pub fn starting_at(cutoff: f64, output: T) -> Self {
        Self {
            cutoff,
            output: Some(output),
        }
    }

    /// The cut-off frequency \[Hz\].
    pub fn cutoff(&self) -> f64 {
        self.cutoff
    }

    /// Filters the sample `x` taken `dt` s after the previous one and returns the new output.
    pub fn update(&mut self, x: T, dt: f64) -> T {
        let alpha = low_pass_gain(dt, self.cutoff);
        let y = match self.output {
            Some(y) if alpha < 1.0 => y + (x - y) * alpha,
            _ => x,
        };
        self.output = Some(y);
        y
    }

    /// The last output (`None` before the first sample).
    pub fn output(&self) -> Option<T> {
        self.output
    }

    /// Forgets the past: the next sample initialises the output.
    pub fn reset(&mut self) {
        self.output = None;
    }

    /// Sets the output to `output`, from which the next sample is filtered.
    pub fn reset_to(&mut self, output: T) {
        self.output = Some(output);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Started at a value, the first sample is filtered from it (`y₁ = y₀ + α (x − y₀)`), and `reset_to`
    /// restarts from the value given; `reset` lets the next sample through.
    #[test]
    fn starting_at_filters_the_first_sample_and_reset_to_restarts() {
        let (dt, fc) = (0.002, 20.0);
        let alpha = low_pass_gain(dt, fc);
        let mut f = FirstOrderLowPass::starting_at(fc, 0.0);
        assert_eq!(f.update(1.0, dt), alpha);
        f.reset_to(2.0);
        assert_eq!(f.output(), Some(2.0));
        assert_eq!(f.update(1.0, dt), 2.0 + (1.0 - 2.0) * alpha);
        f.reset();
        assert_eq!(f.update(1.0, dt), 1.0);
    }

    /// A unit step: after k samples the output is `1 − (1 − α)^k` (the closed form of the recursion), and the
    /// continuous filter's `1 − e^{−t/τ}` is approached as `dt → 0`.
    #[test]
    fn step_response_matches_the_closed_forms() {
        let (fc, dt) = (5.0, 1e-4);
        let alpha = low_pass_gain(dt, fc);
        let mut f = FirstOrderLowPass::new(fc);
        f.update(0.0, dt);
        let tau = 1.0 / (std::f64::consts::TAU * fc);
        for k in 1..=2000 {
            let y = f.update(1.0, dt);
            let discrete = 1.0 - (1.0 - alpha).powi(k);
            assert!((y - discrete).abs() < 1e-12, "k {k}: {y} vs {discrete}");
            let continuous = 1.0 - (-(k as f64) * dt / tau).exp();
            assert!((y - continuous).abs() < 2e-3, "k {k}: {y} vs {continuous}");
        }
    }

    #[test]
    fn zero_cutoff_passes_the_input_and_reset_forgets() {
        let mut f = FirstOrderLowPass::new(0.0);
        assert_eq!(f.update(3.0, 0.01), 3.0);
        assert_eq!(f.update(-2.0, 0.01), -2.0);
        let mut g = FirstOrderLowPass::new(1.0);
        g.update(5.0, 0.01);
        assert!(g.update(0.0, 0.01) > 4.0);
        g.reset();
        assert_eq!(g.output(), None);
        assert_eq!(g.update(0.0, 0.01), 0.0);
    }

    /// Irregular sampling: two half steps filter a constant input like one full step, to second order in
    /// the gain (the discretisation error of backward Euler).
    #[test]
    fn gain_is_consistent_across_sample_periods() {
        let (fc, dt) = (5.0, 1e-3);
        let one = low_pass_gain(dt, fc);
        let half = low_pass_gain(dt / 2.0, fc);
        let two_halves = 1.0 - (1.0 - half) * (1.0 - half);
        assert!(
            (one - two_halves).abs() < one * one,
            "{one} vs {two_halves}"
        );
        assert_eq!(low_pass_gain(dt, 0.0), 1.0);
    }
}
