//! Shaded relief: a picture of a geographic DEM that a person reads at a
//! glance, cut into the tiles of the geographic tiling scheme (EPSG:4326,
//! TMS: `2^(z+1) × 2^z` tiles at zoom `z`, row 0 in the south), the same
//! scheme as the quantized-mesh tiles, so the pictures drape the terrain.
//!
//! Each pixel is the DEM's height at its centre (bilinear, from a box-filtered
//! level whose cell is about the pixel's size, so coarse tiles do not alias),
//! coloured by a hypsometric tint and darkened or lit by a hillshade:
//!
//! * **Hillshade.** The slope by Horn's 3×3 weights (Horn 1981, "Hill
//!   shading and the reflectance map", Proc. IEEE 69(1)) over the
//!   neighbouring pixels in metres on the ground, lit by a distant light from
//!   [`ReliefOptions::azimuth_deg`] at [`ReliefOptions::altitude_deg`];
//!   `shade = max(0, n·l) / sin(altitude)` (1 on flat ground). Pixels larger
//!   than the DEM's cells see gentler slopes: heights are exaggerated by
//!   `sqrt(pixel / cell)` there so relief still shows when zoomed out.
//! * **Tint.** Heights from the data's lowest to its highest, green through
//!   tan and brown to white; heights at or below 0 m a pale blue (sea).
//! * Pixels outside the data are transparent.

use std::sync::Arc;

use crate::grid::metres_per_degree;
use crate::HeightGrid;

/// How relief tiles are drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct ReliefOptions {
    /// Pixels along a tile's side. Default: 256.
    pub tile_px: u32,
    /// Where the light comes from, degrees clockwise from north. Default: 315 (north-west).
    pub azimuth_deg: f64,
    /// The light's height above the horizon, degrees. Default: 45.
    pub altitude_deg: f64,
    /// Brightness of ground facing away from the light (0 to 1). Default: 0.35.
    pub ambient: f64,
    /// Heights multiplied by this before shading. Default: 1.
    pub exaggeration: f64,
}

impl ReliefOptions {
    /// The defaults.
    pub const DEFAULT: ReliefOptions = ReliefOptions {
        tile_px: 256,
        azimuth_deg: 315.0,
        altitude_deg: 45.0,
        ambient: 0.35,
        exaggeration: 1.0,
    };

    /// Sets [`ReliefOptions::tile_px`].
    pub const fn with_tile_px(mut self, px: u32) -> Self {
        self.tile_px = px;
        self
    }
}

impl Default for ReliefOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Why relief cannot be drawn from a grid.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ReliefError {
    /// The grid is not in longitude and latitude.
    #[error("expected a geographic grid (longitude, latitude), found CRS {crs}")]
    NotGeographic {
        /// The grid's CRS.
        crs: String,
    },
    /// Options out of range.
    #[error("expected {expected}, found {found}")]
    BadOptions {
        /// What is allowed.
        expected: &'static str,
        /// What was given.
        found: String,
    },
}

/// The heights of a level: the grid itself (level 0, shared), or a
/// box-filtered copy.
#[derive(Debug)]
enum Heights {
    Grid(Arc<HeightGrid>),
    Own(Vec<f32>),
}

/// One box-filtered level: `2^k` level-0 cells per cell.
#[derive(Debug)]
struct Level {
    width: usize,
    height: usize,
    z: Heights,
    /// Level-0 cells per cell.
    scale: f64,
}

impl Level {
    fn heights(&self) -> &[f32] {
        match &self.z {
            Heights::Grid(g) => g.heights(),
            Heights::Own(v) => v,
        }
    }

