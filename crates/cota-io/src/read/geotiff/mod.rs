//! GeoTIFF reader, on the pure-Rust `tiff` crate (no GDAL).
//!
//! The first image directory (IFD) of the file is read as one band of heights:
//! * Layouts: strips (StripOffsets 273, RowsPerStrip 278, StripByteCounts 279)
//!   and tiles (TileWidth 322, TileLength 323, TileOffsets 324, TileByteCounts
//!   325); chunky or planar samples (PlanarConfiguration 284 = 1 or 2). A chunk
//!   with a byte count of 0 is sparse (as GDAL writes): void when a nodata value
//!   is declared, else 0.
//! * Compression 259: none (1), LZW (5), Deflate (8 and the old 32946), PackBits
//!   (32773); anything else (JPEG 6/7, JPEG 2000, LERC, ZSTD, ...) is refused by
//!   code and name. Predictor 317: horizontal (2) and floating-point (3), both
//!   undone by the `tiff` crate.
//! * Samples: BitsPerSample 258 × SampleFormat 339 (1 uint, 2 int, 3 float)
//!   giving i8, u8, i16, u16, i32, u32, f32, f64, converted to f32 metres.
//! * Bands: SamplesPerPixel 277 > 1 needs [`ReadOptions::band`] (1-based).
//! * Georeference and CRS from the GeoTIFF tags and GeoKeys, see [`geokeys`];
//!   VerticalUnitsGeoKey 4099 in feet scales heights to metres. Grids stored
//!   south-up or east-to-west are flipped so that row 0 is north.
//! * Voids: the GDAL_NODATA tag 42113 (ASCII) compared in the sample's own type,
//!   see [`nodata`]; NaN float samples are always voids.
//!
//! Before anything large is allocated the header's dimensions are checked
//! against [`MAX_SAMPLES`], and every chunk to be decoded must lie
//! inside the file and be able to expand to its decoded size at the
//! compression's largest possible ratio; so a small or truncated file cannot
//! make the reader allocate gigabytes.

mod geokeys;
mod nodata;
mod projection;

use std::io::{self, Cursor};
use std::path::Path;

use cota_core::grid::{check_dimensions, MAX_SAMPLES};
use cota_core::{GridError, HeightGrid};
use tiff::decoder::ifd::Value;
use tiff::decoder::{ChunkType, Decoder, DecodingResult, Limits};
use tiff::tags::Tag;
use tiff::TiffError;

use self::geokeys::GeoTags;
use self::nodata::Sample;
use crate::dem::{DataType, Dem, Format, ReadOptions};
use crate::error::{malformed, ReadErrorKind};

/// The decoder over the file's bytes.
type Dec<'a> = Decoder<Cursor<&'a [u8]>>;

/// Compressions read, for messages.
const SUPPORTED_COMPRESSIONS: &str = "none (1), LZW (5), Deflate (8, 32946), PackBits (32773)";

/// Decodes the content of one GeoTIFF. `path` supplies the name.
pub(crate) fn decode(bytes: &[u8], path: &Path, opts: &ReadOptions) -> Result<Dem, ReadErrorKind> {
    check_first_directory(bytes)?;
    let mut dec = Decoder::new(Cursor::new(bytes))
        .map_err(|e| tiff_error(e, "reading the TIFF header and first image directory"))?;
    let layout = Layout::read(&mut dec)?;
    crate::limits::check(layout.width as u64, layout.height as u64, opts)?;
    let band = select_band(layout.samples, opts.band)?;
    let nodata = read_nodata(&mut dec)?;
    let geo = geokeys::geo_info(&read_geo_tags(&mut dec)?)?;
    let plan = layout.plan(band, bytes.len() as u64)?;
    let mut dec = dec.with_limits(chunk_limits());
    let mut heights = alloc_heights(layout.width, layout.height)?;
    for chunk in &plan {
        read_chunk(&mut dec, &layout, chunk, nodata, &mut heights)?;
    }
    scale_heights(&mut heights, geo.vertical_to_m);
    let mut georef = geo.georef;
    super::orient::north_up(&mut heights, layout.width, layout.height, &mut georef);
    let grid = HeightGrid::new(layout.width, layout.height, heights, georef)?;
    Ok(Dem {
        grid,
        format: Format::GeoTiff,
        data_type: layout.data_type,
        nodata: nodata.map(|v| nodata::effective_nodata(layout.data_type, v)),
        path: path.to_path_buf(),
    })
}

