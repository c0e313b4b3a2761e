//! One tile: the subtree of the global hierarchy inside the tile's square.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §2: a triangle splits at the midpoint of
//! its hypotenuse; both triangles of a diamond read the same error, so a
//! decision per split point is crack-free. Paper `001_49f2c365e8c41172.txt`:
//! the frontier of the tree is the mesh.
//!
//! The tile's roots are the two halves of its square (every triangle larger
//! than the tile is split). A triangle splits when its split point's error
//! (the window's [`Bitree`] up to the alignment zoom's squares, the
//! [`super::cap`] above) exceeds the zoom's threshold. Each leaf then meets
//! `e(T) ≤ threshold` at every lattice sample it covers; a leaf outside the
//! window lies on 0 m and never splits.
//!
//! Also per vertex, on request: a normal from the lattice's slope at the
//! tile's own scale (a central difference over `T_z / 64` cells, at most
//! [`NORMAL_REACH_CELLS`], so two tiles that share a vertex give it the same
//! normal and a shard's part holds what its normals read; straight up
//! beyond the window, on the ellipsoid), and a 256×256 water
//! mask (samples at or below 0 m in the data: sea level in SRTM; land
//! beyond the data; a heuristic, not a coastline).

use rustc_hash::FxHashMap as HashMap;

use super::cap::{square_halves, Cap};
use super::drawn::{DrawnBound, LevelRule, ZoomRules};
use super::error::TilesError;
use super::lattice::Lattice;
use super::lattice::SourcePart;
use super::plan::{children_in, plan_with, LatticeStats, TileRange, TilerOptions, ZoomPlan};
use super::relevant::Relevant;
use super::samples::{SampleSet, Samples};
use super::scheme::{GeographicScheme, TileId};
use super::source_error::{own_errors, Skip, BY_SAMPLE_BELOW};
use crate::bitree::closure::source_closure;
use crate::bitree::error_code::{decode, SplitRule};
use crate::bitree::Bitree;
use crate::grid::metres_per_degree;
use crate::grid::HeightGrid;
use crate::hierarchy::{orient_up, Pt, Tri};
use crate::mesh::check::Region;
use crate::mesh::{Mesh, MeshVertex};
use crate::progress::{Progress, Stages};

/// A tile's water mask: quantized-mesh's extension 2.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum WaterMask {
    /// All land (0) or all water (255).
    Uniform(u8),
    /// 256×256 values, north to south, west to east; 0 land, 255 water.
    Grid(Vec<u8>),
}

/// A tile's mesh and what its encoding needs.
#[derive(Debug, Clone)]
pub struct TileMesh {
    /// The tile.
    pub tile: TileId,
    /// Lattice cells across the tile (`T_z`).
    pub cells: u64,
    /// `[west, south, east, north]`, degrees.
    pub rect_deg: [f64; 4],
    /// Vertices on the tile's lattice samples (column from its west edge,
    /// row from its north edge, `0..=cells`), triangles counter-clockwise
    /// seen from above.
    pub mesh: Mesh,
    /// The bound the tile meets after quantization, metres.
    pub max_error_m: f64,
    /// The bound it meets at the source's own samples, as drawn: the same,
    /// unless the lattice cannot hold the source (see
    /// [`Prepared::source_bound_m`]), metres.
    pub source_bound_m: f64,
    /// The threshold it was extracted at, metres.
    pub threshold_m: f64,
    /// Unit normals per vertex in east, north, up components (on request).
    pub normals_enu: Option<Vec<[f32; 3]>>,
    /// The water mask (on request).
    pub water_mask: Option<WaterMask>,
    /// The tile's children that the pyramid makes, as rectangles.
    pub children: Vec<TileRange>,
}

/// A lattice with its global hierarchy, ready to cut any tile.
///
/// ```
/// use cota_core::tiles::{Lattice, LatticeOptions, Prepared, TileId, TilerOptions};
/// use cota_core::{Crs, GeoRef, HeightGrid, PixelIs};
/// let n = 61;
/// let heights = (0..n * n).map(|i| 300.0 + ((i % n) as f32 * 0.2).sin() * 40.0).collect();
/// let georef = GeoRef { crs: Crs::WGS84, origin_x: 10.0, origin_y: 1.0, pixel_x: 0.01,
///     pixel_y: -0.01, pixel_is: PixelIs::Point, known: true };
/// let source = HeightGrid::new(n, n, heights, georef).unwrap();
/// let lattice = Lattice::resample(&source, &LatticeOptions::DEFAULT).unwrap();
/// let prepared = Prepared::new(&lattice, &source, &TilerOptions::DEFAULT).unwrap();
/// let root = prepared.cut(TileId { z: 0, x: 1, y: 0 }, false, false).unwrap();
/// assert!(root.mesh.triangle_count() >= 2);
/// ```
#[derive(Debug)]
pub struct Prepared<'l> {
    lattice: &'l Lattice,
    tree: Bitree<'l>,
    cap: Cap,
    /// Per stored point, the code of its error against the source's own
    /// samples, closed over its descendants (`bitree::closure`).
    src: Vec<u16>,
    /// The fitted lattice's largest residual at the source's samples: what
    /// the coarse levels above the window's bitree add to their lattice
    /// error to bound their error against the source ([`super::fit`]).
    residual_m: f64,
    zooms: Vec<ZoomPlan>,
    bound: DrawnBound,
    /// Per zoom of `zooms`, the rules per level ([`super::drawn`]).
    rules: Vec<ZoomRules>,
}

