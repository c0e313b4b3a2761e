//! The error of a hierarchy triangle against the **source's own samples**
//! that fall in it: the quantity a tile's bound is stated against.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §3.2: a triangle's error is the largest
//! |plane − h| over the samples it covers. The bitree ([`crate::Bitree`])
//! measures it over the lattice's points; here the same is measured over
//! the source's samples, which the lattice does not hold (they fall between
//! its points), so a tile's triangle is judged against what the user gave.
//!
//! A triangle's samples are found row by row: the source is geographic on
//! an affine grid, so each source row has one latitude (one lattice row
//! position `y`) and its columns increasing longitudes; the triangle's
//! edges are axis-aligned or diagonal, so at each `y` it spans one interval
//! of `x`, and the columns inside it are one run, found by bisection.
//!
//! How it enters the decisions (with the lattice's own error and the fitted
//! lattice's residuals, [`super::fit`]): see [`super::cut`].
//!
//! # Runtime
//! Per level, every source sample in the region is read once (twice on a
//! shared edge), in parallel over the level's split points. Below
//! [`BY_SAMPLE_BELOW`] cells a separable set is read square by square: a
//! square's samples are a rectangle of the axes, so its five corner heights
//! are read once for all of them, each axis position's square and fraction
//! are computed once per size, and the squares that decide nothing
//! ([`super::relevant`]) are not entered. Each triangle's code is taken
//! once from its largest deviation: the rounding up to `f32` and
//! [`encode_up`] are monotone, so that is the largest of the per-sample
//! codes, and every deviation is computed by the same expressions in the
//! same order as sample by sample, so the codes are the same bit for bit.

use rayon::prelude::*;

use super::relevant::Relevant;
use super::samples::{SampleSet, Samples};
use crate::bitree::error_code::encode_up;
use crate::bitree::round_up_f32;
use crate::hierarchy::{Pt, Tri};
use crate::mesh::raster::Plane;
use crate::progress::{Counter, Progress};

/// The largest |plane − h| over the samples of `s` inside triangle `t`
/// (corner heights `z`) and inside `clip` (global, inclusive), rounded up
/// to `f32`; 0 when none.
pub fn triangle_error(t: &Tri, z: [f64; 3], s: &Samples<'_>, clip: [u64; 4]) -> f32 {
    let p = [t.a, t.b, t.c];
    let Some(plane) = Plane::new(p, z) else {
        return 0.0;
    };
    let ys = p.map(|q| f64::from(q[1]));
    let (ymin, ymax) = (ys[0].min(ys[1]).min(ys[2]), ys[0].max(ys[1]).max(ys[2]));
    let (ylo, yhi) = (ymin.max(clip[1] as f64), ymax.min(clip[3] as f64));
    let j0 = s.rows.partition_point(|r| r.1 < ylo);
    let j1 = s.rows.partition_point(|r| r.1 <= yhi);
    let mut e = 0f64;
    for j in j0..j1 {
        let y = s.rows[j].1;
        let Some((xl, xr)) = span_at(&p, y) else {
            continue;
        };
        let (xl, xr) = (xl.max(clip[0] as f64), xr.min(clip[2] as f64));
        let i0 = s.cols.partition_point(|c| c.1 < xl);
        let i1 = s.cols.partition_point(|c| c.1 <= xr);
        for i in i0..i1 {
            e = e.max((plane.at(s.cols[i].1, y) - s.height(i, j)).abs());
        }
    }
    round_up_f32(e)
}

/// The interval of `x` that the triangle `p` covers at height `y` (closed),
/// with a relative slack of `1e-12` so samples on an edge count in both
/// triangles that share it.
fn span_at(p: &[Pt; 3], y: f64) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for k in 0..3 {
        let (a, b) = (p[k], p[(k + 1) % 3]);
        let (ax, ay, bx, by) = (
            f64::from(a[0]),
            f64::from(a[1]),
            f64::from(b[0]),
            f64::from(b[1]),
        );
        let eps = 1e-12 * (ay.abs() + by.abs() + 1.0);
        if y < ay.min(by) - eps || y > ay.max(by) + eps {
            continue;
        }
        if ay == by {
            lo = lo.min(ax.min(bx));
            hi = hi.max(ax.max(bx));
        } else {
            let x = ax + (bx - ax) * (y - ay) / (by - ay);
            lo = lo.min(x);
            hi = hi.max(x);
        }
    }
    let eps = 1e-12 * (lo.abs() + 1.0);
    (lo <= hi).then_some((lo - eps, hi + eps))
}

