//! The lattice fitted to the source's samples, so that the tiles' bound
//! holds at every sample the user gave, not only at the lattice's points.
//!
//! Papers `000_ebf7e3a88dffd361.txt` §3.2 (a triangle's error over the
//! samples it covers) and `001_49f2c365e8c41172.txt` (one hierarchy over a
//! mosaic): the tiles' hierarchy lives on the tiling's lattice, whose points
//! are not the source's samples (3″ SRTM samples fall between the 2.47″
//! lattice points of zoom 12). A bilinear lattice cuts every peak and pit
//! that falls between its points, and a finer lattice does not help: the
//! cut halves with the spacing, and so does the bound of the zoom that uses
//! it.
//!
//! # The design
//! The lattice's unit-triangle surface `L` (the surface of a tile at error
//! 0) is made to pass near every source sample `s`: with `s` in the unit
//! triangle of corners `c_i` and barycentric weights `w_i`, the residual is
//! `r(s) = h(s) − Σ w_i L(c_i)`. While `|r(s)| > τ` for some samples, each
//! such sample asks its corners for the least-norm correction that would
//! zero it, `r(s) · w_i / Σ w_j²`, and a round moves each corner by the mean
//! of its requests weighted by `w_i` (a simultaneous, component-averaged
//! Kaczmarz step: a lone sample is honoured in one round, and several
//! pulling one corner share it instead of adding up), for at most
//! [`ROUNDS`] rounds. The fit runs where the lattice is at least as fine as
//! the source (about 1.5 lattice points per SRTM sample at the default
//! maximum zoom); on a coarser lattice a cell holds several samples it
//! cannot all honour, and the lattice stays bilinear. Then a tile within `thr` of the lattice is within
//! `thr + max |r|` of the source at every sample: the tile's plane minus `L`
//! is linear on each unit triangle, so at `s` it is at most its value at the
//! corners, which the lattice check bounds. The tiles' decisions do not
//! rely on the residuals alone: each split point also carries its error
//! against the source's samples themselves ([`super::source_error`]),
//! so a sample the fit could not honour is still within the bound; the
//! largest residual bounds only the coarse levels above the window (the
//! cap), where the source errors are not measured.
//!
//! The tolerance `τ` is half the bound at the maximum zoom: only the samples
//! the finest tiles could not honour are fitted (peaks and pits between
//! lattice points), and the lattice stays the smooth bilinear surface
//! elsewhere, so coarser tiles need no more triangles than before.
//!
//! # Parts agree with the whole
//! A round reads only samples within a cell of the corners it changes, so
//! after `R` rounds a lattice point depends only on samples within `2R + 2`
//! cells: a part ([`super::Lattice::resample_part`]) is fitted over its
//! region grown by [`FIT_MARGIN`] cells and cropped, and the requests are
//! summed in the samples' row-major order, so its heights are the whole's
//! bit for bit.
//!
//! # Runtime and memory
//! One pass over the region's samples for the residuals, then per round
//! only the samples beyond `τ` and those next to the corners they moved,
//! and a last pass for the largest residual. Only the residuals beyond `τ`
//! and the corrections of the corners they move are held (before, 8 bytes
//! per sample and 16 per lattice point: the largest share of a sharded
//! part's peak while it was read and resampled).

use std::collections::BTreeMap;

use rayon::prelude::*;
use rustc_hash::FxHashMap;

use super::samples::SampleSet;
use crate::progress::{Counter, Progress, Stages};

/// Samples whose residuals are computed together (one progress count).
const CHUNK: usize = 4096;

/// The rounds of the fit.
pub const ROUNDS: usize = 12;
/// Cells a part grows by to be fitted as the whole is.
pub const FIT_MARGIN: u64 = 2 * ROUNDS as u64 + 4;

/// What [`fit`] left.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Fitted {
    /// The largest |residual| over the samples of the inner region, metres.
    pub residual_m: f64,
}

/// The unit triangle under region position `(x, y)` of a region of width
/// `w` whose global parity (`(x0 + y0)` even) is `even0`: its corners as
/// indices into the region's heights and their weights.
#[inline]
fn unit_triangle(x: f64, y: f64, w: usize, h: usize, even0: bool) -> ([usize; 3], [f64; 3]) {
    let i = (x.floor() as usize).min(w - 2);
    let j = (y.floor() as usize).min(h - 2);
    let (fx, fy) = (x - i as f64, y - j as f64);
    let nw = j * w + i;
    let (ne, sw, se) = (nw + 1, nw + w, nw + w + 1);
    let even = (i + j).is_multiple_of(2) == even0;
    if even {
        if fx >= fy {
            ([nw, ne, se], [1.0 - fx, fx - fy, fy])
        } else {
            ([nw, sw, se], [1.0 - fy, fy - fx, fx])
        }
    } else if fx + fy <= 1.0 {
        ([nw, ne, sw], [1.0 - fx - fy, fx, fy])
    } else {
        ([se, sw, ne], [fx + fy - 1.0, 1.0 - fx, 1.0 - fy])
    }
}

