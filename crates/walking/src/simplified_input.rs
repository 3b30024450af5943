//! Plan sample + measurements → the simplified layer's input: the rules the walking stack uses between
//! the planner and the simplified (DCM/ZMP) layer.

use std::time::Duration;

use nalgebra::{Isometry3, Vector2, Vector3};
use stride_block::{feet_support_polygon, seconds, FootRectangle, PolygonError, SupportPolygon};
use stride_planner::{Plan, PlanSample};
use stride_simplified::{HorizonSample, SimplifiedController, SimplifiedError, SimplifiedInput};

/// Why the simplified layer's input could not be filled.
#[derive(Debug, thiserror::Error)]
pub enum SimplifiedInputError {
    /// A support polygon of the measured or planned soles is degenerate (sole dimensions ≤ 0 or not
    /// finite, or a sole pose not finite).
    #[error("support polygon of the {which} soles: {source}")]
    Polygon {
        /// `"measured"` or `"planned"`.
        which: &'static str,
        /// The polygon's error.
        source: PolygonError,
    },
    /// The input's horizon buffer is smaller than the controller's horizon.
    #[error("MPC horizon: {0}")]
    Horizon(#[from] SimplifiedError),
}

/// The measured quantities the simplified layer reads, in the world frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeasuredCentroidal {
    /// CoM position \[m\].
    pub com: Vector3<f64>,
    /// CoM velocity \[m/s\].
    pub com_velocity: Vector3<f64>,
    /// DCM `ξ = x + ẋ/ω` (xy), with the plan's ω \[m\].
    pub dcm: Vector2<f64>,
    /// ZMP (xy; the walking stack passes the low-passed ZMP of the feet wrenches) \[m\].
    pub zmp: Vector2<f64>,
    /// Left and right sole poses.
    pub soles: [Isometry3<f64>; 2],
}

/// The support polygon of the soles `[left, right]` flagged in `contacts`: the convex hull of their
/// rectangles `foot_length` × `foot_width` \[m\] centred on the sole frames (planar position and yaw).
/// With no flag set (a flight phase, which a plan never has) both soles are used.
///
/// # Errors
/// [`PolygonError`] when the hull is degenerate (see [`SupportPolygon::convex_hull`]).
pub fn support_polygon(
    soles: &[Isometry3<f64>; 2],
    contacts: [bool; 2],
    foot_length: f64,
    foot_width: f64,
) -> Result<SupportPolygon, PolygonError> {
    let mut feet = [FootRectangle::centred(&soles[0], foot_length, foot_width); 2];
    let mut n = 0;
    for k in 0..2 {
        if contacts[k] || contacts == [false, false] {
            feet[n] = FootRectangle::centred(&soles[k], foot_length, foot_width);
            n += 1;
        }
    }
    feet_support_polygon(&feet[..n])
}

/// Fills a [`SimplifiedInput`] from the plan and the measurements, every simplified tick; allocation-free.
///
/// The rules (the walking stack's choices):
/// - **support polygon**: the *measured* soles flagged in contact by the *plan*
///   ([`support_polygon`]): the plan says which feet bear weight, the estimate says where they are;
/// - **walking**: the plan has steps and `time` is before its end (the ZMP-CoM controller's walking gains);
/// - **planned references**: the plan sample's xy (its z, the CoM height, is the whole-body layer's);
/// - **MPC horizon**: the plan sampled at `time + k·T`, `k = 0…N` with `T` the layer's period and `N + 1`
///   = [`SimplifiedController::horizon_samples`], each sample with the polygon of its *planned* soles.
///
/// ```
/// use std::time::Duration;
/// use nalgebra::{Isometry3, Vector2, Vector3};
/// use stride_planner::{plan_from_standing, Goal, PlanSample, PlannerConfig};
/// use stride_simplified::{SimplifiedConfig, SimplifiedController, SimplifiedInput};
/// use stride_walking::{MeasuredCentroidal, SimplifiedInputBuilder};
///
/// let soles = [
///     Isometry3::translation(0.0, 0.075, 0.0),
///     Isometry3::translation(0.0, -0.075, 0.0),
/// ];
/// let config = PlannerConfig::default();
/// let goal = Goal::Pose { x: 0.3, y: 0.0, yaw: 0.0 };
/// let plan = plan_from_standing(&config, 9.81, 0.0, &soles[0], &soles[1], &goal)?;
/// let mut controller = SimplifiedController::new(&SimplifiedConfig::default(), Duration::from_millis(10))?;
/// let mut builder = SimplifiedInputBuilder::new(&controller, config.foot_length, config.foot_width);
/// let mut input = builder.new_input(&soles)?;
/// let mut sample = PlanSample::default();
/// plan.sample(0.5, &mut sample);
/// let measured = MeasuredCentroidal {
///     com: sample.com_position,
///     com_velocity: sample.com_velocity,
///     dcm: sample.dcm_position.xy(),
///     zmp: sample.zmp.xy(),
///     soles,
/// };
/// builder.fill(&mut input, Duration::from_millis(500), &plan, &sample, &measured)?;
/// assert!(input.walking);
/// let out = controller.step(&input)?;
/// assert!(out.valid);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
pub struct SimplifiedInputBuilder {
    foot_length: f64,
    foot_width: f64,
    /// The simplified layer's period \[s\].
    period: f64,
    horizon_samples: usize,
    scratch: PlanSample,
}

