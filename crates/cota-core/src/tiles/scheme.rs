//! The geographic tiling scheme (EPSG:4326, TMS) and its lattice, and the
//! error schedule per zoom.
//!
//! References: the quantized-mesh-1.0 specification (CesiumGS/quantized-mesh,
//! "Tiling Scheme and Coordinate System": two root tiles, TMS numbering, `y`
//! counted from the south) and Cesium's estimate of a level's geometric error
//! for a heightmap of 65 samples, which cesium-terrain-builder uses as its
//! error per level.
//!
//! # The lattice
//! At the maximum zoom `Z` a tile spans `S` lattice cells (`S` =
//! [`GeographicScheme::tile_cells`], a power of two), so 180° of latitude or
//! longitude hold `T_0 = S·2^Z` cells of `180 / T_0` degrees. Global lattice
//! coordinates count columns east from 180° W and rows south from 90° N. A
//! tile at zoom `z` is then the square of side `T_z = S·2^(Z−z)` cells whose
//! north-west corner is `(x·T_z, (2^z − 1 − y)·T_z)`: a square of the bitree
//! hierarchy ([`crate::hierarchy`]) over that lattice, at every zoom. That is
//! what lets one hierarchy serve every tile of every zoom.
//!
//! # Across the antimeridian
//! When the data cross ±180°, the lattice's columns are counted from 0°
//! instead ([`GeographicScheme::from_greenwich`]): the footprint is then
//! contiguous on the lattice, which still spans the world (360° = 2·`T_0`
//! columns), so the window, its bitree, the coarse levels and the zero band
//! are built exactly as for any footprint; the prime meridian becomes the
//! lattice's edge, and the antimeridian a border between tiles like any
//! other (shared vertices, no T-junction). The shift is half the world, so a
//! lattice tile's column and its address differ by `2^z` modulo `2^(z+1)`
//! ([`GeographicScheme::address`], its own inverse): every zoom's tile is
//! still a square of the same tiling, with the same diagonals from zoom 1 on
//! (`2^z` is even); only the two root tiles swap their diagonals. Vertices
//! are placed on WGS 84 by longitude, which is periodic, so the as-drawn
//! error model ([`super::drawn`]) is unchanged. Sources are read at the
//! longitude of their own convention (`±360°`, see [`super::sources`]).

/// Largest maximum zoom accepted: lattice coordinates stay below 2^31.
pub const MAX_ZOOM: u8 = 24;

/// WGS 84 semi-major axis, metres (the radius in Cesium's error estimate).
pub const WGS84_A_M: f64 = 6_378_137.0;

/// A tile: zoom `z`, column `x` from 180° W, row `y` from 90° S (TMS).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TileId {
    /// Zoom level (0: the two root tiles).
    pub z: u8,
    /// Column, west to east: `0 .. 2^(z+1)`.
    pub x: u32,
    /// Row, south to north: `0 .. 2^z`.
    pub y: u32,
}

impl std::fmt::Display for TileId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}/{}", self.z, self.x, self.y)
    }
}

/// The geographic (EPSG:4326) TMS tiling with its lattice at the maximum zoom.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GeographicScheme {
    /// The maximum zoom `Z`, whose tiles span [`GeographicScheme::tile_cells`] cells.
    pub max_zoom: u8,
    /// Lattice cells across a tile at the maximum zoom (`S`, a power of two).
    pub tile_cells: u32,
    /// Columns counted east from 0° rather than from 180° W: chosen when the
    /// data cross the antimeridian (see the module docs). Lattice tiles are
    /// then addressed through [`GeographicScheme::address`].
    pub from_greenwich: bool,
}

impl GeographicScheme {
    /// `T_0`: lattice cells across a root tile (180°).
    pub fn root_cells(&self) -> u64 {
        u64::from(self.tile_cells) << self.max_zoom
    }

    /// `T_z`: lattice cells across a tile at zoom `z ≤ Z`.
    pub fn cells_at(&self, z: u8) -> u64 {
        u64::from(self.tile_cells) << (self.max_zoom - z)
    }

    /// The lattice spacing in degrees.
    pub fn cell_deg(&self) -> f64 {
        180.0 / self.root_cells() as f64
    }

