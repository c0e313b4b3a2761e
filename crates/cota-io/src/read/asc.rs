//! ESRI ASCII grids (`.asc`, GDAL's AAIGrid).
//!
//! # Format facts this reader relies on
//! * A header of `key value` pairs, keys case-insensitive, in any order:
//!   `ncols`, `nrows`, `xllcorner` or `xllcenter`, `yllcorner` or `yllcenter`,
//!   `cellsize` (or GDAL's `dx` and `dy` for non-square cells) and an optional
//!   `NODATA_value`. The first token that is not a header key starts the data.
//!   A UTF-8 byte-order mark before the header is skipped.
//! * Then exactly ncols × nrows numbers, row-major from the **northern** row,
//!   separated by any whitespace (line breaks need not match rows).
//! * `xllcorner`/`yllcorner` give the outer lower-left corner of the lower-left
//!   cell ([`PixelIs::Area`], origin at the upper-left corner
//!   y = yll + nrows·cellsize); `xllcenter`/`yllcenter` give the centre of
//!   that cell ([`PixelIs::Point`], origin y = yll + (nrows−1)·cellsize). A
//!   mix of the two is converted to corners.
//! * Values equal to `NODATA_value` (compared as f64 and as f32) and the token
//!   `nan` become voids (NaN). Infinite or non-numeric values are errors that
//!   name their line and grid position; so are fewer or more values than the
//!   header promises.
//! * The CRS lives in a sibling `.prj` file, which a reader of bytes cannot
//!   see, so this reader leaves the CRS [`Crs::Unknown`] (the dispatch in
//!   `read.rs` may then assume WGS 84 when the georeference looks like degrees).
//! * The data type reported is [`DataType::I32`] when every value (and the
//!   nodata value) is an integer literal within i32 range, else
//!   [`DataType::F32`], as GDAL decides for this format.
//! * Dimensions are checked against the sample limit before any allocation,
//!   and the allocation is bounded by the number of values the bytes can hold.

use std::path::Path;

use cota_core::{Crs, GeoRef, HeightGrid, PixelIs};

use crate::dem::{DataType, Dem, Format, ReadOptions};
use crate::error::{malformed, ReadErrorKind};

/// Decodes an ESRI ASCII grid.
pub(crate) fn decode(bytes: &[u8], path: &Path, opts: &ReadOptions) -> Result<Dem, ReadErrorKind> {
    let bytes = bytes.strip_prefix(b"\xef\xbb\xbf").unwrap_or(bytes); // UTF-8 BOM
    let mut tokens = Tokens::new(bytes);
    let header = read_header(&mut tokens)?;
    let (width, height) = header.dimensions(opts)?;
    let georef = header.georef()?;
    let (heights, all_int) = read_values(&mut tokens, &header, width, height)?;
    let grid = HeightGrid::new(width, height, heights, georef)?;
    let nodata_int = header.nodata.is_none_or(|(_, int)| int);
    Ok(Dem {
        grid,
        format: Format::EsriAscii,
        data_type: if all_int && nodata_int {
            DataType::I32
        } else {
            DataType::F32
        },
        nodata: header.nodata.map(|(v, _)| v),
        path: path.to_path_buf(),
    })
}

/// A whitespace-separated token and the 1-based line it starts on.
#[derive(Debug, Clone, Copy)]
struct Token<'a> {
    text: &'a [u8],
    line: usize,
}

impl Token<'_> {
    /// The token for a message (lossy UTF-8, at most 40 bytes).
    fn show(&self) -> String {
        let cut = self.text.get(..40).unwrap_or(self.text);
        let s = String::from_utf8_lossy(cut);
        if cut.len() < self.text.len() {
            format!("{s:?}… on line {}", self.line)
        } else {
            format!("{s:?} on line {}", self.line)
        }
    }
}

/// Splits bytes into whitespace-separated tokens, counting lines.
struct Tokens<'a> {
    rest: &'a [u8],
    line: usize,
}

impl<'a> Tokens<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        Tokens {
            rest: bytes,
            line: 1,
        }
    }

    /// The next token without consuming it.
    fn peek(&self) -> Option<Token<'a>> {
        let mut line = self.line;
        let start = self.rest.iter().position(|b| {
            line += usize::from(*b == b'\n');
            !b.is_ascii_whitespace()
        })?;
        let tail = self.rest.get(start..)?;
        let len = tail
            .iter()
            .position(u8::is_ascii_whitespace)
            .unwrap_or(tail.len());
        Some(Token {
            text: tail.get(..len)?,
            line,
        })
    }
}

impl<'a> Iterator for Tokens<'a> {
    type Item = Token<'a>;

