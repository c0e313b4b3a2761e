//! Mosaics of adjacent tiles: several georeferenced [`HeightGrid`]s placed on
//! one common grid.
//!
//! Terrain larger than one DEM file is modelled by first merging the files of
//! neighbouring areas into one region: paper 001 (`../shared/seeds/001_49f2c365e8c41172.txt`,
//! "Remallado de terrenos multirresolución", §2 and §4) joins five adjacent
//! 1°×1° SRTM `.hgt` tiles along 35°S into one grid before simplifying it. This
//! module is that joining step. It does not resample: tiles must already share
//! one lattice.
//!
//! # Steps
//! 1. **Check** every tile against tile 0: georeferenced (`known`), the same
//!    [`Crs`], the same pixel size within a relative 1e-9 (and the same
//!    orientation), and a sample-centre origin an integer number of pixels away
//!    (within 1e-6 pixel). Tiles may mix [`PixelIs::Area`] and
//!    [`PixelIs::Point`]: positions are compared at sample centres.
//! 2. **Across the antimeridian**: geographic tiles whose union is narrower
//!    with their longitudes taken modulo 360° (an `E179` and a `W180` tile)
//!    are moved by whole turns to lie side by side (`grid::wrap`); tiles
//!    already contiguous are left exactly as they are.
//! 3. **Extent**: the union of the tiles' bounding boxes. Its size is checked
//!    with [`check_dimensions`], and the part of it covered by no tile (the
//!    *holes*, counted exactly from the tile rectangles) must not exceed
//!    [`MosaicOptions::max_hole_fraction`]; both are checked before anything is
//!    allocated, so absurdly distant tiles give an error, not an allocation.
//! 4. **Placement**: the output starts all void (NaN); tiles are copied row by
//!    row in input order, a sample being written only while the output there is
//!    still void. This is [`SeamPolicy::First`], and a void never wins over data.
//! 5. **Seams**: wherever two or more tiles overlap (adjacent SRTM tiles share
//!    their edge row or column), every sample is visited once, the valid values
//!    of all the tiles covering it are compared and, for [`SeamPolicy::Mean`],
//!    replaced by their mean. The [`SeamReport`] gives how many samples were
//!    compared, the largest difference, where, and between which tiles, and the
//!    mean difference.
//!
//! Holes stay void (NaN) and are counted in [`Mosaic::hole_samples`]; fill them
//! (and the tiles' own voids) with [`crate::grid::voids`] if needed.
//!
//! # Output georeference
//! CRS, pixel size and [`PixelIs`] convention of tile 0; origin at the
//! north-west corner of the union (across the antimeridian, its longitudes
//! run on past 180°: 179° to 181°, say). The placement itself does not depend on the
//! order of the tiles; only the seam values under [`SeamPolicy::First`] do.
//!
//! # Memory and runtime
//! The output grid plus O(1): the tiles are copied row by row and the seam pass
//! reads the overlapping samples directly from the tiles. Runtime is linear in
//! the output size plus O(n²) rectangle tests for n tiles.
//!
//! ```
//! use cota_core::{Crs, GeoRef, HeightGrid, PixelIs};
//! use cota_core::grid::mosaic::{mosaic, MosaicOptions};
//! // Two 3x3 tiles sharing a column, one degree apart at 1/2 degree per pixel.
//! let tile = |lon: f64, h: f32| {
//!     let g = GeoRef { crs: Crs::WGS84, origin_x: lon, origin_y: 1.0, pixel_x: 0.5,
//!                      pixel_y: -0.5, pixel_is: PixelIs::Point, known: true };
//!     HeightGrid::new(3, 3, vec![h; 9], g).unwrap()
//! };
//! let m = mosaic(vec![tile(10.0, 100.0), tile(11.0, 110.0)], &MosaicOptions::DEFAULT).unwrap();
//! assert_eq!((m.grid.width(), m.grid.height()), (5, 3));
//! assert_eq!(m.grid.get(2, 1), 105.0); // the shared column: mean of both tiles
//! assert_eq!(m.seams.compared, 3);
//! assert_eq!(m.seams.max_abs_diff_m, 10.0);
//! ```

use crate::grid::{check_dimensions, Crs, GeoRef, GridError, HeightGrid, PixelIs};

/// Largest relative difference between two tiles' pixel sizes still taken as equal.
const PIXEL_SIZE_REL_TOL: f64 = 1e-9;
/// Largest distance, in pixels, of a tile's origin from the common lattice.
const ALIGN_TOL_PX: f64 = 1e-6;
/// Largest tile offset, in pixels, considered at all (beyond it no grid can be allocated).
const MAX_OFFSET_PX: f64 = (1u64 << 40) as f64;

/// What to do where tiles overlap.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum SeamPolicy {
    /// The mean of the valid values of all the tiles covering the sample.
    /// Symmetric: the result does not depend on the order of the tiles. The default.
    #[default]
    Mean,
    /// The first tile (in input order) with a valid value there wins.
    First,
}

/// Options for [`mosaic`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct MosaicOptions {
    /// How overlapping samples are combined. A void never wins over data under
    /// either policy. Default: [`SeamPolicy::Mean`].
    pub seam_policy: SeamPolicy,
    /// Largest fraction (0..=1) of the output's samples that may be covered by
    /// no tile. Guards against tiles far apart, whose union would be mostly
    /// empty. Default: 0.5 (an L of three tiles in a 2×2 square is 1/4 hole; two
    /// diagonal tiles of a 2×2 square just under 1/2).
    pub max_hole_fraction: f64,
    /// Largest allowed difference in metres between overlapping valid samples;
    /// `None` only reports it. Default: `None` (tiles from different SRTM
    /// versions can differ by well over 100 m on their shared edge).
    pub max_seam_diff_m: Option<f64>,
}

impl MosaicOptions {
    /// The defaults, as documented on each field.
    pub const DEFAULT: MosaicOptions = MosaicOptions {
        seam_policy: SeamPolicy::Mean,
        max_hole_fraction: 0.5,
        max_seam_diff_m: None,
    };

