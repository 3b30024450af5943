//! Seeded random QPs with the shape of the whole-body problems, for tests and benchmarks (here and in
//! downstream crates).
//!
//! * [`RandomWbc::tsid_like`]: 62 variables (`accelerations` 38, `contact_forces` 24 = 8 points × 3), a hard
//!   18-row equality (dynamics + contact rows), 40 friction-pyramid / unilateral rows on the forces, 32
//!   two-sided torque-limit rows over all variables (= 64 one-sided rows; 104 one-sided inequalities in all),
//!   soft CoM, torso, posture and regularisation tasks.
//! * [`RandomWbc::ik_like`]: 38 variables (`base_velocity` 6, `joint_velocities` 32), a hard 12-row feet task,
//!   32 two-sided joint-velocity bounds (64 one-sided), soft torso, posture and regularisation tasks.
//!
//! Every problem is feasible by construction (a random point `x_f` satisfies all constraints for every `t`),
//! and the soft targets pull away from it so that a realistic number of inequalities is active.
//! [`RandomWbc::write`] fills the tasks for a time `t`; consecutive `t` give slowly varying problems (warm
//! start). No allocation in `write`.

use nalgebra::{DMatrix, DVector};

use crate::error::QpError;
use crate::problem::{QpProblem, QpSettings};
use crate::task::{TaskId, TaskSpec};
use crate::variables::{VarId, VariableSet};

/// A small deterministic generator (SplitMix64), so this module needs no `rand` dependency.
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// Seeded generator.
    pub fn new(seed: u64) -> Self {
        Self(seed ^ 0x9E37_79B9_7F4A_7C15)
    }
    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in `[lo, hi)`.
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        let u = (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * u
    }
    /// A `rows × cols` matrix with uniform entries in `[-s, s)`.
    pub fn matrix(&mut self, rows: usize, cols: usize, s: f64) -> DMatrix<f64> {
        DMatrix::from_fn(rows, cols, |_, _| self.uniform(-s, s))
    }
    /// A vector with uniform entries in `[lo, hi)`.
    pub fn vector(&mut self, len: usize, lo: f64, hi: f64) -> DVector<f64> {
        DVector::from_fn(len, |_, _| self.uniform(lo, hi))
    }
}

#[derive(Clone, Debug)]
enum Side {
    /// b(t) = A(t) x_point
    EqualityThrough(DVector<f64>),
    /// soft target b(t) = A(t) x_target + offset
    Target(DVector<f64>, DVector<f64>),
    /// l(t) = A(t) x_f − lo_margin, u(t) = A(t) x_f + hi_margin (margins may be ∞)
    Around(DVector<f64>, DVector<f64>),
    /// fixed sides
    Fixed(DVector<f64>, DVector<f64>),
}

#[derive(Clone, Debug)]
struct TaskData {
    id: TaskId,
    a0: DMatrix<f64>,
    a1: DMatrix<f64>,
    side: Side,
    xk: DVector<f64>,
    tmp: DVector<f64>,
    cols: Vec<usize>,
}

/// A random WBC-shaped problem plus the data that regenerates its numbers for any `t`.
pub struct RandomWbc {
    /// The problem (write it with [`RandomWbc::write`], then `problem.solve()`).
    pub problem: QpProblem,
    tasks: Vec<TaskData>,
    feasible_point: DVector<f64>,
}

impl RandomWbc {
    /// A feasible point of every problem of the family.
    pub fn feasible_point(&self) -> &DVector<f64> {
        &self.feasible_point
    }

    fn add(
        tasks: &mut Vec<TaskData>,
        problem: &QpProblem,
        name: &str,
        vars: &[VarId],
        a0: DMatrix<f64>,
        a1: DMatrix<f64>,
        side: Side,
    ) -> Result<(), QpError> {
        let id = problem.task_id(name).ok_or_else(|| QpError::UnknownTask {
            name: name.to_owned(),
        })?;
        let mut cols = Vec::new();
        for &v in vars {
            cols.extend(problem.variables().range(v));
        }
        let rows = a0.nrows();
        tasks.push(TaskData {
            id,
            xk: DVector::zeros(cols.len()),
            tmp: DVector::zeros(rows),
            a0,
            a1,
            side,
            cols,
        });
        Ok(())
    }

