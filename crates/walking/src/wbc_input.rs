//! The walking stack's whole-body input: the planner's sample and the simplified layer's output → the
//! named references and contacts of a [`WbcInput`] (the names of [`stride_wbc::walking`]).

use std::sync::Arc;

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use stride_planner::{FootSample, PlanSample};
use stride_simplified::{FootAdmittanceOutput, FootCorrection, SimplifiedOutput};
use stride_wbc::{walking, ContactId, FrameRefId, FrameReference, InputLayout, WbcError, WbcInput};

/// The walking names: frame references `left_foot`, `right_foot`, `torso` and contacts `left_foot`,
/// `right_foot`. A controller's input must carry them: build it from
/// `controller_layout.union(&walking_layout())`.
pub fn walking_layout() -> InputLayout {
    InputLayout::new(
        [walking::LEFT_FOOT, walking::RIGHT_FOOT, walking::TORSO],
        [walking::LEFT_FOOT, walking::RIGHT_FOOT],
    )
}

/// An input holding the robot at `state` with the names of `controller` (its
/// [`stride_wbc::Tsid::input_layout`] or [`stride_wbc::QpIk::input_layout`]) and the walking names.
pub fn walking_input(state: &stride_model::RobotState, controller: &InputLayout) -> WbcInput {
    WbcInput::new(state.clone(), Arc::new(controller.union(&walking_layout())))
}

/// The walking slots of a [`WbcInput`], resolved once ([`WalkingHandles::new`]) so that
/// [`fill_wbc_input`] does no string lookup per tick.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WalkingHandles {
    left: FrameRefId,
    right: FrameRefId,
    torso: FrameRefId,
    left_contact: ContactId,
    right_contact: ContactId,
}

impl WalkingHandles {
    /// The handles of `input`'s walking names. Errors: a name missing (see [`walking_layout`]).
    pub fn new(input: &WbcInput) -> Result<Self, WbcError> {
        Ok(WalkingHandles {
            left: input.frame_id(walking::LEFT_FOOT)?,
            right: input.frame_id(walking::RIGHT_FOOT)?,
            torso: input.frame_id(walking::TORSO)?,
            left_contact: input.contact_id(walking::LEFT_FOOT)?,
            right_contact: input.contact_id(walking::RIGHT_FOOT)?,
        })
    }
}

/// Fills the walking parts of the whole-body input from the plan sample and, when it has a valid one,
/// the simplified layer's output; the caller sets `state`, `posture` and `angular_momentum`.
/// Allocation-free.
///
/// The choices, as stride-runner has made them:
/// * **CoM**: x and y (position, velocity, acceleration) from the simplified output, which closes the
///   DCM / ZMP feedback; z from the plan (the simplified layer is planar: the plan's CoM height,
///   constant on flat ground). Without a simplified output (`None`, or `valid == false`) all three axes
///   come from the plan.
/// * **Desired ZMP**: the simplified output's, else the plan's (x, y).
/// * **Feet**: the plan's sole pose, twist and acceleration as the `left_foot` / `right_foot` frame
///   references; the plan's contact flags as the `left_foot` / `right_foot` contacts.
/// * **Torso** (`torso` reference, orientation only; translation and linear parts zero): upright (no roll,
///   no pitch), yaw ψ = the mean of the two soles' yaws taken the shorter way round,
///   `ψ = ψ_l + ½ wrap(ψ_r − ψ_l)`; yaw rate the mean of the soles' yaw rates `½ (ω_l,z + ω_r,z)`;
///   zero angular acceleration.
///
/// Errors: `handles` from an input of another layout.
pub fn fill_wbc_input(
    input: &mut WbcInput,
    handles: &WalkingHandles,
    plan: &PlanSample,
    simplified: Option<&SimplifiedOutput>,
) -> Result<(), WbcError> {
    match simplified.filter(|s| s.valid) {
        Some(so) => {
            input.com_position =
                Vector3::new(so.com_position.x, so.com_position.y, plan.com_position.z);
            input.com_velocity =
                Vector3::new(so.com_velocity.x, so.com_velocity.y, plan.com_velocity.z);
            input.com_acceleration = Vector3::new(
                so.com_acceleration.x,
                so.com_acceleration.y,
                plan.com_acceleration.z,
            );
            input.desired_zmp = Some(so.desired_zmp);
        }
        None => {
            input.com_position = plan.com_position;
            input.com_velocity = plan.com_velocity;
            input.com_acceleration = plan.com_acceleration;
            input.desired_zmp = Some(plan.zmp.xy());
        }
    }
    set_foot(input, handles.left, handles.left_contact, &plan.left)?;
    set_foot(input, handles.right, handles.right_contact, &plan.right)?;
    let yaw = crate::soles_heading(&plan.left.pose, &plan.right.pose);
    let torso = input.frame_mut(handles.torso)?;
    torso.pose = Isometry3::from_parts(
        Translation3::identity(),
        UnitQuaternion::from_euler_angles(0.0, 0.0, yaw),
    );
    torso.velocity.fill(0.0);
    torso.velocity[5] = 0.5 * (plan.left.twist[5] + plan.right.twist[5]);
    torso.acceleration.fill(0.0);
    Ok(())
}

