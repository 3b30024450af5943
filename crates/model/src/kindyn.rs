//! The computation workspace: kinematics, Jacobians, centroidal quantities, CRBA, RNEA, ABA.
//!
//! Internally every spatial quantity is expressed in the frame `A'`: world orientation, origin at the current
//! base origin, treated as a fixed inertial frame at this instant (right-trivialized velocities about the base
//! origin). At this instant `^{A'} v_{A',B}` equals the mixed base velocity `[ȯ_B; ω_B]`, and keeping the
//! origin at the base avoids the loss of precision that a world-origin frame suffers far from the origin.
//! Inputs and outputs are converted to the selected [`VelocityRepresentation`] at the boundary.

use std::sync::Arc;

use nalgebra::{
    DMatrix, DVector, Isometry3, Matrix3, Matrix6, Rotation3, Translation3, UnitQuaternion,
    Vector3, Vector6,
};

use crate::error::{check_len, check_shape, ModelError};
use crate::model::{FrameId, Model};
use crate::spatial::{
    ang, blockdiag, cross_force, cross_motion, join, lin, shift_motion, translation_x, Inertia,
};
use crate::state::{convert_velocity, RobotState, VelocityRepresentation};

mod ft_sensors;
mod regressor;

/// A wrench applied ON the robot at a frame: `[force; torque]`, torque about the frame origin, both in world
/// orientation (the frame's mixed frame `F[A]`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExternalWrench {
    /// Frame whose origin is the point of application (and the torque reference point).
    pub frame: FrameId,
    /// `[f; τ]` in N and N·m, world orientation.
    pub wrench: Vector6<f64>,
}

/// Reusable computation workspace bound to one [`Model`]. `new` allocates everything; after that, no method
/// allocates (errors aside).
///
/// `FrameId`s must come from [`Model::frame_id`] of the same model: the getters that return a value directly
/// (`frame_pose`, `frame_velocity`, ...) panic on a `FrameId` of another, smaller model; the methods that
/// return a `Result` report [`ModelError::FrameOutOfRange`].
///
/// # Examples
///
/// The pendulum of [`Model`]'s example (1 kg at 0.5 m below a hinge about y, on a 2 kg base) with the hinge
/// at `q`, checked against the closed forms: the arm's centre of mass at `0.5 (−sin q, 0, −cos q)`, the
/// generalized gravity force `∂V/∂q = m g l sin q` on the hinge and the whole weight `M g` on the base.
///
/// ```
/// use std::sync::Arc;
/// use nalgebra::DVector;
/// use stride_model::{KinDyn, Model, RobotState};
///
/// # let urdf = r#"<robot name="pendulum">
/// #   <link name="base"><inertial><mass value="2"/>
/// #     <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
/// #   <link name="arm"><inertial><origin xyz="0 0 -0.5"/><mass value="1"/>
/// #     <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
/// #   <joint name="hinge" type="revolute"><parent link="base"/><child link="arm"/>
/// #     <axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="10" velocity="5"/></joint>
/// # </robot>"#;
/// let model = Arc::new(Model::from_urdf_str(urdf)?);
/// let mut kd = KinDyn::new(Arc::clone(&model)); // allocates here, never in the methods below
/// let q = 0.3;
/// let mut state = RobotState::zero(&model);
/// state.joint_positions[0] = q;
/// kd.set_state(&state)?;
///
/// let com = kd.com_position(); // (2 kg · 0 + 1 kg · arm CoM) / 3 kg
/// assert!((com.x - (-0.5 * q.sin()) / 3.0).abs() < 1e-12);
/// assert!((com.z - (-0.5 * q.cos()) / 3.0).abs() < 1e-12);
///
/// let mut g = DVector::zeros(model.nv()); // [base wrench; hinge torque]
/// kd.gravity_forces(&mut g)?;
/// assert!((g[6] - 1.0 * 9.81 * 0.5 * q.sin()).abs() < 1e-12);
/// assert!((g[2] - 3.0 * 9.81).abs() < 1e-12);
/// # Ok::<(), stride_model::ModelError>(())
/// ```
#[derive(Clone, Debug)]
pub struct KinDyn {
    model: Arc<Model>,
    repr: VelocityRepresentation,
    gravity: Vector3<f64>,
    // ---- state ----
    base_pose: Isometry3<f64>,
    base_pos: Vector3<f64>,
    base_rot: Matrix3<f64>,
    q: DVector<f64>,
    qd: DVector<f64>,
    base_velocity: Vector6<f64>,
    // ---- per-body caches, frame A' ----
    rot: Vec<Matrix3<f64>>,
    pos: Vec<Vector3<f64>>,
    s: Vec<Vector6<f64>>,
    vel: Vec<Vector6<f64>>,
    /// Velocity-product acceleration term `v_λ × S q̇` of each body's joint.
    c: Vec<Vector6<f64>>,
    /// Body acceleration for ν̇ = 0 in the current representation (J̇ν of the body, frame A').
    bias: Vec<Vector6<f64>>,
    /// World inertias (valid when `inertia_ready`).
    inertia: Vec<Inertia>,
    inertia_ready: bool,
    /// Each revolute body's joint rotation composed with its placement, `placement · R(axis, q)`, and the
    /// joint position `q` it was computed for (both NaN before the first): a joint that has not moved since the
    /// last state (a quantized encoder reading, a joint held still) reuses it, bit for bit.
    local_rot: Vec<Matrix3<f64>>,
    local_rot_q: Vec<f64>,
    /// `force` holds the subtree wrenches of a [`KinDyn::ft_sensor_wrenches`] pass without external
    /// wrenches at the current state (for [`KinDyn::inverse_dynamics_after_ft_sensors`]).
    sensor_pass_ready: bool,
    /// The bodies on the child sides of the force/torque sensors below their host bodies (the sensors'
    /// `child_bodies` and their descendants), increasing, and the same as a mask per body.
    sensor_subtrees: Vec<usize>,
    in_sensor_subtree: Vec<bool>,
    // ---- scratch ----
    acc: Vec<Vector6<f64>>,
    force: Vec<Vector6<f64>>,
    ext: Vec<Vector6<f64>>,
    composite: Vec<Inertia>,
    art: Vec<Matrix6<f64>>,
    u_vec: Vec<Vector6<f64>>,
    d_val: Vec<f64>,
    u_val: Vec<f64>,
}