    /// Sets [`MosaicOptions::seam_policy`].
    pub const fn with_seam_policy(mut self, policy: SeamPolicy) -> Self {
        self.seam_policy = policy;
        self
    }

    /// Sets [`MosaicOptions::max_hole_fraction`].
    pub const fn with_max_hole_fraction(mut self, fraction: f64) -> Self {
        self.max_hole_fraction = fraction;
        self
    }

    /// Sets [`MosaicOptions::max_seam_diff_m`].
    pub const fn with_max_seam_diff_m(mut self, diff_m: Option<f64>) -> Self {
        self.max_seam_diff_m = diff_m;
        self
    }
}

impl Default for MosaicOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Why tiles could not be mosaicked.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum MosaicError {
    /// The list of tiles is empty.
    #[error("no tiles to mosaic")]
    NoTiles,
    /// A tile has no georeference (e.g. a PNG tile), so it cannot be placed.
    #[error("tile {index} has no georeference, so it cannot be placed in a mosaic")]
    Unreferenced {
        /// Index of the tile in the input.
        index: usize,
    },
    /// A tile's transform is not finite or has a zero pixel size.
    #[error("tile {index} has an unusable georeference: origin ({origin_x}, {origin_y}), pixel size {pixel_x} x {pixel_y}")]
    InvalidGeoRef {
        /// Index of the tile in the input.
        index: usize,
        /// Its origin x.
        origin_x: f64,
        /// Its origin y.
        origin_y: f64,
        /// Its pixel width.
        pixel_x: f64,
        /// Its pixel height.
        pixel_y: f64,
    },
    /// Two tiles are in different coordinate systems.
    #[error("tiles in different coordinate systems: tile 0 is in {first}, tile {index} in {other}; reprojection is not supported")]
    CrsMismatch {
        /// Index of the differing tile.
        index: usize,
        /// CRS of tile 0.
        first: Crs,
        /// CRS of the differing tile.
        other: Crs,
    },
    /// Two tiles have different pixel sizes.
    #[error("tiles of different resolution: {first} vs {other} (tile 0 vs tile {index}), resampling is not supported")]
    ResolutionMismatch {
        /// Index of the differing tile.
        index: usize,
        /// Pixel size of tile 0, e.g. "1/1200°".
        first: String,
        /// Pixel size of the differing tile.
        other: String,
    },
    /// Two tiles have opposite axis directions (e.g. one south-up).
    #[error("tile {index} is flipped relative to tile 0 (pixel size {other} vs {first}); flipping is not supported")]
    OrientationMismatch {
        /// Index of the differing tile.
        index: usize,
        /// Signed pixel size (x, y) of tile 0.
        first: String,
        /// Signed pixel size (x, y) of the differing tile.
        other: String,
    },
    /// A tile's samples do not fall on tile 0's lattice.
    #[error("tile {index} is not aligned with tile 0: its samples are {offset_cols} columns and {offset_rows} rows away, not a whole number of pixels; resampling is not supported")]
    NotAligned {
        /// Index of the tile.
        index: usize,
        /// Offset of its first sample from tile 0's, in columns.
        offset_cols: f64,
        /// Offset in rows.
        offset_rows: f64,
    },
    /// Too much of the union of the tiles would be covered by no tile.
    #[error("the tiles are too far apart: {hole_samples} of the {width}x{height} samples of their union ({percent:.1}%) would be covered by no tile, more than the allowed {max_percent:.1}%")]
    TooSparse {
        /// Width of the union.
        width: usize,
        /// Height of the union.
        height: usize,
        /// Samples covered by no tile.
        hole_samples: u64,
        /// `hole_samples` as a percentage of the union.
        percent: f64,
        /// [`MosaicOptions::max_hole_fraction`] as a percentage.
        max_percent: f64,
    },
    /// Overlapping tiles disagree by more than [`MosaicOptions::max_seam_diff_m`].
    #[error("tiles {} and {} differ by {diff_m} m at ({}, {}), more than the allowed {limit_m} m", at.tiles[0], at.tiles[1], at.x, at.y)]
    SeamTooLarge {
        /// The difference found, metres.
        diff_m: f64,
        /// The limit, metres.
        limit_m: f64,
        /// Where.
        at: SeamPoint,
    },
    /// The union is too large to allocate.
    #[error(transparent)]
    Grid(#[from] GridError),
}

/// Where a tile went in the mosaic.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TilePlacement {
    /// Index of the tile in the input.
    pub index: usize,
    /// Output column of the tile's column 0.
    pub col: usize,
    /// Output row of the tile's row 0.
    pub row: usize,
    /// The tile's width in samples.
    pub width: usize,
    /// The tile's height in samples.
    pub height: usize,
}

impl TilePlacement {
    /// True when output sample (`col`, `row`) lies inside this tile.
    #[inline]
    pub fn contains(&self, col: usize, row: usize) -> bool {
        col >= self.col
            && col < self.col + self.width
            && row >= self.row
            && row < self.row + self.height
    }
}

/// A sample where overlapping tiles disagree.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeamPoint {
    /// Output column.
    pub col: usize,
    /// Output row.
    pub row: usize,
    /// CRS x of the sample.
    pub x: f64,
    /// CRS y of the sample.
    pub y: f64,
    /// Input indices of the tiles holding the lowest and the highest value there.
    pub tiles: [usize; 2],
}

/// What the overlaps between tiles looked like.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SeamReport {
    /// Output samples covered by two or more tiles.
    pub overlap_samples: usize,
    /// Of those, samples where at least two tiles hold a valid value: these are compared.
    pub compared: usize,
    /// Largest difference (highest − lowest valid value) over the compared samples, metres.
    pub max_abs_diff_m: f64,
    /// Mean of that difference over the compared samples, metres (0 when none).
    pub mean_abs_diff_m: f64,
    /// Where the largest difference is; `None` when no sample differs.
    pub max_diff_at: Option<SeamPoint>,
}

