//! `cota compare`: paper `000_ebf7e3a88dffd361.txt`'s Table 1 (added points,
//! transmitted points, triangles) and Table 2 (separate-triangle references),
//! bitree against the restricted quadtree of Pajarola 1998, on real data.
//!
//! 1. Read (and mosaic) the inputs, keep the window of `--crop` or `--bbox`,
//!    apply the void policy.
//! 2. Count with `cota_core::compare` (tolerances in metres, or with `%` in
//!    % of the grid's height range; every bitree mode and quadtree variant; optionally every mesh
//!    through the checker; strip references with `--strip-method`, default
//!    guided: the mesh as compared; cells re-triangulates unit cells of the
//!    bitree mesh only, so it is not a like-for-like comparison).
//! 3. Print the tables, or the report as JSON (`n/a`, `null` in JSON, where
//!    a mesh cannot be stripped).

use std::fmt::Write as _;
use std::process::ExitCode;

use cota_core::compare::{compare_with_progress, CompareOptions, Row};
use cota_core::strip::StripMethod;
use serde::Serialize;

use crate::args::CompareArgs;
use crate::input::load;

#[derive(Debug, Clone, Serialize)]
struct Report<'a> {
    input: String,
    crop: Option<[usize; 4]>,
    width: usize,
    height: usize,
    min_m: f64,
    max_m: f64,
    range_m: f64,
    checked: bool,
    modes: &'a [&'static str],
    quadtree: &'a [&'static str],
    /// How the bitree strips were made (`cota_core::strip::StripMethod`).
    strip_method: &'static str,
    rows: &'a [Row],
}

pub fn run(a: &CompareArgs) -> anyhow::Result<ExitCode> {
    crate::input::refuse_hole(a.voids, "compare")?;
    let input = load(&a.input)?;
    let name = crate::input::name(&input.files);
    let mut grid = input.grid;
    crate::input::fill(&mut grid, a.voids)?;
    let opts = CompareOptions::default()
        .with_tolerances(a.tolerances.clone())
        .with_modes(a.modes.iter().map(|m| m.mode()).collect())
        .with_quadtree(a.quadtree.iter().map(|q| q.options()).collect())
        .with_check(a.check)
        .with_strip_method(a.strip_method.method());
    let pb = crate::progress::bar(0, "comparing");
    let c = compare_with_progress(&grid, &opts, &pb.report())?;
    drop(pb);
    let report = Report {
        input: name,
        crop: a
            .input
            .read
            .crop
            .as_ref()
            .map(|c| [c.col, c.row, c.width, c.height]),
        width: grid.width(),
        height: grid.height(),
        min_m: c.min_m,
        max_m: c.max_m,
        range_m: c.range_m,
        checked: a.check,
        modes: &c.modes,
        quadtree: &c.quadtree,
        strip_method: c.strip_method,
        rows: &c.rows,
    };
    if a.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else if !crate::progress::quiet() {
        print!("{}", text(&report));
    }
    Ok(ExitCode::SUCCESS)
}

fn fmt_pct(p: Option<f64>) -> String {
    p.map_or("n/a".into(), |p| format!("{p:.0}%"))
}

/// The report as Markdown tables (one Table 1 per bitree mode, then Table 2).
fn text(r: &Report) -> String {
    let mut s = String::new();
    let crop = r
        .crop
        .map(|c| format!(", crop at column {} row {}", c[0], c[1]))
        .unwrap_or_default();
    let _ = writeln!(
        s,
        "input: {}{} ({} x {}), heights {:.0} to {:.0} m (range {:.0} m); tolerances as given (% of the range, or m){}\n",
        r.input,
        crop,
        r.width,
        r.height,
        r.min_m,
        r.max_m,
        r.range_m,
        if r.checked { "; every mesh checked" } else { "" }
    );
    for quad in r.quadtree {
        for mode in r.modes {
            let _ = writeln!(
                s,
                "Table 1, bitree ({mode}) vs restricted quadtree ({quad}); saving = (QT - BT) / QT\n"
            );
            let _ = writeln!(
                s,
                "| tol | tol (m) | added BT | QT | saving | transmitted BT | QT | saving | triangles BT | QT | saving | strip refs BT | QT |"
            );
            let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|---|");
            for row in r.rows {
                let find =
                    |h: &str, m: &str| row.entries.iter().find(|e| e.hierarchy == h && e.mode == m);
                let sv = row
                    .savings
                    .iter()
                    .find(|v| v.mode == *mode && v.quadtree == *quad);
                let (Some(bt), Some(qt), Some(sv)) =
                    (find("bitree", mode), find("quadtree", quad), sv)
                else {
                    continue;
                };
                let _ = writeln!(
                    s,
                    "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                    row.label,
                    row.tolerance_m.map_or("-".into(), |m| format!("{m:.1}")),
                    bt.added,
                    qt.added,
                    fmt_pct(sv.added_pct),
                    bt.transmitted,
                    qt.transmitted,
                    fmt_pct(sv.transmitted_pct),
                    bt.triangles,
                    qt.triangles,
                    fmt_pct(sv.triangles_pct),
                    fmt_refs(bt.strip_refs),
                    fmt_refs(qt.strip_refs),
                );
            }
            let _ = writeln!(s);
        }
    }
    table2(&mut s, r);

    s
}

/// Table 2: the references as separate triangles and as strips.
fn table2(s: &mut String, r: &Report) {
    let how = if r.strip_method == StripMethod::Guided.name() {
        String::new()
    } else {
        format!(" (bitree strips: {} method)", r.strip_method)
    };
    let _ = writeln!(
        s,
        "Table 2, references: separate triangles (3 each) vs one triangle strip{how}\n"
    );
    let mut header = String::from("| tol |");
    let mut rule = String::from("|---|");
    for mode in r.modes {
        let _ = write!(header, " BT {mode} triangles | separate | strips |");
        rule.push_str("---|---|---|");
    }
    for quad in r.quadtree {
        let _ = write!(header, " QT {quad} triangles | separate | strips |");
        rule.push_str("---|---|---|");
    }
    let _ = writeln!(s, "{header}\n{rule}");
    for row in r.rows {
        let _ = write!(s, "| {} |", row.label);
        let bts = r.modes.iter().filter_map(|m| {
            row.entries
                .iter()
                .find(|e| e.hierarchy == "bitree" && e.mode == *m)
        });
        let qts = r.quadtree.iter().filter_map(|q| {
            row.entries
                .iter()
                .find(|e| e.hierarchy == "quadtree" && e.mode == *q)
        });
        for e in bts.chain(qts) {
            let _ = write!(
                s,
                " {} | {} | {} |",
                e.triangles,
                e.separate_refs,
                fmt_refs(e.strip_refs)
            );
        }
        let _ = writeln!(s);
    }
}

/// A strip reference count for the tables.
fn fmt_refs(r: Option<usize>) -> String {
    r.map_or_else(|| "n/a".to_string(), |n| n.to_string())
}
