//! Physics laws: free fall, conservation, resting contact, friction on an incline, Lemma 1, pushes.
#![allow(clippy::field_reassign_with_default)]

mod common;

use std::sync::Arc;

use nalgebra::{DVector, Isometry3, Translation3, UnitQuaternion, Vector3, Vector6};
use stride_model::{KinDyn, RobotState};
use stride_sim::{ActuationMode, IntegratorKind, PushConfig, SimConfig, SimInput, SimRobot};

fn torque_mode(config: &mut SimConfig) {
    config.actuation.default.mode = ActuationMode::Torque;
}

#[test]
fn free_fall_accelerates_the_com_at_g_with_both_integrators() {
    let model = common::humanoid();
    for integrator in [IntegratorKind::Implicit, IntegratorKind::Explicit] {
        let mut config = common::ideal_config();
        config.integrator = integrator;
        config.contact.surfaces.clear();
        config.fall.min_base_height = -1e9;
        torque_mode(&mut config);
        let mut sim = SimRobot::new(Arc::clone(&model), config, common::PERIOD).unwrap();
        let mut state = RobotState::zero(&model);
        state.base_pose = Isometry3::from_parts(
            Translation3::new(0.1, -0.2, 2.0),
            UnitQuaternion::from_euler_angles(0.3, -0.2, 0.5),
        );
        state.joint_positions = common::bent_knees(&model, 0.3);
        sim.set_initial_state(&state).unwrap();
        let mut kd = KinDyn::new(Arc::clone(&model));
        kd.set_state(&state).unwrap();
        let com0 = kd.com_position();
        let input = SimInput::zeros(model.dof());
        let steps = 1000;
        for _ in 0..steps {
            sim.step(&input).unwrap();
        }
        let t = steps as f64 * sim.period();
        kd.set_state(sim.state()).unwrap();
        let g = Vector3::new(0.0, 0.0, -9.81);
        let v = kd.com_velocity();
        assert!(
            (v - g * t).norm() < 1e-9,
            "{integrator:?}: CoM velocity {v} vs {}",
            g * t
        );
        // Semi-implicit Euler: c(t) = c0 + g t (t + dt) / 2 exactly for a constant acceleration.
        let expected = com0 + g * (t * (t + sim.period()) / 2.0);
        assert!(
            (kd.com_position() - expected).norm() < 1e-9,
            "{integrator:?}: CoM position"
        );
        // The joints stay still in a uniform gravity field, and the IMU reads zero proper acceleration.
        assert!(sim.state().joint_velocities.norm() < 1e-9);
        assert!(
            sim.output().imu.proper_acceleration.norm() < 1e-6,
            "{:?}",
            sim.output().imu.proper_acceleration
        );
    }
}

/// Drift of energy, linear momentum and centroidal angular momentum (relative, largest over the run) and the
/// CoM error after 10 s of free-floating motion with no gravity, no contact and no actuation.
fn free_floating(rate: u32, projection: bool) -> [f64; 4] {
    let model = common::weightless(&common::humanoid());
    let mut config = common::ideal_config();
    config.momentum_projection = projection;
    config.contact.surfaces.clear();
    config.fall.min_base_height = -1e9;
    config.fall.max_tilt = 10.0;
    torque_mode(&mut config);
    let mut sim = SimRobot::new(Arc::clone(&model), config, common::period(rate)).unwrap();
    let mut state = RobotState::zero(&model);
    state.base_pose.translation.vector = Vector3::new(0.0, 0.0, 1.0);
    state.joint_positions = common::bent_knees(&model, 0.2);
    let n = model.dof();
    state.joint_velocities = DVector::from_fn(n, |i, _| 0.6 * ((i as f64) * 1.7).sin());
    state.base_velocity = Vector6::new(0.2, -0.1, 0.3, 0.4, -0.3, 0.2);
    sim.set_initial_state(&state).unwrap();
    let zero_g = Vector3::zeros();
    let (e0, _) = common::energy(&model, &state, zero_g);
    let (h0, c0) = common::momentum(&model, &state);
    let p0 = h0.fixed_rows::<3>(0).into_owned();
    let l0 = h0.fixed_rows::<3>(3).into_owned();
    let input = SimInput::zeros(n);
    let mut drift = [0.0f64; 4];
    let steps = 10 * rate as usize;
    for k in 0..steps {
        sim.step(&input).unwrap();
        if (k + 1) % (rate as usize / 10) == 0 {
            let (e, _) = common::energy(&model, sim.state(), zero_g);
            let (h, c) = common::momentum(&model, sim.state());
            let t = (k + 1) as f64 * sim.period();
            drift[0] = drift[0].max(((e - e0) / e0).abs());
            drift[1] = drift[1].max((h.fixed_rows::<3>(0) - p0).norm() / p0.norm());
            drift[2] = drift[2].max((h.fixed_rows::<3>(3) - l0).norm() / l0.norm());
            drift[3] = drift[3].max((c - (c0 + p0 / model.total_mass() * t)).norm());
        }
    }
    drift
}

