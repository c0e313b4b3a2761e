//! A user-defined projected CRS of a GeoTIFF, from its GeoKeys to a PROJ
//! string, so that it can be reprojected ([`cota_core::Crs::Proj`]).
//!
//! Reference: the OGC GeoTIFF standard 1.1 (OGC 19-008r4), §7 GeoKeys, and
//! its requirement classes for user-defined projected and geodetic CRSs;
//! the EPSG dataset for the codes the keys hold; PROJ's parameter names.
//!
//! 1. The projection: ProjectionGeoKey 3074 as an EPSG conversion code
//!    (16001–16060 UTM zones 1N–60N, 16101–16160 zones 1S–60S), or
//!    ProjCoordTransGeoKey 3075 with its parameters 3078–3095 (transverse
//!    Mercator, Mercator, Lambert conformal conic 1SP and 2SP, Lambert
//!    azimuthal equal area, Albers, polar and oblique stereographic,
//!    equirectangular, Cassini, sinusoidal). Angles are in
//!    GeogAngularUnitsGeoKey 2054's unit (degrees by default, radians),
//!    lengths in ProjLinearUnitsGeoKey 3076's (metres, feet, US survey feet,
//!    or ProjLinearUnitSizeGeoKey 3077 metres); PROJ wants false eastings
//!    and northings in metres.
//! 2. The datum: GeographicTypeGeoKey 2048 (an EPSG geographic CRS), else
//!    GeogGeodeticDatumGeoKey 2050 (an EPSG datum 6xxx, whose geographic
//!    CRS is 4xxx), each through its PROJ definition; else the ellipsoid
//!    (GeogEllipsoidGeoKey 2056, or the axes 2057–2059) with
//!    GeogTOWGS84GeoKey 2062 and the prime meridian 2061.
//! 3. Anything else (an unknown method or unit, a missing parameter or
//!    ellipsoid) gives no definition: the CRS stays a description.

use std::collections::BTreeMap;

use crate::crs::epsg;
use crate::crs::params::ProjParams;

/// GeoKey ids read here.
mod key {
    pub const GEODETIC_DATUM: u16 = 2050;
    pub const PRIME_MERIDIAN: u16 = 2051;
    pub const ANGULAR_UNITS: u16 = 2054;
    pub const ELLIPSOID: u16 = 2056;
    pub const SEMI_MAJOR: u16 = 2057;
    pub const SEMI_MINOR: u16 = 2058;
    pub const INV_FLATTENING: u16 = 2059;
    pub const PRIME_MERIDIAN_LONG: u16 = 2061;
    pub const TOWGS84: u16 = 2062;
    pub const PROJECTION: u16 = 3074;
    pub const COORD_TRANS: u16 = 3075;
    pub const LINEAR_UNITS: u16 = 3076;
    pub const LINEAR_UNIT_SIZE: u16 = 3077;
    pub const STD_PARALLEL1: u16 = 3078;
    pub const STD_PARALLEL2: u16 = 3079;
    pub const NAT_ORIGIN_LONG: u16 = 3080;
    pub const NAT_ORIGIN_LAT: u16 = 3081;
    pub const FALSE_EASTING: u16 = 3082;
    pub const FALSE_NORTHING: u16 = 3083;
    pub const FALSE_ORIGIN_LONG: u16 = 3084;
    pub const FALSE_ORIGIN_LAT: u16 = 3085;
    pub const FALSE_ORIGIN_EASTING: u16 = 3086;
    pub const FALSE_ORIGIN_NORTHING: u16 = 3087;
    pub const CENTER_LONG: u16 = 3088;
    pub const CENTER_LAT: u16 = 3089;
    pub const SCALE_AT_NAT_ORIGIN: u16 = 3092;
    pub const STRAIGHT_VERT_POLE_LONG: u16 = 3095;
}

/// True for the GeoKeys this module reads (besides GeographicTypeGeoKey).
pub(super) fn is_projection_key(id: u16) -> bool {
    (2050..=2062).contains(&id) || (3074..=3095).contains(&id)
}

