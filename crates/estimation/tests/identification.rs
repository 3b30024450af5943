//! Physically consistent inertial-parameter identification [Traversaro 2017, ch. 6–7] on synthetic data:
//! measurements `z = Y ψ_true (+ friction) + n` from stride-model's regressors with random true
//! parameters and Gaussian noise.

mod common;

use common::{bundled_model, Gauss};
use nalgebra::{DMatrix, DVector, Rotation3, Vector3, Vector6};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use stride_estimation::identification::*;
use stride_model::inertial::{
    check_full_consistency, sensor_regressor, BaseParameters, InertialParameters,
    PhysicalParameters, DEFAULT_RANK_TOLERANCE,
};
use stride_model::{KinDyn, RobotState};

/// Noise σ of a six-axis FT sensor (N, N·m), docs/sim.md defaults.
const FT_NOISE: [f64; 6] = [1.5, 1.5, 1.5, 0.05, 0.05, 0.05];

fn uniform(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.random::<f64>()
}

/// A random physical body: mass 1–3 kg, CoM within 0.15 m, random principal axes, second moments
/// 1e-3–2e-2 kg·m².
fn random_body(rng: &mut ChaCha8Rng) -> PhysicalParameters {
    PhysicalParameters {
        mass: uniform(rng, 1.0, 3.0),
        com: Vector3::from_fn(|_, _| uniform(rng, -0.15, 0.15)),
        principal_axes: Rotation3::from_euler_angles(
            uniform(rng, -3.0, 3.0),
            uniform(rng, -1.5, 1.5),
            uniform(rng, -3.0, 3.0),
        ),
        second_moments: Vector3::from_fn(|_, _| uniform(rng, 1e-3, 2e-2)),
    }
}

/// The sensor-form samples `(α^g, ω)` of a body turning about its origin (where the FT sensor is) with
/// rotation vector `φ(t) = A sin(2π t / T + phase_i)` per axis for `duration` s at 100 Hz (velocities and
/// accelerations by central differences of the orientation), gravity 9.81 m/s² along −z of the world.
fn rotation_samples(
    amplitude: f64,
    period: f64,
    duration: f64,
) -> Vec<(Vector6<f64>, Vector3<f64>)> {
    let dt = 0.01;
    let orientation = |t: f64| {
        let w = 2.0 * std::f64::consts::PI / period;
        Rotation3::new(Vector3::new(
            amplitude * (w * t).sin(),
            amplitude * (1.3 * w * t + 1.0).sin(),
            amplitude * (0.7 * w * t + 2.0).sin(),
        ))
    };
    let omega = |t: f64| {
        let h = 1e-5;
        let d = orientation(t).inverse() * orientation(t + h);
        let d0 = orientation(t - h).inverse() * orientation(t);
        (d.scaled_axis() + d0.scaled_axis()) / (2.0 * h)
    };
    let g = Vector3::new(0.0, 0.0, -9.81);
    let steps = (duration / dt) as usize;
    (0..steps)
        .map(|k| {
            let t = k as f64 * dt;
            let w = omega(t);
            let w_dot = (omega(t + 1e-4) - omega(t - 1e-4)) / 2e-4;
            let lin = orientation(t).inverse() * (-g);
            (
                Vector6::new(lin.x, lin.y, lin.z, w_dot.x, w_dot.y, w_dot.z),
                w,
            )
        })
        .collect()
}

/// FT-sensor data of one body (the arm payload of the thesis's §6.4.2) over the samples, with noise.
fn body_data(
    truth: &InertialParameters,
    samples: &[(Vector6<f64>, Vector3<f64>)],
    gauss: &mut Gauss,
) -> ReducedData {
    let mut data = IdentificationData::new(1, 0);
    for (alpha, omega) in samples {
        let y = sensor_regressor(alpha, omega);
        let f = y * truth;
        for r in 0..6 {
            let row = DVector::from_iterator(10, y.row(r).iter().cloned());
            let z = f[r] + FT_NOISE[r] * gauss.sample();
            data.add_row(row.as_view(), z, FT_NOISE[r]).unwrap();
        }
    }
    data.reduce().unwrap()
}

