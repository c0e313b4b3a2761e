//! PMTiles v3 archives of terrain tiles (PNG or WebP, terrain-RGB or
//! Terrarium): [`summary`] for what an archive holds, and the reader that
//! mosaics the tiles of one zoom covering a box ([`ReadOptions::tiles`]).
//!
//! # Format facts this reader relies on (PMTiles v3 specification)
//! * A 127-byte little-endian header: `PMTiles`, version 3; offsets and
//!   lengths (u64) of the root directory (8, 16), metadata (24, 32), leaf
//!   directories (40, 48) and tile data (56, 64); tile counts (72, 80, 88);
//!   clustered (96); internal compression (97) and tile compression (98)
//!   (1 none, 2 gzip, 3 brotli, 4 zstd); tile type (99: 2 PNG, 4 WebP);
//!   min and max zoom (100, 101); bounds as i32 degrees·10⁷ (102..118: west,
//!   south, east, north); centre zoom and position (118..127).
//! * A directory (compressed with the internal compression) is: the number of
//!   entries, then per column, for all entries, the tile-id deltas, the run
//!   lengths, the lengths and the offsets, all unsigned LEB128 varints. An
//!   offset of 0 after the first entry means "right after the previous
//!   entry"; any other is offset + 1. A run length of 0 points to a leaf
//!   directory (offset in the leaf section), any other to tile data covering
//!   that many consecutive tile ids.
//! * Tile ids run along zoom levels, then a Hilbert curve: id(z, x, y) =
//!   (4^z − 1)/3 + d(x, y) with d the Hilbert index on the 2^z grid.
//! * Each tile is decoded by the PNG or WebP reader under the name
//!   `ARCHIVE/z/x/y.ext`, which places it by its Web-Mercator tile bounds;
//!   the tiles are mosaicked (missing tiles are voids).
//!
//! # Bounded memory
//! Only the header, the directories on the way to the tiles asked for and
//! those tiles are read from the file, never the whole archive. Every length
//! is checked against the file's size (and decompressed directories against
//! [`MAX_DIRECTORY_BYTES`]) before it is allocated, at most [`MAX_TILES`]
//! tiles are read, and at most four directory levels are followed.

use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use cota_core::{mosaic, HeightGrid, MosaicOptions};

use super::sniff::{describe_bytes, sniff, Sniffed};
use super::tile::{tiles_covering, TileId};
use crate::dem::{DataType, Dem, Format, PngEncoding, ReadOptions};
use crate::error::{malformed, ReadError, ReadErrorKind};

/// The size of the header.
const HEADER_LEN: usize = 127;
/// The most tiles one read may take.
pub const MAX_TILES: u64 = 4096;
/// The largest directory accepted once decompressed.
pub const MAX_DIRECTORY_BYTES: u64 = 64 << 20;
/// The largest tile accepted (compressed or not).
const MAX_TILE_BYTES: u64 = 64 << 20;
/// Deepest chain of leaf directories followed.
const MAX_DEPTH: usize = 4;

/// What a PMTiles archive holds, from its header ([`summary`]).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct PmtilesSummary {
    /// The tile format: "png", "webp", or another name (which cota cannot read).
    pub tile_type: String,
    /// The smallest zoom.
    pub min_zoom: u8,
    /// The largest zoom.
    pub max_zoom: u8,
    /// West, south, east, north in degrees.
    pub bounds_deg: [f64; 4],
    /// Tiles addressed (0 when the writer did not count).
    pub addressed_tiles: u64,
    /// The tile compression: "none", "gzip", "brotli", "zstd" or "unknown".
    pub tile_compression: String,
}

/// The parsed header.
#[derive(Debug, Clone, PartialEq)]
struct Header {
    root: (u64, u64),
    leaves: (u64, u64),
    data: (u64, u64),
    addressed: u64,
    internal_compression: u8,
    tile_compression: u8,
    tile_type: u8,
    zooms: (u8, u8),
    bounds: [f64; 4],
}