impl KinDyn {
    /// Builds the workspace (allocates) with the zero state, mixed representation and the model's gravity
    /// ([`Model::gravity`]).
    pub fn new(model: Arc<Model>) -> Self {
        let nb = model.body_count();
        let n = model.dof();
        let in_sensor_subtree = sensor_subtree_mask(&model);
        let mut kd = Self {
            repr: VelocityRepresentation::Mixed,
            gravity: model.gravity(),
            base_pose: Isometry3::identity(),
            base_pos: Vector3::zeros(),
            base_rot: Matrix3::identity(),
            q: DVector::zeros(n),
            qd: DVector::zeros(n),
            base_velocity: Vector6::zeros(),
            rot: vec![Matrix3::identity(); nb],
            pos: vec![Vector3::zeros(); nb],
            s: vec![Vector6::zeros(); nb],
            vel: vec![Vector6::zeros(); nb],
            c: vec![Vector6::zeros(); nb],
            bias: vec![Vector6::zeros(); nb],
            inertia: vec![Inertia::zero(); nb],
            inertia_ready: false,
            local_rot: vec![Matrix3::from_element(f64::NAN); nb],
            local_rot_q: vec![f64::NAN; nb],
            sensor_pass_ready: false,
            sensor_subtrees: (0..nb).filter(|&i| in_sensor_subtree[i]).collect(),
            in_sensor_subtree,
            acc: vec![Vector6::zeros(); nb],
            force: vec![Vector6::zeros(); nb],
            ext: vec![Vector6::zeros(); nb],
            composite: vec![Inertia::zero(); nb],
            art: vec![Matrix6::zeros(); nb],
            u_vec: vec![Vector6::zeros(); nb],
            d_val: vec![0.0; nb],
            u_val: vec![0.0; nb],
            model,
        };
        kd.update();
        kd
    }

    /// The model.
    pub fn model(&self) -> &Arc<Model> {
        &self.model
    }

    /// Current velocity representation.
    pub fn representation(&self) -> VelocityRepresentation {
        self.repr
    }

    /// Selects the representation of base velocity, frame velocities, Jacobians, accelerations and of the
    /// base part of generalized forces. The base velocity of the last state is reinterpreted in the new
    /// representation (as iDynTree does: set the representation before the state).
    pub fn set_representation(&mut self, representation: VelocityRepresentation) {
        self.repr = representation;
        self.update();
    }

    /// Gravity acceleration in world coordinates (m/s²).
    pub fn gravity(&self) -> Vector3<f64> {
        self.gravity
    }

    /// Sets this workspace's gravity acceleration in world coordinates (m/s²; default the model's).
    pub fn set_gravity(&mut self, gravity: Vector3<f64>) {
        self.gravity = gravity;
        self.sensor_pass_ready = false;
    }

    /// Sets the state (base velocity in the current representation) and computes the kinematics of every
    /// body (poses, velocities, bias accelerations). Checks sizes and finiteness.
    pub fn set_state(&mut self, state: &RobotState) -> Result<(), ModelError> {
        self.store_state(state)?;
        self.update();
        Ok(())
    }

    /// Validates `state` and stores its numbers, leaving the per-body kinematics to the caller.
    fn store_state(&mut self, state: &RobotState) -> Result<(), ModelError> {
        state.validate(&self.model)?;
        self.base_pose = state.base_pose;
        self.q.copy_from(&state.joint_positions);
        self.qd.copy_from(&state.joint_velocities);
        self.base_velocity = state.base_velocity;
        Ok(())
    }

    /// [`Self::set_state`], taking the kinematics from `source` when it is at the same state: the same model
    /// (the same `Arc`), the same representation and every number of `state` bit for bit (its state, set
    /// by [`Self::set_state`]). The forward pass is then a copy of `source`'s per-body poses, velocities and
    /// bias accelerations, which is what the pass would compute (it is a function of these alone); otherwise
    /// it runs. A plant that keeps the kinematics of its true state saves the runner a pass per tick.
    pub fn set_state_from(
        &mut self,
        state: &RobotState,
        source: &KinDyn,
    ) -> Result<(), ModelError> {
        if !(Arc::ptr_eq(&self.model, &source.model)
            && self.repr == source.repr
            && source.holds_state(state))
        {
            return self.set_state(state);
        }
        self.store_state(state)?;
        self.base_rot = source.base_rot;
        self.base_pos = source.base_pos;
        self.rot.copy_from_slice(&source.rot);
        self.pos.copy_from_slice(&source.pos);
        self.s.copy_from_slice(&source.s);
        self.vel.copy_from_slice(&source.vel);
        self.c.copy_from_slice(&source.c);
        self.bias.copy_from_slice(&source.bias);
        self.local_rot.copy_from_slice(&source.local_rot);
        self.local_rot_q.copy_from_slice(&source.local_rot_q);
        self.inertia_ready = false;
        self.sensor_pass_ready = false;
        Ok(())
    }

