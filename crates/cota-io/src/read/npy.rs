//! NumPy arrays: `.npy` files and `.npz` archives (a ZIP of `.npy` members).
//!
//! # Format facts this reader relies on (NumPy's `format` module, NEP 1)
//! * `.npy`: the magic `\x93NUMPY`, a major and a minor version byte, the
//!   header length (u16 little-endian in version 1, u32 in versions 2 and 3),
//!   then a Python dict literal `{'descr': '<f4', 'fortran_order': False,
//!   'shape': (rows, cols), }`, then the raw data.
//! * `descr` here is a simple type: a byte order (`<` little, `>` big, `|` not
//!   applicable, `=` native, taken as little) and a kind and size: `i1 i2 i4
//!   i8 u1 u2 u4 f4 f8`. Structured, object, complex and other types are refused.
//! * `fortran_order: True` stores columns first; the reader transposes it.
//! * A DEM is a 2-D array (rows from the north, as an image); a shape of any
//!   other rank is refused. NaN is a void. The data must be exactly
//!   rows·cols·size bytes, checked (with the sample limit) before allocating.
//! * `.npz`: each member `NAME.npy` is the array `NAME`. The heights are the
//!   array [`ReadOptions::array`] names, else the only 2-D array, else the one
//!   named `elevation`, `dem`, `z`, `height` or `heights`; anything else is
//!   ambiguous and refused with the list of names.
//! * Georeference: arrays carry none. In an `.npz`, companion scalars decide
//!   when their names do: `cell_size_m` gives the cell size in metres; `dx`,
//!   `dy` with `xmin` and `ymax` (or `ymin`) give a transform in the data's
//!   own units (pixel-is-point, `ymin` taken as the southern row, the steps'
//!   signs ignored); `dx`, `dy` with `x0` and `y0` (the first sample's
//!   centre) give one with signed steps, a positive `dy` meaning rows that
//!   run south to north (flipped north-up). Degrees when small enough to be
//!   degrees (see `GeoRef::guess_geographic`). Scalars are read as f64 (a
//!   UTM coordinate keeps its millimetres). `dx` without `dy`, a zero step, or
//!   steps without an origin are refused. Otherwise
//!   [`ReadOptions::cell_size_m`].
//! * Coordinate arrays: 1-D members `x` and `y` (or `lon` and `lat`,
//!   `longitude` and `latitude`), one value per column and per row, as
//!   xarray and rasterio write them, come first. They give the sample
//!   centres (pixel-is-point) and the direction: `y` rising means the rows
//!   run south to north, `x` falling east to west; the grid is flipped to
//!   north-up (`read/orient.rs`) so it lands where its coordinates say. The
//!   steps must be even (within 10⁻⁶ of a step), else the file is refused.

use std::io::{Cursor, Read};
use std::path::Path;

use cota_core::{GeoRef, HeightGrid, PixelIs};
use zip::ZipArchive;

use crate::dem::{DataType, Dem, Format, ReadOptions};
use crate::error::{malformed, ReadErrorKind};

/// Largest expansion ratio of DEFLATE.
const MAX_DEFLATE_RATIO: u64 = 1032;

/// Names taken for the heights when an archive holds several 2-D arrays.
const HEIGHT_NAMES: [&str; 5] = ["elevation", "dem", "z", "height", "heights"];

/// A parsed `.npy` header.
#[derive(Debug, Clone, PartialEq)]
struct Header {
    kind: u8,
    size: usize,
    big_endian: bool,
    fortran: bool,
    shape: Vec<u64>,
    data_offset: usize,
}

/// True when a ZIP archive holds at least one `.npy` member.
pub(crate) fn is_npz(bytes: &[u8]) -> bool {
    ZipArchive::new(Cursor::new(bytes))
        .map(|z| {
            z.file_names()
                .filter_map(Result::ok)
                .any(|n| n.ends_with(".npy"))
        })
        .unwrap_or(false)
}

/// Decodes a `.npy` file.
pub(crate) fn decode_npy(
    bytes: &[u8],
    path: &Path,
    opts: &ReadOptions,
) -> Result<Dem, ReadErrorKind> {
    let (grid, dt) = array_grid(bytes, GeoRef::unreferenced(opts.cell_size_m), "", opts)?;
    Ok(dem(grid, dt, Format::Npy, path))
}

