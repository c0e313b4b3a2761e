//! The `.cstream` file: framing of cota's progressive stream
//! ([`cota_core::stream`], paper `000_ebf7e3a88dffd361.txt` §3, "Transmisión
//! progresiva") with magic, version, georeference and a checksum per step.
//!
//! 1. [`stream_bytes`] frames an [`EncodedStream`]; [`write_stream`] writes it
//!    atomically ([`write_atomically`]).
//! 2. [`StreamReader`] consumes bytes in chunks as they arrive and applies each
//!    step as soon as its frame is complete and its checksum matches.
//! 3. [`read_stream`] reads a file, optionally stopping at a byte budget or at
//!    the first step whose stated error is small enough.
//!
//! # Layout (all integers little-endian)
//! ```text
//! magic      8 bytes  "COTASTRM"
//! version    u16      1
//! head_len   u32      bytes of `head`
//! head       52 bytes core header (StreamHeader::to_bytes: W, H, quantum,
//!            corners, kind)
//!            u32 number of steps in the file
//!            u8  georef known (0/1)     u8  pixel is (0 area, 1 point)
//!            f64 origin_x  f64 origin_y  f64 pixel_x  f64 pixel_y
//!            u8  crs kind (0 unknown, 1 EPSG, 2 geographic, 3 projected,
//!                4 PROJ definition)
//!            EPSG: u32 code; geographic/projected: u16 length + UTF-8 name;
//!            PROJ: u16 length + UTF-8 PROJ string
//! head_crc   u32      CRC-32 (IEEE) of `head`
//! then per step, coarse to fine:
//! len        u32      bytes of the payload
//! crc        u32      CRC-32 (IEEE) of the payload
//! payload    len bytes (core step: stated max error f32 + range-coded block)
//! ```
//! A file holds exactly the announced number of steps: fewer (even cut at a
//! frame boundary) is reported as truncated, and so is a partial frame —
//! an error by default, or, with [`StreamLimit::partial`] (a partial
//! download), the complete steps decoded and the cut reported beside them.

use std::io::Read;
use std::path::{Path, PathBuf};

use cota_core::stream::{EncodedStream, StepInfo, StreamDecoder, StreamError, StreamHeader};
use cota_core::{Crs, GeoRef, PixelIs};

use crate::export::{write_atomically, WriteError};

/// The file's first 8 bytes.
pub const MAGIC: &[u8; 8] = b"COTASTRM";
/// The format version written and read.
pub const VERSION: u16 = 1;
/// Largest head accepted (the core header, the georeference, a CRS name).
const MAX_HEAD: usize = 1 << 16;
/// Largest step payload accepted.
const MAX_STEP: usize = 1 << 31;

/// What went wrong in a stream's bytes.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum StreamFileError {
    /// Not a cota stream.
    #[error("expected a cota stream starting with \"COTASTRM\", found {found:?}")]
    BadMagic {
        /// The first bytes found.
        found: String,
    },
    /// A version this reader does not know.
    #[error("expected stream format version {VERSION}, found {found}")]
    Version {
        /// The version found.
        found: u16,
    },
    /// The bytes end inside a frame.
    #[error("truncated stream: expected {expected} bytes of {what}, found {found}")]
    Truncated {
        /// Which part.
        what: String,
        /// Bytes needed.
        expected: u64,
        /// Bytes present.
        found: u64,
    },
    /// A checksum mismatch.
    #[error("corrupted stream: {what} has CRC-32 {found:08x}, expected {expected:08x}")]
    Checksum {
        /// Which part.
        what: String,
        /// The stored checksum.
        expected: u32,
        /// The checksum of the bytes.
        found: u32,
    },
    /// A malformed head or step.
    #[error("bad stream {what}: expected {expected}, found {found}")]
    Malformed {
        /// Which part.
        what: String,
        /// What was expected.
        expected: String,
        /// What was found.
        found: String,
    },
    /// The head announces a grid over the sample limit.
    #[error("too large: the head announces a {width}×{height} grid ({samples} samples), over the limit of {limit} samples (raise it with --max-samples)")]
    TooLarge {
        /// Grid width announced.
        width: u32,
        /// Grid height announced.
        height: u32,
        /// Samples announced.
        samples: u64,
        /// The limit.
        limit: u64,
    },
    /// The core decoder rejected a header or step.
    #[error(transparent)]
    Core(#[from] StreamError),
}

