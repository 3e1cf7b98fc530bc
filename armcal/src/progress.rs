//! Progress of long computations, kept apart from them: a calibration tells an [`Observer`]
//! what it is doing, and only the command decides whether a person sees it.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// What watches a calibration. Every method has a silent default.
pub trait Observer {
    /// A stage begins (identifiability, the fit, a validation fold…).
    fn stage(&mut self, _what: &str) {}
    /// The solver's iteration `iteration` left an RMS residual of `rms_mm`.
    fn iteration(&mut self, _iteration: usize, _rms_mm: f64) {}
}

/// Sees nothing.
pub struct Silent;

impl Observer for Silent {}

/// A spinner on stderr with the stage and the solver's latest iteration.
pub struct Spinner {
    bar: indicatif::ProgressBar,
    stage: String,
}

impl Spinner {
    /// A spinner, drawn on stderr.
    pub fn new(prefix: &str) -> Spinner {
        let bar = indicatif::ProgressBar::new_spinner();
        bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
        bar.set_style(
            indicatif::ProgressStyle::with_template(&format!(
                "{{spinner}} {prefix}: {{msg}} [{{elapsed}}]"
            ))
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
        );
        bar.enable_steady_tick(Duration::from_millis(200));
        Spinner {
            bar,
            stage: String::new(),
        }
    }
}

impl Observer for Spinner {
    fn stage(&mut self, what: &str) {
        self.stage = what.to_string();
        self.bar.set_message(what.to_string());
    }

    fn iteration(&mut self, iteration: usize, rms_mm: f64) {
        self.bar.set_message(format!(
            "{}: iteration {iteration}, RMS {rms_mm:.4} mm",
            self.stage
        ));
    }
}

impl Drop for Spinner {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}

/// Plain lines on stderr, for a log: each stage, and the solver at most once a second.
pub struct Log {
    prefix: String,
    stage: String,
    last: Option<Instant>,
}

impl Log {
    /// Lines starting with `prefix`.
    pub fn new(prefix: &str) -> Log {
        Log {
            prefix: prefix.to_string(),
            stage: String::new(),
            last: None,
        }
    }
}

impl Observer for Log {
    fn stage(&mut self, what: &str) {
        self.stage = what.to_string();
        eprintln!("armcal: {}: {what}", self.prefix);
    }

    fn iteration(&mut self, iteration: usize, rms_mm: f64) {
        if self
            .last
            .is_some_and(|t| t.elapsed() < Duration::from_secs(1))
        {
            return;
        }
        self.last = Some(Instant::now());
        eprintln!(
            "armcal: {}: {}: iteration {iteration}, RMS {rms_mm:.4} mm",
            self.prefix, self.stage
        );
    }
}

/// The observer a command uses: a spinner when stderr is a terminal, plain lines when it is
/// not but progress was asked for (`--progress`), else silence (a pipe or a log gets nothing
/// it did not ask for).
pub fn for_command(asked: bool, prefix: &str) -> Box<dyn Observer> {
    if std::io::stderr().is_terminal() {
        Box::new(Spinner::new(prefix))
    } else if asked {
        Box::new(Log::new(prefix))
    } else {
        Box::new(Silent)
    }
}