    /// Whether this workspace's state is `state`, every number bit for bit.
    fn holds_state(&self, state: &RobotState) -> bool {
        let (pose, other) = (&self.base_pose, &state.base_pose);
        let pairs: [(&[f64], &[f64]); 5] = [
            (
                pose.translation.vector.as_slice(),
                other.translation.vector.as_slice(),
            ),
            (
                pose.rotation.coords.as_slice(),
                other.rotation.coords.as_slice(),
            ),
            (
                self.base_velocity.as_slice(),
                state.base_velocity.as_slice(),
            ),
            (self.q.as_slice(), state.joint_positions.as_slice()),
            (self.qd.as_slice(), state.joint_velocities.as_slice()),
        ];
        pairs.iter().all(|(a, b)| {
            a.len() == b.len() && a.iter().zip(*b).all(|(x, y)| x.to_bits() == y.to_bits())
        })
    }

    /// Copies the current state (base velocity in the current representation) into `state` (no allocation
    /// when `state` already has the model's sizes).
    pub fn state_into(&self, state: &mut RobotState) {
        state.base_pose = self.base_pose;
        if state.joint_positions.len() != self.q.len() {
            state.joint_positions = self.q.clone();
        } else {
            state.joint_positions.copy_from(&self.q);
        }
        if state.joint_velocities.len() != self.qd.len() {
            state.joint_velocities = self.qd.clone();
        } else {
            state.joint_velocities.copy_from(&self.qd);
        }
        state.base_velocity = self.base_velocity;
    }

    /// Forward kinematics, velocities and velocity-product terms of every body.
    fn update(&mut self) {
        let m = &*self.model;
        self.base_rot = *self.base_pose.rotation.to_rotation_matrix().matrix();
        self.base_pos = self.base_pose.translation.vector;
        let base_mixed = convert_velocity(
            &self.base_pose,
            &self.base_velocity,
            self.repr,
            VelocityRepresentation::Mixed,
        );
        self.rot[0] = self.base_rot;
        self.pos[0] = Vector3::zeros();
        self.vel[0] = base_mixed;
        self.s[0] = Vector6::zeros();
        self.c[0] = Vector6::zeros();
        // Base acceleration in A' when ν̇ = 0 in the representation [Traversaro 2017, Table 2.2].
        self.bias[0] = match self.repr {
            VelocityRepresentation::Mixed => {
                let od = lin(&base_mixed);
                let w = ang(&base_mixed);
                join(&od.cross(&w), &Vector3::zeros())
            }
            _ => Vector6::zeros(),
        };
        self.inertia_ready = false;
        self.sensor_pass_ready = false;
        // The per-body vectors as slices of the body count, held in locals: the loop reads no `Vec` header
        // back after a store and checks only the parent's index (the same arithmetic, bit for bit).
        let nb = m.body_count();
        let (rot, pos, s, vel) = (
            &mut self.rot[..nb],
            &mut self.pos[..nb],
            &mut self.s[..nb],
            &mut self.vel[..nb],
        );
        let (c, bias) = (&mut self.c[..nb], &mut self.bias[..nb]);
        let (local_rot, local_rot_q) = (&mut self.local_rot[..nb], &mut self.local_rot_q[..nb]);
        let (parent, prismatic) = (&m.parent[..nb], &m.prismatic[..nb]);
        let (placement_pos, axis_in_parent) = (&m.placement_pos[..nb], &m.axis_in_parent[..nb]);
        let (placement_rot, placement_k, placement_k2) = (
            &m.placement_rot[..nb],
            &m.placement_k[..nb],
            &m.placement_k2[..nb],
        );
        let (q_all, qd_all) = (self.q.as_slice(), self.qd.as_slice());
        let (q_all, qd_all) = (&q_all[..nb - 1], &qd_all[..nb - 1]);
        for i in 1..nb {
            let p = parent[i];
            let j = i - 1;
            let rp = rot[p];
            let pj = pos[p] + rp * placement_pos[i];
            // Joint axis in world orientation (invariant under the joint's own rotation).
            let axis_w = rp * axis_in_parent[i];
            let q = q_all[j];
            if prismatic[i] {
                rot[i] = rp * placement_rot[i];
                pos[i] = pj + axis_w * q;
                s[i] = join(&axis_w, &Vector3::zeros());
            } else {
                if q.to_bits() != local_rot_q[i].to_bits() {
                    // placement · R(axis, q) = P + sin q · P K + (1 − cos q) · P K²  (Rodrigues).
                    let (sin, cos) = q.sin_cos();
                    local_rot[i] =
                        placement_rot[i] + placement_k[i] * sin + placement_k2[i] * (1.0 - cos);
                    local_rot_q[i] = q;
                }
                rot[i] = rp * local_rot[i];
                pos[i] = pj;
                s[i] = join(&pj.cross(&axis_w), &axis_w);
            }
            let qd = qd_all[j];
            let vp = vel[p];
            vel[i] = vp + s[i] * qd;
            c[i] = cross_motion(&vp, &s[i]) * qd;
            bias[i] = bias[p] + c[i];
        }
    }

    /// World (A') inertia of body `i` from the current pose.
    #[inline]
    fn compute_inertia(&self, i: usize) -> Inertia {
        let m = &*self.model;
        Inertia::from_body_com(
            m.inertia[i].m,
            &m.body_com[i],
            &m.body_inertia_com[i],
            &self.rot[i],
            &self.pos[i],
        )
    }

    /// Inertia of body `i`: cached when the dynamics have been prepared, computed otherwise.
    #[inline]
    fn body_inertia(&self, i: usize) -> Inertia {
        if self.inertia_ready {
            self.inertia[i]
        } else {
            self.compute_inertia(i)
        }
    }

