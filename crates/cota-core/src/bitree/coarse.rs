//! The coarse levels of the bitree build, in one banded pass over the rows.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §2 (the bitree) and
//! `001_49f2c365e8c41172.txt` (the error of a split point, monotone up the
//! tree). A split point's code is the larger of two things (see the
//! [`super`] module docs): its *own* error, the largest `e(T)` of its
//! diamond's triangles, and its children's codes. Only the second ties a level
//! to the one below it. The own errors of the coarse levels, the levels above
//! the ones [`super::fused`] builds, are what costs: each of those levels
//! reads every sample once, and on a grid larger than the cache, built level by
//! level, each would be one more pass streaming the heights from memory
//! (`2·log2(N)` of them in all, 12 on a 4097² grid).
//!
//! So the build is split in two:
//! 1. **Own errors, banded.** The rows are cut into bands that fit in a
//!    core's L2 cache, taken from a shared queue by whichever thread is free
//!    (during the fine levels' sweep, by a thread with no segment left; then
//!    alongside the seams). In each band, every coarse level
//!    scans the part of each of its inside triangles that lies in the band,
//!    row by row exactly as [`super::span_error`] does, and keeps the largest
//!    deviation per split point (an atomic maximum over the bands): the
//!    heights are read from memory once for all the coarse levels.
//! 2. **Closure, level by level.** Fine to coarse, each split point's code
//!    is the maximum of its children's codes and its own error's code, `+∞`
//!    where a triangle of its diamond straddles the grid's border. A few
//!    thousand points on a 4097² grid.
//!
//! The codes are the level-by-level build's, bit for bit: a maximum is exact
//! whatever the order it is taken in, and every row is evaluated by the same
//! code with the same plane (tested against the level-by-level build).
//!
//! # Runtime
//! One pass over the grid for all the banded levels, `O(n log n)` plane
//! evaluations (each level visits every sample once) but `O(n)` reads from
//! memory; the closure is `O(n / 64²)`.

use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

use rayon::prelude::*;

use super::error::{diamond_code, Codes, Span};
use crate::hierarchy::{
    diamond, first_col, level_rows, level_side, Hierarchy, Level, Placement, Pt,
};

/// About this many bytes of heights per band: half a core's L2 cache on the
/// machines measured (1 MiB), so the band stays there while every coarse
/// level scans it.
const BAND_BYTES: usize = 512 << 10;

/// Bands are at least this many rows (very wide grids)…
const BAND_MIN_ROWS: u32 = 4;

/// …and at most this many (narrow grids, whose bands would otherwise be few).
const BAND_MAX_ROWS: u32 = 64;

/// Rows per band for a grid `width` samples wide.
fn band_rows(width: u32) -> u32 {
    let rows = BAND_BYTES / (4 * width as usize).max(1);
    (rows as u32).clamp(BAND_MIN_ROWS, BAND_MAX_ROWS)
}

/// The split points of one level inside the grid, numbered row by row.
struct Lattice {
    level: Level,
    /// Number of the first point of each row of split points, and the total
    /// at the end.
    starts: Vec<usize>,
}

impl Lattice {
    fn new(level: Level, hier: &Hierarchy) -> Self {
        let (w, h) = (hier.width(), hier.height());
        let (first, step) = level_rows(level);
        let s = level_side(level);
        let mut starts = vec![0];
        let mut y = first;
        let mut n = 0;
        while y < h {
            let x0 = first_col(level, y);
            n += if x0 < w {
                ((w - 1 - x0) / s + 1) as usize
            } else {
                0
            };
            starts.push(n);
            y += step;
        }
        Lattice { level, starts }
    }

