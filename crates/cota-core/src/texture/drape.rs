//! An image georeferenced against a DEM: its placement, its resampling onto
//! the texture raster that spans the DEM, and the texture coordinates of the
//! DEM's samples.
//!
//! Paper `004_ab8d08b3e6a5a70a.txt` maps a satellite photograph onto the
//! terrain; the photograph and the DEM share a CRS but not their resolution
//! or extent. Here:
//! * [`ImagePlacement`]: the outer corner of the image's first pixel and its
//!   pixel size, in the DEM's CRS units (the caller has checked that the CRSs
//!   agree);
//! * the **texture raster** spans the DEM's *samples*: from the centre of
//!   sample column 0 to that of column `W−1` (rows likewise), cut into
//!   `tw × th` texels of about the image's own pixel size
//!   (`tw = round((W−1)·|dx| / |image pixel x|)`, at least 1, at most
//!   [`DrapeOptions::max_side_texels`]). So a mesh vertex at sample
//!   `(col, row)` has the texture coordinates `u = col/(W−1)`,
//!   `v = row/(H−1)` ([`uv`]), glTF's convention (origin at the top-left
//!   corner of the image, row 0 north), and lies in texel
//!   `(⌊u·tw⌋, ⌊v·th⌋)` (the last texel for `u = 1`);
//! * [`drape()`] samples the image at every texel's centre **bilinearly, per
//!   channel** (the four nearest pixel centres, weights by distance, rounded
//!   to the nearest level); within half a pixel of the image's border the
//!   nearest edge pixels are used (clamped). A texel centre outside the
//!   image's footprint is not covered, and any such texel is an error
//!   ([`TextureError::NotCovered`]): cota does not invent colour.

use rayon::prelude::*;

use super::error::TextureError;
use super::image::RgbImage;
use crate::grid::{GeoRef, HeightGrid, PixelIs};

/// Where an image lies, in the DEM's CRS units: `x = origin_x + i·pixel_x`
/// for pixel edge `i` (0 = the west edge of the first column), likewise y
/// (`pixel_y` negative for north-up images).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImagePlacement {
    /// x of the outer corner of the first pixel.
    pub origin_x: f64,
    /// y of the outer corner of the first pixel.
    pub origin_y: f64,
    /// Pixel size along a row (positive: columns go east).
    pub pixel_x: f64,
    /// Pixel size down a column (negative: rows go south).
    pub pixel_y: f64,
}

impl ImagePlacement {
    /// The placement a raster's georeference gives (its pixel-is convention
    /// turned into the outer corner of the first pixel).
    pub fn from_georef(g: &GeoRef) -> Self {
        let half = match g.pixel_is {
            PixelIs::Area => 0.0,
            PixelIs::Point => 0.5,
        };
        ImagePlacement {
            origin_x: g.origin_x - half * g.pixel_x,
            origin_y: g.origin_y - half * g.pixel_y,
            pixel_x: g.pixel_x,
            pixel_y: g.pixel_y,
        }
    }

    /// An image of `width × height` pixels stretched over the DEM's
    /// footprint: its outer edges on the outer edges of the DEM's cells
    /// (half a cell beyond the outer samples), for images that carry no
    /// georeference of their own.
    pub fn spanning(grid: &HeightGrid, width: usize, height: usize) -> Self {
        let g = grid.georef();
        let (x0, y0) = g.sample_xy(-0.5, -0.5);
        let (x1, y1) = g.sample_xy(grid.width() as f64 - 0.5, grid.height() as f64 - 0.5);
        ImagePlacement {
            origin_x: x0,
            origin_y: y0,
            pixel_x: (x1 - x0) / width as f64,
            pixel_y: (y1 - y0) / height as f64,
        }
    }

    /// [`TextureError::BadPlacement`] unless every number is finite and the
    /// pixel sizes are not zero.
    fn validate(&self) -> Result<(), TextureError> {
        let p = [self.origin_x, self.origin_y, self.pixel_x, self.pixel_y];
        if p.iter().all(|v| v.is_finite()) && self.pixel_x != 0.0 && self.pixel_y != 0.0 {
            return Ok(());
        }
        Err(TextureError::BadPlacement {
            origin_x: self.origin_x,
            origin_y: self.origin_y,
            pixel_x: self.pixel_x,
            pixel_y: self.pixel_y,
        })
    }
}

/// Options of [`drape()`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub struct DrapeOptions {
    /// Largest texture side in texels (GPUs take 8192 at least). Default: 8192.
    pub max_side_texels: usize,
}

impl DrapeOptions {
    /// The defaults, as documented on each field.
    pub const DEFAULT: DrapeOptions = DrapeOptions {
        max_side_texels: 8192,
    };

