//! Benchmark of one centroidal-MPC tick (default config: 12 stages of 0.1 s) on a walking schedule: the
//! input time advances by the runner's update period (0.05 s) through a whole step, so the contact
//! schedule shifts and the linearisation point (the previous solution) has to follow it, as in closed
//! loop; `*_warm_active_set` also starts the active-set solver from its previous active set.
use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::Vector3;
use stride_simplified::{CentroidalMpc, CentroidalMpcConfig, CentroidalMpcInput, Foot, MpcContact};

fn contact(foot: Foot, x: f64, y: f64, activation: f64, deactivation: f64) -> MpcContact {
    MpcContact::level(foot, x, y, activation, deactivation)
}

/// The walk at `t0` with a push-like CoM velocity `push` \[m/s\].
fn input(config: &CentroidalMpcConfig, time: Duration, push: Vector3<f64>) -> CentroidalMpcInput {
    let t0 = stride_block::seconds(time);
    let mut i = CentroidalMpcInput::new(config.stages);
    i.time = time;
    i.foot_half_length = 0.06;
    i.foot_half_width = 0.03;
    let contacts = [
        contact(Foot::Right, 0.0, -0.08, -1.0, 0.0),
        contact(Foot::Left, 0.0, 0.08, -1.0, 0.9),
        contact(Foot::Right, 0.15, -0.08, 0.6, 1.9),
        contact(Foot::Left, 0.3, 0.08, 1.6, f64::INFINITY),
    ];
    for c in contacts.iter().filter(|c| c.deactivation > t0) {
        i.push_contact(*c).unwrap();
    }
    let com = |t: f64| Vector3::new(0.15 * t, 0.06 * (std::f64::consts::PI * t).cos(), 0.5);
    i.com_position = com(t0);
    i.com_velocity = Vector3::new(0.15, 0.0, 0.0) + push;
    for k in 0..=config.stages {
        i.com_reference
            .push(com(t0 + k as f64 * config.stage_duration));
    }
    i
}

fn benches(c: &mut Criterion) {
    let cold = CentroidalMpcConfig::default();
    let warm = CentroidalMpcConfig {
        warm_start_active_set: true,
        ..cold
    };
    for (name, push, config) in [
        ("centroidal_mpc_walk", Vector3::zeros(), cold),
        (
            "centroidal_mpc_walk_pushed",
            Vector3::new(0.3, -0.3, 0.0),
            cold,
        ),
        (
            "centroidal_mpc_walk_warm_active_set",
            Vector3::zeros(),
            warm,
        ),
        (
            "centroidal_mpc_walk_pushed_warm_active_set",
            Vector3::new(0.3, -0.3, 0.0),
            warm,
        ),
    ] {
        let inputs: Vec<_> = (0..20)
            .map(|k| input(&config, Duration::from_millis(50 * k), push))
            .collect();
        let mut mpc = CentroidalMpc::new(&config, 33.0, 9.81).unwrap();
        for i in &inputs {
            mpc.step(i).unwrap();
        }
        let mut k = 0;
        c.bench_function(name, |b| {
            b.iter(|| {
                k = (k + 1) % inputs.len();
                mpc.step(black_box(&inputs[k]))
                    .unwrap()
                    .diagnostics
                    .variables
            })
        });
    }
}

criterion_group!(group, benches);
criterion_main!(group);