/// A [`StreamFileError`] or an I/O error, naming the file.
#[derive(Debug, thiserror::Error)]
#[error("{}: {kind}", path.display())]
pub struct StreamReadError {
    /// The file.
    pub path: PathBuf,
    /// What went wrong.
    pub kind: StreamReadErrorKind,
}

/// The cause of a [`StreamReadError`].
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum StreamReadErrorKind {
    /// Reading failed.
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// The content is not a valid stream.
    #[error(transparent)]
    Stream(#[from] StreamFileError),
}

/// CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320) lookup table.
const CRC_TABLE: [u32; 256] = {
    let mut t = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
            k += 1;
        }
        t[i] = c;
        i += 1;
    }
    t
};

/// CRC-32 (IEEE) of `data`.
pub fn crc32(data: &[u8]) -> u32 {
    let mut c = u32::MAX;
    for &b in data {
        c = CRC_TABLE[((c ^ b as u32) & 0xFF) as usize] ^ (c >> 8);
    }
    !c
}

fn head_bytes(header: &StreamHeader, steps: usize, georef: &GeoRef) -> Vec<u8> {
    let mut v = header.to_bytes();
    v.extend_from_slice(&(steps as u32).to_le_bytes());
    v.push(u8::from(georef.known));
    v.push(match georef.pixel_is {
        PixelIs::Area => 0,
        PixelIs::Point => 1,
    });
    for f in [
        georef.origin_x,
        georef.origin_y,
        georef.pixel_x,
        georef.pixel_y,
    ] {
        v.extend_from_slice(&f.to_le_bytes());
    }
    let name = |v: &mut Vec<u8>, kind: u8, s: &str| {
        let b = s.as_bytes();
        let n = b.len().min(u16::MAX as usize);
        v.push(kind);
        v.extend_from_slice(&(n as u16).to_le_bytes());
        v.extend_from_slice(&b[..n]);
    };
    match &georef.crs {
        Crs::Epsg(code) => {
            v.push(1);
            v.extend_from_slice(&code.to_le_bytes());
        }
        Crs::Geographic(s) => name(&mut v, 2, s),
        Crs::Projected(s) => name(&mut v, 3, s),
        Crs::Proj(s) => name(&mut v, 4, s),
        _ => v.push(0),
    }
    v
}

fn parse_head(b: &[u8]) -> Result<(StreamHeader, u32, GeoRef), StreamFileError> {
    use cota_core::stream::HEADER_BYTES;
    let short = |need: usize| StreamFileError::Malformed {
        what: "head".into(),
        expected: format!("at least {need} bytes"),
        found: format!("{} bytes", b.len()),
    };
    let fixed = HEADER_BYTES + 4 + 2 + 32 + 1;
    if b.len() < fixed {
        return Err(short(fixed));
    }
    let header = StreamHeader::from_bytes(&b[..HEADER_BYTES])?;
    let f64_at = |i: usize| {
        let mut a = [0u8; 8];
        a.copy_from_slice(&b[i..i + 8]);
        f64::from_le_bytes(a)
    };
    let steps = u32::from_le_bytes([
        b[HEADER_BYTES],
        b[HEADER_BYTES + 1],
        b[HEADER_BYTES + 2],
        b[HEADER_BYTES + 3],
    ]);
    let g = HEADER_BYTES + 4;
    let known = b[g] != 0;
    let pixel_is = if b[g + 1] == 0 {
        PixelIs::Area
    } else {
        PixelIs::Point
    };
    let (origin_x, origin_y, pixel_x, pixel_y) = (
        f64_at(g + 2),
        f64_at(g + 10),
        f64_at(g + 18),
        f64_at(g + 26),
    );
    if ![origin_x, origin_y, pixel_x, pixel_y]
        .iter()
        .all(|v| v.is_finite())
        || pixel_x == 0.0
        || pixel_y == 0.0
    {
        return Err(StreamFileError::Malformed {
            what: "georeference".into(),
            expected: "finite origin and non-zero finite pixel size".into(),
            found: format!("origin ({origin_x}, {origin_y}), pixel ({pixel_x}, {pixel_y})"),
        });
    }
    let k = fixed - 1;
    let crs = parse_crs(b[k], &b[k + 1..], fixed)?;
    Ok((
        header,
        steps,
        GeoRef {
            crs,
            origin_x,
            origin_y,
            pixel_x,
            pixel_y,
            pixel_is,
            known,
        },
    ))
}

