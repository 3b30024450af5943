//! Inertial-parameter regressors of the whole robot: inverse dynamics (the floating-base regressor, base and
//! joint rows) and the force/torque sensor readings, linear in ψ [Traversaro 2017, eqs. 7.1–7.5].

use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, SMatrix, Vector3, Vector6};

use super::KinDyn;
use crate::error::{check_len, check_shape, ModelError};
use crate::inertial::rigid_body_regressor;
use crate::spatial::{ang, join, lin, shift_motion, skew};

/// A 6 × 10 regressor expressed in frame A' (world orientation, base origin).
type WorldRegressor = SMatrix<f64, 6, 10>;

impl KinDyn {
    /// The floating-base inverse-dynamics regressor `Y(q, ν, ν̇)` ((6 + n) × 10·N, body layout of
    /// [`crate::inertial`]) with `Y ψ = ` [`KinDyn::inverse_dynamics`]`(ν̇, no external wrench)`
    /// `= M ν̇ + C ν + G` for every ψ [Traversaro 2017, eq. 7.1 with f^x = 0]. Its rows are those of inverse
    /// dynamics in the current representation: the first six (`Y_b`) the base wrench dual to the
    /// representation's base velocity (mixed by default), the last n (`Y_s`, the joint-torque regressor)
    /// the joint torques (N·m or N); `nu_dot` is in the current representation.
    ///
    /// Column block `b` (body `b`): the row of each joint `k` on the path from the root to body `b` is
    /// `S_kᵀ X*_b Y(a_b, v_b)` (zero for the other joints), the base rows are `Tᵀ X*_b Y(a_b, v_b)`, with
    /// `Y` the rigid-body regressor of body `b` in its frame ([`rigid_body_regressor`]), `X*_b` its wrench
    /// transform to the computation frame, `S_k` the joint's motion subspace and `T` the base velocity map
    /// of the representation (the RNEA's backward pass, [Traversaro 2017, §4.5]). Does not allocate.
    ///
    /// # Errors
    /// [`ModelError::DimensionMismatch`] for a wrong `nu_dot` length or `out` shape,
    /// [`ModelError::NonFiniteInput`] for a non-finite `nu_dot`.
    pub fn inverse_dynamics_regressor(
        &mut self,
        nu_dot: &DVector<f64>,
        out: &mut DMatrix<f64>,
    ) -> Result<(), ModelError> {
        let nv = self.model.nv();
        let nb = self.model.body_count();
        self.check_nu_dot(nu_dot)?;
        check_shape(
            "inverse_dynamics_regressor output",
            (nv, 10 * nb),
            out.shape(),
        )?;
        self.proper_accelerations(Some(nu_dot));
        out.fill(0.0);
        for b in 0..nb {
            let y = self.world_regressor(b);
            for col in 0..10 {
                let f: Vector6<f64> = y.column(col).into_owned();
                let c = 10 * b + col;
                let base = self.base_t_tr_mul(&f);
                for r in 0..6 {
                    out[(r, c)] = base[r];
                }
                let mut k = b;
                while k != 0 {
                    out[(5 + k, c)] = self.s[k].dot(&f);
                    k = self.model.parent[k];
                }
            }
        }
        Ok(())
    }

