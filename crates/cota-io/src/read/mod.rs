//! Reading DEM files: one file into a [`Dem`] ([`read_dem`], [`read_dem_bytes`]:
//! format detection and dispatch), or several into one grid ([`read_region`]:
//! read in parallel, mosaicked, voids filled).
//!
//! Detection (`sniff`) looks at the content first (magic bytes of
//! ZIP, TIFF, PNG, gzip; the keywords of an ESRI ASCII header; the exact byte
//! size of an SRTM tile) and uses the file name only where content cannot
//! decide (a raw `.hgt` has no header, so its size and name are all there is).
//! A gzipped file is decompressed (once) and its content detected again.
//!
//! Layout: this module dispatches to the readers (`srtm`, `asc`, `png`,
//! `webp`, `geotiff`, `npy`, `usgs_dem`, [`pmtiles`]), which import only
//! [`crate::dem`], [`crate::error`], `sniff` and the shared helpers `rgb`
//! (RGB height encodings) and `tile` (z/x/y web tiles); [`pmtiles`], a
//! container, also calls the `png` and `webp` readers for its tiles; `region`
//! joins what was read. No reader imports this module. A PMTiles archive is read from
//! the open file (its header, directories and the tiles asked for), never whole.

mod asc;
mod geotiff;
mod npy;
mod orient;
pub mod pmtiles;
mod png;
mod region;
mod rgb;
mod sniff;
mod srtm;
mod tile;
mod usgs_dem;
mod webp;

use std::path::Path;

use rayon::prelude::*;

/// The band count of a TIFF, for the imagery reader (`crate::image`).
pub(crate) use geotiff::band_count as tiff_band_count;
pub use region::{join, join_groups, resample_join, Region, RegionOptions, Resampled};
/// What the first bytes of a file look like, for messages.
pub(crate) use sniff::describe_bytes as describe;

use self::sniff::{describe_bytes, name_hint, sniff, Sniffed};
use crate::dem::{Dem, ReadOptions};
use crate::error::{ReadError, ReadErrorKind, RegionError};

/// Reads one DEM file.
///
/// # Errors
/// A [`ReadError`] naming `path` and saying what was expected and found.
pub fn read_dem(path: &Path, opts: &ReadOptions) -> Result<Dem, ReadError> {
    read_dem_counted(path, opts, &|_| {})
}

/// [`read_dem`], telling `counted(bytes)` of each read from the file as
/// it arrives (a PMTiles archive, read in parts, once at the end: its size).
fn read_dem_counted(
    path: &Path,
    opts: &ReadOptions,
    counted: &(dyn Fn(u64) + Sync),
) -> Result<Dem, ReadError> {
    let wrap = |kind| ReadError::new(path, kind);
    if pmtiles::is_pmtiles_file(path) {
        // An archive may be far larger than memory: read only what is asked.
        let mut file = std::fs::File::open(path).map_err(|e| wrap(ReadErrorKind::Io(e)))?;
        let dem = pmtiles::decode(&mut file, path, opts)
            .map(with_guessed_crs)
            .and_then(|d| heights_within(d, opts))
            .map_err(wrap);
        counted(file.metadata().map_or(0, |m| m.len()));
        return dem;
    }
    // The size is checked against the budget before anything is read: a
    // file larger than any DEM within the sample limit is refused unread.
    let file = std::fs::File::open(path).map_err(|e| wrap(ReadErrorKind::Io(e)))?;
    let len = file
        .metadata()
        .map_err(|e| wrap(ReadErrorKind::Io(e)))?
        .len();
    crate::limits::check_file_bytes(len, opts).map_err(wrap)?;
    read_dem_from(
        Counted {
            inner: file,
            counted,
        },
        path,
        opts,
    )
}

/// A reader that tells `counted(bytes)` of each read.
pub(crate) struct Counted<'a, R> {
    /// The reader.
    pub(crate) inner: R,
    /// Told the bytes of each read.
    pub(crate) counted: &'a (dyn Fn(u64) + Sync),
}

impl<R: std::io::Read> std::io::Read for Counted<'_, R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        (self.counted)(n as u64);
        Ok(n)
    }
}