/// The CRS after its kind byte (`rest`, the end of a head of `fixed` bytes
/// before it).
fn parse_crs(kind: u8, rest: &[u8], fixed: usize) -> Result<Crs, StreamFileError> {
    let short = |need: usize| StreamFileError::Malformed {
        what: "head".into(),
        expected: format!("at least {need} bytes"),
        found: format!("{} bytes", fixed + rest.len()),
    };
    Ok(match kind {
        0 => Crs::Unknown,
        1 => {
            let [a, b1, c, d] = *rest else {
                return Err(short(fixed + 4));
            };
            Crs::Epsg(u32::from_le_bytes([a, b1, c, d]))
        }
        2..=4 => {
            let [l0, l1, ref s @ ..] = *rest else {
                return Err(short(fixed + 2));
            };
            let n = u16::from_le_bytes([l0, l1]) as usize;
            if s.len() != n {
                return Err(short(fixed + 2 + n));
            }
            let name = String::from_utf8_lossy(s).into_owned();
            match kind {
                2 => Crs::Geographic(name),
                3 => Crs::Projected(name),
                _ => Crs::Proj(name),
            }
        }
        other => {
            return Err(StreamFileError::Malformed {
                what: "CRS".into(),
                expected: "kind 0, 1, 2, 3 or 4".into(),
                found: format!("kind {other}"),
            })
        }
    })
}

/// The bytes of a `.cstream` file holding `stream` with `georef`.
pub fn stream_bytes(stream: &EncodedStream, georef: &GeoRef) -> Vec<u8> {
    let head = head_bytes(&stream.header, stream.steps.len(), georef);
    let mut v = Vec::new();
    v.extend_from_slice(MAGIC);
    v.extend_from_slice(&VERSION.to_le_bytes());
    v.extend_from_slice(&(head.len() as u32).to_le_bytes());
    v.extend_from_slice(&head);
    v.extend_from_slice(&crc32(&head).to_le_bytes());
    for s in &stream.steps {
        v.extend_from_slice(&(s.payload.len() as u32).to_le_bytes());
        v.extend_from_slice(&crc32(&s.payload).to_le_bytes());
        v.extend_from_slice(&s.payload);
    }
    v
}

/// Bytes of the file up to the end of each step (the first covers the head
/// and step 0).
pub fn step_end_offsets(stream: &EncodedStream, georef: &GeoRef) -> Vec<u64> {
    let head = head_bytes(&stream.header, stream.steps.len(), georef).len() as u64;
    let mut at = 8 + 2 + 4 + head + 4;
    stream
        .steps
        .iter()
        .map(|s| {
            at += 8 + s.payload.len() as u64;
            at
        })
        .collect()
}

/// Writes `stream` to `path` atomically.
///
/// # Errors
/// [`WriteError`] naming the file when it cannot be written.
pub fn write_stream(
    path: &Path,
    stream: &EncodedStream,
    georef: &GeoRef,
) -> Result<(), WriteError> {
    let bytes = stream_bytes(stream, georef);
    write_atomically(path, |w| Ok(w.write_all(&bytes)?))
}

/// One applied step and where it ended in the file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepFrame {
    /// What the decoder reported.
    pub info: StepInfo,
    /// Bytes of the file up to the end of this step.
    pub end_offset: u64,
}

/// Incremental decoding: push bytes as they arrive, get completed steps back.
///
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use cota_core::{GeoRef, HeightGrid};
/// use cota_core::stream::{encode, StreamOptions};
/// use cota_io::stream_file::{stream_bytes, StreamReader};
/// let heights = (0..81).map(|i| ((i * 37) % 11) as f32).collect();
/// let grid = HeightGrid::new(9, 9, heights, GeoRef::unreferenced(30.0))?;
/// let bytes = stream_bytes(&encode(&grid, &StreamOptions::default())?, grid.georef());
/// let mut r = StreamReader::new();
/// let mut steps = 0;
/// for chunk in bytes.chunks(7) {
///     steps += r.push(chunk)?.len();
/// }
/// r.finish()?;
/// assert!(steps >= 2);
/// assert_eq!(r.decoder().map(|d| d.heights_m()), Some(Some(grid.heights().to_vec())));
/// # Ok(())
/// # }
/// ```
#[derive(Debug, Clone, Default)]
pub struct StreamReader {
    buf: Vec<u8>,
    offset: u64,
    decoder: Option<StreamDecoder>,
    georef: Option<GeoRef>,
    announced: u32,
    max_samples: Option<u64>,
}

