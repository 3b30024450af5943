//! The sensors as a real iCub-class robot has them: quantised encoders with differenced and low-passed
//! velocities, an IMU with biases, white noise and a filter-like orientation, the six-axis force/torque sensors
//! with offsets, drift, noise and saturation, and a sensor delay. Every random number comes from one seeded
//! generator, drawn in a fixed order, so a run is reproducible from [`SensorConfig::seed`]. Nothing here
//! allocates after construction except [`Sensors::measure`] right after a state change (it fills the delay
//! line).
//!
//! The contact-surface wrenches ([`Sensors::measure_surface`]) are ground truth.
//!
//! Another plant reuses the same models through the crate's exports [`crate::SensorModels`] (this
//! [`Sensors`]), [`crate::SensorTruth`] and [`crate::SensorReading`]: it fills the truth and calls
//! [`Sensors::record`] each step (stride-mujoco does, so both plants feed the estimator the same sensors).

use nalgebra::{DVector, Isometry3, Matrix6, UnitQuaternion, Vector3, Vector6};
use stride_block::low_pass_gain;
use stride_model::{JointKind, Model, RobotState};

use crate::config::{SensorConfig, VelocitySource};
use crate::contact::{GroundPlane, Point, Surface};
use crate::io::{ImuMeasurement, SimOutput};
use crate::linalg::{ang, join, lin};
use crate::noise::GaussianNoise;

/// `x` rounded to the nearest multiple of `step` (`x` itself when `step == 0`).
pub(crate) fn quantise(x: f64, step: f64) -> f64 {
    if step > 0.0 {
        step * (x / step).round()
    } else {
        x
    }
}

/// Clamps each entry of `v` to `±range` (an entry with range 0 is unbounded).
fn clamp_axes(v: &mut Vector3<f64>, range: &[f64; 3]) {
    for (x, r) in v.iter_mut().zip(range) {
        if *r > 0.0 {
            *x = x.clamp(-r, *r);
        }
    }
}

/// Three uniform samples on `[−bound, bound)`.
fn uniform3(noise: &mut GaussianNoise, bound: f64) -> Vector3<f64> {
    Vector3::new(
        noise.uniform(bound),
        noise.uniform(bound),
        noise.uniform(bound),
    )
}

/// One reading of every sensor (what the delay line holds).
#[derive(Clone, Debug)]
pub struct Reading {
    /// Encoder positions (quantised, noisy), rad or m, model joint order.
    pub joint_positions: DVector<f64>,
    /// Encoder velocities (differenced and low-passed, or true plus noise), rad/s or m/s.
    pub joint_velocities: DVector<f64>,
    /// The IMU.
    pub imu: ImuMeasurement,
    /// Six-axis force/torque sensors in [`Model::ft_sensors`] order (sensor frame), N, N·m.
    pub ft_wrenches: Vec<Vector6<f64>>,
}

impl Reading {
    fn new(dof: usize, ft_sensors: usize) -> Self {
        Self {
            joint_positions: DVector::zeros(dof),
            joint_velocities: DVector::zeros(dof),
            imu: ImuMeasurement {
                orientation: UnitQuaternion::identity(),
                angular_velocity: Vector3::zeros(),
                proper_acceleration: Vector3::zeros(),
            },
            ft_wrenches: vec![Vector6::zeros(); ft_sensors],
        }
    }

    fn copy_from(&mut self, other: &Reading) {
        self.joint_positions.copy_from(&other.joint_positions);
        self.joint_velocities.copy_from(&other.joint_velocities);
        self.imu = other.imu;
        self.ft_wrenches.copy_from_slice(&other.ft_wrenches);
    }
}

/// The true quantities the sensors read at the end of a step.
pub struct Truth<'a> {
    /// Committed state (mixed velocities).
    pub state: &'a RobotState,
    /// `world_H_imu`.
    pub imu_pose: Isometry3<f64>,
    /// Mixed twist of the IMU frame, m/s, rad/s.
    pub imu_twist: Vector6<f64>,
    /// World acceleration of the IMU origin over the step, m/s².
    pub imu_acceleration: Vector3<f64>,
    /// Gravity (world), m/s².
    pub gravity: Vector3<f64>,
    /// Simulated time, s.
    pub time: f64,
    /// Transmitted wrench of each force/torque sensor (sensor frame, measurement direction), N, N·m.
    pub ft_wrenches: &'a [Vector6<f64>],
    /// The state was just set (not reached by a step): restart the velocity filter and fill the delay line.
    pub fresh_start: bool,
}

