//! [`ProjTransform`]: a CRS given by a PROJ string, mapped to and from WGS 84
//! longitude/latitude by proj4rs.
//!
//! Reference: PROJ 4's `pj_transform` pipeline, which proj4rs follows
//! (<https://proj.org/usage/transformations.html>): the source projection's
//! inverse to geodetic longitude/latitude on its ellipsoid, then (when the
//! datum has a `+towgs84` Helmert) geodetic → geocentric, the 3- or
//! 7-parameter Helmert (position-vector convention), geocentric → geodetic on
//! WGS 84; the other direction backwards. The two `proj4rs::Proj` objects are
//! parsed once, when the transform is built; each call only runs the math.

use std::fmt;

use cota_core::GeoTransform;
use proj4rs::Proj;

use super::error::CrsError;

/// WGS 84 longitude/latitude, the other end of every transform.
const WGS84_LONLAT: &str = "+proj=longlat +datum=WGS84 +no_defs";

/// A map between a PROJ-defined CRS and WGS 84 longitude/latitude (degrees).
///
/// ```
/// use cota_core::GeoTransform;
/// use cota_io::crs::ProjTransform;
/// let utm = ProjTransform::new("UTM 33N", "+proj=utm +zone=33 +datum=WGS84 +units=m").unwrap();
/// let [x, y] = utm.from_lonlat(15.0, 0.0).unwrap();
/// assert!((x - 500_000.0).abs() < 1e-6 && y.abs() < 1e-6);
/// let [lon, lat] = utm.to_lonlat(x, y).unwrap();
/// assert!((lon - 15.0).abs() < 1e-12 && lat.abs() < 1e-12);
/// ```
pub struct ProjTransform {
    /// The CRS as shown in messages.
    label: String,
    /// The PROJ string parsed (without `+title`).
    definition: String,
    src: Proj,
    wgs84: Proj,
    /// The CRS is longitude/latitude (proj4rs takes and gives it in radians).
    degrees: bool,
}

impl ProjTransform {
    /// Parses `definition` (a PROJ string) for the CRS shown as `label`.
    ///
    /// # Errors
    /// [`CrsError::BadProj`] when proj4rs cannot read the definition or the
    /// projection has no inverse.
    pub fn new(label: &str, definition: &str) -> Result<Self, CrsError> {
        let bad = |reason: String| CrsError::BadProj {
            definition: definition.to_string(),
            reason,
        };
        let src = Proj::from_proj_string(definition).map_err(|e| bad(e.to_string()))?;
        if !src.has_inverse() || !src.has_forward() {
            return Err(bad(format!(
                "the projection {} has no inverse in proj4rs",
                src.projname()
            )));
        }
        let wgs84 = Proj::from_proj_string(WGS84_LONLAT).map_err(|e| bad(e.to_string()))?;
        Ok(ProjTransform {
            label: label.to_string(),
            definition: definition.to_string(),
            degrees: src.is_latlong(),
            src,
            wgs84,
        })
    }

    /// The PROJ string the transform was built from.
    pub fn definition(&self) -> &str {
        &self.definition
    }

    /// The CRS as shown in messages.
    pub fn label(&self) -> &str {
        &self.label
    }

    /// True when the CRS is longitude/latitude (degrees).
    pub fn is_geographic(&self) -> bool {
        self.degrees
    }

    /// Metres per unit of the CRS's projected coordinates.
    pub fn to_meter(&self) -> f64 {
        self.src.to_meter()
    }

    /// The source ellipsoid's semi-major and semi-minor axes, metres.
    pub fn ellipse_parameters(&self) -> (f64, f64) {
        self.src.ellipse_parameters()
    }

    /// [`GeoTransform::to_lonlat`] with proj4rs's reason on failure.
    ///
    /// # Errors
    /// proj4rs's message (a point outside the projection's domain, say).
    pub fn try_to_lonlat(&self, x: f64, y: f64) -> Result<[f64; 2], String> {
        let mut p = if self.degrees {
            (x.to_radians(), y.to_radians(), 0.0)
        } else {
            (x, y, 0.0)
        };
        proj4rs::transform::transform(&self.src, &self.wgs84, &mut p).map_err(|e| e.to_string())?;
        finite([p.0.to_degrees(), p.1.to_degrees()])
    }

    /// [`GeoTransform::from_lonlat`] with proj4rs's reason on failure.
    ///
    /// # Errors
    /// proj4rs's message.
    pub fn try_from_lonlat(&self, lon: f64, lat: f64) -> Result<[f64; 2], String> {
        let mut p = (lon.to_radians(), lat.to_radians(), 0.0);
        proj4rs::transform::transform(&self.wgs84, &self.src, &mut p).map_err(|e| e.to_string())?;
        if self.degrees {
            finite([p.0.to_degrees(), p.1.to_degrees()])
        } else {
            finite([p.0, p.1])
        }
    }
}

fn finite(p: [f64; 2]) -> Result<[f64; 2], String> {
    if p.iter().all(|v| v.is_finite()) {
        Ok(p)
    } else {
        Err("a non-finite result".to_string())
    }
}

impl fmt::Debug for ProjTransform {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ProjTransform")
            .field("label", &self.label)
            .field("definition", &self.definition)
            .finish_non_exhaustive()
    }
}

impl GeoTransform for ProjTransform {
    fn to_lonlat(&self, x: f64, y: f64) -> Option<[f64; 2]> {
        self.try_to_lonlat(x, y).ok()
    }

    fn from_lonlat(&self, lon: f64, lat: f64) -> Option<[f64; 2]> {
        self.try_from_lonlat(lon, lat).ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn is_send_and_sync() {
        fn check<T: Send + Sync>() {}
        check::<ProjTransform>();
    }

    #[test]
    fn bad_strings_are_refused() {
        for bad in [
            "+proj=nosuch",
            "+proj=utm +zone=99",
            "+proj=utm +datum=nosuch",
        ] {
            let e = ProjTransform::new("x", bad).unwrap_err();
            assert!(matches!(e, CrsError::BadProj { .. }), "{bad}: {e}");
        }
    }
}
