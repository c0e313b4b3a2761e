//! The restricted refinement: top-down from the root, a leaf splits when it
//! straddles the grid's border or the criterion wants it under its current
//! template, after forcing its same-size neighbours into existence; then
//! every leaf is emitted by its template (steps 2–5 of [`super`]; Pajarola
//! 1998, as described in paper `000_ebf7e3a88dffd361.txt` §2.2).

use super::templates::template;
use super::tree::{piece_error, QuadTree};
use super::{Leaf, QuadExtraction, QuadOptions};
use crate::bitree::error_code::{decode, INFINITE};
use crate::bitree::{round_up_f32, PointCounts};
use crate::criteria::{Criterion, Element, MaxVerticalError};
use crate::error::MeshError;
use crate::grid::HeightGrid;
use crate::hierarchy::{orient_up, Hierarchy, Pt};
use crate::mesh::{Mesh, MeshVertex};

impl QuadTree<'_> {
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
}

const ABSENT: u8 = 0;
const LEAF: u8 = 1;
const FORCED: u8 = 2;
const WANTED: u8 = 3;

/// Side neighbours in [`super::templates::SIDES`] order: north, east, south, west.
const NEIGHBOURS: [(i64, i64); 4] = [(0, -1), (1, 0), (0, 1), (-1, 0)];

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

    /// The same-depth neighbours in [`super::templates::SIDES`] order (`None` off the grid).
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

    /// The codes of the 4 side errors of block `(i, j)` under template
    /// `mask` (`None` for a unit block).
    fn side_codes(&self, d: usize, i: u32, j: u32, mask: u8) -> Option<[u16; 4]> {
        let e = self.tree.levels[d].side_err.get(self.idx(d, i, j))?;
        Some([0, 1, 2, 3].map(|side| e[side * 2 + usize::from(mask & (1 << side) != 0)]))
    }

    /// The code of the error of block `(i, j)` under template `mask`: an
    /// upper bound of [`Refiner::leaf_error`] within 0.4 % (0 for a unit
    /// block).
    fn leaf_code(&self, d: usize, i: u32, j: u32, mask: u8) -> u16 {
        self.side_codes(d, i, j, mask)
            .map_or(0, |c| c.into_iter().max().unwrap_or(0))
    }

    /// Exact error of the inside block `(i, j)` under template `mask`: the
    /// largest of its sides' errors, recomputed for the sides whose code is
    /// the largest (the codes keep the order, so the largest error is one
    /// of those).
    fn leaf_error(&self, d: usize, i: u32, j: u32, mask: u8) -> f64 {
        let Some(codes) = self.side_codes(d, i, j, mask) else {
            return 0.0;
        };
        let top = codes.into_iter().max().unwrap_or(0);
        if top == 0 || top >= INFINITE {
            return decode(top) as f64;
        }
        (0..4)
            .filter(|&side| codes[side] == top)
            .map(|side| {
                let with_mid = mask & (1 << side) != 0;
                self.tree.exact_side(d, i, j, side, with_mid) as f64
            })
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
        let mask = self.mask(d, i, j);
        // A pure vertical bound is decided on the code where it can be: the
        // error is at most decode(code) and above decode(code − 1).
        let code = self.leaf_code(d, i, j, mask);
        let by_code = self.criterion.vertical_bound_m().and_then(|b| {
            if decode(code) as f64 <= b {
                Some(false)
            } else if code > 0 && decode(code - 1) as f64 >= b {
                Some(true)
            } else {
                None
            }
        });
        let split = by_code.unwrap_or_else(|| {
            let corners = self.corners(s, i, j);
            let e = Element {
                corners: &corners,
                depth: d as u32,
                vertical_error_m: self.leaf_error(d, i, j, mask),
                grid: tree.grid,
            };
            self.criterion.wants_split(&e)
        });
        if split {
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

    /// Emits the leaves and counts the points (step 5 of [`super`]).
    fn finish(self, opts: &QuadOptions) -> QuadExtraction {
        let tree = self.tree;
        let mut out = Emitter::new(tree.hier);
        for (d, level) in tree.levels.iter().enumerate() {
            for j in 0..level.rows {
                for i in 0..level.cols {
                    let st = self.get(d, i, j);
                    if st >= FORCED {
                        out.split_points(level.size, i, j, st == WANTED);
                    } else if st == LEAF && tree.inside(d, i, j) {
                        self.emit_leaf(&mut out, d, i, j, opts);
                    }
                }
            }
        }
        out.finish(tree.grid)
    }

    /// Emits the inside leaf `(i, j)` of depth `d`: a unit block as two
    /// triangles through its parent's centre, a block without finer
    /// neighbours as its two halves when [`QuadOptions::centre_when_needed`]
    /// and the criterion accepts them, else its template.
    fn emit_leaf(&self, out: &mut Emitter, d: usize, i: u32, j: u32, opts: &QuadOptions) {
        let s = self.tree.levels[d].size;
        let (x0, y0) = (i * s, j * s);
        let leaf = |mask, halves| Leaf {
            depth: d as u32,
            size: s,
            col: x0,
            row: y0,
            mask,
            halves,
        };
        if s == 1 {
            let (cx, cy) = (i | 1, j | 1);
            let (ox, oy) = (
                if cx == i { i + 1 } else { i },
                if cy == j { j + 1 } else { j },
            );
            for k in [[ox, cy], [cx, oy]] {
                out.push_ccw([[cx, cy], [ox, oy], k]);
            }
            out.leaves.push(leaf(0, true));
            return;
        }
        let mask = self.mask(d, i, j);
        if mask == 0 && opts.centre_when_needed {
            if let Some((halves, e)) = self.halves_if_accepted(d, i, j) {
                out.max_leaf = out.max_leaf.max(e);
                for t in halves {
                    out.push_ccw(t);
                }
                out.leaves.push(leaf(mask, true));
                return;
            }
        }
        // The exact error only where it can raise the largest so far.
        if decode(self.leaf_code(d, i, j, mask)) as f64 > out.max_leaf {
            out.max_leaf = out.max_leaf.max(self.leaf_error(d, i, j, mask));
        }
        let half = s / 2;
        for t in template(mask).triangles() {
            out.push_ccw(t.map(|p| [x0 + p[0] * half, y0 + p[1] * half]));
        }
        out.leaves.push(leaf(mask, false));
    }
}

/// The mesh being emitted and its accounting.
struct Emitter {
    hier: Hierarchy,
    tris: Vec<[u32; 3]>,
    leaves: Vec<Leaf>,
    max_leaf: f64,
    wanted_splits: usize,
    forced_splits: usize,
    /// Per sample: 0 not introduced by a split, 1 added, 2 selected.
    class: Vec<u8>,
}

impl Emitter {
    fn new(hier: Hierarchy) -> Self {
        Emitter {
            hier,
            tris: Vec::new(),
            leaves: Vec::new(),
            max_leaf: 0.0,
            wanted_splits: 0,
            forced_splits: 0,
            class: vec![0u8; hier.width() as usize * hier.height() as usize],
        }
    }

    /// Classifies the points the split of block `(i, j)` of side `s`
    /// introduced: its 4 side midpoints and its children's centres.
    fn split_points(&mut self, s: u32, i: u32, j: u32, wanted: bool) {
        let c = if wanted {
            self.wanted_splits += 1;
            2
        } else {
            self.forced_splits += 1;
            1
        };
        let (x0, y0) = (i * s, j * s);
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
        for p in pts {
            if self.hier.contains(p) {
                let k = self.hier.index(p);
                self.class[k] = self.class[k].max(c);
            }
        }
    }

    /// Pushes triangle `t` (grid positions) as sample indices, counter-clockwise.
    fn push_ccw(&mut self, t: [Pt; 3]) {
        let t = if orient_up(t[0], t[1], t[2]) < 0 {
            [t[1], t[0], t[2]]
        } else {
            t
        };
        self.tris.push(t.map(|p| self.hier.index(p) as u32));
    }

    /// The mesh and its point counts.
    fn finish(self, grid: &HeightGrid) -> QuadExtraction {
        let mesh = compact(grid, self.tris);
        let mut points = PointCounts {
            vertices: mesh.vertex_count(),
            triangles: mesh.triangle_count(),
            ..PointCounts::default()
        };
        for v in &mesh.vertices {
            match self.class[self.hier.index([v.col, v.row])] {
                2 => points.selected += 1,
                1 => points.added += 1,
                _ => points.base += 1,
            }
        }
        QuadExtraction {
            mesh,
            points,
            leaves: self.leaves,
            wanted_splits: self.wanted_splits,
            forced_splits: self.forced_splits,
            max_leaf_error_m: self.max_leaf,
        }
    }
}

/// Numbers the used samples row-major and rewrites the triangles: a bit per
/// sample marks the used ones, and a vertex's number is the count of used
/// samples before it.
fn compact(grid: &HeightGrid, mut tris: Vec<[u32; 3]>) -> Mesh {
    let mut bits = vec![0u64; grid.len().div_ceil(64)];
    for &i in tris.iter().flatten() {
        bits[(i / 64) as usize] |= 1u64 << (i % 64);
    }
    let mut before = Vec::with_capacity(bits.len());
    let mut total = 0u32;
    for &word in &bits {
        before.push(total);
        total += word.count_ones();
    }
    let w = grid.width() as u32;
    let heights = grid.heights();
    let mut vertices = Vec::with_capacity(total as usize);
    for (k, &word) in bits.iter().enumerate() {
        let mut rest = word;
        while rest != 0 {
            let i = k as u32 * 64 + rest.trailing_zeros();
            rest &= rest - 1;
            vertices.push(MeshVertex {
                col: i % w,
                row: i / w,
                z_m: heights[i as usize],
            });
        }
    }
    for i in tris.iter_mut().flatten() {
        let (word, bit) = ((*i / 64) as usize, *i % 64);
        *i = before[word] + (bits[word] & ((1u64 << bit) - 1)).count_ones();
    }
    Mesh {
        vertices,
        triangles: tris,
    }
}
