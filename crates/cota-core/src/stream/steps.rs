//! The error-steps stream: the bitree's split points in steps of decreasing
//! threshold, every prefix exactly `Bitree::extract(E_k)` (steps 2, 3 and 5
//! of [`super`]; paper `000_ebf7e3a88dffd361.txt` §3).
//!
//! Each step walks the tree from the roots as extraction does. A straddling
//! triangle splits without a bit (its split point inside the grid gets its
//! height in step 0); at an inside triangle whose split point is neither
//! split nor decided in this step, one bit says whether it splits now, and a
//! new point's height follows as a residual against [`predict`] (floored to
//! the lattice). The sender states the largest error it left unsplit.

use super::format::{
    lattice, quantize, thresholds, EncodedStep, EncodedStream, StreamError, StreamHeader,
    StreamKind, StreamOptions, UNKNOWN,
};
use super::models::{level, residual_ctx, split_ctx, Models, Question};
use super::state::{predict, Answers, Coder, Decoder, Encoder, State};
use crate::bitree::error_code::{decode, SplitRule, INFINITE};
use crate::bitree::Bitree;
use crate::grid::HeightGrid;
use crate::hierarchy::{walk, Tri, Visitor};
use crate::progress::{Counter, Progress, Stages};

/// Encodes `grid` as a progressive stream.
///
/// # Errors
/// [`StreamError::BadQuantum`], [`StreamError::BadMaxError`],
/// [`StreamError::HeightOutOfRange`], or [`StreamError::Mesh`] for grids the
/// bitree refuses (voids, too small).
pub fn encode(grid: &HeightGrid, opts: &StreamOptions) -> Result<EncodedStream, StreamError> {
    encode_with_progress(grid, opts, crate::progress::NONE)
}

/// [`encode`], telling `progress(done, total)` as it goes: the bitree's
/// levels, then each step, weighted by their share of the time (in
/// thousandths, [`crate::progress`]).
///
/// # Errors
/// As [`encode`].
pub fn encode_with_progress(
    grid: &HeightGrid,
    opts: &StreamOptions,
    progress: Progress<'_>,
) -> Result<EncodedStream, StreamError> {
    let e_last = opts.max_error_m;
    if e_last.is_nan() || e_last < 0.0 {
        return Err(StreamError::BadMaxError(e_last));
    }
    let (qgrid, lattice_exact) = quantize(grid, opts.quantum_m)?;
    // The error map, then the steps: about a third and two thirds.
    let stages = Stages::new(progress, &[1, 2]);
    let tree = Bitree::build_with_progress(&qgrid, &stages.stage(0))?;
    stages.finish(0);
    let q = lattice(&qgrid, opts.quantum_m);
    let hier = *tree.hierarchy();
    let header = StreamHeader::new(&hier, opts.quantum_m, &q, StreamKind::ErrorSteps);
    let mut state = State::new(&header);
    let mut models = Models::new();
    let mut steps = Vec::new();
    let schedule = schedule(&tree, opts);
    let second = stages.stage(1);
    let done = Counter::new(&second, schedule.len());
    for (k, thr) in schedule.into_iter().enumerate() {
        let answers = ErrorMap {
            tree: &tree,
            rule: SplitRule::new(thr),
            stated: 0.0,
        };
        let mut c = Encoder::new(&mut models, answers, &q);
        walk_step(&mut state, &mut c, k)?;
        let stated = c.answers.stated;
        let new_points = c.new_points;
        let mut payload = stated.to_le_bytes().to_vec();
        payload.extend_from_slice(&c.enc.finish());
        state.journal.clear();
        let (triangles, vertices) = state.counts();
        steps.push(EncodedStep {
            threshold_m: thr,
            max_error_m: stated as f64,
            payload,
            triangles,
            vertices,
            new_points,
        });
        done.add(1);
    }
    stages.finish(1);
    Ok(EncodedStream {
        header,
        steps,
        lattice_exact,
    })
}

/// The thresholds of the steps: `f32::MAX` (step 0, the coarse mesh), then
/// those of [`thresholds`] from the largest finite error of the map.
fn schedule(tree: &Bitree<'_>, opts: &StreamOptions) -> Vec<f64> {
    let emax = tree
        .error_codes()
        .iter()
        .filter(|&&c| c < INFINITE)
        .fold(0u16, |a, &c| a.max(c));
    let first = f32::MAX as f64;
    let mut v = vec![first];
    v.extend(thresholds(opts, decode(emax) as f64, first));
    v
}