/// The number of bands (SamplesPerPixel 277) of the first image of a TIFF,
/// for the imagery reader (`crate::image`), which then reads each band it
/// needs with [`decode`].
pub(crate) fn band_count(bytes: &[u8]) -> Result<u16, ReadErrorKind> {
    check_first_directory(bytes)?;
    let mut dec = Decoder::new(Cursor::new(bytes))
        .map_err(|e| tiff_error(e, "reading the TIFF header and first image directory"))?;
    Ok(Layout::read(&mut dec)?.samples)
}

/// Checks that the first image directory (IFD) lies inside the file, so that
/// truncated and garbage files get a message with the numbers. Classic TIFF:
/// offset u32 at byte 4, then a u16 entry count, 12 bytes per entry and a u32
/// next-IFD offset. BigTIFF (version 43): offset u64 at byte 8, then a u64
/// count, 20 bytes per entry and a u64 next offset.
fn check_first_directory(bytes: &[u8]) -> Result<(), ReadErrorKind> {
    let le = bytes.starts_with(b"II");
    let uint = |at: usize, n: usize| -> Option<u64> {
        let b = bytes.get(at..at.checked_add(n)?)?;
        let fold = |acc: u64, x: &u8| (acc << 8) | u64::from(*x);
        Some(if le {
            b.iter().rev().fold(0, fold)
        } else {
            b.iter().fold(0, fold)
        })
    };
    let len = bytes.len() as u64;
    let big = uint(2, 2) == Some(43);
    let (offset_at, offset_len, count_len, entry_len) =
        if big { (8, 8, 8, 20) } else { (4, 4, 2, 12) };
    let Some(offset) = uint(offset_at, offset_len) else {
        return Err(malformed(
            format!("a TIFF header of {} bytes", offset_at + offset_len),
            format!("{len} bytes"),
        ));
    };
    if offset == 0 {
        return Err(malformed("the offset of a first image directory", "0"));
    }
    let Some(count) = usize::try_from(offset)
        .ok()
        .and_then(|o| uint(o, count_len))
    else {
        return Err(malformed(
            format!("the first image directory at byte {offset}"),
            format!("a file of {len} bytes (truncated?)"),
        ));
    };
    let size = count
        .saturating_mul(entry_len)
        .saturating_add((count_len + offset_len) as u64);
    if offset.saturating_add(size) > len {
        return Err(malformed(
            format!("an image directory of {count} entries ({size} bytes) at byte {offset}"),
            format!("a file of {len} bytes (truncated?)"),
        ));
    }
    Ok(())
}

/// Turns a `tiff` crate error into a reader error saying what was being done.
fn tiff_error(err: TiffError, context: &str) -> ReadErrorKind {
    match err {
        TiffError::IoError(e) if e.kind() == io::ErrorKind::UnexpectedEof => malformed(
            format!("more data while {context}"),
            format!("the data ends early ({e})"),
        ),
        TiffError::IoError(e) => malformed(format!("valid data while {context}"), e),
        TiffError::UnsupportedError(e) => ReadErrorKind::Unsupported {
            what: "TIFF feature".into(),
            detail: format!("{e} (while {context})"),
        },
        TiffError::FormatError(e) => malformed(format!("a well-formed TIFF while {context}"), e),
        other => malformed(format!("sizes within limits while {context}"), other),
    }
}

/// Reads a tag, naming it in errors.
fn find_tag(dec: &mut Dec<'_>, tag: Tag, name: &str) -> Result<Option<Value>, ReadErrorKind> {
    dec.find_tag(tag)
        .map_err(|e| tiff_error(e, &format!("reading {name}")))
}

/// Reads a numeric tag as f64s; a non-numeric value is malformed.
fn find_numbers(
    dec: &mut Dec<'_>,
    tag: Tag,
    name: &str,
) -> Result<Option<Vec<f64>>, ReadErrorKind> {
    match find_tag(dec, tag, name)? {
        None => Ok(None),
        Some(v) => geokeys::numbers(v)
            .map(Some)
            .ok_or_else(|| malformed(format!("numbers in {name}"), "another value type")),
    }
}

