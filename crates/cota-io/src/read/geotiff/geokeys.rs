//! GeoTIFF georeferencing: the raster-to-model transform and the GeoKeys.
//!
//! * Transform: ModelPixelScaleTag 33550 (sx, sy, sz) with ModelTiepointTag
//!   33922 (I, J, K, X, Y, Z), or ModelTransformationTag 34264 (a 4×4 matrix,
//!   row-major). Both map raster coordinates (I, J) to model (X, Y); raster
//!   (0, 0) is the outer corner of the first pixel for RasterPixelIsArea and
//!   the first sample itself for RasterPixelIsPoint, which is exactly the
//!   origin of [`GeoRef`] under the matching [`PixelIs`].
//! * GeoKeyDirectoryTag 34735: a header (version, revision, minor, count) then
//!   `count` entries (key id, tag location, count, value or offset). Location 0
//!   holds a SHORT value in the entry, location 34737 (GeoAsciiParamsTag) a
//!   `|`-terminated substring; double-valued keys (34736) are not needed here.
//! * Keys read: GTModelTypeGeoKey 1024 (1 projected, 2 geographic),
//!   GTRasterTypeGeoKey 1025 (1 PixelIsArea, 2 PixelIsPoint), GTCitationGeoKey
//!   1026, GeographicTypeGeoKey 2048, GeogCitationGeoKey 2049,
//!   ProjectedCSTypeGeoKey 3072, PCSCitationGeoKey 3073, VerticalUnitsGeoKey
//!   4099. Codes 1..=32766 are EPSG codes; 32767 means user-defined, described
//!   by the citation.
//! * A user-defined projected CRS whose keys define it (ProjectionGeoKey
//!   3074 or ProjCoordTransGeoKey 3075 with its parameters, the datum's and
//!   ellipsoid's keys 2050–2062; doubles in GeoDoubleParamsTag 34736) becomes
//!   [`Crs::Proj`], its PROJ string followed by the description as
//!   `+title="…"` (see [`super::projection`]); without them it stays
//!   [`Crs::Projected`], the description alone.

use cota_core::{Crs, GeoRef, PixelIs};
use tiff::decoder::ifd::Value;

use super::projection::{is_projection_key, ProjKeys};
use crate::error::{malformed, ReadErrorKind};

/// GeoKey ids used here.
mod key {
    pub const MODEL_TYPE: u16 = 1024;
    pub const RASTER_TYPE: u16 = 1025;
    pub const GT_CITATION: u16 = 1026;
    pub const GEOGRAPHIC_TYPE: u16 = 2048;
    pub const GEOG_CITATION: u16 = 2049;
    pub const PROJECTED_TYPE: u16 = 3072;
    pub const PCS_CITATION: u16 = 3073;
    pub const VERTICAL_UNITS: u16 = 4099;
}

/// Tag number of GeoAsciiParamsTag, as a key location.
const ASCII_PARAMS: u16 = 34737;
/// Tag number of GeoDoubleParamsTag, as a key location.
const DOUBLE_PARAMS: u16 = 34736;
/// GeoKey value meaning "user-defined".
const USER_DEFINED: u16 = 32767;

/// The GeoKeys cota uses, as found in the directory.
#[derive(Debug, Default, Clone, PartialEq)]
pub(super) struct GeoKeys {
    model_type: Option<u16>,
    raster_type: Option<u16>,
    projected_type: Option<u16>,
    geographic_type: Option<u16>,
    gt_citation: Option<String>,
    geog_citation: Option<String>,
    pcs_citation: Option<String>,
    vertical_units: Option<u16>,
    /// The keys of a user-defined projection and datum.
    proj: ProjKeys,
}

/// The raw georeferencing tags of the image.
#[derive(Debug, Default, Clone)]
pub(super) struct GeoTags {
    /// ModelPixelScaleTag 33550.
    pub scale: Option<Vec<f64>>,
    /// ModelTiepointTag 33922.
    pub tiepoints: Option<Vec<f64>>,
    /// ModelTransformationTag 34264.
    pub matrix: Option<Vec<f64>>,
    /// GeoKeyDirectoryTag 34735.
    pub key_directory: Option<Vec<u16>>,
    /// GeoAsciiParamsTag 34737.
    pub ascii_params: Option<String>,
    /// GeoDoubleParamsTag 34736.
    pub double_params: Option<Vec<f64>>,
}