/// The sensor models and their internal state (filters, biases, offsets, the delay line).
#[derive(Clone, Debug)]
pub struct Sensors {
    noise: GaussianNoise,
    config: SensorConfig,
    /// Step period, s.
    dt: f64,
    /// Quantisation step of each joint (0: none), rad.
    steps: Vec<f64>,
    /// Velocity filter gain α.
    alpha: f64,
    /// Last reported (quantised) joint positions, before the delay.
    previous_positions: DVector<f64>,
    /// Low-pass filter state of the differenced velocities, rad/s.
    filtered_velocities: DVector<f64>,
    gyro_bias: Vector3<f64>,
    accel_bias: Vector3<f64>,
    /// Constant roll and pitch error of the orientation, rad.
    tilt: [f64; 2],
    /// Yaw drift rate of the orientation, rad/s.
    yaw_rate: f64,
    /// Offset of each force/torque sensor `[f; τ]`.
    ft_offsets: Vec<Vector6<f64>>,
    /// Random-walk drift of each force/torque sensor `[f; τ]`.
    ft_drifts: Vec<Vector6<f64>>,
    /// Raw gains `1 + E` of each force/torque sensor (the inverse of its calibration matrix).
    ft_gains: Vec<Matrix6<f64>>,
    /// Delay line of `delay_steps + 1` readings; `ring[head]` receives the next fresh one.
    ring: Vec<Reading>,
    head: usize,
}

impl Sensors {
    /// The sensors of `model` with `config` (validated by [`crate::SimConfig::validate`]) at the step
    /// period `dt` (s). Call [`Sensors::reset`] before use.
    pub fn new(model: &Model, config: &SensorConfig, dt: f64) -> Self {
        let dof = model.dof();
        let step = match config.encoder.counts_per_revolution {
            0 => 0.0,
            counts => std::f64::consts::TAU / f64::from(counts),
        };
        let steps = model
            .joints()
            .iter()
            .map(|j| match j.kind {
                JointKind::Prismatic => 0.0,
                _ => step,
            })
            .collect();
        let n_ft = model.ft_sensors().len();
        Self {
            noise: GaussianNoise::new(config.seed),
            config: config.clone(),
            dt,
            steps,
            alpha: low_pass_gain(dt, config.encoder.velocity_cutoff),
            previous_positions: DVector::zeros(dof),
            filtered_velocities: DVector::zeros(dof),
            gyro_bias: Vector3::zeros(),
            accel_bias: Vector3::zeros(),
            tilt: [0.0; 2],
            yaw_rate: 0.0,
            ft_offsets: vec![Vector6::zeros(); n_ft],
            ft_drifts: vec![Vector6::zeros(); n_ft],
            ft_gains: vec![Matrix6::identity(); n_ft],
            ring: vec![Reading::new(dof, n_ft); config.delay_steps + 1],
            head: 0,
        }
    }

    /// Restarts the random sequence from the seed and draws the start-up errors, in this order: each
    /// force/torque sensor's offset (force then torque axes), the gyroscope bias, the accelerometer bias, the
    /// roll and pitch error, the yaw drift rate, then (only when `ft.calibration_error > 0`) each sensor's
    /// calibration error `E`, column by column. Drifts restart at zero.
    pub fn reset(&mut self) {
        self.noise.reset();
        let ft = &self.config.ft;
        for (offset, drift) in self.ft_offsets.iter_mut().zip(&mut self.ft_drifts) {
            for k in 0..3 {
                offset[k] = self.noise.uniform(ft.force_offset);
            }
            for k in 3..6 {
                offset[k] = self.noise.uniform(ft.torque_offset);
            }
            *drift = Vector6::zeros();
        }
        let imu = &self.config.imu;
        self.gyro_bias = uniform3(&mut self.noise, imu.gyro_bias);
        self.accel_bias = uniform3(&mut self.noise, imu.accel_bias);
        self.tilt = [
            self.noise.uniform(imu.tilt_error),
            self.noise.uniform(imu.tilt_error),
        ];
        self.yaw_rate = self.noise.uniform(imu.yaw_drift_rate);
        let bound = self.config.ft.calibration_error;
        for gain in &mut self.ft_gains {
            *gain = Matrix6::identity();
            if bound > 0.0 {
                for e in gain.iter_mut() {
                    *e += self.noise.uniform(bound);
                }
            }
        }
    }

