//! TSID: equations of motion against stride-model's RNEA, wrench feasibility, torque limits, a standing
//! robot integrated with forward dynamics, cross-solver agreement, infeasibility + fallback, contact
//! ramps.

mod common;

use std::sync::Arc;
use std::time::Duration;

use common::*;
use nalgebra::{DVector, Vector2, Vector3, Vector6};
use rand::Rng;
use stride_model::{ExternalWrench, KinDyn, Model, RobotState, VelocityRepresentation};
use stride_qp::{Backend, QpStatus};
use stride_wbc::{Priority, TaskConfig, Tsid, TsidConfig, TsidOutput, WbcInput, Weight};

const FOOT_X: [f64; 2] = [-0.1, 0.1];
const FOOT_Y: [f64; 2] = [-0.045, 0.045];
const MU: f64 = 0.33;
/// Period of the tests' TSIDs (the simulated step of `simulate`).
const PERIOD: Duration = Duration::from_millis(1);

fn kd_at(model: &Arc<Model>, state: &RobotState) -> KinDyn {
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_representation(VelocityRepresentation::Mixed);
    kd.set_state(state).unwrap();
    kd
}

/// Checks with stride-model's RNEA that `M ν̇ + h − Σ Jᵀ f = [0; τ]` and that every wrench is feasible.
fn check_physics(model: &Arc<Model>, state: &RobotState, out: &TsidOutput, tol: f64, mu: f64) {
    let mut kd = kd_at(model, state);
    let frames = [
        model.frame_id("l_sole").unwrap(),
        model.frame_id("r_sole").unwrap(),
    ];
    let wrenches: Vec<ExternalWrench> = frames
        .iter()
        .zip(out.contact_wrenches.iter())
        .map(|(f, w)| ExternalWrench {
            frame: *f,
            wrench: *w,
        })
        .collect();
    let mut gen = DVector::zeros(model.nv());
    kd.inverse_dynamics(&out.accelerations, &wrenches, &mut gen)
        .unwrap();
    let base = gen.rows(0, 6).amax();
    assert!(base < tol, "base rows of the dynamics violated by {base}");
    let joints = (gen.rows(6, model.dof()) - &out.joint_torques).amax();
    assert!(
        joints < tol,
        "torques differ from the RNEA ones by {joints}"
    );
    for (i, j) in model.joints().iter().enumerate() {
        assert!(
            out.joint_torques[i].abs() <= j.effort_limit + 1e-9,
            "{}: {}",
            j.name,
            out.joint_torques[i]
        );
    }
    for (f, w) in frames.iter().zip(out.contact_wrenches.iter()) {
        let rt = kd.frame_pose(*f).rotation.inverse();
        let force = rt * Vector3::new(w[0], w[1], w[2]);
        let torque = rt * Vector3::new(w[3], w[4], w[5]);
        let fz = force.z;
        assert!(fz >= -1e-9, "negative normal force {fz}");
        // the inscribed 4-facet pyramid: |fx| + |fy| ≤ μ fz
        assert!(
            force.x.abs() + force.y.abs() <= mu * fz + 1e-7,
            "friction: {force:?}"
        );
        if fz > 1e-6 {
            let cop = Vector2::new(-torque.y / fz, torque.x / fz);
            assert!(
                cop.x >= FOOT_X[0] - 1e-7 && cop.x <= FOOT_X[1] + 1e-7,
                "CoP x {}",
                cop.x
            );
            assert!(
                cop.y >= FOOT_Y[0] - 1e-7 && cop.y <= FOOT_Y[1] + 1e-7,
                "CoP y {}",
                cop.y
            );
        } else {
            assert!(w.amax() < 1e-6, "unloaded foot carries {w:?}");
        }
    }
}

fn perturbed_state(model: &Arc<Model>, rng: &mut rand_chacha::ChaCha8Rng) -> RobotState {
    let q = random_posture(model, rng, 0.15, 0.1);
    let mut state = standing_state(model, &q);
    for i in 0..model.dof() {
        state.joint_velocities[i] = rng.random_range(-0.1..0.1);
    }
    state
}

#[test]
fn solutions_satisfy_the_equations_of_motion_cones_cop_and_torque_limits() {
    let model = bundled_model();
    let mut rng = rng(21);
    for trial in 0..12 {
        let (l, r) = [(true, true), (true, false), (false, true)][trial % 3];
        let mut state = perturbed_state(&model, &mut rng);
        if !(l && r) {
            // the stance sole flat on the ground (a tilted single support can exceed the friction cone)
            flatten_on(&model, &mut state, if l { "l_sole" } else { "r_sole" });
        }
        let mut input = references_at(&model, &state);
        input.com_position += Vector3::new(
            rng.random_range(-0.01..0.01),
            rng.random_range(-0.01..0.01),
            0.0,
        );
        input.posture = Some(default_posture(&model));
        input.set_contact("left_foot", l).unwrap();
        input.set_contact("right_foot", r).unwrap();
        if !(l && r) {
            // single support: a LIPM-consistent CoM acceleration, ZMP at the stance sole point nearest
            // to the CoM projection
            let foot = if l { &input.lf() } else { &input.rf() };
            let local = foot
                .pose
                .inverse_transform_point(&nalgebra::Point3::from(input.com_position));
            let zmp = foot.pose.transform_point(&nalgebra::Point3::new(
                local.x.clamp(FOOT_X[0], FOOT_X[1]),
                local.y.clamp(FOOT_Y[0], FOOT_Y[1]),
                0.0,
            ));
            let height = input.com_position.z - zmp.z;
            let omega2 = 9.81 / height;
            input.com_acceleration.x = omega2 * (input.com_position.x - zmp.x);
            input.com_acceleration.y = omega2 * (input.com_position.y - zmp.y);
        }
        // rubber soles (μ = 1): a random single-support state can need more than μ = 0.33
        let mut config = TsidConfig::default_for_bundled_model();
        for t in &mut config.tasks {
            if let TaskConfig::Contact(c) = t {
                c.friction = 1.0;
            }
        }
        let mut tsid = Tsid::new(Arc::clone(&model), config, PERIOD).unwrap();
        let out = tsid.step(&input).unwrap().clone();
        assert_eq!(out.report.status, QpStatus::Solved, "trial {trial}");
        assert!(!out.report.fallback);
        check_physics(&model, &state, &out, 1e-8, 1.0);
        if !l {
            assert_eq!(out.contact_wrenches[0], Vector6::zeros());
        }
        if !r {
            assert_eq!(out.contact_wrenches[1], Vector6::zeros());
        }
        // hard task residuals are tiny; KKT holds
        for res in out.residuals.iter().filter(|r| r.hard) {
            assert!(
                res.residual < 1e-7,
                "trial {trial} {}: {}",
                res.name,
                res.residual
            );
        }
        let kkt = tsid.qp_problem().unwrap().check_kkt();
        assert!(kkt.is_satisfied(1e-6), "{kkt:?}");
    }
}

