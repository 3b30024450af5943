//! `stride calibrate LOG LOG LOG`: the feet sensors' calibration matrices [Traversaro 2017, (5.11)] from
//! three simulated pole runs (`configs/identify_ft_masses_{0,1,2}.toml`: bare, then 2.1 kg added to each foot
//! at two places; sensors with a calibration error `E` within ±5 %), compared with the simulator's `C`:
//! with the noise and drift off (the pipeline's own error: central-difference accelerations, the rotational
//! terms from the URDF's foot); at the default noise and drift, on every sensor seed of [`SEEDS`], within 1 %
//! with the offset as a random walk and not with it constant over each log (5.10); two logs refused
//! (Lemma 5.2); the added masses read
//! from the logs' `[sim.model]` edits equal the explicit form's; the written overlay, included in a walk on
//! the same sensors, brings the estimated foot wrenches closer to the truth.

mod common;

use std::path::PathBuf;

use common::{root, run_to_the_end, Scratch};
use stride_runner::calibrate_matrix::{
    calibrate_matrix_logs, AddedMassFile, KnownMass, LogMasses, MatrixLogs, MatrixReport,
    OffsetChoice,
};
use stride_runner::config::Scenario;
use stride_runner::run::{run_scenario, RunOptions};

/// The three pole runs, with `sensors` appended to each scenario (e.g. the sensors' noise and drift off).
fn pole_logs(s: &Scratch, tag: &str, sensors: &str) -> Vec<PathBuf> {
    (0..3)
        .map(|j| {
            let text = format!(
                "include = [{:?}]\n{sensors}",
                root()
                    .join(format!("configs/identify_ft_masses_{j}.toml"))
                    .display()
                    .to_string()
            );
            let scenario = Scenario::load(&s.write(&format!("{tag}{j}.toml"), &text)).unwrap();
            let duration = scenario.config.scenario.duration;
            run_to_the_end(s, &scenario, &format!("{tag}{j}"), duration)
        })
        .collect()
}

/// The sensors' noise and drift off (their offsets and calibration error kept), 20 s runs (the pipeline's
/// own error needs no more).
const QUIET: &str =
    "[scenario]\nduration = 20.0\n[sim.sensors.ft]\nforce_noise = 0.0\ntorque_noise = 0.0\n\
                     force_drift = 0.0\ntorque_drift = 0.0\n";

/// The masses of `configs/identify_ft_masses_{1,2}.toml` worked out by hand in the foot frames (the feet
/// sensors' frames): the foot's 0.7 kg at (0.03, 0, −0.03) m scaled by 4 and its centre moved by `d`, so
/// the added 2.1 kg sits at `(2.8 (c + d) − 0.7 c) / 2.1`.
fn explicit_masses() -> AddedMassFile {
    let added = |d: [f64; 3], side: f64, frame: &str| {
        let c = [0.03, 0.0, -0.03];
        let com: [f64; 3] = std::array::from_fn(|i| {
            let d = if i == 1 { side * d[i] } else { d[i] };
            (2.8 * (c[i] + d) - 0.7 * c[i]) / 2.1
        });
        KnownMass {
            frame: frame.into(),
            mass: 2.1,
            com,
        }
    };
    let both = |d: [f64; 3]| LogMasses {
        masses: vec![added(d, 1.0, "l_foot"), added(d, -1.0, "r_foot")],
    };
    AddedMassFile {
        log: vec![
            LogMasses::default(),
            both([-0.231, 0.0338, 0.2858]),
            both([-0.1313, -0.2093, 0.264]),
        ],
    }
}

/// Runs `configs/walk_straight.toml` on sensors with the pole runs' calibration error, with the overlay
/// `overlay` (text) included, for 8 s; the foot force error RMS \[N\].
/// The walk runs on the former 3·10⁷ N/m³ default ground (an explicit overlay): the claim that the matrices
/// improve the walk's foot forces was measured there. On the hard default floor (k 3·10⁸, since 2026-12-06)
/// they improve the torques (2.44 against 9.65 N·m RMS) but not the forces (16.5 against 15.2 N RMS, the
/// hard floor's impacts dominating the force error): re-measured 2026-12-06, not asserted, open.
fn walk_force_error(s: &Scratch, name: &str, overlay: &str) -> (f64, f64) {
    let calibration = s.write(&format!("{name}_overlay.toml"), overlay);
    let text = format!(
        "include = [{:?}, {:?}]\n[sim.sensors.ft]\ncalibration_error = 0.05\n\
         [sim.contact]\nnormal_stiffness = 3.0e7\nnormal_damping = 3.0e5\n\
         tangential_stiffness = 3.0e7\ntangential_damping = 3.0e5\n",
        root()
            .join("configs/walk_straight.toml")
            .display()
            .to_string(),
        calibration.display().to_string()
    );
    let scenario = Scenario::load(&s.write(&format!("{name}.toml"), &text)).unwrap();
    let options = RunOptions {
        duration: Some(8.0),
        ..RunOptions::default()
    };
    let summary = run_scenario(&scenario, &options).unwrap();
    let e = &summary.estimation;
    (e.foot_force_error.rms, e.foot_torque_error.rms)
}

