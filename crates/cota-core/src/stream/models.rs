//! The adaptive models of the stream and how a coded decision picks its
//! context: by the level of the triangle, the step, and what the receiver
//! already knows (step 4 of [`super`]; paper `000_ebf7e3a88dffd361.txt` §3).

use super::coder::{Bit, ResidualModel};
use crate::hierarchy::Tri;

/// Number of level contexts.
const LEVELS: usize = 64;
/// Number of step contexts: steps above `STEPS − 1` share the last one.
const STEPS: usize = 16;

/// One yes/no decision of a walk, naming its model.
#[derive(Debug, Clone, Copy)]
pub(super) enum Question {
    /// Error steps: "this split point splits now"; the context
    /// ([`split_ctx`]).
    Split(usize),
    /// Marks steps: "this side of the split point splits now"; the context.
    Side(usize),
    /// Marks steps: "this new point is selected"; the level.
    Selected(usize),
    /// Marks steps: "this fictitious point becomes selected"; the level.
    Promoted(usize),
}

/// The adaptive models shared by all steps.
#[derive(Debug, Clone)]
pub(super) struct Models {
    /// Error steps: per (level, step, triangle new in this step) split bits.
    split: Vec<Bit>,
    /// Per (level, step) height residuals.
    pub(super) residual: Vec<ResidualModel>,
    /// Marks streams, step 0: per (level, point already present) split bits.
    side: Vec<Bit>,
    /// Marks streams, step 0: per level "selected, not fictitious" bits.
    select: Vec<Bit>,
    /// Marks streams, steps after the first: per (level, point already
    /// present, triangle new in this step) split bits.
    side_later: Vec<Bit>,
    /// Marks streams, steps after the first: per level "a new point is
    /// selected" bits.
    select_later: Vec<Bit>,
    /// Marks streams, steps after the first: per level "a fictitious point
    /// becomes selected" bits.
    promote: Vec<Bit>,
}

impl Models {
    pub(super) fn new() -> Self {
        Models {
            split: vec![Bit::default(); LEVELS * STEPS * 2],
            residual: vec![ResidualModel::default(); LEVELS * STEPS],
            side: vec![Bit::default(); LEVELS * 2],
            select: vec![Bit::default(); LEVELS],
            side_later: vec![Bit::default(); LEVELS * 4],
            select_later: vec![Bit::default(); LEVELS],
            promote: vec![Bit::default(); LEVELS],
        }
    }

    /// The model of `q` in step `step` (the marks streams' step 0 has its
    /// own models).
    pub(super) fn bit(&mut self, q: Question, step: usize) -> &mut Bit {
        match (q, step) {
            (Question::Split(c), _) => &mut self.split[c],
            (Question::Side(c), 0) => &mut self.side[c],
            (Question::Side(c), _) => &mut self.side_later[c],
            (Question::Selected(l), 0) => &mut self.select[l],
            (Question::Selected(l), _) => &mut self.select_later[l],
            (Question::Promoted(l), _) => &mut self.promote[l],
        }
    }
}

/// Context level of a non-unit triangle: `2·log2(s) + [A]` for a triangle
/// on an `s`-square (`A`: the square's halves, `B`: their children).
#[inline]
pub(super) fn level(t: &Tri) -> usize {
    let dx = t.a[0].abs_diff(t.b[0]);
    let dy = t.a[1].abs_diff(t.b[1]);
    let s = dx.max(dy);
    let a = usize::from(dx != 0 && dy != 0);
    ((2 * s.trailing_zeros() as usize) + a).min(LEVELS - 1)
}

/// The error steps' split context: (level, step, whether the triangle was
/// created in this step).
#[inline]
pub(super) fn split_ctx(level: usize, step: usize, fresh: bool) -> usize {
    (level * STEPS + step.min(STEPS - 1)) * 2 + usize::from(fresh)
}

/// The residual context: (level, step).
#[inline]
pub(super) fn residual_ctx(level: usize, step: usize) -> usize {
    level * STEPS + step.min(STEPS - 1)
}
