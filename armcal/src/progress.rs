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
    /// Step `done + 1` of `total` like steps begins (validation folds): a stage named with
    /// its count; the observers that show one add the time left.
    fn step(&mut self, what: &str, done: usize, total: usize) {
        self.stage(&format!("{what} {} of {total}", done + 1));
    }
}

/// The stage of a counted step, with the time left once a step is done: the mean time of the
/// steps so far times the steps left. `since` keeps when the first step of `what` began.
fn counted(since: &mut Option<(String, Instant)>, what: &str, done: usize, total: usize) -> String {
    let start = match since {
        Some((w, t)) if w == what && done > 0 => *t,
        _ => {
            *since = Some((what.to_string(), Instant::now()));
            return format!("{what} {} of {total}", done + 1);
        }
    };
    format!(
        "{what} {} of {total}{}",
        done + 1,
        eta(start.elapsed(), done as u64, total as u64)
    )
}

/// Sees nothing.
pub(crate) struct Silent;

impl Observer for Silent {}

/// A spinner on stderr with the stage and the solver's latest iteration.
pub(crate) struct Spinner {
    bar: indicatif::ProgressBar,
    stage: String,
    steps: Option<(String, Instant)>,
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
            steps: None,
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

    fn step(&mut self, what: &str, done: usize, total: usize) {
        let s = counted(&mut self.steps, what, done, total);
        self.stage(&s);
    }
}

impl Drop for Spinner {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}

/// Plain lines on stderr, for a log: each stage, and the solver at most once a second.
pub(crate) struct Log {
    prefix: String,
    stage: String,
    last: Option<Instant>,
    steps: Option<(String, Instant)>,
}

impl Log {
    /// Lines starting with `prefix`.
    pub fn new(prefix: &str) -> Log {
        Log {
            prefix: prefix.to_string(),
            stage: String::new(),
            last: None,
            steps: None,
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

    fn step(&mut self, what: &str, done: usize, total: usize) {
        let s = counted(&mut self.steps, what, done, total);
        self.stage(&s);
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

/// Progress over a known count of items (rows, fits): a bar with the count and the time left
/// on a terminal; with `--progress` but no terminal (a pipe, a log), a line every few seconds
/// with the count and the time left; else nothing. Estimated from the mean time per item so
/// far, which is what indicatif does too.
pub struct Counter {
    shown: Shown,
    total: u64,
    done: u64,
}

enum Shown {
    Bar(indicatif::ProgressBar),
    Lines {
        prefix: String,
        what: String,
        start: Instant,
        last: Instant,
    },
    Nothing,
}

/// Seconds between two lines of a [`Counter`] without a terminal.
const LINE_EVERY: Duration = Duration::from_secs(5);

impl Counter {
    /// A counter of `total` `what` (e.g. "rows") for the command `prefix`; `asked`: the
    /// user gave `--progress`.
    pub fn new(asked: bool, prefix: &str, what: &str, total: u64) -> Counter {
        let shown = if std::io::stderr().is_terminal() {
            let bar = indicatif::ProgressBar::new(total);
            bar.set_draw_target(indicatif::ProgressDrawTarget::stderr());
            bar.set_style(
                indicatif::ProgressStyle::with_template(&format!(
                    "{prefix}: {{bar:30}} {{pos}}/{{len}} {what} [{{elapsed}}, {{eta}} left]"
                ))
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            Shown::Bar(bar)
        } else if asked {
            let now = Instant::now();
            Shown::Lines {
                prefix: prefix.to_string(),
                what: what.to_string(),
                start: now,
                last: now,
            }
        } else {
            Shown::Nothing
        };
        Counter {
            shown,
            total,
            done: 0,
        }
    }

    /// One more item done.
    pub fn tick(&mut self) {
        self.done += 1;
        match &mut self.shown {
            Shown::Bar(bar) => bar.inc(1),
            Shown::Lines {
                prefix,
                what,
                start,
                last,
            } => {
                if last.elapsed() >= LINE_EVERY || self.done == self.total {
                    *last = Instant::now();
                    eprintln!(
                        "armcal: {prefix}: {} of {} {what}{}",
                        self.done,
                        self.total,
                        eta(start.elapsed(), self.done, self.total)
                    );
                }
            }
            Shown::Nothing => {}
        }
    }
}

/// ", about N s left" from the time `elapsed` over `done` of `total` items (nothing when
/// all are done or none yet).
fn eta(elapsed: Duration, done: u64, total: u64) -> String {
    if done == 0 || done >= total {
        return String::new();
    }
    let left = elapsed.as_secs_f64() / done as f64 * (total - done) as f64;
    format!(", about {left:.0} s left")
}

impl Drop for Counter {
    fn drop(&mut self) {
        if let Shown::Bar(bar) = &self.shown {
            bar.finish_and_clear();
        }
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn eta_is_the_mean_time_per_item_times_the_items_left() {
        let e = super::eta(std::time::Duration::from_secs(10), 1000, 3000);
        assert_eq!(e, ", about 20 s left");
        assert_eq!(super::eta(std::time::Duration::from_secs(10), 0, 3000), "");
        assert_eq!(
            super::eta(std::time::Duration::from_secs(10), 3000, 3000),
            ""
        );
    }

    #[test]
    fn a_counted_stage_adds_the_time_left_from_its_second_step() {
        let mut since = None;
        assert_eq!(super::counted(&mut since, "fold", 0, 5), "fold 1 of 5");
        std::thread::sleep(std::time::Duration::from_millis(5));
        let second = super::counted(&mut since, "fold", 1, 5);
        assert!(second.starts_with("fold 2 of 5, about "), "{second}");
        assert!(second.ends_with(" s left"), "{second}");
        // Another stage starts its own clock.
        assert_eq!(
            super::counted(&mut since, "session", 1, 3),
            "session 2 of 3"
        );
    }
}
