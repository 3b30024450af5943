//! A centroidal-MPC tick allocates nothing once every QP size of the schedule has occurred: a second pass
//! over one step of a walk (the input time advancing by 0.05 s, as the runner ticks it) makes no
//! allocation.
use std::time::Duration;

use nalgebra::Vector3;
use stride_simplified::{CentroidalMpc, CentroidalMpcConfig, CentroidalMpcInput, Foot, MpcContact};

#[global_allocator]
static ALLOC: stride_testkit::CountingAllocator = stride_testkit::CountingAllocator::new();

fn fill(input: &mut CentroidalMpcInput, config: &CentroidalMpcConfig, time: Duration) {
    input.time = time;
    let t0 = stride_block::seconds(time);
    input.contacts.clear();
    input.com_reference.clear();
    let contacts = [
        MpcContact::level(Foot::Right, 0.0, -0.08, -1.0, 0.0),
        MpcContact::level(Foot::Left, 0.0, 0.08, -1.0, 0.9),
        MpcContact::level(Foot::Right, 0.15, -0.08, 0.6, 1.9),
        MpcContact::level(Foot::Left, 0.3, 0.08, 1.6, f64::INFINITY),
    ];
    for c in contacts.iter().filter(|c| c.deactivation > t0) {
        input.push_contact(*c).unwrap();
    }
    let com = |t: f64| Vector3::new(0.15 * t, 0.06 * (std::f64::consts::PI * t).cos(), 0.5);
    input.com_position = com(t0);
    input.com_velocity = Vector3::new(0.4, -0.3, 0.0);
    for k in 0..=config.stages {
        input
            .com_reference
            .push(com(t0 + k as f64 * config.stage_duration));
    }
}

#[test]
fn ticks_allocate_nothing_once_every_size_has_occurred() {
    let config = CentroidalMpcConfig::default();
    let mut mpc = CentroidalMpc::new(&config, 33.0, 9.81).unwrap();
    let mut input = CentroidalMpcInput::new(config.stages);
    let pass = |mpc: &mut CentroidalMpc, input: &mut CentroidalMpcInput| {
        let mut moved = 0.0_f64;
        for k in 0..20 {
            fill(input, &config, Duration::from_millis(50 * k));
            let out = mpc.step(input).unwrap();
            if let Some(c) = out.next_adjusted() {
                moved = moved.max((c.position - c.planned.position).norm());
            }
        }
        moved
    };
    let (_, first) = ALLOC.allocations_during(|| pass(&mut mpc, &mut input));
    let (moved, second) = ALLOC.allocations_during(|| pass(&mut mpc, &mut input));
    assert!(first > 0, "the first pass allocates the QPs of each size");
    assert_eq!(second, 0);
    assert!(moved > 0.0, "the pushed walk moves a footstep");
}