/// The drawn bound of a lattice frame with statistics `stats`, and each
/// zoom's rules.
pub(crate) fn rules_of(
    scheme: &GeographicScheme,
    window: [u64; 4],
    stats: &LatticeStats,
    zooms: &[ZoomPlan],
) -> (DrawnBound, Vec<ZoomRules>) {
    let range = [
        f64::from(stats.lo_m),
        f64::from(stats.hi_m),
        stats.max_step_m,
    ];
    let bound = DrawnBound::new(scheme, window, range, &stats.levels);
    let rules = zooms.iter().map(|p| bound.rules(p.threshold_m)).collect();
    (bound, rules)
}

impl<'l> Prepared<'l> {
    /// Builds the window's bitree and the coarse levels above it.
    ///
    /// # Errors
    /// [`TilesError::BadOptions`], [`TilesError::BelowQuantization`],
    /// [`TilesError::Mesh`].
    ///
    /// # Runtime
    /// The window's [`Bitree::build`] (`O(n log n)`) plus `O(n)` per coarse
    /// level, for `n` window samples.
    pub fn new(
        lattice: &'l Lattice,
        source: &HeightGrid,
        opts: &TilerOptions,
    ) -> Result<Self, TilesError> {
        Prepared::new_with_progress(lattice, source, opts, crate::progress::NONE)
    }

    /// [`Prepared::new`], telling `progress(done, total)` as it goes: the
    /// bitree's levels, the coarse levels, the source errors, weighted by
    /// their share of the time (in thousandths, [`crate::progress`]).
    ///
    /// # Errors
    /// As [`Prepared::new`].
    pub fn new_with_progress(
        lattice: &'l Lattice,
        source: &HeightGrid,
        opts: &TilerOptions,
        progress: Progress<'_>,
    ) -> Result<Self, TilesError> {
        let whole = SourcePart {
            grid: source,
            offset: [0, 0],
        };
        Prepared::new_sampled_with_progress(
            lattice,
            &Samples::new(
                &lattice.frame().source_georef,
                &lattice.frame().scheme,
                whole,
                lattice.stored(),
            ),
            opts,
            progress,
        )
    }

    /// [`Prepared::new`] from the source's samples as a set: what a lattice of
    /// several sources ([`Lattice::resample_sources`]) is prepared from.
    ///
    /// # Errors
    /// As [`Prepared::new`].
    pub fn new_sampled(
        lattice: &'l Lattice,
        samples: &impl SampleSet,
        opts: &TilerOptions,
    ) -> Result<Self, TilesError> {
        Prepared::new_sampled_with_progress(lattice, samples, opts, crate::progress::NONE)
    }

    /// [`Prepared::new_sampled`], telling `progress` as
    /// [`Prepared::new_with_progress`] does.
    ///
    /// # Errors
    /// As [`Prepared::new`].
    pub fn new_sampled_with_progress(
        lattice: &'l Lattice,
        samples: &impl SampleSet,
        opts: &TilerOptions,
        progress: Progress<'_>,
    ) -> Result<Self, TilesError> {
        if lattice.is_part() {
            return Err(TilesError::BadOptions(
                "expected a lattice over its whole window, found a part (use Prepared::new_part)"
                    .into(),
            ));
        }
        let stages = Stages::new(progress, &PREPARE_WEIGHTS);
        let stats = LatticeStats::of(lattice);
        let zooms = plan_with(lattice.frame(), &stats, opts)?;
        stages.finish(0);
        let tree = Bitree::build_with_progress(lattice.grid(), &stages.stage(1))?;
        stages.finish(1);
        let cap = Cap::build(lattice, &tree, &stages.stage(2));
        stages.finish(2);
        let (bound, rules) = rules_of(lattice.scheme(), lattice.window(), &stats, &zooms);
        let src = source_codes(lattice, &tree, samples, &rules, &stages, 3);
        Ok(Prepared {
            lattice,
            tree,
            cap,
            src,
            residual_m: stats.residual_m,
            zooms,
            bound,
            rules,
        })
    }

