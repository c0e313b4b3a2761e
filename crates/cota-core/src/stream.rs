//! Progressive transmission: a compact coarse-to-fine stream of the bitree's
//! split points that never sends a coordinate.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §3 ("Transmisión progresiva"): send the
//! coarse mesh `N0`, then, for successively finer tolerances, the points each
//! one adds; the receiver rebuilds the hierarchy itself. Here every position is
//! implicit in the hierarchy ([`crate::hierarchy`]) and only split decisions
//! and height residuals travel, entropy-coded ([`crate::stream_coder`]).
//!
//! # Overview
//! 1. **Quantise.** Heights become integers `q = round(h / quantum_m)`; the
//!    sender meshes the quantised grid (`q · quantum_m` as `f32`), so every
//!    stated error is exact for it. When every source height already sits on the
//!    lattice (integer metres for SRTM with the default quantum of 1 m; 0.1 m
//!    data with `quantum_m = 0.1`: exactly when `(q · quantum_m) as f32 == h`,
//!    reported as [`EncodedStream::lattice_exact`]) the stream is lossless;
//!    otherwise add `quantum_m / 2` to the stated errors for the source grid.
//! 2. **Steps.** Thresholds `E_0 = f32::MAX > E_1 > … > E_last`: powers of two
//!    from the largest finite error down to `quantum_m`, then the requested
//!    `max_error_m` (default 0). Because [`Bitree`]'s error map is monotone and
//!    diamond-shared, the split set `{m : err[m] > E_k}` is closed under the
//!    hierarchy's dependencies, so after step `k` the receiver holds exactly the
//!    mesh of `Bitree::extract(E_k)`. Step 0 is paper 000's `N0`: the coarsest
//!    mesh the grid's border allows.
//! 3. **Walk.** Each step walks the tree from the two roots exactly as
//!    extraction does (children in [`Tri::children`] order). Straddling
//!    triangles split without a bit. At an inside triangle whose split point is
//!    not yet split and not yet decided in this step, one bit says whether it
//!    splits now. When it splits and its split point has no height yet, the
//!    height follows as a residual against the prediction
//!    `floor((q[a] + q[b]) / 2)` (the midpoint of the hypotenuse `a`–`b`; when
//!    an end lies outside the grid, the floor of the mean of the triangle's
//!    known vertices, else 0). Both triangles of a diamond read the one
//!    decision, so the receiver's mesh is crack-free after every step.
//! 4. **Contexts.** Split bits use an adaptive probability per (level, step,
//!    whether the triangle was created in this step); residuals one
//!    [`ResidualModel`] per (level, step). Level `= 2·log2(s) + [A]` for a
//!    triangle on an `s`-square (`A`: the square's halves, `B`: their
//!    children). Steps above 15 share the context of step 15. Models persist
//!    across steps, and each step is its own range-coded block, so a receiver
//!    can stop after any step.
//! 5. **Stated error.** Each step states `E_k`, the largest `err[m]` among the
//!    split points it left unsplit (0 when none): an upper bound of the true
//!    error of that prefix's mesh at every sample, at most the threshold.
//!
//! # Bit layout
//! Header ([`StreamHeader::to_bytes`], 52 bytes, little-endian): `width: u32`,
//! `height: u32`, `quantum_m: f64`, then `q` of the padded square's corners
//! `(0,0), (N,0), (0,N), (N,N)` as four `i64` (0 for corners outside the grid),
//! then `kind: u32` ([`StreamKind`]: 0 error steps, this file; 1–3 a refined
//! mesh's marks in conforming, fictitious or faithful mode,
//! [`crate::stream_marks`]).
//!
//! Step payload: `max_error_m: f32` (little-endian, the stated `E_k`), then one
//! range-coded block ([`RangeEncoder`]) holding, in walk order, for each
//! candidate triangle `split: bit` and, for each new point,
//! `residual` as binarised by [`ResidualModel`]. Framing (magic, lengths,
//! checksums, georeference) is `cota-io`'s business.
//!
//! # Decoding
//! [`StreamDecoder`] applies steps one by one; a step that fails to decode
//! (truncated, corrupted) is rolled back, so the decoder always holds the last
//! good prefix. Its [`StreamDecoder::mesh`] equals `Bitree::extract(E_k)` of the
//! quantised grid, vertex for vertex.
//!
//! Meshes of other criteria and of the fictitious modes (`refine`'s `Marks`,
//! where fictitious points cost a flag and no height) are streamed coarse to
//! fine by [`encode_marks_progressive`] (vertical-error tolerances) or
//! [`encode_marks_steps`] (any nested marks), [`crate::stream_marks`], and
//! decoded step by step by the same [`StreamDecoder`]; their stated errors
//! are measured exactly and need not decrease from step to step.

