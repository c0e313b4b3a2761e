//! The height grid: W×H heights in metres, per-sample validity, and the
//! georeference that places the samples on the Earth.
//!
//! # Conventions
//! * Samples are stored row-major, row 0 is the **northern** row (as in SRTM,
//!   GeoTIFF and PNG), column 0 the western column.
//! * A void (no data) is stored as `NaN`; validity is `!h.is_nan()`. Readers turn
//!   every nodata value (SRTM -32768, GDAL_NODATA, NODATA_value, NaN) into NaN, so
//!   there is exactly one representation of a void.
//! * The georeference is an affine transform from (column, row) to CRS
//!   coordinates, in the GDAL convention: `x = origin_x + col * pixel_x`,
//!   `y = origin_y + row * pixel_y` (`pixel_y` is negative for north-up grids),
//!   where `(col, row)` are *corner* coordinates when [`PixelIs::Area`] and
//!   *sample-centre* coordinates when [`PixelIs::Point`]. [`GeoRef::sample_xy`]
//!   hides the difference and gives the position of a sample.

pub mod extend;
mod frame;
pub mod geo;
pub mod mosaic;
pub mod voids;
mod wrap;

use std::fmt;

use rayon::prelude::*;

pub use frame::LocalFrame;
pub use geo::{GeoTransform, LonLat};

/// Largest number of samples a grid may hold (2^31, 8 GiB of f32 heights).
///
/// Readers check header dimensions against this before allocating, so an absurd
/// header gives an error instead of an allocation failure.
pub const MAX_SAMPLES: u64 = 1 << 31;

/// Errors from constructing or combining grids.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum GridError {
    /// Width or height is zero.
    #[error("grid dimensions must be at least 1x1, got {width}x{height}")]
    Empty {
        /// Requested width.
        width: usize,
        /// Requested height.
        height: usize,
    },
    /// Dimensions are too large to allocate sensibly.
    #[error("grid of {width}x{height} samples exceeds the limit of {max} samples")]
    TooLarge {
        /// Requested width.
        width: u64,
        /// Requested height.
        height: u64,
        /// The limit, [`MAX_SAMPLES`].
        max: u64,
    },
    /// The height buffer does not have W×H values.
    #[error("expected {expected} heights for the grid, got {got}")]
    LengthMismatch {
        /// W×H.
        expected: usize,
        /// Length of the buffer given.
        got: usize,
    },
    /// A height is infinite.
    #[error("height at column {col}, row {row} is infinite")]
    Infinite {
        /// Column of the sample.
        col: usize,
        /// Row of the sample.
        row: usize,
    },
    /// A window that is empty or does not lie inside the grid.
    #[error("expected a window inside the {grid_width}x{grid_height} grid, found {width}x{height} samples at column {col}, row {row}")]
    WindowOutside {
        /// First column of the window.
        col: usize,
        /// First row of the window.
        row: usize,
        /// Width of the window.
        width: usize,
        /// Height of the window.
        height: usize,
        /// Width of the grid.
        grid_width: usize,
        /// Height of the grid.
        grid_height: usize,
    },
    /// The grid still has voids where none are allowed.
    #[error("grid has {count} void samples (first at column {col}, row {row}); fill them or choose a void policy")]
    HasVoids {
        /// Number of voids.
        count: usize,
        /// Column of the first void.
        col: usize,
        /// Row of the first void.
        row: usize,
    },
}

/// Checks that a W×H grid may be allocated.
///
/// # Errors
/// [`GridError::Empty`] or [`GridError::TooLarge`].
pub fn check_dimensions(width: u64, height: u64) -> Result<(), GridError> {
    if width == 0 || height == 0 {
        return Err(GridError::Empty {
            width: width as usize,
            height: height as usize,
        });
    }
    match width.checked_mul(height) {
        Some(n) if n <= MAX_SAMPLES => Ok(()),
        _ => Err(GridError::TooLarge {
            width,
            height,
            max: MAX_SAMPLES,
        }),
    }
}

/// The coordinate reference system of a grid.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Crs {
    /// Not known (PNG tiles, ASCII grids without a .prj, GeoTIFFs without GeoKeys).
    #[default]
    Unknown,
    /// An EPSG code, e.g. 4326 (WGS 84 geographic) or 3857 (Web Mercator).
    Epsg(u32),
    /// A geographic CRS known only by description (e.g. a user-defined GeoTIFF
    /// geographic type); angles in degrees.
    Geographic(String),
    /// A projected CRS known only by description (e.g. "UTM zone 25S"); linear units in metres.
    Projected(String),
    /// A CRS given by its PROJ definition (`+proj=utm +zone=33 +datum=WGS84 …`):
    /// from `--src-crs`, or built from a file's own projection parameters.
    Proj(String),
}

