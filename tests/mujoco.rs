//! The scenarios on MuJoCo (`--features mujoco`, see docs/mujoco.md), and the error a build without MuJoCo
//! gives when asked for it.

use std::path::{Path, PathBuf};

use stride_runner::config::{PlantKind, Scenario};
#[cfg(feature = "mujoco")]
use stride_runner::run::Outcome;
use stride_runner::run::{run_scenario, RunOptions};

fn config_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("configs")
        .join(name)
}

/// The error of running `scenario` on MuJoCo (panics if it runs).
fn error_on_mujoco(scenario: &Scenario) -> String {
    let options = RunOptions {
        plant: Some(PlantKind::Mujoco),
        no_log: true,
        ..RunOptions::default()
    };
    match run_scenario(scenario, &options) {
        Err(e) => e.to_string(),
        Ok(s) => panic!("expected an error, the run ended with {}", s.outcome),
    }
}

/// A build without the `mujoco` feature rejects the MuJoCo plant with a configuration error that names
/// the command that builds it.
#[cfg(not(feature = "mujoco"))]
#[test]
fn the_mujoco_plant_without_the_feature_names_the_build_command() {
    let scenario = Scenario::load(&config_path("walk_straight.toml")).expect("scenario");
    let message = error_on_mujoco(&scenario);
    assert!(message.contains("scenario.plant"), "{message}");
    assert!(
        message.contains("cargo build --release --features mujoco"),
        "{message}"
    );
}

#[cfg(feature = "mujoco")]
fn run_on_mujoco(name: &str) -> stride_runner::run::RunSummary {
    run_scenario_on_mujoco(&Scenario::load(&config_path(name)).expect("scenario"))
}

/// Torque control (TSID) on MuJoCo: the default walk's goal is reached and the robot stands still, with
/// the DCM tracked as on stride-sim (measured 9.2 mm RMS on MuJoCo, 8.2 mm on stride-sim).
#[cfg(feature = "mujoco")]
#[test]
fn the_torque_walk_reaches_its_goal_on_mujoco() {
    let s = run_on_mujoco("walk_straight_torque.toml");
    assert_eq!(s.outcome, Outcome::GoalReached, "{}", s.outcome);
    assert!(s.max_tilt_deg < 20.0 && s.min_base_height_fraction > 0.8);
    assert!(s.dcm_error.rms < 0.02, "DCM RMS {} m", s.dcm_error.rms);
}

/// Position control (QP-IK) on MuJoCo stands through `stand_push`'s 40 N × 0.2 s push at the chest (measured:
/// largest tilt 1.7°, DCM 10.2 mm RMS).
#[cfg(feature = "mujoco")]
#[test]
fn position_control_stands_through_the_push_on_mujoco() {
    let s = run_on_mujoco("stand_push.toml");
    assert_eq!(s.outcome, Outcome::DurationReached, "{}", s.outcome);
    assert!(s.max_tilt_deg < 5.0, "largest tilt {}°", s.max_tilt_deg);
    assert!(s.min_base_height_fraction > 0.95);
    assert!(s.dcm_error.rms < 0.02, "DCM RMS {} m", s.dcm_error.rms);
}

