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

/// A closed pipe ends the process quietly, as it does coreutils (`armcal … | head`): the
/// default action of SIGPIPE, which Rust's runtime sets to "ignore" (every write to the
/// closed pipe would then fail, and `println!` panic on it). armcal writes its files before
/// it prints, so nothing is left half-written by the signal.
fn quiet_on_closed_pipe() {
    #[cfg(unix)]
    // SAFETY: called first in `main`, before any thread exists; restoring a signal's default
    // disposition touches no memory of the program.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// Whether an error is the reader's end of a pipe closing (where SIGPIPE does not end the
/// process): nothing to report.
fn closed_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// The error and its causes, each said once: a cause whose text the message already holds
/// (an error that quotes its source, a path named by two layers) is not repeated.
fn message(e: &anyhow::Error) -> String {
    let mut s = e.to_string();
    for cause in e.chain().skip(1) {
        let t = cause.to_string();
        if !s.contains(&t) {
            s.push_str(": ");
            s.push_str(&t);
        }
    }
    s
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
    quiet_on_closed_pipe();
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
        if closed_pipe(&e) {
            std::process::exit(141);
        }
        eprintln!("armcal: error: {}", message(&e));
        std::process::exit(error_code);
    }
}