use crate::bitree::error_code::{decode, SplitRule, INFINITE};
use crate::bitree::Bitree;
use crate::error::MeshError;
use crate::grid::HeightGrid;
use crate::hierarchy::{orient_up, Hierarchy, Placement, Pt, Tri};
use crate::mesh::{Mesh, MeshVertex};
use crate::refine::Marks;
use crate::refine::Mode;
use crate::stream_coder::{Bit, RangeDecoder, RangeEncoder, ResidualModel};

pub use crate::stream_marks::{encode_marks, encode_marks_progressive, encode_marks_steps};

/// Largest magnitude of a quantised height (`|q| < 2^40`).
pub(crate) const MAX_Q: i64 = 1 << 40;
/// Number of level contexts.
const LEVELS: usize = 64;
/// Number of step contexts.
const STEPS: usize = 16;
/// Marks a sample whose height is not known yet.
pub(crate) const UNKNOWN: i64 = i64::MIN;
/// Bytes of the header.
pub const HEADER_BYTES: usize = 52;

/// Errors of the progressive stream.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum StreamError {
    /// The grid cannot be meshed (too small, voids...).
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A quantum that is not a positive finite number.
    #[error("expected a positive finite quantum in metres, found {0}")]
    BadQuantum(f64),
    /// A negative or NaN target error.
    #[error("expected a maximum error of 0 m or more, found {0} m")]
    BadMaxError(f64),
    /// A height too large for the quantum.
    #[error("expected |height / quantum| below 2^40, found {height_m} m at column {col}, row {row} with a quantum of {quantum_m} m")]
    HeightOutOfRange {
        /// The height.
        height_m: f64,
        /// Its column.
        col: usize,
        /// Its row.
        row: usize,
        /// The quantum.
        quantum_m: f64,
    },
    /// A header of the wrong size or with impossible values.
    #[error("bad stream header: expected {expected}, found {found}")]
    BadHeader {
        /// What was expected.
        expected: String,
        /// What was found.
        found: String,
    },
    /// A step payload that does not decode.
    #[error("step {step}: expected {expected}, found {found}")]
    BadStep {
        /// The step index (0 = the coarse mesh).
        step: usize,
        /// What was expected.
        expected: String,
        /// What was found.
        found: String,
    },
}

/// Options of [`encode`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct StreamOptions {
    /// Height quantum in metres: heights are sent as integer multiples of it.
    /// Default: 1.0 (lossless for SRTM's integer metres).
    pub quantum_m: f64,
    /// Error of the last step, metres. Default: 0.0 (the lossless `E = 0` mesh).
    pub max_error_m: f64,
    /// Explicit step thresholds in metres (decreasing, each above
    /// `max_error_m`), before the final `max_error_m`. Default: `None`, the
    /// powers of two of the module docs.
    pub thresholds_m: Option<Vec<f64>>,
}

impl Default for StreamOptions {
    fn default() -> Self {
        StreamOptions {
            quantum_m: 1.0,
            max_error_m: 0.0,
            thresholds_m: None,
        }
    }
}

impl StreamOptions {
    /// Sets [`StreamOptions::quantum_m`].
    pub fn with_quantum_m(mut self, q: f64) -> Self {
        self.quantum_m = q;
        self
    }

    /// Sets [`StreamOptions::max_error_m`].
    pub fn with_max_error_m(mut self, e: f64) -> Self {
        self.max_error_m = e;
        self
    }

    /// Sets [`StreamOptions::thresholds_m`].
    pub fn with_thresholds_m(mut self, t: Option<Vec<f64>>) -> Self {
        self.thresholds_m = t;
        self
    }
}

/// What a stream carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StreamKind {
    /// Steps of decreasing error threshold over the bitree's error map
    /// ([`encode`]); every prefix is `Bitree::extract(E_k)`.
    ErrorSteps,
    /// Steps of nested closed [`Marks`] from [`crate::refine`] in this mode
    /// ([`encode_marks_progressive`], [`encode_marks_steps`]): fictitious
    /// points cost a flag and no height.
    Marks(Mode),
}

impl StreamKind {
    fn code(self) -> u32 {
        match self {
            StreamKind::ErrorSteps => 0,
            StreamKind::Marks(Mode::Conforming) => 1,
            StreamKind::Marks(Mode::Fictitious { watertight: true }) => 2,
            StreamKind::Marks(Mode::Fictitious { watertight: false }) => 3,
        }
    }

