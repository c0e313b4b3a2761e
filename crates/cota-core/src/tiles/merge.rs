//! The reducer of a sharded pyramid: the shards' partial maxima
//! ([`super::partial`]) merged into the errors of the coarse split points,
//! and the tiles coarser than the band zoom cut from them, exactly the tiles
//! one machine holding the whole lattice cuts ([`super::Prepared::cut`]).
//!
//! Paper `000_ebf7e3a88dffd361.txt` §2–3 (monotone errors, one decision per
//! split point) and paper `001_49f2c365e8c41172.txt` (one hierarchy over a
//! mosaic). Level by level from the band zoom's squares up:
//!
//! 1. up to the alignment zoom's squares (the window bitree's levels), a
//!    split point splits at a zoom's threshold when its own error (the
//!    maximum of the shards' maxima, rounded up to `f32` as the build rounds
//!    it) or one of its children's does, which is the bitree's exact
//!    decision; its 16-bit code is the maximum of its own error's code and
//!    its children's codes, as the bitree builds it;
//! 2. above them, the coarse levels of [`super::cap`] with the same own
//!    errors (the shards' maxima over the window, and the 0 m beyond from
//!    the corners' heights) and the same children's errors;
//! 3. a tile's walk reads those decisions above the band zoom's squares and
//!    the shards' fine split points below; its vertices' heights, normals
//!    and water-mask samples come from the shards and the band corners.

use rustc_hash::FxHashMap as HashMap;
use std::cell::Cell;
use std::sync::Mutex;

use super::cap::{own_rows, square_tris, t_heights, Cap};
use super::cut::rules_of;
use super::cut::{
    above_cap, addressed, in_window, mesh_of_leaves, walk_leaves, water_of, TileMesh, WaterMask, UP,
};
use super::drawn::{LevelRule, ZoomRules};
use super::error::TilesError;
use super::lattice::LatticeFrame;
use super::partial::{coarse_rules, key, BandCorners, CoarsePartial, WATER_UNKNOWN};
use super::plan::{children_in, LatticeStats, ZoomPlan};
use super::scheme::TileId;
use crate::bitree::error_code::{decode, encode_up};
use crate::bitree::round_up_f32;
use crate::hierarchy::{Pt, Tri};

/// The merged partial maxima of every shard, ready to cut the tiles coarser
/// than the band zoom.
#[derive(Debug)]
pub struct CoarseHierarchy {
    frame: LatticeFrame,
    zooms: Vec<ZoomPlan>,
    rules: Vec<(ZoomPlan, ZoomRules)>,
    band: u8,
    corners: BandCorners,
    /// Fine split points: bits, height.
    fine: HashMap<u64, (u32, f32)>,
    /// The band squares' centres and the window bitree's levels above:
    /// their 16-bit codes (the rules' thresholds are code values, so a code
    /// decides exactly, see [`super::drawn::DrawnBound::rules`]): the
    /// lattice error and the error against the source.
    coded: HashMap<u64, [u16; 2]>,
    cap: Cap,
    /// The fitted lattice's largest residual ([`super::cut::above_cap`]).
    residual_m: f64,
    normals: HashMap<(u64, u8), [f32; 3]>,
    water: HashMap<TileId, Vec<u8>>,
}

/// A shard's data is missing (a partial lost, or from another run).
fn incomplete(what: String) -> TilesError {
    TilesError::BadOptions(format!(
        "expected every shard's partial maxima, found {what} missing"
    ))
}