/// Reads an unsigned integer tag that holds one value per sample (or one for all).
fn find_per_sample(
    dec: &mut Dec<'_>,
    tag: Tag,
    name: &str,
) -> Result<Option<Vec<u16>>, ReadErrorKind> {
    match find_tag(dec, tag, name)? {
        None => Ok(None),
        Some(v) => geokeys::shorts(v)
            .filter(|v| !v.is_empty())
            .map(Some)
            .ok_or_else(|| malformed(format!("SHORT values in {name}"), "another value type")),
    }
}

/// The sample layout of the image, from its tags.
#[derive(Debug, Clone)]
struct Layout {
    width: usize,
    height: usize,
    /// SamplesPerPixel.
    samples: u16,
    /// PlanarConfiguration 2.
    planar: bool,
    data_type: DataType,
    bytes_per_sample: u64,
    compression: u16,
    tiled: bool,
    /// Tile size, or (width, RowsPerStrip) for strips.
    chunk_width: u64,
    chunk_height: u64,
    offsets: Vec<u64>,
    byte_counts: Vec<u64>,
    /// Samples per pixel in a decoded chunk (1 for planar).
    decoded_samples: u16,
}

/// One chunk of the selected band: where it is in the file and in the grid.
#[derive(Debug, Clone, Copy)]
struct ChunkPlan {
    /// Index among all chunks of the image (the tiff crate's index).
    index: u32,
    /// Position among the band's chunks, and their count, for messages.
    ordinal: usize,
    count: usize,
    x0: usize,
    y0: usize,
    /// Size of the chunk's data inside the image.
    width: usize,
    height: usize,
    /// Sparse chunk (no bytes in the file).
    sparse: bool,
    /// Which of the decoded chunk's interleaved samples is the band.
    pick: u16,
}

impl Layout {
    fn read(dec: &mut Dec<'_>) -> Result<Layout, ReadErrorKind> {
        let (w, h) = dec
            .dimensions()
            .map_err(|e| tiff_error(e, "reading the image size"))?;
        check_size(u64::from(w), u64::from(h))?;
        let compression = match find_tag(dec, Tag::Compression, "Compression (259)")? {
            Some(v) => geokeys::shorts(v)
                .and_then(|c| c.first().copied())
                .unwrap_or(0),
            None => 1,
        };
        check_compression(compression)?;
        let bits = find_per_sample(dec, Tag::BitsPerSample, "BitsPerSample (258)")?
            .unwrap_or_else(|| vec![1]);
        let formats = find_per_sample(dec, Tag::SampleFormat, "SampleFormat (339)")?
            .unwrap_or_else(|| vec![1]);
        let data_type = data_type(&formats, &bits)?;
        let samples = find_per_sample(dec, Tag::SamplesPerPixel, "SamplesPerPixel (277)")?
            .and_then(|s| s.first().copied())
            .unwrap_or(1);
        let planar = find_per_sample(dec, Tag::PlanarConfiguration, "PlanarConfiguration (284)")?
            .is_some_and(|p| p.first() == Some(&2));
        let tiled = dec.get_chunk_type() == ChunkType::Tile;
        let (offsets, byte_counts) = chunk_locations(dec, tiled)?;
        let (chunk_width, chunk_height) = dec.chunk_dimensions();
        let decoded_samples = if planar {
            1
        } else {
            dec.colortype()
                .map_err(|e| tiff_error(e, "reading the photometric interpretation"))?
                .num_samples()
        };
        Ok(Layout {
            width: w as usize,
            height: h as usize,
            samples,
            planar,
            data_type,
            bytes_per_sample: u64::from(bits.first().copied().unwrap_or(8) / 8),
            compression,
            tiled,
            chunk_width: u64::from(chunk_width),
            // RowsPerStrip may exceed the height (2^32-1 means one strip);
            // tiles keep their padded size.
            chunk_height: if tiled {
                u64::from(chunk_height)
            } else {
                u64::from(chunk_height).min(u64::from(h))
            },
            offsets,
            byte_counts,
            decoded_samples,
        })
    }

