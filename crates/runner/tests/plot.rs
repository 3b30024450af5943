//! `stride plot`: the figures of a short simulated walk, parsed back from their SVG, and the survival map
//! of a fixture `results.json`.
mod common;

use clap::Parser;
use common::Scratch;
use stride_runner::cli::Cli;
use stride_runner::config::Scenario;
use stride_runner::log::read_log;
use stride_runner::plot::{log_figures, plot_log, plot_sweep, LOG_FIGURES};
use stride_runner::run::{run_scenario, RunOptions};

/// The opening tags `<tag .../>` of an SVG, in document order.
fn elements<'a>(svg: &'a str, tag: &str) -> Vec<&'a str> {
    let open = format!("<{tag} ");
    svg.match_indices(&open)
        .map(|(i, _)| &svg[i..i + svg[i..].find('>').unwrap()])
        .collect()
}

fn attr<'a>(el: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let i = el.find(&key)? + key.len();
    Some(&el[i..i + el[i..].find('"')?])
}

/// Point counts of the polylines of more than two points (data; legend swatches, limits and ticks have 2).
fn data_lines(svg: &str) -> Vec<usize> {
    elements(svg, "polyline")
        .iter()
        .map(|p| attr(p, "points").unwrap().split_whitespace().count())
        .filter(|&n| n > 2)
        .collect()
}

/// The texts of the `<text>` elements.
fn texts(svg: &str) -> Vec<String> {
    svg.split("<text ")
        .skip(1)
        .map(|t| {
            let body = &t[t.find('>').unwrap() + 1..t.find("</text>").unwrap()];
            body.trim().to_string()
        })
        .collect()
}

#[test]
fn a_short_walk_gives_every_figure_with_its_series() {
    let s = Scratch::new("plot-log");
    let sc = Scenario::load(&common::root().join("configs/walk_straight.toml")).unwrap();
    let log_path = s.path("walk.mcap");
    let options = RunOptions {
        output: Some(log_path.clone()),
        duration: Some(1.5),
        ..RunOptions::default()
    };
    run_scenario(&sc, &options).unwrap();
    let dir = s.path("plots");
    let written = plot_log(&log_path, &dir).unwrap();
    assert_eq!(written.len(), LOG_FIGURES.len());
    let log = read_log(&log_path).unwrap();
    let count = |topic: &str| log.topic(topic).count();
    let (plan, track, out) = (
        count("/planner/references"),
        count("/runner/tracking"),
        count("/simplified/output"),
    );
    let (state, feet) = (count("/estimation/state"), count("/sensors/feet"));
    assert!(
        plan > 100 && track > 100 && state > 100,
        "{plan} {track} {state}"
    );
    let read = |f: &str| std::fs::read_to_string(dir.join(f)).unwrap();
    for f in LOG_FIGURES {
        assert!(dir.join(f).is_file(), "{f} missing");
    }
    // Series per figure, each with one point per logged message (1.5 s: no decimation).
    let expect: [(&str, Vec<usize>); 6] = [
        ("dcm.svg", vec![plan, track, plan, track]),
        ("zmp.svg", vec![plan, out, track, plan, out, track]),
        ("com.svg", vec![plan, out, track, plan, out, track]),
        (
            "feet.svg",
            vec![plan, feet, plan, feet, plan, state, feet, plan, state, feet],
        ),
        ("wrenches.svg", vec![state, feet, state, feet]),
        (
            "timing.svg",
            vec![
                count("/simplified/timing"),
                count("/wbc/timing"),
                count("/simplified/timing"),
                count("/wbc/timing"),
            ],
        ),
    ];
    for (f, lines) in expect {
        assert_eq!(data_lines(&read(f)), lines, "{f}");
    }
    let dcm = texts(&read("dcm.svg"));
    for label in [
        "planned DCM",
        "measured DCM",
        "DCM x [m]",
        "DCM y [m]",
        "time [s]",
        "double support",
        "left stance",
    ] {
        assert!(
            dcm.iter().any(|t| t == label),
            "dcm.svg lacks {label:?}: {dcm:?}"
        );
    }
    // The phases from /events are shaded: double support until the first step, then left stance.
    let spans = log_figures::phases(&log).unwrap();
    assert!(spans.len() >= 2, "{spans:?}");
    assert_eq!(spans[0].phase, "double_support");
    let shaded = elements(&read("dcm.svg"), "rect")
        .iter()
        .filter(|r| attr(r, "fill") == Some("#BEBEBE"))
        .count();
    assert_eq!(
        shaded,
        2 * (spans.iter().filter(|p| p.phase == "double_support").count() + 1)
    );
    // Torques: the most loaded joints, true and estimated, with their limits.
    let torques = read("torques.svg");
    assert_eq!(
        data_lines(&torques),
        [count("/sim/state"), state].repeat(log_figures::TORQUE_JOINTS)
    );
    let titles: Vec<_> = texts(&torques)
        .into_iter()
        .filter(|t| t.ends_with("% of limit)"))
        .collect();
    assert_eq!(titles.len(), log_figures::TORQUE_JOINTS, "{titles:?}");
    assert!(texts(&torques).iter().any(|t| t == "effort limit ±"));
}

