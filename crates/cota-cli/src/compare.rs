//! `cota compare`: paper `000_ebf7e3a88dffd361.txt`'s Table 1 (added points,
//! transmitted points, triangles) and Table 2 (separate-triangle references),
//! bitree against the restricted quadtree of Pajarola 1998, on real data.
//!
//! 1. Read (and mosaic) the inputs, apply the void policy, crop if asked.
//! 2. Tolerances are in % of the grid's height range, as in the paper; the
//!    "full" row is the full grid (every sample, `2·(W−1)·(H−1)` triangles).
//! 3. For each tolerance: the bitree in each requested mode (the conforming
//!    extraction of `cota mesh`, and the fictitious-point refinement, watertight
//!    or faithful to the paper) and the restricted quadtree, each with the
//!    exact max-error criterion; optionally every mesh goes through the checker.
//! 4. Strip references: one strip per mesh, `cota_core::strip` for the
//!    bitree with `--strip-method` (default guided: the mesh as compared;
//!    cells re-triangulates unit cells of the bitree mesh only, so it is not
//!    a like-for-like comparison), `cota_core::strip::stripify_quadtree` for the
//!    quadtree; `n/a` (`null` in JSON) when a mesh cannot be stripped.

use std::fmt::Write as _;
use std::process::ExitCode;

use anyhow::Context;
use cota_core::quadtree::{QuadOptions, QuadTree};
use cota_core::refine::{refine, Mode, RefineOptions};
use cota_core::strip::StripMethod;
use cota_core::{check_mesh, Bitree, CheckOptions, ExtractOptions, GeoRef, HeightGrid};
use cota_core::{measure, MaxVerticalError, Mesh};
use serde::Serialize;

use crate::args::{BitreeMode, CompareArgs, Crop, QuadVariant};
use crate::input::load;

/// One hierarchy (and mode) at one tolerance.
#[derive(Debug, Clone, Serialize)]
struct Entry {
    hierarchy: &'static str,
    mode: &'static str,
    vertices: usize,
    triangles: usize,
    /// Points added only to avoid cracks (dependencies, border, fictitious).
    added: usize,
    /// Points whose height must be sent: every vertex with a real height.
    transmitted: usize,
    /// Points the criterion selected (`None` where the mode does not say).
    selected: Option<usize>,
    /// Vertices of the coarsest mesh (`None` where the mode does not say).
    base: Option<usize>,
    /// Vertices with an interpolated height (fictitious modes).
    fictitious: usize,
    /// Quadtree: vertices introduced only by splits the restriction or the
    /// border forced (the split-based count, valid for any criterion).
    added_by_forced_splits: Option<usize>,
    /// Hanging vertices (faithful mode): one line triangle each in strips.
    line_triangles: usize,
    /// References when sent as separate triangles: 3 per triangle.
    separate_refs: usize,
    /// References as one triangle strip (`cota_core::strip` for the bitree,
    /// `cota_core::strip::stripify_quadtree` for the quadtree).
    strip_refs: Option<usize>,
    /// Measured largest |Δz| over every sample, metres.
    max_error_m: f64,
}

/// Bitree savings against the quadtree, `(QT − BT) / QT` in %.
#[derive(Debug, Clone, Serialize)]
struct Saving {
    /// The bitree mode.
    mode: &'static str,
    /// The quadtree variant.
    quadtree: &'static str,
    added_pct: Option<f64>,
    transmitted_pct: Option<f64>,
    triangles_pct: Option<f64>,
}

#[derive(Debug, Clone, Serialize)]
struct Row {
    /// "full" or the tolerance as "7%".
    label: String,
    tolerance_pct: Option<f64>,
    tolerance_m: Option<f64>,
    entries: Vec<Entry>,
    savings: Vec<Saving>,
}

#[derive(Debug, Clone, Serialize)]
struct Report {
    input: String,
    crop: Option<[usize; 4]>,
    width: usize,
    height: usize,
    min_m: f64,
    max_m: f64,
    range_m: f64,
    checked: bool,
    modes: Vec<&'static str>,
    quadtree: Vec<&'static str>,
    /// How the bitree strips were made (`cota_core::strip::StripMethod`).
    strip_method: &'static str,
    rows: Vec<Row>,
}

fn mode_of(m: BitreeMode) -> Option<Mode> {
    match m {
        BitreeMode::Conforming => None,
        BitreeMode::Fictitious => Some(Mode::Fictitious { watertight: true }),
        BitreeMode::Faithful => Some(Mode::Fictitious { watertight: false }),
    }
}

fn mode_name(m: BitreeMode) -> &'static str {
    mode_of(m).map_or("conforming", |m| m.name())
}

fn quad_name(v: QuadVariant) -> &'static str {
    match v {
        QuadVariant::Templates => "templates",
        QuadVariant::CentreWhenNeeded => "centre-when-needed",
    }
}