    /// Builds the bitree of a part of the lattice ([`Lattice::resample_part`])
    /// with the whole pyramid's plan `zooms` (from
    /// [`super::plan::plan_with`] and the whole lattice's statistics
    /// `stats`, which also set the drawn bound). It
    /// cuts exactly the tiles a whole lattice cuts, for the tiles of zooms at
    /// or finer than the alignment zoom whose square, grown by half a tile,
    /// lies in the part (the split points a tile reads lie in that square,
    /// and their errors depend only on the heights there); [`Prepared::cut`]
    /// refuses the others.
    ///
    /// # Errors
    /// [`TilesError::Mesh`].
    ///
    /// # Runtime
    /// The part's [`Bitree::build`].
    pub fn new_part(
        lattice: &'l Lattice,
        source: SourcePart<'_>,
        zooms: Vec<ZoomPlan>,
        stats: &LatticeStats,
    ) -> Result<Self, TilesError> {
        Prepared::new_part_with_progress(lattice, source, zooms, stats, crate::progress::NONE)
    }

    /// [`Prepared::new_part`], telling `progress` as
    /// [`Prepared::new_with_progress`] does.
    ///
    /// # Errors
    /// As [`Prepared::new_part`].
    pub fn new_part_with_progress(
        lattice: &'l Lattice,
        source: SourcePart<'_>,
        zooms: Vec<ZoomPlan>,
        stats: &LatticeStats,
        progress: Progress<'_>,
    ) -> Result<Self, TilesError> {
        let stages = Stages::new(progress, &PREPARE_WEIGHTS);
        stages.finish(0);
        let tree = Bitree::build_with_progress(lattice.grid(), &stages.stage(1))?;
        stages.finish(2);
        let samples = Samples::new(
            &lattice.frame().source_georef,
            &lattice.frame().scheme,
            source,
            lattice.stored(),
        );
        let (bound, rules) = rules_of(lattice.scheme(), lattice.window(), stats, &zooms);
        let src = source_codes(lattice, &tree, &samples, &rules, &stages, 3);
        Ok(Prepared {
            lattice,
            tree,
            cap: Cap::default(),
            src,
            residual_m: stats.residual_m,
            zooms,
            bound,
            rules,
        })
    }

    /// The drawn bound its decisions keep ([`super::drawn`]).
    pub fn drawn_bound(&self) -> &DrawnBound {
        &self.bound
    }

    /// The bound zoom `z`'s tiles meet at the source's own samples, as
    /// drawn: the zoom's bound `e_z`, or more where the lattice cannot hold
    /// the source: a leaf of the finest level (a unit triangle, which cannot
    /// split) is the lattice itself there, within the fitted lattice's
    /// largest residual of the source, plus quantization and the drawn
    /// triangle's own slack. That floor exceeds `e_z` only on a lattice
    /// coarser than the source (a `--max-zoom` below the source's) or where
    /// the fit could not bring a sample within half the finest bound.
    pub fn source_bound_m(&self, z: u8) -> f64 {
        self.zoom(z).map_or(0.0, |p| {
            let floor = self.residual_m + p.margin_m + self.bound.finest_slack_m();
            p.max_error_m.max(floor)
        })
    }

    /// True when this hierarchy cuts tile `t` (an address, as every tile
    /// this type takes and gives: [`GeographicScheme::address`]) exactly:
    /// always for a whole lattice; for a part, when `t` is at or finer than
    /// the alignment zoom and its square grown by half a tile (clipped to
    /// the window) is stored.
    pub fn holds(&self, t: TileId) -> bool {
        let lat = self.lattice;
        if !lat.is_part() {
            return true;
        }
        if t.z < lat.align_zoom() {
            return false;
        }
        let s = lat.scheme();
        let (cells, [x, y]) = (s.cells_at(t.z), s.tile_origin(s.address(t)));
        let (w, st) = (lat.window(), lat.stored());
        // The part's bitree has the global diagonals at this zoom's squares.
        let aligned = st[0] % cells == 0
            && st[1] % cells == 0
            && (st[0] / cells + st[1] / cells).is_multiple_of(2);
        let lo = |v: u64, min: u64| v.saturating_sub(cells / 2).max(min);
        let hi = |v: u64, max: u64| (v + cells + cells / 2).min(max);
        aligned
            && lo(x, w[0]) >= st[0]
            && lo(y, w[1]) >= st[1]
            && hi(x, w[2]) <= st[2]
            && hi(y, w[3]) <= st[3]
    }

    /// The window bitree's codes of the split point `m` (stored by a part):
    /// its lattice error and its error against the source.
    pub(crate) fn code_at(&self, m: Pt) -> [u16; 2] {
        let [x0, y0, _, _] = self.lattice.stored();
        let w = self.lattice.grid().width();
        let i = (u64::from(m[1]) - y0) as usize * w + (u64::from(m[0]) - x0) as usize;
        [self.tree.error_codes()[i], self.src[i]]
    }