/// Per stored point of a region (`origin`, `w × h`, row-major), the code of
/// the own error against `s` of the split points of squares of side
/// `sizes[0]` to `sizes[1]` whose triangles lie inside the region: the
/// largest of its diamond's triangles' [`triangle_error`]s. Heights from
/// `height` (global position). Other points: 0.
///
/// Squares smaller than `by_sample_below` cells are done sample by sample
/// (each finds its triangles at each level in closed form: they are many
/// and each holds a few samples); larger ones triangle by triangle, row
/// spans of samples ([`triangle_error`], as the reduce of a sharded run
/// computes them: `by_sample_below` must not exceed its band squares).
/// Tells `progress(done, total)`: each sample-by-sample size, then the rest.
#[allow(
    clippy::too_many_arguments,
    reason = "the region, the sizes, the heights and the reporting"
)]
pub fn own_errors(
    s: &impl SampleSet,
    origin: [u64; 2],
    [w, h]: [usize; 2],
    sizes: [u64; 2],
    by_sample_below: u64,
    height: &(impl Fn(u64, u64) -> f32 + Sync),
    skip: Option<&Skip<'_>>,
    progress: Progress<'_>,
) -> Vec<u16> {
    let region = [
        origin[0],
        origin[1],
        origin[0] + w as u64 - 1,
        origin[1] + h as u64 - 1,
    ];
    let at =
        |m: Pt| (u64::from(m[1]) - origin[1]) as usize * w + (u64::from(m[0]) - origin[0]) as usize;
    let first = sizes[0].max(2).next_power_of_two();
    let last = sizes[1].min(w.max(h) as u64);
    // Only a separable set has row spans; any other goes sample by sample.
    let below = if s.separable().is_some() {
        by_sample_below
    } else {
        2 * last
    };
    // A set without row spans measures every size up to `last` sample by
    // sample (`split / 2 = last`); a separable one hands the sizes from
    // `split` on to the row pass.
    let split = match s.separable() {
        Some(_) => below.clamp(first, last.max(first)),
        None if last >= first => 2 * last,
        None => first,
    };
    let small: Vec<u64> = pow2(first, split / 2).collect();
    // The sample-by-sample sizes (the most time: one share each), then
    // the levels by rows (one share together).
    let shares = small.len() + 1;
    let sizes_done = Counter::new(progress, shares);
    let mut out = by_sample(s, region, &small, height, &at, skip, &sizes_done);
    if let Some(axes) = s.separable() {
        for size in pow2(split, last) {
            for (m, code) in level_errors(axes, region, size, height, skip) {
                let i = at(m);
                out[i] = out[i].max(code);
            }
        }
    }
    sizes_done.add(1);
    if let Some(k) = skip {
        // Measured or not, an error that decides nothing is stored as 0, so
        // the codes do not depend on which squares were skipped.
        out.iter_mut()
            .filter(|c| **c <= k.floor)
            .for_each(|c| *c = 0);
    }
    out
}

/// What lets [`own_errors`] skip the squares whose source errors decide
/// nothing ([`super::relevant`]).
pub struct Skip<'a> {
    /// The residuals per square.
    pub relevant: &'a Relevant,
    /// An upper bound of the lattice error of a split point, metres.
    pub lattice_m: &'a (dyn Fn(Pt) -> f64 + Sync),
    /// The smallest floor code of every rule: codes at most this are 0.
    pub floor: u16,
}

impl Skip<'_> {
    fn needed(&self, size: u64, i: u64, j: u64) -> bool {
        self.relevant.needed(size, i, j, &self.lattice_m)
    }
}

/// Squares smaller than this many cells (and than a maximum-zoom tile):
/// [`own_errors`] sample by sample.
pub const BY_SAMPLE_BELOW: u64 = 32;