/// Reads one DEM from `reader` (standard input, a pipe, an open file),
/// detected from its content; `name` names it in messages and supplies what
/// a name may (an SRTM position, an extension), so a name without either
/// (`<stdin>`) leaves detection to the content alone: a raw `.hgt` is then
/// recognised by its size (1201² or 3601² samples). At most
/// [`crate::limits::max_file_bytes`] bytes are read: a longer stream is
/// refused as too large once that many have arrived, never held whole.
///
/// # Errors
/// A [`ReadError`] naming `name`: [`ReadErrorKind::FileTooLarge`] past the
/// byte budget, [`ReadErrorKind::Empty`] for no bytes, else as [`read_dem`].
pub fn read_dem_from<R: std::io::Read>(
    reader: R,
    name: &Path,
    opts: &ReadOptions,
) -> Result<Dem, ReadError> {
    let wrap = |kind| ReadError::new(name, kind);
    let bytes = read_capped_content(reader, name, opts).map_err(wrap)?;
    if bytes.is_empty() {
        return Err(wrap(ReadErrorKind::Empty));
    }
    decode_bytes(&bytes, name, opts).map_err(wrap)
}

/// Bytes read before the content decides how many more may follow.
const SNIFF_BYTES: u64 = 1 << 16;

/// Reads `reader` whole, stopping as soon as it holds more than its content
/// may be: content without a known magic number or text header can only be
/// a raw `.hgt` (at most [`crate::limits::HGT_MAX_BYTES`] unless the limit is
/// set), anything else at most [`crate::limits::max_file_bytes`]. A device
/// or a pipe that never ends (`/dev/zero`, standard input) is refused once
/// that many bytes have arrived, whatever its size claims.
fn read_capped_content<R: std::io::Read>(
    mut reader: R,
    name: &Path,
    opts: &ReadOptions,
) -> Result<Vec<u8>, ReadErrorKind> {
    use crate::limits::read_capped;
    let mut bytes = Vec::new();
    read_capped(&mut reader, SNIFF_BYTES, &mut bytes)?;
    let headless = sniff(&bytes) == Sniffed::Unknown;
    let limit = if headless {
        crate::limits::gzip_cap(true, opts)
    } else {
        crate::limits::max_file_bytes(opts)
    };
    let room = limit.saturating_sub(bytes.len() as u64);
    if read_capped(&mut reader, room, &mut bytes)? {
        return Ok(bytes);
    }
    if headless {
        let head = describe_bytes(&bytes[..bytes.len().min(8)]);
        let head = head.rsplit_once(" (").map_or(head.as_str(), |(h, _)| h);
        return Err(ReadErrorKind::UnknownFormat {
            found: format!(
                "{head}… with no magic number, and more than {limit} bytes: longer than a raw \
                 .hgt (the only format without one) may be{} (reading stopped there)",
                name_hint(name)
            ),
        });
    }
    Err(crate::limits::file_too_large(limit.saturating_add(1), opts))
}

/// Applies [`cota_core::GeoRef::guess_geographic`] to a freshly read DEM.
fn with_guessed_crs(mut dem: Dem) -> Dem {
    let g = &dem.grid;
    if let Some(crs) = g.georef().guess_geographic(g.width(), g.height()) {
        let mut georef = g.georef().clone();
        georef.crs = crs;
        dem.grid.set_georef(georef);
    }
    dem
}

/// Decodes DEM content already in memory; `path` supplies the name (SRTM
/// position, extension) and is used in no other way. This is what the fuzzers call.
///
/// # Errors
/// A [`ReadError`] naming `path`.
pub fn read_dem_bytes(bytes: &[u8], path: &Path, opts: &ReadOptions) -> Result<Dem, ReadError> {
    if bytes.is_empty() {
        return Err(ReadError::new(path, ReadErrorKind::Empty));
    }
    decode_bytes(bytes, path, opts).map_err(|k| ReadError::new(path, k))
}

/// Decodes DEM content; `path` supplies the name (SRTM position, extension).
pub(crate) fn decode_bytes(
    bytes: &[u8],
    path: &Path,
    opts: &ReadOptions,
) -> Result<Dem, ReadErrorKind> {
    let dem = match sniff(bytes) {
        // gzip (`N00E010.hgt.gz` as served by the AWS/Mapzen "skadi" tiles, or
        // any other gzipped DEM): decompress and read what is inside.
        Sniffed::Gzip => gunzip_and_decode(bytes, path, opts),
        // A ZIP of `.npy` members is a NumPy `.npz`; any other is read as a
        // zipped SRTM tile.
        Sniffed::Zip if npy::is_npz(bytes) => npy::decode_npz(bytes, path, opts),
        Sniffed::Zip => srtm::decode(bytes, path, opts),
        Sniffed::WebP => webp::decode(bytes, path, opts),
        Sniffed::Npy => npy::decode_npy(bytes, path, opts),
        Sniffed::UsgsDem => usgs_dem::decode(bytes, path, opts),
        Sniffed::Pmtiles => pmtiles::decode(&mut std::io::Cursor::new(bytes), path, opts),
        Sniffed::Tiff => geotiff::decode(bytes, path, opts),
        Sniffed::Png => png::decode(bytes, path, opts),
        Sniffed::Ascii => asc::decode(bytes, path, opts),
        // A raw .hgt has no magic: the SRTM reader decides by size and name.
        Sniffed::Unknown if srtm::looks_like_hgt(bytes, path) => srtm::decode(bytes, path, opts),
        Sniffed::Unknown => Err(ReadErrorKind::UnknownFormat {
            found: format!("{}{}", describe_bytes(bytes), name_hint(path)),
        }),
    }?;
    heights_within(with_guessed_crs(dem), opts)
}

