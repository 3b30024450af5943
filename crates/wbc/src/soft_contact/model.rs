//! The continuum visco-elastic contact of a rectangular sole [Romualdi 2022, Lemma 1, eq. 8.1.7], its
//! parameter regressor [eq. 8.2.17], its linearisation [Corollary 1, eq. 8.1.9–8.1.11] and its wrench rate
//! [eq. 8.2.14]. The linearisation is the linear and rotational spring-damper of [Sygulla 2020, eq. 8].

use nalgebra::{Matrix3, Matrix6, Matrix6x2, Matrix6x3, Rotation3, Vector2, Vector3, Vector6};

use crate::math::skew;

/// The sole: a rectangle `length × width` (m) centred at the origin of its frame, in the frame's x-y plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SoleGeometry {
    /// Size along the sole frame's x axis (`l`), m.
    pub length: f64,
    /// Size along the sole frame's y axis (`w`), m.
    pub width: f64,
}

/// The ground's visco-elastic densities `π = [k; b]` [Romualdi 2022, eq. 8.2.18].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroundParameters {
    /// Stiffness density `k`, N/m³.
    pub stiffness: f64,
    /// Damping density `b`, N·s/m³.
    pub damping: f64,
}

impl GroundParameters {
    /// `[k; b]`.
    pub fn vector(&self) -> Vector2<f64> {
        Vector2::new(self.stiffness, self.damping)
    }
}

/// Where the sole is, how it moves and where it rests (the zero-force pose, the sole at touch-down).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SoleState {
    /// Sole centre `o_B` (world), m.
    pub position: Vector3<f64>,
    /// `ᴵR_B`.
    pub rotation: Rotation3<f64>,
    /// `ȯ_B` (world, mixed), m/s.
    pub linear_velocity: Vector3<f64>,
    /// `ᴵω_{I,B}` (world), rad/s.
    pub angular_velocity: Vector3<f64>,
    /// Zero-force centre `ō_B` (world), m.
    pub rest_position: Vector3<f64>,
    /// Zero-force orientation `ᴵR̄_B`.
    pub rest_rotation: Rotation3<f64>,
}

/// Linear and angular acceleration of the sole frame (mixed: `ö_B`, `ω̇`), m/s², rad/s².
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SoleAcceleration {
    /// `ö_B`, m/s².
    pub linear: Vector3<f64>,
    /// `ω̇`, rad/s².
    pub angular: Vector3<f64>,
}

/// The wrench rate as an affine map of the sole acceleration: `ḟ = h + g [ö_B; ω̇]`
/// [Romualdi 2022, eq. 8.2.14].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WrenchRate {
    /// Velocity-dependent part `h_f`, N/s, N·m/s.
    pub drift: Vector6<f64>,
    /// Acceleration gain `g_f` (block diagonal, negative definite for `b > 0`).
    pub gain: Matrix6<f64>,
}

impl WrenchRate {
    /// `ḟ = h + g [ö; ω̇]`, N/s, N·m/s.
    pub fn at(&self, acceleration: &SoleAcceleration) -> Vector6<f64> {
        let a = &acceleration;
        self.drift
            + self.gain
                * Vector6::new(
                    a.linear.x,
                    a.linear.y,
                    a.linear.z,
                    a.angular.x,
                    a.angular.y,
                    a.angular.z,
                )
    }

    /// This rate averaged over a period `dt` (s) during which the sole's acceleration `a` is held (the
    /// zero-order hold of a sampled controller): within the period `a` also moves the sole by `a dt²/2`,
    /// against the ground's stiffness, so `(f(t + dt) − f(t)) / dt = h + (g + (dt/2) ∂f/∂x) a + O(dt)`
    /// with the stiffness Jacobian `∂f/∂x = (k/b) g` where the sole is at its rest orientation
    /// [Romualdi 2022, Corollary 1: `𝒦 = (k/b) ℬ`]: the gain becomes `g (1 + k dt / (2b))`, the drift is
    /// kept. The sampled loop of the sole's velocity in the ground then contracts by
    /// `(b − k dt/2) / (b + k dt/2)` per period, for every `dt`; with the instantaneous gain it is
    /// `1 − k dt / b`, unstable for `dt > 2b/k`. `b ≤ 0` or `dt ≤ 0`: unchanged.
    pub fn held_over(&self, dt: f64, ground: &GroundParameters) -> WrenchRate {
        let scale = match ground.damping > 0.0 && dt > 0.0 {
            true => 1.0 + ground.stiffness * dt / (2.0 * ground.damping),
            false => 1.0,
        };
        WrenchRate {
            drift: self.drift,
            gain: self.gain * scale,
        }
    }
}

