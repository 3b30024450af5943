//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::sync::Arc;
use std::time::Duration;

use nalgebra::{DMatrix, DVector, Vector3};
use stride_model::{KinDyn, Model, RobotState};
use stride_sim::{
    ActuationConfig, ActuationMode, ContactSurfaceConfig, JointActuatorOverride, SensorConfig,
    SimConfig,
};

/// The default step period of the tests, 500 µs (2 kHz).
pub const PERIOD: Duration = Duration::from_micros(500);

/// The step period of a rate in Hz (whole nanoseconds).
pub fn period(rate_hz: u32) -> Duration {
    Duration::from_nanos(1_000_000_000 / u64::from(rate_hz))
}

/// `model` with no gravity.
pub fn weightless(model: &Model) -> Arc<Model> {
    let mut m = model.clone();
    m.set_gravity(Vector3::zeros())
        .expect("zero gravity is finite");
    Arc::new(m)
}

/// The default configuration with ideal sensors and actuators (no noise, quantisation, filter, delay,
/// friction or torque lag): for the tests that compare the readings with the physics.
pub fn ideal_config() -> SimConfig {
    SimConfig {
        sensors: SensorConfig::ideal(),
        actuation: ActuationConfig::ideal(),
        ..SimConfig::default()
    }
}

/// The bundled humanoid.
pub fn humanoid() -> Arc<Model> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../models/stride_humanoid.urdf"
    );
    Arc::new(Model::from_urdf_file(path).expect("bundled model loads"))
}

/// A homogeneous box `lx × ly × lz` of mass `m`, with a frame `bottom` at the centre of its lower face.
pub fn box_model(m: f64, lx: f64, ly: f64, lz: f64) -> Arc<Model> {
    let ixx = m * (ly * ly + lz * lz) / 12.0;
    let iyy = m * (lx * lx + lz * lz) / 12.0;
    let izz = m * (lx * lx + ly * ly) / 12.0;
    let urdf = format!(
        r#"<?xml version="1.0"?>
<robot name="box">
  <link name="box">
    <inertial><origin xyz="0 0 0" rpy="0 0 0"/><mass value="{m}"/>
      <inertia ixx="{ixx}" ixy="0" ixz="0" iyy="{iyy}" iyz="0" izz="{izz}"/></inertial>
  </link>
  <link name="bottom"/>
  <joint name="bottom_fixed" type="fixed">
    <origin xyz="0 0 {}" rpy="0 0 0"/><parent link="box"/><child link="bottom"/>
  </joint>
</robot>"#,
        -lz / 2.0
    );
    Arc::new(Model::from_urdf_str(&urdf).expect("box URDF loads"))
}

/// A config for a box of footprint `lx × ly` with its contact grid on the `bottom` frame.
pub fn box_config(lx: f64, ly: f64, grid: [usize; 2]) -> SimConfig {
    let mut c = ideal_config();
    c.contact.surfaces = vec![ContactSurfaceConfig {
        name: "bottom".into(),
        frame: "bottom".into(),
        length: lx,
        width: ly,
        grid,
        offset: [0.0; 3],
        ft_sensor: None,
    }];
    c.sensors.imu_frame = "box".into();
    c.fall.min_base_height = -1e9;
    c.fall.max_tilt = 10.0;
    c
}

/// Kinetic energy ½ νᵀ M ν and potential energy −m gᵀ c of a state.
pub fn energy(
    model: &Arc<Model>,
    state: &RobotState,
    gravity: nalgebra::Vector3<f64>,
) -> (f64, f64) {
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_gravity(gravity);
    kd.set_state(state).unwrap();
    let nv = model.nv();
    let mut m = DMatrix::zeros(nv, nv);
    kd.mass_matrix(&mut m).unwrap();
    let mut nu = DVector::zeros(nv);
    nu.rows_mut(0, 6).copy_from(&state.base_velocity);
    nu.rows_mut(6, model.dof())
        .copy_from(&state.joint_velocities);
    let kinetic = 0.5 * nu.dot(&(&m * &nu));
    let potential = -model.total_mass() * gravity.dot(&kd.com_position());
    (kinetic, potential)
}

/// Centroidal momentum `[p; l about the CoM]` and the CoM position of a state.
pub fn momentum(
    model: &Arc<Model>,
    state: &RobotState,
) -> (nalgebra::Vector6<f64>, nalgebra::Vector3<f64>) {
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_state(state).unwrap();
    (kd.centroidal_momentum(), kd.com_position())
}

/// A slightly knee-bent standing posture of the humanoid: hip pitch `a`, knee `2a`, ankle pitch `a`.
pub fn bent_knees(model: &Model, a: f64) -> DVector<f64> {
    let mut q = DVector::zeros(model.dof());
    for (name, v) in [
        ("l_hip_pitch", a),
        ("r_hip_pitch", a),
        ("l_knee", 2.0 * a),
        ("r_knee", 2.0 * a),
        ("l_ankle_pitch", a),
        ("r_ankle_pitch", a),
    ] {
        q[model.joint_index(name).expect("joint exists")] = v;
    }
    q
}

/// The override that puts `joint` in torque mode (every other field the default actuator's).
pub fn torque_mode(joint: &str) -> JointActuatorOverride {
    JointActuatorOverride {
        name: joint.into(),
        mode: Some(ActuationMode::Torque),
        kp: None,
        kd: None,
        effort_limit: None,
        damping: None,
        armature: None,
        coulomb_friction: None,
        torque_bandwidth: None,
    }
}