impl StreamReader {
    /// A reader waiting for the first byte, taking a grid of any size the
    /// format allows.
    pub fn new() -> Self {
        Self::default()
    }

    /// A reader that refuses a head announcing more than `max_samples` grid
    /// samples ([`StreamFileError::TooLarge`]) before the decoder allocates.
    pub fn with_max_samples(max_samples: u64) -> Self {
        StreamReader {
            max_samples: Some(max_samples),
            ..Self::default()
        }
    }

    /// The decoder, once the head has arrived.
    pub fn decoder(&self) -> Option<&StreamDecoder> {
        self.decoder.as_ref()
    }

    /// The georeference, once the head has arrived.
    pub fn georef(&self) -> Option<&GeoRef> {
        self.georef.as_ref()
    }

    /// The number of steps the head announces (0 before the head).
    pub fn announced_steps(&self) -> u32 {
        self.announced
    }

    /// Bytes consumed by complete frames so far.
    pub fn consumed(&self) -> u64 {
        self.offset
    }

    /// Appends `chunk` and applies every step whose frame is now complete.
    ///
    /// # Errors
    /// [`StreamFileError`] for a bad magic, version, head, checksum or step.
    /// After an error the reader keeps the last good prefix and refuses more.
    pub fn push(&mut self, chunk: &[u8]) -> Result<Vec<StepFrame>, StreamFileError> {
        self.buf.extend_from_slice(chunk);
        let mut out = Vec::new();
        loop {
            match self.next_frame()? {
                Some(f) => out.extend(f),
                None => return Ok(out),
            }
        }
    }

    /// Checks that no partial frame is left over and that every announced step
    /// arrived.
    ///
    /// # Errors
    /// [`StreamFileError::Truncated`] when the bytes end inside a frame,
    /// before the head, or before the last announced step.
    pub fn finish(&self) -> Result<(), StreamFileError> {
        let b = &self.buf;
        if self.decoder.is_none() {
            let need = match b.get(10..14) {
                Some(l) => 18 + u32::from_le_bytes([l[0], l[1], l[2], l[3]]) as u64,
                None => 14,
            };
            return Err(StreamFileError::Truncated {
                what: "head".into(),
                expected: need,
                found: b.len() as u64,
            });
        }
        let step = self.decoder.as_ref().map_or(0, |d| d.steps().len());
        if b.is_empty() {
            if step < self.announced as usize {
                return Err(StreamFileError::Truncated {
                    what: format!("steps (the head announces {})", self.announced),
                    expected: self.announced as u64,
                    found: step as u64,
                });
            }
            return Ok(());
        }
        let need = match b.get(..4) {
            Some(l) => 8 + u32::from_le_bytes([l[0], l[1], l[2], l[3]]) as u64,
            None => 8,
        };
        Err(StreamFileError::Truncated {
            what: format!("step {step} frame"),
            expected: need,
            found: b.len() as u64,
        })
    }

