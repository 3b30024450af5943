//! A complete plan (contacts, phases, swing trajectories, DCM segments) and its allocation-free sampler.

use nalgebra::{Isometry3, Vector2, Vector3, Vector6};
use serde::{Deserialize, Serialize};

use crate::contacts::{ContactList, Foot, Phase, PhaseKind};
use crate::dcm::{DcmSegment, PlanarState};
use crate::error::PlannerError;
use crate::swing::SwingTrajectory;
use stride_block::SupportPolygon;

/// Whether the plan reaches the goal.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum PlanOutcome {
    /// The plan ends standing at the goal (or after the commanded velocity duration).
    Complete,
    /// The planning horizon cut the motion: the plan is the feasible prefix, ending standing.
    HorizonReached {
        /// Distance \[m\] from the final mid-feet point to the goal.
        remaining_distance: f64,
        /// Yaw difference \[rad\] between the final heading and the goal heading.
        remaining_yaw: f64,
    },
}

/// References for one foot at one instant (world frame, mixed representation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FootSample {
    /// Sole pose.
    pub pose: Isometry3<f64>,
    /// [linear velocity of the sole origin; angular velocity] \[m/s; rad/s\].
    pub twist: Vector6<f64>,
    /// [linear acceleration; angular acceleration] \[m/s²; rad/s²\].
    pub acceleration: Vector6<f64>,
    /// Whether the foot is planned to be on the ground.
    pub in_contact: bool,
}

impl Default for FootSample {
    fn default() -> Self {
        Self {
            pose: Isometry3::identity(),
            twist: Vector6::zeros(),
            acceleration: Vector6::zeros(),
            in_contact: true,
        }
    }
}

/// All references at one instant. Filled in place by [`Plan::sample`] without allocation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanSample {
    /// Plan time \[s\] the sample was taken at (after clamping to the plan start).
    pub time: f64,
    /// LIPM natural frequency ω \[1/s\].
    pub omega: f64,
    /// DCM position (z = CoM height above ground) \[m\].
    pub dcm_position: Vector3<f64>,
    /// DCM velocity \[m/s\].
    pub dcm_velocity: Vector3<f64>,
    /// ZMP (z = ground height) \[m\].
    pub zmp: Vector3<f64>,
    /// CoM position \[m\].
    pub com_position: Vector3<f64>,
    /// CoM velocity \[m/s\].
    pub com_velocity: Vector3<f64>,
    /// CoM acceleration \[m/s²\].
    pub com_acceleration: Vector3<f64>,
    /// Left foot.
    pub left: FootSample,
    /// Right foot.
    pub right: FootSample,
    /// Gait phase.
    pub phase: PhaseKind,
    /// Convex hull of the soles in contact (CCW, ground plane); `None` in a default sample (and never
    /// `None` in a sample of a plan: some foot is always in contact and the sole dimensions are valid).
    pub support_polygon: Option<SupportPolygon>,
}

impl Default for PlanSample {
    fn default() -> Self {
        Self {
            time: 0.0,
            omega: 0.0,
            dcm_position: Vector3::zeros(),
            dcm_velocity: Vector3::zeros(),
            zmp: Vector3::zeros(),
            com_position: Vector3::zeros(),
            com_velocity: Vector3::zeros(),
            com_acceleration: Vector3::zeros(),
            left: FootSample::default(),
            right: FootSample::default(),
            phase: PhaseKind::DoubleSupport,
            support_polygon: None,
        }
    }
}

impl PlanSample {
    /// The sample of one foot.
    pub fn foot(&self, foot: Foot) -> &FootSample {
        match foot {
            Foot::Left => &self.left,
            Foot::Right => &self.right,
        }
    }
}

/// A plan: everything the lower layers track, from `start_time` on. After `end_time` the robot stands
/// (both feet in contact, DCM at the feet mid-point, CoM converging to it).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// LIPM natural frequency ω = √(g/h) \[1/s\].
    pub omega: f64,
    /// CoM height above the ground \[m\].
    pub com_height: f64,
    /// Ground height (world z of the footsteps) \[m\].
    pub ground_height: f64,
    /// Sole length \[m\].
    pub foot_length: f64,
    /// Sole width \[m\].
    pub foot_width: f64,
    /// First instant of the plan \[s\].
    pub start_time: f64,
    /// End of the final double support \[s\].
    pub end_time: f64,
    /// Closed-form DCM/ZMP/CoM segments, contiguous, the last one unbounded.
    pub segments: Vec<DcmSegment>,
    /// Gait phases, contiguous from `start_time` to `end_time`.
    pub phases: Vec<Phase>,
    /// Contacts of the left foot.
    pub left_contacts: ContactList,
    /// Contacts of the right foot.
    pub right_contacts: ContactList,
    /// Swings of the left foot, by time.
    pub left_swings: Vec<SwingTrajectory>,
    /// Swings of the right foot, by time.
    pub right_swings: Vec<SwingTrajectory>,
    /// Whether the goal is reached.
    pub outcome: PlanOutcome,
    /// Times at which new plans were merged into this one.
    pub merge_times: Vec<f64>,
    /// For a waypoint goal: where the unicycle path of the plan's last part starts and how many of the
    /// goal's waypoints were passed before it (a step adjustment replans towards the waypoints not yet
    /// passed); `None` for the other goals.
    #[serde(default)]
    pub waypoint_progress: Option<WaypointProgress>,
}