    fn from_code(c: u32) -> Option<Self> {
        Some(match c {
            0 => StreamKind::ErrorSteps,
            1 => StreamKind::Marks(Mode::Conforming),
            2 => StreamKind::Marks(Mode::Fictitious { watertight: true }),
            3 => StreamKind::Marks(Mode::Fictitious { watertight: false }),
            _ => return None,
        })
    }
}

/// What a receiver needs before the first step.
#[derive(Debug, Clone, PartialEq)]
pub struct StreamHeader {
    /// Grid width W.
    pub width: u32,
    /// Grid height H.
    pub height: u32,
    /// Height quantum, metres.
    pub quantum_m: f64,
    /// Quantised heights of the padded square's corners (0,0), (N,0), (0,N),
    /// (N,N); 0 for corners outside the grid.
    pub corners_q: [i64; 4],
    /// What the steps carry.
    pub kind: StreamKind,
}

impl StreamHeader {
    /// The 52 header bytes (see the module docs).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut v = Vec::with_capacity(HEADER_BYTES);
        v.extend_from_slice(&self.width.to_le_bytes());
        v.extend_from_slice(&self.height.to_le_bytes());
        v.extend_from_slice(&self.quantum_m.to_le_bytes());
        for c in self.corners_q {
            v.extend_from_slice(&c.to_le_bytes());
        }
        v.extend_from_slice(&self.kind.code().to_le_bytes());
        v
    }

    /// Parses and validates 52 header bytes.
    ///
    /// # Errors
    /// [`StreamError::BadHeader`] for a wrong length, a grid below 2×2 or above
    /// 2^30 per side or 2^31 samples, a bad quantum, corner heights out of
    /// range or an unknown kind.
    pub fn from_bytes(b: &[u8]) -> Result<Self, StreamError> {
        let bad = |expected: &str, found: String| StreamError::BadHeader {
            expected: expected.to_string(),
            found,
        };
        if b.len() != HEADER_BYTES {
            return Err(bad(
                &format!("{HEADER_BYTES} bytes"),
                format!("{} bytes", b.len()),
            ));
        }
        let u32_at = |i: usize| u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
        let u64_at = |i: usize| {
            let mut a = [0u8; 8];
            a.copy_from_slice(&b[i..i + 8]);
            u64::from_le_bytes(a)
        };
        let (width, height) = (u32_at(0), u32_at(4));
        if !(2..=1 << 30).contains(&width)
            || !(2..=1 << 30).contains(&height)
            || width as u64 * height as u64 > 1 << 31
        {
            return Err(bad(
                "a grid of 2..2^30 samples per side and at most 2^31 samples",
                format!("{width}x{height}"),
            ));
        }
        let quantum_m = f64::from_bits(u64_at(8));
        if !(quantum_m.is_finite() && quantum_m > 0.0) {
            return Err(bad("a positive finite quantum", format!("{quantum_m}")));
        }
        let mut corners_q = [0i64; 4];
        for (k, c) in corners_q.iter_mut().enumerate() {
            *c = u64_at(16 + 8 * k) as i64;
            if c.unsigned_abs() >= MAX_Q as u64 {
                return Err(bad("corner heights below 2^40 quanta", format!("{c}")));
            }
        }
        let code = u32_at(48);
        let kind = StreamKind::from_code(code)
            .ok_or_else(|| bad("a stream kind of 0 to 3", format!("{code}")))?;
        Ok(StreamHeader {
            width,
            height,
            quantum_m,
            corners_q,
            kind,
        })
    }
}

/// One encoded step and the mesh it leads to.
#[derive(Debug, Clone, PartialEq)]
pub struct EncodedStep {
    /// The split threshold of this step, metres (`f32::MAX` for step 0).
    pub threshold_m: f64,
    /// The stated max error of the prefix ending here, metres.
    pub max_error_m: f64,
    /// The step's bytes (stated error + range-coded block).
    pub payload: Vec<u8>,
    /// Triangles of the prefix's mesh.
    pub triangles: usize,
    /// Vertices of the prefix's mesh.
    pub vertices: usize,
    /// Points whose height this step sent.
    pub new_points: usize,
}

/// A whole encoded stream.
#[derive(Debug, Clone, PartialEq)]
pub struct EncodedStream {
    /// The header.
    pub header: StreamHeader,
    /// The steps, coarse to fine.
    pub steps: Vec<EncodedStep>,
    /// True when every source height is exactly on the quantum lattice, so the
    /// stream reproduces the source heights exactly.
    pub lattice_exact: bool,
}