/// The SHORT and DOUBLE values of the keys of [`is_projection_key`].
#[derive(Debug, Default, Clone, PartialEq)]
pub(super) struct ProjKeys {
    pub shorts: BTreeMap<u16, u16>,
    pub doubles: BTreeMap<u16, Vec<f64>>,
}

/// Ellipsoids by EPSG code: PROJ's name for each.
const ELLIPSOIDS: &[(u16, &str)] = &[
    (7001, "airy"),
    (7004, "bessel"),
    (7008, "clrk66"),
    (7012, "clrk80"),
    (7019, "GRS80"),
    (7022, "intl"),
    (7024, "krass"),
    (7030, "WGS84"),
    (7043, "WGS72"),
];

impl ProjKeys {
    fn short(&self, id: u16) -> Option<u16> {
        self.shorts.get(&id).copied()
    }

    fn double(&self, id: u16) -> Option<f64> {
        self.doubles
            .get(&id)?
            .first()
            .copied()
            .filter(|v| v.is_finite())
    }

    /// The PROJ definition the keys give (module docs), if any;
    /// `geographic_type` is GeographicTypeGeoKey 2048.
    pub(super) fn definition(&self, geographic_type: Option<u16>) -> Option<String> {
        let unit_m = self.linear_unit_m()?;
        let projection = self.projection(unit_m)?;
        let datum = self.datum(geographic_type)?;
        let units = if unit_m == 1.0 {
            "+units=m".to_string()
        } else {
            format!("+to_meter={unit_m}")
        };
        Some(format!("{projection} {datum} {units} +no_defs"))
    }

    /// Metres per unit of ProjLinearUnitsGeoKey (metre when absent).
    fn linear_unit_m(&self) -> Option<f64> {
        match self.short(key::LINEAR_UNITS) {
            None | Some(9001) => Some(1.0),
            Some(9002) => Some(0.3048),
            Some(9003) => Some(1200.0 / 3937.0),
            Some(9036) => Some(1000.0),
            Some(_) => self.double(key::LINEAR_UNIT_SIZE).filter(|s| *s > 0.0),
        }
    }

    /// Degrees per unit of GeogAngularUnitsGeoKey (degree when absent).
    fn angle_deg(&self, id: u16) -> Option<f64> {
        let v = self.double(id)?;
        match self.short(key::ANGULAR_UNITS) {
            None | Some(9102) => Some(v),
            Some(9101) => Some(v.to_degrees()),
            Some(9105) => Some(v * 0.9),
            Some(_) => None,
        }
    }

    /// The projection's PROJ parameters (module docs, step 1).
    fn projection(&self, unit_m: f64) -> Option<String> {
        if let Some(code) = self.short(key::PROJECTION) {
            match code {
                16001..=16060 => return Some(format!("+proj=utm +zone={}", code - 16000)),
                16101..=16160 => return Some(format!("+proj=utm +zone={} +south", code - 16100)),
                _ => {}
            }
        }
        self.coord_trans(unit_m)
    }

