//! Conforming extraction from a prepared [`Bitree`]: by maximum error or by
//! triangle budget.
//!
//! Paper `001_49f2c365e8c41172.txt`: the frontier of the binary tree is the mesh;
//! a frontier triangle that satisfies the indicator stays, otherwise it splits
//! into its two children, recursively. With the monotone, diamond-shared errors
//! of [`Bitree`] the indicator "`err[mid(T)] ≤ E`" needs no forced-split
//! propagation (Evans et al. 1997 RTIN; Duchaineau et al. 1997 ROAM): both
//! triangles of a diamond split together and a child splits only if its parent
//! did, so the result is watertight with no T-junction, and every triangle left
//! meets `e(T) ≤ E` at every sample it covers.
//!
//! 1. Walk the tree from the two roots; skip triangles outside the grid, split
//!    straddling ones, split inside ones while `err[mid] > E`.
//! 2. Emit each leaf as three sample indices, counter-clockwise seen from above,
//!    and mark its vertices in a bitset.
//! 3. Number the marked samples in row-major order (a popcount prefix over the
//!    bitset) and rewrite the triangles; vertex order is therefore row-major,
//!    which is cache-friendly downstream.
//!
//! By budget, a binary search over `E` (on the `f32` bit patterns, which order
//! like the values) finds the smallest threshold whose mesh has at most `N`
//! triangles; each probe is a counting walk that stops once it passes `N`.
//!
//! # Runtime
//! Proportional to the output (plus `W·H/64` words of bitset); by budget about
//! 32 counting walks of at most `N` triangles.

use crate::bitree::{Bitree, MeshError};
use crate::hierarchy::{orient_up, Placement, Tri};
use crate::mesh::{Mesh, MeshVertex};

/// What to extract.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Target {
    /// The coarsest conforming mesh whose error is at most this many metres at
    /// every sample.
    MaxErrorM(f64),
    /// The mesh with the smallest error threshold that has at most this many
    /// triangles.
    MaxTriangles(usize),
}

/// Options for [`Bitree::extract`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct ExtractOptions {
    /// What to extract. Default: `Target::MaxErrorM(1.0)`.
    pub target: Target,
}

impl ExtractOptions {
    /// The defaults: a 1 m maximum error.
    pub const DEFAULT: ExtractOptions = ExtractOptions {
        target: Target::MaxErrorM(1.0),
    };

    /// Extract with a maximum vertical error in metres.
    pub const fn max_error_m(e: f64) -> Self {
        ExtractOptions {
            target: Target::MaxErrorM(e),
        }
    }

    /// Extract with a triangle budget.
    pub const fn max_triangles(n: usize) -> Self {
        ExtractOptions {
            target: Target::MaxTriangles(n),
        }
    }
}

impl Default for ExtractOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// An extracted mesh and the threshold that produced it.
#[derive(Debug, Clone)]
pub struct Extraction {
    /// The mesh (vertices on samples, triangles counter-clockwise from above).
    pub mesh: Mesh,
    /// The error threshold `E` used, in metres: every sample is within `E` of the mesh.
    pub threshold_m: f64,
}

impl Bitree<'_> {
    /// Extracts a conforming mesh.
    ///
    /// # Errors
    /// [`MeshError::BadMaxError`] for a negative or NaN error,
    /// [`MeshError::BudgetTooSmall`] for a budget below the coarsest mesh.
    pub fn extract(&self, opts: &ExtractOptions) -> Result<Extraction, MeshError> {
        let threshold = match opts.target {
            Target::MaxErrorM(e) => {
                if e.is_nan() || e < 0.0 {
                    return Err(MeshError::BadMaxError(e));
                }
                e
            }
            Target::MaxTriangles(n) => self.threshold_for_budget(n)?,
        };
        Ok(Extraction {
            mesh: self.extract_at(threshold),
            threshold_m: threshold,
        })
    }

    /// Number of triangles the mesh at threshold `e_m` has.
    pub fn count_at(&self, e_m: f64) -> usize {
        let mut w = Walker::new(self, split_threshold(e_m), usize::MAX);
        w.count_all();
        w.count
    }

    /// The smallest threshold whose mesh has at most `n` triangles.
    fn threshold_for_budget(&self, n: usize) -> Result<f64, MeshError> {
        let count = |bits: u32| {
            let mut w = Walker::new(self, f32::from_bits(bits), n);
            w.count_all();
            w.count
        };
        // The coarsest mesh: only the splits the border forces.
        let top = f32::MAX.to_bits();
        let min = count(top);
        if min > n {
            let g = self.grid();
            return Err(MeshError::BudgetTooSmall {
                got: n,
                min,
                width: g.width(),
                height: g.height(),
            });
        }
        if count(0) <= n {
            return Ok(0.0);
        }
        // Invariant: count(lo) > n, count(hi) <= n.
        let (mut lo, mut hi) = (0u32, top);
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if count(mid) <= n {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        Ok(f32::from_bits(hi) as f64)
    }

    /// Extracts the mesh at threshold `e_m` (metres, non-negative).
    fn extract_at(&self, e_m: f64) -> Mesh {
        let mut w = Walker::new(self, split_threshold(e_m), usize::MAX);
        w.emit = true;
        w.count_all();
        compact(self, w.bits, w.corners)
    }
}

