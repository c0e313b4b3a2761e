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
//! Each round also times, the same way, a **perfectly parallel reference**
//! on the same grid: as many passes over the heights as the build has
//! levels, one parallel section each (like the build's levels), every row
//! reduced on its own (its largest second difference), with nothing shared
//! between rows or passes. Its speed-up is what this machine gives
//! level-synchronous passes over that grid with no serial part and no
//! imbalance: the ceiling against which to read the build's.
//!
//! Each round also runs **two one-thread builds at once**, one on each core
//! (two one-thread pools, started together), and takes the slower one's
//! time `Tc`. Their throughput over the round's lone 1-thread build `T1`,
//! `2·T1 / Tc`, is what the two cores give this very work when nothing in it
//! is shared or serial: the same loops, caches and memory traffic. A
//! perfect split of one build over the two cores would take `Tc / 2`, so
//! this is the build's own ceiling, and `speed-up ÷ throughput` its parallel
//! efficiency. (On a machine whose two cores do not slow each other down,
//! the throughput is 2.)
//!
//! With `--levels`, each grid's row is followed by the speed-up of each
//! step of the build (from `Bitree::build_with_progress`, medians over the
//! rounds): the fused fine levels `B(2)–A(s)` as one step, each level up to
//! `A(64)` that the grid was too short to fuse, then the banded coarse levels
//! `B(128)–A(N)` as one step (see `cota_core::hierarchy`). Since the coarse
//! levels' bands fill the threads' idle time during the earlier steps, the
//! steps overlap: the last one is the bands still left, and the closure.
//!
//! Run: `cargo run --release -p cota-bench --bin build-speedup [-- --rounds N] [-- --big] [-- --levels]`.

use std::sync::Mutex;
use std::time::Instant;

use anyhow::Context;
use cota_bench::big::{big_files, load_big, load_mosaic2};
use cota_bench::{load_cases, median};
use cota_core::{Bitree, HeightGrid};
use rayon::prelude::*;

/// Per-round times (seconds) of one grid, whole builds and per level.
struct Pairs {
    two: Vec<f64>,
    one: Vec<f64>,
    /// Levels done after each reported step.
    done: Vec<usize>,
    two_levels: Vec<Vec<f64>>,
    one_levels: Vec<Vec<f64>>,
    /// The perfectly parallel reference, 2 threads and 1.
    ref_two: Vec<f64>,
    ref_one: Vec<f64>,
    /// Two one-thread builds at once, one on each core: the slower one's time.
    copies: Vec<f64>,
}

/// The perfectly parallel reference (see the module doc): `passes` parallel
/// passes over the rows of the heights, entering the pool once as the build
/// does. Returns seconds.
fn time_reference(grid: &HeightGrid, passes: usize) -> f64 {
    let w = grid.width();
    let t = Instant::now();
    let acc = rayon::scope(|_| {
        let mut acc = 0f32;
        for _ in 0..passes {
            acc += grid
                .heights()
                .par_chunks(w)
                .map(|row| {
                    row.windows(3)
                        .map(|x| (x[1] - 0.5 * (x[0] + x[2])).abs())
                        .fold(0f32, f32::max)
                })
                .reduce(|| 0f32, f32::max);
        }
        acc
    });
    std::hint::black_box(acc);
    t.elapsed().as_secs_f64()
}

/// Two one-thread builds of `grid` at once, on the one-thread pools `one`
/// and `other`, started together: the slower one's time, in seconds.
fn time_copies(
    grid: &HeightGrid,
    one: &rayon::ThreadPool,
    other: &rayon::ThreadPool,
) -> anyhow::Result<f64> {
    let start = std::sync::Barrier::new(2);
    let build = |pool: &rayon::ThreadPool| {
        start.wait();
        pool.install(|| time_build(grid)).map(|t| t.0)
    };
    let (a, b) = std::thread::scope(|s| {
        let a = s.spawn(|| build(one));
        let b = build(other);
        (a.join(), b)
    });
    let a = a.map_err(|_| anyhow::anyhow!("a build thread panicked"))??;
    Ok(a.max(b?))
}

/// `f` on the global pool and on the one-thread pool `one`, back to back,
/// the global pool first in even rounds: `(two threads, one thread)`.
fn paired<T>(round: usize, one: &rayon::ThreadPool, f: impl Fn() -> T + Send + Sync) -> (T, T)
where
    T: Send,
{
    if round.is_multiple_of(2) {
        let two = f();
        (two, one.install(&f))
    } else {
        let single = one.install(&f);
        (f(), single)
    }
}

/// One build's time, the time of each step it reported (the fused fine
/// levels are one step, the banded coarse levels another; the last step
/// includes the work after it) with the
/// number of levels done after it, and its number of levels.
fn time_build(grid: &HeightGrid) -> anyhow::Result<(f64, Vec<f64>, Vec<usize>, usize)> {
    let marks = Mutex::new(Vec::new());
    let t = Instant::now();
    let note = |done: usize, total: usize| {
        if let Ok(mut m) = marks.lock() {
            m.push((t.elapsed().as_secs_f64(), done, total));
        }
    };
    let tree = Bitree::build_with_progress(grid, &note).context("build")?;
    let s = t.elapsed().as_secs_f64();
    drop(tree);
    let mut marks = marks.into_inner().unwrap_or_default();
    if let Some(last) = marks.last_mut() {
        last.0 = s;
    }
    let steps = marks
        .iter()
        .scan(0.0, |prev, &(m, _, _)| {
            let d = m - *prev;
            *prev = m;
            Some(d)
        })
        .collect();
    let done = marks.iter().map(|m| m.1).collect();
    let total = marks.last().map_or(0, |m| m.2);
    Ok((s, steps, done, total))
}

