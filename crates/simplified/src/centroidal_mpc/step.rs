//! One tick of [`CentroidalMpc`]: solve, read the solution into the output, keep it as the next
//! linearisation point; the [`stride_block::Block`] implementation.

use std::time::Instant;

use nalgebra::{Vector2, Vector3};
use stride_qp::QpSolver;

use super::io::{
    AdjustedContact, CentroidalMpcDiagnostics, CentroidalMpcInput, CentroidalMpcOutput,
    CentroidalState,
};
use super::layout::CORNERS;
use super::mpc::{foot_index, CentroidalMpc};
use crate::error::{Result, SimplifiedError};

impl CentroidalMpc {
    /// Whether `value` sits on a side of `[lo, hi]` (1e-9).
    fn on_bound(value: f64, lo: f64, hi: f64) -> bool {
        value - lo <= 1e-9 * (1.0 + lo.abs()) || hi - value <= 1e-9 * (1.0 + hi.abs())
    }

    /// Writes the solution into the output and returns the largest gap between the linearised and the
    /// bilinear angular-momentum prediction (11.1.4).
    fn read_solution(&mut self, input: &CentroidalMpcInput) -> f64 {
        let n = self.layout.n;
        let z = self.z.rows(0, n);
        let out = &mut self.output;
        out.time = input.t0();
        out.stage_duration = self.config.stage_duration;
        out.predicted.clear();
        for k in 0..=self.layout.stages.len() {
            let [x, hp, hw] = self.states.state(k, &z);
            out.predicted.push(CentroidalState {
                com_position: x,
                com_velocity: hp / self.body.mass,
                angular_momentum: hw,
            });
        }
        out.contacts.clear();
        for (i, c) in input.contacts.iter().enumerate() {
            let od = self.layout.displacement[i];
            let (position, bound_active) = match od {
                Some(od) => {
                    let qp = self.sized.iter().find(|s| s.qp.n() == n).map(|s| &s.qp);
                    let active = qp.is_some_and(|qp| {
                        (0..2).any(|b| {
                            Self::on_bound(
                                z[od + b],
                                qp.lower_bounds()[od + b],
                                qp.upper_bounds()[od + b],
                            )
                        })
                    });
                    let d = Vector2::new(z[od], z[od + 1]);
                    (c.position + self.geometry[i].axes * d, active)
                }
                None => (c.position, false),
            };
            out.contacts.push(AdjustedContact {
                planned: *c,
                position,
                adjustable: od.is_some(),
                bound_active,
            });
        }
        let mut gap: f64 = 0.0;
        let mut hw = input.angular_momentum;
        let dt = self.config.stage_duration;
        for (k, slots) in self.layout.stages.iter().enumerate() {
            let x = self.output.predicted[k].com_position;
            for slot in slots.iter().flatten() {
                let p = self.output.contacts[slot.contact].position;
                let forces = self.forces_of(slot.contact, slot.offset);
                for (corner, f) in self.geometry[slot.contact].corners.iter().zip(&forces) {
                    hw += (p + corner - x).cross(f) * dt;
                }
            }
            gap = gap.max((hw - self.output.predicted[k + 1].angular_momentum).norm());
        }
        self.output.foot_forces = [Vector3::zeros(); 2];
        let (mut moment, mut normal) = (Vector2::zeros(), 0.0);
        for (idx, entry) in self.corner_forces(0).iter().enumerate() {
            let Some((p, forces)) = entry else { continue };
            let contact = self.layout.stages[0]
                .iter()
                .flatten()
                .find(|s| foot_index(input.contacts[s.contact].foot) == idx)
                .map_or(0, |s| s.contact);
            for (f, corner) in forces.iter().zip(self.corners(contact)) {
                self.output.foot_forces[idx] += f;
                moment += (p + corner).xy() * f.z;
                normal += f.z;
            }
        }
        self.output.desired_zmp = if normal > 0.0 {
            moment / normal
        } else {
            input.com_position.xy()
        };
        gap
    }

    /// Keeps the solution as the next tick's linearisation point.
    fn remember(&mut self, input: &CentroidalMpcInput) {
        let n = self.layout.n;
        let com = self.output.predicted.iter().map(|s| s.com_position);
        let (layout, geometry, z) = (&self.layout, &self.geometry, &self.z);
        let forces = |k: usize, q: usize| -> [Vector3<f64>; CORNERS] {
            layout.stages[k][q].map_or([Vector3::zeros(); CORNERS], |s| {
                let g = &geometry[s.contact].generators;
                std::array::from_fn(|j| g * z.fixed_rows::<4>(s.offset + 4 * j))
            })
        };
        let displacement = |i: usize| {
            layout.displacement[i]
                .filter(|&od| od + 1 < n)
                .map(|od| Vector2::new(z[od], z[od + 1]))
        };
        self.lin.store(
            input,
            layout,
            self.config.stage_duration,
            com,
            forces,
            displacement,
        );
    }
}

impl CentroidalMpc {
    /// One real-time iteration. On error (invalid input, too many contacts, QP failure) the previous
    /// output is kept ([`CentroidalMpc::output`]).
    ///
    /// Inherent, so a caller need not import [`stride_block::Block`] (the `Block` impl calls it).
    pub fn step(&mut self, input: &CentroidalMpcInput) -> Result<&CentroidalMpcOutput> {
        let start = Instant::now();
        input.validate()?;
        let (status, iterations, warm_started) = self.solve(input)?;
        let gap = self.read_solution(input);
        self.remember(input);
        self.output.valid = true;
        self.output.diagnostics = CentroidalMpcDiagnostics {
            status,
            iterations,
            variables: self.layout.n,
            warm_started,
            solve_time: start.elapsed().as_secs_f64(),
            linearization_gap: gap,
        };
        Ok(&self.output)
    }
}

impl stride_block::Block for CentroidalMpc {
    type Input = CentroidalMpcInput;
    type Output = CentroidalMpcOutput;
    type Error = SimplifiedError;

    fn step(&mut self, input: &CentroidalMpcInput) -> Result<&CentroidalMpcOutput> {
        CentroidalMpc::step(self, input)
    }

    fn reset(&mut self) {
        self.lin.reset();
        for s in &mut self.sized {
            s.solver.reset();
        }
        self.output.valid = false;
    }
}