/// The result of [`mosaic`].
#[derive(Debug, Clone, PartialEq)]
pub struct Mosaic {
    /// The merged grid. Holes and the tiles' own voids are NaN.
    pub grid: HeightGrid,
    /// The overlaps between tiles.
    pub seams: SeamReport,
    /// Where each tile went, in input order.
    pub placements: Vec<TilePlacement>,
    /// Output samples covered by no tile (void in `grid`).
    pub hole_samples: usize,
}

/// Merges georeferenced tiles into one grid. See the [module documentation](self)
/// for the rules and the seam policy.
///
/// Takes the tiles by value so that a single tile is returned as is, without a
/// copy (and without any check: there is nothing to place).
///
/// # Errors
/// [`MosaicError`]: no tiles, an unreferenced tile, different CRSs, pixel sizes
/// or orientations, tiles off the common lattice, a union too large or too
/// sparse, or a seam difference above [`MosaicOptions::max_seam_diff_m`].
///
/// # Runtime
/// O(output samples + n² ) for n tiles; memory: the output grid, the tiles
/// (dropped one by one as they are copied) and their overlaps.
pub fn mosaic(tiles: Vec<HeightGrid>, opts: &MosaicOptions) -> Result<Mosaic, MosaicError> {
    if tiles.len() <= 1 {
        let grid = tiles.into_iter().next().ok_or(MosaicError::NoTiles)?;
        let placements = vec![TilePlacement {
            index: 0,
            col: 0,
            row: 0,
            width: grid.width(),
            height: grid.height(),
        }];
        return Ok(Mosaic {
            grid,
            seams: SeamReport::default(),
            placements,
            hole_samples: 0,
        });
    }
    let shapes: Vec<TileShape> = tiles.iter().map(TileShape::of).collect();
    let layout = layout(&shapes, opts)?;
    // Zeroed pages cost nothing until written: each tile's area is committed
    // as it is copied, and the tile is then dropped, keeping only the parts
    // that overlap other tiles (for the seams). Peak: the output plus about
    // one tile, not the output plus every tile.
    let mut out = vec![0f32; layout.width * layout.height];
    let mut patches = Vec::with_capacity(tiles.len());
    for (i, tile) in tiles.into_iter().enumerate() {
        let p = &layout.placements[i];
        copy_first_wins(&mut out, layout.width, &tile, p, &layout.placements[..i]);
        patches.push(overlap_patches(&tile, p, &layout.placements));
    }
    fill_holes(&mut out, layout.width, &layout.placements);
    let grid = HeightGrid::new(layout.width, layout.height, out, layout.georef)?;
    let (grid, seams) = resolve_seams(grid, &patches, &layout.placements, opts.seam_policy);
    if let (Some(limit_m), Some(at)) = (opts.max_seam_diff_m, seams.max_diff_at) {
        if seams.max_abs_diff_m > limit_m {
            return Err(MosaicError::SeamTooLarge {
                diff_m: seams.max_abs_diff_m,
                limit_m,
                at,
            });
        }
    }
    Ok(Mosaic {
        grid,
        seams,
        placements: layout.placements,
        hole_samples: layout.hole_samples as usize,
    })
}

/// What [`layout`] needs of a tile: its georeference and size, not its
/// samples.
#[derive(Debug, Clone, PartialEq)]
pub struct TileShape {
    /// The tile's georeference.
    pub georef: GeoRef,
    /// Width in samples.
    pub width: usize,
    /// Height in samples.
    pub height: usize,
}

impl TileShape {
    /// The shape of `grid`.
    pub fn of(grid: &HeightGrid) -> TileShape {
        TileShape {
            georef: grid.georef().clone(),
            width: grid.width(),
            height: grid.height(),
        }
    }
}

/// The mosaic's extent and where each tile goes: what [`mosaic`] makes of
/// two or more tiles, decided from their shapes alone.
#[derive(Debug, Clone, PartialEq)]
pub struct MosaicLayout {
    /// Width of the mosaic in samples.
    pub width: usize,
    /// Height of the mosaic in samples.
    pub height: usize,
    /// The mosaic's georeference (see the module docs).
    pub georef: GeoRef,
    /// Where each tile goes, in input order.
    pub placements: Vec<TilePlacement>,
    /// Samples covered by no tile.
    pub hole_samples: u64,
}

/// Checks the tiles' shapes against tile 0's and computes the mosaic's
/// extent, georeference and placements, without allocating it: the layout
/// [`mosaic`] uses for two or more tiles (one tile is placed at its own
/// origin, with its georeference marked known).
///
/// # Errors
/// As [`mosaic`], except the seam limit.
pub fn layout(tiles: &[TileShape], opts: &MosaicOptions) -> Result<MosaicLayout, MosaicError> {
    let Some(first) = tiles.first() else {
        return Err(MosaicError::NoTiles);
    };
    let g0 = &first.georef;
    // Integer offset (columns, rows) of each tile's first sample from tile 0's.
    let mut offsets = Vec::with_capacity(tiles.len());
    for (index, tile) in tiles.iter().enumerate() {
        offsets.push(lattice_offset(index, &tile.georef, g0)?);
    }
    let turns = wrap_turns(tiles, &offsets);
    if let Some((turn, k)) = &turns {
        for (o, k) in offsets.iter_mut().zip(k) {
            o.0 += k * turn;
        }
    }
    let min_col = offsets.iter().map(|o| o.0).min().unwrap_or(0);
    let min_row = offsets.iter().map(|o| o.1).min().unwrap_or(0);
    let end_col = tiles
        .iter()
        .zip(&offsets)
        .map(|(t, o)| o.0 + t.width as i64)
        .max()
        .unwrap_or(0);
    let end_row = tiles
        .iter()
        .zip(&offsets)
        .map(|(t, o)| o.1 + t.height as i64)
        .max()
        .unwrap_or(0);
    let (width, height) = ((end_col - min_col) as u64, (end_row - min_row) as u64);
    check_dimensions(width, height)?;
    let (width, height) = (width as usize, height as usize);
    let placements: Vec<TilePlacement> = tiles
        .iter()
        .zip(&offsets)
        .enumerate()
        .map(|(index, (t, o))| TilePlacement {
            index,
            col: (o.0 - min_col) as usize,
            row: (o.1 - min_row) as usize,
            width: t.width,
            height: t.height,
        })
        .collect();
    let total = (width * height) as u64;
    let hole_samples = total - covered_samples(&placements);
    let fraction = hole_samples as f64 / total as f64;
    if fraction > opts.max_hole_fraction {
        return Err(MosaicError::TooSparse {
            width,
            height,
            hole_samples,
            percent: 100.0 * fraction,
            max_percent: 100.0 * opts.max_hole_fraction,
        });
    }
    let shifts_deg: Vec<f64> = match &turns {
        Some((_, k)) => k.iter().map(|&k| 360.0 * k as f64).collect(),
        None => vec![0.0; tiles.len()],
    };
    let georef = output_georef(tiles, &offsets, &shifts_deg, min_col, min_row);
    Ok(MosaicLayout {
        width,
        height,
        georef,
        placements,
        hole_samples,
    })
}

