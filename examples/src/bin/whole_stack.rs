//! Example 4: the whole stack ticked by hand, without stride-runner, for 2 s on the simulator.
//!
//! ```text
//! stride-sim ─sensors─► estimator ─state, feet wrenches─► CentroidalMeter ─► simplified (DCM PI + ZMP-CoM)
//!     ▲                                                                            │ CoM, ZMP refs
//!     └──────────────── joint torques ◄──── TSID ◄── fill_wbc_input ◄── plan ──────┘
//! ```
//!
//! The bundled humanoid, torque-controlled, walks towards a goal 1 m ahead. Each layer runs at the
//! bundled robot's rate (plant and estimator 2 kHz, whole-body 500 Hz, simplified 100 Hz), in one loop
//! of simulator periods; stride-walking holds the rules that chain them. The checks: the robot stays
//! upright (no fall, base height, torso tilt, no QP fallback) and walks forward as planned.
//!
//! Run: `cargo run --release --bin whole_stack` (in the `examples` folder).

use std::process::ExitCode;
use std::sync::Arc;
use std::time::Duration;

use stride_estimation::prelude::*;
use stride_model::prelude::*;
use stride_planner::prelude::*;
use stride_sim::prelude::*;
use stride_simplified::prelude::*;
use stride_walking::prelude::*;
use stride_wbc::prelude::nalgebra::Vector3;
use stride_wbc::prelude::*;

/// Simulated time \[s\].
const DURATION: f64 = 2.0;
/// Layer periods as multiples of the plant's (2 kHz): whole-body 500 Hz, simplified 100 Hz.
const WBC_EVERY: u64 = 4;
const SIMPLIFIED_EVERY: u64 = 20;