#[test]
fn free_floating_motion_conserves_energy_and_momentum() {
    // Semi-implicit Euler is first order: the drifts shrink in proportion to the step.
    let coarse = free_floating(2000, false);
    let fine = free_floating(10000, false);
    let projected = free_floating(2000, true);
    println!("2 kHz projected: {projected:?}");
    println!("2 kHz: {coarse:?}\n10 kHz: {fine:?}");
    assert!(fine[0] < 1e-3, "energy drift {} at 10 kHz", fine[0]);
    assert!(
        fine[1] < 2e-4,
        "linear momentum drift {} at 10 kHz",
        fine[1]
    );
    assert!(
        fine[2] < 1e-3,
        "angular momentum drift {} at 10 kHz",
        fine[2]
    );
    assert!(
        fine[3] < 1e-3,
        "CoM off its straight line by {} m at 10 kHz",
        fine[3]
    );
    for i in 0..4 {
        assert!(
            fine[i] < coarse[i] / 2.5,
            "drift {i} does not converge: {} -> {}",
            coarse[i],
            fine[i]
        );
    }
    // With the momentum projection the momenta are conserved to rounding at 2 kHz, and the energy drift is
    // smaller than without it.
    assert!(
        projected[1] < 1e-9 && projected[2] < 1e-9,
        "projected momentum drift {projected:?}"
    );
    assert!(projected[3] < 1e-3, "projected CoM error {}", projected[3]);
    assert!(
        projected[0] < coarse[0],
        "projected energy drift {} vs {}",
        projected[0],
        coarse[0]
    );
}

#[test]
fn resting_box_carries_its_weight_with_the_predicted_penetration() {
    let (m, lx, ly, lz) = (20.0, 0.4, 0.3, 0.2);
    let model = common::box_model(m, lx, ly, lz);
    for grid in [[2, 2], [3, 3], [5, 4]] {
        let config = common::box_config(lx, ly, grid);
        let k = config.contact.normal_stiffness;
        let mut sim = SimRobot::new(Arc::clone(&model), config, common::PERIOD).unwrap();
        let mut state = RobotState::zero(&model);
        state.base_pose.translation.vector = Vector3::new(0.0, 0.0, lz / 2.0 + 0.005);
        sim.set_initial_state(&state).unwrap();
        let input = SimInput::zeros(0);
        for _ in 0..4000 {
            sim.step(&input).unwrap();
        }
        let out = sim.output();
        let weight = m * 9.81;
        let f = out.surfaces[0].wrench;
        let penetration = lz / 2.0 - out.state.base_pose.translation.vector.z;
        let predicted = weight / (k * lx * ly);
        println!("grid {grid:?}: fz {} N (weight {weight}), sink {penetration:.6e} m (predicted {predicted:.6e})", f[2]);
        assert!(
            (f[2] - weight).abs() < 1e-3 * weight,
            "grid {grid:?}: fz {}",
            f[2]
        );
        assert!(f.fixed_rows::<2>(0).norm() < 1e-6 && f.fixed_rows::<3>(3).norm() < 1e-6);
        assert!(
            (penetration - predicted).abs() < 1e-3 * predicted,
            "sink {penetration} vs {predicted}"
        );
        for p in &out.contact_points {
            assert!((p.penetration - predicted).abs() < 1e-3 * predicted);
        }
        // IMU on the box at rest: proper acceleration +g up.
        assert!((out.imu.proper_acceleration - Vector3::new(0.0, 0.0, 9.81)).norm() < 1e-3);
    }
}

