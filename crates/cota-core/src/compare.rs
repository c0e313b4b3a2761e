//! Paper `000_ebf7e3a88dffd361.txt`'s Table 1 (added points, transmitted
//! points, triangles) and Table 2 (references as separate triangles and as
//! one strip): the bitree against the restricted quadtree of Pajarola 1998,
//! counted the paper's way on one grid.
//!
//! 1. Tolerances are in metres or in % of the grid's height range (as in
//!    the paper), [`Tolerance`]; the "full" row is the full grid (every
//!    sample, `2·(W−1)·(H−1)` triangles).
//! 2. For each tolerance, every bitree mode ([`Mode::Conforming`]: the error
//!    map's extraction; the fictitious modes: the refinement) and every
//!    quadtree variant is meshed with the exact max-error criterion, all from
//!    one [`Mesher`] (each hierarchy prepared once), and optionally checked.
//! 3. Points are counted with one definition for both hierarchies
//!    ([`crate::bitree::points`]): *added* points are those the criterion did
//!    not select; the fictitious modes count their fictitious points as
//!    added and transmit only the others. The quadtree also reports its
//!    split-based count.
//! 4. Strips: the bitree's with the chosen [`StripMethod`], the quadtree's
//!    with [`crate::strip::stripify_quadtree`]; `None` where a mesh cannot be
//!    stripped.
//! 5. Savings: `(QT − BT) / QT` in % for every bitree mode against every
//!    quadtree variant.

use crate::bitree::error_code::decode;
use crate::bitree::Bitree;
use crate::criteria::MaxVerticalError;
use crate::error::MeshError;
use crate::grid::HeightGrid;
use crate::mesh::check::{check_mesh, CheckError};
use crate::mesh::metrics::measure;
use crate::mesh::Mesh;
use crate::mesher::{HierarchyKind, MeshPlan, Meshed, Mesher};
use crate::progress::{Counter, Progress, Stages};
use crate::quadtree::QuadOptions;
use crate::refine::Mode;
use crate::strip::{bitree_strip_refs, full_bitree_mesh, quadtree_strip_refs, StripMethod};

/// One tolerance of a comparison: a vertical bound in metres, or a
/// percentage of the grid's height range (paper 000's Table 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Tolerance {
    /// A bound in metres (at least 0).
    Metres(f64),
    /// A percentage of the grid's height range (at least 0).
    PercentOfRange(f64),
}

impl Tolerance {
    /// The bound in metres on a grid whose height range is `range_m`.
    pub fn metres(self, range_m: f64) -> f64 {
        match self {
            Tolerance::Metres(m) => m,
            Tolerance::PercentOfRange(p) => p / 100.0 * range_m,
        }
    }

    /// The percentage of `range_m` it is (`None` for metres on a flat grid).
    pub fn percent(self, range_m: f64) -> Option<f64> {
        match self {
            Tolerance::Metres(m) => (range_m > 0.0).then(|| 100.0 * m / range_m),
            Tolerance::PercentOfRange(p) => Some(p),
        }
    }

    /// The label of its row: `7%` or `5 m`.
    pub fn label(self) -> String {
        match self {
            Tolerance::Metres(m) => format!("{m} m"),
            Tolerance::PercentOfRange(p) => format!("{p}%"),
        }
    }

    /// What it was given in: `percent_of_range` or `metres`.
    pub fn given_in(self) -> &'static str {
        match self {
            Tolerance::Metres(_) => "metres",
            Tolerance::PercentOfRange(_) => "percent_of_range",
        }
    }
}

/// What to compare.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct CompareOptions {
    /// Tolerances, each at least 0. Default: paper 000's 0, 1, 2, 7, 10,
    /// 14, 50 % of the height range.
    pub tolerances: Vec<Tolerance>,
    /// Bitree modes; repeats are dropped. Default: all three.
    pub modes: Vec<Mode>,
    /// Restricted-quadtree variants; repeats are dropped. Default: the
    /// templates, and the centre only when needed.
    pub quadtree: Vec<QuadOptions>,
    /// Run the invariant checker on every mesh. Default: false.
    pub check: bool,
    /// How the bitree strips are made. Default: [`StripMethod::Guided`],
    /// which strips the meshes as compared.
    pub strip_method: StripMethod,
}

