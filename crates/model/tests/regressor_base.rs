//! Base parameters of the bundled humanoid by SVD of stacked regressors [Traversaro 2017, eqs. 7.6–7.10]:
//! a stable rank with a clear gap, an orthonormal basis, and the invariances that define the identifiable
//! subspace (projections of ψ and null-space changes leave every torque unchanged).

mod common;

use std::sync::Arc;

use nalgebra::{DMatrix, DVector};
use stride_model::inertial::{
    stacked_inverse_dynamics_regressor, BaseParameters, DEFAULT_RANK_TOLERANCE,
};
use stride_model::{KinDyn, Model, RobotState};

fn samples(model: &Model, seed: u64, count: u64) -> Vec<(RobotState, DVector<f64>)> {
    (0..count)
        .map(|k| {
            let s = seed * 1000 + k;
            (
                common::random_state(model, s),
                common::random_vector(model.nv(), s + 500, 4.0),
            )
        })
        .collect()
}

fn base_parameters(kd: &mut KinDyn, seed: u64) -> BaseParameters {
    let model = Arc::clone(kd.model());
    let stacked = stacked_inverse_dynamics_regressor(kd, &samples(&model, seed, 40)).unwrap();
    BaseParameters::from_stacked(stacked, DEFAULT_RANK_TOLERANCE).unwrap()
}

/// Checks the base parameters of `model`; returns the rank and the gap.
fn check_base_parameters(model: &Arc<Model>) -> (usize, f64) {
    let p = 10 * model.body_count();
    let mut kd = KinDyn::new(Arc::clone(model));
    let base = base_parameters(&mut kd, 1);
    let rank = base.rank();
    assert!(rank > 0 && rank < p, "rank {rank} of {p}");
    assert!(base.gap() > 1e6, "gap {:.3e}", base.gap());
    // Orthonormal basis.
    let gram = base.basis.tr_mul(&base.basis);
    assert!((gram - DMatrix::identity(rank, rank)).amax() < 1e-10);
    // The same rank and subspace from other samples.
    for seed in 2..5 {
        let other = base_parameters(&mut kd, seed);
        assert_eq!(other.rank(), rank, "seed {seed}");
        // Same subspace: the projector of one reproduces the other's basis.
        let proj = &base.basis * base.basis.transpose() * &other.basis;
        assert!((proj - &other.basis).amax() < 1e-8, "seed {seed}");
    }
    // Invariances at fresh samples: ψ, its projection and ψ plus a null-space vector give the same torques.
    let psi = model.inertial_parameters();
    let projected = base.project(&psi).unwrap();
    let random = common::random_vector(p, 77, 1.0);
    let null = &random - base.project(&random).unwrap();
    assert!(null.norm() > 0.1);
    let fresh = samples(model, 99, 10);
    let y = stacked_inverse_dynamics_regressor(&mut kd, &fresh).unwrap();
    let tau = &y * &psi;
    let scale = tau.amax();
    assert!((&y * &projected - &tau).amax() < 1e-9 * scale);
    assert!((&y * (&psi + &null * 10.0) - &tau).amax() < 1e-9 * scale);
    assert_eq!(base.base_parameters(&psi).unwrap().len(), rank);
    (rank, base.gap())
}

#[test]
fn humanoid_base_parameters_are_stable_and_invariant() {
    let model = common::humanoid_model().expect("bundled humanoid");
    let (rank, gap) = check_base_parameters(&model);
    println!(
        "stride_humanoid: {rank} base parameters of {}, gap {gap:.2e}",
        10 * model.body_count()
    );
}

#[test]
fn icub_base_parameters_are_stable_and_invariant() {
    let test = "icub_base_parameters_are_stable_and_invariant";
    let Some(path) = stride_testkit::icub_model_urdf(test, "iCubGazeboV2_7") else {
        return;
    };
    let model = Arc::new(Model::from_urdf_file(path).unwrap());
    let (rank, gap) = check_base_parameters(&model);
    println!(
        "iCubGazeboV2_7: {rank} base parameters of {}, gap {gap:.2e}",
        10 * model.body_count()
    );
}

#[test]
fn base_parameters_reject_bad_input() {
    assert!(BaseParameters::from_stacked(DMatrix::zeros(0, 0), 1e-9).is_err());
    let mut m = DMatrix::identity(3, 3);
    m[(0, 0)] = f64::NAN;
    assert!(BaseParameters::from_stacked(m, 1e-9).is_err());
    let full = BaseParameters::from_stacked(DMatrix::identity(4, 3), 1e-9).unwrap();
    assert_eq!(full.rank(), 3);
    assert!(full.gap().is_infinite());
    assert!(full.project(&DVector::zeros(2)).is_err());
}
