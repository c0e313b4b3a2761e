//! Which squares of the hierarchy can hold a triangle whose error against
//! the source's samples changes a decision: the others are not measured.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §3.2 (a split point's error is the
//! largest over the samples its triangles cover; decisions compare it with
//! a threshold). A split point splits on its source error when that error's
//! code exceeds the floor of its zoom's rule ([`super::cut`]); every rule's
//! floor is at least the smallest floor `F` of any zoom and level. So an own
//! error at most `decode(F)` changes no decision (the closure over the
//! hierarchy takes maxima: a value that never exceeds any floor never makes
//! a maximum exceed it) and is stored as 0, measured or not.
//!
//! A triangle `T` of the hierarchy is a union of the lattice's unit
//! triangles, and its plane minus the lattice's unit-triangle surface `L`
//! is linear on each of them, so `|P_T − L| ≤ e_lat(T)` everywhere in `T`,
//! `e_lat(T)` its error over the lattice's points. At a source sample `s`
//! in `T`: `|P_T(s) − h_s| ≤ e_lat(T) + |L(s) − h_s|`. With `r(Q)` the largest
//! residual `|L − h|` over the samples in `T`'s square `Q` (closed), and the
//! bitree's upper bound of `e_lat` at the square's five split points, a
//! square where `e_lat + r(Q) < decode(F)` holds no triangle whose source
//! error matters. After the fit ([`super::fit`]) residuals are small almost
//! everywhere, so most squares of the finest levels are skipped.
//!
//! # Runtime and memory
//! One pass over the samples (each sample's residual into the squares of
//! 2 × 2 cells that hold it), then `O(cells)` for the maxima of every larger
//! square: about 1.3 bytes per lattice point (squares of one cell are never
//! asked for, and not kept).

use rayon::prelude::*;

use super::samples::SampleSet;
use crate::hierarchy::Pt;

/// Margin, metres, for the floating-point rounding of the comparison.
const MARGIN_M: f64 = 1e-3;

/// The largest residual per square of each size (see the module docs).
#[derive(Debug, Clone)]
pub struct Relevant {
    floor_m: f64,
    /// Per level `k` (squares of `2^k` cells, global square indices).
    levels: Vec<Level>,
}

#[derive(Debug, Clone)]
struct Level {
    first: [u64; 2],
    dims: [usize; 2],
    max: Vec<f32>,
}

impl Level {
    fn get(&self, i: u64, j: u64) -> f32 {
        let (Some(a), Some(b)) = (i.checked_sub(self.first[0]), j.checked_sub(self.first[1]))
        else {
            return f32::INFINITY;
        };
        let (a, b) = (a as usize, b as usize);
        if a >= self.dims[0] || b >= self.dims[1] {
            return f32::INFINITY;
        }
        self.max[b * self.dims[0] + a]
    }
}

impl Relevant {
    /// The residuals of the samples of `s` in `region` (global, inclusive)
    /// against the lattice surface `surface(x, y)`, for squares up to
    /// `top` cells; own errors at most `floor_m` change no decision.
    pub fn new(
        s: &impl SampleSet,
        region: [u64; 4],
        top: u64,
        floor_m: f64,
        surface: &(impl Fn(f64, f64) -> f64 + Sync),
    ) -> Relevant {
        // Squares of one cell are never asked for (a split point's square
        // has at least 2 cells): the first level is the squares of 2.
        let mut levels = vec![pairs(s, region, surface)];
        let mut size = 4;
        while size <= top.max(2) {
            let next = coarser(&levels[levels.len() - 1]);
            levels.push(next);
            size *= 2;
        }
        Relevant { floor_m, levels }
    }

    /// Whether square `(i, j)` of `size` cells (a power of two, global
    /// square indices) may hold a triangle whose source error exceeds the
    /// floor; `lattice_m(m)` bounds the lattice error of split point `m`.
    pub fn needed(&self, size: u64, i: u64, j: u64, lattice_m: &impl Fn(Pt) -> f64) -> bool {
        let k = size.trailing_zeros() as usize;
        let Some(level) = k.checked_sub(1).and_then(|k| self.levels.get(k)) else {
            return true;
        };
        let r = f64::from(level.get(i, j));
        if !r.is_finite() {
            return true;
        }
        let (h, x, y) = (size / 2, i * size, j * size);
        let pts = [
            [x + h, y + h],
            [x + h, y],
            [x, y + h],
            [x + size, y + h],
            [x + h, y + size],
        ];
        let lat = pts
            .iter()
            .map(|p| lattice_m([p[0] as u32, p[1] as u32]))
            .fold(0.0, f64::max);
        lat + r + MARGIN_M >= self.floor_m
    }
}

/// Samples whose residuals are computed together.
const CHUNK: usize = 1 << 20;

