//! Expected six-axis force/torque sensor readings: the wrench transmitted through each sensor's fixed joint,
//! i.e. the fixed-joint line of inverse dynamics [Traversaro 2017, §4.3.1, §4.6].

use nalgebra::{DVector, Matrix3, Matrix6, Vector3, Vector6};

use super::{ExternalWrench, KinDyn};
use crate::error::{check_len, ModelError};
use crate::model::FrameId;
use crate::spatial::{ang, cross_force, join, lin, skew, Inertia};

impl KinDyn {
    /// The wrench each force/torque sensor of [`Model::ft_sensors`](crate::Model::ft_sensors) measures (same
    /// order) for the current state, the generalized acceleration `nu_dot` (nv, current representation, as
    /// in [`KinDyn::inverse_dynamics`]) and the `external` wrenches acting on the robot.
    ///
    /// `out[k] = [f; τ]` (N, N·m) is the wrench transmitted through the sensor's fixed joint, expressed in the
    /// sensor frame about its origin [Traversaro 2017, eq. 4.1]: for `child_to_parent` the wrench the child
    /// side applies on the parent side (iDynTree's `SixAxisForceTorqueSensor` convention), for
    /// `parent_to_child` its opposite. With the child-side links `L` (the subtree below the joint),
    /// `child_to_parent` reads `y = − _S X^A Σ_L (φ_L − f^x_L)`, where `φ_L = M_L a_L + v_L ×̄* M_L v_L` is
    /// the net wrench of link `L` (`a_L` its proper acceleration, gravity subtracted) and `f^x_L` the external
    /// wrench on it [Traversaro 2017, eqs. 4.9, 4.17, 4.23b with erratum E12]. A robot standing still on one
    /// foot whose sensor is between ankle and sole reads the ground wrench plus the weight of the sole part.
    ///
    /// # Errors
    /// [`ModelError::DimensionMismatch`] when `nu_dot` is not nv long or `out` is not one entry per sensor,
    /// [`ModelError::NonFiniteInput`] for a non-finite `nu_dot` or wrench, [`ModelError::FrameOutOfRange`]
    /// for a wrench on a frame of another model. Does not allocate.
    pub fn ft_sensor_wrenches(
        &mut self,
        nu_dot: &DVector<f64>,
        external: &[ExternalWrench],
        out: &mut [Vector6<f64>],
    ) -> Result<(), ModelError> {
        self.sensor_pass(nu_dot, external, out, true)
    }

    /// The readings of [`KinDyn::ft_sensor_wrenches`], bit for bit, from the bodies of the sensors'
    /// child sides only (the RNEA's backward pass over the subtrees below the sensors' host bodies, not the
    /// whole tree): for a caller that needs the readings and nothing else of the pass (a simulator's sensor
    /// model). Leaves nothing for [`KinDyn::inverse_dynamics_after_ft_sensors`].
    ///
    /// # Errors
    /// As [`KinDyn::ft_sensor_wrenches`]. Does not allocate.
    pub fn ft_sensor_readings(
        &mut self,
        nu_dot: &DVector<f64>,
        external: &[ExternalWrench],
        out: &mut [Vector6<f64>],
    ) -> Result<(), ModelError> {
        self.sensor_pass(nu_dot, external, out, false)
    }

    /// The readings, from the RNEA over the whole tree (`whole`, then reusable by
    /// [`KinDyn::inverse_dynamics_after_ft_sensors`] when `external` is empty) or over the sensors'
    /// subtrees. Checks sizes and finiteness and gathers the external wrenches first.
    fn sensor_pass(
        &mut self,
        nu_dot: &DVector<f64>,
        external: &[ExternalWrench],
        out: &mut [Vector6<f64>],
        whole: bool,
    ) -> Result<(), ModelError> {
        check_len("nu_dot", self.model.nv(), nu_dot.len())?;
        check_len(
            "ft_sensor_wrenches output",
            self.model.ft_sensors.len(),
            out.len(),
        )?;
        if !nu_dot.iter().all(|v| v.is_finite()) {
            return Err(ModelError::NonFiniteInput { what: "nu_dot" });
        }
        self.gather_wrenches(external)?;
        if whole {
            // `force[i]` = Σ over the subtree of i of (φ − f^x), frame A'.
            self.rnea_forces(Some(nu_dot), true);
            self.sensor_pass_ready = external.is_empty();
        } else {
            self.sensor_subtree_forces(nu_dot);
        }
        self.read_sensors(external, out);
        Ok(())
    }

    /// The readings from the subtree wrenches `force` of the child-side bodies ([Traversaro 2017,
    /// eq. 4.23b]; see [`KinDyn::ft_sensor_wrenches`]).
    fn read_sensors(&self, external: &[ExternalWrench], out: &mut [Vector6<f64>]) {
        let model = &*self.model;
        for (k, (sensor, side)) in model.ft_sensors.iter().zip(&model.ft_sides).enumerate() {
            let h = side.host;
            // Child-side part of the host body: φ = M a + v ×̄* M v with the host's motion.
            let inertia = Inertia::from_body_com(
                side.mass,
                &side.com,
                &side.inertia_at_com,
                &self.rot[h],
                &self.pos[h],
            );
            let momentum = inertia.mul_motion(&self.vel[h]);
            let mut net = inertia.mul_motion(&self.acc[h]) + cross_force(&self.vel[h], &momentum);
            for &c in &side.child_bodies {
                net += self.force[c];
            }
            // External wrenches on child-side frames of the host body (those on child bodies are in `force`).
            for w in external {
                if model.frames[w.frame.0].link == h && side.child_side_frame[w.frame.0] {
                    let (_, _, p) = self.frame_rt(w.frame);
                    let f = lin(&w.wrench);
                    net -= join(&f, &(ang(&w.wrench) + p.cross(&f)));
                }
            }
            // `net` is the wrench of the parent side on the child side, about the A' origin.
            let (_, r, p) = self.frame_rt(sensor.frame);
            let f = lin(&net);
            let tau = ang(&net) - p.cross(&f);
            let reading = join(&r.tr_mul(&f), &r.tr_mul(&tau));
            out[k] = if side.child_to_parent {
                -reading
            } else {
                reading
            };
        }
    }

