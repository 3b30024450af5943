//! The two time-stepping schemes of [`SimRobot`]: the linearly implicit step with its contact-mode and
//! saturation re-solves, the explicit step on the articulated-body algorithm, and the optional momentum
//! projection.
//!
//! Both are semi-implicit Euler: `ν⁺ = ν + dt ν̇`, then the configuration with `ν⁺`. The implicit scheme
//! evaluates the servos, passive damping and contact spring-dampers at the end of the step, linearised, which
//! gives `(M + dt D + dt² K) ν̇ = τ − h + Σ Jᵀ (W₀ − dt K₆ V)` with `M` the composite-rigid-body mass matrix
//! [Featherstone 2008, ch. 6]; the explicit one evaluates every force at the start of the step and uses the
//! articulated-body algorithm [Featherstone 2008, ch. 7].

use nalgebra::{Matrix6, Vector3, Vector6};
use stride_model::{ExternalWrench, VelocityRepresentation};

use super::SimRobot;
use crate::actuator::explicit_friction;
use crate::config::IntegratorKind;
use crate::contact::{start_wrench, surface_matrices, Change};
use crate::error::SimError;
use crate::io::SimInput;
use crate::linalg::{ang, join, lin};

/// How a step's linear solves went.
#[derive(Clone, Copy, Debug)]
pub(super) struct Solve {
    /// Number of linear solves.
    pub(super) solves: usize,
    /// The re-solve cap stopped the step with contact modes or saturations still changing.
    pub(super) cap_hit: bool,
}

impl SimRobot {
    /// Generalized force `Σ Jᵀ w` of the pushes active at the current time (into `external_forces`), and the
    /// list of external wrenches for the explicit path (into `wrenches`).
    pub(super) fn apply_pushes(&mut self) -> Result<(), SimError> {
        self.external_forces.fill(0.0);
        for p in &self.pushes {
            if !p.is_active(self.time_ns) {
                continue;
            }
            match self.config.integrator {
                IntegratorKind::Implicit => {
                    self.kd.frame_jacobian(p.frame, &mut self.push_jacobian)?;
                    self.external_forces
                        .gemv_tr(1.0, &self.push_jacobian, &p.wrench, 1.0);
                }
                IntegratorKind::Explicit => {
                    self.wrenches.push(ExternalWrench {
                        frame: p.frame,
                        wrench: p.wrench,
                    });
                }
            }
        }
        Ok(())
    }

    /// One implicit step: fills `acceleration`, point forces and motor torques. Solves again while the
    /// solution changes a contact mode or a saturation, at most `max_solves` times. A re-solve re-linearises
    /// only the surfaces whose points changed, and refactorises only the branches of the tree (legs, torso)
    /// whose entries changed ([`TreeCholesky::refactor`](crate::linalg::TreeCholesky::refactor)), or nothing
    /// when only the right-hand side changed (a sliding point's normal-force estimate). Each solve gives the
    /// same result as assembling and factorising the whole system again.
    pub(super) fn solve_implicit(&mut self, input: &SimInput) -> Result<Solve, SimError> {
        self.pack_mass_matrix();
        self.kd.bias_forces(&mut self.bias)?;
        for s in &mut self.surfaces {
            self.kd.frame_jacobian(s.frame, &mut s.jacobian)?;
            if !s.columns_found {
                s.find_columns();
                s.branch = s
                    .columns
                    .last()
                    .and_then(|c| self.factorization.branch_of(*c));
                s.columns_found = true;
            }
            s.stale = Change::Mode;
        }
        for p in &mut self.points {
            p.begin_implicit_step(&self.ground);
        }
        self.saturated.fill(false);
        self.friction_switches.fill(0);
        let mut solves = 0;
        loop {
            self.assemble_joints(input);
            self.assemble_contacts();
            if self.config.fixed_base {
                self.hold_base();
            }
            let factored = if solves == 0 {
                self.factorization.factor(&self.system)
            } else if self.system_changed {
                self.factorization
                    .refactor(&self.system, &self.changed_branches)
            } else {
                true
            };
            if !factored {
                return Err(SimError::NotPositiveDefinite {
                    time: self.time_ns as f64 * 1e-9,
                });
            }
            self.acceleration.copy_from(&self.rhs);
            self.factorization.solve(&mut self.acceleration);
            solves += 1;
            self.changed_branches.fill(false);
            self.system_changed = false;
            let changed = self.update_modes(input);
            if !changed || solves >= self.max_solves {
                return Ok(Solve {
                    solves,
                    cap_hit: changed,
                });
            }
        }
    }

