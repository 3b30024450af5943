//! Shared test helpers: a small floating-base test model and random states.
#![allow(dead_code)]

use std::path::PathBuf;
use std::sync::Arc;

use nalgebra::{DVector, Isometry3, Translation3, UnitQuaternion, Vector3, Vector6};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use stride_model::{Model, RobotState};

/// A floating-base tree: torso (root) with a fixed-mounted head frame, two legs (revolute chains with a
/// fixed FT-sensor split and a massless sole frame), a prismatic "telescope" arm with a continuous wrist, and a
/// two-finger gripper where the second finger mimics the first.
pub const TEST_URDF: &str = r#"<?xml version="1.0"?>
<robot name="test_tree">
  <link name="torso">
    <inertial><origin xyz="0.01 0.0 0.1" rpy="0.1 0.2 0.3"/><mass value="5.0"/>
      <inertia ixx="0.10" ixy="0.01" ixz="0.0" iyy="0.08" iyz="0.005" izz="0.05"/></inertial>
    <visual><geometry><box size="0.1 0.1 0.1"/></geometry><material name="red"><texture/></material></visual>
  </link>
  <link name="head">
    <inertial><origin xyz="0 0 0.05"/><mass value="1.0"/>
      <inertia ixx="0.004" ixy="0" ixz="0" iyy="0.004" iyz="0" izz="0.003"/></inertial>
  </link>
  <joint name="neck_fixed" type="fixed"><parent link="torso"/><child link="head"/>
    <origin xyz="0 0 0.3" rpy="0 0 0.2"/></joint>
  <link name="l_thigh">
    <inertial><origin xyz="0 0 -0.15" rpy="0 0 0"/><mass value="2.0"/>
      <inertia ixx="0.02" ixy="0.001" ixz="0" iyy="0.02" iyz="0" izz="0.004"/></inertial>
  </link>
  <joint name="l_hip" type="revolute"><parent link="torso"/><child link="l_thigh"/>
    <origin xyz="0 0.1 -0.05" rpy="0.05 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-1.5" upper="1.5" effort="100" velocity="10"/></joint>
  <link name="l_shin_upper">
    <inertial><origin xyz="0 0.01 -0.1"/><mass value="1.0"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.002"/></inertial>
  </link>
  <joint name="l_knee" type="revolute"><parent link="l_thigh"/><child link="l_shin_upper"/>
    <origin xyz="0 0 -0.3"/><axis xyz="0.1 1 0"/>
    <limit lower="-2" upper="0" effort="100" velocity="10"/></joint>
  <link name="l_shin_lower">
    <inertial><origin xyz="0 0 -0.05"/><mass value="0.5"/>
      <inertia ixx="0.002" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.001"/></inertial>
  </link>
  <joint name="l_ft_sensor" type="fixed"><parent link="l_shin_upper"/><child link="l_shin_lower"/>
    <origin xyz="0 0 -0.15" rpy="0 0.1 0"/></joint>
  <gazebo reference="l_ft_sensor">
    <sensor name="l_ft" type="force_torque"><force_torque><frame>child</frame>
      <measure_direction>child_to_parent</measure_direction></force_torque></sensor>
  </gazebo>
  <link name="l_foot">
    <inertial><origin xyz="0.03 0 -0.02"/><mass value="0.7"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.003" iyz="0" izz="0.003"/></inertial>
  </link>
  <joint name="l_ankle" type="revolute"><parent link="l_shin_lower"/><child link="l_foot"/>
    <origin xyz="0 0 -0.1"/><axis xyz="1 0 0"/>
    <limit lower="-0.5" upper="0.5" effort="50" velocity="10"/></joint>
  <link name="l_sole"/>
  <joint name="l_sole_fixed" type="fixed"><parent link="l_foot"/><child link="l_sole"/>
    <origin xyz="0.02 0 -0.05" rpy="0 0 0.1"/></joint>
  <link name="r_thigh">
    <inertial><origin xyz="0 0 -0.15"/><mass value="2.0"/>
      <inertia ixx="0.02" ixy="0" ixz="0.001" iyy="0.02" iyz="0" izz="0.004"/></inertial>
  </link>
  <joint name="r_hip" type="revolute"><parent link="torso"/><child link="r_thigh"/>
    <origin xyz="0 -0.1 -0.05"/><axis xyz="0 0.6 0.8"/>
    <limit lower="-1.5" upper="1.5" effort="100" velocity="10"/></joint>
  <link name="r_foot">
    <inertial><origin xyz="0.03 0 -0.02"/><mass value="0.7"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.003" iyz="0" izz="0.003"/></inertial>
  </link>
  <joint name="r_knee" type="revolute"><parent link="r_thigh"/><child link="r_foot"/>
    <origin xyz="0 0 -0.4"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="0" effort="100" velocity="10"/></joint>
  <link name="r_sole"/>
  <joint name="r_sole_fixed" type="fixed"><parent link="r_foot"/><child link="r_sole"/>
    <origin xyz="0.02 0 -0.05"/></joint>
  <link name="arm">
    <inertial><origin xyz="0.1 0 0"/><mass value="1.5"/>
      <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  </link>
  <joint name="arm_slide" type="prismatic"><parent link="torso"/><child link="arm"/>
    <origin xyz="0.1 0 0.2" rpy="0 0.3 0"/><axis xyz="1 0 0"/>
    <limit lower="-0.1" upper="0.2" effort="200" velocity="1"/></joint>
  <link name="wrist">
    <inertial><origin xyz="0.02 0.01 0"/><mass value="0.3"/>
      <inertia ixx="0.0003" ixy="0" ixz="0" iyy="0.0002" iyz="0" izz="0.0002"/></inertial>
  </link>
  <joint name="wrist_roll" type="continuous"><parent link="arm"/><child link="wrist"/>
    <origin xyz="0.25 0 0"/><axis xyz="1 0 0"/></joint>
  <link name="finger_a">
    <inertial><origin xyz="0.02 0 0"/><mass value="0.05"/>
      <inertia ixx="0.00001" ixy="0" ixz="0" iyy="0.00002" iyz="0" izz="0.00002"/></inertial>
  </link>
  <joint name="finger_a_joint" type="prismatic"><parent link="wrist"/><child link="finger_a"/>
    <origin xyz="0.05 0.02 0"/><axis xyz="0 1 0"/>
    <limit lower="0" upper="0.04" effort="20" velocity="0.1"/></joint>
  <link name="finger_b">
    <inertial><origin xyz="0.02 0 0"/><mass value="0.05"/>
      <inertia ixx="0.00001" ixy="0" ixz="0" iyy="0.00002" iyz="0" izz="0.00002"/></inertial>
  </link>
  <joint name="finger_b_joint" type="prismatic"><parent link="wrist"/><child link="finger_b"/>
    <origin xyz="0.05 -0.02 0"/><axis xyz="0 -1 0"/>
    <limit lower="0" upper="0.04" effort="20" velocity="0.1"/>
    <mimic joint="finger_a_joint" multiplier="1.0" offset="0.0"/></joint>
  <link name="tool"/>
  <joint name="tool_fixed" type="fixed"><parent link="wrist"/><child link="tool"/>
    <origin xyz="0.1 0 0" rpy="0.3 0 0"/></joint>
