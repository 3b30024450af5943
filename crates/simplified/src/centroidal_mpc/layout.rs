//! Which contact is active at which stage, where its variables sit in the decision vector, and the
//! constant geometry of each contact (corners, cone generators).

use nalgebra::{Matrix3x2, Rotation3, SMatrix, Vector3};

use super::config::CentroidalMpcConfig;
use super::io::{CentroidalMpcInput, MAX_MPC_CONTACTS};
use crate::error::{Result, SimplifiedError};

/// Corners of a sole rectangle (`n_v` of [Romualdi 2022, eq. 11.1.4]).
pub(crate) const CORNERS: usize = 4;
/// Generators of the linearised friction cone per corner.
pub(crate) const GENERATORS: usize = 4;
/// Cone coordinates per active contact and stage.
pub(crate) const CONTACT_VARIABLES: usize = CORNERS * GENERATORS;
/// Feet that can be in contact at once.
pub(crate) const MAX_ACTIVE: usize = 2;

/// An active contact at one stage: the input contact and the offset of its 16 cone coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Slot {
    pub contact: usize,
    pub offset: usize,
}

/// The variable layout of one tick: cone coordinates block by block (a block is `force_hold_stages`
/// consecutive stages sharing their corner forces), then the displacements `d_i` (sole frame x, y) of
/// the adjustable contacts. `stages[k]` lists the contacts active at stage `k` with their block's
/// variables.
#[derive(Debug, Clone)]
pub(crate) struct Layout {
    pub blocks: Vec<[Option<Slot>; MAX_ACTIVE]>,
    pub stages: Vec<[Option<Slot>; MAX_ACTIVE]>,
    pub displacement: [Option<usize>; MAX_MPC_CONTACTS],
    pub n: usize,
}

impl Layout {
    pub fn with_capacity(stages: usize) -> Self {
        Self {
            blocks: Vec::with_capacity(stages),
            stages: Vec::with_capacity(stages),
            displacement: [None; MAX_MPC_CONTACTS],
            n: 0,
        }
    }

    /// Contacts are active at stage `k` when the stage's midpoint `t₀ + (k + ½)·dt` is inside their
    /// activation interval (the schedule Γ_i of (11.1.4)); a block has variables for the contacts active
    /// at any of its stages; a contact is adjustable when it starts after `t₀ + min_remaining_time` and
    /// is active at some stage.
    pub fn build(
        &mut self,
        input: &CentroidalMpcInput,
        config: &CentroidalMpcConfig,
    ) -> Result<()> {
        let dt = config.stage_duration;
        let active = |c: &super::io::MpcContact, k: usize| {
            let t = input.t0() + (k as f64 + 0.5) * dt;
            c.activation <= t && t < c.deactivation
        };
        self.blocks.clear();
        self.stages.clear();
        self.displacement = [None; MAX_MPC_CONTACTS];
        let mut used = [false; MAX_MPC_CONTACTS];
        let mut n = 0;
        for first in (0..config.stages).step_by(config.force_hold_stages) {
            let last = (first + config.force_hold_stages).min(config.stages);
            let mut block = [None; MAX_ACTIVE];
            let mut count = 0;
            for (i, c) in input.contacts.iter().enumerate() {
                if !(first..last).any(|k| active(c, k)) {
                    continue;
                }
                if count == MAX_ACTIVE {
                    return Err(SimplifiedError::TooManyContacts {
                        count: count + 1,
                        reason: "more than two contacts active in one force block",
                    });
                }
                block[count] = Some(Slot {
                    contact: i,
                    offset: n,
                });
                used[i] = true;
                count += 1;
                n += CONTACT_VARIABLES;
            }
            self.blocks.push(block);
            for k in first..last {
                let mut slots = [None; MAX_ACTIVE];
                for (s, b) in slots.iter_mut().zip(block.iter()) {
                    *s = b.filter(|b| active(&input.contacts[b.contact], k));
                }
                self.stages.push(slots);
            }
        }
        for (i, c) in input.contacts.iter().enumerate() {
            if used[i] && c.activation > input.t0() + config.min_remaining_time {
                self.displacement[i] = Some(n);
                n += 2;
            }
        }
        self.n = n;
        Ok(())
    }
}

/// Constant geometry of one contact for a tick.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct ContactGeometry {
    /// Corner offsets `R c_j` in the world frame \[m\].
    pub corners: [Vector3<f64>; CORNERS],
    /// Cone generators (columns) in the world frame: a corner force is `G λ`, `λ ⪰ 0`.
    pub generators: SMatrix<f64, 3, GENERATORS>,
    /// Sole x and y axes in the world frame: `p_i = p_iⁿ + E d_i`.
    pub axes: Matrix3x2<f64>,
}

impl ContactGeometry {
    /// The corners `(±a, ±b, 0)` and the generators `(±μ/√2, ±μ/√2, 1)` in the sole frame, rotated by
    /// `yaw`. Their conic hull is the square pyramid inscribed in the Coulomb cone of friction `μ`
    /// (an inner linearisation: every force it allows satisfies `‖f_t‖ ≤ μ f_z`) [Romualdi 2022,
    /// eq. 11.1.13].
    pub fn new(yaw: f64, half_length: f64, half_width: f64, friction: f64) -> Self {
        let r = Rotation3::from_axis_angle(&Vector3::z_axis(), yaw);
        let s = friction / std::f64::consts::SQRT_2;
        let signs = [(1.0, 1.0), (1.0, -1.0), (-1.0, -1.0), (-1.0, 1.0)];
        let mut g = Self::default();
        for (j, (sx, sy)) in signs.iter().enumerate() {
            g.corners[j] = r * Vector3::new(sx * half_length, sy * half_width, 0.0);
            g.generators
                .set_column(j, &(r * Vector3::new(sx * s, sy * s, 1.0)));
        }
        let m = r.matrix();
        g.axes = Matrix3x2::from_columns(&[m.column(0).into_owned(), m.column(1).into_owned()]);
        g
    }
}
