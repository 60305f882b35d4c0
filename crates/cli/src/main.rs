//! The `cam` binary: parses flags, shows progress, calls the library crates.
//!
//! Exit codes: 0 success; 1 the job ran but found a problem it was asked to fail on (a gouge
//! beyond tolerance, a holder collision); 2 bad input or usage (the message names the file,
//! line and what is wrong) — in that case no output file is written.

mod cl;
mod exit;
mod plan;
mod progress;
mod verify;
mod xy_csv;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// cam: exact finishing toolpaths from triangle meshes, and their verification.
#[derive(Parser)]
#[command(name = "cam", version, about, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Cutter-location points by exact drop-cutter (inverse tool offset), as CSV.
    Cl(cl::ClArgs),
    /// Plan finishing passes and write G-code (verified unless --no-verify).
    Plan(plan::PlanArgs),
    /// Verify a toolpath (G-code or APT) against the part: swept surface, gouge and excess.
    Verify(verify::VerifyArgs),
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    let result = match cli.command {
        Command::Cl(a) => cl::run(a),
        Command::Plan(a) => plan::run(a),
        Command::Verify(a) => verify::run(a),
    };
    exit::finish(result)
}
