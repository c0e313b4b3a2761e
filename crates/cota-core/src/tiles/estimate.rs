//! What a pyramid will cost, told before it is made: its tiles, its lattice
//! and the peak memory of the run, from the lattice's frame alone (the
//! scheme, the footprint and the window; no heights are needed, so a caller
//! can refuse a run that would not fit before it allocates anything).
//!
//! 1. **Tiles**: per zoom from the minimum to the maximum, the tiles whose
//!    square meets the footprint ([`super::plan::range_at`], as the plan makes
//!    them). For a single rectangular source this is the count made; for
//!    several sources whose footprints leave gaps it is an upper bound.
//! 2. **Lattice**: the window's samples, `(x1 − x0 + 1)·(y1 − y0 + 1)`.
//! 3. **Memory**: [`BASE_BYTES`] plus [`BYTES_PER_LATTICE_SAMPLE`] per
//!    window sample plus [`BYTES_PER_SOURCE_SAMPLE`] per source sample. The
//!    window's share covers its heights (`f32`), the bitree's error codes
//!    (`u16`) and what building them holds at once, the source-error codes
//!    (`u16` per point) and the coarse levels; the source's share its grid
//!    (`f32`) and its sample positions while the lattice is fitted. The
//!    constants are fitted to the peak resident memory of `cota tiles` on
//!    SRTM 3″ tiles and a 1″ one (`/usr/bin/time`, maximum zooms 11 to 16,
//!    64 to 4096 cells a tile: 0.06 to 8.6 GB), which they match within
//!    15 % above 100 MB (issue 33; the table is in `docs/tiles-estimate.md`).
//! 4. **CPU time**: [`CPU_SECONDS_PER_LATTICE_SAMPLE`] per window sample
//!    plus [`CPU_SECONDS_PER_SOURCE_SAMPLE`] per source sample (user +
//!    system time; the wall time is about that divided by the threads).
//!    Within a factor of 2 of the runs above, on one machine (x86-64, 2
//!    cores): only its order of magnitude carries to another.

use super::lattice::LatticeFrame;
use super::plan::range_at;

/// Fixed memory of a run: the program, its thread pools and buffers, bytes.
pub const BASE_BYTES: f64 = 40.0e6;

/// Peak memory per lattice window sample, bytes (see the module docs).
pub const BYTES_PER_LATTICE_SAMPLE: f64 = 12.5;

/// Peak memory per source sample, bytes (see the module docs).
pub const BYTES_PER_SOURCE_SAMPLE: f64 = 12.0;

/// CPU time per lattice window sample, seconds (resampling, the bitree,
/// cutting the tiles; user + system time).
pub const CPU_SECONDS_PER_LATTICE_SAMPLE: f64 = 0.25e-6;

/// CPU time per source sample, seconds (reading, filling voids, fitting the
/// lattice to it and each sample's error in its triangles).
pub const CPU_SECONDS_PER_SOURCE_SAMPLE: f64 = 3.0e-6;

/// The cost of a pyramid, before it is made ([`estimate`]).
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct Estimate {
    /// Tiles from the minimum to the maximum zoom (see the module docs).
    pub tiles: u64,
    /// The zooms made, `[min, max]` (none when `min > max`: `tiles` is 0).
    pub zooms: [u8; 2],
    /// The lattice window, `[width, height]` samples.
    pub lattice_size: [u64; 2],
    /// The source's samples.
    pub source_samples: u64,
    /// The run's estimated peak memory, bytes.
    pub memory_bytes: u64,
    /// The estimated CPU time (all threads together), seconds.
    pub cpu_seconds: f64,
}

impl Estimate {
    /// The lattice window's samples.
    pub fn lattice_samples(&self) -> u64 {
        self.lattice_size[0].saturating_mul(self.lattice_size[1])
    }
}