/// What the georeferencing tags give: the grid's georeference and the factor
/// from the file's vertical unit to metres.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct GeoInfo {
    pub georef: GeoRef,
    pub vertical_to_m: f32,
}

/// A north-up affine transform, before orientation normalisation.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Affine {
    origin_x: f64,
    origin_y: f64,
    pixel_x: f64,
    pixel_y: f64,
}

/// Numbers of a tag value (any numeric TIFF type, single or list).
pub(super) fn numbers(v: Value) -> Option<Vec<f64>> {
    match v {
        Value::List(vs) => vs.into_iter().map(number).collect(),
        other => number(other).map(|x| vec![x]),
    }
}

fn number(v: Value) -> Option<f64> {
    Some(match v {
        Value::Byte(x) => f64::from(x),
        Value::Short(x) => f64::from(x),
        Value::SignedByte(x) => f64::from(x),
        Value::SignedShort(x) => f64::from(x),
        Value::Signed(x) => f64::from(x),
        Value::Unsigned(x) => f64::from(x),
        Value::SignedBig(x) => x as f64,
        Value::UnsignedBig(x) => x as f64,
        Value::Float(x) => f64::from(x),
        Value::Double(x) => x,
        Value::Rational(n, d) => f64::from(n) / f64::from(d),
        Value::SRational(n, d) => f64::from(n) / f64::from(d),
        _ => return None,
    })
}

/// Unsigned 16-bit numbers of a tag value (GeoKeyDirectoryTag is SHORT).
pub(super) fn shorts(v: Value) -> Option<Vec<u16>> {
    numbers(v)?
        .into_iter()
        .map(|x| (x.fract() == 0.0 && (0.0..=f64::from(u16::MAX)).contains(&x)).then_some(x as u16))
        .collect()
}

/// Parses GeoKeyDirectoryTag 34735 with the GeoAsciiParamsTag 34737 text
/// and the GeoDoubleParamsTag 34736 values.
///
/// # Errors
/// [`ReadErrorKind::Malformed`] when the directory is shorter than its header says.
pub(super) fn parse_key_directory(
    dir: &[u16],
    ascii: &str,
    doubles: &[f64],
) -> Result<GeoKeys, ReadErrorKind> {
    let [_version, _revision, _minor, count, ref entries @ ..] = *dir else {
        return Err(malformed(
            "a GeoKeyDirectoryTag 34735 header of 4 SHORTs",
            format!("{} values", dir.len()),
        ));
    };
    let count = usize::from(count);
    if entries.len() < 4 * count {
        return Err(malformed(
            format!(
                "{} SHORTs in GeoKeyDirectoryTag 34735 for {count} keys",
                4 + 4 * count
            ),
            format!("{}", dir.len()),
        ));
    }
    let mut keys = GeoKeys::default();
    for entry in entries.chunks_exact(4).take(count) {
        if let [id, location, n, value] = *entry {
            keys.set(id, location, n, value, ascii);
            if is_projection_key(id) {
                keys.set_projection(id, location, n, value, doubles);
            }
        }
    }
    Ok(keys)
}

impl GeoKeys {
    /// Records one directory entry, ignoring keys cota does not use.
    fn set(&mut self, id: u16, location: u16, count: u16, value: u16, ascii: &str) {
        let short = (location == 0).then_some(value);
        let text = || (location == ASCII_PARAMS).then(|| ascii_param(ascii, value, count))?;
        match id {
            key::MODEL_TYPE => self.model_type = short,
            key::RASTER_TYPE => self.raster_type = short,
            key::GEOGRAPHIC_TYPE => self.geographic_type = short,
            key::PROJECTED_TYPE => self.projected_type = short,
            key::VERTICAL_UNITS => self.vertical_units = short,
            key::GT_CITATION => self.gt_citation = text(),
            key::GEOG_CITATION => self.geog_citation = text(),
            key::PCS_CITATION => self.pcs_citation = text(),
            _ => {}
        }
    }

