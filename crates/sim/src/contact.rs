//! The contact model: the ground plane, the grid of points sampling each contact surface, and the law of a
//! point (normal spring-damper that never pulls, Coulomb friction with a stick-slip tangential spring), with
//! its linearisation for the implicit step.

use nalgebra::{
    DMatrix, DVector, Isometry3, Matrix3, Matrix6, Point3, Rotation3, Vector3, Vector6,
};
use serde::{Deserialize, Serialize};
use stride_model::spatial::skew;
use stride_model::{FrameId, Model};

use crate::config::{ContactConfig, ContactSurfaceConfig, GroundConfig};
use crate::error::{find_frame, SimError};
use crate::linalg::{ang, join, lin, TreeCholesky, TreeMatrix};
use crate::patches::{NormalDensities, TangentialDensities};

/// The ground: the plane through `origin` with unit `normal` (pointing out of the ground).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroundPlane {
    /// A point of the plane (world), m.
    pub origin: Vector3<f64>,
    /// Unit normal (world), pointing up out of the ground.
    pub normal: Vector3<f64>,
}

impl GroundPlane {
    /// The plane described by a [`GroundConfig`]: through `[0, 0, height]`, normal `R_x(roll) R_y(pitch) e_z`.
    pub fn from_config(config: &GroundConfig) -> Self {
        let [roll, pitch] = config.inclination;
        let rotation = Rotation3::from_axis_angle(&Vector3::x_axis(), roll)
            * Rotation3::from_axis_angle(&Vector3::y_axis(), pitch);
        Self {
            origin: Vector3::new(0.0, 0.0, config.height),
            normal: rotation * Vector3::z(),
        }
    }

    /// Signed height of `p` above the plane (negative: below, i.e. penetrating), m.
    pub fn height_of(&self, p: &Vector3<f64>) -> f64 {
        self.normal.dot(&(p - self.origin))
    }

    /// Orthogonal projection of `p` on the plane.
    pub fn project(&self, p: &Vector3<f64>) -> Vector3<f64> {
        p - self.normal * self.height_of(p)
    }

    /// Tangential part of a vector (`x − n nᵀ x`).
    pub fn tangential(&self, x: &Vector3<f64>) -> Vector3<f64> {
        x - self.normal * self.normal.dot(x)
    }
}

/// What a contact point is doing during a step.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum ContactMode {
    /// Above the ground, or leaving it (no force).
    #[default]
    Separated,
    /// In contact, held by the tangential stick spring (inside the friction cone).
    Sticking,
    /// In contact and slipping: tangential force on the friction cone.
    Sliding,
}

/// What a solve of the implicit step changed in a contact point's law, ordered by reach.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum Change {
    /// Nothing: the step's linearisation holds.
    None,
    /// The force at the start of the step (a sliding point's normal-force estimate): the right-hand side.
    Force,
    /// The mode (separated, sticking, sliding): the stiffness and damping too.
    Mode,
}

/// Per-point contact parameters (already multiplied by the point's share of the surface area).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLaw {
    /// Normal stiffness, N/m.
    pub normal_stiffness: f64,
    /// Normal damping, N·s/m.
    pub normal_damping: f64,
    /// Tangential (stick) stiffness, N/m.
    pub tangential_stiffness: f64,
    /// Tangential (stick) damping, N·s/m.
    pub tangential_damping: f64,
    /// Coulomb coefficient.
    pub friction: f64,
}

impl PointLaw {
    /// The 3×3 stiffness (`K`) and damping (`D`) of the point in a given mode (`f = −K Δx − D v`).
    pub fn matrices(
        &self,
        mode: ContactMode,
        normal: &Vector3<f64>,
    ) -> (Matrix3<f64>, Matrix3<f64>) {
        let nn = normal * normal.transpose();
        match mode {
            ContactMode::Separated => (Matrix3::zeros(), Matrix3::zeros()),
            ContactMode::Sticking => (
                Matrix3::identity() * self.tangential_stiffness
                    + nn * (self.normal_stiffness - self.tangential_stiffness),
                Matrix3::identity() * self.tangential_damping
                    + nn * (self.normal_damping - self.tangential_damping),
            ),
            ContactMode::Sliding => (nn * self.normal_stiffness, nn * self.normal_damping),
        }
    }
}

