//! The point the real-time iteration linearises about: the previous tick's solution, shifted in time
//! [Diehl 2005], or the nominal CoM with a static force split when there is none.

use nalgebra::{Vector2, Vector3};

use super::io::{CentroidalMpcInput, MpcContact, MAX_MPC_CONTACTS};
use super::layout::{Layout, CORNERS, MAX_ACTIVE};
use stride_block::Foot;

/// Corner forces of one contact at one stage, tagged with the contact's identity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct TaggedForces {
    pub foot: Foot,
    pub activation: f64,
    pub forces: [Vector3<f64>; CORNERS],
}

/// A contact is the same across ticks when the foot and the activation time (1 ms) agree.
fn same(foot: Foot, activation: f64, c: &MpcContact) -> bool {
    foot == c.foot && (activation - c.activation).abs() < 1e-3
}

/// The previous solution (what the next tick linearises about) and the current linearisation point.
#[derive(Debug, Clone)]
pub(crate) struct Linearization {
    valid: bool,
    time: f64,
    stage_duration: f64,
    com: Vec<Vector3<f64>>,
    forces: Vec<[Option<TaggedForces>; MAX_ACTIVE]>,
    displacements: [Option<(Foot, f64, Vector2<f64>)>; MAX_MPC_CONTACTS],
    /// Linearisation point of the current tick: CoM per stage, corner forces per stage and slot,
    /// displacement per contact.
    pub com_bar: Vec<Vector3<f64>>,
    pub force_bar: Vec<[[Vector3<f64>; CORNERS]; MAX_ACTIVE]>,
    pub displacement_bar: [Vector2<f64>; MAX_MPC_CONTACTS],
    /// The force applied at the previous tick per slot of block 0 (for the rate term of the first block).
    pub applied: [Option<[Vector3<f64>; CORNERS]>; MAX_ACTIVE],
}

impl Linearization {
    pub fn with_capacity(stages: usize) -> Self {
        Self {
            valid: false,
            time: 0.0,
            stage_duration: 0.0,
            com: Vec::with_capacity(stages + 1),
            forces: Vec::with_capacity(stages),
            displacements: [None; MAX_MPC_CONTACTS],
            com_bar: Vec::with_capacity(stages + 1),
            force_bar: Vec::with_capacity(stages),
            displacement_bar: [Vector2::zeros(); MAX_MPC_CONTACTS],
            applied: [None; MAX_ACTIVE],
        }
    }

    pub fn reset(&mut self) {
        self.valid = false;
    }

    /// Old stage index covering time `t` (clamped to the old horizon).
    fn old_stage(&self, t: f64, len: usize) -> usize {
        let s = ((t - self.time) / self.stage_duration).floor();
        (s.max(0.0) as usize).min(len.saturating_sub(1))
    }

    fn old_forces(&self, t: f64, c: &MpcContact) -> Option<[Vector3<f64>; CORNERS]> {
        if !self.valid || self.forces.is_empty() {
            return None;
        }
        let s = self.old_stage(t, self.forces.len());
        self.forces[s]
            .iter()
            .flatten()
            .find(|f| same(f.foot, f.activation, c))
            .map(|f| f.forces)
    }

    /// Fills the linearisation point of a tick (`mass`·`gravity` split evenly over the active corners
    /// where the previous solution has no force).
    pub fn prepare(&mut self, input: &CentroidalMpcInput, layout: &Layout, dt: f64, weight: f64) {
        self.com_bar.clear();
        for k in 0..=layout.stages.len() {
            let t = input.t0() + k as f64 * dt;
            let x = if self.valid && self.com.len() > 1 {
                let s =
                    ((t - self.time) / self.stage_duration).clamp(0.0, (self.com.len() - 1) as f64);
                let i = (s.floor() as usize).min(self.com.len() - 2);
                self.com[i].lerp(&self.com[i + 1], s - i as f64)
            } else {
                input.reference(k)
            };
            self.com_bar.push(x);
        }
        self.force_bar.clear();
        for (k, slots) in layout.stages.iter().enumerate() {
            let t = input.t0() + (k as f64 + 0.5) * dt;
            let active = slots.iter().flatten().count().max(1);
            let share = Vector3::new(0.0, 0.0, weight / (active * CORNERS) as f64);
            let mut bar = [[share; CORNERS]; MAX_ACTIVE];
            for (b, slot) in bar.iter_mut().zip(slots) {
                if let Some(f) = slot.and_then(|s| self.old_forces(t, &input.contacts[s.contact])) {
                    *b = f;
                }
            }
            self.force_bar.push(bar);
        }
        self.applied = [None; MAX_ACTIVE];
        if let Some(slots) = layout.blocks.first() {
            for (a, slot) in self.applied.iter_mut().zip(slots) {
                let old = self.valid.then(|| &self.forces[0]);
                *a = slot.and_then(|s| {
                    let c = &input.contacts[s.contact];
                    old?.iter()
                        .flatten()
                        .find(|f| same(f.foot, f.activation, c))
                        .map(|f| f.forces)
                });
            }
        }
        for (i, c) in input.contacts.iter().enumerate() {
            self.displacement_bar[i] = self
                .displacements
                .iter()
                .flatten()
                .find(|(foot, act, _)| self.valid && same(*foot, *act, c))
                .map_or(Vector2::zeros(), |d| d.2);
        }
    }

    /// Stores a solution: predicted CoM per stage, corner forces per stage and slot, displacements.
    pub fn store<'a>(
        &mut self,
        input: &CentroidalMpcInput,
        layout: &Layout,
        dt: f64,
        com: impl Iterator<Item = Vector3<f64>>,
        forces: impl Fn(usize, usize) -> [Vector3<f64>; CORNERS] + 'a,
        displacement: impl Fn(usize) -> Option<Vector2<f64>>,
    ) {
        self.valid = true;
        self.time = input.t0();
        self.stage_duration = dt;
        self.com.clear();
        self.com.extend(com);
        self.forces.clear();
        for (k, slots) in layout.stages.iter().enumerate() {
            let mut tagged = [None; MAX_ACTIVE];
            for (q, (t, slot)) in tagged.iter_mut().zip(slots).enumerate() {
                *t = slot.map(|s| {
                    let c = &input.contacts[s.contact];
                    TaggedForces {
                        foot: c.foot,
                        activation: c.activation,
                        forces: forces(k, q),
                    }
                });
            }
            self.forces.push(tagged);
        }
        self.displacements = [None; MAX_MPC_CONTACTS];
        for (i, c) in input.contacts.iter().enumerate() {
            self.displacements[i] = displacement(i).map(|d| (c.foot, c.activation, d));
        }
    }
}
