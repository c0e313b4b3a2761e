//! SRTM tiles: n×n big-endian `i16`, −32768 a void, the position in the name
//! (`[NS]dd[EW]ddd`), optionally the one `.hgt` member of a ZIP archive.

use std::io::Read;

use crate::{Place, Samples};

/// A raw `.hgt` tile named `name`.
pub(crate) fn from_hgt(bytes: &[u8], name: &str) -> Result<Samples, String> {
    let n = (bytes.len() / 2).isqrt();
    if n < 2 || 2 * n * n != bytes.len() {
        return Err(format!(
            "expected 2·n² bytes of an SRTM tile, found {}",
            bytes.len()
        ));
    }
    let heights = bytes
        .chunks_exact(2)
        .map(|p| match i16::from_be_bytes([p[0], p[1]]) {
            -32768 => f32::NAN,
            v => f32::from(v),
        })
        .collect();
    Ok(Samples {
        width: n,
        height: n,
        heights,
        place: corner(name).map_or(Place::Unknown, |(lat, lon)| Place::Srtm { lat, lon }),
    })
}

/// A `.hgt.zip` archive named `name` holding one `.hgt` member.
pub(crate) fn from_zip(bytes: &[u8], name: &str) -> Result<Samples, String> {
    let mut archive =
        zip::ZipArchive::new(std::io::Cursor::new(bytes)).map_err(|e| e.to_string())?;
    let member = (0..archive.len())
        .find(|&i| {
            archive
                .name_for_index(i)
                .and_then(|n| n.ok())
                .is_some_and(|n| n.to_ascii_lowercase().ends_with(".hgt"))
        })
        .ok_or_else(|| "expected a .hgt member in the ZIP archive, found none".to_string())?;
    let mut file = archive.by_index(member).map_err(|e| e.to_string())?;
    let inner = file.name().map_err(|e| e.to_string())?.to_ascii_lowercase();
    let mut data = Vec::new();
    file.read_to_end(&mut data).map_err(|e| e.to_string())?;
    let mut s = from_hgt(&data, &inner)?;
    if let Some((lat, lon)) = corner(name) {
        s.place = Place::Srtm { lat, lon };
    }
    Ok(s)
}

/// The south-west corner (latitude, longitude) from a name starting
/// `[NS]dd[EW]ddd`, case-insensitive.
fn corner(name: &str) -> Option<(i32, i32)> {
    let b = name.rsplit('/').next()?.as_bytes();
    if b.len() < 7 {
        return None;
    }
    let num = |s: &[u8]| std::str::from_utf8(s).ok()?.parse::<i32>().ok();
    let lat = match b[0].to_ascii_uppercase() {
        b'N' => num(&b[1..3])?,
        b'S' => -num(&b[1..3])?,
        _ => return None,
    };
    let lon = match b[3].to_ascii_uppercase() {
        b'E' => num(&b[4..7])?,
        b'W' => -num(&b[4..7])?,
        _ => return None,
    };
    ((-90..90).contains(&lat) && (-180..180).contains(&lon)).then_some((lat, lon))
}
