//! When an image and a DEM count as being in the same CRS.
//!
//! cota does not reproject. An image is draped on a DEM only when both are
//! in the same CRS, by this rule:
//! 1. the two CRSs are identical (same EPSG code, or the same description);
//! 2. or they have the **same projection** (the same UTM zone and
//!    hemisphere, or both geographic longitude/latitude) on **datums that
//!    agree to well under a metre**: WGS 84, SIRGAS 2000, and a datum the
//!    file leaves unstated on the GRS 1980 ellipsoid (GDAL's
//!    "Datum = unknown; Ellipsoid = GRS80"). SIRGAS 2000 is ITRF2000 at epoch
//!    2000.4 and WGS 84's realisations since G1150 follow the ITRF to a few
//!    centimetres, so the two differ by the plate's drift since 2000, a few
//!    decimetres; GRS 1980 and WGS 84's ellipsoids differ by 0.1 mm. cota
//!    takes the difference as at most [`DATUM_AGREEMENT_M`] = 1 m and
//!    accepts it only when that is at most a tenth of the image's pixel
//!    (so at most 0.1 pixel of misregistration). ETRS89 (now about 0.9 m
//!    from WGS 84 and growing), NAD83 (1–2 m), SAD69, Córrego Alegre and the
//!    like do not qualify;
//! 3. or the image carries no CRS (a PNG or JPEG with a world file, or
//!    stretched over the DEM's extent): it is taken to be in the DEM's.
//!
//! A CRS given by PROJ parameters ([`Crs::Proj`], e.g. a GeoTIFF's
//! user-defined projection) is read the same way: `+proj=utm +zone=N
//! [+south]` or longitude/latitude; `+datum=WGS84` (or the WGS 84 ellipsoid)
//! and the GRS 1980 ellipsoid with no datum and a zero or no `+towgs84`
//! (the "unstated" datum above).
//!
//! Anything else is refused with both CRSs named; `assume_same` (the CLI's
//! `--assume-same-crs`) overrides the refusal for CRSs the rule cannot
//! recognise as equal.
//!
//! The shared pair: the DEM's GeoKeys give "UTM Zone 25, Southern
//! Hemisphere" on a user-defined GRS 1980 geographic CRS with datum
//! "unknown"; the image is EPSG:31985, SIRGAS 2000 / UTM zone 25S, with
//! 28.5 m pixels. Same zone, datums within 1 m ≤ 2.85 m: the same CRS.

use cota_core::Crs;

use crate::crs::params::ProjParams;

/// The largest difference between the datums rule 2 accepts, metres.
pub const DATUM_AGREEMENT_M: f64 = 1.0;

/// The projection of a CRS, as far as the rule needs it.
#[derive(Debug, Clone, PartialEq)]
enum Projection {
    Utm { zone: u32, south: bool },
    Geographic,
    Other,
}

/// The datum of a CRS, as far as the rule needs it.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Datum {
    Wgs84,
    Sirgas2000,
    Grs80Unstated,
    Other,
}

impl Datum {
    /// Whether this datum is one of rule 2's.
    fn itrf_aligned(self) -> bool {
        matches!(
            self,
            Datum::Wgs84 | Datum::Sirgas2000 | Datum::Grs80Unstated
        )
    }
}

/// The projection and datum of an EPSG code cota knows.
fn epsg_parts(code: u32) -> (Projection, Datum) {
    let utm = |zone: u32, south: bool| Projection::Utm { zone, south };
    match code {
        4326 => (Projection::Geographic, Datum::Wgs84),
        4674 => (Projection::Geographic, Datum::Sirgas2000),
        32601..=32660 => (utm(code - 32600, false), Datum::Wgs84),
        32701..=32760 => (utm(code - 32700, true), Datum::Wgs84),
        31965..=31976 => (utm(code - 31954, false), Datum::Sirgas2000),
        31977..=31985 => (utm(code - 31960, true), Datum::Sirgas2000),
        6210 | 6211 => (utm(code - 6187, false), Datum::Sirgas2000),
        _ => (Projection::Other, Datum::Other),
    }
}