/// A contact point of a surface: where it sits in the surface frame and its law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointSpec {
    /// Position in the surface's frame, m.
    pub local: Vector3<f64>,
    /// Its share of the surface (trapezoidal-rule weight; the weights of a surface sum to one).
    pub weight: f64,
    /// The area it stands for (surface area × `weight`), m²: the factor from the law's densities to the law.
    pub area: f64,
    /// The point's law.
    pub law: PointLaw,
}

/// Trapezoidal-rule abscissae and weights of `n` points on `[-size/2, size/2]` (corners included; one point:
/// the centre with weight one). The weights sum to one.
pub fn trapezoid_nodes(n: usize, size: f64) -> impl Iterator<Item = (f64, f64)> {
    (0..n).map(move |i| {
        if n == 1 {
            (0.0, 1.0)
        } else {
            let s = -0.5 * size + size * i as f64 / (n - 1) as f64;
            let w = if i == 0 || i == n - 1 { 0.5 } else { 1.0 } / (n - 1) as f64;
            (s, w)
        }
    })
}

/// The grid points of a rectangular surface with the per-area law of `contact`.
pub fn surface_points(surface: &ContactSurfaceConfig, contact: &ContactConfig) -> Vec<PointSpec> {
    let area = surface.length * surface.width;
    // A degenerate (zero-area) surface still carries the densities over a unit "area" so it is not inert.
    let area = if area > 0.0 { area } else { 1.0 };
    let mut points = Vec::with_capacity(surface.grid[0] * surface.grid[1]);
    for (x, wx) in trapezoid_nodes(surface.grid[0], surface.length) {
        for (y, wy) in trapezoid_nodes(surface.grid[1], surface.width) {
            let weight = wx * wy;
            let share = area * weight;
            points.push(PointSpec {
                local: Vector3::new(
                    surface.offset[0] + x,
                    surface.offset[1] + y,
                    surface.offset[2],
                ),
                weight,
                area: share,
                law: PointLaw {
                    normal_stiffness: contact.normal_stiffness * share,
                    normal_damping: contact.normal_damping * share,
                    tangential_stiffness: contact.tangential_stiffness * share,
                    tangential_damping: contact.tangential_damping * share,
                    friction: contact.friction_coefficient,
                },
            });
        }
    }
    points
}

/// A contact surface resolved against the model, with its per-step data.
#[derive(Clone, Debug)]
pub(crate) struct Surface {
    pub(crate) frame: FrameId,
    pub(crate) ft_frame: Option<FrameId>,
    pub(crate) first_point: usize,
    pub(crate) point_count: usize,
    /// `world_H_surface`.
    pub(crate) pose: Isometry3<f64>,
    /// Mixed twist `[v; ω]` of the surface frame, m/s, rad/s.
    pub(crate) twist: Vector6<f64>,
    /// `world_H_sensor` (the surface pose when no sensor frame is configured).
    pub(crate) ft_pose: Isometry3<f64>,
    /// Mixed Jacobian of the surface frame (6 × nv).
    pub(crate) jacobian: DMatrix<f64>,
    /// Indices of the non-zero columns of `jacobian`: the base's six and those of the joints between the
    /// surface's body and the base, the same at every state ([`Surface::find_columns`]).
    pub(crate) columns: Vec<usize>,
    /// `columns` (and `branch`) are found: [`Surface::find_columns`] ran once.
    pub(crate) columns_found: bool,
    /// The columns of `J` and of `G₆ J` over `columns` (scratch of the implicit assembly).
    column_scratch: Vec<(Vector6<f64>, Vector6<f64>)>,
    /// Branch of the tree factorisation that holds the surface's joints (`None`: only the base moves it).
    pub(crate) branch: Option<usize>,
    /// What of the linearisation must be redone: all of it at the start of a step, then what the points'
    /// changes in the last solve reach.
    pub(crate) stale: Change,
    /// Some point touches: the terms below apply.
    active: bool,
    /// The linearised contact stiffness `K₆` (about the surface origin), N/m, N·m/rad.
    stiffness: Matrix6<f64>,
    /// The surface's terms of the implicit system from the last linearisation: `Jᵀ (W₀ − dt K₆ V)` for each
    /// of `columns`, and the entries of `Jᵀ G₆ J` in the tree pattern as (place in [`TreeMatrix::values`],
    /// value).
    rhs_terms: Vec<f64>,
    matrix_terms: Vec<(usize, f64)>,
    /// `J ν̇` over `columns`, m/s², rad/s².
    pub(crate) acceleration: Vector6<f64>,
    /// Contact wrench of the explicit step, about the surface origin, N, N·m.
    pub(crate) wrench: Vector6<f64>,
}

