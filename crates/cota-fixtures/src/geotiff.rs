//! A small GeoTIFF writer (north-up, one float32 band) and reader (the same
//! shape: float32 strips, scale + tie point, GDAL nodata), for test inputs
//! made at test time.
//!
//! Reference: the OGC GeoTIFF standard 1.1 (OGC 19-008r4): ModelPixelScaleTag
//! 33550, ModelTiepointTag 33922, GeoKeyDirectoryTag 34735 with
//! GTModelTypeGeoKey 1024 (1 projected, 2 geographic), GTRasterTypeGeoKey
//! 1025 (1 PixelIsArea), GeographicTypeGeoKey 2048, GeogAngularUnitsGeoKey
//! 2054 (9102 degree), ProjectedCSTypeGeoKey 3072, ProjLinearUnitsGeoKey 3076
//! (9001 metre); GDAL's GDAL_NODATA tag 42113 (the nodata value as text).
//! These are the tags `cota-io`'s GeoTIFF reader takes.

use std::io::{self, Cursor};
use std::path::Path;

use tiff::decoder::{Decoder, DecodingResult};
use tiff::encoder::{colortype, TiffEncoder};
use tiff::tags::Tag;

/// The CRS of a GeoTIFF to write, by EPSG code.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GeoTiffCrs {
    /// A projected CRS in metres (ProjectedCSTypeGeoKey).
    Projected(u16),
    /// A geographic CRS in degrees (GeographicTypeGeoKey).
    Geographic(u16),
}

/// A north-up, single-band float32 GeoTIFF (pixel-is-area).
#[derive(Debug, Clone, Copy)]
pub struct GeoTiff<'a> {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// `width × height` heights, row-major from the north-west; NaN voids
    /// are written as `nodata`.
    pub heights: &'a [f32],
    /// CRS x of the west edge of the first column (the pixels' outer corner).
    pub west: f64,
    /// CRS y of the north edge of the first row.
    pub north: f64,
    /// Pixel size in CRS units along a row (east).
    pub pixel: f64,
    /// Pixel size in CRS units down a column (south); 0: the same as
    /// `pixel` (square pixels).
    pub pixel_y: f64,
    /// The CRS.
    pub crs: GeoTiffCrs,
    /// The nodata value written for voids (GDAL_NODATA).
    pub nodata: f32,
}

/// The GeoKeyDirectoryTag values of `crs` (pixel-is-area).
fn geokeys(crs: GeoTiffCrs) -> Vec<u16> {
    let mut keys = vec![1, 1, 0, 4];
    match crs {
        GeoTiffCrs::Projected(code) => keys.extend([
            1024, 0, 1, 1, 1025, 0, 1, 1, 3072, 0, 1, code, 3076, 0, 1, 9001,
        ]),
        GeoTiffCrs::Geographic(code) => keys.extend([
            1024, 0, 1, 2, 1025, 0, 1, 1, 2048, 0, 1, code, 2054, 0, 1, 9102,
        ]),
    }
    keys
}

/// The bytes of the GeoTIFF `g` (uncompressed strips).
///
/// # Errors
/// When the heights do not hold `width × height` values, or the encoder fails.
pub fn geotiff_bytes(g: &GeoTiff<'_>) -> io::Result<Vec<u8>> {
    if g.heights.len() != g.width * g.height {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!(
                "expected {} heights for {}x{}, found {}",
                g.width * g.height,
                g.width,
                g.height,
                g.heights.len()
            ),
        ));
    }
    let data: Vec<f32> = g
        .heights
        .iter()
        .map(|h| if h.is_nan() { g.nodata } else { *h })
        .collect();
    let size = |n: usize| u32::try_from(n).map_err(io::Error::other);
    let mut buf = Vec::new();
    let mut enc = TiffEncoder::new(Cursor::new(&mut buf)).map_err(io::Error::other)?;
    let mut img = enc
        .new_image::<colortype::Gray32Float>(size(g.width)?, size(g.height)?)
        .map_err(io::Error::other)?;
    let e = img.encoder();
    let tags: [(Tag, &[f64]); 2] = [
        (
            Tag::ModelPixelScaleTag,
            &[
                g.pixel,
                if g.pixel_y > 0.0 { g.pixel_y } else { g.pixel },
                0.0,
            ],
        ),
        (
            Tag::ModelTiepointTag,
            &[0.0, 0.0, 0.0, g.west, g.north, 0.0],
        ),
    ];
    for (tag, v) in tags {
        e.write_tag(tag, v).map_err(io::Error::other)?;
    }
    e.write_tag(Tag::GeoKeyDirectoryTag, &geokeys(g.crs)[..])
        .map_err(io::Error::other)?;
    e.write_tag(Tag::GdalNodata, g.nodata.to_string().as_str())
        .map_err(io::Error::other)?;
    img.write_data(&data).map_err(io::Error::other)?;
    Ok(buf)
}