    /// The mass matrix at the current state of `kd`, written straight into its packed tree pattern
    /// (`mass_packed`) through the slots found at construction (no dense matrix).
    pub(super) fn pack_mass_matrix(&mut self) {
        let (slots, packed) = (&self.mass_slots, self.mass_packed.values_mut());
        let mut next = slots.iter();
        self.kd.mass_matrix_lower(|_, _, v| {
            if let Some(&slot) = next.next() {
                packed[slot] = v;
            }
        });
    }

    /// Starts `(M + dt D + dt² K) ν̇ = rhs` with the mass matrix and the joints: each servo adds
    /// `armature + dt (kd + d + b) + dt² kp` to its diagonal and its torque at the start of the step
    /// `τ_ff + kp (q_ref − q − dt q̇) + kd (q̇_ref − q̇) − (d + b) q̇ + τ_s` to `rhs` (a saturated joint: its
    /// fixed torque, no gains), where the Coulomb friction phase gives either the stick damper `b` or the
    /// sliding torque `τ_s`; a joint at its end stop ([`crate::stops`]) adds the stop's spring-damper the
    /// same way; `rhs` also gets the pushes and `−h`.
    fn assemble_joints(&mut self, input: &SimInput) {
        let dt = self.dt;
        let nb = 6;
        self.system.copy_from(&self.mass_packed);
        self.rhs.copy_from(&self.external_forces);
        self.rhs -= &self.bias;
        let q = &self.state.joint_positions;
        let qd = &self.state.joint_velocities;
        let system = self.system.values_mut();
        for (j, a) in self.actuators.iter().enumerate() {
            let (mut kp, mut kd) = a.gains();
            let motor = if self.saturated[j] {
                kp = 0.0;
                kd = 0.0;
                self.motor_torques[j]
            } else {
                a.torque(
                    input.joint_torques[j],
                    input.joint_positions[j] - q[j] - dt * qd[j],
                    input.joint_velocities[j] - qd[j],
                )
            };
            let (stick, slide) = self.friction[j].terms(a.coulomb_friction);
            let damping = a.damping + stick;
            let i = nb + j;
            system[self.factorization.diagonal_index(i)] +=
                a.armature + dt * (kd + damping) + dt * dt * kp;
            self.rhs[i] += motor - damping * qd[j] + slide;
            if let Some((k, b, limit)) = self.stops.active(j, q[j], qd[j], dt) {
                system[self.factorization.diagonal_index(i)] += dt * b + dt * dt * k;
                self.rhs[i] += k * (limit - q[j] - dt * qd[j]) - b * qd[j];
            }
        }
    }

    /// A fixed base (`SimConfig::fixed_base`): the base rows and columns of the system become `1 · ν̇_b = 0`,
    /// which leaves the joint rows as the fixed-base dynamics `M_ss q̈ = τ − h_s + …` (the base velocity is
    /// zero, so `h_s` has no base terms). Applied after every assembly, so the refactorisation of unchanged
    /// branches stays valid.
    fn hold_base(&mut self) {
        let n = self.factorization.len();
        let system = self.system.values_mut();
        for k in 0..6 {
            for i in 0..k {
                system[self.factorization.index(i, k)] = 0.0;
            }
            system[self.factorization.diagonal_index(k)] = 1.0;
            self.rhs[k] = 0.0;
        }
        for k in 6..n {
            for i in 0..6 {
                system[self.factorization.index(i, k)] = 0.0;
            }
        }
    }

