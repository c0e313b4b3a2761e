//! EPSG codes: their PROJ definitions and their names.
//!
//! References: the EPSG Geodetic Parameter Dataset (<https://epsg.org>) for
//! the codes and names; the definitions are the PROJ strings of the
//! `crs-definitions` crate (EPSG codes up to 65535), except for Web Mercator
//! (EPSG:3857 and its older codes 900913, 3785, ESRI 102100 and 102113),
//! defined here the way PROJ 4 did: WGS 84 longitude/latitude projected with
//! the spherical Mercator formulas on a sphere of radius 6 378 137 m, the
//! `+nadgrids=@null` null grid saying that the sphere's longitudes and
//! latitudes are WGS 84's (no datum shift). PROJ today writes the same map
//! as `+proj=webmerc +ellps=WGS84`, which proj4rs does not have.
//!
//! Names: crs-definitions carries them only inside its WKT, which cota does
//! not build (about 4 MB); the families of codes and the common codes below
//! give theirs, other codes are shown by number.

/// Web Mercator as a PROJ 4 string (module docs).
pub const WEB_MERCATOR: &str = "+proj=merc +a=6378137 +b=6378137 +lat_ts=0 +lon_0=0 +x_0=0 +y_0=0 +k=1 +units=m +nadgrids=@null +no_defs";

/// The codes of Web Mercator: EPSG:3857, the unofficial 900913, the
/// deprecated EPSG:3785 and ESRI's 102100 and 102113.
const WEB_MERCATOR_CODES: [u32; 5] = [3857, 900_913, 3785, 102_100, 102_113];

/// True for the codes of Web Mercator.
pub fn is_web_mercator(code: u32) -> bool {
    WEB_MERCATOR_CODES.contains(&code)
}

/// The PROJ definition of an EPSG code, or `None` for a code cota has none for.
pub fn definition(code: u32) -> Option<&'static str> {
    if is_web_mercator(code) {
        return Some(WEB_MERCATOR);
    }
    let code = u16::try_from(code).ok()?;
    crs_definitions::from_code(code).map(|d| d.proj4)
}

/// Names of common codes outside the families of [`family_name`].
const NAMES: &[(u32, &str)] = &[
    (2154, "RGF93 v1 / Lambert-93"),
    (2193, "NZGD2000 / New Zealand Transverse Mercator 2000"),
    (2056, "CH1903+ / LV95"),
    (3035, "ETRS89-extended / LAEA Europe"),
    (3347, "NAD83 / Statistics Canada Lambert"),
    (3395, "WGS 84 / World Mercator"),
    (3577, "GDA94 / Australian Albers"),
    (3785, "Popular Visualisation CRS / Mercator (deprecated)"),
    (3857, "WGS 84 / Pseudo-Mercator"),
    (3978, "NAD83 / Canada Atlas Lambert"),
    (4167, "NZGD2000"),
    (4171, "RGF93 v1"),
    (4258, "ETRS89"),
    (4267, "NAD27"),
    (4269, "NAD83"),
    (4277, "OSGB36"),
    (4283, "GDA94"),
    (4326, "WGS 84"),
    (4674, "SIRGAS 2000"),
    (5070, "NAD83 / Conus Albers"),
    (7844, "GDA2020"),
    (27700, "OSGB36 / British National Grid"),
    (28992, "Amersfoort / RD New"),
    (
        900_913,
        "Google Maps Global Mercator (WGS 84 / Pseudo-Mercator)",
    ),
    (102_100, "ESRI: WGS 84 / Web Mercator (auxiliary sphere)"),
    (102_113, "ESRI: WGS 84 / Web Mercator"),
];

/// The name of an EPSG code, where cota knows it.
pub fn name(code: u32) -> Option<String> {
    NAMES
        .iter()
        .find(|(c, _)| *c == code)
        .map(|(_, n)| (*n).to_string())
        .or_else(|| family_name(code))
}

/// Names of the numbered families: UTM zones on WGS 84, NAD83, ETRS89 and
/// SIRGAS 2000, and GDA94/GDA2020's MGA zones.
fn family_name(code: u32) -> Option<String> {
    let utm = |datum: &str, zone: u32, hemisphere: char| {
        Some(format!("{datum} / UTM zone {zone}{hemisphere}"))
    };
    match code {
        32601..=32660 => utm("WGS 84", code - 32600, 'N'),
        32701..=32760 => utm("WGS 84", code - 32700, 'S'),
        26901..=26923 => utm("NAD83", code - 26900, 'N'),
        25828..=25838 => utm("ETRS89", code - 25800, 'N'),
        31965..=31976 => utm("SIRGAS 2000", code - 31954, 'N'),
        31977..=31985 => utm("SIRGAS 2000", code - 31960, 'S'),
        6210 | 6211 => utm("SIRGAS 2000", code - 6187, 'N'),
        28348..=28358 => Some(format!("GDA94 / MGA zone {}", code - 28300)),
        7846..=7859 => Some(format!("GDA2020 / MGA zone {}", code - 7800)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_definitions() {
        assert_eq!(name(32633).as_deref(), Some("WGS 84 / UTM zone 33N"));
        assert_eq!(name(32725).as_deref(), Some("WGS 84 / UTM zone 25S"));
        assert_eq!(name(26916).as_deref(), Some("NAD83 / UTM zone 16N"));
        assert_eq!(name(31985).as_deref(), Some("SIRGAS 2000 / UTM zone 25S"));
        assert_eq!(name(6210).as_deref(), Some("SIRGAS 2000 / UTM zone 23N"));
        assert_eq!(name(28355).as_deref(), Some("GDA94 / MGA zone 55"));
        assert_eq!(
            name(27700).as_deref(),
            Some("OSGB36 / British National Grid")
        );
        assert_eq!(name(12345), None);
        assert_eq!(definition(900_913), Some(WEB_MERCATOR));
        assert_eq!(
            definition(32633),
            Some("+proj=utm +zone=33 +datum=WGS84 +units=m +no_defs")
        );
        assert_eq!(definition(1), None);
        assert_eq!(definition(70_000), None);
    }
}
