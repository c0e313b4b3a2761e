//! The source resampled once onto the tiling's geographic lattice at the
//! maximum zoom, over a window of whole tiles around its footprint.
//!
//! Reference: the lattice of [`super::scheme`]; the resampling is plain
//! bilinear interpolation of the source's samples (no paper: a format
//! adaptation, stated so that the error it adds can be reported apart, see
//! [`resampling_deviation`]).
//!
//! 1. **Footprint.** The source's samples cover the rectangle between its
//!    outermost sample centres, in degrees (a geographic CRS is required).
//! 2. **Window.** The lattice is stored only over a window: the footprint
//!    grown by a margin of at least one maximum-zoom tile, rounded outwards
//!    to whole tiles of an *alignment zoom* `a` (the coarsest zoom whose
//!    window is at most [`WINDOW_GROWTH`] times the one of the maximum zoom),
//!    clipped to the world, with `(x₀ + y₀) / T_a` even so that the window's
//!    own bitree has the global hierarchy's diagonals (see
//!    [`crate::hierarchy`]: a square's diagonal points to the centre of the
//!    square twice its size). Every tile at zoom `a` or finer then lies
//!    inside the window or outside it, and is a square of the window's bitree.
//! 3. **Heights.** Inside the footprint, bilinear interpolation of the four
//!    surrounding source samples. Outside it, the terrain is 0 m (the
//!    ellipsoid, what a globe shows with no terrain): the footprint's edge
//!    value is held one cell beyond it (so the unit cells across the edge
//!    interpolate the source's edge) and falls to 0 over [`ramp_cells`]
//!    cells (the rest of a maximum-zoom tile) along a smoothstep
//!    ([`ramp_factor`]), level at both ends: the data's edge is seen held
//!    flat, with no wall, apron or kink at it, and no terrain is shown
//!    farther than one finest tile from the data. The window's last
//!    alignment tile is 0 m like everything beyond it.
//! 4. **Across the antimeridian.** A source whose longitudes go past ±180°
//!    (179.5° to 180.5°, or -180.5° to -179.5°) is laid on a lattice whose
//!    columns count from 0° ([`GeographicScheme::from_greenwich`]), its
//!    longitudes taken modulo 360° ([`GeographicScheme::lon_offset`]): the
//!    footprint is contiguous there and every step above is unchanged.

use rayon::prelude::*;

use super::coverage::Coverage;
use super::error::TilesError;
use super::fit::{fit, FIT_MARGIN};
use super::samples::Samples;
pub use super::samples::SourcePart;
use super::scheme::{ErrorSchedule, GeographicScheme};
use crate::grid::{Crs, GeoRef, HeightGrid, PixelIs, MAX_SAMPLES};
use crate::progress::{Counter, Progress, Stages};

/// The alignment zoom is the coarsest whose window is at most this many
/// times the window aligned to maximum-zoom tiles.
pub const WINDOW_GROWTH: f64 = 1.25;

/// Options for [`Lattice::resample`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct LatticeOptions {
    /// The maximum zoom; `None`: the smallest whose lattice is at least as
    /// fine as the source ([`GeographicScheme::max_zoom_for`]). Default: `None`.
    pub max_zoom: Option<u8>,
    /// Lattice cells across a tile at the maximum zoom, a power of two from 2
    /// to 4096. Default: 64 (the 65 samples of cesium-terrain-builder's tiles).
    pub tile_cells: u32,
    /// The error schedule of the pyramid: the lattice is fitted to the
    /// source's samples down to half its bound at the maximum zoom
    /// ([`super::fit`]). Default: [`ErrorSchedule::DEFAULT`].
    pub error: ErrorSchedule,
}

impl LatticeOptions {
    /// The defaults, as documented on each field.
    pub const DEFAULT: LatticeOptions = LatticeOptions {
        max_zoom: None,
        tile_cells: 64,
        error: ErrorSchedule::DEFAULT,
    };

    /// Sets [`LatticeOptions::error`].
    pub const fn with_error(mut self, e: ErrorSchedule) -> Self {
        self.error = e;
        self
    }

    /// Sets [`LatticeOptions::max_zoom`].
    pub const fn with_max_zoom(mut self, z: Option<u8>) -> Self {
        self.max_zoom = z;
        self
    }

    /// Sets [`LatticeOptions::tile_cells`].
    pub const fn with_tile_cells(mut self, cells: u32) -> Self {
        self.tile_cells = cells;
        self
    }
}

impl Default for LatticeOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The terrain on the tiling's lattice: a window of heights, 0 m outside it.
/// A *part* ([`Lattice::resample_part`]) stores only a region of the window;
/// its heights elsewhere are not known.
#[derive(Debug, Clone)]
pub struct Lattice {
    frame: LatticeFrame,
    grid: HeightGrid,
    origin: [u64; 2],
    residual_m: f64,
    /// The data's footprints when they are not the frame's rectangle
    /// (several sources, projected ones: [`super::sources`]).
    coverage: Option<Coverage>,
}

/// The window of a footprint at one alignment zoom: `[x0, y0, x1, y1]`
/// global lattice coordinates of its corner samples (inclusive).
type Window = [u64; 4];

