//! Shared test helpers: a seeded Gaussian generator and synthetic IMU/kinematics data from a known
//! trajectory of the IMU and the feet.
#![allow(dead_code)]

use nalgebra::{Matrix3, Rotation3, Vector3, Vector6};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Seeded standard-normal samples (Box–Muller).
pub struct Gauss(ChaCha8Rng);

impl Gauss {
    pub fn new(seed: u64) -> Self {
        Self(ChaCha8Rng::seed_from_u64(seed))
    }
    pub fn sample(&mut self) -> f64 {
        let u1: f64 = self.0.random::<f64>().max(1e-300);
        let u2: f64 = self.0.random::<f64>();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }
    pub fn vec3(&mut self, sigma: &[f64; 3]) -> Vector3<f64> {
        Vector3::new(
            sigma[0] * self.sample(),
            sigma[1] * self.sample(),
            sigma[2] * self.sample(),
        )
    }
}

/// The true state at one instant.
#[derive(Clone, Copy, Debug)]
pub struct Truth {
    pub rot: Matrix3<f64>,
    pub vel: Vector3<f64>,
    pub pos: Vector3<f64>,
    /// Linear acceleration of the IMU, world.
    pub acc: Vector3<f64>,
    /// Angular velocity, IMU frame.
    pub omega: Vector3<f64>,
    pub feet: [Vector3<f64>; 2],
    /// Sole orientations, `world_R_sole`: flat, with the initial heading of the IMU (constant, the feet do
    /// not turn).
    pub foot_rot: [Matrix3<f64>; 2],
    pub stance: [bool; 2],
}

/// A walking trajectory: the IMU moves at a constant forward speed with a lateral sway and a constant body
/// angular velocity (a slow turn plus nothing else), the feet alternate with a fixed step period; a foot in
/// stance is fixed, a swing foot travels on a straight line with a 5 cm bump. `speed = 0` stands still on
/// both feet.
#[derive(Clone, Debug)]
pub struct Walk {
    pub speed: f64,
    pub sway: f64,
    pub step_period: f64,
    pub double_support: f64,
    pub height: f64,
    pub rot0: Matrix3<f64>,
    pub omega: Vector3<f64>,
    /// Optional slip: (foot, start time, duration, displacement) of a foot in stance.
    pub slip: Option<(usize, f64, f64, Vector3<f64>)>,
}

impl Walk {
    pub fn standing() -> Self {
        Self {
            speed: 0.0,
            sway: 0.0,
            step_period: 0.8,
            double_support: 0.2,
            height: 0.64,
            rot0: *Rotation3::from_euler_angles(0.02, -0.03, 0.1).matrix(),
            omega: Vector3::zeros(),
            slip: None,
        }
    }

    pub fn walking(speed: f64) -> Self {
        Self {
            speed,
            sway: 0.03,
            ..Self::standing()
        }
    }

    /// Orientation of both soles: a rotation about z by the initial heading of the IMU.
    pub fn foot_rot(&self) -> Matrix3<f64> {
        let x = self.rot0.column(0);
        *Rotation3::from_axis_angle(&Vector3::z_axis(), x.y.atan2(x.x)).matrix()
    }

    /// Foothold of foot `i` for its `k`-th stance (`k` counted so that the stance covers the body's
    /// position in the middle of that stance).
    fn foothold(&self, foot: usize, k: i64) -> Vector3<f64> {
        let y = if foot == 0 { 0.075 } else { -0.075 };
        // Left stances are centred on t = 2k T, right ones on (2k + 1) T.
        let centre = (2 * k + foot as i64) as f64 * self.step_period;
        Vector3::new(self.speed * centre, y, 0.0)
    }

    pub fn at(&self, t: f64) -> Truth {
        let w = 2.0 * std::f64::consts::PI / (2.0 * self.step_period);
        let pos = Vector3::new(self.speed * t, self.sway * (w * t).sin(), self.height);
        let vel = Vector3::new(self.speed, self.sway * w * (w * t).cos(), 0.0);
        let acc = Vector3::new(0.0, -self.sway * w * w * (w * t).sin(), 0.0);
        let rot = self.rot0 * Rotation3::from_scaled_axis(self.omega * t).matrix();
        let mut feet = [Vector3::zeros(); 2];
        let mut stance = [true; 2];
        if self.speed != 0.0 {
            for (foot, (d, s)) in feet.iter_mut().zip(stance.iter_mut()).enumerate() {
                // Phase of this foot: stance lasts T + double support, centred on its footholds.
                let period = 2.0 * self.step_period;
                let shifted = t - foot as f64 * self.step_period;
                let k = (shifted / period).round() as i64;
                let local = shifted - k as f64 * period; // in [−T, T]
                let half_stance = 0.5 * (self.step_period + self.double_support);
                if local.abs() <= half_stance {
                    *d = self.foothold(foot, k);
                    *s = true;
                } else {
                    let (from, to, u) = if local > 0.0 {
                        let u = (local - half_stance) / (period - 2.0 * half_stance);
                        (self.foothold(foot, k), self.foothold(foot, k + 1), u)
                    } else {
                        let u = (local + period - half_stance) / (period - 2.0 * half_stance);
                        (self.foothold(foot, k - 1), self.foothold(foot, k), u)
                    };
                    *d = from
                        + (to - from) * u
                        + Vector3::new(0.0, 0.0, 0.05 * (std::f64::consts::PI * u).sin());
                    *s = false;
                }
            }
        } else {
            feet = [self.foothold(0, 0), self.foothold(1, 0)];
        }
        if let Some((foot, start, duration, disp)) = self.slip {
            if t >= start {
                let u = ((t - start) / duration).min(1.0);
                feet[foot] += disp * u;
            }
        }
        Truth {
            rot,
            vel,
            pos,
            acc,
            omega: self.omega,
            feet,
            foot_rot: [self.foot_rot(); 2],
            stance,
        }
    }
}