fn pairs(
    grid: &HeightGrid,
    rounds: usize,
    one: &rayon::ThreadPool,
    other: &rayon::ThreadPool,
) -> anyhow::Result<Pairs> {
    // One warm-up of each; the reference makes as many passes as the build
    // has levels.
    let (_, _, done, passes) = time_build(grid)?;
    one.install(|| time_build(grid))?;
    let mut p = Pairs {
        done,
        two: Vec::with_capacity(rounds),
        one: Vec::with_capacity(rounds),
        two_levels: Vec::with_capacity(rounds),
        one_levels: Vec::with_capacity(rounds),
        ref_two: Vec::with_capacity(rounds),
        ref_one: Vec::with_capacity(rounds),
        copies: Vec::with_capacity(rounds),
    };
    time_reference(grid, passes);
    one.install(|| time_reference(grid, passes));
    for r in 0..rounds {
        let (two, single) = paired(r, one, || time_build(grid));
        let ((two, two_levels, _, _), (single, single_levels, _, _)) = (two?, single?);
        p.two.push(two);
        p.two_levels.push(two_levels);
        p.one.push(single);
        p.one_levels.push(single_levels);
        let (ref_two, ref_one) = paired(r, one, || time_reference(grid, passes));
        p.ref_two.push(ref_two);
        p.ref_one.push(ref_one);
        p.copies.push(time_copies(grid, one, other)?);
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
    let ref_ratios: Vec<f64> = p
        .ref_one
        .iter()
        .zip(&p.ref_two)
        .map(|(a, b)| a / b)
        .collect();
    // Two builds at once in about the time of one: the throughput of the
    // two cores over one, from the same round's 1-thread build.
    let throughput: Vec<f64> = p
        .one
        .iter()
        .zip(&p.copies)
        .map(|(a, c)| 2.0 * a / c)
        .collect();
    let (speed_up, ceiling) = (median(&ratios), median(&throughput));
    println!(
        "| {name} | {}×{} | {} | {:.2} ms | {:.2} ms | **{:.2}** | {:.2} | {:.2}–{:.2} | {:.2} | {:.2} ({:.2} ms) | {:.2} | {:.0} % |",
        grid.width(),
        grid.height(),
        ratios.len(),
        m1 * 1e3,
        m2 * 1e3,
        speed_up,
        m1 / m2,
        lo,
        hi,
        best1 / best2,
        median(&ref_ratios),
        median(&p.ref_two) * 1e3,
        ceiling,
        100.0 * speed_up / ceiling,
    );
}

/// One line: each level's 1-thread median over its 2-thread median.
fn level_line(name: &str, p: &Pairs) {
    let n = p.two_levels.iter().map(Vec::len).min().unwrap_or(0);
    let per: Vec<String> = (0..n)
        .map(|k| {
            let one: Vec<f64> = p.one_levels.iter().map(|l| l[k]).collect();
            let two: Vec<f64> = p.two_levels.iter().map(|l| l[k]).collect();
            let name = |i: usize| {
                let kind = if i.is_multiple_of(2) { "B" } else { "A" };
                format!("{kind}({})", 2u32 << (i / 2))
            };
            let first = if k == 0 { 0 } else { p.done[k - 1] };
            let last = p.done.get(k).copied().unwrap_or(first + 1).max(first + 1) - 1;
            let step = if last > first {
                format!("{}–{}", name(first), name(last))
            } else {
                name(first)
            };
            format!(
                "{step} {:.2} ({:.0} µs)",
                median(&one) / median(&two),
                median(&two) * 1e6
            )
        })
        .collect();
    println!(
        "| {name} per level (speed-up, 2-thread median) | {} |",
        per.join(", ")
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
    let levels = args.iter().any(|a| a == "--levels");
    let show = |name: &str, grid: &HeightGrid, p: &Pairs| {
        row(name, grid, p);
        if levels {
            level_line(name, p);
        }
    };
    let one_thread = || {
        rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .context("a one-thread rayon pool")
    };
    let (one, other) = (one_thread()?, one_thread()?);
    println!(
        "Paired build rounds: {} rayon threads vs 1 (median of per-round ratios).\n",
        rayon::current_num_threads()
    );
    println!("| grid | size | rounds | 1 thread (median) | 2 threads (median) | speed-up (median of ratios) | ratio of medians | ratio range | best / best | perfectly parallel reference: speed-up (2-thread median) | two 1-thread builds at once: throughput | speed-up ÷ throughput |");
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for case in load_cases(|m| eprintln!("build-speedup: {m}")) {
        show(
            case.name,
            &case.square,
            &pairs(&case.square, rounds, &one, &other)?,
        );
        if let Some(native) = &case.native {
            let name = format!("srtm{}", native.width());
            show(&name, native, &pairs(native, rounds, &one, &other)?);
        }
    }
    match load_mosaic2() {
        Ok(m) => show("mosaic2", &m.grid, &pairs(&m.grid, rounds, &one, &other)?),
        Err(e) => eprintln!("build-speedup: skipping mosaic2: {e}"),
    }
    if big {
        let scratch = tempfile::tempdir().context("a scratch directory")?;
        let b = big_files(scratch.path(), |m| eprintln!("build-speedup: {m}"))
            .and_then(|b| load_big("big4097", &b.big4097, &b.big4097_note));
        match b {
            Ok(b) => show(
                "big4097",
                &b.grid,
                &pairs(&b.grid, rounds.div_ceil(3), &one, &other)?,
            ),
            Err(e) => eprintln!("build-speedup: skipping big4097: {e}"),
        }
    }
    Ok(())
}
