//! The tiles coarser than the band zoom of a sharded pyramid, made by the
//! reduce from the shards' partial maxima ([`cota_core::tiles::partial`],
//! [`cota_core::tiles::merge`]): no process ever holds the whole lattice.
//!
//! Files under `OUT`, all written atomically and removed by the reduce:
//!
//! * `.cota-shards-N.corners`: the band zoom's tile-corner heights (the plan
//!   step's; every coarse triangle's plane needs only its corners);
//! * `.cota-partial-I-of-N.bin`: shard `I`'s partial maxima, gzipped, with
//!   the pyramid's plan (zooms, thresholds as exact `f64` bits) and its
//!   extensions, written before its record.
//!
//! Both are little-endian binary with a magic and a version; a truncated,
//! foreign or inconsistent file is refused naming it, and its counts are
//! checked against its length before anything is allocated.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use cota_core::tiles::{
    owned_region, shard_plan, BandCorners, CoarseHierarchy, CoarsePartial, FinePoint, Prepared,
    SourcePart, TileId, TileRange, ZoomPlan,
};
use rayon::prelude::*;

use super::frame::ShardFrame;
use super::pyramid::{finish_tile, tile_path, write_file_atomically, PyramidError, PyramidOptions};
use super::quantized_mesh::TileExtensions;

const CORNERS_MAGIC: &[u8; 8] = b"COTACRN1";
const PARTIAL_MAGIC: &[u8; 8] = b"COTAPRT1";

/// The path of the band corners of `shards` shards under `out`.
pub fn corners_path(out: &Path, shards: u32) -> PathBuf {
    out.join(format!(".cota-shards-{shards}.corners"))
}

/// The path of shard `index`'s partial maxima under `out`.
pub fn partial_path(out: &Path, index: u32, shards: u32) -> PathBuf {
    out.join(format!(".cota-partial-{index}-of-{shards}.bin"))
}

pub(super) fn bad(path: &Path, message: String) -> PyramidError {
    PyramidError::Shard {
        path: path.to_path_buf(),
        message,
    }
}

/// Writes the band corners (every one known) for `shards` shards.
///
/// # Errors
/// [`PyramidError::Shard`] when a corner is not known, [`PyramidError::Io`].
pub fn write_band_corners(out: &Path, shards: u32, c: &BandCorners) -> Result<(), PyramidError> {
    let path = corners_path(out, shards);
    if c.missing() > 0 {
        return Err(bad(
            &path,
            format!(
                "expected every band corner's height, found {} missing",
                c.missing()
            ),
        ));
    }
    let mut b = CORNERS_MAGIC.to_vec();
    b.extend(c.cells.to_le_bytes());
    for v in c.window {
        b.extend(v.to_le_bytes());
    }
    for h in &c.heights_m {
        b.extend(h.to_le_bytes());
    }
    write_file_atomically(&path, &b, true)
}

/// Reads the band corners the plan step wrote for `frame`.
///
/// # Errors
/// [`PyramidError::Shard`] for a missing, truncated or foreign file.
pub fn read_band_corners(out: &Path, frame: &ShardFrame) -> Result<BandCorners, PyramidError> {
    let path = corners_path(out, frame.shards);
    let bytes = std::fs::read(&path).map_err(|e| {
        bad(
            &path,
            format!("expected the plan step's band corners, could not read them: {e}"),
        )
    })?;
    let t = frame.frame.scheme.cells_at(frame.band_zoom);
    let window = frame.frame.window;
    let [nx, ny] = BandCorners::dims(window, t);
    let mut r = Reader::new(&bytes, &path);
    r.magic(CORNERS_MAGIC)?;
    let (cells, win) = (r.u64()?, [r.u64()?, r.u64()?, r.u64()?, r.u64()?]);
    if cells != t || win != window || r.left() != nx * ny * 4 {
        return Err(bad(
            &path,
            format!(
                "expected {nx}x{ny} corners every {t} cells over {window:?}, found {} bytes every {cells} cells over {win:?}",
                r.left()
            ),
        ));
    }
    let mut c = BandCorners::new(window, t);
    for h in &mut c.heights_m {
        *h = r.f32()?;
    }
    Ok(c)
}

/// A bounds-checked little-endian reader naming its file.
pub(super) struct Reader<'a> {
    b: &'a [u8],
    at: usize,
    path: &'a Path,
}

impl<'a> Reader<'a> {
    pub(super) fn new(b: &'a [u8], path: &'a Path) -> Self {
        Reader { b, at: 0, path }
    }

    pub(super) fn left(&self) -> usize {
        self.b.len() - self.at
    }