/// Relative errors of (mass, first moment, inertia) of `est` against `truth`.
fn relative_errors(est: &InertialParameters, truth: &InertialParameters) -> [f64; 3] {
    let part = |v: &InertialParameters, r: std::ops::Range<usize>| {
        DVector::from_iterator(r.len(), r.map(|i| v[i]))
    };
    [0..1, 1..4, 4..10]
        .map(|r| (part(est, r.clone()) - part(truth, r.clone())).norm() / part(truth, r).norm())
}

/// A poor guess for the single-body tests: 1 kg at the origin, 1e-2 kg·m² second moments.
fn generic_prior() -> Prior {
    let guess = PhysicalParameters {
        mass: 1.0,
        com: Vector3::zeros(),
        principal_axes: Rotation3::identity(),
        second_moments: Vector3::repeat(1e-2),
    };
    Prior {
        bodies: vec![guess.to_inertial_parameters()],
        extras: DVector::zeros(0),
    }
}

/// The thesis's Table 6.1 pattern [Traversaro 2017, §6.4.2]: on short, slow motions (10 s, period 40 s:
/// |ω̇| ≈ 0.1 rad/s², inertial torques below the sensor noise) the unconstrained least squares (6.19)
/// returns non-physical inertias for every one of 10 random bodies while the manifold estimate (6.26) is always
/// fully consistent; both find mass and first moment (gravity excites them) within 2 %. On fast motions
/// (period 1.5 s) both agree and recover every parameter within 2 %.
#[test]
fn table_6_1_pattern_slow_data_break_least_squares_not_the_manifold() {
    let options = ManifoldOptions {
        prior_weight: 0.0,
        ..ManifoldOptions::default()
    };
    let slow = rotation_samples(1.2, 40.0, 10.0);
    let fast = rotation_samples(1.2, 1.5, 10.0);
    let mut rng = ChaCha8Rng::seed_from_u64(61);
    let mut gauss = Gauss::new(62);
    let mut ls_non_physical = 0;
    let mut inertia_errors = [0.0, 0.0];
    let trials = 10;
    for trial in 0..trials {
        let truth = random_body(&mut rng).to_inertial_parameters();
        let data = body_data(&truth, &slow, &mut gauss);
        let ls = identify_unconstrained(&data, &generic_prior(), 1e-12).unwrap();
        let ls_pi = InertialParameters::from_column_slice(ls.parameters.as_slice());
        if check_full_consistency(&ls_pi).is_err() {
            ls_non_physical += 1;
        }
        let est = identify_on_manifold(&data, &generic_prior(), &options).unwrap();
        let pi = est.bodies[0].to_inertial_parameters();
        assert!(check_full_consistency(&pi).is_ok(), "trial {trial}: {pi:?}");
        for (k, e) in [
            relative_errors(&pi, &truth),
            relative_errors(&ls_pi, &truth),
        ]
        .iter()
        .enumerate()
        {
            assert!(e[0] < 0.02 && e[1] < 0.02, "trial {trial}: {e:?}");
            inertia_errors[k] += e[2] / trials as f64;
        }
        // The manifold estimate fits the data at least as well as any physical body can: its residual is
        // within the noise of the unconstrained optimum.
        assert!(est.normalised_residual < ls.normalised_residual * 1.01 + 0.01);

        let data = body_data(&truth, &fast, &mut gauss);
        let ls = identify_unconstrained(&data, &generic_prior(), 1e-12).unwrap();
        let ls_pi = InertialParameters::from_column_slice(ls.parameters.as_slice());
        let est = identify_on_manifold(&data, &generic_prior(), &options).unwrap();
        let pi = est.bodies[0].to_inertial_parameters();
        assert!(est.converged, "trial {trial}");
        assert!(check_full_consistency(&ls_pi).is_ok(), "trial {trial}");
        for e in [
            relative_errors(&pi, &truth),
            relative_errors(&ls_pi, &truth),
        ] {
            assert!(e.iter().all(|v| *v < 0.02), "trial {trial}: {e:?}");
        }
    }
    assert_eq!(
        ls_non_physical, trials,
        "unconstrained LS non-physical on slow data in only {ls_non_physical} of {trials} trials"
    );
    // Neither determines the inertia from slow data (the thesis's 𝔓 column is "an order of magnitude
    // off" too), but the manifold estimate is closer on average.
    assert!(
        inertia_errors[0] < inertia_errors[1],
        "mean relative inertia error: manifold {}, least squares {}",
        inertia_errors[0],
        inertia_errors[1]
    );
}

