//! The step adjustment replanned from the measured DCM during a push (`[simplified.push] replan_from_dcm`,
//! `configs/layers/push_replan_dcm.toml`) in closed loop on stride-sim (the bundled humanoid, position
//! control, the push response with the hold at once, the crossover and the step out of the held double
//! support): the crossed step a 40 N push to the right asks for once the hold is released, refused by the
//! planner from the plan's own DCM, is applied from the measured one. The walk still falls (the
//! whole-body layer loses the crossing swing, docs/push-recovery.md "The replan from the measured DCM").

mod common;

use common::{adjusted_footsteps, log_options as options, Scratch};
use stride_runner::run::{run_scenario, Outcome};

/// 40 N to the right (−y) for 1 s from 5.5 s, as the right foot (at y −0.075) lands: the hold starts,
/// `step_out` releases it, and the left swing that follows is asked to cross past the right foot. Without
/// the replan from the measured DCM every one of those requests is refused (measured: 0 applied, 149
/// refused, toppled at 6.37 s); with it crossed left touch-downs are applied (measured: 13 applied, 25
/// refused, toppled at 6.36 s in the double support after the crossed touch-down).
#[test]
fn the_released_crossover_is_applied_only_when_replanned_from_the_measured_dcm() {
    let s = Scratch::new("push_replan_dcm");
    let push = "[scenario]\nduration = 6.6\n[simplified.push]\nstep_out = true\n\
                [[sim.pushes]]\nframe = \"chest\"\nstart = 5.5\nduration = 1.0\n\
                wrench = [0.0, -40.0, 0.0, 0.0, 0.0, 0.0]\n";
    let base = [
        "walk_straight_step_adjustment_push_response.toml",
        "layers/step_crossover.toml",
        "layers/push_replan_dcm.toml",
    ];
    let mut seen = Vec::new();
    for (name, layers) in [("on", &base[..]), ("off", &base[..2])] {
        let sc = common::scenario_from_configs(&s, name, layers, push);
        let run = run_scenario(&sc, &options(&s, name)).unwrap();
        assert!(
            matches!(run.outcome, Outcome::Fell { .. }),
            "{}",
            run.render()
        );
        // left touch-downs past the right sole (half width 0.045) by at least crossover_min − 1 mm
        let crossed = adjusted_footsteps(&s.path(&format!("{name}.mcap")))
            .iter()
            .filter(|m| m["foot"] == "left" && m["position"][1].as_f64().unwrap() < -0.075 - 0.099)
            .count();
        seen.push((run.step_adjustments, crossed));
    }
    let (((applied, refused), crossed), ((applied_off, refused_off), crossed_off)) =
        (seen[0], seen[1]);
    assert!(
        crossed >= 1 && applied >= 1,
        "with: {applied} applied, {refused} refused"
    );
    assert_eq!(
        (applied_off, crossed_off),
        (0, 0),
        "without: {refused_off} refused"
    );
    assert!(refused_off > 0);
}