/// The default walk, position control (QP-IK), on MuJoCo: its goal is reached with the measured ZMP
/// low-passed at the default 5 Hz, and the same walk falls with the ZMP unfiltered (measured 2026-12-05 on the
/// ground matched to stride-sim's: goal 6 mm away, DCM 14.8 mm RMS; 2026-12-02 on MuJoCo's default contact:
/// 24 mm, 22.3 mm; unfiltered, a fall at 6.7 s with the ankles saturated by the servos' damping
/// of the CoM velocity reference's jumps; docs/mujoco.md, "Position control").
#[cfg(feature = "mujoco")]
#[test]
fn the_position_walk_reaches_its_goal_on_mujoco_only_with_the_zmp_filter() {
    let s = run_on_mujoco("walk_straight.toml");
    assert_eq!(s.outcome, Outcome::GoalReached, "{}", s.outcome);
    assert!(s.max_tilt_deg < 20.0 && s.min_base_height_fraction > 0.8);
    let mut scenario = Scenario::load(&config_path("walk_straight.toml")).expect("scenario");
    scenario.config.estimation.measured_zmp_cutoff = 0.0;
    let options = RunOptions {
        plant: Some(PlantKind::Mujoco),
        no_log: true,
        ..RunOptions::default()
    };
    let unfiltered = run_scenario(&scenario, &options).expect("run");
    // it fell before the defaults of 2026-12-05 (foot admittance, chest weight 50, `when_read`); it now
    // does not come to a standstill at the goal before the duration runs out
    assert!(
        matches!(
            unfiltered.outcome,
            Outcome::Fell { .. } | Outcome::DurationReached
        ),
        "unfiltered: {}",
        unfiltered.outcome
    );
}

/// Runs the iCub scenario `name` on MuJoCo for the test `test` (skipped loudly without the models) and
/// checks that it reaches its goal upright with the DCM tracked within `dcm_rms_max` \[m\] RMS.
#[cfg(feature = "mujoco")]
fn icub_reaches_its_goal_on_mujoco(test: &str, name: &str, dcm_rms_max: f64) {
    if stride_testkit::icub_model_urdf(test, "iCubGazeboV2_7").is_none() {
        return;
    }
    let s = run_on_mujoco(name);
    assert_eq!(s.outcome, Outcome::GoalReached, "{}", s.outcome);
    assert!(s.max_tilt_deg < 10.0 && s.min_base_height_fraction > 0.9);
    assert!(
        s.dcm_error.rms < dcm_rms_max,
        "DCM RMS {} m",
        s.dcm_error.rms
    );
}

/// The official iCub (iCubGazeboV2_7) on MuJoCo, on its URDF's own sole boxes (0.16 × 0.072 m; stride-sim
/// simulates a 0.19 m sole): the position walk reaches its goal (measured 2026-12-02: 13 mm from it, DCM
/// 15.1 mm RMS, tilt 1.2°; stride-sim 2 mm, 7.9 mm).
#[cfg(feature = "mujoco")]
#[test]
fn icub_walks_to_its_goal_on_mujoco_in_position_control() {
    icub_reaches_its_goal_on_mujoco(
        "icub_walks_to_its_goal_on_mujoco_in_position_control",
        "walk_straight_icub.toml",
        0.025,
    );
}

/// The official iCub on MuJoCo in torque control (TSID): goal reached (measured 2026-12-02: 6 mm from it,
/// DCM 8.3 mm RMS, tilt 2.5°, no joint at its effort limit; stride-sim 2 mm, 8.8 mm).
#[cfg(feature = "mujoco")]
#[test]
fn icub_walks_to_its_goal_on_mujoco_in_torque_control() {
    icub_reaches_its_goal_on_mujoco(
        "icub_walks_to_its_goal_on_mujoco_in_torque_control",
        "walk_straight_icub_torque.toml",
        0.015,
    );
}

