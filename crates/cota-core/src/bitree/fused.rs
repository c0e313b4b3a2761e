//! The fine levels of the bitree build, fused into one cache-blocked pass.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §2 (the bitree, built bottom-up: a split
//! point's error needs its children's). Level by level, each of the 8 to 12
//! finest levels would be one pass over the whole grid and one parallel section;
//! they hold most of the split points and their triangles are small, so the
//! build was bound by those passes. Here the rows are cut into segments that
//! are swept in parallel, every level following a few rows behind the one
//! below it while those rows are still in cache; the seams between segments
//! are filled by a second parallel pass. Every split point is computed once,
//! with the same kernels as the level-by-level build, and the codes are
//! identical (tested on synthetic and real grids, segment and sweep sizes).
//!
//! # Runtime
//! One pass over the grid for the 8 to 12 levels, plus the seams: `O(n)`.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use rayon::prelude::*;

use super::error::{code_of, diamond_error, Codes};
use super::kernels::{fine_a4, fine_b4, small_a, small_b, SMALL_MAX};
use crate::hierarchy::{first_col, level_rows, level_side, Hierarchy, Level, Pt};

/// The finest levels, `B(2)` up to at least `A(FUSED_MIN)` and at most
/// `A(FUSED_MAX)`, are built together in one pass over the rows (see
/// [`sweep`] and [`seams`]); the coarser ones one level at a time.
pub(super) const FUSED_MIN: u32 = 16;
/// See [`FUSED_MIN`].
pub(super) const FUSED_MAX: u32 = 64;

/// The fewest segments of its seam width a grid must hold for a level group
/// to be fused (two per thread on two cores).
pub(super) const MIN_SEGMENTS: u32 = 4;

/// The leading levels of `levels` (fine to coarse) up to `A(s)`.
pub(super) fn up_to(levels: &[Level], s: u32) -> &[Level] {
    let n = levels.iter().take_while(|l| level_side(**l) <= s).count();
    &levels[..n]
}

/// Which levels [`sweep`] and [`seams`] build for a grid of `height` rows on
/// `threads` threads, and in segments of how many rows (see [`segments`]).
///
/// Every fused level saves a pass over the grid, but its seams are wider
/// (`A(64)`'s segments need 252 rows): levels up to `A(64)` are fused while
/// the grid holds at least [`MIN_SEGMENTS`] segments, and always those up to
/// `A(16)`. The levels depend on the grid only, not on the thread count, so
/// that 1- and 2-thread builds do the same steps.
pub(super) fn plan(levels: &[Level], height: u32, threads: u32) -> (&[Level], u32) {
    let mut s = FUSED_MAX;
    while s > FUSED_MIN && Lags::new(up_to(levels, s)).seam_rows() * MIN_SEGMENTS > height {
        s /= 2;
    }
    let fine = up_to(levels, s);
    let seam = Lags::new(fine).seam_rows().max(1);
    // (`seam` rows at least: a grid shorter than that is one segment.)
    (
        fine,
        height.div_ceil(segments(height, seam, threads)).max(seam),
    )
}

/// How many segments of equal height the sweep cuts `height` rows into: as
/// many as are at least `seam` rows tall, up to four per thread (the smaller
/// the last ones, the less a slowed-down thread holds the others up), and a
/// multiple of the thread count where there are enough, so that each thread
/// gets as many rows as the others. (Five segments on two threads would
/// leave one thread three of them.) What imbalance is left, the coarse
/// levels' bands fill (see [`sweep`]).
fn segments(height: u32, seam: u32, threads: u32) -> u32 {
    let fit = (height / seam).max(1);
    let n = fit.min(4 * threads.max(1));
    if n >= threads {
        n - n % threads
    } else {
        n
    }
}

/// How far, in rows, each fused level's codes depend on the rows around them.
pub(super) struct Lags {
    /// `lag[l]`: rows between a split point of level `l` and the farthest
    /// sample of level 0 its code depends on (through its children, their
    /// children, …).
    lag: Vec<u32>,
    /// The farthest rows a level's children lie from it: the last level's.
    reach: u32,
}

