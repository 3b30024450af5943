//! The soft-ground contact model [Romualdi 2022, Lemma 1, Corollary 1, eq. 8.2.14] against independent
//! computations: quadrature of the force density over the sole, finite differences, the simulator's grid
//! contact; the linearisation error as in the thesis's Fig. 8.3.

mod common;

use common::soft::{at_rest, box_model, box_sim_config, join, sole_state, GROUND, SOLE, SOLE_DROP};

use std::sync::Arc;

use nalgebra::{Matrix6, Rotation3, Vector3, Vector6};
use rand::Rng;
use stride_model::{Model, RobotState};
use stride_sim::{ContactMode, IntegratorKind, SimInput, SimRobot};
use stride_wbc::{GroundParameters, SoleAcceleration, SoleState};

/// A random sole state: tilted by up to 0.3 rad, any yaw, displaced by up to 2 cm from rest, moving.
fn random_state(rng: &mut impl Rng) -> SoleState {
    let mut v = || {
        Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
    };
    let (tilt, yaw, rest_yaw) = (v() * 0.3, v().z * 3.0, v().x * 3.0);
    let rest_position = v() * 0.5;
    SoleState {
        position: rest_position + v() * 0.02,
        rotation: Rotation3::from_axis_angle(&Vector3::z_axis(), yaw)
            * Rotation3::new(Vector3::new(tilt.x, tilt.y, 0.0)),
        linear_velocity: v() * 0.2,
        angular_velocity: v() * 1.5,
        rest_position,
        rest_rotation: Rotation3::from_axis_angle(&Vector3::z_axis(), rest_yaw),
    }
}

/// A random sole acceleration: up to 3 m/s² and 9 rad/s² per axis.
fn random_acceleration(rng: &mut impl Rng) -> SoleAcceleration {
    let mut v = |bound: f64| {
        Vector3::new(
            rng.random_range(-bound..bound),
            rng.random_range(-bound..bound),
            rng.random_range(-bound..bound),
        )
    };
    SoleAcceleration {
        linear: v(3.0),
        angular: v(9.0),
    }
}

/// `∫_Ω [ρ; (x − o) × ρ] dΩ` with `ρ = k(x̄ − x) − b ẋ` [Romualdi 2022, eq. 8.1.4–8.1.6] by composite Simpson
/// quadrature over the sole's `(u, v)` with the area element `|e₃ᵀRe₃| du dv` (eq. B.0.10).
fn integrated_wrench(s: &SoleState, g: &GroundParameters, n: usize) -> Vector6<f64> {
    let simpson = |i: usize| {
        if i == 0 || i == n {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        }
    };
    let (hu, hv) = (SOLE.length / n as f64, SOLE.width / n as f64);
    let mut total = Vector6::zeros();
    for i in 0..=n {
        for j in 0..=n {
            let local = Vector3::new(
                -SOLE.length / 2.0 + hu * i as f64,
                -SOLE.width / 2.0 + hv * j as f64,
                0.0,
            );
            let arm = s.rotation * local;
            let x = s.position + arm;
            let rest = s.rest_position + s.rest_rotation * local;
            let velocity = s.linear_velocity + s.angular_velocity.cross(&arm);
            let rho = (rest - x) * g.stiffness - velocity * g.damping;
            let w = simpson(i) * simpson(j) * hu * hv / 9.0 * s.rotation[(2, 2)].abs();
            total += join(&rho, &arm.cross(&rho)) * w;
        }
    }
    total
}

#[test]
fn lemma_1_matches_the_integral_of_the_density_over_the_sole() {
    let mut rng = common::rng(81);
    for _ in 0..20 {
        let s = random_state(&mut rng);
        let closed = SOLE.wrench(&s, &GROUND);
        let numeric = integrated_wrench(&s, &GROUND, 40);
        // Simpson is exact for the quadratic integrands: agreement to rounding.
        assert!(
            (closed - numeric).norm() < 1e-9 * (1.0 + numeric.norm()),
            "{closed} vs {numeric}"
        );
        // The regressor is the same wrench split along k and b.
        let y = SOLE.regressor(&s);
        let stiff = integrated_wrench(
            &s,
            &GroundParameters {
                stiffness: 1.0,
                damping: 0.0,
            },
            40,
        );
        let damp = integrated_wrench(
            &s,
            &GroundParameters {
                stiffness: 0.0,
                damping: 1.0,
            },
            40,
        );
        assert!((y.column(0) - stiff).norm() < 1e-12 * (1.0 + stiff.norm()));
        assert!((y.column(1) - damp).norm() < 1e-12 * (1.0 + damp.norm()));
    }
}

