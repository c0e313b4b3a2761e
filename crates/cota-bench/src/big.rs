//! The large benchmark grids: a 3601² tile, an 8-tile mosaic and a 4097²
//! grid, made of **real** samples only (no upsampling).
//!
//! The shared data holds eight real 1201² SRTM 3" tiles but no block of
//! adjacent ones larger than two, and no 1" (3601²) tile. So, unless
//! `$COTA_BIG_DATA` names a directory with real large data (below), the large
//! grids are built from the eight real tiles **placed side by side at
//! relabelled positions**: each tile is written unchanged (same int16 samples,
//! voids kept) as an SRTM `.hgt` file named after its new position, and the
//! benchmarks read those files back with `cota_io::read_region` (in parallel,
//! joined by `cota_core::mosaic`, default seam policy: mean of the shared
//! edge, then the voids filled harmonically), as `cota mesh` does. **The adjacency is
//! artificial**: except for the pairs that are really adjacent (kept
//! adjacent), neighbouring tiles do not match on their shared edge, and the
//! mosaic's [`SeamReport`] says by how much.
//!
//! The eight tiles ([`SOURCES`]): `N50E011`, `N42E001`, `N00E010`, `N00E011`
//! (top row of the 4×2 block), `N49E011`, `N41E001`, `S29W072` and
//! `geotiff/mt_fuji_90m.tif` (an SRTM 3" tile of Mt Fuji, 1201², int16). In the
//! 4×2 block N50E011 sits above N49E011 and N42E001 above N41E001 (really
//! adjacent, south–north) and N00E010 left of N00E011 (really adjacent,
//! west–east); the other seams are artificial.
//!
//! * `srtm3601`: one 3601² `.hgt` file (read as a 1" tile), the 3×3 block
//!   `[N50E011 N42E001 fuji; N49E011 N41E001 S29W072; N00E010 N00E011
//!   N50E011]` (N50E011 used twice), shared edges from the first tile.
//! * `mosaic8`: the 4×2 block above, eight `.hgt` files, 4801×2401.
//! * `big4097`: the 4×2 block stacked twice (4×4 tiles, 4801²), north-west
//!   4097² crop: 2^12+1, so martini can run on it too.
//!
//! With `$COTA_BIG_DATA` set to a directory, every `*.hgt` / `*.hgt.zip` in it
//! is read: the first 3601² tile (by name) becomes `srtm3601`, and all its
//! 1201² tiles, mosaicked at their **real** positions, become `mosaic8` (and,
//! when at least 4097 samples both ways, `big4097` is its north-west crop).
//! Missing pieces fall back to the relabelled grids, with a note.
//! `bench/get-big-data.sh` prepares such a directory.

use std::path::{Path, PathBuf};

use cota_core::grid::mosaic::{MosaicOptions, SeamPolicy, SeamReport};
use cota_core::HeightGrid;
use cota_io::{read_dem, read_region, ReadOptions, RegionOptions};

use crate::{crop_nw, data_dir};

/// Side of an SRTM 3" tile.
pub const TILE: usize = 1201;

/// The eight real 1201² tiles, as paths under the shared data directory.
pub const SOURCES: [&str; 8] = [
    "srtm/N50E011.hgt.zip",
    "srtm/N42E001.hgt.zip",
    "srtm/N00E010.hgt",
    "srtm/N00E011.hgt.zip",
    "srtm/N49E011.hgt.zip",
    "srtm/N41E001.hgt.zip",
    "srtm/S29W072.hgt.zip",
    "geotiff/mt_fuji_90m.tif",
];

/// The 4×2 block: indices into [`SOURCES`], north row first.
pub const BLOCK_4X2: [[usize; 4]; 2] = [[0, 1, 2, 3], [4, 5, 6, 7]];

/// The 3×3 block of `srtm3601`.
pub const BLOCK_3X3: [[usize; 3]; 3] = [[0, 1, 7], [4, 5, 6], [2, 3, 0]];

/// A grid ready to benchmark, with how it was made.
#[derive(Debug, Clone)]
pub struct BigGrid {
    /// Short name: `srtm3601`, `mosaic8`, `big4097`, `mosaic2`.
    pub name: &'static str,
    /// Where it came from, one line.
    pub description: String,
    /// The files read.
    pub files: Vec<PathBuf>,
    /// The grid, voids filled.
    pub grid: HeightGrid,
    /// Seams of the mosaic (`None` for a single file).
    pub seams: Option<SeamReport>,
    /// Voids filled.
    pub voids_filled: usize,
}

