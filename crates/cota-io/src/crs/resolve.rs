//! From a [`Crs`] to its map to WGS 84 longitude/latitude ([`transform_for`]),
//! and a CRS's name for reports ([`describe`]).
//!
//! References: PROJ's parameters `+datum`, `+towgs84`, `+nadgrids`
//! (<https://proj.org/usage/transformations.html>), the EPSG dataset for
//! which datums are realisations of the ITRF (<https://epsg.org>).
//!
//! The rules, in order:
//! 1. [`Crs::Unknown`]: refused ([`CrsError::Unknown`]).
//! 2. [`Crs::Epsg`]: its PROJ definition ([`super::epsg::definition`]), then 4.
//! 3. [`Crs::Geographic`] (a description only): the identity, unless the
//!    description names a datum far from WGS 84 (NAD27, ED50, OSGB36, Tokyo,
//!    Pulkovo, SAD69, …), which is refused.
//!    [`Crs::Projected`] (a description only): refused.
//! 4. A PROJ definition ([`Crs::Proj`], or an EPSG code's):
//!    * grid shifts (`+nadgrids=` other than `@null`, `+datum=NAD27`) are
//!      refused ([`CrsError::GridShift`]);
//!    * a datum on an ellipsoid other than WGS 84's or GRS 1980's with no
//!      `+datum`, `+towgs84` or `+nadgrids=@null` is refused
//!      ([`CrsError::NoDatumShift`]): PROJ 4 would apply no shift at all;
//!    * longitude/latitude on WGS 84 or a datum taken as WGS 84 (below) is
//!      the identity [`LonLat`];
//!    * anything else is a [`ProjTransform`] (proj4rs), `+towgs84` Helmert
//!      included.
//!
//! **Datums taken as WGS 84.** WGS 84, and the datums on the GRS 1980
//! ellipsoid defined as zero shifts from it (`+datum=NAD83`,
//! `+towgs84=0,0,0`, no shift at all on GRS 1980): NAD83 (EPSG:4269),
//! ETRS89 (4258), GDA94 (4283), GDA2020 (7844), SIRGAS 2000 (4674),
//! NZGD2000 (4167), RGF93 (4171) and the like. Each is a realisation of the
//! ITRF at some epoch, fixed to its plate, so it and today's WGS 84 differ by
//! the plate's drift since then: under a metre for ETRS89, GDA2020 and
//! SIRGAS, about 1–2 m for NAD83 and GDA94. cota ignores this difference, as
//! PROJ does when it has no better transformation (its null "ballpark"
//! transformations, and the zero `+towgs84` of these definitions). Grid and
//! time-dependent transformations are out of scope.

use cota_core::{Crs, GeoTransform, LonLat};

use super::epsg;
use super::error::CrsError;
use super::params::{is_wgs84_like_ellipsoid, ProjParams};
use super::project::ProjTransform;

/// How far, in metres, a point may end from where it started after the map
/// to WGS 84 and back, for a CRS without a datum shift. Projections invert
/// to about 1e-9 m, except for iterative inverses: proj4rs's Lambert
/// conformal conic latitude (PROJ 4's `pj_phi2`, to 1e-10 rad) comes back
/// 1.7e-6 m off on Lambert-93's western edge.
pub const ROUND_TRIP_TOLERANCE_M: f64 = 1e-5;

/// The same for a CRS with a Helmert datum shift, metres. PROJ and
/// proj4rs map 2-D points at height 0 on either side, so a round trip
/// through the shift starts back at another height and ends where the
/// Helmert's scale and rotations move that height difference: 1.3 mm for
/// OSGB36 (EPSG:27700). Projections that cannot be inverted miss by metres.
pub const HELMERT_ROUND_TRIP_TOLERANCE_M: f64 = 0.01;

/// Metres per degree of latitude, roughly, for a tolerance in degrees.
const M_PER_DEGREE: f64 = 111_000.0;

/// The map between `crs` and WGS 84 longitude/latitude (module docs).
///
/// ```
/// use cota_core::Crs;
/// let utm = cota_io::crs::transform_for(&Crs::Epsg(32633)).unwrap();
/// let [lon, lat] = utm.to_lonlat(500_000.0, 0.0).unwrap();
/// assert!((lon - 15.0).abs() < 1e-12 && lat.abs() < 1e-12);
/// assert!(cota_io::crs::transform_for(&Crs::Epsg(4269)).unwrap().is_identity());
/// assert!(cota_io::crs::transform_for(&Crs::Unknown).is_err());
/// ```
///
/// # Errors
/// A [`CrsError`] saying what is missing (module docs).
pub fn transform_for(crs: &Crs) -> Result<Box<dyn GeoTransform>, CrsError> {
    transform_and_tolerance(crs).map(|(t, _)| t)
}