/// The projection and datum a description names ("UTM Zone 25, Southern
/// Hemisphere; GCS Name = GRS 1980(IUGG, 1980); Datum = unknown; …",
/// "WGS 84 / UTM zone 33N").
fn text_parts(text: &str) -> (Projection, Datum) {
    let t = text.to_ascii_lowercase();
    let projection = match t.find("utm zone") {
        Some(at) => utm_from(&t[at + "utm zone".len()..]),
        None if t.contains("longitude") || t.contains("geographic") => Projection::Geographic,
        None => Projection::Other,
    };
    let datum = if t.contains("sirgas") {
        Datum::Sirgas2000
    } else if t.contains("wgs 84") || t.contains("wgs84") || t.contains("wgs_1984") {
        Datum::Wgs84
    } else if (t.contains("grs 1980") || t.contains("grs80")) && !t.contains("nad83") {
        Datum::Grs80Unstated
    } else {
        Datum::Other
    };
    (projection, datum)
}

/// The zone and hemisphere after "utm zone": " 25S", " 25, southern hemisphere".
fn utm_from(rest: &str) -> Projection {
    let rest = rest.trim_start();
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    let Ok(zone) = digits.parse::<u32>() else {
        return Projection::Other;
    };
    let after = rest[digits.len()..].trim_start();
    let south = match after.chars().next() {
        Some('s') => true,
        Some('n') => false,
        _ if after.contains("southern") => true,
        _ if after.contains("northern") => false,
        _ => return Projection::Other,
    };
    if (1..=60).contains(&zone) {
        Projection::Utm { zone, south }
    } else {
        Projection::Other
    }
}

fn parts(crs: &Crs) -> (Projection, Datum) {
    match crs {
        Crs::Epsg(code) => epsg_parts(*code),
        Crs::Geographic(s) => (Projection::Geographic, text_parts(s).1),
        Crs::Projected(s) => text_parts(s),
        Crs::Proj(def) => proj_parts(def),
        _ => (Projection::Other, Datum::Other),
    }
}

/// The projection and datum of a PROJ definition (module docs).
fn proj_parts(def: &str) -> (Projection, Datum) {
    let Some(p) = ProjParams::parse(def) else {
        return (Projection::Other, Datum::Other);
    };
    let zone = p.get("zone").and_then(|z| z.parse::<u32>().ok());
    let projection = match (p.proj(), zone) {
        (Some("utm"), Some(zone)) if (1..=60).contains(&zone) => Projection::Utm {
            zone,
            south: p.has("south"),
        },
        _ if p.is_geographic() => Projection::Geographic,
        _ => Projection::Other,
    };
    let no_shift = p.towgs84().is_none_or(|t| t.iter().all(|v| *v == 0.0)) && !p.has("nadgrids");
    let ellps = p.get("ellps");
    let datum = match p.get("datum") {
        Some(d) if d.eq_ignore_ascii_case("wgs84") => Datum::Wgs84,
        Some(_) => Datum::Other,
        None if no_shift && ellps == Some("WGS84") => Datum::Wgs84,
        None if no_shift && ellps == Some("GRS80") => Datum::Grs80Unstated,
        None => Datum::Other,
    };
    (projection, datum)
}