/// Offset in whole pixels of `g`'s first sample from `g0`'s, after checking
/// that the two georeferences are compatible.
fn lattice_offset(index: usize, g: &GeoRef, g0: &GeoRef) -> Result<(i64, i64), MosaicError> {
    if !g.known {
        return Err(MosaicError::Unreferenced { index });
    }
    let finite = [g.origin_x, g.origin_y, g.pixel_x, g.pixel_y]
        .iter()
        .all(|v| v.is_finite());
    if !finite || g.pixel_x == 0.0 || g.pixel_y == 0.0 {
        return Err(MosaicError::InvalidGeoRef {
            index,
            origin_x: g.origin_x,
            origin_y: g.origin_y,
            pixel_x: g.pixel_x,
            pixel_y: g.pixel_y,
        });
    }
    if g.crs != g0.crs {
        return Err(MosaicError::CrsMismatch {
            index,
            first: g0.crs.clone(),
            other: g.crs.clone(),
        });
    }
    if !same_size(g.pixel_x, g0.pixel_x) || !same_size(g.pixel_y, g0.pixel_y) {
        return Err(MosaicError::ResolutionMismatch {
            index,
            first: describe_pixel(g0),
            other: describe_pixel(g),
        });
    }
    if g.pixel_x.signum() != g0.pixel_x.signum() || g.pixel_y.signum() != g0.pixel_y.signum() {
        return Err(MosaicError::OrientationMismatch {
            index,
            first: format!("{} x {}", g0.pixel_x, g0.pixel_y),
            other: format!("{} x {}", g.pixel_x, g.pixel_y),
        });
    }
    let (x0, y0) = g0.sample_xy(0.0, 0.0);
    let (x, y) = g.sample_xy(0.0, 0.0);
    let dc = (x - x0) / g0.pixel_x;
    let dr = (y - y0) / g0.pixel_y;
    let (rc, rr) = (dc.round(), dr.round());
    if (dc - rc).abs() > ALIGN_TOL_PX
        || (dr - rr).abs() > ALIGN_TOL_PX
        || !dc.is_finite()
        || !dr.is_finite()
    {
        return Err(MosaicError::NotAligned {
            index,
            // + 0.0 turns a -0 into 0 for the message.
            offset_cols: dc + 0.0,
            offset_rows: dr + 0.0,
        });
    }
    if rc.abs() > MAX_OFFSET_PX || rr.abs() > MAX_OFFSET_PX {
        return Err(GridError::TooLarge {
            width: rc.abs() as u64,
            height: rr.abs() as u64,
            max: crate::grid::MAX_SAMPLES,
        }
        .into());
    }
    Ok((rc as i64, rr as i64))
}

/// True when two pixel sizes are equal within [`PIXEL_SIZE_REL_TOL`] (sign ignored).
fn same_size(a: f64, b: f64) -> bool {
    let (a, b) = (a.abs(), b.abs());
    (a - b).abs() <= PIXEL_SIZE_REL_TOL * a.max(b)
}

/// A pixel size for messages: "1/1200°" for geographic grids, "30 m", "2 units".
fn describe_pixel(g: &GeoRef) -> String {
    let one = |p: f64| {
        let p = p.abs();
        if g.crs.is_geographic() {
            let inv = 1.0 / p;
            if inv >= 2.0 && (inv - inv.round()).abs() <= 1e-6 * inv {
                format!("1/{}°", inv.round())
            } else {
                format!("{p}°")
            }
        } else if g.crs == Crs::Unknown {
            format!("{p} units")
        } else {
            format!("{p} m")
        }
    };
    if same_size(g.pixel_x, g.pixel_y) {
        one(g.pixel_x)
    } else {
        format!("{} x {}", one(g.pixel_x), one(g.pixel_y))
    }
}

/// Number of samples covered by at least one placed tile: the area of the union
/// of the rectangles, by vertical strips between distinct column edges.
fn covered_samples(placements: &[TilePlacement]) -> u64 {
    let mut edges: Vec<usize> = placements
        .iter()
        .flat_map(|p| [p.col, p.col + p.width])
        .collect();
    edges.sort_unstable();
    edges.dedup();
    let mut covered = 0u64;
    let mut spans: Vec<(usize, usize)> = Vec::with_capacity(placements.len());
    for strip in edges.windows(2) {
        let (c0, c1) = (strip[0], strip[1]);
        spans.clear();
        spans.extend(
            placements
                .iter()
                .filter(|p| p.col <= c0 && p.col + p.width >= c1)
                .map(|p| (p.row, p.row + p.height)),
        );
        spans.sort_unstable();
        let mut rows = 0u64;
        let mut end = 0usize;
        for &(r0, r1) in &spans {
            let start = r0.max(end);
            if r1 > start {
                rows += (r1 - start) as u64;
                end = r1;
            }
        }
        covered += rows * (c1 - c0) as u64;
    }
    covered
}