    /// Writes the task numbers for time `t` (allocation-free).
    pub fn write(&mut self, t: f64) {
        let (st, ct) = (t.sin(), (0.7 * t).cos() - 1.0);
        for td in &mut self.tasks {
            let task = self.problem.task_mut(td.id);
            let a = task.a_mut();
            a.zip_zip_apply(&td.a0, &td.a1, |v, a0, a1| *v = a0 + st * a1);
            let point = match &td.side {
                Side::EqualityThrough(p) | Side::Around(p, _) => Some(p),
                Side::Target(p, _) => Some(p),
                Side::Fixed(..) => None,
            };
            if let Some(p) = point {
                for (k, &c) in td.cols.iter().enumerate() {
                    td.xk[k] = p[c];
                }
                td.tmp.gemv(1.0, task.a(), &td.xk, 0.0);
            }
            match &td.side {
                Side::EqualityThrough(_) => task.b_mut().copy_from(&td.tmp),
                Side::Target(_, off) => {
                    let b = task.b_mut();
                    b.copy_from(&td.tmp);
                    b.axpy(1.0 + 0.2 * ct, off, 1.0);
                }
                Side::Around(_, margins) => {
                    let rows = td.tmp.len();
                    for i in 0..rows {
                        task.lower_mut()[i] = td.tmp[i] - margins[i];
                        task.upper_mut()[i] = td.tmp[i] + margins[rows + i];
                    }
                }
                Side::Fixed(l, u) => {
                    task.lower_mut().copy_from(l);
                    task.upper_mut().copy_from(u);
                }
            }
        }
    }

    /// TSID-shaped problem (see the module docs) with the given seed and settings.
    pub fn tsid_like(seed: u64, settings: QpSettings) -> Result<Self, QpError> {
        let mut rng = SplitMix64::new(seed);
        let mut vars = VariableSet::new();
        let acc = vars.add("accelerations", 38)?;
        let forces = vars.add("contact_forces", 24)?;
        let specs = vec![
            TaskSpec::equality("dynamics", &[acc, forces], 18),
            TaskSpec::inequality("friction", &[forces], 40),
            TaskSpec::inequality("torque_limits", &[acc, forces], 32),
            TaskSpec::equality("com", &[forces], 3).soft(10.0),
            TaskSpec::equality("torso", &[acc], 3).soft(5.0),
            TaskSpec::equality("posture", &[acc], 32).soft(1.0),
            TaskSpec::equality("regularization", &[acc, forces], 62).soft(1e-3),
        ];
        let problem = QpProblem::new(vars, specs, settings)?;
        let n = 62;
        // feasible point: accelerations in [-2, 2], forces with fz in [20, 60], |fx|,|fy| <= 3
        let mut xf = rng.vector(n, -2.0, 2.0);
        for p in 0..8 {
            xf[38 + 3 * p] = rng.uniform(-3.0, 3.0);
            xf[38 + 3 * p + 1] = rng.uniform(-3.0, 3.0);
            xf[38 + 3 * p + 2] = rng.uniform(20.0, 60.0);
        }
        let mut tasks = Vec::new();
        // dynamics: dense 18 x 62
        let a0 = rng.matrix(18, 62, 1.0);
        let a1 = rng.matrix(18, 62, 0.05);
        Self::add(
            &mut tasks,
            &problem,
            "dynamics",
            &[acc, forces],
            a0,
            a1,
            Side::EqualityThrough(xf.clone()),
        )?;
        // friction pyramid (mu = 0.5) + unilateral fz >= 5
        let mu = 0.5;
        let mut fr = DMatrix::zeros(40, 24);
        let mut upper = DVector::zeros(40);
        for p in 0..8 {
            let (r, c) = (5 * p, 3 * p);
            fr[(r, c)] = 1.0;
            fr[(r, c + 2)] = -mu;
            fr[(r + 1, c)] = -1.0;
            fr[(r + 1, c + 2)] = -mu;
            fr[(r + 2, c + 1)] = 1.0;
            fr[(r + 2, c + 2)] = -mu;
            fr[(r + 3, c + 1)] = -1.0;
            fr[(r + 3, c + 2)] = -mu;
            fr[(r + 4, c + 2)] = -1.0;
            upper[r + 4] = -5.0;
        }
        let lower = DVector::from_element(40, f64::NEG_INFINITY);
        Self::add(
            &mut tasks,
            &problem,
            "friction",
            &[forces],
            fr,
            DMatrix::zeros(40, 24),
            Side::Fixed(lower, upper),
        )?;
        // torque limits: dense rows, margins 0.5..5 on both sides
        let t0 = rng.matrix(32, 62, 1.0);
        let t1 = rng.matrix(32, 62, 0.05);
        let mut margins = rng.vector(64, 0.5, 5.0);
        margins[0] = margins[0].max(0.5);
        Self::add(
            &mut tasks,
            &problem,
            "torque_limits",
            &[acc, forces],
            t0,
            t1,
            Side::Around(xf.clone(), margins),
        )?;
        // soft tasks with targets away from x_f
        let mut target = xf.clone();
        for v in target.iter_mut() {
            *v += rng.uniform(-8.0, 8.0);
        }
        let com0 = rng.matrix(3, 24, 1.0);
        let com1 = rng.matrix(3, 24, 0.05);
        let off = rng.vector(3, -5.0, 5.0);
        Self::add(
            &mut tasks,
            &problem,
            "com",
            &[forces],
            com0,
            com1,
            Side::Target(target.clone(), off),
        )?;
        let torso0 = rng.matrix(3, 38, 1.0);
        let torso1 = rng.matrix(3, 38, 0.05);
        let off = rng.vector(3, -2.0, 2.0);
        Self::add(
            &mut tasks,
            &problem,
            "torso",
            &[acc],
            torso0,
            torso1,
            Side::Target(target.clone(), off),
        )?;
        let mut posture = DMatrix::zeros(32, 38);
        for i in 0..32 {
            posture[(i, 6 + i)] = 1.0;
        }
        let off = rng.vector(32, -3.0, 3.0);
        Self::add(
            &mut tasks,
            &problem,
            "posture",
            &[acc],
            posture,
            DMatrix::zeros(32, 38),
            Side::Target(target.clone(), off),
        )?;
        let reg = DMatrix::identity(62, 62);
        Self::add(
            &mut tasks,
            &problem,
            "regularization",
            &[acc, forces],
            reg,
            DMatrix::zeros(62, 62),
            Side::Target(xf.clone(), DVector::zeros(62)),
        )?;
        let mut s = Self {
            problem,
            tasks,
            feasible_point: xf,
        };
        s.write(0.0);
        Ok(s)
    }

