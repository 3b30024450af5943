use std::sync::Arc;
use std::time::Instant;
use nalgebra::{DMatrix, DVector};
use stride_block::Block;
use stride_model::{KinDyn, Model, RobotState};
use stride_sim::{SimConfig, SimInput, SimRobot, cholesky_in_place, cholesky_solve_in_place};
fn main() {
    let model = Arc::new(Model::from_urdf_file("models/stride_humanoid.urdf").unwrap());
    let mut q = DVector::zeros(model.dof());
    for (n, v) in [("l_hip_pitch", 0.2), ("r_hip_pitch", 0.2), ("l_knee", 0.4), ("r_knee", 0.4), ("l_ankle_pitch", 0.2), ("r_ankle_pitch", 0.2)] { q[model.joint_index(n).unwrap()] = v; }
    let mut kd = KinDyn::new(Arc::clone(&model));
    let mut st = RobotState::zero(&model); st.joint_positions.copy_from(&q);
    st.joint_velocities.fill(0.1);
    let nv = model.nv();
    let mut m = DMatrix::zeros(nv, nv); let mut h = DVector::zeros(nv); let mut j = DMatrix::zeros(6, nv);
    let f = model.frame_id("l_sole").unwrap();
    let n = 20000;
    let t = |name: &str, k: &mut dyn FnMut()| { let s = Instant::now(); for _ in 0..n { k(); } println!("{name}: {:.2} us", s.elapsed().as_secs_f64() * 1e6 / n as f64); };
    t("set_state", &mut || kd.set_state(&st).unwrap());
    t("mass", &mut || kd.mass_matrix(&mut m).unwrap());
    t("bias", &mut || kd.bias_forces(&mut h).unwrap());
    t("jac", &mut || kd.frame_jacobian(f, &mut j).unwrap());
    t("pose", &mut || { std::hint::black_box(kd.frame_pose(f)); });
    t("vel", &mut || { std::hint::black_box(kd.frame_velocity(f)); });
    let mut a = m.clone(); for i in 0..nv { a[(i,i)] += 1.0; }
    let mut l = a.clone(); let mut x = h.clone();
    t("chol", &mut || { l.copy_from(&a); cholesky_in_place(&mut l); x.copy_from(&h); cholesky_solve_in_place(&l, &mut x); });
    let tau = DVector::zeros(model.dof()); let mut acc = DVector::zeros(nv);
    t("aba", &mut || kd.forward_dynamics(&tau, &[], &mut acc).unwrap());
    let mut st2 = st.clone();
    t("integrate", &mut || st2.integrate(&model, stride_model::VelocityRepresentation::Mixed, 1e-4).unwrap());
    let mut sim = SimRobot::new(Arc::clone(&model), SimConfig::default()).unwrap();
    sim.set_standing_on_ground(&q).unwrap();
    let input = SimInput::hold(&q);
    for _ in 0..1000 { sim.step(&input).unwrap(); }
    t("step", &mut || { sim.step(&input).unwrap(); });
}