/// True when the file at `path` opens with the PMTiles signature.
pub fn is_pmtiles_file(path: &Path) -> bool {
    let mut head = [0u8; 7];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut head))
        .is_ok()
        && &head == b"PMTiles"
}

/// Reads the header of the PMTiles archive at `path`.
///
/// # Errors
/// A [`ReadError`] naming `path` when it cannot be read or is no PMTiles v3 archive.
pub fn summary(path: &Path) -> Result<PmtilesSummary, ReadError> {
    let wrap = |k| ReadError::new(path, k);
    let mut f = std::fs::File::open(path).map_err(|e| wrap(ReadErrorKind::Io(e)))?;
    let h = read_header(&mut f).map_err(wrap)?;
    Ok(PmtilesSummary {
        tile_type: type_name(h.tile_type).to_string(),
        min_zoom: h.zooms.0,
        max_zoom: h.zooms.1,
        bounds_deg: h.bounds,
        addressed_tiles: h.addressed,
        tile_compression: compression_name(h.tile_compression).to_string(),
    })
}

/// The name of a tile type code.
fn type_name(t: u8) -> &'static str {
    match t {
        1 => "mvt",
        2 => "png",
        3 => "jpeg",
        4 => "webp",
        5 => "avif",
        _ => "unknown",
    }
}

/// The name of a compression code.
fn compression_name(c: u8) -> &'static str {
    match c {
        1 => "none",
        2 => "gzip",
        3 => "brotli",
        4 => "zstd",
        _ => "unknown",
    }
}

/// Reads and checks the header.
fn read_header<R: Read + Seek>(r: &mut R) -> Result<Header, ReadErrorKind> {
    let mut b = [0u8; HEADER_LEN];
    r.seek(SeekFrom::Start(0))?;
    r.read_exact(&mut b)
        .map_err(|_| malformed("a PMTiles header of 127 bytes", "a shorter file"))?;
    if &b[..7] != b"PMTiles" || b[7] != 3 {
        return Err(ReadErrorKind::Unsupported {
            what: "PMTiles version".into(),
            detail: format!("{}; cota reads version 3", b[7]),
        });
    }
    let u = |at: usize| u64::from_le_bytes(b[at..at + 8].try_into().unwrap_or([0; 8]));
    let deg = |at: usize| {
        f64::from(i32::from_le_bytes(
            b[at..at + 4].try_into().unwrap_or([0; 4]),
        )) / 1e7
    };
    Ok(Header {
        root: (u(8), u(16)),
        leaves: (u(40), u(48)),
        data: (u(56), u(64)),
        addressed: u(72),
        internal_compression: b[97],
        tile_compression: b[98],
        tile_type: b[99],
        zooms: (b[100], b[101]),
        bounds: [deg(102), deg(106), deg(110), deg(114)],
    })
}

/// Reads the tiles [`ReadOptions::tiles`] asks for and mosaics them.
pub(crate) fn decode<R: Read + Seek>(
    r: &mut R,
    path: &Path,
    opts: &ReadOptions,
) -> Result<Dem, ReadErrorKind> {
    let h = read_header(r)?;
    let file_len = r.seek(SeekFrom::End(0))?;
    let ext = match h.tile_type {
        2 => "png",
        4 => "webp",
        t => {
            return Err(ReadErrorKind::Unsupported {
                what: "PMTiles tile type".into(),
                detail: format!("{}; cota reads png and webp terrain tiles", type_name(t)),
            })
        }
    };
    let req = opts.tiles.ok_or_else(|| ReadErrorKind::Unsupported {
        what: "reading a whole PMTiles archive".into(),
        detail: format!(
            "choose the tiles with --input-zoom Z --bbox W,S,E,N (zooms {}..{}, bounds {:?})",
            h.zooms.0, h.zooms.1, h.bounds
        ),
    })?;
    let tiles = requested_tiles(&h, req.zoom, req.bbox_deg)?;
    let mut reader = ArchiveReader { r, h: &h, file_len };
    let mut grids: Vec<HeightGrid> = Vec::new();
    let mut encoding = None;
    for t in tiles {
        let Some(bytes) = reader.tile(t)? else {
            continue;
        };
        let name = path.join(format!("{}/{}/{}.{ext}", t.z, t.x, t.y));
        let dem = decode_tile(&bytes, &name, opts)
            .map_err(|k| malformed(format!("a readable tile {}/{}/{}", t.z, t.x, t.y), k))?;
        if let Format::Png(e) | Format::WebP(e) = dem.format {
            encoding.get_or_insert(e);
        }
        grids.push(dem.grid);
    }
    finish(grids, encoding, path, req.zoom)
}