/// The cost of the pyramid of `frame` from zoom `min_zoom` to the frame's
/// maximum zoom, over a source of `source_samples` samples (see the module
/// docs).
///
/// ```
/// use cota_core::{Crs, GeoRef, PixelIs};
/// use cota_core::tiles::{estimate, LatticeFrame, LatticeOptions};
/// // A 1201² SRTM 3″ tile, 29° S 72° W: its north-west sample at 72° W 28° S.
/// let step = 1.0 / 1200.0;
/// let g = GeoRef { crs: Crs::WGS84, origin_x: -72.0, origin_y: -28.0, pixel_x: step,
///                  pixel_y: -step, pixel_is: PixelIs::Point, known: true };
/// let frame = LatticeFrame::for_source(&g, [1201, 1201], &LatticeOptions::DEFAULT).unwrap();
/// let e = estimate(&frame, 0, 1201 * 1201);
/// assert_eq!(e.zooms, [0, 12]);
/// assert!(e.tiles > 500 && e.tiles < 1000);
/// assert!(e.memory_bytes > 50_000_000 && e.memory_bytes < 150_000_000);
/// ```
pub fn estimate(frame: &LatticeFrame, min_zoom: u8, source_samples: u64) -> Estimate {
    let s = frame.scheme;
    let tiles = (min_zoom..=s.max_zoom)
        .map(|z| range_at(&s, frame.footprint, z).count())
        .fold(0u64, u64::saturating_add);
    let [x0, y0, x1, y1] = frame.window;
    let lattice_size = [x1 - x0 + 1, y1 - y0 + 1];
    let n = lattice_size[0] as f64 * lattice_size[1] as f64;
    let memory =
        BASE_BYTES + BYTES_PER_LATTICE_SAMPLE * n + BYTES_PER_SOURCE_SAMPLE * source_samples as f64;
    Estimate {
        tiles,
        zooms: [min_zoom, s.max_zoom],
        lattice_size,
        source_samples,
        memory_bytes: memory.min(u64::MAX as f64) as u64,
        cpu_seconds: CPU_SECONDS_PER_LATTICE_SAMPLE * n
            + CPU_SECONDS_PER_SOURCE_SAMPLE * source_samples as f64,
    }
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::grid::{Crs, GeoRef, PixelIs};
    use crate::tiles::lattice::LatticeOptions;

    /// A 1° SRTM-like tile of `n`² samples whose south-west sample is at
    /// (`lon`, `lat`).
    fn frame(n: usize, lon: f64, lat: f64, opts: &LatticeOptions) -> LatticeFrame {
        let step = 1.0 / (n - 1) as f64;
        let g = GeoRef {
            crs: Crs::WGS84,
            origin_x: lon,
            origin_y: lat + 1.0,
            pixel_x: step,
            pixel_y: -step,
            pixel_is: PixelIs::Point,
            known: true,
        };
        LatticeFrame::for_source(&g, [n, n], opts).unwrap()
    }

    #[test]
    fn tiles_are_those_of_the_plan_and_grow_fourfold_a_zoom() {
        let opts = LatticeOptions::DEFAULT.with_max_zoom(Some(14));
        let f = frame(1201, -72.0, -29.0, &opts);
        let e = estimate(&f, 0, 1201 * 1201);
        let by_zoom: Vec<u64> = (0..=14)
            .map(|z| range_at(&f.scheme, f.footprint, z).count())
            .collect();
        assert_eq!(e.tiles, by_zoom.iter().sum::<u64>());
        // A 1° tile at zoom 14 (180/2^14 ° a tile): about 91² tiles.
        assert!((91 * 91..=93 * 93).contains(&by_zoom[14]), "{by_zoom:?}");
        assert!(by_zoom[14] > 3 * by_zoom[13]);
        // From zoom 13 on only.
        assert_eq!(estimate(&f, 13, 0).tiles, by_zoom[13] + by_zoom[14]);
        // No zoom to make.
        assert_eq!(estimate(&f, 15, 0).tiles, 0);
    }

    #[test]
    fn memory_follows_the_lattice_window() {
        let lo = estimate(
            &frame(1201, 6.0, 45.0, &LatticeOptions::DEFAULT),
            0,
            1201 * 1201,
        );
        let opts = LatticeOptions::DEFAULT.with_max_zoom(Some(16));
        let hi = estimate(&frame(1201, 6.0, 45.0, &opts), 0, 1201 * 1201);
        // Four zooms finer: 16 times the lattice's side, 256 times its
        // samples (the window is whole tiles, so somewhat less or more).
        let ratio = hi.lattice_samples() as f64 / lo.lattice_samples() as f64;
        assert!((150.0..=350.0).contains(&ratio), "{ratio}");
        assert!(hi.memory_bytes > 50 * lo.memory_bytes);
        let expected = BASE_BYTES
            + BYTES_PER_LATTICE_SAMPLE * hi.lattice_samples() as f64
            + BYTES_PER_SOURCE_SAMPLE * 1201.0 * 1201.0;
        assert_eq!(hi.memory_bytes, expected as u64);
        let cpu = CPU_SECONDS_PER_LATTICE_SAMPLE * hi.lattice_samples() as f64
            + CPU_SECONDS_PER_SOURCE_SAMPLE * 1201.0 * 1201.0;
        assert!((hi.cpu_seconds - cpu).abs() < 1e-9);
    }
}
