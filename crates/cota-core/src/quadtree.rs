//! The restricted quadtree triangulation: the baseline the bitree is compared
//! against.
//!
//! Pajarola 1998, "Large scale terrain visualization using the restricted
//! quadtree triangulation", as described in paper `000_ebf7e3a88dffd361.txt` §2.2
//! (figures 5–7: vertex dependencies; adjacent blocks differ by at most one
//! level) and used by papers `002_9d6c1367b8962b6c.txt`,
//! `003_3a32b63e0cff3a64.txt` and `004_ab8d08b3e6a5a70a.txt`.
//!
//! # Geometry: any W×H grid
//! The same virtual padding as the bitree ([`crate::hierarchy`]): the root block
//! is the square of side `N = 2^k ≥ max(W−1, H−1)` with the grid in its
//! north-west corner. A block of depth `d` has side `s = N >> d`; block `(i, j)`
//! has its north-west corner at sample `(i·s, j·s)`. A block is *inside* when
//! its whole square lies in `[0, W−1] × [0, H−1]`, *outside* when it misses the
//! rectangle's interior (never created), *straddling* otherwise (always split).
//! Only inside blocks become leaves, so every vertex is a sample and the mesh
//! covers exactly the grid's extent.
//!
//! # Overview
//! 1. **Build** ([`QuadTree::build`], once): for every inside block of side
//!    `s ≥ 2` and each of its 4 sides, the exact error of the side's fan piece
//!    without the side's midpoint (triangle corner–corner–centre) and with it
//!    (two triangles). The error of a leaf under any of the 16 templates
//!    ([`crate::quadtree_templates`]) is then the maximum of 4 of these 8
//!    numbers: **exact** for the template the leaf really has, no worst case.
//!    Errors are the largest `|plane − h|` over every sample in or on a piece
//!    ([`crate::mesh::raster::max_deviation`]), rounded up to
//!    `f32`.
//! 2. **Refine** ([`QuadTree::refine`], per criterion): top-down from the root,
//!    coarse levels first. A leaf is split when it straddles the border or when
//!    the [`Criterion`] wants it, given the leaf's *current* template (the
//!    midpoints of the sides whose same-size neighbour is split).
//! 3. **Restriction**: before a block of depth `d` splits, its 4 edge
//!    neighbours of depth `d` must exist; a missing one is created by splitting
//!    its parent (a *forced* split), recursively. Hence adjacent leaves differ by
//!    at most one level.
//! 4. A split changes its neighbours' templates, so those leaves are evaluated
//!    again. Splits are never undone, so this terminates, and at the end every
//!    leaf has been judged with its final template: with
//!    [`crate::MaxVerticalError`] every leaf's exact error is within the bound.
//! 5. **Emit**: each leaf by its template (4 to 8 triangles around the centre,
//!    counter-clockwise seen from above); unit blocks (side 1, only along a
//!    border whose length is odd) as two triangles with the diagonal through
//!    their parent's centre. With [`QuadOptions::centre_when_needed`], a leaf
//!    with no finer neighbour whose two halves satisfy the criterion is
//!    emitted as those 2 triangles (no centre): Pajarola's blocks whose centre
//!    is not selected. Its sides are whole on both sides, so conformity holds.
//!
//! The result is a valid restricted quadtree meeting the criterion at every
//! leaf. It is greedy (a leaf judged with fewer midpoints than it ends up with
//! may split where the final template would have sufficed), like Pajarola's
//! vertex-selection; it is not claimed to be the smallest such mesh.
//!
//! # Selected and added points
//! [`QuadExtraction::points`] counts by splits, for any criterion (the
//! point-level definition shared with the bitree, for the max-error criterion,
//! is [`crate::Bitree::point_counts`], see [`crate::bitree::points`]). A split of a
//! block introduces its 4 side midpoints and the centres of its 4 children
//! (children of side 1 have none). A mesh vertex is
//! * **base**: a corner or the centre of the root block (present before any split);
//! * **selected**: introduced by at least one split the criterion wanted;
//! * **added**: introduced only by forced splits (the restriction, or a block
//!   straddling the grid's border), paper 000's "puntos agregados".
//!
//! # Runtime
//! Build: `O(n log n)`, each level touching every sample about twice, in
//! parallel over rows of blocks. Refine: proportional to the number of blocks
//! created. Memory: 32 bytes per block of side ≥ 2 (about `n·11/3` bytes).

