//! `criterion-table`: the medians of the last `cargo bench -p cota-bench` run as
//! markdown tables, one per group kind (`build`, `extract`, `extract10k`,
//! `delatin`, `read`, `strip`, `stream`, then any other kind found), one row
//! per group and one column per benchmarked function, plus the ratio
//! cota / martini (or cota / meshopt) where both ran. Extraction groups that
//! carry a throughput (cota's output triangles) also get a table of cota's
//! rate in millions of triangles per second, grid by tolerance.
//!
//! Reads `<target>/criterion/**/new/{benchmark,estimates}.json`, where
//! `<target>` is the first argument, else `$CARGO_TARGET_DIR`, else the
//! workspace's `target/`.
//!
//! Run: `cargo run --release -p cota-bench --bin criterion-table [-- TARGET_DIR]`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One benchmark's id, median and throughput (elements per iteration).
struct Entry {
    group: String,
    function: String,
    median_ns: f64,
    elements: Option<u64>,
}

fn find(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            if p.file_name().is_some_and(|n| n == "new") {
                out.push(p);
            } else {
                find(&p, out);
            }
        }
    }
}

fn read(new_dir: &Path) -> Option<Entry> {
    let bench: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(new_dir.join("benchmark.json")).ok()?)
            .ok()?;
    let est: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(new_dir.join("estimates.json")).ok()?)
            .ok()?;
    Some(Entry {
        group: bench.get("group_id")?.as_str()?.to_string(),
        function: bench.get("function_id")?.as_str()?.to_string(),
        median_ns: est.get("median")?.get("point_estimate")?.as_f64()?,
        elements: bench
            .get("throughput")
            .and_then(|t| t.get("Elements"))
            .and_then(serde_json::Value::as_u64),
    })
}

fn fmt_time(ns: f64) -> String {
    if ns < 1e3 {
        format!("{ns:.0} ns")
    } else if ns < 1e6 {
        format!("{:.1} µs", ns / 1e3)
    } else if ns < 1e9 {
        format!("{:.2} ms", ns / 1e6)
    } else {
        format!("{:.2} s", ns / 1e9)
    }
}

/// Sort key of a group's remainder (`fuji513/0.5`): the grid in a fixed order,
/// then the tolerance numerically.
fn row_key(rest: &str) -> (usize, String, f64) {
    let mut parts = rest.splitn(2, '/');
    let grid = parts.next().unwrap_or("");
    let order = [
        "fuji513",
        "puget1025",
        "srtm1025",
        "srtm1201",
        "mosaic2",
        "srtm3601",
        "mosaic8",
        "big4097",
    ]
    .iter()
    .position(|g| *g == grid)
    .unwrap_or(usize::MAX);
    let e = parts.next().and_then(|s| s.parse().ok()).unwrap_or(0.0);
    (order, grid.to_string(), e)
}

