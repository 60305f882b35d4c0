//! Mapping results to messages and exit codes (the only place that prints errors).

use std::process::ExitCode;

/// A job that ran to the end but must fail (exit 1) because of what it found.
#[derive(Debug)]
pub struct Findings(pub String);

impl std::fmt::Display for Findings {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}
impl std::error::Error for Findings {}

/// Prints an error chain as `cam: error: ...` and turns it into the exit code.
pub fn finish(result: anyhow::Result<()>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.downcast_ref::<Findings>().is_some() => {
            eprintln!("cam: {e}");
            ExitCode::from(1)
        }
        Err(e) => {
            eprintln!("cam: error: {e}");
            for cause in e.chain().skip(1) {
                eprintln!("  caused by: {cause}");
            }
            ExitCode::from(2)
        }
    }
}
