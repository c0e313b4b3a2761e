//! A shard's partial maxima for the tiles coarser than the band zoom: what
//! a reducer ([`super::merge`]) needs to cut those tiles exactly as one
//! machine holding the whole lattice would.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §3.2 (the error of a bitree triangle is
//! the largest |plane − h| over its samples; a split point's error is the
//! maximum of its own and its children's) and paper
//! `001_49f2c365e8c41172.txt` (one hierarchy over a mosaic of tiles). A
//! maximum is associative, and a coarse triangle's plane needs only its
//! three corner heights (the band zoom's tile corners, [`BandCorners`], from
//! the plan step), so each shard computes, over the samples it owns (the
//! squares of its band-zoom tiles):
//!
//! 1. **own maxima** of every coarse split point (squares larger than the
//!    band zoom's) whose triangles meet those samples, each sample's value
//!    computed bit for bit as the whole lattice's build computes it (the
//!    window bitree's span formula up to the alignment zoom's squares, the
//!    [`super::cap`] formula above);
//! 2. **fine split points** (the band zoom's squares and below), whose
//!    errors depend only on its part: for each one that splits at some
//!    coarse zoom's threshold, which zooms it splits at (a bit per zoom),
//!    its height, and for the band squares' centres their 16-bit codes;
//! 3. on request, the **vertex normals** its part can compute (fine points,
//!    band-tile corners inside the window; beyond it a normal is straight
//!    up) and the
//!    coarse tiles' **water-mask samples** inside its squares.

use rustc_hash::FxHashMap as HashMap;

use rayon::prelude::*;

use super::cap::{own_rows, square_halves, square_tris, t_heights};
use super::cut::{is_wet, normal_at, water_sample, Prepared};
use super::drawn::{DrawnBound, ZoomRules};
use super::error::TilesError;
use super::lattice::{Lattice, SourcePart};
use super::plan::ZoomPlan;
use super::samples::Samples;
use super::scheme::TileId;
use super::source_error::triangle_error;
use crate::bitree::{clipped_span_error, round_up_f32};
use crate::hierarchy::{Pt, Tri};

/// A water-mask sample that a shard does not own.
pub const WATER_UNKNOWN: u8 = 1;

/// The heights at the band zoom's tile corners over the window (every
/// `cells`-th lattice column and row), row-major; NaN where not yet known.
#[derive(Debug, Clone, PartialEq)]
pub struct BandCorners {
    /// The band zoom's tile side, lattice cells.
    pub cells: u64,
    /// The window, `[x0, y0, x1, y1]` inclusive.
    pub window: [u64; 4],
    /// Heights, metres: `(x1 − x0) / cells + 1` per row.
    pub heights_m: Vec<f32>,
}

impl BandCorners {
    /// Corners over `window` every `cells` cells, none known yet.
    pub fn new(window: [u64; 4], cells: u64) -> BandCorners {
        let [nx, ny] = Self::dims(window, cells);
        BandCorners {
            cells,
            window,
            heights_m: vec![f32::NAN; nx * ny],
        }
    }

    /// Columns and rows of corners.
    pub fn dims(window: [u64; 4], cells: u64) -> [usize; 2] {
        let c = cells.max(1);
        [
            ((window[2] - window[0]) / c + 1) as usize,
            ((window[3] - window[1]) / c + 1) as usize,
        ]
    }

    /// Sets the corners that `lattice` (the whole window or a part) stores.
    pub fn fill_from(&mut self, lattice: &Lattice) {
        let [sx0, sy0, sx1, sy1] = lattice.stored();
        let [nx, ny] = Self::dims(self.window, self.cells);
        for j in 0..ny {
            let y = self.window[1] + j as u64 * self.cells;
            if y < sy0 || y > sy1 {
                continue;
            }
            for i in 0..nx {
                let x = self.window[0] + i as u64 * self.cells;
                if x >= sx0 && x <= sx1 {
                    self.heights_m[j * nx + i] = lattice.height_at(x, y);
                }
            }
        }
    }

    /// How many corners are not known yet.
    pub fn missing(&self) -> usize {
        self.heights_m.iter().filter(|h| h.is_nan()).count()
    }

