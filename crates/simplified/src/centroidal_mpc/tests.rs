//! Checks of the centroidal MPC against closed forms (static balance), the constraints at the solution,
//! the bilinear model, the KKT conditions and a second solver (clarabel).

use nalgebra::{Rotation3, Vector3};
use stride_qp::{check_kkt, ClarabelSettings, ClarabelSolver, QpSolver, SolverOutput};

use super::*;
use crate::Foot;

const MASS: f64 = 33.0;
const G: f64 = 9.81;
const HEIGHT: f64 = 0.5;

fn contact(foot: Foot, x: f64, y: f64, activation: f64, deactivation: f64) -> MpcContact {
    MpcContact::level(foot, x, y, activation, deactivation)
}

fn standing(config: &CentroidalMpcConfig) -> CentroidalMpcInput {
    let mut input = CentroidalMpcInput::new(config.stages);
    input.com_position = Vector3::new(0.0, 0.0, HEIGHT);
    input.foot_half_length = 0.06;
    input.foot_half_width = 0.03;
    input
        .push_contact(contact(Foot::Left, 0.0, 0.08, -1.0, f64::INFINITY))
        .unwrap();
    input
        .push_contact(contact(Foot::Right, 0.0, -0.08, -1.0, f64::INFINITY))
        .unwrap();
    for _ in 0..=config.stages {
        input.com_reference.push(input.com_position);
    }
    input
}

/// Single support on the left foot from t = 0; the right foot lands at 0.6 s at (0.15, −0.08), the left
/// lifts at 0.9 s. The nominal CoM goes from above the left sole towards the middle of the new stance.
fn walking(config: &CentroidalMpcConfig, com_velocity: Vector3<f64>) -> CentroidalMpcInput {
    let mut input = CentroidalMpcInput::new(config.stages);
    input.com_position = Vector3::new(0.0, 0.06, HEIGHT);
    input.com_velocity = com_velocity;
    input.foot_half_length = 0.06;
    input.foot_half_width = 0.03;
    input
        .push_contact(contact(Foot::Left, 0.0, 0.08, -1.0, 0.9))
        .unwrap();
    input
        .push_contact(contact(Foot::Right, 0.15, -0.08, 0.6, f64::INFINITY))
        .unwrap();
    for k in 0..=config.stages {
        let t = k as f64 * config.stage_duration;
        let s = ((t - 0.5) / 0.6).clamp(0.0, 1.0);
        input
            .com_reference
            .push(Vector3::new(0.0, 0.06, HEIGHT).lerp(&Vector3::new(0.15, -0.06, HEIGHT), s));
    }
    input
}

fn solve(config: &CentroidalMpcConfig, input: &CentroidalMpcInput, ticks: usize) -> CentroidalMpc {
    let mut mpc = CentroidalMpc::new(config, MASS, G).unwrap();
    for _ in 0..ticks {
        mpc.step(input).unwrap();
    }
    mpc
}

#[test]
fn standing_balance_matches_the_static_closed_form() {
    let config = CentroidalMpcConfig::default();
    let input = standing(&config);
    let mpc = solve(&config, &input, 3);
    let out = mpc.output();
    for k in 0..config.stages {
        let forces = mpc.corner_forces(k);
        let total: Vector3<f64> = forces.iter().flatten().flat_map(|(_, f)| f.iter()).sum();
        // static balance: the feet carry the weight, nothing horizontal
        assert!(
            (total.z - MASS * G).abs() < 1e-3 * MASS * G,
            "stage {k}: {total}"
        );
        assert!(total.xy().norm() < 1e-3 * MASS * G, "stage {k}: {total}");
        // symmetric stance: each foot carries half
        let left = forces[0].unwrap().1.iter().map(|f| f.z).sum::<f64>();
        assert!(
            (left - 0.5 * MASS * G).abs() < 1e-3 * MASS * G,
            "stage {k}: left {left}"
        );
    }
    for s in &out.predicted {
        assert!((s.com_position - input.com_position).norm() < 1e-4);
        assert!(s.angular_momentum.norm() < 1e-4);
    }
    // the CoP of the forces is under the CoM
    assert!((out.desired_zmp - input.com_position.xy()).norm() < 1e-3);
}