    fn chunk_kind(&self) -> &'static str {
        if self.tiled {
            "tile"
        } else {
            "strip"
        }
    }

    /// Plans the chunks of `band` (0-based) and checks each against the file:
    /// inside it, and not claiming more decoded bytes than its compressed bytes
    /// can give.
    fn plan(&self, band: u16, file_len: u64) -> Result<Vec<ChunkPlan>, ReadErrorKind> {
        if !self.planar && band >= self.decoded_samples {
            return Err(ReadErrorKind::Unsupported {
                what: "TIFF band".into(),
                detail: format!(
                    "band {} is an extra sample of the photometric interpretation that the TIFF decoder drops ({} of {} samples are read)",
                    band + 1,
                    self.decoded_samples,
                    self.samples
                ),
            });
        }
        if self.chunk_width.saturating_mul(self.chunk_height) > MAX_SAMPLES {
            return Err(malformed(
                format!("a {} of at most {MAX_SAMPLES} samples", self.chunk_kind()),
                format!("{}x{}", self.chunk_width, self.chunk_height),
            ));
        }
        let (cw, ch) = (self.chunk_width as usize, self.chunk_height as usize);
        if cw == 0 || ch == 0 {
            return Err(malformed(
                format!("a non-empty {} size", self.chunk_kind()),
                format!("{cw}x{ch}"),
            ));
        }
        let across = self.width.div_ceil(cw);
        let down = self.height.div_ceil(ch);
        let count = across * down;
        let first = if self.planar {
            usize::from(band) * count
        } else {
            0
        };
        let mut plan = Vec::with_capacity(count);
        for ordinal in 0..count {
            let (x0, y0) = ((ordinal % across) * cw, (ordinal / across) * ch);
            let index = first + ordinal;
            let chunk = ChunkPlan {
                index: u32::try_from(index)
                    .map_err(|_| malformed("fewer than 2^32 chunks", format!("chunk {index}")))?,
                ordinal,
                count,
                x0,
                y0,
                width: cw.min(self.width - x0),
                height: ch.min(self.height - y0),
                sparse: self.byte_counts.get(index) == Some(&0),
                pick: if self.planar { 0 } else { band },
            };
            self.check_chunk(&chunk, file_len)?;
            plan.push(chunk);
        }
        check_sparse(&plan, file_len)?;
        Ok(plan)
    }

    /// Bytes the chunk decodes to: a whole tile (tiles are padded), or the
    /// strip's rows.
    fn decoded_bytes(&self, chunk: &ChunkPlan) -> u64 {
        let samples = if self.planar {
            1
        } else {
            u64::from(self.samples)
        };
        let (w, h) = if self.tiled {
            (self.chunk_width, self.chunk_height)
        } else {
            (self.width as u64, chunk.height as u64)
        };
        w.saturating_mul(h)
            .saturating_mul(samples)
            .saturating_mul(self.bytes_per_sample)
    }

    fn check_chunk(&self, chunk: &ChunkPlan, file_len: u64) -> Result<(), ReadErrorKind> {
        let what = format!(
            "{} {} of {}",
            self.chunk_kind(),
            chunk.ordinal + 1,
            chunk.count
        );
        let (Some(&offset), Some(&len)) = (
            self.offsets.get(chunk.index as usize),
            self.byte_counts.get(chunk.index as usize),
        ) else {
            return Err(malformed(
                format!("an offset and byte count for {what}"),
                format!(
                    "{} offsets and {} byte counts",
                    self.offsets.len(),
                    self.byte_counts.len()
                ),
            ));
        };
        if chunk.sparse {
            return Ok(());
        }
        let end = offset.saturating_add(len);
        if end > file_len {
            return Err(malformed(
                format!("{what} at bytes {offset}..{end} of the file"),
                format!("a file of {file_len} bytes (truncated?)"),
            ));
        }
        let needed = self.decoded_bytes(chunk);
        if needed > max_decoded(self.compression, len) {
            let found = if self.compression == 1 {
                format!("{len} bytes")
            } else {
                format!(
                    "{len} bytes of {} data, which cannot expand that far",
                    compression_name(self.compression)
                )
            };
            return Err(malformed(
                format!("{needed} bytes of samples in {what}"),
                found,
            ));
        }
        Ok(())
    }
}

/// Samples sparse chunks may hold whatever the file's size.
const FREE_SPARSE_SAMPLES: u64 = 1 << 24;

/// Samples sparse chunks may hold per byte of file beyond
/// [`FREE_SPARSE_SAMPLES`]: a GDAL file with empty blocks holds its data
/// somewhere, at most 1,024 samples per byte as a Deflate bomb would.
const SPARSE_SAMPLES_PER_BYTE: u64 = 1024;

