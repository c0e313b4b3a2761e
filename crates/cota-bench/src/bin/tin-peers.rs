//! `tin-peers`: cota's TIN against its bitree mesh and greedy Delaunay
//! insertion (the `delatin` crate) at equal **true** error (issue 21).
//!
//! For every grid (Fuji 513², Puget Sound 1025², the SRTM 1025² crop, the
//! real 2-tile mosaic N00E010 + N00E011) and every tolerance `E` in
//! [`cota_bench::TOLERANCES_M`], in the same run:
//! * cota bitree: `Bitree::build` + `extract` at `E`, triangles and time;
//! * cota TIN: `tin::build` at `E` (the bitree build included), triangles,
//!   its true error (verified by `check_mesh(CheckOptions::tin(E))`), time;
//!   and its triangles with `--lock-border`;
//! * delatin at `E`: triangles, true error (`cota_core::measure`, every
//!   sample: delatin's own error claim is not trusted), time;
//! * the ratios TIN / delatin in triangles and in time.
//!
//! Times are the minimum over interleaved rounds (TIN, then delatin, then
//! again): three rounds when delatin takes under 2 s, else one. On a machine
//! shared with other work the minimum is the least disturbed run.
//!
//! Run: `cargo run --release -p cota-bench --bin tin-peers [-- --only NAME]
//! [--delatin-min-e M]` (delatin is skipped below `M` metres; default 0).

#![allow(
    clippy::panic,
    reason = "a report binary: a failed mesh check must stop it loudly"
)]

use std::hint::black_box;
use std::time::Instant;

use cota_bench::big::load_mosaic2;
use cota_bench::{delatin_mesh, heights_f64, load_cases, TOLERANCES_M};
use cota_core::tin::{self, TinOptions};
use cota_core::{check_mesh, measure, Bitree, CheckOptions, ExtractOptions, HeightGrid};

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

fn ms_since(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

fn ms(t: f64) -> String {
    if t < 10.0 {
        format!("{t:.2}")
    } else if t < 100.0 {
        format!("{t:.1}")
    } else {
        format!("{t:.0}")
    }
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

fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".into())
}

/// One tolerance on one grid.
struct Row {
    e: f64,
    bitree: (usize, f64),
    tin: (usize, f64, f64),
    locked: usize,
    delatin: Option<(usize, f64, f64)>,
}

/// Times `f` once.
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let t = Instant::now();
    let out = f();
    (out, ms_since(t))
}

fn run_row(grid: &HeightGrid, hf: &[f64], e: f64, args: &Args) -> Row {
    // The bitree: build + extract, as the TIN's seed is made.
    let (bitree, t_bitree) = timed(|| {
        let tree = Bitree::build(grid).expect("cota builds");
        tree.extract(&ExtractOptions::max_error_m(e))
            .expect("cota extracts")
            .mesh
    });
    let opts = TinOptions::max_error_m(e);
    let (mut t_tin, mut t_del) = (f64::INFINITY, f64::INFINITY);
    let mut tin_mesh = None;
    let mut del_mesh = None;
    let with_delatin = e >= args.delatin_min_e;
    let mut rounds = 3;
    let mut r = 0;
    while r < rounds {
        let (m, t) = timed(|| tin::build(grid, &opts).expect("cota builds a TIN"));
        t_tin = t_tin.min(t);
        tin_mesh = Some(m.mesh);
        if with_delatin {
            let (m, t) = timed(|| delatin_mesh(grid, hf, e).expect("delatin runs"));
            t_del = t_del.min(t);
            if t > 2000.0 {
                rounds = 1;
            }
            del_mesh = Some(black_box(m));
        }
        r += 1;
    }
    let tin_mesh = tin_mesh.expect("at least one round");
    let report = check_mesh(grid, &tin_mesh, &CheckOptions::tin(e))
        .unwrap_or_else(|err| panic!("cota TIN at {e} m fails the check: {err}"));
    let locked = tin::build(grid, &opts.with_lock_border(true))
        .expect("cota builds a TIN with a locked border")
        .mesh;
    check_mesh(grid, &locked, &CheckOptions::tin(e))
        .unwrap_or_else(|err| panic!("cota TIN (locked border) at {e} m fails the check: {err}"));
    let delatin = del_mesh.map(|m| (m.triangle_count(), measure(grid, &m).max_error_m, t_del));
    Row {
        e,
        bitree: (bitree.triangle_count(), t_bitree),
        tin: (tin_mesh.triangle_count(), report.metrics.max_error_m, t_tin),
        locked: locked.triangle_count(),
        delatin,
    }
}

fn run_grid(name: &str, description: &str, grid: &HeightGrid, args: &Args) {
    println!("## {name} ({}×{})\n", grid.width(), grid.height());
    println!(
        "{description}. Load average at start: {}.\n",
        load_average()
    );
    println!("| E (m) | bitree tris | bitree ms | TIN tris | TIN true err (m) | TIN ms | TIN locked-border tris | delatin tris | delatin true err (m) | delatin ms | TIN / delatin tris | TIN / delatin time |");
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let hf = heights_f64(grid);
    for &e in &TOLERANCES_M {
        let r = run_row(grid, &hf, e, args);
        let (dt, de, dm, rt, rm) = match r.delatin {
            Some((n, err, t)) => (
                int(n),
                format!("{err:.3}"),
                ms(t),
                format!("{:.3}", r.tin.0 as f64 / n as f64),
                format!("{:.3}", r.tin.2 / t),
            ),
            None => ("-".into(), "-".into(), "-".into(), "-".into(), "-".into()),
        };
        eprintln!(
            "{name} E={}: bitree {} TIN {} delatin {dt}",
            r.e, r.bitree.0, r.tin.0
        );
        println!(
            "| {} | {} | {} | {} | {:.3} | {} | {} | {dt} | {de} | {dm} | {rt} | {rm} |",
            r.e,
            int(r.bitree.0),
            ms(r.bitree.1),
            int(r.tin.0),
            r.tin.1,
            ms(r.tin.2),
            int(r.locked),
        );
    }
    println!();
}

fn main() {
    let args = parse_args();
    println!("# cota TIN vs cota bitree vs delatin at equal true error\n");
    println!(
        "rayon threads: {}; load average: {}.\n",
        rayon::current_num_threads(),
        load_average()
    );
    let wanted = |name: &str| args.only.as_deref().is_none_or(|o| o == name);
    for case in load_cases(|msg| eprintln!("{msg}")) {
        if wanted(case.name) {
            run_grid(case.name, &case.description, &case.square, &args);
        }
    }
    if wanted("mosaic2") {
        match load_mosaic2() {
            Ok(m) => run_grid(m.name, &m.description, &m.grid, &args),
            Err(e) => eprintln!("skipping mosaic2: {e}"),
        }
    }
}