    pub(super) fn take(&mut self, n: usize) -> Result<&'a [u8], PyramidError> {
        if self.left() < n {
            return Err(bad(
                self.path,
                format!(
                    "expected {n} more bytes at byte {}, found {}: truncated",
                    self.at,
                    self.left()
                ),
            ));
        }
        let s = &self.b[self.at..self.at + n];
        self.at += n;
        Ok(s)
    }

    pub(super) fn magic(&mut self, m: &[u8; 8]) -> Result<(), PyramidError> {
        let found = self.take(8).unwrap_or_default();
        if found != m {
            return Err(bad(
                self.path,
                format!(
                    "expected a file starting {:?}, found {:?}",
                    String::from_utf8_lossy(m),
                    String::from_utf8_lossy(found)
                ),
            ));
        }
        Ok(())
    }

    pub(super) fn arr<const N: usize>(&mut self) -> Result<[u8; N], PyramidError> {
        let mut a = [0u8; N];
        a.copy_from_slice(self.take(N)?);
        Ok(a)
    }

    pub(super) fn u8(&mut self) -> Result<u8, PyramidError> {
        Ok(self.arr::<1>()?[0])
    }
    pub(super) fn u16(&mut self) -> Result<u16, PyramidError> {
        Ok(u16::from_le_bytes(self.arr()?))
    }
    pub(super) fn u32(&mut self) -> Result<u32, PyramidError> {
        Ok(u32::from_le_bytes(self.arr()?))
    }
    pub(super) fn u64(&mut self) -> Result<u64, PyramidError> {
        Ok(u64::from_le_bytes(self.arr()?))
    }
    pub(super) fn f32(&mut self) -> Result<f32, PyramidError> {
        Ok(f32::from_le_bytes(self.arr()?))
    }
    pub(super) fn f64(&mut self) -> Result<f64, PyramidError> {
        Ok(f64::from_le_bytes(self.arr()?))
    }

    /// A count of records of `size` bytes, at most what is left.
    pub(super) fn count(&mut self, size: usize) -> Result<usize, PyramidError> {
        let n = self.u64()?;
        if n > (self.left() / size) as u64 {
            return Err(bad(
                self.path,
                format!(
                    "expected at most {} records of {size} bytes, found a count of {n}",
                    self.left() / size
                ),
            ));
        }
        Ok(n as usize)
    }
}

/// What a shard's partial file holds besides the maxima.
#[derive(Debug, Clone, PartialEq)]
pub struct PartialHeader {
    /// The shard, and the number of shards.
    pub shard: [u32; 2],
    /// The band zoom.
    pub band_zoom: u8,
    /// The pyramid's plan, every zoom.
    pub zooms: Vec<ZoomPlan>,
    /// The extensions of the tiles, and whether they are gzipped.
    pub extensions: TileExtensions,
    /// Gzip each tile.
    pub gzip: bool,
}

fn encode_partial(h: &PartialHeader, p: &CoarsePartial) -> Vec<u8> {
    let mut b = Vec::new();
    b.extend(h.shard[0].to_le_bytes());
    b.extend(h.shard[1].to_le_bytes());
    b.push(h.band_zoom);
    let e = h.extensions;
    b.push(
        u8::from(e.normals)
            | u8::from(e.watermask) << 1
            | u8::from(e.metadata) << 2
            | u8::from(h.gzip) << 3,
    );
    b.extend((h.zooms.len() as u64).to_le_bytes());
    for z in &h.zooms {
        b.push(z.zoom);
        let w = z.window_range;
        for v in [
            z.range.x0, z.range.x1, z.range.y0, z.range.y1, w.x0, w.x1, w.y0, w.y1,
        ] {
            b.extend(v.to_le_bytes());
        }
        for v in [z.max_error_m, z.margin_m, z.threshold_m] {
            b.extend(v.to_le_bytes());
        }
    }
    b.extend((p.fine.len() as u64).to_le_bytes());
    for f in &p.fine {
        b.extend(f.at[0].to_le_bytes());
        b.extend(f.at[1].to_le_bytes());
        b.extend(f.splits.to_le_bytes());
        b.extend(f.code.to_le_bytes());
        b.extend(f.src.to_le_bytes());
        b.extend(f.height_m.to_le_bytes());
    }
    for own in [&p.own, &p.own_src] {
        b.extend((own.len() as u64).to_le_bytes());
        for (m, e) in own {
            b.extend(m[0].to_le_bytes());
            b.extend(m[1].to_le_bytes());
            b.extend(e.to_le_bytes());
        }
    }
    b.extend((p.normals.len() as u64).to_le_bytes());
    for (m, z, n) in &p.normals {
        b.extend(m[0].to_le_bytes());
        b.extend(m[1].to_le_bytes());
        b.push(*z);
        for c in n {
            b.extend(c.to_le_bytes());
        }
    }
    b.extend((p.water.len() as u64).to_le_bytes());
    for (t, g) in &p.water {
        b.push(t.z);
        b.extend(t.x.to_le_bytes());
        b.extend(t.y.to_le_bytes());
        b.extend(g);
    }
    b
}