    /// ProjCoordTransGeoKey and its parameters.
    fn coord_trans(&self, unit_m: f64) -> Option<String> {
        let deg = |id| self.angle_deg(id);
        let m = |id| self.double(id).map(|v| v * unit_m);
        let fe = || {
            Some(format!(
                "+x_0={} +y_0={}",
                m(key::FALSE_EASTING)?,
                m(key::FALSE_NORTHING)?
            ))
        };
        let nat = || {
            Some(format!(
                "+lat_0={} +lon_0={}",
                deg(key::NAT_ORIGIN_LAT)?,
                deg(key::NAT_ORIGIN_LONG)?
            ))
        };
        let centre = || {
            let lat = deg(key::CENTER_LAT).or_else(|| deg(key::NAT_ORIGIN_LAT))?;
            let lon = deg(key::CENTER_LONG).or_else(|| deg(key::NAT_ORIGIN_LONG))?;
            Some(format!("+lat_0={lat} +lon_0={lon}"))
        };
        let k = |id| Some(format!("+k_0={}", self.double(id).unwrap_or(1.0)));
        Some(match self.short(key::COORD_TRANS)? {
            1 => format!(
                "+proj=tmerc {} {} {}",
                nat()?,
                k(key::SCALE_AT_NAT_ORIGIN)?,
                fe()?
            ),
            7 => match deg(key::STD_PARALLEL1) {
                Some(ts) => format!(
                    "+proj=merc +lat_ts={ts} +lon_0={} {}",
                    deg(key::NAT_ORIGIN_LONG)?,
                    fe()?
                ),
                None => format!(
                    "+proj=merc +lon_0={} {} {}",
                    deg(key::NAT_ORIGIN_LONG)?,
                    k(key::SCALE_AT_NAT_ORIGIN)?,
                    fe()?
                ),
            },
            8 => self.lcc_2sp(unit_m)?,
            9 => format!(
                "+proj=lcc +lat_1={} {} {} {}",
                deg(key::NAT_ORIGIN_LAT)?,
                nat()?,
                k(key::SCALE_AT_NAT_ORIGIN)?,
                fe()?
            ),
            10 => format!("+proj=laea {} {}", centre()?, fe()?),
            11 => format!(
                "+proj=aea +lat_1={} +lat_2={} {} {}",
                deg(key::STD_PARALLEL1)?,
                deg(key::STD_PARALLEL2)?,
                centre().or_else(|| self.false_origin_lonlat())?,
                fe()?
            ),
            15 => self.polar_stereographic(unit_m)?,
            16 => format!(
                "+proj=sterea {} {} {}",
                nat()?,
                k(key::SCALE_AT_NAT_ORIGIN)?,
                fe()?
            ),
            17 => format!(
                "+proj=eqc +lat_ts={} {} {}",
                deg(key::STD_PARALLEL1).unwrap_or(0.0),
                centre()?,
                fe()?
            ),
            18 => format!("+proj=cass {} {}", nat()?, fe()?),
            24 => format!(
                "+proj=sinu +lon_0={} {}",
                deg(key::CENTER_LONG).or_else(|| deg(key::NAT_ORIGIN_LONG))?,
                fe()?
            ),
            _ => return None,
        })
    }

    /// `+lat_0 +lon_0` from the false origin's keys.
    fn false_origin_lonlat(&self) -> Option<String> {
        let lat = self.angle_deg(key::FALSE_ORIGIN_LAT)?;
        let lon = self.angle_deg(key::FALSE_ORIGIN_LONG)?;
        Some(format!("+lat_0={lat} +lon_0={lon}"))
    }

    /// Lambert conformal conic with two standard parallels: the false
    /// origin's keys, or the natural origin's as some writers use.
    fn lcc_2sp(&self, unit_m: f64) -> Option<String> {
        let m = |id| self.double(id).map(|v| v * unit_m);
        let origin = self.false_origin_lonlat().or_else(|| {
            let lat = self.angle_deg(key::NAT_ORIGIN_LAT)?;
            let lon = self.angle_deg(key::NAT_ORIGIN_LONG)?;
            Some(format!("+lat_0={lat} +lon_0={lon}"))
        })?;
        let x0 = m(key::FALSE_ORIGIN_EASTING).or_else(|| m(key::FALSE_EASTING))?;
        let y0 = m(key::FALSE_ORIGIN_NORTHING).or_else(|| m(key::FALSE_NORTHING))?;
        Some(format!(
            "+proj=lcc +lat_1={} +lat_2={} {origin} +x_0={x0} +y_0={y0}",
            self.angle_deg(key::STD_PARALLEL1)?,
            self.angle_deg(key::STD_PARALLEL2)?
        ))
    }

    /// Polar stereographic: the pole on the side of the latitude of true
    /// scale (NatOriginLat), centred on StraightVertPoleLong.
    fn polar_stereographic(&self, unit_m: f64) -> Option<String> {
        let ts = self.angle_deg(key::NAT_ORIGIN_LAT)?;
        let lon = self
            .angle_deg(key::STRAIGHT_VERT_POLE_LONG)
            .or_else(|| self.angle_deg(key::NAT_ORIGIN_LONG))?;
        let pole = if ts < 0.0 { -90.0 } else { 90.0 };
        let scale = match self.double(key::SCALE_AT_NAT_ORIGIN) {
            Some(k) if ts.abs() == 90.0 => format!(" +k_0={k}"),
            _ => format!(" +lat_ts={ts}"),
        };
        Some(format!(
            "+proj=stere +lat_0={pole} +lon_0={lon}{scale} +x_0={} +y_0={}",
            self.double(key::FALSE_EASTING)? * unit_m,
            self.double(key::FALSE_NORTHING)? * unit_m
        ))
    }

