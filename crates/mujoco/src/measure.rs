//! What the MuJoCo plant reports after a step: the ground wrench on each sole from MuJoCo's contacts, the
//! six-axis force/torque sensors from stride-model's sensor model, the IMU and encoders through
//! stride-sim's sensor models, actuator torques, the fall flag.
//!
//! **Force/torque sensors.** MuJoCo's own `force`/`torque` sensors need the sensor frame to be a body: the
//! URDF's sensor joints are fixed, and MuJoCo fuses the links on both sides into one body (`fusestatic`,
//! which stride-model's lumping mirrors), so the frame disappears. The transmitted wrench is instead
//! computed by `KinDyn::ft_sensor_wrenches` [Traversaro 2017, §4.3.1] (validated against iDynTree) from
//! MuJoCo's motion: the start-of-step state, the step's generalized acceleration `(ν⁺ − ν)/dt` (mixed) and
//! the step's external wrenches (MuJoCo's contact forces on each sole, the active pushes) — exactly what
//! stride-sim feeds the same function. The sensors' offsets, drift, noise, saturation and delay are then
//! stride-sim's models.

use nalgebra::{Vector3, Vector6};
use stride_model::ExternalWrench;
use stride_sim::SensorTruth;

use crate::robot::MujocoRobot;
use crate::MujocoError;

impl MujocoRobot {
    /// Every output after a step: contacts and FT truth at the start-of-step state, then the IMU, encoders
    /// and the fall check at the new state.
    pub(crate) fn measure(&mut self) -> Result<(), MujocoError> {
        self.kd.set_state(&self.scratch.previous)?;
        self.sole_wrenches();
        let dt = self.period_ns as f64 * 1e-9;
        let s = &mut self.scratch;
        let (prev, now) = (&s.previous, &self.output.state);
        s.nu_dot
            .fixed_rows_mut::<6>(0)
            .copy_from(&((now.base_velocity - prev.base_velocity) / dt));
        for j in 0..now.joint_velocities.len() {
            s.nu_dot[6 + j] = (now.joint_velocities[j] - prev.joint_velocities[j]) / dt;
        }
        let mut external = std::mem::take(&mut self.scratch.external);
        external.clear();
        for k in 0..2 {
            external.push(ExternalWrench {
                frame: self.soles[k],
                wrench: self.output.sole_wrenches[k],
            });
        }
        // The pushes of the step (active at its start time).
        self.active_pushes(self.time_ns - self.period_ns, &mut external);
        let ft = self.kd.ft_sensor_wrenches(
            &self.scratch.nu_dot,
            &external,
            &mut self.output.ft_wrenches_truth,
        );
        self.scratch.external = external;
        ft?;
        self.kd.set_state(&self.output.state)?;
        let v = self.kd.frame_velocity(self.imu_frame).xyz();
        let a = (v - self.scratch.imu_velocity) / dt;
        self.scratch.imu_velocity = v;
        self.read_sensors(a, false);
        self.actuator_torques();
        self.check_fall();
        Ok(())
    }

    /// The measurement of a state just set: no contact force, zero acceleration (stride-sim's convention),
    /// the sensor delay line filled with it.
    pub(crate) fn measure_at_rest(&mut self) -> Result<(), MujocoError> {
        self.output.sole_wrenches = [Vector6::zeros(); 2];
        self.output.sole_contact = [false; 2];
        self.scratch.nu_dot.fill(0.0);
        self.kd.ft_sensor_wrenches(
            &self.scratch.nu_dot,
            &[],
            &mut self.output.ft_wrenches_truth,
        )?;
        self.read_sensors(Vector3::zeros(), true);
        self.output.joint_torques.fill(0.0);
        self.output.saturated.fill(false);
        self.check_fall();
        Ok(())
    }

    /// Encoders, IMU and FT sensors through stride-sim's sensor models (the state in `kd` is the output's).
    fn read_sensors(&mut self, imu_acceleration: Vector3<f64>, fresh_start: bool) {
        self.output.time = std::time::Duration::from_nanos(self.time_ns);
        let truth = SensorTruth {
            state: &self.output.state,
            imu_pose: self.kd.frame_pose(self.imu_frame),
            imu_twist: self.kd.frame_velocity(self.imu_frame),
            imu_acceleration,
            gravity: self.model().gravity(),
            time: self.time_ns as f64 * 1e-9,
            ft_wrenches: &self.output.ft_wrenches_truth,
            fresh_start,
        };
        let r = self.sensors.record(&truth);
        let o = &mut self.output;
        o.joint_positions.copy_from(&r.joint_positions);
        o.joint_velocities.copy_from(&r.joint_velocities);
        o.imu = r.imu;
        o.ft_wrenches.copy_from_slice(&r.ft_wrenches);
    }

    /// The ground wrench on each sole from MuJoCo's contacts of the step: `mj_contactForce` gives the force
    /// in the contact frame (normal first), acting on `geom[1]` and opposite on `geom[0]` [MuJoCo 3.17
    /// documentation, "Contact"]; torque about the sole origin (`kd` holds the start-of-step state).
    fn sole_wrenches(&mut self) {
        let origins = self.soles.map(|f| self.kd.frame_pose(f).translation.vector);
        let mut w = [Vector6::zeros(); 2];
        let mut normal = [0.0; 2];
        for (i, c) in self.data.contact().iter().enumerate() {
            let g = [c.geom[0] as usize, c.geom[1] as usize];
            let (foot, sign) = match (self.geom_contact[g[0]], self.geom_contact[g[1]]) {
                (_, Some(k)) => (k, 1.0),
                (Some(k), None) => (k, -1.0),
                (None, None) => continue,
            };
            let local = self.data.contact_force(i);
            let fr = &c.frame;
            let axis = |a: usize| Vector3::new(fr[3 * a], fr[3 * a + 1], fr[3 * a + 2]);
            let f = sign * (axis(0) * local[0] + axis(1) * local[1] + axis(2) * local[2]);
            let t = sign * (axis(0) * local[3] + axis(1) * local[4] + axis(2) * local[5]);
            let arm = Vector3::from(c.pos) - origins[foot];
            let tau = t + arm.cross(&f);
            w[foot] += Vector6::new(f.x, f.y, f.z, tau.x, tau.y, tau.z);
            normal[foot] += local[0];
        }
        self.output.sole_wrenches = w;
        self.output.sole_contact = normal.map(|n| n > 0.0);
    }

    /// The forces the step applied (actuator `i` drives joint `i` with gear 1; `crate::limits`) and the
    /// saturation flags: a servo pinned at its limit, a torque motor clamped at it.
    fn actuator_torques(&mut self) {
        for (j, s) in self.servos.iter().enumerate() {
            let tau = self.limits.applied[j];
            self.output.joint_torques[j] = tau;
            self.output.saturated[j] = self.limits.is_pinned(j)
                || (s.limit.is_finite() && tau.abs() >= s.limit * (1.0 - 1e-12));
        }
    }

    /// `[sim.fall]`: base origin below `min_base_height` above the ground plane, or the root z axis tilted
    /// beyond `max_tilt` from the ground normal; latched.
    fn check_fall(&mut self) {
        let pose = &self.output.state.base_pose;
        let height = self.ground.height_of(&pose.translation.vector);
        let z = pose.rotation * Vector3::z();
        let tilt = z.dot(&self.ground.normal).clamp(-1.0, 1.0).acos();
        if height < self.fall.min_base_height || tilt > self.fall.max_tilt {
            self.output.fallen = true;
        }
    }
}