impl Lags {
    pub(super) fn new(levels: &[Level]) -> Self {
        // A split point's children lie `s/2` rows away for `A(s)` (its
        // square's side midpoints) and `s/4` for `B(s)` (its triangles' leg
        // midpoints); `B(2)`'s children are unit triangles, with none.
        let child = |l: Level| match l {
            Level::B(2) => 0,
            Level::A(s) => s / 2,
            Level::B(s) => s / 4,
        };
        let mut lag = Vec::with_capacity(levels.len());
        let mut d = 0;
        for &l in levels {
            d += child(l);
            lag.push(d);
        }
        let reach = levels.last().map_or(0, |&l| child(l));
        Lags { lag, reach }
    }

    /// The rows a seam's fix-up reads on each side of it, and so the
    /// shortest segment: `2 × (lag + reach)` of the last level.
    pub(super) fn seam_rows(&self) -> u32 {
        2 * (self.lag.last().copied().unwrap_or(0) + self.reach)
    }
}

/// Rows each step of a segment's sweep adds to level 0 (the others follow at
/// their lag).
pub(super) const SWEEP_ROWS: u32 = 16;

/// The first part of the fused build of `levels` (`B(2), A(2), …`, fine to
/// coarse, from [`plan`]): every split point but those near the boundaries
/// between segments, which [`seams`] fills after it.
///
/// Level-by-level, each fine level would be one pass over the whole grid and
/// one parallel section. Here the grid's rows are cut into segments of
/// `segment_rows` rows, swept in parallel: each segment computes level 0
/// `sweep_rows` rows at a time, and every higher level follows `lag` rows behind,
/// where all its children are already final. So every level reads rows that
/// the one below has just touched, while they are still in cache.
///
/// Near the boundary between two segments a level's children lie on both
/// sides, so each segment leaves `lag[l]` rows of level `l` on its side of
/// the boundary: the *seams*, for [`seams`].
/// Every split point is computed once, with the same kernels as the
/// level-by-level build (the two finest levels a row at a time), and the
/// tests check that the codes are identical.
///
/// **Filler.** The segments are few (their seams make them tall), so the
/// threads can finish them far apart: one woken late, or running slower
/// than the other. Each thread takes the next segment not yet taken and,
/// when none is left, calls `filler` (one unit of other work, `false` when
/// it has none) until the last segment is done, instead of waiting for it.
pub(super) fn sweep(
    heights: &[f32],
    hier: &Hierarchy,
    levels: &[Level],
    segment_rows: u32,
    sweep_rows: u32,
    codes: &mut [u16],
    filler: &(dyn Fn() -> bool + Sync),
) {
    let (w, h) = (hier.width(), hier.height());
    let lags = Lags::new(levels);
    debug_assert!(segment_rows >= lags.seam_rows().max(1));
    let segments: Vec<Mutex<Option<&mut [u16]>>> = codes
        .chunks_mut(segment_rows as usize * w as usize)
        .map(|c| Mutex::new(Some(c)))
        .collect();
    let (next, done) = (AtomicUsize::new(0), AtomicUsize::new(0));
    let segment = |k: usize, chunk: &mut [u16]| {
        let y0 = k as u32 * segment_rows;
        let y1 = (y0 + segment_rows).min(h);
        // Level `l`'s rows in this segment: all of them at the grid's
        // edges, `lag[l]` short of each boundary with another segment.
        let lo = |l: usize| if y0 == 0 { 0 } else { y0 + lags.lag[l] };
        let hi = |l: usize| if y1 == h { h } else { y1 - lags.lag[l] };
        let mut front: Vec<u32> = (0..levels.len()).map(lo).collect();
        let mut end = y0;
        while end < y1 {
            end = (end + sweep_rows).min(y1);
            for (l, &level) in levels.iter().enumerate() {
                let stop = if end == y1 {
                    hi(l)
                } else {
                    end.saturating_sub(lags.lag[l]).min(hi(l))
                };
                if stop > front[l] {
                    rows_of_level(heights, hier, level, front[l]..stop, chunk, y0);
                    front[l] = stop;
                }
            }
        }
    };
    (0..rayon::current_num_threads())
        .into_par_iter()
        .with_max_len(1)
        .for_each(|_| loop {
            let k = next.fetch_add(1, Ordering::Relaxed);
            if let Some(slot) = segments.get(k) {
                // Each segment is taken once: its lock is never contended.
                let chunk = slot.lock().ok().and_then(|mut c| c.take());
                if let Some(chunk) = chunk {
                    segment(k, chunk);
                }
                done.fetch_add(1, Ordering::Relaxed);
            } else if done.load(Ordering::Relaxed) == segments.len() || !filler() {
                break;
            }
        });
}

