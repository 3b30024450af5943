//! TSID-Compliant [Romualdi 2022, §8.2]: the QP's rows against their definitions (the contact dynamics
//! against central differences of Lemma 1 along the chosen motion, the base dynamics and torques against
//! stride-model's RNEA with the measured wrenches, the momentum task, the one-step-ahead feasibility),
//! the KKT conditions of its solution, and the bundled humanoid standing on a soft ground of Table 8.1 in
//! stride-sim, where the rigid TSID falls.

mod common;

use std::sync::Arc;
use std::time::Duration;

use common::soft::{GROUND, SOLE};
use common::*;
use nalgebra::{DVector, Isometry3, Translation3, UnitQuaternion, Vector2, Vector3, Vector6};
use rand::Rng;
use stride_model::{ExternalWrench, KinDyn, Model, RobotState, VelocityRepresentation};
use stride_wbc::GroundParameters;
use stride_wbc::{
    walking, AngularMomentumTaskConfig, ContactModel, Priority, SoleState, TaskConfig, Tsid,
    TsidConfig, WbcInput, WrenchSource,
};

/// The TSID period of these tests (the runner's 500 Hz).
const PERIOD: Duration = Duration::from_millis(2);

fn compliant_config() -> TsidConfig {
    let mut config = TsidConfig::default_for_bundled_model();
    config.contact_model = ContactModel::Compliant;
    // the angular rows of the centroidal momentum task (eq. 8.2.2), hard like the CoM's
    config
        .tasks
        .push(TaskConfig::AngularMomentum(AngularMomentumTaskConfig {
            name: "angular_momentum".into(),
            kp: 10.0,
            reference_joints: Vec::new(),
            reference_frames: Vec::new(),
            priority: Priority::Hard,
            weight: None,
        }));
    config.compliant.ground_stiffness = GROUND.stiffness;
    config.compliant.ground_damping = GROUND.damping;
    config
}

fn kd_at(model: &Arc<Model>, state: &RobotState) -> KinDyn {
    let mut kd = KinDyn::new(Arc::clone(model));
    kd.set_representation(VelocityRepresentation::Mixed);
    kd.set_state(state).unwrap();
    kd
}

const SOLES: [&str; 2] = ["l_sole", "r_sole"];

/// The state `ε` s later under constant acceleration `a` (mixed: world-frame base twist), to second order.
fn advanced(state: &RobotState, a: &DVector<f64>, eps: f64) -> RobotState {
    let mut s = state.clone();
    let v = &state.base_velocity;
    let lin =
        Vector3::new(v[0], v[1], v[2]) * eps + Vector3::new(a[0], a[1], a[2]) * (0.5 * eps * eps);
    let ang =
        Vector3::new(v[3], v[4], v[5]) * eps + Vector3::new(a[3], a[4], a[5]) * (0.5 * eps * eps);
    let p = state.base_pose.translation.vector + lin;
    let r = UnitQuaternion::from_scaled_axis(ang) * state.base_pose.rotation;
    s.base_pose = Isometry3::from_parts(Translation3::from(p), r);
    for k in 0..6 {
        s.base_velocity[k] = v[k] + eps * a[k];
    }
    for i in 0..state.joint_positions.len() {
        s.joint_positions[i] =
            state.joint_positions[i] + eps * state.joint_velocities[i] + 0.5 * eps * eps * a[6 + i];
        s.joint_velocities[i] = state.joint_velocities[i] + eps * a[6 + i];
    }
    s
}

/// Lemma 1's wrench of sole `frame` at `state` with the rest pose `rest`.
fn lemma1(
    model: &Arc<Model>,
    state: &RobotState,
    frame: &str,
    rest: &Isometry3<f64>,
) -> Vector6<f64> {
    let kd = kd_at(model, state);
    let id = model.frame_id(frame).unwrap();
    let pose = kd.frame_pose(id);
    let v = kd.frame_velocity(id);
    let sole = SoleState {
        position: pose.translation.vector,
        rotation: pose.rotation.to_rotation_matrix(),
        linear_velocity: v.fixed_rows::<3>(0).into_owned(),
        angular_velocity: v.fixed_rows::<3>(3).into_owned(),
        rest_position: rest.translation.vector,
        rest_rotation: rest.rotation.to_rotation_matrix(),
    };
    SOLE.wrench(&sole, &GROUND)
}