/// Writes the GeoTIFF `g` to `path`.
///
/// # Errors
/// As [`geotiff_bytes`], and the file's own errors.
pub fn write_geotiff(path: &Path, g: &GeoTiff<'_>) -> io::Result<()> {
    std::fs::write(path, geotiff_bytes(g)?)
}

/// A north-up float32 GeoTIFF as read: heights (nodata as NaN) and where the
/// pixels' outer corner is.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadGeoTiff {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Heights, row-major from the north-west; nodata is NaN.
    pub heights: Vec<f32>,
    /// x of the west edge (pixel-is-area corner), CRS units.
    pub west: f64,
    /// y of the north edge.
    pub north: f64,
    /// Pixel width, CRS units.
    pub pixel_x: f64,
    /// Pixel height (positive), CRS units.
    pub pixel_y: f64,
}

/// Reads a single-band float32 GeoTIFF with a pixel scale and a tie point
/// (pixel-is-area), GDAL_NODATA samples becoming NaN: the shape of the
/// shared `geotiff/dem-hills.tiff`.
///
/// # Errors
/// The reason, when the file is another kind of TIFF or unreadable.
pub fn read_geotiff_f32(path: &Path) -> Result<ReadGeoTiff, String> {
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    let mut dec = Decoder::new(Cursor::new(bytes)).map_err(|e| e.to_string())?;
    let (w, h) = dec.dimensions().map_err(|e| e.to_string())?;
    let scale = dec
        .get_tag_f64_vec(Tag::ModelPixelScaleTag)
        .map_err(|e| format!("ModelPixelScaleTag: {e}"))?;
    let tie = dec
        .get_tag_f64_vec(Tag::ModelTiepointTag)
        .map_err(|e| format!("ModelTiepointTag: {e}"))?;
    let nodata: Option<f32> = dec
        .get_tag_ascii_string(Tag::GdalNodata)
        .ok()
        .and_then(|s| {
            s.trim_matches(|c: char| c == '\0' || c.is_whitespace())
                .parse()
                .ok()
        });
    let (&[sx, sy, ..], &[i, j, _, x, y, ..]) = (&scale[..], &tie[..]) else {
        return Err("expected 2 pixel scales and a 6-value tie point".to_string());
    };
    let DecodingResult::F32(mut heights) = dec.read_image().map_err(|e| e.to_string())? else {
        return Err("expected float32 samples".to_string());
    };
    for v in &mut heights {
        if Some(*v) == nodata {
            *v = f32::NAN;
        }
    }
    Ok(ReadGeoTiff {
        width: w as usize,
        height: h as usize,
        heights,
        west: x - i * sx,
        north: y + j * sy,
        pixel_x: sx,
        pixel_y: sy,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn written_files_read_back() {
        let heights = [1.0, f32::NAN, 3.0, 4.5, 5.0, 6.0];
        let g = GeoTiff {
            width: 3,
            height: 2,
            heights: &heights,
            west: 500_000.0,
            north: 4_000_000.0,
            pixel: 30.0,
            pixel_y: 0.0,
            crs: GeoTiffCrs::Projected(32633),
            nodata: -9999.0,
        };
        let dir =
            std::env::temp_dir().join(format!("cota-fixtures-geotiff-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.tif");
        write_geotiff(&path, &g).unwrap();
        let r = read_geotiff_f32(&path).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(
            (r.width, r.height, r.west, r.north),
            (3, 2, 500_000.0, 4_000_000.0)
        );
        assert_eq!((r.pixel_x, r.pixel_y), (30.0, 30.0));
        assert!(r.heights[1].is_nan());
        assert_eq!(r.heights[5], 6.0);
        assert!(geotiff_bytes(&GeoTiff { width: 4, ..g }).is_err());
    }
}