impl Surface {
    /// A surface on `frame` whose points are `first_point..first_point + point_count`, for a model with `nv`
    /// velocity coordinates.
    pub(crate) fn new(
        frame: FrameId,
        ft_frame: Option<FrameId>,
        first_point: usize,
        point_count: usize,
        nv: usize,
    ) -> Self {
        Self {
            frame,
            ft_frame,
            first_point,
            point_count,
            pose: Isometry3::identity(),
            twist: Vector6::zeros(),
            ft_pose: Isometry3::identity(),
            jacobian: DMatrix::zeros(6, nv),
            columns: Vec::with_capacity(nv),
            columns_found: false,
            column_scratch: Vec::with_capacity(nv),
            branch: None,
            stale: Change::Mode,
            active: false,
            stiffness: Matrix6::zeros(),
            rhs_terms: Vec::with_capacity(nv),
            matrix_terms: Vec::with_capacity(nv * (nv + 1) / 2),
            acceleration: Vector6::zeros(),
            wrench: Vector6::zeros(),
        }
    }

    /// The index range of its points.
    pub(crate) fn points(&self) -> std::ops::Range<usize> {
        self.first_point..self.first_point + self.point_count
    }

    /// Records the non-zero columns of `jacobian` (the degrees of freedom that move the surface). They do not
    /// depend on the state, so the implicit step finds them once: a column of the frame Jacobian is the
    /// motion subspace `[p × a; a]` (revolute) or `[a; 0]` (prismatic) of a joint on the body's path to the
    /// base shifted to the frame, whose world axis `a = R a_local` is as zero as `a_local` at any rotation
    /// `R`; the columns of joints off the path are written as zeros; the base's columns hold `I` blocks.
    /// Test `contact_jacobian_columns_do_not_depend_on_the_state`.
    pub(crate) fn find_columns(&mut self) {
        self.columns.clear();
        for c in 0..self.jacobian.ncols() {
            if self
                .jacobian
                .fixed_view::<6, 1>(0, c)
                .iter()
                .any(|x| *x != 0.0)
            {
                self.columns.push(c);
            }
        }
    }

    /// Keeps the implicit step's matrix terms of the linearised contact `(K₆, D₆)` ([`surface_matrices`];
    /// `None`: no point touches): `Jᵀ G₆ J` with `G₆ = dt² K₆ + dt D₆` over the pattern of `tree` (the
    /// columns lie on one root path, increasing). Follow with [`Surface::set_rhs`].
    pub(crate) fn set_matrices(
        &mut self,
        matrices: Option<(Matrix6<f64>, Matrix6<f64>)>,
        dt: f64,
        tree: &TreeCholesky,
    ) {
        self.active = matrices.is_some();
        let Some((k6, d6)) = matrices else {
            return;
        };
        self.stiffness = k6;
        let g6 = k6 * (dt * dt) + d6 * dt;
        self.column_scratch.clear();
        for &c in &self.columns {
            let col: Vector6<f64> = self.jacobian.fixed_view::<6, 1>(0, c).into_owned();
            self.column_scratch.push((col, g6 * col));
        }
        self.matrix_terms.clear();
        for (n, &c) in self.columns.iter().enumerate() {
            let gc = &self.column_scratch[n].1;
            self.matrix_terms
                .push((tree.diagonal_index(c), self.column_scratch[n].0.dot(gc)));
            for (&r, (jr, _)) in self.columns[n + 1..]
                .iter()
                .zip(&self.column_scratch[n + 1..])
            {
                self.matrix_terms.push((tree.index(c, r), jr.dot(gc)));
            }
        }
    }

    /// Keeps the right-hand side terms `Jᵀ (W₀ − dt K₆ V)` of the start wrench `W₀` ([`start_wrench`]) with the
    /// stiffness of the last [`Surface::set_matrices`].
    pub(crate) fn set_rhs(&mut self, w0: &Vector6<f64>, dt: f64) {
        if !self.active {
            return;
        }
        let w = w0 - self.stiffness * self.twist * dt;
        self.rhs_terms.clear();
        for &c in &self.columns {
            self.rhs_terms
                .push(self.jacobian.fixed_view::<6, 1>(0, c).dot(&w));
        }
    }