use rayon::prelude::*;

use crate::bitree::round_up_f32;
use crate::bitree::PointCounts;
use crate::criteria::{Criterion, Element, MaxVerticalError};
use crate::error::MeshError;
use crate::grid::HeightGrid;
use crate::hierarchy::{orient_up, Hierarchy, Pt};
use crate::mesh::raster::max_deviation;
use crate::mesh::{Mesh, MeshVertex};
use crate::quadtree_templates::{side_pieces, template};

/// Options for [`QuadTree::refine_with`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub struct QuadOptions {
    /// Emit a leaf without finer neighbours as its 2 halves (cut along the
    /// bitree's diagonal for that square) when the criterion accepts them, so
    /// its centre is not a vertex: Pajarola 1998's blocks whose centre is not
    /// selected. Default: false (every leaf is a fan around its centre, the
    /// templates of papers 002–004).
    pub centre_when_needed: bool,
}

impl QuadOptions {
    /// The defaults: every leaf uses its centre.
    pub const DEFAULT: QuadOptions = QuadOptions {
        centre_when_needed: false,
    };

    /// Sets [`QuadOptions::centre_when_needed`].
    pub const fn with_centre_when_needed(mut self, yes: bool) -> Self {
        self.centre_when_needed = yes;
        self
    }
}

/// A block of the restricted quadtree that is a leaf of the mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Leaf {
    /// Depth, 0 at the root.
    pub depth: u32,
    /// Side in grid cells (a power of two).
    pub size: u32,
    /// Column of the north-west corner.
    pub col: u32,
    /// Row of the north-west corner.
    pub row: u32,
    /// The template: which sides carry their midpoint
    /// ([`crate::quadtree_templates::NORTH`] etc.); 0 for unit blocks.
    pub mask: u8,
    /// True when emitted as 2 halves without its centre
    /// ([`QuadOptions::centre_when_needed`], and unit blocks).
    pub halves: bool,
}

/// A restricted-quadtree mesh and its accounting.
#[derive(Debug, Clone)]
pub struct QuadExtraction {
    /// The mesh (vertices on samples, triangles counter-clockwise from above).
    pub mesh: Mesh,
    /// Base, selected and added points by splits (see the module docs).
    pub points: PointCounts,
    /// The leaves.
    pub leaves: Vec<Leaf>,
    /// Splits the criterion wanted.
    pub wanted_splits: usize,
    /// Splits forced by the restriction or by the grid's border.
    pub forced_splits: usize,
    /// The largest exact leaf error (final templates), metres: an upper bound of
    /// the mesh's error at every sample.
    pub max_leaf_error_m: f64,
}

/// Per-level data: block counts and the 8 side errors of every block.
#[derive(Debug, Clone)]
struct Level {
    size: u32,
    cols: u32,
    rows: u32,
    /// `[side·2 + with_midpoint]`, metres rounded up; `+∞` for straddling
    /// blocks; empty for unit blocks.
    side_err: Vec<[f32; 8]>,
}

/// A restricted quadtree with exact per-side errors, ready for refinement.
///
/// ```
/// use cota_core::{check_mesh, CheckOptions, GeoRef, HeightGrid};
/// use cota_core::quadtree::QuadTree;
/// let (w, h) = (33, 20);
/// let heights: Vec<f32> = (0..w * h)
///     .map(|i| ((i % w) as f32 * 0.4).sin() * 30.0 + (i / w) as f32)
///     .collect();
/// let grid = HeightGrid::new(w, h, heights, GeoRef::unreferenced(30.0)).unwrap();
/// let qt = QuadTree::build(&grid).unwrap();
/// let x = qt.extract_max_error_m(2.0).unwrap();
/// check_mesh(&grid, &x.mesh, &CheckOptions::conforming(2.0)).unwrap();
/// ```
#[derive(Debug, Clone)]
pub struct QuadTree<'g> {
    grid: &'g HeightGrid,
    hier: Hierarchy,
    levels: Vec<Level>,
}