    /// Bilinear height at level-0 coordinates (`col`, `row`), clamped to the grid.
    fn at(&self, col: f64, row: f64) -> f64 {
        let off = (self.scale - 1.0) / 2.0;
        let c = ((col - off) / self.scale).clamp(0.0, (self.width - 1) as f64);
        let r = ((row - off) / self.scale).clamp(0.0, (self.height - 1) as f64);
        let (c0, r0) = (c.floor() as usize, r.floor() as usize);
        let (c1, r1) = ((c0 + 1).min(self.width - 1), (r0 + 1).min(self.height - 1));
        let (fc, fr) = (c - c0 as f64, r - r0 as f64);
        let h = self.heights();
        let z = |c: usize, r: usize| f64::from(h[r * self.width + c]);
        let top = z(c0, r0) * (1.0 - fc) + z(c1, r0) * fc;
        let bottom = z(c0, r1) * (1.0 - fc) + z(c1, r1) * fc;
        top * (1.0 - fr) + bottom * fr
    }

    /// The next coarser level (2×2 boxes; a last odd row or column alone).
    fn halve(&self) -> Level {
        let (w, h) = (self.width.div_ceil(2), self.height.div_ceil(2));
        let src = self.heights();
        let mut z = Vec::with_capacity(w * h);
        for r in 0..h {
            for c in 0..w {
                let (mut sum, mut n) = (0.0f64, 0.0f64);
                for rr in (2 * r)..(2 * r + 2).min(self.height) {
                    for cc in (2 * c)..(2 * c + 2).min(self.width) {
                        sum += f64::from(src[rr * self.width + cc]);
                        n += 1.0;
                    }
                }
                z.push((sum / n) as f32);
            }
        }
        Level {
            width: w,
            height: h,
            z: Heights::Own(z),
            scale: self.scale * 2.0,
        }
    }
}

/// A DEM prepared for drawing relief tiles (see the module docs).
#[derive(Debug)]
pub struct Relief {
    levels: Vec<Level>,
    /// Longitude and latitude of sample (0, 0), degrees.
    origin: (f64, f64),
    /// Degrees per column (east) and per row (negative: rows go south).
    step: (f64, f64),
    /// Lowest and highest height, metres.
    range: (f64, f64),
    opts: ReliefOptions,
}

/// Largest zoom [`Relief::max_zoom`] gives.
pub const MAX_RELIEF_ZOOM: u8 = 20;

impl Relief {
    /// Prepares `grid` (no voids expected: they are drawn as their stored
    /// value; shared, not copied) and its box-filtered levels down to a few
    /// cells.
    ///
    /// # Errors
    /// [`ReliefError::NotGeographic`] unless the grid is in longitude and
    /// latitude; [`ReliefError::BadOptions`] for a tile size outside 16..=1024
    /// or an altitude outside (0, 90].
    ///
    /// # Runtime
    /// `O(n)` for `n` samples; the levels take a third of the grid's memory.
    pub fn new(grid: Arc<HeightGrid>, opts: &ReliefOptions) -> Result<Self, ReliefError> {
        let g = grid.georef();
        if !(g.known && g.crs.is_geographic()) {
            return Err(ReliefError::NotGeographic {
                crs: g.crs.to_string(),
            });
        }
        if !(16..=1024).contains(&opts.tile_px) {
            return Err(ReliefError::BadOptions {
                expected: "a tile of 16 to 1024 pixels",
                found: opts.tile_px.to_string(),
            });
        }
        if !(opts.altitude_deg > 0.0 && opts.altitude_deg <= 90.0) {
            return Err(ReliefError::BadOptions {
                expected: "a light altitude above 0 and at most 90 degrees",
                found: opts.altitude_deg.to_string(),
            });
        }
        let (lon0, lat0) = g.sample_xy(0.0, 0.0);
        let (lon1, lat1) = g.sample_xy(1.0, 1.0);
        let (lo, hi) = grid.valid_range().unwrap_or((0.0, 0.0));
        let mut levels = vec![Level {
            width: grid.width(),
            height: grid.height(),
            z: Heights::Grid(grid.clone()),
            scale: 1.0,
        }];
        while let Some(last) = levels.last().filter(|l| l.width.max(l.height) > 4) {
            let next = last.halve();
            levels.push(next);
        }
        Ok(Relief {
            levels,
            origin: (lon0, lat0),
            step: (lon1 - lon0, lat1 - lat0),
            range: (f64::from(lo), f64::from(hi)),
            opts: *opts,
        })
    }