/// The official iCub's fast position walk on MuJoCo, on its URDF's own sole boxes (issues 15 and 16,
/// docs/gait.md "The official iCub"): `walk_fast_icub` reaches its 4 m goal upright at ≥ 0.34 m/s steady, the
/// thesis's 0.3372 m/s on the real robot (measured 2026-12-06 with the sole frames on the sole boxes'
/// bottom: 0.346 m/s, 9 mm from the goal, DCM 17.1 mm RMS, tilt 7.6°; sensor seeds 1–7: 0.352–0.353 m/s,
/// 10–84 mm from the goal). The other side: the tuning it replaced, found by a search on stride-sim's former
/// 0.19 m simulated sole (0.151 m steps every 0.46 s, 30 % double support, CoM 0.53 m above the URDF's
/// `l_sole`, 0.5405 m above the sole frames now, K_CoM 4 / K_ZMP 2.5, k_p 1.6, the held command, the
/// admittance unfiltered), falls (measured on the former frames: at 11.9 s, 1.25 m from the goal, its
/// heading 30° off).
#[cfg(feature = "mujoco")]
#[test]
fn icub_walks_fast_to_its_goal_on_mujoco_on_its_sole_boxes() {
    use stride_runner::position_command::PositionCommand;
    let test = "icub_walks_fast_to_its_goal_on_mujoco_on_its_sole_boxes";
    if stride_testkit::icub_model_urdf(test, "iCubGazeboV2_7").is_none() {
        return;
    }
    let mut scenario = Scenario::load(&config_path("walk_fast_icub.toml")).expect("scenario");
    let s = run_scenario_on_mujoco(&scenario);
    assert_eq!(s.outcome, Outcome::GoalReached, "{}", s.outcome);
    assert!(s.max_tilt_deg < 10.0, "tilt {}°", s.max_tilt_deg);
    let speed = s.gait.steady_speed.expect("enough touch-downs");
    assert!(speed >= 0.34, "steady speed {speed} m/s");
    assert!(s.dcm_error.rms < 0.06, "DCM RMS {} m", s.dcm_error.rms);
    let c = &mut scenario.config;
    let p = &mut c.planner;
    (p.feet_distance_max, p.double_support_fraction) = (0.22, 0.3);
    (p.step_duration_min, p.step_duration_nominal) = (0.46, 1.0);
    (p.com_height, p.nominal_width, p.stop_deceleration) = (0.5405, 0.16, 0.0);
    let zmp_com = &mut c.simplified.zmp_com.walking;
    (zmp_com.k_com, zmp_com.k_zmp) = (4.0, 2.5);
    c.simplified.instantaneous.kp = 1.6;
    c.simplified.foot_admittance.error_cutoff = 0.0;
    c.wbc.position_command = PositionCommand::Hold;
    let former = run_scenario_on_mujoco(&scenario);
    assert!(
        matches!(former.outcome, Outcome::Fell { .. }),
        "the former tuning: {}",
        former.outcome
    );
}

/// `[sim.model]` inertia edits reach MuJoCo: its total mass is the edited plant model's (1e-12 relative),
/// not the controllers' unedited one.
#[cfg(feature = "mujoco")]
#[test]
fn sim_model_inertia_edits_reach_the_mujoco_plant() {
    use std::sync::Arc;
    use stride_runner::mujoco_plant::MujocoPlant;
    use stride_runner::setup::{initial_joint_positions, load_plant_model};

    let mut scenario = Scenario::load(&config_path("walk_straight.toml")).expect("scenario");
    scenario.config.sim.model.mass_scale = 1.1;
    scenario.config.sim.model.links.insert(
        "chest".into(),
        stride_sim::LinkInertiaChange {
            mass_scale: 1.5,
            com_offset: [0.02, 0.0, 0.0],
        },
    );
    let model = Arc::new(stride_model::Model::from_urdf_file(&scenario.urdf_path).expect("model"));
    let plant = load_plant_model(&scenario, &model).expect("edited plant model");
    assert!(plant.total_mass() > 1.1 * model.total_mass());
    let q0 = initial_joint_positions(&scenario, &model).expect("posture");
    let soles = ["l_sole", "r_sole"].map(|f| plant.frame_id(f).expect("sole"));
    let mujoco = MujocoPlant::new(
        &scenario,
        Arc::clone(&plant),
        &scenario.urdf_path,
        &q0,
        soles,
    )
    .expect("MuJoCo plant");
    let mass: f64 = mujoco.mujoco().mj_model().body_mass().iter().sum();
    assert!(
        (mass - plant.total_mass()).abs() < 1e-12 * mass,
        "MuJoCo {mass} kg, edited model {} kg",
        plant.total_mass()
    );
}