    /// Tiles across the world at zoom `z` (east-west, north-south).
    pub fn tiles_at(z: u8) -> [u32; 2] {
        [2u32 << z, 1u32 << z]
    }

    /// The longitude of lattice column 0, degrees: -180, or 0 with
    /// [`GeographicScheme::from_greenwich`].
    pub fn west_deg(&self) -> f64 {
        if self.from_greenwich {
            0.0
        } else {
            -180.0
        }
    }

    /// The address (Cesium's column) of lattice tile `t`, and the lattice
    /// tile of address `t`: the same map both ways (half the world's
    /// columns added modulo the world's with
    /// [`GeographicScheme::from_greenwich`], else none).
    pub fn address(&self, t: TileId) -> TileId {
        if self.from_greenwich {
            TileId {
                x: t.x ^ (1u32 << t.z),
                ..t
            }
        } else {
            t
        }
    }

    /// A longitude in the lattice's own range (from [`GeographicScheme::west_deg`]
    /// on, 360° wide): `lon` itself unless
    /// [`GeographicScheme::from_greenwich`], then `lon` modulo 360.
    pub fn lattice_lon(&self, lon: f64) -> f64 {
        if self.from_greenwich {
            lon.rem_euclid(360.0)
        } else {
            lon
        }
    }

    /// Degrees added to the longitudes of a geographic source whose grid
    /// starts at longitude `west` to bring them into the lattice's range:
    /// 0, or a multiple of 360 with [`GeographicScheme::from_greenwich`]
    /// (a source from -180° on is read from 180° on).
    pub fn lon_offset(&self, west: f64) -> f64 {
        if self.from_greenwich {
            360.0 * ((west.rem_euclid(360.0) - west) / 360.0).round()
        } else {
            0.0
        }
    }

    /// Global lattice column of longitude `lon` (in the lattice's range, see
    /// [`GeographicScheme::lattice_lon`]).
    pub fn col_of(&self, lon: f64) -> f64 {
        (lon - self.west_deg()) / self.cell_deg()
    }

    /// Global lattice column and row of lattice tile `t`'s north-west corner.
    pub fn tile_origin(&self, t: TileId) -> [u64; 2] {
        let s = self.cells_at(t.z);
        let row = u64::from((1u32 << t.z) - 1 - t.y);
        [u64::from(t.x) * s, row * s]
    }

    /// The rectangle of the tile of address `t` in degrees: `[west, south,
    /// east, north]`.
    pub fn tile_rect_deg(&self, t: TileId) -> [f64; 4] {
        let size = 180.0 / f64::from(1u32 << t.z);
        let west = -180.0 + f64::from(t.x) * size;
        let south = -90.0 + f64::from(t.y) * size;
        [west, south, west + size, south + size]
    }

    /// Longitude of a global lattice column, degrees (beyond 180° for the
    /// eastern half of a lattice [`GeographicScheme::from_greenwich`]).
    pub fn lon_of(&self, col: f64) -> f64 {
        self.west_deg() + col * self.cell_deg()
    }

    /// Latitude of a global lattice row, degrees.
    pub fn lat_of(&self, row: f64) -> f64 {
        90.0 - row * self.cell_deg()
    }

    /// The smallest maximum zoom whose lattice is at least as fine as
    /// `source_cell_deg` (the source's finer pixel side), so no resolution
    /// is lost: for SRTM 3″ and `S = 64`, zoom 12 (2.47″).
    pub fn max_zoom_for(source_cell_deg: f64, tile_cells: u32) -> u8 {
        let mut z = 0u8;
        while z < MAX_ZOOM
            && 180.0 / ((u64::from(tile_cells) << z) as f64) > source_cell_deg * (1.0 + 1e-9)
        {
            z += 1;
        }
        z
    }
}

/// How the maximum error of a tile depends on its zoom.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum ErrorSchedule {
    /// cesium-terrain-builder's (and CesiumJS's estimate for a 65-sample
    /// heightmap with two root tiles): `e_z = a·2π·0.25·q / (65·2) / 2^z`
    /// metres, `a` the WGS 84 radius and `q` the factor (75.3 m at zoom 10,
    /// 18.8 m at 12, 4.70 m at 14 for `q = 1`). The default, with `q = 1`.
    Cesium {
        /// The factor `q` (> 0).
        factor: f64,
    },
    /// `max_error_m` at the maximum zoom, doubled at each zoom above it.
    AtMaxZoom {
        /// The bound at the maximum zoom, metres (> 0).
        max_error_m: f64,
    },
}

