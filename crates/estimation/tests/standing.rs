//! The force/torque offsets learnt while standing (`ft_offsets.learn_while_standing`): the weight's split
//! between two soles against the Winkler floor it models, and the estimator recovering known offsets from
//! readings of a robot standing on that split.

mod common;

use std::time::Duration;

use common::{bundled_model, standing_input, standing_split, standing_state};
use nalgebra::{Matrix3, Rotation3, Vector3, Vector6};
use stride_estimation::{standing_foot_wrenches, Estimator, EstimatorConfig};

const PERIOD_NS: u64 = 2_000_000;

/// The split of a linear pressure field `p = a + b x + c y` (a Winkler floor under rigid soles at one
/// height) over two rectangles, by midpoint integration on an `n × n` grid per sole: the field's three
/// coefficients solve the vertical force and the two moments about `com`; the result is each sole's
/// `(f_z, τ_x, τ_y)` about its origin.
fn winkler_split(
    fz: f64,
    com: &Vector3<f64>,
    soles: &[(Matrix3<f64>, Vector3<f64>); 2],
    size: [f64; 2],
    n: usize,
) -> [Vector3<f64>; 2] {
    let cells = |(r, p): (Matrix3<f64>, Vector3<f64>)| {
        let da = size[0] * size[1] / (n * n) as f64;
        (0..n * n).map(move |k| {
            let u = ((k / n) as f64 + 0.5) / n as f64 - 0.5;
            let v = ((k % n) as f64 + 0.5) / n as f64 - 0.5;
            (p + r * Vector3::new(u * size[0], v * size[1], 0.0), da)
        })
    };
    // Rows: Σ p dA = fz, Σ (y − c_y) p dA = 0, Σ (x − c_x) p dA = 0; columns a, b, c.
    let mut m = Matrix3::zeros();
    for sole in soles {
        for (q, da) in cells(*sole) {
            let basis = Vector3::new(1.0, q.x, q.y) * da;
            m += Matrix3::from_rows(&[
                basis.transpose(),
                (basis * (q.y - com.y)).transpose(),
                (basis * (q.x - com.x)).transpose(),
            ]);
        }
    }
    let coef = m.lu().solve(&Vector3::new(fz, 0.0, 0.0)).expect("field");
    soles.map(|sole| {
        let mut out = Vector3::zeros();
        for (q, da) in cells(sole) {
            let f = (coef.x + coef.y * q.x + coef.z * q.y) * da;
            let arm = q - sole.1;
            // (f_z, τ_x, τ_y) of a vertical force f at arm.
            out += Vector3::new(f, arm.y * f, -arm.x * f);
        }
        out
    })
}

#[test]
fn the_standing_split_is_the_winkler_floor_and_balances_the_weight() {
    let yaw = Rotation3::from_axis_angle(&Vector3::z_axis(), 0.3).into_inner();
    let soles = [
        (yaw, Vector3::new(0.20, 0.10, 0.0)),
        (yaw, Vector3::new(0.26, -0.08, 0.0)),
    ];
    let size = [0.20, 0.09];
    let force = Vector3::new(0.0, 0.0, 321.8);
    for com in [
        Vector3::new(0.23, 0.01, 0.55),
        Vector3::new(0.25, 0.06, 0.55),
        Vector3::new(0.19, -0.05, 0.60),
    ] {
        let split = standing_foot_wrenches(&force, &com, &soles, size).expect("split");
        // Equilibrium: the force, and no moment about the CoM.
        let total_f: Vector3<f64> = split
            .iter()
            .map(|w| w.fixed_rows::<3>(0).into_owned())
            .sum();
        let total_m: Vector3<f64> = split
            .iter()
            .zip(&soles)
            .map(|(w, (_, p))| {
                (p - com).cross(&w.fixed_rows::<3>(0)) + w.fixed_rows::<3>(3).into_owned()
            })
            .sum();
        assert!((total_f - force).norm() < 1e-9, "{total_f}");
        assert!(total_m.norm() < 1e-9, "{total_m}");
        // The linear pressure field over both soles, integrated on a 400 × 400 grid per sole.
        let winkler = winkler_split(force.z, &com, &soles, size, 400);
        for (w, expected) in split.iter().zip(&winkler) {
            let got = Vector3::new(w[2], w[3], w[4]);
            assert!(
                (got - expected).norm() < 1e-4 * force.z,
                "split {got} vs Winkler {expected} (CoM {com})"
            );
            assert!(
                w.fixed_rows::<2>(0).norm() < 1e-9 && w[5].abs() < 1e-9,
                "{w}"
            );
        }
    }
    // A sole size that is not a number: no split.
    let com = Vector3::new(0.23, 0.01, 0.55);
    assert!(standing_foot_wrenches(&force, &com, &soles, [f64::NAN, 0.09]).is_none());
}