/// An out-of-range `[mujoco]` value is a configuration error at its key.
#[cfg(feature = "mujoco")]
#[test]
fn an_out_of_range_mujoco_parameter_is_an_error_at_its_key() {
    let mut scenario = Scenario::load(&config_path("walk_straight.toml")).expect("scenario");
    scenario.config.mujoco.solref = Some([0.0001, 1.0]);
    let message = error_on_mujoco(&scenario);
    assert!(message.contains("mujoco.solref"), "{message}");
}

/// The MuJoCo floor's `solref` is derived from the scenario's ground when `[mujoco]` writes none: the
/// default floor under the bundled humanoid (k 3·10⁸, b 9.5·10⁵) is a 1.9 ms contact with damping ratio
/// 0.91 (docs/mujoco.md, "One ground for both plants"), a soft ground of the thesis's Table 8.1 a slower
/// one, and a written `solref` wins.
#[cfg(feature = "mujoco")]
#[test]
fn the_mujoco_floor_is_the_scenarios_ground() {
    use std::sync::Arc;
    use stride_runner::mujoco_plant::MujocoPlant;
    use stride_runner::setup::{initial_joint_positions, load_plant_model};

    let floor_solref = |scenario: &Scenario| {
        let model =
            Arc::new(stride_model::Model::from_urdf_file(&scenario.urdf_path).expect("model"));
        let plant = load_plant_model(scenario, &model).expect("plant model");
        let q0 = initial_joint_positions(scenario, &model).expect("posture");
        let soles = ["l_sole", "r_sole"].map(|f| plant.frame_id(f).expect("sole"));
        let mujoco = MujocoPlant::new(scenario, plant, &scenario.urdf_path, &q0, soles)
            .expect("MuJoCo plant");
        // The floor is the world body's only geom, so MuJoCo numbers it first.
        mujoco.mujoco().mj_model().geom_solref()[0]
    };
    let mut scenario = Scenario::load(&config_path("walk_straight.toml")).expect("scenario");
    let [tau, zeta] = floor_solref(&scenario);
    assert!(
        (tau - 1.918e-3).abs() < 0.001e-3 && (zeta - 0.9085).abs() < 1e-4,
        "{tau} s, {zeta}"
    );
    scenario.config.sim.contact.normal_stiffness = 8e5;
    scenario.config.sim.contact.normal_damping = 1e4;
    let [soft_tau, soft_zeta] = floor_solref(&scenario);
    assert!(
        soft_tau > 0.15 && soft_zeta < 0.2,
        "{soft_tau} s, {soft_zeta}"
    );
    scenario.config.mujoco.solref = Some([0.02, 1.0]);
    assert_eq!(floor_solref(&scenario), [0.02, 1.0]);
}

/// Sets the floor the default was until 2026-12-06 (k 3·10⁷ N/m³, b 3·10⁵ N·s/m³, normal and tangential;
/// MuJoCo's contact is matched to it), for the claims measured on it.
#[cfg(feature = "mujoco")]
fn on_the_former_soft_floor(scenario: &mut Scenario) {
    let g = &mut scenario.config.sim.contact;
    (g.normal_stiffness, g.tangential_stiffness) = (3e7, 3e7);
    (g.normal_damping, g.tangential_damping) = (3e5, 3e5);
}

/// `scenario` on MuJoCo reaches its goal on its own (hard default) floor, then, switched to the former soft
/// floor (`scenario` is left on it, for the other side of a claim measured there), reaches it again with the
/// torso within 10° of upright.
#[cfg(feature = "mujoco")]
fn reaches_its_goal_on_the_hard_then_on_the_former_floor(scenario: &mut Scenario) {
    let hard = run_scenario_on_mujoco(scenario);
    assert_eq!(
        hard.outcome,
        Outcome::GoalReached,
        "hard floor: {}",
        hard.outcome
    );
    on_the_former_soft_floor(scenario);
    let soft = run_scenario_on_mujoco(scenario);
    assert_eq!(soft.outcome, Outcome::GoalReached, "{}", soft.outcome);
    assert!(soft.max_tilt_deg < 10.0, "tilt {}°", soft.max_tilt_deg);
}