#[test]
fn standing_still_needs_no_acceleration_and_carries_the_weight() {
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let input = references_at(&model, &state);
    // without torque regularization and with the angular momentum rate fixed (hard, zero) the feasible
    // ν̇ satisfy M_b ν̇ = 0 and J_feet ν̇ = 0, and every ν̇ cost is minimal at ν̇ = 0: the unique optimum
    let mut config = TsidConfig::default_for_bundled_model();
    config
        .tasks
        .retain(|t| !matches!(t, TaskConfig::TorqueRegularization(_)));
    config.tasks.push(TaskConfig::AngularMomentum(
        stride_wbc::AngularMomentumTaskConfig {
            name: "angular_momentum".into(),
            kp: 0.0,
            reference_joints: Vec::new(),
            reference_frames: Vec::new(),
            priority: Priority::Hard,
            weight: None,
        },
    ));
    let mut tsid = Tsid::new(Arc::clone(&model), config, PERIOD).unwrap();
    let out = tsid.step(&input).unwrap();
    assert_eq!(out.report.status, QpStatus::Solved);
    let fz: f64 = out.contact_wrenches.iter().map(|w| w[2]).sum();
    assert!(
        (fz - model.total_mass() * 9.81).abs() < 1e-8,
        "Σ f_z = {fz}"
    );
    assert!(
        out.accelerations.amax() < 1e-9,
        "ν̇ = {}",
        out.accelerations.amax()
    );
    // default: the QP trades a tiny acceleration for lower torques and sole moments
    let mut tsid = Tsid::new(
        Arc::clone(&model),
        TsidConfig::default_for_bundled_model(),
        PERIOD,
    )
    .unwrap();
    let out = tsid.step(&input).unwrap();
    let fz: f64 = out.contact_wrenches.iter().map(|w| w[2]).sum();
    assert!(
        (fz - model.total_mass() * 9.81).abs() < 1e-8,
        "Σ f_z = {fz}"
    );
    assert!(
        out.accelerations.amax() < 1e-3,
        "ν̇ = {}",
        out.accelerations.amax()
    );
}

/// The angular momentum task with `reference_joints`: the contact wrenches' moment about the CoM is
/// `K_p (h* − h)` with `h*` the centroidal angular momentum (stride-model's, not the task's product of the
/// momentum matrix) of the same state with the base not rotating and only the listed joints moving.
#[test]
fn the_angular_momentum_reference_of_listed_joints_is_their_momentum() {
    let model = bundled_model();
    let mut state = standing_state(&model, &default_posture(&model));
    state.base_velocity = Vector6::new(0.05, -0.02, 0.01, 0.2, -0.1, 0.05);
    let mut rng = common::rng(91);
    for v in state.joint_velocities.iter_mut() {
        *v = rng.random_range(-0.5..0.5);
    }
    let legs: Vec<String> = ["l_hip_roll", "l_knee", "r_hip_pitch", "r_ankle_roll"]
        .iter()
        .map(|s| s.to_string())
        .collect();
    let momentum = |s: &RobotState| {
        let mut kd = KinDyn::new(Arc::clone(&model));
        kd.set_representation(VelocityRepresentation::Mixed);
        kd.set_state(s).unwrap();
        (kd.centroidal_momentum().fixed_rows::<3>(3).into_owned(), kd)
    };
    let mut listed_only = state.clone();
    for k in 3..6 {
        listed_only.base_velocity[k] = 0.0;
    }
    for (j, v) in listed_only.joint_velocities.iter_mut().enumerate() {
        if !legs.contains(&model.joints()[j].name) {
            *v = 0.0;
        }
    }
    let (reference, _) = momentum(&listed_only);
    let (h, kd) = momentum(&state);
    let kp = 4.0;
    let mut config = TsidConfig::default_for_bundled_model();
    config.tasks.push(TaskConfig::AngularMomentum(
        stride_wbc::AngularMomentumTaskConfig {
            name: "angular_momentum".into(),
            kp,
            reference_joints: legs.clone(),
            reference_frames: Vec::new(),
            priority: Priority::Hard,
            weight: None,
        },
    ));
    let mut tsid = Tsid::new(Arc::clone(&model), config, PERIOD).unwrap();
    let out = tsid.step(&references_at(&model, &state)).unwrap().clone();
    assert_eq!(out.report.status, QpStatus::Solved);
    let moment = moment_about_com(&model, &kd, &out);
    let expected = (reference - h) * kp;
    assert!(
        (moment - expected).norm() < 1e-6 * (1.0 + expected.norm()),
        "{moment} vs {expected}"
    );
    assert!((reference - h).norm() > 1e-3, "the test needs h* ≠ h");
    // an unknown joint is refused by name
    let mut config = TsidConfig::default_for_bundled_model();
    config.tasks.push(TaskConfig::AngularMomentum(
        stride_wbc::AngularMomentumTaskConfig {
            name: "angular_momentum".into(),
            kp,
            reference_joints: vec!["no_such_joint".into()],
            reference_frames: Vec::new(),
            priority: Priority::Hard,
            weight: None,
        },
    ));
    let err = Tsid::new(Arc::clone(&model), config, PERIOD).err().unwrap();
    assert!(err.to_string().contains("no_such_joint"), "{err}");
}

/// The moment of `out`'s two sole wrenches about the CoM of the state `kd` holds (N·m).
fn moment_about_com(model: &Model, kd: &KinDyn, out: &TsidOutput) -> Vector3<f64> {
    let com = kd.com_position();
    let mut moment = Vector3::zeros();
    for (w, sole) in out.contact_wrenches.iter().zip(["l_sole", "r_sole"]) {
        let p = kd
            .frame_pose(model.frame_id(sole).unwrap())
            .translation
            .vector;
        moment += (p - com).cross(&w.fixed_rows::<3>(0)) + w.fixed_rows::<3>(3);
    }
    moment
}