impl SimplifiedInputBuilder {
    /// The builder for `controller` (its period and MPC horizon), with soles `foot_length` × `foot_width`
    /// \[m\] (the planner's `foot_length`, `foot_width`).
    pub fn new(controller: &SimplifiedController, foot_length: f64, foot_width: f64) -> Self {
        Self {
            foot_length,
            foot_width,
            period: controller.period(),
            horizon_samples: controller.horizon_samples(),
            scratch: PlanSample::default(),
        }
    }

    /// An input sized for the controller (allocates its horizon buffer), its support polygon the hull
    /// of both `soles` (standing).
    ///
    /// # Errors
    /// [`SimplifiedInputError::Polygon`] when the soles' hull is degenerate.
    pub fn new_input(
        &self,
        soles: &[Isometry3<f64>; 2],
    ) -> Result<SimplifiedInput, SimplifiedInputError> {
        let polygon = self.polygon(soles, [true, true], "measured")?;
        Ok(SimplifiedInput::new(self.horizon_samples, polygon))
    }

    /// Fills `input` at `time` from `plan`, its `sample` at `time` and the `measured` quantities (see the
    /// type's documentation for the rules). On error `input` is partly filled.
    ///
    /// # Errors
    /// [`SimplifiedInputError`] when a support polygon is degenerate or `input`'s horizon buffer is smaller
    /// than the controller's horizon.
    pub fn fill(
        &mut self,
        input: &mut SimplifiedInput,
        time: Duration,
        plan: &Plan,
        sample: &PlanSample,
        measured: &MeasuredCentroidal,
    ) -> Result<(), SimplifiedInputError> {
        let s = sample;
        let contacts = [s.left.in_contact, s.right.in_contact];
        input.support_polygon = self.polygon(&measured.soles, contacts, "measured")?;
        input.time = time;
        input.omega = s.omega;
        input.walking = is_walking(plan, s.time);
        input.planned_dcm_position = s.dcm_position.xy();
        input.planned_dcm_velocity = s.dcm_velocity.xy();
        input.planned_zmp = s.zmp.xy();
        input.planned_com_position = s.com_position.xy();
        input.planned_com_velocity = s.com_velocity.xy();
        input.measured_com_position = measured.com.xy();
        input.measured_com_velocity = measured.com_velocity.xy();
        input.measured_dcm = measured.dcm;
        input.measured_zmp = measured.zmp;
        self.fill_horizon(input, time, plan)
    }

    /// The MPC horizon: the plan at `time + k·T`, `k = 0…N`.
    fn fill_horizon(
        &mut self,
        input: &mut SimplifiedInput,
        time: Duration,
        plan: &Plan,
    ) -> Result<(), SimplifiedInputError> {
        input.horizon.clear();
        let t0 = seconds(time);
        for k in 0..self.horizon_samples {
            let t = t0 + k as f64 * self.period;
            plan.sample(t, &mut self.scratch);
            let h = &self.scratch;
            let soles = [h.left.pose, h.right.pose];
            let contacts = [h.left.in_contact, h.right.in_contact];
            let support = self.polygon(&soles, contacts, "planned")?;
            input.horizon.push(HorizonSample {
                dcm_position: h.dcm_position.xy(),
                zmp: h.zmp.xy(),
                support,
            })?;
        }
        Ok(())
    }

    fn polygon(
        &self,
        soles: &[Isometry3<f64>; 2],
        contacts: [bool; 2],
        which: &'static str,
    ) -> Result<SupportPolygon, SimplifiedInputError> {
        support_polygon(soles, contacts, self.foot_length, self.foot_width)
            .map_err(|source| SimplifiedInputError::Polygon { which, source })
    }
}

/// The "walking" rule: `plan` has steps and plan time `t` \[s\] is before its end.
pub fn is_walking(plan: &Plan, t: f64) -> bool {
    plan.step_count() > 0 && t < plan.end_time
}