impl Default for CompareOptions {
    fn default() -> Self {
        CompareOptions {
            tolerances: [0.0, 1.0, 2.0, 7.0, 10.0, 14.0, 50.0]
                .map(Tolerance::PercentOfRange)
                .to_vec(),
            modes: Mode::ALL.to_vec(),
            quadtree: vec![
                QuadOptions::DEFAULT,
                QuadOptions::DEFAULT.with_centre_when_needed(true),
            ],
            check: false,
            strip_method: StripMethod::Guided,
        }
    }
}

impl CompareOptions {
    /// Sets [`CompareOptions::tolerances`].
    pub fn with_tolerances(mut self, t: Vec<Tolerance>) -> Self {
        self.tolerances = t;
        self
    }

    /// Sets [`CompareOptions::tolerances`], all in % of the height range.
    pub fn with_tolerances_pct(self, t: Vec<f64>) -> Self {
        self.with_tolerances(t.into_iter().map(Tolerance::PercentOfRange).collect())
    }

    /// Sets [`CompareOptions::modes`].
    pub fn with_modes(mut self, modes: Vec<Mode>) -> Self {
        self.modes = modes;
        self
    }

    /// Sets [`CompareOptions::quadtree`].
    pub fn with_quadtree(mut self, variants: Vec<QuadOptions>) -> Self {
        self.quadtree = variants;
        self
    }

    /// Sets [`CompareOptions::check`].
    pub fn with_check(mut self, yes: bool) -> Self {
        self.check = yes;
        self
    }

    /// Sets [`CompareOptions::strip_method`].
    pub fn with_strip_method(mut self, method: StripMethod) -> Self {
        self.strip_method = method;
        self
    }
}

/// Why a comparison failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CompareError {
    /// The grid cannot be meshed, or a tolerance is out of range.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A mesh failed the invariant checker: a bug in cota.
    #[error("the invariant checker rejected a mesh (this is a bug in cota)")]
    Check(#[source] CheckError),
}

/// One hierarchy (and mode) at one tolerance.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[non_exhaustive]
pub struct Entry {
    /// `bitree` or `quadtree`.
    pub hierarchy: &'static str,
    /// The bitree mode ([`Mode::name`]) or the quadtree variant
    /// ([`QuadOptions::name`]).
    pub mode: &'static str,
    /// Mesh vertices.
    pub vertices: usize,
    /// Mesh triangles.
    pub triangles: usize,
    /// Points added only to avoid cracks (dependencies, border, fictitious).
    pub added: usize,
    /// Points whose height must be sent: every vertex with a real height.
    pub transmitted: usize,
    /// Points the criterion selected (`None` where the mode does not say).
    pub selected: Option<usize>,
    /// Vertices of the coarsest mesh (`None` where the mode does not say).
    pub base: Option<usize>,
    /// Vertices with an interpolated height (fictitious modes).
    pub fictitious: usize,
    /// Quadtree: vertices introduced only by splits the restriction or the
    /// border forced (the split-based count, valid for any criterion).
    pub added_by_forced_splits: Option<usize>,
    /// Hanging vertices (faithful mode): one line triangle each in strips.
    pub line_triangles: usize,
    /// References when sent as separate triangles: 3 per triangle.
    pub separate_refs: usize,
    /// References as one triangle strip.
    pub strip_refs: Option<usize>,
    /// Measured largest |Δz| over every sample, metres.
    pub max_error_m: f64,
}

/// Bitree savings against the quadtree, `(QT − BT) / QT` in %.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[non_exhaustive]
pub struct Saving {
    /// The bitree mode.
    pub mode: &'static str,
    /// The quadtree variant.
    pub quadtree: &'static str,
    /// Of the added points (`None` when the quadtree added none).
    pub added_pct: Option<f64>,
    /// Of the transmitted points.
    pub transmitted_pct: Option<f64>,
    /// Of the triangles.
    pub triangles_pct: Option<f64>,
}

