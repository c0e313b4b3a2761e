//! The stream's format: its header, its kinds, its options and errors, the
//! encoded steps, and the height lattice (paper `000_ebf7e3a88dffd361.txt`
//! §3; the bit layout is in [`super`]).

use crate::error::MeshError;
use crate::grid::HeightGrid;
use crate::hierarchy::{Hierarchy, Pt};
use crate::refine::Mode;

/// Largest magnitude of a quantised height (`|q| < 2^40`).
pub(super) const MAX_Q: i64 = 1 << 40;
/// Marks a sample whose height is not known yet.
pub(super) const UNKNOWN: i64 = i64::MIN;
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

/// Options of [`super::encode`] and the marks encoders.
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
        Self::DEFAULT
    }
}

impl StreamOptions {
    /// The defaults, as documented on each field.
    pub const DEFAULT: StreamOptions = StreamOptions {
        quantum_m: 1.0,
        max_error_m: 0.0,
        thresholds_m: None,
    };

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
    /// ([`super::encode`]); every prefix is `Bitree::extract(E_k)`.
    ErrorSteps,
    /// Steps of nested closed [`crate::refine::Marks`] in this mode
    /// ([`super::encode_marks_progressive`], [`super::encode_marks_steps`]): fictitious
    /// points cost a flag and no height.
    Marks(Mode),
}

impl StreamKind {
    pub(super) fn code(self) -> u32 {
        match self {
            StreamKind::ErrorSteps => 0,
            StreamKind::Marks(Mode::Conforming) => 1,
            StreamKind::Marks(Mode::Fictitious { watertight: true }) => 2,
            StreamKind::Marks(Mode::Fictitious { watertight: false }) => 3,
        }
    }

    pub(super) fn from_code(c: u32) -> Option<Self> {
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
    /// The header of a `kind` stream of the grid `hier` whose quantised
    /// heights are `q` (its corners' heights travel in it).
    pub(super) fn new(hier: &Hierarchy, quantum_m: f64, q: &[i64], kind: StreamKind) -> Self {
        StreamHeader {
            width: hier.width(),
            height: hier.height(),
            quantum_m,
            corners_q: corner_points(hier).map(|c| c.map(|p| q[hier.index(p)]).unwrap_or(0)),
            kind,
        }
    }

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
pub(super) fn height_of(q: i64, quantum_m: f64) -> f32 {
    (q as f64 * quantum_m) as f32
}

/// The quantised heights `round(h / quantum_m)` of a quantised grid
/// ([`quantize`]), exact integers.
pub(super) fn lattice(qgrid: &HeightGrid, quantum_m: f64) -> Vec<i64> {
    qgrid
        .heights()
        .iter()
        .map(|&h| (h as f64 / quantum_m).round() as i64)
        .collect()
}

/// The padded square's corners that are grid samples, in header order.
pub(super) fn corner_points(hier: &Hierarchy) -> [Option<Pt>; 4] {
    let n = hier.size();
    [[0, 0], [n, 0], [0, n], [n, n]].map(|p| hier.contains(p).then_some(p))
}

/// The thresholds of the steps after step 0, decreasing, metres (step 2 of
/// [`super`]): the caller's [`StreamOptions::thresholds_m`], each kept when
/// finite, above [`StreamOptions::max_error_m`] and below the one before (the
/// first below `first`); or, without them, the powers of two from the largest
/// not above `emax` (the coarse mesh's error) down to
/// [`StreamOptions::quantum_m`], above `max_error_m` and below `first`; then
/// `max_error_m`.
pub(super) fn thresholds(opts: &StreamOptions, emax: f64, first: f64) -> Vec<f64> {
    let e_last = opts.max_error_m;
    let mut v: Vec<f64> = Vec::new();
    match &opts.thresholds_m {
        Some(t) => {
            for &e in t {
                if e.is_finite() && e > e_last && e < v.last().copied().unwrap_or(first) {
                    v.push(e);
                }
            }
        }
        None => {
            if emax > e_last && emax.is_finite() {
                let mut t = 2f64.powi(emax.log2().floor() as i32);
                while t > e_last && t >= opts.quantum_m && t < first {
                    v.push(t);
                    t /= 2.0;
                }
            }
        }
    }
    v.push(e_last);
    v
}