fn true_offsets(n: usize) -> Vec<Vector6<f64>> {
    (0..n)
        .map(|k| {
            let s = k as f64 + 1.0;
            Vector6::new(4.0 - s, 2.5 * s, -3.0 + s, 0.3, -0.1 * s, 0.2)
        })
        .collect()
}

/// Runs the estimator on a robot standing on the model's split plus `internal` (a wrench added on the left
/// sole and removed from the right, which the weight cannot see) with offsets `offsets`; returns the
/// offsets it holds after 0.2 s.
fn learnt_offsets(
    learn: f64,
    internal: Vector6<f64>,
    offsets: &[Vector6<f64>],
) -> Vec<Vector6<f64>> {
    let model = bundled_model();
    let state = standing_state(&model);
    let mut config = EstimatorConfig {
        sole_size: [0.20, 0.09],
        ..EstimatorConfig::default()
    };
    config.ft_offsets.learn_while_standing = learn;
    let split = standing_split(&model, &state, config.sole_size);
    let ground = [split[0] + internal, split[1] - internal];
    let mut est = Estimator::new(model.clone(), &config, Duration::from_millis(2)).unwrap();
    est.set_initial_state(&state).unwrap();
    for k in 1..=100 {
        let input = standing_input(&model, &state, &ground, offsets, k * PERIOD_NS);
        est.step(&input).unwrap();
    }
    est.output().ft_offsets.clone()
}

#[test]
fn offsets_are_learnt_while_standing_and_not_without() {
    let model = bundled_model();
    let offsets = true_offsets(model.ft_sensors().len());
    // Learning for 0.1 s of the 0.2 s: every sensor's offset, exactly (the readings fit the model).
    let learnt = learnt_offsets(0.1, Vector6::zeros(), &offsets);
    for (got, truth) in learnt.iter().zip(&offsets) {
        assert!((got - truth).norm() < 1e-6, "learnt {got} vs {truth}");
    }
    // Off (the default): the foot sensors keep their initial zeros while both feet stand.
    let config = EstimatorConfig::default();
    assert_eq!(config.ft_offsets.learn_while_standing, 0.0);
    let est = Estimator::new(model.clone(), &config, Duration::from_millis(2)).unwrap();
    let feet = est.foot_sensors();
    let kept = learnt_offsets(0.0, Vector6::zeros(), &offsets);
    for s in feet {
        assert_eq!(kept[s], Vector6::zeros());
    }
}

#[test]
fn an_internal_force_between_the_feet_goes_into_the_learnt_offsets() {
    // The limit of the method: a wrench the feet exchange through the floor (here 10 N pushing them apart)
    // is not seen by the weight, so it is taken for offsets, of opposite signs on the two feet.
    let model = bundled_model();
    let offsets = true_offsets(model.ft_sensors().len());
    let internal = Vector6::new(0.0, 10.0, 0.0, 0.0, 0.0, 0.0);
    let learnt = learnt_offsets(0.1, internal, &offsets);
    let config = EstimatorConfig::default();
    let est = Estimator::new(model.clone(), &config, Duration::from_millis(2)).unwrap();
    for s in est.foot_sensors() {
        let err = (learnt[s] - offsets[s]).fixed_rows::<3>(0).norm();
        assert!(err > 9.0 && err < 11.0, "sensor {s}: force error {err} N");
    }
}