    /// Computes the world inertias of all bodies once per state (lazily: kinematics-only users skip it).
    fn ensure_inertias(&mut self) {
        if !self.inertia_ready {
            // [`Self::compute_inertia`] of every body, over zipped slices (no index checks).
            let m = &*self.model;
            let nb = m.body_count();
            let bodies = m.inertia[..nb]
                .iter()
                .zip(&m.body_com[..nb])
                .zip(&m.body_inertia_com[..nb]);
            let poses = self.rot[..nb].iter().zip(&self.pos[..nb]);
            for (out, (((inertia, com), i_com), (r, p))) in
                self.inertia[..nb].iter_mut().zip(bodies.zip(poses))
            {
                *out = Inertia::from_body_com(inertia.m, com, i_com, r, p);
            }
            self.inertia_ready = true;
        }
    }

    // ------------------------------------------------------------------ helpers

    fn frame_checked(&self, frame: FrameId) -> Result<(), ModelError> {
        if frame.0 < self.model.frames.len() {
            Ok(())
        } else {
            Err(ModelError::FrameOutOfRange {
                index: frame.0,
                count: self.model.frames.len(),
            })
        }
    }

    /// Body index, rotation and position (relative to the base origin, world orientation) of a frame.
    #[inline]
    fn frame_rt(&self, frame: FrameId) -> (usize, Matrix3<f64>, Vector3<f64>) {
        let m = &*self.model;
        let b = m.frames[frame.0].link;
        let r = self.rot[b] * m.frame_rot[frame.0];
        let p = self.pos[b] + self.rot[b] * m.frame_pos[frame.0];
        (b, r, p)
    }

    /// Converts a motion vector of frame A' into the output representation of a frame `(r, p)`.
    #[inline]
    fn out_motion(&self, r: &Matrix3<f64>, p: &Vector3<f64>, v: &Vector6<f64>) -> Vector6<f64> {
        match self.repr {
            VelocityRepresentation::Mixed => shift_motion(v, p),
            VelocityRepresentation::Body => {
                let m = shift_motion(v, p);
                join(&(r.tr_mul(&lin(&m))), &(r.tr_mul(&ang(&m))))
            }
            VelocityRepresentation::Inertial => shift_motion(v, &(-self.base_pos)),
        }
    }

    /// `T` such that (A' base velocity) = T (base velocity in the representation).
    fn base_t(&self) -> Matrix6<f64> {
        match self.repr {
            VelocityRepresentation::Mixed => Matrix6::identity(),
            VelocityRepresentation::Body => blockdiag(&self.base_rot),
            VelocityRepresentation::Inertial => translation_x(&(-self.base_pos)),
        }
    }

    /// `T v`.
    #[inline]
    fn base_t_mul(&self, v: &Vector6<f64>) -> Vector6<f64> {
        match self.repr {
            VelocityRepresentation::Mixed => *v,
            VelocityRepresentation::Body => {
                join(&(self.base_rot * lin(v)), &(self.base_rot * ang(v)))
            }
            VelocityRepresentation::Inertial => shift_motion(v, &self.base_pos),
        }
    }

    /// `T⁻¹ v`.
    #[inline]
    fn base_t_inv_mul(&self, v: &Vector6<f64>) -> Vector6<f64> {
        match self.repr {
            VelocityRepresentation::Mixed => *v,
            VelocityRepresentation::Body => join(
                &(self.base_rot.tr_mul(&lin(v))),
                &(self.base_rot.tr_mul(&ang(v))),
            ),
            VelocityRepresentation::Inertial => shift_motion(v, &(-self.base_pos)),
        }
    }

    /// `Tᵀ f` (a wrench dual to the representation's base velocity).
    #[inline]
    fn base_t_tr_mul(&self, f: &Vector6<f64>) -> Vector6<f64> {
        match self.repr {
            VelocityRepresentation::Mixed => *f,
            VelocityRepresentation::Body => join(
                &(self.base_rot.tr_mul(&lin(f))),
                &(self.base_rot.tr_mul(&ang(f))),
            ),
            VelocityRepresentation::Inertial => {
                // T = [[1, −o^],[0, 1]] ⇒ Tᵀ = [[1, 0],[o^, 1]].
                let fl = lin(f);
                join(&fl, &(ang(f) + self.base_pos.cross(&fl)))
            }
        }
    }

    fn world_gravity6(&self) -> Vector6<f64> {
        join(&self.gravity, &Vector3::zeros())
    }

    fn gather_wrenches(&mut self, wrenches: &[ExternalWrench]) -> Result<(), ModelError> {
        for e in self.ext.iter_mut() {
            *e = Vector6::zeros();
        }
        for w in wrenches {
            self.frame_checked(w.frame)?;
            if !w.wrench.iter().all(|v| v.is_finite()) {
                return Err(ModelError::NonFiniteInput {
                    what: "external wrench",
                });
            }
            let (b, _, p) = self.frame_rt(w.frame);
            let f = lin(&w.wrench);
            self.ext[b] += join(&f, &(ang(&w.wrench) + p.cross(&f)));
        }
        Ok(())
    }

    fn composites(&mut self) {
        self.ensure_inertias();
        let m = &*self.model;
        self.composite.copy_from_slice(&self.inertia);
        for i in (1..m.body_count()).rev() {
            let p = m.parent[i];
            let ci = self.composite[i];
            self.composite[p].add(&ci);
        }
    }

    /// CoM relative to the base origin (world orientation).
    fn com_rel(&self) -> Vector3<f64> {
        let m = &*self.model;
        let mut mass = 0.0;
        let mut h = Vector3::zeros();
        for i in 0..m.body_count() {
            let mi = m.inertia[i].m;
            mass += mi;
            h += (self.rot[i] * m.body_com[i] + self.pos[i]) * mi;
        }
        if mass > 0.0 {
            h / mass
        } else {
            Vector3::zeros()
        }
    }

