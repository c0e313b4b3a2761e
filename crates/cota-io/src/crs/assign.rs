//! `--src-crs`: the CRS a user gives for inputs, against the CRS each file
//! declares ([`src_crs_for`], [`assign_src_crs`]).
//!
//! References: the EPSG dataset (codes), PROJ strings, and the GeoTIFF and
//! ESRI conventions by which a file declares a CRS or none.
//!
//! The rule, for each file:
//! 1. the file declares no CRS ([`Crs::Unknown`]) or only the readers'
//!    guess for a grid whose numbers look like degrees (`Crs::Geographic`
//!    "WGS 84 (assumed: …)"): the flag's CRS is used;
//! 2. the file declares the flag's CRS: fine;
//! 3. they contradict each other, and the file is refused naming both CRSs
//!    ([`CrsError::Contradiction`]), when
//!    * both are EPSG codes, and different ones (the aliases of Web
//!      Mercator count as one code);
//!    * both have a map to WGS 84 and the grid's corners or centre land more
//!      than [`SAME_POSITION_M`] apart under the two;
//!    * one is geographic (degrees) and the other projected;
//!    * both name a UTM zone, and different zones or hemispheres;
//! 4. otherwise the flag's CRS is used: it says precisely what the file
//!    only describes (a citation such as "UTM zone 25S", a definition that
//!    agrees to the millimetre).

use std::path::Path;

use cota_core::grid::metres_per_degree;
use cota_core::{Crs, GeoRef, GeoTransform};

use super::epsg;
use super::error::CrsError;
use super::params::ProjParams;
use super::resolve::{describe, transform_for};
use crate::dem::Dem;

/// Two CRSs that place the same grid coordinates within this distance,
/// metres, are the same CRS for `--src-crs` (datums taken as WGS 84 differ
/// by up to about 2 m in truth, but cota places them identically).
pub const SAME_POSITION_M: f64 = 1.0;

/// The CRS a file read with `--src-crs flag` is in (module docs): `flag`,
/// or the file's own when they are identical.
///
/// # Errors
/// [`CrsError::Contradiction`] naming `path` and both CRSs.
pub fn src_crs_for(
    path: &Path,
    georef: &GeoRef,
    width: usize,
    height: usize,
    flag: &Crs,
) -> Result<Crs, CrsError> {
    let file = &georef.crs;
    if file == flag || is_undeclared(file) {
        return Ok(flag.clone());
    }
    match contradiction(georef, width, height, flag) {
        None => Ok(flag.clone()),
        Some(why) => Err(CrsError::Contradiction {
            path: path.to_path_buf(),
            file: describe(file),
            flag: describe(flag),
            why,
        }),
    }
}

/// [`src_crs_for`] applied to a DEM as read: its grid's CRS becomes the
/// CRS found.
///
/// # Errors
/// As [`src_crs_for`].
pub fn assign_src_crs(dem: &mut Dem, flag: &Crs) -> Result<(), CrsError> {
    let g = &dem.grid;
    let crs = src_crs_for(&dem.path, g.georef(), g.width(), g.height(), flag)?;
    if crs != g.georef().crs {
        let mut georef = g.georef().clone();
        georef.crs = crs;
        dem.grid.set_georef(georef);
    }
    Ok(())
}

/// No CRS, or only the readers' guess of WGS 84 for numbers that look like
/// degrees ([`GeoRef::guess_geographic`]).
fn is_undeclared(crs: &Crs) -> bool {
    match crs {
        Crs::Unknown => true,
        Crs::Geographic(text) => text.starts_with("WGS 84 (assumed"),
        _ => false,
    }
}