/// `scenario` on MuJoCo without a log.
#[cfg(feature = "mujoco")]
fn run_scenario_on_mujoco(scenario: &Scenario) -> stride_runner::run::RunSummary {
    let options = RunOptions {
        plant: Some(PlantKind::Mujoco),
        no_log: true,
        ..RunOptions::default()
    };
    let summary = run_scenario(scenario, &options).expect("run");
    eprintln!("{}", summary.render());
    summary
}

/// The foot admittance of position control on MuJoCo (docs/foot-admittance.md, "MuJoCo"): with its error
/// filter (`simplified.foot_admittance.error_cutoff`, the default) the default walk reaches its goal and
/// stands still, on the hard default floor and on the former soft one. Unfiltered, on the former soft floor
/// MuJoCo's sole-torque chatter (50–250 Hz) reaches the ankle servos through the tilt rates sent as velocity
/// references and the robot rocks at its goal until the run's end (DCM 82.1 mm RMS, measured 2026-12-06);
/// on the hard default floor, with the servo limits on the applied force (`mujoco.servo_saturation`), the
/// unfiltered law stands still at its goal too (DCM 12.5 mm; 34.6 mm and rocking with MuJoCo's clamp).
#[cfg(feature = "mujoco")]
#[test]
fn the_foot_admittance_stands_still_on_mujoco_with_its_error_filter_and_needs_it_on_the_former_soft_floor(
) {
    let s = run_on_mujoco("walk_straight_foot_admittance.toml");
    assert_eq!(s.outcome, Outcome::GoalReached, "{}", s.outcome);
    assert!(s.dcm_error.rms < 0.0148, "DCM RMS {} m", s.dcm_error.rms);
    let mut scenario =
        Scenario::load(&config_path("walk_straight_foot_admittance.toml")).expect("scenario");
    scenario.config.simplified.foot_admittance.error_cutoff = 0.0;
    let unfiltered_hard = run_scenario_on_mujoco(&scenario);
    assert_eq!(
        unfiltered_hard.outcome,
        Outcome::GoalReached,
        "unfiltered, hard floor: {}",
        unfiltered_hard.outcome
    );
    on_the_former_soft_floor(&mut scenario);
    let unfiltered_soft = run_scenario_on_mujoco(&scenario);
    assert_eq!(
        unfiltered_soft.outcome,
        Outcome::DurationReached,
        "unfiltered, former soft floor: {}",
        unfiltered_soft.outcome
    );
    let mut filtered_soft =
        Scenario::load(&config_path("walk_straight_foot_admittance.toml")).expect("scenario");
    on_the_former_soft_floor(&mut filtered_soft);
    let filtered_soft = run_scenario_on_mujoco(&filtered_soft);
    assert_eq!(
        filtered_soft.outcome,
        Outcome::GoalReached,
        "filtered, former soft floor: {}",
        filtered_soft.outcome
    );
}

/// The DCM MPC walk in position control on MuJoCo falls at its goal without the foot admittance and
/// reaches it with the admittance (docs/mujoco.md).
#[cfg(feature = "mujoco")]
#[test]
fn the_mpc_position_walk_reaches_its_goal_on_mujoco_only_with_the_foot_admittance() {
    let mut scenario = Scenario::load(&config_path("walk_straight_mpc.toml")).expect("scenario");
    // on by default in position control since 2026-12-05
    scenario.config.simplified.foot_admittance.enabled = false;
    let without = run_scenario_on_mujoco(&scenario);
    // it fell before the chest weight 50 and `when_read` estimation of 2026-12-05; it now walks on its
    // soles until the duration runs out, never standing still at the goal
    assert!(
        matches!(
            without.outcome,
            Outcome::Fell { .. } | Outcome::DurationReached
        ),
        "without: {}",
        without.outcome
    );
    scenario.config.simplified.foot_admittance.enabled = true;
    let with = run_scenario_on_mujoco(&scenario);
    assert_eq!(with.outcome, Outcome::GoalReached, "with: {}", with.outcome);
}