/// IMU sample of a truth: gyro and proper acceleration with biases and per-sample noise.
pub fn imu_sample(
    truth: &Truth,
    gravity: &Vector3<f64>,
    gyro_bias: &Vector3<f64>,
    acc_bias: &Vector3<f64>,
    gyro_sigma: &[f64; 3],
    acc_sigma: &[f64; 3],
    rng: &mut Gauss,
) -> (Vector3<f64>, Vector3<f64>) {
    let gyro = truth.omega + gyro_bias + rng.vec3(gyro_sigma);
    let acc = truth.rot.transpose() * (truth.acc - gravity) + acc_bias + rng.vec3(acc_sigma);
    (gyro, acc)
}

/// Rotation angle between two rotation matrices \[rad\].
pub fn angle_between(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    Rotation3::from_matrix_unchecked(a.transpose() * b).angle()
}

/// Tilt error: angle between the gravity directions seen in the two IMU frames \[rad\] (roll and pitch).
pub fn tilt_between(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    let z = Vector3::z();
    (a.transpose() * z).angle(&(b.transpose() * z))
}

/// Heading error: angle between the two frames' x axes projected on the ground \[rad\] (yaw).
pub fn yaw_between(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    let xa = a.column(0).xy();
    let xb = b.column(0).xy();
    (xa.x * xb.y - xa.y * xb.x).atan2(xa.dot(&xb)).abs()
}

use std::sync::Arc;
use stride_estimation::{EstimatorInput, ImuReading};
use stride_model::{ExternalWrench, KinDyn, Model, RobotState};

pub fn bundled_model() -> Arc<Model> {
    let path = format!(
        "{}/../../models/stride_humanoid.urdf",
        env!("CARGO_MANIFEST_DIR")
    );
    Arc::new(Model::from_urdf_file(path).expect("bundled model"))
}

/// A standing state of the bundled model: knees and ankles bent, base tilted a little and placed so that
/// the left sole is on z = 0 (the right one too: the posture is symmetric).
/// The weight of `model` standing at `state` split between its soles of `sole_size` \[m\]
/// ([`stride_estimation::standing_foot_wrenches`], world frame, \[N, N·m\]).
pub fn standing_split(
    model: &Arc<Model>,
    state: &RobotState,
    sole_size: [f64; 2],
) -> [Vector6<f64>; 2] {
    let mut kd = KinDyn::new(model.clone());
    kd.set_state(state).unwrap();
    let soles =
        ["l_sole", "r_sole"].map(|s| kd.frame_rotation_translation(model.frame_id(s).unwrap()));
    let force = -model.total_mass() * model.gravity();
    stride_estimation::standing_foot_wrenches(&force, &kd.com_position(), &soles, sole_size)
        .unwrap()
}

pub fn standing_state(model: &Model) -> RobotState {
    let mut state = RobotState::zero(model);
    for (name, v) in [
        ("l_hip_pitch", 0.3),
        ("r_hip_pitch", 0.3),
        ("l_knee", 0.6),
        ("r_knee", 0.6),
        ("l_ankle_pitch", 0.3),
        ("r_ankle_pitch", 0.3),
        ("torso_pitch", 0.1),
    ] {
        if let Some(i) = model.joint_index(name) {
            state.joint_positions[i] = v;
        }
    }
    let mut kd = KinDyn::new(Arc::new(model.clone()));
    kd.set_state(&state).expect("state");
    let sole = kd.frame_pose(model.frame_id("l_sole").expect("l_sole"));
    // Put the sole flat at the world origin's height, with a 0.3 rad heading.
    let target = nalgebra::Isometry3::from_parts(
        nalgebra::Translation3::new(0.2, 0.1, 0.0),
        nalgebra::UnitQuaternion::from_euler_angles(0.0, 0.0, 0.3),
    );
    state.base_pose = target * sole.inverse() * state.base_pose;
    state
}

/// What the sensors of `model` read for a robot at rest in `state` (IMU still, readings from
/// `ft_sensor_wrenches` with the ground wrenches `ground` on the soles, plus `offsets`).
pub fn standing_input(
    model: &Arc<Model>,
    state: &RobotState,
    ground: &[Vector6<f64>; 2],
    offsets: &[Vector6<f64>],
    time_ns: u64,
) -> EstimatorInput {
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_state(state).expect("state");
    let imu = model.frame_id("imu_frame").expect("imu");
    let (r, _) = kd.frame_rotation_translation(imu);
    let soles = ["l_sole", "r_sole"].map(|s| model.frame_id(s).expect("sole"));
    let external = [0, 1].map(|i| ExternalWrench {
        frame: soles[i],
        wrench: ground[i],
    });
    let mut readings = vec![Vector6::zeros(); model.ft_sensors().len()];
    kd.ft_sensor_wrenches(
        &nalgebra::DVector::zeros(model.nv()),
        &external,
        &mut readings,
    )
    .expect("readings");
    for (y, o) in readings.iter_mut().zip(offsets) {
        *y += o;
    }
    EstimatorInput {
        time_ns,
        joint_positions: state.joint_positions.clone(),
        joint_velocities: state.joint_velocities.clone(),
        imu: ImuReading {
            orientation: nalgebra::UnitQuaternion::from_matrix(&r),
            angular_velocity: Vector3::zeros(),
            proper_acceleration: r.transpose() * (-model.gravity()),
        },
        ft_wrenches: readings,
    }
}