const ABSENT: u8 = 0;
const LEAF: u8 = 1;
const FORCED: u8 = 2;
const WANTED: u8 = 3;

/// Side neighbours in [`crate::quadtree_templates::SIDES`] order: north, east, south, west.
const NEIGHBOURS: [(i64, i64); 4] = [(0, -1), (1, 0), (0, 1), (-1, 0)];

impl<'g> QuadTree<'g> {
    /// Computes the side errors of every inside block of `grid`.
    ///
    /// # Errors
    /// [`MeshError::GridTooSmall`], [`MeshError::GridTooLarge`], or
    /// [`MeshError::Voids`] when a sample is NaN (fill voids first).
    pub fn build(grid: &'g HeightGrid) -> Result<Self, MeshError> {
        let hier = crate::error::hierarchy_for(grid)?;
        let mut levels = Vec::new();
        let mut size = hier.size();
        loop {
            let cols = (hier.width() - 1).div_ceil(size);
            let rows = (hier.height() - 1).div_ceil(size);
            let side_err = if size >= 2 {
                (0..rows)
                    .into_par_iter()
                    .flat_map_iter(|j| {
                        (0..cols).map(move |i| block_side_errors(grid, &hier, size, i, j))
                    })
                    .collect()
            } else {
                Vec::new()
            };
            levels.push(Level {
                size,
                cols,
                rows,
                side_err,
            });
            if size == 1 {
                break;
            }
            size /= 2;
        }
        Ok(QuadTree { grid, hier, levels })
    }

    /// The grid this tree was built on.
    pub fn grid(&self) -> &'g HeightGrid {
        self.grid
    }

    /// The padded hierarchy's shape (shared with the bitree).
    pub fn hierarchy(&self) -> &Hierarchy {
        &self.hier
    }

    /// The mesh whose every leaf has an exact error of at most `max_error_m`
    /// metres ([`MaxVerticalError`]).
    ///
    /// # Errors
    /// [`MeshError::BadMaxError`] for a negative or NaN bound.
    pub fn extract_max_error_m(&self, max_error_m: f64) -> Result<QuadExtraction, MeshError> {
        if max_error_m.is_nan() || max_error_m < 0.0 {
            return Err(MeshError::BadMaxError(max_error_m));
        }
        Ok(self.refine(&MaxVerticalError { max_error_m }))
    }

    /// Refines by `criterion` under the restriction (see the module docs).
    ///
    /// The criterion sees each leaf's 4 corners (NW, NE, SE, SW), its depth and
    /// its exact error under its current template.
    pub fn refine(&self, criterion: &dyn Criterion) -> QuadExtraction {
        self.refine_with(criterion, &QuadOptions::DEFAULT)
    }

    /// [`QuadTree::refine`] with options.
    pub fn refine_with(&self, criterion: &dyn Criterion, opts: &QuadOptions) -> QuadExtraction {
        let mut r = Refiner {
            tree: self,
            criterion,
            state: self
                .levels
                .iter()
                .map(|l| vec![ABSENT; (l.cols * l.rows) as usize])
                .collect(),
            pending: vec![Vec::new(); self.levels.len()],
        };
        r.state[0][0] = LEAF;
        r.pending[0].push((0, 0));
        r.run();
        r.finish(opts)
    }

    fn inside(&self, d: usize, i: u32, j: u32) -> bool {
        let s = self.levels[d].size as u64;
        (i as u64 + 1) * s < self.hier.width() as u64
            && (j as u64 + 1) * s < self.hier.height() as u64
    }

    fn in_range(&self, d: usize, i: i64, j: i64) -> Option<(u32, u32)> {
        let l = &self.levels[d];
        (i >= 0 && j >= 0 && i < l.cols as i64 && j < l.rows as i64).then_some((i as u32, j as u32))
    }
}