/// Where the lattice lies, decided by the whole source: the scheme, the
/// footprint, the window and its alignment zoom, and how lattice positions
/// map to the whole source's samples. Every part of one lattice is
/// resampled in the same frame, so its heights are those of the whole
/// lattice bit for bit.
#[derive(Debug, Clone, PartialEq)]
pub struct LatticeFrame {
    /// The tiling scheme (maximum zoom, tile size in cells).
    pub scheme: GeographicScheme,
    /// The source's footprint, `[west col, north row, east col, south row]`.
    pub footprint: [f64; 4],
    /// The window, `[x0, y0, x1, y1]` inclusive.
    pub window: [u64; 4],
    /// The zoom whose tiles the window is made of.
    pub align_zoom: u8,
    /// The whole source's georeference.
    pub source_georef: GeoRef,
    /// The whole source's size in samples, `[width, height]`.
    pub source_size: [usize; 2],
    /// The residual the fit aims for at the source's samples, metres
    /// ([`super::fit`]).
    pub fit_m: f64,
}

impl LatticeFrame {
    /// The frame of `source` (geographic) under `opts`.
    ///
    /// # Errors
    /// [`TilesError::NotGeographic`], [`TilesError::OutsideWorld`],
    /// [`TilesError::BadOptions`].
    pub fn of(source: &HeightGrid, opts: &LatticeOptions) -> Result<LatticeFrame, TilesError> {
        LatticeFrame::for_source(source.georef(), [source.width(), source.height()], opts)
    }

    /// The frame of a source of georeference `g` (geographic) and `size`
    /// `[width, height]` samples under `opts`: [`LatticeFrame::of`] without
    /// the samples, which the frame does not depend on.
    ///
    /// # Errors
    /// As [`LatticeFrame::of`].
    pub fn for_source(
        g: &GeoRef,
        size: [usize; 2],
        opts: &LatticeOptions,
    ) -> Result<LatticeFrame, TilesError> {
        if !g.crs.is_geographic() || !g.known {
            return Err(TilesError::NotGeographic {
                crs: if g.known {
                    g.crs.to_string()
                } else {
                    "none (the input has no georeference)".into()
                },
            });
        }
        let [w, h] = size;
        if w < 2 || h < 2 {
            return Err(TilesError::BadOptions(format!(
                "expected a source of at least 2x2 samples, found {w}x{h}"
            )));
        }
        let mut scheme = scheme_for(g, opts)?;
        scheme.from_greenwich = past_antimeridian(g, size);
        let footprint = footprint(g, size, &scheme)?;
        let (align_zoom, window) = choose_window(&scheme, footprint);
        let pixel = g.pixel_x.abs().min(g.pixel_y.abs());
        let fit_m = fit_tolerance_m(&scheme, pixel, opts);
        Ok(LatticeFrame {
            scheme,
            footprint,
            window,
            align_zoom,
            source_georef: g.clone(),
            source_size: size,
            fit_m,
        })
    }

    /// Degrees added to the source's longitudes to bring them into the
    /// lattice's range ([`GeographicScheme::lon_offset`]).
    pub fn source_lon_offset(&self) -> f64 {
        self.scheme.lon_offset(self.source_georef.origin_x)
    }

    /// `region` grown by what its fit reads ([`FIT_MARGIN`]), in the window.
    fn fit_region(&self, region: [u64; 4]) -> [u64; 4] {
        let w = self.window;
        [
            region[0].saturating_sub(FIT_MARGIN).max(w[0]),
            region[1].saturating_sub(FIT_MARGIN).max(w[1]),
            (region[2] + FIT_MARGIN).min(w[2]),
            (region[3] + FIT_MARGIN).min(w[3]),
        ]
    }

    /// The whole source's columns and rows that resampling `region` reads
    /// (with the fit's margin): `[c0, r0, c1, r1]` inclusive, `None` when it
    /// reads none (all 0 m).
    pub fn source_span(&self, region: [u64; 4]) -> Option<[usize; 4]> {
        let (cols, rows) = axes(self, self.fit_region(region));
        let (c0, c1) = read_span(&cols)?;
        let (r0, r1) = read_span(&rows)?;
        Some([c0, r0, c1, r1])
    }
}

impl Lattice {
    /// Resamples `source` (geographic, no voids) onto the lattice.
    ///
    /// # Errors
    /// [`TilesError::NotGeographic`], [`TilesError::Voids`],
    /// [`TilesError::OutsideWorld`], [`TilesError::BadOptions`],
    /// [`TilesError::TooLarge`].
    ///
    /// # Runtime
    /// `O(window samples)`, in parallel over rows.
    pub fn resample(source: &HeightGrid, opts: &LatticeOptions) -> Result<Lattice, TilesError> {
        Lattice::resample_with_progress(source, opts, crate::progress::NONE)
    }

    /// [`Lattice::resample`], telling `progress(done, total)` as it goes:
    /// the lattice's rows interpolated, then the fit's rounds, weighted by
    /// their share of the time (in thousandths, [`crate::progress`]).
    ///
    /// # Errors
    /// As [`Lattice::resample`].
    pub fn resample_with_progress(
        source: &HeightGrid,
        opts: &LatticeOptions,
        progress: Progress<'_>,
    ) -> Result<Lattice, TilesError> {
        let frame = LatticeFrame::of(source, opts)?;
        let window = frame.window;
        let part = SourcePart {
            grid: source,
            offset: [0, 0],
        };
        Lattice::resample_part_with(&frame, part, window, progress)
    }

    /// Resamples only `region` (global lattice `[x0, y0, x1, y1]`, inside the
    /// frame's window) of the lattice of `frame`, from the part of the source
    /// that `frame.source_span(region)` names (or more): its heights are
    /// those of the whole lattice there.
    ///
    /// # Errors
    /// [`TilesError::Voids`], [`TilesError::TooLarge`],
    /// [`TilesError::BadOptions`] for a region outside the window or a source
    /// part that does not cover what the region reads.
    pub fn resample_part(
        frame: &LatticeFrame,
        source: SourcePart<'_>,
        region: [u64; 4],
    ) -> Result<Lattice, TilesError> {
        Lattice::resample_part_with(frame, source, region, crate::progress::NONE)
    }

