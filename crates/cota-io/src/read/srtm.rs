//! SRTM height tiles: raw `.hgt` files and `.hgt` files inside a ZIP archive.
//!
//! # Format facts this reader relies on
//! * A `.hgt` file has no header: it is n×n big-endian `int16` heights in
//!   metres, row-major from the north-west sample, so its size is exactly
//!   2·n² bytes. n = 1201 for 3 arc-second tiles, 3601 for 1 arc-second
//!   tiles; any n ≥ 2 is accepted.
//! * −32768 marks a void; it becomes NaN.
//! * The file name starts with the latitude and longitude of the tile's
//!   south-west corner, `[NS]dd[EW]ddd` (`N00E010.hgt`, `S29W072.hgt.zip`,
//!   `n49e011.SRTMGL1.hgt.zip`); letters are matched case-insensitively.
//! * Samples sit on whole-degree lines: the tile spans one degree and adjacent
//!   tiles share their edge row or column. So the georeference is EPSG:4326,
//!   pixel-is-point, origin (lon, lat + 1) at the north-west sample and a step
//!   of 1/(n−1) degree.
//! * A tile whose name carries no position (or an impossible one, such as
//!   `N95…`) is still read, with a placeholder georeference:
//!   [`GeoRef::unreferenced`] with the cell size a one-degree tile has on the
//!   mean Earth sphere, 111 195 m / (n−1) (92.7 m for 1201², 30.9 m for 3601²),
//!   and `known == false`.
//! * A `.hgt.zip` must hold exactly one `.hgt` member (other members are
//!   ignored). The position comes from the archive's name, else from the
//!   member's. Its declared size must be 2·n² bytes, and must be within what
//!   DEFLATE can expand the archive to (at most 1032:1), so a forged header
//!   cannot make the reader allocate more than the archive could hold.
//!   Decompression stops one byte past the declared size.

use std::borrow::Cow;
use std::io::{Cursor, Read};
use std::path::Path;

use cota_core::{Crs, GeoRef, HeightGrid, PixelIs};
use zip::ZipArchive;

use super::sniff::{sniff, Sniffed};
use crate::dem::{DataType, Dem, Format, ReadOptions};
use crate::error::{malformed, ReadErrorKind};

/// The SRTM void value.
const VOID: i16 = i16::MIN;

/// Metres of one degree of arc on the mean Earth sphere (radius 6371 km), used
/// for the placeholder cell size of tiles without a position.
const METRES_PER_DEGREE: f64 = 111_195.0;

/// Largest expansion ratio of DEFLATE (258-byte matches coded in about 2 bits).
const MAX_DEFLATE_RATIO: u64 = 1032;

/// Decodes a raw `.hgt` or a `.hgt.zip`. `path` supplies the tile's position.
pub(crate) fn decode(bytes: &[u8], path: &Path, opts: &ReadOptions) -> Result<Dem, ReadErrorKind> {
    let name = file_name(path);
    if sniff(bytes) == Sniffed::Zip {
        decode_zip(bytes, path, &name, opts)
    } else {
        let grid = decode_raw(bytes, &[&name], "", opts)?;
        Ok(dem(grid, Format::SrtmHgt, path))
    }
}

/// True when `bytes` could be a raw `.hgt`: the name ends in `.hgt` (any size:
/// the reader then explains a wrong one), or the size is that of a standard
/// 1201² or 3601² tile.
pub(crate) fn looks_like_hgt(bytes: &[u8], path: &Path) -> bool {
    let named_hgt = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("hgt"));
    named_hgt || matches!(side_for_len(bytes.len() as u64), Some(1201 | 3601))
}

/// Wraps a decoded SRTM grid.
fn dem(grid: HeightGrid, format: Format, path: &Path) -> Dem {
    Dem {
        grid,
        format,
        data_type: DataType::I16,
        nodata: Some(f64::from(VOID)),
        path: path.to_path_buf(),
    }
}

/// The final component of `path`, or "" when there is none.
fn file_name(path: &Path) -> Cow<'_, str> {
    path.file_name()
        .map(|n| n.to_string_lossy())
        .unwrap_or(Cow::Borrowed(""))
}

/// The side n of an n×n tile of `len` bytes (2·n² with n ≥ 2), if any.
fn side_for_len(len: u64) -> Option<u64> {
    if !len.is_multiple_of(2) {
        return None;
    }
    let samples = len / 2;
    let n = samples.isqrt();
    (n >= 2 && n * n == samples).then_some(n)
}

