//! The entry points that share a pass with another computation, checked against the full computation:
//! the mass matrix's tree entries (`mass_matrix_lower`) against the dense CRBA, and the inverse dynamics that
//! reuses a force/torque sensor pass (`inverse_dynamics_after_ft_sensors`) against the RNEA with the
//! external wrenches, and the sensor readings from the sensors' subtrees (`ft_sensor_readings`) against
//! those of the whole pass.

mod common;

use std::sync::Arc;

use nalgebra::{DMatrix, DVector, Vector6};
use stride_model::{ExternalWrench, KinDyn, Model, ModelError, VelocityRepresentation};

const REPRESENTATIONS: [VelocityRepresentation; 3] = [
    VelocityRepresentation::Mixed,
    VelocityRepresentation::Body,
    VelocityRepresentation::Inertial,
];

fn models() -> Vec<Arc<Model>> {
    vec![
        common::test_model(),
        common::humanoid_model().expect("models/stride_humanoid.urdf must exist"),
    ]
}

/// Every entry `mass_matrix_lower` reports is the dense matrix's, bit for bit, each lower entry is reported
/// once, and the entries it does not report are zero in the dense matrix.
#[test]
fn mass_matrix_lower_is_the_dense_lower_triangle() {
    for model in models() {
        let nv = model.nv();
        let mut kd = KinDyn::new(Arc::clone(&model));
        let mut dense = DMatrix::zeros(nv, nv);
        for rep in REPRESENTATIONS {
            kd.set_representation(rep);
            for seed in 0..3 {
                kd.set_state(&common::random_state(&model, seed)).unwrap();
                kd.mass_matrix(&mut dense).unwrap();
                let mut seen = DMatrix::<u32>::zeros(nv, nv);
                kd.mass_matrix_lower(|r, c, v| {
                    assert!(r >= c, "({r}, {c}) is above the diagonal");
                    assert_eq!(
                        v.to_bits(),
                        dense[(r, c)].to_bits(),
                        "({r}, {c}): {v} vs {}",
                        dense[(r, c)]
                    );
                    seen[(r, c)] += 1;
                });
                for c in 0..nv {
                    for r in c..nv {
                        match seen[(r, c)] {
                            1 => {}
                            0 => assert_eq!(dense[(r, c)], 0.0, "({r}, {c}) not reported"),
                            k => panic!("({r}, {c}) reported {k} times"),
                        }
                    }
                }
            }
        }
    }
}

fn relative(a: &DVector<f64>, b: &DVector<f64>) -> f64 {
    (a - b).amax() / b.amax().max(1.0)
}

/// Wrenches on the last frame and on a frame of the first link below the base (two paths to the root).
fn two_wrenches(model: &Model) -> [ExternalWrench; 2] {
    let frames = model.frames();
    let last = model.frame_id(&frames[frames.len() - 1].name).unwrap();
    let near = frames
        .iter()
        .find(|f| f.link == 1)
        .map(|f| model.frame_id(&f.name).unwrap())
        .unwrap();
    [
        ExternalWrench {
            frame: last,
            wrench: Vector6::new(3.0, -2.0, 180.0, 0.4, -1.5, 0.2),
        },
        ExternalWrench {
            frame: near,
            wrench: Vector6::new(-1.0, 5.0, 40.0, 2.0, 0.3, -0.7),
        },
    ]
}

/// The inverse dynamics after a sensor pass equals the RNEA with the wrenches to rounding, in every
/// representation, on random states and accelerations.
#[test]
fn inverse_dynamics_after_ft_sensors_matches_the_rnea() {
    for model in models() {
        let nv = model.nv();
        let mut kd = KinDyn::new(Arc::clone(&model));
        let wrenches = two_wrenches(&model);
        let mut readings = vec![Vector6::zeros(); model.ft_sensors().len()];
        let (mut reused, mut full) = (DVector::zeros(nv), DVector::zeros(nv));
        for rep in REPRESENTATIONS {
            kd.set_representation(rep);
            for seed in 0..3 {
                kd.set_state(&common::random_state(&model, seed)).unwrap();
                let nu_dot = common::random_vector(nv, 10 + seed, 2.0);
                kd.ft_sensor_wrenches(&nu_dot, &[], &mut readings).unwrap();
                kd.inverse_dynamics_after_ft_sensors(&wrenches, &mut reused)
                    .unwrap();
                kd.inverse_dynamics(&nu_dot, &wrenches, &mut full).unwrap();
                let err = relative(&reused, &full);
                assert!(err < 1e-12, "{rep:?} seed {seed}: relative {err:.2e}");
            }
        }
    }
}

