//! The prepared bitree: exact error per split point, built once, extracted many
//! times.
//!
//! Papers `000_ebf7e3a88dffd361.txt` §2 (the bitree) and `001_49f2c365e8c41172.txt`
//! (refinement of the frontier, O(n log n)). The error measure is the one the
//! papers' tests use, made exact: for every triangle `T` of the hierarchy, `e(T)`
//! is the largest `|plane_T − h|` over **every** grid sample inside or on `T`
//! (Martini, after Evans et al. 1997, looks at the hypotenuse midpoint only,
//! which is why its "max error" is not a bound).
//!
//! # What is stored
//! One 16-bit error code per grid sample ([`crate::bitree::error_code`]: the error
//! rounded **up** to 8 significant bits, so 2 bytes per sample beside the
//! grid's 4). For the sample `m` that is the split point of a diamond (see
//! [`crate::hierarchy`]), `err[m]` is the maximum of
//! 1. `e(T)` for each triangle `T` of the diamond that lies inside the grid
//!    (`+∞` when one of them straddles the grid's border, so it is always split),
//! 2. `err` of the split points of those triangles' children.
//!
//! Rule 2 makes `err` monotone up the tree and rule 1 makes both triangles of a
//! diamond decide alike, so the extraction "split `T` iff `err[mid(T)] > E`" is
//! crack-free without any forced-split bookkeeping, and every unsplit triangle
//! meets `e(T) ≤ E`. Errors are computed in `f64` and rounded **up** to `f32`,
//! then to a code, so the bound is never understated; where a code cannot tell
//! whether `err[m] > E` (only the code just above `E`, and only when `E` is not
//! itself a code value), [`Bitree`] recomputes the exact `f32` error of `m`, so
//! the mesh is exactly the one of the unquantised errors.
//!
//! # Build
//! Fine to coarse (`B(2), A(2), B(4), A(4), …`): a split point's code needs its
//! children's. A triangle's samples are visited row by row: every edge is
//! horizontal, vertical or at 45°, so each row is one span found without
//! division, and the plane is evaluated with exact power-of-two arithmetic.
//! Each level touches every sample about once, so the build is `O(n log n)`
//! for `n` samples, about `2·log2(N)` passes.
//!
//! * **The fine levels** (up to `A(16)`, `A(32)` or `A(64)` as the grid's
//!   height allows: 8 to 12 levels, most of the split points) are
//!   built together in one cache-blocked pass (`fused::sweep`): the rows are
//!   cut into segments of equal height, as many for each thread, swept in
//!   parallel, and in each segment every level follows a few rows behind the
//!   one below it, so it reads rows that are still in cache. The seams
//!   between segments are filled by a second parallel pass
//!   (`fused::seams`). Their triangles are small, so each level has a
//!   shortcut that scans its diamond directly, without building triangles or
//!   spans, and the two finest levels are computed a row at a time.
//! * **The coarse levels** (above `A(64)`) are built in two steps
//!   (`coarse.rs`): one parallel pass over bands of rows that fit in a
//!   core's cache computes every coarse split point's own error, all levels
//!   at once, so the heights are read from memory once rather than once per
//!   level; then, level by level, each code takes the maximum with its
//!   children's (a few thousand points). The bands need no codes, so they
//!   are the work of any thread that would otherwise wait: one with no
//!   segment left to sweep, or alongside the seams.
//! * On grids too short to fuse up to `A(64)`, the levels in between are
//!   built one at a time, each in parallel over its rows of split points.
//!
//! **Legs.** The shortcuts skip the samples on a triangle's legs. A leg of an
//! inside triangle is the hypotenuse of one of its children, the plane along
//! it is the same linear interpolation of its two ends, and the child's
//! `e(T)`, which covers every sample on its hypotenuse, is in the child's
//! code, which the parent's code includes: those samples cannot change the
//! parent's code. (The general path scans them anyway; the codes are
//! identical, which the tests check.)
//!
//! # Runtime
//! `O(n log n)`: about `2·log2(max(W, H))` levels, each visiting every sample
//! once, in two passes over the heights (the fused fine levels, the banded
//! coarse ones) plus, on short grids, one per level in between; see
//! `bench/README.md`.