/// Wraps a decoded grid.
fn dem(grid: HeightGrid, data_type: DataType, format: Format, path: &Path) -> Dem {
    Dem {
        grid,
        format,
        data_type,
        nodata: None,
        path: path.to_path_buf(),
    }
}

/// Decodes the height array of a `.npz` archive.
pub(crate) fn decode_npz(
    bytes: &[u8],
    path: &Path,
    opts: &ReadOptions,
) -> Result<Dem, ReadErrorKind> {
    let mut zip = ZipArchive::new(Cursor::new(bytes))
        .map_err(|e| malformed("a valid ZIP archive (.npz)", e))?;
    let names: Vec<String> = zip
        .file_names()
        .filter_map(Result::ok)
        .filter_map(|n| n.strip_suffix(".npy").map(str::to_string))
        .collect();
    let mut headers = Vec::new();
    for n in &names {
        let head = member(&mut zip, n, bytes.len(), Some(4096))?;
        headers.push(parse_header(&head).ok().map(|h| h.shape));
    }
    let chosen = choose(&names, &headers, opts)?;
    let shape = names
        .iter()
        .position(|n| *n == chosen)
        .and_then(|i| headers[i].clone());
    let georef = match coordinate_georef(&mut zip, &names, bytes.len(), shape.as_deref())? {
        Some(g) => g,
        None => companion_georef(&mut zip, &names, bytes.len(), opts)?,
    };
    let data = member(&mut zip, &chosen, bytes.len(), None)?;
    let what = format!(" in array {chosen:?}");
    let (grid, dt) = array_grid(&data, georef, &what, opts)?;
    Ok(dem(grid, dt, Format::Npz, path))
}

