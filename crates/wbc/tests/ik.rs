//! QP-IK: convergence from random reachable postures to random reachable targets, joint limits,
//! exactness of the hard tasks, cross-solver agreement, infeasibility and the fallback.

mod common;

use std::sync::Arc;
use std::time::Duration;

use common::*;
use nalgebra::DVector;
use stride_block::Block;
use stride_model::{KinDyn, Model, VelocityRepresentation};
use stride_qp::{Backend, QpStatus};
use stride_wbc::{IkConfig, QpIk, TaskConfig, WbcInput};

/// Period of the tests' controllers (s), except where a test says otherwise.
const PERIOD: Duration = Duration::from_millis(10);
/// The runner's default WBC period (500 Hz).
const PERIOD_500HZ: Duration = Duration::from_millis(2);

/// Test config: the bundled default with faster gains (the convergence rate per step is `1 − K dt`).
fn test_config(gain: f64) -> IkConfig {
    let mut c = IkConfig::default_for_bundled_model();
    for t in &mut c.tasks {
        match t {
            TaskConfig::Se3(s) => {
                s.kp_linear = gain;
                s.kp_angular = gain;
            }
            TaskConfig::Com(s) => s.kp = gain,
            _ => {}
        }
    }
    c
}

fn limits(model: &Model) -> (Vec<f64>, Vec<f64>) {
    (
        model.joints().iter().map(|j| j.lower).collect(),
        model.joints().iter().map(|j| j.upper).collect(),
    )
}

/// The largest violation of the joint limits by `q` (0 when inside).
fn limit_violation(model: &Model, q: &DVector<f64>) -> f64 {
    let (lo, hi) = limits(model);
    (0..q.len())
        .map(|i| (lo[i] - q[i]).max(q[i] - hi[i]).max(0.0))
        .fold(0.0, f64::max)
}

/// Pose errors of the three hard tasks of the bundled config at `state` against `input`, measured
/// independently of the controller with stride-model.
fn hard_errors(model: &Arc<Model>, state: &stride_model::RobotState, input: &WbcInput) -> f64 {
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_representation(VelocityRepresentation::Mixed);
    kd.set_state(state).unwrap();
    let mut worst: f64 = 0.0;
    for (frame, r) in [("l_sole", &input.lf()), ("r_sole", &input.rf())] {
        let p = kd.frame_pose(model.frame_id(frame).unwrap());
        worst = worst.max((p.translation.vector - r.pose.translation.vector).norm());
        worst = worst.max((r.pose.rotation * p.rotation.inverse()).angle());
    }
    worst.max((kd.com_position() - input.com_position).norm())
}

#[test]
fn converges_from_random_postures_to_random_reachable_targets() {
    let model = bundled_model();
    let mut rng = rng(7);
    let max_steps = 400;
    for trial in 0..6 {
        // reachable target: feet and CoM of a random posture at a random base pose
        let q_target = random_posture(&model, &mut rng, 0.25, 0.05);
        let mut target_state = standing_state(&model, &q_target);
        target_state.base_pose = random_pose(&mut rng, 0.05, 0.1) * target_state.base_pose;
        let mut input = references_at(&model, &target_state);
        // start: another random posture
        let q0 = random_posture(&model, &mut rng, 0.25, 0.05);
        input.state = standing_state(&model, &q0);

        let mut ik = QpIk::new(Arc::clone(&model), test_config(10.0), PERIOD).unwrap();
        let mut converged_at = None;
        for step in 0..max_steps {
            let out = ik.step(&input).unwrap();
            assert_eq!(
                out.report.status,
                QpStatus::Solved,
                "trial {trial} step {step}"
            );
            assert!(!out.report.fallback && !out.report.held);
            assert!(out.joint_positions.iter().all(|v| v.is_finite()));
            let v = limit_violation(&model, &out.joint_positions);
            assert!(
                v < 1e-9,
                "trial {trial} step {step}: joint limits violated by {v}"
            );
            let e = hard_errors(&model, ik.integrated_state(), &input);
            if e < 1e-6 {
                converged_at = Some(step);
                break;
            }
        }
        let step = converged_at.unwrap_or_else(|| {
            panic!(
                "trial {trial}: not converged within {max_steps} steps (error {})",
                hard_errors(&model, ik.integrated_state(), &input)
            )
        });
        eprintln!("trial {trial}: converged in {step} steps");
        assert!(step < max_steps);
    }
}

