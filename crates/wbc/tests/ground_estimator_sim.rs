//! The ground estimator [Romualdi 2022, §8.2.3] on the simulator's anisotropic ground: a sole-sized box set
//! down on each of three patches of Table 8.1's grounds in turn; the estimate, carried from patch to patch
//! with its covariance reset at every touch-down, is within 10 % of each patch's true `k` and `b` within
//! 1 s of touch-down. Without the reset it is not. Prints the convergence table of docs/soft-ground.md
//! (`cargo test --release -p stride-wbc --test ground_estimator_sim -- --nocapture`).

mod common;

use std::sync::Arc;
use std::time::Duration;

use common::soft::{
    at_rest, box_model, box_on_patches_config, estimator_sample, rigid_guess_settings, sole_state,
    BOX_MASS, PATCHES, SOLE, SOLE_DROP,
};
use nalgebra::Vector3;
use stride_model::{Model, RobotState};
use stride_sim::{GaussianNoise, SimRobot};
use stride_wbc::{EstimatorSettings, GroundEstimator, GroundParameters};

/// Force/torque measurement noise, N and N·m.
const WRENCH_STD: [f64; 2] = [2.0, 0.2];

/// The three-patch ground under an 11 × 11 grid on the sole (its torque moments are 2 % above Lemma 1's).
fn anisotropic_sim(model: &Arc<Model>) -> SimRobot {
    let config = box_on_patches_config([11, 11]);
    SimRobot::new(Arc::clone(model), config, Duration::from_micros(500)).expect("box sim")
}

/// Per patch: the estimates `(t since touch-down, k̂, b̂)` over 1 s, the sole set down on the patch
/// centre at half its static sink, rocking at 0.3 rad/s; the covariance reset at touch-down when `reset`.
fn run(reset: bool) -> Vec<Vec<(f64, GroundParameters)>> {
    let model = box_model(
        BOX_MASS,
        [
            BOX_MASS * 0.01 / 12.0,
            BOX_MASS * 0.01 / 12.0,
            BOX_MASS * 0.05 / 12.0,
        ],
    );
    let mut sim = anisotropic_sim(&model);
    let mut noise = GaussianNoise::new(7);
    let settings = EstimatorSettings {
        wrench_std: WRENCH_STD,
        ..rigid_guess_settings()
    };
    let mut estimator = GroundEstimator::new(&settings).expect("estimator settings");
    let mut histories = Vec::new();
    for &(x_min, x_max, k, _) in &PATCHES {
        let rest = Vector3::new(0.5 * (x_min + x_max), 0.0, 0.0);
        let sink = 0.5 * BOX_MASS * 9.81 / (k * SOLE.area());
        let mut state = RobotState::zero(&model);
        state.base_pose.translation.vector = rest + Vector3::new(0.0, 0.0, SOLE_DROP - sink);
        state.base_velocity[3] = 0.3;
        state.base_velocity[4] = -0.3;
        sim.set_state(&state).expect("box state");
        if reset {
            estimator.touch_down();
        }
        let mut history = Vec::new();
        for sample in 1..=500 {
            let (state, wrench) = estimator_sample(&mut sim, &mut noise, WRENCH_STD);
            let regressor = SOLE.regressor(&sole_state(&state, &at_rest(rest)));
            estimator.update(&regressor, &wrench);
            history.push((sample as f64 * 2e-3, estimator.estimate()));
        }
        histories.push(history);
    }
    histories
}

fn within(estimate: &GroundParameters, k: f64, b: f64, tolerance: f64) -> bool {
    ((estimate.stiffness - k) / k).abs() < tolerance
        && ((estimate.damping - b) / b).abs() < tolerance
}

#[test]
fn the_estimate_converges_on_each_patch_within_one_second_of_touch_down() {
    let with_reset = run(true);
    let without_reset = run(false);
    println!("patch | true k, b | t [s] | k̂ (reset) | b̂ (reset) | k̂ (no reset) | b̂ (no reset)");
    for (p, &(_, _, k, b)) in PATCHES.iter().enumerate() {
        for (i, (t, e)) in with_reset[p].iter().enumerate() {
            if [0, 4, 24, 49, 99, 249, 499].contains(&i) {
                let n = without_reset[p][i].1;
                println!(
                    "{p} | {k:.1e}, {b:.1e} | {t:.4} | {:.4e} | {:.4e} | {:.4e} | {:.4e}",
                    e.stiffness, e.damping, n.stiffness, n.damping
                );
            }
        }
        // Within 10 % at 1 s after touch-down and from the first time it gets there on.
        let (_, last) = with_reset[p].last().expect("samples");
        assert!(within(last, k, b, 0.1), "patch {p}: {last:?}");
        let entered = with_reset[p]
            .iter()
            .rposition(|(_, e)| !within(e, k, b, 0.1))
            .map_or(0.0, |i| with_reset[p][i + 1].0);
        println!("patch {p}: within 10 % from {entered:.4} s after touch-down on");
        assert!(entered < 1.0);
    }
    // Without the reset, the covariance shrunk on the first patch holds the estimate back on the others.
    let stuck = (1..PATCHES.len()).any(|p| {
        let (_, _, k, b) = PATCHES[p];
        !within(&without_reset[p].last().expect("samples").1, k, b, 0.1)
    });
    assert!(
        stuck,
        "without the touch-down reset every patch converged too"
    );
}