    /// The height at global `(x, y)`: 0 m beyond the window, the corner's
    /// height on the corners' grid, `None` elsewhere (or not known).
    pub fn height(&self, x: u64, y: u64) -> Option<f32> {
        let [x0, y0, x1, y1] = self.window;
        if x < x0 || x > x1 || y < y0 || y > y1 {
            return Some(0.0);
        }
        let (dx, dy) = (x - x0, y - y0);
        if !dx.is_multiple_of(self.cells) || !dy.is_multiple_of(self.cells) {
            return None;
        }
        let [nx, _] = Self::dims(self.window, self.cells);
        let h = self.heights_m[(dy / self.cells) as usize * nx + (dx / self.cells) as usize];
        (!h.is_nan()).then_some(h)
    }
}

/// A fine split point (the band zoom's squares and below) that splits at a
/// coarse zoom's threshold, or a band square's centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FinePoint {
    /// Global lattice position.
    pub at: [u32; 2],
    /// Bit `i`: it splits at the `i`-th coarse zoom (coarse to fine).
    pub splits: u32,
    /// Its 16-bit error code (band squares' centres; 0 for the others).
    pub code: u16,
    /// The code of its error against the source's samples (band squares'
    /// centres; 0 for the others).
    pub src: u16,
    /// The lattice's height there, metres.
    pub height_m: f32,
}

/// One shard's partial maxima (see the module docs).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CoarsePartial {
    /// Fine split points, in no particular order.
    pub fine: Vec<FinePoint>,
    /// Coarse split points' own errors over the shard's samples, rounded up
    /// to `f32` (absent: 0).
    pub own: Vec<([u32; 2], f32)>,
    /// The window bitree's coarse split points' own errors against the
    /// source's samples the shard owns, rounded up to `f32` (absent: 0).
    pub own_src: Vec<([u32; 2], f32)>,
    /// Vertex normals: position, zoom, unit (east, north, up).
    pub normals: Vec<([u32; 2], u8, [f32; 3])>,
    /// Water-mask samples of coarse tiles: 255 water, 0 land,
    /// [`WATER_UNKNOWN`] where another shard owns the sample.
    pub water: Vec<(TileId, Vec<u8>)>,
}

/// The coarse zooms (those below `band`) of `zooms`, with their rules per
/// level under `bound`.
pub(crate) fn coarse_rules(
    zooms: &[ZoomPlan],
    band: u8,
    bound: &DrawnBound,
) -> Vec<(ZoomPlan, ZoomRules)> {
    zooms
        .iter()
        .filter(|p| p.zoom < band)
        .map(|p| (*p, bound.rules(p.threshold_m)))
        .collect()
}

/// The map key of a global lattice position.
#[inline]
pub(crate) fn key(p: Pt) -> u64 {
    (u64::from(p[0]) << 32) | u64::from(p[1])
}

/// The position of a map key.
#[inline]
pub(crate) fn unkey(k: u64) -> Pt {
    [(k >> 32) as u32, k as u32]
}

impl Prepared<'_> {
    /// This part's partial maxima for the tiles coarser than zoom `band`,
    /// over the samples of `owned` (`[x0, y0, x1, y1]` inclusive: the squares
    /// of the shard's band-zoom tiles), with the band tiles' `corners`;
    /// normals and water-mask samples on request.
    ///
    /// # Errors
    /// [`TilesError::BadOptions`] when `corners` lacks a corner the part
    /// needs, or the part does not hold `owned` with its margin.
    ///
    /// # Runtime
    /// `O(owned samples)` per coarse level (two passes), in parallel, plus
    /// the fine split points' walks.
    pub fn coarse_partial(
        &self,
        owned: [u64; 4],
        band: u8,
        corners: &BandCorners,
        source: SourcePart<'_>,
        normals: bool,
        water: bool,
    ) -> Result<CoarsePartial, TilesError> {
        let rules = coarse_rules(self.zooms(), band, self.drawn_bound());
        let t = self.lattice().scheme().cells_at(band);
        if rules.is_empty() || owned[0] > owned[2] || owned[1] > owned[3] {
            return Ok(CoarsePartial::default());
        }
        if rules.len() > 32 || corners.cells != t {
            return Err(TilesError::BadOptions(format!(
                "expected band corners every {t} cells and at most 32 coarse zooms, found {} and {}",
                corners.cells,
                rules.len()
            )));
        }
        let fine = fine_points(self, owned, t, &rules);
        let own = own_partials(self, owned, t, corners)?;
        let own_src = source_partials(self, owned, t, corners, source)?;
        let normals = if normals {
            vertex_normals(self, owned, t, &fine, &rules)
        } else {
            Vec::new()
        };
        let water = if water {
            water_samples(self.lattice(), owned, &rules)
        } else {
            Vec::new()
        };
        Ok(CoarsePartial {
            fine,
            own,
            own_src,
            normals,
            water,
        })
    }
}