    /// Total momentum about the A' origin and its time derivative for ν̇ = 0.
    fn momentum_and_rate(&self) -> (Vector6<f64>, Vector6<f64>) {
        let mut h = Vector6::zeros();
        let mut hd = Vector6::zeros();
        for k in 0..self.model.body_count() {
            let inertia = self.body_inertia(k);
            let iv = inertia.mul_motion(&self.vel[k]);
            h += iv;
            hd += inertia.mul_motion(&self.bias[k]) + cross_force(&self.vel[k], &iv);
        }
        (h, hd)
    }

    /// Moves a momentum/wrench about the A' origin to the CoM `c` (relative to the base origin).
    #[inline]
    fn to_com(f: &Vector6<f64>, c: &Vector3<f64>) -> Vector6<f64> {
        let fl = lin(f);
        join(&fl, &(ang(f) - c.cross(&fl)))
    }

    // ------------------------------------------------------------------ kinematics

    /// `world_H_frame`.
    pub fn frame_pose(&self, frame: FrameId) -> Isometry3<f64> {
        let (_, r, p) = self.frame_rt(frame);
        Isometry3::from_parts(
            Translation3::from(p + self.base_pos),
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r)),
        )
    }

    /// World rotation matrix and position of a frame (cheaper than [`Self::frame_pose`]).
    pub fn frame_rotation_translation(&self, frame: FrameId) -> (Matrix3<f64>, Vector3<f64>) {
        let (_, r, p) = self.frame_rt(frame);
        (r, p + self.base_pos)
    }

    /// `a_H_b`.
    pub fn relative_transform(&self, a: FrameId, b: FrameId) -> Isometry3<f64> {
        let (_, ra, pa) = self.frame_rt(a);
        let (_, rb, pb) = self.frame_rt(b);
        let r = ra.tr_mul(&rb);
        let p = ra.tr_mul(&(pb - pa));
        Isometry3::from_parts(
            Translation3::from(p),
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r)),
        )
    }

    /// Velocity of a frame in the current representation.
    pub fn frame_velocity(&self, frame: FrameId) -> Vector6<f64> {
        let (b, r, p) = self.frame_rt(frame);
        self.out_motion(&r, &p, &self.vel[b])
    }

    /// Frame Jacobian `J` (6 × nv) with `frame_velocity = J ν`, both in the current representation.
    pub fn frame_jacobian(&self, frame: FrameId, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        self.frame_checked(frame)?;
        let nv = self.model.nv();
        check_shape("frame_jacobian output", (6, nv), out.shape())?;
        let (b, r, p) = self.frame_rt(frame);
        // Column-major 6 × nv storage: column c is data[6c .. 6c + 6].
        let data = out.as_mut_slice();
        data.fill(0.0);
        let base = match self.repr {
            VelocityRepresentation::Mixed => translation_x(&(-p)),
            _ => {
                let t = self.base_t();
                let mut base = Matrix6::zeros();
                for k in 0..6 {
                    let col = self.out_motion(&r, &p, &t.column(k).into_owned());
                    base.set_column(k, &col);
                }
                base
            }
        };
        data[..36].copy_from_slice(base.as_slice());
        let parent = &self.model.parent;
        let mut i = b;
        while i != 0 {
            let col = self.out_motion(&r, &p, &self.s[i]);
            let start = 6 * (5 + i);
            data[start..start + 6].copy_from_slice(col.as_slice());
            i = parent[i];
        }
        Ok(())
    }

    /// Every joint's Jacobian column in one pass, like Pinocchio's `computeJointJacobians` (WORLD frame).
    ///
    /// Column `k` (6 × nv output, `[linear; angular]`) is the inertial (right-trivialized) twist, about the
    /// world origin and in world coordinates, that a unit `ν[k]` gives every body downstream of that degree
    /// of freedom; the base columns map the base velocity in the current representation. The
    /// inertial twist of a body is therefore this matrix times ν with the columns of the joints that are not
    /// its ancestors set to zero. One pass over the bodies, no allocation.
    pub fn joint_jacobians(&self, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        let nv = self.model.nv();
        check_shape("joint_jacobians output", (6, nv), out.shape())?;
        let to_origin = -self.base_pos;
        let t = self.base_t();
        let data = out.as_mut_slice();
        for k in 0..6 {
            let col = shift_motion(&t.column(k).into_owned(), &to_origin);
            data[6 * k..6 * k + 6].copy_from_slice(col.as_slice());
        }
        for i in 1..self.model.body_count() {
            let col = shift_motion(&self.s[i], &to_origin);
            let start = 6 * (5 + i);
            data[start..start + 6].copy_from_slice(col.as_slice());
        }
        Ok(())
    }

    /// `J̇ ν` of a frame: its acceleration in the current representation when ν̇ = 0.
    pub fn frame_bias_acceleration(&self, frame: FrameId) -> Vector6<f64> {
        let (b, r, p) = self.frame_rt(frame);
        let mut a = self.out_motion(&r, &p, &self.bias[b]);
        if self.repr == VelocityRepresentation::Mixed {
            let v = shift_motion(&self.vel[b], &p);
            let od = lin(&v);
            let w = ang(&v);
            let corr = od.cross(&w);
            a[0] -= corr.x;
            a[1] -= corr.y;
            a[2] -= corr.z;
        }
        a
    }

    /// Centre of mass in world coordinates (m). The base origin if the model has no mass.
    pub fn com_position(&self) -> Vector3<f64> {
        self.com_rel() + self.base_pos
    }

    /// CoM velocity in world coordinates (m/s).
    pub fn com_velocity(&self) -> Vector3<f64> {
        let mass = self.model.total_mass;
        if mass <= 0.0 {
            return Vector3::zeros();
        }
        let m = &*self.model;
        let mut p = Vector3::zeros();
        for k in 0..m.body_count() {
            // The linear momentum of body k, `m v − h × ω` with `h = m c` [Traversaro 2017, eq. 2.67]: the
            // linear rows of `I v` (`Inertia::mul_motion`) without the world inertia's rotational part,
            // bit for bit (`h` as `Inertia::from_body_com` forms it when the inertias are not prepared).
            let (mk, h) = if self.inertia_ready {
                (self.inertia[k].m, self.inertia[k].h)
            } else {
                let mk = m.inertia[k].m;
                (mk, (self.rot[k] * m.body_com[k] + self.pos[k]) * mk)
            };
            let v = &self.vel[k];
            p += lin(v) * mk - h.cross(&ang(v));
        }
        p / mass
    }

    /// CoM Jacobian (3 × nv): `com_velocity = J ν`.
    pub fn com_jacobian(&mut self, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        let nv = self.model.nv();
        check_shape("com_jacobian output", (3, nv), out.shape())?;
        let mass = self.model.total_mass;
        out.as_mut_slice().fill(0.0);
        if mass <= 0.0 {
            return Ok(());
        }
        self.composites();
        let base = self.composite[0].matrix() * self.base_t();
        for k in 0..6 {
            for r in 0..3 {
                out[(r, k)] = base[(r, k)] / mass;
            }
        }
        for i in 1..self.model.body_count() {
            let f = self.composite[i].mul_motion(&self.s[i]);
            for r in 0..3 {
                out[(r, 5 + i)] = f[r] / mass;
            }
        }
        Ok(())
    }

    /// `J̇_com ν`: CoM acceleration when ν̇ = 0 (m/s²).
    pub fn com_bias_acceleration(&self) -> Vector3<f64> {
        let mass = self.model.total_mass;
        if mass <= 0.0 {
            return Vector3::zeros();
        }
        let (_, hd) = self.momentum_and_rate();
        lin(&hd) / mass
    }

    /// Total mass (kg).
    pub fn total_mass(&self) -> f64 {
        self.model.total_mass
    }

    /// Centroidal momentum `[p; l]`: linear momentum and angular momentum about the CoM, world orientation.
    pub fn centroidal_momentum(&self) -> Vector6<f64> {
        let (h, _) = self.momentum_and_rate();
        Self::to_com(&h, &self.com_rel())
    }

    /// Centroidal momentum matrix (6 × nv): `centroidal_momentum = CMM ν` [Orin 2013].
    pub fn centroidal_momentum_matrix(&mut self, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        let nv = self.model.nv();
        check_shape("centroidal_momentum_matrix output", (6, nv), out.shape())?;
        self.composites();
        let c = self.com_rel();
        let base = self.composite[0].matrix() * self.base_t();
        for k in 0..6 {
            let col = Self::to_com(&base.column(k).into_owned(), &c);
            out.fixed_view_mut::<6, 1>(0, k).copy_from(&col);
        }
        for i in 1..self.model.body_count() {
            let f = self.composite[i].mul_motion(&self.s[i]);
            out.fixed_view_mut::<6, 1>(0, 5 + i)
                .copy_from(&Self::to_com(&f, &c));
        }
        Ok(())
    }

    /// `d/dt(CMM) ν`: rate of the centroidal momentum when ν̇ = 0 (no gravity, no external forces).
    pub fn centroidal_momentum_bias(&self) -> Vector6<f64> {
        let (_, hd) = self.momentum_and_rate();
        Self::to_com(&hd, &self.com_rel())
    }

    // ------------------------------------------------------------------ dynamics

    /// Mass matrix M (nv × nv) by the composite-rigid-body algorithm [Featherstone 2008], in the current
    /// representation.
    pub fn mass_matrix(&mut self, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        let nv = self.model.nv();
        check_shape("mass_matrix output", (nv, nv), out.shape())?;
        self.composites();
        out.as_mut_slice().fill(0.0);
        out.fixed_view_mut::<6, 6>(0, 0)
            .copy_from(&self.base_mass_block());
        self.joint_mass_entries(|row, col, v| {
            out[(row, col)] = v;
            out[(col, row)] = v;
        });
        Ok(())
    }

    /// The entries of the mass matrix's lower triangle that a kinematic tree may have non-zero
    /// [Featherstone 2008, §6.5], by the composite-rigid-body algorithm in the current representation:
    /// `put(row, col, value)` with `row ≥ col` for the base block's lower triangle, then, for every joint
    /// DoF `d = 6 + j`, its diagonal, its entries with the DoFs of the joints between it and the base, and
    /// its six entries with the base DoFs. The same values as [`KinDyn::mass_matrix`]'s lower triangle, bit
    /// for bit; no other entry is non-zero. Lets a sparse factorisation fill its own storage (no dense
    /// `nv × nv` matrix to clear and gather from). Does not allocate.
    pub fn mass_matrix_lower(&mut self, mut put: impl FnMut(usize, usize, f64)) {
        self.composites();
        let base = self.base_mass_block();
        for col in 0..6 {
            for row in col..6 {
                put(row, col, base[(row, col)]);
            }
        }
        self.joint_mass_entries(put);
    }

    /// `Tᵀ I_c T`: the base block of the mass matrix from the whole robot's composite inertia (after
    /// [`Self::composites`]).
    fn base_mass_block(&self) -> Matrix6<f64> {
        let t = self.base_t();
        t.transpose() * self.composite[0].matrix() * t
    }

    /// The mass matrix's joint columns (after [`Self::composites`]): `put(d, col, v)` for every joint DoF
    /// `d`, with `col` = `d`, the DoFs of the joints above it, then the six base DoFs ([Featherstone 2008],
    /// CRBA: `F = I_c S_i`, `M_ki = S_kᵀ F` up the tree, base entries `Tᵀ F`).
    fn joint_mass_entries(&self, mut put: impl FnMut(usize, usize, f64)) {
        let m = &*self.model;
        for i in 1..m.body_count() {
            let f = self.composite[i].mul_motion(&self.s[i]);
            let col = 5 + i;
            put(col, col, self.s[i].dot(&f));
            let mut k = m.parent[i];
            while k != 0 {
                put(col, 5 + k, self.s[k].dot(&f));
                k = m.parent[k];
            }
            let fb = self.base_t_tr_mul(&f);
            for r in 0..6 {
                put(col, r, fb[r]);
            }
        }
    }

    /// Generalized bias forces `h = C ν + G` (nv), base part dual to the representation's base velocity.
    pub fn bias_forces(&mut self, out: &mut DVector<f64>) -> Result<(), ModelError> {
        check_len("bias_forces output", self.model.nv(), out.len())?;
        for e in self.ext.iter_mut() {
            *e = Vector6::zeros();
        }
        self.rnea(None, true, out);
        Ok(())
    }

    /// Generalized gravity forces `G` (nv).
    pub fn gravity_forces(&mut self, out: &mut DVector<f64>) -> Result<(), ModelError> {
        check_len("gravity_forces output", self.model.nv(), out.len())?;
        for e in self.ext.iter_mut() {
            *e = Vector6::zeros();
        }
        self.rnea(None, false, out);
        Ok(())
    }

    /// Inverse dynamics (RNEA, [Featherstone 2008]): `out = M ν̇ + h − Σ J_fᵀ w_f` = `[base wrench; τ]`,
    /// with ν̇ in the current representation and the external wrenches acting on the robot. The base wrench
    /// is zero for a motion that the external wrenches can produce.
    pub fn inverse_dynamics(
        &mut self,
        nu_dot: &DVector<f64>,
        wrenches: &[ExternalWrench],
        out: &mut DVector<f64>,
    ) -> Result<(), ModelError> {
        let nv = self.model.nv();
        check_len("nu_dot", nv, nu_dot.len())?;
        check_len("inverse_dynamics output", nv, out.len())?;
        if !nu_dot.iter().all(|v| v.is_finite()) {
            return Err(ModelError::NonFiniteInput { what: "nu_dot" });
        }
        self.gather_wrenches(wrenches)?;
        self.rnea(Some(nu_dot), true, out);
        Ok(())
    }

    /// RNEA in frame A'. `velocity = false` computes gravity only.
    fn rnea(&mut self, nu_dot: Option<&DVector<f64>>, velocity: bool, out: &mut DVector<f64>) {
        self.rnea_forces(nu_dot, velocity);
        self.project_forces(out);
    }

    /// The RNEA's projection of the subtree wrenches `force` on the joints and the base: `τ_i = S_iᵀ f_i`,
    /// base `Tᵀ f_0` [Featherstone 2008].
    fn project_forces(&self, out: &mut DVector<f64>) {
        let nb = self.model.body_count();
        for i in 1..nb {
            out[5 + i] = self.s[i].dot(&self.force[i]);
        }
        let fb = self.base_t_tr_mul(&self.force[0]);
        for r in 0..6 {
            out[r] = fb[r];
        }
    }

    /// The RNEA's passes in frame A' without the projection on the joints: `acc[i]` = proper acceleration
    /// of body `i` (gravity subtracted), then `force[i]` = the wrench its parent applies on the subtree of
    /// `i`, `Σ (I a + v ×̄* I v − f^x)` over the subtree [Traversaro 2017, eqs. 4.17, 4.23 with erratum E12].
    /// `velocity = false` computes gravity only (`acc` untouched).
    fn rnea_forces(&mut self, nu_dot: Option<&DVector<f64>>, velocity: bool) {
        self.sensor_pass_ready = false;
        self.ensure_inertias();
        let nb = self.model.body_count();
        let g6 = self.world_gravity6();
        if velocity {
            self.proper_accelerations(nu_dot);
            let motions = self.vel[..nb].iter().zip(&self.acc[..nb]);
            let bodies = self.inertia[..nb].iter().zip(motions).zip(&self.ext[..nb]);
            for (f, ((inertia, (v, a)), ext)) in self.force[..nb].iter_mut().zip(bodies) {
                *f = net_force(inertia, v, a, ext);
            }
        } else {
            for i in 0..nb {
                self.force[i] = self.inertia[i].mul_motion(&(-g6)) - self.ext[i];
            }
        }
        let m = &*self.model;
        for i in (1..nb).rev() {
            let p = m.parent[i];
            let f = self.force[i];
            self.force[p] += f;
        }
    }

    /// `I a + v ×̄* I v − f^x` of body `i` (after [`Self::proper_accelerations`] and
    /// [`Self::ensure_inertias`]) [Traversaro 2017, eq. 4.17].
    #[inline]
    fn net_body_force(&self, i: usize) -> Vector6<f64> {
        net_force(&self.inertia[i], &self.vel[i], &self.acc[i], &self.ext[i])
    }

    /// [`Self::rnea_forces`] (with velocities) for the bodies of the sensors' child-side subtrees only: the
    /// same `force[i]` for those bodies, bit for bit (each sum taken over the same children in the same
    /// order); the others' are left stale.
    fn sensor_subtree_forces(&mut self, nu_dot: &DVector<f64>) {
        self.sensor_pass_ready = false;
        self.ensure_inertias();
        self.proper_accelerations(Some(nu_dot));
        for k in 0..self.sensor_subtrees.len() {
            let i = self.sensor_subtrees[k];
            self.force[i] = self.net_body_force(i);
        }
        for k in (0..self.sensor_subtrees.len()).rev() {
            let i = self.sensor_subtrees[k];
            let p = self.model.parent[i];
            if self.in_sensor_subtree[p] {
                let f = self.force[i];
                self.force[p] += f;
            }
        }
    }

    /// The RNEA's forward pass in frame A': `acc[i]` = proper acceleration of body `i` (gravity
    /// subtracted, [Traversaro 2017, eq. 2.42b]) for the generalized acceleration `nu_dot` (current
    /// representation; `None` = zero).
    fn proper_accelerations(&mut self, nu_dot: Option<&DVector<f64>>) {
        let base_acc = match nu_dot {
            Some(nd) => {
                let vd = Vector6::from_iterator(nd.iter().take(6).copied());
                self.base_t_mul(&vd)
            }
            None => Vector6::zeros(),
        };
        self.acc[0] = base_acc + self.bias[0] - self.world_gravity6();
        let m = &*self.model;
        let nb = m.body_count();
        let (acc, c, s, parent) = (
            &mut self.acc[..nb],
            &self.c[..nb],
            &self.s[..nb],
            &m.parent[..nb],
        );
        let nu_dot = nu_dot.map(|nd| &nd.as_slice()[..nb + 5]);
        for i in 1..nb {
            let mut a = acc[parent[i]] + c[i];
            if let Some(nd) = nu_dot {
                a += s[i] * nd[5 + i];
            }
            acc[i] = a;
        }
    }

    /// Forward dynamics (articulated-body algorithm, [Featherstone 2008]) of the free-floating robot: ν̇ (nv,
    /// in the current representation) produced by joint torques `tau` (n) and external wrenches.
    pub fn forward_dynamics(
        &mut self,
        tau: &DVector<f64>,
        wrenches: &[ExternalWrench],
        out: &mut DVector<f64>,
    ) -> Result<(), ModelError> {
        let n = self.model.dof();
        check_len("tau", n, tau.len())?;
        check_len("forward_dynamics output", n + 6, out.len())?;
        if !tau.iter().all(|v| v.is_finite()) {
            return Err(ModelError::NonFiniteInput { what: "tau" });
        }
        self.gather_wrenches(wrenches)?;
        self.sensor_pass_ready = false;
        self.ensure_inertias();
        let nb = self.model.body_count();
        for i in 0..nb {
            let iv = self.inertia[i].mul_motion(&self.vel[i]);
            self.art[i] = self.inertia[i].matrix();
            self.force[i] = cross_force(&self.vel[i], &iv) - self.ext[i];
        }
        self.articulated_inertias(tau)?;
        let Some(chol) = self.art[0].cholesky() else {
            return Err(ModelError::SingularInertia {
                what: "the floating base".to_string(),
            });
        };
        let a0 = -chol.solve(&self.force[0]);
        self.acc[0] = a0;
        for i in 1..nb {
            let p = self.model.parent[i];
            let a = self.acc[p] + self.c[i];
            let qdd = (self.u_val[i] - self.u_vec[i].dot(&a)) * self.d_val[i];
            self.acc[i] = a + self.s[i] * qdd;
            out[5 + i] = qdd;
        }
        let true_base = a0 + self.world_gravity6() - self.bias[0];
        let vd = self.base_t_inv_mul(&true_base);
        for r in 0..6 {
            out[r] = vd[r];
        }
        if !out.iter().all(|v| v.is_finite()) {
            return Err(ModelError::SingularInertia {
                what: "the floating base".to_string(),
            });
        }
        Ok(())
    }

    /// The ABA's backward pass [Featherstone 2008]: from the leaves up, each body's articulated inertia
    /// `I^A` and bias force `p^A` (initialised in `art`, `force`) are reduced through its joint,
    /// `U = I^A S`, `D = Sᵀ U`, `u = τ − Sᵀ p^A`, `I^a = I^A − U D⁻¹ Uᵀ`, and added to the parent's:
    /// `I^A_p += I^a`, `p^A_p += p^A + I^a c + U D⁻¹ u` (`c` the velocity-product acceleration). Keeps `U`,
    /// `D⁻¹` and `u` for the forward pass. [`ModelError::SingularInertia`] when `D ≤ 1e-14` or not finite.
    fn articulated_inertias(&mut self, tau: &DVector<f64>) -> Result<(), ModelError> {
        let nb = self.model.body_count();
        for i in (1..nb).rev() {
            let p = self.model.parent[i];
            let s = self.s[i];
            let u_vec = self.art[i] * s;
            let d = s.dot(&u_vec);
            if !(d > 1e-14 && d.is_finite()) {
                return Err(ModelError::SingularInertia {
                    what: format!("joint `{}`", self.model.joints[i - 1].name),
                });
            }
            let u = tau[i - 1] - s.dot(&self.force[i]);
            let inv_d = 1.0 / d;
            let ia = self.art[i] - u_vec * (u_vec.transpose() * inv_d);
            let pa = self.force[i] + ia * self.c[i] + u_vec * (u * inv_d);
            self.art[p] += ia;
            self.force[p] += pa;
            self.u_vec[i] = u_vec;
            self.d_val[i] = inv_d;
            self.u_val[i] = u;
        }
        Ok(())
    }
}

/// `I a + v ×̄* I v − f^x` of a body with world inertia `I`, velocity `v`, proper acceleration `a` and
/// external wrench `f^x` [Traversaro 2017, eq. 4.17].
#[inline]
fn net_force(
    inertia: &Inertia,
    v: &Vector6<f64>,
    a: &Vector6<f64>,
    ext: &Vector6<f64>,
) -> Vector6<f64> {
    let iv = inertia.mul_motion(v);
    inertia.mul_motion(a) + cross_force(v, &iv) - ext
}

/// Per body: whether it lies on the child side of a force/torque sensor below the sensor's host body (a
/// sensor's `child_bodies` and their descendants; parents come before their children).
fn sensor_subtree_mask(model: &Model) -> Vec<bool> {
    let nb = model.body_count();
    let mut mask = vec![false; nb];
    for side in &model.ft_sides {
        for &c in &side.child_bodies {
            mask[c] = true;
        }
    }
    for i in 1..nb {
        if mask[model.parent[i]] {
            mask[i] = true;
        }
    }
    mask
}