#[test]
fn a_push_moves_the_next_footstep_in_its_direction() {
    // 0.5 m/s puts the DCM ~11 cm ahead of the CoM (ω ≈ 4.4 s⁻¹), beyond the 6 cm of sole the ankle has:
    // the CoP alone cannot capture it, the step must move.
    let config = CentroidalMpcConfig::default();
    let nominal = solve(&config, &walking(&config, Vector3::zeros()), 3);
    let base = nominal.output().next_adjusted().unwrap().position;
    for (velocity, axis) in [
        (Vector3::new(0.5, 0.0, 0.0), Vector3::x()),
        (Vector3::new(0.0, -0.5, 0.0), -Vector3::y()),
    ] {
        let pushed = solve(&config, &walking(&config, velocity), 3);
        let next = pushed.output().next_adjusted().unwrap();
        let moved = (next.position - base).dot(&axis);
        assert!(
            moved > 0.03,
            "push {velocity}: moved {moved} m along {axis}"
        );
    }
}

/// Every corner force of every stage, with its contact's yaw.
fn all_forces(mpc: &CentroidalMpc, config: &CentroidalMpcConfig) -> Vec<(f64, Vector3<f64>)> {
    let out = mpc.output();
    let mut v = Vec::new();
    for k in 0..config.stages {
        for (foot, entry) in mpc.corner_forces(k).iter().enumerate() {
            let Some((_, forces)) = entry else { continue };
            let yaw = out
                .contacts
                .iter()
                .find(|c| crate::centroidal_mpc::mpc::foot_index(c.planned.foot) == foot)
                .map_or(0.0, |c| c.planned.yaw);
            v.extend(forces.iter().map(|f| (yaw, *f)));
        }
    }
    v
}

#[test]
fn constraints_hold_at_the_solution() {
    let config = CentroidalMpcConfig::default();
    for velocity in [Vector3::zeros(), Vector3::new(0.6, -0.6, 0.0)] {
        let input = walking(&config, velocity);
        let mpc = solve(&config, &input, 1);
        let mu = config.friction;
        for (yaw, f) in all_forces(&mpc, &config) {
            let local = Rotation3::from_axis_angle(&Vector3::z_axis(), -yaw) * f;
            assert!(local.z >= -1e-9, "{local}");
            // the inscribed pyramid (11.1.13) and hence the Coulomb cone
            let side = mu / std::f64::consts::SQRT_2 * local.z + 1e-9;
            assert!(local.x.abs() <= side && local.y.abs() <= side, "{local}");
            assert!(local.xy().norm() <= mu * local.z + 1e-9);
        }
        for c in &mpc.output().contacts {
            let d = c.position - c.planned.position;
            assert!(d.z == 0.0);
            if !c.adjustable {
                assert_eq!(d.norm(), 0.0);
                continue;
            }
            let (lo, hi) = match c.planned.foot {
                Foot::Left => (config.outward[0], config.outward[1]),
                Foot::Right => (-config.outward[1], -config.outward[0]),
            };
            assert!(
                d.x >= config.forward[0] - 1e-9 && d.x <= config.forward[1] + 1e-9,
                "{d}"
            );
            assert!(d.y >= lo - 1e-9 && d.y <= hi + 1e-9, "{d}");
        }
    }
}