fn decode_partial(r: &mut Reader<'_>) -> Result<(PartialHeader, CoarsePartial), PyramidError> {
    let shard = [r.u32()?, r.u32()?];
    let band_zoom = r.u8()?;
    let flags = r.u8()?;
    let mut zooms = Vec::with_capacity(r.count(57)?);
    for _ in 0..zooms.capacity() {
        let zoom = r.u8()?;
        let mut range = || -> Result<TileRange, PyramidError> {
            Ok(TileRange {
                x0: r.u32()?,
                x1: r.u32()?,
                y0: r.u32()?,
                y1: r.u32()?,
            })
        };
        let (range, window_range) = (range()?, range()?);
        let (max_error_m, margin_m, threshold_m) = (r.f64()?, r.f64()?, r.f64()?);
        zooms.push(ZoomPlan {
            zoom,
            range,
            window_range,
            max_error_m,
            margin_m,
            threshold_m,
        });
    }
    let mut p = CoarsePartial::default();
    for _ in 0..r.count(20)? {
        let at = [r.u32()?, r.u32()?];
        let (splits, code) = (r.u32()?, r.u16()?);
        let (src, height_m) = (r.u16()?, r.f32()?);
        p.fine.push(FinePoint {
            at,
            splits,
            code,
            src,
            height_m,
        });
    }
    for _ in 0..r.count(12)? {
        p.own.push(([r.u32()?, r.u32()?], r.f32()?));
    }
    for _ in 0..r.count(12)? {
        p.own_src.push(([r.u32()?, r.u32()?], r.f32()?));
    }
    for _ in 0..r.count(21)? {
        let (m, z) = ([r.u32()?, r.u32()?], r.u8()?);
        p.normals.push((m, z, [r.f32()?, r.f32()?, r.f32()?]));
    }
    for _ in 0..r.count(9 + 65536)? {
        let t = TileId {
            z: r.u8()?,
            x: r.u32()?,
            y: r.u32()?,
        };
        p.water.push((t, r.take(65536)?.to_vec()));
    }
    let extensions = TileExtensions::with(flags & 1 != 0, flags & 2 != 0, flags & 4 != 0);
    let h = PartialHeader {
        shard,
        band_zoom,
        zooms,
        extensions,
        gzip: flags & 8 != 0,
    };
    Ok((h, p))
}

/// Writes shard `header.shard`'s partial maxima (gzipped, atomically).
///
/// # Errors
/// [`PyramidError::Io`].
pub fn write_partial(
    out: &Path,
    header: &PartialHeader,
    p: &CoarsePartial,
) -> Result<(), PyramidError> {
    let path = partial_path(out, header.shard[0], header.shard[1]);
    let mut body = PARTIAL_MAGIC.to_vec();
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    let io = |source| PyramidError::Io {
        path: path.clone(),
        source,
    };
    gz.write_all(&encode_partial(header, p)).map_err(io)?;
    body.extend(gz.finish().map_err(io)?);
    write_file_atomically(&path, &body, true)
}

/// The most a partial file may decompress to (a guard against a bomb).
const MAX_PARTIAL_BYTES: u64 = 1 << 36;

/// Reads a partial file written by [`write_partial`].
///
/// # Errors
/// [`PyramidError::Shard`] for a missing, truncated, foreign or oversized file.
pub fn read_partial(path: &Path) -> Result<(PartialHeader, CoarsePartial), PyramidError> {
    let raw = std::fs::read(path).map_err(|e| {
        bad(
            path,
            format!("expected a shard's partial maxima, could not read them: {e}"),
        )
    })?;
    Reader::new(&raw, path).magic(PARTIAL_MAGIC)?;
    let mut bytes = Vec::new();
    flate2::read::GzDecoder::new(&raw[8..])
        .take(MAX_PARTIAL_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| bad(path, format!("expected gzipped partial maxima, found: {e}")))?;
    if bytes.len() as u64 > MAX_PARTIAL_BYTES {
        return Err(bad(
            path,
            format!("expected at most {MAX_PARTIAL_BYTES} bytes of partial maxima, found more"),
        ));
    }
    let mut r = Reader::new(&bytes, path);
    let got = decode_partial(&mut r)?;
    if r.left() != 0 {
        return Err(bad(
            path,
            format!(
                "expected the end of the partial maxima, found {} more bytes",
                r.left()
            ),
        ));
    }
    Ok(got)
}

