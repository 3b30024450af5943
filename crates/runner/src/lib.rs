//! stride-runner: configuration, scheduler, MCAP logging, replay and the `stride` command line.
#![warn(missing_docs)]

/// `println!` that ignores a closed stdout (e.g. piped into `head`) instead of panicking.
#[macro_export]
macro_rules! outln {
    ($($t:tt)*) => { $crate::cli::write_stdout(format_args!("{}\n", format_args!($($t)*))) };
}

/// `print!` that ignores a closed stdout.
#[macro_export]
macro_rules! out {
    ($($t:tt)*) => { $crate::cli::write_stdout(format_args!($($t)*)) };
}

pub mod calibrate;
pub mod calibrate_matrix;
pub mod centroidal;
pub mod check;
pub mod cli;
pub mod commands;
pub mod config;
pub mod diagnosis;
pub mod error;
pub mod estimation_summary;
pub mod feet;
pub mod flexible;
pub mod gait;
pub mod ground_estimate;
pub mod identify;
pub mod init;
pub mod joint_trajectory;
pub mod log;
mod log_json;
pub mod mcap_file;
pub mod model_cmd;
#[cfg(feature = "mujoco")]
pub mod mujoco_plant;
pub mod plot;
pub mod position_command;
pub mod push;
pub mod push_weights;
pub mod records;
pub mod replay;
pub mod robot;
pub mod run;
pub mod setup;
pub mod sim_plant;
pub mod sink;
pub mod soft_soles;
pub mod stack;
pub mod step_adjust;
pub mod summary;
pub mod sweep;
pub mod sweep_cmd;
mod tf_json;
mod tracking;
pub mod wrench_split;