    /// The regressor of the force/torque sensor readings (6·S × 10·(N + S), FT-split layout of
    /// [`crate::inertial`]): `Y ψ = ` [`KinDyn::ft_sensor_wrenches`]`(ν̇, no external wrench)`, rows
    /// `6k .. 6k + 6` for sensor `k` (sensor frame, `[f; τ]`).
    ///
    /// With no external wrench on the sensor's child side, its reading is minus the sum of the net wrenches
    /// `φ_L = Y_L π_L` of the child-side links (for `child_to_parent`), moved to the sensor frame: the
    /// regressor of the submodel the sensor cuts off, measured by the sensor alone [Traversaro 2017,
    /// eqs. 4.17, 4.23b (erratum E12), 7.2–7.3]. Does not allocate.
    ///
    /// # Errors
    /// Those of [`KinDyn::inverse_dynamics_regressor`], and [`ModelError::SharedFtSensorHost`].
    pub fn ft_sensor_regressor(
        &mut self,
        nu_dot: &DVector<f64>,
        out: &mut DMatrix<f64>,
    ) -> Result<(), ModelError> {
        let nb = self.model.body_count();
        let ns = self.model.ft_sensors.len();
        self.check_nu_dot(nu_dot)?;
        check_shape(
            "ft_sensor_regressor output",
            (6 * ns, 10 * (nb + ns)),
            out.shape(),
        )?;
        self.model.check_ft_hosts()?;
        self.proper_accelerations(Some(nu_dot));
        out.fill(0.0);
        for j in 0..ns {
            // Sensor j's child-side part is on its own child side, and on that of every sensor whose child
            // side holds j's host body.
            let h = self.model.ft_sides[j].host;
            let y = self.world_regressor(h);
            for k in 0..ns {
                if k == j || self.on_child_side(k, h) {
                    self.add_sensor_block(k, nb + j, &y, out);
                }
            }
        }
        for b in 1..nb {
            let y = self.world_regressor(b);
            for k in 0..ns {
                if self.on_child_side(k, b) {
                    self.add_sensor_block(k, b, &y, out);
                }
            }
        }
        Ok(())
    }

    /// The base rows of the submodel above the force/torque sensors `cut` (6 × 10·(N + S), FT-split layout
    /// of [`crate::inertial`]): `Y ψ` is the sum of the net wrenches `X* Y_L π_L` of every part not on a
    /// `cut` sensor's child side, about the base origin with world axes (frame A', the base rows of the
    /// mixed representation whatever the current one; `nu_dot` is in the current representation).
    ///
    /// When every external wrench acts on the child sides of the `cut` sensors (a robot standing on the
    /// soles below its feet sensors), the Newton–Euler equations of that submodel read
    /// `Y ψ = Σ_{k ∈ cut} A_k y_k`, `y_k` the readings and `A_k` [`KinDyn::ft_sensor_parent_side_map`]:
    /// the floating-base regressor's base rows with the measured external wrenches [Traversaro 2017,
    /// eq. 7.1, Theorem 7.1], restricted to the FT submodel (eqs. 7.2–7.4) that the sensors bound. They
    /// see the total mass and the centre of mass, which no joint-torque or FT row of a robot held by its base
    /// determines. With `cut` empty they are the whole robot's base rows. Does not allocate.
    ///
    /// # Errors
    /// Those of [`KinDyn::ft_sensor_regressor`], [`ModelError::FtSensorOutOfRange`] for a `cut` index.
    pub fn ft_submodel_base_regressor(
        &mut self,
        nu_dot: &DVector<f64>,
        cut: &[usize],
        out: &mut DMatrix<f64>,
    ) -> Result<(), ModelError> {
        let nb = self.model.body_count();
        let ns = self.model.ft_sensors.len();
        self.check_nu_dot(nu_dot)?;
        check_shape(
            "ft_submodel_base_regressor output",
            (6, 10 * (nb + ns)),
            out.shape(),
        )?;
        self.model.check_ft_hosts()?;
        for &k in cut {
            self.check_ft_sensor(k)?;
        }
        self.proper_accelerations(Some(nu_dot));
        out.fill(0.0);
        for b in 0..nb {
            if !cut.iter().any(|&k| self.on_child_side(k, b)) {
                let y = self.world_regressor(b);
                out.columns_mut(10 * b, 10).copy_from(&y);
            }
        }
        for j in 0..ns {
            // Sensor j's child-side part is below j and below every sensor whose child side holds its host.
            let h = self.model.ft_sides[j].host;
            if !cut.iter().any(|&k| k == j || self.on_child_side(k, h)) {
                let y = self.world_regressor(h);
                out.columns_mut(10 * (nb + j), 10).copy_from(&y);
            }
        }
        Ok(())
    }

