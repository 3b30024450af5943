//! Example 2: the trajectory planner (stride-planner) and the DCM controller of the simplified layer
//! (stride-simplified) on an ideal linear inverted pendulum.
//!
//! Plans a 1 m walk from standing, then closes the loop on the LIPM integrated by hand: every 10 ms the
//! controller chooses a desired ZMP from the measured DCM and the plan, and the pendulum moves under that
//! ZMP (held over the period, integrated exactly). The pendulum starts 1 cm off the plan; the checks: the
//! DCM converges to the plan and tracks it, the ZMP stays in the feet, the walk ends where planned.
//!
//! Run: `cargo run --release --bin planner_dcm` (in the `examples` folder).

use std::process::ExitCode;
use std::time::Duration;

use stride_planner::prelude::nalgebra::{Isometry3, Vector2};
use stride_planner::prelude::*;
use stride_simplified::prelude::*;
use stride_simplified::LipmDiscretization;
use stride_walking::prelude::*;

/// Gravity \[m/s²\]: the planner's ω = √(g / com_height) comes from it.
const GRAVITY: f64 = 9.81;
/// The simplified layer's period (100 Hz, the bundled robot's rate).
const PERIOD: Duration = Duration::from_millis(10);
/// Initial CoM offset from the plan \[m\] (a disturbance for the controller to remove).
const OFFSET: f64 = 0.01;
/// The tick the error is compared with its closed form at (1 s: the end of the initial double support).
const CHECK_TICK: u32 = 100;

fn main() -> ExitCode {
    stride_examples::run(|checks| {
        // The planner's defaults fit the bundled humanoid (CoM height, feet size and spacing).
        let config = PlannerConfig::default();
        let mut planner = Planner::new(config.clone(), GRAVITY)?;
        let half_width = 0.5 * config.nominal_width;
        let soles = [
            Isometry3::translation(0.0, half_width, 0.0),
            Isometry3::translation(0.0, -half_width, 0.0),
        ];
        let goal = Goal::Pose {
            x: 1.0,
            y: 0.0,
            yaw: 0.0,
        };
        let plan = planner
            .start(Duration::ZERO, &soles[0], &soles[1], &goal)?
            .clone();
        println!(
            "plan: {} steps, {:.2} s",
            plan.step_count(),
            plan.end_time - plan.start_time
        );

        // The DCM controller (PI by default) with the ZMP-CoM controller, and the glue that fills its
        // input from the plan (support polygon, walking flag, MPC horizon).
        let mut controller = SimplifiedController::new(&SimplifiedConfig::default(), PERIOD)?;
        let mut glue =
            SimplifiedInputBuilder::new(&controller, config.foot_length, config.foot_width);
        let mut input = glue.new_input(&soles)?;

        // The pendulum, started at the plan's CoM moved by OFFSET along x, at rest.
        let mut sample = PlanSample::default();
        planner.sample(Duration::ZERO, &mut sample)?;
        let omega = sample.omega;
        let lipm = LipmDiscretization::new(omega, PERIOD.as_secs_f64())?;
        let mut com = sample.com_position.xy() + Vector2::new(OFFSET, 0.0);
        let mut com_velocity = Vector2::zeros();
        let mut zmp = sample.zmp.xy();

        let ticks = ((plan.end_time + 1.0) / PERIOD.as_secs_f64()).ceil() as u32;
        let (mut worst_tracking, mut worst_zmp_outside) = (0.0_f64, 0.0_f64);
        let (mut dcm_error, mut error_at_check) = (0.0, 0.0);
        for k in 0..=ticks {
            let time = PERIOD * k;
            planner.sample(time, &mut sample)?;
            // What a robot would measure; here the pendulum's own state (and the feet where planned).
            let measured = MeasuredCentroidal {
                com: com.push(sample.com_position.z),
                com_velocity: com_velocity.push(0.0),
                dcm: com + com_velocity / omega,
                zmp,
                soles: [sample.left.pose, sample.right.pose],
            };
            dcm_error = (measured.dcm - sample.dcm_position.xy()).norm();
            if k >= CHECK_TICK {
                worst_tracking = worst_tracking.max(dcm_error);
            }
            if k == CHECK_TICK {
                error_at_check = measured.dcm.x - sample.dcm_position.x;
            }
            glue.fill(&mut input, time, &plan, &sample, &measured)?;
            let out = controller.step(&input)?;
            worst_zmp_outside =
                worst_zmp_outside.max(input.support_polygon.max_violation(out.desired_zmp));
            // The ideal pendulum realises the desired ZMP exactly over the period.
            zmp = out.desired_zmp;
            (com, com_velocity) = lipm.step_com(com, com_velocity, zmp);
        }
        // Closed form: with the PI law p = ξ_ref − ξ̇_ref/ω + kp (ξ − ξ_ref) held over T, the pendulum's
        // ξ⁺ = p + e^{ωT} (ξ − p) makes the error decay by λ = e^{ωT} − kp (e^{ωT} − 1) per tick while the
        // ZMP stays inside the feet and the planned ZMP stands still along the axis (x, in the initial
        // double support; along y the planned ZMP moves to the first stance foot within each period,
        // which the held ZMP cannot follow exactly: 1.2 mm of error there).
        let kp = SimplifiedConfig::default().instantaneous.kp;
        let growth = (omega * PERIOD.as_secs_f64()).exp();
        let decay = growth - kp * (growth - 1.0);
        let predicted = OFFSET * decay.powi(CHECK_TICK as i32);
        println!("DCM x error after {CHECK_TICK} ticks: {error_at_check:.6} m (closed form {predicted:.6} m)");
        checks.at_most(
            "DCM x error - closed form",
            (error_at_check - predicted).abs(),
            1e-5,
            "m",
        );
        checks.at_most(
            "DCM error from 1 s on, largest",
            worst_tracking,
            OFFSET,
            "m",
        );
        checks.at_most("DCM error at the end", dcm_error, 0.1 * OFFSET, "m");
        checks.at_most("desired ZMP outside the feet", worst_zmp_outside, 1e-9, "m");
        checks.at_most(
            "CoM x at the end - plan's",
            (com.x - sample.com_position.x).abs(),
            1e-3,
            "m",
        );
        checks.at_least("distance walked", com.x, 0.95, "m");
        Ok(())
    })
}