fn main() -> ExitCode {
    stride_examples::run(|checks| {
        let model = Arc::new(bundled::model()?);
        let soles = bundled::soles(&model)?;
        let chest = model.frame_id(bundled::TORSO).ok_or("no chest")?;
        let posture = bundled::posture(&model)?;
        let sim_period = Duration::from_secs_f64(bundled::SIM_PERIOD);
        let wbc_period = sim_period * WBC_EVERY as u32;
        let simplified_period = sim_period * SIMPLIFIED_EVERY as u32;

        // The plant: stride-sim with every joint torque-driven, standing on its compliant ground.
        let mut sim_config = SimConfig::default();
        sim_config.actuation.default.mode = ActuationMode::Torque;
        let mut sim = SimRobot::new(Arc::clone(&model), sim_config, sim_period)?;
        sim.set_standing_on_ground(&posture)?;
        let mut command = SimInput::hold(&posture);

        // The controllers' initial view: the posture, soles on the ground (the estimator's world frame).
        let initial = RobotState::standing(&model, &posture, soles[0], soles[1])?;
        let mut estimator =
            Estimator::new(Arc::clone(&model), &EstimatorConfig::default(), sim_period)?;
        estimator.set_initial_state(&initial)?;
        let mut sensors = EstimatorInput::new(&model);
        let mut meter = CentroidalMeter::new(Arc::clone(&model), soles);
        let mut zmp_filter = FirstOrderLowPass::new(MEASURED_ZMP_CUTOFF);

        // The plan, from the initial soles towards a pose 1 m ahead.
        let mut planner = Planner::new(PlannerConfig::default(), model.gravity().norm())?;
        let mut kd = KinDyn::new(Arc::clone(&model));
        kd.set_state(&initial)?;
        let start = [kd.frame_pose(soles[0]), kd.frame_pose(soles[1])];
        let goal = Goal::Pose {
            x: 1.0,
            y: 0.0,
            yaw: 0.0,
        };
        planner.start(Duration::ZERO, &start[0], &start[1], &goal)?;
        let mut plan_sample = PlanSample::default();

        // The simplified layer and the glue that fills its input.
        let mut simplified =
            SimplifiedController::new(&SimplifiedConfig::default(), simplified_period)?;
        let config = planner.config();
        let mut simplified_glue =
            SimplifiedInputBuilder::new(&simplified, config.foot_length, config.foot_width);
        let mut simplified_input = simplified_glue.new_input(&start)?;

        // TSID with the bundled robot's tasks; its input carries the walking references, filled by
        // `fill_wbc_input` through handles resolved once.
        let mut tsid = Tsid::new(
            Arc::clone(&model),
            TsidConfig::default_for_bundled_model(),
            wbc_period,
        )?;
        let mut wbc_input = walking_input(&initial, tsid.input_layout());
        let handles = WalkingHandles::new(&wbc_input)?;

        // What the checks watch (from the simulator's truth, which the controllers never read).
        let start_com = sim.kin_dyn().com_position();
        let start_height = sim.state().base_pose.translation.z;
        let (mut lowest, mut tilt, mut fallbacks) = (start_height, 0.0_f64, 0);

        let steps = (DURATION / bundled::SIM_PERIOD).round() as u64;
        for k in 0..steps {
            let time = sim_period * k as u32;

            // 1. Sense: the simulator's sensors → the estimator (encoders, IMU, force/torque sensors).
            let out = sim.output();
            let imu = ImuReading {
                orientation: out.imu.orientation,
                angular_velocity: out.imu.angular_velocity,
                proper_acceleration: out.imu.proper_acceleration,
            };
            sensors.set_readings(
                out.time,
                out.joint_positions.as_slice(),
                out.joint_velocities.as_slice(),
                imu,
                &out.ft_wrenches,
            )?;
            let estimate = estimator.step(&sensors)?;

            if k % WBC_EVERY == 0 {
                // 2. Measure CoM, DCM (with the plan's ω), ZMP (low-passed) and soles from the estimate.
                planner.sample(time, &mut plan_sample)?;
                let measured = meter.measure(
                    &estimate.state,
                    &estimate.foot_wrenches,
                    estimate.contacts,
                    plan_sample.omega,
                )?;
                let dt = if k == 0 {
                    0.0
                } else {
                    wbc_period.as_secs_f64()
                };
                let zmp = zmp_filter.update(measured.zmp, dt);

                // 3. Simplified layer: the DCM controller's desired ZMP and the CoM references. (On an
                //    error this example stops; a controller would hold `simplified.output()`, the last
                //    valid references, as stride-runner does.)
                if k % SIMPLIFIED_EVERY == 0 {
                    let plan = planner.plan().ok_or("no plan")?;
                    let measured = MeasuredCentroidal { zmp, ..measured };
                    simplified_glue.fill(
                        &mut simplified_input,
                        time,
                        plan,
                        &plan_sample,
                        &measured,
                    )?;
                    simplified.step(&simplified_input)?;
                }

                // 4. Whole-body layer: feet, CoM and torso references → joint torques.
                wbc_input.state.copy_from(&estimate.state);
                fill_wbc_input(
                    &mut wbc_input,
                    &handles,
                    &plan_sample,
                    Some(simplified.output()),
                )?;
                let out = tsid.step(&wbc_input)?;
                if !out.report.is_nominal() {
                    fallbacks += 1;
                }
                command.joint_torques.copy_from(&out.joint_torques);
            }

            // 5. The plant advances one period under the last command.
            sim.step(&command)?;
            lowest = lowest.min(sim.state().base_pose.translation.z);
            let up = sim.kin_dyn().frame_pose(chest).rotation * Vector3::z();
            tilt = tilt.max(up.z.clamp(-1.0, 1.0).acos());
        }

        checks.that("no fall", !sim.output().fallen, "fall detector");
        checks.at_least(
            "lowest base height / initial",
            lowest / start_height,
            0.95,
            "",
        );
        checks.at_most("largest torso tilt", tilt.to_degrees(), 5.0, "deg");
        checks.at_most(
            "whole-body ticks not nominal",
            f64::from(fallbacks),
            0.0,
            "ticks",
        );
        // Forward progress, against the plan's (the plan starts from the estimator's world frame, the
        // simulator's differs by a constant offset: compare displacements).
        let walked = sim.kin_dyn().com_position().x - start_com.x;
        planner.sample(Duration::from_secs_f64(DURATION), &mut plan_sample)?;
        let mut plan_start = PlanSample::default();
        planner.sample(Duration::ZERO, &mut plan_start)?;
        let planned = plan_sample.com_position.x - plan_start.com_position.x;
        println!("CoM moved forward {walked:.3} m in {DURATION} s (plan: {planned:.3} m)");
        checks.at_most("CoM advance - plan's", (walked - planned).abs(), 0.02, "m");
        checks.at_least("CoM advance", walked, 0.5 * planned.max(0.0), "m");
        Ok(())
    })
}
