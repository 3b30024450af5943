//! The `stride` command line (work in progress).
use std::process::ExitCode;

/// Entry point of the `stride` binary.
pub fn main() -> ExitCode {
    eprintln!("stride: not implemented yet");
    ExitCode::FAILURE
}