/// The powers of two from `a` to `b` inclusive.
fn pow2(a: u64, b: u64) -> impl Iterator<Item = u64> {
    std::iter::successors(Some(a), |&v| Some(v * 2)).take_while(move |&v| v <= b)
}

/// [`own_errors`] for the squares of the sides `sizes`, sample by sample:
/// each sample in the region, at each size, finds the half (`A`) and the
/// side triangle (`B`) of its square that hold it, and raises their split
/// points' codes (a sample on an edge counts once: both triangles' planes
/// agree there). The sizes' split points are distinct points, so each size
/// is one task with its own array, merged at the end; a separable set's
/// samples are read square by square ([`by_rectangles`]).
fn by_sample(
    s: &impl SampleSet,
    region: [u64; 4],
    sizes: &[u64],
    height: &(impl Fn(u64, u64) -> f32 + Sync),
    at: &(impl Fn(Pt) -> usize + Sync),
    skip: Option<&Skip<'_>>,
    done: &Counter<'_>,
) -> Vec<u16> {
    let n = ((region[2] - region[0] + 1) * (region[3] - region[1] + 1)) as usize;
    let per_size: Vec<(u64, SizeCodes)> = sizes
        .par_iter()
        .map(|&size| {
            let codes = size_codes(s, region, size, height, skip);
            done.add(1);
            (size, codes)
        })
        .collect();
    let mut codes = vec![0u16; n];
    for (size, c) in per_size {
        c.for_each(size, |m, code| {
            let i = at(m);
            codes[i] = codes[i].max(code);
        });
    }
    codes
}

/// One size's codes, per square of the region's grid of `size`-squares
/// (one more row and column for the last squares' east and south sides):
/// the centre (`A`), the north side's and the west side's midpoints (`B`).
struct SizeCodes {
    first: [u64; 2],
    dims: [usize; 2],
    codes: [Vec<u16>; 3],
}

impl SizeCodes {
    /// Calls `f` with every split point that got a code, and the code.
    fn for_each(&self, size: u64, mut f: impl FnMut(Pt, u16)) {
        let h = size / 2;
        for j in 0..self.dims[1] {
            for i in 0..self.dims[0] {
                let k = j * self.dims[0] + i;
                let (x, y) = (
                    (self.first[0] + i as u64) * size,
                    (self.first[1] + j as u64) * size,
                );
                let pts = [[x + h, y + h], [x + h, y], [x, y + h]];
                for (c, p) in self.codes.iter().zip(pts) {
                    if c[k] > 0 {
                        f([p[0] as u32, p[1] as u32], c[k]);
                    }
                }
            }
        }
    }
}

/// The codes of one size (see [`SizeCodes`]): each sample against the
/// closed-form planes of the half and the side triangle of its square that
/// hold it, a separable set square by square ([`by_rectangles`]), any other
/// sample by sample ([`one_by_one`]).
fn size_codes(
    s: &impl SampleSet,
    region: [u64; 4],
    size: u64,
    height: &(impl Fn(u64, u64) -> f32 + Sync),
    skip: Option<&Skip<'_>>,
) -> SizeCodes {
    let first = [region[0].div_ceil(size), region[1].div_ceil(size)];
    let dims = [
        ((region[2] / size + 2).saturating_sub(first[0])) as usize,
        ((region[3] / size + 2).saturating_sub(first[1])) as usize,
    ];
    let needed = skip.map(|k| needed_squares(k, size, first, dims));
    let mut codes = [0, 1, 2].map(|_| vec![0u16; dims[0] * dims[1]]);
    let mut raise = |i: usize, m: &SquareMax| {
        let code = |e: f64| encode_up(round_up_f32(e));
        // The side triangles' split points: north and west are this
        // square's, south the next row's north, east the next column's west.
        let slots = [(0, i), (1, i), (2, i + 1), (1, i + dims[0]), (2, i)];
        for ((arr, ii), e) in slots.into_iter().zip(m.0) {
            codes[arr][ii] = codes[arr][ii].max(code(e));
        }
    };
    let squares = Squares {
        region,
        size,
        first,
        dims,
        needed: needed.as_deref(),
    };
    match s.separable() {
        Some(axes) => by_rectangles(axes, &squares, height, &mut raise),
        None => one_by_one(s, &squares, height, &mut raise),
    }
    SizeCodes { first, dims, codes }
}