/// Why the file's CRS and the flag contradict each other (module docs,
/// rule 3), or `None`.
fn contradiction(georef: &GeoRef, width: usize, height: usize, flag: &Crs) -> Option<String> {
    let file = &georef.crs;
    if let (Crs::Epsg(a), Crs::Epsg(b)) = (file, flag) {
        let aliases = epsg::is_web_mercator(*a) && epsg::is_web_mercator(*b);
        return (!aliases).then(|| "different EPSG codes".to_string());
    }
    if let (Ok(tf), Ok(tg)) = (transform_for(file), transform_for(flag)) {
        if georef.known {
            return apart(georef, width, height, tf.as_ref(), tg.as_ref());
        }
    }
    match (geographic(file), geographic(flag)) {
        (Some(a), Some(b)) if a != b => {
            return Some("one is geographic (degrees), the other projected".to_string())
        }
        _ => {}
    }
    match (utm_zone(file), utm_zone(flag)) {
        (Some(a), Some(b)) if a != b => Some(format!(
            "UTM zone {} against UTM zone {}",
            zone_name(a),
            zone_name(b)
        )),
        _ => None,
    }
}

/// How far apart the two maps put the grid's corners and centre, when more
/// than [`SAME_POSITION_M`].
fn apart(
    georef: &GeoRef,
    width: usize,
    height: usize,
    a: &dyn GeoTransform,
    b: &dyn GeoTransform,
) -> Option<String> {
    let (c1, r1) = (
        width.saturating_sub(1) as f64,
        height.saturating_sub(1) as f64,
    );
    let mut worst = 0.0f64;
    for (c, r) in [
        (0.0, 0.0),
        (c1, 0.0),
        (c1, r1),
        (0.0, r1),
        (c1 / 2.0, r1 / 2.0),
    ] {
        let (x, y) = georef.sample_xy(c, r);
        match (a.to_lonlat(x, y), b.to_lonlat(x, y)) {
            (Some(p), Some(q)) => {
                let [mx, my] = metres_per_degree(p[1]);
                let dlon = (p[0] - q[0] + 180.0).rem_euclid(360.0) - 180.0;
                worst = worst.max((dlon * mx).hypot((p[1] - q[1]) * my));
            }
            (None, None) => {}
            _ => {
                return Some(format!(
                    "the grid's point ({x}, {y}) lies inside one's domain and outside the other's"
                ))
            }
        }
    }
    (worst > SAME_POSITION_M)
        .then(|| format!("the grid's samples land up to {worst:.0} m apart under the two"))
}

/// True for longitude/latitude, false for projected; `None` when unknown.
fn geographic(crs: &Crs) -> Option<bool> {
    match crs {
        Crs::Geographic(_) => Some(true),
        Crs::Projected(_) => Some(false),
        Crs::Epsg(code) => Some(ProjParams::parse(epsg::definition(*code)?)?.is_geographic()),
        Crs::Proj(def) => Some(ProjParams::parse(def)?.is_geographic()),
        _ => None,
    }
}

/// The UTM zone and hemisphere (true: south) a CRS names: `+proj=utm`, or a
/// description such as "UTM Zone 25, Southern Hemisphere" or "WGS 84 / UTM
/// zone 33N".
fn utm_zone(crs: &Crs) -> Option<(u32, bool)> {
    let params = |def: &str| {
        let p = ProjParams::parse(def)?;
        (p.proj() == Some("utm")).then_some(())?;
        Some((p.get("zone")?.parse().ok()?, p.has("south")))
    };
    match crs {
        Crs::Epsg(code) => params(epsg::definition(*code)?),
        Crs::Proj(def) => params(def),
        Crs::Projected(text) => utm_in_text(text),
        _ => None,
    }
}

/// "utm zone" followed by a zone number and a hemisphere, in a description.
fn utm_in_text(text: &str) -> Option<(u32, bool)> {
    let t = text.to_lowercase();
    let rest = t[t.find("utm zone")? + "utm zone".len()..].trim_start();
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    let zone: u32 = digits.parse().ok()?;
    let after = rest[digits.len()..].trim_start_matches([',', ' ']);
    let south = if after.starts_with('s') || after.starts_with("southern") {
        true
    } else if after.starts_with('n') {
        false
    } else {
        return None;
    };
    (1..=60).contains(&zone).then_some((zone, south))
}