    fn next(&mut self) -> Option<Token<'a>> {
        loop {
            let (&b, tail) = self.rest.split_first()?;
            if !b.is_ascii_whitespace() {
                break;
            }
            self.line += usize::from(b == b'\n');
            self.rest = tail;
        }
        let len = self
            .rest
            .iter()
            .position(u8::is_ascii_whitespace)
            .unwrap_or(self.rest.len());
        let (text, tail) = self.rest.split_at(len);
        self.rest = tail;
        Some(Token {
            text,
            line: self.line,
        })
    }
}

/// The header keys.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Key {
    NCols,
    NRows,
    XllCorner,
    XllCenter,
    YllCorner,
    YllCenter,
    CellSize,
    Dx,
    Dy,
    NoData,
}

impl Key {
    /// The key a token names, case-insensitively.
    fn parse(text: &[u8]) -> Option<Key> {
        const KEYS: [(&str, Key); 10] = [
            ("ncols", Key::NCols),
            ("nrows", Key::NRows),
            ("xllcorner", Key::XllCorner),
            ("xllcenter", Key::XllCenter),
            ("yllcorner", Key::YllCorner),
            ("yllcenter", Key::YllCenter),
            ("cellsize", Key::CellSize),
            ("dx", Key::Dx),
            ("dy", Key::Dy),
            ("nodata_value", Key::NoData),
        ];
        KEYS.iter()
            .find(|(name, _)| name.as_bytes().eq_ignore_ascii_case(text))
            .map(|&(_, k)| k)
    }

    /// Index into [`Header::values`].
    fn slot(self) -> usize {
        self as usize
    }

    /// The key as written in messages.
    fn name(self) -> &'static str {
        match self {
            Key::NCols => "ncols",
            Key::NRows => "nrows",
            Key::XllCorner => "xllcorner",
            Key::XllCenter => "xllcenter",
            Key::YllCorner => "yllcorner",
            Key::YllCenter => "yllcenter",
            Key::CellSize => "cellsize",
            Key::Dx => "dx",
            Key::Dy => "dy",
            Key::NoData => "NODATA_value",
        }
    }
}

/// The header values, indexed by [`Key::slot`].
#[derive(Debug, Default)]
struct Header {
    values: [Option<f64>; 10],
    /// The nodata value and whether it was written as an integer.
    nodata: Option<(f64, bool)>,
}

/// Reads `key value` pairs until the first token that is not a key.
fn read_header(tokens: &mut Tokens<'_>) -> Result<Header, ReadErrorKind> {
    let mut header = Header::default();
    while let Some(key) = tokens.peek().and_then(|t| Key::parse(t.text)) {
        let key_token = tokens.next();
        let line = key_token.map_or(0, |t| t.line);
        let value = tokens.next().ok_or_else(|| {
            malformed(
                format!("a value after the header key {} on line {line}", key.name()),
                "the end of the file",
            )
        })?;
        let v = parse_header_number(key, value)?;
        let slot = header.values.get_mut(key.slot());
        match slot {
            Some(Some(_)) => {
                return Err(malformed(
                    format!("the header key {} once", key.name()),
                    format!("it again on line {line}"),
                ))
            }
            Some(s) => *s = Some(v),
            None => {}
        }
        if key == Key::NoData {
            header.nodata = Some((v, int_literal(value.text).is_some()));
        }
    }
    Ok(header)
}

/// Parses a finite header number.
fn parse_header_number(key: Key, token: Token<'_>) -> Result<f64, ReadErrorKind> {
    parse_number(token.text)
        .filter(|v| v.is_finite())
        .ok_or_else(|| {
            malformed(
                format!("a number after the header key {}", key.name()),
                token.show(),
            )
        })
}

/// Parses a decimal number (Rust's float syntax: also `nan`, `inf`).
fn parse_number(text: &[u8]) -> Option<f64> {
    std::str::from_utf8(text).ok()?.parse::<f64>().ok()
}

/// The value of an optionally signed integer literal within i32 range.
fn int_literal(text: &[u8]) -> Option<i32> {
    let digits = text
        .strip_prefix(b"-")
        .or(text.strip_prefix(b"+"))
        .unwrap_or(text);
    if digits.is_empty() || !digits.iter().all(u8::is_ascii_digit) {
        return None;
    }
    std::str::from_utf8(text).ok()?.parse::<i32>().ok()
}

impl Header {
    fn get(&self, key: Key) -> Option<f64> {
        self.values.get(key.slot()).copied().flatten()
    }

    /// A required key's value.
    fn require(&self, key: Key) -> Result<f64, ReadErrorKind> {
        self.get(key).ok_or_else(|| {
            malformed(
                format!("the header key {}", key.name()),
                "a header without it",
            )
        })
    }

