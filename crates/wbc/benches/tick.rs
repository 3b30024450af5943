//! Full ticks (task update + QP build + solve) of the QP-IK and the TSID, both backends, on the bundled
//! model and, when `STRIDE_ICUB_MODELS_DIR` points at a directory containing `iCubGazeboV2_7/model.urdf`,
//! on iCub v2.7; TSID-Flex (`flexible_joints`, the passive hips of `models/stride_humanoid_flex.urdf`);
//! TSID-Compliant (`contact_model = "compliant"`).
//!
//! `cargo bench -p stride-wbc --bench tick -- --warm-up-time 1 --measurement-time 2`

use std::sync::Arc;

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::{DVector, Isometry3, Translation3, UnitQuaternion, Vector2};
use stride_model::{KinDyn, Model, RobotState, VelocityRepresentation};
use stride_qp::Backend;
use stride_wbc::{
    bundled_posture, walking, FrameReference, IkConfig, InputLayout, JointRegularizationTaskConfig,
    QpIk, TaskConfig, Tsid, TsidConfig, WbcInput,
};

struct Robot {
    name: &'static str,
    model: Arc<Model>,
    left: &'static str,
    right: &'static str,
    torso: &'static str,
    posture: DVector<f64>,
}

fn bundled() -> Robot {
    bundled_from("stride_humanoid")
}

/// The bundled model `name` (`models/<name>.urdf`) at the bundled posture.
fn bundled_from(name: &'static str) -> Robot {
    let path = format!("{}/../../models/{name}.urdf", env!("CARGO_MANIFEST_DIR"));
    let model = Arc::new(Model::from_urdf_file(path).expect("bundled model"));
    let mut posture = DVector::zeros(model.dof());
    for (name, v) in bundled_posture() {
        if let Some(i) = model.joint_index(&name) {
            posture[i] = v;
        }
    }
    Robot {
        name,
        model,
        left: "l_sole",
        right: "r_sole",
        torso: "chest",
        posture,
    }
}

fn icub() -> Option<Robot> {
    let dir = std::env::var("STRIDE_ICUB_MODELS_DIR").ok()?;
    let path = format!("{dir}/iCubGazeboV2_7/model.urdf");
    let model = Arc::new(Model::from_urdf_file(&path).ok()?);
    // iCub v2.7 posture of the walking controller (degrees): legs 5.08, 0.41, −0.13, −45.25, −26.45, −0.35
    let mut posture = DVector::zeros(model.dof());
    let deg = std::f64::consts::PI / 180.0;
    for side in ["l", "r"] {
        for (j, v) in [
            ("hip_pitch", 5.082),
            ("hip_roll", 0.406),
            ("hip_yaw", -0.131),
            ("knee", -45.249),
            ("ankle_pitch", -26.454),
            ("ankle_roll", -0.351),
            ("shoulder_pitch", -7.0),
            ("shoulder_roll", 22.0),
            ("shoulder_yaw", 11.0),
            ("elbow", 30.0),
        ] {
            if let Some(i) = model.joint_index(&format!("{side}_{j}")) {
                posture[i] = v * deg;
            }
        }
    }
    let torso = if model.frame_id("chest").is_some() {
        "chest"
    } else {
        "root_link"
    };
    Some(Robot {
        name: "iCubGazeboV2_7",
        model,
        left: "l_sole",
        right: "r_sole",
        torso,
        posture,
    })
}

fn posture_map(robot: &Robot) -> std::collections::BTreeMap<String, f64> {
    robot
        .model
        .joints()
        .iter()
        .enumerate()
        .map(|(i, j)| (j.name.clone(), robot.posture[i]))
        .collect()
}