    /// [`Lattice::resample_part`], telling `progress` as
    /// [`Lattice::resample_with_progress`] does.
    ///
    /// # Errors
    /// As [`Lattice::resample_part`].
    pub fn resample_part_with(
        frame: &LatticeFrame,
        source: SourcePart<'_>,
        region: [u64; 4],
        progress: Progress<'_>,
    ) -> Result<Lattice, TilesError> {
        let (win, s) = (frame.window, &frame.scheme);
        let [sw, sh] = frame.source_size;
        let cells_ok = s.tile_cells.is_power_of_two() && (2..=4096).contains(&s.tile_cells);
        let zoom_ok =
            s.max_zoom <= (30 - s.tile_cells.trailing_zeros() as u8).min(super::scheme::MAX_ZOOM);
        if sw < 2 || sh < 2 || !cells_ok || !zoom_ok || frame.align_zoom > s.max_zoom {
            return Err(TilesError::BadOptions(format!(
                "expected a lattice frame of a source of at least 2x2 samples and a valid scheme, found {frame:?}"
            )));
        }
        if region[0] < win[0]
            || region[1] < win[1]
            || region[2] > win[2]
            || region[3] > win[3]
            || region[0] >= region[2]
            || region[1] >= region[3]
        {
            return Err(TilesError::BadOptions(format!(
                "expected a region inside the lattice window {win:?}, found {region:?}"
            )));
        }
        if let Some((col, row)) = source.grid.first_void() {
            return Err(TilesError::Voids { col, row });
        }
        let (w, h) = (region[2] - region[0] + 1, region[3] - region[1] + 1);
        if w.checked_mul(h).is_none_or(|n| n > MAX_SAMPLES) {
            return Err(TilesError::TooLarge {
                width: w,
                height: h,
            });
        }
        let (heights, residual_m) = fitted(frame, source, region, progress)?;
        let d = frame.scheme.cell_deg();
        let georef = GeoRef {
            crs: Crs::WGS84,
            origin_x: frame.scheme.lon_of(region[0] as f64),
            origin_y: frame.scheme.lat_of(region[1] as f64),
            pixel_x: d,
            pixel_y: -d,
            pixel_is: PixelIs::Point,
            known: true,
        };
        let grid = HeightGrid::new(w as usize, h as usize, heights, georef)
            .map_err(|e| TilesError::BadOptions(e.to_string()))?;
        Ok(Lattice {
            frame: frame.clone(),
            grid,
            origin: [region[0], region[1]],
            residual_m,
            coverage: None,
        })
    }

    /// The largest |lattice − source| at the source's samples it holds,
    /// metres: what the lattice's own surface leaves of the source.
    pub fn residual_m(&self) -> f64 {
        self.residual_m
    }

    /// The lattice over the whole window of `frame` from its heights (see
    /// [`super::sources`]), whose data lie in `coverage`.
    pub(crate) fn from_heights(
        frame: LatticeFrame,
        heights: Vec<f32>,
        residual_m: f64,
        coverage: Coverage,
    ) -> Result<Lattice, TilesError> {
        let win = frame.window;
        let (w, h) = (
            (win[2] - win[0] + 1) as usize,
            (win[3] - win[1] + 1) as usize,
        );
        let d = frame.scheme.cell_deg();
        let georef = GeoRef {
            crs: Crs::WGS84,
            origin_x: frame.scheme.lon_of(win[0] as f64),
            origin_y: frame.scheme.lat_of(win[1] as f64),
            pixel_x: d,
            pixel_y: -d,
            pixel_is: PixelIs::Point,
            known: true,
        };
        let grid = HeightGrid::new(w, h, heights, georef)
            .map_err(|e| TilesError::BadOptions(e.to_string()))?;
        Ok(Lattice {
            origin: [win[0], win[1]],
            frame,
            grid,
            residual_m,
            coverage: Some(coverage),
        })
    }

    /// The data's footprints, when they are not the frame's rectangle.
    pub fn coverage(&self) -> Option<&Coverage> {
        self.coverage.as_ref()
    }

    /// The lattice's unit-triangle surface at global lattice `(x, y)`.
    pub fn unit_surface_at(&self, x: f64, y: f64) -> f64 {
        let [ox, oy] = self.origin;
        unit_surface(&self.grid, self.origin, x - ox as f64, y - oy as f64)
    }

    /// The frame (scheme, footprint, window, source mapping).
    pub fn frame(&self) -> &LatticeFrame {
        &self.frame
    }

    /// The tiling scheme (maximum zoom, tile size in cells).
    pub fn scheme(&self) -> &GeographicScheme {
        &self.frame.scheme
    }

    /// True when only a part of the window is stored.
    pub fn is_part(&self) -> bool {
        self.stored() != self.frame.window
    }

    /// The stored region in global lattice coordinates: `[x0, y0, x1, y1]`,
    /// inclusive (the window, unless a part).
    pub fn stored(&self) -> [u64; 4] {
        let [x0, y0] = self.origin;
        [
            x0,
            y0,
            x0 + self.grid.width() as u64 - 1,
            y0 + self.grid.height() as u64 - 1,
        ]
    }

    /// The stored heights (EPSG:4326, pixel-is-point): the window's, or the
    /// part's.
    pub fn grid(&self) -> &HeightGrid {
        &self.grid
    }

    /// Global lattice column and row of the stored sample (0, 0).
    pub fn origin(&self) -> [u64; 2] {
        self.origin
    }

