//! # cota-bench
//!
//! Shared pieces of cota's benchmarks (`benches/mesh.rs`, criterion) and of the
//! peer comparison report (`src/bin/peers.rs`):
//!
//! * [`load_cases`]: the real grids every benchmark runs on, read from the
//!   shared data directory at run time (never copied into the repository):
//!   Mt Fuji 513² (the 512² terrain-RGB tile with its last row and column
//!   duplicated, as martini's own example does), Puget Sound 1025² (16-bit
//!   gray × 0.1 m) and an SRTM 1201² tile (N00E010, or the bundled
//!   `fixtures/S29W072.hgt.zip` with its voids filled) with its 1025²
//!   north-west crop for martini, which needs a 2^k+1 square.
//! * Adapters that turn the peers' outputs (martini's RTIN, delatin's
//!   Delaunay TIN) into a cota [`Mesh`] with vertices on grid samples and their
//!   true heights, so that [`cota_core::measure`] gives their **true** maximum
//!   error over every sample.
//! * [`martini_lowered`]: the largest martini threshold whose true error is
//!   within a tolerance, found by bisection.

use std::path::PathBuf;

pub mod big;

use cota_core::grid::voids::{fill_voids, FillOptions};
use cota_core::{measure, HeightGrid, Mesh, MeshVertex};
use cota_io::{read_dem, PngEncoding, ReadOptions};
use martini::{Martini, Tile};

/// The error tolerances (metres) every comparison is run at.
pub const TOLERANCES_M: [f64; 7] = [0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0];

/// One benchmark grid.
#[derive(Debug, Clone)]
pub struct Case {
    /// Short name used in benchmark ids, e.g. `fuji513`.
    pub name: &'static str,
    /// What the grid is and where it came from.
    pub description: String,
    /// The 2^k+1 square grid every tool (cota, martini, delatin) meshes.
    pub square: HeightGrid,
    /// The native grid when it is not a 2^k+1 square (the SRTM tile, 1201²),
    /// meshed by cota only; `square` is then its north-west crop.
    pub native: Option<HeightGrid>,
}

/// The shared data directory: `$COTA_SHARED_DATA`, else `shared/data` beside
/// the repository (`<repo>/../shared/data`); [`cota_fixtures::shared_data_dir`].
pub fn data_dir() -> PathBuf {
    cota_fixtures::shared_data_dir()
}

/// The positional arguments of a criterion benchmark binary (its filters),
/// skipping the values of criterion's options that take one. Used to skip the
/// (costly) set-up of grids whose benchmarks a filter excludes.
pub fn bench_filters() -> Vec<String> {
    const WITH_VALUE: [&str; 19] = [
        "--save-baseline",
        "-s",
        "--baseline",
        "-b",
        "--baseline-lenient",
        "--load-baseline",
        "--sample-size",
        "--warm-up-time",
        "--measurement-time",
        "--nresamples",
        "--noise-threshold",
        "--confidence-level",
        "--significance-level",
        "--profile-time",
        "--plotting-backend",
        "--output-format",
        "--color",
        "-c",
        "--format",
    ];
    let mut out = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if WITH_VALUE.contains(&a.as_str()) {
            args.next();
        } else if !a.starts_with('-') {
            out.push(a);
        }
    }
    out
}

/// Whether benchmarks whose ids start with `prefix` (e.g. `extract/big4097`)
/// may match one of `filters` (all match when there is none). Criterion's
/// filters are regular expressions; a filter with regex syntax beyond `.` is
/// taken to match everything, and so is one without `/` naming no group kind
/// or grid (e.g. a function name, `cota`); else it matches when it is part of
/// `prefix` or starts with it.
pub fn wanted(filters: &[String], prefix: &str) -> bool {
    const KNOWN: [&str; 11] = [
        "build", "extract", "delatin", "read", "strip", "stream", "fuji", "puget", "srtm",
        "mosaic", "big",
    ];
    filters.is_empty()
        || filters.iter().any(|f| {
            f.chars().any(|c| "^$*+?()[]{}|\\".contains(c))
                || (!f.contains('/') && !KNOWN.iter().any(|k| f.contains(k)))
                || prefix.contains(f.as_str())
                || f.starts_with(prefix)
        })
}

/// Reads DEM files, mosaics them and fills their voids: the input of the
/// tiling benchmarks (`tiles-peers`, `tiles-codec`).
///
/// # Errors
/// A file that cannot be read, or inputs that cannot be mosaicked.
pub fn load_mosaic(files: &[PathBuf]) -> anyhow::Result<HeightGrid> {
    let grids = files
        .iter()
        .map(|p| Ok(read_dem(p, &ReadOptions::DEFAULT)?.grid))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let mut g = cota_core::mosaic(grids, &cota_core::MosaicOptions::DEFAULT)?.grid;
    fill_voids(&mut g, &FillOptions::DEFAULT)?;
    Ok(g)
}

