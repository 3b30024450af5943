//! `stride sweep`: results independent of the thread count and of sharding, key errors located in the
//! sweep file, reproducible random sampling, push directions.
mod common;

use std::path::{Path, PathBuf};

use clap::Parser;
use common::Scratch;
use stride_runner::cli::Cli;
use stride_runner::commands::dispatch;
use stride_runner::config::ConfigError;
use stride_runner::sweep::{self, Sweep, SweepOptions};

/// A 1 s walk (the default walk, cut short) and a sweep of 4 variants over it: mass scale × push direction.
fn small_sweep(s: &Scratch, extra: &str) -> PathBuf {
    let walk = common::root().join("configs/walk_straight.toml");
    s.write(
        "walk_short.toml",
        &format!(
            "include = [{:?}]\n[scenario]\nduration = 1.0\n",
            walk.canonicalize().unwrap()
        ),
    );
    s.write(
        "sweeps/small.toml",
        &format!(
            "[sweep]\nscenario = \"../walk_short.toml\"\n{extra}\n\
             [[sweep.axes]]\nkey = \"sim.model.mass_scale\"\nvalues = [0.9, 1.1]\n\
             [sweep.push]\nframe = \"chest\"\nduration = 0.3\nmagnitudes = [30.0]\n\
             directions_deg = [0.0, 90.0]\nstarts = [0.5]\n"
        ),
    )
}

/// `results.csv` with the `wall_s` column removed (the only wall-clock column).
fn csv_without_wall(dir: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("results.csv")).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let wall = header.iter().position(|c| *c == "wall_s").unwrap();
    text.lines()
        .map(|l| {
            let mut cells: Vec<&str> = l.split(',').collect();
            cells.remove(wall);
            cells.join(",")
        })
        .collect()
}

fn cli(args: &[&str]) {
    let mut argv = vec!["stride"];
    argv.extend(args);
    dispatch(Cli::try_parse_from(argv).unwrap()).unwrap();
}

#[test]
fn results_do_not_depend_on_threads_or_shards() {
    let s = Scratch::new("sweep-jobs");
    let file = small_sweep(&s, "");
    let f = file.to_str().unwrap();
    let dir = |n: &str| s.path(n).to_str().unwrap().to_string();
    cli(&["sweep", f, "-j", "1", "-o", &dir("j1"), "--no-progress"]);
    cli(&["sweep", f, "-j", "2", "-o", &dir("j2"), "--no-progress"]);
    cli(&[
        "sweep",
        f,
        "--shard",
        "1/2",
        "-o",
        &dir("s1"),
        "--no-progress",
    ]);
    cli(&[
        "sweep",
        f,
        "--shard",
        "2/2",
        "-o",
        &dir("s2"),
        "--no-progress",
    ]);
    cli(&[
        "sweep",
        "merge",
        &dir("s2"),
        &dir("s1"),
        "-o",
        &dir("merged"),
    ]);
    let j1 = csv_without_wall(&s.path("j1"));
    assert_eq!(j1.len(), 5, "{j1:?}");
    assert!(j1[1].contains(",timeout,"), "{}", j1[1]);
    assert_eq!(j1, csv_without_wall(&s.path("j2")));
    assert_eq!(j1, csv_without_wall(&s.path("merged")));
    // Shard 1/2 holds the even variants.
    let s1 = csv_without_wall(&s.path("s1"));
    assert_eq!(s1.len(), 3);
    assert!(s1[1].starts_with("0,") && s1[2].starts_with("2,"), "{s1:?}");
    // results.json round-trips: the merged one equals the single run's but for wall_s.
    let strip = |d: &str| {
        let mut r = sweep::Results::read(&s.path(d)).unwrap();
        let w = r.columns.iter().position(|c| c == "wall_s").unwrap() - 1;
        for row in &mut r.rows {
            row.cells[w] = sweep::Cell::Empty;
        }
        r
    };
    assert_eq!(strip("j1"), strip("merged"));
    // Merging an incomplete set is refused.
    let partial = sweep::merge(vec![sweep::Results::read(&s.path("s1")).unwrap()]);
    assert!(partial.unwrap_err().contains("missing"));
}