    /// Inverse dynamics ([`KinDyn::inverse_dynamics`]: `out = M ν̇ + h − Σ J_fᵀ w_f` = `[base wrench; τ]`)
    /// with the `nu_dot` of the last [`KinDyn::ft_sensor_wrenches`] call, which must have had no external
    /// wrench and the current state, reusing that call's RNEA: its subtree wrenches `Σ φ` less, on the path
    /// from each wrench's body to the root, the wrench moved to the A' origin (the RNEA is linear in the
    /// external wrenches, [Featherstone 2008, §5.3]), projected on the joints. Equal to
    /// [`KinDyn::inverse_dynamics`] to rounding (the sums are taken in another order), at the cost of one
    /// walk up the tree per wrench. Lets an estimator predict the sensor readings, estimate the contact
    /// wrenches from them, then compute the joint torques with one RNEA.
    ///
    /// # Errors
    /// [`ModelError::NoSensorPass`] without such a pass (or after a change of state, representation or
    /// gravity, or another dynamics call), [`ModelError::DimensionMismatch`] when `out` is not nv long,
    /// [`ModelError::NonFiniteInput`], [`ModelError::FrameOutOfRange`] for a wrench. Does not allocate.
    pub fn inverse_dynamics_after_ft_sensors(
        &mut self,
        wrenches: &[ExternalWrench],
        out: &mut DVector<f64>,
    ) -> Result<(), ModelError> {
        check_len("inverse_dynamics output", self.model.nv(), out.len())?;
        if !self.sensor_pass_ready {
            return Err(ModelError::NoSensorPass);
        }
        for w in wrenches {
            self.frame_checked(w.frame)?;
            if !w.wrench.iter().all(|v| v.is_finite()) {
                return Err(ModelError::NonFiniteInput {
                    what: "external wrench",
                });
            }
        }
        self.sensor_pass_ready = false;
        for w in wrenches {
            let (b, _, p) = self.frame_rt(w.frame);
            let f = lin(&w.wrench);
            let at_origin = join(&f, &(ang(&w.wrench) + p.cross(&f)));
            let mut k = b;
            loop {
                self.force[k] -= at_origin;
                if k == 0 {
                    break;
                }
                k = self.model.parent[k];
            }
        }
        self.project_forces(out);
        Ok(())
    }

    /// The 6×6 matrix `A` by which force/torque sensor `sensor`'s reading changes, `Δy = A w`, when an
    /// external wrench `w = [f; τ]` (N, N·m; world orientation, torque about the origin of `frame`) is added
    /// on `frame` with the accelerations held fixed.
    ///
    /// When `frame` lies on the sensor's child side, `A = ± [[Rᵀ, 0], [Rᵀ (p_F − p_S)^, Rᵀ]]` (`R`, `p_S` the
    /// sensor frame's orientation and origin, `p_F` the origin of `frame`; `+` for `child_to_parent`): the
    /// wrench moved to the sensor frame [Traversaro 2017, eqs. 4.1, 4.20]; when it lies on the parent side,
    /// `A = 0`. A wrench estimate on a sole is then `A⁻¹ (y − y₀)`, `y₀` the reading without it
    /// [Traversaro 2017, eq. 4.21].
    ///
    /// # Errors
    /// [`ModelError::FtSensorOutOfRange`], [`ModelError::FrameOutOfRange`].
    pub fn ft_sensor_wrench_map(
        &self,
        sensor: usize,
        frame: FrameId,
        out: &mut Matrix6<f64>,
    ) -> Result<(), ModelError> {
        self.check_ft_sensor(sensor)?;
        self.frame_checked(frame)?;
        let side = &self.model.ft_sides[sensor];
        if !side.child_side_frame[frame.0] {
            *out = Matrix6::zeros();
            return Ok(());
        }
        let (_, r, ps) = self.frame_rt(self.model.ft_sensors[sensor].frame);
        let (_, _, pf) = self.frame_rt(frame);
        let rt: Matrix3<f64> = r.transpose();
        let sign = if side.child_to_parent { 1.0 } else { -1.0 };
        let d: Vector3<f64> = pf - ps;
        *out = Matrix6::zeros();
        out.fixed_view_mut::<3, 3>(0, 0).copy_from(&(rt * sign));
        out.fixed_view_mut::<3, 3>(3, 3).copy_from(&(rt * sign));
        out.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&(rt * skew(&d) * sign));
        Ok(())
    }

    /// [`ModelError::FtSensorOutOfRange`] unless `sensor` indexes [`crate::Model::ft_sensors`].
    pub(super) fn check_ft_sensor(&self, sensor: usize) -> Result<(), ModelError> {
        let count = self.model.ft_sensors.len();
        if sensor < count {
            Ok(())
        } else {
            Err(ModelError::FtSensorOutOfRange {
                index: sensor,
                count,
            })
        }
    }
}