    /// West, south, east and north of the samples, degrees (west and east
    /// past ±180° for a grid laid out across the antimeridian).
    pub fn bounds_deg(&self) -> [f64; 4] {
        let l = &self.levels[0];
        let (w, n) = self.origin;
        let e = w + self.step.0 * (l.width - 1) as f64;
        let s = n + self.step.1 * (l.height - 1) as f64;
        [w.min(e), s.min(n), w.max(e), s.max(n)]
    }

    /// The pixels along a tile's side.
    pub fn tile_px(&self) -> u32 {
        self.opts.tile_px
    }

    /// The first zoom whose pixels are no larger than the DEM's cells (at
    /// most [`MAX_RELIEF_ZOOM`]).
    pub fn max_zoom(&self) -> u8 {
        let cell = self.step.0.abs().max(1e-12);
        let mut z = 0u8;
        while z < MAX_RELIEF_ZOOM && tile_deg(z) / f64::from(self.opts.tile_px) > cell {
            z += 1;
        }
        z
    }

    /// The tiles `(x, y)` of zoom `z` (TMS) that hold some of the data. A
    /// grid that runs past ±180° (a mosaic across the antimeridian, laid out
    /// from 179° to 181° say) has its tiles on both sides of it.
    pub fn tiles_at(&self, z: u8) -> impl Iterator<Item = (u32, u32)> {
        let [w, s, e, n] = self.bounds_deg();
        let d = tile_deg(z);
        let cols = 2u64 << z;
        let rows = 1u64 << z;
        let span = |lo: f64, hi: f64, origin: f64, count: u64| {
            let a = ((lo - origin) / d).floor().clamp(0.0, (count - 1) as f64) as u32;
            let b = ((hi - origin) / d).floor().clamp(0.0, (count - 1) as f64) as u32;
            a..=b
        };
        let ys = span(s, n, -90.0, rows);
        let xs: Vec<u32> = if w >= -180.0 && e <= 180.0 {
            span(w, e, -180.0, cols).collect()
        } else {
            // Whole columns from the west edge's to the east edge's, each
            // taken modulo the world's columns, once.
            let a = ((w + 180.0) / d).floor() as i64;
            let b = ((e + 180.0) / d).floor() as i64;
            let mut xs: Vec<u32> = (a..=b)
                .take(cols as usize)
                .map(|x| x.rem_euclid(cols as i64) as u32)
                .collect();
            xs.sort_unstable();
            xs.dedup();
            xs
        };
        xs.into_iter()
            .flat_map(move |x| ys.clone().map(move |y| (x, y)))
    }

    /// The whole turns (−360°, 0 or 360°) that move tile `z/x/y` (TMS) onto
    /// the data, if any: 0 unless the grid runs past ±180°.
    fn turn_onto_data(&self, z: u8, x: u32, y: u32) -> Option<f64> {
        let [w, s, e, n] = self.bounds_deg();
        let [tw, ts, te, tn] = tile_bounds(z, x, y);
        if ts > n || tn < s {
            return None;
        }
        [0.0, 360.0, -360.0]
            .into_iter()
            .find(|t| tw + t <= e && te + t >= w)
    }

    /// True when tile `z/x/y` (TMS) holds some of the data.
    pub fn overlaps(&self, z: u8, x: u32, y: u32) -> bool {
        self.turn_onto_data(z, x, y).is_some()
    }