/// The window `c` of `g`, with its georeference shifted to the window.
pub fn crop(g: &HeightGrid, c: &Crop) -> anyhow::Result<HeightGrid> {
    let fits = |start: usize, len: usize, total: usize| {
        start.checked_add(len).is_some_and(|end| end <= total)
    };
    if c.width < 2
        || c.height < 2
        || !fits(c.col, c.width, g.width())
        || !fits(c.row, c.height, g.height())
    {
        anyhow::bail!(
            "--crop {},{},{},{}: expected a window of at least 2x2 samples inside the {}x{} grid",
            c.col,
            c.row,
            c.width,
            c.height,
            g.width(),
            g.height()
        );
    }
    let mut heights = Vec::with_capacity(c.width * c.height);
    for r in c.row..c.row + c.height {
        let start = r * g.width() + c.col;
        heights.extend_from_slice(&g.heights()[start..start + c.width]);
    }
    let src = g.georef();
    let georef = GeoRef {
        origin_x: src.origin_x + c.col as f64 * src.pixel_x,
        origin_y: src.origin_y + c.row as f64 * src.pixel_y,
        ..src.clone()
    };
    Ok(HeightGrid::new(c.width, c.height, heights, georef)?)
}

fn pct(bt: usize, qt: usize) -> Option<f64> {
    (qt > 0).then(|| 100.0 * (qt as f64 - bt as f64) / qt as f64)
}

fn max_error(grid: &HeightGrid, mesh: &Mesh, check: Option<CheckOptions>) -> anyhow::Result<f64> {
    Ok(match check {
        Some(o) => {
            check_mesh(grid, mesh, &o)
                .context("the invariant checker rejected a mesh (this is a bug in cota)")?
                .metrics
                .max_error_m
        }
        None => measure(grid, mesh).max_error_m,
    })
}

pub fn run(a: &CompareArgs) -> anyhow::Result<ExitCode> {
    if let Some(t) = a.tolerances.iter().find(|t| !t.is_finite() || **t < 0.0) {
        anyhow::bail!("--tolerances: expected percentages of 0 or more, found {t}");
    }
    let input = load(&a.input)?;
    let name = crate::input::name(&input.files);
    let mut grid = input.grid;
    crate::input::fill(&mut grid, a.voids)?;
    if let Some(c) = &a.crop {
        grid = crop(&grid, c)?;
    }
    let (lo, hi) = grid.valid_range().context("the grid has no valid sample")?;
    let range = (hi - lo) as f64;
    let mut modes: Vec<BitreeMode> = Vec::new();
    for &m in &a.modes {
        if !modes.iter().any(|&k| mode_name(k) == mode_name(m)) {
            modes.push(m);
        }
    }

    let mut quads: Vec<QuadVariant> = Vec::new();
    for &v in &a.quadtree {
        if !quads.iter().any(|&k| quad_name(k) == quad_name(v)) {
            quads.push(v);
        }
    }
    let tree = Bitree::build(&grid)?;
    let qt = QuadTree::build(&grid)?;
    let (w, h) = (grid.width(), grid.height());
    let full_tris = 2 * (w - 1) * (h - 1);
    let full_mesh = cota_core::strip::full_bitree_mesh(w as u32, h as u32);
    let method = a.strip_method.method();
    let full_strip_bt = bitree_strip_refs(&full_mesh, method);
    let full_strip_qt = Some(cota_core::strip::stripify_quadtree(&full_mesh).refs());
    let full = |hierarchy, mode| Entry {
        hierarchy,
        mode,
        vertices: w * h,
        triangles: full_tris,
        added: 0,
        transmitted: w * h,
        selected: Some(w * h),
        base: Some(0),
        fictitious: 0,
        added_by_forced_splits: None,
        line_triangles: 0,
        separate_refs: 3 * full_tris,
        strip_refs: if hierarchy == "bitree" {
            full_strip_bt
        } else {
            full_strip_qt
        },
        max_error_m: 0.0,
    };
    let mut full_entries: Vec<Entry> = modes
        .iter()
        .map(|&m| full("bitree", mode_name(m)))
        .collect();
    full_entries.extend(quads.iter().map(|&v| full("quadtree", quad_name(v))));
    let mut rows = vec![with_savings(Row {
        label: "full".into(),
        tolerance_pct: None,
        tolerance_m: None,
        entries: full_entries,
        savings: Vec::new(),
    })];

    for &p in &a.tolerances {
        let e = p / 100.0 * range;
        let conforming = a.check.then_some(CheckOptions::conforming(e));
        let mut entries = Vec::new();
        for &m in &modes {
            let entry = match mode_of(m) {
                None => {
                    let x = tree.extract(&ExtractOptions::max_error_m(e))?;
                    let c = tree.point_counts(&x.mesh, x.threshold_m);
                    Entry {
                        hierarchy: "bitree",
                        mode: "conforming",
                        vertices: c.vertices,
                        triangles: c.triangles,
                        added: c.added,
                        transmitted: c.vertices,
                        selected: Some(c.selected),
                        base: Some(c.base),
                        fictitious: 0,
                        added_by_forced_splits: None,
                        line_triangles: 0,
                        separate_refs: 3 * c.triangles,
                        strip_refs: bitree_strip_refs(&x.mesh, method),
                        max_error_m: max_error(&grid, &x.mesh, conforming)?,
                    }
                }
                Some(mode) => {
                    let crit = MaxVerticalError { max_error_m: e };
                    let r = refine(&grid, &crit, &RefineOptions::DEFAULT.with_mode(mode))?;
                    let check = a.check.then_some(
                        CheckOptions::conforming(e)
                            .with_allow_fictitious(true)
                            .with_conforming(mode.is_conforming()),
                    );
                    let tris = r.mesh.triangle_count();
                    Entry {
                        hierarchy: "bitree",
                        mode: mode.name(),
                        vertices: r.mesh.vertex_count(),
                        triangles: tris,
                        added: r.fictitious_points,
                        transmitted: r.transmitted_points,
                        selected: None,
                        base: None,
                        fictitious: r.fictitious_points,
                        added_by_forced_splits: None,
                        line_triangles: r.line_triangles,
                        separate_refs: 3 * tris,
                        strip_refs: bitree_strip_refs(&r.mesh, method),
                        max_error_m: max_error(&grid, &r.mesh, check)?,
                    }
                }
            };
            entries.push(entry);
        }
        for &v in &quads {
            let opts = QuadOptions::DEFAULT
                .with_centre_when_needed(matches!(v, QuadVariant::CentreWhenNeeded));
            let x = qt.refine_with(&MaxVerticalError { max_error_m: e }, &opts);
            let c = tree.point_counts(&x.mesh, e);
            entries.push(Entry {
                hierarchy: "quadtree",
                mode: quad_name(v),
                vertices: c.vertices,
                triangles: c.triangles,
                added: c.added,
                transmitted: c.vertices,
                selected: Some(c.selected),
                base: Some(c.base),
                fictitious: 0,
                added_by_forced_splits: Some(x.points.added),
                line_triangles: 0,
                separate_refs: 3 * c.triangles,
                strip_refs: Some(cota_core::strip::stripify_quadtree(&x.mesh).refs()),
                max_error_m: max_error(&grid, &x.mesh, conforming)?,
            });
        }
        rows.push(with_savings(Row {
            label: format!("{p}%"),
            tolerance_pct: Some(p),
            tolerance_m: Some(e),
            entries,
            savings: Vec::new(),
        }));
    }

    let report = Report {
        input: name,
        crop: a.crop.as_ref().map(|c| [c.col, c.row, c.width, c.height]),
        width: w,
        height: h,
        min_m: lo as f64,
        max_m: hi as f64,
        range_m: range,
        checked: a.check,
        modes: modes.iter().map(|&m| mode_name(m)).collect(),
        quadtree: quads.iter().map(|&v| quad_name(v)).collect(),
        strip_method: method.name(),
        rows,
    };
    if a.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print!("{}", text(&report));
    }
    Ok(ExitCode::SUCCESS)
}

