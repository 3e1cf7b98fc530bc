//! `armcal`: the host tool of quatarm.
//!
//! Each subcommand lives in its own module under `commands/`, which owns its arguments and
//! its output; the library (`armcal::…`) holds the logic they share with tests.

use clap::{Parser, Subcommand};

mod commands;

/// Host tool for articulated-arm CMMs: evaluate, simulate, calibrate, diagnose, build
/// calibration tables, decode firmware streams.
#[derive(Parser)]
#[command(name = "armcal", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Evaluate the arm model on joint readings: CSV in, XYZ and probe direction out.
    Eval(commands::eval::Args),
    /// Simulate measurements of a virtual arm (point, spat, length or sphere data).
    Simulate(commands::simulate::Args),
    /// Identify the arm's parameters from measured data.
    Calibrate(commands::calibrate::Args),
    /// Show what the model gets wrong, name the cause, extend the model, measure the gain.
    Diagnose(commands::diagnose::Args),
    /// Build or show a binary calibration table for the firmware.
    #[command(subcommand)]
    Table(commands::table::Command),
    /// Decode the firmware's binary stream to CSV.
    Decode(commands::decode::Args),
    /// Measure the firmware paths against the f64 reference over random poses.
    Accuracy(commands::accuracy::Args),
    /// Acceptance tests (ISO 10360-12, ASME B89.4.22) on measured data, with the decision.
    Check(commands::check::Args),
}

/// Whether the command line runs `armcal check`, whose errors have an exit code of their own
/// (3): its 1 and 2 are verdicts, which a wrong file must never look like.
fn is_check(args: &[std::ffi::OsString]) -> bool {
    args.iter()
        .skip(1)
        .find(|a| !a.to_string_lossy().starts_with('-'))
        .is_some_and(|a| a == "check")
}

fn main() {
    let args: Vec<std::ffi::OsString> = std::env::args_os().collect();
    let check = is_check(&args);
    let error_code = if check {
        armcal::acceptance::verdict::EXIT_ERROR
    } else {
        1
    };
    let cli = match Cli::try_parse_from(&args) {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            // Help and version are no error; a usage error is clap's 2, check's 3.
            let code = match (e.use_stderr(), check) {
                (false, _) => 0,
                (true, true) => error_code,
                (true, false) => e.exit_code(),
            };
            std::process::exit(code);
        }
    };
    let result = match cli.command {
        Command::Eval(a) => commands::eval::run(a),
        Command::Simulate(a) => commands::simulate::run(a),
        Command::Calibrate(a) => commands::calibrate::run(a),
        Command::Diagnose(a) => commands::diagnose::run(a),
        Command::Table(c) => commands::table::run(c),
        Command::Decode(a) => commands::decode::run(a),
        Command::Accuracy(a) => commands::accuracy::run(a),
        // The verdict's exit code: 0 conforms, 1 does not, 2 cannot decide.
        Command::Check(a) => commands::check::run(a).map(|code| {
            if code != 0 {
                std::process::exit(code)
            }
        }),
    };
    if let Err(e) = result {
        eprintln!("armcal: error: {e:#}");
        std::process::exit(error_code);
    }
}