/// Reads the eight real tiles of [`SOURCES`] (voids as NaN).
///
/// # Errors
/// A missing or unreadable file, or one that is not 1201².
pub fn source_tiles() -> Result<Vec<HeightGrid>, String> {
    let dir = data_dir();
    SOURCES
        .iter()
        .map(|rel| {
            let p = dir.join(rel);
            let dem = read_dem(&p, &ReadOptions::DEFAULT).map_err(|e| e.to_string())?;
            if dem.grid.width() != TILE || dem.grid.height() != TILE {
                return Err(format!(
                    "{}: expected {TILE}x{TILE}, found {}x{}",
                    p.display(),
                    dem.grid.width(),
                    dem.grid.height()
                ));
            }
            Ok(dem.grid)
        })
        .collect()
}

/// SRTM name of the tile whose south-west corner is at (`lat`, `lon`).
pub fn srtm_name(lat: i32, lon: i32) -> String {
    let ns = if lat >= 0 { 'N' } else { 'S' };
    let ew = if lon >= 0 { 'E' } else { 'W' };
    format!("{ns}{:02}{ew}{:03}.hgt", lat.abs(), lon.abs())
}

/// `grid` as SRTM bytes (big-endian int16, NaN as -32768). The heights must
/// be integers in the int16 range (true of every tile of [`SOURCES`]).
///
/// # Errors
/// A height that is not an int16.
pub fn hgt_bytes(grid: &HeightGrid) -> Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(2 * grid.len());
    for (i, &h) in grid.heights().iter().enumerate() {
        let v: i16 = if h.is_nan() {
            -32768
        } else if h.fract() == 0.0 && (-32767.0..=32767.0).contains(&h) {
            h as i16
        } else {
            return Err(format!(
                "sample {i}: expected an int16 height, found {h} (not an SRTM tile?)"
            ));
        };
        out.extend_from_slice(&v.to_be_bytes());
    }
    Ok(out)
}

/// Writes `tiles` at the positions of `layout` (row 0 north) as SRTM files in
/// `dir`, the north-west tile named after (`lat0`, `lon0`) + (row 0, col 0).
/// Returns the paths in row-major order.
///
/// # Errors
/// I/O errors, non-int16 heights.
pub fn write_layout<const C: usize>(
    dir: &Path,
    tiles: &[HeightGrid],
    layout: &[[usize; C]],
    (lat0, lon0): (i32, i32),
) -> Result<Vec<PathBuf>, String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let mut paths = Vec::new();
    for (r, row) in layout.iter().enumerate() {
        for (c, &t) in row.iter().enumerate() {
            let p = dir.join(srtm_name(lat0 - r as i32, lon0 + c as i32));
            std::fs::write(&p, hgt_bytes(&tiles[t])?)
                .map_err(|e| format!("{}: {e}", p.display()))?;
            paths.push(p);
        }
    }
    Ok(paths)
}

/// Reads `files`, mosaics them (default options: seams averaged) and fills the
/// voids harmonically, as `cota mesh` does with several inputs.
///
/// # Errors
/// Read, mosaic and fill errors, as text naming the files.
pub fn read_mosaic(files: &[PathBuf]) -> Result<(HeightGrid, Option<SeamReport>, usize), String> {
    read_mosaic_with(files, SeamPolicy::Mean)
}

fn read_mosaic_with(
    files: &[PathBuf],
    policy: SeamPolicy,
) -> Result<(HeightGrid, Option<SeamReport>, usize), String> {
    let opts = RegionOptions::DEFAULT.with_mosaic(MosaicOptions::DEFAULT.with_seam_policy(policy));
    let r = read_region(files, &opts).map_err(|e| format!("{:#}", anyhow::Error::from(e)))?;
    Ok((r.grid, r.seams, r.voids))
}

/// The input files of the large grids, written (relabelled) into `scratch`
/// or found in `$COTA_BIG_DATA`.
#[derive(Debug, Clone)]
pub struct BigFiles {
    /// The 3601² tile (one file).
    pub tile3601: Vec<PathBuf>,
    /// Its provenance.
    pub tile3601_note: String,
    /// The tiles of the mosaic.
    pub mosaic8: Vec<PathBuf>,
    /// Their provenance.
    pub mosaic8_note: String,
    /// The tiles the 4097² grid is cropped from.
    pub big4097: Vec<PathBuf>,
    /// Their provenance.
    pub big4097_note: String,
}