/// A double-support state on the soft ground: the default posture perturbed, soles sunk, everything moving.
fn moving_stance(
    model: &Arc<Model>,
    rng: &mut rand_chacha::ChaCha8Rng,
) -> (RobotState, [Isometry3<f64>; 2]) {
    let q = random_posture(model, rng, 0.05, 0.1);
    let mut state = standing_state(model, &q);
    for k in 0..6 {
        state.base_velocity[k] = rng.random_range(-0.05..0.05);
    }
    for i in 0..model.dof() {
        state.joint_velocities[i] = rng.random_range(-0.1..0.1);
    }
    // rest poses 8 mm above the soles: the soles carry about their share of the weight
    let kd = kd_at(model, &state);
    let rest = SOLES.map(|f| {
        let mut p = kd.frame_pose(model.frame_id(f).unwrap());
        p.translation.vector.z += 0.008;
        p
    });
    (state, rest)
}

/// The input holding the robot where it is, with measured wrenches and a CoM reference 1 cm ahead.
fn input_with_wrenches(
    model: &Arc<Model>,
    tsid: &Tsid,
    state: &RobotState,
    wrenches: &[Vector6<f64>; 2],
) -> WbcInput {
    let reference = references_at(model, state);
    let mut input = tsid.input(state);
    input.com_position = reference.com_position + Vector3::new(0.01, 0.0, 0.0);
    for name in [walking::LEFT_FOOT, walking::RIGHT_FOOT, walking::TORSO] {
        input
            .set_frame_reference(name, *reference.frame_reference(name).unwrap())
            .unwrap();
    }
    input.posture = reference.posture.clone();
    for (name, w) in [walking::LEFT_FOOT, walking::RIGHT_FOOT]
        .iter()
        .zip(wrenches)
    {
        let id = input.contact_id(name).unwrap();
        input.contact_mut(id).unwrap().measured_wrench = *w;
    }
    input
}