    /// Adds the terms of the last [`Surface::set_matrices`] and [`Surface::set_rhs`] to the implicit system and its right-hand side.
    pub(crate) fn add_to(&self, system: &mut TreeMatrix, rhs: &mut DVector<f64>) {
        if !self.active {
            return;
        }
        for (&c, r) in self.columns.iter().zip(&self.rhs_terms) {
            rhs[c] += r;
        }
        let values = system.values_mut();
        for &(i, v) in &self.matrix_terms {
            values[i] += v;
        }
    }
}

/// A contact point with its memory (the stick anchor) and its per-step data.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Point {
    pub(crate) surface: usize,
    /// Position in the surface frame, m.
    pub(crate) local: Vector3<f64>,
    /// The area it stands for, m² ([`PointSpec::area`]).
    pub(crate) area: f64,
    pub(crate) law: PointLaw,
    /// Where the tangential spring is attached (on the ground), while in contact.
    pub(crate) anchor: Option<Vector3<f64>>,
    /// World position, m.
    pub(crate) position: Vector3<f64>,
    /// `position − surface origin` (world), m.
    pub(crate) arm: Vector3<f64>,
    /// World velocity, m/s.
    pub(crate) velocity: Vector3<f64>,
    /// Depth below the ground plane (negative: above), m.
    pub(crate) penetration: f64,
    pub(crate) mode: ContactMode,
    /// Unit tangential direction of the friction force while sliding.
    slide_direction: Vector3<f64>,
    /// Normal force the sliding friction is scaled with (previous iteration), N.
    normal_force_estimate: f64,
    /// Force at the start of the step with the current mode (`f₀`), N.
    force_start: Vector3<f64>,
    /// Force applied during the step, N.
    pub(crate) force: Vector3<f64>,
    /// Velocity at the end of the step, m/s.
    velocity_end: Vector3<f64>,
}

impl Point {
    /// A separated point of surface `surface`.
    pub(crate) fn new(surface: usize, spec: &PointSpec) -> Self {
        Self {
            surface,
            local: spec.local,
            area: spec.area,
            law: spec.law,
            anchor: None,
            position: Vector3::zeros(),
            arm: Vector3::zeros(),
            velocity: Vector3::zeros(),
            penetration: 0.0,
            mode: ContactMode::Separated,
            slide_direction: Vector3::zeros(),
            normal_force_estimate: 0.0,
            force_start: Vector3::zeros(),
            force: Vector3::zeros(),
            velocity_end: Vector3::zeros(),
        }
    }

    /// Position, velocity and penetration from the pose and mixed twist of its surface:
    /// `p = H l`, `v = v_s + ω_s × (p − o_s)`.
    pub(crate) fn place(
        &mut self,
        pose: &Isometry3<f64>,
        twist: &Vector6<f64>,
        ground: &GroundPlane,
    ) {
        self.position = (pose * Point3::from(self.local)).coords;
        self.arm = self.position - pose.translation.vector;
        self.velocity = lin(twist) + ang(twist).cross(&self.arm);
        self.penetration = -ground.height_of(&self.position);
    }

    /// The law from the ground's densities where the point is: `k_n = k A`, `b_n = b A`, and the tangential
    /// `k_t A`, `b_t A` (`A` its area).
    pub(crate) fn set_densities(
        &mut self,
        (normal, tangential): (NormalDensities, TangentialDensities),
    ) {
        self.law.normal_stiffness = normal.stiffness * self.area;
        self.law.normal_damping = normal.damping * self.area;
        self.law.tangential_stiffness = tangential.stiffness * self.area;
        self.law.tangential_damping = tangential.damping * self.area;
    }

    /// After the state was replaced: a penetrating point keeps its anchor (or sticks where it is), the others
    /// lose it; the force is the explicit estimate at the new state.
    pub(crate) fn restart(&mut self, ground: &GroundPlane) {
        if self.penetration > 0.0 {
            if self.anchor.is_none() {
                self.anchor = Some(ground.project(&self.position));
            }
        } else {
            self.anchor = None;
        }
        self.mode = if self.penetration > 0.0 {
            ContactMode::Sticking
        } else {
            ContactMode::Separated
        };
        let (force, mode) = self.explicit_force(ground);
        self.force = force;
        self.mode = mode;
    }