/// The fast torque walk on MuJoCo (docs/mujoco.md, "Torque walks that fell on MuJoCo"): with the soft CoM
/// task of `walk_fast_torque.toml` it reaches its goal without a relaxed TSID solve; with the walking preset's
/// hard CoM task (configs/layers/walk_fast_base.toml, the 0.22 m walk, in torque control) the QP takes the CoM
/// acceleration from the upper body and needs relaxed solves (measured 2026-12-07: 202, the torso tilted
/// 14.6°; it still reaches its goal since the CoM task's own vertical gains of 2026-12-07, where before them
/// the torso toppled).
#[cfg(feature = "mujoco")]
#[test]
fn the_fast_torque_walk_needs_no_relaxed_solve_on_mujoco_only_with_a_soft_com_task() {
    let s = run_on_mujoco("walk_fast_torque.toml");
    assert_eq!(s.outcome, Outcome::GoalReached, "{}", s.outcome);
    assert_eq!(s.wbc_fallbacks, 0);
    let mut hard = Scenario::load(&config_path("layers/walk_fast_base.toml")).expect("scenario");
    hard.config.scenario.control_mode = stride_runner::config::ControlMode::Torque;
    let hard = run_scenario_on_mujoco(&hard);
    assert!(hard.wbc_fallbacks > 0, "hard CoM task: {}", hard.outcome);
}

/// The fast torque curve on MuJoCo (docs/mujoco.md, "Torque walks that fell on MuJoCo"; issue 16): with the
/// estimation layer's joint velocity filter that `walk_curve_fast_torque.toml` sets (150 Hz) it reaches its
/// goal at ≥ 0.25 m/s without a relaxed TSID solve (measured: goal 5 mm away, tilt 4.9°); with the encoders'
/// low-passed velocities (`joint_velocity_bandwidth = 0`) the swing feet strike the ground and it falls
/// (measured: 0.36 m before its goal, torso tilt 20°).
#[cfg(feature = "mujoco")]
#[test]
fn the_fast_torque_curve_reaches_its_goal_on_mujoco_with_filtered_joint_velocities() {
    let s = run_on_mujoco("walk_curve_fast_torque.toml");
    assert_eq!(s.outcome, Outcome::GoalReached, "{}", s.outcome);
    assert_eq!(s.wbc_fallbacks, 0);
    let speed = s.gait.steady_speed.expect("enough touch-downs");
    assert!(speed >= 0.25, "steady speed {speed} m/s");
    let mut unfiltered =
        Scenario::load(&config_path("walk_curve_fast_torque.toml")).expect("scenario");
    unfiltered.config.estimation.joint_velocity_bandwidth = 0.0;
    let fell = run_scenario_on_mujoco(&unfiltered);
    assert!(
        matches!(fell.outcome, Outcome::Fell { .. }),
        "encoders' velocities: {}",
        fell.outcome
    );
}