/// It refuses to run without a fresh pass free of external wrenches: none yet, after a new state, after a
/// pass with a wrench, after another dynamics call, and a second time on one pass.
#[test]
fn inverse_dynamics_after_ft_sensors_needs_a_fresh_free_pass() {
    let model = common::humanoid_model().unwrap();
    let nv = model.nv();
    let mut kd = KinDyn::new(Arc::clone(&model));
    let wrenches = two_wrenches(&model);
    let nu_dot = DVector::zeros(nv);
    let mut readings = vec![Vector6::zeros(); model.ft_sensors().len()];
    let mut out = DVector::zeros(nv);
    let state = common::random_state(&model, 4);
    kd.set_state(&state).unwrap();
    let refused = |kd: &mut KinDyn, out: &mut DVector<f64>| {
        matches!(
            kd.inverse_dynamics_after_ft_sensors(&wrenches, out),
            Err(ModelError::NoSensorPass)
        )
    };
    assert!(refused(&mut kd, &mut out), "no pass yet");
    kd.ft_sensor_wrenches(&nu_dot, &[], &mut readings).unwrap();
    kd.set_state(&state).unwrap();
    assert!(refused(&mut kd, &mut out), "after set_state");
    kd.ft_sensor_wrenches(&nu_dot, &wrenches[..1], &mut readings)
        .unwrap();
    assert!(refused(&mut kd, &mut out), "after a pass with a wrench");
    kd.ft_sensor_wrenches(&nu_dot, &[], &mut readings).unwrap();
    kd.bias_forces(&mut out).unwrap();
    assert!(refused(&mut kd, &mut out), "after another RNEA");
    kd.ft_sensor_wrenches(&nu_dot, &[], &mut readings).unwrap();
    let mut short = DVector::zeros(nv - 1);
    assert!(matches!(
        kd.inverse_dynamics_after_ft_sensors(&wrenches, &mut short),
        Err(ModelError::DimensionMismatch { .. })
    ));
    kd.inverse_dynamics_after_ft_sensors(&wrenches, &mut out)
        .unwrap();
    assert!(refused(&mut kd, &mut out), "a second time on one pass");
}

/// The readings from the sensors' subtrees are those of the whole RNEA, bit for bit, with wrenches on a
/// sole (a child body's subtree), on the foot sensor's host body (its child side) and elsewhere.
#[test]
fn ft_sensor_readings_are_the_whole_pass_readings() {
    let model = common::humanoid_model().unwrap();
    let nv = model.nv();
    let mut kd = KinDyn::new(Arc::clone(&model));
    let mut wrenches = two_wrenches(&model).to_vec();
    for (frame, k) in [("l_sole", 1.0), ("r_foot_ft_sensor", -0.5), ("l_foot", 2.0)] {
        wrenches.push(ExternalWrench {
            frame: model.frame_id(frame).unwrap(),
            wrench: Vector6::new(1.0, -2.0, 150.0, 0.3, -0.4, 0.1) * k,
        });
    }
    let ns = model.ft_sensors().len();
    assert!(ns >= 2, "the humanoid has its foot sensors");
    let (mut subtree, mut whole) = (vec![Vector6::zeros(); ns], vec![Vector6::zeros(); ns]);
    let bits = |r: &[Vector6<f64>]| {
        r.iter()
            .flat_map(|w| w.iter().map(|v| v.to_bits()))
            .collect::<Vec<_>>()
    };
    for rep in REPRESENTATIONS {
        kd.set_representation(rep);
        for seed in 0..3 {
            kd.set_state(&common::random_state(&model, seed)).unwrap();
            let nu_dot = common::random_vector(nv, 20 + seed, 2.0);
            for external in [&wrenches[..], &[]] {
                kd.ft_sensor_readings(&nu_dot, external, &mut subtree)
                    .unwrap();
                kd.ft_sensor_wrenches(&nu_dot, external, &mut whole)
                    .unwrap();
                assert_eq!(bits(&subtree), bits(&whole), "{rep:?} seed {seed}");
                assert!(whole.iter().all(|w| w.amax() > 0.0));
            }
        }
    }
}