#[test]
fn joint_limits_hold_when_the_target_needs_more_than_the_range() {
    let model = bundled_model();
    let q = common::default_posture(&model);
    let state = standing_state(&model, &q);
    let mut input = references_at(&model, &state);
    // CoM far down: needs more knee flexion than the range allows (CoM soft so the QP stays feasible)
    input.com_position.z -= 0.5;
    let mut config = test_config(10.0);
    for t in &mut config.tasks {
        if let TaskConfig::Com(c) = t {
            c.priority = stride_wbc::Priority::Soft;
            c.weight = Some(stride_wbc::Weight::Scalar(100.0));
        }
    }
    let mut ik = QpIk::new(Arc::clone(&model), config, PERIOD).unwrap();
    let mut reached_a_limit = false;
    let (lo, hi) = limits(&model);
    for _ in 0..300 {
        let out = ik.step(&input).unwrap();
        assert!(out.report.status.is_success());
        let v = limit_violation(&model, &out.joint_positions);
        assert!(v < 1e-9, "joint limits violated by {v}");
        reached_a_limit |= (0..q.len()).any(|i| {
            (out.joint_positions[i] - lo[i]).abs() < 1e-6
                || (hi[i] - out.joint_positions[i]).abs() < 1e-6
        });
    }
    assert!(
        reached_a_limit,
        "the test should drive some joint to its limit"
    );
}

#[test]
fn hard_tasks_are_satisfied_exactly_and_velocity_mode_reproduces_reference_rates() {
    let model = bundled_model();
    let mut rng = rng(11);
    let q = random_posture(&model, &mut rng, 0.2, 0.1);
    let state = standing_state(&model, &q);
    let mut input = references_at(&model, &state);
    // zero errors, non-zero reference velocities of the feet and the CoM
    input.lf_mut().velocity = nalgebra::Vector6::new(0.1, 0.0, 0.05, 0.0, 0.0, 0.2);
    input.com_velocity = nalgebra::Vector3::new(0.05, 0.01, 0.0);
    let mut config = test_config(10.0);
    config.feedback = stride_wbc::IkFeedback::Measured;
    let mut ik = QpIk::new(Arc::clone(&model), config, PERIOD_500HZ).unwrap();
    let out = ik.step(&input).unwrap().clone();
    assert_eq!(out.report.status, QpStatus::Solved);
    let mut nu = DVector::zeros(model.nv());
    nu.fixed_rows_mut::<6>(0).copy_from(&out.base_velocity);
    nu.rows_mut(6, model.dof()).copy_from(&out.joint_velocities);
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_representation(VelocityRepresentation::Mixed);
    kd.set_state(&state).unwrap();
    let mut j = nalgebra::DMatrix::zeros(6, model.nv());
    kd.frame_jacobian(model.frame_id("l_sole").unwrap(), &mut j)
        .unwrap();
    assert!((&j * &nu - input.lf().velocity).norm() < 1e-9);
    kd.frame_jacobian(model.frame_id("r_sole").unwrap(), &mut j)
        .unwrap();
    assert!((&j * &nu).norm() < 1e-9);
    let mut jc = nalgebra::DMatrix::zeros(3, model.nv());
    kd.com_jacobian(&mut jc).unwrap();
    assert!((&jc * &nu - input.com_velocity).norm() < 1e-9);
    // per-task residuals of the hard tasks are reported and tiny
    for r in out.residuals.iter().filter(|r| r.hard) {
        assert!(r.residual < 1e-9, "{}: {}", r.name, r.residual);
    }
    // KKT of the solved QP
    let kkt = ik.qp_problem().check_kkt();
    assert!(kkt.is_satisfied(1e-7), "{kkt:?}");
}