/// The 8 side errors of block `(i, j)` of side `size` (`+∞` when it straddles).
fn block_side_errors(grid: &HeightGrid, hier: &Hierarchy, size: u32, i: u32, j: u32) -> [f32; 8] {
    let (x0, y0) = (i as u64 * size as u64, j as u64 * size as u64);
    if x0 + size as u64 >= hier.width() as u64 || y0 + size as u64 >= hier.height() as u64 {
        return [f32::INFINITY; 8];
    }
    let half = size / 2;
    let at = |p: Pt| [i * size + p[0] * half, j * size + p[1] * half];
    let mut out = [0f32; 8];
    for side in 0..4 {
        for with_mid in [false, true] {
            let (a, b) = side_pieces(side, with_mid);
            let mut e = piece_error(grid, a.map(at));
            if let Some(b) = b {
                e = e.max(piece_error(grid, b.map(at)));
            }
            out[side * 2 + usize::from(with_mid)] = round_up_f32(e);
        }
    }
    out
}

/// Largest |plane − h| over the samples in or on triangle `t` (grid
/// positions), the plane through its corners' sample heights.
fn piece_error(grid: &HeightGrid, t: [Pt; 3]) -> f64 {
    max_deviation(
        grid,
        t,
        t.map(|p| grid.get(p[0] as usize, p[1] as usize) as f64),
    )
}

/// What a leaf should do.
enum Decision {
    Keep,
    Split { wanted: bool },
}

/// The refinement's working state.
struct Refiner<'a, 'g> {
    tree: &'a QuadTree<'g>,
    criterion: &'a dyn Criterion,
    /// Per depth, per block: `ABSENT`, `LEAF`, `FORCED` or `WANTED`.
    state: Vec<Vec<u8>>,
    /// Per depth: leaves to (re)evaluate.
    pending: Vec<Vec<(u32, u32)>>,
}

impl Refiner<'_, '_> {
    fn idx(&self, d: usize, i: u32, j: u32) -> usize {
        (j * self.tree.levels[d].cols + i) as usize
    }

    fn get(&self, d: usize, i: u32, j: u32) -> u8 {
        self.state[d][self.idx(d, i, j)]
    }

    fn set(&mut self, d: usize, i: u32, j: u32, v: u8) {
        let k = self.idx(d, i, j);
        self.state[d][k] = v;
    }

    /// The same-depth neighbours in [`crate::quadtree_templates::SIDES`] order (`None` off the grid).
    fn neighbours(&self, d: usize, i: u32, j: u32) -> [Option<(u32, u32)>; 4] {
        NEIGHBOURS.map(|(di, dj)| self.tree.in_range(d, i as i64 + di, j as i64 + dj))
    }

    /// The template mask of block `(i, j)`: sides whose neighbour is split.
    fn mask(&self, d: usize, i: u32, j: u32) -> u8 {
        let mut m = 0;
        for (side, n) in self.neighbours(d, i, j).into_iter().enumerate() {
            if let Some((ni, nj)) = n {
                if self.get(d, ni, nj) >= FORCED {
                    m |= 1 << side;
                }
            }
        }
        m
    }

    /// Exact error of the inside block `(i, j)` under template `mask`.
    fn leaf_error(&self, d: usize, i: u32, j: u32, mask: u8) -> f64 {
        let l = &self.tree.levels[d];
        let Some(e) = l.side_err.get(self.idx(d, i, j)) else {
            return 0.0;
        };
        (0..4)
            .map(|side| e[side * 2 + usize::from(mask & (1 << side) != 0)] as f64)
            .fold(0.0, f64::max)
    }

    /// The corners (NW, NE, SE, SW) of block `(i, j)` of side `s`, with heights.
    fn corners(&self, s: u32, i: u32, j: u32) -> [[f64; 3]; 4] {
        let grid = self.tree.grid;
        let corner = |x: u32, y: u32| [x as f64, y as f64, grid.get(x as usize, y as usize) as f64];
        let (x0, y0) = (i * s, j * s);
        [
            corner(x0, y0),
            corner(x0 + s, y0),
            corner(x0 + s, y0 + s),
            corner(x0, y0 + s),
        ]
    }