/// The largest residual per square of 2 × 2 cells over the unit cells of
/// `region`: a sample counts in every cell of `region` whose closed span
/// holds it, and a square takes the maxima of its cells (as [`coarser`]
/// would of a level of unit cells, which is not kept: 4 B a lattice point).
fn pairs(
    s: &impl SampleSet,
    region: [u64; 4],
    surface: &(impl Fn(f64, f64) -> f64 + Sync),
) -> Level {
    let first = [region[0], region[1]];
    let dims = [
        (region[2] - region[0]).max(1) as usize,
        (region[3] - region[1]).max(1) as usize,
    ];
    let mut pairs = coarser_shape(first, dims);
    let w2 = pairs.dims[0];
    // The residuals a chunk at a time (4 B a sample of the chunk), each
    // sample's position read again rather than kept (issue 29, item 6).
    for c in 0..s.len().div_ceil(CHUNK) {
        let range = c * CHUNK..((c + 1) * CHUNK).min(s.len());
        let residual: Vec<f32> = range
            .clone()
            .into_par_iter()
            .map(|k| {
                let [x, y, h] = s.sample(k);
                (surface(x, y) - h).abs() as f32
            })
            .collect();
        for (k, r) in range.zip(residual) {
            let [x, y, _] = s.sample(k);
            for cx in touching(x, first[0], dims[0]) {
                for cy in touching(y, first[1], dims[1]) {
                    let a = (first[0] + cx as u64) / 2 - pairs.first[0];
                    let b = (first[1] + cy as u64) / 2 - pairs.first[1];
                    let m = &mut pairs.max[b as usize * w2 + a as usize];
                    // Rounded up: an f32 below the f64 residual would not bound it.
                    *m = m.max(r.next_up());
                }
            }
        }
    }
    pairs
}

/// The cells (local indices) whose closed span holds coordinate `v`.
fn touching(v: f64, first: u64, n: usize) -> impl Iterator<Item = usize> {
    let f = v.floor();
    let c = f - first as f64;
    let on_border = f == v;
    let lo = if on_border { c - 1.0 } else { c };
    (lo as i64..=c as i64).filter_map(move |i| usize::try_from(i).ok().filter(|&i| i < n))
}

/// The level of squares twice as large as those of a level at `first`
/// of `dims` squares (global indices halve), all maxima 0.
fn coarser_shape(first: [u64; 2], dims: [usize; 2]) -> Level {
    let last = [
        (first[0] + dims[0] as u64).saturating_sub(1) / 2,
        (first[1] + dims[1] as u64).saturating_sub(1) / 2,
    ];
    let first = [first[0] / 2, first[1] / 2];
    let dims = [
        (last[0] + 1 - first[0]) as usize,
        (last[1] + 1 - first[1]) as usize,
    ];
    Level {
        first,
        dims,
        max: vec![0f32; dims[0] * dims[1]],
    }
}

/// The maxima of squares twice as large (global indices halve).
fn coarser(l: &Level) -> Level {
    let Level {
        first,
        dims,
        mut max,
    } = coarser_shape(l.first, l.dims);
    for b in 0..l.dims[1] {
        for a in 0..l.dims[0] {
            let (gi, gj) = (l.first[0] + a as u64, l.first[1] + b as u64);
            let k = (gj / 2 - first[1]) as usize * dims[0] + (gi / 2 - first[0]) as usize;
            max[k] = max[k].max(l.max[b * l.dims[0] + a]);
        }
    }
    Level { first, dims, max }
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::tiles::samples::Listed;

    /// The squares of 2 cells, filled from the samples directly, are the
    /// maxima of the unit cells' levels (the old first level), on a region
    /// at an odd origin whose squares straddle its edges, samples on cell
    /// borders and outside the region included.
    #[test]
    fn pairs_are_the_maxima_of_the_unit_cells() {
        let region = [3, 5, 14, 12];
        let mut pts = Vec::new();
        for k in 0..600u32 {
            let x = 1.0 + f64::from(k % 29) * 0.5 + f64::from(k % 7) * 0.01;
            let y = 3.0 + f64::from(k / 29) * 0.5;
            pts.push([x, y, f64::from((k * 37) % 101) * 0.1]);
        }
        let s = Listed::new(pts);
        let surface = |x: f64, y: f64| 0.3 * x - 0.2 * y;
        let got = pairs(&s, region, &surface);
        let (first, dims) = ([3u64, 5u64], [11usize, 7usize]);
        let mut cells = vec![0f32; dims[0] * dims[1]];
        for k in 0..s.len() {
            let [x, y, h] = s.sample(k);
            let r = ((surface(x, y) - h).abs() as f32).next_up();
            for cx in touching(x, first[0], dims[0]) {
                for cy in touching(y, first[1], dims[1]) {
                    let m = &mut cells[cy * dims[0] + cx];
                    *m = m.max(r);
                }
            }
        }
        let want = coarser(&Level {
            first,
            dims,
            max: cells,
        });
        assert_eq!((got.first, got.dims), (want.first, want.dims));
        assert_eq!(got.max, want.max);
        assert!(got.max.iter().any(|&m| m > 0.0));
    }

    #[test]
    fn a_large_residual_marks_its_squares_and_only_them() {
        // Samples at cell centres of a 16×16 region, the lattice flat at 0;
        // one sample 5 m off at (9.5, 2.5), one on a cell border at (4, 7).
        let mut pts: Vec<[f64; 3]> = (0..16)
            .flat_map(|j| (0..16).map(move |i| [i as f64 + 0.5, j as f64 + 0.5, 0.01]))
            .collect();
        pts.push([9.5, 2.5, 5.0]);
        pts.push([4.0, 7.0, 3.0]);
        let s = Listed::new(pts);
        let r = Relevant::new(&s, [0, 0, 16, 16], 16, 1.0, &|_, _| 0.0);
        let flat = |_: Pt| 0.0;
        assert!(r.needed(2, 4, 1, &flat)); // the square (8..10, 2..4)
        assert!(!r.needed(2, 3, 1, &flat));
        assert!(r.needed(8, 1, 0, &flat));
        assert!(!r.needed(8, 0, 1, &flat));
        // The border sample counts on both sides of x = 4.
        assert!(r.needed(4, 0, 1, &flat) && r.needed(4, 1, 1, &flat));
        // A lattice error near the floor makes a square needed.
        assert!(r.needed(2, 0, 0, &|_| 0.995));
        assert!(!r.needed(2, 0, 0, &|_| 0.5));
    }
}
