//! [`parse_crs`]: the text of `--src-crs` as a [`Crs`].
//!
//! References: the `AUTHORITY:CODE` form of CRS names (`EPSG:32633`, as PROJ
//! and GDAL accept them) and PROJ strings (<https://proj.org/usage/projections.html>).

use cota_core::Crs;

use super::epsg;
use super::error::CrsError;
use super::params::ProjParams;
use super::project::ProjTransform;

/// Parses `EPSG:N` (any case, blanks allowed around the parts) or a PROJ
/// string starting with `+` (`+proj=utm +zone=33 +datum=WGS84`).
///
/// ```
/// use cota_core::Crs;
/// use cota_io::crs::parse_crs;
/// assert_eq!(parse_crs("epsg:32633").unwrap(), Crs::Epsg(32633));
/// assert_eq!(
///     parse_crs(" +proj=utm  +zone=33 +datum=WGS84 ").unwrap(),
///     Crs::Proj("+proj=utm +zone=33 +datum=WGS84".into())
/// );
/// assert!(parse_crs("EPSG:99999").is_err());
/// ```
///
/// # Errors
/// [`CrsError::UnknownEpsg`] for a code cota has no definition for,
/// [`CrsError::BadProj`] for a PROJ string proj4rs cannot read,
/// [`CrsError::Unparseable`] for anything else.
pub fn parse_crs(text: &str) -> Result<Crs, CrsError> {
    let t = text.trim();
    let unparseable = || CrsError::Unparseable {
        found: text.to_string(),
    };
    if t.starts_with('+') {
        let params = ProjParams::parse(t).ok_or_else(|| CrsError::BadProj {
            definition: t.to_string(),
            reason: "expected +key=value parameters separated by blanks".to_string(),
        })?;
        // proj4rs must read it; datum questions are transform_for's.
        ProjTransform::new(t, &params.without_title())?;
        return Ok(Crs::Proj(
            t.split_whitespace().collect::<Vec<_>>().join(" "),
        ));
    }
    let (authority, code) = t.split_once(':').ok_or_else(unparseable)?;
    if !authority.trim().eq_ignore_ascii_case("epsg") {
        return Err(unparseable());
    }
    let code: u32 = code.trim().parse().map_err(|_| unparseable())?;
    match epsg::definition(code) {
        Some(_) => Ok(Crs::Epsg(code)),
        None => Err(CrsError::UnknownEpsg { code }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn forms() {
        assert_eq!(parse_crs("EPSG:4326").unwrap(), Crs::Epsg(4326));
        assert_eq!(parse_crs("Epsg : 27700").unwrap(), Crs::Epsg(27700));
        assert_eq!(parse_crs("EPSG:900913").unwrap(), Crs::Epsg(900_913));
        for bad in [
            "",
            "4326",
            "ESRI:102100",
            "EPSG:",
            "EPSG:x",
            "EPSG:-1",
            "WGS84",
        ] {
            assert!(
                matches!(parse_crs(bad), Err(CrsError::Unparseable { .. })),
                "{bad}"
            );
        }
        assert_eq!(
            parse_crs("EPSG:12").unwrap_err(),
            CrsError::UnknownEpsg { code: 12 }
        );
        let e = parse_crs("+proj=nosuch +ellps=WGS84").unwrap_err();
        assert!(matches!(e, CrsError::BadProj { .. }), "{e}");
        let e = parse_crs("+proj=utm +title=\"open").unwrap_err();
        assert!(matches!(e, CrsError::BadProj { .. }), "{e}");
    }
}
