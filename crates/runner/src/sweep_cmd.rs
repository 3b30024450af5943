//! The `stride sweep` and `stride sweep merge` subcommands.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use crate::cli::{CliError, SweepArgs, SweepCommand};
use crate::sweep::{self, Results, Sweep, SweepOptions};

/// `stride sweep SWEEP.toml [-j N] [-o DIR] [--shard I/N] [--logs]` or `stride sweep merge DIR... -o DIR`.
pub fn sweep(args: SweepArgs) -> Result<ExitCode, CliError> {
    if let Some(SweepCommand::Merge { dirs, output }) = args.command {
        return merge(&dirs, &output);
    }
    let path = args
        .file
        .ok_or_else(|| CliError::msg("expected a sweep file or `merge`"))?;
    let sweep = Sweep::load(&path)?;
    let out = args.output.unwrap_or_else(|| sweep::default_output(&path));
    let stop = Arc::new(AtomicBool::new(false));
    {
        let stop = Arc::clone(&stop);
        let _ = ctrlc::set_handler(move || stop.store(true, Ordering::SeqCst));
    }
    let options = SweepOptions {
        jobs: args.jobs.unwrap_or(0),
        shard: args.shard,
        logs: args.logs.then(|| out.join("logs")),
        progress: !args.no_progress,
        stop: Some(Arc::clone(&stop)),
    };
    if let Some(l) = &options.logs {
        std::fs::create_dir_all(l).map_err(|e| CliError::msg(format!("{}: {e}", l.display())))?;
    }
    let n = sweep
        .variants
        .iter()
        .filter(|v| options.shard.is_none_or(|s| s.owns(v.index)))
        .count();
    crate::outln!(
        "sweep {}: {} variants of {}{}",
        path.display(),
        sweep.variants.len(),
        sweep.base.config.scenario.name,
        options
            .shard
            .map(|s| format!(", shard {}/{}: {n} variants", s.index, s.count))
            .unwrap_or_default()
    );
    let results = sweep::run(&sweep, &options);
    write(&results, &out)?;
    crate::out!(
        "{}",
        sweep::results::outcome_table(&results, sweep.columns.len())
    );
    crate::outln!("results: {}", out.join("results.csv").display());
    if stop.load(Ordering::SeqCst) {
        return Err(CliError::msg(format!(
            "interrupted: {} of {n} variants ran (their rows are written)",
            results.rows.len()
        )));
    }
    Ok(ExitCode::SUCCESS)
}

fn merge(dirs: &[PathBuf], out: &Path) -> Result<ExitCode, CliError> {
    let parts = dirs
        .iter()
        .map(|d| Results::read(d))
        .collect::<Result<Vec<_>, _>>()
        .map_err(CliError::msg)?;
    let merged = sweep::merge(parts).map_err(CliError::msg)?;
    write(&merged, out)?;
    for d in dirs {
        copy_logs(&d.join("logs"), &out.join("logs"))?;
    }
    let axes = merged.columns.len() - 1 - sweep::METRIC_COLUMNS.len();
    crate::out!("{}", sweep::results::outcome_table(&merged, axes));
    crate::outln!(
        "merged {} shards ({} variants) into {}",
        dirs.len(),
        merged.variants,
        out.join("results.csv").display()
    );
    Ok(ExitCode::SUCCESS)
}

fn write(r: &Results, dir: &Path) -> Result<(), CliError> {
    r.write(dir)
        .map_err(|e| CliError::msg(format!("writing {}: {e}", dir.display())))
}

/// Copies a shard's `logs/` (if any) into the merged folder.
fn copy_logs(from: &Path, to: &Path) -> Result<(), CliError> {
    let Ok(entries) = std::fs::read_dir(from) else {
        return Ok(());
    };
    let err =
        |e: std::io::Error| CliError::msg(format!("copying logs from {}: {e}", from.display()));
    std::fs::create_dir_all(to).map_err(err)?;
    for e in entries {
        let e = e.map_err(err)?;
        std::fs::copy(e.path(), to.join(e.file_name())).map_err(err)?;
    }
    Ok(())
}