/// Refuses sparse chunks (byte count 0) that make a small file a grid of
/// voids of any size: 292 bytes declaring 16 391 × 64 258 samples, all in
/// one empty strip, made the reader allocate and fill 4 GB (found by the
/// fuzzer).
fn check_sparse(plan: &[ChunkPlan], file_len: u64) -> Result<(), ReadErrorKind> {
    let sparse: u64 = plan
        .iter()
        .filter(|c| c.sparse)
        .map(|c| c.width as u64 * c.height as u64)
        .sum();
    let allowed = FREE_SPARSE_SAMPLES.max(SPARSE_SAMPLES_PER_BYTE.saturating_mul(file_len));
    if sparse <= allowed {
        return Ok(());
    }
    Err(malformed(
        format!(
            "at most {allowed} samples in empty (sparse) blocks of a file of {file_len} bytes ({SPARSE_SAMPLES_PER_BYTE} per byte, {FREE_SPARSE_SAMPLES} at least)"
        ),
        format!("{sparse} samples in blocks with a byte count of 0: a decompression bomb"),
    ))
}

/// Fails with [`ReadErrorKind::TooLarge`] for dimensions over the grid limit.
fn check_size(width: u64, height: u64) -> Result<(), ReadErrorKind> {
    check_dimensions(width, height).map_err(|e| match e {
        GridError::TooLarge { width, height, max } => {
            ReadErrorKind::TooLarge { width, height, max }
        }
        other => ReadErrorKind::Grid(other),
    })
}

/// The most bytes `len` compressed bytes can decode to, with a little slack.
fn max_decoded(compression: u16, len: u64) -> u64 {
    let ratio = match compression {
        1 => return len,
        // A PackBits run of 2 bytes gives at most 128.
        32773 => 64,
        // Deflate's limit is about 1032:1.
        8 | 32946 => 1040,
        // An LZW code of 9..12 bits gives at most 4096 bytes.
        _ => 4096,
    };
    len.saturating_mul(ratio).saturating_add(1024)
}

/// Accepts the compressions the reader decodes.
fn check_compression(code: u16) -> Result<(), ReadErrorKind> {
    match code {
        1 | 5 | 8 | 32946 | 32773 => Ok(()),
        _ => Err(ReadErrorKind::Unsupported {
            what: "GeoTIFF compression".into(),
            detail: format!(
                "code {code} ({}); supported: {SUPPORTED_COMPRESSIONS}",
                compression_name(code)
            ),
        }),
    }
}

/// The usual name of a TIFF compression code.
fn compression_name(code: u16) -> &'static str {
    match code {
        1 => "none",
        2 => "CCITT RLE",
        3 => "CCITT Group 3 fax",
        4 => "CCITT Group 4 fax",
        5 => "LZW",
        6 => "old-style JPEG",
        7 => "JPEG",
        8 | 32946 => "Deflate",
        32773 => "PackBits",
        34661 => "JBIG",
        34712 => "JPEG 2000",
        34887 => "LERC",
        34925 => "LZMA",
        50000 => "ZSTD",
        50001 => "WebP",
        52546 => "JPEG XL",
        _ => "unknown",
    }
}

/// The sample type from SampleFormat and BitsPerSample (uniform over samples).
fn data_type(formats: &[u16], bits: &[u16]) -> Result<DataType, ReadErrorKind> {
    let format = formats.first().copied().unwrap_or(1);
    let depth = bits.first().copied().unwrap_or(1);
    let uniform = formats.iter().all(|&f| f == format) && bits.iter().all(|&b| b == depth);
    let found = match (format, depth) {
        _ if !uniform => None,
        (1, 8) => Some(DataType::U8),
        (2, 8) => Some(DataType::I8),
        (1, 16) => Some(DataType::U16),
        (2, 16) => Some(DataType::I16),
        (1, 32) => Some(DataType::U32),
        (2, 32) => Some(DataType::I32),
        (3, 32) => Some(DataType::F32),
        (3, 64) => Some(DataType::F64),
        _ => None,
    };
    found.ok_or_else(|| ReadErrorKind::Unsupported {
        what: "GeoTIFF sample type".into(),
        detail: format!(
            "SampleFormat {formats:?} with BitsPerSample {bits:?}; supported: 8/16/32-bit signed (2) or unsigned (1) integers, 32/64-bit floats (3)"
        ),
    })
}