#[test]
fn the_wrench_rate_is_the_time_derivative_of_the_wrench() {
    let mut rng = common::rng(82);
    for _ in 0..20 {
        let s = random_state(&mut rng);
        let acc = random_acceleration(&mut rng);
        // The state at time t along the motion with constant accelerations.
        let at = |t: f64| SoleState {
            position: s.position + s.linear_velocity * t + acc.linear * (0.5 * t * t),
            rotation: Rotation3::new(s.angular_velocity * t + acc.angular * (0.5 * t * t))
                * s.rotation,
            linear_velocity: s.linear_velocity + acc.linear * t,
            angular_velocity: s.angular_velocity + acc.angular * t,
            ..s
        };
        let eps = 1e-6;
        let numeric =
            (SOLE.wrench(&at(eps), &GROUND) - SOLE.wrench(&at(-eps), &GROUND)) / (2.0 * eps);
        let rate = SOLE.wrench_rate(&s, &GROUND);
        let analytic = rate.at(&acc);
        assert!(
            (analytic - numeric).norm() < 1e-5 * (1.0 + numeric.norm()),
            "{analytic} vs {numeric}"
        );
        // g is negative definite on the force block and negative semi-definite on the torque block.
        let eig = rate.gain.symmetric_eigenvalues();
        assert!(eig.iter().all(|e| *e <= 1e-9), "{eig}");
    }
}

/// The wrench rate of a held acceleration ([`stride_wbc::WrenchRate::held_over`]) against Lemma 1's change over
/// the period along that motion, on the stiffest, least damped ground of Table 8.1 (`k dt / 2b = 2` at
/// 500 Hz): the instantaneous rate misses the stiffness's share of the acceleration, the held one does not.
#[test]
fn the_held_wrench_rate_is_the_wrench_change_over_the_period() {
    let ground = GroundParameters {
        stiffness: 2e6,
        damping: 1e3,
    };
    let dt = 0.002;
    let mut rng = common::rng(83);
    for _ in 0..20 {
        let mut s = random_state(&mut rng);
        s.rest_rotation = s.rotation;
        s.rest_position = s.position + Vector3::new(0.0, 0.0, rng.random_range(0.0..0.02));
        s.angular_velocity *= 0.1;
        let acc = random_acceleration(&mut rng);
        let end = SoleState {
            position: s.position + s.linear_velocity * dt + acc.linear * (0.5 * dt * dt),
            rotation: Rotation3::new(s.angular_velocity * dt + acc.angular * (0.5 * dt * dt))
                * s.rotation,
            linear_velocity: s.linear_velocity + acc.linear * dt,
            angular_velocity: s.angular_velocity + acc.angular * dt,
            ..s
        };
        let change = (SOLE.wrench(&end, &ground) - SOLE.wrench(&s, &ground)) / dt;
        let rate = SOLE.wrench_rate(&s, &ground);
        let held = rate.held_over(dt, &ground).at(&acc);
        let instant = rate.at(&acc);
        let (e_held, e_instant) = ((held - change).norm(), (instant - change).norm());
        assert!(
            e_held < 0.05 * e_instant,
            "held {held} instantaneous {instant} change {change}"
        );
        // the gain scales by 1 + k dt / 2b = 3
        assert!(
            (rate.held_over(dt, &ground).gain - rate.gain * 3.0).norm() < 1e-12 * rate.gain.norm()
        );
    }
}