/// Slides a box on a plane inclined by `theta`; returns (distance slid along the slope after `duration`,
/// acceleration fitted over the second half).
fn slide_on_incline(theta: f64, mu: f64, duration: f64) -> (f64, f64) {
    let (m, lx, ly, lz) = (5.0, 0.3, 0.2, 0.1);
    let model = common::box_model(m, lx, ly, lz);
    let mut config = common::box_config(lx, ly, [3, 3]);
    config.ground.inclination = [0.0, theta];
    config.contact.friction_coefficient = mu;
    let mut sim = SimRobot::new(Arc::clone(&model), config.clone(), common::PERIOD).unwrap();
    // Box aligned with the slope, resting on it with the static sink.
    let rotation = UnitQuaternion::from_euler_angles(0.0, theta, 0.0);
    let normal = rotation * Vector3::z();
    let sink = m * 9.81 * theta.cos() / (config.contact.normal_stiffness * lx * ly);
    let mut state = RobotState::zero(&model);
    state.base_pose =
        Isometry3::from_parts(Translation3::from(normal * (lz / 2.0 - sink)), rotation);
    sim.set_initial_state(&state).unwrap();
    let down = rotation * Vector3::x(); // along +x the plane descends
    let input = SimInput::zeros(0);
    let dt = sim.period();
    let steps = (duration / dt).round() as usize;
    let start = state.base_pose.translation.vector;
    let mut samples = Vec::new();
    for k in 0..steps {
        sim.step(&input).unwrap();
        if k >= steps / 2 {
            let v = sim.state().base_velocity.fixed_rows::<3>(0).dot(&down);
            samples.push(((k + 1) as f64 * dt, v));
        }
    }
    let d = (sim.state().base_pose.translation.vector - start).dot(&down);
    // Least-squares slope of v(t).
    let nn = samples.len() as f64;
    let (st, sv) = samples
        .iter()
        .fold((0.0, 0.0), |a, s| (a.0 + s.0, a.1 + s.1));
    let (mt, mv) = (st / nn, sv / nn);
    let (num, den) = samples.iter().fold((0.0, 0.0), |a, s| {
        (a.0 + (s.0 - mt) * (s.1 - mv), a.1 + (s.0 - mt).powi(2))
    });
    (d, num / den)
}

#[test]
fn box_sticks_below_the_friction_angle_and_slides_above_it() {
    let mu: f64 = 0.5;
    let friction_angle = mu.atan(); // 26.6°
                                    // Below: it must not creep.
    let (d, _) = slide_on_incline(friction_angle - 0.05, mu, 2.0);
    println!("below: slid {d:.3e} m");
    assert!(d.abs() < 1e-4, "slid {d} m below the friction angle");
    // Above: a = g (sin θ − μ cos θ).
    for theta in [friction_angle + 0.1, 0.7] {
        let (d, a) = slide_on_incline(theta, mu, 1.0);
        let expected = 9.81 * (theta.sin() - mu * theta.cos());
        println!("theta {theta:.3}: slid {d:.3} m, a {a:.4} vs {expected:.4}");
        assert!(
            (a - expected).abs() < 0.02 * expected,
            "a = {a} vs {expected}"
        );
    }
}

