//! # cota-fixtures
//!
//! The data cota's tests and benchmarks run on, as **plain data**: row-major
//! `f32` heights (north row first, voids NaN) with what the file said about
//! its place ([`Samples`]). It depends on no cota crate (only `zip`, `flate2`,
//! `image-webp`, `tiff` and `proj4rs`), so
//! `cota-core`'s own tests can use it without a dependency cycle; each crate
//! turns [`Samples`] into its grid type in its `tests/common`.
//!
//! * [`bundled`] / [`bundled_tile`]: the real DEMs in the repository's
//!   `fixtures/` (SRTM `.hgt.zip`, ESRI ASCII `.asc`; provenance in
//!   `fixtures/README.md`).
//! * [`shared_data_dir`], [`shared_data`], [`shared`]: the shared real DEMs,
//!   `$COTA_SHARED_DATA` (the one variable name, [`SHARED_DATA_ENV`]) or
//!   `<workspace>/../shared/data`. [`shared_data`] and [`shared`] print
//!   `skipped: …` to stderr and return `None` when the data is absent, so a
//!   test can `let Some(dir) = shared_data() else { return };`.
//! * [`read`]: an SRTM (`.hgt`, `.hgt.zip`) or ESRI ASCII file, anywhere.
//! * [`crop`]: a window of row-major heights.
//! * [`rough_terrain`]: smooth hills plus seeded noise, for property tests.
//! * [`bombs`]: a gzip bomb and a PNG dimension bomb, written streaming.
//! * [`formats`]: writers of Terrarium WebP tiles, PMTiles archives, NumPy
//!   `.npy`/`.npz` and USGS ASCII DEMs, made from real heights in a test's set-up.
//! * [`geotiff`]: a float32 GeoTIFF writer (and reader of the same shape).
//! * [`derived`]: **derived test inputs**, projected GeoTIFFs resampled at
//!   test time from real geographic DEMs (NAD83 / UTM 16N at 1 m from the
//!   shared `dem-hills.tiff`; WGS 84 / UTM 19S at 30 m from the bundled
//!   SRTM tile).
//!
//! The readers here are deliberately small (the formats of the bundled and
//! shared SRTM and ASCII files, no more); `cota-io` is the real reader, and
//! its own tests check it against these files.
#![warn(missing_docs)]

mod ascii;
pub mod bombs;
pub mod derived;
pub mod formats;
pub mod geotiff;
mod srtm;

use std::fmt;
use std::path::{Path, PathBuf};

/// The environment variable naming the shared data directory.
pub const SHARED_DATA_ENV: &str = "COTA_SHARED_DATA";

/// The bundled real SRTM tile (SRTM 3", 1201², the Chilean coast, 21 voids).
pub const BUNDLED_TILE: &str = "S29W072.hgt.zip";

/// A grid as plain data.
#[derive(Debug, Clone, PartialEq)]
pub struct Samples {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// `width × height` heights in metres, row-major from the north-west
    /// sample; voids (nodata) are NaN.
    pub heights: Vec<f32>,
    /// Where the file says the grid is.
    pub place: Place,
}

/// Where a grid sits, as its file says: enough to rebuild its georeference.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Place {
    /// An SRTM tile named after its south-west corner (whole degrees):
    /// EPSG:4326, samples on whole-degree lines (pixel-is-point), the
    /// north-west sample at (`lon`, `lat` + 1), a step of 1/(n−1) degree.
    Srtm {
        /// Latitude of the south-west corner, degrees.
        lat: i32,
        /// Longitude of the south-west corner, degrees.
        lon: i32,
    },
    /// An ESRI ASCII grid's header: the lower-left corner (or centre) and
    /// the cell size, in the file's (unnamed) CRS units.
    Ascii {
        /// x of the lower-left cell's corner or centre.
        x_ll: f64,
        /// y of the lower-left cell's corner or centre.
        y_ll: f64,
        /// Cell size.
        cell: f64,
        /// True for `xllcenter`/`yllcenter`, false for the corner keys.
        centre: bool,
    },
    /// Nothing known (an SRTM file without a position in its name, a crop).
    Unknown,
}