#[test]
fn clarabel_and_active_set_agree_on_ik_ticks() {
    let model = bundled_model();
    let mut rng = rng(3);
    for _ in 0..5 {
        let q_target = random_posture(&model, &mut rng, 0.2, 0.05);
        let input_target = references_at(&model, &standing_state(&model, &q_target));
        let mut input = input_target.clone();
        input.state = standing_state(&model, &random_posture(&model, &mut rng, 0.2, 0.05));
        let mut a = test_config(10.0);
        a.qp.backend = Backend::ActiveSet;
        let mut c = a.clone();
        c.qp.backend = Backend::Clarabel;
        let mut ik_a = QpIk::new(Arc::clone(&model), a, PERIOD).unwrap();
        let mut ik_c = QpIk::new(Arc::clone(&model), c, PERIOD).unwrap();
        for _ in 0..3 {
            let oa = ik_a.step(&input).unwrap().clone();
            let oc = ik_c.step(&input).unwrap().clone();
            assert!(oa.report.status.is_success() && oc.report.status.is_success());
            let d = (&oa.joint_velocities - &oc.joint_velocities)
                .amax()
                .max((oa.base_velocity - oc.base_velocity).amax());
            assert!(d < 1e-6, "active set vs clarabel differ by {d}");
            // keep both integrating from the same state
            let s = ik_a.integrated_state().clone();
            ik_c.set_integrated_state(&s).unwrap();
        }
    }
}

#[test]
fn unreachable_feet_fall_back_to_the_relaxed_problem_without_nan() {
    let model = bundled_model();
    let q = common::default_posture(&model);
    let state = standing_state(&model, &q);
    let mut input = references_at(&model, &state);
    // feet 3 m apart: the joint-limit bounds make the hard feet + CoM rows infeasible at once
    input.lf_mut().pose.translation.vector.y += 1.5;
    input.rf_mut().pose.translation.vector.y -= 1.5;
    let mut ik = QpIk::new(Arc::clone(&model), test_config(100.0), PERIOD).unwrap();
    let out = ik.step(&input).unwrap();
    assert_eq!(out.report.status, QpStatus::Infeasible);
    assert!(
        out.report.fallback,
        "the relaxed problem should give the command"
    );
    assert_eq!(out.report.relaxed_status, Some(QpStatus::Solved));
    assert!(!out.report.held);
    assert!(out.joint_positions.iter().all(|v| v.is_finite()));
    assert!(limit_violation(&model, &out.joint_positions) < 1e-9);
    // the hard feet tasks are violated and say so
    let feet: f64 = out
        .residuals
        .iter()
        .filter(|r| r.name.ends_with("foot"))
        .map(|r| r.residual)
        .sum();
    assert!(feet > 1.0);
}

#[test]
fn a_failed_tick_holds_the_last_valid_command() {
    let model = bundled_model();
    let q = common::default_posture(&model);
    let state = standing_state(&model, &q);
    let input = references_at(&model, &state);
    let mut config = test_config(10.0);
    config.qp.fallback = false;
    let mut ik = QpIk::new(Arc::clone(&model), config, PERIOD).unwrap();
    let good = ik.step(&input).unwrap().joint_positions.clone();
    let mut bad = input.clone();
    bad.lf_mut().pose.translation.vector.y += 1.5;
    bad.rf_mut().pose.translation.vector.y -= 1.5;
    let out = ik.step(&bad).unwrap();
    assert!(out.report.held);
    assert_eq!(out.joint_positions, good);
    assert!(out.joint_velocities.iter().all(|v| *v == 0.0));
}

