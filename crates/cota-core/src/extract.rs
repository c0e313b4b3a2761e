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
//! 1. **Top of the tree** (sequential, tiny): walk from the two roots, skip
//!    triangles outside the grid, split straddling ones; each triangle inside
//!    the grid that stops splitting or is at most [`TASK_DEPTH`] splits above
//!    the unit level becomes a *task*. Tasks are in depth-first order.
//! 2. **Count** the leaves of every task (in parallel): split while
//!    `err[mid] > E`. Inside the grid a triangle is just three sample indices:
//!    the midpoint of the hypotenuse `a`–`b` is the sample `(a + b) / 2`
//!    (indices are linear in the coordinates), and the children of `(a, b, c)`
//!    are `(c, a, m)` and `(b, c, m)`, all counter-clockwise like the roots.
//! 3. **Emit** every task's leaves into its own slice of the output (sizes from
//!    step 2, so the triangle array is allocated once at its final size), in
//!    parallel; the order is the sequential depth-first order.
//! 4. **Number the vertices** row-major: a bitset of the samples that are
//!    vertices, then a popcount prefix. The vertices are the split points that
//!    split (every split point with `err > E` is reached, since `err` grows up
//!    the tree) plus the root corners inside the grid: on dense meshes the
//!    bitset comes from a parallel scan of the error codes, on sparse ones
//!    from the triangles' corners. Triangle corners are then rewritten from
//!    sample to vertex indices in parallel.
//!
//! The split test reads 16-bit error codes ([`crate::error_code`]) and settles
//! the rare ambiguous code exactly, so the mesh is the one of the exact errors.
//!
//! By budget, a binary search over the error codes finds the smallest code
//! value `E` whose mesh has at most `N` triangles (16 probes); each probe is a
//! parallel counting walk that stops once it passes `N`.
//!
//! # Runtime
//! Proportional to the output (plus a scan of `W·H` codes, or `W·H/64` bitset
//! words, for the numbering), on all cores; by budget about 16 counting walks
//! of at most `N` triangles.

use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;

use crate::bitree::{Bitree, MeshError};
use crate::error_code::{SplitRule, INFINITE};
use crate::hierarchy::{Placement, Tri};
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
            mesh: self.extract_at(&SplitRule::new(threshold)),
            threshold_m: threshold,
        })
    }

    /// Number of triangles the mesh at threshold `e_m` has.
    pub fn count_at(&self, e_m: f64) -> usize {
        let rule = SplitRule::new(e_m);
        let tasks = self.tasks(&rule);
        count_tasks(self, &rule, &tasks, usize::MAX)
    }

    /// The smallest code value `E` whose mesh has at most `n` triangles.
    fn threshold_for_budget(&self, n: usize) -> Result<f64, MeshError> {
        let count = |code: u16| {
            let rule = SplitRule::at_code(code);
            let tasks = self.tasks(&rule);
            count_tasks(self, &rule, &tasks, n)
        };
        // The coarsest mesh: only the splits the border forces.
        let top = INFINITE - 2;
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
        let (mut lo, mut hi) = (0u16, top);
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if count(mid) <= n {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        Ok(SplitRule::at_code(hi).threshold as f64)
    }

    /// Extracts the mesh of `rule`.
    fn extract_at(&self, rule: &SplitRule) -> Mesh {
        let tasks = self.tasks(rule);
        if looks_dense(self, rule) {
            // Vertices first (from the codes), then triangles straight in
            // vertex indices.
            let words = numbered(vertex_bits_from_codes(self, rule));
            let expected = expected_triangles(self, &words);
            let tris = emit_tasks(self, rule, &tasks, expected, |i| vertex_id(&words, i));
            let vertices = vertices(self, &words);
            Mesh {
                vertices,
                triangles: tris,
            }
        } else {
            // Triangles in sample indices, then their corners are the vertices.
            let mut tris = emit_tasks(self, rule, &tasks, 0, |i| i);
            let words = numbered(vertex_bits_from_triangles(self, &tris));
            tris.par_chunks_mut(4096).for_each(|chunk| {
                for t in chunk {
                    for i in t.iter_mut() {
                        *i = vertex_id(&words, *i);
                    }
                }
            });
            let vertices = vertices(self, &words);
            Mesh {
                vertices,
                triangles: tris,
            }
        }
    }

    /// The top of the walk: inside triangles, in depth-first order, each
    /// walked as one task.
    fn tasks(&self, rule: &SplitRule) -> Vec<Task> {
        let mut out = Vec::new();
        for r in self.hierarchy().roots() {
            self.top(r, rule, &mut out);
        }
        out
    }

    fn top(&self, t: Tri, rule: &SplitRule, out: &mut Vec<Task>) {
        let hier = self.hierarchy();
        match hier.place(&t) {
            Placement::Outside => {}
            Placement::Straddling => {
                let (c0, c1) = t.children();
                self.top(c0, rule, out);
                self.top(c1, rule, out);
            }
            Placement::Inside => {
                let depth = depth_of(&t);
                if depth <= TASK_DEPTH || !self.splits_index(hier.index(t.mid()), rule) {
                    out.push(Task {
                        a: hier.index(t.a) as u32,
                        b: hier.index(t.b) as u32,
                        c: hier.index(t.c) as u32,
                        depth,
                    });
                } else {
                    let (c0, c1) = t.children();
                    self.top(c0, rule, out);
                    self.top(c1, rule, out);
                }
            }
        }
    }
}