/// The second part of the fused build (after [`sweep`] with the same
/// `levels` and `segment_rows`): the seams, rows `y − lag[l] .. y + lag[l]`
/// of each level `l` around each boundary `y` between segments, level by
/// level, reading `reach` rows further. The seams are independent of each
/// other, and filled in parallel.
pub(super) fn seams(
    heights: &[f32],
    hier: &Hierarchy,
    levels: &[Level],
    segment_rows: u32,
    codes: &mut [u16],
) {
    let (w, h) = (hier.width(), hier.height());
    let lags = Lags::new(levels);
    let margin = lags.lag.last().copied().unwrap_or(0) + lags.reach;
    let mut seams: Vec<(u32, &mut [u16])> = Vec::new();
    let mut rest: &mut [u16] = codes;
    let mut rest_row = 0u32;
    let mut y = segment_rows;
    while y < h && margin > 0 {
        let (r0, r1) = (y - margin, (y + margin).min(h));
        let (_, tail) =
            std::mem::take(&mut rest).split_at_mut((r0 - rest_row) as usize * w as usize);
        let (seam, tail) = tail.split_at_mut((r1 - r0) as usize * w as usize);
        seams.push((r0, seam));
        rest = tail;
        rest_row = r1;
        y += segment_rows;
    }
    seams.into_par_iter().for_each(|(r0, seam)| {
        let y = r0 + margin;
        for (l, &level) in levels.iter().enumerate() {
            let rows = y - lags.lag[l]..(y + lags.lag[l]).min(h);
            rows_of_level(heights, hier, level, rows, seam, r0);
        }
    });
}

/// Computes the split points of `level` on grid rows `rows` into `chunk`,
/// which holds grid rows `row0 ..` and every child those points have. The
/// level's shortcut is chosen once here, so that each row's loop is
/// specialised to it (the fine levels have about one split point per sample).
fn rows_of_level(
    heights: &[f32],
    hier: &Hierarchy,
    level: Level,
    rows: std::ops::Range<u32>,
    chunk: &mut [u16],
    row0: u32,
) {
    let at = Rows {
        heights,
        hier,
        level,
        rows,
        row0,
    };
    match level {
        Level::B(2) => at.fill_b2(chunk),
        Level::A(2) => at.fill_a2(chunk),
        Level::B(4) => at.fill(chunk, |m, c| fine_b4(heights, hier, m, c)),
        Level::A(4) => at.fill(chunk, |m, c| fine_a4(heights, hier, m, c)),
        Level::B(s) if s <= SMALL_MAX => at.fill(chunk, |m, c| small_b(heights, hier, s, m, c)),
        Level::A(s) if s <= SMALL_MAX => at.fill(chunk, |m, c| small_a(heights, hier, s, m, c)),
        _ => at.fill(chunk, |_, _| None),
    }
}

/// The rows of one level for [`rows_of_level`].
struct Rows<'a> {
    heights: &'a [f32],
    hier: &'a Hierarchy,
    level: Level,
    rows: std::ops::Range<u32>,
    row0: u32,
}