    /// The split points, in their numbering's order.
    fn points<'h>(&self, hier: &'h Hierarchy) -> impl Iterator<Item = Pt> + 'h {
        let (level, s) = (self.level, level_side(self.level));
        let (first, step) = level_rows(level);
        (first..hier.height())
            .step_by(step as usize)
            .flat_map(move |y| {
                (first_col(level, y)..hier.width())
                    .step_by(s as usize)
                    .map(move |x| [x, y])
            })
    }

    /// Number of split points.
    fn len(&self) -> usize {
        self.starts.last().copied().unwrap_or(0)
    }

    /// The number of the split point `m`, which must be on the lattice.
    fn index(&self, m: Pt) -> usize {
        let (first, step) = level_rows(self.level);
        let k = ((m[1] - first) / step) as usize;
        let x0 = first_col(self.level, m[1]);
        self.starts[k] + ((m[0] - x0) / level_side(self.level)) as usize
    }
}

/// The own errors of a run of consecutive levels, filled band by band from
/// a shared queue of bands ([`OwnErrors::scan_next`]), then closed into codes
/// by [`close`]. The bands read the heights only, not the codes, so the build
/// hands them out to whichever thread has nothing else to do while the finer
/// levels are built.
pub(super) struct OwnErrors {
    /// Each level's split points and their own errors so far, as `f64` bits
    /// (non-negative `f64`s order like their bits, so an atomic maximum of
    /// the bits is the maximum of the errors).
    levels: Vec<(Lattice, Vec<AtomicU64>)>,
    /// Rows per band, and the number of bands.
    rows: u32,
    bands: u32,
    /// The next band not yet taken.
    next: AtomicU32,
}

impl OwnErrors {
    /// No band scanned yet: every own error 0.
    pub(super) fn new(hier: &Hierarchy, levels: &[Level]) -> Self {
        let levels: Vec<_> = levels
            .iter()
            .map(|&l| {
                let lattice = Lattice::new(l, hier);
                let errors = (0..lattice.len()).map(|_| AtomicU64::new(0)).collect();
                (lattice, errors)
            })
            .collect();
        let rows = band_rows(hier.width());
        let bands = if levels.is_empty() {
            0
        } else {
            hier.height().div_ceil(rows)
        };
        OwnErrors {
            levels,
            rows,
            bands,
            next: AtomicU32::new(0),
        }
    }

    /// Takes the next band from the queue and folds it into every level's
    /// own errors; `false` (doing nothing) once every band has been taken.
    pub(super) fn scan_next(&self, heights: &[f32], hier: &Hierarchy) -> bool {
        let b = self.next.fetch_add(1, Ordering::Relaxed);
        if b >= self.bands {
            // Keep the counter from wrapping however often it is asked.
            self.next.store(self.bands, Ordering::Relaxed);
            return false;
        }
        let r0 = b * self.rows;
        let r1 = (r0 + self.rows - 1).min(hier.height() - 1);
        for (lattice, errors) in &self.levels {
            scan_band(heights, hier, lattice, errors, r0, r1);
        }
        true
    }

    /// Scans every band still in the queue, on all the pool's threads.
    pub(super) fn scan_rest(&self, heights: &[f32], hier: &Hierarchy) {
        (0..rayon::current_num_threads())
            .into_par_iter()
            .with_max_len(1)
            .for_each(|_| while self.scan_next(heights, hier) {});
    }
}

/// Closes `own` (every band scanned) into the codes of its levels, fine to
/// coarse, every finer level's codes already in `codes`.
pub(super) fn close(hier: &Hierarchy, own: OwnErrors, codes: &mut [u16]) {
    debug_assert!(own.next.load(Ordering::Relaxed) >= own.bands);
    // The closure is sequential: a few thousand points on a 4097² grid, fewer
    // than the cost of two parallel sections a level on a small one.
    for (lattice, own) in own.levels {
        for (m, e) in lattice.points(hier).zip(own) {
            // The own error is the diamond's, found by the banded pass; the
            // children are a finer level's split points: final.
            let e = f64::from_bits(e.into_inner());
            let view = Codes { c: codes, base: 0 };
            codes[hier.index(m)] = diamond_code(hier, lattice.level, m, view, |_| e);
        }
    }
}

