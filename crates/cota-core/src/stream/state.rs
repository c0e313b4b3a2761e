//! What sender and receiver both know between steps, the one coder trait
//! both directions of a walk go through, and the one height predictor.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §3: the receiver rebuilds the hierarchy
//! itself, so only decisions and heights travel. A walk asks its questions
//! through [`Coder`]: the [`Encoder`] answers them from the source (an
//! error map, a refinement's marks) and writes each answer, the [`Decoder`]
//! reads them; both code each new point's height as a residual against
//! [`predict`], the midpoint of its hypotenuse.

use super::coder::{RangeDecoder, RangeEncoder};
use super::format::{corner_points, StreamHeader, MAX_Q, UNKNOWN};
use super::models::{Models, Question};
use crate::hierarchy::{orient_up, walk, Hierarchy, Pt, Tri, Visitor};
use crate::mesh::{Mesh, MeshVertex};
use crate::refine::Marks;

/// Both directions of a walk: the encoder answers from the source and codes
/// the answer, the decoder decodes it.
pub(super) trait Coder {
    /// The answer to `q` about triangle `t` (split point index `i`) in step
    /// `step`.
    ///
    /// # Errors
    /// A description of what could not be decoded.
    fn bit(&mut self, q: Question, step: usize, t: &Tri, i: usize) -> Result<bool, String>;

    /// The quantised height of sample `i`, coded with residual context
    /// `ctx` against the prediction `pred`.
    ///
    /// # Errors
    /// A description of what could not be decoded.
    fn height(&mut self, ctx: usize, i: usize, pred: i64) -> Result<i64, String>;
}

/// The source the encoder answers from.
pub(super) trait Answers {
    /// The answer to `q` about triangle `t` (split point index `i`).
    fn answer(&mut self, q: Question, t: &Tri, i: usize) -> bool;
}

/// The sending direction: answers from `answers`, heights from `q`.
pub(super) struct Encoder<'a, A> {
    pub(super) enc: RangeEncoder,
    pub(super) models: &'a mut Models,
    pub(super) answers: A,
    pub(super) q: &'a [i64],
    /// Heights sent.
    pub(super) new_points: usize,
}

impl<'a, A: Answers> Encoder<'a, A> {
    pub(super) fn new(models: &'a mut Models, answers: A, q: &'a [i64]) -> Self {
        Encoder {
            enc: RangeEncoder::new(),
            models,
            answers,
            q,
            new_points: 0,
        }
    }
}

impl<A: Answers> Coder for Encoder<'_, A> {
    fn bit(&mut self, q: Question, step: usize, t: &Tri, i: usize) -> Result<bool, String> {
        let yes = self.answers.answer(q, t, i);
        self.enc.bit(self.models.bit(q, step), yes);
        Ok(yes)
    }

    fn height(&mut self, ctx: usize, i: usize, pred: i64) -> Result<i64, String> {
        let q = self.q[i];
        self.models.residual[ctx].encode(&mut self.enc, q - pred);
        self.new_points += 1;
        Ok(q)
    }
}

/// The receiving direction.
pub(super) struct Decoder<'a, 'b> {
    pub(super) dec: RangeDecoder<'b>,
    pub(super) models: &'a mut Models,
    /// Heights received.
    pub(super) new_points: usize,
}

impl<'a, 'b> Decoder<'a, 'b> {
    pub(super) fn new(models: &'a mut Models, block: &'b [u8]) -> Self {
        Decoder {
            dec: RangeDecoder::new(block),
            models,
            new_points: 0,
        }
    }
}

impl Coder for Decoder<'_, '_> {
    fn bit(&mut self, q: Question, step: usize, _t: &Tri, _i: usize) -> Result<bool, String> {
        Ok(self.dec.bit(self.models.bit(q, step)))
    }

    fn height(&mut self, ctx: usize, _i: usize, pred: i64) -> Result<i64, String> {
        let r = self.models.residual[ctx].decode(&mut self.dec);
        self.new_points += 1;
        match pred.checked_add(r) {
            Some(q) if q.abs() < MAX_Q => Ok(q),
            _ => Err(format!(
                "a height below 2^40 quanta, found a residual of {r} on a prediction of {pred}"
            )),
        }
    }
}

/// The one height predictor: the mean of the known heights of the ends of
/// `t`'s hypotenuse (its midpoint), or, when an end is unknown (outside the
/// grid), the mean of its known vertices, else 0. `known` gives a sample's
/// height in any unit; each stream kind rounds the prediction to its lattice
/// (the error steps take the floor in quanta, the marks steps round in
/// metres to the nearest quantum).
pub(super) fn predict(t: &Tri, known: impl Fn(Pt) -> Option<f64>) -> f64 {
    match (known(t.a), known(t.b)) {
        (Some(a), Some(b)) => (a + b) / 2.0,
        _ => {
            let v: Vec<f64> = [t.a, t.b, t.c].into_iter().filter_map(known).collect();
            if v.is_empty() {
                0.0
            } else {
                v.iter().sum::<f64>() / v.len() as f64
            }
        }
    }
}