    /// The datum's PROJ parameters (module docs, step 2).
    fn datum(&self, geographic_type: Option<u16>) -> Option<String> {
        let by_code = |code: u16| {
            let def = ProjParams::parse(epsg::definition(u32::from(code))?)?;
            def.is_geographic().then(|| datum_part(&def))?
        };
        let epsg_code = |c: Option<u16>| c.filter(|c| (1..32767).contains(c));
        if let Some(def) = epsg_code(geographic_type).and_then(by_code) {
            return Some(def);
        }
        if let Some(d) =
            epsg_code(self.short(key::GEODETIC_DATUM)).filter(|d| (6001..=6999).contains(d))
        {
            if let Some(def) = by_code(d - 2000) {
                return Some(def);
            }
        }
        self.user_datum()
    }

    /// A user-defined datum: ellipsoid, Helmert, prime meridian.
    fn user_datum(&self) -> Option<String> {
        let mut parts = vec![self.ellipsoid()?];
        if let Some(t) = self.doubles.get(&key::TOWGS84) {
            if (t.len() == 3 || t.len() == 7) && t.iter().all(|v| v.is_finite()) {
                let v: Vec<String> = t.iter().map(f64::to_string).collect();
                parts.push(format!("+towgs84={}", v.join(",")));
            }
        }
        let pm = match self.short(key::PRIME_MERIDIAN) {
            None | Some(8901) => self.angle_deg(key::PRIME_MERIDIAN_LONG).unwrap_or(0.0),
            Some(_) => self.angle_deg(key::PRIME_MERIDIAN_LONG)?,
        };
        if pm != 0.0 {
            parts.push(format!("+pm={pm}"));
        }
        Some(parts.join(" "))
    }

    /// `+ellps=NAME` for a known ellipsoid (by code or by its axes), else
    /// `+a= +rf=` or `+a= +b=`.
    fn ellipsoid(&self) -> Option<String> {
        if let Some(code) = self.short(key::ELLIPSOID) {
            if let Some((_, name)) = ELLIPSOIDS.iter().find(|(c, _)| *c == code) {
                return Some(format!("+ellps={name}"));
            }
        }
        let a = self.double(key::SEMI_MAJOR).filter(|a| *a > 0.0)?;
        match (
            self.double(key::INV_FLATTENING),
            self.double(key::SEMI_MINOR),
        ) {
            (Some(rf), _)
                if (a - 6_378_137.0).abs() < 1e-6 && (rf - 298.257_222_101).abs() < 1e-9 =>
            {
                Some("+ellps=GRS80".to_string())
            }
            (Some(rf), _)
                if (a - 6_378_137.0).abs() < 1e-6 && (rf - 298.257_223_563).abs() < 1e-9 =>
            {
                Some("+ellps=WGS84".to_string())
            }
            (Some(rf), _) if rf > 0.0 => Some(format!("+a={a} +rf={rf}")),
            (_, Some(b)) if b > 0.0 => Some(format!("+a={a} +b={b}")),
            _ => Some(format!("+a={a} +b={a}")),
        }
    }
}