    /// Records a key of a user-defined projection: a SHORT in the entry, or
    /// `count` doubles at `offset` of GeoDoubleParamsTag (dropped when out of range).
    fn set_projection(&mut self, id: u16, location: u16, count: u16, value: u16, doubles: &[f64]) {
        match location {
            0 => {
                self.proj.shorts.insert(id, value);
            }
            DOUBLE_PARAMS => {
                let start = usize::from(value);
                if let Some(v) = doubles.get(start..start + usize::from(count)) {
                    self.proj.doubles.insert(id, v.to_vec());
                }
            }
            _ => {}
        }
    }

    /// The coordinate reference system the keys describe.
    pub(super) fn crs(&self) -> Crs {
        match self.model_type {
            Some(1) => self.projected_crs(),
            Some(2) => self.geographic_crs(),
            Some(_) => Crs::Unknown,
            None if self.projected_type.is_some() => self.projected_crs(),
            None if self.geographic_type.is_some() => self.geographic_crs(),
            None => Crs::Unknown,
        }
    }

    /// A projected CRS: its EPSG code, or its citation followed by the
    /// geographic CRS's citation (the datum and ellipsoid of a user-defined
    /// projection: "UTM Zone 25, Southern Hemisphere; GCS Name = GRS
    /// 1980(IUGG, 1980); Datum = unknown; …"), which the imagery reader's CRS
    /// rule reads.
    fn projected_crs(&self) -> Crs {
        if let Some(code) = epsg(self.projected_type) {
            return Crs::Epsg(code);
        }
        let name = self
            .pcs_citation
            .clone()
            .or_else(|| self.gt_citation.clone())
            .unwrap_or_else(|| user_defined("projected", self.projected_type));
        let description = match &self.geog_citation {
            Some(g) if !name.contains(g.as_str()) => format!("{name}; {g}"),
            _ => name,
        };
        match self.proj.definition(self.geographic_type) {
            Some(def) => Crs::Proj(format!(
                "{def} +title=\"{}\"",
                description.replace('"', "'")
            )),
            None => Crs::Projected(description),
        }
    }

    fn geographic_crs(&self) -> Crs {
        match epsg(self.geographic_type) {
            Some(code) => Crs::Epsg(code),
            None => Crs::Geographic(
                self.geog_citation
                    .clone()
                    .or_else(|| self.gt_citation.clone())
                    .unwrap_or_else(|| user_defined("geographic", self.geographic_type)),
            ),
        }
    }

    /// PixelIsPoint when GTRasterTypeGeoKey is 2, else PixelIsArea (the default).
    fn pixel_is(&self) -> PixelIs {
        match self.raster_type {
            Some(2) => PixelIs::Point,
            _ => PixelIs::Area,
        }
    }

    /// Factor from VerticalUnitsGeoKey's unit to metres; 1 when absent or unknown.
    fn vertical_to_m(&self) -> f32 {
        match self.vertical_units {
            Some(9002) => 0.3048,          // international foot
            Some(9003) => 1200.0 / 3937.0, // US survey foot
            Some(9036) => 1000.0,          // kilometre
            _ => 1.0,                      // metre (9001), absent or user-defined
        }
    }
}

/// An EPSG code from a CRS key: 1..=32766 (0 is undefined, 32767 user-defined,
/// above that private).
fn epsg(code: Option<u16>) -> Option<u32> {
    code.filter(|c| (1..USER_DEFINED).contains(c))
        .map(u32::from)
}

fn user_defined(kind: &str, code: Option<u16>) -> String {
    match code {
        Some(c) if c != USER_DEFINED && c != 0 => format!("{kind} CRS with private code {c}"),
        _ => format!("user-defined {kind} CRS"),
    }
}

/// The citation at `offset..offset+count` of the ASCII params, cleaned: the
/// `|` separators of GDAL's "GCS Name = …|Datum = …|" style become "; ", and
/// surrounding blanks go. A count running past the end is cut short; `None`
/// when the offset is out of range or the text empty.
fn ascii_param(ascii: &str, offset: u16, count: u16) -> Option<String> {
    let start = usize::from(offset);
    let end = (start + usize::from(count)).min(ascii.len());
    let raw = ascii.get(start..end)?;
    let parts: Vec<&str> = raw
        .split('|')
        .map(str::trim)
        .filter(|p| !p.is_empty())
        .collect();
    (!parts.is_empty()).then(|| parts.join("; "))
}