/// One row of the tables: every entry at one tolerance.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[non_exhaustive]
pub struct Row {
    /// "full", or the tolerance as given: "7%" or "5 m".
    pub label: String,
    /// What the tolerance was given in: `percent_of_range` or `metres`
    /// (`None` for the full row).
    pub tolerance_given_in: Option<&'static str>,
    /// The tolerance in % of the height range (`None` for the full row, and
    /// for metres on a flat grid).
    pub tolerance_pct: Option<f64>,
    /// The tolerance in metres.
    pub tolerance_m: Option<f64>,
    /// The bitree modes' entries, then the quadtree variants'.
    pub entries: Vec<Entry>,
    /// Every bitree mode against every quadtree variant.
    pub savings: Vec<Saving>,
}

/// The whole comparison.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct Comparison {
    /// The grid's lowest height, metres.
    pub min_m: f64,
    /// The grid's highest height, metres.
    pub max_m: f64,
    /// Their difference: what the tolerances are a percentage of.
    pub range_m: f64,
    /// The bitree modes compared (names), repeats dropped.
    pub modes: Vec<&'static str>,
    /// The quadtree variants compared (names), repeats dropped.
    pub quadtree: Vec<&'static str>,
    /// The bitree strips' method ([`StripMethod::name`]).
    pub strip_method: &'static str,
    /// The full row, then one per tolerance.
    pub rows: Vec<Row>,
}

/// Compares the hierarchies on `grid` (a grid without voids), as the module
/// docs say.
///
/// # Errors
/// [`CompareError::Mesh`] for a grid that cannot be meshed or a negative
/// tolerance, [`CompareError::Check`] when a mesh fails the checker.
pub fn compare(grid: &HeightGrid, opts: &CompareOptions) -> Result<Comparison, CompareError> {
    compare_with_progress(grid, opts, crate::progress::NONE)
}

/// [`compare`], telling `progress(done, total)` as it goes: the bitree's
/// levels, the quadtree's, the full row, then each mesh of each tolerance
/// (every mode and quadtree variant), weighted by their expected share of
/// the time (in thousandths, [`crate::progress`]; a tolerance's meshes by
/// how many split points exceed it).
///
/// # Errors
/// As [`compare`].
pub fn compare_with_progress(
    grid: &HeightGrid,
    opts: &CompareOptions,
    progress: Progress<'_>,
) -> Result<Comparison, CompareError> {
    let modes = distinct(&opts.modes, |m| m.name());
    let quads = distinct(&opts.quadtree, QuadOptions::name);
    let stages = Stages::new(progress, &OUTER_WEIGHTS);
    let mesher = Mesher::new(grid);
    // The hierarchies the rows mesh: the bitree's error map (no extension
    // for odd spans, as the rows), the quadtree.
    let any = MaxVerticalError { max_error_m: 0.0 };
    let bitree = MeshPlan::new(&any).with_extend_odd_spans(false);
    mesher.prepare(&bitree, &stages.stage(0))?;
    stages.finish(0);
    let quadtree =
        MeshPlan::new(&any).with_hierarchy(HierarchyKind::Quadtree(QuadOptions::DEFAULT));
    mesher.prepare(&quadtree, &stages.stage(1))?;
    stages.finish(1);
    let (lo, hi) = grid.valid_range().unwrap_or((0.0, 0.0));
    let range = (hi - lo) as f64;
    let tolerances_m: Vec<f64> = opts.tolerances.iter().map(|t| t.metres(range)).collect();
    let entries = modes.len() + quads.len();
    let weights = row_weights(mesher.bitree()?, &tolerances_m, entries, opts.check);
    let rest = stages.stage(2);
    let rows_done = Stages::new(&rest, &weights);
    let c = Comparer {
        mesher: &mesher,
        modes: &modes,
        quads: &quads,
        opts,
    };
    let mut rows = vec![c.full_row()];
    rows_done.finish(0);
    for (k, &t) in opts.tolerances.iter().enumerate() {
        let row = rows_done.stage(k + 1);
        rows.push(c.row(t, range, &Counter::new(&row, entries))?);
        rows_done.finish(k + 1);
    }
    stages.finish(2);
    Ok(Comparison {
        min_m: lo as f64,
        max_m: hi as f64,
        range_m: range,
        modes: modes.iter().map(|m| m.name()).collect(),
        quadtree: quads.iter().map(QuadOptions::name).collect(),
        strip_method: opts.strip_method.name(),
        rows,
    })
}

