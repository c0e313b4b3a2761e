//! `peers`: cota against martini and delatin at equal **true** error.
//!
//! For every benchmark grid (see [`cota_bench::load_cases`]) and every
//! tolerance `E` in [`cota_bench::TOLERANCES_M`], prints markdown tables of:
//! * martini at threshold `E`: triangles and its true maximum error over every
//!   sample (its threshold only looks at hypotenuse midpoints, so it is not a
//!   bound), and the ratio true/E;
//! * martini "lowered": its threshold bisected down until the true error is
//!   `≤ E`, and its triangle count there;
//! * delatin at `E`: triangles and true error;
//! * cota at `E`: triangles, verified `≤ E` by `check_mesh(conforming(E))`, and
//!   the ratios cota/martini-lowered and cota/delatin;
//! * build and extraction times (quick `Instant` medians; the criterion
//!   numbers of `benches/mesh.rs` are the official ones).
//!
//! Run: `cargo run --release -p cota-bench --bin peers [-- --only NAME]
//! [--delatin-min-e M]` (delatin is skipped below `M` metres; default 0).

#![allow(
    clippy::panic,
    reason = "a report binary: a failed mesh check must stop it loudly"
)]

use std::hint::black_box;
use std::time::Instant;

use cota_bench::{
    delatin_mesh, heights_f64, load_cases, martini_lowered, martini_mesh, martini_raw,
    martini_threshold_for_budget, martini_tile, median, Case, TOLERANCES_M,
};
use cota_core::{check_mesh, measure, Bitree, CheckOptions, ExtractOptions, HeightGrid};
use martini::Martini;

/// Command-line options.
struct Args {
    only: Option<String>,
    delatin_min_e: f64,
}

fn parse_args() -> Args {
    let mut args = Args {
        only: None,
        delatin_min_e: 0.0,
    };
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        match a.as_str() {
            "--only" => args.only = it.next(),
            "--delatin-min-e" => {
                args.delatin_min_e = it
                    .next()
                    .and_then(|v| v.parse().ok())
                    .expect("--delatin-min-e takes a number of metres");
            }
            other => {
                eprintln!("unknown argument {other:?}; expected --only NAME or --delatin-min-e M");
                std::process::exit(2);
            }
        }
    }
    args
}

/// Runs `f` repeatedly (at least 3 times, until 0.3 s have passed or 25 runs)
/// and returns its last result and the median time in milliseconds. A single
/// run longer than 0.3 s is timed once.
fn time<T>(mut f: impl FnMut() -> T) -> (T, f64) {
    let start = Instant::now();
    let mut out = f();
    let first = start.elapsed().as_secs_f64() * 1e3;
    if first > 300.0 {
        return (out, first);
    }
    let mut times = vec![first];
    let total = Instant::now();
    while times.len() < 3 || (total.elapsed().as_secs_f64() < 0.3 && times.len() < 25) {
        let t = Instant::now();
        out = f();
        times.push(t.elapsed().as_secs_f64() * 1e3);
    }
    times.sort_by(f64::total_cmp);
    (out, times[times.len() / 2])
}

/// How many times `peers` builds each grid with each builder.
const BUILD_ROUNDS: usize = 15;

/// The minimum and the median of `v` (not empty; `BUILD_ROUNDS` is odd, so
/// the median is a sample).
fn min_median(v: Vec<f64>) -> (f64, f64) {
    (v.iter().copied().fold(f64::INFINITY, f64::min), median(&v))
}

/// `1234567` → `1,234,567`.
fn int(n: usize) -> String {
    let s = n.to_string();
    let mut out = String::new();
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}

fn ms(t: f64) -> String {
    if t < 1.0 {
        format!("{t:.3}")
    } else if t < 100.0 {
        format!("{t:.2}")
    } else {
        format!("{t:.0}")
    }
}

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".into())
}

/// One row of the comparison.
struct Row {
    e: f64,
    martini_tris: usize,
    martini_err: f64,
    martini_ms: f64,
    low_thr: f64,
    low_tris: usize,
    low_err: f64,
    delatin: Option<(usize, f64, f64)>,
    cota_tris: usize,
    cota_err: f64,
    cota_ms: f64,
}

fn one_thread_pool() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a one-thread rayon pool")
}