/// Progress along a waypoint goal ([`Plan::waypoint_progress`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct WaypointProgress {
    /// Start pose of the unicycle path towards the remaining waypoints.
    pub origin: crate::geometry::Pose2,
    /// Number of the goal's waypoints already passed when that path was built.
    pub passed: usize,
}

impl Plan {
    /// Contacts of one foot.
    pub fn contacts(&self, foot: Foot) -> &ContactList {
        match foot {
            Foot::Left => &self.left_contacts,
            Foot::Right => &self.right_contacts,
        }
    }

    /// Swings of one foot.
    pub fn swings(&self, foot: Foot) -> &[SwingTrajectory] {
        match foot {
            Foot::Left => &self.left_swings,
            Foot::Right => &self.right_swings,
        }
    }

    /// All contacts of both feet sorted by activation time (then left before right).
    pub fn footsteps(&self) -> Vec<crate::contacts::PlannedContact> {
        let mut all: Vec<_> = self
            .left_contacts
            .contacts
            .iter()
            .chain(self.right_contacts.contacts.iter())
            .cloned()
            .collect();
        all.sort_by(|a, b| a.activation_time.total_cmp(&b.activation_time));
        all
    }

    /// Number of steps (swings of both feet).
    pub fn step_count(&self) -> usize {
        self.left_swings.len() + self.right_swings.len()
    }

    /// Gait phase at `t` (double support after `end_time`).
    pub fn phase_at(&self, t: f64) -> PhaseKind {
        let i = self.phases.partition_point(|p| p.start <= t);
        if i == 0 {
            return PhaseKind::DoubleSupport;
        }
        let p = &self.phases[i - 1];
        if t < p.end {
            p.kind
        } else {
            PhaseKind::DoubleSupport
        }
    }

    /// Planar DCM/ZMP/CoM at `t` (clamped to the plan start).
    pub fn planar_at(&self, t: f64) -> PlanarState {
        let t = t.max(self.start_time);
        let i = self.segments.partition_point(|s| s.start <= t).max(1) - 1;
        let s = &self.segments[i];
        s.evaluate_local(t - s.start, self.omega)
    }

    fn foot_at(&self, foot: Foot, t: f64) -> FootSample {
        let contacts = self.contacts(foot);
        if let Some(c) = contacts.active_at(t) {
            return FootSample {
                pose: c.pose,
                twist: Vector6::zeros(),
                acceleration: Vector6::zeros(),
                in_contact: true,
            };
        }
        let swings = self.swings(foot);
        let i = swings.partition_point(|s| s.lift_time <= t);
        if i > 0 && t < swings[i - 1].land_time {
            let st = swings[i - 1].evaluate(t);
            return FootSample {
                pose: st.pose,
                twist: st.twist,
                acceleration: st.acceleration,
                in_contact: false,
            };
        }
        // before the first contact (cannot happen for plans built by the planner): hold the nearest pose.
        let pose = contacts
            .last_before(t)
            .or_else(|| contacts.contacts.first())
            .map_or_else(Isometry3::identity, |c| c.pose);
        FootSample {
            pose,
            twist: Vector6::zeros(),
            acceleration: Vector6::zeros(),
            in_contact: true,
        }
    }

    /// Writes all references at time `t` \[s\] into `out`. Times before `start_time` (and NaN) are clamped to
    /// `start_time`; after `end_time` the robot stands. O(log n), no allocation.
    pub fn sample(&self, t: f64, out: &mut PlanSample) {
        let t = t.max(self.start_time);
        let st = self.planar_at(t);
        let h = self.com_height;
        let g = self.ground_height;
        out.time = t;
        out.omega = self.omega;
        out.dcm_position = Vector3::new(st.dcm.x, st.dcm.y, g + h);
        out.dcm_velocity = Vector3::new(st.dcm_velocity.x, st.dcm_velocity.y, 0.0);
        out.zmp = Vector3::new(st.zmp.x, st.zmp.y, g);
        out.com_position = Vector3::new(st.com.x, st.com.y, g + h);
        out.com_velocity = Vector3::new(st.com_velocity.x, st.com_velocity.y, 0.0);
        out.com_acceleration = Vector3::new(st.com_acceleration.x, st.com_acceleration.y, 0.0);
        out.left = self.foot_at(Foot::Left, t);
        out.right = self.foot_at(Foot::Right, t);
        out.phase = self.phase_at(t);
        let mut pts = [Vector2::zeros(); 8];
        let mut n = 0;
        for f in [&out.left, &out.right] {
            if f.in_contact {
                let c = SupportPolygon::foot_corners(&f.pose, self.foot_length, self.foot_width);
                pts[n..n + 4].copy_from_slice(&c);
                n += 4;
            }
        }
        out.support_polygon = SupportPolygon::convex_hull(&pts[..n]).ok();
    }

