//! Pushes in LIPM simulation: a DCM offset inside the foot is recovered; the largest recoverable
//! offset of each controller is found by bisection and compared with the capture bound (the distance
//! from the reference DCM to the foot edge: beyond it no ZMP inside the foot can stop the DCM).
mod common;

use common::OMEGA;
use nalgebra::Vector2;
use stride_simplified::*;

const PERIOD: f64 = 0.01;

enum Controller {
    Instantaneous(DcmInstantaneousController),
    Predictive(Box<(DcmPredictiveController, DcmHorizon)>),
}

fn make(kind: usize) -> Controller {
    match kind {
        0 => Controller::Instantaneous(
            DcmInstantaneousController::new(DcmInstantaneousConfig::default()).unwrap(),
        ),
        1 => Controller::Instantaneous(
            DcmInstantaneousController::new(DcmInstantaneousConfig {
                kp: 2.0,
                ki: 1.0,
                integral_limit: 0.03,
            })
            .unwrap(),
        ),
        _ => {
            let c = DcmPredictiveController::new(DcmPredictiveConfig::default(), PERIOD).unwrap();
            let h = DcmHorizon::with_capacity(c.horizon_samples());
            Controller::Predictive(Box::new((c, h)))
        }
    }
}

/// Standing on one foot with the DCM at the foot centre; the push moves the DCM by `offset` along
/// `direction`. Returns true when the DCM is back within 1 mm after 10 s, the ZMP having stayed in the
/// foot. The realised ZMP follows the desired one through a first-order lag of time constant `lag` [s]
/// (0: perfect ZMP tracking), a crude model of the whole-body layer's ZMP tracking.
fn recovers(kind: usize, direction: Vector2<f64>, offset: f64, lag: f64) -> bool {
    let foot = SupportPolygon::rectangle(-0.05, 0.07, -0.03, 0.03).unwrap();
    let reference = Vector2::new(0.01, 0.0);
    let d = LipmDiscretization::new(OMEGA, PERIOD).unwrap();
    let mut controller = make(kind);
    let (mut x, mut v) = (reference, direction * (offset * OMEGA));
    let blend = if lag > 0.0 {
        1.0 - (-PERIOD / lag).exp()
    } else {
        1.0
    };
    let mut realised = reference;
    for _ in 0..1000 {
        let dcm = dcm_from_com(x, v, OMEGA);
        if (dcm - reference).norm() > 0.3 {
            // far outside the foot: fallen
            return false;
        }
        let zmp = match &mut controller {
            Controller::Instantaneous(c) => {
                c.step(reference, Vector2::zeros(), dcm, OMEGA, &foot, PERIOD)
                    .unwrap()
                    .desired_zmp
            }
            Controller::Predictive(boxed) => {
                let (c, h) = &mut **boxed;
                h.clear();
                for _ in 0..c.horizon_samples() {
                    h.push(HorizonSample {
                        dcm_position: reference,
                        zmp: reference,
                        support: foot,
                    })
                    .unwrap();
                }
                let out = c.step(OMEGA, dcm, h, &foot).unwrap();
                // The QP only fails (fallback law) once the DCM has left the foot (no capture possible).
                if foot.contains(dcm, 0.0) {
                    assert!(
                        !out.diagnostics.fallback,
                        "fallback with the DCM inside the foot: {dcm:?}"
                    );
                }
                out.desired_zmp
            }
        };
        assert!(foot.contains(zmp, 1e-9));
        realised += (zmp - realised) * blend;
        (x, v) = d.step_com(x, v, realised);
    }
    (dcm_from_com(x, v, OMEGA) - reference).norm() < 1e-3
}

fn largest_recoverable(kind: usize, direction: Vector2<f64>, lag: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, 0.2);
    assert!(recovers(kind, direction, lo, lag));
    assert!(!recovers(kind, direction, hi, lag));
    while hi - lo > 1e-4 {
        let mid = 0.5 * (lo + hi);
        if recovers(kind, direction, mid, lag) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

#[test]
fn largest_recoverable_push_reaches_the_capture_bound() {
    let names = [
        "instantaneous kp=1.2",
        "instantaneous kp=2 ki=1",
        "predictive (2 s)",
    ];
    // (direction, distance from the reference DCM to the foot edge)
    let cases = [
        (Vector2::new(1.0, 0.0), 0.06),
        (Vector2::new(-1.0, 0.0), 0.06),
        (Vector2::new(0.0, 1.0), 0.03),
    ];
    for (kind, name) in names.iter().enumerate() {
        for (direction, bound) in cases {
            let largest = largest_recoverable(kind, direction, 0.0);
            eprintln!("{name}: direction {:?}: largest recoverable DCM offset {largest:.4} m (bound {bound} m)", [direction.x, direction.y]);
            // No controller keeping the ZMP in the foot can do better than the bound; these reach it.
            assert!(largest <= bound + 1e-4, "{name}");
            assert!(largest >= 0.98 * bound, "{name}: {largest}");
        }
    }
}

#[test]
fn largest_recoverable_push_with_zmp_tracking_lag() {
    // With a 50 ms lag between desired and realised ZMP the bound is no longer reachable: the report
    // compares the controllers (docs/simplified.md); small pushes must still be recovered.
    let names = [
        "instantaneous kp=1.2",
        "instantaneous kp=2 ki=1",
        "predictive (2 s)",
    ];
    let direction = Vector2::new(1.0, 0.0);
    let bound = 0.06;
    for (kind, name) in names.iter().enumerate() {
        assert!(recovers(kind, direction, 0.1 * bound, 0.05), "{name}");
        let largest = largest_recoverable(kind, direction, 0.05);
        eprintln!("{name}: 50 ms ZMP lag: largest recoverable forward DCM offset {largest:.4} m (bound {bound} m)");
        assert!(largest <= bound + 1e-4, "{name}");
    }
}