/// Per square of a [`SizeCodes`] grid, whether its errors can decide.
fn needed_squares(k: &Skip<'_>, size: u64, first: [u64; 2], dims: [usize; 2]) -> Vec<bool> {
    (0..dims[0] * dims[1])
        .into_par_iter()
        .map(|q| {
            let (i, j) = ((q % dims[0]) as u64, (q / dims[0]) as u64);
            k.needed(size, first[0] + i, first[1] + j)
        })
        .collect()
}

/// The grid of one size's squares in a region (see [`SizeCodes`]), and
/// which of them are measured.
struct Squares<'a> {
    region: [u64; 4],
    size: u64,
    first: [u64; 2],
    dims: [usize; 2],
    needed: Option<&'a [bool]>,
}

impl Squares<'_> {
    /// The index of square `(si, sj)` when it lies inside the region and is
    /// needed, with its corner heights `[nw, ne, sw, se, centre]`.
    fn measured(
        &self,
        si: u64,
        sj: u64,
        height: &impl Fn(u64, u64) -> f32,
    ) -> Option<(usize, [f64; 5])> {
        let (size, r) = (self.size, self.region);
        let (x0, y0) = (si * size, sj * size);
        if x0 < r[0] || x0 + size > r[2] || y0 < r[1] || y0 + size > r[3] {
            return None;
        }
        let i = (sj - self.first[1]) as usize * self.dims[0] + (si - self.first[0]) as usize;
        if self.needed.is_some_and(|n| !n[i]) {
            return None;
        }
        let h = |x: u64, y: u64| f64::from(height(x, y));
        let corners = [
            h(x0, y0),
            h(x0 + size, y0),
            h(x0, y0 + size),
            h(x0 + size, y0 + size),
            h(x0 + size / 2, y0 + size / 2),
        ];
        Some((i, corners))
    }
}

/// The largest |plane − h| of one square's samples in its half (`A`) and
/// in its side triangles (`B`: north, east, south, west), in that order;
/// NaN counts as `+∞` (as [`encode_up`] takes it). The code of a maximum is
/// the maximum of the codes ([`round_up_f32`] and [`encode_up`] are
/// monotone), so one code per triangle is the per-sample codes' maximum.
#[derive(Debug, Clone, Copy, Default)]
struct SquareMax([f64; 5]);

impl SquareMax {
    /// Raises the maxima with one sample of height `hs` at `(fx, fy)` in
    /// the square (`even`, `corners`: see [`square_planes`]).
    #[inline]
    fn add(&mut self, corners: [f64; 5], even: bool, fx: f64, fy: f64, hs: f64) {
        let (a, (b, side)) = square_planes(corners, even, fx, fy);
        let k = match side {
            Side::North => 1,
            Side::East => 2,
            Side::South => 3,
            Side::West => 4,
        };
        for (slot, z) in [(0, a), (k, b)] {
            let d = (z - hs).abs();
            let d = if d.is_nan() { f64::INFINITY } else { d };
            self.0[slot] = self.0[slot].max(d);
        }
    }
}

/// [`size_codes`] for any sample set: the samples in turn, each into the
/// square that holds it.
fn one_by_one(
    s: &impl SampleSet,
    q: &Squares<'_>,
    height: &impl Fn(u64, u64) -> f32,
    raise: &mut impl FnMut(usize, &SquareMax),
) {
    let sz = q.size as f64;
    for k in 0..s.len() {
        let [x, y, hs] = s.sample(k);
        let (si, sj) = ((x / sz).floor(), (y / sz).floor());
        if si < 0.0 || sj < 0.0 {
            continue;
        }
        let (fx, fy) = (x / sz - si, y / sz - sj);
        let Some((i, corners)) = q.measured(si as u64, sj as u64, height) else {
            continue;
        };
        let mut m = SquareMax::default();
        m.add(
            corners,
            (si as u64 + sj as u64).is_multiple_of(2),
            fx,
            fy,
            hs,
        );
        raise(i, &m);
    }
}

