//! Bad inputs give errors and leave the held output unchanged; configs reject unknown fields.
use std::time::Duration;

use nalgebra::{Vector2, Vector3, Vector6};
use stride_simplified::*;

const OMEGA: f64 = 4.302_325_511_579_751;

type Setter = Box<dyn Fn(&mut SimplifiedInput)>;

fn good_input(block: &SimplifiedController) -> SimplifiedInput {
    let foot = SupportPolygon::rectangle(-0.05, 0.07, -0.03, 0.03).unwrap();
    let mut input = SimplifiedInput::new(block.horizon_samples(), foot);
    input.omega = OMEGA;
    for _ in 0..block.horizon_samples() {
        input
            .horizon
            .push(HorizonSample {
                dcm_position: Vector2::zeros(),
                zmp: Vector2::zeros(),
                support: foot,
            })
            .unwrap();
    }
    input.measured_dcm = Vector2::new(0.005, 0.0);
    input
}

#[test]
fn non_finite_inputs_are_rejected_and_the_last_output_is_held() {
    for kind in [
        DcmControllerKind::Instantaneous,
        DcmControllerKind::Predictive,
    ] {
        let config = SimplifiedConfig {
            dcm_controller: kind,
            ..Default::default()
        };
        let mut block = SimplifiedController::new(&config, Duration::from_millis(10)).unwrap();
        assert!(!block.output().valid);
        let input = good_input(&block);
        let held = *block.step(&input).unwrap();
        assert!(held.valid);
        let setters: Vec<(&str, Setter)> = vec![
            ("omega", Box::new(|i| i.omega = f64::NAN)),
            ("omega", Box::new(|i| i.omega = -1.0)),
            ("omega", Box::new(|i| i.omega = f64::INFINITY)),
            (
                "planned_dcm_position",
                Box::new(|i| i.planned_dcm_position.x = f64::NAN),
            ),
            (
                "planned_dcm_velocity",
                Box::new(|i| i.planned_dcm_velocity.y = f64::INFINITY),
            ),
            ("planned_zmp", Box::new(|i| i.planned_zmp.x = f64::NAN)),
            (
                "planned_com_position",
                Box::new(|i| i.planned_com_position.x = f64::NAN),
            ),
            (
                "planned_com_velocity",
                Box::new(|i| i.planned_com_velocity.x = f64::NEG_INFINITY),
            ),
            (
                "measured_com_position",
                Box::new(|i| i.measured_com_position.y = f64::NAN),
            ),
            (
                "measured_com_velocity",
                Box::new(|i| i.measured_com_velocity.y = f64::NAN),
            ),
            ("measured_dcm", Box::new(|i| i.measured_dcm.x = f64::NAN)),
            (
                "measured_zmp",
                Box::new(|i| i.measured_zmp.x = f64::INFINITY),
            ),
        ];
        for (name, set) in setters {
            let mut bad = input.clone();
            set(&mut bad);
            let err = block.step(&bad).unwrap_err();
            match err {
                SimplifiedError::NonFiniteInput { name: n } => assert_eq!(n, name),
                SimplifiedError::InvalidParameter { name: n, .. } => assert_eq!(n, name),
                other => panic!("{other:?}"),
            }
            assert_eq!(*block.output(), held, "{kind:?} {name}: output changed");
        }
        // The state did not move either: the next good step gives the same as a fresh controller's
        // second step.
        let mut fresh = SimplifiedController::new(&config, Duration::from_millis(10)).unwrap();
        fresh.step(&input).unwrap();
        let a = *fresh.step(&input).unwrap();
        let b = *block.step(&input).unwrap();
        assert_eq!(a.desired_zmp, b.desired_zmp);
        assert_eq!(a.com_position, b.com_position);
        assert_eq!(a.diagnostics.integral_term, b.diagnostics.integral_term);
    }
}

#[test]
fn horizon_errors_and_short_horizons() {
    let config = SimplifiedConfig {
        dcm_controller: DcmControllerKind::Predictive,
        ..Default::default()
    };
    let mut block = SimplifiedController::new(&config, Duration::from_millis(10)).unwrap();
    let mut input = good_input(&block);
    let sample = input.horizon.samples()[0];
    assert_eq!(
        input.horizon.push(sample),
        Err(SimplifiedError::HorizonFull { capacity: 201 })
    );
    // A horizon longer than the plan: the plan's last sample is held.
    input.horizon.clear();
    for _ in 0..17 {
        input.horizon.push(sample).unwrap();
    }
    let out = block.step(&input).unwrap();
    assert_eq!(out.diagnostics.mpc.held_samples, 201 - 17);
    assert!(out.desired_zmp.iter().all(|v| v.is_finite()));
    // An empty one is an error and holds the output.
    let held = *block.output();
    input.horizon.clear();
    assert_eq!(
        block.step(&input).unwrap_err(),
        SimplifiedError::EmptyHorizon
    );
    assert_eq!(*block.output(), held);
    // Non-finite horizon data.
    input
        .horizon
        .push(HorizonSample {
            dcm_position: Vector2::new(f64::NAN, 0.0),
            ..sample
        })
        .unwrap();
    assert!(matches!(
        block.step(&input),
        Err(SimplifiedError::NonFiniteInput {
            name: "horizon.dcm_position"
        })
    ));
}