impl CoarseHierarchy {
    /// Merges `partials` (one per shard, any order) of the pyramid planned
    /// as `zooms` over `frame` (whole-lattice statistics `stats`), band zoom
    /// `band`, with the band `corners`.
    ///
    /// # Errors
    /// [`TilesError::BadOptions`] when a partial or a corner is missing.
    ///
    /// # Runtime
    /// Linear in the partials' size, plus `O(window / T_band²)` per coarse
    /// level and the cap's levels (beyond-window parts by row ends).
    pub fn new(
        frame: &LatticeFrame,
        stats: &LatticeStats,
        zooms: Vec<ZoomPlan>,
        band: u8,
        corners: BandCorners,
        partials: Vec<CoarsePartial>,
    ) -> Result<CoarseHierarchy, TilesError> {
        if corners.missing() > 0 {
            return Err(incomplete(format!(
                "{} band corner heights",
                corners.missing()
            )));
        }
        let (bound, _) = rules_of(&frame.scheme, frame.window, stats, &[]);
        let rules = coarse_rules(&zooms, band, &bound);
        let mut h = CoarseHierarchy {
            frame: frame.clone(),
            zooms,
            rules,
            band,
            corners,
            fine: HashMap::default(),
            coded: HashMap::default(),
            cap: Cap::default(),
            residual_m: stats.residual_m,
            normals: HashMap::default(),
            water: HashMap::default(),
        };
        let own = h.absorb(partials);
        h.bitree_levels(&own)?;
        let own = own.0;
        h.cap = h.cap_levels(&own)?;
        Ok(h)
    }

    /// Takes the shards' data in; returns the merged own errors (against
    /// the lattice, against the source).
    fn absorb(&mut self, partials: Vec<CoarsePartial>) -> (HashMap<u64, f32>, HashMap<u64, f32>) {
        let mut own: HashMap<u64, f32> = HashMap::default();
        let mut own_src: HashMap<u64, f32> = HashMap::default();
        let t = self.frame.scheme.cells_at(self.band);
        for p in partials {
            for f in p.fine {
                let centre = f.at.map(u64::from).map(|v| v % t == t / 2);
                if centre == [true, true] {
                    let slot = self.coded.entry(key(f.at)).or_insert([0; 2]);
                    *slot = [slot[0].max(f.code), slot[1].max(f.src)];
                }
                let slot = self.fine.entry(key(f.at)).or_insert((0, f.height_m));
                slot.0 |= f.splits;
            }
            for (m, e) in p.own {
                let slot = own.entry(key(m)).or_insert(0.0);
                *slot = slot.max(e);
            }
            for (m, e) in p.own_src {
                let slot = own_src.entry(key(m)).or_insert(0.0);
                *slot = slot.max(e);
            }
            for (m, z, n) in p.normals {
                self.normals.insert((key(m), z), n);
            }
            for (tile, grid) in p.water {
                match self.water.get_mut(&tile) {
                    None => {
                        self.water.insert(tile, grid);
                    }
                    Some(have) => {
                        for (a, b) in have.iter_mut().zip(grid) {
                            if *a == WATER_UNKNOWN {
                                *a = b;
                            }
                        }
                    }
                }
            }
        }
        (own, own_src)
    }

    /// The window bitree's levels above the band squares: their codes.
    fn bitree_levels(
        &mut self,
        own: &(HashMap<u64, f32>, HashMap<u64, f32>),
    ) -> Result<(), TilesError> {
        let s = self.frame.scheme;
        let t = s.cells_at(self.band);
        let top = s.cells_at(self.frame.align_zoom);
        let [x0, y0, x1, y1] = self.frame.window;
        let mut size = 2 * t;
        while size <= top {
            let squares: Vec<[u64; 2]> = (y0 / size..y1 / size)
                .flat_map(|j| (x0 / size..x1 / size).map(move |i| [i, j]))
                .collect();
            for &[i, j] in &squares {
                for tri in square_tris(i, j, size).0 {
                    self.join(own, &tri)?;
                }
            }
            for &[i, j] in &squares {
                for tri in square_tris(i, j, size).1 {
                    self.join(own, &tri)?;
                }
            }
            size *= 2;
        }
        Ok(())
    }