    /// The two halves of the inside block `(i, j)` (cut along `\` when `i + j`
    /// is even, `/` when odd, as the bitree) and their exact error, when the
    /// criterion accepts them.
    fn halves_if_accepted(&self, d: usize, i: u32, j: u32) -> Option<([[Pt; 3]; 2], f64)> {
        let s = self.tree.levels[d].size;
        let (x0, y0) = (i * s, j * s);
        let (nw, ne, se, sw) = ([x0, y0], [x0 + s, y0], [x0 + s, y0 + s], [x0, y0 + s]);
        let halves = if (i + j).is_multiple_of(2) {
            [[nw, se, ne], [se, nw, sw]]
        } else {
            [[ne, sw, se], [sw, ne, nw]]
        };
        let e = halves
            .iter()
            .map(|&t| round_up_f32(piece_error(self.tree.grid, t)) as f64)
            .fold(0.0, f64::max);
        let corners = self.corners(s, i, j);
        let el = Element {
            corners: &corners,
            depth: d as u32,
            vertical_error_m: e,
            grid: self.tree.grid,
        };
        (!self.criterion.wants_split(&el)).then_some((halves, e))
    }

    fn decide(&self, d: usize, i: u32, j: u32) -> Decision {
        let tree = self.tree;
        let s = tree.levels[d].size;
        if s == 1 {
            return Decision::Keep;
        }
        if !tree.inside(d, i, j) {
            return Decision::Split { wanted: false };
        }
        let corners = self.corners(s, i, j);
        let e = Element {
            corners: &corners,
            depth: d as u32,
            vertical_error_m: self.leaf_error(d, i, j, self.mask(d, i, j)),
            grid: tree.grid,
        };
        if self.criterion.wants_split(&e) {
            Decision::Split { wanted: true }
        } else {
            Decision::Keep
        }
    }

    fn run(&mut self) {
        while let Some(d) = self.pending.iter().position(|p| !p.is_empty()) {
            let Some((i, j)) = self.pending[d].pop() else {
                continue;
            };
            if self.get(d, i, j) != LEAF {
                continue;
            }
            if let Decision::Split { wanted } = self.decide(d, i, j) {
                self.split(d, i, j, wanted);
            }
        }
    }

