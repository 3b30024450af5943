//! LIPM/DCM helpers, measured ZMP, polygons: checked against closed forms and brute force.
use nalgebra::{Matrix2, Vector2, Vector3, Vector6};
use proptest::prelude::*;
use stride_simplified::*;

#[test]
fn natural_frequency_and_closed_form_dcm() {
    // 17.2 #11: h = 0.53, g = 9.81 → ω = 4.3023, doubling time ln2/ω = 0.161 s.
    let omega = natural_frequency(0.53, 9.81).unwrap();
    assert!((omega - 4.3023).abs() < 1e-4);
    assert!((2f64.ln() / omega - 0.1611).abs() < 1e-4);
    assert!(natural_frequency(0.0, 9.81).is_err());
    assert!(natural_frequency(0.5, f64::NAN).is_err());
    assert!(natural_frequency(-0.5, 9.81).is_err());
    // 17.2 #10: x0 = 0.02, ẋ0 = 0.1, p = 0, t = 0.3 → ξ = 0.157201 both ways.
    let (x0, v0, t) = (0.02, 0.1, 0.3);
    let x = x0 * (omega * t).cosh() + v0 / omega * (omega * t).sinh();
    let v = x0 * omega * (omega * t).sinh() + v0 * (omega * t).cosh();
    let xi_closed = dcm_from_com(Vector2::new(x, 0.0), Vector2::new(v, 0.0), omega).x;
    let xi_exp = (x0 + v0 / omega) * (omega * t).exp();
    assert!((xi_closed - 0.157201).abs() < 1e-6);
    assert!((xi_exp - 0.157201).abs() < 1e-6);
    let d = LipmDiscretization::new(omega, t).unwrap();
    let (xd, vd) = d.step_com(
        Vector2::new(x0, 0.0),
        Vector2::new(v0, 0.0),
        Vector2::zeros(),
    );
    assert!((xd.x - x).abs() < 1e-14 && (vd.x - v).abs() < 1e-14);
    assert!(
        (d.step_dcm(Vector2::new(x0 + v0 / omega, 0.0), Vector2::zeros())
            .x
            - xi_exp)
            .abs()
            < 1e-14
    );
}

#[test]
fn zmp_from_dcm_inverts_the_dcm_dynamics() {
    // Corrected sign (erratum 9): p = ξ − ξ̇/ω, and ξ̇ = ω(ξ − p).
    let omega = 3.7;
    let xi = Vector2::new(0.3, -0.2);
    let p = Vector2::new(0.1, 0.05);
    let xi_dot = dcm_velocity(xi, p, omega);
    assert!((zmp_from_dcm(xi, xi_dot, omega) - p).norm() < 1e-15);
    // Under the LIPM, with ξ = x + ẋ/ω, ξ̇ = ẋ + ẍ/ω = ω(ξ − p) when ẍ = ω²(x − p).
    let (x, v) = (Vector2::new(0.2, 0.1), Vector2::new(0.4, -0.3));
    let a = (x - p) * omega * omega;
    let xi = dcm_from_com(x, v, omega);
    assert!(((v + a / omega) - dcm_velocity(xi, p, omega)).norm() < 1e-14);
}