    /// Adds triangle `tri`'s own errors and its children's to its split
    /// point, as the bitree and `bitree::closure::source_closure` build
    /// them.
    fn join(
        &mut self,
        (own, own_src): &(HashMap<u64, f32>, HashMap<u64, f32>),
        tri: &Tri,
    ) -> Result<(), TilesError> {
        let m = key(tri.mid());
        let e = own.get(&m).copied().unwrap_or(0.0);
        let e_src = own_src.get(&m).copied().unwrap_or(0.0);
        let mut c = [encode_up(e), encode_up(e_src)];
        let (c0, c1) = tri.children();
        for q in [c0.mid(), c1.mid()] {
            let cc = self
                .coded
                .get(&key(q))
                .copied()
                .ok_or_else(|| incomplete(format!("the split point {q:?}")))?;
            c = [c[0].max(cc[0]), c[1].max(cc[1])];
        }
        let slot = self.coded.entry(m).or_insert([0; 2]);
        *slot = [slot[0].max(c[0]), slot[1].max(c[1])];
        Ok(())
    }

    /// The coarse levels above the window bitree's: the cap.
    fn cap_levels(&self, own: &HashMap<u64, f32>) -> Result<Cap, TilesError> {
        let s = self.frame.scheme;
        let top = s.cells_at(self.frame.align_zoom);
        let window = self.frame.window;
        let missing: Mutex<Option<Pt>> = Mutex::new(None);
        let corners = &self.corners;
        let own_of = |tri: &Tri| {
            let inside = own.get(&key(tri.mid())).copied().unwrap_or(0.0);
            let z = t_heights(tri, |x, y| corners.height(x, y).unwrap_or(0.0));
            inside.max(round_up_f32(own_rows(window, tri, z, true, None)))
        };
        let below = |m: Pt| {
            let [x, y] = m.map(u64::from);
            if x < window[0] || x > window[2] || y < window[1] || y > window[3] {
                return 0.0;
            }
            match self.coded.get(&key(m)) {
                Some(&c) => decode(c[0]),
                None => {
                    if let Ok(mut g) = missing.lock() {
                        *g = Some(m);
                    }
                    0.0
                }
            }
        };
        let cap = Cap::build_with(
            s.root_cells(),
            window,
            top,
            own_of,
            below,
            crate::progress::NONE,
        );
        let missing = missing.into_inner().unwrap_or(None);
        match missing {
            Some(m) => Err(incomplete(format!("the split point {m:?}"))),
            None => Ok(cap),
        }
    }