    /// The zoom whose tiles the window is made of (see the module docs).
    pub fn align_zoom(&self) -> u8 {
        self.frame.align_zoom
    }

    /// The source's footprint in global lattice coordinates (fractional):
    /// `[west col, north row, east col, south row]`.
    pub fn footprint(&self) -> [f64; 4] {
        self.frame.footprint
    }

    /// The footprint in degrees, `[west, south, east, north]`, longitudes
    /// within -180..180: `west > east` when it crosses the antimeridian
    /// (the convention of GeoJSON's bounding boxes, RFC 7946 §5.2).
    pub fn footprint_deg(&self) -> [f64; 4] {
        let (s, fp) = (self.scheme(), self.frame.footprint);
        let wrap = |l: f64| {
            if s.from_greenwich && l > 180.0 {
                l - 360.0
            } else {
                l
            }
        };
        [
            wrap(s.lon_of(fp[0])),
            s.lat_of(fp[3]),
            wrap(s.lon_of(fp[2])),
            s.lat_of(fp[1]),
        ]
    }

    /// The window in global lattice coordinates: `[x0, y0, x1, y1]`, inclusive.
    pub fn window(&self) -> [u64; 4] {
        self.frame.window
    }

    /// The height at global lattice position `(col, row)`: the stored one,
    /// 0 m outside the stored region (for a part, only its region is known).
    #[inline]
    pub fn height_at(&self, col: u64, row: u64) -> f32 {
        let (c, r) = (
            col.wrapping_sub(self.origin[0]),
            row.wrapping_sub(self.origin[1]),
        );
        if c < self.grid.width() as u64 && r < self.grid.height() as u64 {
            self.grid.heights()[r as usize * self.grid.width() + c as usize]
        } else {
            0.0
        }
    }
}

/// The scheme for a source: its maximum zoom matched to the source's finer
/// pixel side unless given.
fn scheme_for(g: &GeoRef, opts: &LatticeOptions) -> Result<GeographicScheme, TilesError> {
    scheme_for_pixel(g.pixel_x.abs().min(g.pixel_y.abs()), opts)
}

/// The scheme for a source whose finer pixel side is `pixel` degrees.
pub(crate) fn scheme_for_pixel(
    pixel: f64,
    opts: &LatticeOptions,
) -> Result<GeographicScheme, TilesError> {
    let cells = opts.tile_cells;
    if !cells.is_power_of_two() || !(2..=4096).contains(&cells) {
        return Err(TilesError::BadOptions(format!(
            "expected a tile size of 2 to 4096 lattice cells, a power of two, found {cells}"
        )));
    }
    if !(pixel.is_finite() && pixel > 0.0) {
        return Err(TilesError::BadOptions(format!(
            "expected a positive pixel size in degrees, found {pixel}"
        )));
    }
    let max_zoom = opts
        .max_zoom
        .unwrap_or_else(|| GeographicScheme::max_zoom_for(pixel, cells));
    // Global lattice columns (2·S·2^Z) stay below 2^31.
    let limit = (30 - cells.trailing_zeros() as u8).min(super::scheme::MAX_ZOOM);
    if max_zoom > limit {
        return Err(TilesError::BadOptions(format!(
            "expected a maximum zoom of at most {limit} for tiles of {cells} cells, found {max_zoom}"
        )));
    }
    Ok(GeographicScheme {
        max_zoom,
        tile_cells: cells,
        from_greenwich: false,
    })
}

/// The source's sample-centre rectangle in degrees: `[west, south, east,
/// north]`.
fn rect_deg(g: &GeoRef, [width, height]: [usize; 2]) -> [f64; 4] {
    let (w, h) = (width as f64 - 1.0, height as f64 - 1.0);
    let (xa, ya) = g.sample_xy(0.0, 0.0);
    let (xb, yb) = g.sample_xy(w, h);
    [xa.min(xb), ya.min(yb), xa.max(xb), ya.max(yb)]
}

/// Whether the source's longitudes go past ±180° (less than a turn wide):
/// it is then laid on a lattice counted from 0° (see the module docs).
fn past_antimeridian(g: &GeoRef, size: [usize; 2]) -> bool {
    let [west, _, east, _] = rect_deg(g, size);
    let eps = 1e-9;
    (west < -180.0 - eps || east > 180.0 + eps) && east - west <= 360.0
}

/// The source's sample-centre rectangle in global lattice coordinates:
/// `[west col, north row, east col, south row]`.
fn footprint(g: &GeoRef, size: [usize; 2], s: &GeographicScheme) -> Result<[f64; 4], TilesError> {
    let [west, south, east, north] = rect_deg(g, size);
    let eps = 1e-9;
    let lat_ok = south >= -90.0 - eps && north <= 90.0 + eps;
    let off = s.lon_offset(g.origin_x);
    let (lo, hi) = (west + off - s.west_deg(), east + off - s.west_deg());
    if lat_ok && s.from_greenwich && (lo < -eps || hi > 360.0 + eps) {
        return Err(TilesError::AcrossAntimeridian { west, east });
    }
    if lo < -eps || hi > 360.0 + eps || !lat_ok {
        return Err(TilesError::OutsideWorld {
            west,
            south,
            east,
            north,
        });
    }
    let d = s.cell_deg();
    Ok([
        (lo / d).max(0.0),
        ((90.0 - north) / d).max(0.0),
        (hi / d).min(2.0 * s.root_cells() as f64),
        ((90.0 - south) / d).min(s.root_cells() as f64),
    ])
}