#[test]
fn config_parses_from_toml_and_rejects_unknown_types_and_keys() {
    let text = r#"
feedback = "integrated"

[qp]
backend = "active_set"

[[tasks]]
type = "se3"
name = "left_foot"
frame = "l_sole"
reference = "left_foot"
kp_linear = 7.0
kp_angular = 5.0
priority = "hard"

[[tasks]]
type = "com"
name = "com"
kp = 2.0
mask = [true, true, false]
priority = "hard"

[[tasks]]
type = "so3"
name = "torso"
frame = "chest"
reference = "torso"
kp = 5.0
weight = [5.0, 5.0, 1.0]

[[tasks]]
type = "joint_regularization"
name = "posture"
kp = 5.0
posture = { l_knee = 0.5 }
joint_weights = { l_elbow = 2.0 }

[[tasks]]
type = "joint_position_limits"
name = "limits"
"#;
    let config: IkConfig = toml::from_str(text).unwrap();
    assert_eq!(config.tasks.len(), 5);
    let model = bundled_model();
    QpIk::new(Arc::clone(&model), config, PERIOD).unwrap();

    let unknown_type = text.replace("type = \"com\"", "type = \"centre_of_mass\"");
    assert!(toml::from_str::<IkConfig>(&unknown_type).is_err());
    let unknown_key = text.replace("kp = 2.0", "kp = 2.0\nki = 1.0");
    assert!(toml::from_str::<IkConfig>(&unknown_key).is_err());

    // model-level errors carry names
    let bad_frame = text.replace("frame = \"l_sole\"", "frame = \"l_foot_sole\"");
    let err = QpIk::new(
        Arc::clone(&model),
        toml::from_str(&bad_frame).unwrap(),
        PERIOD,
    )
    .err()
    .unwrap();
    assert!(err.to_string().contains("l_foot_sole"), "{err}");
    let bad_joint = text.replace("l_knee = 0.5", "l_kne = 0.5");
    let err = QpIk::new(
        Arc::clone(&model),
        toml::from_str(&bad_joint).unwrap(),
        PERIOD,
    )
    .err()
    .unwrap();
    assert!(err.to_string().contains("l_kne"), "{err}");
    // TSID-only task in the IK
    let tsid_task = format!("{text}\n[[tasks]]\ntype = \"joint_torque_limits\"\nname = \"tau\"\n");
    let err = QpIk::new(
        Arc::clone(&model),
        toml::from_str(&tsid_task).unwrap(),
        PERIOD,
    )
    .err()
    .unwrap();
    assert!(err.to_string().contains("joint_torque_limits"), "{err}");
    // the defaults serialize and parse back identically
    let default = IkConfig::default_for_bundled_model();
    let back: IkConfig = toml::from_str(&toml::to_string(&default).unwrap()).unwrap();
    assert_eq!(back, default);
}

#[test]
fn null_space_elimination_gives_the_full_problem_solution() {
    let model = bundled_model();
    let mut rng = rng(17);
    for _ in 0..5 {
        let target = references_at(
            &model,
            &standing_state(&model, &random_posture(&model, &mut rng, 0.2, 0.05)),
        );
        let mut input = target.clone();
        input.state = standing_state(&model, &random_posture(&model, &mut rng, 0.2, 0.05));
        let reduced_config = test_config(10.0);
        let mut full_config = reduced_config.clone();
        full_config.eliminate_equalities = false;
        let mut reduced = QpIk::new(Arc::clone(&model), reduced_config, PERIOD).unwrap();
        let mut full = QpIk::new(Arc::clone(&model), full_config, PERIOD).unwrap();
        let a = reduced.step(&input).unwrap().clone();
        let b = full.step(&input).unwrap().clone();
        assert_eq!(reduced.qp_problem().n(), model.nv() - 15);
        assert_eq!(full.qp_problem().n(), model.nv());
        let d = (&a.joint_velocities - &b.joint_velocities)
            .amax()
            .max((a.base_velocity - b.base_velocity).amax());
        assert!(d < 1e-6, "eliminated vs full differ by {d}");
    }
}

