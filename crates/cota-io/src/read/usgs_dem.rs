//! USGS ASCII DEM (`.dem`): one type A header record and B profile records.
//!
//! # Format facts this reader relies on (USGS National Mapping Program
//! Technical Instructions, "Standards for Digital Elevation Models", Part 2)
//! * The file is ASCII in 1024-byte blocks (some copies have line breaks
//!   added). The type A record is the first block; its fields sit at fixed
//!   byte positions (1-based, inclusive): DEM level 145–150, pattern 151–156,
//!   planimetric reference system 157–162 (0 geographic, 1 UTM, 2 State
//!   Plane), zone 163–168, ground units 529–534 (0 radians, 1 feet, 2 metres,
//!   3 arc-seconds), elevation units 535–540 (1 feet, 2 metres), spatial
//!   resolution x, y, z 817–852 (three `E12.6`), rows and columns 853–864
//!   (two `I6`: 1 and the number of profiles), horizontal datum 891–896
//!   (1 NAD27, 2 WGS72, 3 WGS84, 4 NAD83; blank in old files). Reals use
//!   Fortran's `D` exponent.
//! * Each B record is one profile, a column running south to north: row and
//!   column numbers, the number of elevations m (and 1), the ground x and y of
//!   its first (southern) elevation, the local datum elevation, the profile's
//!   minimum and maximum, then m integers. A profile spans blocks; numbers are
//!   read as whitespace- or sign-separated tokens, so block padding and added
//!   line breaks do not matter. Profiles may start at different y (a UTM
//!   quadrangle is not a rectangle in UTM): the grid is their bounding box,
//!   samples outside every profile are voids.
//! * Height = value · z resolution + datum elevation, converted from feet
//!   where the elevation units say so. −32767 (and below) is a void.
//! * Georeference: arc-seconds become degrees (pixel-is-point) in the datum's
//!   geographic CRS; UTM metres become "UTM zone N". Other ground units are
//!   refused. Anything after the last profile (a type C record) is ignored.
//! * The number of profiles must be what the A record says.

use std::path::Path;

use cota_core::{Crs, GeoRef, HeightGrid, PixelIs};

use crate::dem::{DataType, Dem, Format, ReadOptions};
use crate::error::{malformed, ReadErrorKind};

/// The USGS void value (and everything below it).
const VOID: f64 = -32767.0;

/// Feet in metres.
const FOOT_M: f64 = 0.3048;

/// What the type A record says.
#[derive(Debug, Clone, PartialEq)]
struct HeaderA {
    ref_sys: i64,
    zone: i64,
    ground_units: i64,
    elev_units: i64,
    res: [f64; 3],
    profiles: u64,
    datum: i64,
}

/// One profile (a column from south to north).
struct Profile {
    x: f64,
    y: f64,
    values: Vec<f32>,
}

/// Text of the 1-based inclusive byte range `a..=b` of the A record.
fn field(bytes: &[u8], a: usize, b: usize) -> &str {
    bytes
        .get(a - 1..b)
        .and_then(|s| std::str::from_utf8(s).ok())
        .unwrap_or("")
        .trim()
}

/// An integer field (blank = None).
fn int(bytes: &[u8], a: usize, b: usize) -> Option<i64> {
    field(bytes, a, b).parse().ok()
}

/// A Fortran real (`D` or `E` exponent).
fn real(s: &str) -> Option<f64> {
    s.trim().replace(['D', 'd'], "E").parse().ok()
}

/// True when `bytes` open with a plausible type A record.
pub(crate) fn is_usgs_dem(bytes: &[u8]) -> bool {
    bytes.len() >= 1024
        && matches!(int(bytes, 145, 150), Some(1..=4))
        && int(bytes, 151, 156) == Some(1)
        && matches!(int(bytes, 157, 162), Some(0..=2))
        && matches!(int(bytes, 529, 534), Some(0..=3))
        && matches!(int(bytes, 535, 540), Some(1..=2))
}

/// Parses the type A record.
fn header(bytes: &[u8]) -> Result<HeaderA, ReadErrorKind> {
    let need = |v: Option<i64>, what: &str, a: usize, b: usize| {
        v.ok_or_else(|| {
            malformed(
                format!("{what} in bytes {a}-{b} of the type A record"),
                format!("{:?}", field(bytes, a, b)),
            )
        })
    };
    let res = [817, 829, 841].map(|a| real(field(bytes, a, a + 11)));
    let [Some(rx), Some(ry), Some(rz)] = res else {
        return Err(malformed(
            "three spatial resolutions (E12.6) in bytes 817-852 of the type A record",
            format!("{:?}", field(bytes, 817, 852)),
        ));
    };
    let profiles = need(int(bytes, 859, 864), "the number of profiles", 859, 864)?;
    Ok(HeaderA {
        ref_sys: need(int(bytes, 157, 162), "the reference system code", 157, 162)?,
        zone: int(bytes, 163, 168).unwrap_or(0),
        ground_units: need(int(bytes, 529, 534), "the ground units code", 529, 534)?,
        elev_units: need(int(bytes, 535, 540), "the elevation units code", 535, 540)?,
        res: [rx, ry, rz],
        profiles: u64::try_from(profiles).unwrap_or(0),
        datum: int(bytes, 891, 896).unwrap_or(0),
    })
}