mod by_level;
pub(crate) mod closure;
mod coarse;
mod error;
pub mod error_code;
pub mod extract;
mod fused;
mod kernels;
pub mod points;

use crate::error::{hierarchy_for, MeshError};
use crate::grid::HeightGrid;
use crate::hierarchy::{diamond, level_of, levels, Hierarchy, Level, Placement, Pt, Tri};
use by_level::build_level;
use error::{span_error, triangle_error};
use error_code::SplitRule;
use fused::SWEEP_ROWS;
use kernels::SMALL_MAX;

pub(crate) use error::{clipped_span_error, round_up_f32};
pub use extract::{ExtractOptions, Extraction, Target, TASK_DEPTH};
pub use points::PointCounts;

/// A bitree with the exact error of every split point, ready for extraction.
///
/// "Prepare once, extract many": [`Bitree::build`] costs `O(n log n)`;
/// each [`Bitree::extract`] costs time proportional to the mesh it returns.
///
/// ```
/// use cota_core::{GeoRef, HeightGrid, Bitree, ExtractOptions, check_mesh, CheckOptions};
/// // A small real-looking grid: a ridge with noise.
/// let (w, h) = (37, 23);
/// let heights: Vec<f32> = (0..w * h)
///     .map(|i| {
///         let (x, y) = ((i % w) as f32, (i / w) as f32);
///         100.0 + 20.0 * (x * 0.3).sin() * (y * 0.2).cos() + ((i * 7919) % 13) as f32 * 0.1
///     })
///     .collect();
/// let grid = HeightGrid::new(w, h, heights, GeoRef::unreferenced(30.0)).unwrap();
/// let tin = Bitree::build(&grid).unwrap();
/// for e in [0.0, 0.5, 2.0, 10.0] {
///     let mesh = tin.extract(&ExtractOptions::max_error_m(e)).unwrap().mesh;
///     let report = check_mesh(&grid, &mesh, &CheckOptions::conforming(e)).unwrap();
///     assert!(report.metrics.max_error_m <= e);
/// }
/// ```
#[derive(Debug, Clone)]
pub struct Bitree<'g> {
    /// The grid, or (for [`Bitree::build_owned`]) the grid the tree owns.
    grid: std::borrow::Cow<'g, HeightGrid>,
    hier: Hierarchy,
    codes: Vec<u16>,
    /// The largest hierarchy triangles inside the grid, depth-first: where
    /// every extraction starts (see [`extract`]).
    inside: Vec<Tri>,
}

/// A callback told `(levels_done, levels_total)` as the build progresses
/// ([`crate::progress`]).
pub use crate::progress::Progress;

impl<'g> Bitree<'g> {
    /// Builds the exact error of every split point of `grid`.
    ///
    /// # Errors
    /// [`MeshError::GridTooSmall`], [`MeshError::GridTooLarge`], or
    /// [`MeshError::Voids`] when a sample is NaN (fill voids first).
    ///
    /// # Runtime
    /// `O(n log n)`: `2·log2(max(W, H))` levels, each visiting every sample
    /// once, in parallel, in about two passes over the heights (see the
    /// module docs).
    pub fn build(grid: &'g HeightGrid) -> Result<Self, MeshError> {
        Self::build_with_progress(grid, &|_, _| {})
    }

    /// [`Bitree::build`], calling `progress(levels_done, levels_total)` after each level.
    ///
    /// # Errors
    /// As [`Bitree::build`].
    pub fn build_with_progress(
        grid: &'g HeightGrid,
        progress: Progress<'_>,
    ) -> Result<Self, MeshError> {
        Self::from_grid(std::borrow::Cow::Borrowed(grid), progress)
    }

