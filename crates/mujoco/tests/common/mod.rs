//! Shared set-up of the MuJoCo plant tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use nalgebra::{DVector, Isometry3, Translation3, Vector3};
use stride_model::{KinDyn, Model, RobotState};
use stride_mujoco::{MujocoConfig, MujocoOutput, MujocoRobot, PlantSetup};
use stride_sim::{ActuationConfig, SensorConfig, SimConfig, SimInput};

/// The bundled humanoid's URDF.
pub fn humanoid_urdf() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/stride_humanoid.urdf")
}

/// The bundled humanoid's crouched posture (`stride_model::bundled::POSTURE`).
pub fn crouch(model: &Model) -> DVector<f64> {
    let mut q = DVector::zeros(model.dof());
    for (name, v) in stride_model::bundled::POSTURE {
        q[model.joint_index(name).expect("joint")] = v;
    }
    q
}

/// iCub's crouch of `configs/robots/icub_v2_7.toml` (knees bend negative).
pub fn icub_crouch(model: &Model) -> DVector<f64> {
    let mut q = DVector::zeros(model.dof());
    for (name, v) in [
        ("l_hip_pitch", 0.35),
        ("l_knee", -0.7),
        ("l_ankle_pitch", -0.35),
        ("r_hip_pitch", 0.35),
        ("r_knee", -0.7),
        ("r_ankle_pitch", -0.35),
        ("l_shoulder_pitch", -0.2),
        ("l_shoulder_roll", 0.25),
        ("l_elbow", 0.5),
        ("r_shoulder_pitch", -0.2),
        ("r_shoulder_roll", 0.25),
        ("r_elbow", 0.5),
    ] {
        q[model.joint_index(name).expect("joint")] = v;
    }
    q
}

/// Ideal sensors and actuators with the given servo gains (exact readings, no delays, no friction).
pub fn ideal_sim(kp: f64, kd: f64) -> SimConfig {
    let mut sim = SimConfig {
        actuation: ActuationConfig::ideal(),
        sensors: SensorConfig::ideal(),
        ..SimConfig::default()
    };
    sim.actuation.default.kp = kp;
    sim.actuation.default.kd = kd;
    sim
}

/// The plant on `urdf` at 2 kHz with the default MuJoCo parameters.
pub fn plant(model: &Arc<Model>, urdf: &Path, sim: &SimConfig, soles: [&str; 2]) -> MujocoRobot {
    MujocoRobot::new(
        Arc::clone(model),
        &PlantSetup {
            urdf,
            sim,
            mujoco: &MujocoConfig::default(),
            soles,
            period: Duration::from_micros(500),
            inertias_from_model: false,
        },
    )
    .expect("MuJoCo plant")
}

/// The robot at joint positions `q` with the left sole level and the lowest sole on `z = 0`.
pub fn standing(model: &Arc<Model>, q: &DVector<f64>) -> RobotState {
    let mut state = RobotState::zero(model);
    state.joint_positions.copy_from(q);
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_state(&state).expect("state");
    let left = model.frame_id("l_sole").expect("l_sole");
    let right = model.frame_id("r_sole").expect("r_sole");
    state.base_pose = Isometry3::from_parts(
        Translation3::identity(),
        kd.frame_pose(left).rotation.inverse(),
    );
    kd.set_state(&state).expect("state");
    let low = kd
        .frame_pose(left)
        .translation
        .z
        .min(kd.frame_pose(right).translation.z);
    state.base_pose.translation.vector -= Vector3::new(0.0, 0.0, low);
    state
}

/// A free box `size` (m) of `mass` (kg) with a `sole` frame at the centre of its bottom face, as a URDF file
/// in the temporary folder; its principal inertias are a homogeneous box's, or all `inertia` (kg·m²).
pub fn box_urdf(name: &str, mass: f64, size: [f64; 3], inertia: Option<f64>) -> PathBuf {
    let [x, y, z] = size;
    let i = |a: f64, b: f64| inertia.unwrap_or(mass * (a * a + b * b) / 12.0);
    let text = format!(
        r#"<robot name="{name}">
  <link name="box">
    <inertial><origin xyz="0 0 0"/><mass value="{mass}"/>
      <inertia ixx="{}" ixy="0" ixz="0" iyy="{}" iyz="0" izz="{}"/></inertial>
    <collision><origin xyz="0 0 0"/><geometry><box size="{x} {y} {z}"/></geometry></collision>
  </link>
  <link name="sole"/>
  <joint name="sole_fixed_joint" type="fixed"><origin xyz="0 0 {}"/><parent link="box"/><child link="sole"/></joint>
</robot>"#,
        i(y, z),
        i(x, z),
        i(x, y),
        -z / 2.0
    );
    let path =
        std::env::temp_dir().join(format!("stride_mujoco_{name}_{}.urdf", std::process::id()));
    std::fs::write(&path, text).expect("write URDF");
    path
}

/// Holds `q` for 2 s (4000 steps at 2 kHz) and checks that the robot stands on both soles with its weight
/// on them: no fall, Σ f_z = m g within 0.1 % (`model`'s mass). Returns the last output.
pub fn stands_with_its_weight(
    robot: &mut MujocoRobot,
    model: &Model,
    q: &DVector<f64>,
) -> MujocoOutput {
    let input = SimInput::hold(q);
    for _ in 0..4000 {
        robot.step(&input).expect("step");
    }
    let out = robot.output().clone();
    assert!(!out.fallen && out.sole_contact == [true, true]);
    let weight = model.total_mass() * 9.81;
    let fz = out.sole_wrenches[0][2] + out.sole_wrenches[1][2];
    assert!(
        (fz - weight).abs() < 1e-3 * weight,
        "Σ f_z {fz} N vs m g {weight} N"
    );
    out
}