    /// IK-shaped problem (see the module docs) with the given seed and settings.
    pub fn ik_like(seed: u64, settings: QpSettings) -> Result<Self, QpError> {
        let mut rng = SplitMix64::new(seed);
        let mut vars = VariableSet::new();
        let base = vars.add("base_velocity", 6)?;
        let joints = vars.add("joint_velocities", 32)?;
        let specs = vec![
            TaskSpec::equality("feet", &[base, joints], 12),
            TaskSpec::equality("torso", &[base, joints], 3).soft(5.0),
            TaskSpec::equality("posture", &[joints], 32).soft(1.0),
            TaskSpec::equality("regularization", &[base, joints], 38).soft(1e-3),
        ];
        let mut problem = QpProblem::new(vars, specs, settings)?;
        let n = 38;
        let xf = rng.vector(n, -0.5, 0.5);
        for j in 0..32 {
            let lo = xf[6 + j] - rng.uniform(0.2, 1.5);
            let hi = xf[6 + j] + rng.uniform(0.2, 1.5);
            problem.lower_bounds_mut(joints)[j] = lo;
            problem.upper_bounds_mut(joints)[j] = hi;
        }
        let mut tasks = Vec::new();
        let f0 = rng.matrix(12, 38, 1.0);
        let f1 = rng.matrix(12, 38, 0.05);
        Self::add(
            &mut tasks,
            &problem,
            "feet",
            &[base, joints],
            f0,
            f1,
            Side::EqualityThrough(xf.clone()),
        )?;
        let mut target = xf.clone();
        for v in target.iter_mut() {
            *v += rng.uniform(-2.5, 2.5);
        }
        let t0 = rng.matrix(3, 38, 1.0);
        let t1 = rng.matrix(3, 38, 0.05);
        let off = rng.vector(3, -1.0, 1.0);
        Self::add(
            &mut tasks,
            &problem,
            "torso",
            &[base, joints],
            t0,
            t1,
            Side::Target(target.clone(), off),
        )?;
        let posture = DMatrix::identity(32, 32);
        let off = rng.vector(32, -1.0, 1.0);
        Self::add(
            &mut tasks,
            &problem,
            "posture",
            &[joints],
            posture,
            DMatrix::zeros(32, 32),
            Side::Target(target.clone(), off),
        )?;
        Self::add(
            &mut tasks,
            &problem,
            "regularization",
            &[base, joints],
            DMatrix::identity(38, 38),
            DMatrix::zeros(38, 38),
            Side::Target(xf.clone(), DVector::zeros(38)),
        )?;
        let mut s = Self {
            problem,
            tasks,
            feasible_point: xf,
        };
        s.write(0.0);
        Ok(s)
    }
}
