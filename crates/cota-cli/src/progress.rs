//! Progress of each phase: on a terminal, a bar with its fraction, elapsed
//! time and time left (a spinner for a phase whose length is not known);
//! with the hidden `COTA_PROGRESS=plain`, plain lines `PHASE DONE/TOTAL` on
//! stderr instead, at each new percent (for tests and logs); nothing
//! otherwise, and nothing at all with `--quiet`.

use std::io::{IsTerminal, Write as _};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};

/// `--quiet`: no progress at all.
static QUIET: AtomicBool = AtomicBool::new(false);

/// How often bars and spinners redraw, so that the elapsed time and the
/// spinner move even while a phase reports nothing.
const TICK: Duration = Duration::from_millis(120);

/// The environment variable that asks for plain progress lines
/// (`COTA_PROGRESS=plain`), whether stderr is a terminal or not.
const PLAIN_VAR: &str = "COTA_PROGRESS";

/// Sets `--quiet` for the whole run.
pub fn set_quiet(quiet: bool) {
    QUIET.store(quiet, Ordering::Relaxed);
}

/// True with `--quiet`: no progress, and no text report (errors, warnings
/// and a report asked for with `--json` are still printed).
pub fn quiet() -> bool {
    QUIET.load(Ordering::Relaxed)
}

/// How progress is shown in this run.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Shown {
    /// Not at all: `--quiet`, or stderr is not a terminal.
    Hidden,
    /// Bars and spinners drawn on the terminal.
    Drawn,
    /// Plain lines (`COTA_PROGRESS=plain`).
    Plain,
}

fn shown() -> Shown {
    if quiet() {
        Shown::Hidden
    } else if std::env::var_os(PLAIN_VAR).is_some_and(|v| v == "plain") {
        Shown::Plain
    } else if std::io::stderr().is_terminal() {
        Shown::Drawn
    } else {
        Shown::Hidden
    }
}

/// What a bar counts.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Unit {
    Steps,
    Bytes,
}

/// The style of a bar whose length is known: the fraction, the elapsed time
/// and the time left.
fn bar_style(pb: &ProgressBar, unit: Unit) {
    let count = match unit {
        Unit::Steps => "{human_pos}/{human_len}",
        Unit::Bytes => "{bytes}/{total_bytes}",
    };
    let template =
        format!("{{msg:>14}} [{{bar:30}}] {{percent:>3}}% {count}  {{elapsed}}, {{eta}} left");
    if let Ok(style) = ProgressStyle::with_template(&template) {
        pb.set_style(style.progress_chars("=> "));
    }
}

/// The style of a phase whose length is not known (yet).
fn spinner_style(pb: &ProgressBar) {
    if let Ok(style) = ProgressStyle::with_template("{msg:>14} {spinner} {elapsed}") {
        pb.set_style(style);
    }
}

/// The progress of one phase, shown as [`shown`] says; cleared when
/// dropped. Safe to move from several threads at once (rayon loops report
/// through it): it never moves back, and plain lines come in order.
pub struct Bar {
    pb: ProgressBar,
    plain: bool,
    unit: Unit,
    what: String,
    state: Mutex<State>,
}

/// Where a [`Bar`] stands.
#[derive(Debug, Default)]
struct State {
    done: u64,
    total: u64,
    /// The percent of the last plain line, if any.
    printed: Option<u64>,
}

/// A bar of `len` steps named `what`. With `len` 0 (not known yet) it is a
/// spinner until [`Bar::set`] gives it a length.
pub fn bar(len: u64, what: &str) -> Bar {
    Bar::new(len, what, Unit::Steps)
}

/// A bar of `len` bytes named `what`.
pub fn bytes(len: u64, what: &str) -> Bar {
    Bar::new(len, what, Unit::Bytes)
}

impl Bar {
    fn new(len: u64, what: &str, unit: Unit) -> Bar {
        let shown = shown();
        let pb = match shown {
            Shown::Drawn if len > 0 => {
                let pb = ProgressBar::new(len);
                bar_style(&pb, unit);
                pb
            }
            Shown::Drawn => {
                let pb = ProgressBar::new_spinner();
                spinner_style(&pb);
                pb
            }
            Shown::Hidden | Shown::Plain => ProgressBar::hidden(),
        };
        if shown == Shown::Drawn {
            pb.set_message(what.to_string());
            pb.enable_steady_tick(TICK);
        }
        let bar = Bar {
            pb,
            plain: shown == Shown::Plain,
            unit,
            what: what.to_string(),
            state: Mutex::new(State::default()),
        };
        if len > 0 {
            bar.set(0, len);
        }
        bar
    }

    /// Moves the bar to `done` of `total` (a spinner becomes a bar the first
    /// time a total is known). A `done` below one already shown is ignored
    /// (several threads report in any order) unless the total changed.
    pub fn set(&self, done: u64, total: u64) {
        let Ok(mut s) = self.state.lock() else {
            return;
        };
        let done = done.min(total);
        if total != s.total {
            *s = State {
                done,
                total,
                printed: None,
            };
            if !self.pb.is_hidden() {
                self.pb.set_length(total);
                bar_style(&self.pb, self.unit);
            }
        } else if done < s.done {
            return;
        }
        s.done = done;
        self.pb.set_position(done);
        if self.plain && total > 0 {
            let pct = done.saturating_mul(100) / total;
            if s.printed.is_none_or(|p| pct > p) {
                s.printed = Some(pct);
                // One write per line, so that threads do not interleave.
                let line = format!("{} {done}/{total}\n", self.what);
                let _ = std::io::stderr().lock().write_all(line.as_bytes());
            }
        }
    }

    /// Moves the bar to `done` of the total it has.
    pub fn set_position(&self, done: u64) {
        let total = self.state.lock().map_or(0, |s| s.total);
        self.set(done, total);
    }

    /// The bar as a `(done, total)` callback, what the core's progress
    /// parameters take.
    pub fn report(&self) -> impl Fn(usize, usize) + Sync + '_ {
        |done, total| self.set(done as u64, total as u64)
    }
}

impl Drop for Bar {
    fn drop(&mut self) {
        self.pb.finish_and_clear();
    }
}

/// A spinner for a short phase of unknown length; cleared when dropped.
pub struct Spinner(ProgressBar);

impl Drop for Spinner {
    fn drop(&mut self) {
        self.0.finish_and_clear();
    }
}

/// A spinner named `what`, drawn on a terminal only (plain progress has no
/// line for it).
pub fn spinner(what: &str) -> Spinner {
    if shown() != Shown::Drawn {
        return Spinner(ProgressBar::hidden());
    }
    let pb = ProgressBar::new_spinner();
    spinner_style(&pb);
    pb.set_message(what.to_string());
    pb.enable_steady_tick(TICK);
    Spinner(pb)
}