    /// The RGBA pixels of tile `z/x/y` (TMS), rows from the north, or `None`
    /// when the tile holds none of the data.
    pub fn tile_rgba(&self, z: u8, x: u32, y: u32) -> Option<Vec<u8>> {
        if z > 30 {
            return None;
        }
        let turn = self.turn_onto_data(z, x, y)?;
        let px = self.opts.tile_px as usize;
        let [west, _, _, north] = tile_bounds(z, x, y);
        let west = west + turn;
        let d = tile_deg(z) / px as f64;
        let side = px + 2;
        let h = self.heights_around(west, north, d, side);
        let lat_mid = north - tile_deg(z) / 2.0;
        let [mx, my] = metres_per_degree(lat_mid);
        let cell_m = self.step.0.abs() * mx;
        let zf = self.opts.exaggeration * (d * mx / cell_m).max(1.0).sqrt();
        let shade = Shader::new(&self.opts, d * mx, d * my, zf);
        let mut out = vec![0u8; px * px * 4];
        for j in 0..px {
            let lat = north - (j as f64 + 0.5) * d;
            for i in 0..px {
                let lon = west + (i as f64 + 0.5) * d;
                if !self.inside(lon, lat) {
                    continue;
                }
                let at = |di: usize, dj: usize| h[(j + dj) * side + i + di];
                let win = [
                    at(0, 0),
                    at(1, 0),
                    at(2, 0),
                    at(0, 1),
                    at(1, 1),
                    at(2, 1),
                    at(0, 2),
                    at(1, 2),
                    at(2, 2),
                ];
                let rgb = self.colour(win[4], shade.shade(&win));
                let o = (j * px + i) * 4;
                out[o..o + 3].copy_from_slice(&rgb);
                out[o + 3] = 255;
            }
        }
        Some(out)
    }

    /// The hillshade of [`Relief::tile_rgba`] at the 3×3 heights `win`
    /// (rows from the north) spaced `dx_m`, `dy_m` apart: 1 on flat ground.
    pub fn hillshade(&self, win: &[f64; 9], dx_m: f64, dy_m: f64) -> f64 {
        Shader::new(&self.opts, dx_m, dy_m, self.opts.exaggeration).shade(win)
    }

    /// Heights at the centres of `side`² pixels of `d` degrees, the first
    /// one pixel west and north of (`west`, `north`): a tile's pixels with a
    /// one-pixel border, from the level whose cells are about a pixel.
    fn heights_around(&self, west: f64, north: f64, d: f64, side: usize) -> Vec<f64> {
        let level = self.level_for(d);
        let mut h = vec![0.0f64; side * side];
        for j in 0..side {
            let lat = north - (j as f64 - 0.5) * d;
            for i in 0..side {
                let lon = west + (i as f64 - 0.5) * d;
                let (c, r) = self.col_row(lon, lat);
                h[j * side + i] = level.at(c, r);
            }
        }
        h
    }

    /// The level whose cells are about `pixel_deg` wide (not larger).
    fn level_for(&self, pixel_deg: f64) -> &Level {
        let ratio = pixel_deg / self.step.0.abs().max(1e-12);
        let k = if ratio >= 2.0 {
            ratio.log2().floor() as usize
        } else {
            0
        };
        &self.levels[k.min(self.levels.len() - 1)]
    }

    /// Level-0 column and row of a longitude and latitude.
    fn col_row(&self, lon: f64, lat: f64) -> (f64, f64) {
        (
            (lon - self.origin.0) / self.step.0,
            (lat - self.origin.1) / self.step.1,
        )
    }

    /// True within the samples' extent.
    fn inside(&self, lon: f64, lat: f64) -> bool {
        let (c, r) = self.col_row(lon, lat);
        let l = &self.levels[0];
        let eps = 1e-9;
        c >= -eps
            && r >= -eps
            && c <= (l.width - 1) as f64 + eps
            && r <= (l.height - 1) as f64 + eps
    }

    /// Tint of height `h` scaled by `shade`.
    fn colour(&self, h: f64, shade: f64) -> [u8; 3] {
        let tint = if h <= 0.0 && self.range.0 <= 0.0 {
            SEA
        } else {
            let lo = self.range.0.max(0.0);
            let t = ((h - lo) / (self.range.1 - lo).max(1.0)).clamp(0.0, 1.0);
            ramp(t)
        };
        let a = self.opts.ambient;
        let k = (a + (1.0 - a) * shade).clamp(0.0, 1.25);
        tint.map(|c| (c * k).round().clamp(0.0, 255.0) as u8)
    }
}

