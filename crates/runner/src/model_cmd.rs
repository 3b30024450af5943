//! `stride model info` and `stride model eval`.
use std::process::ExitCode;

use crate::cli::{CliError, ModelCommand};

/// Runs a `stride model` subcommand.
pub fn model(_command: ModelCommand) -> Result<ExitCode, CliError> {
    Err(CliError::msg("stride model: stride-model is not available yet"))
}
