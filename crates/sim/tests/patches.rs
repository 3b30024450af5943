//! Ground patches: the contact force under a sole on each patch follows that patch's law (normal, and
//! tangential when the patch gives it), a sole across a border sums the two laws point by point, a box resting on a patch sinks by that patch's static sink, and
//! invalid patches are refused.

mod common;

use std::sync::Arc;

use nalgebra::{Vector3, Vector6};
use stride_model::RobotState;
use stride_sim::{trapezoid_nodes, GroundPatchConfig, SimConfig, SimError, SimInput, SimRobot};

const L: f64 = 0.2;
const W: f64 = 0.1;
const LZ: f64 = 0.05;

/// Three patches of Table 8.1's grounds [Romualdi 2022, Table 8.1] on `[0, 3)` m; the default law elsewhere.
fn three_patches() -> Vec<GroundPatchConfig> {
    [
        (0.0, 1.0, 2e6, 1e4),
        (1.0, 2.0, 8e5, 1e3),
        (2.0, 3.0, 1e6, 1e4),
    ]
    .into_iter()
    .map(|(x_min, x_max, k, b)| GroundPatchConfig::normal(x_min, x_max, k, b))
    .collect()
}

fn patched_config(grid: [usize; 2]) -> SimConfig {
    let mut config = common::box_config(L, W, grid);
    config.ground.patches = three_patches();
    config
}

/// The wrench on the box's sole with its bottom centre at `x`, sunk by `depth`, moving down at `speed`.
fn sole_wrench(sim: &mut SimRobot, x: f64, depth: f64, speed: f64) -> Vector6<f64> {
    let model = Arc::clone(sim.model());
    let mut state = RobotState::zero(&model);
    state.base_pose.translation.vector = Vector3::new(x, 0.0, LZ / 2.0 - depth);
    state.base_velocity[2] = -speed;
    sim.set_state(&state).unwrap();
    sim.output().surfaces[0].wrench
}

#[test]
fn the_normal_force_on_each_patch_follows_that_patch_law() {
    let model = common::box_model(1.0, L, W, LZ);
    let config = patched_config([5, 5]);
    let default = (
        config.contact.normal_stiffness,
        config.contact.normal_damping,
    );
    let mut sim = SimRobot::new(Arc::clone(&model), config, common::PERIOD).unwrap();
    let (depth, speed) = (0.004, 0.01);
    let cases = [(0.5, 2e6, 1e4), (1.5, 8e5, 1e3), (2.5, 1e6, 1e4)];
    for (x, k, b) in cases.into_iter().chain([(-0.5, default.0, default.1)]) {
        let f = sole_wrench(&mut sim, x, depth, speed);
        // ρ = k δ + b v on every point, summed over the area l w.
        let expected = L * W * (k * depth + b * speed);
        assert!(
            (f[2] - expected).abs() < 1e-9 * expected,
            "x {x}: fz {} vs {expected}",
            f[2]
        );
        assert!(f.fixed_rows::<3>(3).norm() < 1e-9 * expected, "x {x}: {f}");
    }
}

/// The sole's wrenches over 40 steps (20 ms) of the box sunk 4 mm at `x` and sliding along +x at 1 cm/s.
fn sliding_wrenches(config: SimConfig, x: f64) -> Vec<Vector6<f64>> {
    let model = common::box_model(1.0, L, W, LZ);
    let mut sim = SimRobot::new(Arc::clone(&model), config, common::PERIOD).unwrap();
    let mut state = RobotState::zero(&model);
    state.base_pose.translation.vector = Vector3::new(x, 0.0, LZ / 2.0 - 0.004);
    state.base_velocity[0] = 0.01;
    sim.set_state(&state).unwrap();
    let input = SimInput::zeros(0);
    let mut wrenches = vec![sim.output().surfaces[0].wrench];
    for _ in 0..40 {
        sim.step(&input).unwrap();
        wrenches.push(sim.output().surfaces[0].wrench);
    }
    wrenches
}