/// Decodes one tile (PNG or WebP, by content) under its `z/x/y` name.
fn decode_tile(bytes: &[u8], name: &Path, opts: &ReadOptions) -> Result<Dem, ReadErrorKind> {
    match sniff(bytes) {
        Sniffed::Png => super::png::decode(bytes, name, opts),
        Sniffed::WebP => super::webp::decode(bytes, name, opts),
        _ => Err(malformed("a PNG or WebP tile", describe_bytes(bytes))),
    }
}

/// The mosaic of the tiles read.
fn finish(
    grids: Vec<HeightGrid>,
    encoding: Option<PngEncoding>,
    path: &Path,
    zoom: u8,
) -> Result<Dem, ReadErrorKind> {
    if grids.is_empty() {
        return Err(malformed(
            format!("at least one tile of zoom {zoom} in the box"),
            "none in the archive",
        ));
    }
    let opts = MosaicOptions::DEFAULT.with_max_hole_fraction(1.0);
    let m = mosaic(grids, &opts).map_err(|e| malformed("tiles that mosaic", e))?;
    Ok(Dem {
        grid: m.grid,
        format: Format::Pmtiles(encoding.unwrap_or(PngEncoding::Terrarium)),
        data_type: DataType::Rgb8,
        nodata: None,
        path: PathBuf::from(path),
    })
}

/// The tiles of `zoom` covering `bbox`, checked against the archive and [`MAX_TILES`].
fn requested_tiles(h: &Header, zoom: u8, bbox: [f64; 4]) -> Result<Vec<TileId>, ReadErrorKind> {
    if zoom < h.zooms.0 || zoom > h.zooms.1 || zoom > super::tile::MAX_ZOOM {
        return Err(malformed(
            format!(
                "--input-zoom within the archive's zooms {}..{}",
                h.zooms.0, h.zooms.1
            ),
            zoom,
        ));
    }
    let [w, s, e, n] = bbox;
    let ok = w < e && s < n && w >= -180.0 && e <= 180.0 && s >= -90.0 && n <= 90.0;
    if !ok {
        return Err(malformed(
            "--bbox W,S,E,N in degrees with W < E and S < N",
            format!("{bbox:?}"),
        ));
    }
    let (x0, x1, y0, y1) = tiles_covering(zoom, bbox);
    let count = u64::from(x1 - x0 + 1) * u64::from(y1 - y0 + 1);
    if count > MAX_TILES {
        return Err(malformed(
            format!("a box of at most {MAX_TILES} tiles at zoom {zoom}"),
            format!("{count} tiles"),
        ));
    }
    Ok((y0..=y1)
        .flat_map(|y| (x0..=x1).filter_map(move |x| TileId::new(zoom, x, y)))
        .collect())
}

/// The Hilbert tile id of a tile.
pub(crate) fn tile_id(t: TileId) -> u64 {
    let z = u32::from(t.z);
    let acc = ((1u64 << (2 * z)) - 1) / 3;
    let n = 1u64 << z;
    let (mut x, mut y) = (u64::from(t.x), u64::from(t.y));
    let mut d = 0u64;
    let mut s = n / 2;
    while s > 0 {
        let rx = u64::from(x & s > 0);
        let ry = u64::from(y & s > 0);
        d += s * s * ((3 * rx) ^ ry);
        if ry == 0 {
            if rx == 1 {
                x = n - 1 - x;
                y = n - 1 - y;
            }
            std::mem::swap(&mut x, &mut y);
        }
        s /= 2;
    }
    acc + d
}