/// The quantised copy of `grid` and whether it equals the source.
///
/// # Errors
/// [`StreamError::BadQuantum`], [`StreamError::HeightOutOfRange`] (also for NaN).
pub fn quantize(grid: &HeightGrid, quantum_m: f64) -> Result<(HeightGrid, bool), StreamError> {
    if !(quantum_m.is_finite() && quantum_m > 0.0) {
        return Err(StreamError::BadQuantum(quantum_m));
    }
    let w = grid.width();
    let mut exact = true;
    let mut out = Vec::with_capacity(grid.len());
    for (i, &h) in grid.heights().iter().enumerate() {
        let q = (h as f64 / quantum_m).round();
        if q.is_nan() || q.abs() >= MAX_Q as f64 {
            return Err(StreamError::HeightOutOfRange {
                height_m: h as f64,
                col: i % w,
                row: i / w,
                quantum_m,
            });
        }
        let z = height_of(q as i64, quantum_m);
        exact &= z == h;
        out.push(z);
    }
    let g = HeightGrid::new(w, grid.height(), out, grid.georef().clone())
        .map_err(|e| StreamError::Mesh(MeshError::Voids(e)))?;
    Ok((g, exact))
}

/// The height in metres of quantised height `q`.
#[inline]
fn height_of(q: i64, quantum_m: f64) -> f32 {
    (q as f64 * quantum_m) as f32
}

/// Encodes `grid` as a progressive stream.
///
/// # Errors
/// [`StreamError::BadQuantum`], [`StreamError::BadMaxError`],
/// [`StreamError::HeightOutOfRange`], or [`StreamError::Mesh`] for grids the
/// bitree refuses (voids, too small).
pub fn encode(grid: &HeightGrid, opts: &StreamOptions) -> Result<EncodedStream, StreamError> {
    let e_last = opts.max_error_m;
    if e_last.is_nan() || e_last < 0.0 {
        return Err(StreamError::BadMaxError(e_last));
    }
    let (qgrid, lattice_exact) = quantize(grid, opts.quantum_m)?;
    let tree = Bitree::build(&qgrid)?;
    let q: Vec<i64> = qgrid
        .heights()
        .iter()
        .map(|&h| (h as f64 / opts.quantum_m).round() as i64)
        .collect();
    let hier = *tree.hierarchy();
    let header = StreamHeader {
        width: hier.width(),
        height: hier.height(),
        quantum_m: opts.quantum_m,
        corners_q: corner_points(&hier).map(|c| c.map(|p| q[hier.index(p)]).unwrap_or(0)),
        kind: StreamKind::ErrorSteps,
    };
    let mut state = State::new(&header);
    let mut models = Models::new();
    let mut steps = Vec::new();
    for (k, thr) in schedule(&tree, opts).into_iter().enumerate() {
        let mut c = Enc {
            enc: RangeEncoder::new(),
            models: &mut models,
            tree: &tree,
            q: &q,
            rule: SplitRule::new(thr),
            stated: 0.0,
            new_points: 0,
        };
        state.walk_step(&mut c, k)?;
        let stated = c.stated;
        let new_points = c.new_points;
        let mut payload = stated.to_le_bytes().to_vec();
        payload.extend_from_slice(&c.enc.finish());
        state.journal.clear();
        let mesh = state.mesh();
        steps.push(EncodedStep {
            threshold_m: thr,
            max_error_m: stated as f64,
            payload,
            triangles: mesh.triangle_count(),
            vertices: mesh.vertex_count(),
            new_points,
        });
    }
    Ok(EncodedStream {
        header,
        steps,
        lattice_exact,
    })
}

/// The thresholds of the steps (see the module docs).
fn schedule(tree: &Bitree<'_>, opts: &StreamOptions) -> Vec<f64> {
    let e_last = opts.max_error_m;
    let mut v = vec![f32::MAX as f64];
    match &opts.thresholds_m {
        Some(t) => {
            for &e in t {
                if e.is_finite() && e > e_last && v.last().is_some_and(|&p| e < p) {
                    v.push(e);
                }
            }
        }
        None => {
            let emax = tree
                .error_codes()
                .iter()
                .filter(|&&c| c < INFINITE)
                .fold(0u16, |a, &c| a.max(c));
            let emax = decode(emax) as f64;
            if emax > 0.0 {
                let mut t = 2f64.powi(emax.log2().floor() as i32);
                while t > e_last && t >= opts.quantum_m && t < f32::MAX as f64 {
                    v.push(t);
                    t /= 2.0;
                }
            }
        }
    }
    v.push(e_last);
    v
}

/// The padded square's corners that are grid samples, in header order.
pub(crate) fn corner_points(hier: &Hierarchy) -> [Option<Pt>; 4] {
    let n = hier.size();
    [[0, 0], [n, 0], [0, n], [n, n]].map(|p| hier.contains(p).then_some(p))
}

