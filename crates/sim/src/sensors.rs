//! The sensors: encoders, six-axis force/torque sensors of the contact surfaces and the IMU, with their
//! optional seeded noise. They read the committed state and the forces of the last step.

use nalgebra::{DVector, Isometry3, UnitQuaternion, Vector3, Vector6};
use stride_model::RobotState;

use crate::config::NoiseConfig;
use crate::contact::{GroundPlane, Point, Surface};
use crate::io::{ImuMeasurement, SimOutput};
use crate::linalg::{ang, join, lin};
use crate::noise::GaussianNoise;

/// The measurement noise: its standard deviations and the one seeded generator every sensor draws from (in a
/// fixed order, so a run is reproducible from the seed).
#[derive(Clone, Debug)]
pub(crate) struct Sensors {
    noise: GaussianNoise,
    config: NoiseConfig,
}

impl Sensors {
    /// Sensors with the noise `config` (generator seeded with `config.seed`).
    pub(crate) fn new(config: &NoiseConfig) -> Self {
        Self {
            noise: GaussianNoise::new(config.seed),
            config: config.clone(),
        }
    }

    /// Restarts the noise sequence from the seed.
    pub(crate) fn reset(&mut self) {
        self.noise.reset();
    }

    /// Encoder positions and velocities (`q + n_q`, `q̇ + n_q̇`, drawn joint by joint in that order), rad, rad/s.
    pub(crate) fn read_encoders(
        &mut self,
        state: &RobotState,
        positions: &mut DVector<f64>,
        velocities: &mut DVector<f64>,
    ) {
        for j in 0..state.joint_positions.len() {
            positions[j] = state.joint_positions[j] + self.noise.sample(self.config.joint_position);
            velocities[j] =
                state.joint_velocities[j] + self.noise.sample(self.config.joint_velocity);
        }
    }

    /// `out.surfaces[index]` from the forces of the surface's points: the wrench about the surface origin
    /// (world orientation), the sensor's wrench in its frame about its origin (plus noise, force then torque),
    /// the normal force and the centre of pressure on the ground. Copies each point into `out.contact_points`
    /// and adds its wrench about the world origin to `out.total_contact_wrench` (point by point, in order).
    pub(crate) fn measure_surface(
        &mut self,
        index: usize,
        surface: &Surface,
        points: &[Point],
        ground: &GroundPlane,
        out: &mut SimOutput,
    ) {
        let o = surface.pose.translation.vector;
        let o_ft = surface.ft_pose.translation.vector;
        let mut w = Vector6::zeros();
        let mut w_ft = Vector6::zeros();
        let mut in_contact = false;
        let contact_points = &mut out.contact_points[surface.points()];
        for (p, cp) in points.iter().zip(contact_points.iter_mut()) {
            let f = p.force;
            if f != Vector3::zeros() {
                in_contact = true;
            }
            w += join(&f, &(p.position - o).cross(&f));
            w_ft += join(&f, &(p.position - o_ft).cross(&f));
            out.total_contact_wrench += join(&f, &p.position.cross(&f));
            cp.position = p.position;
            cp.force = f;
            cp.penetration = p.penetration;
            cp.mode = p.mode;
        }
        let r_ft = surface.ft_pose.rotation;
        let f_s =
            r_ft.inverse_transform_vector(&lin(&w_ft)) + self.noise.sample3(self.config.force);
        let t_s =
            r_ft.inverse_transform_vector(&ang(&w_ft)) + self.noise.sample3(self.config.torque);
        let m = &mut out.surfaces[index];
        m.in_contact = in_contact;
        m.wrench = w;
        m.sensor_wrench = join(&f_s, &t_s);
        let n = ground.normal;
        let fz = n.dot(&lin(&w));
        m.normal_force = fz.max(0.0);
        let o_ground = ground.project(&o);
        m.center_of_pressure = if fz > 1e-9 {
            // Torque about the projected origin, then the point of the plane where it has no tangential part:
            // `p_cop = o' + n × τ' / f_n`.
            let t = ang(&w) + (o - o_ground).cross(&lin(&w));
            o_ground + n.cross(&t) / fz
        } else {
            o_ground
        };
    }

    /// The IMU reading from its frame's pose and mixed twist and the world acceleration `a` of its origin
    /// (m/s²): orientation `world_R_imu · exp(n_R)`, angular velocity `Rᵀ ω + n_ω`, proper acceleration
    /// `Rᵀ (a − g) + n_a` (noise drawn in that order).
    pub(crate) fn measure_imu(
        &mut self,
        pose: &Isometry3<f64>,
        twist: &Vector6<f64>,
        acceleration: &Vector3<f64>,
        gravity: &Vector3<f64>,
        imu: &mut ImuMeasurement,
    ) {
        let rot = pose.rotation;
        let orientation_noise = self.noise.sample3(self.config.orientation);
        imu.orientation = rot * UnitQuaternion::from_scaled_axis(orientation_noise);
        imu.angular_velocity =
            rot.inverse_transform_vector(&ang(twist)) + self.noise.sample3(self.config.gyroscope);
        imu.proper_acceleration = rot.inverse_transform_vector(&(acceleration - gravity))
            + self.noise.sample3(self.config.accelerometer);
    }
}