/// The fastest position walk on MuJoCo (docs/mujoco.md, "The fast position walks"): with its file's settings
/// (the QP-IK's command interpolated to every plant step, `wbc.position_command = "interpolate"`, and the foot
/// admittance's gains of before 2026-12-06) the 0.44 m/s walk reaches its goal within 20 s (measured: at
/// 13.4 s, 9 mm from it, DCM 28.5 mm RMS); with the admittance's hard-floor defaults of 2026-12-06 it walks the
/// distance but does not reach the goal (measured: 0.118 m off at 45 s, DCM 105.6 mm RMS). Both measured on
/// MuJoCo's floor matched to the former 3·10⁷ N/m³ default ground, which this test keeps (explicit) for
/// both sides. On the floor matched to the hard default (k 3·10⁸, since 2026-12-06) the walk with its file's
/// settings reaches its goal too since the servo limits act on the applied force (`mujoco.servo_saturation`;
/// measured 2026-12-06: at 13.3 s, 0.078 m from it, DCM 54.1 mm RMS; before that change it did not within
/// 20 s).
#[cfg(feature = "mujoco")]
#[test]
fn the_fast_upright_walk_reaches_its_goal_on_mujoco_with_its_admittance_gains() {
    use stride_runner::position_command::PositionCommand;
    use stride_simplified::FootAdmittanceConfig;
    let mut scenario = Scenario::load(&config_path("walk_fast_upright.toml")).expect("scenario");
    scenario.config.scenario.duration = 20.0;
    assert_eq!(
        scenario.config.wbc.position_command,
        PositionCommand::Interpolate
    );
    reaches_its_goal_on_the_hard_then_on_the_former_floor(&mut scenario);
    let d = FootAdmittanceConfig::default();
    let a = &mut scenario.config.simplified.foot_admittance;
    (a.torque_gain, a.torque_leak_time, a.force_gain) =
        (d.torque_gain, d.torque_leak_time, d.force_gain);
    let defaults = run_scenario_on_mujoco(&scenario);
    assert_ne!(
        defaults.outcome,
        Outcome::GoalReached,
        "the admittance's default gains: {}",
        defaults.outcome
    );
}

/// Issue 15's position-control speed on MuJoCo (docs/gait.md, "`walk_fast.toml` on both plants"):
/// `walk_fast.toml` (0.25 m steps every 0.47 s, braking at 0.3 m/s² before the goal) reaches its goal at
/// ≥ 0.40 m/s steady with each of the sensor seeds 0–3 on the hard default floor (measured 2026-12-06:
/// 0.415–0.427 m/s, 0.012–0.089 m from the goal, tilt ≤ 8.1°). The other side: the same steps without the
/// braking fall while stopping with seed 2 (measured: at 11.46 s, 3.94 m, DCM error).
#[cfg(feature = "mujoco")]
#[test]
fn the_fast_walk_reaches_its_goal_at_0_4_m_per_s_on_mujoco_with_every_sensor_seed() {
    let scenario = Scenario::load(&config_path("walk_fast.toml")).expect("scenario");
    for seed in 0..4 {
        let mut seeded = scenario.clone();
        seeded.config.sim.sensors.seed = seed;
        let s = run_scenario_on_mujoco(&seeded);
        assert_eq!(
            s.outcome,
            Outcome::GoalReached,
            "seed {seed}: {}",
            s.outcome
        );
        let speed = s.gait.steady_speed.expect("enough touch-downs");
        assert!(speed >= 0.40, "seed {seed}: steady speed {speed} m/s");
        assert!(
            s.max_tilt_deg < 10.0,
            "seed {seed}: tilt {}°",
            s.max_tilt_deg
        );
    }
    let mut unbraked = scenario;
    unbraked.config.sim.sensors.seed = 2;
    unbraked.config.planner.stop_deceleration = 0.0;
    let fell = run_scenario_on_mujoco(&unbraked);
    assert!(
        matches!(fell.outcome, Outcome::Fell { .. }),
        "no braking, seed 2: {}",
        fell.outcome
    );
}