    /// Adds each touching surface's `Jᵀ (dt D₆ + dt² K₆) J` to the system and `Jᵀ (W₀ − dt K₆ V)` to `rhs`, over
    /// the non-zero columns of `J` only (the joints that move the surface), which keeps the branch-induced
    /// sparsity of the mass matrix. A surface is linearised again only as far as its points changed in the last
    /// solve (a changed mode marks its branch in `changed_branches`); otherwise its terms of the last solve
    /// are added.
    fn assemble_contacts(&mut self) {
        for s in &mut self.surfaces {
            let points = &mut self.points[s.points()];
            if s.stale == Change::Mode {
                s.set_matrices(
                    surface_matrices(points, &self.ground),
                    self.dt,
                    &self.factorization,
                );
                if let Some(b) = s.branch {
                    self.changed_branches[b] = true;
                }
                self.system_changed = true;
            }
            if s.stale != Change::None {
                s.set_rhs(&start_wrench(points, &self.ground), self.dt);
            }
            s.stale = Change::None;
            s.add_to(&mut self.system, &mut self.rhs);
        }
    }

    /// After a solve: end-of-step motor torques and contact forces; switches the saturations and contact modes
    /// that the solution violates (marking the surfaces to linearise again and the branches of the joints
    /// that changed). Returns whether anything changed (then the step is solved again).
    fn update_modes(&mut self, input: &SimInput) -> bool {
        let mut changed = self.saturate_joints(input);
        changed |= self.switch_friction();
        for s in &mut self.surfaces {
            s.acceleration = Vector6::zeros();
            for &c in &s.columns {
                s.acceleration += s.jacobian.fixed_view::<6, 1>(0, c) * self.acceleration[c];
            }
        }
        for p in &mut self.points {
            let s = &mut self.surfaces[p.surface];
            let change = p.settle(&s.acceleration, &self.ground, self.dt);
            s.stale = s.stale.max(change);
            changed |= change != Change::None;
        }
        changed
    }

    /// Marks the branch of joint `j` as changed.
    fn joint_changed(&mut self, j: usize) {
        self.system_changed = true;
        if let Some(b) = self.factorization.branch_of(6 + j) {
            self.changed_branches[b] = true;
        }
    }

    /// The servo torques at the end of the step, `τ_ff + kp (q_ref − q − dt q̇⁺) + kd (q̇_ref − q̇⁺)`; a joint
    /// beyond its effort limit is saturated (its torque fixed at the limit). Returns whether one saturated.
    fn saturate_joints(&mut self, input: &SimInput) -> bool {
        let dt = self.dt;
        let mut changed = false;
        for j in 0..self.actuators.len() {
            if self.saturated[j] {
                continue;
            }
            let a = &self.actuators[j];
            let v_end = self.state.joint_velocities[j] + dt * self.acceleration[6 + j];
            let t = a.torque(
                input.joint_torques[j],
                input.joint_positions[j] - self.state.joint_positions[j] - dt * v_end,
                input.joint_velocities[j] - v_end,
            );
            if t.abs() > a.limit {
                self.saturated[j] = true;
                self.motor_torques[j] = a.limit.copysign(t);
                self.joint_changed(j);
                changed = true;
            } else {
                self.motor_torques[j] = t;
            }
        }
        changed
    }

    /// Switches the Coulomb friction phases the solution violates (each joint at most twice per step, so the
    /// re-solves end). Returns whether one switched.
    fn switch_friction(&mut self) -> bool {
        let mut changed = false;
        for j in 0..self.actuators.len() {
            let tau_c = self.actuators[j].coulomb_friction;
            if tau_c == 0.0 || self.friction_switches[j] >= 2 {
                continue;
            }
            let v_end = self.state.joint_velocities[j] + self.dt * self.acceleration[6 + j];
            if let Some(next) = self.friction[j].switch(tau_c, v_end) {
                self.friction[j] = next;
                self.friction_switches[j] += 1;
                self.joint_changed(j);
                changed = true;
            }
        }
        changed
    }