#[test]
fn push_direction_90_pushes_along_y() {
    let s = Scratch::new("sweep-push");
    let sw = Sweep::load(&small_sweep(&s, "")).unwrap();
    assert_eq!(sw.variants.len(), 4);
    let v = &sw.variants[1];
    assert_eq!(v.push.unwrap().direction_deg, 90.0);
    let sc = sw.scenario(v).unwrap();
    let p = sc.config.sim.pushes.last().unwrap();
    assert_eq!(p.frame, "chest");
    assert_eq!((p.start, p.duration), (0.5, 0.3));
    assert_eq!(p.wrench, [0.0, 30.0, 0.0, 0.0, 0.0, 0.0]);
    assert_eq!(sc.config.sim.model.mass_scale, 0.9);
    let p0 = sw.scenario(&sw.variants[0]).unwrap();
    assert_eq!(
        p0.config.sim.pushes.last().unwrap().wrench,
        [30.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    );
    assert_eq!(sweep::push_force(10.0, 180.0), [-10.0, 0.0]);
    assert_eq!(sweep::push_force(10.0, 270.0), [0.0, -10.0]);
}

fn load_err(s: &Scratch, text: &str) -> (usize, String) {
    let walk = common::root().join("configs/walk_straight.toml");
    let p = s.write(
        "bad.toml",
        &format!(
            "[sweep]\nscenario = {:?}\n{text}",
            walk.canonicalize().unwrap()
        ),
    );
    match Sweep::load(&p) {
        Err(ConfigError::Invalid {
            location: Some(l),
            key,
            message,
        }) => {
            assert_eq!(l.path, p);
            (l.line, format!("{key}: {message}"))
        }
        other => panic!("expected a located error, got {other:?}"),
    }
}

#[test]
fn key_errors_name_the_sweep_file_line() {
    let s = Scratch::new("sweep-errors");
    // Unknown key: the line of `key`.
    let (line, m) = load_err(
        &s,
        "[[sweep.axes]]\nkey = \"sim.contact.normal_stiffnes\"\nvalues = [1e6]\n",
    );
    assert_eq!(line, 4, "{m}");
    assert!(m.contains("unknown field `normal_stiffnes`"), "{m}");
    // Wrong type: the line of the value.
    let (line, m) = load_err(
        &s,
        "[[sweep.axes]]\nkey = \"sim.contact.normal_stiffness\"\nvalues = [\n  1e6,\n  \"soft\",\n]\n",
    );
    assert_eq!(line, 7, "{m}");
    assert!(m.contains("invalid type"), "{m}");
    // Out of range (the scenario's validation): the line of the value.
    let (line, m) = load_err(
        &s,
        "[[sweep.axes]]\nkey = \"sim.contact.normal_damping\"\nvalues = [1e3,\n -1.0]\n",
    );
    assert_eq!(line, 6, "{m}");
    // An array entry past the end.
    let (line, m) = load_err(
        &s,
        "[[sweep.axes]]\nkey = \"sim.pushes[3].start\"\nvalues = [1.0]\n",
    );
    assert_eq!(line, 4, "{m}");
    // A key of the sweep file itself.
    let (line, m) = load_err(&s, "sample = 3\n");
    assert_eq!(line, 3, "{m}");
}

#[test]
fn random_mode_is_reproducible_from_its_seed() {
    let s = Scratch::new("sweep-random");
    let text = |seed: u64| {
        format!(
            "mode = \"random\"\nsamples = 6\nseed = {seed}\n\
             [[sweep.axes]]\nkey = \"sim.contact.friction_coefficient\"\nmin = 0.3\nmax = 1.0\n"
        )
    };
    let values = |seed: u64| {
        let p = small_sweep(&s, &text(seed));
        let sw = Sweep::load(&p).unwrap();
        assert_eq!(sw.variants.len(), 6);
        sw.variants
            .iter()
            .map(|v| format!("{:?} {:?}", v.values, v.push))
            .collect::<Vec<_>>()
    };
    let a = values(7);
    assert_eq!(a, values(7));
    assert_ne!(a, values(8));
    let sw = Sweep::load(&small_sweep(&s, &text(7))).unwrap();
    for v in &sw.variants {
        let mu = v.values[0].as_float().unwrap();
        assert!((0.3..=1.0).contains(&mu), "{mu}");
        assert!([0.9, 1.1].contains(&v.values[1].as_float().unwrap()));
    }
    // The sampled values reach the scenario.
    let sc = sw.scenario(&sw.variants[2]).unwrap();
    assert_eq!(
        sc.config.sim.contact.friction_coefficient,
        sw.variants[2].values[0].as_float().unwrap()
    );
}

#[test]
fn sweep_options_default_to_every_core() {
    let o = SweepOptions::default();
    assert_eq!(o.jobs, 0);
    assert!("0/2".parse::<sweep::Shard>().is_err());
    assert!("3/2".parse::<sweep::Shard>().is_err());
    let sh: sweep::Shard = "2/3".parse().unwrap();
    assert!(sh.owns(1) && sh.owns(4) && !sh.owns(0));
}

#[test]
fn example_sweeps_load() {
    let dir = common::root().join("configs/sweeps");
    for (file, n) in [
        ("push_walk.toml", 48),
        ("ground_contact.toml", 6),
        ("mass_mismatch.toml", 7),
    ] {
        let sw = Sweep::load(&dir.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_eq!(sw.variants.len(), n, "{file}");
        for v in &sw.variants {
            sw.scenario(v).unwrap_or_else(|e| panic!("{file}: {e}"));
        }
    }
}
