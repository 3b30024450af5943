//! The plan → simplified-input glue: the support-polygon rule, the walking rule, the MPC horizon, and no
//! allocation per tick (counted with a global allocator).

use std::time::Duration;

use nalgebra::{Isometry3, Vector2};
use stride_planner::{plan_from_standing, Goal, Plan, PlanSample, PlannerConfig};
use stride_simplified::{
    DcmControllerKind, SimplifiedConfig, SimplifiedController, SimplifiedInput,
};
use stride_walking::{support_polygon, MeasuredCentroidal, SimplifiedInputBuilder};

#[global_allocator]
static ALLOC: stride_testkit::CountingAllocator = stride_testkit::CountingAllocator::new();

const PERIOD: Duration = Duration::from_millis(10);

fn soles() -> [Isometry3<f64>; 2] {
    [
        Isometry3::translation(0.0, 0.075, 0.0),
        Isometry3::translation(0.0, -0.075, 0.0),
    ]
}

fn walk() -> (PlannerConfig, Plan) {
    let config = PlannerConfig::default();
    let s = soles();
    let goal = Goal::Pose {
        x: 0.4,
        y: 0.0,
        yaw: 0.0,
    };
    let plan = plan_from_standing(&config, 9.81, 0.0, &s[0], &s[1], &goal).expect("plan");
    (config, plan)
}

fn measured(sample: &PlanSample, soles: [Isometry3<f64>; 2]) -> MeasuredCentroidal {
    MeasuredCentroidal {
        com: sample.com_position,
        com_velocity: sample.com_velocity,
        dcm: sample.dcm_position.xy(),
        zmp: sample.zmp.xy(),
        soles,
    }
}

fn predictive() -> SimplifiedController {
    let config = SimplifiedConfig {
        dcm_controller: DcmControllerKind::Predictive,
        ..SimplifiedConfig::default()
    };
    SimplifiedController::new(&config, PERIOD).expect("controller")
}

#[test]
fn support_polygon_takes_the_flagged_soles_and_both_in_flight() {
    let s = soles();
    let left = support_polygon(&s, [true, false], 0.2, 0.09).unwrap();
    assert!(left.contains(Vector2::new(0.0, 0.075), 0.0));
    assert!(!left.contains(Vector2::new(0.0, -0.075), 0.0));
    assert!((left.area() - 0.2 * 0.09).abs() < 1e-12);
    let both = support_polygon(&s, [true, true], 0.2, 0.09).unwrap();
    assert!((both.area() - 0.2 * (0.15 + 0.09)).abs() < 1e-12);
    let none = support_polygon(&s, [false, false], 0.2, 0.09).unwrap();
    assert_eq!(none, both);
    assert!(support_polygon(&s, [true, false], 0.0, 0.09).is_err());
}

#[test]
fn fill_follows_the_plan_measured_soles_and_horizon() {
    let (config, plan) = walk();
    let controller = predictive();
    let n = controller.horizon_samples();
    assert!(n > 1);
    let mut builder =
        SimplifiedInputBuilder::new(&controller, config.foot_length, config.foot_width);
    let mut input: SimplifiedInput = builder.new_input(&soles()).unwrap();
    let mut sample = PlanSample::default();
    // single support: the plan has one foot in contact; the polygon is that foot at its *measured* pose
    let t = plan
        .phases
        .iter()
        .find(|p| matches!(p.kind, stride_planner::PhaseKind::SingleSupport { .. }))
        .map(|p| 0.5 * (p.start + p.end))
        .expect("a single support");
    plan.sample(t, &mut sample);
    let stance = if sample.left.in_contact { 0 } else { 1 };
    let mut measured_soles = soles();
    measured_soles[stance] =
        Isometry3::translation(0.01, measured_soles[stance].translation.y, 0.0);
    let m = measured(&sample, measured_soles);
    builder
        .fill(&mut input, Duration::from_secs_f64(t), &plan, &sample, &m)
        .unwrap();
    assert!(input.walking);
    assert_eq!(input.omega, sample.omega);
    assert_eq!(input.planned_dcm_position, sample.dcm_position.xy());
    assert_eq!(input.measured_zmp, m.zmp);
    let centre = measured_soles[stance].translation.vector.xy();
    assert!((input.support_polygon.vertex_mean() - centre).norm() < 1e-12);
    assert_eq!(input.horizon.len(), n);
    // the horizon's samples are the plan at t + k T
    let k = n - 1;
    plan.sample(t + k as f64 * PERIOD.as_secs_f64(), &mut sample);
    // (t went through a Duration: nanosecond rounding)
    let dcm = input.horizon.samples()[k].dcm_position;
    assert!((dcm - sample.dcm_position.xy()).norm() < 1e-9);
    // after the plan's end: standing
    plan.sample(plan.end_time + 0.5, &mut sample);
    let m = measured(&sample, soles());
    let end = Duration::from_secs_f64(plan.end_time + 0.5);
    builder.fill(&mut input, end, &plan, &sample, &m).unwrap();
    assert!(!input.walking);
}

#[test]
fn fill_does_not_allocate() {
    let (config, plan) = walk();
    let controller = predictive();
    let mut builder =
        SimplifiedInputBuilder::new(&controller, config.foot_length, config.foot_width);
    let mut input = builder.new_input(&soles()).unwrap();
    let mut sample = PlanSample::default();
    let (_, n) = ALLOC.allocations_during(|| {
        for k in 0..400 {
            let time = PERIOD * k;
            plan.sample(time.as_secs_f64(), &mut sample);
            let m = measured(&sample, [sample.left.pose, sample.right.pose]);
            builder.fill(&mut input, time, &plan, &sample, &m).unwrap();
        }
    });
    assert_eq!(n, 0, "SimplifiedInputBuilder::fill allocated");
}