/// The band squares of side `t` inside `owned`, as their north-west corners.
fn band_squares(owned: [u64; 4], t: u64) -> Vec<[u64; 2]> {
    let (i0, i1) = (owned[0] / t, owned[2] / t);
    let (j0, j1) = (owned[1] / t, owned[3] / t);
    (j0..j1)
        .flat_map(|j| (i0..i1).map(move |i| [i * t, j * t]))
        .collect()
}

/// The fine split points of the squares in `owned` that split at the
/// smallest coarse threshold (and every square's centre), with their bits.
fn fine_points(
    prep: &Prepared<'_>,
    owned: [u64; 4],
    t: u64,
    rules: &[(ZoomPlan, ZoomRules)],
) -> Vec<FinePoint> {
    // The zoom of the lowest threshold splits wherever any coarse zoom does
    // (the drawn bound's slack depends on the level, not the zoom).
    let lowest = rules
        .iter()
        .min_by(|a, b| a.0.threshold_m.total_cmp(&b.0.threshold_m))
        .and_then(|(p, _)| prep.zoom_index(p.zoom));
    let Some(lowest) = lowest else {
        return Vec::new();
    };
    let zi: Vec<usize> = rules
        .iter()
        .filter_map(|(p, _)| prep.zoom_index(p.zoom))
        .collect();
    let lat = prep.lattice();
    let mask = |tri: &Tri| {
        zi.iter()
            .enumerate()
            .filter(|(_, &z)| prep.splits(tri, z))
            .fold(0u32, |m, (i, _)| m | (1 << i))
    };
    let found: Vec<FinePoint> = band_squares(owned, t)
        .par_iter()
        .flat_map_iter(|&[x, y]| {
            let (x0, y0, s) = (x as u32, y as u32, t as u32);
            let sq = [[x0, y0], [x0 + s, y0], [x0, y0 + s], [x0 + s, y0 + s]];
            let halves = square_halves(sq, (x / t + y / t).is_multiple_of(2));
            let centre = halves[0].mid();
            let [code, src] = prep.code_at(centre);
            let mut out = vec![FinePoint {
                at: centre,
                splits: mask(&halves[0]),
                code,
                src,
                height_m: lat.height_at(u64::from(centre[0]), u64::from(centre[1])),
            }];
            let mut stack: Vec<Tri> = halves.to_vec();
            while let Some(tri) = stack.pop() {
                if tri.is_unit() || !prep.splits(&tri, lowest) {
                    continue;
                }
                let (c0, c1) = tri.children();
                stack.extend([c0, c1]);
                let m = tri.mid();
                if m != centre {
                    out.push(FinePoint {
                        at: m,
                        splits: mask(&tri),
                        code: 0,
                        src: 0,
                        height_m: lat.height_at(u64::from(m[0]), u64::from(m[1])),
                    });
                }
            }
            out
        })
        .collect();
    let mut by_key: HashMap<u64, FinePoint> =
        HashMap::with_capacity_and_hasher(found.len(), Default::default());
    for p in found {
        by_key.entry(key(p.at)).or_insert(p);
    }
    by_key.into_values().collect()
}

/// The squares of side `s` whose closed square meets `owned`, within
/// `range` (`[i0, j0, i1, j1]` inclusive).
fn squares_meeting(owned: [u64; 4], s: u64, range: [u64; 4]) -> Vec<[u64; 2]> {
    let lo = |v: u64| v.saturating_sub(1) / s;
    let (i0, i1) = (lo(owned[0]).max(range[0]), (owned[2] / s).min(range[2]));
    let (j0, j1) = (lo(owned[1]).max(range[1]), (owned[3] / s).min(range[3]));
    (j0..=j1)
        .flat_map(|j| (i0..=i1).map(move |i| [i, j]))
        .collect()
}