/// Whole robot, fixed base (a robot on a pole): joint torques `τ = Y_s ψ + τ_c sign(q̇)` with the joint
/// rows of the inverse-dynamics regressor [Traversaro 2017, eqs. 7.1, 7.5] at random states, random true
/// parameters (every body's mass ×0.8–1.2, CoM moved by up to 2 cm, inertia rescaled and turned), Coulomb
/// friction as extra unknowns, noise σ 0.05 N·m. The identifiable combinations (base parameters, SVD of
/// the stacked regressor, eqs. 7.6–7.10) are recovered within 2 % by the manifold method with the URDF
/// as prior, while the prior itself is off by more; every identified body is fully consistent.
#[test]
fn whole_robot_base_parameters_recovered_and_every_body_physical() {
    let model = bundled_model();
    let (nb, dof) = (model.body_count(), model.dof());
    let mut kd = KinDyn::new(model.clone());
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut gauss = Gauss::new(8);
    let prior_psi = model.inertial_parameters();
    let mut truth = prior_psi.clone();
    for b in 0..nb {
        let pi = InertialParameters::from_column_slice(&prior_psi.as_slice()[10 * b..10 * b + 10]);
        let mut theta = nearest_physical(&pi);
        theta.mass *= uniform(&mut rng, 0.8, 1.2);
        theta.com += Vector3::from_fn(|_, _| uniform(&mut rng, -0.02, 0.02));
        theta.second_moments = theta
            .second_moments
            .map(|l| l * uniform(&mut rng, 0.7, 1.3));
        theta.principal_axes *=
            Rotation3::new(Vector3::from_fn(|_, _| uniform(&mut rng, -0.2, 0.2)));
        truth
            .fixed_rows_mut::<10>(10 * b)
            .copy_from(&theta.to_inertial_parameters());
    }
    let friction = DVector::from_fn(dof, |_, _| uniform(&mut rng, 0.05, 0.2));
    let sigma = 0.05;
    let mut data = IdentificationData::new(nb, dof);
    let mut y = DMatrix::zeros(model.nv(), 10 * nb);
    let mut stacked = DMatrix::zeros(200 * dof, 10 * nb);
    for k in 0..600 {
        let mut state = RobotState::zero(&model);
        state.joint_positions = DVector::from_fn(dof, |_, _| uniform(&mut rng, -1.2, 1.2));
        state.joint_velocities = DVector::from_fn(dof, |_, _| uniform(&mut rng, -2.0, 2.0));
        let mut nu_dot = DVector::zeros(model.nv());
        for j in 0..dof {
            nu_dot[6 + j] = uniform(&mut rng, -5.0, 5.0);
        }
        kd.set_state(&state).unwrap();
        kd.inverse_dynamics_regressor(&nu_dot, &mut y).unwrap();
        let joint_rows = y.rows(6, dof);
        let tau = joint_rows * &truth;
        for j in 0..dof {
            let sign = state.joint_velocities[j].signum();
            let mut row = DVector::zeros(10 * nb + dof);
            row.rows_mut(0, 10 * nb)
                .copy_from(&joint_rows.row(j).transpose());
            row[10 * nb + j] = sign;
            let z = tau[j] + friction[j] * sign + sigma * gauss.sample();
            data.add_row(row.as_view(), z, sigma).unwrap();
        }
        if k < 200 {
            stacked.rows_mut(k * dof, dof).copy_from(&joint_rows);
        }
    }
    let data = data.reduce().unwrap();
    let base = BaseParameters::from_stacked(stacked, DEFAULT_RANK_TOLERANCE).unwrap();
    let prior = Prior {
        bodies: (0..nb)
            .map(|b| {
                InertialParameters::from_column_slice(&prior_psi.as_slice()[10 * b..10 * b + 10])
            })
            .collect(),
        extras: DVector::zeros(dof),
    };
    let est = identify_on_manifold(&data, &prior, &ManifoldOptions::default()).unwrap();
    let truth_base = base.base_parameters(&truth).unwrap();
    let error = |psi: &DVector<f64>| {
        (base.base_parameters(psi).unwrap() - &truth_base).norm() / truth_base.norm()
    };
    let psi = est.parameters.rows(0, 10 * nb).into_owned();
    assert!(
        error(&psi) < 0.02,
        "base parameters off by {:.2} %",
        100.0 * error(&psi)
    );
    assert!(
        error(&prior_psi) > 0.05,
        "the prior is already close: {}",
        error(&prior_psi)
    );
    let friction_error = (est.parameters.rows(10 * nb, dof) - &friction).amax();
    assert!(
        friction_error < 0.01,
        "friction off by {friction_error} N·m"
    );
    for (b, theta) in est.bodies.iter().enumerate() {
        let pi = theta.to_inertial_parameters();
        assert!(check_full_consistency(&pi).is_ok(), "body {b}: {pi:?}");
    }
    assert!(est.normalised_residual < 1.1, "{}", est.normalised_residual);
}