/// The transform from the tags: scale + tiepoint, else the matrix.
///
/// # Errors
/// [`ReadErrorKind::Unsupported`] for rotated/sheared matrices and for tie
/// points without a pixel scale (ground control points);
/// [`ReadErrorKind::Malformed`] for short or degenerate values.
fn affine(tags: &GeoTags) -> Result<Option<Affine>, ReadErrorKind> {
    match (&tags.scale, &tags.tiepoints, &tags.matrix) {
        (Some(scale), Some(tie), _) => from_scale_and_tiepoint(scale, tie).map(Some),
        (_, _, Some(m)) => from_matrix(m).map(Some),
        (None, Some(tie), None) => Err(ReadErrorKind::Unsupported {
            what: "GeoTIFF georeferencing".into(),
            detail: format!(
                "{} tie point(s) in ModelTiepointTag 33922 without ModelPixelScaleTag 33550 (ground control points); only scale + tie point or ModelTransformationTag 34264 are read",
                tie.len() / 6
            ),
        }),
        _ => Ok(None),
    }
}

fn from_scale_and_tiepoint(scale: &[f64], tie: &[f64]) -> Result<Affine, ReadErrorKind> {
    let (&[sx, sy, ..], &[i, j, _, x, y, ..]) = (scale, tie) else {
        return Err(malformed(
            "at least 2 values in ModelPixelScaleTag 33550 and 6 in ModelTiepointTag 33922",
            format!("{} and {}", scale.len(), tie.len()),
        ));
    };
    let usable = [sx, sy, i, j, x, y].iter().all(|v| v.is_finite()) && sx != 0.0 && sy != 0.0;
    if !usable {
        return Err(malformed(
            "a finite non-zero pixel scale and a finite tie point",
            format!("scale ({sx}, {sy}), tie point ({i}, {j}) -> ({x}, {y})"),
        ));
    }
    Ok(Affine {
        origin_x: x - i * sx,
        origin_y: y + j * sy,
        pixel_x: sx,
        pixel_y: -sy,
    })
}

fn from_matrix(m: &[f64]) -> Result<Affine, ReadErrorKind> {
    let &[a, b, _, d, e, f, _, h, ..] = m else {
        return Err(malformed(
            "16 values in ModelTransformationTag 34264",
            format!("{}", m.len()),
        ));
    };
    if !(b == 0.0 && e == 0.0) {
        return Err(ReadErrorKind::Unsupported {
            what: "GeoTIFF georeferencing".into(),
            detail: format!(
                "rotated or sheared ModelTransformationTag 34264 (row term {b}, column term {e}); only north-up grids are read"
            ),
        });
    }
    let usable = [a, d, f, h].iter().all(|v| v.is_finite()) && a != 0.0 && f != 0.0;
    if !usable {
        return Err(malformed(
            "finite non-zero pixel sizes in ModelTransformationTag 34264",
            format!("x size {a}, y size {f}, origin ({d}, {h})"),
        ));
    }
    Ok(Affine {
        origin_x: d,
        origin_y: h,
        pixel_x: a,
        pixel_y: f,
    })
}

/// Builds the georeference from the tags.
///
/// Without a transform the georeference is a placeholder (`known: false`) at
/// (0, 0) with the ModelPixelScale's pixel size, or 1 without it; the CRS still
/// comes from the GeoKeys if there are any.
///
/// # Errors
/// See [`affine`] and [`parse_key_directory`].
pub(super) fn geo_info(tags: &GeoTags) -> Result<GeoInfo, ReadErrorKind> {
    let keys = match &tags.key_directory {
        Some(dir) => Some(parse_key_directory(
            dir,
            tags.ascii_params.as_deref().unwrap_or(""),
            tags.double_params.as_deref().unwrap_or(&[]),
        )?),
        None => None,
    };
    let crs = keys.as_ref().map_or(Crs::Unknown, GeoKeys::crs);
    let vertical_to_m = keys.as_ref().map_or(1.0, GeoKeys::vertical_to_m);
    let georef = match affine(tags)? {
        Some(t) => GeoRef {
            crs,
            origin_x: t.origin_x,
            origin_y: t.origin_y,
            pixel_x: t.pixel_x,
            pixel_y: t.pixel_y,
            pixel_is: keys.as_ref().map_or(PixelIs::Area, GeoKeys::pixel_is),
            known: true,
        },
        None => placeholder(crs, tags.scale.as_deref()),
    };
    Ok(GeoInfo {
        georef,
        vertical_to_m,
    })
}