/// [`transform_for`], with the round-trip tolerance of the CRS in its own
/// units: [`ROUND_TRIP_TOLERANCE_M`], or [`HELMERT_ROUND_TRIP_TOLERANCE_M`]
/// when it shifts the datum, in metres for projected CRSs (or the CRS's
/// unit, e.g. US feet) and as degrees of latitude (111 km each) for
/// geographic ones.
///
/// # Errors
/// As [`transform_for`].
pub fn transform_and_tolerance(crs: &Crs) -> Result<(Box<dyn GeoTransform>, f64), CrsError> {
    let plain = |t: Box<dyn GeoTransform>| (t, ROUND_TRIP_TOLERANCE_M / M_PER_DEGREE);
    match crs {
        Crs::Unknown => Err(CrsError::Unknown),
        Crs::Epsg(code) => {
            let def = epsg::definition(*code).ok_or(CrsError::UnknownEpsg { code: *code })?;
            for_definition(&describe(crs), def)
        }
        Crs::Proj(def) => for_definition(&describe(crs), def),
        Crs::Geographic(text) => match far_datum(text) {
            None => Ok(plain(Box::new(LonLat))),
            Some(named) => Err(CrsError::DescriptionOnly {
                crs: text.clone(),
                why: format!(
                    "; it names {named}, a datum that may lie hundreds of metres from WGS 84"
                ),
            }),
        },
        Crs::Projected(text) => Err(CrsError::DescriptionOnly {
            crs: text.clone(),
            why: String::new(),
        }),
        other => Err(CrsError::DescriptionOnly {
            crs: other.to_string(),
            why: String::new(),
        }),
    }
}

/// The CRS for reports: `EPSG:27700 (OSGB36 / British National Grid)`, a
/// PROJ string's title and definition, or the description.
pub fn describe(crs: &Crs) -> String {
    match crs {
        Crs::Epsg(code) => match epsg::name(*code) {
            Some(name) => format!("EPSG:{code} ({name})"),
            None => format!("EPSG:{code}"),
        },
        Crs::Proj(def) => match ProjParams::parse(def) {
            Some(p) => match p.title() {
                Some(t) => format!("{t} ({})", p.without_title()),
                None => p.without_title(),
            },
            None => def.clone(),
        },
        other => other.to_string(),
    }
}

/// The PROJ string a CRS is mapped by: an EPSG code's definition, or a
/// [`Crs::Proj`] without its title; `None` for other CRSs.
pub fn definition(crs: &Crs) -> Option<String> {
    match crs {
        Crs::Epsg(code) => epsg::definition(*code).map(str::to_string),
        Crs::Proj(def) => {
            Some(ProjParams::parse(def).map_or_else(|| def.clone(), |p| p.without_title()))
        }
        _ => None,
    }
}

/// Whether a PROJ definition's longitudes and latitudes are taken as WGS
/// 84's, and if not why.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Datum {
    /// WGS 84 or a datum taken as WGS 84 (module docs).
    Wgs84Like,
    /// A Helmert shift (or a zero shift on another ellipsoid).
    Shifted,
}

/// The map of a PROJ definition (module docs, rule 4) and its round-trip
/// tolerance.
fn for_definition(label: &str, def: &str) -> Result<(Box<dyn GeoTransform>, f64), CrsError> {
    let params = ProjParams::parse(def).ok_or_else(|| CrsError::BadProj {
        definition: def.to_string(),
        reason: "expected +key=value parameters separated by blanks".to_string(),
    })?;
    refuse_grids(label, &params)?;
    let t = ProjTransform::new(label, &params.without_title())?;
    let (a, b) = t.ellipse_parameters();
    let datum = datum_of(label, &params, a, b)?;
    if datum == Datum::Wgs84Like && is_plain_lonlat(&params) {
        return Ok((Box::new(LonLat), ROUND_TRIP_TOLERANCE_M / M_PER_DEGREE));
    }
    let tolerance_m = match datum {
        Datum::Wgs84Like => ROUND_TRIP_TOLERANCE_M,
        Datum::Shifted => HELMERT_ROUND_TRIP_TOLERANCE_M,
    };
    let unit_m = if t.is_geographic() {
        M_PER_DEGREE
    } else {
        t.to_meter()
    };
    Ok((Box::new(t), tolerance_m / unit_m))
}