#[test]
fn the_rows_of_the_compliant_qp_are_their_definitions() {
    let model = bundled_model();
    let mut rng = rng(14);
    let config = compliant_config();
    let (kh, horizon) = (
        config.compliant.momentum_rate_gain,
        config.compliant.feasibility_horizon,
    );
    for trial in 0..6 {
        let (state, rest) = moving_stance(&model, &mut rng);
        let measured = [0, 1].map(|k| lemma1(&model, &state, SOLES[k], &rest[k]));
        let mut tsid = Tsid::new(Arc::clone(&model), config.clone(), PERIOD).unwrap();
        let input = input_with_wrenches(&model, &tsid, &state, &measured);
        let out = tsid.step(&input).unwrap().clone();
        assert!(out.report.is_nominal(), "trial {trial}: {:?}", out.report);
        let dt = PERIOD.as_secs_f64();
        let rates: Vec<Vector6<f64>> = (0..2)
            .map(|k| (out.contact_wrenches[k] - measured[k]) / dt)
            .collect();
        // the controller's rest pose is the sole raised by the static sink of its measured force
        let kd = kd_at(&model, &state);
        let rest_used = [0, 1].map(|k| {
            let mut p = kd.frame_pose(model.frame_id(SOLES[k]).unwrap());
            let c = p.rotation.to_rotation_matrix()[(2, 2)].abs();
            p.translation.vector +=
                measured[k].fixed_rows::<3>(0) / (GROUND.stiffness * SOLE.area() * c);
            p
        });
        // contact dynamics (eq. 8.2.15): ḟ = d/dt Lemma 1 along the chosen motion (central differences)
        let eps = 1e-5;
        for k in 0..2 {
            let ahead = lemma1(
                &model,
                &advanced(&state, &out.accelerations, eps),
                SOLES[k],
                &rest_used[k],
            );
            let behind = lemma1(
                &model,
                &advanced(&state, &out.accelerations, -eps),
                SOLES[k],
                &rest_used[k],
            );
            let fd = (ahead - behind) / (2.0 * eps);
            let err = (rates[k] - fd).norm();
            assert!(
                err <= 1e-4 * (1.0 + fd.norm()),
                "trial {trial}, {}: ḟ {:?} vs finite differences {:?}",
                SOLES[k],
                rates[k].transpose(),
                fd.transpose()
            );
        }
        // base dynamics and torques with the measured wrenches (eq. 8.2.13, 8.2.1): RNEA
        let mut kd = kd_at(&model, &state);
        let ext: Vec<ExternalWrench> = (0..2)
            .map(|k| ExternalWrench {
                frame: model.frame_id(SOLES[k]).unwrap(),
                wrench: measured[k],
            })
            .collect();
        let mut gen = DVector::zeros(model.nv());
        kd.inverse_dynamics(&out.accelerations, &ext, &mut gen)
            .unwrap();
        assert!(
            gen.rows(0, 6).amax() < 1e-6,
            "base rows: {}",
            gen.rows(0, 6).amax()
        );
        let tau_err = (gen.rows(6, model.dof()) - &out.joint_torques).amax();
        assert!(
            tau_err < 1e-6,
            "torques differ from the RNEA's by {tau_err}"
        );
        // CoM (hard): Σ ḟ = k_h (m ẍ* − m g − Σ f) with ẍ* = K_d (0 − ẋ) + K_p (x* − x)
        let m = model.total_mass();
        // (the preset's vertical row has its own gains, `kp_z`, `kd_z`)
        let gains = |xy: f64, z: f64| Vector3::new(xy, xy, z);
        let acc = gains(
            stride_wbc::BUNDLED_TSID_COM_KD,
            stride_wbc::BUNDLED_TSID_COM_KD_Z,
        )
        .component_mul(&(-kd.com_velocity()))
            + gains(
                stride_wbc::BUNDLED_TSID_COM_KP,
                stride_wbc::BUNDLED_TSID_COM_KP_Z,
            )
            .component_mul(&(input.com_position - kd.com_position()));
        let total: Vector3<f64> = (0..2)
            .map(|k| measured[k].fixed_rows::<3>(0).into_owned())
            .sum();
        let want = (m * acc - m * model.gravity() - total) * kh;
        let got: Vector3<f64> = rates
            .iter()
            .map(|r| r.fixed_rows::<3>(0).into_owned())
            .sum();
        assert!(
            (got - want).norm() < 1e-6 * (1.0 + want.norm()),
            "Σḟ {got:?} vs {want:?}"
        );
        // feasibility one step ahead (eq. 8.2.12): f + T ḟ in the friction pyramid and the CoP region
        for k in 0..2 {
            let w = measured[k] + rates[k] * horizon;
            let rt = kd
                .frame_pose(model.frame_id(SOLES[k]).unwrap())
                .rotation
                .inverse();
            let f = rt * w.fixed_rows::<3>(0).into_owned();
            let t = rt * w.fixed_rows::<3>(3).into_owned();
            assert!(f.z > 0.0, "{}: normal force {}", SOLES[k], f.z);
            let cop = Vector2::new(-t.y / f.z, t.x / f.z);
            let [x, y] = [stride_wbc::BUNDLED_COP_X, stride_wbc::BUNDLED_COP_Y];
            assert!(
                cop.x >= x[0] - 1e-7 && cop.x <= x[1] + 1e-7,
                "CoP x {}",
                cop.x
            );
            assert!(
                cop.y >= y[0] - 1e-7 && cop.y <= y[1] + 1e-7,
                "CoP y {}",
                cop.y
            );
        }
        let kkt = tsid.qp_problem().unwrap().check_kkt();
        assert!(kkt.is_satisfied(1e-7), "trial {trial}: {kkt:?}");
    }
}

/// What [`stand_on_soft_ground`] saw.
#[derive(Debug)]
struct Standing {
    /// Time of the fall or of the simulator's divergence (s), `None`: stood for the whole run.
    fell_at: Option<f64>,
    /// Largest CoM displacement from the start (m).
    worst: f64,
    /// TSID ticks solved by the relaxed fallback or held.
    fallbacks: usize,
    /// The compliant model's ground at the end.
    ground: Option<GroundParameters>,
}