    /// Explicit force from the point's state (anchor, penetration, velocity), clamped to never pull and
    /// projected on the friction cone: `f_n = k δ − b δ̇`, `f_t = −k_t T(p − a) − b_t T v`, `|f_t| ≤ μ f_n`.
    pub(crate) fn explicit_force(&self, ground: &GroundPlane) -> (Vector3<f64>, ContactMode) {
        if self.penetration <= 0.0 {
            return (Vector3::zeros(), ContactMode::Separated);
        }
        let n = ground.normal;
        let law = &self.law;
        let fn_ =
            law.normal_stiffness * self.penetration - law.normal_damping * n.dot(&self.velocity);
        if fn_ <= 0.0 {
            return (Vector3::zeros(), ContactMode::Separated);
        }
        let anchor = self
            .anchor
            .unwrap_or_else(|| ground.project(&self.position));
        let ft = -ground.tangential(&(self.position - anchor)) * law.tangential_stiffness
            - ground.tangential(&self.velocity) * law.tangential_damping;
        let ftn = ft.norm();
        let limit = law.friction * fn_;
        if ftn > limit {
            (n * fn_ + ft * (limit / ftn), ContactMode::Sliding)
        } else {
            (n * fn_ + ft, ContactMode::Sticking)
        }
    }

    /// The explicit step of the point: its force at the start of the step (anchoring it when it touches down,
    /// dragging the anchor when it slides). Returns the force, N.
    pub(crate) fn explicit_step(&mut self, ground: &GroundPlane) -> Vector3<f64> {
        if self.penetration > 0.0 {
            if self.anchor.is_none() {
                self.anchor = Some(ground.project(&self.position));
            }
            self.mode = ContactMode::Sticking;
        } else {
            self.mode = ContactMode::Separated;
            self.anchor = None;
        }
        let (f, mode) = self.explicit_force(ground);
        self.force = f;
        self.mode = mode;
        self.velocity_end = self.velocity;
        if mode == ContactMode::Sliding {
            self.anchor = Some(
                ground.project(&self.position)
                    + ground.tangential(&f) / self.law.tangential_stiffness,
            );
        }
        f
    }

    /// Start of an implicit step: a penetrating point sticks (anchored where it is if it just touched down),
    /// the others are separated.
    pub(crate) fn begin_implicit_step(&mut self, ground: &GroundPlane) {
        if self.penetration > 0.0 {
            self.mode = ContactMode::Sticking;
            if self.anchor.is_none() {
                self.anchor = Some(ground.project(&self.position));
            }
        } else {
            self.mode = ContactMode::Separated;
        }
        self.normal_force_estimate = 0.0;
    }

    /// Force at the start of the step in the current (non-separated) mode, `f₀ = n (k δ − b n·v) + f_t`, with
    /// the stick spring `f_t = −k_t T(p − a) − b_t T v` or the sliding friction `μ f_n ê`; kept as `force_start`.
    fn start_force(&mut self, ground: &GroundPlane) -> Vector3<f64> {
        let n = ground.normal;
        let law = &self.law;
        let vn = n.dot(&self.velocity);
        let mut f0 = n * (law.normal_stiffness * self.penetration - law.normal_damping * vn);
        match self.mode {
            ContactMode::Sticking => {
                let anchor = self.anchor.unwrap_or(self.position);
                f0 -= ground.tangential(&(self.position - anchor)) * law.tangential_stiffness;
                f0 -= ground.tangential(&self.velocity) * law.tangential_damping;
            }
            ContactMode::Sliding => {
                f0 += self.slide_direction * (law.friction * self.normal_force_estimate);
            }
            ContactMode::Separated => {}
        }
        self.force_start = f0;
        f0
    }

    /// After an implicit solve: the end-of-step force `f = f₀ − K v⁺ dt − D a dt` (`a` the point's acceleration
    /// from the surface's `J ν̇`), and the mode the solution implies: a pulling point separates, a sticking
    /// point outside the friction cone slides, a sliding point whose slip reverses sticks, a sliding point
    /// whose normal force moved updates its estimate. Returns what changed.
    pub(crate) fn settle(
        &mut self,
        surface_acceleration: &Vector6<f64>,
        ground: &GroundPlane,
        dt: f64,
    ) -> Change {
        if self.mode == ContactMode::Separated {
            self.force = Vector3::zeros();
            self.velocity_end = self.velocity;
            return Change::None;
        }
        let n = ground.normal;
        let acc = lin(surface_acceleration) + ang(surface_acceleration).cross(&self.arm);
        let v_end = self.velocity + acc * dt;
        let (k, d) = self.law.matrices(self.mode, &n);
        let f = self.force_start - k * v_end * dt - d * acc * dt;
        self.force = f;
        self.velocity_end = v_end;
        let fn_end = n.dot(&f);
        if fn_end < 0.0 {
            self.mode = ContactMode::Separated;
            self.force = Vector3::zeros();
            return Change::Mode;
        }
        match self.mode {
            ContactMode::Sticking => self.leave_cone(&ground.tangential(&f), fn_end),
            ContactMode::Sliding => self.stop_or_track_slip(ground, &v_end, fn_end),
            ContactMode::Separated => Change::None,
        }
    }