    /// The lattice.
    pub fn lattice(&self) -> &'l Lattice {
        self.lattice
    }

    /// The plan of every zoom made, coarse to fine.
    pub fn zooms(&self) -> &[ZoomPlan] {
        &self.zooms
    }

    /// The plan of zoom `z`, if it is made.
    pub fn zoom(&self, z: u8) -> Option<&ZoomPlan> {
        self.zooms.iter().find(|p| p.zoom == z)
    }

    /// Coarse split points stored above the window's bitree.
    pub fn cap_points(&self) -> usize {
        self.cap.len()
    }

    /// Every tile of the pyramid, zoom by zoom (addresses).
    pub fn tiles(&self) -> impl Iterator<Item = TileId> + '_ {
        let s = *self.lattice.scheme();
        self.zooms.iter().flat_map(move |p| {
            let r = p.range;
            (r.y0..=r.y1)
                .flat_map(move |y| (r.x0..=r.x1).map(move |x| TileId { z: p.zoom, x, y }))
                .filter(move |&t| self.covers_lattice(t))
                .map(move |t| s.address(t))
        })
    }

    /// Whether tile `t` lies in its zoom's range ([`ZoomPlan::range`], in
    /// lattice tiles), its zoom being made.
    pub fn in_range(&self, t: TileId) -> bool {
        let l = self.lattice.scheme().address(t);
        self.zoom(t.z).is_some_and(|p| p.range.contains(l.x, l.y))
    }

    /// Number of tiles in the pyramid.
    pub fn tile_count(&self) -> u64 {
        match self.lattice.coverage() {
            None => self.zooms.iter().map(|p| p.range.count()).sum(),
            Some(_) => self.tiles().count() as u64,
        }
    }

    /// Whether the pyramid makes tile `t` (in its zoom's range): both roots
    /// always, and a tile whose square meets the data's footprint with a
    /// positive area ([`super::coverage::Coverage`]; the range alone for a
    /// single rectangular footprint).
    pub fn covers(&self, t: TileId) -> bool {
        self.covers_lattice(self.lattice.scheme().address(t))
    }

    /// [`Prepared::covers`] of lattice tile `t`.
    fn covers_lattice(&self, t: TileId) -> bool {
        let Some(cov) = self.lattice.coverage() else {
            return true;
        };
        if t.z == 0 {
            return true;
        }
        let s = self.lattice.scheme();
        let (c, [x, y]) = (s.cells_at(t.z) as f64, s.tile_origin(t).map(|v| v as f64));
        cov.meets([x, y, x + c, y + c])
    }

    /// The tiles of zoom `z` that the pyramid makes, as rectangles (rows of
    /// runs; the zoom's range when every tile in it is made).
    pub fn available(&self, z: u8) -> Vec<TileRange> {
        let Some(p) = self.zoom(z) else {
            return Vec::new();
        };
        let s = self.lattice.scheme();
        covered_runs(p.range, |x, y| self.covers_lattice(TileId { z, x, y }))
            .into_iter()
            .flat_map(|r| addressed(s, z, r))
            .collect()
    }

    /// The samples tile `t` is checked against: its square of the lattice.
    pub fn region(&self, t: TileId) -> Region<'l> {
        let s = self.lattice.scheme();
        let [gx, gy] = s.tile_origin(s.address(t));
        let [ox, oy] = self.lattice.origin();
        let n = self.lattice.scheme().cells_at(t.z) + 1;
        Region {
            grid: self.lattice.grid(),
            origin: [ox as i64 - gx as i64, oy as i64 - gy as i64],
            size: [n, n],
            background_m: 0.0,
        }
    }

    /// Cuts tile `t`, with per-vertex normals and a water mask on request.
    ///
    /// # Errors
    /// [`TilesError::NoSuchTile`] for a tile outside the pyramid or, for a
    /// part, one it does not hold ([`Prepared::holds`]).
    ///
    /// # Runtime
    /// Proportional to the tile's triangles (plus 256² lattice reads for the
    /// water mask).
    pub fn cut(&self, t: TileId, normals: bool, water: bool) -> Result<TileMesh, TilesError> {
        if !(self.makes(t) && self.holds(t)) {
            return Err(self.no_such_tile(t));
        }
        let children = self.children(self.lattice.scheme().address(t));
        self.cut_square(t, [normals, water], children)
    }

    /// Whether the pyramid makes tile `t`: its zoom is made, and `t` is in
    /// the zoom's range and meets the data ([`Prepared::covers`]).
    pub fn makes(&self, t: TileId) -> bool {
        self.in_range(t) && self.covers(t)
    }

    /// Whether `t` is a *fill* tile: not made ([`Prepared::makes`]), on a
    /// made zoom, and a child of a made tile that has a made child. A
    /// format whose clients draw a refined tile only through its children
    /// (3D Tiles' REPLACE refinement) needs every quadrant of such a tile;
    /// quantized-mesh clients upsample the parent instead.
    pub fn is_fill(&self, t: TileId) -> bool {
        if t.z == 0 || self.zoom(t.z).is_none() || self.makes(t) {
            return false;
        }
        let parent = TileId {
            z: t.z - 1,
            x: t.x / 2,
            y: t.y / 2,
        };
        self.makes(parent) && quadrants(parent).into_iter().any(|c| self.makes(c))
    }

    /// Every fill tile ([`Prepared::is_fill`]), zoom by zoom.
    pub fn fills(&self) -> impl Iterator<Item = TileId> + '_ {
        self.tiles()
            .flat_map(quadrants)
            .filter(move |&c| self.is_fill(c))
    }

    /// Cuts fill tile `t` ([`Prepared::is_fill`]) from the same global
    /// hierarchy as the pyramid's tiles: beyond the lattice's window the
    /// terrain is the ellipsoid (0 m) and only the drawn bound's curvature
    /// term splits (a few triangles), inside it the lattice's heights (the
    /// ramp down from the data's edge); its border vertices are its
    /// same-zoom neighbours'. It has no children.
    ///
    /// # Errors
    /// [`TilesError::NoSuchTile`] for a tile that is not a fill tile or
    /// that a part does not hold.
    pub fn cut_fill(&self, t: TileId, normals: bool) -> Result<TileMesh, TilesError> {
        if !(self.is_fill(t) && self.holds(t)) {
            return Err(self.no_such_tile(t));
        }
        self.cut_square(t, [normals, false], Vec::new())
    }

    fn no_such_tile(&self, t: TileId) -> TilesError {
        TilesError::NoSuchTile {
            tile: t,
            min_zoom: self.zooms.first().map_or(0, |p| p.zoom),
            max_zoom: self.lattice.scheme().max_zoom,
        }
    }

    /// The subtree of `t`'s square at its zoom's threshold (the zoom is
    /// made), with normals and water mask as `[normals, water]` say.
    fn cut_square(
        &self,
        t: TileId,
        [normals, water]: [bool; 2],
        children: Vec<TileRange>,
    ) -> Result<TileMesh, TilesError> {
        let plan = self.zoom(t.z).ok_or_else(|| self.no_such_tile(t))?;
        let s = self.lattice.scheme();
        let lt = s.address(t);
        let cells = s.cells_at(t.z);
        let origin = s.tile_origin(lt);
        let zi = self.zoom_index(t.z).unwrap_or(0);
        let leaves = walk_leaves(origin, cells, |tri| self.splits(tri, zi));
        let mesh = self.mesh_of(&leaves, origin);
        Ok(TileMesh {
            tile: t,
            cells,
            rect_deg: s.tile_rect_deg(t),
            normals_enu: normals.then(|| self.normals(&mesh, origin, cells)),
            water_mask: water.then(|| self.water(origin, cells)),
            mesh,
            max_error_m: plan.max_error_m,
            source_bound_m: self.source_bound_m(t.z),
            threshold_m: plan.threshold_m,
            children,
        })
    }

    /// The children of lattice tile `t` that the pyramid makes, as runs of
    /// addresses.
    fn children(&self, t: TileId) -> Vec<TileRange> {
        let (s, z) = (self.lattice.scheme(), t.z + 1);
        children_in(t, self.zoom(z))
            .map(|r| covered_runs(r, |x, y| self.covers_lattice(TileId { z, x, y })))
            .unwrap_or_default()
            .into_iter()
            .flat_map(|r| addressed(s, z, r))
            .collect()
    }

    /// The index of zoom `z` in [`Prepared::zooms`].
    pub(crate) fn zoom_index(&self, z: u8) -> Option<usize> {
        self.zooms.iter().position(|p| p.zoom == z)
    }

    /// Whether `t` splits at the `zi`-th zoom: the drawn bound's rule for
    /// its level ([`super::drawn`]), against the window's bitree up to the
    /// alignment zoom's squares, the cap above.
    #[inline]
    pub(crate) fn splits(&self, t: &Tri, zi: usize) -> bool {
        let rule = match self.rules[zi].of(t, self.lattice.window()) {
            LevelRule::Always => return true,
            LevelRule::Above(rule) => rule,
        };
        let m = t.mid();
        let size = t.a[0].abs_diff(t.b[0]).max(t.a[1].abs_diff(t.b[1]));
        let top = self.lattice.scheme().cells_at(self.lattice.align_zoom());
        if u64::from(size) > top {
            return above_cap(self.cap.error(m), self.residual_m, &rule);
        }
        // Beyond the window every error is 0; a part holds the split points
        // its tiles read ([`Prepared::holds`]).
        let [x0, y0, x1, y1] = self.lattice.stored();
        let (x, y) = (u64::from(m[0]), u64::from(m[1]));
        if x < x0 || x > x1 || y < y0 || y > y1 {
            return false;
        }
        let w = self.lattice.grid().width();
        let i = (y - y0) as usize * w + (x - x0) as usize;
        self.src[i] > rule.floor || self.tree.splits_index(i, &rule)
    }

    /// The leaves as a mesh in tile coordinates, vertices in first-use order.
    fn mesh_of(&self, leaves: &[Tri], o: [u64; 2]) -> Mesh {
        mesh_of_leaves(leaves, o, |x, y| self.lattice.height_at(x, y))
    }

    /// Per-vertex unit normals (east, north, up): [`normal_at`] inside the
    /// window, straight up (the ellipsoid's) beyond it.
    fn normals(&self, mesh: &Mesh, o: [u64; 2], cells: u64) -> Vec<[f32; 3]> {
        let s = self.lattice.scheme();
        let h = |x: u64, y: u64| self.lattice.height_at(x, y);
        let w = self.lattice.window();
        mesh.vertices
            .iter()
            .map(|v| {
                let (x, y) = (o[0] + u64::from(v.col), o[1] + u64::from(v.row));
                if in_window(w, x, y) {
                    normal_at(s, h, x, y, cells)
                } else {
                    UP
                }
            })
            .collect()
    }

    /// The water mask: 256×256 nearest lattice samples, water at or below
    /// 0 m in the data ([`is_wet`]).
    fn water(&self, o: [u64; 2], cells: u64) -> WaterMask {
        let f = self.lattice.frame();
        water_of(o, cells, |_, x, y| {
            is_wet(f, x, y, self.lattice.height_at(x, y))
        })
    }
}

