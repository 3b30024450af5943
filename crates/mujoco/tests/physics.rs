//! Physics laws and conversions of the MuJoCo plant (needs MuJoCo: `--features mujoco`).
#![cfg(feature = "mujoco")]

mod common;

use std::sync::Arc;

use common::*;
use mujoco_rs::prelude::*;
use nalgebra::{DVector, Isometry3, Translation3, UnitQuaternion, Vector3, Vector6};
use stride_model::{KinDyn, Model, RobotState};
use stride_mujoco::{state_from_mujoco, MujocoError};
use stride_sim::{PushConfig, SimInput};

/// A 20 kg box dropped from 5 cm comes to rest: the ground force equals its weight, centred under it.
#[test]
fn a_dropped_box_settles_with_the_ground_force_equal_to_its_weight() {
    let urdf = box_urdf("dropped_box", 20.0, [0.2, 0.1, 0.1], None);
    let model = Arc::new(Model::from_urdf_file(&urdf).expect("box"));
    let sim = ideal_sim(1000.0, 60.0);
    let mut plant = plant(&model, &urdf, &sim, ["sole", "sole"]);
    let mut state = RobotState::zero(&model);
    state.base_pose.translation.vector = Vector3::new(0.0, 0.0, 0.1);
    plant.set_initial_state(&state).expect("state");
    let input = SimInput::zeros(0);
    for _ in 0..4000 {
        plant.step(&input).expect("step");
    }
    let out = plant.output();
    let weight = 20.0 * 9.81;
    let w = out.sole_wrenches[0];
    assert!(out.sole_contact[0] && !out.sole_contact[1]);
    assert!(
        (w[2] - weight).abs() < 1e-6 * weight,
        "f_z {} vs m g {weight}",
        w[2]
    );
    assert!(w.fixed_rows::<2>(0).norm() < 1e-6, "tangential force {w}");
    // Centre of pressure at the sole origin: no torque about it.
    assert!(w.fixed_rows::<3>(3).norm() < 1e-6, "torque {w}");
    // At rest above the plane by less than MuJoCo's soft-contact penetration (solimp width 1 mm).
    let z = out.state.base_pose.translation.z;
    assert!(
        (z - 0.05).abs() < 2e-3 && out.state.base_velocity.norm() < 1e-4,
        "z {z}"
    );
    std::fs::remove_file(urdf).ok();
}

/// With no gravity, a push of `f` during `T` at the sole (5 cm below the centre of mass) gives the linear
/// momentum `J = f T` and the angular momentum `(p − c) × J + τ T` about the centre of mass. The box's
/// inertia (100 kg·m²) keeps it from turning during the push (< 1e-4 rad), so the arm stays `(0, 0, −0.05)`.
#[test]
fn a_push_at_a_frame_gives_its_impulse_and_moment() {
    let urdf = box_urdf("pushed_box", 20.0, [0.2, 0.1, 0.1], Some(100.0));
    let mut model = Model::from_urdf_file(&urdf).expect("box");
    model.set_gravity(Vector3::zeros()).expect("gravity");
    let model = Arc::new(model);
    let mut sim = ideal_sim(1000.0, 60.0);
    sim.pushes.push(PushConfig {
        frame: "sole".into(),
        start: 0.01,
        duration: 0.1,
        wrench: [10.0, 4.0, 0.0, 0.0, 0.0, 0.5],
    });
    let mut plant = plant(&model, &urdf, &sim, ["sole", "sole"]);
    let mut state = RobotState::zero(&model);
    state.base_pose.translation.vector = Vector3::new(0.0, 0.0, 1.0);
    plant.set_initial_state(&state).expect("state");
    for _ in 0..400 {
        plant.step(&SimInput::zeros(0)).expect("step");
    }
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_state(plant.state()).expect("state");
    let h = kd.centroidal_momentum();
    let j = Vector3::new(1.0, 0.4, 0.0);
    assert!(
        (h.fixed_rows::<3>(0) - j).norm() < 1e-9,
        "linear momentum {h}"
    );
    let expected = Vector3::new(0.0, 0.0, -0.05).cross(&j) + Vector3::new(0.0, 0.0, 0.05);
    let l = h.fixed_rows::<3>(3);
    assert!(
        (l - expected).norm() < 1e-4 * expected.norm(),
        "angular momentum {l} vs {expected}"
    );
    std::fs::remove_file(urdf).ok();
}

