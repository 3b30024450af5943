//! The runner's side of the centroidal MPC (issue 13 part 2, `[simplified] dcm_controller =
//! "centroidal_mpc"`): its input from the plan and the measured state, its re-solve period, the swing
//! retargeting from its adjusted footstep and the `/planner/adjusted_footsteps` record.
//!
//! Every `update_period` (simplified ticks in between reuse the last prediction): the contacts of both
//! feet that are active inside the horizon (positions as planned before any adjustment of this layer, so
//! the box (11.1.14) stays around the nominal), the plan's CoM at the MPC's stages, the measured CoM and
//! CoM velocity (the estimator gives no angular momentum: zero). When the first adjustable contact is the
//! touch-down of the swing in progress and the MPC moved it by more than `deadband` from what the plan has,
//! [`stride_planner::Planner::adjust_step`] retargets the swing (same touch-down time) and replans the rest.

use std::time::Duration;

use nalgebra::Vector2;
use stride_block::seconds;
use stride_planner::{Foot, Plan, PlanSample, StepAdjustmentRequest};
use stride_simplified::{
    CentroidalMpc, CentroidalMpcConfig, CentroidalMpcInput, CentroidalMpcOutput, ComReference,
    MpcContact, SimplifiedError, SimplifiedInput,
};

use crate::step_adjust::AdjustedFootstepMsg;

/// Contacts whose nominal position this layer remembers (the ones it moved).
const REMEMBERED: usize = 4;

/// The centroidal MPC with its input buffer and the nominals of the contacts it moved; no allocation
/// after the first ticks (one QP per problem size, allocated when that size first occurs).
pub struct CentroidalLayer {
    mpc: CentroidalMpc,
    input: CentroidalMpcInput,
    next_solve: f64,
    nominals: [Option<(Foot, f64, Vector2<f64>)>; REMEMBERED],
    next_nominal: usize,
    mass: f64,
    /// Time and measured CoM velocity of the last solve.
    last_velocity: Option<(f64, nalgebra::Vector3<f64>)>,
}

/// What the layer reads of the robot at a tick (world frame, SI units).
#[derive(Debug, Clone, Copy)]
pub struct CentroidalMeasurement {
    /// Measured CoM \[m\].
    pub com: nalgebra::Vector3<f64>,
    /// Measured CoM velocity \[m/s\].
    pub com_velocity: nalgebra::Vector3<f64>,
    /// Sum of the estimated feet contact forces \[N\].
    pub feet_force: nalgebra::Vector3<f64>,
    /// Sole half length and half width \[m\].
    pub foot_half: (f64, f64),
    /// The push response's horizontal estimate of the external force (zero without it) \[N\].
    pub push_estimate: Vector2<f64>,
}

impl CentroidalLayer {
    /// The layer for a robot of `mass` \[kg\] under `gravity` \[m/s²\].
    pub fn new(
        config: &CentroidalMpcConfig,
        mass: f64,
        gravity: f64,
    ) -> Result<Self, SimplifiedError> {
        Ok(Self {
            mpc: CentroidalMpc::new(config, mass, gravity)?,
            input: CentroidalMpcInput::new(config.stages),
            next_solve: f64::NEG_INFINITY,
            nominals: [None; REMEMBERED],
            next_nominal: 0,
            mass,
            last_velocity: None,
        })
    }

    /// The last valid output.
    pub fn output(&self) -> &CentroidalMpcOutput {
        self.mpc.output()
    }

    /// The configuration.
    pub fn config(&self) -> &CentroidalMpcConfig {
        self.mpc.config()
    }

    fn nominal(&self, foot: Foot, activation: f64) -> Option<Vector2<f64>> {
        self.nominals
            .iter()
            .flatten()
            .find(|(f, a, _)| *f == foot && (a - activation).abs() < 1e-3)
            .map(|n| n.2)
    }