/// The window at alignment zoom `a` (see the module docs).
fn window_at(s: &GeographicScheme, fp: [f64; 4], a: u8) -> Window {
    let t = s.cells_at(a);
    // The ramp (one maximum-zoom tile) plus the zero band (a tile of the
    // alignment zoom).
    let margin = f64::from(s.tile_cells) + t as f64;
    let (wmax, hmax) = (2 * s.root_cells(), s.root_cells());
    let lo = |v: f64| ((v - margin).max(0.0) / t as f64).floor() as u64 * t;
    let hi = |v: f64, max: u64| (((v + margin) / t as f64).ceil() as u64 * t).min(max);
    let (mut x0, mut y0) = (lo(fp[0]), lo(fp[1]));
    let (x1, y1) = (hi(fp[2], wmax).max(x0 + t), hi(fp[3], hmax).max(y0 + t));
    if (x0 / t + y0 / t) % 2 == 1 {
        if x0 >= t {
            x0 -= t;
        } else {
            y0 -= t;
        }
    }
    [x0, y0, x1, y1]
}

/// The alignment zoom and its window: the coarsest zoom whose window is at
/// most [`WINDOW_GROWTH`] times the maximum zoom's.
pub(crate) fn choose_window(s: &GeographicScheme, fp: [f64; 4]) -> (u8, Window) {
    let area = |w: &Window| (w[2] - w[0] + 1) as f64 * (w[3] - w[1] + 1) as f64;
    let finest = window_at(s, fp, s.max_zoom);
    let limit = area(&finest) * WINDOW_GROWTH;
    (0..s.max_zoom)
        .map(|a| (a, window_at(s, fp, a)))
        .find(|(_, w)| area(w) <= limit)
        .unwrap_or((s.max_zoom, finest))
}

/// Where the zero band ends on each side of the window: `[west col, north
/// row, east col, south row]`. Along a border that is not the world's edge
/// the last tile of the alignment zoom (`T_a` cells) is 0 m. A split point
/// on the border at a level of the window's bitree (`B(T_a)` or finer) then
/// has no error: its error is the largest own error over split points that
/// its diamond's descendants reach, whose diamonds stay within
/// `T_a/2 + T_a/4 + … < T_a` of the border. So the squares outside, whose
/// errors the window does not hold, inherit none through the closure.
fn zero_band(s: &GeographicScheme, win: Window, a: u8) -> [f64; 4] {
    let half = s.cells_at(a) as f64;
    let (wmax, hmax) = (2 * s.root_cells(), s.root_cells());
    let inset = |v: u64, edge: u64, dir: f64| {
        if v == edge {
            v as f64
        } else {
            v as f64 + dir * half
        }
    };
    [
        inset(win[0], 0, 1.0),
        inset(win[1], 0, 1.0),
        inset(win[2], wmax, -1.0),
        inset(win[3], hmax, -1.0),
    ]
}

/// The fit's tolerance ([`super::fit`]): half the bound at the maximum zoom
/// where the lattice is at least as fine as the source's `pixel_deg`
/// (degrees); none (an infinite tolerance) on a coarser lattice, whose cells
/// hold several samples that no surface through its points can honour.
pub(crate) fn fit_tolerance_m(s: &GeographicScheme, pixel_deg: f64, opts: &LatticeOptions) -> f64 {
    if s.cell_deg() > pixel_deg * (1.0 + 1e-9) {
        f64::INFINITY
    } else {
        opts.error.max_error_m(s.max_zoom, s.max_zoom) / 2.0
    }
}

/// Lattice cells over which the data's edge falls to the ellipsoid beyond
/// the footprint, after the edge value held one cell: a maximum-zoom tile
/// less that cell (the window's margin holds it), at least one. Along
/// it the height follows [`ramp_factor`], level at both ends, so that no
/// wall or apron shows at the data's edge and the ellipsoid is reached
/// within one finest tile of the data; its steps stay near the terrain's own
/// (they set the quantization margin, [`super::plan`]).
pub fn ramp_cells(s: &GeographicScheme) -> f64 {
    f64::from(s.tile_cells.saturating_sub(1).max(1))
}

/// The share of the edge's height kept `cells` lattice cells beyond the
/// footprint: 1 up to one cell, then a smoothstep `1 − 3t² + 2t³` with
/// `t = (cells − 1) / ramp`, 0 from `ramp + 1` cells on. Level where it
/// leaves the edge (the data's edge seen held flat, not cut) and where it
/// meets the ellipsoid; its steepest slope is `1.5 / ramp` of the edge's
/// height per cell.
pub fn ramp_factor(cells: f64, ramp: f64) -> f64 {
    let t = ((cells - 1.0) / ramp).clamp(0.0, 1.0);
    1.0 - t * t * (3.0 - 2.0 * t)
}

/// Per lattice column (or row): the source's first sample index, the
/// interpolation weight, and the ramp factor outside the footprint.
#[derive(Debug, Clone, Copy)]
struct Axis {
    i0: usize,
    frac: f64,
    ramp: f64,
}