/// The relative times of [`compare_with_progress`]'s builds of the bitree
/// and the quadtree, and of its rows (with the default tolerances, measured
/// on an SRTM 1" tile).
const OUTER_WEIGHTS: [usize; 3] = [2, 20, 978];

/// The relative times of the full row and of each tolerance's row: each
/// mesh a base cost plus one about proportional to its points, taken from
/// the share of the split points whose error exceeds the tolerance; the
/// full row strips the full grid's meshes (measured on an SRTM 1" tile).
fn row_weights(tree: &Bitree<'_>, tolerances_m: &[f64], entries: usize, check: bool) -> Vec<usize> {
    const BASE: f64 = 100.0;
    const FULL: f64 = 4000.0;
    let mut counts = vec![0usize; 1 << 16];
    for &c in tree.error_codes() {
        counts[usize::from(c)] += 1;
    }
    let n = tree.error_codes().len().max(1) as f64;
    let share = |e: f64| {
        let above: usize = (0..=u16::MAX)
            .filter(|&c| f64::from(decode(c)) > e)
            .map(|c| counts[usize::from(c)])
            .sum();
        above as f64 / n
    };
    let per_mesh = if check { 2.0 } else { 1.0 };
    let mut w = vec![(0.15 * FULL * entries as f64) as usize];
    w.extend(
        tolerances_m
            .iter()
            .map(|&e| (per_mesh * entries as f64 * (BASE + FULL * share(e))) as usize),
    );
    w
}

/// The items of `all` whose names are not repeats, in order.
fn distinct<T: Copy>(all: &[T], name: impl Fn(&T) -> &'static str) -> Vec<T> {
    let mut out: Vec<T> = Vec::new();
    for x in all {
        if !out.iter().any(|k| name(k) == name(x)) {
            out.push(*x);
        }
    }
    out
}

/// The comparison's shared state.
struct Comparer<'a, 'g> {
    mesher: &'a Mesher<'g>,
    modes: &'a [Mode],
    quads: &'a [QuadOptions],
    opts: &'a CompareOptions,
}

impl Comparer<'_, '_> {
    /// The full grid: every sample selected, nothing added.
    fn full_row(&self) -> Row {
        let g = self.mesher.grid();
        let (w, h) = (g.width(), g.height());
        let triangles = 2 * (w - 1) * (h - 1);
        // The full mesh is made once for each strip (each consumes it).
        let full = || full_bitree_mesh(w as u32, h as u32);
        let strip_bt = self.bitree_strip_refs(full());
        let strip_qt = Some(quadtree_strip_refs(full()));
        let entry = |hierarchy, mode, strip_refs| Entry {
            hierarchy,
            mode,
            vertices: w * h,
            triangles,
            added: 0,
            transmitted: w * h,
            selected: Some(w * h),
            base: Some(0),
            fictitious: 0,
            added_by_forced_splits: None,
            line_triangles: 0,
            separate_refs: 3 * triangles,
            strip_refs,
            max_error_m: 0.0,
        };
        let mut entries: Vec<Entry> = self
            .modes
            .iter()
            .map(|m| entry("bitree", m.name(), strip_bt))
            .collect();
        entries.extend(
            self.quads
                .iter()
                .map(|q| entry("quadtree", q.name(), strip_qt)),
        );
        with_savings("full".into(), None, None, entries)
    }

    /// Every entry at tolerance `t` on a height range of `range_m`.
    fn row(&self, t: Tolerance, range_m: f64, done: &Counter<'_>) -> Result<Row, CompareError> {
        let e = t.metres(range_m);
        let crit = MaxVerticalError { max_error_m: e };
        let mut entries = Vec::new();
        for &mode in self.modes {
            // The hierarchy's own triangles: the points and strips are
            // counted on them (paper 000), so no extension for odd spans.
            let plan = MeshPlan::new(&crit)
                .with_mode(mode)
                .with_extend_odd_spans(false);
            let m = self.mesher.mesh(&plan)?;
            entries.push(self.bitree_entry(mode, m, e)?);
            done.add(1);
        }
        for &q in self.quads {
            let plan = MeshPlan::new(&crit).with_hierarchy(HierarchyKind::Quadtree(q));
            let m = self.mesher.mesh(&plan)?;
            entries.push(self.quadtree_entry(q, m, e)?);
            done.add(1);
        }
        let mut row = with_savings(t.label(), t.percent(range_m), Some(e), entries);
        row.tolerance_given_in = Some(t.given_in());
        Ok(row)
    }