#[test]
fn corollary_1_is_the_first_order_expansion_of_lemma_1_at_rest() {
    let base = at_rest(Vector3::new(0.3, -0.1, 0.0));
    // Jacobian of the Lemma 1 wrench w.r.t. (o − ō, Θ (roll-pitch-yaw), ȯ, Θ̇ = ω at Θ = 0) by central
    // differences.
    let perturbed = |k: usize, h: f64| {
        let mut d = [0.0; 12];
        d[k] = h;
        let mut s = base;
        s.position += Vector3::new(d[0], d[1], d[2]);
        s.rotation = Rotation3::from_euler_angles(d[3], d[4], d[5]);
        s.linear_velocity = Vector3::new(d[6], d[7], d[8]);
        s.angular_velocity = Vector3::new(d[9], d[10], d[11]);
        SOLE.wrench(&s, &GROUND)
    };
    let [kl, ka, bl, ba] = SOLE.linear_gains(&GROUND);
    let mut expected = nalgebra::SMatrix::<f64, 6, 12>::zeros();
    expected.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-kl));
    expected.fixed_view_mut::<3, 3>(3, 3).copy_from(&(-ka));
    expected.fixed_view_mut::<3, 3>(0, 6).copy_from(&(-bl));
    expected.fixed_view_mut::<3, 3>(3, 9).copy_from(&(-ba));
    let h = 1e-6;
    for k in 0..12 {
        let column = (perturbed(k, h) - perturbed(k, -h)) / (2.0 * h);
        let reference = expected.column(k);
        assert!(
            (column - reference).norm() < 1e-6 * (1.0 + reference.norm()),
            "column {k}: {column} vs {reference}"
        );
    }
    // The linearised wrench of eq. 8.1.9 is that Jacobian applied to the deviations.
    let dev = Vector3::new(0.001, -0.002, 0.003);
    let lin = SOLE.linear_wrench(
        &GROUND,
        &dev,
        &Vector3::zeros(),
        &Vector3::zeros(),
        &Vector3::zeros(),
    );
    assert!((lin.fixed_rows::<3>(0) + kl * dev).norm() < 1e-12);
}

/// `e₆ᵀ ε_f`, the yaw-torque error of the linear model at zero velocity, roll and pitch, yaw `ψ`
/// [Romualdi 2022, Fig. 8.3].
fn yaw_torque_error(psi: f64) -> (f64, f64) {
    let s = SoleState {
        rotation: Rotation3::from_axis_angle(&Vector3::z_axis(), psi),
        ..at_rest(Vector3::zeros())
    };
    let exact = SOLE.wrench(&s, &GROUND)[5];
    let z = Vector3::zeros();
    let linear = SOLE.linear_wrench(&GROUND, &z, &z, &Vector3::new(0.0, 0.0, psi), &z)[5];
    (exact - linear, linear)
}

#[test]
fn the_linearisation_error_grows_with_the_yaw_angle_as_in_fig_8_3() {
    let (l, w) = (SOLE.length, SOLE.width);
    let k_yaw = GROUND.stiffness * l * w * (l * l + w * w) / 12.0;
    let mut previous = 0.0;
    for i in 1..=30 {
        let psi = 0.05 * i as f64;
        let (error, linear) = yaw_torque_error(psi);
        // Closed form of the difference: μ_z = −k_yaw sin ψ against −k_yaw ψ.
        let expected = k_yaw * (psi - psi.sin());
        assert!(
            (error - expected).abs() < 1e-12 * k_yaw,
            "ψ {psi}: {error} vs {expected}"
        );
        assert!(error > previous, "the error grows with ψ");
        previous = error;
        // Below 0.24 rad the linear model is within 1 % of the exact torque, beyond 0.25 rad it is not.
        let relative = error.abs() / linear.abs();
        if psi <= 0.24 {
            assert!(relative < 0.01, "ψ {psi}: {relative}");
        } else if psi >= 0.25 {
            assert!(relative > 0.01, "ψ {psi}: {relative}");
        }
    }
}

/// The simulator with an isotropic sticking law (tangential = normal densities, no friction limit), a fine
/// grid on the sole and explicit forces (the wrench of a step is the one of the state it starts from): the
/// discretisation of the density of Lemma 1 over the sole's own area. A 2 kg box carries the sole.
fn isotropic_sim(model: &Arc<Model>) -> SimRobot {
    let mut config = box_sim_config([61, 61]);
    config.integrator = IntegratorKind::Explicit;
    config.contact.normal_stiffness = GROUND.stiffness;
    config.contact.normal_damping = GROUND.damping;
    config.contact.tangential_stiffness = GROUND.stiffness;
    config.contact.tangential_damping = GROUND.damping;
    config.contact.friction_coefficient = 1e6;
    SimRobot::new(
        Arc::clone(model),
        config,
        std::time::Duration::from_micros(500),
    )
    .expect("box sim")
}

