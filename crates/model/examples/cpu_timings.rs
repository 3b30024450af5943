//! Per-call time of the main algorithms on the states of the reference fixtures, by the protocol
//! `tools/bench/pinocchio_bench.cpp` applies to Pinocchio, so that the two sides of
//! `tools/bench/vs-pinocchio` time the same states with the same statistic:
//!
//! - states: the 20 states of `crates/model/tests/fixtures/<model>.json` (joints mapped by name; base
//!   velocity in the representation timed, mixed by default; `nu_dot` and `joint_torques` as the inputs of
//!   RNEA and ABA), cycled through in order;
//! - one untimed warm-up pass of `calls / 10` calls, then `rounds` rounds of `calls` calls each;
//! - per round, the wall-clock time (monotonic clock) and the thread's CPU time
//!   ([`stride_testkit::thread_cpu_time`], `CLOCK_THREAD_CPUTIME_ID`: time on a CPU, which preemption by
//!   other processes does not inflate) divided by `calls`; the figure printed for each clock is its best
//!   (smallest) round.
//!
//! Every timed call starts with `KinDyn::set_state` (forward kinematics, velocities, world inertias), as
//! each Pinocchio algorithm starts with its own forward pass.
//!
//! ```text
//! cargo run --release -p stride-model --example cpu_timings -- [--calls N] [--rounds R] [--body] [MODEL ...]
//! ```
//!
//! MODEL is a fixture name (default: `stride_humanoid` and, when `STRIDE_ICUB_MODELS_DIR` is set,
//! `iCubGazeboV2_7`); `--body` times the body representation (Pinocchio's) instead of the mixed one.
//! Output, one line per algorithm: `<model>/<algorithm> <wall µs> <cpu µs>` (the format of
//! `pinocchio_bench`), with a header per model on standard error.

use std::error::Error;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use nalgebra::{DMatrix, DVector, Isometry3, Quaternion, Translation3, UnitQuaternion, Vector6};
use serde_json::Value;
use stride_model::{FrameId, KinDyn, Model, RobotState, VelocityRepresentation};

type Result<T> = std::result::Result<T, Box<dyn Error>>;

/// Options of one run.
struct Options {
    calls: usize,
    rounds: usize,
    representation: VelocityRepresentation,
    models: Vec<String>,
}

/// One fixture state: the robot state and the inputs of RNEA (`nu_dot`) and ABA (`tau`).
struct Sample {
    state: RobotState,
    nu_dot: DVector<f64>,
    tau: DVector<f64>,
}

/// The thread's CPU time (ns).
fn thread_cpu_ns() -> Result<u128> {
    Ok(stride_testkit::thread_cpu_time()
        .ok_or("no thread CPU time clock (CLOCK_THREAD_CPUTIME_ID)")?
        .as_nanos())
}

/// Best round's (wall, CPU) µs per call of `f`, by the protocol of the module documentation.
fn time<F: FnMut(usize)>(opts: &Options, states: usize, mut f: F) -> Result<(f64, f64)> {
    for k in 0..opts.calls / 10 {
        f(k % states);
    }
    let (mut wall, mut cpu) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..opts.rounds {
        let (c0, w0) = (thread_cpu_ns()?, Instant::now());
        for k in 0..opts.calls {
            f(k % states);
        }
        let w = w0.elapsed().as_nanos() as f64;
        let c = thread_cpu_ns()?.saturating_sub(c0) as f64;
        wall = wall.min(w / opts.calls as f64 / 1e3);
        cpu = cpu.min(c / opts.calls as f64 / 1e3);
    }
    Ok((wall, cpu))
}

fn numbers(v: &Value, what: &str) -> Result<Vec<f64>> {
    v.as_array()
        .ok_or_else(|| format!("{what}: not an array"))?
        .iter()
        .map(|x| {
            x.as_f64()
                .ok_or_else(|| format!("{what}: not a number").into())
        })
        .collect()
}

