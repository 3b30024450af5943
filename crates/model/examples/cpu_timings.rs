//! Per-call CPU time of the main algorithms, measured with the thread's own CPU time
//! (`/proc/thread-self/schedstat`, Linux) so that the figures hold on a loaded machine, where wall-clock
//! benchmarks are inflated by preemption. Complements `cargo bench -p stride-model`.
//!
//! `cargo run --release -p stride-model --example cpu_timings [URDF ...]` (default: the bundled humanoid and,
//! with `STRIDE_ICUB_MODELS_DIR`, iCubGazeboV2_7).

use std::path::PathBuf;
use std::sync::Arc;

use nalgebra::{DMatrix, DVector, Isometry3, Translation3, UnitQuaternion, Vector3, Vector6};
use stride_model::{FrameId, KinDyn, Model, RobotState};

fn thread_cpu_ns() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    text.split_whitespace().next()?.parse().ok()
}

/// Deterministic pseudo-random numbers in [-1, 1] (no extra dependency).
fn lcg(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

fn states(model: &Model) -> Vec<RobotState> {
    let mut seed = 7u64;
    let n = model.dof();
    (0..100)
        .map(|_| RobotState {
            base_pose: Isometry3::from_parts(
                Translation3::new(lcg(&mut seed), lcg(&mut seed), 0.6),
                UnitQuaternion::from_scaled_axis(Vector3::new(
                    lcg(&mut seed),
                    lcg(&mut seed),
                    lcg(&mut seed),
                )),
            ),
            joint_positions: DVector::from_fn(n, |_, _| lcg(&mut seed)),
            base_velocity: Vector6::from_fn(|_, _| lcg(&mut seed)),
            joint_velocities: DVector::from_fn(n, |_, _| lcg(&mut seed)),
        })
        .collect()
}

fn time<F: FnMut(usize)>(label: &str, calls: usize, mut f: F) {
    // Best of 5 rounds.
    let mut best = f64::INFINITY;
    for _ in 0..5 {
        let (Some(t0), wall0) = (thread_cpu_ns(), std::time::Instant::now()) else {
            eprintln!("no /proc/thread-self/schedstat: cannot measure CPU time");
            return;
        };
        for k in 0..calls {
            f(k % 100);
        }
        let t1 = thread_cpu_ns().unwrap_or(t0);
        let _ = wall0;
        best = best.min((t1 - t0) as f64 / calls as f64 / 1000.0);
    }
    println!("{label:<40} {best:8.2} µs");
}

fn run(path: PathBuf) {
    let model = match Model::from_urdf_file(&path) {
        Ok(m) => Arc::new(m),
        Err(e) => {
            eprintln!("{}: {e}", path.display());
            return;
        }
    };
    println!(
        "{} ({} DoF, {} frames)",
        model.name(),
        model.dof(),
        model.frames().len()
    );
    let nv = model.nv();
    let st = states(&model);
    let mut kd = KinDyn::new(Arc::clone(&model));
    let frames: Vec<FrameId> = model
        .frames()
        .iter()
        .map(|f| model.frame_id(&f.name).expect("frame"))
        .collect();
    let links: Vec<FrameId> = model
        .bodies()
        .iter()
        .map(|b| model.frame_id(&b.name).expect("frame"))
        .collect();
    let mut jac = DMatrix::zeros(6, nv);
    let mut mass = DMatrix::zeros(nv, nv);
    let mut cmm = DMatrix::zeros(6, nv);
    let mut out = DVector::zeros(nv);
    let nu_dot = DVector::from_fn(nv, |k, _| (k % 7) as f64 * 0.1 - 0.3);
    let tau = DVector::from_fn(nv - 6, |k, _| (k % 5) as f64 - 2.0);
    let calls = 20000;
    let mut sink = 0.0;
    time("set_state (FK + velocities)", calls, |k| {
        kd.set_state(&st[k]).unwrap()
    });
    time("forward kinematics, all frames", calls, |k| {
        kd.set_state(&st[k]).unwrap();
        for &f in &frames {
            sink += kd.frame_rotation_translation(f).1.x;
        }
    });
    time("all link Jacobians", calls, |k| {
        kd.set_state(&st[k]).unwrap();
        for &f in &links {
            kd.frame_jacobian(f, &mut jac).unwrap();
        }
        sink += jac[(0, 0)];
    });
    time("CRBA (mass matrix)", calls, |k| {
        kd.set_state(&st[k]).unwrap();
        kd.mass_matrix(&mut mass).unwrap();
        sink += mass[(0, 0)];
    });
    time("RNEA (inverse dynamics)", calls, |k| {
        kd.set_state(&st[k]).unwrap();
        kd.inverse_dynamics(&nu_dot, &[], &mut out).unwrap();
        sink += out[0];
    });
    time("ABA (forward dynamics)", calls, |k| {
        kd.set_state(&st[k]).unwrap();
        kd.forward_dynamics(&tau, &[], &mut out).unwrap();
        sink += out[0];
    });
    time("CMM (centroidal momentum matrix)", calls, |k| {
        kd.set_state(&st[k]).unwrap();
        kd.centroidal_momentum_matrix(&mut cmm).unwrap();
        sink += cmm[(0, 0)];
    });
    if !sink.is_finite() {
        println!("(non-finite sink)");
    }
}

fn main() {
    let args: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    if !args.is_empty() {
        args.into_iter().for_each(run);
        return;
    }
    run(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../models/stride_humanoid.urdf"));
    if let Some(dir) = std::env::var_os("STRIDE_ICUB_MODELS_DIR") {
        run(PathBuf::from(dir).join("iCubGazeboV2_7/model.urdf"));
    }
}