/// `reference_frames`: the reference is the angular momentum of the motion that moves the listed frames at
/// their references' velocities with the base translating as measured and not rotating: with the soles'
/// references set to their velocities in a state where only the 12 leg joints move (a random planned
/// motion), the rigid TSID's contact moment about the CoM is `K_p (h* − h)` with `h*` stride-model's
/// centroidal momentum of that planned state, to the damped least squares' bias (λ = 1e-3 against leg
/// Jacobians whose smallest singular value is of order 0.1: a relative 1e-4); a reference name the
/// controller does not know is refused by name, and so is the key in the QP-IK.
#[test]
fn the_angular_momentum_reference_of_planned_frames_is_the_momentum_of_the_planned_legs() {
    let model = bundled_model();
    let mut state = standing_state(&model, &default_posture(&model));
    state.base_velocity = Vector6::new(0.05, -0.02, 0.01, 0.2, -0.1, 0.05);
    let mut rng = common::rng(93);
    for v in state.joint_velocities.iter_mut() {
        *v = rng.random_range(-0.5..0.5);
    }
    let mut planned = state.clone();
    for k in 3..6 {
        planned.base_velocity[k] = 0.0;
    }
    for (j, v) in planned.joint_velocities.iter_mut().enumerate() {
        let name = &model.joints()[j].name;
        let leg = [
            "hip_pitch",
            "hip_roll",
            "hip_yaw",
            "knee",
            "ankle_pitch",
            "ankle_roll",
        ]
        .iter()
        .any(|s| *name == format!("l_{s}") || *name == format!("r_{s}"));
        *v = if leg {
            rng.random_range(-0.5..0.5)
        } else {
            0.0
        };
    }
    let kd_of = |s: &RobotState| {
        let mut kd = KinDyn::new(Arc::clone(&model));
        kd.set_representation(VelocityRepresentation::Mixed);
        kd.set_state(s).unwrap();
        kd
    };
    let kd_planned = kd_of(&planned);
    let reference = kd_planned
        .centroidal_momentum()
        .fixed_rows::<3>(3)
        .into_owned();
    let kd = kd_of(&state);
    let h = kd.centroidal_momentum().fixed_rows::<3>(3).into_owned();
    let kp = 4.0;
    let task = |frames: &[(&str, &str)]| {
        TaskConfig::AngularMomentum(stride_wbc::AngularMomentumTaskConfig {
            name: "angular_momentum".into(),
            kp,
            reference_joints: Vec::new(),
            reference_frames: frames
                .iter()
                .map(|(f, r)| stride_wbc::MomentumReferenceFrame {
                    frame: f.to_string(),
                    reference: r.to_string(),
                })
                .collect(),
            priority: Priority::Hard,
            weight: None,
        })
    };
    let mut config = TsidConfig::default_for_bundled_model();
    config
        .tasks
        .push(task(&[("l_sole", "left_foot"), ("r_sole", "right_foot")]));
    let mut tsid = Tsid::new(Arc::clone(&model), config, PERIOD).unwrap();
    let mut input = references_at(&model, &state);
    input.lf_mut().velocity = kd_planned.frame_velocity(model.frame_id("l_sole").unwrap());
    input.rf_mut().velocity = kd_planned.frame_velocity(model.frame_id("r_sole").unwrap());
    let out = tsid.step(&input).unwrap().clone();
    assert_eq!(out.report.status, QpStatus::Solved);
    let moment = moment_about_com(&model, &kd, &out);
    let expected = (reference - h) * kp;
    assert!(
        (moment - expected).norm() < 1e-4 * expected.norm(),
        "{moment} vs {expected}"
    );
    assert!((reference - h).norm() > 1e-3, "the test needs h* ≠ h");
    // an unknown frame is refused by name
    let mut config = TsidConfig::default_for_bundled_model();
    config.tasks.push(task(&[("no_such_frame", "left_foot")]));
    let err = Tsid::new(Arc::clone(&model), config, PERIOD).err().unwrap();
    assert!(err.to_string().contains("no_such_frame"), "{err}");
    let mut ik = stride_wbc::IkConfig::default_for_bundled_model();
    ik.tasks.push(task(&[("l_sole", "left_foot")]));
    let err = stride_wbc::QpIk::new(Arc::clone(&model), ik, PERIOD)
        .err()
        .unwrap();
    assert!(err.to_string().contains("reference_frames"), "{err}");
}

/// Integrates the closed loop TSID → forward dynamics with the planned wrenches as the contact
/// wrenches (rigid contacts held by the contact constraint) with a semi-implicit Euler step.
fn simulate(
    model: &Arc<Model>,
    tsid: &mut Tsid,
    input: &mut WbcInput,
    steps: usize,
    dt: f64,
    mut each: impl FnMut(usize, &TsidOutput, &RobotState, &RobotState),
) {
    let frames = [
        model.frame_id("l_sole").unwrap(),
        model.frame_id("r_sole").unwrap(),
    ];
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_representation(VelocityRepresentation::Mixed);
    let mut acc = DVector::zeros(model.nv());
    for k in 0..steps {
        let out = tsid.step(input).unwrap().clone();
        assert!(out.report.status.is_success(), "step {k}: {:?}", out.report);
        let wrenches = [
            ExternalWrench {
                frame: frames[0],
                wrench: out.contact_wrenches[0],
            },
            ExternalWrench {
                frame: frames[1],
                wrench: out.contact_wrenches[1],
            },
        ];
        let before = input.state.clone();
        kd.set_state(&input.state).unwrap();
        kd.forward_dynamics(&out.joint_torques, &wrenches, &mut acc)
            .unwrap();
        assert!(
            (&acc - &out.accelerations).amax() < 1e-6,
            "forward dynamics disagrees with the TSID"
        );
        let s = &mut input.state;
        s.base_velocity += acc.fixed_rows::<6>(0) * dt;
        for i in 0..model.dof() {
            s.joint_velocities[i] += acc[6 + i] * dt;
        }
        s.integrate(model, VelocityRepresentation::Mixed, dt)
            .unwrap();
        each(k, &out, &before, s);
    }
}

#[test]
fn a_standing_robot_under_tsid_keeps_its_com_still() {
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let mut input = references_at(&model, &state);
    let com0 = input.com_position;
    let feet0 = [input.lf().pose, input.rf().pose];
    let mut tsid = Tsid::new(
        Arc::clone(&model),
        TsidConfig::default_for_bundled_model(),
        PERIOD,
    )
    .unwrap();
    let frames = [
        model.frame_id("l_sole").unwrap(),
        model.frame_id("r_sole").unwrap(),
    ];
    let mut worst_com: f64 = 0.0;
    let mut worst_foot: f64 = 0.0;
    simulate(&model, &mut tsid, &mut input, 2000, 1e-3, |_, _, _, s| {
        let kd = kd_at(&model, s);
        worst_com = worst_com.max((kd.com_position() - com0).norm());
        for (f, p0) in frames.iter().zip(feet0.iter()) {
            worst_foot = worst_foot
                .max((kd.frame_pose(*f).translation.vector - p0.translation.vector).norm());
        }
    });
    assert!(worst_com < 1e-6, "CoM moved by {worst_com} m in 2 s");
    assert!(worst_foot < 1e-6, "a foot moved by {worst_foot} m");
}

#[test]
fn a_com_reference_step_is_tracked_with_the_com_task_dynamics() {
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let mut input = references_at(&model, &state);
    let com0 = input.com_position;
    // the CoM reference steps 2.2 cm away (inside the support polygon)
    input.com_position += Vector3::new(0.02, 0.01, 0.0);
    let config = TsidConfig::default_for_bundled_model();
    // The hard CoM task makes the error obey ë = −K_d ė − K_p e (e(0) = 0.022 m, ė(0) = 0): simulate until
    // its envelope e(0)/√(1−ζ²)·exp(−ζωt) (underdamped) is below 1e-5 m, then expect < 1e-4 m.
    let (kp, kd) = config
        .tasks
        .iter()
        .find_map(|t| match t {
            TaskConfig::Com(c) => Some((c.kp, c.kd)),
            _ => None,
        })
        .unwrap();
    let omega = kp.sqrt();
    let zeta = kd / (2.0 * omega);
    assert!(zeta > 0.0 && zeta < 1.0, "underdamped CoM gains expected");
    let e0 = 0.02_f64.hypot(0.01);
    let horizon = ((e0 / (1.0 - zeta * zeta).sqrt()) / 1e-5).ln() / (zeta * omega);
    let steps = (horizon / 1e-3).ceil() as usize;
    let mut tsid = Tsid::new(Arc::clone(&model), config, PERIOD).unwrap();
    let mut last = f64::INFINITY;
    let target = input.com_position;
    simulate(
        &model,
        &mut tsid,
        &mut input,
        steps,
        1e-3,
        |_, out, before, after| {
            check_physics(&model, before, out, 1e-8, MU);
            last = (kd_at(&model, after).com_position() - target).norm();
        },
    );
    assert!(
        last < 1e-4,
        "CoM error after {horizon:.2} s: {last} (started 0.022 from {com0:?})"
    );
}