    /// Splits the leaf `(i, j)` of depth `d`, first forcing its same-depth
    /// neighbours into existence (the restriction).
    fn split(&mut self, d: usize, i: u32, j: u32, wanted: bool) {
        let ns = self.neighbours(d, i, j);
        for &(ni, nj) in ns.iter().flatten() {
            self.ensure_exists(d, ni, nj);
        }
        self.set(d, i, j, if wanted { WANTED } else { FORCED });
        if d + 1 < self.state.len() {
            for (a, b) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                if let Some((ci, cj)) =
                    self.tree
                        .in_range(d + 1, 2 * i as i64 + a, 2 * j as i64 + b)
                {
                    self.set(d + 1, ci, cj, LEAF);
                    self.pending[d + 1].push((ci, cj));
                }
            }
        }
        // The neighbours' templates changed: judge them again.
        for &(ni, nj) in ns.iter().flatten() {
            if self.get(d, ni, nj) == LEAF {
                self.pending[d].push((ni, nj));
            }
        }
    }

    /// Makes block `(i, j)` of depth `d` exist by splitting its ancestors.
    fn ensure_exists(&mut self, d: usize, i: u32, j: u32) {
        if d == 0 || self.get(d, i, j) != ABSENT {
            return;
        }
        let (pi, pj) = (i / 2, j / 2);
        self.ensure_exists(d - 1, pi, pj);
        if self.get(d - 1, pi, pj) == LEAF {
            let wanted = matches!(self.decide(d - 1, pi, pj), Decision::Split { wanted: true });
            self.split(d - 1, pi, pj, wanted);
        }
    }

    /// Emits the leaves and counts the points.
    fn finish(self, opts: &QuadOptions) -> QuadExtraction {
        let tree = self.tree;
        let (w, h) = (tree.hier.width(), tree.hier.height());
        let sample = |x: u32, y: u32| y as usize * w as usize + x as usize;
        let mut tris: Vec<[u32; 3]> = Vec::new();
        let mut leaves = Vec::new();
        let mut max_leaf = 0f64;
        let (mut wanted_splits, mut forced_splits) = (0, 0);
        // 0: not introduced by a split, 1: added, 2: selected.
        let mut class = vec![0u8; w as usize * h as usize];
        for (d, level) in tree.levels.iter().enumerate() {
            let s = level.size;
            for j in 0..level.rows {
                for i in 0..level.cols {
                    let st = self.get(d, i, j);
                    let (x0, y0) = (i * s, j * s);
                    if st >= FORCED {
                        let c = if st == WANTED {
                            wanted_splits += 1;
                            2
                        } else {
                            forced_splits += 1;
                            1
                        };
                        let (hs, q) = (s / 2, s / 4);
                        let mut pts = vec![
                            [x0 + hs, y0],
                            [x0 + s, y0 + hs],
                            [x0 + hs, y0 + s],
                            [x0, y0 + hs],
                        ];
                        if q > 0 {
                            for (a, b) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                                pts.push([x0 + q + a * hs, y0 + q + b * hs]);
                            }
                        }
                        for [x, y] in pts {
                            if x < w && y < h {
                                let k = sample(x, y);
                                class[k] = class[k].max(c);
                            }
                        }
                    } else if st == LEAF && tree.inside(d, i, j) {
                        if s == 1 {
                            let (cx, cy) = (i | 1, j | 1);
                            let (ox, oy) = (
                                if cx == i { i + 1 } else { i },
                                if cy == j { j + 1 } else { j },
                            );
                            for k in [[ox, cy], [cx, oy]] {
                                push_ccw(&mut tris, sample, [[cx, cy], [ox, oy], k]);
                            }
                            leaves.push(Leaf {
                                depth: d as u32,
                                size: 1,
                                col: i,
                                row: j,
                                mask: 0,
                                halves: true,
                            });
                            continue;
                        }
                        let mask = self.mask(d, i, j);
                        if mask == 0 && opts.centre_when_needed {
                            if let Some((halves, e)) = self.halves_if_accepted(d, i, j) {
                                max_leaf = max_leaf.max(e);
                                for t in halves {
                                    push_ccw(&mut tris, sample, t);
                                }
                                leaves.push(Leaf {
                                    depth: d as u32,
                                    size: s,
                                    col: x0,
                                    row: y0,
                                    mask,
                                    halves: true,
                                });
                                continue;
                            }
                        }
                        max_leaf = max_leaf.max(self.leaf_error(d, i, j, mask));
                        let half = s / 2;
                        for t in template(mask).triangles() {
                            push_ccw(
                                &mut tris,
                                sample,
                                t.map(|p| [x0 + p[0] * half, y0 + p[1] * half]),
                            );
                        }
                        leaves.push(Leaf {
                            depth: d as u32,
                            size: s,
                            col: x0,
                            row: y0,
                            mask,
                            halves: false,
                        });
                    }
                }
            }
        }
        let mesh = compact(tree.grid, tris);
        let mut points = PointCounts {
            vertices: mesh.vertex_count(),
            triangles: mesh.triangle_count(),
            ..PointCounts::default()
        };
        for v in &mesh.vertices {
            match class[sample(v.col, v.row)] {
                2 => points.selected += 1,
                1 => points.added += 1,
                _ => points.base += 1,
            }
        }
        QuadExtraction {
            mesh,
            points,
            leaves,
            wanted_splits,
            forced_splits,
            max_leaf_error_m: max_leaf,
        }
    }
}

/// Pushes triangle `t` (grid positions) as sample indices, counter-clockwise.
fn push_ccw(tris: &mut Vec<[u32; 3]>, sample: impl Fn(u32, u32) -> usize, t: [Pt; 3]) {
    let t = if orient_up(t[0], t[1], t[2]) < 0 {
        [t[1], t[0], t[2]]
    } else {
        t
    };
    tris.push(t.map(|p| sample(p[0], p[1]) as u32));
}

/// Numbers the used samples row-major and rewrites the triangles.
fn compact(grid: &HeightGrid, mut tris: Vec<[u32; 3]>) -> Mesh {
    let mut used: Vec<u32> = tris.iter().flatten().copied().collect();
    used.sort_unstable();
    used.dedup();
    let w = grid.width() as u32;
    let heights = grid.heights();
    let vertices = used
        .iter()
        .map(|&i| MeshVertex {
            col: i % w,
            row: i / w,
            z_m: heights[i as usize],
        })
        .collect();
    for t in &mut tris {
        for i in t.iter_mut() {
            *i = used.partition_point(|&u| u < *i) as u32;
        }
    }
    Mesh {
        vertices,
        triangles: tris,
    }
}