/// Decodes raw tile bytes. `names` are tried in order for the position;
/// `what` qualifies the data in error messages (e.g. " in member X").
fn decode_raw(
    data: &[u8],
    names: &[&str],
    what: &str,
    opts: &ReadOptions,
) -> Result<HeightGrid, ReadErrorKind> {
    let len = data.len() as u64;
    let n = side_for_len(len).ok_or_else(|| size_error(len, what))?;
    crate::limits::check(n, n, opts)?;
    let heights = be_i16_to_heights(data)?;
    let n = n as usize;
    let georef = names
        .iter()
        .find_map(|name| parse_corner(name))
        .map_or_else(|| unpositioned_georef(n), |c| tile_georef(c, n));
    Ok(HeightGrid::new(n, n, heights, georef)?)
}

/// Converts big-endian int16 samples to metres, voids to NaN.
fn be_i16_to_heights(data: &[u8]) -> Result<Vec<f32>, ReadErrorKind> {
    let (pairs, _) = data.as_chunks::<2>();
    let mut heights = crate::limits::try_vec(pairs.len(), "the tile's heights")?;
    heights.extend(pairs.iter().map(|&pair| match i16::from_be_bytes(pair) {
        VOID => f32::NAN,
        v => f32::from(v),
    }));
    Ok(heights)
}

/// The error for a byte count that is not 2·n².
fn size_error(len: u64, what: &str) -> ReadErrorKind {
    let n = u128::from((len / 2).isqrt());
    let (lo, hi) = (n.max(2), n.max(1) + 1);
    let nearest = if lo == hi {
        format!("{} for {hi}²", 2 * hi * hi)
    } else {
        format!("{} for {lo}², {} for {hi}²", 2 * lo * lo, 2 * hi * hi)
    };
    malformed(
        format!(
            "2·n² bytes of big-endian int16 for an n×n SRTM tile (1201² = 2884802 for 3\", \
             3601² = 25934402 for 1\"; nearest: {nearest})"
        ),
        format!("{len} bytes{what}"),
    )
}

/// The south-west corner (latitude, longitude) in whole degrees from a name
/// starting `[NS]dd[EW]ddd`, case-insensitive; `None` when absent or impossible.
fn parse_corner(name: &str) -> Option<(i32, i32)> {
    let head: [u8; 7] = name.as_bytes().get(..7)?.try_into().ok()?;
    let [ns, la1, la2, ew, lo1, lo2, lo3] = head;
    let lat_sign = match ns.to_ascii_uppercase() {
        b'N' => 1,
        b'S' => -1,
        _ => return None,
    };
    let lon_sign = match ew.to_ascii_uppercase() {
        b'E' => 1,
        b'W' => -1,
        _ => return None,
    };
    let lat = lat_sign * digits(&[la1, la2])?;
    let lon = lon_sign * digits(&[lo1, lo2, lo3])?;
    ((-90..=89).contains(&lat) && (-180..=179).contains(&lon)).then_some((lat, lon))
}

/// The decimal value of ASCII digits, `None` if any is not a digit.
fn digits(ds: &[u8]) -> Option<i32> {
    ds.iter().try_fold(0i32, |acc, &d| {
        d.is_ascii_digit().then(|| acc * 10 + i32::from(d - b'0'))
    })
}

/// The georeference of an n×n tile whose south-west corner is (`lat`, `lon`).
fn tile_georef((lat, lon): (i32, i32), n: usize) -> GeoRef {
    let step = 1.0 / (n as f64 - 1.0);
    GeoRef {
        crs: Crs::Epsg(4326),
        origin_x: f64::from(lon),
        origin_y: f64::from(lat) + 1.0,
        pixel_x: step,
        pixel_y: -step,
        pixel_is: PixelIs::Point,
        known: true,
    }
}

/// The placeholder georeference of an n×n tile without a position.
fn unpositioned_georef(n: usize) -> GeoRef {
    GeoRef::unreferenced(METRES_PER_DEGREE / (n as f64 - 1.0))
}

/// Decodes a ZIP holding one `.hgt` member.
fn decode_zip(
    bytes: &[u8],
    path: &Path,
    outer_name: &str,
    opts: &ReadOptions,
) -> Result<Dem, ReadErrorKind> {
    let mut archive = ZipArchive::new(Cursor::new(bytes)).map_err(|e| {
        malformed(
            "a ZIP archive holding one SRTM .hgt tile",
            format!("an unreadable ZIP archive ({e})"),
        )
    })?;
    let (index, member_name) = single_hgt_member(&archive)?;
    let data = read_member(&mut archive, index, &member_name, bytes.len() as u64, opts)?;
    let inner_name = member_name.rsplit('/').next().unwrap_or(&member_name);
    let what = format!(" in ZIP member {member_name}");
    let grid = decode_raw(&data, &[outer_name, inner_name], &what, opts)?;
    Ok(dem(grid, Format::SrtmHgtZip, path))
}