/// A state written to MuJoCo and read back is the same; every body's pose and the sole's velocity computed
/// by MuJoCo equal stride-model's for that state.
#[test]
fn the_state_conversion_round_trips_against_stride_model_kinematics() {
    let urdf = humanoid_urdf();
    let model = Arc::new(Model::from_urdf_file(&urdf).expect("humanoid"));
    let mut plant = plant(
        &model,
        &urdf,
        &ideal_sim(1000.0, 60.0),
        ["l_sole", "r_sole"],
    );
    let n = model.dof();
    let mut state = RobotState::zero(&model);
    state.base_pose = Isometry3::from_parts(
        Translation3::new(0.3, -0.2, 0.9),
        UnitQuaternion::from_euler_angles(0.3, -0.2, 1.1),
    );
    state.joint_positions = DVector::from_fn(n, |i, _| 0.3 * ((i as f64) * 0.7).sin());
    state.base_velocity = Vector6::new(0.1, -0.3, 0.2, 0.5, -0.4, 0.9);
    state.joint_velocities = DVector::from_fn(n, |i, _| ((i as f64) * 1.3).cos());
    plant.set_initial_state(&state).expect("state");
    let (qa, dofs) = (
        plant.joint_qpos_addresses().to_vec(),
        joint_dofs(&plant, &model),
    );
    let mut back = RobotState::zero(&model);
    let data = plant.mj_data();
    state_from_mujoco(data.qpos(), data.qvel(), &qa, &dofs, &mut back);
    assert!(
        (back.base_pose.translation.vector - state.base_pose.translation.vector).norm() < 1e-15
    );
    assert!(back.base_pose.rotation.angle_to(&state.base_pose.rotation) < 1e-12);
    assert!((back.base_velocity - state.base_velocity).norm() < 1e-12);
    assert_eq!(back.joint_positions, state.joint_positions);
    assert_eq!(back.joint_velocities, state.joint_velocities);
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_state(&state).expect("state");
    for (b, &id) in model.bodies().iter().zip(plant.body_ids()) {
        let pose = kd.frame_pose(model.frame_id(&b.name).expect("body frame"));
        let p = Vector3::from(data.xpos()[id]);
        let q = data.xquat()[id];
        let r = UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]));
        assert!(
            (p - pose.translation.vector).norm() < 1e-12,
            "{}: {p} vs {}",
            b.name,
            pose.translation.vector
        );
        assert!(r.angle_to(&pose.rotation) < 1e-12, "{}", b.name);
    }
    // MuJoCo's velocity of the sole's body at its origin, [ω; v] in world orientation, against the
    // mixed velocity of the body frame from stride-model.
    let foot = model.frames()[model.frame_id("l_sole").expect("l_sole").index()].link;
    let v = data.object_velocity(MjtObjBase::mjOBJ_XBODY, plant.body_ids()[foot], false);
    let mixed = kd.frame_velocity(model.frame_id(&model.bodies()[foot].name).expect("frame"));
    let mj = Vector6::new(v[3], v[4], v[5], v[0], v[1], v[2]);
    assert!((mj - mixed).norm() < 1e-12, "{mj} vs {mixed}");
}

fn joint_dofs(plant: &stride_mujoco::MujocoRobot, model: &Model) -> Vec<usize> {
    let mj = plant.mj_model();
    model
        .joints()
        .iter()
        .map(|j| {
            let id = mj
                .name_to_id(MjtObjBase::mjOBJ_JOINT, &j.name)
                .expect("joint");
            mj.jnt_dofadr()[id] as usize
        })
        .collect()
}

/// Each stride joint's `qpos` address belongs to the MuJoCo joint of the same name, and driving one joint
/// moves the MuJoCo body of the same name as stride-model predicts.
#[test]
fn joints_are_mapped_by_name() {
    let urdf = humanoid_urdf();
    let model = Arc::new(Model::from_urdf_file(&urdf).expect("humanoid"));
    let plant = plant(
        &model,
        &urdf,
        &ideal_sim(1000.0, 60.0),
        ["l_sole", "r_sole"],
    );
    let mj = plant.mj_model();
    for (j, &a) in model.joints().iter().zip(plant.joint_qpos_addresses()) {
        let id = (0..mj.njnt() as usize)
            .find(|&k| mj.jnt_qposadr()[k] as usize == a)
            .expect("a joint at the address");
        assert_eq!(
            mj.id_to_name(MjtObjBase::mjOBJ_JOINT, id),
            Some(j.name.as_str())
        );
        let act = mj
            .name_to_id(MjtObjBase::mjOBJ_ACTUATOR, &j.name)
            .expect("actuator");
        assert_eq!(
            act,
            model.joint_index(&j.name).expect("index"),
            "actuator order"
        );
    }
    let mut state = RobotState::zero(&model);
    let mut plant = plant;
    let knee = model.joint_index("r_knee").expect("r_knee");
    state.joint_positions[knee] = 0.8;
    plant.set_initial_state(&state).expect("state");
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_state(&state).expect("state");
    let sole = model.frame_id("r_sole").expect("r_sole");
    let body = model.frames()[sole.index()].link;
    let p = Vector3::from(plant.mj_data().xpos()[plant.body_ids()[body]]);
    let expected = kd.frame_pose(model.frame_id(&model.bodies()[body].name).expect("frame"));
    assert!((p - expected.translation.vector).norm() < 1e-12);
}