    /// Consumes one complete frame from the buffer: `Some(step or nothing)`,
    /// `None` when more bytes are needed.
    fn next_frame(&mut self) -> Result<Option<Option<StepFrame>>, StreamFileError> {
        let b = &self.buf;
        let Some(decoder) = self.decoder.as_mut() else {
            let n = b.len().min(8);
            if b[..n] != MAGIC[..n] {
                return Err(StreamFileError::BadMagic {
                    found: String::from_utf8_lossy(&b[..n]).into_owned(),
                });
            }
            let Some(v) = b.get(8..14) else {
                return Ok(None);
            };
            let version = u16::from_le_bytes([v[0], v[1]]);
            if version != VERSION {
                return Err(StreamFileError::Version { found: version });
            }
            let len = u32::from_le_bytes([v[2], v[3], v[4], v[5]]) as usize;
            if len > MAX_HEAD {
                return Err(StreamFileError::Malformed {
                    what: "head".into(),
                    expected: format!("at most {MAX_HEAD} bytes"),
                    found: format!("{len} bytes"),
                });
            }
            let Some(rest) = b.get(14..18 + len) else {
                return Ok(None);
            };
            let (head, c) = rest.split_at(len);
            let stored = u32::from_le_bytes([c[0], c[1], c[2], c[3]]);
            let actual = crc32(head);
            if stored != actual {
                return Err(StreamFileError::Checksum {
                    what: "the head".into(),
                    expected: stored,
                    found: actual,
                });
            }
            let (header, announced, georef) = parse_head(head)?;
            let samples = u64::from(header.width) * u64::from(header.height);
            if let Some(limit) = self.max_samples.filter(|&l| samples > l) {
                return Err(StreamFileError::TooLarge {
                    width: header.width,
                    height: header.height,
                    samples,
                    limit,
                });
            }
            self.announced = announced;
            self.decoder = Some(StreamDecoder::new(header));
            self.georef = Some(georef);
            self.buf.drain(..18 + len);
            self.offset += 18 + len as u64;
            return Ok(Some(None));
        };
        let Some(l) = b.get(..8) else {
            return Ok(None);
        };
        let len = u32::from_le_bytes([l[0], l[1], l[2], l[3]]) as usize;
        let stored = u32::from_le_bytes([l[4], l[5], l[6], l[7]]);
        let step = decoder.steps().len();
        if step >= self.announced as usize {
            return Err(StreamFileError::Malformed {
                what: format!("step {step}"),
                expected: format!(
                    "no more than the {} steps the head announces",
                    self.announced
                ),
                found: "more bytes".into(),
            });
        }
        if len > MAX_STEP {
            return Err(StreamFileError::Malformed {
                what: format!("step {step}"),
                expected: format!("at most {MAX_STEP} bytes"),
                found: format!("{len} bytes"),
            });
        }
        let Some(payload) = b.get(8..8 + len) else {
            return Ok(None);
        };
        let actual = crc32(payload);
        if stored != actual {
            return Err(StreamFileError::Checksum {
                what: format!("step {step}"),
                expected: stored,
                found: actual,
            });
        }
        let info = decoder.apply_step(payload)?;
        self.buf.drain(..8 + len);
        self.offset += 8 + len as u64;
        Ok(Some(Some(StepFrame {
            info,
            end_offset: self.offset,
        })))
    }
}

/// Where [`read_stream`] stops.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[non_exhaustive]
pub struct StreamLimit {
    /// Use only the steps that end within this many bytes of the file.
    /// Default: `None` (all).
    pub max_bytes: Option<u64>,
    /// Stop at the first step whose stated max error is at most this, metres.
    /// Default: `None` (all).
    pub max_error_m: Option<f64>,
    /// Refuse a head announcing more grid samples than this. Default: `None`,
    /// the machine's budget ([`crate::limits::default_max_samples`]).
    pub max_samples: Option<u64>,
    /// Keep the complete steps of a stream that ends inside a step frame or
    /// before its last announced step (a partial download), reporting what
    /// is missing in [`DecodedStream::truncated`], instead of refusing it.
    /// The head and step 0 must be whole. Default: `false` (refuse).
    pub partial: bool,
}

impl StreamLimit {
    /// Every step.
    pub const ALL: StreamLimit = StreamLimit {
        max_bytes: None,
        max_error_m: None,
        max_samples: None,
        partial: false,
    };

    /// Sets [`StreamLimit::partial`].
    pub const fn with_partial(mut self, partial: bool) -> Self {
        self.partial = partial;
        self
    }

    /// Sets [`StreamLimit::max_bytes`].
    pub const fn with_max_bytes(mut self, n: Option<u64>) -> Self {
        self.max_bytes = n;
        self
    }

    /// Sets [`StreamLimit::max_error_m`].
    pub const fn with_max_error_m(mut self, e: Option<f64>) -> Self {
        self.max_error_m = e;
        self
    }