/// Builds `levels` (consecutive, fine to coarse, every finer level's codes
/// already in `codes`): own errors in one banded pass, then the closure.
#[cfg(test)]
pub(super) fn build_banded(heights: &[f32], hier: &Hierarchy, levels: &[Level], codes: &mut [u16]) {
    close(hier, own_errors(heights, hier, levels), codes);
}

/// The own error of every split point of `levels` (0 where a triangle of its
/// diamond straddles the border), every band scanned.
#[cfg(test)]
fn own_errors(heights: &[f32], hier: &Hierarchy, levels: &[Level]) -> OwnErrors {
    let own = OwnErrors::new(hier, levels);
    own.scan_rest(heights, hier);
    own
}

/// Folds into `own` the largest deviation, over rows `r0..=r1`, of the inside
/// triangles of every split point of `lattice` whose diamond meets those rows.
/// Diamonds with a triangle straddling the border are skipped: their code is
/// `+∞` whatever their own error.
fn scan_band(
    heights: &[f32],
    hier: &Hierarchy,
    lattice: &Lattice,
    own: &[AtomicU64],
    r0: u32,
    r1: u32,
) {
    let (w, h) = (hier.width(), hier.height());
    let s = level_side(lattice.level);
    let hv = |p: Pt| f64::from(heights[p[1] as usize * w as usize + p[0] as usize]);
    // A diamond of `A(s)` or `B(s)` spans the rows `s/2` either side of its
    // split point.
    let lo = r0.saturating_sub(s / 2);
    let hi = (r1 + s / 2).min(h - 1);
    let (first, step) = level_rows(lattice.level);
    let mut k = lo.saturating_sub(first).div_ceil(step);
    loop {
        let y = first + k * step;
        if y > hi {
            break;
        }
        k += 1;
        let mut x = first_col(lattice.level, y);
        while x < w {
            let m = [x, y];
            x += s;
            let tris = diamond(lattice.level, m, hier.size());
            let places = tris.map(|t| t.map(|t| hier.place(&t)));
            if places.contains(&Some(Placement::Straddling)) {
                continue;
            }
            let mut e = 0f64;
            for (t, place) in tris.iter().zip(places) {
                let (Some(t), Some(Placement::Inside)) = (t, place) else {
                    continue;
                };
                let span = Span::new(w as usize, t, [hv(t.a), hv(t.b), hv(t.c)]);
                let (ymin, ymax) = span.rows();
                let (a, b) = (ymin.max(i64::from(r0)), ymax.min(i64::from(r1)));
                if a <= b {
                    e = e.max(span.max_dev(heights, a, b));
                }
            }
            if e > 0.0 {
                own[lattice.index(m)].fetch_max(e.to_bits(), Ordering::Relaxed);
            }
        }
    }
}

#[cfg(test)]
mod test {
    use super::super::by_level::fill_level;
    use super::super::fused;
    use super::super::test::{fixture, grid, level_by_level, rough};
    use super::*;
    use crate::hierarchy::levels;