/// A servo at its effort limit on MuJoCo (`mujoco.servo_saturation`, docs/mujoco.md, "Servos at their
/// limits"): the 0.22 m walk of configs/layers/walk_fast_base.toml (`walk_fast` until 2026-12-06) with
/// sensor seed 3 reaches its goal with the limit applied on the force the step
/// applies (measured 2026-12-06: 14 mm from it, the ankles 0.3 s at their limits, c_et 6.6 J/kg/m); with
/// MuJoCo's own clamp of the start-of-step force the clamped servos' damping is explicit, their torque
/// flips between the limits at the plant rate (ankles 1.7 s at their limits, c_et 14.0 J/kg/m) and the walk
/// stands 0.11 m beside its goal at 45 s. Both measured on the former soft floor (k 3·10⁷), where the claim
/// is checked on both sides; on the hard default floor the walk reaches its goal with either limit
/// (measured 2026-12-06), and the test checks the default there.
#[cfg(feature = "mujoco")]
#[test]
fn the_fast_walk_reaches_its_goal_on_mujoco_only_with_the_servo_limit_on_the_applied_force() {
    use stride_runner::config::mujoco::MujocoServoSaturation;
    let mut scenario =
        Scenario::load(&config_path("layers/walk_fast_base.toml")).expect("scenario");
    scenario.config.sim.sensors.seed = 3;
    assert_eq!(
        scenario.config.mujoco.servo_saturation,
        MujocoServoSaturation::AppliedForce
    );
    reaches_its_goal_on_the_hard_then_on_the_former_floor(&mut scenario);
    scenario.config.mujoco.servo_saturation = MujocoServoSaturation::StartOfStep;
    let clamped = run_scenario_on_mujoco(&scenario);
    assert_ne!(
        clamped.outcome,
        Outcome::GoalReached,
        "MuJoCo's clamp: {}",
        clamped.outcome
    );
}

/// The fixed base on MuJoCo (`sim.fixed_base`: the root a mocap body held at the initial pose, no collision
/// geometry without contact surfaces): `configs/identify_ft_legs.toml` swings the legs of the robot on its
/// pole for 30 s, the base does not move, and `stride calibrate` recovers the FT offsets from the log within
/// the bounds of stride-sim's test (crates/runner/tests/calibrate.rs; measured on MuJoCo: at most 0.110 N and
/// 0.036 N·m off, within 0.003 of stride-sim's errors on the same seed).
#[cfg(feature = "mujoco")]
#[test]
fn on_a_pole_in_mujoco_the_base_stays_and_the_ft_offsets_are_recovered() {
    let scenario = Scenario::load(&config_path("identify_ft_legs.toml")).expect("scenario");
    let dir = std::env::temp_dir().join(format!("stride-mujoco-pole-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let log = dir.join("legs.mcap");
    let duration = 30.0;
    let options = RunOptions {
        plant: Some(PlantKind::Mujoco),
        duration: Some(duration),
        output: Some(log.clone()),
        ..RunOptions::default()
    };
    let s = run_scenario(&scenario, &options).expect("run");
    assert_eq!(s.outcome, Outcome::DurationReached, "{}", s.outcome);
    assert_eq!(base_poses_in_log(&log).len(), 1, "the base moved");
    let report = stride_runner::calibrate::calibrate_log(&log, None).expect("calibrate");
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(report.sensors.len(), 4);
    let ft = &scenario.config.sim.sensors.ft;
    for c in &report.sensors {
        let truth = c.truth.expect("simulated");
        for i in 0..6 {
            let bound = stride_testkit::ft_offset_error_bound(
                i,
                c.offset_std[i],
                ft.force_drift,
                ft.torque_drift,
                duration,
            );
            let err = (c.offset[i] - truth[i]).abs();
            assert!(
                err < bound,
                "{} axis {i}: error {err:.4} > {bound:.4}",
                c.name
            );
        }
    }
}

/// The distinct true base poses (`/sim/state` `base`, as logged) of the log at `path`.
#[cfg(feature = "mujoco")]
fn base_poses_in_log(path: &Path) -> Vec<String> {
    let bytes = std::fs::read(path).expect("log");
    let mut poses: Vec<String> = Vec::new();
    for message in mcap::MessageStream::new(&bytes).expect("mcap") {
        let message = message.expect("message");
        if message.channel.topic != "/sim/state" {
            continue;
        }
        let state: serde_json::Value = serde_json::from_slice(&message.data).expect("json");
        let base = state["base"].to_string();
        if !poses.contains(&base) {
            poses.push(base);
        }
    }
    assert!(!poses.is_empty(), "no /sim/state in the log");
    poses
}