    /// The tiles this hierarchy cuts: every tile coarser than the band zoom
    /// (addresses, as [`super::Prepared::tiles`] gives them).
    pub fn tiles(&self) -> impl Iterator<Item = TileId> + '_ {
        let s = self.frame.scheme;
        self.rules.iter().flat_map(move |(p, _)| {
            let (r, z) = (p.range, p.zoom);
            (r.y0..=r.y1)
                .flat_map(move |y| (r.x0..=r.x1).map(move |x| s.address(TileId { z, x, y })))
        })
    }

    /// The band zoom.
    pub fn band_zoom(&self) -> u8 {
        self.band
    }

    /// Whether `tri` splits at the `i`-th coarse zoom, as
    /// [`super::Prepared`] decides it.
    fn splits(&self, tri: &Tri, i: usize) -> bool {
        let rule = match self.rules[i].1.of(tri, self.frame.window) {
            LevelRule::Always => return true,
            LevelRule::Above(rule) => rule,
        };
        let m = tri.mid();
        let size = tri.a[0].abs_diff(tri.b[0]).max(tri.a[1].abs_diff(tri.b[1]));
        let s = self.frame.scheme;
        if u64::from(size) > s.cells_at(self.frame.align_zoom) {
            return above_cap(self.cap.error(m), self.residual_m, &rule);
        }
        let [x0, y0, x1, y1] = self.frame.window;
        let (x, y) = (u64::from(m[0]), u64::from(m[1]));
        if x < x0 || x > x1 || y < y0 || y > y1 {
            return false;
        }
        if u64::from(size) > s.cells_at(self.band) {
            self.coded
                .get(&key(m))
                .is_some_and(|c| c[0] > rule.floor || c[1] > rule.floor)
        } else {
            self.fine.get(&key(m)).is_some_and(|f| f.0 & (1 << i) != 0)
        }
    }

    /// The height at a vertex: band corners, fine points, 0 m beyond.
    fn height(&self, x: u64, y: u64) -> Option<f32> {
        self.corners
            .height(x, y)
            .or_else(|| self.fine.get(&key([x as u32, y as u32])).map(|f| f.1))
    }

    /// Cuts tile `t` (an address, coarser than the band zoom), as
    /// [`super::Prepared::cut`] cuts it from the whole lattice.
    ///
    /// # Errors
    /// [`TilesError::NoSuchTile`] for a tile it does not cut,
    /// [`TilesError::BadOptions`] when a shard's data is missing.
    pub fn cut(&self, t: TileId, normals: bool, water: bool) -> Result<TileMesh, TilesError> {
        let s = self.frame.scheme;
        let lt = s.address(t);
        let (i, (plan, _)) = self
            .rules
            .iter()
            .enumerate()
            .find(|(_, (p, _))| p.zoom == t.z && p.range.contains(lt.x, lt.y))
            .ok_or(TilesError::NoSuchTile {
                tile: t,
                min_zoom: self.rules.first().map_or(0, |p| p.0.zoom),
                max_zoom: self.band.saturating_sub(1),
            })?;
        let (cells, o) = (s.cells_at(t.z), s.tile_origin(lt));
        let leaves = walk_leaves(o, cells, |tri| self.splits(tri, i));
        let missing: Cell<Option<[u64; 2]>> = Cell::new(None);
        let mesh = mesh_of_leaves(&leaves, o, |x, y| {
            self.height(x, y).unwrap_or_else(|| {
                missing.set(Some([x, y]));
                0.0
            })
        });
        if let Some(p) = missing.get() {
            return Err(incomplete(format!(
                "the height at lattice {p:?} of tile {t}"
            )));
        }
        let normals_enu = normals.then(|| self.normals(&mesh, o, t.z)).transpose()?;
        let water_mask = water.then(|| self.water(lt, o, cells)).transpose()?;
        Ok(TileMesh {
            tile: t,
            cells,
            rect_deg: s.tile_rect_deg(t),
            normals_enu,
            water_mask,
            mesh,
            max_error_m: plan.max_error_m,
            source_bound_m: plan.max_error_m.max(self.residual_m + plan.margin_m),
            threshold_m: plan.threshold_m,
            children: children_in(lt, self.zooms.iter().find(|p| p.zoom == t.z + 1))
                .map(|r| addressed(&s, t.z + 1, r))
                .unwrap_or_default(),
        })
    }

    /// The vertex normals: from the shards inside the window, straight up
    /// beyond it.
    fn normals(
        &self,
        mesh: &crate::mesh::Mesh,
        o: [u64; 2],
        z: u8,
    ) -> Result<Vec<[f32; 3]>, TilesError> {
        mesh.vertices
            .iter()
            .map(|v| {
                let (x, y) = (o[0] + u64::from(v.col), o[1] + u64::from(v.row));
                if !in_window(self.frame.window, x, y) {
                    return Ok(UP);
                }
                self.normals
                    .get(&(key([x as u32, y as u32]), z))
                    .copied()
                    .ok_or_else(|| {
                        incomplete(format!("the normal at lattice ({x}, {y}), zoom {z}"))
                    })
            })
            .collect()
    }

    /// The water mask of lattice tile `t`: the shards' samples, land
    /// beyond the window.
    fn water(&self, t: TileId, o: [u64; 2], cells: u64) -> Result<WaterMask, TilesError> {
        let [x0, y0, x1, y1] = self.frame.window;
        let grid = self.water.get(&t);
        let missing = Cell::new(false);
        let mask = water_of(o, cells, |k, x, y| {
            if x < x0 || x > x1 || y < y0 || y > y1 {
                return false;
            }
            match grid.map(|g| g[k]) {
                Some(v) if v != WATER_UNKNOWN => v == 255,
                _ => {
                    missing.set(true);
                    false
                }
            }
        });
        if missing.get() {
            return Err(incomplete(format!("water-mask samples of tile {t}")));
        }
        Ok(mask)
    }
}