/// Refuses a DEM holding a height beyond [`ReadOptions::max_abs_height_m`]
/// (never above [`crate::dem::MAX_ABS_HEIGHT_M`]), naming the first such
/// sample.
fn heights_within(dem: Dem, opts: &ReadOptions) -> Result<Dem, ReadErrorKind> {
    let limit = opts.max_abs_height_m.min(crate::dem::MAX_ABS_HEIGHT_M);
    let g = &dem.grid;
    let beyond = g
        .heights()
        .iter()
        .position(|h| f64::from(h.abs()) > limit && !h.is_nan());
    match beyond {
        None => Ok(dem),
        Some(i) => Err(ReadErrorKind::AbsurdHeight {
            found_m: f64::from(g.heights()[i]),
            col: i % g.width().max(1),
            row: i / g.width().max(1),
            limit_m: limit,
            hint: match dem.format {
                crate::Format::Png(crate::PngEncoding::Gray16) => {
                    "a 16-bit gray PNG's levels are metres unless --gray-scale-m says otherwise; \
                     give its metres per level"
                }
                _ => "convert the file or declare its nodata",
            },
        }),
    }
}

/// Largest expansion of DEFLATE, used to refuse gzip bombs early.
const MAX_GZIP_RATIO: u64 = 1032;

/// Bytes decompressed before the content is sniffed to choose the cap.
const GZIP_SNIFF_BYTES: u64 = 1 << 16;

/// Decompresses a gzip file (one level) and decodes its content under the
/// name without `.gz`. Decompression stops as soon as the output exceeds what
/// the content may be ([`crate::limits`]): a `.hgt` (by name, or content
/// without magic) one 3601² tile unless the limit is set, anything else 8
/// bytes per sample of the limit; and never more than DEFLATE's largest ratio.
fn gunzip_and_decode(bytes: &[u8], path: &Path, opts: &ReadOptions) -> Result<Dem, ReadErrorKind> {
    use std::io::Read;
    let name = match path.extension() {
        Some(e) if e.eq_ignore_ascii_case("gz") => path.with_extension(""),
        _ => path.to_path_buf(),
    };
    let broken = |e: std::io::Error| {
        crate::error::malformed("a complete gzip stream", format!("a broken one ({e})"))
    };
    let mut decoder = flate2::read::GzDecoder::new(bytes);
    let mut inner = Vec::new();
    (&mut decoder)
        .take(GZIP_SNIFF_BYTES)
        .read_to_end(&mut inner)
        .map_err(broken)?;
    let named_hgt = name
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("hgt"));
    let hgt = named_hgt || sniff(&inner) == Sniffed::Unknown;
    let cap = crate::limits::gzip_cap(hgt, opts).min(bytes.len() as u64 * MAX_GZIP_RATIO);
    let rest = (cap + 1).saturating_sub(inner.len() as u64);
    decoder.take(rest).read_to_end(&mut inner).map_err(broken)?;
    if inner.len() as u64 > cap {
        return Err(ReadErrorKind::Expands {
            what: format!(
                "the gzip stream (holding {})",
                if hgt { "a .hgt" } else { "a DEM" }
            ),
            limit: cap,
        });
    }
    if inner.is_empty() {
        return Err(crate::error::malformed(
            "a DEM inside the gzip stream",
            "nothing",
        ));
    }
    if sniff(&inner) == Sniffed::Gzip {
        return Err(ReadErrorKind::Unsupported {
            what: "gzip nesting".into(),
            detail: "a gzip stream inside a gzip stream; decompress the outer one first".into(),
        });
    }
    let mut dem = decode_bytes(&inner, &name, opts)?;
    dem.path = path.to_path_buf();
    Ok(dem)
}