    /// [`Bitree::build_with_progress`] on a grid the tree keeps: the
    /// clamp-extended grid of [`crate::grid::extend`], which only the tree
    /// needs.
    ///
    /// # Errors
    /// As [`Bitree::build`].
    pub(crate) fn build_owned(
        grid: HeightGrid,
        progress: Progress<'_>,
    ) -> Result<Bitree<'static>, MeshError> {
        Bitree::from_grid(std::borrow::Cow::Owned(grid), progress)
    }

    fn from_grid(
        grid: std::borrow::Cow<'g, HeightGrid>,
        progress: Progress<'_>,
    ) -> Result<Self, MeshError> {
        let (hier, codes) = Self::codes_for(&grid, progress)?;
        let inside = hier.inside_roots();
        Ok(Bitree {
            grid,
            hier,
            codes,
            inside,
        })
    }

    /// The hierarchy and the error codes of `grid`.
    fn codes_for(
        grid: &HeightGrid,
        progress: Progress<'_>,
    ) -> Result<(Hierarchy, Vec<u16>), MeshError> {
        // One pool entry for the whole build, the void check included.
        crate::par::on_pool(|| -> Result<_, MeshError> {
            let hier = hierarchy_for(grid)?;
            let mut codes = vec![0u16; grid.len()];
            let levels = levels(hier.size());
            let threads = rayon::current_num_threads() as u32;
            let (fine, segment_rows) = fused::plan(&levels, hier.height(), threads);
            // The levels from `banded` on, above `A(SMALL_MAX)`, are built
            // by the banded pass (`coarse.rs`).
            let banded = fused::up_to(&levels, SMALL_MAX).len();
            let heights = grid.heights();
            // The coarse levels' own errors read only the heights: their
            // bands fill the time a thread would wait for the others, at the
            // end of the sweep and during the seams.
            let own = coarse::OwnErrors::new(&hier, &levels[banded..]);
            let filler = || own.scan_next(heights, &hier);
            fused::sweep(
                heights,
                &hier,
                fine,
                segment_rows,
                SWEEP_ROWS,
                &mut codes,
                &filler,
            );
            // The rest of the levels up to `A(SMALL_MAX)`, alongside the
            // bands left: the fused levels' seams, then the levels between
            // the fused ones and the banded ones (only on grids too short to
            // fuse up to `A(SMALL_MAX)`), one level at a time with their
            // shortcuts.
            rayon::join(
                || {
                    fused::seams(heights, &hier, fine, segment_rows, &mut codes);
                    progress(fine.len(), levels.len());
                    for (k, level) in levels.iter().enumerate().take(banded).skip(fine.len()) {
                        build_level(heights, &hier, *level, &mut codes);
                        progress(k + 1, levels.len());
                    }
                },
                || own.scan_rest(heights, &hier),
            );
            if banded < levels.len() {
                coarse::close(&hier, own, &mut codes);
                progress(levels.len(), levels.len());
            }
            Ok((hier, codes))
        })
    }

    /// The grid this bitree was built on.
    pub fn grid(&self) -> &HeightGrid {
        &self.grid
    }

    /// The hierarchy's shape.
    pub fn hierarchy(&self) -> &Hierarchy {
        &self.hier
    }

    /// The largest hierarchy triangles inside the grid, in depth-first order.
    pub(crate) fn inside_roots(&self) -> &[Tri] {
        &self.inside
    }

    /// The monotone error code of every split point, indexed like the grid's
    /// samples (0 at samples that split nothing); decode with
    /// [`error_code::decode`] for an upper bound in metres.
    /// [`error_code::INFINITE`] marks split points that must always split
    /// because a triangle there straddles the grid's border.
    pub fn error_codes(&self) -> &[u16] {
        &self.codes
    }

    /// An upper bound, in metres, of the monotone error of the split point at
    /// sample index `i` (`+∞`: always split; 0 for an index out of range).
    pub fn error_bound_m(&self, i: usize) -> f32 {
        self.codes.get(i).map_or(0.0, |&c| error_code::decode(c))
    }

    /// Whether the split point at sample index `i` splits under `rule`: its
    /// exact monotone error exceeds the rule's threshold.
    #[inline]
    pub(crate) fn splits_index(&self, i: usize, rule: &SplitRule) -> bool {
        match rule.decide(self.codes[i]) {
            Some(d) => d,
            None => !self.exact_within(i, rule),
        }
    }

    /// The tie-break of [`SplitRule`]: whether the exact monotone error of the
    /// split point at index `i` (whose code is `rule.floor + 1`) is at most the
    /// threshold. Recomputes the own error of `i`, and recurses into the child
    /// split points whose codes are ambiguous too (codes never grow downwards).
    #[cold]
    fn exact_within(&self, i: usize, rule: &SplitRule) -> bool {
        let w = self.hier.width() as usize;
        let m = [(i % w) as u32, (i / w) as u32];
        let own = match self.own_error_at(m) {
            Some(e) => round_up_f32(e),
            None => 0.0,
        };
        if own > rule.threshold {
            return false;
        }
        let Some(level) = level_of(m, self.hier.size()) else {
            return true;
        };
        for t in diamond(level, m, self.hier.size()).into_iter().flatten() {
            if self.hier.place(&t) != Placement::Inside {
                continue;
            }
            let (c0, c1) = t.children();
            if c0.is_unit() {
                continue;
            }
            for c in [c0.mid(), c1.mid()] {
                let j = self.hier.index(c);
                let split = match rule.decide(self.codes[j]) {
                    Some(d) => d,
                    None => !self.exact_within(j, rule),
                };
                if split {
                    return false;
                }
            }
        }
        true
    }

    /// The *own* error of the split point `m`: the largest exact `e(T)` of the
    /// triangles of its diamond that lie inside the grid, without the values
    /// propagated from finer levels (`+∞` when one straddles the border). `None`
    /// when `m` splits nothing (a root corner). Used by the point accounting of
    /// [`points`] (added for `cota compare`).
    pub(crate) fn own_error_at(&self, m: Pt) -> Option<f64> {
        let level = level_of(m, self.hier.size())?;
        let heights = self.grid.heights();
        let w = self.hier.width() as usize;
        let hv = |p: Pt| heights[p[1] as usize * w + p[0] as usize] as f64;
        let mut e = 0f64;
        for t in diamond(level, m, self.hier.size()).into_iter().flatten() {
            match self.hier.place(&t) {
                Placement::Outside => continue,
                Placement::Straddling => return Some(f64::INFINITY),
                Placement::Inside => {}
            }
            e = e.max(match level {
                Level::B(2) => triangle_error(heights, &self.hier, level, &t),
                _ => span_error(heights, w, &t, hv(t.a), hv(t.b), hv(t.c)),
            });
        }
        Some(e)
    }
}

