//! One module per subcommand, and the few helpers they share.

pub mod accept;
pub mod accuracy;
pub mod args;
pub mod budget;
pub mod calibrate;
pub mod check;
pub mod data_in;
pub mod decode;
pub mod diagnose;
pub mod eval;
pub mod simulate;
pub mod table;
pub mod written;

/// Prints a command's report on stdout: its JSON with `--json` (for a program), else its
/// text (for a person); only the one asked for is made.
pub fn print_report(
    json: bool,
    as_json: impl FnOnce() -> String,
    as_text: impl FnOnce() -> String,
) {
    if json {
        println!("{}", as_json());
    } else {
        print!("{}", as_text());
    }
}
