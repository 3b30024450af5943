//! stride-runner: configuration, scheduler, MCAP logging, replay and the `stride` command line.
#![warn(missing_docs)]

pub mod cli;
pub mod commands;
pub mod config;
pub mod log;
pub mod model_cmd;
pub mod records;
pub mod replay;
pub mod robot;
pub mod run;
pub mod sim_plant;
pub mod stack;