/// Moves the `left_foot` / `right_foot` references of `input` (filled by [`fill_wbc_input`]) by the foot
/// admittance's corrections ([`stride_simplified::FootAdmittance`]): each sole's orientation is turned by
/// its roll and pitch about the sole's own x and y axes after the planned orientation, `R = R_plan R_y(θ_y)
/// R_x(θ_x)` (nalgebra's roll-pitch-yaw with zero yaw), its angular velocity gains `R_plan (θ̇_x, θ̇_y, 0)`,
/// and its height and vertical velocity gain the correction's. A zero correction leaves the reference
/// bit for bit. Allocation-free.
///
/// Errors: `handles` from an input of another layout.
pub fn apply_foot_admittance(
    input: &mut WbcInput,
    handles: &WalkingHandles,
    corrections: &FootAdmittanceOutput,
) -> Result<(), WbcError> {
    for (frame, c) in [handles.left, handles.right]
        .into_iter()
        .zip(&corrections.feet)
    {
        if *c != FootCorrection::default() {
            correct_foot(input.frame_mut(frame)?, c);
        }
    }
    Ok(())
}

fn correct_foot(reference: &mut FrameReference, c: &FootCorrection) {
    let planned = reference.pose.rotation;
    reference.pose.rotation = planned * UnitQuaternion::from_euler_angles(c.tilt.x, c.tilt.y, 0.0);
    reference.pose.translation.z += c.height;
    let rate = planned * Vector3::new(c.tilt_rate.x, c.tilt_rate.y, 0.0);
    for axis in 0..3 {
        reference.velocity[3 + axis] += rate[axis];
    }
    reference.velocity[2] += c.height_rate;
}

fn set_foot(
    input: &mut WbcInput,
    frame: FrameRefId,
    contact: ContactId,
    foot: &FootSample,
) -> Result<(), WbcError> {
    *input.frame_mut(frame)? = FrameReference {
        pose: foot.pose,
        velocity: foot.twist,
        acceleration: foot.acceleration,
    };
    input.contact_mut(contact)?.active = foot.in_contact;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use stride_model::{bundled, Model, RobotState};

    #[test]
    fn fills_feet_contacts_and_an_upright_torso_between_the_feet_yaws() {
        let model = Model::from_urdf_str(bundled::URDF).unwrap();
        let mut input = walking_input(&RobotState::zero(&model), &InputLayout::default());
        let handles = WalkingHandles::new(&input).unwrap();
        let mut plan = PlanSample {
            com_position: Vector3::new(0.1, 0.0, 0.54),
            ..Default::default()
        };
        plan.left.pose.rotation = UnitQuaternion::from_euler_angles(0.0, 0.0, 3.0);
        plan.right.pose.rotation = UnitQuaternion::from_euler_angles(0.0, 0.0, -3.0);
        plan.left.twist[5] = 0.2;
        plan.left.in_contact = true;
        plan.right.in_contact = false;
        fill_wbc_input(&mut input, &handles, &plan, None).unwrap();
        let torso = input.frame_reference(walking::TORSO).unwrap();
        let (roll, pitch, yaw) = torso.pose.rotation.euler_angles();
        // 3 and −3 rad are 0.28 rad apart across ±π: the mean is π, not 0
        assert!(roll.abs() < 1e-12 && pitch.abs() < 1e-12);
        assert!((yaw.abs() - std::f64::consts::PI).abs() < 1e-9, "{yaw}");
        assert!((torso.velocity[5] - 0.1).abs() < 1e-15);
        assert!(input.contact_named(walking::LEFT_FOOT).unwrap().active);
        assert!(!input.contact_named(walking::RIGHT_FOOT).unwrap().active);
        assert_eq!(input.com_position, plan.com_position);
    }

    #[test]
    fn foot_admittance_turns_the_sole_about_its_own_axes_and_zero_changes_nothing() {
        let model = Model::from_urdf_str(bundled::URDF).unwrap();
        let mut input = walking_input(&RobotState::zero(&model), &InputLayout::default());
        let handles = WalkingHandles::new(&input).unwrap();
        let mut plan = PlanSample::default();
        plan.left.pose = Isometry3::from_parts(
            Translation3::new(0.1, 0.07, 0.0),
            UnitQuaternion::from_euler_angles(0.0, 0.0, std::f64::consts::FRAC_PI_2),
        );
        plan.left.twist[0] = 0.3;
        fill_wbc_input(&mut input, &handles, &plan, None).unwrap();
        let before = input.clone();
        apply_foot_admittance(&mut input, &handles, &FootAdmittanceOutput::default()).unwrap();
        assert_eq!(input, before, "a zero correction changes nothing");
        let mut out = FootAdmittanceOutput::default();
        out.feet[0] = FootCorrection {
            tilt: nalgebra::Vector2::new(0.0, -0.05),
            tilt_rate: nalgebra::Vector2::new(0.0, -0.2),
            height: 0.004,
            height_rate: 0.01,
        };
        apply_foot_admittance(&mut input, &handles, &out).unwrap();
        let left = input.frame_reference(walking::LEFT_FOOT).unwrap();
        // the sole's x axis (world +y) now points 0.05 rad up: toe up for a negative pitch
        let toe = left.pose.rotation * Vector3::x();
        assert!(
            (toe - Vector3::new(0.0, 0.05f64.cos(), 0.05f64.sin())).norm() < 1e-12,
            "{toe}"
        );
        assert!((left.pose.translation.z - 0.004).abs() < 1e-15);
        // the pitch rate about the sole's y axis (world −x)
        let w = left.velocity.fixed_rows::<3>(3);
        assert!((w - Vector3::new(0.2, 0.0, 0.0)).norm() < 1e-12, "{w}");
        assert_eq!(left.velocity[0], 0.3);
        assert_eq!(left.velocity[2], 0.01);
        assert_eq!(
            input.frame_reference(walking::RIGHT_FOOT).unwrap(),
            before.frame_reference(walking::RIGHT_FOOT).unwrap()
        );
    }
}