/// Refuses grid-based datum shifts: `+nadgrids=` other than `@null`, and
/// `+datum=NAD27` without a `+towgs84` (its PROJ 4 definition is
/// NADCON/NTv2 grids).
fn refuse_grids(label: &str, p: &ProjParams) -> Result<(), CrsError> {
    let grids = match (p.get("nadgrids"), p.get("datum")) {
        (Some("@null"), _) => return Ok(()),
        (Some(g), _) => g.to_string(),
        (None, Some(d)) if d.eq_ignore_ascii_case("nad27") && !p.has("towgs84") => {
            "@conus,@alaska,@ntv2_0.gsb,@ntv1_can.dat (NAD27's)".to_string()
        }
        _ => return Ok(()),
    };
    Err(CrsError::GridShift {
        crs: label.to_string(),
        grids,
    })
}

/// Which datum a definition names (module docs), in proj4rs's precedence:
/// `+nadgrids` (only `@null` gets here), then `+towgs84`, then `+datum`,
/// then the ellipsoid alone.
fn datum_of(label: &str, p: &ProjParams, a: f64, b: f64) -> Result<Datum, CrsError> {
    let wgs_ellipsoid = is_wgs84_like_ellipsoid(a, b);
    if p.has("nadgrids") {
        return Ok(Datum::Wgs84Like); // `@null`: the others are refused first
    }
    if p.has("towgs84") {
        let zero = p.towgs84().is_some_and(|v| v.iter().all(|x| *x == 0.0));
        return Ok(if zero && wgs_ellipsoid {
            Datum::Wgs84Like
        } else {
            Datum::Shifted
        });
    }
    match p.get("datum").map(str::to_ascii_lowercase).as_deref() {
        Some("wgs84" | "nad83") => Ok(Datum::Wgs84Like),
        Some(_) => Ok(Datum::Shifted),
        None if wgs_ellipsoid => Ok(Datum::Wgs84Like),
        None => Err(CrsError::NoDatumShift {
            crs: label.to_string(),
            ellipsoid: p
                .get("ellps")
                .map_or_else(|| format!("a={a} m, b={b} m"), str::to_string),
            definition: p.without_title(),
        }),
    }
}

/// True for longitude/latitude in degrees east and north from Greenwich:
/// no prime meridian, axis order, or geocentric latitude to apply.
fn is_plain_lonlat(p: &ProjParams) -> bool {
    let greenwich = match p.get("pm") {
        None => true,
        Some(pm) => pm.eq_ignore_ascii_case("greenwich") || pm.parse::<f64>() == Ok(0.0),
    };
    p.is_geographic()
        && greenwich
        && matches!(p.get("axis"), None | Some("enu"))
        && !p.has("geoc")
        && !p.has("lon_0")
}

/// Datums (and their ellipsoids) far from WGS 84 that a geographic
/// description may name, lower case, with the name reported.
const FAR_DATUMS: &[(&str, &str)] = &[
    ("nad27", "NAD27"),
    ("north american 1927", "NAD27"),
    ("north_american_1927", "NAD27"),
    ("clarke 1866", "the Clarke 1866 ellipsoid"),
    ("clarke 1880", "the Clarke 1880 ellipsoid"),
    ("ed50", "ED50"),
    ("european 1950", "ED50"),
    ("european_1950", "ED50"),
    ("osgb", "OSGB36"),
    ("airy", "the Airy ellipsoid"),
    ("tokyo", "Tokyo"),
    ("pulkovo", "Pulkovo 1942"),
    ("krass", "the Krassowsky ellipsoid"),
    ("sad69", "SAD69"),
    ("south american 1969", "SAD69"),
    ("corrego alegre", "Córrego Alegre"),
    ("córrego alegre", "Córrego Alegre"),
    ("potsdam", "Potsdam (DHDN)"),
    ("dhdn", "DHDN"),
    ("bessel", "the Bessel ellipsoid"),
    ("hayford", "the International 1924 ellipsoid"),
    ("international 1924", "the International 1924 ellipsoid"),
    ("everest", "the Everest ellipsoid"),
    ("arc 1950", "Arc 1950"),
    ("arc 1960", "Arc 1960"),
    ("nzgd49", "NZGD49"),
    ("agd66", "AGD66"),
    ("agd84", "AGD84"),
    ("ch1903", "CH1903"),
];