    /// Fills the MPC input at `time` from `plan` (`sample` is a scratch buffer).
    fn fill(
        &mut self,
        plan: &Plan,
        m: &CentroidalMeasurement,
        sample: &mut PlanSample,
        time: Duration,
    ) -> Result<(), SimplifiedError> {
        let t = seconds(time);
        let c = *self.mpc.config();
        let end = t + c.stage_duration * c.stages as f64;
        let external = self.external_force(m, t);
        let i = &mut self.input;
        i.time = time;
        (i.com_position, i.com_velocity) = (m.com, m.com_velocity);
        (i.foot_half_length, i.foot_half_width) = m.foot_half;
        i.external_force = external;
        i.contacts.clear();
        i.com_reference.clear();
        for foot in [Foot::Left, Foot::Right] {
            for pc in &plan.contacts(foot).contacts {
                let deactivation = pc.deactivation_time.unwrap_or(f64::INFINITY);
                if deactivation <= t || pc.activation_time >= end {
                    continue;
                }
                let mut position = pc.pose.translation.vector;
                if let Some(n) = self.nominal(foot, pc.activation_time) {
                    position.x = n.x;
                    position.y = n.y;
                }
                self.input.push_contact(MpcContact {
                    foot,
                    position,
                    yaw: pc.pose.rotation.euler_angles().2,
                    activation: pc.activation_time,
                    deactivation,
                })?;
            }
        }
        for k in 0..=c.stages {
            plan.sample(t + k as f64 * c.stage_duration, sample);
            self.input.com_reference.push(sample.com_position);
        }
        Ok(())
    }

    /// The horizontal external force \[N\]: with `push_estimate` the push response's estimate, with
    /// `external_force` `m ẍ − Σ f_feet` (zero at the first solve); zero when both are off or below the
    /// threshold. Remembers the velocity for the next solve.
    fn external_force(&mut self, m: &CentroidalMeasurement, t: f64) -> nalgebra::Vector3<f64> {
        let c = self.mpc.config();
        let last = self.last_velocity.replace((t, m.com_velocity));
        let mut f = if c.push_estimate {
            nalgebra::Vector3::new(m.push_estimate.x, m.push_estimate.y, 0.0)
        } else {
            let Some((t0, v0)) = last.filter(|(t0, _)| c.external_force && t > *t0) else {
                return nalgebra::Vector3::zeros();
            };
            (m.com_velocity - v0) * (self.mass / (t - t0)) - m.feet_force
        };
        f.z = 0.0;
        if f.norm() < c.external_force_threshold {
            f.fill(0.0);
        }
        f
    }

    /// Re-solves when `update_period` has passed since the last solve; `Ok(true)` when it solved.
    pub fn tick(
        &mut self,
        plan: &Plan,
        measurement: &CentroidalMeasurement,
        sample: &mut PlanSample,
        time: Duration,
    ) -> Result<bool, SimplifiedError> {
        let t = seconds(time);
        if t + 1e-9 < self.next_solve {
            return Ok(false);
        }
        self.next_solve = t + self.mpc.config().update_period;
        self.fill(plan, measurement, sample, time)?;
        self.mpc.step(&self.input)?;
        Ok(true)
    }

    /// Writes the prediction at `t` into the PI's planned references (`track_prediction`); returns it.
    pub fn write_references(&self, input: &mut SimplifiedInput, t: f64) -> ComReference {
        let r = self.output().reference_at(t);
        if self.config().track_prediction && self.output().valid {
            let w = input.omega;
            input.planned_com_position = r.position.xy();
            input.planned_com_velocity = r.velocity.xy();
            input.planned_dcm_position = (r.position + r.velocity / w).xy();
            input.planned_dcm_velocity = (r.velocity + r.acceleration / w).xy();
        }
        r
    }

    /// The swing retargeting the last solution asks for at `time`, if any (see the module documentation).
    pub fn request(&self, plan: &Plan, time: Duration) -> Option<StepAdjustmentRequest> {
        let out = self.output();
        let next = out.next_adjusted()?;
        let step = plan.current_step(seconds(time))?;
        let swing = step.swing;
        if swing.foot != next.planned.foot
            || (swing.land_time - next.planned.activation).abs() > 1e-3
        {
            return None;
        }
        let c = self.config();
        let target = next.position.xy();
        ((target - swing.end.translation.vector.xy()).norm() > c.deadband).then_some(
            StepAdjustmentRequest {
                time,
                target,
                land_time: swing.land_time,
                min_remaining: c.min_remaining_time,
            },
        )
    }

