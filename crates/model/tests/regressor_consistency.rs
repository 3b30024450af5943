//! Physical-consistency checks [Traversaro 2017, Definitions 6.1–6.2, eqs. 6.18, 6.20–6.21] on constructed
//! bodies on both sides of each limit, the fully consistent parametrisation θ = (m, c, Q, L) (Theorem 6.1),
//! and the official iCub models' inconsistent bodies.

use nalgebra::{Matrix3, Rotation3, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use stride_model::inertial::{
    check_consistency, check_full_consistency, inertial_parameters, InertiaViolation,
    InertialParameters, PhysicalParameters,
};

fn body(m: f64, moments: [f64; 3]) -> InertialParameters {
    // Off-origin CoM and rotated axes, so the checks must undo the parallel-axis theorem and rotation.
    let q = Rotation3::from_euler_angles(0.3, -0.7, 1.2);
    let i_c = q.matrix() * Matrix3::from_diagonal(&Vector3::from(moments)) * q.matrix().transpose();
    inertial_parameters(m, &Vector3::new(0.1, -0.2, 0.05), &i_c)
}

#[test]
fn mass_must_be_positive() {
    assert!(check_consistency(&body(1e-3, [1e-6, 1e-6, 1e-6])).is_ok());
    for m in [0.0, -0.5] {
        assert_eq!(
            check_consistency(&body(m, [0.0; 3])),
            Err(InertiaViolation::NonPositiveMass { mass: m })
        );
    }
}

#[test]
fn inertia_about_the_com_must_be_positive_semidefinite() {
    assert!(check_consistency(&body(2.0, [0.0, 0.0, 0.0])).is_ok()); // point mass
    assert!(check_consistency(&body(2.0, [0.1, 0.2, -1e-13])).is_ok()); // round-off
    match check_consistency(&body(2.0, [0.1, 0.2, -1e-3])) {
        Err(InertiaViolation::NegativeMoment { moments }) => {
            assert!((moments[0] + 1e-3).abs() < 1e-12, "{moments:?}")
        }
        other => panic!("{other:?}"),
    }
}

/// The thesis's counter-example: m = 1, I_C = diag(1, 1, 3) is consistent (positive definite) but not
/// fully consistent (J_z = 3 > J_x + J_y = 2, L_z = −1/2); the limit J_z = J_x + J_y (a flat plate) is.
#[test]
fn triangle_inequalities_separate_full_consistency() {
    assert!(check_full_consistency(&body(1.0, [1.0, 1.0, 2.0])).is_ok());
    assert!(check_full_consistency(&body(1.0, [1.0, 1.0, 2.0 + 1e-10])).is_ok());
    let bad = body(1.0, [1.0, 1.0, 3.0]);
    assert!(check_consistency(&bad).is_ok());
    match check_full_consistency(&bad) {
        Err(InertiaViolation::TriangleInequality {
            moments,
            axis,
            second_moment,
        }) => {
            assert_eq!(axis, 2);
            assert!((second_moment + 0.5).abs() < 1e-12, "{second_moment}");
            assert!((moments[2] - 3.0).abs() < 1e-12);
        }
        other => panic!("{other:?}"),
    }
    assert!(check_full_consistency(&body(1.0, [1.0, 1.0, 2.0 + 1e-6])).is_err());
    // Full consistency also requires consistency.
    assert!(matches!(
        check_full_consistency(&body(0.0, [0.0; 3])),
        Err(InertiaViolation::NonPositiveMass { .. })
    ));
}

fn random_theta(r: &mut ChaCha8Rng) -> PhysicalParameters {
    PhysicalParameters {
        mass: r.random_range(0.01..10.0),
        com: Vector3::from_fn(|_, _| r.random_range(-0.5..0.5)),
        principal_axes: Rotation3::from_scaled_axis(Vector3::from_fn(|_, _| {
            r.random_range(-3.0..3.0)
        })),
        // Some second moments at zero: flat and thin bodies are on the boundary of 𝔓.
        second_moments: Vector3::from_fn(|_, _| r.random_range(-0.05_f64..0.2).max(0.0)),
    }
}

/// Theorem 6.1: every θ ∈ 𝔓 maps to fully consistent parameters, those of the uniform cuboid of
/// (6.22) (its inertia about the CoM in principal axes is `m/3 diag(d_y²+d_z², d_x²+d_z², d_x²+d_y²)`).
#[test]
fn every_theta_is_a_physical_body() {
    let mut r = ChaCha8Rng::seed_from_u64(6);
    for _ in 0..500 {
        let theta = random_theta(&mut r);
        let pi = theta.to_inertial_parameters();
        assert!(check_full_consistency(&pi).is_ok(), "{theta:?}");
        let d = theta.cuboid_half_sides();
        let m = theta.mass;
        let j = Vector3::new(
            d.y * d.y + d.z * d.z,
            d.x * d.x + d.z * d.z,
            d.x * d.x + d.y * d.y,
        ) * (m / 3.0);
        let q = theta.principal_axes.matrix();
        let cuboid = inertial_parameters(
            m,
            &theta.com,
            &(q * Matrix3::from_diagonal(&j) * q.transpose()),
        );
        assert!((cuboid - pi).amax() < 1e-12, "{theta:?}");
    }
}

#[test]
fn theta_round_trips_on_consistent_parameters() {
    let mut r = ChaCha8Rng::seed_from_u64(7);
    for _ in 0..500 {
        let pi = random_theta(&mut r).to_inertial_parameters();
        let theta = PhysicalParameters::from_inertial_parameters(&pi).unwrap();
        assert!(theta.principal_axes.matrix().determinant() > 0.0);
        assert!(theta.second_moments.min() >= 0.0);
        let back = theta.to_inertial_parameters();
        assert!(
            (back - pi).amax() < 1e-12 * pi.amax().max(1.0),
            "{pi:?} vs {back:?}"
        );
    }
    assert!(PhysicalParameters::from_inertial_parameters(&body(1.0, [1.0, 1.0, 3.0])).is_err());
}

/// The official iCubNancy01 model has bodies that are not fully consistent (issue 19): both `ankle_1` links
/// have principal moments (3.47e-3, 4.29e-3, 4.766) kg·m², consistent (positive definite) but far outside
/// the triangle inequality (L = −2.379 kg·m²); the loader warns about the same links. Its massless bodies
/// fail `m > 0`. iCubGazeboV2_7 passes every check.
#[test]
fn icub_nancy01_has_inconsistent_bodies() {
    let test = "icub_nancy01_has_inconsistent_bodies";
    let Some(dir) = stride_testkit::icub_models_dir(test) else {
        return;
    };
    let model = stride_model::Model::from_urdf_file(dir.join("iCubNancy01/model.urdf")).unwrap();
    let full = model.inertia_violations(true);
    let consistent = model.inertia_violations(false);
    for link in ["l_ankle_1", "r_ankle_1"] {
        let v = full
            .iter()
            .find(|v| v.name == link)
            .unwrap_or_else(|| panic!("{link} not reported: {full:?}"));
        match v.violation {
            InertiaViolation::TriangleInequality {
                axis,
                second_moment,
                moments,
            } => {
                assert_eq!(axis, 2);
                assert!((second_moment + 2.379084).abs() < 1e-5, "{second_moment}");
                assert!((moments[2] - 4.76593).abs() < 1e-5, "{moments:?}");
            }
            ref other => panic!("{link}: {other:?}"),
        }
        assert!(
            consistent.iter().all(|v| v.name != link),
            "{link} is consistent"
        );
        assert!(
            model
                .warnings()
                .iter()
                .any(|w| w.contains(link) && w.contains("triangle inequality")),
            "loader warning for {link}"
        );
    }
    for link in ["torso_1", "torso_2", "neck_1", "neck_2"] {
        assert!(
            consistent.iter().any(|v| v.name == link
                && v.violation == InertiaViolation::NonPositiveMass { mass: 0.0 }),
            "{link}: {consistent:?}"
        );
    }
    let clean = stride_model::Model::from_urdf_file(dir.join("iCubGazeboV2_7/model.urdf")).unwrap();
    assert!(clean.inertia_violations(true).is_empty());
}