    /// The banded build gives the level-by-level build's codes on every
    /// banded level, on synthetic and real grids of several shapes (square,
    /// tall, wide, one band's worth of rows, two samples across, with
    /// diamonds straddling the borders), banding the levels above `A(64)` as
    /// the build does and above `A(16)`, where each band meets more and
    /// smaller triangles.
    #[test]
    fn banded_levels_match_the_level_by_level_build() {
        let f = rough;
        let grids = [
            grid(300, 260, f),
            grid(513, 513, f),
            grid(129, 700, f),
            grid(1100, 140, f),
            grid(200, 40, f),
            grid(3000, 2, f),
            grid(2, 3000, f),
            fixture("boulder_srtmgl3_240x144.asc"),
            fixture("bijou_gully_subset_5m_edit_dx_filled.asc"),
            fixture("S29W072.hgt.zip"),
        ];
        let mut banded_levels = 0;
        for g in &grids {
            let hier = Hierarchy::new(g.width() as u32, g.height() as u32);
            let all = levels(hier.size());
            let expected = level_by_level(g, &hier, &all);
            for fine_max in [16, 64] {
                let fine = fused::up_to(&all, fine_max);
                let mut banded = expected.clone();
                let coarse = &all[fine.len()..];
                // Clear the banded levels' codes, so that stale ones cannot pass.
                for &level in coarse {
                    fill_level(&hier, level, &mut banded, |_, _| 0);
                }
                build_banded(g.heights(), &hier, coarse, &mut banded);
                banded_levels += coarse.len();
                assert!(
                    banded == expected,
                    "{}x{} grid, levels above A({fine_max}): banded codes differ",
                    g.width(),
                    g.height()
                );
            }
        }
        assert!(banded_levels >= 40, "only {banded_levels} levels banded");
    }

    /// Each banded own error is exactly the largest `e(T)` of the diamond's
    /// inside triangles, each scanned whole: a band that misses rows, or a
    /// diamond missed by a band, shows here even where the children's codes
    /// would hide it.
    #[test]
    fn banded_own_errors_are_the_whole_triangles_errors() {
        let grids = [
            grid(300, 260, |x, y| {
                ((x * 7 + y * 13) % 29) as f32 * 0.9 + (x as f32 * 0.05).sin() * 40.0
            }),
            fixture("boulder_srtmgl3_240x144.asc"),
            fixture("bijou_gully_subset_5m_edit_dx_filled.asc"),
        ];
        let mut checked = 0;
        for g in &grids {
            let tree = crate::Bitree::build(g).unwrap();
            let hier = tree.hierarchy();
            let all = levels(hier.size());
            let coarse = &all[fused::up_to(&all, 16).len()..];
            for (lattice, errors) in own_errors(g.heights(), hier, coarse).levels {
                for m in lattice.points(hier) {
                    // The whole triangles' error; 0 where one straddles the
                    // border (the banded pass skips those diamonds).
                    let e = tree
                        .own_error_at(m)
                        .filter(|e| e.is_finite())
                        .unwrap_or(0.0);
                    let got = f64::from_bits(errors[lattice.index(m)].load(Ordering::Relaxed));
                    assert_eq!(got, e, "{:?} at {m:?}", lattice.level);
                    checked += usize::from(e > 0.0);
                }
            }
        }
        assert!(checked >= 300, "only {checked} non-zero own errors checked");
    }

    /// The lattice numbers its points `0..len` in the order it lists them.
    #[test]
    fn lattice_numbers_its_points_in_order() {
        for (w, h) in [(1025, 1025), (300, 260), (1100, 140), (129, 700)] {
            let hier = Hierarchy::new(w, h);
            for level in levels(hier.size()) {
                let lattice = Lattice::new(level, &hier);
                let points: Vec<Pt> = lattice.points(&hier).collect();
                assert_eq!(points.len(), lattice.len(), "{w}x{h} {level:?}");
                for (k, &m) in points.iter().enumerate() {
                    assert!(m[0] < w && m[1] < h);
                    assert_eq!(lattice.index(m), k, "{w}x{h} {level:?} {m:?}");
                }
            }
        }
    }

    #[test]
    fn bands_fit_the_cache_and_stay_within_bounds() {
        for w in [1025, 3601, 4097, 10_001] {
            let bytes = band_rows(w) as usize * w as usize * 4;
            assert!(bytes <= BAND_BYTES && 2 * bytes > BAND_BYTES, "{w} wide");
        }
        assert_eq!(band_rows(513), BAND_MAX_ROWS);
        assert_eq!(band_rows(200_000), BAND_MIN_ROWS);
        assert_eq!(band_rows(1), BAND_MAX_ROWS);
    }
}