#[test]
fn linear_dynamics_match_a_forward_euler_rollout_of_the_forces() {
    let config = CentroidalMpcConfig {
        external_force_stages: 3,
        ..CentroidalMpcConfig::default()
    };
    let mut input = walking(&config, Vector3::new(0.3, -0.2, 0.0));
    input.external_force = Vector3::new(25.0, -10.0, 0.0);
    let mpc = solve(&config, &input, 1);
    let out = mpc.output();
    let dt = config.stage_duration;
    let (mut x, mut v) = (input.com_position, input.com_velocity);
    for k in 0..config.stages {
        let total: Vector3<f64> = mpc
            .corner_forces(k)
            .iter()
            .flatten()
            .flat_map(|(_, f)| f.iter())
            .sum();
        let external = if k < 3 {
            input.external_force
        } else {
            Vector3::zeros()
        };
        x += v * dt;
        v += ((total + external) / MASS - Vector3::new(0.0, 0.0, G)) * dt;
        assert!(
            (out.predicted[k + 1].com_position - x).norm() < 1e-9,
            "stage {k}"
        );
        assert!(
            (out.predicted[k + 1].com_velocity - v).norm() < 1e-9,
            "stage {k}"
        );
    }
}

#[test]
fn the_real_time_iteration_converges_to_the_bilinear_model() {
    let config = CentroidalMpcConfig::default();
    let input = walking(&config, Vector3::new(0.3, -0.2, 0.0));
    let mut mpc = CentroidalMpc::new(&config, MASS, G).unwrap();
    let first = mpc.step(&input).unwrap().diagnostics.linearization_gap;
    let mut gap = first;
    for _ in 0..15 {
        gap = mpc.step(&input).unwrap().diagnostics.linearization_gap;
    }
    assert!(
        first > 1e-4,
        "the first iterate should be off the bilinear model: {first}"
    );
    assert!(gap < 1e-6 * first.max(1.0), "gap {first} -> {gap}");
}

#[test]
fn kkt_holds_and_clarabel_agrees() {
    let config = CentroidalMpcConfig::default();
    let input = walking(&config, Vector3::new(0.5, -0.3, 0.0));
    let mpc = solve(&config, &input, 2);
    let qp = mpc.qp().unwrap();
    let ours = mpc.solver_output().unwrap();
    let report = check_kkt(qp, ours);
    assert!(report.is_satisfied(1e-6), "{report:?}");
    let mut clarabel = ClarabelSolver::new(ClarabelSettings::default());
    let mut theirs = SolverOutput::new(qp);
    clarabel.solve(qp, &mut theirs);
    assert!(theirs.status.is_success(), "{:?}", theirs.status);
    let scale = 1.0 + ours.objective.abs();
    assert!((ours.objective - theirs.objective).abs() < 1e-6 * scale);
    let n = qp.n();
    let (a, b) = (ours.x.rows(n - 2, 2), theirs.x.rows(n - 2, 2));
    assert!((a - b).norm() < 1e-5, "displacements {a} vs {b}");
}

#[test]
fn bad_input_is_an_error_and_keeps_the_output() {
    let config = CentroidalMpcConfig::default();
    let input = standing(&config);
    let mut mpc = solve(&config, &input, 1);
    let before = mpc.output().clone();
    let mut bad = input.clone();
    bad.com_velocity.x = f64::NAN;
    assert!(mpc.step(&bad).is_err());
    let mut crowded = input.clone();
    crowded
        .push_contact(contact(Foot::Left, 0.1, 0.08, -1.0, f64::INFINITY))
        .unwrap();
    assert!(matches!(
        mpc.step(&crowded),
        Err(crate::SimplifiedError::TooManyContacts { .. })
    ));
    let mut empty = input.clone();
    empty.com_reference.clear();
    assert!(mpc.step(&empty).is_err());
    assert_eq!(mpc.output(), &before);
    assert!(CentroidalMpc::new(&config, 0.0, G).is_err());
}