/// The four children of `t`.
fn quadrants(t: TileId) -> [TileId; 4] {
    let (z, x, y) = (t.z + 1, 2 * t.x, 2 * t.y);
    [(0, 0), (1, 0), (0, 1), (1, 1)].map(|(dx, dy)| TileId {
        z,
        x: x + dx,
        y: y + dy,
    })
}

/// Whether a coarse split point above the window's bitree, of lattice
/// error `e_m`, splits under `rule`: its error against the source is at
/// most `e_m` plus the fitted lattice's largest residual `residual_m` (the
/// triangle's plane minus the lattice is linear on each unit triangle).
#[inline]
pub(crate) fn above_cap(e_m: f32, residual_m: f64, rule: &SplitRule) -> bool {
    f64::from(e_m) + residual_m > f64::from(rule.threshold)
}

/// Per stored point of `lattice` (whose bitree is `tree`): the code of its
/// error against the source's samples in `source`, closed over its
/// descendants (`bitree::closure::source_closure`); 0 where it decides
/// nothing under any of `rules` (not measured where the lattice error and
/// the residuals prove it: [`super::relevant`]).
fn source_codes(
    lattice: &Lattice,
    tree: &Bitree<'_>,
    samples: &impl SampleSet,
    rules: &[ZoomRules],
    stages: &Stages<'_>,
    first: usize,
) -> Vec<u16> {
    let g = lattice.grid();
    let (w, h) = (g.width(), g.height());
    let top = lattice.scheme().cells_at(lattice.align_zoom());
    let height = |x: u64, y: u64| lattice.height_at(x, y);
    let [ox, oy] = lattice.origin();
    let region = [ox, oy, ox + w as u64 - 1, oy + h as u64 - 1];
    let floor = rules
        .iter()
        .map(ZoomRules::min_floor)
        .min()
        .unwrap_or(u16::MAX);
    let surface = |x: f64, y: f64| lattice.unit_surface_at(x, y);
    let relevant = Relevant::new(samples, region, top, f64::from(decode(floor)), &surface);
    stages.finish(first);
    let lattice_m = |m: Pt| {
        let (x, y) = (u64::from(m[0]), u64::from(m[1]));
        if x < region[0] || x > region[2] || y < region[1] || y > region[3] {
            return f64::INFINITY;
        }
        f64::from(tree.error_bound_m((y - oy) as usize * w + (x - ox) as usize))
    };
    let skip = Skip {
        relevant: &relevant,
        lattice_m: &lattice_m,
        floor,
    };
    let own = own_errors(
        samples,
        lattice.origin(),
        [w, h],
        [2, top],
        BY_SAMPLE_BELOW.min(u64::from(lattice.scheme().tile_cells)),
        &height,
        Some(&skip),
        &stages.stage(first + 1),
    );
    stages.finish(first + 1);
    let closed = source_closure(tree.hierarchy(), &own);
    stages.finish(first + 2);
    closed
}