/// Both feet matrices within `bound` (relative Frobenius), the true `C` far from identity, the foot's mass.
fn check_matrices(report: &MatrixReport, bound: f64) {
    let names: Vec<&str> = report.sensors.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["l_foot_ft_sensor", "r_foot_ft_sensor"]);
    for c in &report.sensors {
        let error = c.relative_error().expect("simulated");
        assert!(error < bound, "{}: ‖Ĉ − C‖_F / ‖C‖_F = {error}", c.name);
        // The true C is off identity by far more than the estimate is off C.
        let truth = c.truth.unwrap();
        let off = (truth - nalgebra::Matrix6::identity()).norm() / truth.norm();
        assert!(off > 5.0 * error, "{}: C off identity by {off}", c.name);
        // The foot: 0.7 kg, first moment 0.7 (0.03, 0, −0.03) kg m in the sensor frame.
        assert!(
            (c.fit.mass - 0.7).abs() < 0.02,
            "{}: mass {}",
            c.name,
            c.fit.mass
        );
    }
}

#[test]
fn feet_calibration_matrices_from_three_logs_and_the_walk_they_improve() {
    let s = Scratch::new("calibrate_matrix");
    let logs = pole_logs(&s, "quiet", QUIET);

    // Noise and drift off: the pipeline's own error (0.14 % when measured; docs/identification.md).
    let report = calibrate_matrix_logs(&logs, None, None, OffsetChoice::DriftFromLog).unwrap();
    check_matrices(&report, 0.003);
    // The masses and first moments read from the logged edits are the hand-worked ones. (The edits also
    // scale the foot's rotational inertia, which the point masses of the explicit form lack: in these fast
    // swings the rotational terms then differ by enough that the explicit form's C is off by ~4 %, so only
    // the masses are compared here.)
    let explicit = calibrate_matrix_logs(
        &logs,
        None,
        Some(&explicit_masses()),
        OffsetChoice::DriftFromLog,
    )
    .unwrap();
    for (a, b) in report.sensors.iter().zip(&explicit.sensors) {
        for (pa, pb) in a.added.iter().zip(&b.added) {
            let d = (pa.fixed_rows::<4>(0) - pb.fixed_rows::<4>(0)).norm();
            assert!(d < 1e-12, "{}: {pa} vs {pb}", a.name);
        }
    }

    // Two logs: refused before solving (Lemma 5.2), naming the sensor and the lemma.
    let err = calibrate_matrix_logs(&logs[..2], None, None, OffsetChoice::DriftFromLog)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("l_foot_ft_sensor") && err.contains("Lemma 5.2") && err.contains("rank 36"),
        "{err}"
    );
    // A leg sensor's child side moves: refused by name.
    let err = calibrate_matrix_logs(
        &logs,
        Some("l_leg_ft_sensor"),
        None,
        OffsetChoice::DriftFromLog,
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("rigid body"), "{err}");

    // The overlay: with the matrices the estimated foot wrenches match the truth better than with the same
    // offsets alone.
    let (force_with, torque_with) = walk_force_error(&s, "with", &report.to_toml(&logs));
    let (force_without, torque_without) = walk_force_error(&s, "without", &report.offsets_toml());
    eprintln!(
        "foot force error RMS: {force_with:.3} N with C, {force_without:.3} N without; torque \
         {torque_with:.4} / {torque_without:.4} N m"
    );
    assert!(
        force_with < 0.8 * force_without,
        "force {force_with} vs {force_without}"
    );
    assert!(
        torque_with < torque_without,
        "torque {torque_with} vs {torque_without}"
    );
}

