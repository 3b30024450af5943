//! `stride plot`: SVG figures of a run's MCAP log ([`plot_log`]) or a sweep's `results.json`
//! ([`plot_sweep`]). docs/plots.md shows every figure.

use std::path::{Path, PathBuf};

pub mod chart;
pub mod log_figures;
pub mod sweep;

pub use log_figures::{plot_log, GROUND_ESTIMATE_FIGURE, LOG_FIGURES};
pub use sweep::plot_sweep;

/// Why a plot failed.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// The log or results file could not be read or lacks what a figure needs.
    #[error("{0}")]
    Log(String),
    /// An output directory or input file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// Drawing failed.
    #[error("drawing: {0}")]
    Draw(String),
    /// A bad option.
    #[error("{0}")]
    Usage(String),
}

/// The default output directory: `<stem>_plots/` next to a log, the results file's own directory for a
/// sweep.
pub fn default_dir(input: &Path) -> PathBuf {
    let parent = input.parent().unwrap_or(Path::new(""));
    if is_results(input) {
        return parent.to_path_buf();
    }
    let stem = input
        .file_stem()
        .map_or_else(|| "log".into(), |s| s.to_string_lossy().into_owned());
    parent.join(format!("{stem}_plots"))
}

/// A sweep's results (`.json`) rather than a log.
pub fn is_results(input: &Path) -> bool {
    input.extension().is_some_and(|e| e == "json")
}