/// The null-space path (factorization, compact-WY basis, projections, stacked Hessian) against the
/// straightforward reference, the full problem with its 15 hard rows solved by the same backend: the
/// QP is strictly convex, so the two agree to the solver's tolerance, over integrated ticks of the default
/// configuration (limits as bounds) and in the reported task residuals.
#[test]
fn null_space_path_matches_the_full_problem_to_solver_tolerance_over_integrated_ticks() {
    let model = bundled_model();
    let mut rng = rng(29);
    let mut worst: f64 = 0.0;
    for _ in 0..5 {
        let target = references_at(
            &model,
            &standing_state(&model, &random_posture(&model, &mut rng, 0.2, 0.05)),
        );
        let mut input = target.clone();
        input.state = standing_state(&model, &random_posture(&model, &mut rng, 0.2, 0.05));
        let reduced_config = IkConfig::default_for_bundled_model();
        let mut full_config = reduced_config.clone();
        full_config.eliminate_equalities = false;
        let mut reduced = QpIk::new(Arc::clone(&model), reduced_config, PERIOD_500HZ).unwrap();
        let mut full = QpIk::new(Arc::clone(&model), full_config, PERIOD_500HZ).unwrap();
        for tick in 0..3 {
            let a = reduced.step(&input).unwrap().clone();
            let b = full.step(&input).unwrap().clone();
            assert_eq!(reduced.qp_problem().n(), model.nv() - 15);
            assert_eq!(a.report.status, QpStatus::Solved);
            let scale = 1.0 + b.joint_velocities.amax().max(b.base_velocity.amax());
            let d = (&a.joint_velocities - &b.joint_velocities)
                .amax()
                .max((a.base_velocity - b.base_velocity).amax())
                / scale;
            worst = worst.max(d);
            assert!(
                d < 1e-9,
                "tick {tick}: eliminated vs full differ by {d} (relative)"
            );
            for (ra, rb) in a.residuals.iter().zip(&b.residuals) {
                let dr = (ra.residual - rb.residual).abs();
                assert!(
                    dr < 1e-8 * scale,
                    "{}: residual {} vs {}",
                    ra.name,
                    ra.residual,
                    rb.residual
                );
            }
        }
    }
    eprintln!("largest relative difference, eliminated vs full: {worst:e}");
}

#[test]
fn redundant_hard_tasks_are_solved_by_both_backends_alike() {
    // a second hard task on the left sole duplicates 6 rows: the hard rows are rank deficient, the
    // null-space reduction declines and the full problem (dependent but consistent rows) is solved
    let model = bundled_model();
    let mut rng = rng(23);
    let target = references_at(
        &model,
        &standing_state(&model, &random_posture(&model, &mut rng, 0.2, 0.05)),
    );
    let mut input = target.clone();
    input.state = standing_state(&model, &random_posture(&model, &mut rng, 0.2, 0.05));
    let mut config = test_config(10.0);
    let duplicate = config
        .tasks
        .iter()
        .find(|t| t.name() == "left_foot")
        .unwrap()
        .clone();
    if let TaskConfig::Se3(mut c) = duplicate {
        c.name = "left_foot_again".into();
        config.tasks.push(TaskConfig::Se3(c));
    }
    let mut outputs = Vec::new();
    for backend in [Backend::ActiveSet, Backend::Clarabel] {
        let mut c = config.clone();
        c.qp.backend = backend;
        c.qp.clarabel.tolerance = 1e-12;
        let mut ik = QpIk::new(Arc::clone(&model), c, PERIOD).unwrap();
        let out = ik.step(&input).unwrap().clone();
        assert!(
            out.report.status.is_success(),
            "{backend:?}: {:?}",
            out.report
        );
        assert!(!out.report.fallback);
        assert_eq!(
            ik.qp_problem().n(),
            model.nv(),
            "the full problem was solved"
        );
        outputs.push(out);
    }
    let d = (&outputs[0].joint_velocities - &outputs[1].joint_velocities).amax();
    assert!(d < 1e-6, "backends differ by {d}");
    // and the same answer as without the duplicate
    let mut ik = QpIk::new(Arc::clone(&model), test_config(10.0), PERIOD).unwrap();
    let plain = ik.step(&input).unwrap();
    assert!((&plain.joint_velocities - &outputs[0].joint_velocities).amax() < 1e-6);
}

#[test]
fn soft_weights_change_at_run_time() {
    let model = bundled_model();
    let q = common::default_posture(&model);
    let state = standing_state(&model, &q);
    let mut input = references_at(&model, &state);
    // torso reference tilted: torso task and posture task compete
    input.torso_mut().pose.rotation =
        nalgebra::UnitQuaternion::from_euler_angles(0.0, 0.2, 0.0) * input.torso().pose.rotation;
    let mut config = test_config(10.0);
    config.feedback = stride_wbc::IkFeedback::Measured;
    let mut ik = QpIk::new(Arc::clone(&model), config.clone(), PERIOD).unwrap();
    let before = ik.step(&input).unwrap().joint_velocities.clone();
    ik.set_task_weight("torso", &[500.0]).unwrap();
    let after = ik.step(&input).unwrap().joint_velocities.clone();
    // same as a controller built with that weight
    // only the `torso` task: the default config has a second SO(3) task (`pelvis`)
    for t in &mut config.tasks {
        if let TaskConfig::So3(c) = t {
            if c.name == "torso" {
                c.weight = Some(stride_wbc::Weight::Scalar(500.0));
            }
        }
    }
    let mut reference = QpIk::new(Arc::clone(&model), config, PERIOD).unwrap();
    let expected = reference.step(&input).unwrap().joint_velocities.clone();
    assert!((&after - &expected).amax() < 1e-9);
    assert!((&after - &before).amax() > 1e-3);
    assert!(
        ik.set_task_weight("left_foot", &[1.0]).is_err(),
        "hard tasks have no weight"
    );
    assert!(ik.set_task_weight("nope", &[1.0]).is_err());
    assert!(ik.set_task_weight("torso", &[-1.0]).is_err());
}