/// The array to read: the requested one, or the only (or conventionally
/// named) 2-D one.
fn choose(
    names: &[String],
    shapes: &[Option<Vec<u64>>],
    opts: &ReadOptions,
) -> Result<String, ReadErrorKind> {
    let list = || names.join(", ");
    if let Some(want) = &opts.array {
        return names
            .iter()
            .find(|n| n.as_str() == want.as_str())
            .cloned()
            .ok_or_else(|| {
                malformed(
                    format!("an array named {:?} (--array)", want.as_str()),
                    format!("the arrays {}", list()),
                )
            });
    }
    let two_d: Vec<&String> = names
        .iter()
        .zip(shapes)
        .filter(|(_, s)| s.as_ref().is_some_and(|s| s.len() == 2))
        .map(|(n, _)| n)
        .collect();
    match two_d.as_slice() {
        [one] => Ok((*one).clone()),
        [] => Err(malformed(
            "a 2-D array of heights in the .npz",
            format!("none among the arrays {}", list()),
        )),
        many => HEIGHT_NAMES
            .iter()
            .find_map(|h| many.iter().find(|n| n.as_str() == *h))
            .map(|n| (*n).clone())
            .ok_or_else(|| ReadErrorKind::Unsupported {
                what: "ambiguous .npz".into(),
                detail: format!(
                    "it holds several 2-D arrays ({}); choose one with --array NAME",
                    many.iter()
                        .map(|s| s.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            }),
    }
}

/// Names of the 1-D coordinate arrays, (columns, rows).
const COORDINATE_NAMES: [(&str, &str); 3] = [("x", "y"), ("lon", "lat"), ("longitude", "latitude")];

/// The georeference the 1-D coordinate arrays give (`x`/`y` and the like,
/// one value per column and per row of the heights' `shape`), with their
/// directions: a positive `pixel_y` for rows that run south to north.
fn coordinate_georef(
    zip: &mut ZipArchive<Cursor<&[u8]>>,
    names: &[String],
    file_len: usize,
    shape: Option<&[u64]>,
) -> Result<Option<GeoRef>, ReadErrorKind> {
    let Some(&[rows, cols]) = shape else {
        return Ok(None);
    };
    let has = |n: &str| names.iter().any(|m| m == n);
    let Some((xn, yn)) = COORDINATE_NAMES.iter().find(|(x, y)| has(x) && has(y)) else {
        return Ok(None);
    };
    let cap = Some(
        rows.max(cols)
            .saturating_add(1)
            .saturating_mul(8)
            .saturating_add(4096),
    );
    let xs = coordinates(&member(zip, xn, file_len, cap)?, xn, cols)?;
    let ys = coordinates(&member(zip, yn, file_len, cap)?, yn, rows)?;
    let (Some((x0, dx)), Some((y0, dy))) = (even_step(&xs, xn)?, even_step(&ys, yn)?) else {
        return Ok(None);
    };
    Ok(Some(GeoRef {
        crs: cota_core::Crs::Unknown,
        origin_x: x0,
        origin_y: y0,
        pixel_x: dx,
        pixel_y: dy,
        pixel_is: PixelIs::Point,
        known: true,
    }))
}

/// The values of 1-D coordinate array `name`, which must hold `n` of them.
fn coordinates(bytes: &[u8], name: &str, n: u64) -> Result<Vec<f64>, ReadErrorKind> {
    let h = parse_header(bytes)?;
    let data = bytes.get(h.data_offset..).unwrap_or_default();
    if h.shape != [n] || data.len() as u64 != n.saturating_mul(h.size as u64) {
        return Err(malformed(
            format!("coordinate array {name:?} of {n} values, one per sample"),
            format!("shape {:?}", h.shape),
        ));
    }
    Ok(values(data, &h).collect())
}

/// The first value and the step of evenly spaced coordinates (`None` for
/// fewer than two); uneven or non-finite steps are refused.
fn even_step(v: &[f64], name: &str) -> Result<Option<(f64, f64)>, ReadErrorKind> {
    let (Some(&first), Some(&last)) = (v.first(), v.last()) else {
        return Ok(None);
    };
    if v.len() < 2 {
        return Ok(None);
    }
    let step = (last - first) / (v.len() - 1) as f64;
    let uneven = v.iter().enumerate().find(|(i, c)| {
        let off = (*c - (first + *i as f64 * step)).abs();
        off.is_nan() || off > 1e-6 * step.abs()
    });
    if !(step.is_finite() && step != 0.0) || uneven.is_some() {
        let at = uneven.map_or(0, |(i, _)| i);
        return Err(malformed(
            format!("evenly spaced coordinates in array {name:?} (a regular grid)"),
            format!(
                "{} at index {at} where an even step of {step} gives {}",
                v.get(at).copied().unwrap_or(f64::NAN),
                first + at as f64 * step
            ),
        ));
    }
    Ok(Some((first, step)))
}

/// The georeference the companion scalars give, else the placeholder.
fn companion_georef(
    zip: &mut ZipArchive<Cursor<&[u8]>>,
    names: &[String],
    file_len: usize,
    opts: &ReadOptions,
) -> Result<GeoRef, ReadErrorKind> {
    let mut scalar = |name: &str| -> Result<Option<f64>, ReadErrorKind> {
        if !names.iter().any(|n| n == name) {
            return Ok(None);
        }
        let bytes = member(zip, name, file_len, Some(4096))?;
        Ok(scalar_value(&bytes))
    };
    if let Some(c) = scalar("cell_size_m")?.filter(|c| *c > 0.0 && c.is_finite()) {
        return Ok(GeoRef::unreferenced(c));
    }
    let (dx, dy) = (scalar("dx")?, scalar("dy")?);
    let (x0, y0) = (scalar("x0")?, scalar("y0")?);
    let (xmin, ymin, ymax) = (scalar("xmin")?, scalar("ymin")?, scalar("ymax")?);
    if dx.is_none() && dy.is_none() {
        return Ok(GeoRef::unreferenced(opts.cell_size_m));
    }
    let (Some(dx), Some(dy)) = (dx, dy) else {
        return Err(malformed(
            "both scalars \"dx\" and \"dy\" (the sample spacing)",
            "only one of them",
        ));
    };
    if !(dx.is_finite() && dy.is_finite() && dx != 0.0 && dy != 0.0) {
        return Err(malformed(
            "finite, non-zero scalars \"dx\" and \"dy\"",
            format!("dx = {dx}, dy = {dy}"),
        ));
    }
    let georef = |origin_x: f64, origin_y: f64, pixel_x: f64, pixel_y: f64| GeoRef {
        crs: cota_core::Crs::Unknown,
        origin_x,
        origin_y,
        pixel_x,
        pixel_y,
        pixel_is: PixelIs::Point,
        known: true,
    };
    // `x0`/`y0`: the centre of the first sample, with signed steps (a
    // positive `dy`: rows run south to north; a negative `dx`: columns
    // east to west; flipped north-up on reading).
    if let (Some(x0), Some(y0)) = (x0, y0) {
        return Ok(georef(x0, y0, dx, dy));
    }
    // Extents: `dx`, `dy` are sizes (their sign is ignored), rows north to south.
    let (dx, dy) = (dx.abs(), dy.abs());
    match (xmin.or(x0), ymax, ymin) {
        (Some(x), Some(top), _) => Ok(georef(x, top, dx, -dy)),
        // Only the southern row: placed below (see `place_southern`).
        (Some(x), None, Some(bottom)) => Ok(GeoRef {
            pixel_y: f64::NAN,
            ..georef(x, bottom, dx, -dy)
        }),
        _ => Err(malformed(
            "with \"dx\" and \"dy\", the scalars \"xmin\" and \"ymax\" (or \"ymin\"), or \"x0\" and \"y0\"",
            {
                let given: Vec<&str> = [("xmin", xmin), ("ymin", ymin), ("ymax", ymax), ("x0", x0), ("y0", y0)]
                    .iter()
                    .filter(|(_, v)| v.is_some())
                    .map(|(n, _)| *n)
                    .collect();
                if given.is_empty() {
                    "none of them".to_string()
                } else {
                    format!("only {}", given.join(", "))
                }
            },
        )),
    }
}

/// The value of a 0-d or one-element numeric array, if it is one.
fn scalar_value(bytes: &[u8]) -> Option<f64> {
    let h = parse_header(bytes).ok()?;
    if h.shape.iter().product::<u64>() != 1 {
        return None;
    }
    let raw = bytes.get(h.data_offset..h.data_offset + h.size)?;
    // As f64: a UTM coordinate in f32 would lose decimetres.
    let first = values(raw, &h).next();
    first
}

/// Reads member `NAME.npy` (at most `limit` bytes when given), refusing a
/// declared size beyond what the archive could hold.
fn member(
    zip: &mut ZipArchive<Cursor<&[u8]>>,
    name: &str,
    file_len: usize,
    limit: Option<u64>,
) -> Result<Vec<u8>, ReadErrorKind> {
    let full = format!("{name}.npy");
    let f = zip
        .by_name(&full)
        .map_err(|e| malformed(format!("a readable member {full}"), e))?;
    let declared = f.size();
    let cap = (file_len as u64).saturating_mul(MAX_DEFLATE_RATIO);
    if declared > cap {
        return Err(malformed(
            format!("member {full} of at most {cap} bytes (DEFLATE packs at most {MAX_DEFLATE_RATIO}:1)"),
            format!("a declared size of {declared} bytes"),
        ));
    }
    let take = limit.unwrap_or(declared).min(declared);
    let mut out = Vec::with_capacity(take as usize);
    f.take(take)
        .read_to_end(&mut out)
        .map_err(|e| malformed(format!("a complete member {full}"), e))?;
    Ok(out)
}

/// Parses the header of a `.npy` file.
fn parse_header(bytes: &[u8]) -> Result<Header, ReadErrorKind> {
    let prefix = |n: usize| {
        bytes
            .get(..n)
            .ok_or_else(|| malformed("a .npy header", format!("{} bytes", bytes.len())))
    };
    let fixed = prefix(10)?;
    if !fixed.starts_with(b"\x93NUMPY") {
        return Err(malformed("the .npy signature \\x93NUMPY", "other bytes"));
    }
    let (len, start): (usize, usize) = match fixed[6] {
        1 => (usize::from(u16::from_le_bytes([fixed[8], fixed[9]])), 10),
        2 | 3 => {
            let b = prefix(12)?;
            (u32::from_le_bytes([b[8], b[9], b[10], b[11]]) as usize, 12)
        }
        v => {
            return Err(ReadErrorKind::Unsupported {
                what: ".npy version".into(),
                detail: format!("{v}; cota reads versions 1 to 3"),
            })
        }
    };
    let text = prefix(start.saturating_add(len))?
        .get(start..)
        .map(String::from_utf8_lossy)
        .unwrap_or_default();
    let (kind, size, big_endian) = parse_descr(&text)?;
    let fortran = dict_value(&text, "fortran_order")
        .ok_or_else(|| malformed("a fortran_order entry in the .npy header", text.trim()))?
        .starts_with("True");
    let shape = parse_shape(&text)?;
    Ok(Header {
        kind,
        size,
        big_endian,
        fortran,
        shape,
        data_offset: start + len,
    })
}

/// The text after `'key':` in a header dict.
fn dict_value<'a>(text: &'a str, key: &str) -> Option<&'a str> {
    let at = text.find(&format!("'{key}'"))?;
    let rest = &text[at + key.len() + 2..];
    Some(rest.trim_start().strip_prefix(':')?.trim_start())
}