    /// Each force/torque sensor's offset `b` drawn at the last reset (`[f; τ]`, raw space), without the drift
    /// accumulated since.
    pub fn ft_offsets(&self) -> &[Vector6<f64>] {
        &self.ft_offsets
    }

    /// Each force/torque sensor's calibration matrix `C = (1 + E)⁻¹`: the reading `r` gives the wrench
    /// `C (r − b)` [Traversaro 2017, eq. (5.1)] (identity when `ft.calibration_error` is 0).
    pub fn ft_calibration_matrices(&self) -> Vec<Matrix6<f64>> {
        self.ft_gains
            .iter()
            .map(|g| g.try_inverse().unwrap_or_else(Matrix6::identity))
            .collect()
    }

    /// Takes a reading of every sensor (encoders, IMU, force/torque sensors, drawing their noise in that order)
    /// into the delay line and copies the reading of `delay_steps` steps ago into `out`. After a state change
    /// (`truth.fresh_start`) the whole delay line is filled with the new reading (this allocates once).
    pub(crate) fn measure(&mut self, truth: &Truth<'_>, out: &mut SimOutput) {
        let delayed = self.record(truth);
        out.joint_positions.copy_from(&delayed.joint_positions);
        out.joint_velocities.copy_from(&delayed.joint_velocities);
        out.imu = delayed.imu;
        out.ft_wrenches.copy_from_slice(&delayed.ft_wrenches);
        out.ft_wrenches_truth.copy_from_slice(truth.ft_wrenches);
    }

    /// Takes a reading of every sensor into the delay line (encoders, IMU, force/torque sensors, drawing
    /// their noise in that order) and returns the reading of `delay_steps` steps ago. After a state change
    /// (`truth.fresh_start`) the whole line is filled with the new reading. `truth.ft_wrenches` must hold
    /// one wrench per sensor of the model.
    pub fn record(&mut self, truth: &Truth<'_>) -> &Reading {
        let head = self.head;
        let mut fresh = std::mem::replace(&mut self.ring[head], Reading::new(0, 0));
        self.read_encoders(truth, &mut fresh);
        self.read_imu(truth, &mut fresh.imu);
        self.read_ft(truth.ft_wrenches, &mut fresh.ft_wrenches);
        if truth.fresh_start {
            for (k, r) in self.ring.iter_mut().enumerate() {
                if k != head {
                    r.copy_from(&fresh);
                }
            }
        }
        self.ring[head] = fresh;
        self.head = (head + 1) % self.ring.len();
        &self.ring[self.head]
    }

    /// Encoder positions `quantise(q + n_q)` and velocities (differenced and low-passed, or true) plus `n_q̇`,
    /// drawn joint by joint in that order.
    fn read_encoders(&mut self, truth: &Truth<'_>, reading: &mut Reading) {
        let e = &self.config.encoder;
        let state = truth.state;
        for j in 0..state.joint_positions.len() {
            let q = quantise(
                state.joint_positions[j] + self.noise.sample(e.position_noise),
                self.steps[j],
            );
            let v = match e.velocity_source {
                VelocitySource::FilteredDifference => {
                    let y = &mut self.filtered_velocities[j];
                    if truth.fresh_start {
                        *y = state.joint_velocities[j];
                    } else {
                        let raw = (q - self.previous_positions[j]) / self.dt;
                        *y += self.alpha * (raw - *y);
                    }
                    *y
                }
                VelocitySource::Truth => state.joint_velocities[j],
            };
            self.previous_positions[j] = q;
            reading.joint_positions[j] = q;
            reading.joint_velocities[j] = v + self.noise.sample(e.velocity_noise);
        }
    }

    /// The IMU: the biases take their random-walk step, then the angular velocity `Rᵀ ω + b_ω + n_ω`, the
    /// proper acceleration `Rᵀ (a − g) + b_a + n_a` and the orientation `exp(δ^) world_R_imu` with
    /// `δ = [e_roll, e_pitch, ψ̇ t] + n_R` (noise drawn in that order).
    fn read_imu(&mut self, truth: &Truth<'_>, imu: &mut ImuMeasurement) {
        let c = &self.config.imu;
        let sqrt_dt = self.dt.sqrt();
        self.gyro_bias += self.noise.sample3(c.gyro_bias_random_walk * sqrt_dt);
        self.accel_bias += self.noise.sample3(c.accel_bias_random_walk * sqrt_dt);
        let rot = truth.imu_pose.rotation;
        imu.angular_velocity = rot.inverse_transform_vector(&ang(&truth.imu_twist))
            + self.gyro_bias
            + self.noise.sample3(c.gyro_noise_density / sqrt_dt);
        imu.proper_acceleration = rot
            .inverse_transform_vector(&(truth.imu_acceleration - truth.gravity))
            + self.accel_bias
            + self.noise.sample3(c.accel_noise_density / sqrt_dt);
        let error = Vector3::new(self.tilt[0], self.tilt[1], self.yaw_rate * truth.time)
            + self.noise.sample3(c.orientation_noise);
        imu.orientation = UnitQuaternion::from_scaled_axis(error) * rot;
    }

