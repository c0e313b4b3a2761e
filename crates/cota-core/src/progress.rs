//! Progress callbacks: a long entry point (`*_with_progress`) calls a
//! [`Progress`] with `(done, total)` as it goes, from any thread, and with
//! `(total, total)` when it is done. Only the caller decides what to do with
//! it (the CLI draws a bar); the plain entry points pass [`NONE`], which
//! costs one empty call every few thousand rows.
//!
//! Inside the crate, `Counter` counts work done in parallel loops and
//! reports at most a few hundred times; `Stages` turns the stages of a
//! phase, each with its own `(done, total)`, into one fraction of the phase
//! (in thousandths), each stage weighted by its share of the phase's time.

use std::sync::atomic::{AtomicUsize, Ordering};

/// A callback told `(done, total)` as work progresses: steps, levels or rows,
/// as the function taking it says.
pub type Progress<'a> = &'a (dyn Fn(usize, usize) + Sync);

/// A progress callback that does nothing.
pub const NONE: Progress<'static> = &|_, _| {};

/// How many times at most a [`Counter`] reports (plus the end).
const REPORTS: usize = 256;

/// Counts work done (rows, samples) from any thread and reports it to a
/// [`Progress`] each time another 1/256 of the total is done, and at the end.
pub(crate) struct Counter<'a> {
    progress: Progress<'a>,
    total: usize,
    done: AtomicUsize,
}

impl<'a> Counter<'a> {
    /// A counter of `total` units, reporting `(0, total)` at once.
    pub(crate) fn new(progress: Progress<'a>, total: usize) -> Self {
        progress(0, total);
        Counter {
            progress,
            total,
            done: AtomicUsize::new(0),
        }
    }

    /// Counts `n` more units done.
    pub(crate) fn add(&self, n: usize) {
        let before = self.done.fetch_add(n, Ordering::Relaxed);
        let after = (before + n).min(self.total);
        let step = |d: usize| d.saturating_mul(REPORTS) / self.total.max(1);
        if step(after) != step(before) || after == self.total {
            (self.progress)(after, self.total);
        }
    }
}

/// The stages of one phase, weighted: stage `i`'s `(done, total)` is
/// reported as the phase's `(start_i + weight_i · done / total, SCALE)`.
pub(crate) struct Stages<'a> {
    progress: Progress<'a>,
    /// Each stage's start, in thousandths of the phase; then [`SCALE`].
    starts: Vec<usize>,
}

/// The total a [`Stages`] reports: thousandths of the phase.
pub(crate) const SCALE: usize = 1000;

impl<'a> Stages<'a> {
    /// Stages with the relative costs `weights` (any unit), reporting
    /// `(0, SCALE)` at once.
    pub(crate) fn new(progress: Progress<'a>, weights: &[usize]) -> Self {
        let sum = weights.iter().sum::<usize>().max(1);
        let mut starts = Vec::with_capacity(weights.len() + 1);
        let mut acc = 0;
        for w in weights {
            starts.push(acc * SCALE / sum);
            acc += w;
        }
        starts.push(SCALE);
        progress(0, SCALE);
        Stages { progress, starts }
    }

    /// Stage `i`'s own `(done, total)`, reported as the phase's.
    pub(crate) fn report(&self, i: usize, done: usize, total: usize) {
        let (Some(&lo), Some(&hi)) = (self.starts.get(i), self.starts.get(i + 1)) else {
            return;
        };
        let share = if total == 0 {
            hi - lo
        } else {
            ((hi - lo) as u128 * done.min(total) as u128 / total as u128) as usize
        };
        (self.progress)(lo + share, SCALE);
    }

    /// Stage `i` as a [`Progress`] of its own.
    pub(crate) fn stage(&self, i: usize) -> impl Fn(usize, usize) + Sync + '_ {
        move |done, total| self.report(i, done, total)
    }

    /// Stage `i` is done.
    pub(crate) fn finish(&self, i: usize) {
        self.report(i, 1, 1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Mutex;

    #[test]
    fn a_counter_reports_rarely_and_reaches_the_total() {
        let seen = Mutex::new(Vec::new());
        let p = |d, t| seen.lock().unwrap().push((d, t));
        let c = Counter::new(&p, 10_000);
        for _ in 0..10_000 {
            c.add(1);
        }
        let seen = seen.into_inner().unwrap();
        assert!(seen.len() <= REPORTS + 2, "{}", seen.len());
        assert_eq!(seen.first(), Some(&(0, 10_000)));
        assert_eq!(seen.last(), Some(&(10_000, 10_000)));
        assert!(seen.windows(2).all(|w| w[0].0 < w[1].0));
    }

    #[test]
    fn stages_follow_their_weights() {
        let seen = Mutex::new(Vec::new());
        let p = |d, t| seen.lock().unwrap().push((d, t));
        let s = Stages::new(&p, &[1, 3]);
        s.report(0, 1, 2);
        s.finish(0);
        s.stage(1)(1, 3);
        s.finish(1);
        let seen = seen.into_inner().unwrap();
        let done: Vec<usize> = seen.iter().map(|x| x.0).collect();
        assert_eq!(done, [0, 125, 250, 500, 1000]);
        assert!(seen.iter().all(|x| x.1 == SCALE));
    }
}
