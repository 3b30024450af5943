//! stride-runner: configuration, scheduler, MCAP logging, replay and the `stride` command line.
pub mod cli;