/// The own maxima over `owned` of every coarse split point above squares of
/// side `t`.
fn own_partials(
    prep: &Prepared<'_>,
    owned: [u64; 4],
    t: u64,
    corners: &BandCorners,
) -> Result<Vec<([u32; 2], f32)>, TilesError> {
    let lat = prep.lattice();
    let s = lat.scheme();
    let top = s.cells_at(lat.align_zoom());
    let [x0, y0, x1, y1] = lat.window();
    let mut own: HashMap<u64, f32> = HashMap::default();
    let mut size = 2 * t;
    while size <= s.root_cells() {
        let (nx, ny) = (2 * s.root_cells() / size, s.root_cells() / size);
        let range = if size <= top {
            // The window bitree's squares: those inside the window.
            [x0 / size, y0 / size, x1 / size - 1, y1 / size - 1]
        } else {
            let first = |v: u64| (v / size).saturating_sub(2);
            let last = |v: u64, n: u64| (v / size + 2).min(n - 1);
            [first(x0), first(y0), last(x1, nx), last(y1, ny)]
        };
        let found: Vec<(Pt, f32)> = squares_meeting(owned, size, range)
            .par_iter()
            .map(|&[i, j]| {
                let (sides, halves) = square_tris(i, j, size);
                let tris = sides.into_iter().chain(halves);
                tris.map(|tri| {
                    Ok((
                        tri.mid(),
                        partial_of(lat, &tri, size <= top, owned, corners)?,
                    ))
                })
                .collect::<Result<Vec<_>, TilesError>>()
            })
            .collect::<Result<Vec<_>, TilesError>>()?
            .into_iter()
            .flatten()
            .filter(|(_, e)| *e > 0.0)
            .collect();
        for (m, e) in found {
            let slot = own.entry(key(m)).or_insert(0.0);
            *slot = slot.max(e);
        }
        size *= 2;
    }
    Ok(own.into_iter().map(|(k, e)| (unkey(k), e)).collect())
}

/// The own errors against the source's samples in `owned` of the window
/// bitree's split points above squares of side `t` (up to the alignment
/// zoom's squares), planes from the band `corners`.
fn source_partials(
    prep: &Prepared<'_>,
    owned: [u64; 4],
    t: u64,
    corners: &BandCorners,
    source: SourcePart<'_>,
) -> Result<Vec<([u32; 2], f32)>, TilesError> {
    let lat = prep.lattice();
    let s = lat.scheme();
    let top = s.cells_at(lat.align_zoom());
    let [x0, y0, x1, y1] = lat.window();
    let samples = Samples::new(
        &lat.frame().source_georef,
        &lat.frame().scheme,
        source,
        owned,
    );
    let mut own: HashMap<u64, f32> = HashMap::default();
    let mut size = 2 * t;
    while size <= top {
        let range = [x0 / size, y0 / size, x1 / size - 1, y1 / size - 1];
        let found: Vec<(Pt, f32)> = squares_meeting(owned, size, range)
            .par_iter()
            .map(|&[i, j]| {
                let (sides, halves) = square_tris(i, j, size);
                sides
                    .into_iter()
                    .chain(halves)
                    .map(|tri| {
                        let z = corner_heights(&tri, corners)?;
                        Ok((tri.mid(), triangle_error(&tri, z, &samples, owned)))
                    })
                    .collect::<Result<Vec<_>, TilesError>>()
            })
            .collect::<Result<Vec<_>, TilesError>>()?
            .into_iter()
            .flatten()
            .filter(|(_, e)| *e > 0.0)
            .collect();
        for (m, e) in found {
            let slot = own.entry(key(m)).or_insert(0.0);
            *slot = slot.max(e);
        }
        size *= 2;
    }
    Ok(own.into_iter().map(|(k, e)| (unkey(k), e)).collect())
}

/// The heights of `tri`'s corners from the band corners.
fn corner_heights(tri: &Tri, corners: &BandCorners) -> Result<[f64; 3], TilesError> {
    let missing = std::cell::Cell::new(None);
    let z = t_heights(tri, |x, y| {
        corners.height(x, y).unwrap_or_else(|| {
            missing.set(Some([x, y]));
            0.0
        })
    });
    match missing.get() {
        Some([x, y]) => Err(TilesError::BadOptions(format!(
            "expected the band corners to hold the height at lattice ({x}, {y}), found none"
        ))),
        None => Ok(z),
    }
}

