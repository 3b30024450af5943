//! Warnings about the initial posture: soles on the ground and level, the planner's geometry against the
//! posture, and the simulated ground's rotational stiffness under a sole against the robot's toppling
//! stiffness.

use std::sync::Arc;

use nalgebra::{DVector, Isometry3, Vector3};
use stride_model::{FrameId, KinDyn, Model, RobotState};
use stride_sim::{surface_points, ContactConfig, ContactSurfaceConfig};

use crate::config::ScenarioConfig;
use crate::robot::RobotError;

/// Largest height of the higher sole above the ground in the standing posture before a warning \[m\].
pub const SOLE_HEIGHT_TOLERANCE: f64 = 0.002;
/// Largest tilt of a sole from level in the standing posture before a warning \[deg\].
pub const SOLE_TILT_TOLERANCE_DEG: f64 = 1.0;
/// Largest depth of a foot's collision geometry below its sole frame before a warning \[m\].
pub const SOLE_GEOMETRY_TOLERANCE: f64 = 0.005;
/// Largest relative difference between `planner.com_height` and the posture's CoM height [-].
pub const COM_HEIGHT_TOLERANCE: f64 = 0.05;
/// Largest relative difference between `planner.nominal_width` and the posture's feet distance [-].
pub const WIDTH_TOLERANCE: f64 = 0.10;
/// The ground's roll (and pitch) stiffness under a sole must be at least this multiple of `m g h` [-].
pub const GROUND_STIFFNESS_MARGIN: f64 = 2.0;

/// The robot standing at its initial posture (left sole level at z = 0, as the runner starts it).
#[derive(Debug, Clone)]
pub struct Stance {
    /// World poses of the left and right sole.
    pub soles: [Isometry3<f64>; 2],
    /// CoM position, world \[m\].
    pub com: Vector3<f64>,
    /// Total mass \[kg\].
    pub mass: f64,
    /// Gravity magnitude \[m/s²\].
    pub gravity: f64,
}

impl Stance {
    /// The stance of `model` at joint positions `q` with sole frames `soles`.
    pub fn new(
        model: &Arc<Model>,
        q: &DVector<f64>,
        soles: [FrameId; 2],
    ) -> Result<Self, RobotError> {
        let state = RobotState::standing(model, q, soles[0], soles[1])?;
        let mut kd = KinDyn::new(Arc::clone(model));
        kd.set_state(&state)?;
        Ok(Self {
            soles: [kd.frame_pose(soles[0]), kd.frame_pose(soles[1])],
            com: kd.com_position(),
            mass: model.total_mass(),
            gravity: model.gravity().norm(),
        })
    }

    /// CoM height above the lower sole \[m\].
    pub fn com_height(&self) -> f64 {
        self.com.z - self.soles[0].translation.z.min(self.soles[1].translation.z)
    }

    /// Lateral distance between the soles: the right sole's origin seen from the left sole, along its
    /// y axis \[m\].
    pub fn feet_width(&self) -> f64 {
        let rel = self.soles[0].inverse() * self.soles[1];
        -rel.translation.y
    }

    /// The toppling stiffness `m g h` of an inverted pendulum of the robot's mass at its CoM height: the
    /// gravity torque per radian of tilt about the sole \[N·m/rad\].
    pub fn toppling_stiffness(&self) -> f64 {
        self.mass * self.gravity * self.com_height()
    }
}

/// Soles on the ground and level; planner geometry against the posture.
pub fn posture_warnings(c: &ScenarioConfig, stance: &Stance) -> Vec<String> {
    let mut out = Vec::new();
    for (side, pose) in ["left", "right"].iter().zip(&stance.soles) {
        let key = format!("robot.{side}_sole");
        let z = pose.translation.z;
        if z > SOLE_HEIGHT_TOLERANCE {
            out.push(format!(
                "`{key}`: {:.1} mm above the ground in the initial posture (the other sole is on it); \
                 expected both soles on the ground (check robot.initial_joint_positions and the sole frames)",
                z * 1e3
            ));
        }
        let up = pose.rotation * Vector3::z();
        let tilt = up.angle(&Vector3::z()).to_degrees();
        if tilt > SOLE_TILT_TOLERANCE_DEG {
            out.push(format!(
                "`{key}`: tilted {tilt:.1}° from level in the initial posture; expected z up, level soles"
            ));
        }
    }
    let h = stance.com_height();
    let planned = c.planner.com_height;
    if (planned - h).abs() > COM_HEIGHT_TOLERANCE * h {
        out.push(format!(
            "`planner.com_height` = {planned} m, but the initial posture's CoM is {h:.3} m above the soles \
             (more than {:.0} % apart); expected about {h:.3}",
            COM_HEIGHT_TOLERANCE * 100.0
        ));
    }
    let w = stance.feet_width();
    let nominal = c.planner.nominal_width;
    if (nominal - w).abs() > WIDTH_TOLERANCE * w {
        out.push(format!(
            "`planner.nominal_width` = {nominal} m, but the soles are {w:.3} m apart in the initial posture \
             (more than {:.0} % apart); expected about {w:.3}",
            WIDTH_TOLERANCE * 100.0
        ));
    }
    if w < c.planner.min_width {
        out.push(format!(
            "`planner.min_width` = {} m is wider than the initial posture's {w:.3} m between the soles",
            c.planner.min_width
        ));
    }
    out
}