/// Context level of a non-unit triangle (see the module docs).
#[inline]
pub(crate) fn level(t: &Tri) -> usize {
    let dx = t.a[0].abs_diff(t.b[0]);
    let dy = t.a[1].abs_diff(t.b[1]);
    let s = dx.max(dy);
    let a = usize::from(dx != 0 && dy != 0);
    ((2 * s.trailing_zeros() as usize) + a).min(LEVELS - 1)
}

/// The adaptive models shared by all steps.
#[derive(Debug, Clone)]
pub(crate) struct Models {
    split: Vec<Bit>,
    pub(crate) residual: Vec<ResidualModel>,
    /// Marks streams: per (level, point already present) split bits.
    pub(crate) side: Vec<Bit>,
    /// Marks streams: per level "selected, not fictitious" bits.
    pub(crate) select: Vec<Bit>,
    /// Marks streams, steps after the first: per (level, point already
    /// present, triangle new in this step) split bits.
    pub(crate) side_later: Vec<Bit>,
    /// Marks streams, steps after the first: per level "a new point is
    /// selected" bits.
    pub(crate) select_later: Vec<Bit>,
    /// Marks streams, steps after the first: per level "a fictitious point
    /// becomes selected" bits.
    pub(crate) promote: Vec<Bit>,
}

impl Models {
    pub(crate) fn new() -> Self {
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
}

#[inline]
fn split_ctx(level: usize, step: usize, fresh: bool) -> usize {
    (level * STEPS + step.min(STEPS - 1)) * 2 + usize::from(fresh)
}

#[inline]
pub(crate) fn residual_ctx(level: usize, step: usize) -> usize {
    level * STEPS + step.min(STEPS - 1)
}

/// The two directions of one walk: the encoder answers from the source, the
/// decoder from the bits.
trait Coder {
    /// Whether sample `m` splits now.
    fn split(&mut self, ctx: usize, m: usize) -> Result<bool, String>;
    /// The quantised height of `m`, given its prediction.
    fn height(&mut self, ctx: usize, m: usize, pred: i64) -> Result<i64, String>;
}

struct Enc<'a> {
    enc: RangeEncoder,
    models: &'a mut Models,
    tree: &'a Bitree<'a>,
    q: &'a [i64],
    rule: SplitRule,
    stated: f32,
    new_points: usize,
}

impl Coder for Enc<'_> {
    fn split(&mut self, ctx: usize, m: usize) -> Result<bool, String> {
        let yes = self.tree.splits_index(m, &self.rule);
        self.enc.bit(&mut self.models.split[ctx], yes);
        if !yes {
            // The code's bound, or the threshold when the exact tie-break
            // found the error at most the threshold.
            let e = self.tree.error_bound_m(m).min(self.rule.threshold);
            self.stated = self.stated.max(e);
        }
        Ok(yes)
    }

    fn height(&mut self, ctx: usize, m: usize, pred: i64) -> Result<i64, String> {
        let q = self.q[m];
        self.models.residual[ctx].encode(&mut self.enc, q - pred);
        self.new_points += 1;
        Ok(q)
    }
}

struct Dec<'a, 'b> {
    dec: RangeDecoder<'b>,
    models: &'a mut Models,
    new_points: usize,
}

impl Coder for Dec<'_, '_> {
    fn split(&mut self, ctx: usize, _m: usize) -> Result<bool, String> {
        Ok(self.dec.bit(&mut self.models.split[ctx]))
    }