/// Whether an image in `image` may be draped on a DEM in `dem` (module
/// docs); `image_pixel_m` is the image's pixel size in metres. `Ok` holds
/// the rule that applied, for reports; `Err` says why not.
pub fn same_crs(
    dem: &Crs,
    image: &Crs,
    image_pixel_m: f64,
    assume_same: bool,
) -> Result<String, String> {
    if dem == image {
        return Ok(format!("identical ({dem})"));
    }
    if *image == Crs::Unknown {
        return Ok(format!("the image has no CRS: taken as the DEM's ({dem})"));
    }
    let ((pd, dd), (pi, di)) = (parts(dem), parts(image));
    let same_projection = pd == pi && pd != Projection::Other;
    if same_projection && dd.itrf_aligned() && di.itrf_aligned() {
        if DATUM_AGREEMENT_M <= 0.1 * image_pixel_m {
            return Ok(format!(
                "same projection, datums within {DATUM_AGREEMENT_M} m (at most a tenth of the image's {image_pixel_m:.3} m pixel)"
            ));
        }
        if !assume_same {
            return Err(format!(
                "the same projection, but datums that may differ by up to {DATUM_AGREEMENT_M} m, more than a tenth of the image's {image_pixel_m:.3} m pixel; reproject one of them, or pass --assume-same-crs"
            ));
        }
    }
    if assume_same {
        return Ok("assumed the same (--assume-same-crs)".to_string());
    }
    Err(if *dem == Crs::Unknown {
        "the DEM has no CRS to compare with; pass --assume-same-crs if they are the same"
            .to_string()
    } else {
        "cota does not reproject: give the image in the DEM's CRS, or pass --assume-same-crs if they are the same".to_string()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const DEM: &str = "UTM Zone 25, Southern Hemisphere; GCS Name = GRS 1980(IUGG, 1980); Datum = unknown; Ellipsoid = GRS80; Primem = Greenwich";

    #[test]
    fn the_shared_pair_is_the_same_crs() {
        let dem = Crs::Projected(DEM.into());
        assert!(same_crs(&dem, &Crs::Epsg(31985), 28.5, false).is_ok());
        assert!(same_crs(&dem, &Crs::Epsg(32725), 28.5, false).is_ok());
        assert!(same_crs(&Crs::Epsg(32725), &Crs::Epsg(31985), 28.5, false).is_ok());
        // Another zone, another hemisphere, a far datum: refused.
        for other in [32724, 32625, 29195, 25833] {
            let e = same_crs(&dem, &Crs::Epsg(other), 28.5, false).unwrap_err();
            assert!(e.contains("does not reproject"), "{e}");
        }
        // A 0.5 m orthophoto: 1 m of datum doubt is too much.
        assert!(same_crs(&dem, &Crs::Epsg(31985), 0.5, false).is_err());
        assert!(same_crs(&dem, &Crs::Epsg(31985), 0.5, true).is_ok());
        assert!(same_crs(
            &Crs::Projected("UTM Zone 25, Southern Hemisphere".into()),
            &Crs::Epsg(31985),
            28.5,
            false
        )
        .is_err());
    }

    #[test]
    fn descriptions_parse() {
        assert_eq!(
            utm_from(" 33n"),
            Projection::Utm {
                zone: 33,
                south: false
            }
        );
        assert_eq!(
            utm_from("25, southern hemisphere"),
            Projection::Utm {
                zone: 25,
                south: true
            }
        );
        assert_eq!(
            text_parts("WGS 84 / UTM zone 19S"),
            (
                Projection::Utm {
                    zone: 19,
                    south: true
                },
                Datum::Wgs84
            )
        );
        assert_eq!(
            epsg_parts(31985),
            (
                Projection::Utm {
                    zone: 25,
                    south: true
                },
                Datum::Sirgas2000
            )
        );
        assert_eq!(
            epsg_parts(31965).0,
            Projection::Utm {
                zone: 11,
                south: false
            }
        );
        assert_eq!(
            epsg_parts(31977).0,
            Projection::Utm {
                zone: 17,
                south: true
            }
        );
        let own = Crs::Proj(
            "+proj=utm +zone=25 +south +ellps=GRS80 +towgs84=0,0,0 +units=m +no_defs +title=\"UTM 25S\"".into(),
        );
        assert!(same_crs(&own, &Crs::Epsg(31985), 28.5, false).is_ok());
        assert!(same_crs(&own, &Crs::Epsg(32724), 28.5, false).is_err());
        assert_eq!(
            proj_parts("+proj=utm +zone=33 +datum=WGS84"),
            (
                Projection::Utm {
                    zone: 33,
                    south: false
                },
                Datum::Wgs84
            )
        );
        assert_eq!(
            proj_parts("+proj=longlat +ellps=intl +towgs84=-87,-98,-121").1,
            Datum::Other
        );
        assert!(same_crs(&Crs::Unknown, &Crs::Unknown, 30.0, false).is_ok());
        assert!(same_crs(&Crs::Epsg(4326), &Crs::Unknown, 30.0, false).is_ok());
        assert!(same_crs(&Crs::Unknown, &Crs::Epsg(4326), 30.0, false).is_err());
    }
}