/// Stands the bundled humanoid in stride-sim (torque mode, ideal sensors, 2 kHz; ideal actuators or
/// stride-sim's default ones: 30 Hz torque lag, 1 ms command delay, 0.1 N·m Coulomb friction) on the
/// isotropic ground `(k, b)` for `duration` s under the default TSID with `contact_model` (the compliant one
/// with a hard angular momentum task, [`compliant_config`]) at 500 Hz, on the plant's state and its
/// contact wrenches (the runner's ground-truth measurement), references holding the initial stance.
fn stand_on_soft_ground(
    contact_model: ContactModel,
    ideal_actuators: bool,
    k: f64,
    b: f64,
    duration: f64,
    tweak: impl Fn(&mut TsidConfig),
) -> Standing {
    use stride_sim::{ActuationConfig, ActuationMode, SensorConfig, SimConfig, SimInput, SimRobot};
    let model = bundled_model();
    let mut config = SimConfig {
        actuation: ActuationConfig::ideal(),
        sensors: SensorConfig::ideal(),
        ..SimConfig::default()
    };
    if !ideal_actuators {
        config.actuation = ActuationConfig::default();
        config.actuation.default.mode = ActuationMode::Torque;
    }
    config.actuation.default.mode = ActuationMode::Torque;
    // isotropic ground, as Lemma 1's density `ρ = k(x̄ − x) − b ẋ` [Romualdi 2022, eq. 8.1.6]
    config.contact.normal_stiffness = k;
    config.contact.normal_damping = b;
    config.contact.tangential_stiffness = k;
    config.contact.tangential_damping = b;
    let mut sim = SimRobot::new(Arc::clone(&model), config, Duration::from_micros(500)).unwrap();
    let state = sim
        .set_standing_on_ground(&default_posture(&model))
        .unwrap();
    let mut tsid_config = match contact_model {
        ContactModel::Compliant => compliant_config(),
        ContactModel::Rigid => TsidConfig::default_for_bundled_model(),
    };
    tsid_config.compliant.ground_stiffness = k;
    tsid_config.compliant.ground_damping = b;
    tweak(&mut tsid_config);
    let mut tsid = Tsid::new(Arc::clone(&model), tsid_config, PERIOD).unwrap();
    let reference = references_at(&model, &state);
    let mut input = input_with_wrenches(&model, &tsid, &state, &[Vector6::zeros(); 2]);
    input.com_position = reference.com_position;
    let ids = [walking::LEFT_FOOT, walking::RIGHT_FOOT].map(|n| input.contact_id(n).unwrap());
    let mut command = SimInput::zeros(model.dof());
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_representation(VelocityRepresentation::Mixed);
    let mut outcome = Standing {
        fell_at: None,
        worst: 0.0,
        fallbacks: 0,
        ground: None,
    };
    let ratio = (PERIOD.as_secs_f64() / sim.period()).round() as usize;
    for step in 0..(duration / sim.period()).round() as usize {
        if step % ratio == 0 {
            input.state.clone_from(sim.state());
            for (k, id) in ids.iter().enumerate() {
                let surface = sim.output().surfaces.get(k);
                input.contact_mut(*id).unwrap().measured_wrench =
                    surface.map_or(Vector6::zeros(), |s| s.wrench);
            }
            let out = tsid.step(&input).unwrap();
            outcome.fallbacks += usize::from(out.report.fallback || out.report.held);
            command.joint_torques.copy_from(&out.joint_torques);
        }
        let t = step as f64 * sim.period();
        if sim.step(&command).is_err() || sim.output().fallen {
            outcome.fell_at = Some(t);
            break;
        }
        kd.set_state(sim.state()).unwrap();
        outcome.worst = outcome
            .worst
            .max((kd.com_position() - reference.com_position).norm());
    }
    outcome.ground = tsid.ground();
    outcome
}

#[test]
fn the_compliant_tsid_stands_on_soft_ground_where_the_rigid_one_falls() {
    let compliant = stand_on_soft_ground(ContactModel::Compliant, true, 1e6, 1e4, 3.0, |_| {});
    let rigid = stand_on_soft_ground(ContactModel::Rigid, true, 1e6, 1e4, 3.0, |_| {});
    eprintln!("compliant: {compliant:?}\nrigid: {rigid:?}");
    assert!(compliant.fell_at.is_none(), "{compliant:?}");
    assert!(compliant.worst < 2e-3, "{compliant:?}");
    assert_eq!(compliant.fallbacks, 0, "{compliant:?}");
    assert!(rigid.fell_at.is_some(), "{rigid:?}");
}

/// The limit found: with stride-sim's default actuators (torque lag, delay, joint friction) the compliant
/// TSID's torso pitch oscillates (about 2 Hz, growing) and the robot falls within 3 s (docs/soft-ground.md).
#[test]
fn the_compliant_tsid_falls_with_the_default_actuators() {
    let real = stand_on_soft_ground(ContactModel::Compliant, false, 1e6, 1e4, 3.0, |_| {});
    eprintln!("default actuators: {real:?}");
    assert!(real.fell_at.is_some(), "{real:?}");
}