    /// One explicit step: servo torques (saturated) and contact forces at the start of the step, then the
    /// articulated-body algorithm for `ν̇`.
    pub(super) fn solve_explicit(&mut self, input: &SimInput) -> Result<Solve, SimError> {
        let q = &self.state.joint_positions;
        let qd = &self.state.joint_velocities;
        for (j, a) in self.actuators.iter().enumerate() {
            let mut t = a.torque(
                input.joint_torques[j],
                input.joint_positions[j] - q[j],
                input.joint_velocities[j] - qd[j],
            );
            self.saturated[j] = t.abs() > a.limit;
            if self.saturated[j] {
                t = a.limit.copysign(t);
            }
            self.motor_torques[j] = t;
        }
        for s in &mut self.surfaces {
            s.wrench = Vector6::zeros();
        }
        for p in &mut self.points {
            let f = p.explicit_step(&self.ground);
            let s = &mut self.surfaces[p.surface];
            s.wrench += join(&f, &p.arm.cross(&f));
        }
        for s in &self.surfaces {
            if s.wrench != Vector6::zeros() {
                self.wrenches.push(ExternalWrench {
                    frame: s.frame,
                    wrench: s.wrench,
                });
            }
        }
        // Joint torques for ABA: motor minus passive damping and the regularised Coulomb friction.
        for (j, a) in self.actuators.iter().enumerate() {
            self.joint_torque_buffer[j] = self.motor_torques[j] - a.damping * qd[j]
                + explicit_friction(a.coulomb_friction, qd[j]);
        }
        self.kd.forward_dynamics(
            &self.joint_torque_buffer,
            &self.wrenches,
            &mut self.acceleration,
        )?;
        Ok(Solve {
            solves: 1,
            cap_hit: false,
        })
    }

    /// `next_state` from the state and `acceleration`: `ν⁺ = ν + dt ν̇`, the configuration integrated with
    /// `ν⁺` (base on SO(3)), then the momentum projection when `momentum_start` (`(h, c)` at the start of the
    /// step) is given, and the divergence checks.
    pub(super) fn integrate(
        &mut self,
        momentum_start: Option<(Vector6<f64>, Vector3<f64>)>,
    ) -> Result<(), SimError> {
        let dt = self.dt;
        self.next_state.copy_from(&self.state);
        for i in 0..6 {
            self.next_state.base_velocity[i] += dt * self.acceleration[i];
        }
        if self.config.fixed_base {
            self.next_state.base_velocity = Vector6::zeros();
        }
        for j in 0..self.model.dof() {
            self.next_state.joint_velocities[j] += dt * self.acceleration[6 + j];
        }
        let momentum_target = momentum_start.map(|(h, c)| h + dt * self.external_wrench_about(&c));
        self.next_state
            .integrate(&self.model, VelocityRepresentation::Mixed, dt)?;
        if let Some(h) = momentum_target {
            self.project_momentum(&h)?;
        }
        self.check_divergence()
    }

    /// Total external wrench of the step (gravity, contact forces, active pushes) about the point `c`, world
    /// orientation, with the geometry at the start of the step (the dynamics workspace must still hold it).
    fn external_wrench_about(&self, c: &Vector3<f64>) -> Vector6<f64> {
        let mut force = self.gravity * self.model.total_mass();
        let mut torque = Vector3::zeros();
        for p in &self.points {
            force += p.force;
            torque += (p.position - c).cross(&p.force);
        }
        for p in &self.pushes {
            if p.is_active(self.time_ns) {
                let f = lin(&p.wrench);
                let o = self.kd.frame_pose(p.frame).translation.vector;
                force += f;
                torque += ang(&p.wrench) + (o - c).cross(&f);
            }
        }
        join(&force, &torque)
    }

    /// Sets the base velocity of `next_state` so that its centroidal momentum equals `target`
    /// (`A_b ν_b = h − A_s q̇`, the joint velocities kept). Leaves the dynamics workspace at `next_state`.
    fn project_momentum(&mut self, target: &Vector6<f64>) -> Result<(), SimError> {
        self.kd.set_state(&self.next_state)?;
        self.kd
            .centroidal_momentum_matrix(&mut self.momentum_matrix)?;
        let mut rhs = *target;
        for (j, v) in self.next_state.joint_velocities.iter().enumerate() {
            rhs -= self.momentum_matrix.fixed_view::<6, 1>(0, 6 + j) * *v;
        }
        let base: Matrix6<f64> = self.momentum_matrix.fixed_view::<6, 6>(0, 0).into_owned();
        if let Some(v) = base.lu().solve(&rhs) {
            if v.iter().all(|x| x.is_finite()) {
                self.next_state.base_velocity = v;
            }
        }
        Ok(())
    }
}