impl ErrorSchedule {
    /// The default: [`ErrorSchedule::Cesium`] with factor 1.
    pub const DEFAULT: ErrorSchedule = ErrorSchedule::Cesium { factor: 1.0 };

    /// The bound of a tile at zoom `z` when the maximum zoom is `max_zoom`, metres.
    pub fn max_error_m(&self, z: u8, max_zoom: u8) -> f64 {
        match *self {
            ErrorSchedule::Cesium { factor } => {
                WGS84_A_M * 2.0 * std::f64::consts::PI * 0.25 * factor
                    / (65.0 * 2.0)
                    / f64::from(1u32 << z)
            }
            ErrorSchedule::AtMaxZoom { max_error_m } => {
                max_error_m * f64::from(1u32 << (max_zoom.saturating_sub(z)))
            }
        }
    }

    /// The schedule's own parameter is positive and finite.
    pub fn is_valid(&self) -> bool {
        let p = match *self {
            ErrorSchedule::Cesium { factor } => factor,
            ErrorSchedule::AtMaxZoom { max_error_m } => max_error_m,
        };
        p.is_finite() && p > 0.0
    }
}

impl Default for ErrorSchedule {
    fn default() -> Self {
        Self::DEFAULT
    }
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn cesium_schedule_matches_the_issue() {
        let s = ErrorSchedule::DEFAULT;
        assert!((s.max_error_m(10, 12) - 75.3).abs() < 0.05);
        assert!((s.max_error_m(12, 12) - 18.8).abs() < 0.05);
        assert!((s.max_error_m(14, 14) - 4.70).abs() < 0.005);
        let e = ErrorSchedule::AtMaxZoom { max_error_m: 2.0 };
        assert_eq!(e.max_error_m(12, 12), 2.0);
        assert_eq!(e.max_error_m(10, 12), 8.0);
    }

    #[test]
    fn srtm_3_arc_seconds_gives_zoom_12() {
        assert_eq!(GeographicScheme::max_zoom_for(1.0 / 1200.0, 64), 12);
        assert_eq!(GeographicScheme::max_zoom_for(1.0 / 3600.0, 64), 14);
        let s = GeographicScheme {
            max_zoom: 12,
            tile_cells: 64,
            from_greenwich: false,
        };
        assert!((s.cell_deg() * 3600.0 - 2.4719).abs() < 1e-3);
    }

    #[test]
    fn tiles_are_squares_of_the_lattice() {
        let s = GeographicScheme {
            max_zoom: 3,
            tile_cells: 4,
            from_greenwich: false,
        };
        assert_eq!(s.root_cells(), 32);
        let t = TileId { z: 1, x: 2, y: 1 };
        assert_eq!(s.tile_origin(t), [32, 0]);
        assert_eq!(s.tile_rect_deg(t), [0.0, 0.0, 90.0, 90.0]);
        assert_eq!(s.lon_of(32.0), 0.0);
        assert_eq!(s.lat_of(0.0), 90.0);
        let t0 = TileId { z: 0, x: 0, y: 0 };
        assert_eq!(s.tile_origin(t0), [0, 0]);
        assert_eq!(s.cells_at(0), 32);
    }

    #[test]
    fn greenwich_columns_wrap_at_the_antimeridian() {
        let s = GeographicScheme {
            max_zoom: 3,
            tile_cells: 4,
            from_greenwich: true,
        };
        assert_eq!(s.lon_of(32.0), 180.0);
        assert_eq!(s.col_of(s.lattice_lon(-179.0)), 181.0 / s.cell_deg());
        // Lattice tile 3 of zoom 2 (90..180°) is Cesium's 7, and back.
        let t = TileId { z: 2, x: 3, y: 1 };
        assert_eq!(s.address(t), TileId { z: 2, x: 7, y: 1 });
        assert_eq!(s.address(s.address(t)), t);
        assert_eq!(s.tile_rect_deg(s.address(t))[2], 180.0);
        assert_eq!(s.address(TileId { z: 2, x: 4, y: 1 }).x, 0);
    }
}