#[test]
fn config_ranges_and_unknown_keys_are_rejected() {
    let ok = CentroidalMpcConfig::default();
    assert!(ok.validate().is_ok());
    for bad in [
        CentroidalMpcConfig { stages: 1, ..ok },
        CentroidalMpcConfig {
            stage_duration: 0.0,
            ..ok
        },
        CentroidalMpcConfig {
            friction: -0.1,
            ..ok
        },
        CentroidalMpcConfig {
            forward: [0.01, 0.1],
            ..ok
        },
        CentroidalMpcConfig {
            outward: [-0.1, f64::NAN],
            ..ok
        },
        CentroidalMpcConfig {
            push_estimate: true,
            external_force: true,
            ..ok
        },
    ] {
        assert!(bad.validate().is_err(), "{bad:?}");
    }
    assert!(toml::from_str::<CentroidalMpcConfig>("stages = 10\nfriction = 0.5").is_ok());
    assert!(toml::from_str::<CentroidalMpcConfig>("horizon = 10").is_err());
    // the push estimate needs the push response that makes it
    let mut simplified = crate::SimplifiedConfig::default();
    simplified.centroidal_mpc.push_estimate = true;
    assert!(simplified.validate().is_err());
    simplified.push.enabled = true;
    assert!(simplified.validate().is_ok());
}

#[test]
fn a_constant_external_force_moves_the_standing_cop_by_the_closed_form() {
    // Static balance under a horizontal force F at the CoM (the push estimate held over the horizon):
    // the feet push back with −F and, moments about the CoM, their CoP sits F h / (m g) = F / (m ω²)
    // along F from the CoM [Romualdi 2022, eq. 11.2.1] (4.6 and 3.1 cm here, inside the soles).
    let config = CentroidalMpcConfig {
        push_estimate: true,
        ..CentroidalMpcConfig::default()
    };
    for force in [Vector3::new(30.0, 0.0, 0.0), Vector3::new(0.0, -20.0, 0.0)] {
        let mut input = standing(&config);
        input.external_force = force;
        let mpc = solve(&config, &input, 10);
        let expected = input.com_position.xy() + force.xy() * HEIGHT / (MASS * G);
        // within 2 mm (4 % of the larger shift): the CoM may wander by a millimetre over the horizon,
        // traded against the force-rate and corner-average costs
        let zmp = mpc.output().desired_zmp;
        assert!(
            (zmp - expected).norm() < 2e-3,
            "F {force}: CoP {zmp}, closed form {expected}"
        );
        let first: Vector3<f64> = mpc
            .corner_forces(0)
            .iter()
            .flatten()
            .flat_map(|(_, f)| f.iter())
            .sum();
        assert!(
            (first.xy() + force.xy()).norm() < 0.03 * force.norm(),
            "F {force}: feet {first}"
        );
        assert!((first.z - MASS * G).abs() < 1e-3 * MASS * G, "{first}");
    }
}

#[test]
fn a_constant_external_force_moves_the_next_touch_down_along_it() {
    // The push estimate held over the horizon: the stance CoP must end F h / (m g) along F from the
    // CoM (the standing closed form above); the sole takes part of it (±6 cm lengthwise, ±3 cm across)
    // and the next touch-down the rest, so the step moves along F by a part of that shift. Inward
    // (+y for the right foot) the box has no room (`outward` ≥ 0).
    let config = CentroidalMpcConfig {
        push_estimate: true,
        ..CentroidalMpcConfig::default()
    };
    let touch_down = |force: Vector3<f64>| {
        let mut input = walking(&config, Vector3::zeros());
        input.external_force = force;
        solve(&config, &input, 10)
            .output()
            .next_adjusted()
            .unwrap()
            .position
    };
    let base = touch_down(Vector3::zeros());
    let mut moves = Vec::new();
    for force in [
        Vector3::new(40.0, 0.0, 0.0),
        Vector3::new(-40.0, 0.0, 0.0),
        Vector3::new(0.0, -40.0, 0.0),
        Vector3::new(20.0, 0.0, 0.0),
    ] {
        let shift = force.norm() * HEIGHT / (MASS * G);
        let moved = (touch_down(force) - base).dot(&force.normalize());
        assert!(
            moved > 0.25 * shift && moved < 0.10 * 2f64.sqrt() + 1e-9,
            "F {force}: moved {moved} m along it, closed-form CoP shift {shift} m"
        );
        moves.push(moved);
    }
    // twice the force, a larger move
    assert!(moves[0] > moves[3] + 5e-3, "{moves:?}");
}