/// The far datum a description names, if any.
fn far_datum(text: &str) -> Option<&'static str> {
    let t = text.to_lowercase();
    FAR_DATUMS
        .iter()
        .find(|(key, _)| t.contains(key))
        .map(|(_, name)| *name)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refused(crs: Crs) -> CrsError {
        transform_for(&crs).expect_err(&format!("{crs:?} should be refused"))
    }

    #[test]
    fn identities() {
        for code in [4326, 4269, 4258, 4283, 4674, 4167, 4171] {
            let t = transform_for(&Crs::Epsg(code)).unwrap();
            assert!(t.is_identity(), "EPSG:{code}");
        }
        for def in [
            "+proj=longlat +datum=WGS84 +no_defs",
            "+proj=longlat +ellps=GRS80 +no_defs",
            "+proj=latlong +ellps=GRS80 +towgs84=0,0,0",
        ] {
            assert!(transform_for(&Crs::Proj(def.into())).unwrap().is_identity());
        }
        let g = Crs::Geographic("GCS Name = GRS 1980; Datum = unknown".into());
        assert!(transform_for(&g).unwrap().is_identity());
        // The reader's guess for an ESRI grid, and dem-hills.tiff's citation.
        let g = Crs::Geographic("WGS 84 (assumed: coordinates look like degrees)".into());
        assert!(transform_for(&g).unwrap().is_identity());
        let g =
            Crs::Geographic("Datum = Unknown based on Delambre 1810 (Belgium) ellipsoid".into());
        assert!(transform_for(&g).unwrap().is_identity());
    }

    #[test]
    fn shifted_geographic_is_not_the_identity() {
        // OSGB36 longitude/latitude: a Helmert of about 100 m.
        let t = transform_for(&Crs::Epsg(4277)).unwrap();
        assert!(!t.is_identity());
        let [lon, lat] = t.to_lonlat(-2.0, 53.0).unwrap();
        // PROJ 9 (pyproj) gives -2.001448898919734, 53.00030802027235.
        assert!((lon + 2.001_448_898_919_734).abs() < 1e-12, "{lon}");
        assert!((lat - 53.000_308_020_272_35).abs() < 1e-12, "{lat}");
        // Back within a centimetre (heights differ on the two sides).
        let [x, y] = t.from_lonlat(lon, lat).unwrap();
        assert!((x + 2.0).abs() < 1e-7 && (y - 53.0).abs() < 1e-7, "{x} {y}");
        let (_, tol) = transform_and_tolerance(&Crs::Epsg(4277)).unwrap();
        assert!((tol - 0.01 / 111_000.0).abs() < 1e-15);
        let (_, tol) = transform_and_tolerance(&Crs::Epsg(27700)).unwrap();
        assert_eq!(tol, HELMERT_ROUND_TRIP_TOLERANCE_M);
        let (_, tol) = transform_and_tolerance(&Crs::Epsg(32633)).unwrap();
        assert_eq!(tol, ROUND_TRIP_TOLERANCE_M);
    }

    #[test]
    fn refusals() {
        assert_eq!(refused(Crs::Unknown), CrsError::Unknown);
        assert_eq!(refused(Crs::Epsg(1)), CrsError::UnknownEpsg { code: 1 });
        assert!(matches!(
            refused(Crs::Epsg(4267)),
            CrsError::GridShift { .. }
        ));
        assert!(matches!(
            refused(Crs::Epsg(26715)),
            CrsError::GridShift { .. }
        ));
        let e = refused(Crs::Proj("+proj=utm +zone=30 +ellps=intl".into()));
        assert!(matches!(e, CrsError::NoDatumShift { .. }), "{e}");
        assert!(e.to_string().contains("intl"), "{e}");
        let e = refused(Crs::Proj(
            "+proj=utm +zone=30 +nadgrids=x.gsb +ellps=intl".into(),
        ));
        assert!(matches!(e, CrsError::GridShift { .. }), "{e}");
        let e = refused(Crs::Projected("UTM zone 11".into()));
        assert!(e.to_string().contains("--src-crs EPSG:N"), "{e}");
        let e = refused(Crs::Geographic(
            "NAD27 or NAD83 (USGS DEM without a datum code)".into(),
        ));
        assert!(e.to_string().contains("NAD27"), "{e}");
        let e = refused(Crs::Proj("+proj=utm +zone=oops".into()));
        assert!(matches!(e, CrsError::BadProj { .. }), "{e}");
        let e = refused(Crs::Proj("utm zone 3".into()));
        assert!(matches!(e, CrsError::BadProj { .. }), "{e}");
    }

    #[test]
    fn descriptions() {
        assert_eq!(
            describe(&Crs::Epsg(27700)),
            "EPSG:27700 (OSGB36 / British National Grid)"
        );
        assert_eq!(describe(&Crs::Epsg(9999)), "EPSG:9999");
        assert_eq!(
            describe(&Crs::Proj(
                "+proj=utm +zone=25 +south +title=\"UTM 25S\"".into()
            )),
            "UTM 25S (+proj=utm +zone=25 +south)"
        );
        assert_eq!(describe(&Crs::Unknown), "unknown");
        assert_eq!(
            definition(&Crs::Epsg(4326)).as_deref(),
            Some("+proj=longlat +datum=WGS84 +no_defs")
        );
        assert_eq!(
            definition(&Crs::Proj("+proj=merc +title=x".into())).as_deref(),
            Some("+proj=merc")
        );
        assert_eq!(definition(&Crs::Projected("UTM".into())), None);
    }
}