fn main() {
    let target = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from))
        .unwrap_or_else(|| cota_bench::repo_root().join("target"));
    let root = target.join("criterion");
    let mut dirs = Vec::new();
    find(&root, &mut dirs);
    let entries: Vec<Entry> = dirs.iter().filter_map(|d| read(d)).collect();
    if entries.is_empty() {
        eprintln!(
            "no criterion results under {}; run `cargo bench -p cota-bench` first",
            root.display()
        );
        std::process::exit(1);
    }
    print_rates(&entries);
    // kind -> (functions in order, rows: rest -> function -> median)
    type Rows = BTreeMap<(usize, String, u64, String), BTreeMap<String, f64>>;
    let mut kinds: BTreeMap<String, (Vec<String>, Rows)> = BTreeMap::new();
    for e in &entries {
        let (kind, rest) = e.group.split_once('/').unwrap_or((e.group.as_str(), ""));
        let (funcs, rows) = kinds.entry(kind.to_string()).or_default();
        if !funcs.contains(&e.function) {
            funcs.push(e.function.clone());
        }
        let (order, grid, tol) = row_key(rest);
        rows.entry((order, grid, tol.to_bits(), rest.to_string()))
            .or_default()
            .insert(e.function.clone(), e.median_ns);
    }
    let preferred = [
        "cota",
        "cota_1thread",
        "cota_by_error",
        "cota_by_budget",
        "cota_build_and_extract",
        "martini",
        "delatin",
        "meshopt",
        "read_dem",
        "read_mosaic_fill",
        "encode",
        "decode",
    ];
    let known = [
        "build",
        "extract",
        "extract10k",
        "delatin",
        "read",
        "strip",
        "stream",
    ];
    let mut order: Vec<String> = known.iter().map(|k| k.to_string()).collect();
    order.extend(
        kinds
            .keys()
            .filter(|k| !known.contains(&k.as_str()))
            .cloned(),
    );
    for kind in &order {
        let kind = kind.as_str();
        let Some((funcs, rows)) = kinds.get_mut(kind) else {
            continue;
        };
        funcs.sort_by_key(|f| preferred.iter().position(|p| p == f).unwrap_or(usize::MAX));
        let peer = ["martini", "meshopt"]
            .into_iter()
            .find(|p| funcs.iter().any(|f| f == p));
        let ratio = funcs.iter().any(|f| f == "cota") && peer.is_some();
        let peer = peer.unwrap_or("");
        println!("### {kind}\n");
        let mut head = format!("| {kind} |");
        let mut rule = String::from("|---|");
        for f in funcs.iter() {
            head.push_str(&format!(" {f} |"));
            rule.push_str("---:|");
        }
        if ratio {
            head.push_str(&format!(" cota / {peer} |"));
            rule.push_str("---:|");
        }
        println!("{head}\n{rule}");
        for ((_, _, _, rest), vals) in rows.iter() {
            let mut line = format!("| {rest} |");
            for f in funcs.iter() {
                match vals.get(f) {
                    Some(&ns) => line.push_str(&format!(" {} |", fmt_time(ns))),
                    None => line.push_str(" - |"),
                }
            }
            if ratio {
                match (vals.get("cota"), vals.get(peer)) {
                    (Some(c), Some(m)) => line.push_str(&format!(" {:.2} |", c / m)),
                    _ => line.push_str(" - |"),
                }
            }
            println!("{line}");
        }
        println!();
    }
}

/// cota's extraction rate (M output triangles/s), one row per grid, one
/// column per tolerance.
fn print_rates(entries: &[Entry]) {
    let mut grids: BTreeMap<(usize, String), BTreeMap<u64, f64>> = BTreeMap::new();
    let mut tols: Vec<f64> = Vec::new();
    for e in entries {
        let Some(rest) = e.group.strip_prefix("extract/") else {
            continue;
        };
        let (Some(n), "cota") = (e.elements, e.function.as_str()) else {
            continue;
        };
        let (order, grid, tol) = row_key(rest);
        if !tols.contains(&tol) {
            tols.push(tol);
        }
        grids
            .entry((order, grid))
            .or_default()
            .insert(tol.to_bits(), n as f64 / e.median_ns * 1e3);
    }
    if grids.is_empty() {
        return;
    }
    tols.sort_by(f64::total_cmp);
    println!("### extraction rate (M output triangles/s, cota, from the medians)\n");
    let mut head = String::from("| grid |");
    let mut rule = String::from("|---|");
    for t in &tols {
        head.push_str(&format!(" {t} m |"));
        rule.push_str("---:|");
    }
    println!("{head}\n{rule}");
    for ((_, grid), rates) in &grids {
        let mut line = format!("| {grid} |");
        for t in &tols {
            match rates.get(&t.to_bits()) {
                Some(r) => line.push_str(&format!(" {r:.0} |")),
                None => line.push_str(" |"),
            }
        }
        println!("{line}");
    }
    println!();
}