/// The datum parameters of a geographic CRS's definition.
fn datum_part(def: &ProjParams) -> Option<String> {
    const DATUM_KEYS: [&str; 10] = [
        "datum", "ellps", "a", "b", "rf", "f", "R", "towgs84", "nadgrids", "pm",
    ];
    let parts: Vec<String> = DATUM_KEYS
        .iter()
        .filter_map(|k| def.get(k).map(|v| format!("+{k}={v}")))
        .collect();
    (!parts.is_empty()).then(|| parts.join(" "))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn keys(shorts: &[(u16, u16)], doubles: &[(u16, f64)]) -> ProjKeys {
        ProjKeys {
            shorts: shorts.iter().copied().collect(),
            doubles: doubles.iter().map(|&(k, v)| (k, vec![v])).collect(),
        }
    }

    #[test]
    fn olinda_user_defined_utm_25s() {
        // The keys of texture/olinda_dem_utm25s.tif.
        let mut k = keys(
            &[
                (2050, 32767),
                (2054, 9102),
                (2056, 32767),
                (3074, 16125),
                (3076, 9001),
            ],
            &[(2057, 6_378_137.0), (2059, 298.257_222_101), (2061, 0.0)],
        );
        k.doubles.insert(2062, vec![0.0, 0.0, 0.0]);
        assert_eq!(
            k.definition(Some(32767)).as_deref(),
            Some("+proj=utm +zone=25 +south +ellps=GRS80 +towgs84=0,0,0 +units=m +no_defs")
        );
    }

    #[test]
    fn parameters_and_datums() {
        // Transverse Mercator in US survey feet on NAD83 (GeographicType 4269).
        let k = keys(
            &[(3075, 1), (3076, 9003)],
            &[
                (3080, -120.5),
                (3081, 35.0),
                (3082, 1_640_416.666_666_667),
                (3083, 0.0),
                (3092, 0.9999),
            ],
        );
        let d = k.definition(Some(4269)).unwrap();
        assert!(
            d.starts_with("+proj=tmerc +lat_0=35 +lon_0=-120.5 +k_0=0.9999 +x_0=500000.00000"),
            "{d}"
        );
        assert!(
            d.ends_with("+datum=NAD83 +to_meter=0.3048006096012192 +no_defs"),
            "{d}"
        );
        // Lambert conformal conic 2SP, datum by code (6258 -> 4258), radians.
        let r = |d: f64| d.to_radians();
        let k = keys(
            &[(3075, 8), (2050, 6258), (2054, 9101)],
            &[
                (3078, r(49.0)),
                (3079, r(44.0)),
                (3084, r(3.0)),
                (3085, r(46.5)),
                (3086, 700_000.0),
                (3087, 6_600_000.0),
            ],
        );
        let d = k.definition(None).unwrap();
        assert!(d.starts_with("+proj=lcc +lat_1=49"), "{d}");
        assert!(
            d.contains("+x_0=700000 +y_0=6600000 +ellps=GRS80 +towgs84=0,0,0,0,0,0,0"),
            "{d}"
        );
        // Polar stereographic, south, user-defined WGS 84 ellipsoid by code.
        let k = keys(
            &[(3075, 15), (2056, 7030)],
            &[(3081, -71.0), (3095, 0.0), (3082, 0.0), (3083, 0.0)],
        );
        assert_eq!(
            k.definition(Some(32767)).as_deref(),
            Some("+proj=stere +lat_0=-90 +lon_0=0 +lat_ts=-71 +x_0=0 +y_0=0 +ellps=WGS84 +units=m +no_defs")
        );
    }

    #[test]
    fn missing_pieces_give_none() {
        // No ellipsoid at all; an unknown method; a missing parameter; an
        // unknown angular unit.
        assert_eq!(keys(&[(3074, 16001)], &[]).definition(None), None);
        assert_eq!(keys(&[(3075, 26)], &[(2057, 6e6)]).definition(None), None);
        assert_eq!(
            keys(&[(3075, 1)], &[(2057, 6e6), (3080, 0.0)]).definition(None),
            None
        );
        let k = keys(
            &[(3075, 10), (2054, 9999)],
            &[
                (2057, 6e6),
                (3088, 1.0),
                (3089, 1.0),
                (3082, 0.0),
                (3083, 0.0),
            ],
        );
        assert_eq!(k.definition(None), None);
        // A sphere.
        let k = keys(&[(3074, 16033)], &[(2057, 6_371_000.0)]);
        assert_eq!(
            k.definition(None).as_deref(),
            Some("+proj=utm +zone=33 +a=6371000 +b=6371000 +units=m +no_defs")
        );
    }
}