/// Computes and writes shard `index`'s partial maxima from its prepared part
/// `prep` (after the plan step wrote `frame` and the band corners).
///
/// # Errors
/// [`PyramidError::Shard`] for missing corners, [`PyramidError::Tiles`],
/// [`PyramidError::Io`].
pub fn write_shard_partial(
    prep: &Prepared<'_>,
    source: SourcePart<'_>,
    out: &Path,
    frame: &ShardFrame,
    index: u32,
    opts: &PyramidOptions,
) -> Result<(), PyramidError> {
    let corners = read_band_corners(out, frame)?;
    let band = frame.band_zoom;
    let shard = shard_plan(prep.zooms(), frame.shards)?
        .into_iter()
        .nth(index as usize)
        .map(|s| s.from_zoom(band));
    let owned = shard.and_then(|s| owned_region(&s, &frame.frame.scheme, band));
    let ext = opts.extensions;
    let partial = match owned {
        Some(o) => prep.coarse_partial(o, band, &corners, source, ext.normals, ext.watermask)?,
        None => CoarsePartial::default(),
    };
    let header = PartialHeader {
        shard: [index, frame.shards],
        band_zoom: band,
        zooms: prep.zooms().to_vec(),
        extensions: ext,
        gzip: opts.gzip,
    };
    write_partial(out, &header, &partial)
}

/// Reads every shard's partial maxima, merges them and writes the tiles
/// coarser than the band zoom (skipping those there unless `force`);
/// returns how many tiles it wrote and how many it found there.
///
/// # Errors
/// [`PyramidError::Shard`] naming a missing, damaged or disagreeing partial
/// file, [`PyramidError::Tiles`], [`PyramidError::Io`], and the tile's
/// encode or decode errors (a bug: never written).
pub fn write_reduced_coarse(
    out: &Path,
    frame: &ShardFrame,
    force: bool,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<[u64; 2], PyramidError> {
    let corners = read_band_corners(out, frame)?;
    let mut first: Option<PartialHeader> = None;
    let mut partials = Vec::new();
    for i in 0..frame.shards {
        let path = partial_path(out, i, frame.shards);
        let (h, p) = read_partial(&path)?;
        let agrees = first
            .as_ref()
            .is_none_or(|f| f.zooms == h.zooms && f.extensions == h.extensions && f.gzip == h.gzip);
        if h.shard != [i, frame.shards] || h.band_zoom != frame.band_zoom || !agrees {
            return Err(bad(&path, format!("expected shard {i} of {} of this run, found shard {:?} of another run or settings", frame.shards, h.shard)));
        }
        first.get_or_insert(h);
        partials.push(p);
    }
    let Some(h) = first else {
        return Ok([0, 0]);
    };
    let hier = CoarseHierarchy::new(
        &frame.frame,
        &frame.stats,
        h.zooms,
        frame.band_zoom,
        corners,
        partials,
    )?;
    let opts = PyramidOptions::DEFAULT
        .with_extensions(h.extensions)
        .with_gzip(h.gzip)
        .with_force(force);
    let tiles: Vec<TileId> = hier.tiles().collect();
    let done = AtomicU64::new(0);
    let written = tiles
        .par_iter()
        .map(|&t| {
            let path = tile_path(out, t);
            let wrote = if !force && path.is_file() {
                0
            } else {
                let tile = hier.cut(t, opts.extensions.normals, opts.extensions.watermask)?;
                let made = finish_tile(tile, &opts, None, None)?;
                write_file_atomically(&path, &made.bytes, force)?;
                1
            };
            progress(done.fetch_add(1, Ordering::Relaxed) + 1);
            Ok(wrote)
        })
        .collect::<Result<Vec<u64>, PyramidError>>()?
        .iter()
        .sum();
    Ok([written, tiles.len() as u64 - written])
}

/// Removes the band corners and the partial files of `shards` shards.
///
/// # Errors
/// [`PyramidError::Io`].
pub fn remove_coarse_files(out: &Path, shards: u32) -> Result<(), PyramidError> {
    let paths = (0..shards)
        .map(|i| partial_path(out, i, shards))
        .chain([corners_path(out, shards)]);
    for p in paths.filter(|p| p.is_file()) {
        std::fs::remove_file(&p).map_err(|source| PyramidError::Io { path: p, source })?;
    }
    Ok(())
}