/// Min-jerk profile s(t) ∈ [0, 1] and its derivative over duration `d`.
fn min_jerk(t: f64, d: f64) -> (f64, f64) {
    let x = (t / d).clamp(0.0, 1.0);
    let s = x * x * x * (10.0 - 15.0 * x + 6.0 * x * x);
    let ds = 30.0 * x * x * (1.0 - x) * (1.0 - x) / d;
    (s, ds)
}

#[test]
fn a_step_with_the_default_config_tracks_feet_and_com_references() {
    // a walking-like motion at 500 Hz: CoM shifts over the left foot, the right foot swings 10 cm
    // forward with a 3 cm apex, then the CoM moves between the feet; references carry feedforward
    // velocities, so the integrated IK tracks them with small lag
    let model = bundled_model();
    let state = standing_state(&model, &common::default_posture(&model));
    let start = references_at(&model, &state);
    let mut input = start.clone();
    let config = IkConfig::default_for_bundled_model();
    let dt = PERIOD_500HZ.as_secs_f64();
    let mut ik = QpIk::new(Arc::clone(&model), config, PERIOD_500HZ).unwrap();
    let com0 = start.com_position;
    let left = start.lf().pose.translation.vector;
    let right0 = start.rf().pose.translation.vector;
    let (shift, swing, settle) = (1.0, 0.8, 1.0);
    let steps = ((shift + swing + settle) / dt) as usize;
    let mut worst_foot: f64 = 0.0;
    let mut worst_com: f64 = 0.0;
    for k in 0..steps {
        let t = k as f64 * dt;
        // CoM: to 80 % over the left foot, then to the middle of the new support polygon
        let (s1, ds1) = min_jerk(t, shift);
        let (s3, ds3) = min_jerk(t - shift - swing, settle);
        let over_left = nalgebra::Vector3::new(left.x, 0.8 * left.y, com0.z)
            - nalgebra::Vector3::new(com0.x, com0.y, com0.z);
        let middle = nalgebra::Vector3::new(0.05, 0.0, com0.z) - (com0 + over_left);
        input.com_position = com0 + over_left * s1 + middle * s3;
        input.com_velocity = over_left * ds1 + middle * ds3;
        // right foot swing
        let (s2, ds2) = min_jerk(t - shift, swing);
        let apex = (std::f64::consts::PI * s2).sin();
        let dapex = std::f64::consts::PI * (std::f64::consts::PI * s2).cos() * ds2;
        input.rf_mut().pose.translation.vector =
            right0 + nalgebra::Vector3::new(0.1 * s2, 0.0, 0.03 * apex);
        input.rf_mut().velocity =
            nalgebra::Vector6::new(0.1 * ds2, 0.0, 0.03 * dapex, 0.0, 0.0, 0.0);
        let out = ik.step(&input).unwrap();
        assert_eq!(out.report.status, QpStatus::Solved, "t = {t}");
        assert!(!out.report.fallback);
        assert!(limit_violation(&model, &out.joint_positions) < 1e-9);
        let mut kd = KinDyn::new(Arc::clone(&model));
        kd.set_representation(VelocityRepresentation::Mixed);
        kd.set_state(ik.integrated_state()).unwrap();
        let r = kd.frame_pose(model.frame_id("r_sole").unwrap());
        worst_foot =
            worst_foot.max((r.translation.vector - input.rf().pose.translation.vector).norm());
        worst_com = worst_com.max((kd.com_position() - input.com_position).norm());
    }
    // one Euler step of lag on a ≤ 0.25 m/s reference is ≤ 0.5 mm
    assert!(worst_foot < 1e-3, "right foot tracking error {worst_foot}");
    assert!(worst_com < 1e-3, "CoM tracking error {worst_com}");
}

