//! `void-fill`: the harmonic void fill against the build on the same grid,
//! timed in **pairs** (issue 22's target: fill ≤ 3× build).
//!
//! The grid is `srtm3601` of [`cota_bench::big`] (one 3601² `.hgt`, voids
//! kept) with its whole northern half (rows 0..1800) blanked: one void of
//! 6.48 M samples bordered by a single row of real heights, plus the tile's
//! own small voids in the south. Every round fills a copy of it
//! (`fill_voids`, default options: harmonic, tolerance 1 mm) and builds the
//! `Bitree` of the filled grid, back to back, order alternating; the ratio is
//! the median of the per-round ratios. The fill's copy of the grid is not
//! timed.
//!
//! `--tolerance-m T` and `--max-cycles N` set [`FillOptions::tolerance_m`]
//! and [`FillOptions::max_iterations`] (to make a converged reference).
//!
//! `--write-void OUT.f32` and `--write-filled OUT.f32` write the blanked and
//! the filled grid as raw little-endian `f32` (row-major from the north-west
//! corner, NaN for voids), to compare fills between versions;
//! `--against REF.f32` prints the largest difference of the fill from a
//! reference fill of the same blanked grid.
//!
//! Run: `cargo run --release -p cota-bench --bin void-fill [-- --rounds N]`.

use std::io::Write;
use std::path::Path;
use std::time::Instant;

use anyhow::{bail, Context};
use cota_bench::big::big_files;
use cota_bench::median;
use cota_core::{fill_voids, Bitree, FillOptions, HeightGrid};
use cota_io::{read_dem, ReadOptions};

fn blanked_3601() -> anyhow::Result<HeightGrid> {
    let scratch = tempfile::tempdir()?;
    let files =
        big_files(scratch.path(), |m| eprintln!("void-fill: {m}")).map_err(anyhow::Error::msg)?;
    let Some(path) = files.tile3601.first() else {
        bail!("no 3601² tile");
    };
    let mut grid = read_dem(path, &ReadOptions::DEFAULT)?.grid;
    let w = grid.width();
    let half = grid.height() / 2;
    grid.heights_mut()[..half * w].fill(f32::NAN);
    Ok(grid)
}

fn write_raw(g: &HeightGrid, out: &Path) -> anyhow::Result<()> {
    let f = std::fs::File::create(out).with_context(|| format!("creating {}", out.display()))?;
    let mut w = std::io::BufWriter::new(f);
    for h in g.heights() {
        w.write_all(&h.to_le_bytes())?;
    }
    w.flush()
        .with_context(|| format!("writing {}", out.display()))
}

fn read_raw(path: &Path, n: usize) -> anyhow::Result<Vec<f32>> {
    let b = std::fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    if b.len() != 4 * n {
        bail!(
            "{}: expected {} bytes, found {}",
            path.display(),
            4 * n,
            b.len()
        );
    }
    Ok(b.chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect())
}

fn flag<'a>(args: &'a [String], name: &str) -> Option<&'a str> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .map(String::as_str)
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let rounds: usize = flag(&args, "--rounds").unwrap_or("7").parse()?;
    let mut opts = FillOptions::DEFAULT;
    if let Some(t) = flag(&args, "--tolerance-m") {
        opts = opts.with_tolerance_m(t.parse()?);
    }
    if let Some(n) = flag(&args, "--max-cycles") {
        opts = opts.with_max_iterations(n.parse()?);
    }
    let void = blanked_3601()?;
    if let Some(out) = flag(&args, "--write-void") {
        write_raw(&void, Path::new(out))?;
    }
    let (mut fill_s, mut build_s, mut ratios) = (vec![], vec![], vec![]);
    let mut filled = void.clone();
    let report = fill_voids(&mut filled, &opts)?;
    println!(
        "grid {}x{}: {} voids in {} components, largest {}; {} cycles, converged {}, last change {:.2e} m",
        void.width(),
        void.height(),
        report.filled,
        report.components,
        report.largest_component,
        report.max_iterations_used,
        report.converged,
        report.last_change_m
    );
    for round in 0..rounds {
        let mut g = void.clone();
        let mut time_fill = || -> anyhow::Result<f64> {
            let t = Instant::now();
            fill_voids(&mut g, &opts)?;
            Ok(t.elapsed().as_secs_f64())
        };
        let time_build = || -> anyhow::Result<f64> {
            let t = Instant::now();
            std::hint::black_box(Bitree::build(&filled)?);
            Ok(t.elapsed().as_secs_f64())
        };
        let (f, b) = if round % 2 == 0 {
            let f = time_fill()?;
            (f, time_build()?)
        } else {
            let b = time_build()?;
            (time_fill()?, b)
        };
        fill_s.push(f);
        build_s.push(b);
        ratios.push(f / b);
    }
    println!(
        "fill {:.1} ms, build {:.1} ms (medians of {rounds} rounds); fill/build {:.2} (median of per-round ratios)",
        1e3 * median(&fill_s),
        1e3 * median(&build_s),
        median(&ratios)
    );
    if let Some(out) = flag(&args, "--write-filled") {
        write_raw(&filled, Path::new(out))?;
    }
    if let Some(reference) = flag(&args, "--against") {
        let r = read_raw(Path::new(reference), filled.len())?;
        let d = filled
            .heights()
            .iter()
            .zip(&r)
            .map(|(a, b)| (a - b).abs())
            .fold(0f32, f32::max);
        println!("largest difference from {reference}: {d:.2e} m");
    }
    Ok(())
}