fn with_savings(mut row: Row) -> Row {
    let mut savings = Vec::new();
    for q in row.entries.iter().filter(|e| e.hierarchy == "quadtree") {
        for b in row.entries.iter().filter(|e| e.hierarchy == "bitree") {
            savings.push(Saving {
                mode: b.mode,
                quadtree: q.mode,
                added_pct: pct(b.added, q.added),
                transmitted_pct: pct(b.transmitted, q.transmitted),
                triangles_pct: pct(b.triangles, q.triangles),
            });
        }
    }
    row.savings = savings;
    row
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
        "input: {}{} ({} x {}), heights {:.0} to {:.0} m (range {:.0} m); tolerances in % of the range{}\n",
        r.input,
        crop,
        r.width,
        r.height,
        r.min_m,
        r.max_m,
        r.range_m,
        if r.checked { "; every mesh checked" } else { "" }
    );
    for quad in &r.quadtree {
        for mode in &r.modes {
            let _ = writeln!(
                s,
                "Table 1, bitree ({mode}) vs restricted quadtree ({quad}); saving = (QT - BT) / QT\n"
            );
            let _ = writeln!(
                s,
                "| tol | tol (m) | added BT | QT | saving | transmitted BT | QT | saving | triangles BT | QT | saving | strip refs BT | QT |"
            );
            let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|---|---|---|");
            for row in &r.rows {
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
    for mode in &r.modes {
        let _ = write!(header, " BT {mode} triangles | separate | strips |");
        rule.push_str("---|---|---|");
    }
    for quad in &r.quadtree {
        let _ = write!(header, " QT {quad} triangles | separate | strips |");
        rule.push_str("---|---|---|");
    }
    let _ = writeln!(s, "{header}\n{rule}");
    for row in &r.rows {
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
    s
}

/// The strip references of a bitree mesh (`None` if it cannot be stripped).
fn bitree_strip_refs(mesh: &cota_core::Mesh, method: StripMethod) -> Option<usize> {
    cota_core::strip::stripify_bitree_with(mesh, method)
        .ok()
        .map(|s| s.strip.refs())
}

/// A strip reference count for the tables.
fn fmt_refs(r: Option<usize>) -> String {
    r.map_or_else(|| "n/a".to_string(), |n| n.to_string())
}