/// The median of `v` (the mean of the middle two for an even count; NaN when
/// empty).
pub fn median(v: &[f64]) -> f64 {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// The repository root; [`cota_fixtures::workspace_root`].
pub fn repo_root() -> PathBuf {
    cota_fixtures::workspace_root()
}

/// Loads every benchmark grid that can be found, in a fixed order (Fuji,
/// Puget Sound, SRTM). A grid whose file is missing or unreadable is skipped
/// and `note` is told why.
pub fn load_cases(mut note: impl FnMut(&str)) -> Vec<Case> {
    let mut cases = Vec::new();
    match load_fuji() {
        Ok(c) => cases.push(c),
        Err(e) => note(&format!("skipping fuji513: {e}")),
    }
    match load_puget() {
        Ok(c) => cases.push(c),
        Err(e) => note(&format!("skipping puget1025: {e}")),
    }
    match load_srtm() {
        Ok(c) => cases.push(c),
        Err(e) => note(&format!("skipping srtm: {e}")),
    }
    cases
}

fn load_fuji() -> Result<Case, String> {
    let path = data_dir().join("png").join("fuji.png");
    if !path.exists() {
        return Err(format!("{} is absent", path.display()));
    }
    let opts = ReadOptions::DEFAULT.with_png_encoding(Some(PngEncoding::TerrainRgb));
    let dem = read_dem(&path, &opts).map_err(|e| e.to_string())?;
    let grid = pad_to(&dem.grid, 513).map_err(|e| e.to_string())?;
    Ok(Case {
        name: "fuji513",
        description: format!(
            "Mt Fuji, {} terrain-RGB 512² padded to 513² by duplicating the last row and column",
            path.display()
        ),
        square: grid,
        native: None,
    })
}

fn load_puget() -> Result<Case, String> {
    let path = data_dir().join("png").join("ps_height_1k.png");
    if !path.exists() {
        return Err(format!("{} is absent", path.display()));
    }
    let opts = ReadOptions::DEFAULT
        .with_png_encoding(Some(PngEncoding::Gray16))
        .with_gray(0.1, 0.0);
    let dem = read_dem(&path, &opts).map_err(|e| e.to_string())?;
    if dem.grid.width() != 1025 || dem.grid.height() != 1025 {
        return Err(format!(
            "expected 1025x1025 in {}, found {}x{}",
            path.display(),
            dem.grid.width(),
            dem.grid.height()
        ));
    }
    Ok(Case {
        name: "puget1025",
        description: format!("Puget Sound, {} 16-bit gray × 0.1 m, 1025²", path.display()),
        square: dem.grid,
        native: None,
    })
}

fn load_srtm() -> Result<Case, String> {
    let shared = data_dir().join("srtm").join("N00E010.hgt");
    let bundled = cota_fixtures::fixture(cota_fixtures::BUNDLED_TILE);
    let path = if shared.exists() { shared } else { bundled };
    let dem = read_dem(&path, &ReadOptions::DEFAULT).map_err(|e| e.to_string())?;
    let mut grid = dem.grid;
    let voids = grid.void_count();
    if voids > 0 {
        fill_voids(&mut grid, &FillOptions::DEFAULT).map_err(|e| e.to_string())?;
    }
    let square = crop_nw(&grid, 1025).map_err(|e| e.to_string())?;
    let fill = if voids > 0 {
        format!(", {voids} voids filled (harmonic)")
    } else {
        String::new()
    };
    Ok(Case {
        name: "srtm1025",
        description: format!(
            "SRTM {} {}x{}{fill}; martini, delatin and the cota comparison use its 1025² north-west crop",
            path.display(),
            grid.width(),
            grid.height()
        ),
        square,
        native: Some(grid),
    })
}

/// `grid` grown to `n`×`n` by repeating its last column and last row.
///
/// # Errors
/// When the grid is larger than `n` or the result is not a valid grid.
pub fn pad_to(grid: &HeightGrid, n: usize) -> Result<HeightGrid, cota_core::GridError> {
    let (w, h) = (grid.width(), grid.height());
    let mut out = Vec::with_capacity(n * n);
    for y in 0..n {
        let sy = y.min(h - 1);
        for x in 0..n {
            out.push(grid.get(x.min(w - 1), sy));
        }
    }
    HeightGrid::new(n, n, out, grid.georef().clone())
}

/// The `n`×`n` north-west corner of `grid` (rows and columns `0..n`).
///
/// # Errors
/// When the result is not a valid grid.
pub fn crop_nw(grid: &HeightGrid, n: usize) -> Result<HeightGrid, cota_core::GridError> {
    grid.window(0, 0, grid.width().min(n), grid.height().min(n))
}

/// Martini's precomputed errors for `grid` (a `martini.size`² grid).
pub fn martini_tile(martini: &Martini, grid: &HeightGrid) -> Tile {
    let w = grid.width();
    let heights = grid.heights();
    martini.create_terrain(|x, y| heights[y * w + x] as f64)
}

/// Martini's raw output at `max_error`: flat `[col, row, z]` vertex triples
/// (grid coordinates, the transform recovers them from martini's (u, v)) and
/// triangle indices. This is what the extraction benchmark times.
pub fn martini_raw(
    martini: &mut Martini,
    tile: &Tile,
    grid: &HeightGrid,
    max_error: f64,
) -> (Vec<f32>, Vec<u32>) {
    let w = grid.width();
    let max = (martini.size - 1) as f64;
    let heights = grid.heights();
    let (vertices, indices, _uvs) = tile.construct_mesh(martini, max_error, &mut |(u, v)| {
        let col = (u * max).round();
        let row = ((1.0 - v) * max).round();
        let z = heights[row as usize * w + col as usize] as f64;
        (col, row, z)
    });
    (vertices, indices)
}

/// Martini's mesh at `max_error` as a cota [`Mesh`]: vertices on the grid
/// samples with their true heights, triangles counter-clockwise from above.
pub fn martini_mesh(martini: &mut Martini, tile: &Tile, grid: &HeightGrid, max_error: f64) -> Mesh {
    let (vertices, indices) = martini_raw(martini, tile, grid, max_error);
    let w = grid.width();
    let vertices = vertices
        .chunks_exact(3)
        .map(|v| {
            let (col, row) = (v[0] as u32, v[1] as u32);
            MeshVertex {
                col,
                row,
                z_m: grid.heights()[row as usize * w + col as usize],
            }
        })
        .collect();
    let triangles = indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .collect();
    counter_clockwise(Mesh {
        vertices,
        triangles,
    })
}

/// Delatin's TIN of `grid` at `max_error` as a cota [`Mesh`]. `heights` is the
/// grid's heights as `f64` (delatin's input type), converted once by the caller.
///
/// # Errors
/// Delatin's own errors.
pub fn delatin_mesh(
    grid: &HeightGrid,
    heights: &[f64],
    max_error: f64,
) -> Result<Mesh, delatin::TriangulationError> {
    let (points, triangles) = delatin::triangulate(
        heights,
        (grid.width(), grid.height()),
        delatin::Error(max_error),
    )?;
    let w = grid.width();
    let vertices = points
        .iter()
        .map(|&(x, y)| MeshVertex {
            col: x as u32,
            row: y as u32,
            z_m: grid.heights()[y * w + x],
        })
        .collect();
    let triangles = triangles
        .iter()
        .map(|&(a, b, c)| [a as u32, b as u32, c as u32])
        .collect();
    Ok(counter_clockwise(Mesh {
        vertices,
        triangles,
    }))
}

/// `grid`'s heights as `f64`, delatin's input.
pub fn heights_f64(grid: &HeightGrid) -> Vec<f64> {
    grid.heights().iter().map(|&h| h as f64).collect()
}

/// Reorders each triangle's corners so that it is counter-clockwise seen from
/// above (cota's convention); degenerate triangles are left as they are.
pub fn counter_clockwise(mut mesh: Mesh) -> Mesh {
    for k in 0..mesh.triangles.len() {
        let t = mesh.triangles[k];
        if mesh.signed_area2(t) < 0 {
            mesh.triangles[k] = [t[0], t[2], t[1]];
        }
    }
    mesh
}

/// Martini with its threshold lowered until its true error meets a tolerance.
#[derive(Debug, Clone)]
pub struct Lowered {
    /// The threshold passed to martini, metres.
    pub threshold_m: f64,
    /// Its mesh.
    pub mesh: Mesh,
    /// The mesh's true maximum error over every sample, metres.
    pub true_max_error_m: f64,
    /// How many martini meshes the search built and measured.
    pub probes: usize,
}

/// The largest martini threshold (to a relative precision of 1e-6) whose mesh
/// has a true maximum error of at most `tolerance_m`, found by bisection on
/// `[0, tolerance_m]`: threshold 0 always qualifies (martini then splits every
/// triangle that is not exactly planar), and if `tolerance_m` itself qualifies
/// it is returned. The true error need not be monotone in the threshold, so
/// the result is a qualifying threshold, not necessarily the largest one.
pub fn martini_lowered(
    martini: &mut Martini,
    tile: &Tile,
    grid: &HeightGrid,
    tolerance_m: f64,
) -> Lowered {
    let mut probes = 0;
    let mut probe = |m: &mut Martini, t: f64| {
        probes += 1;
        let mesh = martini_mesh(m, tile, grid, t);
        let err = measure(grid, &mesh).max_error_m;
        (mesh, err)
    };
    let (mesh, err) = probe(martini, tolerance_m);
    if err <= tolerance_m {
        return Lowered {
            threshold_m: tolerance_m,
            mesh,
            true_max_error_m: err,
            probes,
        };
    }
    let (mut lo, mut hi) = (0.0f64, tolerance_m);
    let mut best = None;
    while hi - lo > tolerance_m * 1e-6 {
        let mid = 0.5 * (lo + hi);
        let (mesh, err) = probe(martini, mid);
        if err <= tolerance_m {
            lo = mid;
            best = Some((mesh, err));
        } else {
            hi = mid;
        }
    }
    let (mesh, err) = match best {
        Some(b) => b,
        None => probe(martini, lo),
    };
    Lowered {
        threshold_m: lo,
        mesh,
        true_max_error_m: err,
        probes,
    }
}

/// The largest martini threshold whose mesh has at most `budget` triangles,
/// by bisection on `[0, hi_m]` (martini's count only grows as its threshold
/// drops). Returns the threshold and the count there.
pub fn martini_threshold_for_budget(
    martini: &mut Martini,
    tile: &Tile,
    grid: &HeightGrid,
    budget: usize,
    hi_m: f64,
) -> (f64, usize) {
    let count = |m: &mut Martini, t: f64| martini_raw(m, tile, grid, t).1.len() / 3;
    let (mut lo, mut hi) = (0.0f64, hi_m);
    if count(martini, hi) > budget {
        return (hi, count(martini, hi));
    }
    // Invariant: count(hi) <= budget; count(lo) > budget unless lo == 0.
    while hi - lo > hi_m * 1e-7 {
        let mid = 0.5 * (lo + hi);
        if count(martini, mid) <= budget {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    (hi, count(martini, hi))
}

#[cfg(test)]
mod test {
    use super::*;
    use cota_core::{check_mesh, CheckOptions, GeoRef};

    fn bumpy(n: usize) -> HeightGrid {
        let v = (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f32, (i / n) as f32);
                50.0 * (x * 0.21).sin() * (y * 0.13).cos() + ((i * 7919) % 17) as f32 * 0.3
            })
            .collect();
        HeightGrid::new(n, n, v, GeoRef::unreferenced(10.0)).expect("valid grid")
    }

    #[test]
    fn peer_meshes_are_valid_cota_meshes() {
        let g = bumpy(33);
        let mut m = Martini::new(33);
        let tile = martini_tile(&m, &g);
        for e in [0.0, 1.0, 5.0] {
            let mesh = martini_mesh(&mut m, &tile, &g, e);
            check_mesh(&g, &mesh, &CheckOptions::DEFAULT).expect("martini mesh tiles the grid");
            let mesh = delatin_mesh(&g, &heights_f64(&g), e).expect("delatin runs");
            check_mesh(&g, &mesh, &CheckOptions::DEFAULT.with_conforming(true))
                .expect("delatin mesh tiles the grid");
        }
        // Martini at threshold 0 is exact.
        let mesh = martini_mesh(&mut m, &tile, &g, 0.0);
        assert_eq!(measure(&g, &mesh).max_error_m, 0.0);
    }

    #[test]
    fn lowered_martini_meets_the_tolerance() {
        let g = bumpy(65);
        let mut m = Martini::new(65);
        let tile = martini_tile(&m, &g);
        for e in [0.5, 2.0, 10.0] {
            let low = martini_lowered(&mut m, &tile, &g, e);
            assert!(low.true_max_error_m <= e);
            assert!(low.threshold_m <= e);
            assert_eq!(measure(&g, &low.mesh).max_error_m, low.true_max_error_m);
        }
    }

    #[test]
    fn filters_skip_only_what_they_exclude() {
        let f = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert!(wanted(&[], "build/big4097"));
        assert!(wanted(&f(&["big4097"]), "build/big4097"));
        assert!(!wanted(&f(&["big4097"]), "build/fuji513"));
        assert!(wanted(&f(&["extract/mosaic2/5"]), "extract/mosaic2"));
        assert!(!wanted(&f(&["extract/mosaic2/5"]), "build/mosaic2"));
        assert!(wanted(&f(&["build/"]), "build/mosaic2"));
        // A function name or a regex may match anything.
        assert!(wanted(&f(&["cota"]), "build/fuji513"));
        assert!(wanted(&f(&["^build/(fuji|puget)"]), "build/fuji513"));
    }

    #[test]
    fn pad_and_crop() {
        let g = bumpy(5);
        let p = pad_to(&g, 7).expect("pad");
        assert_eq!(p.get(6, 6), g.get(4, 4));
        assert_eq!(p.get(2, 6), g.get(2, 4));
        let c = crop_nw(&p, 5).expect("crop");
        assert_eq!(c, g);
    }
}
