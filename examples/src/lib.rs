//! What the four example programs share: a list of named checks printed as they run, and the exit code
//! they end with (non-zero when a check failed, so that CI notices).

use std::process::ExitCode;

/// The checks of one example program.
#[derive(Debug, Default)]
pub struct Checks {
    failed: Vec<String>,
}

impl Checks {
    /// Checks that `value` is at most `limit` (both in the unit `unit`), prints the result.
    pub fn at_most(&mut self, what: &str, value: f64, limit: f64, unit: &str) {
        self.that(
            what,
            value <= limit,
            &format!("{value:.3e} {unit} (limit {limit:.1e})"),
        );
    }

    /// Checks that `value` is at least `limit`, prints the result.
    pub fn at_least(&mut self, what: &str, value: f64, limit: f64, unit: &str) {
        self.that(
            what,
            value >= limit,
            &format!("{value:.4} {unit} (at least {limit:.4})"),
        );
    }

    /// Records `ok` under `what`, with `detail` printed beside it.
    pub fn that(&mut self, what: &str, ok: bool, detail: &str) {
        println!("{} {what}: {detail}", if ok { "ok  " } else { "FAIL" });
        if !ok {
            self.failed.push(what.to_owned());
        }
    }

    /// The program's exit code: failure when any check failed.
    pub fn finish(self) -> ExitCode {
        if self.failed.is_empty() {
            println!("all checks passed");
            ExitCode::SUCCESS
        } else {
            eprintln!("failed: {}", self.failed.join(", "));
            ExitCode::FAILURE
        }
    }
}

/// Runs an example's body: its checks' exit code, or failure with the error printed.
pub fn run(body: impl FnOnce(&mut Checks) -> Result<(), Box<dyn std::error::Error>>) -> ExitCode {
    let mut checks = Checks::default();
    match body(&mut checks) {
        Ok(()) => checks.finish(),
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