/// The colours of the map's cells (rectangles wider than the legend swatches), as rows from the top.
fn cells(svg: &str) -> Vec<Vec<String>> {
    let mut rects: Vec<(i64, i64, String)> = elements(svg, "rect")
        .iter()
        .filter(|r| attr(r, "fill").is_some_and(|f| f.starts_with('#') && f != "#FFFFFF"))
        .filter(|r| attr(r, "width").unwrap().parse::<f64>().unwrap() > 20.0)
        .map(|r| {
            let n = |k| attr(r, k).unwrap().parse::<f64>().unwrap() as i64;
            (n("y"), n("x"), attr(r, "fill").unwrap().to_string())
        })
        .collect();
    rects.sort();
    let mut rows: Vec<Vec<String>> = Vec::new();
    let mut last_y = None;
    for (y, _, fill) in rects {
        if last_y != Some(y) {
            rows.push(Vec::new());
            last_y = Some(y);
        }
        rows.last_mut().unwrap().push(fill);
    }
    rows
}

const GOAL: &str = "#2CA02C";
const FELL: &str = "#D62728";
const TIMEOUT: &str = "#FF7F0E";
const ERROR: &str = "#7F7F7F";
/// Half goal, half fell.
const HALF: &str = "#81642A";

#[test]
fn the_survival_map_has_one_cell_per_axis_pair_coloured_by_outcome() {
    let s = Scratch::new("plot-sweep");
    let results = common::root().join("crates/runner/tests/fixtures/sweep_results.json");
    // Default axes: the first two keys (push.magnitude across, push.direction_deg up); push.start varies
    // in the (150, 0) cell only, where one run reached the goal and one fell.
    let file = plot_sweep(&results, &s.0, None, None).unwrap();
    assert!(file.ends_with("survival_push.magnitude_push.direction_deg.svg"));
    let svg = std::fs::read_to_string(&file).unwrap();
    assert_eq!(
        cells(&svg),
        vec![
            vec![GOAL, FELL, TIMEOUT],     // 90°: magnitudes 50, 100, 150 (no 200)
            vec![GOAL, GOAL, HALF, ERROR], // 0°: magnitudes 50, 100, 150, 200
        ]
    );
    let t = texts(&svg);
    assert!(t.iter().any(|x| x == "1/2 goal"), "{t:?}");
    for label in [
        "push.magnitude",
        "push.direction_deg",
        "all goal",
        "all fell",
        "150",
    ] {
        assert!(t.iter().any(|x| x == label), "lacks {label:?}: {t:?}");
    }
    // Other axes through the command line: direction across, start up.
    let cli = Cli::parse_from([
        "stride",
        "plot",
        results.to_str().unwrap(),
        "-o",
        s.0.to_str().unwrap(),
        "--x",
        "push.direction_deg",
        "--y",
        "push.start",
    ]);
    stride_runner::commands::dispatch(cli).unwrap();
    let svg =
        std::fs::read_to_string(s.path("survival_push.direction_deg_push.start.svg")).unwrap();
    // start 2.0: only 0° (fell); start 1.0: 0° has 3 goal and an error, 90° a goal, a fall and a timeout.
    let (three_quarters, one_third) = ("#57822B", "#9D4F29");
    assert_eq!(
        cells(&svg),
        vec![vec![FELL], vec![three_quarters, one_third]]
    );
    let t = texts(&svg);
    assert!(
        t.iter().any(|x| x == "3/4 goal") && t.iter().any(|x| x == "1/3 goal"),
        "{t:?}"
    );
    // An unknown axis is an error that names the axes.
    let e = plot_sweep(&results, &s.0, Some("push.nope"), None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("push.start"), "{e}");
}