/// The base pose and twist that put the sole at `s` (its rest pose is not part of the robot state).
fn box_state(model: &Arc<Model>, s: &SoleState) -> RobotState {
    let mut state = RobotState::zero(model);
    let q = nalgebra::UnitQuaternion::from_rotation_matrix(&s.rotation);
    let arm = s.rotation * Vector3::new(0.0, 0.0, SOLE_DROP);
    state.base_pose = nalgebra::Isometry3::from_parts((s.position + arm).into(), q);
    let v = s.linear_velocity + s.angular_velocity.cross(&arm);
    state.base_velocity = join(&v, &s.angular_velocity);
    state
}

#[test]
fn the_simulator_grid_contact_is_a_discretisation_of_lemma_1() {
    let model = box_model(2.0, [0.01; 3]);
    let mut rng = common::rng(83);
    for _ in 0..6 {
        let mut sim = isotropic_sim(&model);
        // Touch-down: the sole flat, 4 mm deep, moving; the simulator anchors every point where it projects
        // on the ground, so the zero-force pose is the flat one on the ground plane.
        let yaw = Rotation3::from_axis_angle(&Vector3::z_axis(), rng.random_range(-3.0..3.0));
        let (x, y) = (rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
        let mut r = |a: f64| rng.random_range(-a..a);
        let start = SoleState {
            position: Vector3::new(x, y, -0.004),
            rotation: yaw,
            linear_velocity: Vector3::new(r(0.05), r(0.05), r(0.02)),
            // Tilting at 0.3–0.4 rad/s about both x and y (either sign), turning at 1 rad/s.
            angular_velocity: Vector3::new(
                (0.3 + r(0.1).abs()).copysign(r(1.0)),
                (0.3 + r(0.1).abs()).copysign(r(1.0)),
                1.0,
            ),
            rest_position: Vector3::new(x, y, 0.0),
            rest_rotation: yaw,
        };
        sim.set_state(&box_state(&model, &start)).unwrap();
        // 10 ms of motion: the sole tilts, slides and turns with every point still pressing and sticking.
        let input = SimInput::zeros(0);
        for _ in 0..19 {
            sim.step(&input).unwrap();
        }
        let before = sole_state(sim.state(), &start);
        sim.step(&input).unwrap();
        let out = sim.output();
        assert!(out
            .contact_points
            .iter()
            .all(|p| p.penetration > 0.0 && p.mode == ContactMode::Sticking));
        assert!(
            before.rotation[(2, 2)] < 1.0 - 5e-7,
            "the sole tilted by more than 1 mrad"
        );
        let simulated = out.surfaces[0].wrench;
        // The simulator integrates over the sole's own area, Lemma 1 over its projection on the ground.
        let lemma = SOLE.wrench(&before, &GROUND) / before.rotation[(2, 2)].abs();
        let error = simulated - lemma;
        assert!(
            error.fixed_rows::<3>(0).norm() < 1e-9 * lemma.norm(),
            "force {simulated} vs {lemma}"
        );
        // The trapezoidal grid of 61 × 61 points weighs the second moments 1 + 2/60² too much.
        let torque = lemma.fixed_rows::<3>(3).norm();
        assert!(
            error.fixed_rows::<3>(3).norm() < 1e-3 * torque,
            "torque {simulated} vs {lemma}"
        );
    }
}

#[test]
fn rate_gain_blocks_are_the_damping_of_corollary_1_at_rest() {
    let s = at_rest(Vector3::zeros());
    let [_, _, bl, ba] = SOLE.linear_gains(&GROUND);
    let g = SOLE.wrench_rate(&s, &GROUND).gain;
    let mut expected = Matrix6::zeros();
    expected.fixed_view_mut::<3, 3>(0, 0).copy_from(&(-bl));
    expected.fixed_view_mut::<3, 3>(3, 3).copy_from(&(-ba));
    assert!(
        (g - expected).norm() < 1e-12 * expected.norm(),
        "{g} vs {expected}"
    );
}
