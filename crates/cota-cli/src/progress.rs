//! Progress on a terminal, nothing otherwise: bars where the length is
//! known, spinners that tick steadily where it is not. Nothing is drawn when
//! stderr is not a terminal or with `--quiet`.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};

/// `--quiet`: no progress at all.
static QUIET: AtomicBool = AtomicBool::new(false);

/// How often bars and spinners redraw, so that the elapsed time and the
/// spinner move even while a phase reports nothing.
const TICK: Duration = Duration::from_millis(120);

/// Sets `--quiet` for the whole run.
pub fn set_quiet(quiet: bool) {
    QUIET.store(quiet, Ordering::Relaxed);
}

/// True with `--quiet`: no progress, and no text report (errors, warnings
/// and a report asked for with `--json` are still printed).
pub fn quiet() -> bool {
    QUIET.load(Ordering::Relaxed)
}

/// True when progress is drawn: stderr is a terminal and no `--quiet`.
fn shown() -> bool {
    !quiet() && std::io::stderr().is_terminal()
}

/// The style of a bar whose length is known.
fn bar_style(pb: &ProgressBar) {
    if let Ok(style) = ProgressStyle::with_template("{msg:>12} [{bar:30}] {pos}/{len} {elapsed}") {
        pb.set_style(style.progress_chars("=> "));
    }
}

/// A bar of `len` steps on stderr when it is a terminal, hidden otherwise.
/// With `len` 0 (not known yet) it is a spinner until [`set_progress`]
/// gives it a length.
pub fn bar(len: u64, what: &str) -> ProgressBar {
    if !shown() {
        return ProgressBar::hidden();
    }
    let pb = if len == 0 {
        let pb = ProgressBar::new_spinner();
        if let Ok(style) = ProgressStyle::with_template("{msg:>12} {spinner} {elapsed}") {
            pb.set_style(style);
        }
        pb
    } else {
        let pb = ProgressBar::new(len);
        bar_style(&pb);
        pb
    };
    pb.set_message(what.to_string());
    pb.enable_steady_tick(TICK);
    pb
}

/// Moves `pb` to `done` of `total` steps; the first time a total is known,
/// a spinner from [`bar`] becomes a bar.
pub fn set_progress(pb: &ProgressBar, done: u64, total: u64) {
    if total > 0 && pb.length() != Some(total) {
        pb.set_length(total);
        bar_style(pb);
    }
    pb.set_position(done);
}

/// A spinner for a phase of unknown length; cleared when dropped.
pub struct Spinner(ProgressBar);

impl Drop for Spinner {
    fn drop(&mut self) {
        self.0.finish_and_clear();
    }
}

/// A spinner named `what` on stderr when it is a terminal, hidden otherwise.
pub fn spinner(what: &str) -> Spinner {
    if !shown() {
        return Spinner(ProgressBar::hidden());
    }
    let pb = ProgressBar::new_spinner();
    if let Ok(style) = ProgressStyle::with_template("{msg:>12} {spinner} {elapsed}") {
        pb.set_style(style);
    }
    pb.set_message(what.to_string());
    pb.enable_steady_tick(TICK);
    Spinner(pb)
}