    /// ncols and nrows, checked against the sample limit.
    fn dimensions(&self, opts: &ReadOptions) -> Result<(usize, usize), ReadErrorKind> {
        let w = self.count(Key::NCols)?;
        let h = self.count(Key::NRows)?;
        crate::limits::check(w, h, opts)?;
        let w = usize::try_from(w).map_err(|_| malformed("a smaller ncols", w))?;
        let h = usize::try_from(h).map_err(|_| malformed("a smaller nrows", h))?;
        Ok((w, h))
    }

    /// A positive whole-number header value.
    fn count(&self, key: Key) -> Result<u64, ReadErrorKind> {
        let v = self.require(key)?;
        if v >= 1.0 && v.fract() == 0.0 {
            // Saturates for huge values, which the dimension check then refuses.
            Ok(v as u64)
        } else {
            Err(malformed(
                format!("{} to be a whole number ≥ 1", key.name()),
                v,
            ))
        }
    }

    /// Cell width and height (positive).
    fn cell_size(&self) -> Result<(f64, f64), ReadErrorKind> {
        let (dx, dy) = match (
            self.get(Key::CellSize),
            self.get(Key::Dx),
            self.get(Key::Dy),
        ) {
            (Some(c), None, None) => (c, c),
            (None, Some(dx), Some(dy)) => (dx, dy),
            (None, Some(d), None) | (None, None, Some(d)) => (d, d),
            (None, None, None) => {
                return Err(malformed("the header key cellsize (or dx and dy)", "none"))
            }
            _ => return Err(malformed("either cellsize or dx/dy in the header", "both")),
        };
        if dx > 0.0 && dy > 0.0 {
            Ok((dx, dy))
        } else {
            Err(malformed("a positive cell size", format!("{dx} by {dy}")))
        }
    }

    /// The lower-left coordinate along one axis and whether it is a corner.
    fn lower_left(&self, corner: Key, center: Key) -> Result<(f64, bool), ReadErrorKind> {
        match (self.get(corner), self.get(center)) {
            (Some(v), None) => Ok((v, true)),
            (None, Some(v)) => Ok((v, false)),
            (None, None) => Err(malformed(
                format!("the header key {} or {}", corner.name(), center.name()),
                "neither",
            )),
            (Some(_), Some(_)) => Err(malformed(
                format!("one of {} and {}", corner.name(), center.name()),
                "both",
            )),
        }
    }

    /// The georeference (CRS unknown: it would be in a sibling .prj).
    fn georef(&self) -> Result<GeoRef, ReadErrorKind> {
        let (x, x_corner) = self.lower_left(Key::XllCorner, Key::XllCenter)?;
        let (y, y_corner) = self.lower_left(Key::YllCorner, Key::YllCenter)?;
        let (dx, dy) = self.cell_size()?;
        let rows = self.get(Key::NRows).unwrap_or(1.0);
        let (origin_x, origin_y, pixel_is) = if x_corner || y_corner {
            let xc = if x_corner { x } else { x - dx / 2.0 };
            let yc = if y_corner { y } else { y - dy / 2.0 };
            (xc, yc + rows * dy, PixelIs::Area)
        } else {
            (x, y + (rows - 1.0) * dy, PixelIs::Point)
        };
        Ok(GeoRef {
            crs: Crs::Unknown,
            origin_x,
            origin_y,
            pixel_x: dx,
            pixel_y: -dy,
            pixel_is,
            known: true,
        })
    }
}

/// Reads exactly `width`·`height` values; returns the heights and whether
/// every value was an integer literal.
fn read_values(
    tokens: &mut Tokens<'_>,
    header: &Header,
    width: usize,
    height: usize,
) -> Result<(Vec<f32>, bool), ReadErrorKind> {
    let expected = width * height;
    // Each value takes at least two bytes (a digit and a separator), so the
    // input bounds the allocation whatever the header claims.
    let capacity = expected.min(tokens.rest.len() / 2 + 1);
    let mut heights = crate::limits::try_vec(capacity, &format!("{width}x{height} heights"))?;
    let mut all_int = true;
    let nodata = header.nodata.map(|(v, _)| v);
    for token in tokens.by_ref().take(expected) {
        let i = heights.len();
        let (h, int) = parse_value(token, nodata, i, width)?;
        all_int &= int;
        heights.push(h);
    }
    let expectation = || {
        format!(
            "{expected} values ({width} columns × {height} rows, from the header) after the header"
        )
    };
    if heights.len() < expected {
        return Err(malformed(expectation(), format!("{}", heights.len())));
    }
    if let Some(extra) = tokens.next() {
        let more = 1 + tokens.count();
        return Err(malformed(
            expectation(),
            format!("{} (the first extra is {})", expected + more, extra.show()),
        ));
    }
    Ok((heights, all_int))
}

