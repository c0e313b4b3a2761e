//! Gauss–Seidel over bands of rows in parallel: the rows are cut into bands
//! of [`BAND_ROWS`]; the even bands are relaxed in parallel, then the odd
//! ones. A band reads the last row of the band above and the first row of the
//! band below, which the other pass owns and nobody writes meanwhile. The
//! bands are fixed, whatever the number of threads, so the result is too.
//!
//! A block (here: band) Gauss–Seidel ordering of the red–black smoother of
//! Briggs, Henson & McCormick, *A Multigrid Tutorial* (2nd ed., SIAM 2000),
//! §4: inside a band the red cells, then the black ones.

use rayon::prelude::*;

/// Rows per band.
pub(super) const BAND_ROWS: usize = 32;

/// Levels of fewer cells than this are worked on by one thread: the small
/// coarse levels are visited hundreds of times per cycle (W-cycles), where
/// handing out the work would cost more than the work.
pub(super) const PARALLEL_CELLS: usize = 1 << 15;

/// Rows of `width` cells per parallel task for a level's row-wise loops: a
/// level of fewer than [`PARALLEL_CELLS`] cells is one task.
pub(super) fn min_rows(width: usize) -> usize {
    PARALLEL_CELLS.div_ceil(width.max(1))
}

/// Calls `f(first_row, band, above, below)` for every band of `rows`, even
/// bands in parallel, then odd ones; `above` is the row just above the band
/// (`None` for the first), `below` the row just below (`None` for the last).
/// Returns the largest value `f` returned. Rows of `width` cells: a level
/// of fewer than [`PARALLEL_CELLS`] cells is done on this thread, in the
/// same order (so with the same result).
pub(super) fn two_pass<T: Send + Sync>(
    rows: &mut [T],
    width: usize,
    f: impl Fn(usize, &mut [T], Option<&T>, Option<&T>) -> f32 + Sync,
) -> f32 {
    if rows.len() * width < PARALLEL_CELLS {
        return one_thread(rows, f);
    }
    let mut max = 0f32;
    for parity in 0..2 {
        let mut work: Vec<(usize, &mut [T])> = Vec::new();
        let mut fixed: Vec<Option<&[T]>> = Vec::new();
        for (k, band) in rows.chunks_mut(BAND_ROWS).enumerate() {
            if k % 2 == parity {
                work.push((k, band));
                fixed.push(None);
            } else {
                fixed.push(Some(band));
            }
        }
        let m = work
            .into_par_iter()
            .map(|(k, band)| {
                let above = k
                    .checked_sub(1)
                    .and_then(|j| fixed[j])
                    .and_then(|b| b.last());
                let below = fixed.get(k + 1).copied().flatten().and_then(|b| b.first());
                f(k * BAND_ROWS, band, above, below)
            })
            .reduce(|| 0f32, f32::max);
        max = max.max(m);
    }
    max
}

/// [`two_pass`] on this thread: the even bands, then the odd ones.
fn one_thread<T>(
    rows: &mut [T],
    f: impl Fn(usize, &mut [T], Option<&T>, Option<&T>) -> f32,
) -> f32 {
    let mut max = 0f32;
    let n = rows.len();
    for parity in 0..2 {
        let mut first = parity * BAND_ROWS;
        while first < n {
            let last = (first + BAND_ROWS).min(n);
            let (head, tail) = rows.split_at_mut(first);
            let (band, rest) = tail.split_at_mut(last - first);
            max = max.max(f(first, band, head.last(), rest.first()));
            first += 2 * BAND_ROWS;
        }
    }
    max
}

/// Row `i` of `band` mutably, with the rows just above and below it (from the
/// band, else `above` / `below`).
pub(super) fn row_with_neighbours<'b, T>(
    band: &'b mut [T],
    i: usize,
    above: Option<&'b T>,
    below: Option<&'b T>,
) -> (&'b mut T, Option<&'b T>, Option<&'b T>) {
    let (head, tail) = band.split_at_mut(i);
    let (mid, rest) = tail.split_first_mut().expect("row index inside the band");
    let up = head.last().or(above);
    let down = rest.first().or(below);
    (mid, up, down)
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn every_row_once_with_its_neighbours() {
        // Width 1: on this thread; the whole width: in parallel.
        for width in [1, PARALLEL_CELLS] {
            rows_once(width);
        }
    }

    fn rows_once(width: usize) {
        let mut rows: Vec<Vec<f32>> = (0..100).map(|y| vec![y as f32]).collect();
        let seen = std::sync::Mutex::new(Vec::new());
        two_pass(&mut rows, width, |first, band, above, below| {
            assert_eq!(above.map(|r| r[0] as usize), first.checked_sub(1));
            let last = first + band.len() - 1;
            assert_eq!(
                below.map(|r| r[0] as usize),
                (last < 99).then_some(last + 1)
            );
            for i in 0..band.len() {
                let (mid, up, down) = row_with_neighbours(band, i, above, below);
                let y = mid[0] as usize;
                assert_eq!(up.map(|r| r[0] as usize), y.checked_sub(1));
                assert_eq!(down.map(|r| r[0] as usize), (y < 99).then_some(y + 1));
                seen.lock().map(|mut s| s.push(y)).ok();
            }
            0.0
        });
        let mut s = seen.into_inner().unwrap_or_default();
        s.sort_unstable();
        assert_eq!(s, (0..100).collect::<Vec<_>>());
    }
}