#[cfg(test)]
mod test {
    use super::error_code::{encode_up, INFINITE};
    use super::*;
    use crate::grid::GeoRef;
    use crate::hierarchy::first_col;

    pub(super) fn grid(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> HeightGrid {
        let v = (0..w * h).map(|i| f(i % w, i / w)).collect();
        HeightGrid::new(w, h, v, GeoRef::unreferenced(1.0)).unwrap()
    }

    /// A rough synthetic terrain for comparing build paths: a sawtooth, a
    /// saddle and a wave, so that no two neighbouring diamonds agree.
    pub(super) fn rough(x: usize, y: usize) -> f32 {
        ((x * 37 + y * 11) % 13) as f32 * 1.7 - (x * y) as f32 * 0.03 + (y as f32 * 0.1).sin()
    }

    /// The codes of `levels` (consecutive from the finest) built level by
    /// level, the other samples 0: the reference the faster paths must match.
    pub(super) fn level_by_level(g: &HeightGrid, hier: &Hierarchy, levels: &[Level]) -> Vec<u16> {
        let mut codes = vec![0u16; g.len()];
        for &level in levels {
            build_level(g.heights(), hier, level, &mut codes);
        }
        codes
    }

    pub(super) use crate::testing::fixture;

    /// Brute force e(T) by testing every sample of the bounding box.
    fn brute(g: &HeightGrid, t: &Tri) -> f64 {
        let p = [t.a, t.b, t.c];
        let f = |q: Pt| g.get(q[0] as usize, q[1] as usize) as f64;
        let (x0, y0) = (p[0][0] as f64, p[0][1] as f64);
        let (x1, y1, x2, y2) = (
            p[1][0] as f64 - x0,
            p[1][1] as f64 - y0,
            p[2][0] as f64 - x0,
            p[2][1] as f64 - y0,
        );
        let det = x1 * y2 - x2 * y1;
        let mut e = 0f64;
        for y in 0..g.height() {
            for x in 0..g.width() {
                let (px, py) = (x as f64 - x0, y as f64 - y0);
                let l1 = (px * y2 - x2 * py) / det;
                let l2 = (x1 * py - px * y1) / det;
                if l1 >= -1e-12 && l2 >= -1e-12 && l1 + l2 <= 1.0 + 1e-12 {
                    let z = f(p[0]) * (1.0 - l1 - l2) + f(p[1]) * l1 + f(p[2]) * l2;
                    e = e.max((z - g.get(x, y) as f64).abs());
                }
            }
        }
        e
    }

    #[test]
    fn span_error_matches_brute_force_on_every_level() {
        let g = grid(17, 17, |x, y| {
            ((x * 31 + y * 17) % 11) as f32 + (x * y) as f32 * 0.01
        });
        let hier = Hierarchy::new(17, 17);
        for level in levels(hier.size()) {
            let s = match level {
                Level::A(s) | Level::B(s) => s,
            };
            for y in 0..17u32 {
                let mut x = first_col(level, y);
                let on_row = match level {
                    Level::A(_) => y % s == s / 2,
                    Level::B(_) => y % (s / 2) == 0,
                };
                while on_row && x < 17 {
                    for t in diamond(level, [x, y], hier.size()).into_iter().flatten() {
                        if hier.place(&t) == Placement::Inside && s > 2 {
                            let fast = triangle_error(g.heights(), &hier, level, &t);
                            let slow = brute(&g, &t);
                            assert!((fast - slow).abs() < 1e-9, "{level:?} {t:?} {fast} {slow}");
                        }
                    }
                    x += s;
                }
            }
        }
    }

    #[test]
    fn errors_are_monotone_and_planes_are_exact() {
        let g = grid(33, 20, |x, y| 3.0 * x as f32 - 0.5 * y as f32 + 100.0);
        let t = Bitree::build(&g).unwrap();
        // A plane has zero error everywhere except where the border forces splits.
        assert!(t.error_codes().iter().all(|&e| e == 0 || e == INFINITE));
    }

    /// The monotone errors as the unquantised build stored them (`f32`
    /// rounded up), computed independently from `own_error_at`.
    fn reference_errors(t: &Bitree<'_>) -> Vec<f32> {
        let hier = t.hierarchy();
        let n = hier.size();
        let rank = |l: Level| match l {
            Level::B(s) => 2 * s.trailing_zeros(),
            Level::A(s) => 2 * s.trailing_zeros() + 1,
        };
        let mut order: Vec<(u32, Pt, Level)> = (0..hier.height())
            .flat_map(|y| (0..hier.width()).map(move |x| [x, y]))
            .filter_map(|m| level_of(m, n).map(|l| (rank(l), m, l)))
            .collect();
        order.sort_by_key(|&(r, m, _)| (r, m[1], m[0]));
        let mut err = vec![0f32; t.grid().len()];
        for (_, m, level) in order {
            let mut e = t.own_error_at(m).map_or(0.0, round_up_f32);
            for tri in diamond(level, m, n).into_iter().flatten() {
                if hier.place(&tri) != Placement::Inside {
                    continue;
                }
                let (c0, c1) = tri.children();
                if !c0.is_unit() {
                    e = e
                        .max(err[hier.index(c0.mid())])
                        .max(err[hier.index(c1.mid())]);
                }
            }
            err[hier.index(m)] = e;
        }
        err
    }

    #[test]
    fn codes_bound_the_exact_errors_and_split_exactly() {
        for (w, h) in [(23, 17), (33, 33), (40, 9)] {
            let g = grid(w, h, |x, y| {
                (x as f32 * 0.37).sin() * 13.1
                    + (y as f32 * 0.23).cos() * 7.7
                    + ((x * 7 + y * 13) % 5) as f32 * 0.173
            });
            let t = Bitree::build(&g).unwrap();
            let reference = reference_errors(&t);
            for (i, (&c, &e)) in t.error_codes().iter().zip(&reference).enumerate() {
                assert_eq!(c, encode_up(e), "sample {i}");
            }
            // Thresholds exactly at, just below and between the exact errors:
            // the ambiguous codes, which the tie-break must settle.
            let mut thresholds: Vec<f64> = reference
                .iter()
                .filter(|e| e.is_finite() && **e > 0.0)
                .step_by(7)
                .flat_map(|&e| [e as f64, e.next_down() as f64, e as f64 * 0.999])
                .collect();
            thresholds.extend([0.0, 0.3, 1.7, 4.2]);
            let mut ambiguous = 0;
            for &thr in &thresholds {
                let rule = SplitRule::new(thr);
                for (i, &e) in reference.iter().enumerate() {
                    if level_of([(i % w) as u32, (i / w) as u32], t.hierarchy().size()).is_none() {
                        continue;
                    }
                    ambiguous += usize::from(rule.decide(t.error_codes()[i]).is_none());
                    let exact = e > rule.threshold;
                    assert_eq!(t.splits_index(i, &rule), exact, "sample {i}, E = {thr}");
                }
            }
            assert!(
                ambiguous > 0,
                "the thresholds never exercised the tie-break"
            );
        }
    }

    /// The build gives the same codes on any number of threads: the fused
    /// sweep's segments, their seams and the banded pass alongside them all
    /// depend on the thread count, on grids whose heights take each of the
    /// plan's cases (fused up to `A(16)`, `A(32)`, `A(64)`; one segment, four,
    /// eight), real and synthetic.
    #[test]
    fn builds_the_same_codes_on_any_number_of_threads() {
        let f = rough;
        let grids = [
            grid(90, 41, f),
            grid(300, 260, f),
            grid(180, 513, f),
            grid(150, 1201, f),
            grid(70, 2100, f),
            fixture("S29W072.hgt.zip"),
        ];
        let pool = |n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap()
        };
        for g in &grids {
            let one = pool(1).install(|| Bitree::build(g).unwrap().codes);
            assert!(one.iter().any(|&c| c != 0 && c != INFINITE));
            for n in [2, 3, 8] {
                let many = pool(n).install(|| Bitree::build(g).unwrap().codes);
                assert!(many == one, "{}×{} on {n} threads", g.width(), g.height());
            }
        }
    }

    #[test]
    fn rejects_voids_and_tiny_grids() {
        let g = grid(1, 5, |_, _| 0.0);
        assert!(matches!(
            Bitree::build(&g),
            Err(MeshError::GridTooSmall { .. })
        ));
        let g = grid(4, 4, |x, y| if x == 2 && y == 1 { f32::NAN } else { 1.0 });
        assert!(matches!(Bitree::build(&g), Err(MeshError::Voids(_))));
    }
}