/// The sender's answers: a split point splits when its error exceeds the
/// step's threshold; the largest error left unsplit is stated.
struct ErrorMap<'t> {
    tree: &'t Bitree<'t>,
    rule: SplitRule,
    /// The largest error bound of a split point left unsplit, metres.
    stated: f32,
}

impl Answers for ErrorMap<'_> {
    fn answer(&mut self, _q: Question, _t: &Tri, m: usize) -> bool {
        let yes = self.tree.splits_index(m, &self.rule);
        if !yes {
            // The code's bound, or the threshold when the exact tie-break
            // found the error at most the threshold.
            let e = self.tree.error_bound_m(m).min(self.rule.threshold);
            self.stated = self.stated.max(e);
        }
        yes
    }
}

/// Decodes one error step into `st`; returns the number of heights read. On
/// error the step is rolled back and `st` holds the previous prefix.
///
/// # Errors
/// [`StreamError::BadStep`] for a block that does not decode or is short.
pub(super) fn decode_step(
    st: &mut State,
    models: &mut Models,
    step: usize,
    block: &[u8],
) -> Result<usize, StreamError> {
    let mut d = Decoder::new(models, block);
    let walked = walk_step(st, &mut d, step);
    let overrun = d.dec.overrun();
    let result = match walked {
        Err(e) => Err(e),
        Ok(()) if overrun > 0 => Err(StreamError::BadStep {
            step,
            expected: format!("{} bytes of coded data", block.len() + overrun),
            found: format!("{} (truncated or corrupted)", block.len()),
        }),
        Ok(()) => Ok(d.new_points),
    };
    match result {
        Ok(n) => {
            st.journal.clear();
            Ok(n)
        }
        Err(e) => {
            rollback(st);
            Err(e)
        }
    }
}

/// Forgets every split and height of the current step. Only points split
/// in this step received a height in it, and they are all in the journal.
fn rollback(st: &mut State) {
    for &i in &st.journal {
        st.split[i] = false;
        st.q[i] = UNKNOWN;
    }
    st.journal.clear();
}

/// One step's walk through `c` (a new epoch: each split point is decided at
/// most once per step, whichever diamond triangle meets it first).
fn walk_step<C: Coder>(st: &mut State, c: &mut C, step: usize) -> Result<(), StreamError> {
    st.epoch += 1;
    st.journal.clear();
    let hier = st.hier;
    walk(&hier, &hier.roots(), (), &mut StepWalk { st, c, step }).map_err(|found| {
        StreamError::BadStep {
            step,
            expected: "a decodable step".into(),
            found,
        }
    })
}

/// The walk of one error step.
struct StepWalk<'a, C> {
    st: &'a mut State,
    c: &'a mut C,
    step: usize,
}

impl<C: Coder> StepWalk<'_, C> {
    /// Sample `i` (`t`'s split point) receives its height.
    fn learn(&mut self, t: &Tri, i: usize) -> Result<(), String> {
        let st = &*self.st;
        let pred = predict(t, |p| st.known(p).map(|v| v as f64)).floor() as i64;
        let v = self.c.height(residual_ctx(level(t), self.step), i, pred)?;
        self.st.q[i] = v;
        Ok(())
    }

    /// True when `t`'s apex (its parent's split point) was split in this step.
    fn parent_fresh(&self, t: &Tri) -> bool {
        let st = &*self.st;
        st.hier.contains(t.c) && st.decided[st.hier.index(t.c)] == st.epoch
    }
}

impl<C: Coder> Visitor for StepWalk<'_, C> {
    type Down = ();
    type Error = String;

    fn straddling(&mut self, t: &Tri, _down: ()) -> Result<(), String> {
        let m = t.mid();
        if self.st.hier.contains(m) {
            let i = self.st.hier.index(m);
            if !self.st.split[i] {
                self.st.split[i] = true;
                self.st.decided[i] = self.st.epoch;
                self.st.journal.push(i);
            }
            if self.st.q[i] == UNKNOWN {
                self.learn(t, i)?;
            }
        }
        Ok(())
    }

    fn inside(&mut self, t: &Tri, _down: ()) -> Result<Option<()>, String> {
        let i = self.st.hier.index(t.mid());
        if !self.st.split[i] {
            if self.st.decided[i] == self.st.epoch {
                return Ok(None);
            }
            let fresh = self.parent_fresh(t);
            let ctx = split_ctx(level(t), self.step, fresh);
            self.st.decided[i] = self.st.epoch;
            if !self.c.bit(Question::Split(ctx), self.step, t, i)? {
                return Ok(None);
            }
            self.st.split[i] = true;
            self.st.journal.push(i);
            if self.st.q[i] == UNKNOWN {
                self.learn(t, i)?;
            }
        }
        Ok(Some(()))
    }
}