/// Inside triangles at most this many splits above the unit level are walked
/// as one task (at most `2^TASK_DEPTH` leaves each).
pub const TASK_DEPTH: u32 = 12;

/// A triangle inside the grid, as sample indices (hypotenuse `a`–`b`, apex
/// `c`, counter-clockwise), and the number of splits down to the unit level.
#[derive(Debug, Clone, Copy)]
struct Task {
    a: u32,
    b: u32,
    c: u32,
    depth: u32,
}

/// Splits from `t` down to a unit triangle: `2·log2(s)` for the halves of an
/// `s`-square (`A(s)`), one less for a triangle on an `s`-side (`B(s)`).
fn depth_of(t: &Tri) -> u32 {
    let dx = t.a[0].abs_diff(t.b[0]);
    let dy = t.a[1].abs_diff(t.b[1]);
    if dx == dy {
        2 * dx.trailing_zeros()
    } else {
        (2 * dx.max(dy).trailing_zeros()).saturating_sub(1)
    }
}

/// The sample halfway between samples `a` and `b` (their coordinates' sums
/// are even, so the index sum is too), without overflowing `u32`.
#[inline(always)]
fn mid(a: u32, b: u32) -> u32 {
    (a >> 1) + (b >> 1) + (a & b & 1)
}

/// Leaves under `t`.
fn count_leaves(tree: &Bitree<'_>, rule: &SplitRule, t: Task) -> usize {
    let mut n = 0;
    walk_task(tree, rule, t, |_, _, _| n += 1);
    n
}

/// Total leaves of `tasks`, in parallel; stops early (returning more than
/// `cap`) once the running total passes `cap`.
fn count_tasks(tree: &Bitree<'_>, rule: &SplitRule, tasks: &[Task], cap: usize) -> usize {
    let total = AtomicUsize::new(0);
    tasks.par_iter().for_each(|t| {
        if total.load(Ordering::Relaxed) > cap {
            return;
        }
        let n = count_leaves(tree, rule, *t);
        total.fetch_add(n, Ordering::Relaxed);
    });
    total.into_inner()
}

/// Appends the leaves under `t`, depth-first, corners mapped by `id`.
fn emit_leaves(
    tree: &Bitree<'_>,
    rule: &SplitRule,
    t: Task,
    id: &impl Fn(u32) -> u32,
    out: &mut Vec<[u32; 3]>,
) {
    walk_task(tree, rule, t, |a, b, c| out.push([id(a), id(b), id(c)]));
}