/// A georeference with no position: origin (0, 0), the pixel scale if usable.
fn placeholder(crs: Crs, scale: Option<&[f64]>) -> GeoRef {
    let (sx, sy) = match scale {
        Some(&[sx, sy, ..]) if sx.is_finite() && sy.is_finite() && sx > 0.0 && sy > 0.0 => (sx, sy),
        _ => (1.0, 1.0),
    };
    GeoRef {
        crs,
        pixel_x: sx,
        pixel_y: -sy,
        ..GeoRef::unreferenced(1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A key directory with the given (id, location, count, value) entries.
    fn directory(entries: &[[u16; 4]]) -> Vec<u16> {
        let mut d = vec![1, 1, 0, entries.len() as u16];
        d.extend(entries.iter().flatten());
        d
    }

    #[test]
    fn epsg_keys() {
        let d = directory(&[[1024, 0, 1, 2], [1025, 0, 1, 1], [2048, 0, 1, 4326]]);
        let k = parse_key_directory(&d, "", &[]).unwrap();
        assert_eq!(k.crs(), Crs::Epsg(4326));
        assert_eq!(k.pixel_is(), PixelIs::Area);
        let d = directory(&[[1024, 0, 1, 1], [1025, 0, 1, 2], [3072, 0, 1, 3857]]);
        let k = parse_key_directory(&d, "", &[]).unwrap();
        assert_eq!(k.crs(), Crs::Epsg(3857));
        assert_eq!(k.pixel_is(), PixelIs::Point);
    }

    #[test]
    fn user_defined_keys_use_citations() {
        let ascii = "UTM Zone 25, Southern Hemisphere|GCS Name = GRS 1980|Datum = unknown||";
        let d = directory(&[
            [1024, 0, 1, 1],
            [1026, ASCII_PARAMS, 33, 0],
            [2048, 0, 1, 32767],
            [2049, ASCII_PARAMS, 36, 33],
            [3072, 0, 1, 32767],
        ]);
        let k = parse_key_directory(&d, ascii, &[]).unwrap();
        assert_eq!(
            k.crs(),
            Crs::Projected(
                "UTM Zone 25, Southern Hemisphere; GCS Name = GRS 1980; Datum = unknown".into()
            )
        );
        let d = directory(&[
            [1024, 0, 1, 2],
            [2048, 0, 1, 32767],
            [2049, ASCII_PARAMS, 38, 33], // count past the end: cut short
        ]);
        let k = parse_key_directory(&d, ascii, &[]).unwrap();
        assert_eq!(
            k.crs(),
            Crs::Geographic("GCS Name = GRS 1980; Datum = unknown".into())
        );
        // No citation at all; citation pointing outside the params.
        let d = directory(&[
            [1024, 0, 1, 2],
            [2048, 0, 1, 32767],
            [2049, ASCII_PARAMS, 9, 500],
        ]);
        let k = parse_key_directory(&d, ascii, &[]).unwrap();
        assert_eq!(
            k.crs(),
            Crs::Geographic("user-defined geographic CRS".into())
        );
        let d = directory(&[[3072, 0, 1, 40000]]);
        let k = parse_key_directory(&d, "", &[]).unwrap();
        assert_eq!(
            k.crs(),
            Crs::Projected("projected CRS with private code 40000".into())
        );
    }

    #[test]
    fn user_defined_projection_becomes_a_definition() {
        // The keys of texture/olinda_dem_utm25s.tif (GDAL's user-defined UTM 25S).
        let ascii = "UTM Zone 25, Southern Hemisphere|GCS Name = GRS 1980(IUGG, 1980)|Datum = unknown|Ellipsoid = GRS80|Primem = Greenwich||";
        let d = directory(&[
            [1024, 0, 1, 1],
            [1026, ASCII_PARAMS, 33, 0],
            [2048, 0, 1, 32767],
            [2049, ASCII_PARAMS, 86, 33],
            [2050, 0, 1, 32767],
            [2054, 0, 1, 9102],
            [2056, 0, 1, 32767],
            [2057, DOUBLE_PARAMS, 1, 0],
            [2059, DOUBLE_PARAMS, 1, 1],
            [2061, DOUBLE_PARAMS, 1, 2],
            [2062, DOUBLE_PARAMS, 3, 3],
            [3072, 0, 1, 32767],
            [3074, 0, 1, 16125],
            [3076, 0, 1, 9001],
        ]);
        let doubles = [6_378_137.0, 298.257_222_101, 0.0, 0.0, 0.0, 0.0];
        let k = parse_key_directory(&d, ascii, &doubles).unwrap();
        assert_eq!(
            k.crs(),
            Crs::Proj(
                "+proj=utm +zone=25 +south +ellps=GRS80 +towgs84=0,0,0 +units=m +no_defs \
                 +title=\"UTM Zone 25, Southern Hemisphere; GCS Name = GRS 1980(IUGG, 1980); \
                 Datum = unknown; Ellipsoid = GRS80; Primem = Greenwich\""
                    .into()
            )
        );
        // Doubles out of range: no ellipsoid, so the description alone.
        let k = parse_key_directory(&d, ascii, &doubles[..2]).unwrap();
        assert!(matches!(k.crs(), Crs::Proj(_)), "2057 and 2059 are enough");
        let k = parse_key_directory(&d, ascii, &[]).unwrap();
        assert!(matches!(k.crs(), Crs::Projected(_)), "{:?}", k.crs());
    }

    #[test]
    fn short_directory_is_malformed() {
        let mut d = directory(&[[1024, 0, 1, 2], [2048, 0, 1, 4326]]);
        d.truncate(9);
        let e = parse_key_directory(&d, "", &[]).unwrap_err().to_string();
        assert!(e.contains("12 SHORTs") && e.contains("found 9"), "{e}");
        assert!(parse_key_directory(&[1, 1], "", &[]).is_err());
    }

    #[test]
    fn tiepoint_maps_raster_point_to_origin() {
        let tags = GeoTags {
            scale: Some(vec![2.0, 3.0, 0.0]),
            tiepoints: Some(vec![10.0, 20.0, 0.0, 1000.0, 5000.0, 0.0]),
            ..GeoTags::default()
        };
        let g = geo_info(&tags).unwrap().georef;
        assert_eq!((g.origin_x, g.origin_y), (980.0, 5060.0));
        assert_eq!((g.pixel_x, g.pixel_y), (2.0, -3.0));
        assert!(g.known);
        assert_eq!(g.crs, Crs::Unknown);
    }

    #[test]
    fn matrix_without_rotation_is_read_and_with_rotation_refused() {
        let mut m = vec![0.0; 16];
        m[0] = 30.0;
        m[3] = 500_000.0;
        m[5] = -30.0;
        m[7] = 4_000_000.0;
        m[15] = 1.0;
        let tags = GeoTags {
            matrix: Some(m.clone()),
            ..GeoTags::default()
        };
        let g = geo_info(&tags).unwrap().georef;
        assert_eq!(
            (g.origin_x, g.origin_y, g.pixel_x, g.pixel_y),
            (500_000.0, 4_000_000.0, 30.0, -30.0)
        );
        m[1] = 0.5;
        let tags = GeoTags {
            matrix: Some(m),
            ..GeoTags::default()
        };
        let e = geo_info(&tags).unwrap_err().to_string();
        assert!(
            e.starts_with("unsupported GeoTIFF georeferencing: rotated"),
            "{e}"
        );
    }

    #[test]
    fn gcps_are_refused_and_scale_alone_gives_a_placeholder() {
        let tags = GeoTags {
            tiepoints: Some(vec![0.0; 24]),
            ..GeoTags::default()
        };
        let e = geo_info(&tags).unwrap_err().to_string();
        assert!(e.contains("4 tie point(s)"), "{e}");
        let tags = GeoTags {
            scale: Some(vec![5.0, 5.0, 0.0]),
            ..GeoTags::default()
        };
        let g = geo_info(&tags).unwrap().georef;
        assert!(!g.known);
        assert_eq!((g.pixel_x, g.pixel_y), (5.0, -5.0));
        let g = geo_info(&GeoTags::default()).unwrap().georef;
        assert_eq!(g, GeoRef::unreferenced(1.0));
    }

    #[test]
    fn vertical_units() {
        let d = directory(&[[4099, 0, 1, 9002]]);
        let k = parse_key_directory(&d, "", &[]).unwrap();
        assert_eq!(k.vertical_to_m(), 0.3048);
        assert_eq!(GeoKeys::default().vertical_to_m(), 1.0);
    }
}