/// Offsets and byte counts of all chunks.
fn chunk_locations(dec: &mut Dec<'_>, tiled: bool) -> Result<(Vec<u64>, Vec<u64>), ReadErrorKind> {
    let (off_tag, count_tag, names) = if tiled {
        (
            Tag::TileOffsets,
            Tag::TileByteCounts,
            ("TileOffsets (324)", "TileByteCounts (325)"),
        )
    } else {
        (
            Tag::StripOffsets,
            Tag::StripByteCounts,
            ("StripOffsets (273)", "StripByteCounts (279)"),
        )
    };
    let mut get = |tag, name: &str| -> Result<Vec<u64>, ReadErrorKind> {
        find_tag(dec, tag, name)?
            .ok_or_else(|| malformed(format!("a {name} tag"), "none"))?
            .into_u64_vec()
            .map_err(|e| tiff_error(e, &format!("reading {name}")))
    };
    Ok((get(off_tag, names.0)?, get(count_tag, names.1)?))
}

/// The 0-based band to read.
fn select_band(samples: u16, band: Option<u16>) -> Result<u16, ReadErrorKind> {
    match band {
        None if samples == 1 => Ok(0),
        None => Err(malformed(
            "a single-band DEM",
            format!("{samples} bands; choose one with --band"),
        )),
        Some(b) if (1..=samples).contains(&b) => Ok(b - 1),
        Some(b) => Err(malformed(
            format!("a band in 1..={samples}"),
            format!("band {b}"),
        )),
    }
}

/// The GDAL_NODATA value, if declared.
fn read_nodata(dec: &mut Dec<'_>) -> Result<Option<f64>, ReadErrorKind> {
    match find_tag(dec, Tag::GdalNodata, "GDAL_NODATA (42113)")? {
        None => Ok(None),
        Some(Value::Ascii(text)) => nodata::parse_nodata(&text),
        Some(_) => Err(malformed(
            "ASCII text in the GDAL_NODATA tag 42113",
            "another value type",
        )),
    }
}

/// The georeferencing tags. An unreadable GeoAsciiParams (citations only) is
/// ignored.
fn read_geo_tags(dec: &mut Dec<'_>) -> Result<GeoTags, ReadErrorKind> {
    let key_directory = match find_tag(dec, Tag::GeoKeyDirectoryTag, "GeoKeyDirectoryTag (34735)")?
    {
        None => None,
        Some(v) => Some(geokeys::shorts(v).ok_or_else(|| {
            malformed(
                "SHORT values in GeoKeyDirectoryTag 34735",
                "another value type",
            )
        })?),
    };
    let ascii_params = match dec.find_tag(Tag::GeoAsciiParamsTag) {
        Ok(Some(Value::Ascii(s))) => Some(s),
        _ => None,
    };
    // Like the ASCII params, optional: unreadable doubles only leave a
    // user-defined CRS as its description.
    let double_params = match dec.find_tag(Tag::GeoDoubleParamsTag) {
        Ok(Some(v)) => geokeys::numbers(v),
        _ => None,
    };
    Ok(GeoTags {
        scale: find_numbers(dec, Tag::ModelPixelScaleTag, "ModelPixelScaleTag (33550)")?,
        tiepoints: find_numbers(dec, Tag::ModelTiepointTag, "ModelTiepointTag (33922)")?,
        matrix: find_numbers(
            dec,
            Tag::ModelTransformationTag,
            "ModelTransformationTag (34264)",
        )?,
        key_directory,
        ascii_params,
        double_params,
    })
}

/// Limits for chunk decoding: the reader's own checks ([`Layout::plan`]) bound
/// every chunk by the file's size, so the crate's limits only need to stay
/// clear of legitimate chunks (up to a whole f64 grid of [`MAX_SAMPLES`]).
fn chunk_limits() -> Limits {
    let big = usize::try_from(MAX_SAMPLES.saturating_mul(8)).unwrap_or(usize::MAX);
    let mut limits = Limits::default();
    limits.decoding_buffer_size = big;
    limits.intermediate_buffer_size = big;
    limits
}

