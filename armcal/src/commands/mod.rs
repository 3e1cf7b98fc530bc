//! One module per subcommand.

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