/// Horn's slope and the light.
struct Shader {
    light: [f64; 3],
    dx_m: f64,
    dy_m: f64,
    zf: f64,
}

impl Shader {
    fn new(o: &ReliefOptions, dx_m: f64, dy_m: f64, zf: f64) -> Self {
        let (az, alt) = (o.azimuth_deg.to_radians(), o.altitude_deg.to_radians());
        Shader {
            light: [az.sin() * alt.cos(), az.cos() * alt.cos(), alt.sin()],
            dx_m,
            dy_m,
            zf,
        }
    }

    /// `max(0, n·l) / sin(altitude)` at the centre of `w` (rows from the north).
    fn shade(&self, w: &[f64; 9]) -> f64 {
        let east = (w[2] + 2.0 * w[5] + w[8]) - (w[0] + 2.0 * w[3] + w[6]);
        let north = (w[0] + 2.0 * w[1] + w[2]) - (w[6] + 2.0 * w[7] + w[8]);
        let gx = self.zf * east / (8.0 * self.dx_m);
        let gy = self.zf * north / (8.0 * self.dy_m);
        let n = [-gx, -gy, 1.0];
        let len = (gx * gx + gy * gy + 1.0).sqrt();
        let dot = (n[0] * self.light[0] + n[1] * self.light[1] + n[2] * self.light[2]) / len;
        dot.max(0.0) / self.light[2]
    }
}

/// Pale blue for heights at or below sea level.
const SEA: [f64; 3] = [158.0, 188.0, 204.0];

/// The hypsometric ramp at `t` in [0, 1]: green, tan, brown, grey, white.
fn ramp(t: f64) -> [f64; 3] {
    const STOPS: [(f64, [f64; 3]); 6] = [
        (0.0, [88.0, 132.0, 84.0]),
        (0.2, [142.0, 168.0, 98.0]),
        (0.45, [214.0, 198.0, 140.0]),
        (0.7, [168.0, 128.0, 92.0]),
        (0.9, [204.0, 196.0, 188.0]),
        (1.0, [252.0, 252.0, 252.0]),
    ];
    for k in 1..STOPS.len() {
        let (t1, c1) = STOPS[k];
        if t <= t1 {
            let (t0, c0) = STOPS[k - 1];
            let f = (t - t0) / (t1 - t0);
            return [0, 1, 2].map(|i| c0[i] + (c1[i] - c0[i]) * f);
        }
    }
    STOPS[STOPS.len() - 1].1
}

/// Degrees a tile of zoom `z` spans (both ways).
pub fn tile_deg(z: u8) -> f64 {
    180.0 / f64::from(1u32 << z.min(30))
}