    /// A sticking point whose tangential force `ft` exceeds the cone `μ f_n` starts sliding along `ft`.
    fn leave_cone(&mut self, ft: &Vector3<f64>, fn_end: f64) -> Change {
        let ftn = ft.norm();
        if ftn > self.law.friction * fn_end * (1.0 + 1e-12) && ftn > 0.0 {
            self.mode = ContactMode::Sliding;
            self.slide_direction = ft / ftn;
            self.normal_force_estimate = fn_end;
            Change::Mode
        } else {
            Change::None
        }
    }

    /// A sliding point whose end velocity runs along the friction force (the slip stopped within the step)
    /// sticks again with its spring on the cone; otherwise its normal force estimate follows `fn_end`
    /// (to 1e-6 relative), which changes only its force at the start of the step.
    fn stop_or_track_slip(
        &mut self,
        ground: &GroundPlane,
        v_end: &Vector3<f64>,
        fn_end: f64,
    ) -> Change {
        let mu = self.law.friction;
        let vt = ground.tangential(v_end);
        if vt.dot(&self.slide_direction) > 1e-9 {
            self.mode = ContactMode::Sticking;
            self.anchor = Some(
                ground.project(&self.position)
                    + self.slide_direction
                        * (mu * self.normal_force_estimate / self.law.tangential_stiffness),
            );
            Change::Mode
        } else if (fn_end - self.normal_force_estimate).abs()
            > 1e-6 * (1.0 + self.normal_force_estimate)
        {
            self.normal_force_estimate = fn_end;
            Change::Force
        } else {
            Change::None
        }
    }

    /// After an accepted step: a separated point forgets its anchor, a sliding point's anchor follows the
    /// slip so that its spring sits on the cone at the end of the step.
    pub(crate) fn commit(&mut self, ground: &GroundPlane, dt: f64) {
        match self.mode {
            ContactMode::Separated => self.anchor = None,
            ContactMode::Sticking => {}
            ContactMode::Sliding => {
                let end = self.position + self.velocity_end * dt;
                self.anchor = Some(
                    ground.project(&end)
                        + ground.tangential(&self.force) / self.law.tangential_stiffness,
                );
            }
        }
    }
}

/// The configured contact surfaces of `model` and all their points, surface by surface.
pub(crate) fn build_surfaces(
    model: &Model,
    config: &ContactConfig,
) -> Result<(Vec<Surface>, Vec<Point>), SimError> {
    let mut surfaces = Vec::with_capacity(config.surfaces.len());
    let mut points = Vec::new();
    for (si, sc) in config.surfaces.iter().enumerate() {
        let parameter = |key: &str| format!("contact.surfaces[{}].{key}", sc.name);
        let frame = find_frame(model, &parameter("frame"), &sc.frame)?;
        let ft_frame = match &sc.ft_sensor {
            Some(name) => Some(find_frame(model, &parameter("ft_sensor"), name)?),
            None => None,
        };
        let specs = surface_points(sc, config);
        surfaces.push(Surface::new(
            frame,
            ft_frame,
            points.len(),
            specs.len(),
            model.nv(),
        ));
        points.extend(specs.iter().map(|spec| Point::new(si, spec)));
    }
    Ok((surfaces, points))
}