/// The height buffer, all void, allocated without aborting on failure.
fn alloc_heights(width: usize, height: usize) -> Result<Vec<f32>, ReadErrorKind> {
    let n = width * height; // checked against the sample limit by `decode`
    let mut v = crate::limits::try_vec(n, &format!("{width}x{height} heights"))?;
    v.resize(n, f32::NAN);
    Ok(v)
}

/// Decodes one chunk of the band into `heights`.
fn read_chunk(
    dec: &mut Dec<'_>,
    layout: &Layout,
    chunk: &ChunkPlan,
    nodata: Option<f64>,
    heights: &mut [f32],
) -> Result<(), ReadErrorKind> {
    let dst = Dst {
        heights,
        grid_width: layout.width,
        chunk,
        samples: usize::from(layout.decoded_samples.max(1)),
        band: usize::from(chunk.pick),
    };
    if chunk.sparse {
        dst.fill(if nodata.is_some() { f32::NAN } else { 0.0 });
        return Ok(());
    }
    let context = format!(
        "decoding {} {} of {} ({})",
        layout.chunk_kind(),
        chunk.ordinal + 1,
        chunk.count,
        compression_name(layout.compression)
    );
    let data = dec
        .read_chunk(chunk.index)
        .map_err(|e| tiff_error(e, &context))?;
    let nd = nodata.unwrap_or(f64::NAN);
    match data {
        DecodingResult::I8(v) => dst.place(&v, nodata.and(i8::nodata_as(nd))),
        DecodingResult::U8(v) => dst.place(&v, nodata.and(u8::nodata_as(nd))),
        DecodingResult::I16(v) => dst.place(&v, nodata.and(i16::nodata_as(nd))),
        DecodingResult::U16(v) => dst.place(&v, nodata.and(u16::nodata_as(nd))),
        DecodingResult::I32(v) => dst.place(&v, nodata.and(i32::nodata_as(nd))),
        DecodingResult::U32(v) => dst.place(&v, nodata.and(u32::nodata_as(nd))),
        DecodingResult::F32(v) => dst.place(&v, nodata.and(f32::nodata_as(nd))),
        DecodingResult::F64(v) => dst.place(&v, nodata.and(f64::nodata_as(nd))),
        _ => Err(malformed(
            format!("{} samples while {context}", layout.data_type),
            "another sample type from the decoder",
        )),
    }
}

/// Where a decoded chunk goes in the grid.
struct Dst<'a> {
    heights: &'a mut [f32],
    grid_width: usize,
    chunk: &'a ChunkPlan,
    /// Interleaved samples per pixel in the decoded chunk, and which to take.
    samples: usize,
    band: usize,
}

impl Dst<'_> {
    /// The grid row slice of chunk row `r`.
    fn row(&mut self, r: usize) -> Option<&mut [f32]> {
        let start = (self.chunk.y0 + r) * self.grid_width + self.chunk.x0;
        self.heights.get_mut(start..start + self.chunk.width)
    }

    fn fill(mut self, value: f32) {
        for r in 0..self.chunk.height {
            if let Some(row) = self.row(r) {
                row.fill(value);
            }
        }
    }

    /// Converts the decoded samples (rows of `chunk.width` pixels) into heights.
    fn place<T: Sample>(mut self, src: &[T], nodata: Option<T>) -> Result<(), ReadErrorKind> {
        let stride = self.chunk.width * self.samples;
        let needed = stride * self.chunk.height;
        if src.len() < needed {
            return Err(malformed(
                format!(
                    "{needed} decoded samples in chunk {}",
                    self.chunk.ordinal + 1
                ),
                format!("{}", src.len()),
            ));
        }
        let band = self.band;
        let samples = self.samples;
        for (r, src_row) in src.chunks(stride).take(self.chunk.height).enumerate() {
            let Some(row) = self.row(r) else {
                return Err(malformed(
                    "a chunk inside the image",
                    "one reaching outside",
                ));
            };
            let picked = src_row.iter().skip(band).step_by(samples);
            for (h, s) in row.iter_mut().zip(picked) {
                *h = s.height(nodata);
            }
        }
        Ok(())
    }
}

/// Multiplies heights by the vertical unit's size in metres.
fn scale_heights(heights: &mut [f32], to_m: f32) {
    if to_m != 1.0 {
        heights.iter_mut().for_each(|h| *h *= to_m);
    }
}