/// Second moments of the sole per unit area along its x and y axes: `l²/12`, `w²/12`, m².
fn moments(sole: &SoleGeometry) -> (f64, f64) {
    (
        sole.length * sole.length / 12.0,
        sole.width * sole.width / 12.0,
    )
}

/// `|e₃ᵀ R e₃|`, the area ratio of the sole projected on the ground [Romualdi 2022, eq. B.0.10].
fn projection_factor(rotation: &Rotation3<f64>) -> f64 {
    rotation[(2, 2)].abs()
}

/// `(l²/12) [(R e₁)×]² + (w²/12) [(R e₂)×]²`: the per-area rotational damping shape of eq. 8.1.7b.
fn rotational_shape(sole: &SoleGeometry, rotation: &Rotation3<f64>) -> Matrix3<f64> {
    let (mx, my) = moments(sole);
    let a = skew(&(rotation * Vector3::x()));
    let e = skew(&(rotation * Vector3::y()));
    a * a * mx + e * e * my
}

impl SoleGeometry {
    /// Sole area `l w`, m².
    pub fn area(&self) -> f64 {
        self.length * self.width
    }

    /// The regressor `𝒴` with `f = 𝒴 [k; b]` [Romualdi 2022, eq. 8.2.17]: force rows
    /// `l w |c| [ō − o, −ȯ]`, torque rows (about `o_B`)
    /// `l w |c| [(l²/12)(Re₁)× R̄e₁ + (w²/12)(Re₂)× R̄e₂, ((l²/12)[(Re₁)×]² + (w²/12)[(Re₂)×]²) ω]`.
    pub fn regressor(&self, state: &SoleState) -> Matrix6x2<f64> {
        let (mx, my) = moments(self);
        let scale = self.area() * projection_factor(&state.rotation);
        let r = &state.rotation;
        let rest = &state.rest_rotation;
        let spring_torque = (r * Vector3::x()).cross(&(rest * Vector3::x())) * mx
            + (r * Vector3::y()).cross(&(rest * Vector3::y())) * my;
        let damper_torque = rotational_shape(self, r) * state.angular_velocity;
        let mut y = Matrix6x2::zeros();
        y.fixed_view_mut::<3, 1>(0, 0)
            .copy_from(&((state.rest_position - state.position) * scale));
        y.fixed_view_mut::<3, 1>(0, 1)
            .copy_from(&(-state.linear_velocity * scale));
        y.fixed_view_mut::<3, 1>(3, 0)
            .copy_from(&(spring_torque * scale));
        y.fixed_view_mut::<3, 1>(3, 1)
            .copy_from(&(damper_torque * scale));
        y
    }

    /// The regressor column of a rest-height error `θ = k δ` (N/m²): the force a rest plane `δ` above
    /// `ō` adds to Lemma 1 [Romualdi 2022, eq. 8.1.7a with `ō + δ e₃`], `l w |c| e₃`, and no torque (a
    /// uniform density has no moment about the sole centre). See [`crate::GroundRestEstimator`].
    pub fn rest_height_column(&self, state: &SoleState) -> Vector6<f64> {
        Vector6::new(
            0.0,
            0.0,
            self.area() * projection_factor(&state.rotation),
            0.0,
            0.0,
            0.0,
        )
    }

    /// `[𝒴, l w |c| e₃]`: the regressor of eq. 8.2.17 with the rest-height column
    /// ([`Self::rest_height_column`]), `f = 𝒴 [k; b] + l w |c| e₃ k δ`.
    pub fn regressor_with_rest_height(&self, state: &SoleState) -> Matrix6x3<f64> {
        let mut y = Matrix6x3::zeros();
        y.fixed_view_mut::<6, 2>(0, 0)
            .copy_from(&self.regressor(state));
        y.set_column(2, &self.rest_height_column(state));
        y
    }

    /// The contact wrench `[f; μ]` (force, torque about the sole centre; world axes), N, N·m
    /// [Romualdi 2022, Lemma 1, eq. 8.1.7a–b], as `𝒴 π`.
    pub fn wrench(&self, state: &SoleState, ground: &GroundParameters) -> Vector6<f64> {
        self.regressor(state) * ground.vector()
    }