/// Kind byte, item size and byte order of a simple `descr`.
fn parse_descr(text: &str) -> Result<(u8, usize, bool), ReadErrorKind> {
    let v = dict_value(text, "descr")
        .ok_or_else(|| malformed("a descr entry in the .npy header", text.trim()))?;
    let unsupported = |d: &str| ReadErrorKind::Unsupported {
        what: ".npy dtype".into(),
        detail: format!("{d}; cota reads i1 i2 i4 i8 u1 u2 u4 f4 f8 (either byte order)"),
    };
    let Some(inner) = v.strip_prefix('\'').and_then(|s| s.split('\'').next()) else {
        return Err(unsupported(v.split('}').next().unwrap_or(v)));
    };
    let b = inner.as_bytes();
    let (order, kind, size) = match b {
        [o @ (b'<' | b'>' | b'|' | b'='), k, rest @ ..] => (*o, *k, rest),
        _ => return Err(unsupported(inner)),
    };
    let size: usize = std::str::from_utf8(size)
        .ok()
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| unsupported(inner))?;
    match (kind, size) {
        (b'i', 1 | 2 | 4 | 8) | (b'u', 1 | 2 | 4) | (b'f', 4 | 8) => {
            Ok((kind, size, order == b'>'))
        }
        _ => Err(unsupported(inner)),
    }
}

