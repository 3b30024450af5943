//! Example 3: the torque whole-body controller (TSID, stride-wbc) holding the standing robot on its two
//! feet.
//!
//! Builds TSID with the bundled robot's task list, gives it references equal to where the robot stands
//! (feet, CoM, upright torso) and solves one tick. The checks: the torques it returns are the model's
//! inverse dynamics (RNEA) of its own accelerations with its own contact wrenches (to 1e-9), the contact
//! forces carry the weight, and the robot is held still.
//!
//! Run: `cargo run --release --bin tsid_standing` (in the `examples` folder).

use std::process::ExitCode;
use std::sync::Arc;
use std::time::{Duration, Instant};

use stride_model::prelude::*;
use stride_wbc::prelude::nalgebra::{DVector, Isometry3, Vector3};
use stride_wbc::prelude::*;

fn main() -> ExitCode {
    stride_examples::run(|checks| {
        let model = Arc::new(bundled::model()?);
        // The bundled posture with the soles flat on the ground (`RobotState::standing` for any robot).
        let soles = bundled::soles(&model)?;
        let state = bundled::standing_state(&model)?;
        let mut kd = KinDyn::new(Arc::clone(&model));
        kd.set_state(&state)?;

        // TSID with the bundled robot's tasks (feet, CoM, upright chest and pelvis, posture, contacts,
        // limits), at the bundled robot's whole-body rate.
        let period = Duration::from_secs_f64(bundled::WBC_PERIOD);
        let mut tsid = Tsid::new(
            Arc::clone(&model),
            TsidConfig::default_for_bundled_model(),
            period,
        )?;

        // Its input: the measured state, then every reference. `Tsid::input` names the references and
        // contacts of the task list (here `left_foot`, `right_foot`, `torso`); they start at the identity
        // pose, and the CoM reference at zero: set them all.
        let mut input = tsid.input(&state);
        input.set_frame_reference(
            walking::LEFT_FOOT,
            FrameReference::still(kd.frame_pose(soles[0])),
        )?;
        input.set_frame_reference(
            walking::RIGHT_FOOT,
            FrameReference::still(kd.frame_pose(soles[1])),
        )?;
        // The torso reference is orientation only: upright, facing world x.
        input.set_frame_reference(walking::TORSO, FrameReference::still(Isometry3::identity()))?;
        input.set_contact(walking::LEFT_FOOT, true)?;
        input.set_contact(walking::RIGHT_FOOT, true)?;
        input.com_position = kd.com_position();
        input.desired_zmp = Some(input.com_position.xy());

        // The contact tasks, in the order of the output's contact wrenches, name their frames in the
        // config.
        let mut contact_frames = Vec::new();
        for task in &tsid.config().tasks {
            if let TaskConfig::Contact(contact) = task {
                contact_frames.push(model.frame_id(&contact.frame).ok_or("contact frame")?);
            }
        }

        let out = tsid.step(&input)?;
        checks.that(
            "QP solved without fallback",
            out.report.is_nominal(),
            &format!("{:?}", out.report.status),
        );

        // Independent check: the model's inverse dynamics of TSID's accelerations with TSID's contact
        // wrenches (applied at the sole origins, world orientation) gives a zero base wrench and TSID's
        // torques.
        let wrenches: Vec<ExternalWrench> = contact_frames
            .iter()
            .zip(&out.contact_wrenches)
            .map(|(&frame, &wrench)| ExternalWrench { frame, wrench })
            .collect();
        let mut generalized = DVector::zeros(model.nv());
        kd.inverse_dynamics(&out.accelerations, &wrenches, &mut generalized)?;
        checks.at_most(
            "base wrench of the RNEA",
            generalized.rows(0, 6).amax(),
            1e-9,
            "N, N m",
        );
        checks.at_most(
            "TSID torques - RNEA torques",
            (generalized.rows(6, model.dof()) - &out.joint_torques).amax(),
            1e-9,
            "N m",
        );

        // Static balance: the contact forces carry the weight, the robot does not accelerate.
        let force: Vector3<f64> = out
            .contact_wrenches
            .iter()
            .map(|w| w.fixed_rows::<3>(0).into_owned())
            .sum();
        let weight = model.total_mass() * model.gravity().norm();
        checks.at_most(
            "contact forces - weight",
            (force - Vector3::new(0.0, 0.0, weight)).amax(),
            1e-3 * weight,
            "N",
        );
        checks.at_most(
            "largest acceleration",
            out.accelerations.amax(),
            1e-3,
            "m/s², rad/s²",
        );
        println!(
            "left / right normal force: {:.1} / {:.1} N",
            out.contact_wrenches[0][2], out.contact_wrenches[1][2]
        );

        // The cost of a tick (the figure README.md quotes for debug and release builds).
        const TICKS: u32 = 100;
        let clock = Instant::now();
        for _ in 0..TICKS {
            tsid.step(&input)?;
        }
        println!(
            "TSID tick: {:.3} ms (mean of {TICKS})",
            clock.elapsed().as_secs_f64() * 1e3 / f64::from(TICKS)
        );
        Ok(())
    })
}
