//! Seeded Gaussian noise (Box–Muller on a ChaCha8 stream), allocation free.

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A reproducible source of standard normal samples.
#[derive(Clone, Debug)]
pub struct GaussianNoise {
    rng: ChaCha8Rng,
    seed: u64,
}

impl GaussianNoise {
    /// A generator started from `seed`.
    pub fn new(seed: u64) -> Self {
        Self {
            rng: ChaCha8Rng::seed_from_u64(seed),
            seed,
        }
    }

    /// Restarts the sequence from the seed.
    pub fn reset(&mut self) {
        self.rng = ChaCha8Rng::seed_from_u64(self.seed);
    }

    /// One sample of `N(0, std²)`; no random number is drawn when `std == 0`, so disabled noise does not
    /// shift the sequences of the other sensors.
    pub fn sample(&mut self, std: f64) -> f64 {
        if std == 0.0 {
            return 0.0;
        }
        // u1 in (0, 1] so that ln(u1) is finite.
        let u1: f64 = 1.0 - self.rng.random::<f64>();
        let u2: f64 = self.rng.random::<f64>();
        std * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// One sample of the uniform distribution on `[−bound, bound)`; no random number is drawn when
    /// `bound == 0`.
    pub fn uniform(&mut self, bound: f64) -> f64 {
        if bound == 0.0 {
            return 0.0;
        }
        bound * (2.0 * self.rng.random::<f64>() - 1.0)
    }

    /// Three independent samples of `N(0, std²)`.
    pub fn sample3(&mut self, std: f64) -> Vector3<f64> {
        Vector3::new(self.sample(std), self.sample(std), self.sample(std))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn noise_has_the_requested_moments_and_is_reproducible() {
        let mut g = GaussianNoise::new(7);
        let n = 200_000;
        let samples: Vec<f64> = (0..n).map(|_| g.sample(2.0)).collect();
        let mean = samples.iter().sum::<f64>() / n as f64;
        let var = samples.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.02, "mean {mean}");
        assert!((var.sqrt() - 2.0).abs() < 0.02, "std {}", var.sqrt());
        g.reset();
        assert_eq!(g.sample(2.0).to_bits(), samples[0].to_bits());
        assert_eq!(g.sample(0.0), 0.0);
        let uniform: Vec<f64> = (0..n).map(|_| g.uniform(3.0)).collect();
        assert!(uniform.iter().all(|u| u.abs() <= 3.0));
        let var = uniform.iter().map(|u| u * u).sum::<f64>() / n as f64;
        // Uniform on [−b, b): variance b²/3.
        assert!((var - 3.0).abs() < 0.03, "variance {var}");
        assert_eq!(g.uniform(0.0), 0.0);
    }
}