#[test]
fn discretization_matches_the_matrix_exponential_for_any_dt() {
    let omega = 4.3;
    // Continuous per-axis system [x; ẋ]' = [[0, 1], [ω², 0]][x; ẋ] + [0; −ω²] p.
    let a = Matrix2::new(0.0, 1.0, omega * omega, 0.0);
    for dt in [0.0, 1e-4, 0.002, 0.01, 0.1, 1.0, -0.05] {
        let d = LipmDiscretization::new(omega, dt).unwrap();
        let expected = (a * dt).exp();
        assert!(
            (d.state_matrix() - expected).amax() <= 1e-10 * expected.amax(),
            "dt {dt}"
        );
        // B = ∫₀^dt e^{Aτ} dτ [0; −ω²] = (e^{A dt} − I) A⁻¹ [0; −ω²]
        let b = (expected - Matrix2::identity())
            * a.try_inverse().unwrap()
            * Vector2::new(0.0, -omega * omega);
        assert!(
            (d.input_vector() - b).amax() <= 1e-10 * (1.0 + b.amax()),
            "dt {dt}"
        );
        // DCM transition from the CoM one: ξ = x + ẋ/ω
        assert!((d.dcm_transition() - (omega * dt).exp()).abs() < 1e-12);
        assert!((d.dcm_transition() + d.dcm_input() - 1.0).abs() < 1e-15);
    }
    // Backward step inverts the forward one.
    let f = LipmDiscretization::new(omega, 0.3).unwrap();
    let bwd = LipmDiscretization::new(omega, -0.3).unwrap();
    let p = Vector2::new(0.01, 0.02);
    let (x, v) = f.step_com(Vector2::new(0.1, 0.0), Vector2::new(0.2, 0.1), p);
    let (x0, v0) = bwd.step_com(x, v, p);
    assert!(
        (x0 - Vector2::new(0.1, 0.0)).norm() < 1e-14
            && (v0 - Vector2::new(0.2, 0.1)).norm() < 1e-13
    );
    assert!(LipmDiscretization::new(omega, f64::NAN).is_err());
    assert!(LipmDiscretization::new(0.0, 0.01).is_err());
}

#[test]
fn measured_zmp_matches_the_single_foot_formula_and_the_cop() {
    // 17.2 #14: vertical force f at surface point (a, b, 0) → μ = (b f, −a f, 0) about the origin → ZMP (a, b).
    let (a, b, f) = (0.03, -0.01, 250.0);
    let w = FootWrench {
        wrench: Vector6::new(0.0, 0.0, f, b * f, -a * f, 0.0),
        point: Vector3::zeros(),
    };
    let z = measured_zmp(&[w], 0.0, 1.0).unwrap();
    assert!((z - Vector2::new(a, b)).norm() < 1e-15);
    // Two feet each with pure vertical point forces: the ZMP is the force-weighted mean of the points
    // (centre of pressure), wherever the torques are expressed.
    let points = [
        Vector3::new(0.1, 0.08, 0.02),
        Vector3::new(-0.05, -0.08, 0.02),
    ];
    let forces = [
        Vector3::new(3.0, -2.0, 180.0),
        Vector3::new(-1.0, 4.0, 120.0),
    ];
    let ground = 0.02;
    let sensor = [
        Vector3::new(0.12, 0.1, 0.1),
        Vector3::new(-0.02, -0.07, 0.09),
    ];
    let feet: Vec<FootWrench> = (0..2)
        .map(|i| {
            // torque about the sensor point of a force applied at points[i]
            let tau = (points[i] - sensor[i]).cross(&forces[i]);
            FootWrench {
                wrench: Vector6::new(forces[i].x, forces[i].y, forces[i].z, tau.x, tau.y, tau.z),
                point: sensor[i],
            }
        })
        .collect();
    let z = measured_zmp(&feet, ground, 1.0).unwrap();
    // Horizontal torque about the ZMP on the ground plane vanishes.
    let zmp3 = Vector3::new(z.x, z.y, ground);
    let mut torque = Vector3::zeros();
    for i in 0..2 {
        torque += (points[i] - zmp3).cross(&forces[i]);
    }
    assert!(
        torque.x.abs() < 1e-12 && torque.y.abs() < 1e-12,
        "{torque:?}"
    );
    // with only vertical forces it is the centre of pressure
    let vertical: Vec<FootWrench> = (0..2)
        .map(|i| {
            let fz = Vector3::new(0.0, 0.0, forces[i].z);
            let tau = (points[i] - sensor[i]).cross(&fz);
            FootWrench {
                wrench: Vector6::new(0.0, 0.0, fz.z, tau.x, tau.y, tau.z),
                point: sensor[i],
            }
        })
        .collect();
    let z = measured_zmp(&vertical, ground, 1.0).unwrap();
    let cop =
        (points[0].xy() * forces[0].z + points[1].xy() * forces[1].z) / (forces[0].z + forces[1].z);
    assert!((z - cop).norm() < 1e-14);
}