/// Calls `leaf(a, b, c)` for every leaf under `t`, depth-first (the order of
/// the sequential recursion). Iterative, with an explicit stack: a task is at
/// most [`TASK_DEPTH`] splits deep unless it does not split at all.
#[inline(always)]
fn walk_task(tree: &Bitree<'_>, rule: &SplitRule, t: Task, mut leaf: impl FnMut(u32, u32, u32)) {
    let mut stack = [[0u32; 4]; STACK];
    stack[0] = [t.a, t.b, t.c, t.depth];
    let mut sp = 1;
    while sp > 0 {
        sp -= 1;
        let [a, b, c, depth] = stack[sp];
        if depth > 0 && sp + 2 <= STACK {
            let m = mid(a, b);
            if tree.splits_index(m as usize, rule) {
                // Second child below the first: the first is walked first.
                stack[sp] = [b, c, m, depth - 1];
                stack[sp + 1] = [c, a, m, depth - 1];
                sp += 2;
                continue;
            }
        }
        leaf(a, b, c);
    }
}

/// Stack slots of the task walks: one per level of a task plus one.
const STACK: usize = 2 * TASK_DEPTH as usize + 2;

/// A bitset word of vertex samples and the number of vertices before it.
#[derive(Debug, Clone, Copy, Default)]
struct Word {
    bits: u64,
    base: u32,
}

/// The vertex bitset from the error codes: every split point that splits,
/// plus the root corners inside the grid.
fn vertex_bits_from_codes(tree: &Bitree<'_>, rule: &SplitRule) -> Vec<Word> {
    let codes = tree.error_codes();
    let mut words = vec![Word::default(); codes.len().div_ceil(64)];
    words
        .par_chunks_mut(256)
        .enumerate()
        .for_each(|(k, chunk)| {
            for (j, word) in chunk.iter_mut().enumerate() {
                let first = (k * 256 + j) * 64;
                let end = (first + 64).min(codes.len());
                let span = &codes[first..end];
                let mut bits = 0u64;
                for (b, &code) in span.iter().enumerate() {
                    bits |= u64::from(code > rule.floor) << b;
                }
                if rule.ambiguous {
                    let mut rest = 0u64;
                    for (b, &code) in span.iter().enumerate() {
                        rest |= u64::from(code == rule.tie) << b;
                    }
                    while rest != 0 {
                        let b = rest.trailing_zeros();
                        rest &= rest - 1;
                        if !tree.splits_index(first + b as usize, rule) {
                            bits &= !(1u64 << b);
                        }
                    }
                }
                word.bits = bits;
            }
        });
    let hier = tree.hierarchy();
    let n = hier.size();
    for p in [[0, 0], [n, 0], [0, n], [n, n]] {
        if hier.contains(p) {
            let i = hier.index(p);
            words[i / 64].bits |= 1u64 << (i % 64);
        }
    }
    words
}

/// The vertex bitset from the triangles' corners (sparse meshes).
fn vertex_bits_from_triangles(tree: &Bitree<'_>, tris: &[[u32; 3]]) -> Vec<Word> {
    let mut words = vec![Word::default(); tree.grid().len().div_ceil(64)];
    for t in tris {
        for &i in t {
            words[(i / 64) as usize].bits |= 1u64 << (i % 64);
        }
    }
    words
}

/// Fills in each word's `base`: the number of vertices before it.
fn numbered(mut words: Vec<Word>) -> Vec<Word> {
    let mut total = 0u32;
    for w in &mut words {
        w.base = total;
        total += w.bits.count_ones();
    }
    words
}

/// The row-major vertex index of vertex sample `i`.
#[inline(always)]
fn vertex_id(words: &[Word], i: u32) -> u32 {
    match words.get((i / 64) as usize) {
        Some(w) => w.base + (w.bits & ((1u64 << (i % 64)) - 1)).count_ones(),
        None => 0,
    }
}

/// Whether the mesh of `rule` is likely to have a vertex on at least one
/// sample in sixteen: then scanning every code for the vertex set is cheaper
/// than marking triangle corners. Looks at 1024 evenly spaced codes; only
/// the path taken depends on it, never the mesh.
fn looks_dense(tree: &Bitree<'_>, rule: &SplitRule) -> bool {
    let codes = tree.error_codes();
    let n = codes.len() as u64;
    // Scattered probes (Fibonacci hashing): a regular stride would follow the
    // hierarchy's levels, which live on regular sub-lattices.
    let hits = (0..1024u64)
        .filter(|&j| {
            let i = (j.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 11) % n;
            codes[i as usize] > rule.floor
        })
        .count();
    hits * 16 >= 1024
}