/// The relative times of preparing ([`Prepared::new_with_progress`]): the
/// statistics and the plan, the window's bitree, the coarse levels, the
/// squares whose source errors matter, the source errors, their closure
/// (measured on an SRTM 1" tile).
const PREPARE_WEIGHTS: [usize; 6] = [6, 13, 31, 8, 37, 5];

/// The addresses of the lattice tiles of `r` at zoom `z`
/// ([`GeographicScheme::address`]): `r` itself, or, on a lattice counted
/// from 0°, its parts east and west of the antimeridian, each moved by half
/// the world (two rectangles where `r` crosses it, west to east).
pub fn addressed(s: &GeographicScheme, z: u8, r: TileRange) -> Vec<TileRange> {
    if !s.from_greenwich {
        return vec![r];
    }
    let half = 1u32 << z;
    let parts = [(r.x0.max(half), r.x1), (r.x0, r.x1.min(half - 1))];
    parts
        .into_iter()
        .filter(|(a, b)| a <= b)
        .map(|(a, b)| TileRange {
            x0: a ^ half,
            x1: b ^ half,
            ..r
        })
        .collect()
}

/// The tiles of `range` for which `made(x, y)` holds, as rectangles: runs
/// along each row, merged with the row below when they span the same
/// columns.
pub(crate) fn covered_runs(range: TileRange, made: impl Fn(u32, u32) -> bool) -> Vec<TileRange> {
    let mut out: Vec<TileRange> = Vec::new();
    for y in range.y0..=range.y1 {
        let mut x = range.x0;
        while x <= range.x1 {
            if !made(x, y) {
                x += 1;
                continue;
            }
            let start = x;
            while x < range.x1 && made(x + 1, y) {
                x += 1;
            }
            let run = TileRange {
                x0: start,
                x1: x,
                y0: y,
                y1: y,
            };
            match out
                .iter_mut()
                .find(|r| r.y1 + 1 == y && r.x0 == start && r.x1 == x)
            {
                Some(r) => r.y1 = y,
                None => out.push(run),
            }
            x += 1;
        }
    }
    out
}

