//! TSID-Flex [Romualdi 2022, §9.2, eq. (9.2.12)]: with `flexible_joints`, the passive joints' torques are
//! the measured spring-damper torques (not decisions) and the solution still satisfies the whole equations
//! of motion (checked with stride-model's RNEA); the rigid TSID on the same state commands other torques on
//! them. Bad names and inputs are refused.

mod common;

use std::sync::Arc;
use std::time::Duration;

use common::*;
use nalgebra::DVector;
use stride_model::Model;
use stride_qp::QpStatus;
use stride_wbc::{Tsid, TsidConfig, WbcInput};

const PERIOD: Duration = Duration::from_millis(1);
const FLEX: [&str; 4] = [
    "l_hip_flex_pitch",
    "l_hip_flex_roll",
    "r_hip_flex_pitch",
    "r_hip_flex_roll",
];

fn soles() -> Vec<String> {
    vec!["l_sole".into(), "r_sole".into()]
}

fn flex_model() -> Arc<Model> {
    let path = format!(
        "{}/../../models/stride_humanoid_flex.urdf",
        env!("CARGO_MANIFEST_DIR")
    );
    Arc::new(Model::from_urdf_file(path).expect("flexible-hip model loads"))
}

/// The springs of the test, k N·m/rad and b = 2√k N·m·s/rad.
const K: f64 = 1000.0;

fn tsid(model: &Arc<Model>, flexible: bool) -> Tsid {
    let mut config = TsidConfig::default_for_bundled_model();
    if flexible {
        config.flexible_joints = FLEX.iter().map(|s| s.to_string()).collect();
    }
    Tsid::new(Arc::clone(model), config, PERIOD).unwrap()
}

/// Standing on both feet with deflected, moving hips; the passive torques `−k s − b ṡ` (k = 1000 N·m/rad,
/// b = 2√k) in the input.
fn deflected_input(model: &Arc<Model>) -> WbcInput {
    let mut q = default_posture(model);
    let deflection = [0.02, -0.01, 0.015, 0.008];
    for (name, s) in FLEX.iter().zip(deflection) {
        q[model.joint_index(name).unwrap()] = s;
    }
    let mut state = standing_state(model, &q);
    let mut rng = rng(7);
    for i in 0..model.dof() {
        state.joint_velocities[i] = 0.05 * rand::Rng::random_range(&mut rng, -1.0..1.0);
    }
    let mut input = references_at(model, &state);
    input.posture = Some(default_posture(model));
    let (k, b) = (K, 2.0 * K.sqrt());
    for name in FLEX {
        let j = model.joint_index(name).unwrap();
        input.flexible_torques[j] = -k * state.joint_positions[j] - b * state.joint_velocities[j];
    }
    input
}

#[test]
fn flexible_joints_get_their_passive_torque_and_the_motion_stays_consistent() {
    let model = flex_model();
    let input = deflected_input(&model);
    let mut flex = tsid(&model, true);
    let out = flex.step(&input).unwrap().clone();
    assert_eq!(out.report.status, QpStatus::Solved);
    assert!(!out.report.fallback);
    for name in FLEX {
        let j = model.joint_index(name).unwrap();
        assert!(
            (out.joint_torques[j] - input.flexible_torques[j]).abs() < 1e-7,
            "{name}: {} vs passive {}",
            out.joint_torques[j],
            input.flexible_torques[j]
        );
    }
    let residual = dynamics_residual(&model, &input.state, &soles(), &out);
    assert!(
        residual < 1e-7,
        "equations of motion violated by {residual}"
    );
    let dynamics = out.residuals.iter().find(|r| r.name == "dynamics").unwrap();
    assert!(dynamics.hard && dynamics.residual < 1e-7, "{dynamics:?}");

    // With the springs known, the rows hold the passive torque at the end of the period, advanced by the
    // chosen flexible acceleration: τ = τ^f − k h ṡ − (k h² + b h) s̈ (linearly implicit).
    let (k, b, h) = (K, 2.0 * K.sqrt(), PERIOD.as_secs_f64());
    flex.set_flexible_springs(&[(k, b); 4]).unwrap();
    let out = flex.step(&input).unwrap().clone();
    assert_eq!(out.report.status, QpStatus::Solved);
    for name in FLEX {
        let j = model.joint_index(name).unwrap();
        let advanced = input.flexible_torques[j]
            - k * h * input.state.joint_velocities[j]
            - (k * h * h + b * h) * out.accelerations[6 + j];
        assert!(
            (out.joint_torques[j] - advanced).abs() < 1e-7,
            "{name}: {} vs advanced passive {advanced}",
            out.joint_torques[j]
        );
    }
    let residual = dynamics_residual(&model, &input.state, &soles(), &out);
    assert!(
        residual < 1e-7,
        "equations of motion violated by {residual}"
    );

    // The rigid TSID treats the hips as motors: its torques there are not the springs'.
    let mut rigid = tsid(&model, false);
    let out = rigid.step(&input).unwrap();
    let differs = FLEX.iter().any(|name| {
        let j = model.joint_index(name).unwrap();
        (out.joint_torques[j] - input.flexible_torques[j]).abs() > 1.0
    });
    assert!(
        differs,
        "the rigid TSID happened to command the passive torques"
    );
}

#[test]
fn unknown_or_repeated_flexible_joints_and_bad_torques_are_refused() {
    let model = flex_model();
    let build = |names: &[&str]| {
        let mut config = TsidConfig::default_for_bundled_model();
        config.flexible_joints = names.iter().map(|s| s.to_string()).collect();
        match Tsid::new(Arc::clone(&model), config, PERIOD) {
            Ok(_) => panic!("{names:?} accepted"),
            Err(e) => e.to_string(),
        }
    };
    let err = build(&["no_hip"]);
    assert!(err.contains("no_hip"), "{err}");
    let err = build(&["l_hip_flex_roll", "l_hip_flex_roll"]);
    assert!(err.contains("twice"), "{err}");

    let mut flex = tsid(&model, true);
    let mut input = deflected_input(&model);
    input.flexible_torques[model.joint_index("r_hip_flex_roll").unwrap()] = f64::NAN;
    let err = flex.step(&input).unwrap_err().to_string();
    assert!(err.contains("r_hip_flex_roll"), "{err}");
    input.flexible_torques = DVector::zeros(3);
    assert!(flex.step(&input).is_err());
    assert!(flex.set_flexible_springs(&[(1.0, 1.0); 3]).is_err());
    assert!(flex.set_flexible_springs(&[(1.0, -1.0); 4]).is_err());
    assert!(flex.set_flexible_springs(&[(f64::NAN, 1.0); 4]).is_err());
}