/// Reads `paths` (in parallel), joins them into one grid by their
/// georeference and fills its voids, as `opts` says. One path gives that
/// file's grid (no copy); the files may be in any format [`read_dem`] reads.
///
/// ```
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use cota_io::{read_region, RegionOptions};
/// let tile = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/S29W072.hgt.zip");
/// let region = read_region(&[tile], &RegionOptions::DEFAULT)?;
/// assert_eq!((region.grid.width(), region.grid.height()), (1201, 1201));
/// assert_eq!(region.grid.void_count(), 0);
/// assert_eq!(region.fill.map(|f| f.filled), Some(region.voids));
/// # Ok(())
/// # }
/// ```
///
/// # Errors
/// [`RegionError::Read`] for the first file (in input order) that cannot be
/// read, else as [`join`].
///
/// # Memory
/// The files are read on rayon's pool, each by one thread, and every tile is
/// held until the mosaic places it; the mosaic then drops each tile as it is
/// copied. So the peak is about the output grid plus, per reading thread, the
/// one file it is decoding (its bytes and the decoder's scratch, at most
/// about one tile), where a sequential read needed the output plus about one
/// tile.
pub fn read_region<P: AsRef<Path> + Sync>(
    paths: &[P],
    opts: &RegionOptions,
) -> Result<Region, RegionError> {
    read_region_with_progress(paths, opts, &|_, _| {})
}

/// [`read_region`] reading the files one after the other on the calling
/// thread: slower, but every tile is allocated by one thread, so a process
/// that reads several regions in turn (the plan step of sharded tiling)
/// reuses the memory of the last one instead of leaving it in the reading
/// threads' allocator arenas.
///
/// # Errors
/// As [`read_region`].
pub fn read_region_in_turn<P: AsRef<Path>>(
    paths: &[P],
    opts: &RegionOptions,
) -> Result<Region, RegionError> {
    if paths.is_empty() {
        return Err(RegionError::NoFiles);
    }
    let dems = paths
        .iter()
        .map(|p| read_dem(p.as_ref(), &opts.read))
        .collect::<Result<Vec<Dem>, ReadError>>()?;
    join(dems, opts)
}

/// [`read_region`], calling `progress(bytes_read, bytes)` as the files are
/// read (from the reading threads; `bytes` the files' sizes).
///
/// # Errors
/// As [`read_region`].
pub fn read_region_with_progress<P: AsRef<Path> + Sync>(
    paths: &[P],
    opts: &RegionOptions,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<Region, RegionError> {
    if paths.is_empty() {
        return Err(RegionError::NoFiles);
    }
    let dems = read_dems_with_progress(paths, &opts.read, progress)?;
    join(dems, opts)
}

/// Reads each file on rayon's pool (one file per task), calling
/// `progress(bytes_read, bytes)` as their bytes arrive (`bytes`: the files'
/// sizes; `(bytes, bytes)` at the end, whatever was read): the
/// files [`read_region_with_progress`] joins, for a caller that looks at
/// each (sets its CRS, say: [`crate::crs::assign_src_crs`]) before [`join`].
///
/// # Errors
/// The [`ReadError`] of the first file (in input order) that cannot be read.
pub fn read_dems_with_progress<P: AsRef<Path> + Sync>(
    paths: &[P],
    opts: &ReadOptions,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<Vec<Dem>, ReadError> {
    read_dems_counted(paths, opts, false, progress)
}

/// [`read_dems_with_progress`], the files read in parallel or (`in_turn`)
/// one after the other on the calling thread (see [`read_region_in_turn`]).
///
/// # Errors
/// As [`read_dems_with_progress`].
pub fn read_dems_counted<P: AsRef<Path> + Sync>(
    paths: &[P],
    opts: &ReadOptions,
    in_turn: bool,
    progress: &(dyn Fn(u64, u64) + Sync),
) -> Result<Vec<Dem>, ReadError> {
    use std::sync::atomic::{AtomicU64, Ordering};
    let size = |p: &P| std::fs::metadata(p.as_ref()).map_or(0, |m| m.len());
    let total: u64 = paths.iter().map(size).sum();
    let done = AtomicU64::new(0);
    progress(0, total);
    let counted = |n: u64| {
        let d = done.fetch_add(n, Ordering::Relaxed) + n;
        progress(d.min(total), total);
    };
    let one = |p: &P| read_dem_counted(p.as_ref(), opts, &counted);
    let read: Vec<Result<Dem, ReadError>> = if in_turn {
        paths.iter().map(one).collect()
    } else {
        paths.par_iter().with_max_len(1).map(one).collect()
    };
    progress(total, total);
    read.into_iter().collect()
}