/// The columns in a turn (360°) and the turns to move each tile by
/// ([`super::wrap`]) when the tiles are geographic, their columns run east,
/// a turn is a whole number of columns, every tile lies within ±360° of
/// longitude, and the moved tiles' union is narrower; `None` otherwise
/// (the tiles are laid out as they are).
fn wrap_turns(tiles: &[TileShape], offsets: &[(i64, i64)]) -> Option<(i64, Vec<i64>)> {
    let g0 = &tiles[0].georef;
    if !g0.crs.is_geographic() || g0.pixel_x <= 0.0 {
        return None;
    }
    let turn = 360.0 / g0.pixel_x;
    let whole = turn.round();
    if (turn - whole).abs() > ALIGN_TOL_PX * whole || !(1.0..=MAX_OFFSET_PX).contains(&whole) {
        return None;
    }
    let on_world = tiles.iter().all(|t| {
        let (west, _) = t.georef.sample_xy(0.0, 0.0);
        let (east, _) = t.georef.sample_xy(t.width as f64 - 1.0, 0.0);
        (-360.0..=360.0).contains(&west) && (-360.0..=360.0).contains(&east)
    });
    if !on_world {
        return None;
    }
    let cols: Vec<(i64, i64)> = tiles
        .iter()
        .zip(offsets)
        .map(|(t, o)| (o.0, t.width as i64))
        .collect();
    let turn = whole as i64;
    super::wrap::turns(&cols, turn).map(|k| (turn, k))
}

/// Tile 0's CRS, pixel size and convention, with the origin moved to the union's
/// north-west corner. Each coordinate of the origin is taken from a tile that
/// reaches that edge, so that it is exact when the conventions agree; its x
/// moved by that tile's `shifts_deg` (whole turns, across the antimeridian).
fn output_georef(
    tiles: &[TileShape],
    offsets: &[(i64, i64)],
    shifts_deg: &[f64],
    min_col: i64,
    min_row: i64,
) -> GeoRef {
    let g0 = &tiles[0].georef;
    let mut out = g0.clone();
    out.known = true;
    let west = offsets.iter().position(|o| o.0 == min_col).unwrap_or(0);
    let north = offsets.iter().position(|o| o.1 == min_row).unwrap_or(0);
    out.origin_x = origin_in(&tiles[west].georef, g0.pixel_is, true);
    if shifts_deg[west] != 0.0 {
        out.origin_x += shifts_deg[west];
    }
    out.origin_y = origin_in(&tiles[north].georef, g0.pixel_is, false);
    out
}

/// `g`'s origin x (or y) expressed in the convention `pixel_is`.
fn origin_in(g: &GeoRef, pixel_is: PixelIs, x: bool) -> f64 {
    let (origin, pixel) = if x {
        (g.origin_x, g.pixel_x)
    } else {
        (g.origin_y, g.pixel_y)
    };
    match (g.pixel_is, pixel_is) {
        (PixelIs::Area, PixelIs::Point) => origin + 0.5 * pixel,
        (PixelIs::Point, PixelIs::Area) => origin - 0.5 * pixel,
        _ => origin,
    }
}

/// Copies `tile` into `out` at its placement, row by row, writing only where the
/// output is still void: the first valid value wins, a void never overwrites data.
fn copy_first_wins(
    out: &mut [f32],
    out_width: usize,
    tile: &HeightGrid,
    p: &TilePlacement,
    earlier: &[TilePlacement],
) {
    let w = tile.width();
    for (r, src) in tile.heights().chunks_exact(w).enumerate() {
        let row = p.row + r;
        // Column spans of this row already covered by earlier tiles: there the
        // earlier value wins unless it is void.
        let spans: Vec<(usize, usize)> = earlier
            .iter()
            .filter(|e| row >= e.row && row < e.row + e.height)
            .map(|e| (e.col, e.col + e.width))
            .collect();
        let start = row * out_width + p.col;
        for (k, (d, &s)) in out[start..start + w].iter_mut().zip(src).enumerate() {
            let col = p.col + k;
            if !spans.iter().any(|&(a, b)| col >= a && col < b) || d.is_nan() {
                *d = s;
            }
        }
    }
}

/// Sets the samples covered by no tile to NaN (the output starts zeroed).
fn fill_holes(out: &mut [f32], out_width: usize, placements: &[TilePlacement]) {
    for (row, line) in out.chunks_exact_mut(out_width).enumerate() {
        let mut spans: Vec<(usize, usize)> = placements
            .iter()
            .filter(|p| row >= p.row && row < p.row + p.height)
            .map(|p| (p.col, p.col + p.width))
            .collect();
        spans.sort_unstable();
        let mut next = 0;
        for (a, b) in spans {
            if a > next {
                line[next..a].fill(f32::NAN);
            }
            next = next.max(b);
        }
        if next < out_width {
            line[next..].fill(f32::NAN);
        }
    }
}

/// The samples of one tile that other tiles also cover: one rectangle per
/// overlapping tile, in output coordinates.
struct Patch {
    col: usize,
    row: usize,
    width: usize,
    height: usize,
    heights: Vec<f32>,
}

fn overlap_patches(tile: &HeightGrid, p: &TilePlacement, all: &[TilePlacement]) -> Vec<Patch> {
    let mut out = Vec::new();
    for q in all.iter().filter(|q| q.index != p.index) {
        let (c0, c1) = (p.col.max(q.col), (p.col + p.width).min(q.col + q.width));
        let (r0, r1) = (p.row.max(q.row), (p.row + p.height).min(q.row + q.height));
        if c0 >= c1 || r0 >= r1 {
            continue;
        }
        let mut heights = Vec::with_capacity((c1 - c0) * (r1 - r0));
        for row in r0..r1 {
            for col in c0..c1 {
                heights.push(tile.get(col - p.col, row - p.row));
            }
        }
        out.push(Patch {
            col: c0,
            row: r0,
            width: c1 - c0,
            height: r1 - r0,
            heights,
        });
    }
    out
}