/// Decodes a USGS ASCII DEM.
pub(crate) fn decode(bytes: &[u8], path: &Path, opts: &ReadOptions) -> Result<Dem, ReadErrorKind> {
    let a = header(bytes)?;
    if !(a.res[0] > 0.0 && a.res[1] > 0.0 && a.res[2] > 0.0) {
        return Err(malformed(
            "positive spatial resolutions in the type A record",
            format!("{:?}", a.res),
        ));
    }
    let crs = crs(&a)?;
    let profiles = read_profiles(&bytes[1024.min(bytes.len())..], &a)?;
    let grid = to_grid(&profiles, &a, crs, opts)?;
    Ok(Dem {
        grid,
        format: Format::UsgsDem,
        data_type: DataType::I32,
        nodata: Some(VOID),
        path: path.to_path_buf(),
    })
}

/// The CRS the reference system, units and datum name.
fn crs(a: &HeaderA) -> Result<Crs, ReadErrorKind> {
    match (a.ref_sys, a.ground_units) {
        (0, 3) => Ok(match a.datum {
            1 => Crs::Epsg(4267),
            2 => Crs::Epsg(4322),
            3 => Crs::WGS84,
            4 => Crs::Epsg(4269),
            _ => Crs::Geographic("NAD27 or NAD83 (USGS DEM without a datum code)".into()),
        }),
        (1, 2) => Ok(Crs::Projected(format!("UTM zone {}", a.zone))),
        (2, 2) => Ok(Crs::Projected(format!("State Plane zone {}", a.zone))),
        (r, u) => Err(ReadErrorKind::Unsupported {
            what: "USGS DEM ground units".into(),
            detail: format!(
                "reference system {r} with ground units code {u}; cota reads geographic arc-seconds (0, 3) and UTM or State Plane metres (1 or 2, 2)"
            ),
        }),
    }
}

/// Number tokens of the B records: whitespace- or sign-separated.
struct Tokens<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Tokens<'a> {
    /// The next token, or `None` at the end.
    fn next_token(&mut self) -> Option<&'a str> {
        let b = self.bytes;
        while self.pos < b.len() && b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        let start = self.pos;
        let mut i = start;
        while i < b.len() && !b[i].is_ascii_whitespace() {
            let sign = b[i] == b'-' || b[i] == b'+';
            let after_exp = i > start && matches!(b[i - 1], b'D' | b'd' | b'E' | b'e');
            if sign && i > start && !after_exp {
                break;
            }
            i += 1;
        }
        self.pos = i;
        (i > start).then(|| std::str::from_utf8(&b[start..i]).unwrap_or("?"))
    }

    /// The next token as a real, or an error naming `what`.
    fn real(&mut self, what: &str, profile: u64) -> Result<f64, ReadErrorKind> {
        let t = self.next_token();
        t.and_then(real).ok_or_else(|| {
            malformed(
                format!("{what} of profile {} (a number)", profile + 1),
                t.map_or("the end of the file".to_string(), |t| format!("{t:?}")),
            )
        })
    }
}

/// Reads the B records the A record announces.
fn read_profiles(body: &[u8], a: &HeaderA) -> Result<Vec<Profile>, ReadErrorKind> {
    // Every profile takes at least one 1024-byte block (or, with line breaks
    // and trimmed padding, some 60 bytes): refuse a count the file cannot hold.
    if a.profiles == 0 || a.profiles > body.len() as u64 / 16 + 1 {
        return Err(malformed(
            format!(
                "a number of profiles the file can hold (it has {} bytes after the A record)",
                body.len()
            ),
            format!("{} profiles in the type A record", a.profiles),
        ));
    }
    let mut t = Tokens {
        bytes: body,
        pos: 0,
    };
    let mut out = Vec::with_capacity(a.profiles as usize);
    for p in 0..a.profiles {
        let Some(profile) = read_profile(&mut t, p, a)? else {
            return Err(malformed(
                format!(
                    "{} profiles (type B records), as the type A record says",
                    a.profiles
                ),
                format!("{p}"),
            ));
        };
        out.push(profile);
    }
    Ok(out)
}