/// The `torso` and `pelvis` tasks with `reference_offset`, the `pelvis` task removed (it would compare
/// different references between the two controllers of the test).
fn offset_config(offset: stride_wbc::ReferenceOffset) -> IkConfig {
    let mut c = test_config(10.0);
    c.feedback = stride_wbc::IkFeedback::Measured;
    c.tasks.retain(|t| t.name() != "pelvis");
    for t in &mut c.tasks {
        if let TaskConfig::So3(s) = t {
            s.reference_offset = offset;
        }
    }
    c
}

#[test]
fn initial_reference_offset_keeps_the_frames_initial_orientation_relative_to_the_reference() {
    use nalgebra::{UnitQuaternion, Vector3};
    use stride_wbc::ReferenceOffset;
    let model = bundled_model();
    let q = common::default_posture(&model);
    let mut state = standing_state(&model, &q);
    // A robot whose chest is not world-aligned when "upright" (as iCub's chest: x left, y up, z forward):
    // the whole robot rotated by an arbitrary R₀.
    let r0 = UnitQuaternion::from_euler_angles(0.3, -0.2, 2.5);
    state.base_pose =
        nalgebra::Isometry3::from_parts(nalgebra::Translation3::identity(), r0) * state.base_pose;
    let mut input = references_at(&model, &state);
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_representation(VelocityRepresentation::Mixed);
    kd.set_state(&state).unwrap();
    let chest = kd.frame_pose(model.frame_id("chest").unwrap()).rotation;
    // The torso reference is a heading (yaw) only; the recorded offset is R_refᵀ R_chest.
    let reference0 = UnitQuaternion::from_euler_angles(0.0, 0.0, 0.4);
    let offset = reference0.inverse() * chest;
    input.torso_mut().pose.rotation = reference0;
    let mut with_offset = QpIk::new(
        Arc::clone(&model),
        offset_config(ReferenceOffset::Initial),
        PERIOD,
    )
    .unwrap();
    let mut plain = QpIk::new(
        Arc::clone(&model),
        offset_config(ReferenceOffset::None),
        PERIOD,
    )
    .unwrap();
    // First tick: the offset is recorded, so the torso task's reference is the chest's own orientation,
    // which is what the plain controller gets as an absolute reference.
    let first = with_offset.step(&input).unwrap().joint_velocities.clone();
    let mut absolute = input.clone();
    absolute.torso_mut().pose.rotation = chest;
    let expected = plain.step(&absolute).unwrap().joint_velocities.clone();
    assert!((&first - &expected).amax() < 1e-9);
    // A new heading and angular velocity: the reference is R_ref · R_off, the angular velocity unchanged.
    let reference1 = UnitQuaternion::from_euler_angles(0.0, 0.0, 0.55);
    input.torso_mut().pose.rotation = reference1;
    input.set_torso_angular_velocity(Vector3::new(0.0, 0.0, 0.3));
    absolute.torso_mut().pose.rotation = reference1 * offset;
    absolute.set_torso_angular_velocity(input.torso_angular_velocity());
    let turned = with_offset.step(&input).unwrap().joint_velocities.clone();
    let expected = plain.step(&absolute).unwrap().joint_velocities.clone();
    assert!(
        (&turned - &expected).amax() < 1e-9,
        "{}",
        (&turned - &expected).amax()
    );
    assert!(
        (&turned - &first).amax() > 1e-3,
        "the heading change moves the robot"
    );
    // Without the offset the same input would drive the chest to the bare yaw (a large rotation).
    let bare = plain.step(&input).unwrap().joint_velocities.clone();
    assert!((&bare - &turned).amax() > 1e-2);
    // `reset` records the offset again, at the next tick.
    with_offset.reset();
    absolute.torso_mut().pose.rotation = chest;
    absolute.set_torso_angular_velocity(input.torso_angular_velocity());
    let again = with_offset.step(&input).unwrap().joint_velocities.clone();
    let expected = plain.step(&absolute).unwrap().joint_velocities.clone();
    assert!((&again - &expected).amax() < 1e-9);
}