    /// Sets [`StreamLimit::max_samples`].
    pub const fn with_max_samples(mut self, n: Option<u64>) -> Self {
        self.max_samples = n;
        self
    }
}

/// A decoded prefix of a stream file.
#[derive(Debug, Clone)]
pub struct DecodedStream {
    /// The decoder holding the prefix.
    pub decoder: StreamDecoder,
    /// The georeference from the head.
    pub georef: GeoRef,
    /// The applied steps.
    pub steps: Vec<StepFrame>,
    /// Size of the whole file in bytes.
    pub file_bytes: u64,
    /// With [`StreamLimit::partial`], what a cut stream lacks: the error a
    /// whole stream would have been refused with. `None` when whole.
    pub truncated: Option<Truncation>,
}

/// What a cut stream lacks ([`DecodedStream::truncated`]).
#[derive(Debug, Clone)]
pub struct Truncation {
    /// The refusal it replaces ([`StreamFileError::Truncated`]).
    pub error: StreamFileError,
    /// The steps the head announces.
    pub announced_steps: u32,
}

/// Reads `path` and decodes it up to `limit`, one frame at a time: bytes past
/// the limits are never read, and no frame is larger than the format allows.
///
/// # Errors
/// [`StreamReadError`] naming the file: I/O, bad magic or version, checksum,
/// truncation (also when `max_bytes` is too small for the head and step 0),
/// a grid over the sample limit, or a step the core decoder rejects.
pub fn read_stream(path: &Path, limit: &StreamLimit) -> Result<DecodedStream, StreamReadError> {
    read_stream_with_progress(path, limit, &|_, _| {})
}