/// Parses one value (the `i`-th of a grid `width` wide) into metres, nodata
/// to NaN; also says whether it was an integer literal.
fn parse_value(
    token: Token<'_>,
    nodata: Option<f64>,
    i: usize,
    width: usize,
) -> Result<(f32, bool), ReadErrorKind> {
    if let Some(v) = int_literal(token.text) {
        let v = f64::from(v);
        return Ok((to_height(v, nodata), true));
    }
    match parse_number(token.text) {
        Some(v) if v.is_nan() => Ok((f32::NAN, false)),
        Some(v) if v.is_finite() && (v as f32).is_finite() => Ok((to_height(v, nodata), false)),
        _ => Err(malformed(
            format!(
                "a finite number for the value at column {}, row {} (0-based)",
                i % width.max(1),
                i / width.max(1)
            ),
            token.show(),
        )),
    }
}

/// The height of a finite value: NaN when it equals the nodata value.
fn to_height(v: f64, nodata: Option<f64>) -> f32 {
    match nodata {
        Some(nd) if v == nd || v as f32 == nd as f32 => f32::NAN,
        _ => v as f32,
    }
}

#[cfg(test)]
mod test {
    use super::*;

    fn read(text: &str) -> Result<Dem, ReadErrorKind> {
        decode(text.as_bytes(), Path::new("t.asc"), &ReadOptions::DEFAULT)
    }

    #[test]
    fn corner_header() {
        let d = read("NCOLS 3\nnrows 2\nxllcorner 10\nyllcorner 20\ncellsize 5\nnodata_value -9999\n1 2 3\n4 -9999 6\n")
            .unwrap();
        assert_eq!(d.grid.width(), 3);
        assert_eq!(d.grid.void_count(), 1);
        assert_eq!(d.data_type, DataType::I32);
        let g = d.grid.georef();
        assert_eq!(
            (g.origin_x, g.origin_y, g.pixel_is),
            (10.0, 30.0, PixelIs::Area)
        );
        assert_eq!(g.sample_xy(0.0, 1.0), (12.5, 22.5));
    }

    #[test]
    fn center_header_and_floats() {
        let d = read("ncols 2 nrows 2 xllcenter 0 yllcenter 0 cellsize 1\n1.5 2\n3 4e0").unwrap();
        assert_eq!(d.data_type, DataType::F32);
        let g = d.grid.georef();
        assert_eq!((g.origin_y, g.pixel_is), (1.0, PixelIs::Point));
        assert_eq!(g.sample_xy(0.0, 1.0), (0.0, 0.0));
        assert_eq!(d.grid.heights(), &[1.5, 2.0, 3.0, 4.0]);
    }

    #[test]
    fn byte_order_mark() {
        let d = decode(
            b"\xef\xbb\xbfncols 1 nrows 1 xllcorner 0 yllcorner 0 cellsize 1 5",
            Path::new("t.asc"),
            &ReadOptions::DEFAULT,
        )
        .unwrap();
        assert_eq!(d.grid.heights(), &[5.0]);
        assert_eq!(
            super::super::sniff::sniff(b"\xef\xbb\xbfNCOLS 1"),
            super::super::sniff::Sniffed::Ascii
        );
    }

    #[test]
    fn dx_dy() {
        let d = read("ncols 1 nrows 2 xllcorner 0 yllcorner 0 dx 2 dy 3 7 8").unwrap();
        let g = d.grid.georef();
        assert_eq!((g.pixel_x, g.pixel_y, g.origin_y), (2.0, -3.0, 6.0));
    }

    #[test]
    fn errors() {
        let e = read("ncols 2 nrows 2 xllcorner 0 yllcorner 0 cellsize 1\n1 2 3").unwrap_err();
        assert!(e.to_string().contains("expected 4 values"), "{e}");
        assert!(e.to_string().contains("found 3"), "{e}");
        let e = read("ncols 2 nrows 2 xllcorner 0 yllcorner 0 cellsize 1\n1 2\n3 x").unwrap_err();
        assert!(e.to_string().contains("column 1, row 1"), "{e}");
        assert!(e.to_string().contains("line 3"), "{e}");
        let e = read("ncols 1 nrows 1 xllcorner 0 yllcorner 0 cellsize 1 1 2 3").unwrap_err();
        assert!(e.to_string().contains("found 3"), "{e}");
        let e = read("ncols 100000000 nrows 100000000 xllcorner 0 yllcorner 0 cellsize 1 1")
            .unwrap_err();
        assert!(matches!(e, ReadErrorKind::TooLarge { .. }), "{e}");
        let e = read("ncols 1 nrows 1 yllcorner 0 cellsize 1 1").unwrap_err();
        assert!(e.to_string().contains("xllcorner"), "{e}");
        let e = read("ncols 1 nrows 1 xllcorner 0 yllcorner 0 cellsize 1 inf").unwrap_err();
        assert!(e.to_string().contains("finite"), "{e}");
    }
}