fn zone_name((zone, south): (u32, bool)) -> String {
    format!("{zone}{}", if south { 'S' } else { 'N' })
}

#[cfg(test)]
mod tests {
    use super::*;
    use cota_core::PixelIs;

    fn utm_grid(crs: Crs) -> GeoRef {
        GeoRef {
            crs,
            origin_x: 288_776.25,
            origin_y: 9_120_760.75,
            pixel_x: 90.0,
            pixel_y: -90.0,
            pixel_is: PixelIs::Area,
            known: true,
        }
    }

    fn check(file: Crs, flag: Crs) -> Result<Crs, CrsError> {
        src_crs_for(Path::new("f.tif"), &utm_grid(file), 111, 111, &flag)
    }

    #[test]
    fn undeclared_and_same() {
        assert_eq!(check(Crs::Unknown, Crs::Epsg(31985)), Ok(Crs::Epsg(31985)));
        let guess = Crs::Geographic("WGS 84 (assumed: coordinates look like degrees)".into());
        assert_eq!(check(guess, Crs::Epsg(4326)), Ok(Crs::Epsg(4326)));
        assert_eq!(
            check(Crs::Epsg(31985), Crs::Epsg(31985)),
            Ok(Crs::Epsg(31985))
        );
        assert_eq!(
            check(Crs::Epsg(3857), Crs::Epsg(900_913)),
            Ok(Crs::Epsg(900_913))
        );
        // The same map written another way: the flag's form is kept.
        let own =
            Crs::Proj("+proj=utm +zone=25 +south +ellps=GRS80 +towgs84=0,0,0 +units=m".into());
        assert_eq!(check(own.clone(), Crs::Epsg(31985)), Ok(Crs::Epsg(31985)));
        assert_eq!(check(own, Crs::Epsg(32725)), Ok(Crs::Epsg(32725)));
        // A description refined by the flag.
        let desc = Crs::Projected("UTM Zone 25, Southern Hemisphere".into());
        assert_eq!(check(desc, Crs::Epsg(31985)), Ok(Crs::Epsg(31985)));
    }

    #[test]
    fn contradictions() {
        let why = |file: Crs, flag: Crs| match check(file, flag) {
            Err(CrsError::Contradiction { why, path, .. }) => {
                assert_eq!(path, Path::new("f.tif"));
                why
            }
            other => panic!("expected a contradiction, got {other:?}"),
        };
        assert!(why(Crs::Epsg(31985), Crs::Epsg(32725)).contains("EPSG codes"));
        let own = Crs::Proj("+proj=utm +zone=25 +south +ellps=GRS80 +units=m".into());
        let w = why(own, Crs::Epsg(32724));
        assert!(w.contains("m apart"), "{w}");
        let desc = Crs::Projected("UTM Zone 25, Southern Hemisphere".into());
        assert!(why(desc.clone(), Crs::Epsg(4326)).contains("geographic"));
        let w = why(
            desc,
            Crs::Proj("+proj=utm +zone=24 +south +ellps=intl".into()),
        );
        assert!(w.contains("25S against UTM zone 24S"), "{w}");
        let e = check(Crs::Epsg(31985), Crs::Epsg(4326))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with(
                "f.tif: the file declares its CRS as EPSG:31985 (SIRGAS 2000 / UTM zone 25S)"
            ) && e.contains("--src-crs EPSG:4326 (WGS 84)")
                && e.contains("drop --src-crs"),
            "{e}"
        );
    }

    #[test]
    fn utm_descriptions() {
        assert_eq!(
            utm_in_text("UTM Zone 25, Southern Hemisphere"),
            Some((25, true))
        );
        assert_eq!(utm_in_text("WGS 84 / UTM zone 33N"), Some((33, false)));
        assert_eq!(utm_in_text("UTM zone 11"), None);
        assert_eq!(utm_in_text("UTM zone 61N"), None);
    }
}