    /// Samples the whole plan every `dt` seconds from `start_time` to `end_time` (inclusive) into the JSON
    /// shape of `stride plan --json` (docs/cli.md). Allocates; meant for tools, not for control loops.
    pub fn report(&self, dt: f64) -> Result<PlanReport, PlannerError> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(PlannerError::InvalidTime {
                name: "dt",
                value: dt,
                reason: "must be finite and > 0",
            });
        }
        let span = self.end_time - self.start_time;
        let n = (span / dt + 1e-9).floor();
        if n > 1.0e7 {
            return Err(PlannerError::InvalidTime {
                name: "dt",
                value: dt,
                reason: "would produce more than 1e7 samples",
            });
        }
        let n = n as usize;
        let mut samples = Vec::with_capacity(n + 1);
        let mut s = PlanSample::default();
        for k in 0..=n {
            let t = self.start_time + k as f64 * dt;
            self.sample(t, &mut s);
            samples.push(SampleReport::from_sample(&s));
        }
        let footsteps = self
            .footsteps()
            .iter()
            .map(|c| FootstepReport {
                foot: c.foot,
                position: v3(&c.pose.translation.vector),
                orientation_xyzw: xyzw(&c.pose),
                activation_time: c.activation_time,
                deactivation_time: c.deactivation_time,
            })
            .collect();
        Ok(PlanReport {
            footsteps,
            samples,
            foot_size: FootSizeReport {
                length: self.foot_length,
                width: self.foot_width,
            },
        })
    }
}

fn v3(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

fn xyzw(h: &Isometry3<f64>) -> [f64; 4] {
    let q = h.rotation.coords;
    [q.x, q.y, q.z, q.w]
}

/// A contact in the `stride plan --json` output.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FootstepReport {
    /// `"left"` or `"right"`.
    pub foot: Foot,
    /// Sole position \[m\].
    pub position: [f64; 3],
    /// Sole orientation, quaternion \[x, y, z, w\].
    pub orientation_xyzw: [f64; 4],
    /// Touch-down time \[s\] (the plan start for the initial stance).
    pub activation_time: f64,
    /// Lift-off time \[s\]; `null` for the final stance.
    pub deactivation_time: Option<f64>,
}

/// A foot in a `stride plan --json` sample.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FootReport {
    /// Sole position \[m\].
    pub position: [f64; 3],
    /// Sole orientation \[x, y, z, w\].
    pub orientation_xyzw: [f64; 4],
    /// Linear velocity of the sole origin \[m/s\] (world).
    pub linear_velocity: [f64; 3],
    /// Angular velocity \[rad/s\] (world).
    pub angular_velocity: [f64; 3],
    /// Planned contact.
    pub in_contact: bool,
}

impl FootReport {
    fn from_sample(f: &FootSample) -> Self {
        Self {
            position: v3(&f.pose.translation.vector),
            orientation_xyzw: xyzw(&f.pose),
            linear_velocity: [f.twist[0], f.twist[1], f.twist[2]],
            angular_velocity: [f.twist[3], f.twist[4], f.twist[5]],
            in_contact: f.in_contact,
        }
    }
}

/// One sample of `stride plan --json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SampleReport {
    /// Time \[s\].
    pub time: f64,
    /// DCM position \[m\].
    pub dcm_position: [f64; 3],
    /// DCM velocity \[m/s\].
    pub dcm_velocity: [f64; 3],
    /// ZMP \[m\].
    pub zmp: [f64; 3],
    /// CoM position \[m\].
    pub com_position: [f64; 3],
    /// CoM velocity \[m/s\].
    pub com_velocity: [f64; 3],
    /// ω \[1/s\].
    pub omega: f64,
    /// Left foot.
    pub left_foot: FootReport,
    /// Right foot.
    pub right_foot: FootReport,
}

impl SampleReport {
    /// Converts a [`PlanSample`].
    pub fn from_sample(s: &PlanSample) -> Self {
        Self {
            time: s.time,
            dcm_position: v3(&s.dcm_position),
            dcm_velocity: v3(&s.dcm_velocity),
            zmp: v3(&s.zmp),
            com_position: v3(&s.com_position),
            com_velocity: v3(&s.com_velocity),
            omega: s.omega,
            left_foot: FootReport::from_sample(&s.left),
            right_foot: FootReport::from_sample(&s.right),
        }
    }
}

/// Sole size in `stride plan --json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FootSizeReport {
    /// Length \[m\].
    pub length: f64,
    /// Width \[m\].
    pub width: f64,
}

/// The whole `stride plan --json` object.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanReport {
    /// All contacts (initial stance included), by activation time.
    pub footsteps: Vec<FootstepReport>,
    /// Samples every `dt` from the plan start to its end.
    pub samples: Vec<SampleReport>,
    /// Sole size.
    pub foot_size: FootSizeReport,
}