/// What sender and receiver both know: which split points split, and heights.
#[derive(Debug, Clone)]
pub(super) struct State {
    pub(super) hier: Hierarchy,
    /// Error steps: split points split so far.
    pub(super) split: Vec<bool>,
    /// Epoch of the last decision on each sample (see [`super::steps`]).
    pub(super) decided: Vec<u32>,
    pub(super) epoch: u32,
    /// Quantised heights, [`UNKNOWN`] where none was sent yet.
    pub(super) q: Vec<i64>,
    /// Samples split or given a height by the current step (for rollback).
    pub(super) journal: Vec<usize>,
    /// Marks streams: the decoded closed marks, which then drive the walk.
    pub(super) marks: Option<Marks>,
}

impl State {
    /// Nothing split, the heights of the header's corners known.
    pub(super) fn new(h: &StreamHeader) -> Self {
        let hier = Hierarchy::new(h.width, h.height);
        let n = h.width as usize * h.height as usize;
        let mut q = vec![UNKNOWN; n];
        for (c, &v) in corner_points(&hier).iter().zip(&h.corners_q) {
            if let Some(p) = c {
                q[hier.index(*p)] = v;
            }
        }
        State {
            hier,
            split: vec![false; n],
            decided: vec![0; n],
            epoch: 0,
            q,
            journal: Vec::new(),
            marks: None,
        }
    }

    /// The known height of sample `p` in quanta, if any.
    pub(super) fn known(&self, p: Pt) -> Option<i64> {
        if self.hier.contains(p) {
            let v = self.q[self.hier.index(p)];
            (v != UNKNOWN).then_some(v)
        } else {
            None
        }
    }

    /// Leaves of the current mesh (inside triangles, split iff marked), in
    /// the walk's order.
    pub(super) fn leaves(&self, f: impl FnMut(&Tri)) {
        let mut v = LeafWalk { st: self, f };
        let Ok(()) = walk(&self.hier, &self.hier.roots(), (), &mut v);
    }

    /// Triangles and vertices of the current mesh (error-steps streams).
    pub(super) fn counts(&self) -> (usize, usize) {
        let mut used = vec![false; self.split.len()];
        let mut triangles = 0;
        let mut vertices = 0;
        self.leaves(|t| {
            triangles += 1;
            for p in [t.a, t.b, t.c] {
                let i = self.hier.index(p);
                if !used[i] {
                    used[i] = true;
                    vertices += 1;
                }
            }
        });
        (triangles, vertices)
    }

    /// The current mesh: leaves counter-clockwise from above, vertices numbered
    /// row-major (as [`crate::Bitree::extract`] numbers them), heights 0.
    pub(super) fn mesh(&self) -> Mesh {
        let mut tris: Vec<[u32; 3]> = Vec::new();
        let n = self.split.len();
        let mut used = vec![u32::MAX; n];
        self.leaves(|t| {
            let (a, b) = if orient_up(t.a, t.b, t.c) > 0 {
                (t.a, t.b)
            } else {
                (t.b, t.a)
            };
            let ids = [a, b, t.c].map(|p| self.hier.index(p) as u32);
            for &i in &ids {
                used[i as usize] = 0;
            }
            tris.push(ids);
        });
        let w = self.hier.width();
        let mut vertices = Vec::new();
        for (i, u) in used.iter_mut().enumerate() {
            if *u == 0 {
                *u = vertices.len() as u32;
                vertices.push(MeshVertex {
                    col: i as u32 % w,
                    row: i as u32 / w,
                    z_m: 0.0,
                });
            }
        }
        for t in &mut tris {
            for i in t.iter_mut() {
                *i = used[*i as usize];
            }
        }
        Mesh {
            vertices,
            triangles: tris,
        }
    }
}

/// The walk of [`State::leaves`]: a triangle splits where the decoded marks
/// say (marks streams) or its split point has split (error steps).
struct LeafWalk<'s, F> {
    st: &'s State,
    f: F,
}

impl<F: FnMut(&Tri)> Visitor for LeafWalk<'_, F> {
    type Down = ();
    type Error = std::convert::Infallible;

    fn straddling(&mut self, _t: &Tri, _down: ()) -> Result<(), Self::Error> {
        Ok(())
    }

    fn inside(&mut self, t: &Tri, _down: ()) -> Result<Option<()>, Self::Error> {
        let split = match &self.st.marks {
            Some(m) => m.splits(t),
            None => self.st.split[self.st.hier.index(t.mid())],
        };
        Ok(split.then_some(()))
    }

    fn leaf(&mut self, t: &Tri, _down: ()) {
        (self.f)(t);
    }
}