impl Rows<'_> {
    /// The general path's code of `m`, stored.
    #[cold]
    fn general(&self, chunk: &mut [u16], x: usize, y: usize) {
        let (w, base) = (
            self.hier.width() as usize,
            self.row0 as usize * self.hier.width() as usize,
        );
        let m = [x as u32, y as u32];
        chunk[y * w + x - base] = diamond_error(
            self.heights,
            self.hier,
            self.level,
            m,
            Codes { c: chunk, base },
        );
    }

    /// [`fine_b2`] a row at a time, as slices (the finest level has a split
    /// point at every other sample, so its per-point overhead counts most).
    fn fill_b2(&self, chunk: &mut [u16]) {
        let (w, h) = (self.hier.width() as usize, self.hier.height() as usize);
        let base = self.row0 as usize * w;
        let hv = |v: f32| v as f64;
        for y in self.rows.start as usize..self.rows.end as usize {
            if y == 0 || y + 1 >= h {
                let mut x = first_col(self.level, y as u32) as usize;
                while x < w {
                    self.general(chunk, x, y);
                    x += 2;
                }
                continue;
            }
            let out = &mut chunk[y * w - base..][..w];
            let mid = &self.heights[y * w..][..w];
            if y % 2 == 0 {
                // Horizontal hypotenuses: x = 1, 3, … ≤ w − 2.
                for (o, t) in out[1..]
                    .iter_mut()
                    .step_by(2)
                    .zip(mid.windows(3).step_by(2))
                {
                    *o = code_of((hv(t[1]) - 0.5 * (hv(t[0]) + hv(t[2]))).abs());
                }
                if w % 2 == 0 {
                    self.general(chunk, w - 1, y);
                }
            } else {
                // Vertical hypotenuses: x = 2, 4, … ≤ w − 2; x = 0 is on the border.
                let up = &self.heights[(y - 1) * w..][..w];
                let dn = &self.heights[(y + 1) * w..][..w];
                let inner = out[2..]
                    .iter_mut()
                    .step_by(2)
                    .zip(mid[2..].iter().step_by(2))
                    .zip(up[2..].iter().step_by(2).zip(dn[2..].iter().step_by(2)))
                    .take((w - 2) / 2);
                for ((o, &m), (&a, &b)) in inner {
                    *o = code_of((hv(m) - 0.5 * (hv(a) + hv(b))).abs());
                }
                self.general(chunk, 0, y);
                if w % 2 == 1 {
                    self.general(chunk, w - 1, y);
                }
            }
        }
    }

    /// [`fine_a2`] a row at a time, as slices.
    fn fill_a2(&self, chunk: &mut [u16]) {
        let (w, h) = (self.hier.width() as usize, self.hier.height() as usize);
        let base = self.row0 as usize * w;
        let hv = |v: f32| v as f64;
        let first = (self.rows.start as usize) | 1;
        for y in (first..self.rows.end as usize).step_by(2) {
            if y + 1 >= h {
                for x in (1..w).step_by(2) {
                    self.general(chunk, x, y);
                }
                continue;
            }
            let (_, rest) = chunk.split_at_mut((y - 1) * w - base);
            let (cu, rest) = rest.split_at_mut(w);
            let (cm, rest) = rest.split_at_mut(w);
            let cd = &rest[..w];
            let hu = &self.heights[(y - 1) * w..][..w];
            let hm = &self.heights[y * w..][..w];
            let hd = &self.heights[(y + 1) * w..][..w];
            // The square (k, (y−1)/2) is cut along `\` when k + (y−1)/2 is even.
            let ky = (y - 1) / 2;
            for x in (1..w - 1).step_by(2) {
                let (a, b) = if ((x - 1) / 2 + ky) % 2 == 0 {
                    (hu[x - 1], hd[x + 1])
                } else {
                    (hu[x + 1], hd[x - 1])
                };
                let own = code_of((hv(hm[x]) - 0.5 * (hv(a) + hv(b))).abs());
                cm[x] = own.max(cm[x - 1]).max(cm[x + 1]).max(cu[x]).max(cd[x]);
            }
            if w % 2 == 0 {
                self.general(chunk, w - 1, y);
            }
        }
    }

    /// Writes the code of every split point on the rows: `fast`'s, or the
    /// general path's where `fast` gives `None` (near the border).
    #[inline(always)]
    fn fill(&self, chunk: &mut [u16], fast: impl Fn(Pt, Codes<'_>) -> Option<u16>) {
        let w = self.hier.width();
        let s = level_side(self.level);
        let (first, step) = level_rows(self.level);
        let base = self.row0 as usize * w as usize;
        // The first row of the level at or after `rows.start`.
        let start = self.rows.start;
        let mut y = if start <= first {
            first
        } else {
            start + (step - (start - first) % step) % step
        };
        while y < self.rows.end {
            let mut x = first_col(self.level, y);
            while x < w {
                let m = [x, y];
                let codes = Codes { c: chunk, base };
                let code = fast(m, codes).unwrap_or_else(|| {
                    diamond_error(self.heights, self.hier, self.level, m, codes)
                });
                chunk[y as usize * w as usize + x as usize - base] = code;
                x += s;
            }
            y += step;
        }
    }
}