/// [`size_codes`] for separable samples: each square's samples are a
/// rectangle of the axes, read with its corners loaded once; each axis
/// position's square and fraction are computed once per size, as
/// [`one_by_one`] computes them per sample, so every plane value is the
/// same. Rows of squares in parallel.
fn by_rectangles(
    s: &Samples<'_>,
    q: &Squares<'_>,
    height: &(impl Fn(u64, u64) -> f32 + Sync),
    raise: &mut impl FnMut(usize, &SquareMax),
) {
    let (cols, rows) = (
        AxisRuns::new(&s.cols, q.size),
        AxisRuns::new(&s.rows, q.size),
    );
    let g = s.part.grid;
    // Rows of squares in blocks, each raised before the next is measured:
    // the maxima of a whole region at once took 48 B a square (issue 29,
    // item 6). The same squares are raised in the same order.
    for block in rows.runs.chunks(ROWS_PER_BLOCK) {
        let per_row: Vec<Vec<(usize, SquareMax)>> = block
            .par_iter()
            .map(|(sj, rr)| {
                cols.runs
                    .iter()
                    .filter_map(|(si, cr)| {
                        let (i, corners) = q.measured(*si, *sj, height)?;
                        let even = (si + sj).is_multiple_of(2);
                        let mut m = SquareMax::default();
                        for j in rr.clone() {
                            let row = &g.heights()[s.rows[j].0 * g.width()..];
                            for i in cr.clone() {
                                let hs = f64::from(row[s.cols[i].0]);
                                m.add(corners, even, cols.frac[i], rows.frac[j], hs);
                            }
                        }
                        Some((i, m))
                    })
                    .collect()
            })
            .collect();
        for (i, m) in per_row.iter().flatten() {
            raise(*i, m);
        }
    }
}

/// Rows of squares [`by_rectangles`] measures before raising their codes.
const ROWS_PER_BLOCK: usize = 64;

/// One axis of separable samples cut into squares of one size: the runs
/// of consecutive positions in one square (its index, the positions'
/// indices), and each position's fraction into its square.
struct AxisRuns {
    runs: Vec<(u64, std::ops::Range<usize>)>,
    frac: Vec<f64>,
}

impl AxisRuns {
    fn new(axis: &[(usize, f64)], size: u64) -> AxisRuns {
        let sz = size as f64;
        let mut runs: Vec<(u64, std::ops::Range<usize>)> = Vec::new();
        let mut frac = Vec::with_capacity(axis.len());
        for (k, &(_, v)) in axis.iter().enumerate() {
            let q = (v / sz).floor();
            frac.push(v / sz - q);
            if q < 0.0 {
                continue;
            }
            match runs.last_mut() {
                Some((sq, r)) if *sq == q as u64 && r.end == k => r.end = k + 1,
                _ => runs.push((q as u64, k..k + 1)),
            }
        }
        AxisRuns { runs, frac }
    }
}

/// A side of a square.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Side {
    North,
    East,
    South,
    West,
}

/// At `(fx, fy)` in a square (fractions east and south of its north-west
/// corner) whose corner heights are `[nw, ne, sw, se, centre]` and whose
/// diagonal runs `\` when `even`: the plane of the half (`A`) that holds
/// the point, and the plane of the side triangle (`B`, apex at the centre)
/// that holds it, with its side. The planes of [`super::cap::square_tris`]
/// in closed form.
#[inline]
fn square_planes(
    [nw, ne, sw, se, c]: [f64; 5],
    even: bool,
    fx: f64,
    fy: f64,
) -> (f64, (f64, Side)) {
    let half = match (even, fx >= fy, fx + fy <= 1.0) {
        (true, true, _) => nw + (ne - nw) * fx + (se - ne) * fy,
        (true, false, _) => nw + (sw - nw) * fy + (se - sw) * fx,
        (false, _, true) => nw + (ne - nw) * fx + (sw - nw) * fy,
        (false, _, false) => se + (sw - se) * (1.0 - fx) + (ne - se) * (1.0 - fy),
    };
    let side = if fy <= fx && fy <= 1.0 - fx {
        (nw + (ne - nw) * fx + (2.0 * c - nw - ne) * fy, Side::North)
    } else if fx >= fy && fx >= 1.0 - fy {
        (
            ne + (se - ne) * fy + (2.0 * c - ne - se) * (1.0 - fx),
            Side::East,
        )
    } else if fy >= fx && fy >= 1.0 - fx {
        (
            sw + (se - sw) * fx + (2.0 * c - sw - se) * (1.0 - fy),
            Side::South,
        )
    } else {
        (nw + (sw - nw) * fy + (2.0 * c - nw - sw) * fx, Side::West)
    };
    (half, side)
}