/// The `shape` tuple.
fn parse_shape(text: &str) -> Result<Vec<u64>, ReadErrorKind> {
    let v = dict_value(text, "shape")
        .ok_or_else(|| malformed("a shape entry in the .npy header", text.trim()))?;
    let inner = v
        .strip_prefix('(')
        .and_then(|s| s.split(')').next())
        .ok_or_else(|| malformed("a shape tuple in the .npy header", v))?;
    inner
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| s.trim_end_matches('L').parse::<u64>())
        .collect::<Result<_, _>>()
        .map_err(|_| malformed("a shape of whole numbers", inner))
}

/// The grid of a `.npy` file's bytes with `georef`; `what` qualifies errors.
fn array_grid(
    bytes: &[u8],
    georef: GeoRef,
    what: &str,
    opts: &ReadOptions,
) -> Result<(HeightGrid, DataType), ReadErrorKind> {
    let h = parse_header(bytes)?;
    let [rows, cols] = h.shape[..] else {
        return Err(ReadErrorKind::Unsupported {
            what: "array shape".into(),
            detail: format!("{:?}{what}; a DEM is a 2-D array (rows, cols)", h.shape),
        });
    };
    crate::limits::check(cols, rows, opts)?;
    let need = rows * cols * h.size as u64;
    let data = &bytes[h.data_offset.min(bytes.len())..];
    if data.len() as u64 != need {
        return Err(malformed(
            format!("{need} bytes of data for a {rows}x{cols} array{what}"),
            format!("{} bytes", data.len()),
        ));
    }
    let mut heights = convert(data, &h);
    if h.fortran {
        heights = transpose(&heights, rows as usize, cols as usize);
    }
    let mut georef = place_southern(georef, rows as usize);
    super::orient::north_up(&mut heights, cols as usize, rows as usize, &mut georef);
    let grid = HeightGrid::new(cols as usize, rows as usize, heights, georef)?;
    Ok((grid, data_type(h.kind, h.size)))
}

/// Completes a georeference given by its southern row (`ymin` only).
fn place_southern(mut g: GeoRef, rows: usize) -> GeoRef {
    if g.pixel_y.is_nan() {
        let dy = g.pixel_x.abs();
        g.origin_y += (rows as f64 - 1.0) * dy;
        g.pixel_y = -dy;
    }
    g
}

/// Column-major `rows` × `cols` values to row-major.
fn transpose(v: &[f32], rows: usize, cols: usize) -> Vec<f32> {
    (0..rows)
        .flat_map(|r| (0..cols).map(move |c| v[c * rows + r]))
        .collect()
}

/// The values as f32 metres (NaN stays a void; infinities become voids).
fn convert(data: &[u8], h: &Header) -> Vec<f32> {
    values(data, h)
        .map(|v| if v.is_finite() { v as f32 } else { f32::NAN })
        .collect()
}