/// The humanoid standing in its crouch on position servos: the soles carry its weight (Σ f_z = m g), the
/// centre of pressure is under the centre of mass, and each foot sensor reads its sole's ground force minus
/// the weight of the foot below it (0.7 kg), in world orientation.
#[test]
fn the_standing_humanoid_carries_its_weight() {
    let urdf = humanoid_urdf();
    let model = Arc::new(Model::from_urdf_file(&urdf).expect("humanoid"));
    let mut plant = plant(
        &model,
        &urdf,
        &ideal_sim(10000.0, 200.0),
        ["l_sole", "r_sole"],
    );
    let q = crouch(&model);
    plant
        .set_initial_state(&standing(&model, &q))
        .expect("state");
    let out = stands_with_its_weight(&mut plant, &model, &q);
    let fz = out.sole_wrenches[0][2] + out.sole_wrenches[1][2];
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_state(&out.state).expect("state");
    let com = kd.com_position();
    let mut moment = Vector3::zeros();
    for (k, name) in ["l_sole", "r_sole"].iter().enumerate() {
        let o = kd
            .frame_pose(model.frame_id(name).expect("sole"))
            .translation
            .vector;
        let w = out.sole_wrenches[k];
        let f = w.fixed_rows::<3>(0).into_owned();
        moment += w.fixed_rows::<3>(3) + o.cross(&f);
    }
    // ZMP on z = 0 (the soles sink less than 2 mm): x = −τ_y / f_z, y = τ_x / f_z.
    let zmp = Vector3::new(-moment.y / fz, moment.x / fz, 0.0);
    assert!(
        (zmp.xy() - com.xy()).norm() < 1e-3,
        "ZMP {zmp} vs CoM {com}"
    );
    for (k, sensor) in ["l_foot_ft_sensor", "r_foot_ft_sensor"].iter().enumerate() {
        let i = model.ft_sensor_index(sensor).expect("sensor");
        let frame = model.ft_sensors()[i].frame;
        let r = kd.frame_pose(frame).rotation;
        let f_world = r * out.ft_wrenches_truth[i].fixed_rows::<3>(0);
        let expected = out.sole_wrenches[k][2] - 0.7 * 9.81;
        assert!(
            (f_world.z.abs() - expected).abs() < 0.05,
            "{sensor}: {f_world} vs {expected}"
        );
    }
}

/// A non-finite command names the joint and changes nothing.
#[test]
fn a_non_finite_command_is_an_error_and_changes_nothing() {
    let urdf = humanoid_urdf();
    let model = Arc::new(Model::from_urdf_file(&urdf).expect("humanoid"));
    let mut plant = plant(
        &model,
        &urdf,
        &ideal_sim(10000.0, 200.0),
        ["l_sole", "r_sole"],
    );
    let q = crouch(&model);
    plant
        .set_initial_state(&standing(&model, &q))
        .expect("state");
    let before = plant.output().clone();
    let mut input = SimInput::hold(&q);
    input.joint_positions[3] = f64::NAN;
    match plant.step(&input) {
        Err(MujocoError::NonFiniteCommand { joint, .. }) => {
            assert_eq!(joint, model.joints()[3].name)
        }
        other => panic!("expected NonFiniteCommand, got {other:?}"),
    }
    assert_eq!(plant.output().state, before.state);
    assert_eq!(plant.output().time, before.time);
}

/// A finite command MuJoCo rejects (a position set-point beyond its `mjMAXVAL` of 1e10) raises MuJoCo's
/// bad-ctrl warning: the step fails with it and the state of before the step is kept.
#[test]
fn a_mujoco_warning_fails_the_step_and_restores_the_state() {
    let urdf = humanoid_urdf();
    let model = Arc::new(Model::from_urdf_file(&urdf).expect("humanoid"));
    let mut plant = plant(
        &model,
        &urdf,
        &ideal_sim(10000.0, 200.0),
        ["l_sole", "r_sole"],
    );
    let q = crouch(&model);
    plant
        .set_initial_state(&standing(&model, &q))
        .expect("state");
    plant.step(&SimInput::hold(&q)).expect("step");
    let before = plant.output().clone();
    let qpos = plant.mj_data().qpos().to_vec();
    let mut input = SimInput::hold(&q);
    input.joint_positions[5] = 1e12;
    match plant.step(&input) {
        Err(MujocoError::Warning { warning, .. }) => assert!(warning.contains("ctrl"), "{warning}"),
        other => panic!("expected a MuJoCo warning, got {other:?}"),
    }
    assert_eq!(plant.output().state, before.state);
    assert_eq!(plant.output().time, before.time);
    assert_eq!(plant.mj_data().qpos(), qpos.as_slice());
}
