//! The source's own samples placed on the tiling's lattice: what the fit
//! ([`super::fit`]) and the errors against the source
//! ([`super::source_error`]) read.
//!
//! Papers `000_ebf7e3a88dffd361.txt` §3.2 (a triangle's error over the
//! samples it covers) and `001_49f2c365e8c41172.txt` (one hierarchy over
//! several DEMs). Two sets:
//!
//! * [`Samples`]: a geographic source (WGS 84 longitude/latitude on an
//!   affine grid). Each source row lies on one lattice row position and each
//!   column on one lattice column position, so the set is the product of two
//!   sorted axes: no position is stored per sample, and the samples in a
//!   box are a rectangle of indices.
//! * [`Listed`]: any set of sources (projected CRSs, mixed resolutions):
//!   each sample's position stored, in buckets of lattice cells.
//!
//! Both number their samples in one fixed order, the order every sum over
//! them follows, so that parts of a sharded run add in the same order as
//! the whole.

use super::scheme::GeographicScheme;
use crate::grid::{GeoRef, HeightGrid};

/// A set of source samples on the lattice: positions in global lattice
/// coordinates (fractional columns east, rows south) and heights.
pub trait SampleSet: Sync {
    /// The number of samples.
    fn len(&self) -> usize;

    /// Whether there is none.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Sample `k`: `[x, y, height_m]`.
    fn sample(&self, k: usize) -> [f64; 3];

    /// The indices of the samples in the closed box `[x0, y0, x1, y1]`,
    /// increasing, appended to `out`.
    fn within(&self, b: [f64; 4], out: &mut Vec<usize>);

    /// The set as separable axes, when it is one (row spans are then found
    /// by bisection, [`super::source_error::triangle_error`]).
    fn separable(&self) -> Option<&Samples<'_>> {
        None
    }
}

/// A part of the whole source: `grid` holds the whole source's samples from
/// column `offset[0]` and row `offset[1]` on.
#[derive(Debug, Clone, Copy)]
pub struct SourcePart<'a> {
    /// The samples.
    pub grid: &'a HeightGrid,
    /// Where they sit in the whole source, `[column, row]`.
    pub offset: [usize; 2],
}

/// The samples of a part of a geographic source, per column and per row.
#[derive(Debug, Clone)]
pub struct Samples<'a> {
    /// The part of the source.
    pub part: SourcePart<'a>,
    /// Per column in range: `(column of the part, global lattice x)`,
    /// increasing in x.
    pub cols: Vec<(usize, f64)>,
    /// Per row in range: `(row of the part, global lattice y)`, increasing
    /// in y.
    pub rows: Vec<(usize, f64)>,
}

impl<'a> Samples<'a> {
    /// The samples of `part` (a part of the source georeferenced by `g`,
    /// on the lattice of `scheme`) whose positions lie in `region` (global
    /// `[x0, y0, x1, y1]`, inclusive).
    pub fn new(
        g: &GeoRef,
        scheme: &GeographicScheme,
        part: SourcePart<'a>,
        region: [u64; 4],
    ) -> Samples<'a> {
        let (d, off) = (scheme.cell_deg(), scheme.lon_offset(g.origin_x));
        let [ox, oy] = part.offset;
        let inside = |v: f64, lo: u64, hi: u64| v >= lo as f64 && v <= hi as f64;
        let mut cols: Vec<(usize, f64)> = (0..part.grid.width())
            .map(|c| (c, scheme.col_of(g.sample_xy((ox + c) as f64, 0.0).0 + off)))
            .filter(|p| inside(p.1, region[0], region[2]))
            .collect();
        let mut rows: Vec<(usize, f64)> = (0..part.grid.height())
            .map(|r| (r, (90.0 - g.sample_xy(0.0, (oy + r) as f64).1) / d))
            .filter(|p| inside(p.1, region[1], region[3]))
            .collect();
        cols.sort_by(|a, b| a.1.total_cmp(&b.1));
        rows.sort_by(|a, b| a.1.total_cmp(&b.1));
        Samples { part, cols, rows }
    }

    /// The height of the sample at column `i`, row `j` of the axes.
    #[inline]
    pub(crate) fn height(&self, i: usize, j: usize) -> f64 {
        let g = self.part.grid;
        f64::from(g.heights()[self.rows[j].0 * g.width() + self.cols[i].0])
    }

    /// The range of axis indices whose positions lie in `[lo, hi]`.
    fn range(axis: &[(usize, f64)], lo: f64, hi: f64) -> std::ops::Range<usize> {
        axis.partition_point(|p| p.1 < lo)..axis.partition_point(|p| p.1 <= hi)
    }
}

