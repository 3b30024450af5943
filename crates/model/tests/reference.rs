//! stride-model against iDynTree 15.1 and Pinocchio 4.1.
//!
//! The fixtures in `tests/fixtures/*.json` are written by `tools/reference/generate_fixtures.py`, which
//! computes every quantity with both libraries and refuses to write a fixture unless they agree to 1e-10
//! (relative). Mixed and inertial numbers come from iDynTree's `KinDynComputations`, body numbers and the
//! forward dynamics (ABA) from Pinocchio. See the script's doc string for the conventions of the files.
//!
//! Every quantity must match with `max |stride − reference| ≤ 1e-9 · max(1, ‖reference‖∞)`.
//!
//! The official iCub URDFs are not committed: the tests find them in `$STRIDE_ICUB_MODELS_DIR/<model>/model.urdf`
//! (the `share/iCub/robots` directory of the `icub-models` package, printed by
//! `tools/reference/icub-models-dir.sh`), by the rule of [`stride_testkit::icub_model_urdf`]: without the variable
//! they are skipped with a printed reason (an error under CI, `CI` set); with it, a missing model is an error.

use std::path::PathBuf;
use std::sync::Arc;

use nalgebra::{
    DMatrix, DVector, Isometry3, Matrix3, Quaternion, Translation3, UnitQuaternion, Vector3,
    Vector6,
};
use serde_json::Value;
use stride_model::{ExternalWrench, KinDyn, Model, RobotState, VelocityRepresentation};

/// Relative tolerance of every comparison.
const TOL: f64 = 1e-9;

fn manifest_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn load_fixture(name: &str) -> Value {
    let path = manifest_dir()
        .join("tests")
        .join("fixtures")
        .join(format!("{name}.json"));
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("cannot parse {}: {e}", path.display()))
}

/// Where the URDF of a fixture is: in the repository, or an official iCub model found by
/// [`stride_testkit::icub_model_urdf`] for the test named `test` (`None`, the skip printed, when
/// `STRIDE_ICUB_MODELS_DIR` is unset; a failure when it is set and the model is missing).
fn urdf_path(test: &str, fx: &Value) -> Option<PathBuf> {
    if let Some(rel) = fx["urdf"].as_str() {
        return Some(manifest_dir().join("..").join("..").join(rel));
    }
    let icub = fx["icub_model"]
        .as_str()
        .expect("fixture has neither urdf nor icub_model");
    stride_testkit::icub_model_urdf(test, icub)
}

fn vec_of(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap_or_else(|| panic!("expected an array, got {v}"))
        .iter()
        .map(|x| {
            x.as_f64()
                .unwrap_or_else(|| panic!("expected a number, got {x}"))
        })
        .collect()
}

fn mat_of(v: &Value) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = v.as_array().expect("matrix").iter().map(vec_of).collect();
    let ncols = rows.first().map_or(0, |r| r.len());
    DMatrix::from_fn(rows.len(), ncols, |r, c| rows[r][c])
}

/// The symmetric matrix stored as its upper triangle (row r holds columns r..n-1).
fn sym_of_upper(v: &Value) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = v.as_array().expect("matrix").iter().map(vec_of).collect();
    let n = rows.len();
    let mut m = DMatrix::zeros(n, n);
    for (r, row) in rows.iter().enumerate() {
        assert_eq!(row.len(), n - r, "mass_matrix_upper row {r}");
        for (k, x) in row.iter().enumerate() {
            m[(r, r + k)] = *x;
            m[(r + k, r)] = *x;
        }
    }
    m
}

fn v6(v: &[f64]) -> Vector6<f64> {
    Vector6::from_column_slice(v)
}

/// Accumulates the comparisons of one model: worst relative error per quantity and every failure.
struct Report {
    model: String,
    worst: Vec<(String, f64)>,
    failures: Vec<String>,
    checks: usize,
}

impl Report {
    fn new(model: &str) -> Self {
        Self {
            model: model.to_string(),
            worst: Vec::new(),
            failures: Vec::new(),
            checks: 0,
        }
    }