/// The own error of the coarse triangle `tri` over the samples of `owned`
/// (the window bitree's formula when `bitree`, the cap's otherwise).
fn partial_of(
    lat: &Lattice,
    tri: &Tri,
    bitree: bool,
    owned: [u64; 4],
    corners: &BandCorners,
) -> Result<f32, TilesError> {
    let missing = std::cell::Cell::new(None);
    let z = t_heights(tri, |x, y| {
        corners.height(x, y).unwrap_or_else(|| {
            missing.set(Some([x, y]));
            0.0
        })
    });
    if let Some([x, y]) = missing.get() {
        return Err(TilesError::BadOptions(format!(
            "expected the band corners to hold the height at lattice ({x}, {y}), found none"
        )));
    }
    let e = if bitree {
        let g = lat.grid();
        clipped_span_error(g.heights(), g.width(), lat.origin(), tri, z, owned)
    } else {
        own_rows(lat.window(), tri, z, false, Some((lat, owned, None)))
    };
    Ok(round_up_f32(e))
}

/// The normals this part computes: fine points at the zooms they are
/// vertices of, and band-tile corners (within the normals' reach of the
/// window, owned by the shard whose squares hold the nearest window sample)
/// at every coarse zoom.
fn vertex_normals(
    prep: &Prepared<'_>,
    owned: [u64; 4],
    t: u64,
    fine: &[FinePoint],
    rules: &[(ZoomPlan, ZoomRules)],
) -> Vec<([u32; 2], u8, [f32; 3])> {
    let lat = prep.lattice();
    let s = lat.scheme();
    let h = |x: u64, y: u64| lat.height_at(x, y);
    let mut out = Vec::new();
    for (i, (p, _)) in rules.iter().enumerate() {
        let cells = s.cells_at(p.zoom);
        for f in fine.iter().filter(|f| f.splits & (1 << i) != 0) {
            let [x, y] = f.at.map(u64::from);
            out.push((f.at, p.zoom, normal_at(s, h, x, y, cells)));
        }
        for c in window_corners(lat.window(), owned, t) {
            let [x, y] = c.map(u64::from);
            out.push((c, p.zoom, normal_at(s, h, x, y, cells)));
        }
    }
    out
}

/// The band-tile corners of `window` (every `t` cells) inside `owned`.
pub(crate) fn window_corners(window: [u64; 4], owned: [u64; 4], t: u64) -> Vec<Pt> {
    let (xs, ys) = (window[0]..=window[2], window[1]..=window[3]);
    let mut out = Vec::new();
    for y in ys.step_by(t as usize) {
        if !(owned[1]..=owned[3]).contains(&y) {
            continue;
        }
        for x in xs.clone().step_by(t as usize) {
            if (owned[0]..=owned[2]).contains(&x) {
                out.push([x as u32, y as u32]);
            }
        }
    }
    out
}

/// The coarse tiles' water-mask samples inside `owned`.
fn water_samples(
    lat: &Lattice,
    owned: [u64; 4],
    rules: &[(ZoomPlan, ZoomRules)],
) -> Vec<(TileId, Vec<u8>)> {
    let s = lat.scheme();
    let tiles: Vec<TileId> = rules
        .iter()
        .flat_map(|(p, _)| {
            let r = p.range;
            let z = p.zoom;
            (r.y0..=r.y1).flat_map(move |y| (r.x0..=r.x1).map(move |x| TileId { z, x, y }))
        })
        .filter(|&tile| {
            let (o, c) = (s.tile_origin(tile), s.cells_at(tile.z));
            o[0] <= owned[2] && o[0] + c >= owned[0] && o[1] <= owned[3] && o[1] + c >= owned[1]
        })
        .collect();
    tiles
        .into_par_iter()
        .filter_map(|tile| {
            let (o, c) = (s.tile_origin(tile), s.cells_at(tile.z));
            let mut any = false;
            let mut grid = vec![WATER_UNKNOWN; 256 * 256];
            for j in 0..256u64 {
                for i in 0..256u64 {
                    let [x, y] = water_sample(o, c, i, j);
                    if (owned[0]..=owned[2]).contains(&x) && (owned[1]..=owned[3]).contains(&y) {
                        let wet = is_wet(lat.frame(), x, y, lat.height_at(x, y));
                        grid[(j * 256 + i) as usize] = if wet { 255 } else { 0 };
                        any = true;
                    }
                }
            }
            any.then_some((tile, grid))
        })
        .collect()
}