/// The value tile `patches` holds at output sample (`col`, `row`), if any.
fn patch_value(patches: &[Patch], col: usize, row: usize) -> Option<f32> {
    patches.iter().find_map(|q| {
        (col >= q.col && col < q.col + q.width && row >= q.row && row < q.row + q.height)
            .then(|| q.heights[(row - q.row) * q.width + (col - q.col)])
    })
}

/// Visits every output sample covered by two or more tiles once, compares the
/// tiles' valid values there and applies the seam policy.
fn resolve_seams(
    mut grid: HeightGrid,
    tiles: &[Vec<Patch>],
    placements: &[TilePlacement],
    policy: SeamPolicy,
) -> (HeightGrid, SeamReport) {
    let mut report = SeamReport::default();
    let mut sum_diff = 0.0f64;
    let width = grid.width();
    let georef = grid.georef().clone();
    let out = grid.heights_mut();
    for (j, pj) in placements.iter().enumerate() {
        for (i, pi) in placements[..j].iter().enumerate() {
            let (c0, c1) = (
                pi.col.max(pj.col),
                (pi.col + pi.width).min(pj.col + pj.width),
            );
            let (r0, r1) = (
                pi.row.max(pj.row),
                (pi.row + pi.height).min(pj.row + pj.height),
            );
            for row in r0..r1 {
                for col in c0..c1 {
                    // Visit the sample from the pair of its first two covering
                    // tiles only, so that it is counted once.
                    let earlier = placements[..j]
                        .iter()
                        .enumerate()
                        .any(|(k, pk)| k != i && pk.contains(col, row));
                    if earlier {
                        continue;
                    }
                    report.overlap_samples += 1;
                    let s = sample_stats(tiles, &placements[i..], col, row);
                    if s.count >= 2 {
                        let diff = f64::from(s.max.0) - f64::from(s.min.0);
                        report.compared += 1;
                        sum_diff += diff;
                        if diff > report.max_abs_diff_m {
                            let (x, y) = georef.sample_xy(col as f64, row as f64);
                            report.max_abs_diff_m = diff;
                            report.max_diff_at = Some(SeamPoint {
                                col,
                                row,
                                x,
                                y,
                                tiles: [s.min.1, s.max.1],
                            });
                        }
                    }
                    if policy == SeamPolicy::Mean && s.count >= 1 {
                        out[row * width + col] = (s.sum / s.count as f64) as f32;
                    }
                }
            }
        }
    }
    if report.compared > 0 {
        report.mean_abs_diff_m = sum_diff / report.compared as f64;
    }
    (grid, report)
}

/// Valid values of the tiles covering one output sample.
struct SampleStats {
    count: usize,
    sum: f64,
    /// Lowest value and the index of its tile.
    min: (f32, usize),
    /// Highest value and the index of its tile.
    max: (f32, usize),
}

/// Gathers the valid values at output (`col`, `row`) of the tiles in `placements`
/// (a suffix of all placements; indices are the tiles' input indices).
fn sample_stats(
    tiles: &[Vec<Patch>],
    placements: &[TilePlacement],
    col: usize,
    row: usize,
) -> SampleStats {
    let mut s = SampleStats {
        count: 0,
        sum: 0.0,
        min: (f32::INFINITY, 0),
        max: (f32::NEG_INFINITY, 0),
    };
    for p in placements.iter().filter(|p| p.contains(col, row)) {
        let Some(v) = patch_value(&tiles[p.index], col, row) else {
            continue;
        };
        if v.is_nan() {
            continue;
        }
        s.count += 1;
        s.sum += f64::from(v);
        if v < s.min.0 {
            s.min = (v, p.index);
        }
        if v > s.max.0 {
            s.max = (v, p.index);
        }
    }
    s
}

#[cfg(test)]
mod test {
    use super::*;

    /// A tile of `w`×`h` samples whose first sample is at (`x0`, `y0`), pixel `px`
    /// (pixel-is-point, north-up, WGS 84), heights from `f(col, row)` in tile coordinates.
    fn tile(
        w: usize,
        h: usize,
        x0: f64,
        y0: f64,
        px: f64,
        f: impl Fn(usize, usize) -> f32,
    ) -> HeightGrid {
        let g = GeoRef {
            crs: Crs::WGS84,
            origin_x: x0,
            origin_y: y0,
            pixel_x: px,
            pixel_y: -px,
            pixel_is: PixelIs::Point,
            known: true,
        };
        let mut v = Vec::with_capacity(w * h);
        for r in 0..h {
            for c in 0..w {
                v.push(f(c, r));
            }
        }
        HeightGrid::new(w, h, v, g).unwrap()
    }

    /// A global surface sampled at lattice position (X = x0/px + c, Y = ...).
    fn surface(x0: f64, y0: f64, px: f64) -> impl Fn(usize, usize) -> f32 {
        move |c, r| {
            let gx = (x0 / px).round() as i64 + c as i64;
            let gy = (y0 / px).round() as i64 - r as i64;
            (gx * 3 + gy * 7) as f32
        }
    }

    fn opts() -> MosaicOptions {
        MosaicOptions::DEFAULT
    }

    #[test]
    fn single_tile_is_returned_as_is() {
        let t = tile(4, 3, 0.0, 0.0, 1.0, |c, r| (c + r) as f32);
        let m = mosaic(vec![t.clone()], &opts()).unwrap();
        assert_eq!(m.grid, t);
        assert_eq!(m.seams, SeamReport::default());
        assert_eq!(m.hole_samples, 0);
        assert!(matches!(mosaic(vec![], &opts()), Err(MosaicError::NoTiles)));
    }