fn adapt<'a>(tasks: impl Iterator<Item = &'a mut TaskConfig>, robot: &Robot) {
    for t in tasks {
        match t {
            TaskConfig::Se3(c) if c.frame == "l_sole" => c.frame = robot.left.into(),
            TaskConfig::Se3(c) if c.frame == "r_sole" => c.frame = robot.right.into(),
            TaskConfig::So3(c) => c.frame = robot.torso.into(),
            TaskConfig::Contact(c) if c.frame == "l_sole" => c.frame = robot.left.into(),
            TaskConfig::Contact(c) if c.frame == "r_sole" => c.frame = robot.right.into(),
            TaskConfig::JointRegularization(JointRegularizationTaskConfig {
                posture,
                joint_weights,
                ..
            }) => {
                *posture = posture_map(robot);
                joint_weights.clear();
            }
            _ => {}
        }
    }
}

/// Standing input at the robot's posture, CoM reference 1 cm off (the QPs do work every tick).
fn input(robot: &Robot) -> WbcInput {
    let model = &robot.model;
    let mut state = RobotState::zero(model);
    state.joint_positions.copy_from(&robot.posture);
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_representation(VelocityRepresentation::Mixed);
    kd.set_state(&state).unwrap();
    // base placed so that the left sole is flat on z = 0 (iCub's root_link is yawed by π and the
    // walking posture pitches the feet)
    let l = kd.frame_pose(model.frame_id(robot.left).unwrap());
    let (_, _, yaw) = l.rotation.euler_angles();
    let flat = Isometry3::from_parts(
        Translation3::new(l.translation.x, l.translation.y, 0.0),
        UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
    );
    state.base_pose = flat * l.inverse() * state.base_pose;
    kd.set_state(&state).unwrap();
    let layout = InputLayout::new(
        [walking::LEFT_FOOT, walking::RIGHT_FOOT, walking::TORSO],
        [walking::LEFT_FOOT, walking::RIGHT_FOOT],
    );
    let mut input = WbcInput::new(state, Arc::new(layout));
    input.com_position = kd.com_position();
    input.com_position.x += 0.01;
    let pose = |frame: &str| kd.frame_pose(model.frame_id(frame).unwrap());
    let torso = FrameReference::still(Isometry3::from_parts(
        Translation3::identity(),
        pose(robot.torso).rotation,
    ));
    for (name, reference) in [
        (walking::LEFT_FOOT, FrameReference::still(pose(robot.left))),
        (
            walking::RIGHT_FOOT,
            FrameReference::still(pose(robot.right)),
        ),
        (walking::TORSO, torso),
    ] {
        input.set_frame_reference(name, reference).unwrap();
    }
    input.desired_zmp = Some(Vector2::new(input.com_position.x, input.com_position.y));
    input
}

fn bench(c: &mut Criterion) {
    let mut robots = vec![bundled()];
    robots.extend(icub());
    for robot in &robots {
        let input = input(robot);
        for backend in [Backend::ActiveSet, Backend::Clarabel] {
            let tag = match backend {
                Backend::ActiveSet => "active_set",
                Backend::Clarabel => "clarabel",
            };
            let mut config = IkConfig::default_for_bundled_model();
            config.qp.backend = backend;
            // measured feedback: every tick solves the same problem (warm-started), as a velocity-
            // controlled robot standing still would
            config.feedback = stride_wbc::IkFeedback::Measured;
            adapt(config.tasks.iter_mut(), robot);
            let mut ik = QpIk::new(
                Arc::clone(&robot.model),
                config,
                std::time::Duration::from_millis(2),
            )
            .expect("IK builds");
            ik.step(&input).unwrap();
            c.bench_function(&format!("qp_ik/{}/{tag}", robot.name), |b| {
                b.iter(|| ik.step(&input).unwrap().report.iterations)
            });
            let report = ik.step(&input).unwrap().report;
            assert!(
                report.status.is_success() && !report.fallback,
                "{}: the benchmarked IK tick must be a nominal solve: {report:?}",
                robot.name
            );
            let mut config = TsidConfig::default_for_bundled_model();
            config.qp.backend = backend;
            adapt(config.tasks.iter_mut(), robot);
            let mut tsid = Tsid::new(
                Arc::clone(&robot.model),
                config,
                std::time::Duration::from_millis(1),
            )
            .expect("TSID builds");
            tsid.step(&input).unwrap();
            c.bench_function(&format!("tsid/{}/{tag}", robot.name), |b| {
                b.iter(|| tsid.step(&input).unwrap().report.iterations)
            });
            let report = tsid.step(&input).unwrap().report;
            assert!(
                report.status.is_success() && !report.fallback,
                "{}: the benchmarked TSID tick must be a nominal solve: {report:?}",
                robot.name
            );
        }
    }
}

