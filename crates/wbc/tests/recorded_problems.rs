//! Cross-solver agreement on QPs recorded from the controllers (JSON fixtures in tests/fixtures).
//!
//! `cargo test -p stride-wbc --test recorded_problems -- --ignored record` rewrites the fixtures.

mod common;

use std::path::PathBuf;
use std::sync::Arc;

use common::*;
use nalgebra::{DMatrix, DVector, Vector2};
use serde::{Deserialize, Serialize};
use stride_qp::{
    check_kkt, ActiveSetSettings, ActiveSetSolver, ClarabelSettings, ClarabelSolver, DenseQp,
    QpSolver, QpStatus, SolverOutput,
};
use stride_wbc::{IkConfig, QpIk, Tsid, TsidConfig};

/// A dense QP as JSON: matrices as rows; infinite sides as `null`.
#[derive(Serialize, Deserialize)]
struct Fixture {
    name: String,
    n: usize,
    hessian: Vec<Vec<f64>>,
    gradient: Vec<f64>,
    eq_matrix: Vec<Vec<f64>>,
    eq_rhs: Vec<f64>,
    ineq_matrix: Vec<Vec<f64>>,
    ineq_lower: Vec<Option<f64>>,
    ineq_upper: Vec<Option<f64>>,
    lower_bounds: Vec<Option<f64>>,
    upper_bounds: Vec<Option<f64>>,
}

fn rows<S: nalgebra::storage::Storage<f64, nalgebra::Dyn, nalgebra::Dyn>>(
    m: &nalgebra::Matrix<f64, nalgebra::Dyn, nalgebra::Dyn, S>,
) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|i| m.row(i).iter().copied().collect())
        .collect()
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

impl Fixture {
    fn from_qp(name: &str, qp: &DenseQp) -> Self {
        Fixture {
            name: name.to_owned(),
            n: qp.n(),
            hessian: rows(qp.hessian()),
            gradient: qp.gradient().iter().copied().collect(),
            eq_matrix: rows(&qp.eq_matrix()),
            eq_rhs: qp.eq_rhs().iter().copied().collect(),
            ineq_matrix: rows(&qp.ineq_matrix()),
            ineq_lower: qp.ineq_lower().iter().map(|v| finite(*v)).collect(),
            ineq_upper: qp.ineq_upper().iter().map(|v| finite(*v)).collect(),
            lower_bounds: qp.lower_bounds().iter().map(|v| finite(*v)).collect(),
            upper_bounds: qp.upper_bounds().iter().map(|v| finite(*v)).collect(),
        }
    }

    fn to_qp(&self) -> DenseQp {
        let n = self.n;
        let mut qp = DenseQp::new(n, self.eq_rhs.len(), self.ineq_lower.len());
        let m = |r: &Vec<Vec<f64>>, cols: usize| DMatrix::from_fn(r.len(), cols, |i, j| r[i][j]);
        qp.hessian_mut().copy_from(&m(&self.hessian, n));
        qp.gradient_mut()
            .copy_from(&DVector::from_vec(self.gradient.clone()));
        if !self.eq_rhs.is_empty() {
            qp.eq_matrix_mut().copy_from(&m(&self.eq_matrix, n));
            qp.eq_rhs_mut()
                .copy_from(&DVector::from_vec(self.eq_rhs.clone()));
        }
        if !self.ineq_lower.is_empty() {
            qp.ineq_matrix_mut().copy_from(&m(&self.ineq_matrix, n));
            let side = |v: &[Option<f64>], inf: f64| {
                DVector::from_iterator(v.len(), v.iter().map(|x| x.unwrap_or(inf)))
            };
            qp.ineq_lower_mut()
                .copy_from(&side(&self.ineq_lower, f64::NEG_INFINITY));
            qp.ineq_upper_mut()
                .copy_from(&side(&self.ineq_upper, f64::INFINITY));
        }
        for j in 0..n {
            qp.lower_bounds_mut()[j] = self.lower_bounds[j].unwrap_or(f64::NEG_INFINITY);
            qp.upper_bounds_mut()[j] = self.upper_bounds[j].unwrap_or(f64::INFINITY);
        }
        qp
    }
}