</robot>
"#;

pub fn test_model() -> Arc<Model> {
    Arc::new(Model::from_urdf_str(TEST_URDF).expect("test model loads"))
}

/// The bundled humanoid (written by another helper).
pub fn humanoid_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../models/stride_humanoid.urdf")
}

pub fn humanoid_model() -> Option<Arc<Model>> {
    let path = humanoid_path();
    if path.exists() {
        Some(Arc::new(
            Model::from_urdf_file(&path).expect("bundled humanoid loads"),
        ))
    } else {
        None
    }
}

/// A random state: base pose within a few metres of the origin, joints within limits (±π for unbounded).
pub fn random_state(model: &Model, seed: u64) -> RobotState {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = model.dof();
    let pos = Vector3::new(
        rng.random_range(-2.0..2.0),
        rng.random_range(-2.0..2.0),
        rng.random_range(0.0..2.0),
    );
    let axis = Vector3::new(
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
        rng.random_range(-1.0..1.0),
    );
    let rot = UnitQuaternion::from_scaled_axis(axis * rng.random_range(0.0..3.0));
    let q = DVector::from_iterator(
        n,
        model.joints().iter().map(|j| {
            let lo = if j.lower.is_finite() { j.lower } else { -3.0 };
            let hi = if j.upper.is_finite() { j.upper } else { 3.0 };
            rng.random_range(lo..=hi)
        }),
    );
    let v = Vector6::from_iterator((0..6).map(|_| rng.random_range(-1.0..1.0)));
    let qd = DVector::from_iterator(n, (0..n).map(|_| rng.random_range(-2.0..2.0)));
    RobotState {
        base_pose: Isometry3::from_parts(Translation3::from(pos), rot),
        joint_positions: q,
        base_velocity: v,
        joint_velocities: qd,
    }
}

pub fn random_vector(n: usize, seed: u64, scale: f64) -> DVector<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    DVector::from_iterator(n, (0..n).map(|_| rng.random_range(-scale..scale)))
}