/// Refusals: wrong sizes, non-finite rows and non-positive σ are errors, not NaN.
#[test]
fn bad_inputs_are_errors() {
    let mut data = IdentificationData::new(1, 0);
    assert!(matches!(data.reduce(), Err(IdentificationError::NoData)));
    let row = DVector::from_element(10, 1.0);
    assert!(data.add_row(row.as_view(), 1.0, 0.0).is_err());
    assert!(data.add_row(row.as_view(), f64::NAN, 1.0).is_err());
    let short = DVector::from_element(9, 1.0);
    assert!(matches!(
        data.add_row(short.as_view(), 1.0, 1.0),
        Err(IdentificationError::Size { .. })
    ));
    data.add_row(row.as_view(), 1.0, 1.0).unwrap();
    let reduced = data.reduce().unwrap();
    let mut prior = generic_prior();
    prior.extras = DVector::zeros(2);
    assert!(identify_on_manifold(&reduced, &prior, &ManifoldOptions::default()).is_err());
    let mut prior = generic_prior();
    prior.bodies[0][0] = f64::INFINITY;
    assert!(identify_on_manifold(&reduced, &prior, &ManifoldOptions::default()).is_err());
}

/// A prior weight per parameter kind (`ManifoldOptions::inertia_prior_weight`, the regularised objective
/// of [Traversaro 2017, §6.3] with a diagonal weight): on slow rotations (period 40 s: the inertial torques
/// below the noise, gravity still determines mass and first moment) with a prior whose mass is 20 % high,
/// CoM 1 cm off and second moments ×1.5, a strong pull on the inertias alone (`ρ_I` = 10⁴, `ρ` = 10⁻⁴)
/// keeps `vech(I_B)` at least ten times closer to the prior's than the uniform weight (`ρ_I` = `ρ`), which
/// lets noise move the inertias, while the mass and first moment follow the data (within 2 %). A negative
/// `ρ_I` is refused.
#[test]
fn inertia_prior_weight_holds_the_inertias_and_lets_the_masses_follow_the_data() {
    let slow = rotation_samples(1.2, 40.0, 10.0);
    let mut rng = ChaCha8Rng::seed_from_u64(71);
    let mut gauss = Gauss::new(72);
    for trial in 0..5 {
        let body = random_body(&mut rng);
        let truth = body.to_inertial_parameters();
        let prior_body = PhysicalParameters {
            mass: 1.2 * body.mass,
            com: body.com + Vector3::new(0.01, -0.01, 0.01),
            second_moments: 1.5 * body.second_moments,
            ..body
        };
        let prior = Prior {
            bodies: vec![prior_body.to_inertial_parameters()],
            extras: DVector::zeros(0),
        };
        let data = body_data(&truth, &slow, &mut gauss);
        let inertia_shift = |options: &ManifoldOptions| {
            let est = identify_on_manifold(&data, &prior, options).unwrap();
            let pi = est.bodies[0].to_inertial_parameters();
            let e = relative_errors(&pi, &truth);
            let shift = (pi.rows(4, 6) - prior.bodies[0].rows(4, 6)).norm()
                / prior.bodies[0].rows(4, 6).norm();
            (e, shift)
        };
        let uniform = ManifoldOptions::default();
        let held = ManifoldOptions {
            inertia_prior_weight: Some(1e4),
            ..uniform
        };
        let (e_held, shift_held) = inertia_shift(&held);
        let (_, shift_uniform) = inertia_shift(&uniform);
        assert!(
            e_held[0] < 0.02 && e_held[1] < 0.02,
            "trial {trial}: {e_held:?}"
        );
        assert!(
            shift_held < 0.1 * shift_uniform,
            "trial {trial}: inertia moved {shift_held} (held) vs {shift_uniform} (uniform)"
        );
    }
    let data = body_data(
        &random_body(&mut rng).to_inertial_parameters(),
        &slow[..100],
        &mut gauss,
    );
    let negative = ManifoldOptions {
        inertia_prior_weight: Some(-1.0),
        ..ManifoldOptions::default()
    };
    assert!(matches!(
        identify_on_manifold(&data, &generic_prior(), &negative),
        Err(IdentificationError::Invalid { .. })
    ));
}

