//! `stride sweep`: one scenario run over a grid or a random sample of parameter values, variants in
//! parallel, results as CSV and JSON (format and recipes: `docs/sweeps.md`).
//!
//! Every variant is a deterministic run of its own scenario ([`spec::Sweep::scenario`]), so its row is the
//! same whatever the number of threads or the shard that ran it; only `wall_s` measures wall-clock time.

pub mod results;
pub mod spec;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Instant;

pub use results::{merge, Cell, Results, Row, METRIC_COLUMNS};
pub use spec::{push_force, Sweep, Variant};

use crate::run::{run_scenario, RunOptions};

/// `--shard I/N`: variant `k` belongs to shard `I` when `k mod N = I − 1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// 1-based shard number.
    pub index: usize,
    /// Number of shards.
    pub count: usize,
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("`{s}`: expected I/N with 1 ≤ I ≤ N, e.g. 1/4");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count) = (
            i.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        if index == 0 || index > count {
            return Err(bad());
        }
        Ok(Self { index, count })
    }
}

impl Shard {
    /// Whether variant `k` is this shard's.
    pub fn owns(&self, k: usize) -> bool {
        k % self.count == self.index - 1
    }
}

/// How to run a sweep.
#[derive(Debug, Clone, Default)]
pub struct SweepOptions {
    /// Worker threads (0: the core count).
    pub jobs: usize,
    /// Only this shard's variants.
    pub shard: Option<Shard>,
    /// Write each variant's MCAP log into this folder (`variant_NNNN.mcap`).
    pub logs: Option<PathBuf>,
    /// Draw a progress bar over runs (when stderr is a terminal).
    pub progress: bool,
    /// Set from outside (Ctrl-C) to stop: running variants end as interrupted, no new one starts.
    pub stop: Option<Arc<AtomicBool>>,
}

/// Runs the sweep's variants (this shard's) on `options.jobs` threads; rows by variant index. Variants
/// whose scenario is invalid or whose run fails are `error` rows (the reason on stderr). Variants not
/// started because of `stop` have no row.
pub fn run(sweep: &Sweep, options: &SweepOptions) -> Results {
    let todo: Vec<&Variant> = sweep
        .variants
        .iter()
        .filter(|v| options.shard.is_none_or(|s| s.owns(v.index)))
        .collect();
    let jobs = match options.jobs {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        j => j,
    }
    .min(todo.len().max(1));
    let bar = progress_bar(options.progress, todo.len());
    let next = AtomicUsize::new(0);
    let rows: Mutex<Vec<Row>> = Mutex::new(Vec::with_capacity(todo.len()));
    std::thread::scope(|scope| {
        for _ in 0..jobs {
            scope.spawn(|| loop {
                if options
                    .stop
                    .as_ref()
                    .is_some_and(|s| s.load(Ordering::SeqCst))
                {
                    break;
                }
                let Some(v) = todo.get(next.fetch_add(1, Ordering::SeqCst)) else {
                    break;
                };
                let row = run_variant(sweep, v, options);
                if let Some(b) = &bar {
                    b.inc(1);
                }
                rows.lock().unwrap_or_else(|p| p.into_inner()).push(row);
            });
        }
    });
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    let mut rows = rows.into_inner().unwrap_or_else(|p| p.into_inner());
    rows.sort_by_key(|r| r.variant);
    let mut columns = vec!["variant".to_string()];
    columns.extend(sweep.columns.iter().cloned());
    columns.extend(METRIC_COLUMNS.iter().map(|c| c.to_string()));
    Results {
        columns,
        variants: sweep.variants.len(),
        shard: options.shard.map(|s| format!("{}/{}", s.index, s.count)),
        rows,
    }
}

fn run_variant(sweep: &Sweep, v: &Variant, options: &SweepOptions) -> Row {
    let start = Instant::now();
    let summary = sweep.scenario(v).map_err(|e| e.to_string()).and_then(|sc| {
        let run = RunOptions {
            output: options
                .logs
                .as_ref()
                .map(|d| d.join(format!("variant_{:04}.mcap", v.index))),
            no_log: options.logs.is_none(),
            stop: options.stop.clone(),
            ..RunOptions::default()
        };
        run_scenario(&sc, &run).map_err(|e| crate::cli::one_paragraph(&e))
    });
    let wall = start.elapsed().as_secs_f64();
    match &summary {
        Ok(s) => {
            if let crate::run::Outcome::Error { message } = &s.outcome {
                tracing::warn!("variant {} ({}): {message}", v.index, sweep.describe(v));
            }
        }
        Err(e) => eprintln!("variant {} ({}): {e}", v.index, sweep.describe(v)),
    }
    let mut cells: Vec<Cell> = v.values.iter().map(Cell::from_toml).collect();
    cells.extend(results::metric_cells(summary.as_ref().ok(), wall));
    Row {
        variant: v.index,
        cells,
    }
}

fn progress_bar(enabled: bool, n: usize) -> Option<indicatif::ProgressBar> {
    use std::io::IsTerminal;
    if !enabled || !std::io::stderr().is_terminal() {
        return None;
    }
    let pb = indicatif::ProgressBar::new(n as u64);
    let style =
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} runs  {elapsed} (eta {eta})")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar());
    pb.set_style(style);
    Some(pb)
}

/// The default output folder of a sweep file: `sweep_<file stem>` in the working directory.
pub fn default_output(path: &Path) -> PathBuf {
    let stem = path
        .file_stem()
        .map_or_else(|| "sweep".into(), |s| s.to_string_lossy().into_owned());
    PathBuf::from(format!("sweep_{stem}"))
}