/// The leaves under the square with north-west corner `o` and side `cells`,
/// depth-first, splitting where `splits` says.
pub(crate) fn walk_leaves(o: [u64; 2], cells: u64, splits: impl Fn(&Tri) -> bool) -> Vec<Tri> {
    let (x0, y0, s) = (o[0] as u32, o[1] as u32, cells as u32);
    let (nw, ne, sw, se) = ([x0, y0], [x0 + s, y0], [x0, y0 + s], [x0 + s, y0 + s]);
    let even = (u64::from(x0) / cells + u64::from(y0) / cells).is_multiple_of(2);
    let roots = square_halves([nw, ne, sw, se], even);
    let mut stack: Vec<Tri> = roots.iter().rev().copied().collect();
    let mut out = Vec::new();
    while let Some(t) = stack.pop() {
        if !t.is_unit() && splits(&t) {
            let (c0, c1) = t.children();
            stack.push(c1);
            stack.push(c0);
        } else {
            out.push(t);
        }
    }
    out
}

/// The leaves as a mesh in the coordinates of the tile whose north-west
/// corner is `o`, vertices in first-use order, heights from `height`.
pub(crate) fn mesh_of_leaves(
    leaves: &[Tri],
    o: [u64; 2],
    height: impl Fn(u64, u64) -> f32,
) -> Mesh {
    let mut ids: HashMap<Pt, u32> =
        HashMap::with_capacity_and_hasher(leaves.len(), Default::default());
    let mut mesh = Mesh {
        vertices: Vec::with_capacity(leaves.len() / 2 + 4),
        triangles: Vec::with_capacity(leaves.len()),
    };
    for t in leaves {
        let mut tri = [t.a, t.b, t.c];
        if orient_up(tri[0], tri[1], tri[2]) < 0 {
            tri.swap(1, 2);
        }
        let idx = tri.map(|p| {
            *ids.entry(p).or_insert_with(|| {
                mesh.vertices.push(MeshVertex {
                    col: (u64::from(p[0]) - o[0]) as u32,
                    row: (u64::from(p[1]) - o[1]) as u32,
                    z_m: height(u64::from(p[0]), u64::from(p[1])),
                });
                (mesh.vertices.len() - 1) as u32
            })
        });
        mesh.triangles.push(idx);
    }
    mesh
}

/// The normal of the ellipsoid in east, north, up components.
pub(crate) const UP: [f32; 3] = [0.0, 0.0, 1.0];