/// Index and name of the only member named `*.hgt`.
fn single_hgt_member<R: Read + std::io::Seek>(
    archive: &ZipArchive<R>,
) -> Result<(usize, String), ReadErrorKind> {
    let names: Vec<String> = (0..archive.len())
        .map(|i| {
            archive
                .name_for_index(i)
                .and_then(Result::ok)
                .map_or_else(String::new, |n| n.into_owned())
        })
        .collect();
    let mut hgt = names
        .iter()
        .enumerate()
        .filter(|(_, n)| n.to_ascii_lowercase().ends_with(".hgt"));
    match (hgt.next(), hgt.next()) {
        (Some((i, name)), None) => Ok((i, name.clone())),
        (None, _) => Err(malformed(
            "a ZIP archive holding one SRTM .hgt tile",
            format!("no .hgt member among {}", list_names(&names, "member")),
        )),
        (Some(_), Some(_)) => {
            let all: Vec<String> = names
                .iter()
                .filter(|n| n.to_ascii_lowercase().ends_with(".hgt"))
                .cloned()
                .collect();
            Err(malformed(
                "a ZIP archive holding one SRTM .hgt tile",
                list_names(&all, ".hgt member"),
            ))
        }
    }
}

/// "N members (\"a\", \"b\", …)" for a message.
fn list_names(names: &[String], what: &str) -> String {
    const SHOWN: usize = 5;
    let shown: Vec<String> = names.iter().take(SHOWN).map(|n| format!("{n:?}")).collect();
    let more = if names.len() > SHOWN { ", …" } else { "" };
    match names.len() {
        0 => format!("0 {what}s"),
        1 => format!("1 {what} ({}{more})", shown.join(", ")),
        n => format!("{n} {what}s ({}{more})", shown.join(", ")),
    }
}

/// Decompresses member `index` after checking its declared size.
fn read_member<R: Read + std::io::Seek>(
    archive: &mut ZipArchive<R>,
    index: usize,
    name: &str,
    archive_len: u64,
    opts: &ReadOptions,
) -> Result<Vec<u8>, ReadErrorKind> {
    let unreadable = |e: &dyn std::fmt::Display| {
        malformed(
            format!("ZIP member {name} to decompress"),
            format!("an error: {e}"),
        )
    };
    let mut member = archive.by_index(index).map_err(|e| unreadable(&e))?;
    let declared = member.size();
    let what = format!(" declared for ZIP member {name}");
    let n = side_for_len(declared).ok_or_else(|| size_error(declared, &what))?;
    crate::limits::check(n, n, opts)?;
    let possible = archive_len.saturating_mul(MAX_DEFLATE_RATIO);
    if declared > possible {
        return Err(malformed(
            format!("at most {possible} bytes from a ZIP archive of {archive_len} bytes"),
            format!("{declared} bytes{what}"),
        ));
    }
    let capacity = usize::try_from(declared).map_err(|_| size_error(declared, &what))?;
    let mut data = crate::limits::try_vec(capacity, &format!("ZIP member {name}"))?;
    (&mut member)
        .take(declared.saturating_add(1))
        .read_to_end(&mut data)
        .map_err(|e| unreadable(&e))?;
    if data.len() as u64 != declared {
        return Err(malformed(
            format!("{declared} bytes{what}"),
            format!("{} bytes after decompression", data.len()),
        ));
    }
    Ok(data)
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn sides() {
        assert_eq!(side_for_len(2 * 1201 * 1201), Some(1201));
        assert_eq!(side_for_len(8), Some(2));
        assert_eq!(side_for_len(2), None);
        assert_eq!(side_for_len(1000), None);
        assert_eq!(side_for_len(0), None);
    }

    #[test]
    fn corners() {
        assert_eq!(parse_corner("N00E010.hgt"), Some((0, 10)));
        assert_eq!(parse_corner("s29w072.hgt.zip"), Some((-29, -72)));
        assert_eq!(parse_corner("N49E011.SRTMGL1.hgt.zip"), Some((49, 11)));
        assert_eq!(parse_corner("N95E010.hgt"), None);
        assert_eq!(parse_corner("tile.hgt"), None);
        assert_eq!(parse_corner("N0"), None);
        assert_eq!(parse_corner("Né0E010"), None);
    }

    #[test]
    fn size_message() {
        let m = size_error(1000, "").to_string();
        assert!(m.contains("found 1000 bytes"), "{m}");
        assert!(m.contains("2884802"), "{m}");
        assert!(m.contains("968 for 22²"), "{m}");
        let m = size_error(u64::MAX, "").to_string();
        assert!(m.contains("found 18446744073709551615 bytes"), "{m}");
    }

    #[test]
    fn voids_and_sign() {
        let h = be_i16_to_heights(&[0x80, 0x00, 0xff, 0xfe, 0x01, 0x00]).unwrap();
        assert!(h[0].is_nan());
        assert_eq!(&h[1..], &[-2.0, 256.0]);
    }
}
