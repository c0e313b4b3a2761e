//! `build-speedup`: the rayon speed-up of `Bitree::build` on 2 threads over 1,
//! measured in **pairs**.
//!
//! Criterion's `build/<grid>` group times all `cota` samples, then all
//! `cota_1thread` samples: on a small VM whose speed drifts by 10–30 % over
//! seconds, the ratio of the two medians moves with the drift. Here every
//! round times one build on the global pool and one inside a one-thread pool,
//! back to back (their order alternating between rounds), and the speed-up is
//! the median over rounds of the per-round ratio. The ratio of the two
//! medians and the best-of ratio (fastest 1-thread build over fastest
//! 2-thread build) are printed too: when they disagree, the machine was
//! drifting during the run.
//!
//! Grids: the criterion grids (`fuji513`, `puget1025`, `srtm1025`, `srtm1201`,
//! `mosaic2`), plus `big4097` with `--big`.
//!
//! Run: `cargo run --release -p cota-bench --bin build-speedup [-- --rounds N] [-- --big]`.

use std::time::Instant;

use anyhow::Context;
use cota_bench::big::{big_files, load_big, load_mosaic2};
use cota_bench::{load_cases, median};
use cota_core::{Bitree, HeightGrid};

/// Per-round times (seconds) of one grid.
struct Pairs {
    two: Vec<f64>,
    one: Vec<f64>,
}

fn time_build(grid: &HeightGrid) -> anyhow::Result<f64> {
    let t = Instant::now();
    let tree = Bitree::build(grid).context("build")?;
    let s = t.elapsed().as_secs_f64();
    drop(tree);
    Ok(s)
}

fn pairs(grid: &HeightGrid, rounds: usize, one: &rayon::ThreadPool) -> anyhow::Result<Pairs> {
    // One warm-up of each.
    time_build(grid)?;
    one.install(|| time_build(grid))?;
    let mut p = Pairs {
        two: Vec::with_capacity(rounds),
        one: Vec::with_capacity(rounds),
    };
    for r in 0..rounds {
        if r % 2 == 0 {
            p.two.push(time_build(grid)?);
            p.one.push(one.install(|| time_build(grid))?);
        } else {
            p.one.push(one.install(|| time_build(grid))?);
            p.two.push(time_build(grid)?);
        }
    }
    Ok(p)
}

fn row(name: &str, grid: &HeightGrid, p: &Pairs) {
    let ratios: Vec<f64> = p.one.iter().zip(&p.two).map(|(a, b)| a / b).collect();
    let best1 = p.one.iter().copied().fold(f64::INFINITY, f64::min);
    let best2 = p.two.iter().copied().fold(f64::INFINITY, f64::min);
    let (lo, hi) = ratios
        .iter()
        .fold((f64::INFINITY, 0f64), |(l, h), &r| (l.min(r), h.max(r)));
    let (m1, m2) = (median(&p.one), median(&p.two));
    println!(
        "| {name} | {}×{} | {} | {:.2} ms | {:.2} ms | **{:.2}** | {:.2} | {:.2}–{:.2} | {:.2} |",
        grid.width(),
        grid.height(),
        ratios.len(),
        m1 * 1e3,
        m2 * 1e3,
        median(&ratios),
        m1 / m2,
        lo,
        hi,
        best1 / best2,
    );
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let rounds = args
        .iter()
        .position(|a| a == "--rounds")
        .and_then(|i| args.get(i + 1))
        .map(|s| s.parse::<usize>())
        .transpose()
        .context("--rounds takes a whole number")?
        .unwrap_or(15);
    let big = args.iter().any(|a| a == "--big");
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .context("a one-thread rayon pool")?;
    println!(
        "Paired build rounds: {} rayon threads vs 1 (median of per-round ratios).\n",
        rayon::current_num_threads()
    );
    println!("| grid | size | rounds | 1 thread (median) | 2 threads (median) | speed-up (median of ratios) | ratio of medians | ratio range | best / best |");
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|");
    for case in load_cases(|m| eprintln!("build-speedup: {m}")) {
        row(case.name, &case.square, &pairs(&case.square, rounds, &one)?);
        if let Some(native) = &case.native {
            let name = format!("srtm{}", native.width());
            row(&name, native, &pairs(native, rounds, &one)?);
        }
    }
    match load_mosaic2() {
        Ok(m) => row("mosaic2", &m.grid, &pairs(&m.grid, rounds, &one)?),
        Err(e) => eprintln!("build-speedup: skipping mosaic2: {e}"),
    }
    if big {
        let scratch = tempfile::tempdir().context("a scratch directory")?;
        let b = big_files(scratch.path(), |m| eprintln!("build-speedup: {m}"))
            .and_then(|b| load_big("big4097", &b.big4097, &b.big4097_note));
        match b {
            Ok(b) => row(
                "big4097",
                &b.grid,
                &pairs(&b.grid, rounds.div_ceil(3), &one)?,
            ),
            Err(e) => eprintln!("build-speedup: skipping big4097: {e}"),
        }
    }
    Ok(())
}