/// The sensor seeds (`[sim.sensors] seed`: each draws its own `C`, offsets, noise and drift) of the
/// default-noise test.
const SEEDS: [u64; 5] = [0, 1, 2, 3, 4];

/// Held while a thread reads its logs.
static READING: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Both feet's `‖Ĉ − C‖_F / ‖C‖_F` on one seed's three 40 s logs: with the offset as a random walk (and
/// [`check_matrices`] within 1 %), then constant over each log on the same logs (seed 0: two logs refused,
/// Lemma 5.2). The logs are deleted.
fn seed_errors(s: &Scratch, seed: u64) -> ([f64; 2], [f64; 2]) {
    let logs = pole_logs(
        s,
        &format!("seed{seed}_"),
        &format!("[sim.sensors]\nseed = {seed}\n"),
    );
    // One thread reads at a time: `read_log` holds a whole 40 s log in memory.
    let read = {
        let _one_at_a_time = READING.lock().unwrap_or_else(|e| e.into_inner());
        MatrixLogs::read(&logs).unwrap()
    };
    let drift = read
        .calibrate(None, None, OffsetChoice::DriftFromLog)
        .unwrap();
    assert!(matches!(
        drift.offsets,
        stride_estimation::calibration::OffsetModel::RandomWalk(_)
    ));
    let constant = read.calibrate(None, None, OffsetChoice::Constant).unwrap();
    if seed == 0 {
        // Two logs are still refused (Lemma 5.2).
        let err = calibrate_matrix_logs(&logs[..2], None, None, OffsetChoice::DriftFromLog)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("Lemma 5.2") && err.contains("rank 36"),
            "{err}"
        );
    }
    for log in &logs {
        std::fs::remove_file(log).unwrap();
    }
    let errors = |r: &MatrixReport| -> [f64; 2] {
        std::array::from_fn(|i| r.sensors[i].relative_error().expect("simulated"))
    };
    eprintln!(
        "seed {seed}: random walk {:?}, constant {:?}",
        errors(&drift),
        errors(&constant)
    );
    check_matrices(&drift, 0.01);
    (errors(&drift), errors(&constant))
}

/// Issue 19: at the default sensor noise and drift, on every seed of [`SEEDS`], the three 40 s logs give
/// both feet's `C` within 1 % with the offset as a random walk (the logged `[sim.sensors.ft]` figures;
/// measured: worst 0.904 %, seed 2's right foot). The other side, on the same logs: with the offset
/// constant over each log, as in (5.10), the worst matrix is beyond 1.2 % (measured 1.454 %, seed 0's right
/// foot) and the root mean square of the ten errors is above 1.2× the random walk's (measured 1.33×);
/// without the drift model both would be the random walk's own. docs/identification.md, "Calibration
/// matrix from logs", has the table. The seeds run on two threads.
#[test]
fn at_the_default_noise_and_drift_every_seed_is_within_one_percent_with_the_drift_model() {
    let s = Scratch::new("calibrate_matrix_drift");
    let (even, odd): (Vec<u64>, Vec<u64>) = SEEDS.iter().partition(|k| *k % 2 == 0);
    let results: Vec<([f64; 2], [f64; 2])> = std::thread::scope(|scope| {
        let s = &s;
        let other = scope.spawn(move || odd.iter().map(|k| seed_errors(s, *k)).collect::<Vec<_>>());
        let mut out: Vec<_> = even.iter().map(|k| seed_errors(s, *k)).collect();
        out.extend(other.join().unwrap());
        out
    });
    // Every foot's error with each offset model: (random walk, constant).
    let (drift, constant): (Vec<f64>, Vec<f64>) = results
        .iter()
        .flat_map(|(d, c)| d.iter().copied().zip(c.iter().copied()))
        .unzip();
    let worst = |e: &[f64]| e.iter().copied().fold(0.0, f64::max);
    let rms = |e: &[f64]| (e.iter().map(|v| v * v).sum::<f64>() / e.len() as f64).sqrt();
    let (drift_worst, constant_worst) = (worst(&drift), worst(&constant));
    let ratio = rms(&constant) / rms(&drift);
    eprintln!("worst: random walk {drift_worst}, constant {constant_worst}; RMS ratio {ratio}");
    assert!(drift_worst < 0.01, "random walk: worst {drift_worst}");
    assert!(
        constant_worst > 0.012,
        "constant offset: worst {constant_worst} (the drift model is not needed?)"
    );
    assert!(ratio > 1.2, "constant / random walk RMS {ratio}");
}
