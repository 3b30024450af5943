//! [`CentroidalMpc`]: one real-time iteration per tick on stride-qp's active-set solver.

use nalgebra::{DVector, Vector3};
use stride_qp::{ActiveSetSettings, ActiveSetSolver, DenseQp, QpSolver, SolverOutput};

use super::config::CentroidalMpcConfig;
use super::cost::{assemble, Tracking};
use super::dynamics::{Body, Condensed};
use super::io::{CentroidalMpcInput, CentroidalMpcOutput, MAX_MPC_CONTACTS};
use super::layout::{ContactGeometry, Layout, CONTACT_VARIABLES, CORNERS, GENERATORS, MAX_ACTIVE};
use super::linearization::Linearization;
use crate::error::{check_positive, Result, SimplifiedError};
use stride_block::Foot;

/// A foot's adjusted sole position and its four corner forces at one stage (None: not in contact).
pub type FootCornerForces = Option<(Vector3<f64>, [Vector3<f64>; CORNERS])>;

/// A QP and its solver for one problem size (the size changes with the contact schedule; each size is
/// allocated once, the first time it occurs, and warm-started from its own previous solve).
pub(crate) struct SizedQp {
    pub(super) qp: DenseQp,
    pub(super) solver: ActiveSetSolver,
    pub(super) out: SolverOutput,
}

impl SizedQp {
    fn new(n: usize, warm_start: bool) -> Self {
        let qp = DenseQp::new(n, 0, 0);
        let mut solver = ActiveSetSolver::new(ActiveSetSettings {
            warm_start,
            ..ActiveSetSettings::default()
        });
        solver.reserve(n, 0, 0);
        let out = SolverOutput::new(&qp);
        Self { qp, solver, out }
    }
}

/// The centroidal MPC with footstep adjustment [Romualdi 2022, §11.1] as a real-time iteration
/// [Diehl 2005]: each tick linearises the bilinear centroidal dynamics about the previous solution,
/// condenses the states and solves one QP in the cone coordinates and the contact displacements.
pub struct CentroidalMpc {
    pub(super) config: CentroidalMpcConfig,
    pub(super) body: Body,
    pub(super) layout: Layout,
    pub(super) geometry: [ContactGeometry; MAX_MPC_CONTACTS],
    pub(super) states: Condensed,
    pub(super) tracking: Tracking,
    pub(super) lin: Linearization,
    pub(super) sized: Vec<SizedQp>,
    pub(super) z: DVector<f64>,
    pub(super) output: CentroidalMpcOutput,
}

impl CentroidalMpc {
    /// Validates the config, checks `mass` \[kg\] and `gravity` \[m/s², magnitude along −z\] and allocates
    /// the buffers of the largest problem (two contacts at every stage).
    pub fn new(config: &CentroidalMpcConfig, mass: f64, gravity: f64) -> Result<Self> {
        config.validate()?;
        check_positive("mass", mass)?;
        check_positive("gravity", gravity)?;
        let n = config.stages;
        let max_variables = n * MAX_ACTIVE * CONTACT_VARIABLES + 2 * MAX_MPC_CONTACTS;
        Ok(Self {
            config: *config,
            body: Body {
                mass,
                gravity,
                dt: config.stage_duration,
                external_stages: config.external_stages(),
            },
            layout: Layout::with_capacity(n),
            geometry: [ContactGeometry::default(); MAX_MPC_CONTACTS],
            states: Condensed::new(n, max_variables),
            tracking: Tracking::new(n, max_variables),
            lin: Linearization::with_capacity(n),
            sized: Vec::with_capacity(4 * n),
            z: DVector::zeros(max_variables),
            output: CentroidalMpcOutput {
                predicted: Vec::with_capacity(n + 1),
                contacts: Vec::with_capacity(MAX_MPC_CONTACTS),
                ..CentroidalMpcOutput::default()
            },
        })
    }

    /// The configuration.
    pub fn config(&self) -> &CentroidalMpcConfig {
        &self.config
    }

    /// The last valid output.
    pub fn output(&self) -> &CentroidalMpcOutput {
        &self.output
    }

    /// The QP of the last tick (for checks with another backend or [`stride_qp::check_kkt`]).
    pub fn qp(&self) -> Option<&DenseQp> {
        self.sized
            .iter()
            .find(|s| s.qp.n() == self.layout.n)
            .map(|s| &s.qp)
    }

    /// The active-set output of the last tick.
    pub fn solver_output(&self) -> Option<&SolverOutput> {
        self.sized
            .iter()
            .find(|s| s.qp.n() == self.layout.n)
            .map(|s| &s.out)
    }

    /// Corner forces of the last solution at stage `k`, per foot (left, right; zero when not in contact)
    /// \[N\], and the adjusted sole positions of those contacts.
    pub fn corner_forces(&self, k: usize) -> [FootCornerForces; 2] {
        let mut out = [None; 2];
        let Some(slots) = self.layout.stages.get(k) else {
            return out;
        };
        for slot in slots.iter().flatten() {
            let c = &self.output.contacts[slot.contact];
            let idx = foot_index(c.planned.foot);
            out[idx] = Some((c.position, self.forces_of(slot.contact, slot.offset)));
        }
        out
    }

    /// World corner offsets of contact `i` of the last tick \[m\].
    pub fn corners(&self, i: usize) -> [Vector3<f64>; CORNERS] {
        self.geometry[i].corners
    }

    pub(super) fn forces_of(&self, contact: usize, offset: usize) -> [Vector3<f64>; CORNERS] {
        let g = &self.geometry[contact].generators;
        std::array::from_fn(|j| {
            let l = self.z.rows(offset + j * GENERATORS, GENERATORS);
            g * l
        })
    }

    /// Layout, geometry, linearisation point, condensed states, QP; returns the solve status.
    pub(super) fn solve(
        &mut self,
        input: &CentroidalMpcInput,
    ) -> Result<(stride_qp::QpStatus, usize, bool)> {
        let c = self.config;
        self.layout.build(input, &c)?;
        for (g, contact) in self.geometry.iter_mut().zip(&input.contacts) {
            *g = ContactGeometry::new(
                contact.yaw,
                input.foot_half_length,
                input.foot_half_width,
                c.friction,
            );
        }
        let weight = self.body.mass * self.body.gravity;
        self.lin
            .prepare(input, &self.layout, c.stage_duration, weight);
        self.states
            .propagate(input, &self.layout, &self.geometry, &self.lin, self.body);
        let n = self.layout.n;
        let (layout, geometry, states, lin) =
            (&self.layout, &self.geometry, &self.states, &self.lin);
        let tracking = &mut self.tracking;
        let i = match self.sized.iter().position(|s| s.qp.n() == n) {
            Some(i) => i,
            None => {
                self.sized.push(SizedQp::new(n, c.warm_start_active_set));
                self.sized.len() - 1
            }
        };
        let s = &mut self.sized[i];
        assemble(
            &mut s.qp, tracking, input, layout, geometry, states, lin, &c,
        );
        s.solver.solve(&s.qp, &mut s.out);
        let status = s.out.status;
        if !status.is_success() || !s.out.x.iter().all(|v| v.is_finite()) {
            return Err(SimplifiedError::CentroidalSolverFailed {
                status,
                iterations: s.out.iterations,
            });
        }
        self.z.rows_mut(0, n).copy_from(&s.out.x);
        Ok((status, s.out.iterations, s.out.warm_started))
    }
}

/// 0 for the left foot, 1 for the right.
pub(crate) fn foot_index(foot: Foot) -> usize {
    match foot {
        Foot::Left => 0,
        Foot::Right => 1,
    }
}