impl Crs {
    /// WGS 84 geographic, EPSG:4326.
    pub const WGS84: Crs = Crs::Epsg(4326);

    /// True when coordinates are longitude/latitude in degrees.
    pub fn is_geographic(&self) -> bool {
        match self {
            Crs::Epsg(code) => is_geographic_epsg(*code),
            Crs::Geographic(_) => true,
            Crs::Proj(def) => def.contains("+proj=longlat") || def.contains("+proj=latlong"),
            _ => false,
        }
    }
}

/// EPSG codes of geographic 2D CRSs that cota recognises (WGS 84, NAD83, ETRS89,
/// NAD27, GRS 1980 and the like: the 4000–4999 block).
fn is_geographic_epsg(code: u32) -> bool {
    (4000..5000).contains(&code)
}

impl fmt::Display for Crs {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Crs::Unknown => write!(f, "unknown"),
            Crs::Epsg(code) => write!(f, "EPSG:{code}"),
            Crs::Geographic(s) | Crs::Projected(s) | Crs::Proj(s) => write!(f, "{s}"),
        }
    }
}

/// Whether a georeference's origin refers to a pixel's corner or its centre
/// (GeoTIFF's RasterPixelIsArea / RasterPixelIsPoint).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PixelIs {
    /// The transform maps (0,0) to the outer corner of the first pixel; samples
    /// are at pixel centres. GDAL's default, ESRI `xllcorner`.
    #[default]
    Area,
    /// The transform maps (0,0) to the first sample itself. SRTM, ESRI `xllcenter`.
    Point,
}

/// Where a grid sits: CRS and affine transform.
#[derive(Debug, Clone, PartialEq)]
pub struct GeoRef {
    /// The coordinate reference system. Default: [`Crs::Unknown`].
    pub crs: Crs,
    /// CRS x of the transform's origin (see [`PixelIs`]).
    pub origin_x: f64,
    /// CRS y of the transform's origin.
    pub origin_y: f64,
    /// Pixel size along a row, in CRS units (positive: columns go east).
    pub pixel_x: f64,
    /// Pixel size down a column, in CRS units (negative for north-up grids).
    pub pixel_y: f64,
    /// Corner or centre convention of the origin.
    pub pixel_is: PixelIs,
    /// True when the transform came from the file; false when it is the
    /// placeholder of [`GeoRef::unreferenced`].
    pub known: bool,
}

impl GeoRef {
    /// A placeholder for grids without georeference (PNG tiles, raw arrays):
    /// pixel-is-point at (0,0), `cell_size_m` metres per sample, y up to the north.
    pub fn unreferenced(cell_size_m: f64) -> Self {
        GeoRef {
            crs: Crs::Unknown,
            origin_x: 0.0,
            origin_y: 0.0,
            pixel_x: cell_size_m,
            pixel_y: -cell_size_m,
            pixel_is: PixelIs::Point,
            known: false,
        }
    }

    /// CRS coordinates of the sample at (`col`, `row`), which may be fractional.
    pub fn sample_xy(&self, col: f64, row: f64) -> (f64, f64) {
        let half = match self.pixel_is {
            PixelIs::Area => 0.5,
            PixelIs::Point => 0.0,
        };
        (
            self.origin_x + (col + half) * self.pixel_x,
            self.origin_y + (row + half) * self.pixel_y,
        )
    }

    /// For a known transform in an unknown CRS: `Some(Crs::Geographic(..))` when
    /// the whole `width × height` grid lies within longitude/latitude bounds
    /// (±180°, ±90°) and the pixel is below 0.01 units, which only degrees make
    /// sense of (an ESRI ASCII clip of SRTM without its `.prj`, say). `None`
    /// otherwise. Readers apply it so that cell sizes in metres stay right.
    pub fn guess_geographic(&self, width: usize, height: usize) -> Option<Crs> {
        if self.crs != Crs::Unknown || !self.known {
            return None;
        }
        let small = self.pixel_x.abs() < 0.01 && self.pixel_y.abs() < 0.01;
        let (x0, y0) = self.sample_xy(-0.5, -0.5);
        let (x1, y1) = self.sample_xy(width as f64 - 0.5, height as f64 - 0.5);
        let fits =
            [x0, x1].iter().all(|x| x.abs() <= 180.0) && [y0, y1].iter().all(|y| y.abs() <= 90.0);
        (small && fits).then(|| {
            Crs::Geographic("WGS 84 (assumed: coordinates and cell size look like degrees)".into())
        })
    }