/// The CoM task's vertical row has its own gains (`kp_z`, `kd_z`; the walking preset's 100 / 20 against
/// 25 / 5 horizontally): one tick on a standing robot at rest with the reference 1 cm ahead and 1 cm above
/// the CoM asks `Σ f = m (K_p e) − m g` per row with each row's `K_p`; without `kp_z` the vertical row uses
/// `kp`.
#[test]
fn the_com_height_row_uses_its_own_gains() {
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let mut input = references_at(&model, &state);
    let e = Vector3::new(0.01, 0.0, 0.01);
    input.com_position += e;
    let m = model.total_mass();
    let g = -model.gravity().z;
    let force = |config: TsidConfig| -> Vector3<f64> {
        let mut tsid = Tsid::new(Arc::clone(&model), config, PERIOD).unwrap();
        let out = tsid.step(&input).unwrap();
        assert_eq!(out.report.status, QpStatus::Solved);
        out.contact_wrenches
            .iter()
            .map(|w| w.fixed_rows::<3>(0).into_owned())
            .sum()
    };
    let preset = TsidConfig::default_for_bundled_model();
    let com = preset
        .tasks
        .iter()
        .find_map(|t| match t {
            TaskConfig::Com(c) => Some(c.clone()),
            _ => None,
        })
        .unwrap();
    assert_eq!(
        (com.kp, com.kd, com.kp_z, com.kd_z),
        (
            stride_wbc::BUNDLED_TSID_COM_KP,
            stride_wbc::BUNDLED_TSID_COM_KD,
            Some(stride_wbc::BUNDLED_TSID_COM_KP_Z),
            Some(stride_wbc::BUNDLED_TSID_COM_KD_Z)
        )
    );
    assert!(com.kp_z.unwrap() > com.kp);
    let f = force(preset.clone());
    let tol = 1e-6 * m * g;
    assert!((f.x - m * com.kp * e.x).abs() < tol, "Σ f_x = {}", f.x);
    assert!(f.y.abs() < tol, "Σ f_y = {}", f.y);
    let want_z = m * (com.kp_z.unwrap() * e.z + g);
    assert!(
        (f.z - want_z).abs() < tol,
        "Σ f_z = {} (want {want_z})",
        f.z
    );
    // without the vertical gains the vertical row is the horizontal rows' spring
    let mut same = preset;
    for t in &mut same.tasks {
        if let TaskConfig::Com(c) = t {
            c.kp_z = None;
            c.kd_z = None;
        }
    }
    let f = force(same);
    let want_z = m * (com.kp * e.z + g);
    assert!(
        (f.z - want_z).abs() < tol,
        "Σ f_z = {} (want {want_z})",
        f.z
    );
    assert!((f.x - m * com.kp * e.x).abs() < tol, "Σ f_x = {}", f.x);
}

/// The bundled TSID as it was before its pelvis task (chest SO(3) at weight 10 only): the configuration
/// on which the two solvers agree on every output to 1e-6.
fn chest_only_config() -> TsidConfig {
    let mut c = TsidConfig::default_for_bundled_model();
    c.tasks.retain(|t| t.name() != "pelvis");
    for t in &mut c.tasks {
        if let TaskConfig::So3(f) = t {
            f.weight = Some(Weight::Scalar(10.0));
        }
    }
    c
}

/// Largest differences between the active-set and the clarabel solutions of `config` over six ticks
/// (perturbed states, single and double support): (accelerations, total foot wrench, every output).
fn active_set_vs_clarabel(config: &TsidConfig) -> (f64, f64, f64) {
    let model = bundled_model();
    let mut rng = rng(5);
    let mut worst = (0.0_f64, 0.0_f64, 0.0_f64);
    for trial in 0..6 {
        let state = perturbed_state(&model, &mut rng);
        let mut input = references_at(&model, &state);
        input.com_position.x += 0.01;
        input.desired_zmp = Some(Vector2::new(input.com_position.x, input.com_position.y));
        input.set_contact("right_foot", trial % 2 == 0).unwrap();
        let a = config.clone();
        let mut c = a.clone();
        c.qp.backend = Backend::Clarabel;
        // the reference at its tightest tolerance (at the default 1e-10 clarabel's own error in the
        // weakly penalized wrench-distribution directions reaches 1e-5 N; its KKT residual says so)
        c.qp.clarabel.tolerance = 1e-12;
        let mut ta = Tsid::new(Arc::clone(&model), a, PERIOD).unwrap();
        let mut tc = Tsid::new(Arc::clone(&model), c, PERIOD).unwrap();
        let oa = ta.step(&input).unwrap().clone();
        let oc = tc.step(&input).unwrap().clone();
        assert!(oa.report.status.is_success() && oc.report.status.is_success());
        let acc = (&oa.accelerations - &oc.accelerations).amax();
        let total = ((oa.contact_wrenches[0] + oa.contact_wrenches[1])
            - (oc.contact_wrenches[0] + oc.contact_wrenches[1]))
            .amax();
        let all = acc
            .max((&oa.joint_torques - &oc.joint_torques).amax())
            .max((oa.contact_wrenches[0] - oc.contact_wrenches[0]).amax())
            .max((oa.contact_wrenches[1] - oc.contact_wrenches[1]).amax());
        worst = (worst.0.max(acc), worst.1.max(total), worst.2.max(all));
    }
    worst
}

#[test]
fn clarabel_and_active_set_agree_on_tsid_ticks() {
    let (_, _, all) = active_set_vs_clarabel(&chest_only_config());
    assert!(all < 1e-6, "active set vs clarabel differ by {all}");
    // With the pelvis task (weight 50) the split of the load between the two feet in double support, which
    // only the 1e-4 wrench regularization penalizes, is relatively 5x weaker: clarabel at 1e-12 leaves it
    // 4e-6 N from the active set's (and the joint torques 3e-6 N m, through the feet's Jacobians). What
    // the task set determines agrees as tightly: the accelerations and the total wrench on the feet.
    let (acc, total, _) = active_set_vs_clarabel(&TsidConfig::default_for_bundled_model());
    assert!(acc < 1e-8, "accelerations differ by {acc}");
    assert!(total < 1e-6, "total foot wrenches differ by {total}");
}

