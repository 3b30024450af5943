mod common;
use std::sync::Arc;
use common::*;
use stride_block::Block;
use stride_model::{KinDyn, VelocityRepresentation};
use stride_wbc::{IkConfig, QpIk, Tsid, TsidConfig, IkFeedback};
#[test]
fn dbg() {
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let mut input = references_at(&model, &state);
    input.com_position.x += 0.01;
    input.desired_zmp = Some(nalgebra::Vector2::new(input.com_position.x, 0.0));
    let mut c = IkConfig::default_for_bundled_model(); c.feedback = IkFeedback::Measured;
    let mut ik = QpIk::new(Arc::clone(&model), c).unwrap();
    let mut tsid = Tsid::new(Arc::clone(&model), TsidConfig::default_for_bundled_model()).unwrap();
    for _ in 0..100 { ik.step(&input).unwrap(); tsid.step(&input).unwrap(); }
    let (mut s, mut t, mut it) = (0.0, 0.0, 0);
    for _ in 0..1000 { let o = ik.step(&input).unwrap(); s += o.report.solve_time; t += o.report.tick_time; it += o.report.iterations; }
    eprintln!("IK solve {:.1} us tick {:.1} us iters {}", s * 1e3, t * 1e3, it as f64 / 1000.0);
    let (mut s, mut t, mut it) = (0.0, 0.0, 0);
    for _ in 0..1000 { let o = tsid.step(&input).unwrap(); s += o.report.solve_time; t += o.report.tick_time; it += o.report.iterations; }
    eprintln!("TSID solve {:.1} us tick {:.1} us iters {}", s * 1e3, t * 1e3, it as f64 / 1000.0);
    let mut kd = KinDyn::new(Arc::clone(&model)); kd.set_representation(VelocityRepresentation::Mixed);
    let mut m = nalgebra::DMatrix::zeros(model.nv(), model.nv()); let mut h = nalgebra::DVector::zeros(model.nv());
    let mut j = nalgebra::DMatrix::zeros(6, model.nv()); let mut jc = nalgebra::DMatrix::zeros(3, model.nv());
    let f = model.frame_id("l_sole").unwrap();
    let n = 1000;
    let t0 = std::time::Instant::now(); for _ in 0..n { kd.set_state(&state).unwrap(); } let a = t0.elapsed().as_secs_f64()/n as f64*1e6;
    let t0 = std::time::Instant::now(); for _ in 0..n { kd.mass_matrix(&mut m).unwrap(); } let b = t0.elapsed().as_secs_f64()/n as f64*1e6;
    let t0 = std::time::Instant::now(); for _ in 0..n { kd.bias_forces(&mut h).unwrap(); } let c = t0.elapsed().as_secs_f64()/n as f64*1e6;
    let t0 = std::time::Instant::now(); for _ in 0..n { kd.frame_jacobian(f, &mut j).unwrap(); } let d = t0.elapsed().as_secs_f64()/n as f64*1e6;
    let t0 = std::time::Instant::now(); for _ in 0..n { kd.com_jacobian(&mut jc).unwrap(); } let e = t0.elapsed().as_secs_f64()/n as f64*1e6;
    let t0 = std::time::Instant::now(); for _ in 0..n { std::hint::black_box(kd.frame_bias_acceleration(f)); } let g = t0.elapsed().as_secs_f64()/n as f64*1e6;
    eprintln!("set_state {a:.1} M {b:.1} h {c:.1} J {d:.1} Jcom {e:.1} bias {g:.1} us");
}
#[test]
fn dbg2() {
    use stride_qp::{ActiveSetSolver, ActiveSetSettings, QpSolver, SolverOutput};
    let model = bundled_model();
    let state = standing_state(&model, &default_posture(&model));
    let mut input = references_at(&model, &state);
    input.com_position.x += 0.01;
    let mut c = IkConfig::default_for_bundled_model(); c.feedback = IkFeedback::Measured;
    let mut ik = QpIk::new(Arc::clone(&model), c).unwrap();
    let mut tsid = Tsid::new(Arc::clone(&model), TsidConfig::default_for_bundled_model()).unwrap();
    ik.step(&input).unwrap(); tsid.step(&input).unwrap();
    for (name, qp) in [("ik", ik.qp_problem().dense_qp().clone()), ("tsid", tsid.qp_problem().unwrap().dense_qp().clone())] {
        let mut s = ActiveSetSolver::new(ActiveSetSettings::default());
        let mut out = SolverOutput::new(&qp);
        s.solve(&qp, &mut out);
        let n = 300;
        let t0 = std::time::Instant::now(); for _ in 0..n { s.solve(&qp, &mut out); } let warm = t0.elapsed().as_secs_f64()/n as f64*1e6;
        let mut s2 = ActiveSetSolver::new(ActiveSetSettings { warm_start: false, ..Default::default() });
        let t0 = std::time::Instant::now(); for _ in 0..n { s2.solve(&qp, &mut out); } let cold = t0.elapsed().as_secs_f64()/n as f64*1e6;
        eprintln!("{name}: n {} eq {} ineq {} warm {warm:.1} us cold {cold:.1} us iters {}", qp.n(), qp.n_eq(), qp.n_ineq(), out.iterations);
    }
}