/// One axis of the resampling: `to_source(k)` gives the source coordinate
/// (fractional sample index) of lattice index `k` (global `start + k`);
/// `fp0`/`fp1` the footprint's ends and `w0`/`w1` the window's, in global
/// lattice coordinates; `n` the source's sample count on the axis.
fn axis(
    count: usize,
    start: u64,
    to_source: impl Fn(f64) -> f64,
    [fp0, fp1]: [f64; 2],
    [w0, w1]: [f64; 2],
    n: usize,
    ramp_cells: f64,
) -> Vec<Axis> {
    let last = (n - 1) as f64;
    (0..count)
        .map(|k| {
            let gx = (start + k as u64) as f64;
            let sx = to_source(gx).clamp(0.0, last);
            let i0 = (sx.floor() as usize).min(n - 2);
            // Full edge value up to one cell beyond the footprint, so the
            // unit cells across its edge interpolate the source's edge, then
            // down to 0 m over `ramp_cells` cells, shortened where the zero
            // band (or the world's edge) comes sooner.
            let (beyond, room) = if gx < fp0 {
                (fp0 - gx, fp0 - w0)
            } else if gx > fp1 {
                (gx - fp1, w1 - fp1)
            } else {
                (0.0, f64::INFINITY)
            };
            let ramp = ramp_factor(beyond, ramp_cells.min(room - 1.0).max(1.0));
            Axis {
                i0,
                frac: sx - i0 as f64,
                ramp,
            }
        })
        .collect()
}

/// The columns and rows of `region` as [`Axis`] entries of the whole source.
fn axes(frame: &LatticeFrame, region: Window) -> (Vec<Axis>, Vec<Axis>) {
    let (s, fp, g) = (&frame.scheme, frame.footprint, &frame.source_georef);
    let half = match g.pixel_is {
        PixelIs::Area => 0.5,
        PixelIs::Point => 0.0,
    };
    let (w, h) = (
        (region[2] - region[0] + 1) as usize,
        (region[3] - region[1] + 1) as usize,
    );
    let band = zero_band(s, frame.window, frame.align_zoom);
    let ramp = ramp_cells(s);
    let off = frame.source_lon_offset();
    let cols = axis(
        w,
        region[0],
        |gx| (s.lon_of(gx) - off - g.origin_x) / g.pixel_x - half,
        [fp[0], fp[2]],
        [band[0], band[2]],
        frame.source_size[0],
        ramp,
    );
    let rows = axis(
        h,
        region[1],
        |gy| (s.lat_of(gy) - g.origin_y) / g.pixel_y - half,
        [fp[1], fp[3]],
        [band[1], band[3]],
        frame.source_size[1],
        ramp,
    );
    (cols, rows)
}

/// The source indices an axis reads (`i0` and `i0 + 1` where its ramp is
/// not 0), `None` when it reads none.
fn read_span(axis: &[Axis]) -> Option<(usize, usize)> {
    let read = axis.iter().filter(|a| a.ramp != 0.0);
    let lo = read.clone().map(|a| a.i0).min()?;
    let hi = read.map(|a| a.i0 + 1).max()?;
    Some((lo, hi))
}

/// The heights of `region`, bilinear then fitted to the source's samples
/// over the region grown by the fit's margin ([`super::fit`]), and the
/// largest residual left at the samples in `region`.
fn fitted(
    frame: &LatticeFrame,
    source: SourcePart<'_>,
    region: Window,
    progress: Progress<'_>,
) -> Result<(Vec<f32>, f64), TilesError> {
    // Interpolation, the fit, the crop: their shares of the time.
    let stages = Stages::new(progress, &RESAMPLE_WEIGHTS);
    let grown = frame.fit_region(region);
    let mut heights = fill(frame, source, grown, &stages.stage(0))?;
    stages.finish(0);
    let (w, h) = (
        (grown[2] - grown[0] + 1) as usize,
        (grown[3] - grown[1] + 1) as usize,
    );
    let at = Samples::new(&frame.source_georef, &frame.scheme, source, grown);
    let f = fit(
        &mut heights,
        [w, h],
        [grown[0], grown[1]],
        &at,
        frame.fit_m,
        region,
        &stages.stage(1),
    );
    stages.finish(1);
    let [ox, oy] = [
        (region[0] - grown[0]) as usize,
        (region[1] - grown[1]) as usize,
    ];
    let rw = (region[2] - region[0] + 1) as usize;
    let crop = |v: &[f32]| -> Vec<f32> {
        (0..=(region[3] - region[1]) as usize)
            .flat_map(|r| {
                let start = (oy + r) * w + ox;
                v[start..start + rw].iter().copied()
            })
            .collect()
    };
    let cropped = crop(&heights);
    stages.finish(2);
    Ok((cropped, f.residual_m))
}

/// The relative times of [`fitted`]'s stages: the interpolation, the fit,
/// the crop (measured on an SRTM 1" tile).
const RESAMPLE_WEIGHTS: [usize; 3] = [12, 85, 3];

/// The heights of `region`: bilinear inside the footprint, the edge value
/// ramped to 0 at the window's border outside it.
fn fill(
    frame: &LatticeFrame,
    source: SourcePart<'_>,
    region: Window,
    progress: Progress<'_>,
) -> Result<Vec<f32>, TilesError> {
    let (cols, rows) = axes(frame, region);
    let (sw, sh) = (source.grid.width(), source.grid.height());
    let [ox, oy] = source.offset;
    let covers = |span: Option<(usize, usize)>, o: usize, n: usize| {
        span.is_none_or(|(lo, hi)| lo >= o && hi < o + n)
    };
    if !covers(read_span(&cols), ox, sw) || !covers(read_span(&rows), oy, sh) {
        return Err(TilesError::BadOptions(format!(
            "expected a source part covering the samples lattice region {region:?} reads, found {sw}x{sh} samples at {:?} of the whole source",
            source.offset
        )));
    }
    let src = source.grid.heights();
    let w = cols.len();
    let mut out = vec![0f32; w * rows.len()];
    let done = Counter::new(progress, rows.len());
    out.par_chunks_mut(w).zip(&rows).for_each(|(line, ry)| {
        done.add(1);
        if ry.ramp == 0.0 {
            return;
        }
        let r = ry.i0 - oy;
        let (top, bottom) = (&src[r * sw..], &src[(r + 1) * sw..]);
        for (o, cx) in line.iter_mut().zip(&cols) {
            let ramp = cx.ramp * ry.ramp;
            if ramp == 0.0 {
                continue;
            }
            let c = cx.i0 - ox;
            let (a, b) = (top[c] as f64, top[c + 1] as f64);
            let (c, d) = (bottom[c] as f64, bottom[c + 1] as f64);
            let upper = a + (b - a) * cx.frac;
            let lower = c + (d - c) * cx.frac;
            *o = ((upper + (lower - upper) * ry.frac) * ramp) as f32;
        }
    });
    Ok(out)
}