/// A body on the boundary of 𝔓 (a thin rod: `L = (0, 0, L_z)`, two second moments at their bound) seen on
/// fast rotations (20 s) without a prior: the projected-Newton steps (bounded coordinates whose gradient points
/// out of 𝔓 held) converge to the body within 2 % in every group, and the estimate stays on the boundary's
/// physical side.
#[test]
fn a_body_on_the_boundary_is_recovered_and_the_iteration_converges() {
    let fast = rotation_samples(1.2, 1.5, 20.0);
    let mut rng = ChaCha8Rng::seed_from_u64(81);
    let mut gauss = Gauss::new(82);
    let options = ManifoldOptions {
        prior_weight: 0.0,
        ..ManifoldOptions::default()
    };
    for trial in 0..5 {
        let body = PhysicalParameters {
            second_moments: Vector3::new(0.0, 0.0, uniform(&mut rng, 5e-3, 2e-2)),
            ..random_body(&mut rng)
        };
        let truth = body.to_inertial_parameters();
        let data = body_data(&truth, &fast, &mut gauss);
        let est = identify_on_manifold(&data, &generic_prior(), &options).unwrap();
        let pi = est.bodies[0].to_inertial_parameters();
        assert!(
            est.converged,
            "trial {trial}: {} iterations",
            est.iterations
        );
        assert!(check_full_consistency(&pi).is_ok(), "trial {trial}");
        let e = relative_errors(&pi, &truth);
        assert!(e.iter().all(|v| *v < 0.02), "trial {trial}: {e:?}");
    }
}