/// The ground estimator inside the compliant TSID [Romualdi 2022, §8.2.3] (`estimate_ground`): both soles
/// touch down with zero force (their rest poses), then the robot sinks and rises by up to 1 cm while the
/// measured wrenches are Lemma 1's on `k = 1e6, b = 1e4`; from a prior of `k = 2e6, b = 2e4` the ground the
/// controller uses ends within 1 % of the truth. (Standing from start-up does not identify `k`: a sole
/// loaded before the first tick has no zero-force pose, so its rest pose comes from the prior.)
#[test]
fn the_ground_estimate_inside_the_tsid_finds_k_and_b() {
    // the soles touch down exactly at zero force: no threshold needed to find their impact
    for ground in sink_and_rise(0.0, 0.0, stride_wbc::EstimatorRestPose::Level) {
        assert!(
            (ground.stiffness / GROUND.stiffness - 1.0).abs() < 0.01,
            "{ground:?}"
        );
        assert!(
            (ground.damping / GROUND.damping - 1.0).abs() < 0.01,
            "{ground:?}"
        );
    }
}

/// The ground estimates of both soles after 300 ticks in which the robot, from a prior of `k = 2e6,
/// b = 2e4` and `estimator_contact_force = threshold`, sinks and rises by up to 1 cm over a ground
/// (`GROUND`, Lemma 1's wrenches) whose surface is `gap` (m) below the soles at the start (no wrench above it).
fn sink_and_rise(
    threshold: f64,
    gap: f64,
    rest_pose: stride_wbc::EstimatorRestPose,
) -> Vec<stride_wbc::GroundParameters> {
    let (model_ground, estimates) = sink_and_rise_with(threshold, gap, rest_pose, |_| {});
    assert_eq!(model_ground, estimates.first().copied());
    estimates
}

/// [`sink_and_rise`] with `tweak` applied to the compliant settings: the ground of the first contact's
/// model and the estimates.
fn sink_and_rise_with(
    threshold: f64,
    gap: f64,
    rest_pose: stride_wbc::EstimatorRestPose,
    tweak: impl Fn(&mut stride_wbc::config::CompliantConfig),
) -> (
    Option<stride_wbc::GroundParameters>,
    Vec<stride_wbc::GroundParameters>,
) {
    let model = bundled_model();
    let mut config = compliant_config();
    config.compliant.ground_stiffness = 2e6;
    config.compliant.ground_damping = 2e4;
    config.compliant.estimate_ground = true;
    config.compliant.estimator_contact_force = threshold;
    config.compliant.estimator_rest_pose = rest_pose;
    tweak(&mut config.compliant);
    let mut tsid = Tsid::new(Arc::clone(&model), config, PERIOD).unwrap();
    let start = standing_state(&model, &default_posture(&model));
    let kd = kd_at(&model, &start);
    let rest = SOLES.map(|f| {
        let mut p = kd.frame_pose(model.frame_id(f).unwrap());
        p.translation.vector.z -= gap;
        p
    });
    let dt = PERIOD.as_secs_f64();
    for k in 0..300 {
        let t = k as f64 * dt;
        let w = 2.0 * std::f64::consts::PI / 0.4;
        let depth = 0.005 * (1.0 - (w * t).cos());
        let mut state = start.clone();
        state.base_pose.translation.vector.z -= depth;
        state.base_velocity[2] = -0.005 * w * (w * t).sin();
        let measured = [0, 1].map(|c| match depth >= gap {
            true => lemma1(&model, &state, SOLES[c], &rest[c]),
            false => Vector6::zeros(),
        });
        let input = input_with_wrenches(&model, &tsid, &state, &measured);
        tsid.step(&input).unwrap();
    }
    (tsid.ground(), tsid.ground_estimates().unwrap().to_vec())
}

