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
//! 1. **Top of the tree** (sequential, tiny): the largest triangles inside
//!    the grid (the roots split while they straddle its border, found once
//!    per [`Bitree`]) are split while they split and are more than
//!    [`TASK_DEPTH`] splits above the unit level; each triangle where this
//!    stops becomes a *task*. Tasks are in depth-first order.
//! 2. **Walk** every task (in parallel): split while `err[mid] > E`. Inside
//!    the grid a triangle is just three sample indices: the midpoint of the
//!    hypotenuse `a`–`b` is the sample `(a + b) / 2` (indices are linear in
//!    the coordinates), and the children of `(a, b, c)` are `(c, a, m)` and
//!    `(b, c, m)`, all counter-clockwise like the roots. The output order is
//!    the sequential depth-first order.
//! 3. **Number the vertices** row-major: a bitset of the samples that are
//!    vertices, then a popcount prefix. The vertices are the split points that
//!    split (every split point with `err > E` is reached, since `err` grows up
//!    the tree) plus the root corners inside the grid.
//!
//! The order of the steps depends on the mesh's density (guessed from 1024
//! scattered codes; only the speed depends on the guess). Unless the mesh is
//! scattered, step 3 comes first, from a parallel scan of the codes. The walk
//! then writes vertex indices (each split numbers its new vertex; the
//! children inherit the other corners' numbers), and its split test reads
//! the vertex bitset instead of the codes: a split point splits exactly when
//! it is a vertex, and the bitset is an eighth of the codes' size (2 bits a
//! sample with its numbering, against 16), so the walk's scattered reads miss
//! the cache less. On the benchmark grids this made extraction 1.05–1.4×
//! faster (the walk alone on big4097 at 50 m: 22 → 14 ms).
//!
//! - **Dense** meshes: each task's leaf count follows from the bitset alone,
//!   by popcounts over the task's rows (see `leaves_from_bits`), so the
//!   output is allocated once at its final size and each task writes its
//!   leaves straight into its own slice.
//! - **Sparse** meshes (fewer than one sample in 16 a vertex): runs of tasks
//!   are walked into their own buffers, which are then copied into place;
//!   the copy costs less than the per-task counts when the task rows hold
//!   few vertices.
//! - **Scattered** meshes (fewer than one in 64): the scan of every code
//!   would cost more than the walk, so the runs are walked in sample indices,
//!   the bitset comes from their corners, and the runs are renumbered while
//!   they are copied into place.
//!
//! Each call enters the rayon pool once (see `on_pool`): entering it per
//! parallel section costs more than a sparse extraction.
//!
//! The split test reads 16-bit error codes ([`crate::bitree::error_code`]) and settles
//! the rare ambiguous code exactly, so the mesh is the one of the exact errors;
//! the scan for the bitset settles them the same way.
//!
//! By budget, a binary search over the error codes finds the smallest code
//! value `E` whose mesh has at most `N` triangles (16 probes); each probe is a
//! parallel counting walk that stops once it passes `N`.
//!
//! # Runtime
//! Proportional to the output, plus a scan of the `W·H` codes (or, for
//! scattered meshes, of `W·H/64` bitset words) for the numbering, on all
//! cores; by budget about 16 counting walks of at most `N` triangles.

use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;