fn hard_zmp_config() -> TsidConfig {
    let mut c = TsidConfig::default_for_bundled_model();
    for t in &mut c.tasks {
        if let TaskConfig::Zmp(z) = t {
            z.priority = Priority::Hard;
            z.weight = None;
        }
    }
    c
}

#[test]
fn desired_zmp_outside_the_support_polygon_is_infeasible_and_falls_back() {
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let mut input = references_at(&model, &state);
    // a hard ZMP 0.5 m in front of the feet: no wrench in the cones produces it
    input.desired_zmp = Some(Vector2::new(0.5, 0.0));
    let mut tsid = Tsid::new(Arc::clone(&model), hard_zmp_config(), PERIOD).unwrap();
    let out = tsid.step(&input).unwrap().clone();
    assert_eq!(out.report.status, QpStatus::Infeasible);
    assert!(out.report.fallback && !out.report.held);
    assert_eq!(out.report.relaxed_status, Some(QpStatus::Solved));
    // documented fallback: hard equalities relaxed, inequalities (cones, CoP, torque limits) kept hard
    let kd = kd_at(&model, &state);
    for (frame, w) in ["l_sole", "r_sole"].iter().zip(out.contact_wrenches.iter()) {
        let rt = kd
            .frame_pose(model.frame_id(frame).unwrap())
            .rotation
            .inverse();
        let f = rt * Vector3::new(w[0], w[1], w[2]);
        let t = rt * Vector3::new(w[3], w[4], w[5]);
        assert!(f.z >= -1e-9 && f.x.abs() + f.y.abs() <= MU * f.z + 1e-7);
        if f.z > 1e-6 {
            assert!(-t.y / f.z <= FOOT_X[1] + 1e-7);
        }
    }
    let zmp = out.residuals.iter().find(|r| r.name == "zmp").unwrap();
    assert!(
        zmp.hard && zmp.residual > 1.0,
        "the violated hard ZMP shows in its residual: {zmp:?}"
    );
    assert!(out.joint_torques.iter().all(|v| v.is_finite()));

    // same problem with the ZMP inside the feet: feasible, nominal path
    input.desired_zmp = Some(Vector2::new(0.0, 0.0));
    let out = tsid.step(&input).unwrap();
    assert_eq!(out.report.status, QpStatus::Solved);
    assert!(!out.report.fallback);
}

#[test]
fn com_target_far_outside_the_support_polygon_with_hard_wrench_constraints_is_infeasible() {
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let mut input = references_at(&model, &state);
    // K_p (x_ref − x) = K_p · 1 m = 25 m/s² forward (default K_p): needs |Σ f_x| = m·25 ≫ μ Σ f_z = m·3.2
    input.com_position.x += 1.0;
    let mut config = TsidConfig::default_for_bundled_model();
    config.qp.fallback = false;
    let mut tsid = Tsid::new(Arc::clone(&model), config, PERIOD).unwrap();
    let first = tsid
        .step(&references_at(&model, &state))
        .unwrap()
        .joint_torques
        .clone();
    let out = tsid.step(&input).unwrap();
    assert_eq!(out.report.status, QpStatus::Infeasible);
    assert!(
        out.report.held,
        "no fallback configured: the last valid torques are held"
    );
    assert_eq!(out.joint_torques, first);
}

/// Largest per-tick torque change while the right foot lifts off at t = 0.
fn lift_off_torque_jump(ramp_time: f64) -> (f64, Vec<f64>) {
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let mut input = references_at(&model, &state);
    let mut config = TsidConfig::default_for_bundled_model();
    for t in &mut config.tasks {
        if let TaskConfig::Contact(c) = t {
            c.ramp_time = ramp_time;
        }
    }
    let mut tsid = Tsid::new(Arc::clone(&model), config, PERIOD).unwrap();
    let mut previous = tsid.step(&input).unwrap().joint_torques.clone();
    input.set_contact("right_foot", false).unwrap();
    let mut worst: f64 = 0.0;
    let mut right_fz = Vec::new();
    for _ in 0..80 {
        let out = tsid.step(&input).unwrap();
        assert!(out.report.status.is_success());
        worst = worst.max((&out.joint_torques - &previous).amax());
        previous.copy_from(&out.joint_torques);
        right_fz.push(out.contact_wrenches[1][2]);
    }
    (worst, right_fz)
}

#[test]
fn lift_off_ramps_the_wrench_instead_of_jumping() {
    let (jump_ramped, fz) = lift_off_torque_jump(0.05);
    let (jump_instant, fz_instant) = lift_off_torque_jump(0.0);
    // instant: the foot is unloaded at the first tick
    assert_eq!(fz_instant[0], 0.0);
    // ramped: the normal force decreases to zero over 50 ticks, never increasing, then stays zero
    assert!(fz[0] > 0.0);
    for k in 1..fz.len() {
        assert!(
            fz[k] <= fz[k - 1] + 1e-9,
            "tick {k}: {} > {}",
            fz[k],
            fz[k - 1]
        );
    }
    assert!(fz[49..].iter().all(|f| *f == 0.0), "{:?}", &fz[45..]);
    assert!(
        jump_ramped < 0.2 * jump_instant,
        "ramped torque jump {jump_ramped} vs instant {jump_instant}"
    );
}

#[test]
fn config_parses_from_toml_and_requires_the_dynamics() {
    let default = TsidConfig::default_for_bundled_model();
    let text = toml::to_string(&default).unwrap();
    let back: TsidConfig = toml::from_str(&text).unwrap();
    assert_eq!(back, default);
    let model = bundled_model();
    let mut no_dynamics = default.clone();
    no_dynamics
        .tasks
        .retain(|t| !matches!(t, TaskConfig::FloatingBaseDynamics(_)));
    let err = Tsid::new(Arc::clone(&model), no_dynamics, PERIOD)
        .err()
        .unwrap();
    assert!(err.to_string().contains("floating_base_dynamics"), "{err}");
    let bad = text.replace("friction = 0.33", "friction = 0.33\nrestitution = 0.1");
    assert!(toml::from_str::<TsidConfig>(&bad).is_err());
}

#[test]
fn null_space_elimination_gives_the_full_problem_solution() {
    let model = bundled_model();
    let mut rng = rng(8);
    for trial in 0..6 {
        let state = perturbed_state(&model, &mut rng);
        let mut input = references_at(&model, &state);
        input.com_position.y += 0.005;
        input.desired_zmp = Some(Vector2::new(input.com_position.x, input.com_position.y));
        input.set_contact("left_foot", trial % 3 != 1).unwrap();
        let mut reduced = Tsid::new(
            Arc::clone(&model),
            TsidConfig::default_for_bundled_model(),
            PERIOD,
        )
        .unwrap();
        let mut config = TsidConfig::default_for_bundled_model();
        config.eliminate_equalities = false;
        let mut full = Tsid::new(Arc::clone(&model), config, PERIOD).unwrap();
        let a = reduced.step(&input).unwrap().clone();
        let b = full.step(&input).unwrap().clone();
        assert_eq!(a.report.status, QpStatus::Solved);
        assert_eq!(b.report.status, QpStatus::Solved);
        // the reduced problem has only the null-space coordinates as variables
        assert!(reduced.qp_problem().unwrap().n() < full.qp_problem().unwrap().n());
        let d = (&a.joint_torques - &b.joint_torques)
            .amax()
            .max((&a.accelerations - &b.accelerations).amax())
            .max((a.contact_wrenches[0] - b.contact_wrenches[0]).amax());
        assert!(d < 1e-6, "trial {trial}: eliminated vs full differ by {d}");
    }
}