/// The linearised contact stiffness and damping of one surface for the implicit step: `(K₆, D₆)` with
/// `K₆ = Σ Pᵢᵀ Kᵢ Pᵢ`, `D₆ = Σ Pᵢᵀ Dᵢ Pᵢ`, `Pᵢ = [I, −(rᵢ×)]` (surface twist → point velocity), over the points
/// in contact in their current modes ([`PointLaw::matrices`]). `None` when every point is separated.
pub(crate) fn surface_matrices(
    points: &[Point],
    ground: &GroundPlane,
) -> Option<(Matrix6<f64>, Matrix6<f64>)> {
    let n = ground.normal;
    let mut stiffness = PointSum::default();
    let mut damping = PointSum::default();
    let mut active = false;
    for p in points {
        let law = &p.law;
        // `K = α I + β n nᵀ` and the same for `D`, as in `PointLaw::matrices`.
        let ((k_alpha, k_beta), (d_alpha, d_beta)) = match p.mode {
            ContactMode::Separated => continue,
            ContactMode::Sticking => (
                (
                    law.tangential_stiffness,
                    law.normal_stiffness - law.tangential_stiffness,
                ),
                (
                    law.tangential_damping,
                    law.normal_damping - law.tangential_damping,
                ),
            ),
            ContactMode::Sliding => ((0.0, law.normal_stiffness), (0.0, law.normal_damping)),
        };
        active = true;
        let u = join(&n, &p.arm.cross(&n));
        stiffness.add(k_alpha, k_beta, &p.arm, &u);
        damping.add(d_alpha, d_beta, &p.arm, &u);
    }
    active.then(|| (stiffness.matrix(), damping.matrix()))
}

/// The sum `Σ Pᵀ (α I + β n nᵀ) P` over the points of a surface, `P = [I, −R]`, `R = (r×)`: each point adds
/// `α [I, −R; R, −R²] + β u uᵀ` with `u = Pᵀ n = [n; r × n]` and `−R² = |r|² I − r rᵀ`, kept as the sums of
/// `α`, `α r`, `α (|r|² I − r rᵀ)` and `β u uᵀ` (its upper triangle, row by row).
#[derive(Default)]
struct PointSum {
    alpha: f64,
    alpha_r: Vector3<f64>,
    alpha_rr: Matrix3<f64>,
    beta_uu: [f64; 21],
}

impl PointSum {
    /// Adds a point at `r` (from the surface origin) with `α`, `β` and `u`.
    fn add(&mut self, alpha: f64, beta: f64, r: &Vector3<f64>, u: &Vector6<f64>) {
        if alpha != 0.0 {
            self.alpha += alpha;
            self.alpha_r += r * alpha;
            self.alpha_rr += (Matrix3::identity() * r.norm_squared() - r * r.transpose()) * alpha;
        }
        let mut e = 0;
        for i in 0..6 {
            let bu = beta * u[i];
            for j in i..6 {
                self.beta_uu[e] += bu * u[j];
                e += 1;
            }
        }
    }

    /// The 6×6 sum.
    fn matrix(&self) -> Matrix6<f64> {
        let mut m = Matrix6::zeros();
        let mut e = 0;
        for i in 0..6 {
            for j in i..6 {
                m[(i, j)] = self.beta_uu[e];
                m[(j, i)] = self.beta_uu[e];
                e += 1;
            }
        }
        let r = skew(&self.alpha_r);
        for i in 0..3 {
            m[(i, i)] += self.alpha;
            for j in 0..3 {
                m[(i, j + 3)] -= r[(i, j)];
                m[(i + 3, j)] += r[(i, j)];
                m[(i + 3, j + 3)] += self.alpha_rr[(i, j)];
            }
        }
        m
    }
}