use super::error_code::{SplitRule, INFINITE};
use super::Bitree;
use crate::error::MeshError;
use crate::hierarchy::{RowSpans, Tri};
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
            Target::MaxTriangles(n) => crate::par::on_pool(|| self.threshold_for_budget(n))?,
        };
        Ok(Extraction {
            mesh: crate::par::on_pool(|| self.extract_at(&SplitRule::new(threshold))),
            threshold_m: threshold,
        })
    }

    /// Number of triangles the mesh at threshold `e_m` has.
    pub fn count_at(&self, e_m: f64) -> usize {
        let rule = SplitRule::new(e_m);
        crate::par::on_pool(|| {
            let tasks = self.tasks(&rule);
            count_tasks(self, &rule, &tasks, usize::MAX)
        })
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
        if count(top) > n {
            // Counted in full (not stopped past `n`), so the error states the true minimum.
            let rule = SplitRule::at_code(top);
            let min = count_tasks(self, &rule, &self.tasks(&rule), usize::MAX);
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
        let share = vertex_share(self, rule);
        // About two triangles per vertex.
        let expected = (2.0 * share * self.grid().len() as f64) as usize;
        if share >= DENSE_SHARE {
            self.extract_dense(rule, &tasks)
        } else if share >= SPARSE_SHARE {
            self.extract_sparse(rule, &tasks, expected)
        } else {
            self.extract_scattered(rule, &tasks, expected)
        }
    }

    /// Vertices first (from the codes), then each task's leaf count (from
    /// the vertices), then the triangles straight in vertex indices, each
    /// task into its own slice of the output.
    fn extract_dense(&self, rule: &SplitRule, tasks: &[Task]) -> Mesh {
        let words = numbered(vertex_bits_from_codes(self, rule));
        let w = self.grid().width();
        let counts: Vec<usize> = tasks
            .par_iter()
            .with_min_len(8)
            .map(|t| leaves_from_bits(&words, w, t))
            .collect();
        debug_assert!(tasks
            .iter()
            .zip(&counts)
            .all(|(t, &n)| count_leaves(self, rule, *t) == n));
        let Some(triangles) = emit_tasks(&words, tasks, &counts) else {
            // A count that is not the walk's would be a bug: take the path
            // that does not depend on counts rather than return a wrong mesh.
            return self.sparse_from(words, tasks, 0);
        };
        Mesh {
            vertices: vertices(self, &words),
            triangles,
        }
    }

    /// Vertices first (from the codes), then runs of tasks walked in
    /// parallel into their own buffers in vertex indices, then the runs
    /// copied into place.
    fn extract_sparse(&self, rule: &SplitRule, tasks: &[Task], expected: usize) -> Mesh {
        self.sparse_from(
            numbered(vertex_bits_from_codes(self, rule)),
            tasks,
            expected,
        )
    }

    /// [`Bitree::extract_sparse`] given the numbered vertex bitset.
    fn sparse_from(&self, words: Vec<Word>, tasks: &[Task], expected: usize) -> Mesh {
        let parts = walk_runs(tasks, expected, |t, out| {
            walk_task_ids(t, &words, |tri| out.push(tri));
        });
        Mesh {
            vertices: vertices(self, &words),
            triangles: place_runs(&parts, |i| i),
        }
    }

    /// Runs of tasks walked in parallel into their own buffers in sample
    /// indices, the vertices from their corners, then the runs copied into
    /// place in vertex indices: for meshes so sparse that scanning every code
    /// for the vertices would cost more than marking the corners.
    fn extract_scattered(&self, rule: &SplitRule, tasks: &[Task], expected: usize) -> Mesh {
        let parts = walk_runs(tasks, expected, |t, out| {
            walk_task(
                t,
                |m| self.splits_index(m as usize, rule),
                |a, b, c| {
                    out.push([a, b, c]);
                },
            );
        });
        let mut words: Vec<Word> = bytemuck::zeroed_vec(self.grid().len().div_ceil(64));
        for &i in parts.iter().flatten().flatten() {
            words[(i / 64) as usize].bits |= 1u64 << (i % 64);
        }
        let words = numbered(words);
        Mesh {
            vertices: vertices(self, &words),
            triangles: place_runs(&parts, |i| vertex_id(&words, i)),
        }
    }

    /// The top of the walk: inside triangles, in depth-first order, each
    /// walked as one task.
    fn tasks(&self, rule: &SplitRule) -> Vec<Task> {
        let mut out = Vec::new();
        for &t in self.inside_roots() {
            self.top(t, rule, &mut out);
        }
        out
    }

    /// Splits the inside triangle `t` while it splits and is more than
    /// [`TASK_DEPTH`] splits deep.
    fn top(&self, t: Tri, rule: &SplitRule, out: &mut Vec<Task>) {
        let hier = self.hierarchy();
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
    walk_task(t, |m| tree.splits_index(m as usize, rule), |_, _, _| n += 1);
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

/// Calls `leaf(a, b, c)` for every leaf under `t`, depth-first (the order of
/// the sequential recursion), a triangle splitting where `splits(mid)`.
/// Iterative, with an explicit stack: a task is at most [`TASK_DEPTH`]
/// splits deep unless it does not split at all.
#[inline(always)]
fn walk_task(t: Task, splits: impl Fn(u32) -> bool, mut leaf: impl FnMut(u32, u32, u32)) {
    let mut stack = [[0u32; 4]; STACK];
    stack[0] = [t.a, t.b, t.c, t.depth];
    let mut sp = 1;
    while sp > 0 {
        sp -= 1;
        let [a, b, c, depth] = stack[sp];
        if depth > 0 && sp + 2 <= STACK {
            let m = mid(a, b);
            if splits(m) {
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

/// [`walk_task`] on the numbered vertex bitset `words`, calling `leaf` with
/// the corners' vertex indices. A triangle splits where its split point is a
/// vertex, and the split's new vertex is numbered from the word the test
/// has just read; the children inherit the other two corners' numbers on the
/// stack. So each split costs one popcount, where numbering every leaf's
/// corners cost three bitset lookups a triangle (1.0–1.09× faster
/// extractions on the benchmark grids, most at 50 m and 1 m).
#[inline(always)]
fn walk_task_ids(t: Task, words: &[Word], mut leaf: impl FnMut([u32; 3])) {
    let id = |i| vertex_id(words, i);
    let mut stack = [[0u32; 8]; STACK];
    stack[0] = [t.a, t.b, t.c, t.depth, id(t.a), id(t.b), id(t.c), 0];
    let mut sp = 1;
    while sp > 0 {
        sp -= 1;
        let [a, b, c, depth, ia, ib, ic, _] = stack[sp];
        if depth > 0 && sp + 2 <= STACK {
            let m = mid(a, b);
            if let Some(w) = words.get((m / 64) as usize) {
                if w.bits >> (m % 64) & 1 == 1 {
                    let im = w.rank(m % 64);
                    stack[sp] = [b, c, m, depth - 1, ib, ic, im, 0];
                    stack[sp + 1] = [c, a, m, depth - 1, ic, ia, im, 0];
                    sp += 2;
                    continue;
                }
            }
        }
        leaf([ia, ib, ic]);
    }
}

/// Stack slots of the task walks: one per level of a task plus one.
const STACK: usize = 2 * TASK_DEPTH as usize + 2;

/// A bitset word of vertex samples and the number of vertices before it.
/// Zeroable: the arrays of them come zeroed from the allocator (see
/// [`vertices`]).
#[derive(Debug, Clone, Copy, Default, bytemuck::Zeroable)]
struct Word {
    bits: u64,
    base: u32,
}

impl Word {
    /// The vertex number of bit `b` of this word (set or not: the vertices
    /// before it).
    #[inline(always)]
    fn rank(&self, b: u32) -> u32 {
        self.base + (self.bits & ((1u64 << b) - 1)).count_ones()
    }
}

/// The vertex bitset from the error codes: every split point that splits,
/// plus the root corners inside the grid.
fn vertex_bits_from_codes(tree: &Bitree<'_>, rule: &SplitRule) -> Vec<Word> {
    let codes = tree.error_codes();
    let mut words: Vec<Word> = bytemuck::zeroed_vec(codes.len().div_ceil(64));
    words
        .par_chunks_mut(256)
        .enumerate()
        .for_each(|(k, chunk)| {
            for (j, word) in chunk.iter_mut().enumerate() {
                let first = (k * 256 + j) * 64;
                let end = (first + 64).min(codes.len());
                let span = &codes[first..end];
                let mut bits = pack(span, |c| c > rule.floor);
                if rule.ambiguous {
                    let mut rest = pack(span, |c| c == rule.tie);
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
    set_root_corners(tree, &mut words);
    words
}

/// Bit `b` set where `test(span[b])`, for a span of at most 64 codes. Full
/// spans go through a byte per code (a loop the compiler vectorises) packed
/// eight at a time by a multiply: byte `i` of `x · 0x0102…80` gathers the low
/// bits of bytes `0..=i`, shifted, so the top byte is their 8-bit mask.
#[inline(always)]
fn pack(span: &[u16], test: impl Fn(u16) -> bool) -> u64 {
    if span.len() != 64 {
        return span
            .iter()
            .enumerate()
            .fold(0u64, |bits, (b, &c)| bits | u64::from(test(c)) << b);
    }
    let mut bytes = [0u8; 64];
    for (d, &c) in bytes.iter_mut().zip(span) {
        *d = u8::from(test(c));
    }
    let mut bits = 0u64;
    for (g, eight) in bytes.chunks_exact(8).enumerate() {
        let mut le = [0u8; 8];
        le.copy_from_slice(eight);
        let x = u64::from_le_bytes(le);
        bits |= (x.wrapping_mul(0x0102_0408_1020_4080) >> 56) << (8 * g);
    }
    bits
}

/// Adds the roots' corners inside the grid to the vertex bitset: the only
/// vertices that are no split point.
fn set_root_corners(tree: &Bitree<'_>, words: &mut [Word]) {
    let hier = tree.hierarchy();
    let n = hier.size();
    for p in [[0, 0], [n, 0], [0, n], [n, n]] {
        if hier.contains(p) {
            let i = hier.index(p);
            words[i / 64].bits |= 1u64 << (i % 64);
        }
    }
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
        Some(w) => w.rank(i % 64),
        None => 0,
    }
}

/// The share of samples likely to be vertices of the mesh of `rule`, from
/// 1024 scattered codes. Only the path taken and buffer sizes depend on it,
/// never the mesh.
fn vertex_share(tree: &Bitree<'_>, rule: &SplitRule) -> f64 {
    let codes = tree.error_codes();
    let n = codes.len() as u128;
    // Scattered probes (Fibonacci hashing, reduced to the range by a
    // multiply): a regular stride would follow the hierarchy's levels, which
    // live on regular sub-lattices.
    let hits = (0..PROBES)
        .filter(|&j| {
            let h = j.wrapping_mul(0x9E37_79B9_7F4A_7C15);
            let i = ((u128::from(h) * n) >> 64) as usize;
            codes[i] > rule.floor
        })
        .count();
    hits as f64 / PROBES as f64
}

/// At this share of vertices or more, counting each task's leaves from the
/// vertex bitset costs less than copying walked runs into place.
const DENSE_SHARE: f64 = 1.0 / 16.0;

/// At this share of vertices or more, a scan of every code finds the
/// vertices faster than marking the walked triangles' corners (measured on
/// the benchmark grids: the scan costs about 0.15 ns a sample on 2 cores,
/// the corners about 6 ns a triangle more).
const SPARSE_SHARE: f64 = 1.0 / 64.0;

/// Codes looked at by [`vertex_share`].
const PROBES: u64 = 1024;

/// The leaves of every task in depth-first order, in vertex indices of the
/// numbered vertex bitset `words`, given each task's leaf count: the output
/// is allocated once at its final size and every task writes its own slice
/// of it, in parallel; nothing is copied. `None` if a task's walk does not
/// have its count of leaves.
fn emit_tasks(words: &[Word], tasks: &[Task], counts: &[usize]) -> Option<Vec<[u32; 3]>> {
    // Zeroed allocation: large blocks come from the OS already zero, so the
    // pages are touched only once, by the writers.
    let mut tris = vec![[0u32; 3]; counts.iter().sum()];
    let slices = split_lengths(&mut tris, counts.iter().copied());
    let all_counted = tasks
        .par_iter()
        .zip(slices.into_par_iter())
        .with_min_len(4)
        .all(|(t, out)| {
            let mut slots = out.iter_mut();
            let mut over = false;
            walk_task_ids(*t, words, |tri| match slots.next() {
                Some(s) => *s = tri,
                None => over = true,
            });
            !over && slots.next().is_none()
        });
    all_counted.then_some(tris)
}

/// The leaves of every task in depth-first order, as `walk` appends them to
/// a buffer: runs of tasks are walked in parallel, each into its own buffer.
/// For sparse meshes, where counting each task's leaves first would cost
/// more than copying the buffers into place.
fn walk_runs(
    tasks: &[Task],
    expected: usize,
    walk: impl Fn(Task, &mut Vec<[u32; 3]>) + Sync,
) -> Vec<Vec<[u32; 3]>> {
    // Buffers sized for a run's share of the expected triangles, plus a
    // quarter, so that few of them grow.
    let per_task = expected / tasks.len().max(1);
    // At least RUNS_PER_THREAD runs per thread, so that uneven runs even out.
    let threads = rayon::current_num_threads().max(1);
    let run = (tasks.len() / (RUNS_PER_THREAD * threads)).clamp(1, RUN);
    tasks
        .par_chunks(run)
        .map(|run| {
            let mut out = Vec::with_capacity(run.len() * (per_task + per_task / 4 + 4));
            for t in run {
                walk(*t, &mut out);
            }
            out
        })
        .collect()
}

/// `out` cut into consecutive slices of the given lengths (their sum at most
/// `out.len()`), for parallel writers.
fn split_lengths<T>(out: &mut [T], lens: impl IntoIterator<Item = usize>) -> Vec<&mut [T]> {
    let mut slices = Vec::new();
    let mut rest = out;
    for n in lens {
        let (head, tail) = rest.split_at_mut(n);
        slices.push(head);
        rest = tail;
    }
    slices
}

/// The runs of [`walk_runs`] in order, corners mapped by `id`, copied into
/// place in parallel.
fn place_runs(parts: &[Vec<[u32; 3]>], id: impl Fn(u32) -> u32 + Sync) -> Vec<[u32; 3]> {
    let mut tris = vec![[0u32; 3]; parts.iter().map(Vec::len).sum()];
    let slices = split_lengths(&mut tris, parts.iter().map(Vec::len));
    parts
        .par_iter()
        .zip(slices.into_par_iter())
        .with_min_len(8)
        .for_each(|(p, s)| {
            for (d, t) in s.iter_mut().zip(p) {
                *d = t.map(&id);
            }
        });
    tris
}

/// Most tasks per run of [`walk_runs`].
const RUN: usize = 16;

/// Fewest runs per thread in [`walk_runs`] (when there are tasks enough).
const RUNS_PER_THREAD: usize = 16;

/// Leaves under task `t` of the mesh whose vertex set is `words` (grid
/// width `w`), without walking it.
///
/// Every split inside the task adds one leaf, and a split is a vertex `v` of
/// the mesh seen from one of the (at most two) triangles of its diamond. A
/// diamond is a square around `v`, and the task is a bitree triangle coarser
/// than it, so the diamond has both triangles in the task when `v` is inside
/// it, one when `v` is on one of its edges (the task's own split point
/// included), and none at its corners. So the leaves are
/// `1 + 2·inside + on_edges = 1 + 2·closed − boundary − corners`, counted
/// row by row with popcounts. A task deeper than [`TASK_DEPTH`] is made only
/// when it does not split: one leaf.
fn leaves_from_bits(words: &[Word], w: usize, t: &Task) -> usize {
    if t.depth > TASK_DEPTH {
        return 1;
    }
    let w64 = w as i64;
    let xy = |i: u32| [i64::from(i) % w64, i64::from(i) / w64];
    let spans = RowSpans::new([xy(t.a), xy(t.b), xy(t.c)]);
    let (y0, y1) = spans.rows();
    let (mut closed, mut boundary) = (0usize, 0usize);
    for y in y0..=y1 {
        let (l, r) = spans.at(y);
        if l > r {
            continue;
        }
        let (i, j) = ((y * w64 + l) as usize, (y * w64 + r) as usize);
        let n = ones(words, i, j);
        closed += n;
        boundary += if spans.horizontal() == Some(y) {
            n
        } else {
            usize::from(is_vertex(words, i)) + usize::from(j > i && is_vertex(words, j))
        };
    }
    let at_corners: usize = [t.a, t.b, t.c]
        .iter()
        .map(|&i| usize::from(is_vertex(words, i as usize)))
        .sum();
    (1 + 2 * closed).saturating_sub(boundary + at_corners)
}

/// Whether sample `i` is a vertex.
#[inline(always)]
fn is_vertex(words: &[Word], i: usize) -> bool {
    words
        .get(i / 64)
        .is_some_and(|wd| wd.bits >> (i % 64) & 1 == 1)
}

/// Vertices among samples `i..=j`.
fn ones(words: &[Word], i: usize, j: usize) -> usize {
    let (wi, wj) = (i / 64, j / 64);
    let lo = !0u64 << (i % 64);
    let hi = !0u64 >> (63 - j % 64);
    let bits = |k: usize| words.get(k).map_or(0, |wd| wd.bits);
    if wi == wj {
        return (bits(wi) & lo & hi).count_ones() as usize;
    }
    let mut n = (bits(wi) & lo).count_ones() + (bits(wj) & hi).count_ones();
    for k in wi + 1..wj {
        n += bits(k).count_ones();
    }
    n as usize
}

/// The mesh vertices of the numbered bitset, row-major, in parallel.
fn vertices(tree: &Bitree<'_>, words: &[Word]) -> Vec<MeshVertex> {
    let total = words.last().map_or(0, |w| w.base + w.bits.count_ones());
    let grid = tree.grid();
    let w = grid.width() as u32;
    let heights = grid.heights();
    // Zeroed allocation: a large one comes from the OS already zero, so its
    // pages are first touched by the parallel writers below, not by a
    // sequential fill (at 93 MB of vertices that fill took 56–82 ms here).
    let mut vertices: Vec<MeshVertex> = bytemuck::zeroed_vec(total as usize);
    const CHUNK: usize = 1024;
    // Vertices per chunk of words, from the numbering's prefix.
    let first = |k: usize| words.get(k * CHUNK).map_or(total, |w| w.base) as usize;
    let slices = split_lengths(
        &mut vertices,
        (0..words.len().div_ceil(CHUNK)).map(|k| first(k + 1) - first(k)),
    );
    words
        .par_chunks(CHUNK)
        .zip(slices.into_par_iter())
        .enumerate()
        .for_each(|(k, (chunk, out))| {
            let mut slots = out.iter_mut();
            // One division per chunk: the first sample of each word is
            // advanced by 64 columns, wrapping rows, without dividing.
            let start = (k * CHUNK * 64) as u32;
            let (mut row0, mut col0) = (start / w, start % w);
            for (j, word) in chunk.iter().enumerate() {
                if j > 0 {
                    col0 += 64;
                    while col0 >= w {
                        col0 -= w;
                        row0 += 1;
                    }
                }
                let first = start + 64 * j as u32;
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

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, reason = "tests unwrap to fail loudly")]

    use super::*;
    use crate::{GeoRef, HeightGrid};

    /// Smooth hills plus seeded noise, so that errors vary across levels.
    fn terrain(w: usize, h: usize, seed: u64) -> HeightGrid {
        let v = cota_fixtures::hills_and_noise(w, h, seed, 5.0);
        HeightGrid::new(w, h, v, GeoRef::unreferenced(10.0)).unwrap()
    }

    #[test]
    fn pack_is_the_bit_by_bit_mask() {
        let mut s = 0x2545_f491_4f6c_dd1du64;
        for len in [64usize, 63, 1, 17] {
            for _ in 0..200 {
                let span: Vec<u16> = (0..len)
                    .map(|_| {
                        s ^= s << 13;
                        s ^= s >> 7;
                        s ^= s << 17;
                        (s % 7) as u16
                    })
                    .collect();
                let want = span
                    .iter()
                    .enumerate()
                    .fold(0u64, |m, (b, &c)| m | u64::from(c > 3) << b);
                assert_eq!(pack(&span, |c| c > 3), want, "{span:?}");
            }
        }
    }

    /// The three paths give the same mesh at every density, and the leaf counts
    /// from the vertex bitset are those of the walk, task by task.
    #[test]
    fn dense_sparse_and_scattered_paths_agree() {
        for (w, h, seed) in [
            (37, 23, 1),
            (129, 65, 2),
            (300, 170, 3),
            (70, 301, 4),
            (257, 257, 5),
        ] {
            let g = terrain(w, h, seed);
            let tree = Bitree::build(&g).unwrap();
            for e in [0.0, 0.3, 1.0, 2.5, 5.0, 10.0, 20.0, 40.0, 80.0, 1e9] {
                let rule = SplitRule::new(e);
                let tasks = tree.tasks(&rule);
                let dense = tree.extract_dense(&rule, &tasks);
                let sparse = tree.extract_sparse(&rule, &tasks, 0);
                let scattered = tree.extract_scattered(&rule, &tasks, 0);
                assert_eq!(dense.vertices, sparse.vertices, "{w}x{h} E={e}");
                assert_eq!(dense.triangles, sparse.triangles, "{w}x{h} E={e}");
                assert_eq!(dense.vertices, scattered.vertices, "{w}x{h} E={e}");
                assert_eq!(dense.triangles, scattered.triangles, "{w}x{h} E={e}");
                assert_eq!(dense.triangles.len(), tree.count_at(e), "{w}x{h} E={e}");
                let words = numbered(vertex_bits_from_codes(&tree, &rule));
                for t in &tasks {
                    assert_eq!(
                        leaves_from_bits(&words, w, t),
                        count_leaves(&tree, &rule, *t),
                        "{w}x{h} E={e} task {t:?}"
                    );
                }
            }
        }
    }
}