/// Tasks per parallel window: bounds the per-task buffers alive at once to
/// `WINDOW · 2^TASK_DEPTH` triangles.
const WINDOW: usize = 256;

/// The leaves of every task in depth-first order, corners mapped by `id`.
/// Windows of tasks are walked in parallel into per-task buffers, then
/// appended in order.
fn emit_tasks(
    tree: &Bitree<'_>,
    rule: &SplitRule,
    tasks: &[Task],
    expected: usize,
    id: impl Fn(u32) -> u32 + Sync,
) -> Vec<[u32; 3]> {
    let mut tris: Vec<[u32; 3]> = Vec::with_capacity(expected);
    for window in tasks.chunks(WINDOW) {
        // Runs of 16 tasks share a buffer: fewer allocations on sparse meshes,
        // where most tasks are a single leaf.
        let parts: Vec<Vec<[u32; 3]>> = window
            .par_chunks(16)
            .map(|run| {
                let mut out = Vec::new();
                for t in run {
                    emit_leaves(tree, rule, *t, &id, &mut out);
                }
                out
            })
            .collect();
        tris.reserve(parts.iter().map(Vec::len).sum());
        for p in parts {
            tris.extend_from_slice(&p);
        }
    }
    // Growth may have left up to half the capacity unused: give it back
    // (large blocks shrink in place).
    tris.shrink_to_fit();
    tris
}

/// The triangle count of a triangulation of the grid rectangle whose vertices
/// are `words`: Euler's `T = 2V − B − 2`, with `B` vertices on the border.
fn expected_triangles(tree: &Bitree<'_>, words: &[Word]) -> usize {
    let (w, h) = (tree.grid().width(), tree.grid().height());
    let is_vertex = |i: usize| {
        words
            .get(i / 64)
            .is_some_and(|wd| wd.bits >> (i % 64) & 1 == 1)
    };
    let v = words.last().map_or(0, |wd| wd.base + wd.bits.count_ones()) as usize;
    let mut border = 0usize;
    for x in 0..w {
        border += usize::from(is_vertex(x)) + usize::from(is_vertex((h - 1) * w + x));
    }
    for y in 1..h.saturating_sub(1) {
        border += usize::from(is_vertex(y * w)) + usize::from(is_vertex(y * w + w - 1));
    }
    (2 * v).saturating_sub(border + 2)
}

/// The mesh vertices of the numbered bitset, row-major, in parallel.
fn vertices(tree: &Bitree<'_>, words: &[Word]) -> Vec<MeshVertex> {
    let total = words.last().map_or(0, |w| w.base + w.bits.count_ones());
    let grid = tree.grid();
    let w = grid.width() as u32;
    let heights = grid.heights();
    let mut vertices = vec![
        MeshVertex {
            col: 0,
            row: 0,
            z_m: 0.0
        };
        total as usize
    ];
    const CHUNK: usize = 1024;
    let mut slices = Vec::with_capacity(words.len().div_ceil(CHUNK));
    let mut rest = vertices.as_mut_slice();
    for chunk in words.chunks(CHUNK) {
        let n: u32 = chunk.iter().map(|w| w.bits.count_ones()).sum();
        let (head, tail) = rest.split_at_mut(n as usize);
        slices.push(head);
        rest = tail;
    }
    words
        .par_chunks(CHUNK)
        .zip(slices.into_par_iter())
        .enumerate()
        .for_each(|(k, (chunk, out))| {
            let mut slots = out.iter_mut();
            for (j, word) in chunk.iter().enumerate() {
                let first = ((k * CHUNK + j) * 64) as u32;
                // One division per word; columns advance without dividing.
                let (row0, col0) = (first / w, first % w);
                let mut rest = word.bits;
                while rest != 0 {
                    let bit = rest.trailing_zeros();
                    rest &= rest - 1;
                    let (mut row, mut col) = (row0, col0 + bit);
                    while col >= w {
                        col -= w;
                        row += 1;
                    }
                    if let Some(v) = slots.next() {
                        *v = MeshVertex {
                            col,
                            row,
                            z_m: heights[(first + bit) as usize],
                        };
                    }
                }
            }
        });
    vertices
}