    /// Sets [`DrapeOptions::max_side_texels`] (at least 1).
    pub const fn with_max_side_texels(mut self, n: usize) -> Self {
        self.max_side_texels = if n == 0 { 1 } else { n };
        self
    }
}

impl Default for DrapeOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The texture coordinates `[u, v]` of the sample at (`col`, `row`) of
/// `grid` (see the module docs): `u = col/(W−1)`, `v = row/(H−1)`.
pub fn uv(grid: &HeightGrid, col: f64, row: f64) -> [f64; 2] {
    let span = |n: usize| (n.max(2) - 1) as f64;
    [col / span(grid.width()), row / span(grid.height())]
}

/// The texture raster's size for `grid` and an image of `at`'s pixel size.
pub fn texture_size(grid: &HeightGrid, at: &ImagePlacement, opts: &DrapeOptions) -> [usize; 2] {
    let g = grid.georef();
    let texels = |samples: usize, cell: f64, pixel: f64| {
        let n = ((samples.max(2) - 1) as f64 * cell.abs() / pixel.abs()).round();
        (n.max(1.0) as usize).min(opts.max_side_texels.max(1))
    };
    [
        texels(grid.width(), g.pixel_x, at.pixel_x),
        texels(grid.height(), g.pixel_y, at.pixel_y),
    ]
}

/// Resamples `image`, placed at `at` in `grid`'s CRS, onto the texture raster
/// that spans `grid`'s samples (see the module docs: bilinear per channel).
///
/// # Errors
/// [`TextureError::BadPlacement`]; [`TextureError::NotCovered`] when any
/// texel centre lies outside the image.
pub fn drape(
    image: &RgbImage,
    at: &ImagePlacement,
    grid: &HeightGrid,
    opts: &DrapeOptions,
) -> Result<RgbImage, TextureError> {
    at.validate()?;
    let [tw, th] = texture_size(grid, at, opts);
    let g = grid.georef();
    let (x0, y0) = g.sample_xy(0.0, 0.0);
    let (x1, y1) = g.sample_xy(grid.width() as f64 - 1.0, grid.height() as f64 - 1.0);
    // Image pixel coordinates (edges) of each texel centre's column and row.
    let fx: Vec<f64> = (0..tw)
        .map(|i| (x0 + (i as f64 + 0.5) / tw as f64 * (x1 - x0) - at.origin_x) / at.pixel_x)
        .collect();
    let fy: Vec<f64> = (0..th)
        .map(|j| (y0 + (j as f64 + 0.5) / th as f64 * (y1 - y0) - at.origin_y) / at.pixel_y)
        .collect();
    let (iw, ih) = (image.width() as f64, image.height() as f64);
    let inside = |f: f64, n: f64| (0.0..=n).contains(&f);
    let cols_in = fx.iter().filter(|&&f| inside(f, iw)).count();
    let rows_in = fy.iter().filter(|&&f| inside(f, ih)).count();
    if cols_in < tw || rows_in < th {
        return Err(TextureError::NotCovered {
            dem: extent(x0, x1, y0, y1),
            image: extent(
                at.origin_x,
                at.origin_x + iw * at.pixel_x,
                at.origin_y,
                at.origin_y + ih * at.pixel_y,
            ),
            uncovered: tw * th - cols_in * rows_in,
            texels: tw * th,
        });
    }
    let taps_x: Vec<Tap> = fx.iter().map(|&f| Tap::new(f, image.width())).collect();
    let pixels: Vec<[u8; 3]> = fy
        .par_iter()
        .flat_map_iter(|&f| {
            let ty = Tap::new(f, image.height());
            taps_x.iter().map(move |tx| bilinear(image, tx, &ty))
        })
        .collect();
    RgbImage::new(tw, th, pixels)
}

/// `x0..x1 × y0..y1`, for messages.
fn extent(x0: f64, x1: f64, y0: f64, y1: f64) -> String {
    let (xa, xb) = (x0.min(x1), x0.max(x1));
    let (ya, yb) = (y0.min(y1), y0.max(y1));
    format!("x {xa:.3}..{xb:.3}, y {ya:.3}..{yb:.3}")
}

/// The two pixel centres either side of a position along one axis, and the
/// weight of the second.
#[derive(Debug, Clone, Copy)]
struct Tap {
    i0: usize,
    i1: usize,
    t: f64,
}