/// The null-space path (factorization, compact-WY basis, projections with the shared torque rows, stacked
/// Hessian) against the straightforward reference, the full problem with its hard rows solved by the same
/// backend, over consecutive ticks in double and single support: the QP is strictly convex, so the
/// solutions and the reported residuals agree to the solver's tolerance.
#[test]
fn null_space_path_matches_the_full_problem_to_solver_tolerance() {
    let model = bundled_model();
    let mut rng = rng(31);
    let mut worst: f64 = 0.0;
    for trial in 0..6 {
        let state = perturbed_state(&model, &mut rng);
        let mut input = references_at(&model, &state);
        input.com_position.y += 0.005;
        input.desired_zmp = Some(Vector2::new(input.com_position.x, input.com_position.y));
        let config = TsidConfig::default_for_bundled_model();
        let mut full_config = config.clone();
        full_config.eliminate_equalities = false;
        let mut reduced = Tsid::new(Arc::clone(&model), config, PERIOD).unwrap();
        let mut full = Tsid::new(Arc::clone(&model), full_config, PERIOD).unwrap();
        for tick in 0..4 {
            // lift the left foot from the second tick of odd trials (load ramp, then single support)
            input
                .set_contact("left_foot", trial % 2 == 0 || tick == 0)
                .unwrap();
            let a = reduced.step(&input).unwrap().clone();
            let b = full.step(&input).unwrap().clone();
            assert_eq!(a.report.status, QpStatus::Solved);
            let scale = 1.0 + b.joint_torques.amax().max(b.accelerations.amax());
            let d = (&a.joint_torques - &b.joint_torques)
                .amax()
                .max((&a.accelerations - &b.accelerations).amax())
                .max((a.contact_wrenches[0] - b.contact_wrenches[0]).amax())
                .max((a.contact_wrenches[1] - b.contact_wrenches[1]).amax())
                / scale;
            worst = worst.max(d);
            assert!(
                d < 1e-9,
                "trial {trial}, tick {tick}: eliminated vs full differ by {d}"
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
fn soft_weights_change_at_run_time() {
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let mut input = references_at(&model, &state);
    input.com_position.x += 0.01;
    let mut tsid = Tsid::new(
        Arc::clone(&model),
        TsidConfig::default_for_bundled_model(),
        PERIOD,
    )
    .unwrap();
    tsid.step(&input).unwrap();
    tsid.set_task_weight("torque_regularization", &[1e-2])
        .unwrap();
    tsid.set_task_weight(
        "wrench_regularization",
        &[1e-3, 1e-3, 1e-5, 1e-2, 1e-2, 1e-2],
    )
    .unwrap();
    let changed = tsid.step(&input).unwrap().joint_torques.clone();
    let mut config = TsidConfig::default_for_bundled_model();
    for t in &mut config.tasks {
        match t {
            TaskConfig::TorqueRegularization(c) => c.weight = stride_wbc::Weight::Scalar(1e-2),
            TaskConfig::WrenchRegularization(c) => {
                c.weight = stride_wbc::Weight::PerRow(vec![1e-3, 1e-3, 1e-5, 1e-2, 1e-2, 1e-2])
            }
            _ => {}
        }
    }
    let mut reference = Tsid::new(Arc::clone(&model), config, PERIOD).unwrap();
    reference.step(&input).unwrap();
    let expected = reference.step(&input).unwrap().joint_torques.clone();
    assert!(
        (&changed - &expected).amax() < 1e-8,
        "{}",
        (&changed - &expected).amax()
    );
    assert!(tsid.set_task_weight("com", &[1.0]).is_err(), "hard");
    assert!(
        tsid.set_task_weight("joint_torque_limits", &[1.0]).is_err(),
        "constraint"
    );
}

fn min_jerk(t: f64, d: f64) -> (f64, f64, f64) {
    let x = (t / d).clamp(0.0, 1.0);
    let inside = t > 0.0 && t < d;
    let s = x * x * x * (10.0 - 15.0 * x + 6.0 * x * x);
    let ds = if inside {
        30.0 * x * x * (1.0 - x) * (1.0 - x) / d
    } else {
        0.0
    };
    let dds = if inside {
        60.0 * x * (1.0 - x) * (1.0 - 2.0 * x) / (d * d)
    } else {
        0.0
    };
    (s, ds, dds)
}

#[test]
fn a_step_under_tsid_with_forward_dynamics_lands_the_foot_and_tracks_the_com() {
    // CoM over the left foot (1 s), right foot swing 8 cm forward with a 3 cm apex (0.8 s, contact
    // unloaded by the ramp), touch-down and CoM to the middle (1 s); integrated with ABA and the planned
    // wrenches as rigid contact wrenches
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let mut input = references_at(&model, &state);
    let com0 = input.com_position;
    let left = input.lf().pose.translation.vector;
    let right0 = input.rf().pose.translation.vector;
    let (shift, swing, settle) = (1.0, 0.8, 1.0);
    let dt = 1e-3;
    let over_left = Vector3::new(left.x, 0.85 * left.y, com0.z) - com0;
    let landing = right0 + Vector3::new(0.08, 0.0, 0.0);
    let middle = Vector3::new(0.5 * (left.x + landing.x), 0.0, com0.z) - (com0 + over_left);
    // contact stabilization (Baumgarte): the Euler integration of this test drifts the stance foot by
    // O(dt) per tick once the robot moves (3.5e-5 m over the step without it)
    let mut config = TsidConfig::default_for_bundled_model();
    for task in &mut config.tasks {
        if let TaskConfig::Contact(c) = task {
            c.kp = 400.0;
            c.kd = 40.0;
        }
    }
    let mut tsid = Tsid::new(Arc::clone(&model), config, PERIOD).unwrap();
    let mut worst_com: f64 = 0.0;
    let mut t = 0.0;
    let steps = ((shift + swing + settle) / dt) as usize;
    let frames = [
        model.frame_id("l_sole").unwrap(),
        model.frame_id("r_sole").unwrap(),
    ];
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_representation(VelocityRepresentation::Mixed);
    let mut acc = DVector::zeros(model.nv());
    for _ in 0..steps {
        let (s1, ds1, dds1) = min_jerk(t, shift);
        let (s3, ds3, dds3) = min_jerk(t - shift - swing, settle);
        input.com_position = com0 + over_left * s1 + middle * s3;
        input.com_velocity = over_left * ds1 + middle * ds3;
        input.com_acceleration = over_left * dds1 + middle * dds3;
        let (s2, ds2, dds2) = min_jerk(t - shift, swing);
        let pi = std::f64::consts::PI;
        let (a, da, dda) = (
            (pi * s2).sin(),
            pi * (pi * s2).cos() * ds2,
            -pi * pi * (pi * s2).sin() * ds2 * ds2 + pi * (pi * s2).cos() * dds2,
        );
        input.rf_mut().pose.translation.vector =
            right0 + (landing - right0) * s2 + Vector3::new(0.0, 0.0, 0.03 * a);
        let v = (landing - right0) * ds2 + Vector3::new(0.0, 0.0, 0.03 * da);
        let acc_ref = (landing - right0) * dds2 + Vector3::new(0.0, 0.0, 0.03 * dda);
        input.rf_mut().velocity = Vector6::new(v.x, v.y, v.z, 0.0, 0.0, 0.0);
        input.rf_mut().acceleration = Vector6::new(acc_ref.x, acc_ref.y, acc_ref.z, 0.0, 0.0, 0.0);
        input
            .set_contact("right_foot", !(t >= shift && t < shift + swing))
            .unwrap();

        let out = tsid.step(&input).unwrap().clone();
        assert_eq!(
            out.report.status,
            QpStatus::Solved,
            "t = {t}: {:?}",
            out.report
        );
        check_physics(&model, &input.state, &out, 1e-8, MU);
        let wrenches = [
            ExternalWrench {
                frame: frames[0],
                wrench: out.contact_wrenches[0],
            },
            ExternalWrench {
                frame: frames[1],
                wrench: out.contact_wrenches[1],
            },
        ];
        kd.set_state(&input.state).unwrap();
        kd.forward_dynamics(&out.joint_torques, &wrenches, &mut acc)
            .unwrap();
        let s = &mut input.state;
        s.base_velocity += acc.fixed_rows::<6>(0) * dt;
        for i in 0..model.dof() {
            s.joint_velocities[i] += acc[6 + i] * dt;
        }
        s.integrate(&model, VelocityRepresentation::Mixed, dt)
            .unwrap();
        t += dt;
        let kd_now = kd_at(&model, s);
        worst_com = worst_com.max((kd_now.com_position() - input.com_position).norm());
    }
    let kd_end = kd_at(&model, &input.state);
    let r = kd_end.frame_pose(frames[1]).translation.vector;
    let l = kd_end.frame_pose(frames[0]).translation.vector;
    assert!(
        (r - landing).norm() < 1e-3,
        "right foot landed {} m from the target",
        (r - landing).norm()
    );
    assert!(
        (l - left).norm() < 1e-6,
        "the stance foot moved by {}",
        (l - left).norm()
    );
    assert!(worst_com < 5e-3, "CoM tracking error {worst_com}");
}

#[test]
fn default_contacts_keep_the_cop_inside_the_compliance_margin() {
    // A ZMP pulled strongly towards the toes (soft task, large weight) ends on the default CoP bound
    // (stride_wbc::BUNDLED_COP_X), not on the sole edge: the margin a compliant floor needs is active.
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let mut input = references_at(&model, &state);
    let kd = kd_at(&model, &state);
    let frames = ["l_sole", "r_sole"].map(|f| model.frame_id(f).unwrap());
    let mid = 0.5
        * (kd.frame_pose(frames[0]).translation.vector
            + kd.frame_pose(frames[1]).translation.vector);
    input.desired_zmp = Some(Vector2::new(mid.x + 0.095, mid.y));
    let mut tsid = Tsid::new(
        Arc::clone(&model),
        TsidConfig::default_for_bundled_model(),
        PERIOD,
    )
    .unwrap();
    tsid.set_task_weight("zmp", &[1e3]).unwrap();
    let out = tsid.step(&input).unwrap().clone();
    assert_eq!(out.report.status, QpStatus::Solved);
    check_physics(&model, &state, &out, 1e-8, MU);
    for (f, w) in frames.iter().zip(out.contact_wrenches.iter()) {
        let rt = kd.frame_pose(*f).rotation.inverse();
        let force = rt * Vector3::new(w[0], w[1], w[2]);
        let torque = rt * Vector3::new(w[3], w[4], w[5]);
        assert!(force.z > 50.0, "both feet loaded: {force:?}");
        let cop_x = -torque.y / force.z;
        assert!(
            (cop_x - stride_wbc::BUNDLED_COP_X[1]).abs() < 1e-6,
            "CoP x {cop_x} should sit on the bound {}",
            stride_wbc::BUNDLED_COP_X[1]
        );
        let cop_y = torque.x / force.z;
        assert!(cop_y.abs() <= stride_wbc::BUNDLED_COP_Y[1] + 1e-7);
    }
}

#[test]
fn a_weight_on_a_hard_task_is_a_configuration_error_naming_the_task() {
    let model = bundled_model();
    let mut config = TsidConfig::default_for_bundled_model();
    for t in &mut config.tasks {
        if let TaskConfig::Zmp(z) = t {
            z.priority = Priority::Hard;
        }
    }
    // the default zmp task is soft with a weight: made hard, its weight is an error naming it
    let err = Tsid::new(Arc::clone(&model), config.clone(), PERIOD)
        .err()
        .unwrap();
    assert!(
        matches!(&err, stride_wbc::WbcError::InvalidConfig { task, key: "weight", .. } if task == "zmp"),
        "{err}"
    );
    for t in &mut config.tasks {
        if let TaskConfig::Zmp(z) = t {
            z.weight = None;
        }
    }
    Tsid::new(Arc::clone(&model), config, PERIOD).unwrap();
    assert!(Tsid::new(
        Arc::clone(&model),
        TsidConfig::default_for_bundled_model(),
        Duration::ZERO
    )
    .is_err());
}

/// What [`pushed_in_the_simulator`] saw: whether the robot fell, the largest and the final CoM
/// displacement from the start (m), and the TSID ticks that held their last command.
struct PushOutcome {
    fallen: bool,
    worst: f64,
    last: f64,
    held: usize,
}

/// Stands the bundled robot in stride-sim (torque mode, compliant ground, 2 kHz) under the default TSID
/// running at the simulator's rate, references holding the initial stance, and pushes its chest forward
/// with `push` N for 0.1 s at t = 0.2 s, for `duration` s. `feedback = false` holds the first tick's
/// torques (the TSID never sees the push).
fn pushed_in_the_simulator(push: f64, feedback: bool, duration: f64) -> PushOutcome {
    use stride_sim::{
        ActuationConfig, ActuationMode, PushConfig, SensorConfig, SimConfig, SimInput, SimRobot,
    };
    let model = bundled_model();
    // The TSID on the plant's exact state with ideal actuators (no friction, torque lag or command delay):
    // the test is about the controller, the realistic plant is the runner's business.
    let mut config = SimConfig {
        actuation: ActuationConfig::ideal(),
        sensors: SensorConfig::ideal(),
        ..SimConfig::default()
    };
    config.actuation.default.mode = ActuationMode::Torque;
    let mut sim = SimRobot::new(Arc::clone(&model), config, Duration::from_micros(500)).unwrap();
    let state = sim
        .set_standing_on_ground(&default_posture(&model))
        .unwrap();
    sim.add_push(&PushConfig {
        frame: "chest".into(),
        start: 0.2,
        duration: 0.1,
        wrench: [push, 0.0, 0.0, 0.0, 0.0, 0.0],
    })
    .unwrap();
    let mut input = references_at(&model, &state);
    let com0 = input.com_position;
    let period = Duration::from_secs_f64(sim.period());
    let mut tsid = Tsid::new(
        Arc::clone(&model),
        TsidConfig::default_for_bundled_model(),
        period,
    )
    .unwrap();
    let mut command = SimInput::zeros(model.dof());
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_representation(VelocityRepresentation::Mixed);
    let mut outcome = PushOutcome {
        fallen: false,
        worst: 0.0,
        last: 0.0,
        held: 0,
    };
    for k in 0..(duration / sim.period()).round() as usize {
        input.state.clone_from(sim.state());
        if feedback || k == 0 {
            let out = tsid.step(&input).unwrap();
            outcome.held += usize::from(out.report.held);
            command.joint_torques.copy_from(&out.joint_torques);
        }
        sim.step(&command).unwrap();
        kd.set_state(sim.state()).unwrap();
        outcome.last = (kd.com_position() - com0).norm();
        outcome.worst = outcome.worst.max(outcome.last);
        if sim.output().fallen {
            outcome.fallen = true;
            break;
        }
    }
    outcome
}

#[test]
fn a_pushed_robot_in_the_simulator_stays_up() {
    // Closed loop TSID ↔ stride-sim, measured: the 40 N push moves the CoM by 12.8 mm, it is back within
    // 0.9 mm 1.2 s after the push; unpushed, the CoM moves by 4 µm; the same push with the torques held
    // open-loop makes the robot fall.
    let pushed = pushed_in_the_simulator(PUSH, true, 1.5);
    assert!(!pushed.fallen, "the TSID let the pushed robot fall");
    assert_eq!(pushed.held, 0, "every TSID tick solved");
    assert!(
        pushed.worst > 5e-3,
        "the push is seen: CoM moved {} m",
        pushed.worst
    );
    assert!(
        pushed.last < 2e-3,
        "the CoM came back: {} m off at the end",
        pushed.last
    );
    let quiet = pushed_in_the_simulator(0.0, true, 1.5);
    assert!(
        !quiet.fallen && quiet.worst < 1e-4,
        "unpushed: CoM moved {} m",
        quiet.worst
    );
    let open_loop = pushed_in_the_simulator(PUSH, false, 1.5);
    assert!(
        open_loop.fallen,
        "without feedback the same push should topple the robot (CoM moved {} m)",
        open_loop.worst
    );
}

/// Stands the bundled robot in stride-sim under `config` at the runner's 500 Hz on the plant's exact state,
/// with stride-sim's default actuators in torque mode (0.1 N·m Coulomb friction per joint, a 30 Hz torque
/// lag starting from zero, a 2-step command delay), references holding the initial stance, for `duration`
/// s; returns the CoM height error (reference − CoM, m) at every simulator step.
fn com_height_standing_on_default_actuators(config: TsidConfig, duration: f64) -> Vec<f64> {
    use stride_sim::{ActuationMode, SensorConfig, SimConfig, SimInput, SimRobot};
    let model = bundled_model();
    let mut sim_config = SimConfig {
        sensors: SensorConfig::ideal(),
        ..SimConfig::default()
    };
    sim_config.actuation.default.mode = ActuationMode::Torque;
    let mut sim =
        SimRobot::new(Arc::clone(&model), sim_config, Duration::from_micros(500)).unwrap();
    let state = sim
        .set_standing_on_ground(&default_posture(&model))
        .unwrap();
    let mut input = references_at(&model, &state);
    let reference = input.com_position.z;
    let mut tsid = Tsid::new(Arc::clone(&model), config, Duration::from_millis(2)).unwrap();
    let mut command = SimInput::zeros(model.dof());
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_representation(VelocityRepresentation::Mixed);
    let mut errors = Vec::new();
    for k in 0..(duration / sim.period()).round() as usize {
        if k % 4 == 0 {
            input.state.clone_from(sim.state());
            let out = tsid.step(&input).unwrap();
            assert!(!out.report.held, "every TSID tick solved");
            command.joint_torques.copy_from(&out.joint_torques);
        }
        sim.step(&command).unwrap();
        assert!(!sim.output().fallen);
        kd.set_state(sim.state()).unwrap();
        errors.push(reference - kd.com_position().z);
    }
    errors
}

/// The CoM height on stride-sim's default actuators, both sides (docs/wbc.md, "The CoM height"): with the
/// CoM task's horizontal gains on the vertical row (K_p 25, K_d 5: a vertical spring of `m K_p` ≈ 820 N/m)
/// the torque lag's start from zero drops the standing robot's CoM by millimetres and the joints' Coulomb
/// friction holds it there; the preset's vertical gains (K_p 100, K_d 20) recover it. Measured: single gain
/// 2.9 mm at worst, 2.9 mm RMS over the last 0.5 s of 1.5 s; vertical gains 1.3 mm and 1.1 mm.
#[test]
fn the_com_height_recovers_from_the_actuators_start_with_the_vertical_gains() {
    let rms = |e: &[f64]| (e.iter().map(|x| x * x).sum::<f64>() / e.len() as f64).sqrt();
    let preset = TsidConfig::default_for_bundled_model();
    let mut single = preset.clone();
    for t in &mut single.tasks {
        if let TaskConfig::Com(c) = t {
            c.kp_z = None;
            c.kd_z = None;
        }
    }
    let stiff = com_height_standing_on_default_actuators(preset, 1.5);
    let soft = com_height_standing_on_default_actuators(single, 1.5);
    let (stiff_tail, soft_tail) = (&stiff[2000..], &soft[2000..]);
    let stiff_worst = stiff.iter().fold(0.0_f64, |m, e| m.max(e.abs()));
    let soft_worst = soft.iter().fold(0.0_f64, |m, e| m.max(e.abs()));
    let report = format!(
        "vertical gains: worst {stiff_worst} m, last 0.5 s RMS {} m; single gain: worst {soft_worst} m, last \
         0.5 s RMS {} m",
        rms(stiff_tail),
        rms(soft_tail)
    );
    assert!(stiff_worst < 2e-3 && rms(stiff_tail) < 1.5e-3, "{report}");
    assert!(rms(soft_tail) > 2.5e-3, "{report}");
    assert!(rms(soft_tail) > 2.0 * rms(stiff_tail), "{report}");
}

/// The push of [`a_pushed_robot_in_the_simulator_stays_up`] (N, forward, on the chest, for 0.1 s).
const PUSH: f64 = 40.0;