fn fixtures_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures")
}

#[test]
#[ignore = "rewrites the fixtures"]
fn record() {
    let model = bundled_model();
    let mut out: Vec<Fixture> = Vec::new();
    // the full problems (stride-qp's nominal formulation, what clarabel and the fallback path solve);
    // the null-space reduced problems are checked against them in tests/tsid.rs and tests/ik.rs
    for eliminate in [false] {
        let tag = "full";
        let mut rng = rng(99);
        // QP-IK: a few ticks towards a random target
        let target = references_at(
            &model,
            &standing_state(&model, &random_posture(&model, &mut rng, 0.2, 0.05)),
        );
        let mut input = target.clone();
        input.state = standing_state(&model, &random_posture(&model, &mut rng, 0.2, 0.05));
        let mut config = IkConfig::default_for_bundled_model();
        config.eliminate_equalities = eliminate;
        let mut ik = QpIk::new(
            Arc::clone(&model),
            config,
            std::time::Duration::from_millis(2),
        )
        .unwrap();
        for k in 0..3 {
            ik.step(&input).unwrap();
            out.push(Fixture::from_qp(
                &format!("qp_ik_tick{k}_{tag}"),
                ik.qp_problem().dense_qp(),
            ));
        }
        // TSID: double support with a ZMP, then a lift-off ramp and single support
        let state = standing_state(&model, &default_posture(&model));
        let mut input = references_at(&model, &state);
        input.com_position.x += 0.01;
        input.desired_zmp = Some(Vector2::new(0.005, 0.0));
        let mut config = TsidConfig::default_for_bundled_model();
        config.eliminate_equalities = eliminate;
        let mut tsid = Tsid::new(
            Arc::clone(&model),
            config,
            std::time::Duration::from_millis(1),
        )
        .unwrap();
        tsid.step(&input).unwrap();
        out.push(Fixture::from_qp(
            &format!("tsid_double_support_zmp_{tag}"),
            tsid.qp_problem().unwrap().dense_qp(),
        ));
        input.set_contact("right_foot", false).unwrap();
        input.desired_zmp = None;
        for k in 0..60 {
            tsid.step(&input).unwrap();
            if k == 10 {
                out.push(Fixture::from_qp(
                    &format!("tsid_lift_off_ramp_{tag}"),
                    tsid.qp_problem().unwrap().dense_qp(),
                ));
            }
        }
        out.push(Fixture::from_qp(
            &format!("tsid_single_support_{tag}"),
            tsid.qp_problem().unwrap().dense_qp(),
        ));
    }
    std::fs::create_dir_all(fixtures_dir()).unwrap();
    for f in &out {
        let path = fixtures_dir().join(format!("{}.json", f.name));
        std::fs::write(&path, serde_json::to_string(f).unwrap()).unwrap();
    }
}

fn solve(solver: &mut dyn QpSolver, qp: &DenseQp) -> SolverOutput {
    let mut out = SolverOutput::new(qp);
    solver.solve(qp, &mut out);
    out
}

#[test]
fn recorded_problems_agree_between_clarabel_and_active_set() {
    let mut count = 0;
    let mut entries: Vec<_> = std::fs::read_dir(fixtures_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for path in entries
        .into_iter()
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
    {
        let fixture: Fixture =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        let qp = fixture.to_qp();
        let a = solve(&mut ActiveSetSolver::new(ActiveSetSettings::default()), &qp);
        let c = solve(
            &mut ClarabelSolver::new(ClarabelSettings {
                tolerance: 1e-12,
                ..Default::default()
            }),
            &qp,
        );
        assert_eq!(a.status, QpStatus::Solved, "{}", fixture.name);
        assert!(c.status.is_success(), "{}: {:?}", fixture.name, c.status);
        let d = (&a.x - &c.x).amax();
        assert!(
            d < 1e-6,
            "{}: active set vs clarabel differ by {d}",
            fixture.name
        );
        let kkt = check_kkt(&qp, &a);
        assert!(kkt.is_satisfied(1e-8), "{}: {kkt:?}", fixture.name);
        count += 1;
    }
    assert!(count >= 6, "expected the recorded fixtures, found {count}");
}