    /// Compares `got` with `reference` (same shape, flattened) and records the relative error.
    fn compare(&mut self, quantity: &str, context: &str, got: &[f64], reference: &[f64]) {
        self.checks += 1;
        assert_eq!(got.len(), reference.len(), "{quantity} {context}: size");
        let scale = reference.iter().fold(1.0_f64, |m, x| m.max(x.abs()));
        let (mut err, mut at) = (0.0_f64, 0);
        for (i, (g, r)) in got.iter().zip(reference).enumerate() {
            let e = (g - r).abs();
            if e > err || e.is_nan() {
                err = if e.is_nan() { f64::INFINITY } else { e };
                at = i;
            }
        }
        let rel = err / scale;
        match self.worst.iter_mut().find(|(q, _)| q == quantity) {
            Some((_, w)) => *w = w.max(rel),
            None => self.worst.push((quantity.to_string(), rel)),
        }
        if rel > TOL {
            self.failures.push(format!(
                "{} {quantity} [{context}]: max abs error {err:.3e} at element {at} (stride {:.12e}, reference {:.12e}), \
                 scale {scale:.3e}, relative {rel:.3e}",
                self.model, got[at], reference[at]
            ));
        }
    }

    fn finish(self) {
        println!(
            "{}: {} comparisons; worst relative error per quantity:",
            self.model, self.checks
        );
        for (q, w) in &self.worst {
            println!("  {q:<36} {w:.2e}");
        }
        if !self.failures.is_empty() {
            let shown: Vec<&String> = self.failures.iter().take(40).collect();
            panic!(
                "{}: {} of {} comparisons exceed {TOL:e} (relative):\n{}",
                self.model,
                self.failures.len(),
                self.checks,
                shown
                    .iter()
                    .map(|s| s.as_str())
                    .collect::<Vec<_>>()
                    .join("\n")
            );
        }
    }
}

/// Maps the fixture's ordering (joints by name) onto the model's.
struct Ordering {
    /// fixture ν index → model ν index.
    nu: Vec<usize>,
}

impl Ordering {
    fn new(model: &Model, joint_names: &[String]) -> Self {
        assert_eq!(
            model.dof(),
            joint_names.len(),
            "number of joints: stride {} vs fixture",
            model.dof()
        );
        let mut nu: Vec<usize> = (0..6).collect();
        for name in joint_names {
            let j = model
                .joint_index(name)
                .unwrap_or_else(|| panic!("stride model has no joint `{name}`"));
            nu.push(6 + j);
        }
        Self { nu }
    }

    /// Fixture-ordered joint vector → model order.
    fn joints_to_model(&self, x: &[f64]) -> DVector<f64> {
        let n = x.len();
        let mut out = DVector::zeros(n);
        for (k, v) in x.iter().enumerate() {
            out[self.nu[6 + k] - 6] = *v;
        }
        out
    }

    /// Fixture-ordered ν-sized vector → model order.
    fn nu_to_model(&self, x: &[f64]) -> DVector<f64> {
        let mut out = DVector::zeros(x.len());
        for (k, v) in x.iter().enumerate() {
            out[self.nu[k]] = *v;
        }
        out
    }

    /// Model-ordered ν-sized vector → fixture order.
    fn nu_from_model(&self, x: &DVector<f64>) -> Vec<f64> {
        self.nu.iter().map(|&i| x[i]).collect()
    }

    /// Model-ordered matrix with ν columns → fixture order, flattened row-major.
    fn cols_from_model(&self, m: &DMatrix<f64>) -> Vec<f64> {
        let mut out = Vec::with_capacity(m.nrows() * m.ncols());
        for r in 0..m.nrows() {
            for &c in &self.nu {
                out.push(m[(r, c)]);
            }
        }
        out
    }

    /// Model-ordered ν × ν matrix → fixture order, flattened row-major.
    fn square_from_model(&self, m: &DMatrix<f64>) -> Vec<f64> {
        let mut out = Vec::with_capacity(m.nrows() * m.ncols());
        for &r in &self.nu {
            for &c in &self.nu {
                out.push(m[(r, c)]);
            }
        }
        out
    }
}