/// Reads profile `p`; `None` when the data ends before it.
fn read_profile(t: &mut Tokens, p: u64, a: &HeaderA) -> Result<Option<Profile>, ReadErrorKind> {
    let Some(first) = t.next_token() else {
        return Ok(None);
    };
    if first.parse::<i64>().is_err() {
        return Ok(None);
    }
    let _col = t.real("the column number", p)?;
    let m = t.real("the number of elevations", p)?;
    let _n = t.real("the number of columns", p)?;
    let (x, y) = (
        t.real("the x of the first elevation", p)?,
        t.real("the y", p)?,
    );
    let datum = t.real("the datum elevation", p)?;
    let _min = t.real("the minimum elevation", p)?;
    let _max = t.real("the maximum elevation", p)?;
    let remaining = (t.bytes.len() - t.pos) as f64 / 2.0 + 1.0;
    if !(m >= 1.0 && m <= remaining) {
        return Err(malformed(
            format!(
                "a number of elevations in profile {} that the file can hold",
                p + 1
            ),
            format!("{m}"),
        ));
    }
    let unit = if a.elev_units == 1 { FOOT_M } else { 1.0 };
    let mut values = Vec::with_capacity(m as usize);
    for _ in 0..m as usize {
        let v = t.real("an elevation", p)?;
        values.push(if v <= VOID {
            f32::NAN
        } else {
            ((v * a.res[2] + datum) * unit) as f32
        });
    }
    Ok(Some(Profile { x, y, values }))
}

/// The grid of the profiles: their bounding box, voids where none reaches.
fn to_grid(
    profiles: &[Profile],
    a: &HeaderA,
    crs: Crs,
    opts: &ReadOptions,
) -> Result<HeightGrid, ReadErrorKind> {
    let [dx, dy, _] = a.res;
    let y0 = profiles.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
    let start_row = |p: &Profile| ((p.y - y0) / dy).round() as u64;
    let rows = profiles
        .iter()
        .map(|p| start_row(p).saturating_add(p.values.len() as u64))
        .max()
        .unwrap_or(1);
    let cols = profiles.len();
    crate::limits::check(cols as u64, rows, opts)?;
    check_fill(profiles, cols as u64 * rows)?;
    let (rows, x0) = (rows as usize, profiles.first().map_or(0.0, |p| p.x));
    let mut heights = vec![f32::NAN; rows * cols];
    for (c, p) in profiles.iter().enumerate() {
        let s = start_row(p) as usize;
        for (k, v) in p.values.iter().enumerate() {
            // k counts north from the profile's start; row 0 is the northern row.
            heights[(rows - 1 - (s + k)) * cols + c] = *v;
        }
    }
    let scale = if a.ground_units == 3 {
        1.0 / 3600.0
    } else {
        1.0
    };
    let georef = GeoRef {
        crs,
        origin_x: x0 * scale,
        origin_y: (y0 + (rows as f64 - 1.0) * dy) * scale,
        pixel_x: dx * scale,
        pixel_y: -dy * scale,
        pixel_is: PixelIs::Point,
        known: true,
    };
    Ok(HeightGrid::new(cols, rows, heights, georef)?)
}

/// Grid samples the profiles may leave void beyond [`FREE_SAMPLES`], per
/// elevation they hold. A real DEM's profiles fill most of their bounding box
/// (a 7.5-minute quad in UTM is skewed by a few degrees; a 1-degree DEM is
/// full).
const SAMPLES_PER_ELEVATION: u64 = 64;

/// Samples any grid may have, however few elevations fill it.
const FREE_SAMPLES: u64 = 1 << 24;

/// Refuses profiles placed so far apart that a few elevations span a huge
/// grid of voids (found by the fuzzer: a profile whose `y` lies millions of
/// rows above the others made a small file allocate gigabytes).
fn check_fill(profiles: &[Profile], samples: u64) -> Result<(), ReadErrorKind> {
    let elevations: u64 = profiles.iter().map(|p| p.values.len() as u64).sum();
    let allowed = FREE_SAMPLES.max(SAMPLES_PER_ELEVATION.saturating_mul(elevations));
    if samples <= allowed {
        return Ok(());
    }
    Err(malformed(
        format!(
            "profiles that fill their grid (at most {SAMPLES_PER_ELEVATION} grid samples per elevation, {FREE_SAMPLES} at least)"
        ),
        format!(
            "{elevations} elevations spread over {samples} samples: the profiles' x and y are far apart"
        ),
    ))
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn tokens_split_on_signs() {
        let mut t = Tokens {
            bytes: b"  1 -32767-32767 0.5D+03-1\n 7",
            pos: 0,
        };
        let all: Vec<&str> = std::iter::from_fn(|| t.next_token()).collect();
        assert_eq!(all, ["1", "-32767", "-32767", "0.5D+03", "-1", "7"]);
        assert_eq!(real("0.5D+03"), Some(500.0));
    }
}