/// Fits `heights` (a `w × h` region whose sample (0, 0) is global lattice
/// `origin`) to the samples `at` inside it (see the module docs), down to
/// residuals of `tau_m`; the residual is reported over the samples inside
/// `inner` (global `[x0, y0, x1, y1]`); tells `progress(done, total)` as
/// the residuals are computed, then after each round (in thousandths,
/// [`crate::progress`]).
pub(crate) fn fit(
    heights: &mut [f32],
    [w, h]: [usize; 2],
    origin: [u64; 2],
    at: &impl SampleSet,
    tau_m: f64,
    inner: [u64; 4],
    progress: Progress<'_>,
) -> Fitted {
    if w < 2 || h < 2 || at.is_empty() {
        return Fitted::default();
    }
    let even0 = (origin[0] + origin[1]).is_multiple_of(2);
    let (ox, oy) = (origin[0] as f64, origin[1] as f64);
    let tri = |k: usize| {
        let [x, y, _] = at.sample(k);
        unit_triangle(x - ox, y - oy, w, h, even0)
    };
    let residual = |heights: &[f32], k: usize| {
        let (c, wt) = tri(k);
        at.sample(k)[2]
            - (0..3)
                .map(|i| wt[i] * f64::from(heights[c[i]]))
                .sum::<f64>()
    };
    // The residuals, then the rounds: about half the time each. Only the
    // residuals beyond `tau_m` are kept (a few samples: the peaks and pits
    // between lattice points), in sample order, and the corrections only
    // for the corners they move: no array per sample or per point.
    let stages = Stages::new(progress, &[1, 1]);
    let chunks = at.len().div_ceil(CHUNK);
    let first = stages.stage(0);
    let done = Counter::new(&first, chunks);
    let shared: &[f32] = heights;
    let mut hot: BTreeMap<usize, f64> = (0..chunks)
        .into_par_iter()
        .flat_map_iter(|c| {
            done.add(1);
            (c * CHUNK..((c + 1) * CHUNK).min(at.len()))
                .map(|k| (k, residual(shared, k)))
                .filter(|&(_, r)| r.abs() > tau_m)
        })
        .collect::<Vec<_>>()
        .into_iter()
        .collect();
    stages.finish(0);
    for round in 0..ROUNDS {
        stages.report(1, round, ROUNDS);
        if hot.is_empty() {
            break;
        }
        // Each corner's requests, summed in the samples' order.
        let mut asked: FxHashMap<usize, (f64, f64)> = FxHashMap::default();
        let mut touched = Vec::with_capacity(3 * hot.len());
        for (&k, &r) in &hot {
            let (c, wt) = tri(k);
            let norm = wt.iter().map(|v| v * v).sum::<f64>();
            for i in 0..3 {
                if wt[i] <= 0.0 {
                    continue;
                }
                let (corr, weight) = asked.entry(c[i]).or_insert_with(|| {
                    touched.push(c[i]);
                    (0.0, 0.0)
                });
                *corr += r * wt[i] * wt[i] / norm;
                *weight += wt[i];
            }
        }
        for &c in &touched {
            let (corr, weight) = asked[&c];
            heights[c] = (f64::from(heights[c]) + corr / weight) as f32;
        }
        for k in neighbours(at, &touched, w, origin) {
            let r = residual(heights, k);
            if r.abs() > tau_m {
                hot.insert(k, r);
            } else {
                hot.remove(&k);
            }
        }
    }
    // Every sample's residual against the fitted heights (those the rounds
    // did not reach are as they were).
    let inside = |v: f64, lo: u64, hi: u64| v >= lo as f64 && v <= hi as f64;
    let shared: &[f32] = heights;
    let residual_m = (0..at.len())
        .into_par_iter()
        .filter(|&k| {
            let [x, y, _] = at.sample(k);
            inside(x, inner[0], inner[2]) && inside(y, inner[1], inner[3])
        })
        .map(|k| residual(shared, k).abs())
        .reduce(|| 0.0, f64::max);
    stages.finish(1);
    Fitted { residual_m }
}

/// The samples in the cells around the region points `touched` (a region
/// of width `w` whose sample (0, 0) is global `origin`), each once, in
/// increasing order.
fn neighbours(at: &impl SampleSet, touched: &[usize], w: usize, origin: [u64; 2]) -> Vec<usize> {
    let mut out: Vec<usize> = Vec::new();
    for &c in touched {
        let x = (origin[0] + (c % w) as u64) as f64;
        let y = (origin[1] + (c / w) as u64) as f64;
        at.within([x - 1.0, y - 1.0, x + 1.0, y + 1.0], &mut out);
    }
    out.sort_unstable();
    out.dedup();
    out
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::tiles::samples::Listed;

    #[test]
    fn unit_triangles_interpolate_their_corners() {
        for even0 in [true, false] {
            for (x, y) in [(0.2, 0.1), (0.1, 0.7), (0.9, 0.8), (1.5, 1.25)] {
                let (c, w) = unit_triangle(x, y, 4, 4, even0);
                assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
                assert!(w.iter().all(|&v| v >= -1e-12), "{w:?}");
                // The corners are around the point.
                for k in c {
                    let (cx, cy) = ((k % 4) as f64, (k / 4) as f64);
                    assert!((cx - x).abs() <= 1.0 && (cy - y).abs() <= 1.0);
                }
            }
        }
    }

    /// A spike between lattice points: bilinear resampling cuts it, the fit
    /// brings the surface to within the tolerance of it.
    #[test]
    fn a_spike_between_lattice_points_is_honoured() {
        let n = 9;
        let mut v = vec![100f32; n * n];
        v[4 * n + 4] = 180.0;
        // Source samples 1.3 cells apart, offset by 0.45 of a cell.
        let pos = |k: usize| 0.45 + 1.3 * k as f64;
        let at = Listed::new(
            (0..n * n)
                .map(|k| [pos(k % n), pos(k / n), f64::from(v[k])])
                .collect(),
        );
        let (w, h) = (13, 13);
        let mut heights = vec![100f32; w * h];
        let f = fit(
            &mut heights,
            [w, h],
            [0, 0],
            &at,
            0.5,
            [0, 0, 12, 12],
            crate::progress::NONE,
        );
        assert!(f.residual_m <= 2.0, "{f:?}");
        assert!(heights.iter().any(|&z| z > 150.0));
    }
}
