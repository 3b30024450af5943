//! A measurement of the walking stack's centroidal quantities allocates nothing (counting global
//! allocator).

use std::sync::Arc;

use nalgebra::{DVector, Vector6};
use stride_model::{bundled, RobotState};
use stride_walking::CentroidalMeter;

#[global_allocator]
static ALLOC: stride_testkit::CountingAllocator = stride_testkit::CountingAllocator::new();

#[test]
fn measuring_allocates_nothing() {
    let model = Arc::new(bundled::model().unwrap());
    let soles = [
        model.frame_id(bundled::LEFT_SOLE).unwrap(),
        model.frame_id(bundled::RIGHT_SOLE).unwrap(),
    ];
    let state =
        RobotState::standing(&model, &DVector::zeros(model.dof()), soles[0], soles[1]).unwrap();
    let mut meter = CentroidalMeter::new(Arc::clone(&model), soles);
    let half = Vector6::new(0.0, 0.0, 0.5 * model.total_mass() * 9.81, 0.0, 0.0, 0.0);
    meter
        .measure(&state, &[half; 2], [true, true], 4.2)
        .unwrap();
    let (_, n) = ALLOC.allocations_during(|| {
        for contacts in [[true, true], [true, false], [false, false]] {
            meter.measure(&state, &[half; 2], contacts, 4.2).unwrap();
        }
    });
    assert_eq!(n, 0, "measure allocated {n} times");
}