/// `estimator_open_loop`: on the same prescribed motion (the estimate does not feed back into it) the
/// estimates are those of the closed loop to the bit, and the contact model keeps the prior `2e6, 2e4`.
/// `estimate_rest_height` on a rest plane that is right (the soles flat, 3 mm above the ground): `k̂`,
/// `b̂` within 10 % as without it.
#[test]
fn the_open_loop_estimate_and_the_rest_height_in_the_tsid() {
    use stride_wbc::EstimatorRestPose::Level;
    let closed = sink_and_rise(5.0, 0.003, Level);
    let (model_ground, open) =
        sink_and_rise_with(5.0, 0.003, Level, |c| c.estimator_open_loop = true);
    assert_eq!(open, closed);
    assert_eq!(
        model_ground,
        Some(stride_wbc::GroundParameters {
            stiffness: 2e6,
            damping: 2e4
        })
    );
    let (_, rest) = sink_and_rise_with(5.0, 0.003, Level, |c| c.estimate_rest_height = true);
    for g in rest {
        assert!((g.stiffness / GROUND.stiffness - 1.0).abs() < 0.1, "{g:?}");
        assert!((g.damping / GROUND.damping - 1.0).abs() < 0.1, "{g:?}");
    }
    let mut bad = compliant_config();
    bad.compliant.estimate_ground = true;
    bad.compliant.estimate_rest_height = true;
    bad.compliant.estimator_rest_height_std = 0.0;
    assert!(matches!(
        Tsid::new(bundled_model(), bad, PERIOD),
        Err(stride_wbc::WbcError::InvalidConfig {
            key: "estimator_rest_height_std",
            ..
        })
    ));
}

/// `estimator_accept_std` (the gate): on the same prescribed motion the estimates are those of the
/// ungated closed loop to the bit; the contact model takes them once their standard deviations are below
/// 10 % of them (it ends on the estimate), and keeps the prior `2e6, 2e4` when the bound is never met
/// (1e-9). A bound that is not > 0 is refused by name.
#[test]
fn the_gate_feeds_the_model_only_a_converged_estimate() {
    use stride_wbc::EstimatorRestPose::Level;
    let closed = sink_and_rise(5.0, 0.003, Level);
    let (taken, gated) = sink_and_rise_with(5.0, 0.003, Level, |c| c.estimator_accept_std = 0.1);
    assert_eq!(gated, closed);
    assert_eq!(taken, Some(closed[0]));
    let (held, never) = sink_and_rise_with(5.0, 0.003, Level, |c| c.estimator_accept_std = 1e-9);
    assert_eq!(never, closed);
    assert_eq!(
        held,
        Some(stride_wbc::GroundParameters {
            stiffness: 2e6,
            damping: 2e4
        })
    );
    for bound in [0.0, -1.0, f64::NAN] {
        let mut bad = compliant_config();
        bad.compliant.estimate_ground = true;
        bad.compliant.estimator_accept_std = bound;
        assert!(matches!(
            Tsid::new(bundled_model(), bad, PERIOD),
            Err(stride_wbc::WbcError::InvalidConfig {
                key: "estimator_accept_std",
                ..
            })
        ));
    }
}

/// The ground estimate of a sole whose planned touch-down comes before its impact: both soles start 3 mm
/// above the ground (no wrench there; Lemma 1's below) and sink by up to 1 cm (7 mm into the ground). With
/// the default `estimator_contact_force` (5 N) the rest pose waits for the sole to meet the ground and the
/// estimate ends within 10 % of `k = 1e6, b = 1e4` (prior `2e6, 2e4`), with either `estimator_rest_pose`;
/// with the threshold at 0 and the `"impact"` rest pose the rest pose is the sole's pose at the planned
/// touch-down, 3 mm above the ground, and `k̂` is more than 25 % off (measured 7.4e5).
#[test]
fn the_ground_estimate_waits_for_the_sole_to_meet_the_ground() {
    use stride_wbc::EstimatorRestPose::{Impact, Level};
    for rest_pose in [Level, Impact] {
        for g in sink_and_rise(5.0, 0.003, rest_pose) {
            assert!((g.stiffness / GROUND.stiffness - 1.0).abs() < 0.1, "{g:?}");
            assert!((g.damping / GROUND.damping - 1.0).abs() < 0.1, "{g:?}");
        }
    }
    for g in sink_and_rise(0.0, 0.003, Impact) {
        assert!((g.stiffness / GROUND.stiffness - 1.0).abs() > 0.25, "{g:?}");
    }
}