    /// The linear stiffness and damping of Corollary 1 [Romualdi 2022, eq. 8.1.10–8.1.11]:
    /// `(𝒦_l, 𝒦_a, ℬ_l, ℬ_a)` with `𝒦_l = k l w I₃`, `𝒦_a = k (l w/12) diag(w², l², l² + w²)` and the same with `b`.
    pub fn linear_gains(&self, ground: &GroundParameters) -> [Matrix3<f64>; 4] {
        let lw = self.area();
        let (l2, w2) = (self.length * self.length, self.width * self.width);
        let shape = Matrix3::from_diagonal(&Vector3::new(w2, l2, l2 + w2)) * (lw / 12.0);
        [
            Matrix3::identity() * (ground.stiffness * lw),
            shape * ground.stiffness,
            Matrix3::identity() * (ground.damping * lw),
            shape * ground.damping,
        ]
    }

    /// The linearised wrench [Romualdi 2022, Corollary 1, eq. 8.1.9] for a rest pose `R̄ = I₃` at
    /// `rest_position`: `f_l = 𝒦_l (ō − o) − ℬ_l ȯ`, `μ_l = −𝒦_a Θ − ℬ_a Θ̇` with `Θ` the roll-pitch-yaw
    /// angles (rad) and `Θ̇` their rates (rad/s).
    pub fn linear_wrench(
        &self,
        ground: &GroundParameters,
        offset: &Vector3<f64>,
        velocity: &Vector3<f64>,
        angles: &Vector3<f64>,
        angle_rates: &Vector3<f64>,
    ) -> Vector6<f64> {
        let [kl, ka, bl, ba] = self.linear_gains(ground);
        let force = -kl * offset - bl * velocity;
        let torque = -ka * angles - ba * angle_rates;
        Vector6::new(force.x, force.y, force.z, torque.x, torque.y, torque.z)
    }

    /// The wrench rate `ḟ = h + g [ö; ω̇]` [Romualdi 2022, eq. 8.2.14], the time derivative of eq. 8.1.7 with
    /// constant `k`, `b`, `ō`, `R̄`: with `a = Re₁`, `e = Re₂`, `c = e₃ᵀRe₃`, `ȧ = ω × a`,
    /// `d|c|/dt = sign(c) e₃ᵀ(ω × Re₃)`,
    /// * `g = blockdiag(−b l w |c| I₃, b l w |c| ((l²/12)[a×]² + (w²/12)[e×]²))`,
    /// * `h_f = (d|c|/dt / |c|) f − k l w |c| ȯ`,
    /// * `h_μ = (d|c|/dt / |c|) μ + l w |c| { k Σ m (ȧ × ā) + b Σ m (ȧ × (a × ω) + a × (ȧ × ω)) }` over
    ///   `(m, a, ā) ∈ {(l²/12, Re₁, R̄e₁), (w²/12, Re₂, R̄e₂)}`.
    pub fn wrench_rate(&self, state: &SoleState, ground: &GroundParameters) -> WrenchRate {
        let (k, b) = (ground.stiffness, ground.damping);
        let r = &state.rotation;
        let w = &state.angular_velocity;
        let c = r[(2, 2)];
        let scale = self.area() * c.abs();
        let c_rate = c.signum() * Vector3::z().dot(&w.cross(&(r * Vector3::z())));
        let relative = if scale > 0.0 { c_rate / c.abs() } else { 0.0 };
        let wrench = self.wrench(state, ground);
        let (mx, my) = moments(self);
        let mut torque_drift = Vector3::zeros();
        for (m, axis) in [(mx, Vector3::x()), (my, Vector3::y())] {
            let a = r * axis;
            let a_rest = state.rest_rotation * axis;
            let a_rate = w.cross(&a);
            torque_drift += (a_rate.cross(&a_rest) * k
                + (a_rate.cross(&a.cross(w)) + a.cross(&a_rate.cross(w))) * b)
                * m;
        }
        let force_drift =
            wrench.fixed_rows::<3>(0) * relative - state.linear_velocity * (k * scale);
        let torque_drift = wrench.fixed_rows::<3>(3) * relative + torque_drift * scale;
        let mut gain = Matrix6::zeros();
        gain.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Matrix3::identity() * (-b * scale)));
        gain.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(rotational_shape(self, r) * (b * scale)));
        WrenchRate {
            drift: Vector6::new(
                force_drift.x,
                force_drift.y,
                force_drift.z,
                torque_drift.x,
                torque_drift.y,
                torque_drift.z,
            ),
            gain,
        }
    }
}