/// Whether global lattice `(x, y)` lies in `window` (inclusive).
#[inline]
pub(crate) fn in_window(w: [u64; 4], x: u64, y: u64) -> bool {
    (w[0]..=w[2]).contains(&x) && (w[1]..=w[3]).contains(&y)
}

/// How far (lattice cells) a vertex normal looks on each side: `T_z / 64`
/// for a tile of `T_z` cells, at least 1 and at most this, so that a shard
/// holding its part plus this margin computes the normals of its vertices
/// for every zoom (see [`super::partial`]).
pub const NORMAL_REACH_CELLS: u64 = 256;

/// The unit normal (east, north, up) at global lattice position `(x, y)` for
/// a tile of `cells` cells: the lattice's slope from `height` over
/// `k = clamp(cells / 64, 1, NORMAL_REACH_CELLS)` cells on each side of the
/// vertex (clamped to the world), so two tiles that share a vertex give it
/// the same normal.
pub(crate) fn normal_at(
    s: &GeographicScheme,
    height: impl Fn(u64, u64) -> f32,
    x: u64,
    y: u64,
    cells: u64,
) -> [f32; 3] {
    let k = (cells / 64).clamp(1, NORMAL_REACH_CELLS);
    let (wmax, hmax) = (2 * s.root_cells(), s.root_cells());
    let d = s.cell_deg();
    let h = |x: u64, y: u64| f64::from(height(x, y));
    let (xa, xb) = (x.saturating_sub(k), (x + k).min(wmax));
    let (ya, yb) = (y.saturating_sub(k), (y + k).min(hmax));
    let [mx, my] = metres_per_degree(s.lat_of(y as f64));
    let dx = (h(xb, y) - h(xa, y)) / (((xb - xa) as f64) * d * mx).max(1e-9);
    // Rows run south: the slope to the north is minus the slope down the rows.
    let dn = -(h(x, yb) - h(x, ya)) / (((yb - ya) as f64) * d * my).max(1e-9);
    let n = [-dx, -dn, 1.0];
    let len = (n[0] * n[0] + n[1] * n[1] + 1.0).sqrt();
    n.map(|c| (c / len) as f32)
}

/// Whether the lattice sample `(x, y)` of height `h_m` is water in a water
/// mask: at or below 0 m (sea level in SRTM), and in the data (its
/// footprint and the cell beyond its edge). Beyond the data the terrain is
/// the ellipsoid's 0 m, but nothing says it is sea: land.
#[inline]
pub(crate) fn is_wet(f: &super::lattice::LatticeFrame, x: u64, y: u64, h_m: f32) -> bool {
    let [w, n, e, s] = f.footprint;
    let (x, y) = (x as f64, y as f64);
    h_m <= 0.0 && x >= w - 1.0 && x <= e + 1.0 && y >= n - 1.0 && y <= s + 1.0
}

/// The global lattice position of water-mask sample `(i, j)` (0..256) of
/// the tile with north-west corner `o` and side `cells`.
#[inline]
pub(crate) fn water_sample(o: [u64; 2], cells: u64, i: u64, j: u64) -> [u64; 2] {
    [
        o[0] + (i * cells + 127) / 255,
        o[1] + (j * cells + 127) / 255,
    ]
}

/// The water mask of the tile with north-west corner `o` and side `cells`:
/// 256×256 nearest lattice samples, `wet(index, x, y)` for each.
pub(crate) fn water_of(
    o: [u64; 2],
    cells: u64,
    wet: impl Fn(usize, u64, u64) -> bool,
) -> WaterMask {
    let mut grid = Vec::with_capacity(256 * 256);
    for j in 0..256u64 {
        for i in 0..256u64 {
            let [x, y] = water_sample(o, cells, i, j);
            grid.push(if wet(grid.len(), x, y) { 255u8 } else { 0 });
        }
    }
    match grid.first() {
        Some(&v) if grid.iter().all(|&g| g == v) => WaterMask::Uniform(v),
        _ => WaterMask::Grid(grid),
    }
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn addresses_of_a_range_across_the_antimeridian_are_two_ranges() {
        let mut s = GeographicScheme {
            max_zoom: 3,
            tile_cells: 4,
            from_greenwich: true,
        };
        // Zoom 3: 16 columns; lattice columns 6..9 straddle 180° (8).
        let r = TileRange {
            x0: 6,
            x1: 9,
            y0: 1,
            y1: 2,
        };
        let range = |x0, x1| TileRange { x0, x1, ..r };
        assert_eq!(addressed(&s, 3, r), vec![range(0, 1), range(14, 15)]);
        assert_eq!(addressed(&s, 3, range(9, 12)), vec![range(1, 4)]);
        s.from_greenwich = false;
        assert_eq!(addressed(&s, 3, r), vec![r]);
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
#[path = "cut_fill_tests.rs"]
mod fill_tests;