/// How far the lattice's surface is from the source, at the source's samples.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Deviation {
    /// Largest |lattice − source| over the source's samples, metres.
    pub max_m: f64,
    /// Root mean square of the same, metres.
    pub rms_m: f64,
    /// Source samples compared.
    pub samples: usize,
}

/// The resampling's own deviation: at every source sample, the lattice's
/// full-resolution surface (its unit cells cut along the hierarchy's
/// diagonals, the surface of a tile at error 0) against the source height.
/// A tile within `e` of the lattice at every lattice sample is therefore
/// within `e` plus this of the source at every source sample: both surfaces
/// are linear on each unit triangle of the lattice. For a part
/// ([`Lattice::resample_part`]), over the source samples inside it.
pub fn resampling_deviation(source: &HeightGrid, lattice: &Lattice) -> Deviation {
    resampling_deviation_with_progress(source, lattice, crate::progress::NONE)
}

/// [`resampling_deviation`], telling `progress(rows_done, rows)` of the
/// source's rows as it goes.
pub fn resampling_deviation_with_progress(
    source: &HeightGrid,
    lattice: &Lattice,
    progress: Progress<'_>,
) -> Deviation {
    let g = source.georef();
    let s = lattice.scheme();
    // The source's own longitudes (a part of the source may be one file
    // west of the antimeridian, in its own convention).
    let (d, off) = (s.cell_deg(), s.lon_offset(g.origin_x));
    let [ox, oy] = lattice.origin();
    let grid = lattice.grid();
    let (sw, src) = (source.width(), source.heights());
    let (gw, gh) = ((grid.width() - 1) as f64, (grid.height() - 1) as f64);
    // A part's lattice: only the source samples inside it.
    let part = lattice.is_part();
    let rows = Counter::new(progress, source.height());
    let (max, sum, n) = (0..source.height())
        .into_par_iter()
        .map(|row| {
            rows.add(1);
            let (mut max, mut sum, mut n) = (0f64, 0f64, 0);
            for col in 0..sw {
                let (lon, lat) = g.sample_xy(col as f64, row as f64);
                let x = s.col_of(lon + off) - ox as f64;
                let y = (90.0 - lat) / d - oy as f64;
                if part && (!(0.0..=gw).contains(&x) || !(0.0..=gh).contains(&y)) {
                    continue;
                }
                let dz = unit_surface(grid, [ox, oy], x, y) - src[row * sw + col] as f64;
                max = max.max(dz.abs());
                sum += dz * dz;
                n += 1;
            }
            (max, sum, n)
        })
        .reduce(
            || (0.0, 0.0, 0),
            |a, b| (a.0.max(b.0), a.1 + b.1, a.2 + b.2),
        );
    Deviation {
        max_m: max,
        rms_m: if n > 0 { (sum / n as f64).sqrt() } else { 0.0 },
        samples: n,
    }
}

/// The lattice's unit-triangle surface at window position `(x, y)`
/// (fractional columns and rows), cells cut like the hierarchy's unit
/// squares: `\` when the global `col + row` is even, `/` when odd.
fn unit_surface(grid: &HeightGrid, origin: [u64; 2], x: f64, y: f64) -> f64 {
    let (w, h) = (grid.width(), grid.height());
    let x = x.clamp(0.0, (w - 1) as f64);
    let y = y.clamp(0.0, (h - 1) as f64);
    let (i, j) = (
        (x.floor() as usize).min(w - 2),
        (y.floor() as usize).min(h - 2),
    );
    let (fx, fy) = (x - i as f64, y - j as f64);
    let z = |c: usize, r: usize| grid.heights()[r * w + c] as f64;
    let (nw, ne, sw, se) = (z(i, j), z(i + 1, j), z(i, j + 1), z(i + 1, j + 1));
    let even = (origin[0] + i as u64 + origin[1] + j as u64).is_multiple_of(2);
    if even {
        // Diagonal from the north-west to the south-east corner.
        if fx >= fy {
            nw + (ne - nw) * fx + (se - ne) * fy
        } else {
            nw + (sw - nw) * fy + (se - sw) * fx
        }
    } else if fx + fy <= 1.0 {
        // Diagonal from the north-east to the south-west corner.
        nw + (ne - nw) * fx + (sw - nw) * fy
    } else {
        se + (sw - se) * (1.0 - fx) + (ne - se) * (1.0 - fy)
    }
}

#[cfg(test)]
mod test {
    use super::*;