/// The codes of the triangles of the squares of side `size` inside
/// `region` (its sides as `B(size)` and halves as `A(size)`), each at its
/// split point.
fn level_errors(
    s: &Samples<'_>,
    region: [u64; 4],
    size: u64,
    height: &(impl Fn(u64, u64) -> f32 + Sync),
    skip: Option<&Skip<'_>>,
) -> Vec<(Pt, u16)> {
    let (i0, i1) = (region[0].div_ceil(size), (region[2] + 1) / size);
    let (j0, j1) = (region[1].div_ceil(size), (region[3] + 1) / size);
    if i0 >= i1 || j0 >= j1 {
        return Vec::new();
    }
    (j0..j1)
        .into_par_iter()
        .flat_map_iter(|j| {
            (i0..i1)
                .filter(move |&i| skip.is_none_or(|k| k.needed(size, i, j)))
                .flat_map(move |i| {
                    let (sides, halves) = super::cap::square_tris(i, j, size);
                    sides.into_iter().chain(halves).map(move |t| {
                        let z = [t.a, t.b, t.c]
                            .map(|q| f64::from(height(u64::from(q[0]), u64::from(q[1]))));
                        (t.mid(), encode_up(triangle_error(&t, z, s, region)))
                    })
                })
        })
        .collect()
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::grid::{Crs, GeoRef, HeightGrid, PixelIs};
    use crate::tiles::lattice::{LatticeFrame, SourcePart};
    use crate::tiles::{LatticeOptions, TileId};

    #[test]
    fn spans_hold_edges_and_nothing_else() {
        let p = [[0, 0], [4, 4], [4, 0]];
        assert_eq!(
            span_at(&p, 2.0).map(|(a, b)| (a.round(), b.round())),
            Some((2.0, 4.0))
        );
        assert!(span_at(&p, 4.5).is_none());
        let (a, b) = span_at(&p, 0.0).unwrap();
        assert!(a <= 0.0 && b >= 4.0);
    }

    /// A rough 37² grid at 10° E, 1° N, 0.01° apart, and its lattice frame.
    fn rough_grid() -> (HeightGrid, LatticeFrame) {
        let n = 37;
        let v: Vec<f32> = (0..n * n)
            .map(|k| ((k * 7919) % 1000) as f32 * 0.37 + (k % n) as f32)
            .collect();
        let g = GeoRef {
            crs: Crs::WGS84,
            origin_x: 10.0,
            origin_y: 1.0,
            pixel_x: 0.01,
            pixel_y: -0.01,
            pixel_is: PixelIs::Point,
            known: true,
        };
        let grid = HeightGrid::new(n, n, v, g).unwrap();
        let frame = LatticeFrame::of(&grid, &LatticeOptions::DEFAULT).unwrap();
        (grid, frame)
    }

    /// Square by square (a separable set) and sample by sample (the same
    /// samples listed) give the same codes, bit for bit.
    #[test]
    fn squares_and_samples_give_the_same_codes() {
        let (grid, frame) = rough_grid();
        let part = SourcePart {
            grid: &grid,
            offset: [0, 0],
        };
        let w = frame.window;
        let s = Samples::new(&frame.source_georef, &frame.scheme, part, w);
        let listed =
            crate::tiles::samples::Listed::new((0..s.len()).map(|k| s.sample(k)).collect());
        let height = |x: u64, y: u64| ((x * 31 + y * 17) % 97) as f32;
        let dims = [(w[2] - w[0] + 1) as usize, (w[3] - w[1] + 1) as usize];
        let at =
            |m: Pt| (u64::from(m[1]) - w[1]) as usize * dims[0] + (u64::from(m[0]) - w[0]) as usize;
        let done = Counter::new(crate::progress::NONE, 1);
        let sizes = [2, 4, 8, 16];
        let a = by_sample(&s, w, &sizes, &height, &at, None, &done);
        let b = by_sample(&listed, w, &sizes, &height, &at, None, &done);
        assert!(a.iter().filter(|c| **c > 0).count() > 100);
        assert_eq!(a, b);
    }

    /// Listed samples (projected or mixed sources, no row spans) are
    /// measured at every size, the largest included, as the same samples on
    /// a grid are by squares and rows.
    #[test]
    fn listed_samples_are_measured_at_every_size() {
        let (grid, frame) = rough_grid();
        let part = SourcePart {
            grid: &grid,
            offset: [0, 0],
        };
        let w = frame.window;
        let s = Samples::new(&frame.source_georef, &frame.scheme, part, w);
        let listed =
            crate::tiles::samples::Listed::new((0..s.len()).map(|k| s.sample(k)).collect());
        let dims = [(w[2] - w[0] + 1) as usize, (w[3] - w[1] + 1) as usize];
        let last = (dims[0].max(dims[1]) as u64 / 2).next_power_of_two();
        fn errors(set: &impl SampleSet, w: [u64; 4], dims: [usize; 2], last: u64) -> Vec<u16> {
            let height = |x: u64, y: u64| ((x * 31 + y * 17) % 97) as f32;
            let (origin, sizes, none) = ([w[0], w[1]], [2, last], crate::progress::NONE);
            own_errors(set, origin, dims, sizes, 2 * last, &height, None, none)
        }
        let (a, b) = (errors(&s, w, dims, last), errors(&listed, w, dims, last));
        // The split points of the largest squares: their centres.
        let centres: Vec<usize> = (0..dims[1])
            .flat_map(|y| (0..dims[0]).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let (gx, gy) = (x as u64 + w[0], y as u64 + w[1]);
                gx % last == last / 2 && gy % last == last / 2
            })
            .map(|(x, y)| y * dims[0] + x)
            .collect();
        assert!(!centres.is_empty());
        assert!(
            centres.iter().any(|&i| b[i] > 0),
            "largest size not measured"
        );
        assert_eq!(a, b);
    }

    /// A single peak between lattice points: the triangle over it sees it.
    #[test]
    fn a_peak_between_points_is_seen() {
        let n = 11;
        let mut v = vec![10f32; n * n];
        v[5 * n + 5] = 60.0;
        let g = GeoRef {
            crs: Crs::WGS84,
            origin_x: 10.0,
            origin_y: 1.0,
            pixel_x: 0.01,
            pixel_y: -0.01,
            pixel_is: PixelIs::Point,
            known: true,
        };
        let grid = HeightGrid::new(n, n, v, g).unwrap();
        let frame = LatticeFrame::of(&grid, &LatticeOptions::DEFAULT).unwrap();
        let part = SourcePart {
            grid: &grid,
            offset: [0, 0],
        };
        let s = Samples::new(&frame.source_georef, &frame.scheme, part, frame.window);
        assert_eq!((s.cols.len(), s.rows.len()), (n, n));
        let (x, y) = (s.cols[5].1, s.rows[5].1);
        let (x0, y0) = ((x as u32) - 3, (y as u32) - 3);
        let t = Tri {
            a: [x0, y0],
            b: [x0 + 8, y0 + 8],
            c: [x0 + 8, y0],
        };
        let t2 = Tri {
            a: t.b,
            b: t.a,
            c: [x0, y0 + 8],
        };
        let e = triangle_error(&t, [10.0; 3], &s, frame.window).max(triangle_error(
            &t2,
            [10.0; 3],
            &s,
            frame.window,
        ));
        assert!((e - 50.0).abs() < 1e-3, "{e}");
        let _ = TileId { z: 0, x: 0, y: 0 };
    }
}