/// A fixture that cannot be read: the file and why.
#[derive(Debug)]
pub struct FixtureError {
    /// The file.
    pub path: PathBuf,
    /// What went wrong.
    pub reason: String,
}

impl fmt::Display for FixtureError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.path.display(), self.reason)
    }
}

impl std::error::Error for FixtureError {}

/// The cargo workspace root (two levels above this crate).
pub fn workspace_root() -> PathBuf {
    tidy(Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(".."))
}

/// The repository's `fixtures/` directory.
pub fn fixtures_dir() -> PathBuf {
    workspace_root().join("fixtures")
}

/// A file of the repository's `fixtures/` directory.
pub fn fixture(name: &str) -> PathBuf {
    fixtures_dir().join(name)
}

/// A bundled fixture (`fixtures/NAME`, `.hgt.zip` or `.asc`) as plain data.
///
/// # Panics
/// When the file is missing or unreadable (the repository is incomplete):
/// this is for tests and benchmarks.
#[allow(
    clippy::panic,
    reason = "test data: a missing bundled file is a broken checkout"
)]
pub fn bundled(name: &str) -> Samples {
    read(&fixture(name)).unwrap_or_else(|e| panic!("bundled fixture: {e}"))
}

/// The bundled real tile, [`BUNDLED_TILE`].
///
/// # Panics
/// As [`bundled`].
pub fn bundled_tile() -> Samples {
    bundled(BUNDLED_TILE)
}

/// Where the shared data directory is: `$COTA_SHARED_DATA` when set, else
/// `<workspace>/../shared/data`. It may not exist; see [`shared_data`].
pub fn shared_data_dir() -> PathBuf {
    match std::env::var_os(SHARED_DATA_ENV) {
        Some(d) => PathBuf::from(d),
        None => tidy(workspace_root().join("..").join("shared").join("data")),
    }
}

/// The shared data directory when it exists; else prints
/// `skipped: shared data not found at DIR (set COTA_SHARED_DATA)` to stderr
/// and returns `None`.
pub fn shared_data() -> Option<PathBuf> {
    let dir = shared_data_dir();
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!(
            "skipped: shared data not found at {} (set {SHARED_DATA_ENV})",
            dir.display()
        );
        None
    }
}

/// The shared data file `rel` (e.g. `srtm/N00E010.hgt`) when it exists; else
/// prints `skipped: …` to stderr and returns `None`.
pub fn shared(rel: &str) -> Option<PathBuf> {
    let p = shared_data()?.join(rel);
    if p.exists() {
        Some(p)
    } else {
        eprintln!("skipped: shared data file {} not found", p.display());
        None
    }
}

/// Reads an SRTM (`.hgt`, `.hgt.zip`) or ESRI ASCII (`.asc`) file.
///
/// # Errors
/// A [`FixtureError`] naming the file: unreadable, another extension, or not
/// what its format requires.
pub fn read(path: &Path) -> Result<Samples, FixtureError> {
    let fail = |reason: String| FixtureError {
        path: path.to_path_buf(),
        reason,
    };
    let bytes = std::fs::read(path).map_err(|e| fail(e.to_string()))?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if name.ends_with(".hgt.zip") {
        srtm::from_zip(&bytes, &name).map_err(fail)
    } else if name.ends_with(".hgt") {
        srtm::from_hgt(&bytes, &name).map_err(fail)
    } else if name.ends_with(".asc") {
        ascii::parse(&bytes).map_err(fail)
    } else {
        Err(fail(
            "expected an .hgt, .hgt.zip or .asc file name".to_string(),
        ))
    }
}

/// The `w × h` window at column `col`, row `row` of the row-major heights
/// `heights` of a grid `width` samples wide.
///
/// # Panics
/// When the window does not fit the grid.
pub fn crop(heights: &[f32], width: usize, col: usize, row: usize, w: usize, h: usize) -> Vec<f32> {
    assert!(
        col + w <= width && (row + h) * width <= heights.len(),
        "window outside the grid"
    );
    (row..row + h)
        .flat_map(|r| {
            heights[r * width + col..r * width + col + w]
                .iter()
                .copied()
        })
        .collect()
}