#[test]
fn reference_offset_is_rejected_on_position_tasks() {
    let text = r#"
[[tasks]]
type = "r3"
name = "hand"
frame = "chest"
reference = "initial"
reference_offset = "initial"
kp = 1.0
"#;
    let config: IkConfig = toml::from_str(text).unwrap();
    let err = QpIk::new(bundled_model(), config, PERIOD).err().unwrap();
    let text = err.to_string();
    assert!(
        text.contains("reference_offset") && text.contains("hand"),
        "{text}"
    );
    // and the default is `none`
    let so3: IkConfig = toml::from_str(
        "[[tasks]]\ntype = \"so3\"\nname = \"t\"\nframe = \"chest\"\nreference = \"torso\"\n",
    )
    .unwrap();
    assert!(matches!(
        &so3.tasks[0],
        TaskConfig::So3(c) if c.reference_offset == stride_wbc::ReferenceOffset::None
    ));
}

#[test]
fn a_weight_on_a_hard_task_is_a_configuration_error_naming_the_task() {
    let text = r#"
[[tasks]]
type = "com"
name = "centre"
kp = 2.0
priority = "hard"
weight = 3.0

[[tasks]]
type = "so3"
name = "torso"
frame = "chest"
reference = "torso"
kp = 5.0
weight = [5.0, 5.0, 1.0]
"#;
    let model = bundled_model();
    let config: IkConfig = toml::from_str(text).unwrap();
    let err = QpIk::new(Arc::clone(&model), config, PERIOD).err().unwrap();
    assert!(
        matches!(&err, stride_wbc::WbcError::InvalidConfig { task, key: "weight", .. } if task == "centre"),
        "{err}"
    );
    // without the weight the same hard task builds; soft tasks keep scalar and per-row weights
    let config: IkConfig = toml::from_str(&text.replace("weight = 3.0\n", "")).unwrap();
    QpIk::new(Arc::clone(&model), config, PERIOD).unwrap();
    // a hard posture task with a weight is rejected too
    let posture = format!(
        "{}\n[[tasks]]\ntype = \"joint_regularization\"\nname = \"posture\"\npriority = \"hard\"\nweight = 2.0\n",
        text.replace("weight = 3.0\n", "")
    );
    let err = QpIk::new(
        Arc::clone(&model),
        toml::from_str(&posture).unwrap(),
        PERIOD,
    )
    .err()
    .unwrap();
    assert!(err.to_string().contains("posture"), "{err}");
    // a zero period is an error
    let config: IkConfig = toml::from_str(&text.replace("weight = 3.0\n", "")).unwrap();
    assert!(QpIk::new(Arc::clone(&model), config, Duration::ZERO).is_err());
}

/// Task names address tasks in errors, residuals and logs: QP-IK and TSID reject a list with a name twice,
/// naming it, and accept the same list with the names made unique.
#[test]
fn duplicate_task_names_are_rejected_by_both_controllers() {
    let model = bundled_model();
    let mut ik = IkConfig::default_for_bundled_model();
    let mut tsid = stride_wbc::TsidConfig::default_for_bundled_model();
    for tasks in [&mut ik.tasks, &mut tsid.tasks] {
        let copy = tasks
            .iter()
            .find(|t| matches!(t, TaskConfig::Com(_)))
            .cloned()
            .expect("a CoM task");
        tasks.push(copy);
    }
    let ik_err = QpIk::new(Arc::clone(&model), ik.clone(), PERIOD).err();
    let tsid_err = stride_wbc::Tsid::new(Arc::clone(&model), tsid.clone(), PERIOD).err();
    for e in [ik_err, tsid_err] {
        let message = e.expect("a duplicate name is an error").to_string();
        assert!(
            message.contains("com") && message.contains("duplicate"),
            "{message}"
        );
    }
    ik.tasks.pop();
    tsid.tasks.pop();
    assert!(QpIk::new(Arc::clone(&model), ik, PERIOD).is_ok());
    assert!(stride_wbc::Tsid::new(model, tsid, PERIOD).is_ok());
}