    #[test]
    fn two_tiles_sharing_a_column() {
        let px = 0.25;
        let a = tile(5, 5, 10.0, 1.0, px, surface(10.0, 1.0, px));
        let b = tile(5, 5, 11.0, 1.0, px, surface(11.0, 1.0, px));
        let m = mosaic(vec![b.clone(), a.clone()], &opts()).unwrap();
        assert_eq!((m.grid.width(), m.grid.height()), (9, 5));
        assert_eq!(m.grid.georef().origin_x, 10.0);
        assert_eq!(m.grid.georef().origin_y, 1.0);
        assert_eq!(m.placements[0].col, 4);
        assert_eq!(m.placements[1].col, 0);
        assert_eq!(m.seams.overlap_samples, 5);
        assert_eq!(m.seams.compared, 5);
        assert_eq!(m.seams.max_abs_diff_m, 0.0);
        assert_eq!(m.seams.max_diff_at, None);
        assert_eq!(m.hole_samples, 0);
        let f = surface(10.0, 1.0, px);
        for r in 0..5 {
            for c in 0..9 {
                assert_eq!(m.grid.get(c, r), f(c, r), "({c},{r})");
            }
        }
    }

    #[test]
    fn seam_mean_first_and_voids() {
        let a = tile(3, 2, 0.0, 1.0, 1.0, |_, _| 10.0);
        let mut b = tile(3, 2, 2.0, 1.0, 1.0, |_, _| 20.0);
        b.heights_mut()[3] = f32::NAN; // (0, 1) of b: the shared column, row 1
        let mean = mosaic(vec![a.clone(), b.clone()], &opts()).unwrap();
        assert_eq!(mean.grid.get(2, 0), 15.0);
        assert_eq!(mean.grid.get(2, 1), 10.0, "a void never wins");
        assert_eq!(mean.seams.overlap_samples, 2);
        assert_eq!(mean.seams.compared, 1);
        assert_eq!(mean.seams.max_abs_diff_m, 10.0);
        assert_eq!(mean.seams.mean_abs_diff_m, 10.0);
        let at = mean.seams.max_diff_at.unwrap();
        assert_eq!(
            (at.col, at.row, at.x, at.y, at.tiles),
            (2, 0, 2.0, 1.0, [0, 1])
        );

        let first = opts().with_seam_policy(SeamPolicy::First);
        let m = mosaic(vec![b.clone(), a.clone()], &first).unwrap();
        assert_eq!(m.grid.get(2, 0), 20.0);
        assert_eq!(m.grid.get(2, 1), 10.0, "a void never wins");
        assert_eq!(m.seams.max_diff_at.unwrap().tiles, [1, 0]);

        let strict = opts().with_max_seam_diff_m(Some(5.0));
        let err = mosaic(vec![a, b], &strict).unwrap_err();
        assert!(
            matches!(err, MosaicError::SeamTooLarge { diff_m, .. } if diff_m == 10.0),
            "{err}"
        );
    }

    #[test]
    fn four_tiles_share_a_corner_sample() {
        let px = 0.5;
        let mk = |x0: f64, y0: f64, h: f32| tile(3, 3, x0, y0, px, move |_, _| h);
        let tiles = vec![
            mk(0.0, 2.0, 1.0),
            mk(1.0, 2.0, 2.0),
            mk(0.0, 1.0, 3.0),
            mk(1.0, 1.0, 6.0),
        ];
        let m = mosaic(tiles, &opts()).unwrap();
        assert_eq!((m.grid.width(), m.grid.height()), (5, 5));
        // The centre is shared by four tiles and counted once.
        assert_eq!(m.seams.overlap_samples, 5 + 5 - 1);
        assert_eq!(m.grid.get(2, 2), 3.0);
        assert_eq!(m.seams.max_abs_diff_m, 5.0);
        let at = m.seams.max_diff_at.unwrap();
        assert_eq!((at.col, at.row, at.tiles), (2, 2, [0, 3]));
        assert_eq!(m.grid.void_count(), 0);
    }

    #[test]
    fn hole_in_a_two_by_two_is_void_and_counted() {
        let px = 0.5;
        let mk = |x0: f64, y0: f64| tile(3, 3, x0, y0, px, surface(x0, y0, px));
        let m = mosaic(vec![mk(0.0, 2.0), mk(1.0, 2.0), mk(0.0, 1.0)], &opts()).unwrap();
        assert_eq!(m.hole_samples, 4);
        assert_eq!(m.grid.void_count(), 4);
        assert!(m.grid.get(4, 4).is_nan() && m.grid.get(3, 3).is_nan());
        assert!(!m.grid.get(2, 3).is_nan() && !m.grid.get(3, 2).is_nan());
    }

    #[test]
    fn far_apart_tiles_are_refused_before_allocation() {
        let a = tile(3, 3, 0.0, 0.0, 1.0, |_, _| 0.0);
        let b = tile(3, 3, 100.0, 0.0, 1.0, |_, _| 0.0);
        let err = mosaic(vec![a.clone(), b.clone()], &opts()).unwrap_err();
        assert!(
            matches!(
                err,
                MosaicError::TooSparse {
                    hole_samples: 291,
                    ..
                }
            ),
            "{err}"
        );
        let loose = opts().with_max_hole_fraction(1.0);
        assert_eq!(
            mosaic(vec![a.clone(), b], &loose).unwrap().hole_samples,
            291
        );
        let c = tile(3, 3, 1e9, -1e9, 1.0, |_, _| 0.0);
        let err = mosaic(vec![a, c], &loose).unwrap_err();
        assert!(
            matches!(err, MosaicError::Grid(GridError::TooLarge { .. })),
            "{err}"
        );
    }