#[test]
fn the_tangential_law_on_a_patch_is_its_own_and_the_floor_s_off_it() {
    // Patch 2 (x in [1, 2)) with its tangential densities equal to its normal ones; the others without.
    let (kt, bt) = (8e5, 1e3);
    let mut patched = patched_config([5, 5]);
    patched.ground.patches[1].tangential_stiffness = Some(kt);
    patched.ground.patches[1].tangential_damping = Some(bt);
    // At rest sunk on patch 2 and sliding at 1 cm/s: every point's stick spring is anchored where it is, so
    // the force is the damping's `−b_t v` per area, the patch's `b_t`, not the floor's.
    let first = sliding_wrenches(patched.clone(), 1.5)[0];
    let expected = -L * W * bt * 0.01;
    assert!(
        (first[0] - expected).abs() < 1e-9 * expected.abs(),
        "fx {} vs {expected}",
        first[0]
    );
    // Through the steps (stiffness and damping, sticking and slipping): on patch 2 the same, bit for bit, as
    // a floor whose own tangential densities are the patch's; off it (patches 1 and 3 and the default
    // ground) the same as without the patch's tangential keys.
    let mut floor_like_patch = patched_config([5, 5]);
    floor_like_patch.contact.tangential_stiffness = kt;
    floor_like_patch.contact.tangential_damping = bt;
    let on_patch = sliding_wrenches(patched.clone(), 1.5);
    assert_eq!(on_patch, sliding_wrenches(floor_like_patch, 1.5));
    assert_ne!(on_patch, sliding_wrenches(patched_config([5, 5]), 1.5));
    for x in [-0.5, 0.5, 2.5] {
        assert_eq!(
            sliding_wrenches(patched.clone(), x),
            sliding_wrenches(patched_config([5, 5]), x),
            "x {x}"
        );
    }
}

#[test]
fn a_sole_across_a_border_sums_the_two_laws_point_by_point() {
    let model = common::box_model(1.0, L, W, LZ);
    let grid = [9, 3];
    let mut sim = SimRobot::new(Arc::clone(&model), patched_config(grid), common::PERIOD).unwrap();
    let depth = 0.004;
    // Centre 0.03 m before the border at x = 1: the points with x ≥ 1 are on the softer patch.
    let centre = 0.97;
    let f = sole_wrench(&mut sim, centre, depth, 0.0);
    let expected: f64 = trapezoid_nodes(grid[0], L)
        .map(|(u, weight)| {
            let k = if centre + u < 1.0 { 2e6 } else { 8e5 };
            k * weight * L * W * depth
        })
        .sum();
    assert!(
        (f[2] - expected).abs() < 1e-9 * expected,
        "fz {} vs {expected}",
        f[2]
    );
    // The stiffer rear half pushes more: a nose-down torque about y is positive.
    assert!(f[4] > 0.0, "{f}");
}

#[test]
fn a_box_resting_on_a_patch_sinks_by_that_patch_static_sink() {
    let m = 10.0;
    let model = common::box_model(m, L, W, LZ);
    for (x, k) in [(0.5, 2e6), (1.5, 8e5)] {
        let mut sim =
            SimRobot::new(Arc::clone(&model), patched_config([3, 3]), common::PERIOD).unwrap();
        let mut state = RobotState::zero(&model);
        state.base_pose.translation.vector = Vector3::new(x, 0.0, LZ / 2.0);
        sim.set_initial_state(&state).unwrap();
        let input = SimInput::zeros(0);
        // 10 s: the softest patch (damping ratio 0.025) settles to 5e-5 of its first swing.
        for _ in 0..20_000 {
            sim.step(&input).unwrap();
        }
        let sink = LZ / 2.0 - sim.state().base_pose.translation.vector.z;
        let predicted = m * 9.81 / (k * L * W);
        assert!(
            (sink - predicted).abs() < 1e-3 * predicted,
            "x {x}: sink {sink} vs {predicted}"
        );
    }
}

#[test]
fn invalid_or_overlapping_patches_are_refused() {
    let model = common::box_model(1.0, L, W, LZ);
    let mut cases = Vec::new();
    let mut overlapping = three_patches();
    overlapping[1].x_min = 0.9;
    cases.push((overlapping, "ground.patches[1]"));
    let mut reversed = three_patches();
    reversed[0].x_max = -1.0;
    cases.push((reversed, "ground.patches[0]"));
    let mut soft = three_patches();
    soft[2].normal_stiffness = 0.0;
    cases.push((soft, "ground.patches[2].normal_stiffness"));
    let mut damping = three_patches();
    damping[2].normal_damping = f64::NAN;
    cases.push((damping, "ground.patches[2].normal_damping"));
    let mut slippery = three_patches();
    slippery[1].tangential_stiffness = Some(0.0);
    cases.push((slippery, "ground.patches[1].tangential_stiffness"));
    let mut tangential_damping = three_patches();
    tangential_damping[0].tangential_damping = Some(-1.0);
    cases.push((tangential_damping, "ground.patches[0].tangential_damping"));
    let mut infinite = three_patches();
    infinite[0].tangential_damping = Some(f64::INFINITY);
    cases.push((infinite, "ground.patches[0].tangential_damping"));
    for (patches, name) in cases {
        let mut config = common::box_config(L, W, [3, 3]);
        config.ground.patches = patches;
        match SimRobot::new(Arc::clone(&model), config, common::PERIOD) {
            Err(SimError::InvalidConfig { parameter, .. }) => assert_eq!(parameter, name),
            other => panic!("{name}: {:?}", other.err()),
        }
    }
}