/// One directory entry.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Entry {
    tile_id: u64,
    offset: u64,
    length: u64,
    run_length: u64,
}

/// Reads directories and tiles from an open archive.
struct ArchiveReader<'a, R> {
    r: &'a mut R,
    h: &'a Header,
    file_len: u64,
}

impl<R: Read + Seek> ArchiveReader<'_, R> {
    /// `len` bytes at `offset` (of `section`, named in errors), within the file.
    fn bytes(&mut self, offset: u64, len: u64, section: &str) -> Result<Vec<u8>, ReadErrorKind> {
        let end = offset.checked_add(len).filter(|e| *e <= self.file_len);
        if end.is_none() || len > MAX_DIRECTORY_BYTES.max(MAX_TILE_BYTES) {
            return Err(malformed(
                format!("{section} inside the file of {} bytes", self.file_len),
                format!("{len} bytes at offset {offset}"),
            ));
        }
        self.r.seek(SeekFrom::Start(offset))?;
        let mut out = vec![0u8; len as usize];
        self.r.read_exact(&mut out)?;
        Ok(out)
    }

    /// The directory at `offset`, `len` (absolute), decompressed and parsed.
    fn directory(&mut self, offset: u64, len: u64) -> Result<Vec<Entry>, ReadErrorKind> {
        let raw = self.bytes(offset, len, "a directory")?;
        let plain = decompress(
            raw,
            self.h.internal_compression,
            MAX_DIRECTORY_BYTES,
            "directory",
        )?;
        parse_directory(&plain)
    }

    /// The bytes of tile `t`, `None` when the archive lacks it.
    fn tile(&mut self, t: TileId) -> Result<Option<Vec<u8>>, ReadErrorKind> {
        let id = tile_id(t);
        let (mut off, mut len) = self.h.root;
        for _ in 0..MAX_DEPTH {
            let dir = self.directory(off, len)?;
            let Some(e) = find(&dir, id) else {
                return Ok(None);
            };
            if e.run_length > 0 {
                let start = self.h.data.0.saturating_add(e.offset);
                let raw = self.bytes(start, e.length, "a tile")?;
                let plain = decompress(raw, self.h.tile_compression, MAX_TILE_BYTES, "tile")?;
                return Ok(Some(plain));
            }
            (off, len) = (self.h.leaves.0.saturating_add(e.offset), e.length);
        }
        Err(malformed(
            format!("at most {MAX_DEPTH} directory levels"),
            "more (a directory loop?)",
        ))
    }
}

/// The entry holding tile `id` (or the leaf directory that may), if any.
fn find(dir: &[Entry], id: u64) -> Option<Entry> {
    let i = dir.partition_point(|e| e.tile_id <= id).checked_sub(1)?;
    let e = dir[i];
    (e.run_length == 0 || id < e.tile_id.saturating_add(e.run_length)).then_some(e)
}

/// Decompresses directory or tile bytes (none or gzip), at most `cap` bytes.
fn decompress(
    raw: Vec<u8>,
    compression: u8,
    cap: u64,
    what: &str,
) -> Result<Vec<u8>, ReadErrorKind> {
    match compression {
        0 | 1 => Ok(raw),
        2 => {
            let mut out = Vec::new();
            flate2::read::GzDecoder::new(raw.as_slice())
                .take(cap + 1)
                .read_to_end(&mut out)
                .map_err(|e| {
                    malformed(
                        format!("a gzip-compressed {what}"),
                        format!("a broken one ({e})"),
                    )
                })?;
            if out.len() as u64 > cap {
                return Err(malformed(
                    format!("a {what} of at most {cap} bytes"),
                    "more",
                ));
            }
            Ok(out)
        }
        c => Err(ReadErrorKind::Unsupported {
            what: format!("PMTiles {what} compression"),
            detail: format!("{}; cota reads none and gzip", compression_name(c)),
        }),
    }
}