/// The files of the large grids: from `$COTA_BIG_DATA` where it has them,
/// else the relabelled real tiles written into `scratch` (about 60 MB).
///
/// # Errors
/// Missing shared data, I/O errors.
pub fn big_files(scratch: &Path, mut note: impl FnMut(&str)) -> Result<BigFiles, String> {
    let (mut real3601, mut real_tiles) = (None, Vec::new());
    if let Some(dir) = std::env::var_os("COTA_BIG_DATA") {
        let dir = PathBuf::from(dir);
        let (a, b) = scan_big_data(&dir)?;
        real3601 = a;
        real_tiles = b;
        note(&format!(
            "COTA_BIG_DATA={}: {} 3601² tile, {} 1201² tiles",
            dir.display(),
            if real3601.is_some() { "a" } else { "no" },
            real_tiles.len()
        ));
    }
    let need_relabelled = real3601.is_none() || real_tiles.len() < 8;
    let tiles = if need_relabelled {
        source_tiles()?
    } else {
        Vec::new()
    };
    const ARTIFICIAL: &str =
        "relabelled real SRTM 3\" tiles (artificial adjacency, see cota_bench::big)";
    let (tile3601, tile3601_note) = match real3601 {
        Some(p) => {
            let n = format!("real 1\" tile {}", p.display());
            (vec![p], n)
        }
        None => {
            // Joined with the first tile winning on shared edges, so the file
            // keeps integer heights.
            let parts = write_layout(&scratch.join("t3x3"), &tiles, &BLOCK_3X3, (12, 120))?;
            let raw = raw_mosaic(&parts)?;
            if raw.width() != 3601 || raw.height() != 3601 {
                return Err(format!(
                    "3x3 block: expected 3601x3601, found {}x{}",
                    raw.width(),
                    raw.height()
                ));
            }
            let p = scratch.join("N10E100.hgt");
            std::fs::write(&p, hgt_bytes(&raw)?).map_err(|e| format!("{}: {e}", p.display()))?;
            (vec![p], format!("3×3 {ARTIFICIAL}"))
        }
    };
    let (mosaic8, mosaic8_note, big4097, big4097_note) = if real_tiles.len() >= 8 {
        let n = format!("{} real adjacent 1201² tiles", real_tiles.len());
        (real_tiles.clone(), n.clone(), real_tiles, n)
    } else {
        let m8 = write_layout(&scratch.join("m4x2"), &tiles, &BLOCK_4X2, (1, 100))?;
        let stacked = [BLOCK_4X2[0], BLOCK_4X2[1], BLOCK_4X2[0], BLOCK_4X2[1]];
        let m16 = write_layout(&scratch.join("m4x4"), &tiles, &stacked, (3, 110))?;
        (
            m8,
            format!("4×2 {ARTIFICIAL}"),
            m16,
            format!("4×4 (the 4×2 block twice) {ARTIFICIAL}, north-west 4097² crop"),
        )
    };
    Ok(BigFiles {
        tile3601,
        tile3601_note,
        mosaic8,
        mosaic8_note,
        big4097,
        big4097_note,
    })
}

/// The mosaic of `files` under [`SeamPolicy::First`], voids kept.
fn raw_mosaic(files: &[PathBuf]) -> Result<HeightGrid, String> {
    let opts = RegionOptions::DEFAULT
        .with_mosaic(MosaicOptions::DEFAULT.with_seam_policy(SeamPolicy::First))
        .with_fill(None);
    let r = read_region(files, &opts).map_err(|e| format!("{:#}", anyhow::Error::from(e)))?;
    Ok(r.grid)
}

/// The first 3601² tile (by file name) and every 1201² tile in `dir`.
fn scan_big_data(dir: &Path) -> Result<(Option<PathBuf>, Vec<PathBuf>), String> {
    let rd = std::fs::read_dir(dir).map_err(|e| format!("COTA_BIG_DATA {}: {e}", dir.display()))?;
    let mut names: Vec<PathBuf> = rd
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            let n = p.to_string_lossy().to_ascii_lowercase();
            n.ends_with(".hgt") || n.ends_with(".hgt.zip")
        })
        .collect();
    names.sort();
    let (mut t3601, mut t1201) = (None, Vec::new());
    for p in names {
        let dem = read_dem(&p, &ReadOptions::DEFAULT).map_err(|e| e.to_string())?;
        match dem.grid.width() {
            3601 if t3601.is_none() => t3601 = Some(p),
            TILE => t1201.push(p),
            _ => {}
        }
    }
    Ok((t3601, t1201))
}