#[cfg(test)]
mod test {
    use super::super::levels;
    use super::super::test::{fixture, grid, level_by_level, rough};
    use super::*;

    /// The fused build of the fine levels, cut into segments with seams
    /// between them, computes exactly the codes of the level-by-level build,
    /// on synthetic and real grids, for segment heights from the shortest
    /// allowed up.
    #[test]
    fn fused_fine_levels_match_the_level_by_level_build() {
        let f = rough;
        let grids = [
            grid(70, 203, f),
            grid(131, 257, f),
            grid(200, 130, f),
            grid(9, 300, f),
            grid(40, 600, f),
            grid(65, 61, f),
            fixture("boulder_srtmgl3_240x144.asc"),
            fixture("hugo_site.asc"),
        ];
        let mut seams_cut = 0;
        for g in &grids {
            let hier = Hierarchy::new(g.width() as u32, g.height() as u32);
            let all = levels(hier.size());
            for s in [FUSED_MIN, 2 * FUSED_MIN, FUSED_MAX] {
                let fine = up_to(&all, s);
                assert!(!fine.is_empty() && fine.len() <= 12);
                let expected = level_by_level(g, &hier, fine);
                let shortest = Lags::new(fine).seam_rows();
                for segment_rows in [shortest, shortest + 5, 2 * shortest + 3] {
                    for sweep_rows in [1, 3, SWEEP_ROWS] {
                        let mut fused = vec![0u16; g.len()];
                        let no_filler = || false;
                        sweep(
                            g.heights(),
                            &hier,
                            fine,
                            segment_rows,
                            sweep_rows,
                            &mut fused,
                            &no_filler,
                        );
                        seams(g.heights(), &hier, fine, segment_rows, &mut fused);
                        seams_cut += (hier.height() - 1) / segment_rows;
                        assert!(
                        fused == expected,
                        "{}x{}, levels up to {s}, segments of {segment_rows} rows, swept {sweep_rows} at a time",
                        g.width(),
                        g.height()
                    );
                    }
                }
            }
        }
        assert!(seams_cut >= 10, "only {seams_cut} seams exercised");
    }

    /// The plan fuses more levels on taller grids, the same whatever the
    /// thread count, and never cuts a segment shorter than its seams.
    #[test]
    fn plan_fuses_more_levels_on_taller_grids() {
        let side = |l: &[Level]| l.last().map(|&l| level_side(l));
        for (height, threads, top) in [
            (40, 2, 16),
            (513, 2, 32),
            (513, 1, 32),
            (1025, 2, 64),
            (1201, 2, 64),
            (2401, 2, 64),
            (4097, 2, 64),
            (4097, 16, 64),
        ] {
            let all = levels(4096);
            let (fine, segment_rows) = plan(&all, height, threads);
            assert_eq!(side(fine), Some(top), "{height} rows, {threads} threads");
            assert!(segment_rows >= Lags::new(fine).seam_rows());
            assert!(segment_rows >= height.div_ceil(4 * threads));
            // Equal segments, as many for each thread.
            let n = height.div_ceil(segment_rows);
            assert!(
                n == 1 || n % threads == 0,
                "{height} rows, {threads} threads: {n} segments"
            );
            assert!(
                n == 1 || n * segment_rows - height < n,
                "{height} rows: {n} × {segment_rows}"
            );
        }
        // A grid too small for `A(16)` fuses all its levels.
        let all = levels(8);
        assert_eq!(plan(&all, 9, 2).0, &all[..]);
    }
}