    #[test]
    fn tiles_across_the_antimeridian_are_joined_modulo_360() {
        let px = 0.25;
        // E179 and W180 (its samples one turn east, at 180..181).
        let e = tile(5, 5, 179.0, 1.0, px, surface(179.0, 1.0, px));
        let w = tile(5, 5, -180.0, 1.0, px, surface(180.0, 1.0, px));
        for tiles in [vec![e.clone(), w.clone()], vec![w.clone(), e.clone()]] {
            let m = mosaic(tiles, &opts()).unwrap();
            assert_eq!((m.grid.width(), m.grid.height()), (9, 5));
            assert_eq!(m.grid.georef().origin_x, 179.0);
            assert_eq!((m.hole_samples, m.seams.max_abs_diff_m), (0, 0.0));
            let f = surface(179.0, 1.0, px);
            for r in 0..5 {
                for c in 0..9 {
                    assert_eq!(m.grid.get(c, r), f(c, r), "({c},{r})");
                }
            }
        }
        // Touching 180° from either side: laid out as before, no turn.
        let west = tile(5, 5, 178.0, 1.0, px, |_, _| 1.0);
        let m = mosaic(vec![e.clone(), west], &opts()).unwrap();
        assert_eq!((m.grid.width(), m.grid.georef().origin_x), (9, 178.0));
        let east = tile(5, 5, -179.0, 1.0, px, |_, _| 1.0);
        let m = mosaic(vec![w.clone(), east], &opts()).unwrap();
        assert_eq!((m.grid.width(), m.grid.georef().origin_x), (9, -180.0));
        // Projected tiles are never wrapped; across 180° and 0° is refused.
        let projected = |t: &HeightGrid| {
            let mut t = t.clone();
            let g = GeoRef {
                crs: Crs::Epsg(32660),
                ..t.georef().clone()
            };
            t.set_georef(g);
            t
        };
        let err = mosaic(vec![projected(&e), projected(&w)], &opts()).unwrap_err();
        assert!(matches!(err, MosaicError::TooSparse { .. }), "{err}");
        let zero = tile(5, 5, 0.0, 1.0, px, |_, _| 1.0);
        let err = mosaic(vec![e, w, zero], &opts()).unwrap_err();
        assert!(matches!(err, MosaicError::TooSparse { .. }), "{err}");
    }

    #[test]
    fn incompatible_tiles_are_refused() {
        let a = tile(3, 3, 10.0, 1.0, 1.0 / 1200.0, |_, _| 0.0);
        let fine = tile(3, 3, 10.0, 1.0, 1.0 / 3600.0, |_, _| 0.0);
        let err = mosaic(vec![a.clone(), fine], &opts()).unwrap_err();
        assert_eq!(
            err.to_string(),
            "tiles of different resolution: 1/1200° vs 1/3600° (tile 0 vs tile 1), resampling is not supported"
        );

        let mut utm = a.clone();
        let mut g = utm.georef().clone();
        g.crs = Crs::Epsg(32631);
        utm.set_georef(g);
        let err = mosaic(vec![a.clone(), utm], &opts()).unwrap_err();
        assert!(
            err.to_string().contains("EPSG:4326") && err.to_string().contains("EPSG:32631"),
            "{err}"
        );

        let half = tile(3, 3, 10.0 + 0.5 / 1200.0, 1.0, 1.0 / 1200.0, |_, _| 0.0);
        let err = mosaic(vec![a.clone(), half], &opts()).unwrap_err();
        assert!(
            matches!(err, MosaicError::NotAligned { index: 1, offset_cols, .. } if (offset_cols - 0.5).abs() < 1e-9),
            "{err}"
        );

        let png = HeightGrid::new(3, 3, vec![0.0; 9], GeoRef::unreferenced(30.0)).unwrap();
        let err = mosaic(vec![a.clone(), png], &opts()).unwrap_err();
        assert_eq!(err, MosaicError::Unreferenced { index: 1 });

        let mut flipped = a.clone();
        let mut g = flipped.georef().clone();
        g.pixel_y = -g.pixel_y;
        flipped.set_georef(g);
        let err = mosaic(vec![a, flipped], &opts()).unwrap_err();
        assert!(
            matches!(err, MosaicError::OrientationMismatch { index: 1, .. }),
            "{err}"
        );
    }

    #[test]
    fn area_and_point_tiles_combine() {
        let px = 0.5;
        let a = tile(3, 3, 0.0, 1.0, px, surface(0.0, 1.0, px));
        let mut b = tile(3, 3, 1.0, 1.0, px, surface(1.0, 1.0, px));
        // Same lattice, written with the corner convention.
        let mut g = b.georef().clone();
        g.pixel_is = PixelIs::Area;
        g.origin_x -= 0.5 * px;
        g.origin_y += 0.5 * px;
        b.set_georef(g);
        let m = mosaic(vec![b, a], &opts()).unwrap();
        assert_eq!((m.grid.width(), m.grid.height()), (5, 3));
        assert_eq!(m.seams.max_abs_diff_m, 0.0);
        // Output convention: tile 0's (Area); its first sample is still at (0, 1).
        assert_eq!(m.grid.georef().pixel_is, PixelIs::Area);
        assert_eq!(m.grid.georef().sample_xy(0.0, 0.0), (0.0, 1.0));
    }

    #[test]
    fn overlapping_tiles_are_compared_everywhere() {
        let a = tile(4, 4, 0.0, 4.0, 1.0, |_, _| 1.0);
        let b = tile(4, 4, 2.0, 2.0, 1.0, |_, _| 3.0);
        let m = mosaic(vec![a, b], &opts()).unwrap();
        assert_eq!((m.grid.width(), m.grid.height()), (6, 6));
        assert_eq!(m.seams.overlap_samples, 4);
        assert_eq!(m.grid.get(2, 2), 2.0);
        assert_eq!(m.hole_samples, 8);
    }

    #[test]
    fn union_area() {
        let p = |col, row, width, height| TilePlacement {
            index: 0,
            col,
            row,
            width,
            height,
        };
        assert_eq!(covered_samples(&[p(0, 0, 3, 3), p(2, 0, 3, 3)]), 15);
        assert_eq!(covered_samples(&[p(0, 0, 3, 3), p(0, 0, 3, 3)]), 9);
        assert_eq!(covered_samples(&[p(0, 0, 2, 2), p(5, 5, 2, 2)]), 8);
        assert_eq!(covered_samples(&[p(0, 0, 10, 1), p(4, 0, 1, 10)]), 19);
    }
}