impl Samples {
    /// The `w × h` window at (`col`, `row`), placed nowhere ([`Place::Unknown`]).
    ///
    /// # Panics
    /// As [`crop`].
    pub fn crop(&self, col: usize, row: usize, w: usize, h: usize) -> Samples {
        Samples {
            width: w,
            height: h,
            heights: crop(&self.heights, self.width, col, row, w, h),
            place: Place::Unknown,
        }
    }

    /// Void (NaN) samples.
    pub fn void_count(&self) -> usize {
        self.heights.iter().filter(|h| h.is_nan()).count()
    }
}

/// A seeded rough terrain, `w × h` heights in metres (row-major): smooth
/// hills (±50 m) plus xorshift noise of up to `noise_m` metres, so that
/// errors differ across the levels of a hierarchy. The same arguments give
/// the same heights.
pub fn hills_and_noise(w: usize, h: usize, seed: u64, noise_m: f32) -> Vec<f32> {
    let mut s = seed | 1;
    (0..w * h)
        .map(|i| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            let noise = (s % 1000) as f32 / 1000.0;
            50.0 * (x * 0.21).sin() * (y * 0.13).cos() + noise_m * noise
        })
        .collect()
}

/// [`hills_and_noise`] with 10 m of noise: the rough terrain of the
/// property tests.
pub fn rough_terrain(w: usize, h: usize, seed: u64) -> Vec<f32> {
    hills_and_noise(w, h, seed, 10.0)
}

/// `p` without `..` components when it exists, else `p` as it is.
fn tidy(p: PathBuf) -> PathBuf {
    std::fs::canonicalize(&p).unwrap_or(p)
}

#[cfg(test)]
mod test {
    #![allow(clippy::unwrap_used, reason = "tests")]
    use super::*;

    #[test]
    fn the_bundled_tile_is_the_documented_one() {
        let t = bundled_tile();
        assert_eq!((t.width, t.height), (1201, 1201));
        assert_eq!(t.place, Place::Srtm { lat: -29, lon: -72 });
        assert_eq!(t.void_count(), 21);
        let valid = t.heights.iter().copied().filter(|h| !h.is_nan());
        let (lo, hi) = valid.fold((f32::MAX, f32::MIN), |(a, b), h| (a.min(h), b.max(h)));
        assert_eq!((lo, hi), (-5.0, 1899.0), "fixtures/README.md");
    }

    #[test]
    fn the_bundled_ascii_grids_are_the_documented_ones() {
        let hugo = bundled("hugo_site.asc");
        assert_eq!((hugo.width, hugo.height, hugo.void_count()), (76, 55, 2028));
        let boulder = bundled("boulder_srtmgl3_240x144.asc");
        assert_eq!(
            (boulder.width, boulder.height, boulder.void_count()),
            (240, 144, 0)
        );
        let bijou = bundled("bijou_gully_subset_5m_edit_dx_filled.asc");
        assert_eq!((bijou.width, bijou.height), (105, 77));
        assert!(matches!(bijou.place, Place::Ascii { centre: false, .. }));
    }

    #[test]
    fn crops_are_windows() {
        let t = bundled_tile();
        let c = t.crop(900, 600, 3, 2);
        assert_eq!(c.heights[0], t.heights[600 * 1201 + 900]);
        assert_eq!(c.heights[5], t.heights[601 * 1201 + 902]);
        assert_eq!(c.place, Place::Unknown);
    }

    #[test]
    fn rough_terrain_is_seeded() {
        assert_eq!(rough_terrain(7, 5, 3), rough_terrain(7, 5, 3));
        assert_ne!(rough_terrain(7, 5, 3), rough_terrain(7, 5, 4));
        assert_eq!(rough_terrain(7, 5, 3).len(), 35);
    }

    #[test]
    fn other_files_are_refused_by_name() {
        let e = read(&fixture("terrarium.png")).unwrap_err();
        assert!(e.to_string().contains("terrarium.png"), "{e}");
    }
}