/// TSID-Flex on the flexible-hip humanoid: the four passive hips (k = 2085 N·m/rad, b = 2√k), deflected.
fn bench_tsid_flex(c: &mut Criterion) {
    let robot = bundled_from("stride_humanoid_flex");
    let mut input = input(&robot);
    let flex = [
        "l_hip_flex_pitch",
        "l_hip_flex_roll",
        "r_hip_flex_pitch",
        "r_hip_flex_roll",
    ];
    let (k, b) = (2085.0, 2.0 * 2085f64.sqrt());
    for name in flex {
        input.flexible_torques[robot.model.joint_index(name).unwrap()] = -k * 0.01;
    }
    let mut config = TsidConfig::default_for_bundled_model();
    config.flexible_joints = flex.iter().map(|s| s.to_string()).collect();
    let mut tsid = Tsid::new(
        Arc::clone(&robot.model),
        config,
        std::time::Duration::from_millis(2),
    )
    .expect("TSID-Flex builds");
    tsid.set_flexible_springs(&[(k, b); 4]).unwrap();
    tsid.step(&input).unwrap();
    c.bench_function("tsid_flex/stride_humanoid_flex/active_set", |bench| {
        bench.iter(|| tsid.step(&input).unwrap().report.iterations)
    });
    let report = tsid.step(&input).unwrap().report;
    assert!(
        report.status.is_success() && !report.fallback,
        "the benchmarked TSID-Flex tick must be a nominal solve: {report:?}"
    );
}

/// TSID-Compliant (`contact_model = "compliant"`, the walking preset plus a hard angular momentum task) on
/// the bundled humanoid standing on `k = 1e6 N/m³` with the soles' measured wrenches at their share of the
/// weight.
fn bench_tsid_compliant(c: &mut Criterion) {
    let robot = bundled();
    let mut input = input(&robot);
    let weight = robot.model.total_mass() * 9.81 / 2.0;
    for name in [walking::LEFT_FOOT, walking::RIGHT_FOOT] {
        let id = input.contact_id(name).unwrap();
        input.contact_mut(id).unwrap().measured_wrench[2] = weight;
    }
    let mut config = TsidConfig::default_for_bundled_model();
    config.contact_model = stride_wbc::ContactModel::Compliant;
    config.tasks.push(TaskConfig::AngularMomentum(
        stride_wbc::AngularMomentumTaskConfig {
            name: "angular_momentum".into(),
            kp: 10.0,
            reference_joints: Vec::new(),
            reference_frames: Vec::new(),
            priority: stride_wbc::Priority::Hard,
            weight: None,
        },
    ));
    let mut tsid = Tsid::new(
        Arc::clone(&robot.model),
        config,
        std::time::Duration::from_millis(2),
    )
    .expect("TSID-Compliant builds");
    tsid.step(&input).unwrap();
    c.bench_function("tsid_compliant/stride_humanoid/active_set", |bench| {
        bench.iter(|| tsid.step(&input).unwrap().report.iterations)
    });
    let report = tsid.step(&input).unwrap().report;
    assert!(
        report.status.is_success() && !report.fallback,
        "the benchmarked TSID-Compliant tick must be a nominal solve: {report:?}"
    );
}

criterion_group!(benches, bench, bench_tsid_flex, bench_tsid_compliant);
criterion_main!(benches);