impl Tap {
    /// `edge` in pixel-edge units (pixel `i`'s centre at `i + 0.5`), clamped
    /// to the centres of the first and last of `n` pixels.
    fn new(edge: f64, n: usize) -> Self {
        let c = (edge - 0.5).clamp(0.0, (n - 1) as f64);
        let i0 = (c.floor() as usize).min(n - 1);
        let i1 = (i0 + 1).min(n - 1);
        Tap {
            i0,
            i1,
            t: c - i0 as f64,
        }
    }
}

/// Bilinear interpolation of each channel, rounded to the nearest level.
fn bilinear(image: &RgbImage, x: &Tap, y: &Tap) -> [u8; 3] {
    let (a, b) = (image.get(x.i0, y.i0), image.get(x.i1, y.i0));
    let (c, d) = (image.get(x.i0, y.i1), image.get(x.i1, y.i1));
    std::array::from_fn(|k| {
        let top = f64::from(a[k]) * (1.0 - x.t) + f64::from(b[k]) * x.t;
        let bottom = f64::from(c[k]) * (1.0 - x.t) + f64::from(d[k]) * x.t;
        (top * (1.0 - y.t) + bottom * y.t).round().clamp(0.0, 255.0) as u8
    })
}

#[cfg(test)]
#[allow(clippy::unwrap_used, reason = "tests")]
mod tests {
    use super::*;

    fn grid(w: usize, h: usize, cell: f64) -> HeightGrid {
        let g = GeoRef {
            crs: crate::grid::Crs::Epsg(31985),
            origin_x: 1000.0,
            origin_y: 5000.0,
            pixel_x: cell,
            pixel_y: -cell,
            pixel_is: PixelIs::Area,
            known: true,
        };
        HeightGrid::new(w, h, vec![0.0; w * h], g).unwrap()
    }

    #[test]
    fn same_raster_is_copied_exactly() {
        // An image on the DEM's own cells: the texture spans the samples
        // (4x3 texels of the cell size) and a constant image stays constant.
        let g = grid(5, 4, 10.0);
        let img = RgbImage::new(5, 4, vec![[7, 8, 9]; 20]).unwrap();
        let at = ImagePlacement::from_georef(g.georef());
        let t = drape(&img, &at, &g, &DrapeOptions::DEFAULT).unwrap();
        assert_eq!([t.width(), t.height()], [4, 3]);
        assert!(t.pixels().iter().all(|p| *p == [7, 8, 9]));
    }

    #[test]
    fn a_linear_ramp_is_reproduced() {
        // Red grows by 2 per image pixel eastwards: bilinear reproduces a
        // linear ramp at every texel centre (to the rounding).
        let g = grid(11, 11, 30.0);
        let (w, h) = (40, 40);
        let px: Vec<[u8; 3]> = (0..w * h).map(|i| [(2 * (i % w)) as u8, 0, 0]).collect();
        let img = RgbImage::new(w, h, px).unwrap();
        let at = ImagePlacement {
            origin_x: 1000.0,
            origin_y: 5000.0,
            pixel_x: 10.0,
            pixel_y: -10.0,
        };
        let t = drape(&img, &at, &g, &DrapeOptions::DEFAULT).unwrap();
        assert_eq!(t.width(), 30);
        for i in 0..t.width() {
            // Texel centre x = 1015 + (i + 0.5)·10 -> image centre coordinate.
            let c = (15.0 + (i as f64 + 0.5) * 10.0) / 10.0 - 0.5;
            assert_eq!(t.get(i, 3)[0], (2.0 * c).round() as u8, "texel {i}");
        }
    }

    #[test]
    fn an_image_elsewhere_is_refused() {
        let g = grid(11, 11, 30.0);
        let img = RgbImage::new(4, 4, vec![[1, 2, 3]; 16]).unwrap();
        let at = ImagePlacement {
            origin_x: 90_000.0,
            origin_y: 5000.0,
            pixel_x: 10.0,
            pixel_y: -10.0,
        };
        let e = drape(&img, &at, &g, &DrapeOptions::DEFAULT).unwrap_err();
        assert!(
            matches!(e, TextureError::NotCovered { uncovered, texels, .. } if uncovered == texels)
        );
        let bad = ImagePlacement { pixel_x: 0.0, ..at };
        assert!(matches!(
            drape(&img, &bad, &g, &DrapeOptions::DEFAULT),
            Err(TextureError::BadPlacement { .. })
        ));
    }

    #[test]
    fn uv_spans_the_samples() {
        let g = grid(5, 3, 1.0);
        assert_eq!(uv(&g, 0.0, 0.0), [0.0, 0.0]);
        assert_eq!(uv(&g, 4.0, 2.0), [1.0, 1.0]);
        assert_eq!(uv(&g, 2.0, 1.0), [0.5, 0.5]);
    }
}