/// The largest `f32` not above `e`: `err > e` ⇔ `err > split_threshold(e)` for
/// every `f32` `err`.
fn split_threshold(e: f64) -> f32 {
    let f = e as f32;
    if f as f64 > e {
        f.next_down()
    } else {
        f
    }
}

/// The recursive walk shared by counting and emitting.
struct Walker<'a, 'g> {
    tree: &'a Bitree<'g>,
    threshold: f32,
    cap: usize,
    count: usize,
    emit: bool,
    corners: Vec<[u32; 3]>,
    bits: Vec<u64>,
}

impl<'a, 'g> Walker<'a, 'g> {
    fn new(tree: &'a Bitree<'g>, threshold: f32, cap: usize) -> Self {
        Walker {
            tree,
            threshold,
            cap,
            count: 0,
            emit: false,
            corners: Vec::new(),
            bits: Vec::new(),
        }
    }

    fn count_all(&mut self) {
        if self.emit {
            let n = self.tree.grid().len();
            self.bits = vec![0u64; n.div_ceil(64)];
        }
        for r in self.tree.hierarchy().roots() {
            self.walk(r, false);
        }
    }

    fn walk(&mut self, t: Tri, inside: bool) {
        if self.count > self.cap {
            return;
        }
        let hier = self.tree.hierarchy();
        let inside = inside
            || match hier.place(&t) {
                Placement::Outside => return,
                Placement::Straddling => false,
                Placement::Inside => true,
            };
        if t.is_unit() {
            if inside {
                self.leaf(t);
            }
            return;
        }
        if inside && self.tree.err_at(t.mid()) <= self.threshold {
            self.leaf(t);
            return;
        }
        let (c0, c1) = t.children();
        self.walk(c0, inside);
        self.walk(c1, inside);
    }

    #[inline]
    fn leaf(&mut self, t: Tri) {
        self.count += 1;
        if !self.emit {
            return;
        }
        let (a, b, c) = if orient_up(t.a, t.b, t.c) > 0 {
            (t.a, t.b, t.c)
        } else {
            (t.b, t.a, t.c)
        };
        let hier = self.tree.hierarchy();
        let ids = [
            hier.index(a) as u32,
            hier.index(b) as u32,
            hier.index(c) as u32,
        ];
        for &i in &ids {
            self.bits[(i / 64) as usize] |= 1u64 << (i % 64);
        }
        self.corners.push(ids);
    }
}

/// Numbers the marked samples row-major and rewrites triangle corners from
/// sample indices to vertex indices.
fn compact(tree: &Bitree<'_>, bits: Vec<u64>, mut tris: Vec<[u32; 3]>) -> Mesh {
    let mut prefix = Vec::with_capacity(bits.len());
    let mut total = 0u32;
    for &word in &bits {
        prefix.push(total);
        total += word.count_ones();
    }
    let grid = tree.grid();
    let w = grid.width() as u32;
    let heights = grid.heights();
    let mut vertices = Vec::with_capacity(total as usize);
    for (k, &word) in bits.iter().enumerate() {
        let mut rest = word;
        while rest != 0 {
            let bit = rest.trailing_zeros();
            rest &= rest - 1;
            let i = k as u32 * 64 + bit;
            vertices.push(MeshVertex {
                col: i % w,
                row: i / w,
                z_m: heights[i as usize],
            });
        }
    }
    for t in &mut tris {
        for i in t.iter_mut() {
            let (word, bit) = ((*i / 64) as usize, *i % 64);
            let below = bits[word] & ((1u64 << bit) - 1);
            *i = prefix[word] + below.count_ones();
        }
    }
    Mesh {
        vertices,
        triangles: tris,
    }
}