    /// Each force/torque sensor: its drift takes a random-walk step (force then torque axes), then
    /// `(1 + E) w + offset + drift + n` (force noise, torque noise) clamped at the full scale.
    fn read_ft(&mut self, truth: &[Vector6<f64>], out: &mut [Vector6<f64>]) {
        let c = &self.config.ft;
        let sqrt_dt = self.dt.sqrt();
        for (i, w) in truth.iter().enumerate() {
            let drift = &mut self.ft_drifts[i];
            let d = join(
                &self.noise.sample3(c.force_drift * sqrt_dt),
                &self.noise.sample3(c.torque_drift * sqrt_dt),
            );
            *drift += d;
            let gained = if c.calibration_error > 0.0 {
                self.ft_gains[i] * w
            } else {
                *w
            };
            let biased = gained + self.ft_offsets[i] + *drift;
            let mut f = lin(&biased) + self.noise.sample3(c.force_noise);
            let mut t = ang(&biased) + self.noise.sample3(c.torque_noise);
            clamp_axes(&mut f, &c.force_range);
            clamp_axes(&mut t, &c.torque_range);
            out[i] = join(&f, &t);
        }
    }

    /// `out.surfaces[index]` from the forces of the surface's points (ground truth): the wrench about the
    /// surface origin (world orientation), the same wrench in the contact sensor frame about its origin, the
    /// normal force and the centre of pressure on the ground. Copies each point into `out.contact_points` and
    /// adds its wrench about the world origin to `out.total_contact_wrench` (point by point, in order).
    pub(crate) fn measure_surface(
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
        let f_s = r_ft.inverse_transform_vector(&lin(&w_ft));
        let t_s = r_ft.inverse_transform_vector(&ang(&w_ft));
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
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantise_rounds_to_the_nearest_step() {
        let step = std::f64::consts::TAU / 4096.0;
        assert_eq!(quantise(0.4 * step, step), 0.0);
        assert_eq!(quantise(0.6 * step, step), step);
        assert_eq!(quantise(-2.6 * step, step), -3.0 * step);
        assert_eq!(quantise(0.123, 0.0), 0.123);
    }

    /// A sine at the cut-off frequency comes out of the filter with gain 1/√2 and a 45° lag; a slow sine is
    /// delayed by `1/(2π f_c)`.
    #[test]
    fn the_velocity_filter_has_its_cut_off_and_delay() {
        let dt = 0.0005;
        let fc = 10.0;
        let alpha = low_pass_gain(dt, fc);
        // Gain and phase from a least-squares fit of the steady-state output on sin and cos.
        let response = |f: f64| {
            let w = std::f64::consts::TAU * f;
            let (mut y, mut s, mut c) = (0.0, 0.0, 0.0);
            let n = (20.0 / f / dt) as usize;
            let skip = n / 2;
            for k in 0..n {
                let t = k as f64 * dt;
                y += alpha * ((w * t).sin() - y);
                if k >= skip {
                    s += y * (w * t).sin();
                    c += y * (w * t).cos();
                }
            }
            let m = (n - skip) as f64 / 2.0;
            let (a, b) = (s / m, c / m);
            ((a * a + b * b).sqrt(), (-b).atan2(a))
        };
        let (gain, lag) = response(fc);
        assert!((gain - 0.5f64.sqrt()).abs() < 0.01, "gain {gain}");
        assert!(
            (lag - std::f64::consts::FRAC_PI_4).abs() < 0.02,
            "lag {lag} rad"
        );
        let f = 0.5;
        let (gain, lag) = response(f);
        let delay = lag / (std::f64::consts::TAU * f);
        let expected = 1.0 / (std::f64::consts::TAU * fc);
        assert!(gain > 0.99, "gain {gain}");
        assert!(
            (delay - expected).abs() < 0.03 * expected,
            "delay {delay} s, expected {expected} s"
        );
    }
}