    /// A 1°×1° geographic grid at 0.01° with a smooth surface.
    pub(crate) fn smooth_source() -> HeightGrid {
        let n = 101;
        let heights = (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f32, (i / n) as f32);
                200.0 + 50.0 * (x * 0.07).sin() + 30.0 * (y * 0.05).cos()
            })
            .collect();
        let georef = GeoRef {
            crs: Crs::WGS84,
            origin_x: 10.0,
            origin_y: 1.0,
            pixel_x: 0.01,
            pixel_y: -0.01,
            pixel_is: PixelIs::Point,
            known: true,
        };
        HeightGrid::new(n, n, heights, georef).unwrap()
    }

    #[test]
    fn window_is_aligned_zero_bordered_and_covers_the_footprint() {
        let src = smooth_source();
        let lat = Lattice::resample(&src, &LatticeOptions::DEFAULT).unwrap();
        let s = lat.scheme();
        assert_eq!(s.max_zoom, 9); // 180/(64·2^9) = 0.0055° ≤ 0.01°
        let [x0, y0, x1, y1] = lat.window();
        let t = s.cells_at(lat.align_zoom());
        assert!(x0 % t == 0 && y0 % t == 0 && x1 % t == 0 && y1 % t == 0);
        assert_eq!((x0 / t + y0 / t) % 2, 0);
        let fp = lat.footprint();
        assert!((x0 as f64) < fp[0] && (x1 as f64) > fp[2]);
        let g = lat.grid();
        let (w, h) = (g.width(), g.height());
        for c in 0..w {
            assert_eq!(g.get(c, 0), 0.0);
            assert_eq!(g.get(c, h - 1), 0.0);
        }
        for r in 0..h {
            assert_eq!(g.get(0, r), 0.0);
            assert_eq!(g.get(w - 1, r), 0.0);
        }
        assert_eq!(lat.height_at(x0 - 1, y0), 0.0);
        // The zero band: an alignment tile inside every border.
        let band = t as usize;
        for r in 0..h {
            for c in (0..band).chain(w - band..w) {
                assert_eq!(g.get(c, r), 0.0);
            }
        }
    }

    #[test]
    fn beyond_the_edge_the_terrain_is_held_level_then_eases_to_0_within_a_tile() {
        let src = smooth_source();
        let lat = Lattice::resample(&src, &LatticeOptions::DEFAULT).unwrap();
        let s = lat.scheme();
        let (fp, tile) = (lat.footprint(), f64::from(s.tile_cells));
        // Along the row through the footprint's middle, eastwards past its edge.
        let y = ((fp[1] + fp[3]) / 2.0).round() as u64;
        let first = fp[2].floor() as u64 + 1;
        let edge = lat.height_at(fp[2].floor() as u64, y);
        let h: Vec<f64> = (first..first + s.tile_cells as u64 + 4)
            .map(|x| f64::from(lat.height_at(x, y)))
            .collect();
        assert!(edge > 100.0);
        // Level at the edge: the first cell beyond holds the edge's value
        // within one cell of the source's slope, the next steps are small.
        let steps: Vec<f64> = h.windows(2).map(|w| (w[1] - w[0]).abs()).collect();
        let largest = steps.iter().cloned().fold(0.0, f64::max);
        assert!(
            largest <= 1.5 * f64::from(edge) / (tile - 1.0) + 1.0,
            "steps {steps:?}"
        );
        assert!(steps[1] < largest / 3.0, "not level at the edge: {steps:?}");
        // Down monotonically, and 0 m from one finest tile out on.
        assert!(h.windows(2).all(|w| w[1] <= w[0] + 1e-6), "{h:?}");
        let beyond = |x: u64| x as f64 - fp[2];
        for (k, v) in h.iter().enumerate() {
            if beyond(first + k as u64) >= tile {
                assert_eq!(*v, 0.0, "{} cells out", beyond(first + k as u64));
            }
        }
        assert_eq!(ramp_factor(1.0, 10.0), 1.0);
        assert_eq!(ramp_factor(11.0, 10.0), 0.0);
        assert!((ramp_factor(6.0, 10.0) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn bilinear_reproduces_a_plane_and_deviation_is_small() {
        let n = 41;
        let heights = (0..n * n)
            .map(|i| 100.0 + 2.0 * (i % n) as f32 - 3.0 * (i / n) as f32)
            .collect();
        let georef = GeoRef {
            crs: Crs::WGS84,
            origin_x: 20.0,
            origin_y: -5.0,
            pixel_x: 0.005,
            pixel_y: -0.005,
            pixel_is: PixelIs::Point,
            known: true,
        };
        let src = HeightGrid::new(n, n, heights, georef).unwrap();
        let lat = Lattice::resample(&src, &LatticeOptions::DEFAULT).unwrap();
        let dev = resampling_deviation(&src, &lat);
        assert_eq!(dev.samples, n * n);
        // Exact inside; across the footprint's edge the lattice holds the
        // edge value one cell out: within a cell's slope (5 m per 0.005°).
        assert!(dev.max_m < 3.0 && dev.rms_m < 0.3, "{dev:?}");
        let smooth = smooth_source();
        let lat = Lattice::resample(&smooth, &LatticeOptions::DEFAULT).unwrap();
        let dev = resampling_deviation(&smooth, &lat);
        assert!(dev.max_m < 0.5 && dev.rms_m < dev.max_m, "{dev:?}");
    }

    #[test]
    fn refuses_projected_and_void_sources() {
        let mut src = smooth_source();
        let mut g = src.georef().clone();
        g.crs = Crs::Projected("UTM zone 25S".into());
        src.set_georef(g);
        let err = Lattice::resample(&src, &LatticeOptions::DEFAULT).unwrap_err();
        assert!(err.to_string().contains("UTM zone 25S"), "{err}");
        let mut src = smooth_source();
        src.heights_mut()[5] = f32::NAN;
        assert!(matches!(
            Lattice::resample(&src, &LatticeOptions::DEFAULT),
            Err(TilesError::Voids { .. })
        ));
    }
}