#[test]
fn empty_or_degenerate_polygons_are_rejected() {
    let p = |x: f64, y: f64| Vector2::new(x, y);
    assert!(SupportPolygon::convex_hull(&[]).is_err());
    assert!(SupportPolygon::convex_hull(&[p(0.0, 0.0), p(1.0, 0.0)]).is_err());
    assert!(SupportPolygon::convex_hull(&[p(0.0, 0.0), p(1.0, 0.0), p(2.0, 0.0)]).is_err());
    assert!(SupportPolygon::convex_hull(&[p(0.0, 0.0), p(0.0, 0.0), p(0.0, 0.0)]).is_err());
    assert!(SupportPolygon::convex_hull(&[p(0.0, 0.0), p(1e-6, 0.0), p(0.0, 1e-6)]).is_err());
    assert!(SupportPolygon::convex_hull(&[p(0.0, 0.0), p(1.0, 0.0), p(f64::NAN, 1.0)]).is_err());
    assert!(SupportPolygon::rectangle(0.0, 0.0, 0.0, 1.0).is_err());
    assert!(feet_support_polygon(&[]).is_err());
    // serde goes through the same validation
    assert!(serde_json::from_str::<SupportPolygon>("[[0,0],[1,0],[2,0]]").is_err());
    let ok: SupportPolygon = serde_json::from_str("[[0,0],[1,0],[1,1],[0,1],[0.5,0.5]]").unwrap();
    assert_eq!(ok.len(), 4);
}

#[test]
fn measured_zmp_needs_a_loaded_foot() {
    let loaded = FootWrench {
        wrench: Vector6::new(0.0, 0.0, 100.0, 0.0, 0.0, 0.0),
        point: Vector3::zeros(),
    };
    let light = FootWrench {
        wrench: Vector6::new(0.0, 0.0, 0.5, 0.0, 0.0, 0.0),
        point: Vector3::zeros(),
    };
    assert!(measured_zmp(&[loaded], 0.0, 10.0).is_ok());
    assert!(matches!(
        measured_zmp(&[light], 0.0, 10.0),
        Err(SimplifiedError::InsufficientNormalForce { .. })
    ));
    assert!(matches!(
        measured_zmp(&[], 0.0, 10.0),
        Err(SimplifiedError::InsufficientNormalForce { .. })
    ));
    let pulling = FootWrench {
        wrench: Vector6::new(0.0, 0.0, -100.0, 0.0, 0.0, 0.0),
        point: Vector3::zeros(),
    };
    assert!(measured_zmp(&[pulling], 0.0, 10.0).is_err());
    let nan = FootWrench {
        wrench: Vector6::new(f64::NAN, 0.0, 100.0, 0.0, 0.0, 0.0),
        point: Vector3::zeros(),
    };
    assert!(matches!(
        measured_zmp(&[nan], 0.0, 10.0),
        Err(SimplifiedError::NonFiniteInput { .. })
    ));
    assert!(measured_zmp(&[loaded], f64::NAN, 10.0).is_err());
    assert!(measured_zmp(&[loaded], 0.0, 0.0).is_err());
}

#[test]
fn configs_validate_and_reject_unknown_fields() {
    let config: SimplifiedConfig = toml::from_str(
        r#"
        dcm_controller = "predictive"
        [instantaneous]
        kp = 1.1
        [predictive]
        horizon = 1.5
        zmp_rate_reference = "zero"
        solver = "clarabel"
        [zmp_com]
        walking = { k_zmp = 3.0, k_com = 10.0 }
        transition_time = 0.1
        "#,
    )
    .unwrap();
    assert_eq!(config.dcm_controller, DcmControllerKind::Predictive);
    assert_eq!(config.instantaneous.kp, 1.1);
    assert_eq!(config.instantaneous.ki, 0.0);
    assert_eq!(config.predictive.horizon, 1.5);
    assert_eq!(config.predictive.solver, MpcSolverKind::Clarabel);
    assert_eq!(config.zmp_com.walking.k_com, 10.0);
    assert_eq!(config.zmp_com.standing, ZmpComConfig::default().standing);
    config.validate().unwrap();
    assert!(toml::from_str::<SimplifiedConfig>("dcm_controler = \"predictive\"").is_err());
    assert!(toml::from_str::<SimplifiedConfig>("[instantaneous]\nkd = 1.0").is_err());
    assert!(toml::from_str::<SimplifiedConfig>("dcm_controller = \"magic\"").is_err());
    assert!(toml::from_str::<SimplifiedConfig>("[zmp_com]\nwalking = { k_zmp = 1.0 }").is_err());
    let empty: SimplifiedConfig = toml::from_str("").unwrap();
    assert_eq!(empty, SimplifiedConfig::default());
    let bad = |f: &dyn Fn(&mut SimplifiedConfig)| {
        let mut c = SimplifiedConfig::default();
        f(&mut c);
        assert!(SimplifiedController::new(&c, Duration::from_millis(10)).is_err());
    };
    bad(&|c| c.instantaneous.kp = 0.9);
    bad(&|c| c.instantaneous.ki = -1.0);
    bad(&|c| c.instantaneous.integral_limit = f64::NAN);
    bad(&|c| c.zmp_com.walking.k_zmp = 0.0);
    bad(&|c| c.zmp_com.standing.k_com = 0.5);
    bad(&|c| c.zmp_com.transition_time = -0.1);
    bad(&|c| c.predictive.horizon = 0.0);
    bad(&|c| c.predictive.dcm_weight = -1.0);
    bad(&|c| c.predictive.max_iterations = 0);
    assert!(SimplifiedController::new(&SimplifiedConfig::default(), Duration::ZERO).is_err());
}