fn run_case(case: &Case, args: &Args) {
    let grid = &case.square;
    let size = grid.width();
    println!("## {} ({}×{})\n", case.name, grid.width(), grid.height());
    println!("{}.\n", case.description);
    println!("Load average at start: {}.\n", load_average());

    // Build: the three builders interleaved, so that they share whatever load
    // the machine has; min and median of BUILD_ROUNDS rounds.
    let pool = one_thread_pool();
    let (mut m, t_mnew) = time(|| Martini::new(size as u32));
    let (mut c2, mut c1, mut mt) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..BUILD_ROUNDS {
        let t = Instant::now();
        black_box(Bitree::build(grid).expect("cota builds"));
        c2.push(t.elapsed().as_secs_f64() * 1e3);
        pool.install(|| {
            let t = Instant::now();
            black_box(Bitree::build(grid).expect("cota builds"));
            c1.push(t.elapsed().as_secs_f64() * 1e3);
        });
        let t = Instant::now();
        black_box(martini_tile(&m, grid));
        mt.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let (c2, c1, mt) = (min_median(c2), min_median(c1), min_median(mt));
    println!("Build, {BUILD_ROUNDS} interleaved rounds:\n");
    println!("| build | min ms | median ms |\n|---|---:|---:|");
    println!(
        "| cota `Bitree::build` ({} rayon threads) | {} | {} |",
        rayon::current_num_threads(),
        ms(c2.0),
        ms(c2.1)
    );
    println!(
        "| cota `Bitree::build` (1 thread) | {} | {} |",
        ms(c1.0),
        ms(c1.1)
    );
    println!("| martini `create_terrain` | {} | {} |", ms(mt.0), ms(mt.1));
    println!(
        "| martini `Martini::new` (per grid size, reusable) | | {} |",
        ms(t_mnew)
    );
    println!(
        "| ratio cota / martini `create_terrain` | {:.2} | {:.2} |",
        c2.0 / mt.0,
        c2.1 / mt.1
    );
    println!(
        "| ratio cota (1 thread) / martini `create_terrain` | {:.2} | {:.2} |\n",
        c1.0 / mt.0,
        c1.1 / mt.1
    );
    let tree = Bitree::build(grid).expect("cota builds");
    let tile = martini_tile(&m, grid);

    let hf = heights_f64(grid);
    let mut rows = Vec::new();
    for &e in &TOLERANCES_M {
        let (ext, cota_ms) = time(|| {
            tree.extract(&ExtractOptions::max_error_m(e))
                .expect("cota extracts")
        });
        let report = check_mesh(grid, &ext.mesh, &CheckOptions::conforming(e))
            .unwrap_or_else(|err| panic!("cota mesh at {e} m fails the check: {err}"));
        let (_, martini_ms) = time(|| martini_raw(&mut m, &tile, grid, e));
        let mm = martini_mesh(&mut m, &tile, grid, e);
        let martini_err = measure(grid, &mm).max_error_m;
        let low = martini_lowered(&mut m, &tile, grid, e);
        let delatin = (e >= args.delatin_min_e).then(|| {
            let (mesh, t) = time(|| delatin_mesh(grid, &hf, e).expect("delatin runs"));
            (mesh.triangle_count(), measure(grid, &mesh).max_error_m, t)
        });
        let row = Row {
            e,
            martini_tris: mm.triangle_count(),
            martini_err,
            martini_ms,
            low_thr: low.threshold_m,
            low_tris: low.mesh.triangle_count(),
            low_err: low.true_max_error_m,
            delatin,
            cota_tris: ext.mesh.triangle_count(),
            cota_err: report.metrics.max_error_m,
            cota_ms,
        };
        eprintln!(
            "{} E={e}: cota {} martini-lowered {} delatin {:?}",
            case.name,
            row.cota_tris,
            row.low_tris,
            row.delatin.map(|d| d.0)
        );
        rows.push(row);
    }

    println!(
        "Triangle counts at a true maximum error ≤ E (errors are exact, over every sample):\n"
    );
    println!("| E (m) | martini tris @E | martini true max err (m) | true/E | martini-lowered threshold (m) | martini-lowered tris | its true err (m) | delatin tris | delatin true err (m) | cota tris | cota true err (m) | cota / martini-lowered | cota / delatin |");
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in &rows {
        let (dt, de, ratio_d) = match r.delatin {
            Some((n, err, _)) => (
                int(n),
                format!("{err:.3}"),
                format!("{:.2}", r.cota_tris as f64 / n as f64),
            ),
            None => ("-".into(), "-".into(), "-".into()),
        };
        println!(
            "| {} | {} | {:.3} | {:.2} | {:.6} | {} | {:.3} | {} | {} | {} | {:.3} | {:.2} | {} |",
            r.e,
            int(r.martini_tris),
            r.martini_err,
            r.martini_err / r.e,
            r.low_thr,
            int(r.low_tris),
            r.low_err,
            dt,
            de,
            int(r.cota_tris),
            r.cota_err,
            r.cota_tris as f64 / r.low_tris as f64,
            ratio_d
        );
    }
    println!();
    println!("Extraction times (ms, quick medians):\n");
    println!("| E (m) | cota `extract` | martini `construct_mesh` @E | delatin `triangulate` |");
    println!("|---:|---:|---:|---:|");
    for r in &rows {
        let d = r.delatin.map_or("-".into(), |(_, _, t)| ms(t));
        println!(
            "| {} | {} | {} | {} |",
            r.e,
            ms(r.cota_ms),
            ms(r.martini_ms),
            d
        );
    }
    println!();

    // A ~10k-triangle mesh.
    let budget = 10_000;
    let e10k = tree
        .extract(&ExtractOptions::max_triangles(budget))
        .expect("cota extracts by budget")
        .threshold_m;
    let (ext, t_err) = time(|| {
        tree.extract(&ExtractOptions::max_error_m(e10k))
            .expect("cota extracts")
    });
    let (_, t_budget) = time(|| {
        tree.extract(&ExtractOptions::max_triangles(budget))
            .expect("cota extracts by budget")
    });
    let (m_thr, m_count) = martini_threshold_for_budget(&mut m, &tile, grid, budget, 10_000.0);
    let (_, t_m10k) = time(|| martini_raw(&mut m, &tile, grid, m_thr));
    let m_err = measure(grid, &martini_mesh(&mut m, &tile, grid, m_thr)).max_error_m;
    let c_err = measure(grid, &ext.mesh).max_error_m;
    println!("A mesh of about {} triangles:\n", int(budget));
    println!("| | threshold (m) | tris | true max err (m) | ms |\n|---|---:|---:|---:|---:|");
    println!(
        "| cota `max_error_m` | {e10k:.3} | {} | {c_err:.3} | {} |",
        int(ext.mesh.triangle_count()),
        ms(t_err)
    );
    println!(
        "| cota `max_triangles({budget})` (bisection) | {e10k:.3} | {} | {c_err:.3} | {} |",
        int(ext.mesh.triangle_count()),
        ms(t_budget)
    );
    println!(
        "| martini `construct_mesh` | {m_thr:.3} | {} | {m_err:.3} | {} |\n",
        int(m_count),
        ms(t_m10k)
    );

    if let Some(native) = &case.native {
        run_native(native);
    }
}

/// cota alone on a grid martini cannot take (not 2^k+1).
fn run_native(grid: &HeightGrid) {
    println!(
        "cota alone on the full {}×{} tile:\n",
        grid.width(),
        grid.height()
    );
    let (tree, t_build) = time(|| Bitree::build(grid).expect("cota builds"));
    println!("| E (m) | cota tris | cota true err (m) | extract ms |\n|---:|---:|---:|---:|");
    println!("| build | | | {} |", ms(t_build));
    for &e in &TOLERANCES_M {
        let (ext, t) = time(|| {
            tree.extract(&ExtractOptions::max_error_m(e))
                .expect("cota extracts")
        });
        let report = check_mesh(grid, &ext.mesh, &CheckOptions::conforming(e))
            .unwrap_or_else(|err| panic!("cota mesh at {e} m fails the check: {err}"));
        println!(
            "| {e} | {} | {:.3} | {} |",
            int(ext.mesh.triangle_count()),
            report.metrics.max_error_m,
            ms(t)
        );
    }
    println!();
}

fn main() {
    let args = parse_args();
    let cases = load_cases(|msg| eprintln!("{msg}"));
    if cases.is_empty() {
        eprintln!("no benchmark grid found; set COTA_SHARED_DATA to the shared data directory");
        std::process::exit(1);
    }
    println!("# cota vs martini vs delatin at equal true error\n");
    println!(
        "rayon threads: {}; load average: {}.\n",
        rayon::current_num_threads(),
        load_average()
    );
    for case in &cases {
        if args.only.as_deref().is_some_and(|o| o != case.name) {
            continue;
        }
        run_case(case, &args);
    }
}