/// Rotational stiffness of the simulated ground under one contact surface, about the axes through its
/// centre of stiffness along the surface frame's x (roll) and y (pitch) \[N·m/rad\].
///
/// Each grid point `i` is a normal spring of stiffness `k_i = k · L · W · w_i` (`w_i` its
/// trapezoidal-rule weight, [`surface_points`]), so tilting the surface by `θ` about x loads it with
/// `k_i (y_i − ȳ) θ` and `K_roll = Σ k_i (y_i − ȳ)²` (ȳ the stiffness-weighted mean). For a continuous
/// rectangle this is `k L W³ / 12`; for the default 3-point grid across the width the trapezoidal
/// weights give `k L W³ / 8`.
pub fn ground_rotational_stiffness(
    surface: &ContactSurfaceConfig,
    contact: &ContactConfig,
) -> (f64, f64) {
    let points = surface_points(surface, contact);
    let total: f64 = points.iter().map(|p| p.law.normal_stiffness).sum();
    if total <= 0.0 {
        return (0.0, 0.0);
    }
    let mean = points
        .iter()
        .map(|p| p.local * p.law.normal_stiffness)
        .sum::<Vector3<f64>>()
        / total;
    let moment = |axis: usize| {
        points
            .iter()
            .map(|p| p.law.normal_stiffness * (p.local[axis] - mean[axis]).powi(2))
            .sum::<f64>()
    };
    (moment(1), moment(0))
}

/// The simulated ground under each contact surface against the toppling stiffness `m g h`: a warning
/// per surface whose roll or pitch stiffness is below [`GROUND_STIFFNESS_MARGIN`] `· m g h` (the foot
/// then rolls on the ground before the ZMP reaches the sole's edge).
pub fn ground_warnings(c: &ScenarioConfig, stance: &Stance) -> Vec<String> {
    let mgh = stance.toppling_stiffness();
    let mut out = Vec::new();
    for (i, s) in c.sim.contact.surfaces.iter().enumerate() {
        let (roll, pitch) = ground_rotational_stiffness(s, &c.sim.contact);
        for (axis, k) in [("roll", roll), ("pitch", pitch)] {
            if k < GROUND_STIFFNESS_MARGIN * mgh {
                out.push(format!(
                    "`sim.contact.surfaces[{i}]` ({}): the simulated ground's {axis} stiffness under it is \
                     {k:.0} N·m/rad, below {GROUND_STIFFNESS_MARGIN}× the robot's toppling stiffness m·g·h \
                     = {mgh:.0} N·m/rad (m = {:.1} kg, h = {:.3} m): the foot will roll on the ground; raise \
                     `sim.contact.normal_stiffness` (now {} N/m³) to at least {:.3e} N/m³",
                    s.name,
                    stance.mass,
                    stance.com_height(),
                    c.sim.contact.normal_stiffness,
                    c.sim.contact.normal_stiffness * GROUND_STIFFNESS_MARGIN * mgh / k.max(f64::MIN_POSITIVE)
                ));
            }
        }
    }
    out
}

/// A warning per sole frame that the foot's collision geometry reaches more than
/// [`SOLE_GEOMETRY_TOLERANCE`] below (the frame is then above the sole, e.g. an ankle link), or whose
/// geometry could not be read.
pub fn sole_geometry_warnings(
    urdf: &std::path::Path,
    model: &Arc<Model>,
    soles: [FrameId; 2],
) -> Vec<String> {
    let mut out = Vec::new();
    for (side, frame) in ["left", "right"].into_iter().zip(soles) {
        match crate::feet::collision_depth_below(urdf, model, frame) {
            Ok(Some(depth)) if depth > SOLE_GEOMETRY_TOLERANCE => out.push(format!(
                "`robot.{side}_sole`: the foot's collision geometry reaches {:.1} mm below the sole frame, \
                 so the frame is above the sole; `stride model feet` proposes one on the sole",
                depth * 1e3
            )),
            Ok(_) => {}
            Err(e) => out.push(format!(
                "`robot.{side}_sole`: the foot's collision geometry was not read: {e}"
            )),
        }
    }
    out
}