/// `lift_off_force`: a contact whose flag opens (its planned lift-off) stays in the QP after its 0.02 s load
/// ramp while its measured normal force exceeds the setting, with that force as its bound (the chosen wrench
/// one period ahead does not exceed it), and leaves once the force is below; with the default (`inf`) it
/// leaves when the ramp ends whatever it carries. A negative setting is refused by name.
#[test]
fn a_loaded_sole_leaves_the_qp_only_below_the_lift_off_force() {
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let weight = model.total_mass() * 9.81;
    let wrench = |fz: f64| Vector6::new(0.0, 0.0, fz, 0.0, 0.0, 0.0);
    let run = |lift_off_force: f64| {
        let mut config = compliant_config();
        config.compliant.lift_off_force = lift_off_force;
        let mut tsid = Tsid::new(Arc::clone(&model), config, PERIOD).unwrap();
        let mut input = input_with_wrenches(
            &model,
            &tsid,
            &state,
            &[wrench(weight / 2.0), wrench(weight / 2.0)],
        );
        tsid.step(&input).unwrap();
        // the right contact opens with 60 N still on its sole, for 15 periods (0.03 s)
        let right = input.contact_id(walking::RIGHT_FOOT).unwrap();
        input.contact_mut(right).unwrap().active = false;
        input.contact_mut(right).unwrap().measured_wrench = wrench(60.0);
        let mut chosen = Vec::new();
        for _ in 0..15 {
            let out = tsid.step(&input).unwrap();
            chosen.push((out.contact_load[1], out.contact_wrenches[1].z));
        }
        // the sole unloads to 10 N
        input.contact_mut(right).unwrap().measured_wrench = wrench(10.0);
        let load_after = tsid.step(&input).unwrap().contact_load[1];
        (chosen, load_after)
    };
    let (held, after) = run(20.0);
    let (last_load, last_fz) = *held.last().unwrap();
    assert!(last_load > 0.0, "{held:?}");
    assert!(last_fz <= 60.0 + 1e-6, "{held:?}");
    assert_eq!(after, 0.0);
    let (released, _) = run(f64::INFINITY);
    assert_eq!(released.last().unwrap().0, 0.0, "{released:?}");
    let mut config = compliant_config();
    config.compliant.lift_off_force = -1.0;
    let err = Tsid::new(Arc::clone(&model), config, PERIOD).err().unwrap();
    assert!(err.to_string().contains("lift_off_force"), "{err}");
}

/// The joint torques of two ticks of a standing compliant TSID with `source`: the first with the soles'
/// share of the weight measured, the second with `second` measured (the state unchanged).
fn torques_after(
    source: WrenchSource,
    filter_time: f64,
    second: &[Vector6<f64>; 2],
) -> DVector<f64> {
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let half = model.total_mass() * 9.81 / 2.0;
    let share = Vector6::new(0.0, 0.0, half, 0.0, 0.0, 0.0);
    let mut config = compliant_config();
    config.compliant.wrench_source = source;
    config.compliant.wrench_filter_time = filter_time;
    let mut tsid = Tsid::new(Arc::clone(&model), config, PERIOD).unwrap();
    tsid.step(&input_with_wrenches(&model, &tsid, &state, &[share, share]))
        .unwrap();
    let input = input_with_wrenches(&model, &tsid, &state, second);
    tsid.step(&input).unwrap().joint_torques.clone()
}