fn row_major(m: &DMatrix<f64>) -> Vec<f64> {
    let mut out = Vec::with_capacity(m.nrows() * m.ncols());
    for r in 0..m.nrows() {
        for c in 0..m.ncols() {
            out.push(m[(r, c)]);
        }
    }
    out
}

fn representation(name: &str) -> VelocityRepresentation {
    match name {
        "mixed" => VelocityRepresentation::Mixed,
        "body" => VelocityRepresentation::Body,
        "inertial" => VelocityRepresentation::Inertial,
        other => panic!("unknown representation {other}"),
    }
}

fn pose_of(position: &[f64], xyzw: &[f64]) -> Isometry3<f64> {
    let q = UnitQuaternion::from_quaternion(Quaternion::new(xyzw[3], xyzw[0], xyzw[1], xyzw[2]));
    Isometry3::from_parts(Translation3::new(position[0], position[1], position[2]), q)
}

fn rotation_of(pose: &Isometry3<f64>) -> Matrix3<f64> {
    *pose.rotation.to_rotation_matrix().matrix()
}

/// Compares the model of fixture `name` with the fixture, in the test named `test`.
fn check_model(test: &str, name: &str) {
    let fx = load_fixture(name);
    let Some(path) = urdf_path(test, &fx) else {
        return;
    };
    let model = Model::from_urdf_file(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let model = Arc::new(model);
    let mut report = Report::new(name);

    // ---- model-level facts ----
    let joint_names: Vec<String> = fx["joint_names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap().to_string())
        .collect();
    let order = Ordering::new(&model, &joint_names);
    let nv = model.nv();
    assert_eq!(nv, joint_names.len() + 6);
    let base = fx["base_link"].as_str().unwrap();
    assert_eq!(model.root_link(), base, "{name}: root link");
    report.compare(
        "total_mass",
        "model",
        &[model.total_mass()],
        &[fx["total_mass"].as_f64().unwrap()],
    );
    // Force/torque sensors: the same mounting joints as iDynTree finds, and iDynTree's names among ours
    // (a URDF may name a sensor twice, in a gazebo block and in an iDynTree <sensor>: stride may list both).
    let strings = |v: &Value| -> Vec<String> {
        v.as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_str().unwrap().to_string())
            .collect()
    };
    let mut fixture_joints = strings(&fx["ft_sensor_joints"]);
    fixture_joints.sort();
    let mut model_joints: Vec<String> =
        model.ft_sensors().iter().map(|s| s.joint.clone()).collect();
    model_joints.sort();
    model_joints.dedup();
    assert_eq!(
        model_joints, fixture_joints,
        "{name}: joints carrying force/torque sensors"
    );
    let model_names: Vec<&str> = model.ft_sensors().iter().map(|s| s.name.as_str()).collect();
    for sensor in strings(&fx["ft_sensors"]) {
        assert!(
            model_names.contains(&sensor.as_str()),
            "{name}: no force/torque sensor `{sensor}` in {model_names:?}"
        );
    }
    if model_names.len() != fixture_joints.len() {
        println!(
            "{name}: note: {} force/torque sensor entries on {} joints: {model_names:?}",
            model_names.len(),
            fixture_joints.len()
        );
    }

    let frame = |n: &str| {
        model
            .frame_id(n)
            .unwrap_or_else(|| panic!("{name}: stride model has no frame `{n}`"))
    };
    let gravity = vec_of(&fx["gravity"]);

    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_gravity(Vector3::new(gravity[0], gravity[1], gravity[2]));
    let mut mass = DMatrix::zeros(nv, nv);
    let mut jac = DMatrix::zeros(6, nv);
    let mut com_jac = DMatrix::zeros(3, nv);
    let mut cmm = DMatrix::zeros(6, nv);
    let mut vec_nv = DVector::zeros(nv);

    for (k, st) in fx["states"].as_array().unwrap().iter().enumerate() {
        let base_pose = pose_of(
            &vec_of(&st["base_position"]),
            &vec_of(&st["base_orientation_xyzw"]),
        );
        let q = order.joints_to_model(&vec_of(&st["joint_positions"]));
        let qd = order.joints_to_model(&vec_of(&st["joint_velocities"]));
        let nu_dot = order.nu_to_model(&vec_of(&st["nu_dot"]));
        let tau = order.joints_to_model(&vec_of(&st["joint_torques"]));
        let wrenches: Vec<ExternalWrench> = st["external_wrenches"]
            .as_array()
            .unwrap()
            .iter()
            .map(|w| ExternalWrench {
                frame: frame(w["frame"].as_str().unwrap()),
                wrench: v6(&vec_of(&w["wrench"])),
            })
            .collect();

        for (rep_name, rep) in st["representations"].as_object().unwrap() {
            let ctx = format!("state {k}, {rep_name}");
            kd.set_representation(representation(rep_name));
            let state = RobotState {
                base_pose,
                joint_positions: q.clone(),
                base_velocity: v6(&vec_of(&st["base_velocity"][rep_name.as_str()])),
                joint_velocities: qd.clone(),
            };
            kd.set_state(&state).unwrap();

            // ---- representation-independent kinematics ----
            for (fname, pose) in st["poses"].as_object().unwrap() {
                let reference = pose_of(
                    &vec_of(&pose["position"]),
                    &vec_of(&pose["orientation_xyzw"]),
                );
                let got = kd.frame_pose(frame(fname));
                let c = format!("{ctx}, {fname}");
                report.compare(
                    "frame position",
                    &c,
                    got.translation.vector.as_slice(),
                    reference.translation.vector.as_slice(),
                );
                report.compare(
                    "frame rotation",
                    &c,
                    rotation_of(&got).as_slice(),
                    rotation_of(&reference).as_slice(),
                );
            }
            report.compare(
                "com position",
                &ctx,
                kd.com_position().as_slice(),
                &vec_of(&st["com_position"]),
            );
            report.compare(
                "com velocity",
                &ctx,
                kd.com_velocity().as_slice(),
                &vec_of(&st["com_velocity"]),
            );
            report.compare(
                "centroidal momentum",
                &ctx,
                kd.centroidal_momentum().as_slice(),
                &vec_of(&st["centroidal_momentum"]),
            );

            // ---- dynamics ----
            kd.mass_matrix(&mut mass).unwrap();
            let m_ref = sym_of_upper(&rep["mass_matrix_upper"]);
            report.compare(
                "mass matrix",
                &ctx,
                &order.square_from_model(&mass),
                &row_major(&m_ref),
            );
            kd.bias_forces(&mut vec_nv).unwrap();
            report.compare(
                "bias forces h",
                &ctx,
                &order.nu_from_model(&vec_nv),
                &vec_of(&rep["bias_forces"]),
            );
            kd.gravity_forces(&mut vec_nv).unwrap();
            report.compare(
                "gravity forces G",
                &ctx,
                &order.nu_from_model(&vec_nv),
                &vec_of(&rep["gravity_forces"]),
            );

            // ---- frames ----
            for (fname, fr) in rep["frames"].as_object().unwrap() {
                let id = frame(fname);
                let c = format!("{ctx}, {fname}");
                kd.frame_jacobian(id, &mut jac).unwrap();
                report.compare(
                    "frame jacobian",
                    &c,
                    &order.cols_from_model(&jac),
                    &row_major(&mat_of(&fr["jacobian"])),
                );
                report.compare(
                    "frame bias acceleration",
                    &c,
                    kd.frame_bias_acceleration(id).as_slice(),
                    &vec_of(&fr["bias_acceleration"]),
                );
                report.compare(
                    "frame velocity",
                    &c,
                    kd.frame_velocity(id).as_slice(),
                    &vec_of(&fr["velocity"]),
                );
            }

            // ---- CoM and centroidal ----
            kd.com_jacobian(&mut com_jac).unwrap();
            report.compare(
                "com jacobian",
                &ctx,
                &order.cols_from_model(&com_jac),
                &row_major(&mat_of(&rep["com_jacobian"])),
            );
            report.compare(
                "com bias acceleration",
                &ctx,
                kd.com_bias_acceleration().as_slice(),
                &vec_of(&rep["com_bias_acceleration"]),
            );
            kd.centroidal_momentum_matrix(&mut cmm).unwrap();
            report.compare(
                "centroidal momentum matrix",
                &ctx,
                &order.cols_from_model(&cmm),
                &row_major(&mat_of(&rep["centroidal_momentum_matrix"])),
            );
            report.compare(
                "centroidal momentum bias",
                &ctx,
                kd.centroidal_momentum_bias().as_slice(),
                &vec_of(&rep["centroidal_momentum_bias"]),
            );

            // ---- inverse dynamics with external wrenches ----
            kd.inverse_dynamics(&nu_dot, &wrenches, &mut vec_nv)
                .unwrap();
            report.compare(
                "inverse dynamics",
                &ctx,
                &order.nu_from_model(&vec_nv),
                &vec_of(&rep["inverse_dynamics"]),
            );

            // ---- forward dynamics (ABA) with external wrenches ----
            let mut acc = DVector::zeros(nv);
            kd.forward_dynamics(&tau, &wrenches, &mut acc).unwrap();
            if let Some(fd) = rep.get("forward_dynamics") {
                report.compare(
                    "forward dynamics",
                    &ctx,
                    &order.nu_from_model(&acc),
                    &vec_of(fd),
                );
            }
            // The equations of motion must hold for the computed acceleration: ID(FD(τ)) = [0; τ], relative to
            // the size of the terms M ν̇ that cancel (well defined even when M is badly conditioned).
            kd.inverse_dynamics(&acc, &wrenches, &mut vec_nv).unwrap();
            let mut expected = DVector::zeros(nv);
            expected.rows_mut(6, nv - 6).copy_from(&tau);
            let cancel_scale = mass.amax() * acc.amax();
            let residual = (&vec_nv - &expected).amax() / cancel_scale.max(1.0);
            report.compare("equations of motion residual", &ctx, &[residual], &[0.0]);
        }
    }
    report.finish();
}

#[test]
fn reference_stride_humanoid() {
    check_model("reference_stride_humanoid", "stride_humanoid");
}

#[test]
fn reference_icub_gazebo_v2_7() {
    check_model("reference_icub_gazebo_v2_7", "iCubGazeboV2_7");
}

#[test]
fn reference_icub_genova04() {
    check_model("reference_icub_genova04", "iCubGenova04");
}

#[test]
fn reference_icub_lisboa01() {
    check_model("reference_icub_lisboa01", "iCubLisboa01");
}

/// The fixtures themselves are consistent with the conventions the tests rely on: the three base velocities
/// of a state describe the same motion (mixed ↔ body ↔ inertial), so a wrong conversion in the generator
/// cannot hide behind a matching wrong conversion in stride.
#[test]
fn fixture_base_velocities_are_one_motion() {
    for name in [
        "stride_humanoid",
        "iCubGazeboV2_7",
        "iCubGenova04",
        "iCubLisboa01",
    ] {
        let fx = load_fixture(name);
        for st in fx["states"].as_array().unwrap() {
            let pose = pose_of(
                &vec_of(&st["base_position"]),
                &vec_of(&st["base_orientation_xyzw"]),
            );
            let r = rotation_of(&pose);
            let p = pose.translation.vector;
            let m = vec_of(&st["base_velocity"]["mixed"]);
            let b = vec_of(&st["base_velocity"]["body"]);
            let i = vec_of(&st["base_velocity"]["inertial"]);
            let (pdot, w) = (
                Vector3::new(m[0], m[1], m[2]),
                Vector3::new(m[3], m[4], m[5]),
            );
            let body_lin = r.transpose() * pdot;
            let body_ang = r.transpose() * w;
            let inertial_lin = pdot - w.cross(&p);
            for k in 0..3 {
                assert!(
                    (body_lin[k] - b[k]).abs() < 1e-10 && (body_ang[k] - b[3 + k]).abs() < 1e-10,
                    "{name} body"
                );
                assert!(
                    (inertial_lin[k] - i[k]).abs() < 1e-10 && (w[k] - i[3 + k]).abs() < 1e-10,
                    "{name} inertial"
                );
            }
        }
    }
}

/// The bundled humanoid is what docs/models.md says it is.
#[test]
fn bundled_humanoid_matches_its_documentation() {
    let path = manifest_dir().join("../../models/stride_humanoid.urdf");
    let model = Arc::new(Model::from_urdf_file(&path).unwrap());
    assert_eq!(model.root_link(), "root_link");
    assert_eq!(model.dof(), 32);
    assert!(
        (model.total_mass() - 32.8).abs() < 1e-9,
        "total mass {}",
        model.total_mass()
    );
    assert!(
        model.warnings().is_empty(),
        "warnings: {:?}",
        model.warnings()
    );
    let mut sensors: Vec<&str> = model.ft_sensors().iter().map(|s| s.name.as_str()).collect();
    sensors.sort_unstable();
    assert_eq!(
        sensors,
        [
            "l_foot_ft_sensor",
            "l_leg_ft_sensor",
            "r_foot_ft_sensor",
            "r_leg_ft_sensor"
        ]
    );
    for name in [
        "imu_frame",
        "head_imu",
        "l_hand_palm",
        "r_hand_palm",
        "l_sole",
        "r_sole",
    ] {
        assert!(model.frame_id(name).is_some(), "frame {name}");
    }
    let mut kd = KinDyn::new(Arc::clone(&model));
    let mut state = RobotState::zero(&model);
    state.base_pose = Isometry3::translation(0.0, 0.0, 0.6);
    kd.set_state(&state).unwrap();
    // zero configuration: soles flat on z = 0, aligned with the world, 0.15 m apart, 0.03 m ahead of the ankles
    let l = kd.frame_pose(model.frame_id("l_sole").unwrap());
    let r = kd.frame_pose(model.frame_id("r_sole").unwrap());
    for (sole, y) in [(l, 0.075), (r, -0.075)] {
        assert!(
            (sole.translation.vector - Vector3::new(0.03, y, 0.0)).norm() < 1e-12,
            "{sole}"
        );
        assert!(sole.rotation.angle() < 1e-12);
    }
    let top_of_head = kd.frame_pose(model.frame_id("head").unwrap()).translation.z + 0.05 + 0.06;
    assert!((top_of_head - 1.05).abs() < 1e-9, "height {top_of_head}");
    assert!(
        (kd.com_position().z - 0.560).abs() < 1e-3,
        "straight CoM height {}",
        kd.com_position().z
    );
    // knee-bent stance hip = a, knee = 2a, ankle = a keeps the soles flat; positive knee bends backwards
    let a = 0.4;
    for side in ["l", "r"] {
        state.joint_positions[model.joint_index(&format!("{side}_hip_pitch")).unwrap()] = a;
        state.joint_positions[model.joint_index(&format!("{side}_knee")).unwrap()] = 2.0 * a;
        state.joint_positions[model.joint_index(&format!("{side}_ankle_pitch")).unwrap()] = a;
    }
    kd.set_state(&state).unwrap();
    let l = kd.frame_pose(model.frame_id("l_sole").unwrap());
    let knee = kd.frame_pose(model.frame_id("l_lower_leg").unwrap());
    let hip = kd.frame_pose(model.frame_id("l_hip_1").unwrap());
    let ankle = kd.frame_pose(model.frame_id("l_ankle_1").unwrap());
    assert!(l.rotation.angle() < 1e-12, "sole stays flat");
    assert!(
        knee.translation.x > hip.translation.x && knee.translation.x > ankle.translation.x,
        "knee ahead"
    );
    let com_above_sole = kd.com_position().z - l.translation.z;
    assert!(
        (com_above_sole - 0.531).abs() < 1e-3,
        "bent CoM height {com_above_sole}"
    );
}