/// Reads an unsigned LEB128 varint.
fn varint(b: &[u8], pos: &mut usize) -> Result<u64, ReadErrorKind> {
    let mut v = 0u64;
    for shift in (0..64).step_by(7) {
        let byte = *b
            .get(*pos)
            .ok_or_else(|| malformed("a complete directory", "it ends inside a number"))?;
        *pos += 1;
        v |= u64::from(byte & 0x7f) << shift;
        if byte & 0x80 == 0 {
            return Ok(v);
        }
    }
    Err(malformed(
        "a directory varint of at most 10 bytes",
        "a longer one",
    ))
}

/// Parses a decompressed directory.
fn parse_directory(b: &[u8]) -> Result<Vec<Entry>, ReadErrorKind> {
    let mut pos = 0;
    let n = varint(b, &mut pos)?;
    // Each entry takes at least 4 bytes (one per column).
    if n > b.len() as u64 / 4 {
        return Err(malformed(
            format!("a directory entry count its {} bytes can hold", b.len()),
            n,
        ));
    }
    let n = n as usize;
    let mut e = vec![
        Entry {
            tile_id: 0,
            offset: 0,
            length: 0,
            run_length: 0
        };
        n
    ];
    let mut last = 0u64;
    for x in &mut e {
        last = last
            .checked_add(varint(b, &mut pos)?)
            .ok_or_else(|| malformed("increasing tile ids", "an overflow"))?;
        x.tile_id = last;
    }
    for x in &mut e {
        x.run_length = varint(b, &mut pos)?;
    }
    for x in &mut e {
        x.length = varint(b, &mut pos)?;
    }
    for i in 0..n {
        let v = varint(b, &mut pos)?;
        // 0 means "right after the previous entry", so the first cannot be 0.
        e[i].offset = match (v, i) {
            (0, 0) => return Err(malformed("a first directory offset above 0", "0")),
            (0, i) => e[i - 1].offset.saturating_add(e[i - 1].length),
            (v, _) => v - 1,
        };
    }
    Ok(e)
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn hilbert_ids() {
        let id = |z, x, y| tile_id(TileId::new(z, x, y).unwrap());
        assert_eq!(id(0, 0, 0), 0);
        assert_eq!(
            [id(1, 0, 0), id(1, 0, 1), id(1, 1, 1), id(1, 1, 0)],
            [1, 2, 3, 4]
        );
        assert_eq!(id(2, 0, 0), 5);
        assert_eq!(id(3, 7, 0), 84); // the last tile of zoom 3's curve
    }

    #[test]
    fn absurd_zooms_are_refused() {
        let h = Header {
            root: (0, 0),
            leaves: (0, 0),
            data: (0, 0),
            addressed: 0,
            internal_compression: 1,
            tile_compression: 1,
            tile_type: 4,
            zooms: (0, 255),
            bounds: [0.0; 4],
        };
        let e = requested_tiles(&h, 200, [-1.0, -1.0, 1.0, 1.0]).unwrap_err();
        assert!(e.to_string().contains("found 200"), "{e}");
        assert_eq!(
            requested_tiles(&h, 1, [-1.0, -1.0, 1.0, 1.0])
                .unwrap()
                .len(),
            4
        );
    }

    #[test]
    fn directories() {
        // Two entries: ids 5 and 6, run lengths 1, lengths 10 and 20, offsets 0 and "next".
        let b = [2u8, 5, 1, 1, 1, 10, 20, 1, 0];
        let d = parse_directory(&b).unwrap();
        assert_eq!(
            d[1],
            Entry {
                tile_id: 6,
                offset: 10,
                length: 20,
                run_length: 1
            }
        );
        assert_eq!(find(&d, 6), Some(d[1]));
        assert_eq!(find(&d, 7), None);
        assert!(parse_directory(&[200, 1]).is_err());
        assert!(parse_directory(&[2, 5, 1, 1]).is_err());
    }
}