    /// The map `A` from force/torque sensor `sensor`'s reading `y` (sensor frame, `[f; τ]`) to the wrench
    /// its child side applies on its parent side, about the base origin with world axes (frame A'):
    /// `A = ± [[R, 0], [p^ R, R]]` (`R`, `p` the sensor frame's orientation and origin in A'; `+` for
    /// `child_to_parent`) [Traversaro 2017, eqs. 2.47, 4.1]. The right-hand side of
    /// [`KinDyn::ft_submodel_base_regressor`].
    ///
    /// # Errors
    /// [`ModelError::FtSensorOutOfRange`].
    pub fn ft_sensor_parent_side_map(
        &self,
        sensor: usize,
        out: &mut Matrix6<f64>,
    ) -> Result<(), ModelError> {
        self.check_ft_sensor(sensor)?;
        let (_, r, p) = self.frame_rt(self.model.ft_sensors[sensor].frame);
        let sign = if self.model.ft_sides[sensor].child_to_parent {
            1.0
        } else {
            -1.0
        };
        *out = Matrix6::zeros();
        out.fixed_view_mut::<3, 3>(0, 0).copy_from(&(r * sign));
        out.fixed_view_mut::<3, 3>(3, 3).copy_from(&(r * sign));
        out.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&(skew(&p) * r * sign));
        Ok(())
    }

    fn check_nu_dot(&self, nu_dot: &DVector<f64>) -> Result<(), ModelError> {
        check_len("nu_dot", self.model.nv(), nu_dot.len())?;
        if nu_dot.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(ModelError::NonFiniteInput { what: "nu_dot" })
        }
    }

    /// Whether body `b` hangs from force/torque sensor `k`'s child side (is in the subtree of one of the
    /// side's child bodies).
    fn on_child_side(&self, k: usize, b: usize) -> bool {
        let side = &self.model.ft_sides[k];
        let mut i = b;
        while i != 0 {
            if side.child_bodies.contains(&i) {
                return true;
            }
            i = self.model.parent[i];
        }
        false
    }

    /// Adds to column block `block` of sensor `k`'s rows the reading produced by the net wrench `X* Y π`
    /// (A') of a child-side part: minus it (`child_to_parent`) in the sensor frame about its origin.
    fn add_sensor_block(&self, k: usize, block: usize, y: &WorldRegressor, out: &mut DMatrix<f64>) {
        let side = &self.model.ft_sides[k];
        let (_, r, p) = self.frame_rt(self.model.ft_sensors[k].frame);
        let sign = if side.child_to_parent { -1.0 } else { 1.0 };
        for col in 0..10 {
            let net: Vector6<f64> = y.column(col).into_owned();
            let f = lin(&net);
            let tau = ang(&net) - p.cross(&f);
            let reading = join(&r.tr_mul(&f), &r.tr_mul(&tau)) * sign;
            for row in 0..6 {
                out[(6 * k + row, 10 * block + col)] += reading[row];
            }
        }
    }

    /// The rigid-body regressor of body `b` (or of a part moving with it, parameters in its frame) with
    /// its net wrench moved to A': `X*_{A'←B} Y(a_B, v_B)` [Traversaro 2017, eqs. 2.47, 6.4]. Needs `acc`
    /// (the RNEA's forward pass).
    fn world_regressor(&self, b: usize) -> WorldRegressor {
        let (r, p): (&Matrix3<f64>, &Vector3<f64>) = (&self.rot[b], &self.pos[b]);
        let to_body = |m: &Vector6<f64>| {
            let at_origin = shift_motion(m, p);
            join(&r.tr_mul(&lin(&at_origin)), &r.tr_mul(&ang(&at_origin)))
        };
        let y = rigid_body_regressor(&to_body(&self.acc[b]), &to_body(&self.vel[b]));
        let mut out = WorldRegressor::zeros();
        for col in 0..10 {
            let f = r * Vector3::new(y[(0, col)], y[(1, col)], y[(2, col)]);
            let t = r * Vector3::new(y[(3, col)], y[(4, col)], y[(5, col)]) + p.cross(&f);
            out.set_column(col, &join(&f, &t));
        }
        out
    }
}