/// Loads one of the large grids from its files.
///
/// # Errors
/// Read, mosaic and fill errors.
pub fn load_big(name: &'static str, files: &[PathBuf], note: &str) -> Result<BigGrid, String> {
    let (mut grid, seams, voids_filled) = read_mosaic(files)?;
    if name == "big4097" {
        if grid.width() < 4097 || grid.height() < 4097 {
            return Err(format!(
                "big4097: expected at least 4097x4097 samples, found {}x{}",
                grid.width(),
                grid.height()
            ));
        }
        grid = crop_nw(&grid, 4097).map_err(|e| e.to_string())?;
    }
    Ok(BigGrid {
        name,
        description: format!(
            "{name} {}x{}: {note}; {} file(s), {voids_filled} voids filled",
            grid.width(),
            grid.height(),
            files.len()
        ),
        files: files.to_vec(),
        grid,
        seams,
        voids_filled,
    })
}

/// The real 2-tile mosaic N00E010 + N00E011 (really adjacent, west–east),
/// 2401×1201.
///
/// # Errors
/// Missing shared data, read or mosaic errors.
pub fn load_mosaic2() -> Result<BigGrid, String> {
    let dir = data_dir().join("srtm");
    let files = vec![dir.join("N00E010.hgt"), dir.join("N00E011.hgt.zip")];
    for f in &files {
        if !f.exists() {
            return Err(format!("{} is absent", f.display()));
        }
    }
    let (grid, seams, voids_filled) = read_mosaic(&files)?;
    Ok(BigGrid {
        name: "mosaic2",
        description: format!(
            "mosaic2 {}x{}: real adjacent tiles N00E010 + N00E011 (SRTM 3\")",
            grid.width(),
            grid.height()
        ),
        files,
        grid,
        seams,
        voids_filled,
    })
}

/// One line on a mosaic's seams.
pub fn seam_line(s: &SeamReport) -> String {
    format!(
        "seams: {} overlapping samples, |Δ| max {:.0} m, mean {:.1} m",
        s.compared, s.max_abs_diff_m, s.mean_abs_diff_m
    )
}

#[cfg(test)]
mod test {
    #![allow(clippy::unwrap_used, reason = "tests")]
    use super::*;

    #[test]
    fn names_follow_srtm() {
        assert_eq!(srtm_name(0, 10), "N00E010.hgt");
        assert_eq!(srtm_name(-29, -72), "S29W072.hgt");
        assert_eq!(srtm_name(1, 100), "N01E100.hgt");
    }

    /// Two copies of the bundled real tile written side by side come back as
    /// one 2401×1201 mosaic holding the tile's own samples, with the seam
    /// (the tile's east column against its west column) reported.
    #[test]
    fn relabelled_layout_reads_back_as_a_mosaic() {
        let fixture = cota_fixtures::fixture(cota_fixtures::BUNDLED_TILE);
        let tile = read_dem(&fixture, &ReadOptions::DEFAULT).unwrap().grid;
        let dir = tempfile::tempdir().unwrap();
        let files =
            write_layout(dir.path(), std::slice::from_ref(&tile), &[[0, 0]], (1, 100)).unwrap();
        let names: Vec<String> = files
            .iter()
            .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names, ["N01E100.hgt", "N01E101.hgt"]);
        let (g, seams, filled) = read_mosaic(&files).unwrap();
        assert_eq!((g.width(), g.height()), (2 * TILE - 1, TILE));
        assert_eq!(
            filled,
            2 * tile.void_count(),
            "both copies' voids (none on the seam)"
        );
        let seams = seams.unwrap();
        assert_eq!(seams.overlap_samples, TILE);
        assert!(
            seams.max_abs_diff_m > 0.0,
            "west and east edges of a real tile differ"
        );
        for (col, row) in [(0, 0), (600, 17), (1199, 1200), (1300, 5)] {
            let src = tile.get(col % (TILE - 1), row);
            if !src.is_nan() {
                assert_eq!(g.get(col, row), src, "sample ({col}, {row})");
            }
        }
        assert!(hgt_bytes(&g).is_err() || g.heights().iter().all(|h| h.fract() == 0.0));
    }
}