fn fixture(name: &str) -> Result<Value> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(format!("{name}.json"));
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(serde_json::from_str(&text)?)
}

/// The URDF of a fixture: in the repository, or `$STRIDE_ICUB_MODELS_DIR/<icub_model>/model.urdf`.
fn urdf_of(fx: &Value) -> Result<PathBuf> {
    if let Some(rel) = fx["urdf"].as_str() {
        return Ok(Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../..")
            .join(rel));
    }
    let icub = fx["icub_model"]
        .as_str()
        .ok_or("fixture has neither urdf nor icub_model")?;
    let dir = std::env::var_os("STRIDE_ICUB_MODELS_DIR")
        .ok_or_else(|| format!("{icub}: STRIDE_ICUB_MODELS_DIR is not set"))?;
    Ok(PathBuf::from(dir).join(icub).join("model.urdf"))
}

/// The fixture's states in the model's joint order, base velocity in `rep`.
fn samples(model: &Model, fx: &Value, rep: VelocityRepresentation) -> Result<Vec<Sample>> {
    let names = fx["joint_names"].as_array().ok_or("joint_names")?;
    let index: Vec<usize> = names
        .iter()
        .map(|n| {
            let n = n.as_str().unwrap_or("");
            model
                .joint_index(n)
                .ok_or_else(|| format!("no joint {n}").into())
        })
        .collect::<Result<_>>()?;
    let rep_key = match rep {
        VelocityRepresentation::Body => "body",
        VelocityRepresentation::Inertial => "inertial",
        VelocityRepresentation::Mixed => "mixed",
    };
    let by_name = |xs: &[f64]| {
        let mut out = DVector::zeros(model.dof());
        for (&j, &x) in index.iter().zip(xs) {
            out[j] = x;
        }
        out
    };
    let states = fx["states"].as_array().ok_or("states")?;
    states
        .iter()
        .map(|st| {
            let p = numbers(&st["base_position"], "base_position")?;
            let o = numbers(&st["base_orientation_xyzw"], "base_orientation_xyzw")?;
            let nu_dot = numbers(&st["nu_dot"], "nu_dot")?;
            let rotation = UnitQuaternion::from_quaternion(Quaternion::new(o[3], o[0], o[1], o[2]));
            let mut nu_dot_model = DVector::zeros(model.nv());
            nu_dot_model.rows_mut(0, 6).copy_from_slice(&nu_dot[..6]);
            nu_dot_model
                .rows_mut(6, model.dof())
                .copy_from(&by_name(&nu_dot[6..]));
            Ok(Sample {
                state: RobotState {
                    base_pose: Isometry3::from_parts(Translation3::new(p[0], p[1], p[2]), rotation),
                    joint_positions: by_name(&numbers(&st["joint_positions"], "joint_positions")?),
                    base_velocity: Vector6::from_column_slice(&numbers(
                        &st["base_velocity"][rep_key],
                        "base_velocity",
                    )?),
                    joint_velocities: by_name(&numbers(
                        &st["joint_velocities"],
                        "joint_velocities",
                    )?),
                },
                nu_dot: nu_dot_model,
                tau: by_name(&numbers(&st["joint_torques"], "joint_torques")?),
            })
        })
        .collect()
}

