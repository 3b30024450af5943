//! The `stride` command-line tool. All logic lives in `stride-runner`; this binary only forwards to it so
//! that `cargo run --release -- <subcommand>` works from the workspace root.

fn main() -> std::process::ExitCode {
    stride_runner::commands::main()
}