    /// A bitree mode's entry: the conforming extraction counts selected,
    /// added and base points; the fictitious modes count their fictitious
    /// points as added. The mesh is consumed by its strip, last.
    fn bitree_entry(&self, mode: Mode, m: Meshed, e: f64) -> Result<Entry, CompareError> {
        let triangles = m.mesh.triangle_count();
        let max_error_m = self.max_error(&m)?;
        let mut entry = Entry {
            hierarchy: "bitree",
            mode: mode.name(),
            vertices: m.mesh.vertex_count(),
            triangles,
            added: m.fictitious_points,
            transmitted: m.transmitted_points,
            selected: None,
            base: None,
            fictitious: m.fictitious_points,
            added_by_forced_splits: None,
            line_triangles: m.line_triangles,
            separate_refs: 3 * triangles,
            strip_refs: None,
            max_error_m,
        };
        if mode == Mode::Conforming {
            let c = self.mesher.bitree()?.point_counts(&m.mesh, e);
            entry.added = c.added;
            entry.selected = Some(c.selected);
            entry.base = Some(c.base);
        }
        entry.strip_refs = self.bitree_strip_refs(m.mesh);
        Ok(entry)
    }

    /// A quadtree variant's entry, its points counted as the bitree's; the
    /// mesh is consumed by its strip, last.
    fn quadtree_entry(&self, q: QuadOptions, m: Meshed, e: f64) -> Result<Entry, CompareError> {
        let c = self.mesher.bitree()?.point_counts(&m.mesh, e);
        let max_error_m = self.max_error(&m)?;
        let added_by_forced_splits = m.split_points.map(|p| p.added);
        Ok(Entry {
            hierarchy: "quadtree",
            mode: q.name(),
            vertices: c.vertices,
            triangles: c.triangles,
            added: c.added,
            transmitted: c.vertices,
            selected: Some(c.selected),
            base: Some(c.base),
            fictitious: 0,
            added_by_forced_splits,
            line_triangles: 0,
            separate_refs: 3 * c.triangles,
            strip_refs: Some(quadtree_strip_refs(m.mesh)),
            max_error_m,
        })
    }

    /// The mesh's measured largest error, through the checker when asked.
    fn max_error(&self, m: &Meshed) -> Result<f64, CompareError> {
        let grid = self.mesher.grid();
        Ok(if self.opts.check {
            check_mesh(grid, &m.mesh, &m.check)
                .map_err(CompareError::Check)?
                .metrics
                .max_error_m
        } else {
            measure(grid, &m.mesh).max_error_m
        })
    }

    /// The strip references of a bitree mesh, which is consumed (`None` if
    /// it cannot be stripped).
    fn bitree_strip_refs(&self, mesh: Mesh) -> Option<usize> {
        bitree_strip_refs(mesh, self.opts.strip_method).ok()
    }
}

/// The row with its savings: every bitree entry against every quadtree one.
fn with_savings(
    label: String,
    tolerance_pct: Option<f64>,
    tolerance_m: Option<f64>,
    entries: Vec<Entry>,
) -> Row {
    let pct = |bt: usize, qt: usize| (qt > 0).then(|| 100.0 * (qt as f64 - bt as f64) / qt as f64);
    let mut savings = Vec::new();
    for q in entries.iter().filter(|e| e.hierarchy == "quadtree") {
        for b in entries.iter().filter(|e| e.hierarchy == "bitree") {
            savings.push(Saving {
                mode: b.mode,
                quadtree: q.mode,
                added_pct: pct(b.added, q.added),
                transmitted_pct: pct(b.transmitted, q.transmitted),
                triangles_pct: pct(b.triangles, q.triangles),
            });
        }
    }
    Row {
        label,
        tolerance_given_in: None,
        tolerance_pct,
        tolerance_m,
        entries,
        savings,
    }
}