/// Times every algorithm on the fixture `name` and prints one line per algorithm.
fn run(name: &str, opts: &Options) -> Result<()> {
    let fx = fixture(name)?;
    let path = urdf_of(&fx)?;
    let model =
        Arc::new(Model::from_urdf_file(&path).map_err(|e| format!("{}: {e}", path.display()))?);
    let st = samples(&model, &fx, opts.representation)?;
    eprintln!(
        "cpu_timings: {name} ({} DoF, {} frames, {} states, {:?} representation, {} calls x {} rounds)",
        model.dof(),
        model.frames().len(),
        st.len(),
        opts.representation,
        opts.calls,
        opts.rounds
    );
    let nv = model.nv();
    let mut kd = KinDyn::new(Arc::clone(&model));
    kd.set_representation(opts.representation);
    let frames: Vec<FrameId> = model
        .frames()
        .iter()
        .map(|f| model.frame_id(&f.name).ok_or("frame"))
        .collect::<std::result::Result<_, _>>()?;
    let links: Vec<FrameId> = model
        .bodies()
        .iter()
        .map(|b| model.frame_id(&b.name).ok_or("body frame"))
        .collect::<std::result::Result<_, _>>()?;
    let mut jac = DMatrix::zeros(6, nv);
    let mut mass = DMatrix::zeros(nv, nv);
    let mut cmm = DMatrix::zeros(6, nv);
    let mut out = DVector::zeros(nv);
    let mut sink = 0.0;
    // Every state was validated by one set_state before the timings: the unwraps below cannot fire.
    for s in &st {
        kd.set_state(&s.state)?;
    }
    let n = st.len();
    let report = |algo: &str, t: (f64, f64)| println!("{name}/{algo} {:.4} {:.4}", t.0, t.1);
    report(
        "set_state",
        time(opts, n, |k| kd.set_state(&st[k].state).unwrap())?,
    );
    report(
        "fk",
        time(opts, n, |k| {
            kd.set_state(&st[k].state).unwrap();
            for &f in &frames {
                sink += kd.frame_rotation_translation(f).1.x;
            }
        })?,
    );
    report(
        "jacobians",
        time(opts, n, |k| {
            kd.set_state(&st[k].state).unwrap();
            kd.joint_jacobians(&mut jac).unwrap();
            sink += jac[(0, nv - 1)];
        })?,
    );
    report(
        "link_jacobians",
        time(opts, n, |k| {
            kd.set_state(&st[k].state).unwrap();
            for &f in &links {
                kd.frame_jacobian(f, &mut jac).unwrap();
                sink += jac[(0, 0)];
            }
        })?,
    );
    report(
        "crba",
        time(opts, n, |k| {
            kd.set_state(&st[k].state).unwrap();
            kd.mass_matrix(&mut mass).unwrap();
            sink += mass[(0, 0)];
        })?,
    );
    report(
        "rnea",
        time(opts, n, |k| {
            kd.set_state(&st[k].state).unwrap();
            kd.inverse_dynamics(&st[k].nu_dot, &[], &mut out).unwrap();
            sink += out[0];
        })?,
    );
    report(
        "aba",
        time(opts, n, |k| {
            kd.set_state(&st[k].state).unwrap();
            kd.forward_dynamics(&st[k].tau, &[], &mut out).unwrap();
            sink += out[0];
        })?,
    );
    report(
        "cmm",
        time(opts, n, |k| {
            kd.set_state(&st[k].state).unwrap();
            kd.centroidal_momentum_matrix(&mut cmm).unwrap();
            sink += cmm[(0, 0)];
        })?,
    );
    eprintln!("cpu_timings: {name} (checksum {sink:e})");
    Ok(())
}

fn options() -> Result<Options> {
    let mut opts = Options {
        calls: 20000,
        rounds: 7,
        representation: VelocityRepresentation::Mixed,
        models: Vec::new(),
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--calls" => opts.calls = args.next().ok_or("--calls N")?.parse()?,
            "--rounds" => opts.rounds = args.next().ok_or("--rounds R")?.parse()?,
            "--body" => opts.representation = VelocityRepresentation::Body,
            _ if a.starts_with("--") => return Err(format!("unknown option {a}").into()),
            _ => opts.models.push(a),
        }
    }
    if opts.calls == 0 || opts.rounds == 0 {
        return Err("--calls and --rounds must be positive".into());
    }
    if opts.models.is_empty() {
        opts.models.push("stride_humanoid".into());
        if std::env::var_os("STRIDE_ICUB_MODELS_DIR").is_some() {
            opts.models.push("iCubGazeboV2_7".into());
        }
    }
    Ok(opts)
}

fn main() -> Result<()> {
    let opts = options()?;
    for name in &opts.models {
        run(name, &opts)?;
    }
    Ok(())
}