    /// Ground distance in metres of one pixel step along x and along y at the
    /// grid position (`col`, `row`).
    ///
    /// * Geographic CRSs: degrees converted on the WGS 84 ellipsoid at the
    ///   sample's latitude (prime-vertical radius for x, meridional radius for y).
    /// * EPSG:3857 (and 900913): Web Mercator metres scaled by cos(latitude), the
    ///   projection's true scale at that latitude.
    /// * Other and unknown CRSs: CRS units are taken as metres.
    pub fn pixel_size_m_at(&self, col: f64, row: f64) -> [f64; 2] {
        let (px, py) = (self.pixel_x.abs(), self.pixel_y.abs());
        match &self.crs {
            c if c.is_geographic() => {
                let (_, lat) = self.sample_xy(col, row);
                let [mx, my] = metres_per_degree(lat);
                [px * mx, py * my]
            }
            Crs::Epsg(3857) | Crs::Epsg(900913) | Crs::Epsg(3785) => {
                let (_, y) = self.sample_xy(col, row);
                let lat = web_mercator_lat_rad(y);
                [px * lat.cos(), py * lat.cos()]
            }
            _ => [px, py],
        }
    }
}

/// WGS 84 semi-major axis in metres.
const WGS84_A: f64 = 6_378_137.0;
/// WGS 84 first eccentricity squared.
const WGS84_E2: f64 = 6.694_379_990_141_3e-3;

/// Metres per degree of longitude and of latitude at latitude `lat_deg` on WGS 84.
pub fn metres_per_degree(lat_deg: f64) -> [f64; 2] {
    let phi = lat_deg.clamp(-90.0, 90.0).to_radians();
    let s2 = phi.sin() * phi.sin();
    let w = (1.0 - WGS84_E2 * s2).sqrt();
    let n = WGS84_A / w; // prime vertical radius of curvature
    let m = WGS84_A * (1.0 - WGS84_E2) / (w * w * w); // meridional radius
    let deg = std::f64::consts::PI / 180.0;
    [n * phi.cos() * deg, m * deg]
}

/// Latitude in radians of a Web Mercator y coordinate in metres.
fn web_mercator_lat_rad(y: f64) -> f64 {
    (2.0 * (y / WGS84_A).exp().atan()) - std::f64::consts::FRAC_PI_2
}

/// A W×H grid of heights in metres with its georeference.
///
/// Heights are `f32` metres, row-major from the northern row. Voids are `NaN`.
///
/// ```
/// use cota_core::{HeightGrid, GeoRef};
/// let g = HeightGrid::new(3, 2, vec![1.0, 2.0, 3.0, 4.0, f32::NAN, 6.0], GeoRef::unreferenced(30.0)).unwrap();
/// assert_eq!(g.void_count(), 1);
/// assert_eq!(g.valid_range(), Some((1.0, 6.0)));
/// assert_eq!(g.cell_size_m(), [30.0, 30.0]);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct HeightGrid {
    width: usize,
    height: usize,
    heights: Vec<f32>,
    georef: GeoRef,
}

impl HeightGrid {
    /// Builds a grid from row-major heights (row 0 north). `NaN` marks voids.
    ///
    /// # Errors
    /// [`GridError::Empty`], [`GridError::TooLarge`], [`GridError::LengthMismatch`],
    /// or [`GridError::Infinite`] when a height is ±∞.
    pub fn new(
        width: usize,
        height: usize,
        heights: Vec<f32>,
        georef: GeoRef,
    ) -> Result<Self, GridError> {
        check_dimensions(width as u64, height as u64)?;
        if heights.len() != width * height {
            return Err(GridError::LengthMismatch {
                expected: width * height,
                got: heights.len(),
            });
        }
        if let Some(i) = heights.iter().position(|h| h.is_infinite()) {
            return Err(GridError::Infinite {
                col: i % width,
                row: i / width,
            });
        }
        Ok(HeightGrid {
            width,
            height,
            heights,
            georef,
        })
    }

    /// Number of columns (W).
    #[inline]
    pub fn width(&self) -> usize {
        self.width
    }

    /// Number of rows (H).
    #[inline]
    pub fn height(&self) -> usize {
        self.height
    }

    /// Number of samples, W×H.
    #[inline]
    pub fn len(&self) -> usize {
        self.heights.len()
    }

