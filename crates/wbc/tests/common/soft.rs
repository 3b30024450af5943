//! Fixtures of the soft-ground tests and bench: the bundled humanoid's sole, a ground of Table 8.1
//! [Romualdi 2022], a stance state, estimator settings, and a box whose bottom face is that sole, simulated
//! by stride-sim.
#![allow(dead_code)]

use std::sync::Arc;

use nalgebra::{Rotation3, Vector3, Vector6};
use stride_model::{Model, RobotState};
use stride_sim::{
    ContactSurfaceConfig, GaussianNoise, GroundPatchConfig, SimConfig, SimInput, SimRobot,
};
use stride_wbc::{EstimatorSettings, GroundParameters, SoleGeometry, SoleState};

/// The bundled humanoid's sole, 0.20 × 0.09 m.
pub const SOLE: SoleGeometry = SoleGeometry {
    length: 0.2,
    width: 0.09,
};

/// Table 8.1's `k = 1e6 N/m³`, `b = 1e4 N·s/m³`.
pub const GROUND: GroundParameters = GroundParameters {
    stiffness: 1e6,
    damping: 1e4,
};

/// The box's sole frame below its centre, m.
pub const SOLE_DROP: f64 = 0.025;

/// A flat sole at rest at `position`, which is also its zero-force pose.
pub fn at_rest(position: Vector3<f64>) -> SoleState {
    SoleState {
        position,
        rotation: Rotation3::identity(),
        linear_velocity: Vector3::zeros(),
        angular_velocity: Vector3::zeros(),
        rest_position: position,
        rest_rotation: Rotation3::identity(),
    }
}

/// A sole sunk 1 cm, slightly tilted and moving, resting at the origin.
pub fn stance_sample() -> SoleState {
    SoleState {
        position: Vector3::new(0.01, 0.0, -0.01),
        rotation: Rotation3::new(Vector3::new(0.02, -0.03, 0.1)),
        linear_velocity: Vector3::new(0.01, 0.0, -0.02),
        angular_velocity: Vector3::new(0.1, 0.2, 0.0),
        rest_position: Vector3::zeros(),
        rest_rotation: Rotation3::identity(),
    }
}

/// Estimator settings starting from stride-sim's rigid floor (3e7, 3e5) with that much uncertainty and an
/// F/T noise of 2 N, 0.2 N·m.
pub fn rigid_guess_settings() -> EstimatorSettings {
    EstimatorSettings {
        initial: GroundParameters {
            stiffness: 3e7,
            damping: 3e5,
        },
        initial_std: [3e7, 3e5],
        wrench_std: [2.0, 0.2],
    }
}

/// `[a; b]`.
pub fn join(a: &Vector3<f64>, b: &Vector3<f64>) -> Vector6<f64> {
    Vector6::new(a.x, a.y, a.z, b.x, b.y, b.z)
}

/// A box of `mass` (kg) and diagonal inertia `inertia` (kg m²) with a `bottom` frame [`SOLE_DROP`] below its
/// centre.
pub fn box_model(mass: f64, inertia: [f64; 3]) -> Arc<Model> {
    let [ixx, iyy, izz] = inertia;
    let urdf = format!(
        r#"<?xml version="1.0"?>
<robot name="box">
  <link name="box">
    <inertial><origin xyz="0 0 0" rpy="0 0 0"/><mass value="{mass}"/>
      <inertia ixx="{ixx}" ixy="0" ixz="0" iyy="{iyy}" iyz="0" izz="{izz}"/></inertial>
  </link>
  <link name="bottom"/>
  <joint name="bottom_fixed" type="fixed">
    <origin xyz="0 0 -{SOLE_DROP}" rpy="0 0 0"/><parent link="box"/><child link="bottom"/>
  </joint>
</robot>"#
    );
    Arc::new(Model::from_urdf_str(&urdf).expect("box URDF loads"))
}

/// A simulator config with one contact surface, [`SOLE`] on `bottom` with a `grid`, and no fall detection.
pub fn box_sim_config(grid: [usize; 2]) -> SimConfig {
    let mut config = SimConfig::default();
    config.contact.surfaces = vec![ContactSurfaceConfig {
        name: "sole".into(),
        frame: "bottom".into(),
        length: SOLE.length,
        width: SOLE.width,
        grid,
        offset: [0.0; 3],
        ft_sensor: None,
    }];
    config.sensors.imu_frame = "box".into();
    config.fall.min_base_height = -1e9;
    config.fall.max_tilt = 10.0;
    config
}

/// The sole's pose and mixed twist in a box state, with the rest pose of `rest`.
pub fn sole_state(state: &RobotState, rest: &SoleState) -> SoleState {
    let rotation = state.base_pose.rotation.to_rotation_matrix();
    let arm = rotation * Vector3::new(0.0, 0.0, -SOLE_DROP);
    let w: Vector3<f64> = state.base_velocity.fixed_rows::<3>(3).into_owned();
    SoleState {
        position: state.base_pose.translation.vector + arm,
        rotation,
        linear_velocity: state.base_velocity.fixed_rows::<3>(0) + w.cross(&arm),
        angular_velocity: w,
        rest_position: rest.rest_position,
        rest_rotation: rest.rest_rotation,
    }
}

/// Half the bundled humanoid's mass: the box of the ground estimator's simulator tests, kg.
pub const BOX_MASS: f64 = 16.0;

/// The three patches of Table 8.1's grounds along world x, `(x_min, x_max, k, b)`.
pub const PATCHES: [(f64, f64, f64, f64); 3] = [
    (0.0, 1.0, 2e6, 1e4),
    (1.0, 2.0, 8e5, 1e3),
    (2.0, 3.0, 1e6, 1e4),
];

/// Simulator steps per estimator update (2 kHz simulation, 500 Hz estimator as the whole-body controller).
pub const DECIMATION: usize = 4;

/// [`box_sim_config`] with a `grid` over the ground of [`PATCHES`].
pub fn box_on_patches_config(grid: [usize; 2]) -> SimConfig {
    let mut config = box_sim_config(grid);
    config.ground.patches = PATCHES
        .iter()
        .map(|&(x_min, x_max, k, b)| GroundPatchConfig::normal(x_min, x_max, k, b))
        .collect();
    config
}

/// Steps the box `sim` [`DECIMATION`] times (one estimator period, 2 ms) and returns its state and its
/// sole's wrench plus Gaussian noise of `wrench_std` (`[force (N), torque (N·m)]`).
pub fn estimator_sample(
    sim: &mut SimRobot,
    noise: &mut GaussianNoise,
    wrench_std: [f64; 2],
) -> (RobotState, Vector6<f64>) {
    let input = SimInput::zeros(0);
    for _ in 0..DECIMATION {
        sim.step(&input).expect("sim step");
    }
    let out = sim.output();
    let mut wrench = out.surfaces[0].wrench;
    for (i, w) in wrench.iter_mut().enumerate() {
        *w += noise.sample(wrench_std[i / 3]);
    }
    (out.state.clone(), wrench)
}