/// `wrench_source`: with `"model"` the rows read Lemma 1's wrench at the soles' state about their
/// touch-down poses, so a measured wrench changed after the touch-down changes no torque, where with
/// `"measured"` it does; with `"filtered"` a small change of the measured wrench moves the torques by
/// `α = period / (τ + period)` of what it moves them with `"measured"` (the QP's solution is affine in
/// the wrench while its active set holds), and a time constant near zero is the measured source.
#[test]
fn the_wrench_source_sets_what_the_rows_read() {
    let model = bundled_model();
    let half = model.total_mass() * 9.81 / 2.0;
    let share = Vector6::new(0.0, 0.0, half, 0.0, 0.0, 0.0);
    let same = [share, share];
    let kick = Vector6::new(0.4, -0.3, 1.0, 0.02, -0.03, 0.01);
    let changed = [share + kick, share - kick * 0.5];
    let dist = |a: &DVector<f64>, b: &DVector<f64>| (a - b).norm();
    // model: the measured change does nothing
    let model_same = torques_after(WrenchSource::Model, 0.05, &same);
    let model_changed = torques_after(WrenchSource::Model, 0.05, &changed);
    assert!(
        dist(&model_same, &model_changed) < 1e-9,
        "{}",
        dist(&model_same, &model_changed)
    );
    // measured: it does
    let measured_same = torques_after(WrenchSource::Measured, 0.05, &same);
    let measured_changed = torques_after(WrenchSource::Measured, 0.05, &changed);
    let full = dist(&measured_same, &measured_changed);
    assert!(full > 1e-3, "{full}");
    // filtered: α of it
    let tau = 0.05;
    let alpha = PERIOD.as_secs_f64() / (tau + PERIOD.as_secs_f64());
    let filtered_same = torques_after(WrenchSource::Filtered, tau, &same);
    let filtered_changed = torques_after(WrenchSource::Filtered, tau, &changed);
    let part = &filtered_changed - &filtered_same;
    let expected = (&measured_changed - &measured_same) * alpha;
    assert!(
        dist(&part, &expected) < 1e-6 * full,
        "{} of {}",
        dist(&part, &expected),
        full * alpha
    );
    // a time constant near zero: the measured wrench
    let instant = torques_after(WrenchSource::Filtered, 1e-12, &changed);
    assert!(dist(&instant, &measured_changed) < 1e-6 * full);
    // refused
    let mut config = compliant_config();
    config.compliant.wrench_filter_time = 0.0;
    let err = Tsid::new(Arc::clone(&model), config, PERIOD).err().unwrap();
    assert!(err.to_string().contains("wrench_filter_time"), "{err}");
}

/// The joint torques of the second tick of a standing compliant TSID whose angular momentum task has `kp`,
/// with `angular_momentum_damping = zeta` and `momentum_rate_gain = kh`, asked an angular momentum
/// away from the robot's (so that the task's gain moves the torques).
fn torques_with_angular_gain(kp: f64, zeta: f64, kh: f64) -> DVector<f64> {
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let half = model.total_mass() * 9.81 / 2.0;
    let share = Vector6::new(0.0, 0.0, half, 0.0, 0.0, 0.0);
    let mut config = compliant_config();
    for task in &mut config.tasks {
        if let TaskConfig::AngularMomentum(t) = task {
            t.kp = kp;
        }
    }
    config.compliant.momentum_rate_gain = kh;
    config.compliant.angular_momentum_damping = zeta;
    let mut tsid = Tsid::new(Arc::clone(&model), config, PERIOD).unwrap();
    tsid.step(&input_with_wrenches(&model, &tsid, &state, &[share, share]))
        .unwrap();
    let mut input = input_with_wrenches(&model, &tsid, &state, &[share, share]);
    input.angular_momentum = Vector3::new(0.3, -0.2, 0.1);
    tsid.step(&input).unwrap().joint_torques.clone()
}

/// `angular_momentum_damping` (`ζ`): the angular momentum task's `K_p` becomes `k_h / (4 ζ²)` whatever its
/// configured `kp` (the same torques as that `kp` configured, to 1e-9), at two momentum rate gains; off
/// (0) the configured `kp` is kept (other torques); a negative or non-finite `ζ` is refused by name.
#[test]
fn the_angular_momentum_gain_is_derived_from_the_momentum_rate_gain() {
    let dist = |a: &DVector<f64>, b: &DVector<f64>| (a - b).norm();
    for (zeta, kh) in [(1.0, 25.0), (0.8, 60.0)] {
        let derived = torques_with_angular_gain(3.0, zeta, kh);
        let configured = torques_with_angular_gain(kh / (4.0 * zeta * zeta), 0.0, kh);
        let own = torques_with_angular_gain(3.0, 0.0, kh);
        assert!(
            dist(&derived, &configured) < 1e-9 * configured.norm(),
            "ζ {zeta}, k_h {kh}: {}",
            dist(&derived, &configured)
        );
        assert!(
            dist(&derived, &own) > 1e-3,
            "ζ {zeta}, k_h {kh}: {}",
            dist(&derived, &own)
        );
    }
    let model = bundled_model();
    for zeta in [-1.0, f64::NAN, f64::INFINITY] {
        let mut config = compliant_config();
        config.compliant.angular_momentum_damping = zeta;
        let err = Tsid::new(Arc::clone(&model), config, PERIOD).err().unwrap();
        assert!(
            err.to_string().contains("angular_momentum_damping"),
            "{err}"
        );
    }
}