    /// Records that the planner applied `request`; returns the log record.
    pub fn applied(
        &mut self,
        plan_foot: Foot,
        request: &StepAdjustmentRequest,
        dcm: &Vector2<f64>,
    ) -> AdjustedFootstepMsg {
        let out = self.mpc.output();
        let next = out.next_adjusted().copied();
        let nominal = next.map_or(request.target, |n| n.planned.position.xy());
        if self.nominal(plan_foot, request.land_time).is_none() {
            self.nominals[self.next_nominal] = Some((plan_foot, request.land_time, nominal));
            self.next_nominal = (self.next_nominal + 1) % REMEMBERED;
        }
        AdjustedFootstepMsg {
            time: seconds(request.time),
            foot: plan_foot.name(),
            nominal_position: nominal.into(),
            position: request.target.into(),
            displacement: (request.target - nominal).into(),
            nominal_touchdown_time: request.land_time,
            touchdown_time: request.land_time,
            measured_dcm: (*dcm).into(),
            offset_slack: [0.0; 2],
            bound_active: next.is_some_and(|n| n.bound_active),
            qp_status: out.diagnostics.status,
            iterations: out.diagnostics.iterations,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn measurement(velocity: Vector3<f64>, feet: Vector3<f64>) -> CentroidalMeasurement {
        CentroidalMeasurement {
            com: Vector3::zeros(),
            com_velocity: velocity,
            feet_force: feet,
            foot_half: (0.06, 0.03),
            push_estimate: Vector2::zeros(),
        }
    }

    #[test]
    fn the_external_force_is_newtons_law_on_the_measurements() {
        let config = CentroidalMpcConfig {
            external_force: true,
            ..CentroidalMpcConfig::default()
        };
        let mut layer = CentroidalLayer::new(&config, 30.0, 9.81).unwrap();
        let weight = Vector3::new(0.0, 0.0, 30.0 * 9.81);
        // first solve: no previous velocity
        let still = measurement(Vector3::zeros(), weight);
        assert_eq!(layer.external_force(&still, 1.0), Vector3::zeros());
        // the CoM accelerates by (1, 0) m/s² while the feet push back by 20 N along −y:
        // f = m a − Σ f = (30, 20) N, vertical dropped
        let pushed = measurement(
            Vector3::new(0.05, 0.0, 0.0),
            weight + Vector3::new(0.0, -20.0, 0.0),
        );
        let f = layer.external_force(&pushed, 1.05);
        assert!((f - Vector3::new(30.0, 20.0, 0.0)).norm() < 1e-9, "{f}");
        // below the 30 N threshold: ignored
        let small = measurement(
            Vector3::new(0.05, 0.0, 0.0),
            weight + Vector3::new(-10.0, 0.0, 0.0),
        );
        assert_eq!(layer.external_force(&small, 1.1), Vector3::zeros());
        // disabled: always zero
        let mut off = CentroidalLayer::new(&CentroidalMpcConfig::default(), 30.0, 9.81).unwrap();
        off.external_force(&still, 1.0);
        assert_eq!(off.external_force(&pushed, 1.05), Vector3::zeros());
    }

    #[test]
    fn with_push_estimate_the_external_force_is_the_push_responses() {
        let config = CentroidalMpcConfig {
            push_estimate: true,
            ..CentroidalMpcConfig::default()
        };
        let mut layer = CentroidalLayer::new(&config, 30.0, 9.81).unwrap();
        let weight = Vector3::new(0.0, 0.0, 30.0 * 9.81);
        // the estimate as it is from the first solve, whatever the CoM does
        let mut m = measurement(Vector3::new(0.3, 0.0, 0.0), weight);
        m.push_estimate = Vector2::new(-35.0, 12.0);
        assert_eq!(
            layer.external_force(&m, 1.0),
            Vector3::new(-35.0, 12.0, 0.0)
        );
        // below the threshold: ignored
        m.push_estimate = Vector2::new(20.0, -10.0);
        assert_eq!(layer.external_force(&m, 1.05), Vector3::zeros());
    }
}