    fn height(&mut self, ctx: usize, _m: usize, pred: i64) -> Result<i64, String> {
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

/// What sender and receiver both know: which split points split, and heights.
#[derive(Debug, Clone)]
pub(crate) struct State {
    pub(crate) hier: Hierarchy,
    split: Vec<bool>,
    /// Epoch of the last decision on each sample (see `walk_step`).
    decided: Vec<u32>,
    epoch: u32,
    pub(crate) q: Vec<i64>,
    /// Samples split or given a height by the current step (for rollback).
    journal: Vec<usize>,
    /// Marks streams: the decoded closed marks, which then drive the walk.
    pub(crate) marks: Option<Marks>,
}

impl State {
    pub(crate) fn new(h: &StreamHeader) -> Self {
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

    fn walk_step<C: Coder>(&mut self, c: &mut C, step: usize) -> Result<(), StreamError> {
        self.epoch += 1;
        self.journal.clear();
        for r in self.hier.roots() {
            self.walk(c, r, false, step)
                .map_err(|found| StreamError::BadStep {
                    step,
                    expected: "a decodable step".into(),
                    found,
                })?;
        }
        Ok(())
    }

    /// Forgets every split and height of the current step. Only points split
    /// in this step received a height in it, and they are all in the journal.
    fn rollback(&mut self) {
        for &i in &self.journal {
            self.split[i] = false;
            self.q[i] = UNKNOWN;
        }
        self.journal.clear();
    }

    fn walk<C: Coder>(
        &mut self,
        c: &mut C,
        t: Tri,
        inside: bool,
        step: usize,
    ) -> Result<(), String> {
        let inside = inside
            || match self.hier.place(&t) {
                Placement::Outside => return Ok(()),
                Placement::Straddling => false,
                Placement::Inside => true,
            };
        if t.is_unit() {
            return Ok(());
        }
        let m = t.mid();
        if !inside {
            if self.hier.contains(m) {
                let i = self.hier.index(m);
                if !self.split[i] {
                    self.split[i] = true;
                    self.decided[i] = self.epoch;
                    self.journal.push(i);
                }
                if self.q[i] == UNKNOWN {
                    self.learn(c, &t, i, step)?;
                }
            }
        } else {
            let i = self.hier.index(m);
            if !self.split[i] {
                if self.decided[i] == self.epoch {
                    return Ok(());
                }
                let fresh = self.parent_fresh(&t);
                let lvl = level(&t);
                self.decided[i] = self.epoch;
                if !c.split(split_ctx(lvl, step, fresh), i)? {
                    return Ok(());
                }
                self.split[i] = true;
                self.journal.push(i);
                if self.q[i] == UNKNOWN {
                    self.learn(c, &t, i, step)?;
                }
            }
        }
        let (c0, c1) = t.children();
        self.walk(c, c0, inside, step)?;
        self.walk(c, c1, inside, step)
    }

    /// True when `t`'s apex (its parent's split point) was split in this step.
    fn parent_fresh(&self, t: &Tri) -> bool {
        self.hier.contains(t.c) && self.decided[self.hier.index(t.c)] == self.epoch
    }

    fn learn<C: Coder>(&mut self, c: &mut C, t: &Tri, i: usize, step: usize) -> Result<(), String> {
        let known = |p: Pt| {
            if self.hier.contains(p) {
                let v = self.q[self.hier.index(p)];
                (v != UNKNOWN).then_some(v)
            } else {
                None
            }
        };
        let pred = match (known(t.a), known(t.b)) {
            (Some(a), Some(b)) => (a + b).div_euclid(2),
            _ => {
                let vals: Vec<i64> = [t.a, t.b, t.c].into_iter().filter_map(known).collect();
                if vals.is_empty() {
                    0
                } else {
                    vals.iter().sum::<i64>().div_euclid(vals.len() as i64)
                }
            }
        };
        let v = c.height(residual_ctx(level(t), step), i, pred)?;
        self.q[i] = v;
        Ok(())
    }

    /// Leaves of the current mesh (inside triangles, split iff marked).
    fn leaves(&self, mut f: impl FnMut(&Tri)) {
        let mut stack: Vec<(Tri, bool)> = self.hier.roots().map(|r| (r, false)).to_vec();
        stack.reverse();
        while let Some((t, inside)) = stack.pop() {
            let inside = inside
                || match self.hier.place(&t) {
                    Placement::Outside => continue,
                    Placement::Straddling => false,
                    Placement::Inside => true,
                };
            if t.is_unit() {
                if inside {
                    f(&t);
                }
                continue;
            }
            if inside {
                let split = match &self.marks {
                    Some(m) => m.splits(&t),
                    None => self.split[self.hier.index(t.mid())],
                };
                if !split {
                    f(&t);
                    continue;
                }
            }
            let (c0, c1) = t.children();
            stack.push((c1, inside));
            stack.push((c0, inside));
        }
    }

    /// Triangles and vertices of the current mesh (error-steps streams).
    fn counts(&self) -> (usize, usize) {
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
    /// row-major (as [`Bitree::extract`] numbers them).
    pub(crate) fn mesh(&self) -> Mesh {
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

/// Statistics of one applied step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepInfo {
    /// Index of the step (0 = the coarse mesh).
    pub index: usize,
    /// The stated max error of the prefix ending here, metres.
    pub max_error_m: f64,
    /// Points whose height this step carried.
    pub new_points: usize,
    /// Bytes of the step's payload.
    pub payload_bytes: usize,
    /// Triangles of the prefix's mesh.
    pub triangles: usize,
    /// Vertices of the prefix's mesh.
    pub vertices: usize,
}

/// The receiving end: applies steps and yields the mesh of the prefix.
#[derive(Debug, Clone)]
pub struct StreamDecoder {
    header: StreamHeader,
    state: State,
    models: Models,
    steps: Vec<StepInfo>,
    /// Marks streams: the mesh `refine::triangulate` makes of the marks.
    marks_mesh: Option<Mesh>,
}

impl StreamDecoder {
    /// A decoder for a stream with this header.
    pub fn new(header: StreamHeader) -> Self {
        let state = State::new(&header);
        StreamDecoder {
            header,
            state,
            models: Models::new(),
            steps: Vec::new(),
            marks_mesh: None,
        }
    }

    /// The header.
    pub fn header(&self) -> &StreamHeader {
        &self.header
    }

    /// The steps applied so far.
    pub fn steps(&self) -> &[StepInfo] {
        &self.steps
    }

    /// The stated max error of the current prefix (`None` before step 0).
    pub fn max_error_m(&self) -> Option<f64> {
        self.steps.last().map(|s| s.max_error_m)
    }

    /// Applies one step payload. On error the decoder keeps the previous prefix.
    ///
    /// # Errors
    /// [`StreamError::BadStep`] when the payload is short, states an error that
    /// is negative, NaN, above `f32::MAX` or (error-steps streams) above the
    /// previous step's, or its coded block is truncated or corrupted (for
    /// marks streams also: its points disagree with their closure).
    pub fn apply_step(&mut self, payload: &[u8]) -> Result<StepInfo, StreamError> {
        let index = self.steps.len();
        let bad = |expected: String, found: String| StreamError::BadStep {
            step: index,
            expected,
            found,
        };
        let [e0, e1, e2, e3, ..] = *payload else {
            return Err(bad(
                "at least 4 bytes".into(),
                format!("{} bytes", payload.len()),
            ));
        };
        let stated = f32::from_le_bytes([e0, e1, e2, e3]) as f64;
        // Marks streams state exact measured errors, which need not decrease.
        let prev = match self.header.kind {
            StreamKind::ErrorSteps => self.max_error_m().unwrap_or(f64::INFINITY),
            StreamKind::Marks(_) => f32::MAX as f64,
        };
        if !(stated >= 0.0 && stated <= prev) {
            return Err(bad(
                format!("a stated max error between 0 m and {prev} m"),
                format!("{stated} m"),
            ));
        }
        let block = &payload[4..];
        if let StreamKind::Marks(mode) = self.header.kind {
            let saved = self.models.clone();
            let (mesh, new_points) = crate::stream_marks::decode(
                &mut self.state,
                &mut self.models,
                &self.header,
                mode,
                index,
                block,
            )
            .map_err(|found| {
                self.models = saved;
                bad("a decodable marks step".into(), found)
            })?;
            let info = StepInfo {
                index,
                max_error_m: stated,
                new_points,
                payload_bytes: payload.len(),
                triangles: mesh.triangle_count(),
                vertices: mesh.vertex_count(),
            };
            self.marks_mesh = Some(mesh);
            self.steps.push(info);
            return Ok(info);
        }
        let mut d = Dec {
            dec: RangeDecoder::new(block),
            models: &mut self.models,
            new_points: 0,
        };
        let saved = d.models.clone();
        let walked = self.state.walk_step(&mut d, index);
        let overrun = d.dec.overrun();
        let new_points = d.new_points;
        let result = match walked {
            Err(e) => Err(e),
            Ok(()) if overrun > 0 => Err(bad(
                format!("{} bytes of coded data", block.len() + overrun),
                format!("{} (truncated or corrupted)", block.len()),
            )),
            Ok(()) => Ok(()),
        };
        if let Err(e) = result {
            self.state.rollback();
            self.models = saved;
            return Err(e);
        }
        self.state.journal.clear();
        let (triangles, vertices) = self.state.counts();
        let info = StepInfo {
            index,
            max_error_m: stated,
            new_points,
            payload_bytes: payload.len(),
            triangles,
            vertices,
        };
        self.steps.push(info);
        Ok(info)
    }

    /// The mesh of the current prefix (empty before step 0), vertex heights
    /// `q · quantum_m` as `f32`: equal, vertex for vertex, to
    /// `Bitree::extract(E_k)` on the quantised grid (marks streams: to the
    /// sender's `refine::triangulate` of step `k`'s marks).
    pub fn mesh(&self) -> Mesh {
        if self.steps.is_empty() {
            return Mesh::default();
        }
        if let Some(m) = &self.marks_mesh {
            return m.clone();
        }
        let mut m = self.state.mesh();
        let w = self.header.width as usize;
        for v in &mut m.vertices {
            let q = self.state.q[v.row as usize * w + v.col as usize];
            v.z_m = height_of(q, self.header.quantum_m);
        }
        m
    }

    /// The height of every sample as the current prefix's surface gives it:
    /// sent heights exactly, the others interpolated on their leaf (midpoint
    /// of each hypotenuse, recursively, which is the leaf's plane). When the
    /// stated max error is below `quantum_m / 2`, interpolated heights are
    /// rounded to the lattice, which recovers them exactly. `None` before step 0.
    pub fn heights_m(&self) -> Option<Vec<f32>> {
        let stated = self.max_error_m()?;
        let qm = self.header.quantum_m;
        let snap = stated < qm / 2.0;
        let hier = self.state.hier;
        let mut z: Vec<f64> = self
            .state
            .q
            .iter()
            .map(|&q| {
                if q == UNKNOWN {
                    f64::NAN
                } else {
                    q as f64 * qm
                }
            })
            .collect();
        if let Some(m) = &self.marks_mesh {
            // Fictitious vertices carry their interpolated mesh height.
            let w = hier.width() as usize;
            for v in &m.vertices {
                z[v.row as usize * w + v.col as usize] = v.z_m as f64;
            }
        }
        self.state.leaves(|leaf| {
            let mut stack = vec![*leaf];
            while let Some(t) = stack.pop() {
                if t.is_unit() {
                    continue;
                }
                let i = hier.index(t.mid());
                if z[i].is_nan() {
                    let v = (z[hier.index(t.a)] + z[hier.index(t.b)]) / 2.0;
                    z[i] = if snap { (v / qm).round() * qm } else { v };
                }
                let (c0, c1) = t.children();
                stack.push(c0);
                stack.push(c1);
            }
        });
        Some(z.into_iter().map(|v| v as f32).collect())
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, reason = "tests")]
mod test {
    use super::*;
    use crate::grid::GeoRef;
    use crate::{check_mesh, CheckOptions, ExtractOptions};

    fn grid(w: usize, h: usize) -> HeightGrid {
        let v = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32, (i / w) as f32);
                (200.0 + 40.0 * (x * 0.21).sin() * (y * 0.17).cos()).round()
                    + ((i * 7919) % 5) as f32
            })
            .collect();
        HeightGrid::new(w, h, v, GeoRef::unreferenced(30.0)).unwrap()
    }

    #[test]
    fn every_prefix_is_extract_and_checks() {
        for (w, h) in [(33, 33), (37, 23), (2, 9), (40, 41)] {
            let g = grid(w, h);
            let s = encode(&g, &StreamOptions::default()).unwrap();
            assert!(s.lattice_exact);
            let tree = Bitree::build(&g).unwrap();
            let hb = StreamHeader::from_bytes(&s.header.to_bytes()).unwrap();
            let mut d = StreamDecoder::new(hb);
            for step in &s.steps {
                let info = d.apply_step(&step.payload).unwrap();
                let mesh = d.mesh();
                let want = tree
                    .extract(&ExtractOptions::max_error_m(step.threshold_m))
                    .unwrap()
                    .mesh;
                assert_eq!(mesh, want, "{w}x{h} step {}", info.index);
                assert_eq!(mesh.triangle_count(), step.triangles);
                check_mesh(&g, &mesh, &CheckOptions::conforming(info.max_error_m)).unwrap();
            }
            let z = d.heights_m().unwrap_or_default();
            assert_eq!(z, g.heights());
        }
    }

    #[test]
    fn random_payloads_never_panic() {
        let g = grid(21, 13);
        let s = encode(&g, &StreamOptions::default()).unwrap();
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        for len in 0..400usize {
            let mut d = StreamDecoder::new(s.header.clone());
            let mut p = vec![0u8; 4];
            for _ in 0..len {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                p.push(x as u8);
            }
            if d.apply_step(&p).is_ok() {
                let _ = d.apply_step(&p);
                let m = d.mesh();
                assert!(m.triangle_count() >= 2);
                let _ = d.heights_m();
            } else {
                assert!(d.steps().is_empty());
                assert_eq!(d.mesh(), Mesh::default());
            }
        }
    }

    #[test]
    fn bad_options_and_headers_are_errors() {
        let g = grid(9, 9);
        let o = StreamOptions::default().with_quantum_m(0.0);
        assert!(matches!(encode(&g, &o), Err(StreamError::BadQuantum(_))));
        let o = StreamOptions::default().with_max_error_m(-1.0);
        assert!(matches!(encode(&g, &o), Err(StreamError::BadMaxError(_))));
        let mut h = encode(&g, &StreamOptions::default())
            .unwrap()
            .header
            .to_bytes();
        assert!(StreamHeader::from_bytes(&h[..47]).is_err());
        h[0] = 1;
        let e = StreamHeader::from_bytes(&h).unwrap_err().to_string();
        assert!(e.contains("expected") && e.contains("found 1x9"), "{e}");
    }
}