#[test]
fn feet_hull_of_two_rectangles() {
    let foot = |x: f64, y: f64, yaw: f64| FootRectangle {
        position: Vector2::new(x, y),
        yaw,
        x_min: -0.05,
        x_max: 0.07,
        y_min: -0.03,
        y_max: 0.03,
    };
    let hull = feet_support_polygon(&[foot(0.0, 0.08, 0.0), foot(0.0, -0.08, 0.0)]).unwrap();
    assert_eq!(hull.len(), 4);
    assert!((hull.area() - 0.12 * 0.22).abs() < 1e-14);
    let hull = feet_support_polygon(&[foot(0.1, 0.08, 0.0), foot(0.0, -0.08, 0.0)]).unwrap();
    assert_eq!(hull.len(), 6);
    // every corner is inside, the hull is counter-clockwise and convex
    for f in [foot(0.1, 0.08, 0.0), foot(0.0, -0.08, 0.0)] {
        for c in f.corners() {
            assert!(hull.contains(c, 1e-12));
        }
    }
    let yawed = feet_support_polygon(&[foot(0.1, 0.08, 0.3), foot(0.0, -0.08, -0.2)]).unwrap();
    assert!(yawed.len() >= 6 && yawed.len() <= 8);
    assert!(yawed.area() > 0.0);
    let single = feet_support_polygon(&[foot(0.0, 0.0, 0.7)]).unwrap();
    assert!((single.area() - 0.12 * 0.06).abs() < 1e-14);
}

fn arbitrary_points() -> impl Strategy<Value = Vec<Vector2<f64>>> {
    prop::collection::vec((-1.0f64..1.0, -1.0f64..1.0), 3..20)
        .prop_map(|v| v.into_iter().map(|(x, y)| Vector2::new(x, y)).collect())
}

proptest! {
    #[test]
    fn hull_contains_its_points_and_is_convex(points in arbitrary_points()) {
        if let Ok(hull) = SupportPolygon::convex_hull(&points) {
            for p in &points {
                prop_assert!(hull.contains(*p, 1e-12));
            }
            let v = hull.vertices();
            for i in 0..v.len() {
                let e1 = v[(i + 1) % v.len()] - v[i];
                let e2 = v[(i + 2) % v.len()] - v[(i + 1) % v.len()];
                prop_assert!(e1.x * e2.y - e1.y * e2.x > 0.0);
            }
        }
    }

    #[test]
    fn projection_is_the_nearest_point_of_the_polygon(points in arbitrary_points(), px in -3.0f64..3.0, py in -3.0f64..3.0) {
        if let Ok(hull) = SupportPolygon::convex_hull(&points) {
            let p = Vector2::new(px, py);
            let (q, active) = hull.project(p);
            prop_assert!(hull.contains(q, 1e-12));
            prop_assert_eq!(active, !hull.contains(p, 0.0));
            if !active { prop_assert_eq!(q, p); }
            // brute force: no point of a fine sampling of the polygon is closer
            let v = hull.vertices();
            let d = (p - q).norm();
            for i in 0..v.len() {
                for s in 0..=50 {
                    let on_edge = v[i] + (v[(i + 1) % v.len()] - v[i]) * (s as f64 / 50.0);
                    prop_assert!((p - on_edge).norm() >= d - 1e-12);
                    let inside = hull.vertex_mean() + (on_edge - hull.vertex_mean()) * 0.5;
                    prop_assert!((p - inside).norm() >= d - 1e-12);
                }
            }
        }
    }
}

/// A fresh input's ω is a 0.5 m LIPM's under 9.81 m/s², bit for bit (the layer has no gravity of its
/// own; the value only has to be valid until the caller writes the plan's ω).
#[test]
fn the_placeholder_omega_is_that_of_a_half_metre_lipm() {
    assert_eq!(
        PLACEHOLDER_OMEGA.to_bits(),
        (9.81_f64 / 0.5).sqrt().to_bits()
    );
    let support = SupportPolygon::rectangle(-0.05, 0.07, -0.03, 0.03).unwrap();
    assert_eq!(SimplifiedInput::new(0, support).omega, PLACEHOLDER_OMEGA);
    assert_eq!(natural_frequency(0.5, 9.81).unwrap(), PLACEHOLDER_OMEGA);
}