/// [`read_stream`], telling `progress(bytes_read, bytes)` as the steps are
/// read and decoded (`bytes`: the file's size, or `max_bytes` when
/// smaller; `(bytes, bytes)` at the end, wherever the limits stopped).
///
/// # Errors
/// As [`read_stream`].
pub fn read_stream_with_progress(
    path: &Path,
    limit: &StreamLimit,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<DecodedStream, StreamReadError> {
    let err = |kind: StreamReadErrorKind| StreamReadError {
        path: path.to_path_buf(),
        kind,
    };
    let file = std::fs::File::open(path).map_err(|e| err(e.into()))?;
    let size = file.metadata().map_err(|e| err(e.into()))?.len();
    let total = size.min(limit.max_bytes.unwrap_or(u64::MAX));
    let done = std::sync::atomic::AtomicU64::new(0);
    progress(0, total);
    let counted = |n: u64| {
        let d = done.fetch_add(n, std::sync::atomic::Ordering::Relaxed) + n;
        progress(d.min(total), total);
    };
    let reader = crate::read::Counted {
        inner: file,
        counted: &counted,
    };
    let mut d = decode_stream_from(std::io::BufReader::new(reader), limit, false).map_err(err)?;
    progress(total, total);
    d.file_bytes = size;
    Ok(d)
}

/// [`read_stream`] on any reader (standard input): `name` is what errors
/// call it. [`DecodedStream::file_bytes`] counts the whole input, the rest
/// after the limits read and dropped.
///
/// # Errors
/// As [`read_stream`].
pub fn read_stream_from(
    reader: impl Read,
    name: &Path,
    limit: &StreamLimit,
) -> Result<DecodedStream, StreamReadError> {
    decode_stream_from(reader, limit, true).map_err(|kind| StreamReadError {
        path: name.to_path_buf(),
        kind,
    })
}

/// [`read_stream`] on bytes in memory.
///
/// # Errors
/// As [`read_stream`], without the file name.
pub fn decode_stream_bytes(
    bytes: &[u8],
    limit: &StreamLimit,
) -> Result<DecodedStream, StreamFileError> {
    decode_stream_from(bytes, limit, true).map_err(|e| match e {
        StreamReadErrorKind::Stream(s) => s,
        StreamReadErrorKind::Io(e) => StreamFileError::Malformed {
            what: "bytes".into(),
            expected: "bytes in memory".into(),
            found: e.to_string(),
        },
    })
}

/// Reads `r` frame by frame (the fixed prefix, then the rest once its
/// length is known and allowed) and decodes up to `limit`; `count_rest`:
/// read what is left after the limits to count the input's bytes.
fn decode_stream_from(
    mut r: impl Read,
    limit: &StreamLimit,
    count_rest: bool,
) -> Result<DecodedStream, StreamReadErrorKind> {
    let max_samples = limit
        .max_samples
        .unwrap_or_else(crate::limits::default_max_samples);
    let mut rd = StreamReader::with_max_samples(max_samples);
    let mut steps: Vec<StepFrame> = Vec::new();
    let cap = limit.max_bytes.unwrap_or(u64::MAX);
    let mut read = 0u64;
    let mut stopped = false;
    loop {
        if let Some(e) = limit.max_error_m {
            if steps.last().is_some_and(|s| s.info.max_error_m <= e) {
                stopped = true;
                break;
            }
        }
        let have_head = rd.decoder().is_some();
        let mut frame = Vec::new();
        let prefix = if have_head { 8 } else { 14 };
        read_up_to(&mut r, &mut frame, prefix)?;
        if frame.is_empty() {
            break;
        }
        let end = next_frame_end(&frame, 0, have_head) as u64;
        if read.saturating_add(end) > cap && rd.decoder().is_some_and(|d| !d.steps().is_empty()) {
            stopped = true;
            read += frame.len() as u64;
            break;
        }
        let most = if have_head {
            MAX_STEP + 8
        } else {
            MAX_HEAD + 18
        } as u64;
        if frame.len() == prefix && end <= most {
            read_up_to(&mut r, &mut frame, end as usize)?;
        }
        read += frame.len() as u64;
        steps.extend(rd.push(&frame)?);
        if (frame.len() as u64) < end {
            break;
        }
    }
    let mut truncated = None;
    if !stopped {
        match rd.finish() {
            Ok(()) => {}
            Err(e) if limit.partial && rd.decoder().is_some() && !steps.is_empty() => {
                truncated = Some(Truncation {
                    error: e,
                    announced_steps: rd.announced,
                });
            }
            Err(e) => return Err(e.into()),
        }
    }
    if count_rest {
        read += std::io::copy(&mut r, &mut std::io::sink())?;
    }
    let mut d = finish_decoded(rd, steps, limit, read)?;
    d.truncated = truncated;
    Ok(d)
}

/// Appends bytes from `r` to `buf` until it holds `len` bytes or the input
/// ends.
fn read_up_to(r: &mut impl Read, buf: &mut Vec<u8>, len: usize) -> std::io::Result<()> {
    let want = len.saturating_sub(buf.len()) as u64;
    r.take(want).read_to_end(buf).map(|_| ())
}

/// The checks after the last frame read: step 0 within `max_bytes`, a head
/// and a step present.
fn finish_decoded(
    r: StreamReader,
    steps: Vec<StepFrame>,
    limit: &StreamLimit,
    read: u64,
) -> Result<DecodedStream, StreamFileError> {
    if let Some(n) = limit.max_bytes {
        if let Some(first) = steps.first() {
            if first.end_offset > n {
                return Err(StreamFileError::Truncated {
                    what: "the head and step 0 (--max-bytes)".into(),
                    expected: first.end_offset,
                    found: n,
                });
            }
        }
    }
    let (Some(decoder), Some(georef)) = (r.decoder().cloned(), r.georef().cloned()) else {
        return Err(StreamFileError::Truncated {
            what: "head".into(),
            expected: 18,
            found: read,
        });
    };
    if steps.is_empty() {
        return Err(StreamFileError::Truncated {
            what: "step 0 frame".into(),
            expected: 8,
            found: 0,
        });
    }
    Ok(DecodedStream {
        decoder,
        georef,
        steps,
        file_bytes: read,
        truncated: None,
    })
}

/// End of the frame starting at `at` (head or step), saturating on garbage.
fn next_frame_end(b: &[u8], at: usize, have_head: bool) -> usize {
    let u32_at = |i: usize| {
        b.get(i..i + 4)
            .map(|l| u32::from_le_bytes([l[0], l[1], l[2], l[3]]) as usize)
    };
    if !have_head {
        return match u32_at(at + 10) {
            Some(len) => at.saturating_add(18).saturating_add(len),
            None => b.len(),
        };
    }
    match u32_at(at) {
        Some(len) => at.saturating_add(8).saturating_add(len),
        None => b.len(),
    }
}