/// The values, as f64.
fn values<'a>(data: &'a [u8], h: &'a Header) -> impl Iterator<Item = f64> + 'a {
    let be = h.big_endian;
    data.chunks_exact(h.size.max(1)).map(move |c| {
        let mut b = [0u8; 8];
        if be {
            b[8 - c.len()..].copy_from_slice(c);
            b.reverse();
        } else {
            b[..c.len()].copy_from_slice(c);
        }
        match (h.kind, h.size) {
            (b'i', 1) => f64::from(b[0] as i8),
            (b'i', 2) => f64::from(i16::from_le_bytes([b[0], b[1]])),
            (b'i', 4) => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            (b'i', _) => i64::from_le_bytes(b) as f64,
            (b'u', 1) => f64::from(b[0]),
            (b'u', 2) => f64::from(u16::from_le_bytes([b[0], b[1]])),
            (b'u', 4) => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            (b'u', _) => u64::from_le_bytes(b) as f64,
            (_, 4) => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            _ => f64::from_le_bytes(b),
        }
    })
}

/// The reported data type.
fn data_type(kind: u8, size: usize) -> DataType {
    match (kind, size) {
        (b'i', 1) => DataType::I8,
        (b'i', 2) => DataType::I16,
        (b'i', 4) => DataType::I32,
        (b'i', _) => DataType::I64,
        (b'u', 1) => DataType::U8,
        (b'u', 2) => DataType::U16,
        (b'u', _) => DataType::U32,
        (_, 4) => DataType::F32,
        _ => DataType::F64,
    }
}

#[cfg(test)]
mod test {
    use super::*;

    fn npy(descr: &str, fortran: bool, shape: &str, data: &[u8]) -> Vec<u8> {
        let f = if fortran { "True" } else { "False" };
        let mut dict = format!("{{'descr': '{descr}', 'fortran_order': {f}, 'shape': {shape}, }}");
        while (10 + dict.len() + 1) % 64 != 0 {
            dict.push(' ');
        }
        dict.push('\n');
        let mut out = b"\x93NUMPY\x01\x00".to_vec();
        out.extend_from_slice(&(dict.len() as u16).to_le_bytes());
        out.extend_from_slice(dict.as_bytes());
        out.extend_from_slice(data);
        out
    }

    #[test]
    fn orders_and_types() {
        let le: Vec<u8> = [1i16, 2, 3, 4, 5, 6]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let (g, dt) = array_grid(
            &npy("<i2", false, "(2, 3)", &le),
            GeoRef::unreferenced(1.0),
            "",
            &ReadOptions::DEFAULT,
        )
        .unwrap();
        assert_eq!((g.width(), g.height(), dt), (3, 2, DataType::I16));
        assert_eq!(g.heights(), &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
        // Fortran order: the same bytes are columns.
        let (g, _) = array_grid(
            &npy("<i2", true, "(2, 3)", &le),
            GeoRef::unreferenced(1.0),
            "",
            &ReadOptions::DEFAULT,
        )
        .unwrap();
        assert_eq!(g.heights(), &[1.0, 3.0, 5.0, 2.0, 4.0, 6.0]);
        let be: Vec<u8> = [1.5f64, f64::NAN]
            .iter()
            .flat_map(|v| v.to_be_bytes())
            .collect();
        let (g, _) = array_grid(
            &npy(">f8", false, "(1, 2)", &be),
            GeoRef::unreferenced(1.0),
            "",
            &ReadOptions::DEFAULT,
        )
        .unwrap();
        assert_eq!(g.get(0, 0), 1.5);
        assert!(g.get(1, 0).is_nan());
    }

    #[test]
    fn refusals() {
        let e = parse_header(&npy("<c16", false, "(1, 1)", &[0; 16])).unwrap_err();
        assert!(e.to_string().contains("c16"), "{e}");
        let e = array_grid(
            &npy("<f4", false, "(2, 2, 2)", &[0; 32]),
            GeoRef::unreferenced(1.0),
            "",
            &ReadOptions::DEFAULT,
        )
        .unwrap_err();
        assert!(e.to_string().contains("2-D"), "{e}");
        let e = array_grid(
            &npy("<f4", false, "(2, 2)", &[0; 12]),
            GeoRef::unreferenced(1.0),
            "",
            &ReadOptions::DEFAULT,
        )
        .unwrap_err();
        assert!(e.to_string().contains("16 bytes"), "{e}");
    }
}