    /// Always false: a grid has at least one sample.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.heights.is_empty()
    }

    /// The heights, row-major from the northern row; voids are NaN.
    #[inline]
    pub fn heights(&self) -> &[f32] {
        &self.heights
    }

    /// Mutable heights (e.g. for void filling). Writing ±∞ is a logic error.
    #[inline]
    pub fn heights_mut(&mut self) -> &mut [f32] {
        &mut self.heights
    }

    /// Consumes the grid and returns its heights.
    pub fn into_heights(self) -> Vec<f32> {
        self.heights
    }

    /// Height at (`col`, `row`); NaN for a void. Panics when out of range.
    #[inline]
    pub fn get(&self, col: usize, row: usize) -> f32 {
        self.heights[row * self.width + col]
    }

    /// True when the sample at (`col`, `row`) holds data.
    #[inline]
    pub fn is_valid(&self, col: usize, row: usize) -> bool {
        !self.get(col, row).is_nan()
    }

    /// The georeference.
    #[inline]
    pub fn georef(&self) -> &GeoRef {
        &self.georef
    }

    /// Replaces the georeference.
    pub fn set_georef(&mut self, georef: GeoRef) {
        self.georef = georef;
    }

    /// Number of void (NaN) samples.
    pub fn void_count(&self) -> usize {
        self.heights.iter().filter(|h| h.is_nan()).count()
    }

    /// Index (column, row) of the first void, if any.
    pub fn first_void(&self) -> Option<(usize, usize)> {
        // Every mesh build starts here, so the scan is fast: blocks in
        // parallel, each reduced without a branch per sample (which
        // vectorises), then the first block with a void searched.
        const BLOCK: usize = 1 << 14;
        let block = self
            .heights
            .par_chunks(BLOCK)
            .position_first(|b| b.iter().fold(false, |any, h| any | h.is_nan()))?;
        let i = block * BLOCK
            + self.heights[block * BLOCK..]
                .iter()
                .position(|h| h.is_nan())?;
        Some((i % self.width, i / self.width))
    }

    /// Fails with [`GridError::HasVoids`] when any sample is a void.
    ///
    /// # Errors
    /// [`GridError::HasVoids`].
    pub fn require_no_voids(&self) -> Result<(), GridError> {
        match self.first_void() {
            None => Ok(()),
            Some((col, row)) => Err(GridError::HasVoids {
                count: self.void_count(),
                col,
                row,
            }),
        }
    }

    /// Smallest and largest valid height, or `None` when every sample is void.
    pub fn valid_range(&self) -> Option<(f32, f32)> {
        let mut it = self.heights.iter().copied().filter(|h| !h.is_nan());
        let first = it.next()?;
        Some(it.fold((first, first), |(lo, hi), h| (lo.min(h), hi.max(h))))
    }

    /// The window of `width × height` samples whose north-west sample is
    /// (`col`, `row`), as a grid of its own whose georeference is shifted to
    /// the window (same CRS and pixel size).
    ///
    /// ```
    /// use cota_core::{GeoRef, HeightGrid};
    /// let g = HeightGrid::new(3, 2, vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0], GeoRef::unreferenced(30.0)).unwrap();
    /// let w = g.window(1, 0, 2, 2).unwrap();
    /// assert_eq!(w.heights(), &[2.0, 3.0, 5.0, 6.0]);
    /// assert!(g.window(2, 0, 2, 2).is_err());
    /// ```
    ///
    /// # Errors
    /// [`GridError::WindowOutside`] when the window is empty or leaves the grid.
    pub fn window(
        &self,
        col: usize,
        row: usize,
        width: usize,
        height: usize,
    ) -> Result<HeightGrid, GridError> {
        let fits = |start: usize, len: usize, total: usize| {
            len > 0 && start.checked_add(len).is_some_and(|end| end <= total)
        };
        if !fits(col, width, self.width) || !fits(row, height, self.height) {
            return Err(GridError::WindowOutside {
                col,
                row,
                width,
                height,
                grid_width: self.width,
                grid_height: self.height,
            });
        }
        let mut heights = Vec::with_capacity(width * height);
        for r in row..row + height {
            let start = r * self.width + col;
            heights.extend_from_slice(&self.heights[start..start + width]);
        }
        let src = &self.georef;
        let georef = GeoRef {
            origin_x: src.origin_x + col as f64 * src.pixel_x,
            origin_y: src.origin_y + row as f64 * src.pixel_y,
            ..src.clone()
        };
        HeightGrid::new(width, height, heights, georef)
    }

    /// The grid's local frame in metres (x east, y north, z up, origin at the
    /// south-west sample).
    pub fn local_frame(&self) -> LocalFrame {
        LocalFrame::of(self)
    }

    /// Cell size `[dx, dy]` in metres at the grid's centre (see
    /// [`GeoRef::pixel_size_m_at`] for how geographic and Web Mercator grids are
    /// converted). Always positive.
    pub fn cell_size_m(&self) -> [f64; 2] {
        self.georef.pixel_size_m_at(
            (self.width as f64 - 1.0) / 2.0,
            (self.height as f64 - 1.0) / 2.0,
        )
    }
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn rejects_bad_shapes() {
        let g = GeoRef::unreferenced(1.0);
        assert!(matches!(
            HeightGrid::new(0, 3, vec![], g.clone()),
            Err(GridError::Empty { .. })
        ));
        assert!(matches!(
            HeightGrid::new(2, 2, vec![0.0; 3], g.clone()),
            Err(GridError::LengthMismatch {
                expected: 4,
                got: 3
            })
        ));
        assert!(matches!(
            HeightGrid::new(2, 1, vec![0.0, f32::INFINITY], g),
            Err(GridError::Infinite { col: 1, row: 0 })
        ));
        assert!(check_dimensions(1 << 20, 1 << 20).is_err());
        assert!(check_dimensions(u64::MAX, 2).is_err());
    }

    /// The first void in row-major order, wherever it falls among the
    /// blocks scanned in parallel, including several voids in one block and
    /// voids in later blocks.
    #[test]
    fn first_void_is_the_first_in_row_order() {
        let (w, h) = (301, 200);
        let grid = |voids: &[(usize, usize)]| {
            let mut v = vec![1.5f32; w * h];
            for &(c, r) in voids {
                v[r * w + c] = f32::NAN;
            }
            HeightGrid::new(w, h, v, GeoRef::unreferenced(1.0)).unwrap()
        };
        assert_eq!(grid(&[]).first_void(), None);
        for voids in [
            vec![(0, 0)],
            vec![(300, 199)],
            vec![(123, 150), (5, 190)],
            vec![(7, 60), (6, 60), (299, 54), (0, 199)],
            vec![(200, 180), (100, 180)],
        ] {
            let first = voids
                .iter()
                .map(|&(c, r)| (r, c))
                .min()
                .map(|(r, c)| (c, r));
            let g = grid(&voids);
            assert_eq!(g.first_void(), first, "{voids:?}");
            assert_eq!(g.void_count(), voids.len());
        }
    }

    #[test]
    fn srtm_cell_size_at_equator_and_45() {
        // SRTM 3" tile at the equator: 1/1200 degree.
        let g = GeoRef {
            crs: Crs::WGS84,
            origin_x: 10.0,
            origin_y: 1.0,
            pixel_x: 1.0 / 1200.0,
            pixel_y: -1.0 / 1200.0,
            pixel_is: PixelIs::Point,
            known: true,
        };
        let [dx, dy] = g.pixel_size_m_at(600.0, 1200.0); // latitude 0
        assert!((dx - 92.77).abs() < 0.05, "{dx}");
        assert!((dy - 92.13).abs() < 0.05, "{dy}");
        let [mx, _] = metres_per_degree(45.0);
        assert!((mx - 78_847.0).abs() < 5.0, "{mx}");
    }

    #[test]
    fn degrees_are_guessed_only_when_nothing_else_fits() {
        let mut g = GeoRef {
            crs: Crs::Unknown,
            origin_x: -105.55,
            origin_y: 40.21,
            pixel_x: 1.0 / 1200.0,
            pixel_y: -1.0 / 1200.0,
            pixel_is: PixelIs::Area,
            known: true,
        };
        assert!(g
            .guess_geographic(240, 144)
            .is_some_and(|c| c.is_geographic()));
        g.pixel_x = 10.0;
        g.pixel_y = -10.0;
        assert_eq!(g.guess_geographic(240, 144), None); // 10-unit cells: metres
        assert_eq!(GeoRef::unreferenced(0.001).guess_geographic(5, 5), None);
    }

    #[test]
    fn web_mercator_scale() {
        let g = GeoRef {
            crs: Crs::Epsg(3857),
            origin_x: 0.0,
            origin_y: 7_361_866.11, // about 55 degrees north
            pixel_x: 10.0,
            pixel_y: -10.0,
            pixel_is: PixelIs::Area,
            known: true,
        };
        let [dx, _] = g.pixel_size_m_at(0.0, 0.0);
        assert!((dx - 10.0 * 55f64.to_radians().cos()).abs() < 0.01, "{dx}");
    }
}