impl SampleSet for Samples<'_> {
    fn len(&self) -> usize {
        self.cols.len() * self.rows.len()
    }

    #[inline]
    fn sample(&self, k: usize) -> [f64; 3] {
        let n = self.cols.len();
        let (i, j) = (k % n, k / n);
        [self.cols[i].1, self.rows[j].1, self.height(i, j)]
    }

    fn within(&self, b: [f64; 4], out: &mut Vec<usize>) {
        let n = self.cols.len();
        let cols = Samples::range(&self.cols, b[0], b[2]);
        for j in Samples::range(&self.rows, b[1], b[3]) {
            out.extend(cols.clone().map(|i| j * n + i));
        }
    }

    fn separable(&self) -> Option<&Samples<'_>> {
        Some(self)
    }
}

/// Samples with their positions stored, in buckets of `CELLS × CELLS`
/// lattice cells.
#[derive(Debug, Clone, Default)]
pub struct Listed {
    samples: Vec<[f64; 3]>,
    /// The first bucket's corner, global lattice.
    origin: [f64; 2],
    dims: [usize; 2],
    /// Per bucket (row-major), its samples' indices: `index[starts[b]..starts[b + 1]]`.
    starts: Vec<usize>,
    index: Vec<u32>,
}

impl Listed {
    /// Lattice cells across a bucket.
    const CELLS: f64 = 4.0;

    /// The set of `samples` (`[x, y, height_m]`, global lattice), in their
    /// order.
    pub fn new(samples: Vec<[f64; 3]>) -> Listed {
        if samples.is_empty() {
            return Listed::default();
        }
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for s in &samples {
            for a in 0..2 {
                lo[a] = lo[a].min(s[a]);
                hi[a] = hi[a].max(s[a]);
            }
        }
        let origin = [
            (lo[0] / Self::CELLS).floor() * Self::CELLS,
            (lo[1] / Self::CELLS).floor() * Self::CELLS,
        ];
        let dims = [0, 1].map(|a| ((hi[a] - origin[a]) / Self::CELLS) as usize + 1);
        let bucket = |s: &[f64; 3]| {
            let i = ((s[0] - origin[0]) / Self::CELLS) as usize;
            let j = ((s[1] - origin[1]) / Self::CELLS) as usize;
            j.min(dims[1] - 1) * dims[0] + i.min(dims[0] - 1)
        };
        let mut starts = vec![0usize; dims[0] * dims[1] + 1];
        for s in &samples {
            starts[bucket(s) + 1] += 1;
        }
        for b in 1..starts.len() {
            starts[b] += starts[b - 1];
        }
        let mut fill = starts.clone();
        let mut index = vec![0u32; samples.len()];
        for (k, s) in samples.iter().enumerate() {
            let b = bucket(s);
            index[fill[b]] = k as u32;
            fill[b] += 1;
        }
        Listed {
            samples,
            origin,
            dims,
            starts,
            index,
        }
    }
}

impl SampleSet for Listed {
    fn len(&self) -> usize {
        self.samples.len()
    }

    #[inline]
    fn sample(&self, k: usize) -> [f64; 3] {
        self.samples[k]
    }

    fn within(&self, b: [f64; 4], out: &mut Vec<usize>) {
        if self.samples.is_empty() {
            return;
        }
        let first = out.len();
        let cell = |v: f64, o: f64, n: usize| {
            (((v - o) / Self::CELLS).floor().max(0.0) as usize).min(n - 1)
        };
        let (i0, i1) = (
            cell(b[0], self.origin[0], self.dims[0]),
            cell(b[2], self.origin[0], self.dims[0]),
        );
        let (j0, j1) = (
            cell(b[1], self.origin[1], self.dims[1]),
            cell(b[3], self.origin[1], self.dims[1]),
        );
        for j in j0..=j1 {
            for i in i0..=i1 {
                let bk = j * self.dims[0] + i;
                for &k in &self.index[self.starts[bk]..self.starts[bk + 1]] {
                    let s = self.samples[k as usize];
                    if s[0] >= b[0] && s[0] <= b[2] && s[1] >= b[1] && s[1] <= b[3] {
                        out.push(k as usize);
                    }
                }
            }
        }
        out[first..].sort_unstable();
    }
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn listed_finds_what_a_scan_finds() {
        let pts: Vec<[f64; 3]> = (0..500)
            .map(|k| {
                let t = k as f64;
                [100.0 + (t * 7.3) % 40.0, 200.0 + (t * 3.1) % 25.0, t]
            })
            .collect();
        let l = Listed::new(pts.clone());
        for b in [
            [110.0, 205.0, 121.5, 212.0],
            [99.0, 199.0, 141.0, 226.0],
            [130.0, 220.0, 130.0, 220.0],
        ] {
            let mut got = Vec::new();
            l.within(b, &mut got);
            let want: Vec<usize> = (0..pts.len())
                .filter(|&k| {
                    pts[k][0] >= b[0] && pts[k][0] <= b[2] && pts[k][1] >= b[1] && pts[k][1] <= b[3]
                })
                .collect();
            assert_eq!(got, want);
        }
    }
}