#[test]
fn fine_grid_reproduces_lemma_1() {
    // [Romualdi 2022, Lemma 1]: l = 0.2, w = 0.1, k = 1e6 N/m³.
    let (l, w, k) = (0.2, 0.1, 1e6);
    let model = common::box_model(1.0, l, w, 0.05);
    let mut config = common::box_config(l, w, [41, 41]);
    config.contact.normal_stiffness = k;
    config.contact.normal_damping = 0.0;
    config.contact.tangential_damping = 0.0;
    let mut sim = SimRobot::new(Arc::clone(&model), config, common::PERIOD).unwrap();
    // Sink test: δ = 5 mm ⇒ f = l w k δ = 100 N, no torque.
    let delta = 0.005;
    let mut state = RobotState::zero(&model);
    state.base_pose.translation.vector = Vector3::new(0.0, 0.0, 0.025 - delta);
    sim.set_state(&state).unwrap();
    let f = sim.output().surfaces[0].wrench;
    assert!((f[2] - 100.0).abs() < 1e-9, "{f}");
    assert!(f.fixed_rows::<3>(3).norm() < 1e-9);
    // Small rotations about x and y (sunk deep enough that every point stays in contact): μ = −𝒦_a Θ,
    // 𝒦_a = k l w / 12 diag(w², l², ·).
    let theta = 0.01;
    for (axis, expected) in [
        (Vector3::x_axis(), -k * l * w * w * w / 12.0 * theta),
        (Vector3::y_axis(), -k * l * w * l * l / 12.0 * theta),
    ] {
        let rotation = UnitQuaternion::from_axis_angle(&axis, theta);
        // Place the bottom centre at depth δ: base = bottom + R [0, 0, lz/2].
        let bottom = Vector3::new(0.0, 0.0, -delta);
        state.base_pose = Isometry3::from_parts(
            Translation3::from(bottom + rotation * Vector3::new(0.0, 0.0, 0.025)),
            rotation,
        );
        sim.set_state(&state).unwrap();
        let wr = sim.output().surfaces[0].wrench;
        let torque = wr.fixed_rows::<3>(3).dot(&axis);
        println!("axis {axis:?}: torque {torque:.6} vs Lemma 1 {expected:.6}");
        assert!(
            (torque - expected).abs() < 2e-3 * expected.abs(),
            "torque {torque} vs {expected}"
        );
    }
}

#[test]
fn a_push_changes_the_momentum_by_its_impulse() {
    let (m, lx, ly, lz) = (3.0, 0.2, 0.2, 0.2);
    let model = common::weightless(&common::box_model(m, lx, ly, lz));
    let mut config = common::box_config(lx, ly, [2, 2]);
    config.contact.surfaces.clear();
    config.pushes.push(PushConfig {
        frame: "box".into(),
        start: 0.1,
        duration: 0.2,
        wrench: [6.0, -3.0, 0.0, 0.0, 0.0, 0.0],
    });
    let mut sim = SimRobot::new(Arc::clone(&model), config, common::PERIOD).unwrap();
    let input = SimInput::zeros(0);
    for _ in 0..1000 {
        sim.step(&input).unwrap();
    }
    let v = sim.state().base_velocity;
    let expected = Vector3::new(6.0, -3.0, 0.0) * 0.2 / m;
    assert!((v.fixed_rows::<3>(0) - expected).norm() < 1e-9, "{v}");
    assert!(v.fixed_rows::<3>(3).norm() < 1e-12);
}

#[test]
fn a_tumbling_sliding_box_comes_to_rest_flat_carrying_its_weight() {
    // Lands on an edge while sliding: every contact mode and transition is exercised.
    let (m, lx, ly, lz) = (4.0, 0.3, 0.2, 0.1);
    let model = common::box_model(m, lx, ly, lz);
    let mut config = common::box_config(lx, ly, [3, 3]);
    config.contact.friction_coefficient = 0.5;
    let mut sim = SimRobot::new(Arc::clone(&model), config, common::PERIOD).unwrap();
    let mut state = RobotState::zero(&model);
    state.base_pose = Isometry3::from_parts(
        Translation3::new(0.0, 0.0, 0.15),
        UnitQuaternion::from_euler_angles(0.2, 0.3, 0.1),
    );
    state.base_velocity = Vector6::new(1.0, 0.3, 0.0, 0.0, 0.0, 2.0);
    sim.set_initial_state(&state).unwrap();
    let input = SimInput::zeros(0);
    let mut max_solves = 0;
    let mut slid = false;
    for _ in 0..8000 {
        let out = sim.step(&input).unwrap();
        max_solves = max_solves.max(out.solves);
        slid |= out
            .contact_points
            .iter()
            .any(|p| p.mode == stride_sim::ContactMode::Sliding);
    }
    let out = sim.output();
    let v = out.state.base_velocity;
    let tilt = (out.state.base_pose.rotation * Vector3::z()).z.acos();
    println!(
        "max solves {max_solves}, v {:.2e}, tilt {tilt:.2e}",
        v.norm()
    );
    assert!(slid, "the box should have slid");
    assert!(v.norm() < 1e-4, "still moving: {v}");
    assert!(tilt < 1e-6, "not flat: {tilt}");
    assert!((out.total_contact_wrench[2] - m * 9.81).abs() < 1e-3 * m * 9.81);
    assert!(max_solves < 20, "mode iterations hit the cap");
}