/// The contact wrench of one surface at the start of the step about its origin, `W₀ = Σ [f₀ᵢ; rᵢ × f₀ᵢ]` over
/// the points in contact in their current modes (N, N·m). Stores each point's `f₀`.
pub(crate) fn start_wrench(points: &mut [Point], ground: &GroundPlane) -> Vector6<f64> {
    let mut w0 = Vector6::zeros();
    for p in points {
        if p.mode == ContactMode::Separated {
            continue;
        }
        let f0 = p.start_force(ground);
        let t = p.arm.cross(&f0);
        w0 += join(&f0, &t);
    }
    w0
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The premise of finding a surface's columns once: the non-zero columns of every frame Jacobian of the
    /// bundled humanoid (mixed, as the simulator's) are the same at many states, far from the standing one.
    #[test]
    fn contact_jacobian_columns_do_not_depend_on_the_state() {
        use std::sync::Arc;
        use stride_model::{KinDyn, VelocityRepresentation};
        let model = Arc::new(stride_model::bundled::model().expect("bundled model"));
        let mut kd = KinDyn::new(Arc::clone(&model));
        kd.set_representation(VelocityRepresentation::Mixed);
        let mut state = stride_model::bundled::standing_state(&model).expect("standing state");
        let ids: Vec<_> = model
            .frames()
            .iter()
            .map(|f| model.frame_id(&f.name).expect("a frame's own name"))
            .collect();
        let mut surface = Surface::new(ids[0], None, 0, 0, model.nv());
        let mut columns = Vec::new();
        for (frame, &id) in ids.iter().enumerate() {
            surface.frame = id;
            for k in 0..40 {
                let x = k as f64;
                for (j, q) in state.joint_positions.iter_mut().enumerate() {
                    *q = if k == 0 {
                        0.0
                    } else {
                        3.0 * (1.3 * x + 0.7 * j as f64).sin()
                    };
                }
                for (j, v) in state.joint_velocities.iter_mut().enumerate() {
                    *v = (x + j as f64).cos();
                }
                state.base_pose.rotation = nalgebra::UnitQuaternion::from_euler_angles(
                    0.3 * x.sin(),
                    0.2 * x.cos(),
                    0.1 * x,
                );
                kd.set_state(&state).expect("state");
                kd.frame_jacobian(surface.frame, &mut surface.jacobian)
                    .expect("jacobian");
                surface.find_columns();
                if k == 0 {
                    columns.clone_from(&surface.columns);
                    assert!(columns.len() >= 6, "frame {frame}");
                } else {
                    assert_eq!(surface.columns, columns, "frame {frame}, state {k}");
                }
            }
        }
    }

    #[test]
    fn trapezoid_weights_sum_to_one_and_integrate_quadratics_in_the_limit() {
        for n in [1, 2, 3, 5, 9] {
            let s: f64 = trapezoid_nodes(n, 0.2).map(|(_, w)| w).sum();
            assert!((s - 1.0).abs() < 1e-15);
        }
        // Second moment → l²/12 as the grid refines.
        let l = 0.2;
        let m: f64 = trapezoid_nodes(2001, l).map(|(x, w)| w * x * x).sum();
        assert!((m - l * l / 12.0).abs() < 1e-6 * l * l);
    }

    #[test]
    fn surface_matrices_are_the_sum_of_the_point_matrices() {
        let ground = GroundPlane::from_config(&GroundConfig {
            height: 0.0,
            inclination: [0.05, -0.1],
            ..GroundConfig::default()
        });
        let law = PointLaw {
            normal_stiffness: 3e5,
            normal_damping: 2e3,
            tangential_stiffness: 1e5,
            tangential_damping: 5e2,
            friction: 0.8,
        };
        let spec = PointSpec {
            local: Vector3::zeros(),
            weight: 1.0,
            area: 1.0,
            law,
        };
        let mut points = Vec::new();
        for (k, mode) in [
            ContactMode::Sticking,
            ContactMode::Sliding,
            ContactMode::Separated,
            ContactMode::Sticking,
        ]
        .into_iter()
        .enumerate()
        {
            let mut p = Point::new(0, &spec);
            p.arm = Vector3::new(0.1 * k as f64 - 0.12, 0.03 * k as f64, -0.02);
            p.mode = mode;
            points.push(p);
        }
        let (k6, d6) = surface_matrices(&points, &ground).expect("touching");
        let (mut k_ref, mut d_ref) = (Matrix6::zeros(), Matrix6::zeros());
        for p in &points {
            let (k, d) = p.law.matrices(p.mode, &ground.normal);
            let mut map = nalgebra::Matrix3x6::zeros();
            map.fixed_view_mut::<3, 3>(0, 0)
                .copy_from(&Matrix3::identity());
            map.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-skew(&p.arm)));
            k_ref += map.transpose() * k * map;
            d_ref += map.transpose() * d * map;
        }
        assert!((k6 - k_ref).norm() < 1e-9 * k_ref.norm(), "{k6} vs {k_ref}");
        assert!((d6 - d_ref).norm() < 1e-9 * d_ref.norm(), "{d6} vs {d_ref}");
        for p in &mut points {
            p.mode = ContactMode::Separated;
        }
        assert!(surface_matrices(&points, &ground).is_none());
    }

    #[test]
    fn inclined_plane_descends_along_x_for_positive_pitch() {
        let g = GroundPlane::from_config(&GroundConfig {
            height: 0.0,
            inclination: [0.0, 0.1],
            ..GroundConfig::default()
        });
        assert!(g.height_of(&Vector3::new(1.0, 0.0, 0.0)) > 0.0);
        assert!((g.normal.norm() - 1.0).abs() < 1e-15);
        let p = Vector3::new(0.3, 0.2, 0.5);
        assert!(g.height_of(&g.project(&p)).abs() < 1e-15);
    }
}