/// West, south, east and north of tile `z/x/y` (TMS), degrees.
pub fn tile_bounds(z: u8, x: u32, y: u32) -> [f64; 4] {
    let d = tile_deg(z);
    let w = -180.0 + f64::from(x) * d;
    let s = -90.0 + f64::from(y) * d;
    [w, s, w + d, s + d]
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::{Crs, GeoRef, PixelIs};

    /// A cone 30 km high (slopes of about 0.5) on a 1° × 1° grid of `n`²
    /// samples at (10°E, 0°).
    fn cone(n: usize) -> HeightGrid {
        let mut z = Vec::with_capacity(n * n);
        let c = (n - 1) as f64 / 2.0;
        for r in 0..n {
            for k in 0..n {
                let d = ((k as f64 - c).powi(2) + (r as f64 - c).powi(2)).sqrt() / c;
                z.push((30_000.0 * (1.0 - d).max(0.0)) as f32 + 10.0);
            }
        }
        let step = 1.0 / (n - 1) as f64;
        let g = GeoRef {
            crs: Crs::Epsg(4326),
            origin_x: 10.0,
            origin_y: 1.0,
            pixel_x: step,
            pixel_y: -step,
            pixel_is: PixelIs::Point,
            known: true,
        };
        HeightGrid::new(n, n, z, g).unwrap_or_else(|e| panic!("{e}"))
    }

    fn lum(p: &[u8]) -> f64 {
        f64::from(p[0]) + f64::from(p[1]) + f64::from(p[2])
    }

    #[test]
    fn the_lit_side_is_brighter_and_outside_is_transparent() {
        let r = Relief::new(Arc::new(cone(257)), &ReliefOptions::DEFAULT)
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(r.bounds_deg(), [10.0, 0.0, 11.0, 1.0]);
        let z = r.max_zoom();
        assert_eq!(
            z, 8,
            "1/256 degree cells need 2^(z+1) x 256 px over 360 degrees"
        );
        // Zoom 7: one tile of 1.40625 degrees holds the whole cone.
        let tiles: Vec<_> = r.tiles_at(7).collect();
        assert_eq!(tiles, vec![(135, 64)]);
        let px = r.tile_rgba(7, 135, 64).unwrap_or_else(|| panic!("no tile"));
        let d = tile_deg(7) / 256.0;
        let at = |lon: f64, lat: f64| {
            let [w, _, _, n] = tile_bounds(7, 135, 64);
            let (i, j) = (((lon - w) / d) as usize, ((n - lat) / d) as usize);
            &px[(j * 256 + i) * 4..(j * 256 + i) * 4 + 4]
        };
        let (nw, se) = (at(10.3, 0.7), at(10.7, 0.3));
        assert_eq!((nw[3], se[3]), (255, 255));
        assert!(lum(nw) > lum(se) + 60.0, "{nw:?} vs {se:?}");
        assert_eq!(at(9.9, 0.5)[3], 0, "west of the data");
        assert_eq!(at(10.5, 1.2)[3], 0, "north of the data");
        assert!(r.tile_rgba(7, 0, 0).is_none());
        assert!(!r.overlaps(7, 134, 64) || r.tiles_at(7).any(|t| t == (134, 64)));
    }

    #[test]
    fn a_grid_across_the_antimeridian_has_tiles_on_both_sides() {
        // The cone laid out from 179.5 to 180.5 degrees, as a mosaic of an
        // E179 and a W180 tile is.
        let mut g = cone(129);
        let mut geo = g.georef().clone();
        geo.origin_x = 179.5;
        g.set_georef(geo);
        let r = Relief::new(Arc::new(g), &ReliefOptions::DEFAULT).unwrap_or_else(|e| panic!("{e}"));
        // Zoom 6: tiles of 2.8125 degrees; columns 0 (from -180) and 127
        // (to 180) each hold half the data.
        let tiles: Vec<_> = r.tiles_at(6).collect();
        assert_eq!(tiles, vec![(0, 32), (127, 32)]);
        let opaque = |x: u32| {
            let px = r
                .tile_rgba(6, x, 32)
                .unwrap_or_else(|| panic!("no tile {x}"));
            px.chunks(4).filter(|p| p[3] == 255).count()
        };
        let (east_of, west_of) = (opaque(0), opaque(127));
        assert!(east_of > 1000 && west_of > 1000, "{east_of} and {west_of}");
        assert!(
            east_of.abs_diff(west_of) * 10 < east_of,
            "{east_of} vs {west_of}"
        );
        assert!(r.overlaps(6, 0, 32) && r.overlaps(6, 127, 32));
        assert!(!r.overlaps(6, 1, 32) && !r.overlaps(6, 126, 32));
        assert!(r.tile_rgba(6, 64, 32).is_none());
    }

    #[test]
    fn flat_ground_shades_to_one_and_projected_grids_are_refused() {
        let r = Relief::new(Arc::new(cone(33)), &ReliefOptions::DEFAULT)
            .unwrap_or_else(|e| panic!("{e}"));
        assert!((r.hillshade(&[5.0; 9], 30.0, 30.0) - 1.0).abs() < 1e-12);
        let mut g = cone(33);
        let mut geo = g.georef().clone();
        geo.crs = Crs::Epsg(32719);
        g.set_georef(geo);
        assert!(matches!(
            Relief::new(Arc::new(g), &ReliefOptions::DEFAULT),
            Err(ReliefError::NotGeographic { .. })
        ));
    }
}
