//! How far the estimation layer's view of the robot is from the plant's truth: the figures of the
//! summary's `estimation` lines, accumulated at every whole-body tick.

use serde::Serialize;

use crate::robot::PlantTruth;
use crate::summary::ErrorStats;
use stride_estimation::EstimatorOutput;

/// Estimation errors of a run (estimate − truth).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct EstimationSummary {
    /// `ekf` or `ground_truth` (the controllers read the plant's truth: every error below is zero).
    pub kind: String,
    /// Horizontal base position error at the end, x and y, divided by the distance walked [m/m]
    /// (the drift; `None` when the robot walked less than 0.1 m).
    pub drift_per_metre: Option<[f64; 2]>,
    /// Horizontal base position error at the end, x and y \[m\].
    pub final_position_error: [f64; 2],
    /// Base height error `|z_est − z|` \[m\].
    pub height_error: ErrorStats,
    /// Base tilt error: angle between the estimated and the true vertical seen from the base \[rad\]
    /// (roll and pitch; the yaw is unobservable and reported apart).
    pub tilt_error: ErrorStats,
    /// Base yaw error at the end \[rad\].
    pub final_yaw_error: f64,
    /// Base linear velocity error `‖v_est − v‖` [m/s].
    pub velocity_error: ErrorStats,
    /// Whole-body ticks where a detected contact differs from the plant's, and all ticks compared.
    pub contact_disagreements: (u64, u64),
    /// Foot force error `‖f_est − f‖` of each foot at each tick (the ground's wrench on the foot, from the
    /// force/torque sensors) \[N\].
    pub foot_force_error: ErrorStats,
    /// Foot torque error `‖τ_est − τ‖` about the sole of each foot at each tick \[N·m\].
    pub foot_torque_error: ErrorStats,
}

impl EstimationSummary {
    /// An empty summary of the estimation `kind`.
    pub fn new(kind: &str) -> Self {
        Self {
            kind: kind.into(),
            ..Self::default()
        }
    }

    /// Adds one comparison of the estimate with the truth.
    pub(crate) fn add(&mut self, estimate: &EstimatorOutput, truth: &PlantTruth) {
        let (e, t) = (&estimate.state, &truth.state);
        let dp = e.base_pose.translation.vector - t.base_pose.translation.vector;
        self.final_position_error = [dp.x, dp.y];
        self.height_error.add(dp.z.abs());
        let up_e = e.base_pose.rotation.inverse() * nalgebra::Vector3::z();
        let up_t = t.base_pose.rotation.inverse() * nalgebra::Vector3::z();
        self.tilt_error.add(up_e.angle(&up_t));
        let yaw = |q: &nalgebra::UnitQuaternion<f64>| q.euler_angles().2;
        self.final_yaw_error = stride_planner::geometry::wrap_angle(
            yaw(&e.base_pose.rotation) - yaw(&t.base_pose.rotation),
        );
        let dv = e.base_velocity.fixed_rows::<3>(0) - t.base_velocity.fixed_rows::<3>(0);
        self.velocity_error.add(dv.norm());
        for (e, t) in estimate.foot_wrenches.iter().zip(&truth.foot_wrenches) {
            self.foot_force_error
                .add((e.fixed_rows::<3>(0) - t.fixed_rows::<3>(0)).norm());
            self.foot_torque_error
                .add((e.fixed_rows::<3>(3) - t.fixed_rows::<3>(3)).norm());
        }
        let (disagree, all) = &mut self.contact_disagreements;
        *all += 1;
        if estimate.contacts != truth.feet_in_contact {
            *disagree += 1;
        }
    }

    /// Sets the drift from the distance walked \[m\].
    pub(crate) fn finish(&mut self, distance: f64) {
        self.drift_per_metre = (distance >= 0.1).then(|| {
            [
                self.final_position_error[0] / distance,
                self.final_position_error[1] / distance,
            ]
        });
    }

    /// The summary's estimation lines.
    pub(crate) fn render(&self, s: &mut String) {
        use std::fmt::Write as _;
        if self.kind == "ground_truth" {
            let _ = writeln!(
                s,
                "  estimation: GROUND TRUTH (the controllers read the simulator's state; debugging only)"
            );
            return;
        }
        let drift = match self.drift_per_metre {
            Some([x, y]) => format!("{:.2} % / {:.2} %", x * 100.0, y * 100.0),
            None => "n/a (walked < 0.1 m)".into(),
        };
        let (disagree, all) = self.contact_disagreements;
        let _ = writeln!(
            s,
            "  estimation ({}): drift x/y {drift} of the distance (final error {:.1} / {:.1} mm), yaw {:.2}°",
            self.kind,
            self.final_position_error[0] * 1e3,
            self.final_position_error[1] * 1e3,
            self.final_yaw_error.to_degrees()
        );
        let _ = writeln!(
            s,
            "    height {:.1} mm RMS ({:.1} max), tilt {:.3}° RMS ({:.3} max), velocity {:.1} cm/s RMS ({:.1} max), \
             contacts differ {:.1} % of ticks",
            self.height_error.rms * 1e3,
            self.height_error.max * 1e3,
            self.tilt_error.rms.to_degrees(),
            self.tilt_error.max.to_degrees(),
            self.velocity_error.rms * 1e2,
            self.velocity_error.max * 1e2,
            if all > 0 { 100.0 * disagree as f64 / all as f64 } else { 0.0 }
        );
        let _ = writeln!(
            s,
            "    foot wrenches: force {:.2} N RMS ({:.1} max), torque {:.3} N m RMS ({:.2} max)",
            self.foot_force_error.rms,
            self.foot_force_error.max,
            self.foot_torque_error.rms,
            self.foot_torque_error.max
        );
    }
}
