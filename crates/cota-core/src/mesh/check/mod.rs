//! The one invariant checker: tests, fuzzers and `cota mesh --check` all call
//! [`check_mesh`].
//!
//! It proves, for a mesh over a W×H grid:
//! 1. **vertices on samples**: every index is in range, every vertex sits on a
//!    grid sample, no two vertices share a sample, and each vertex carries the
//!    sample's true height (or, where allowed, a *fictitious point*'s height,
//!    paper `000_ebf7e3a88dffd361.txt` §2.2: exactly the midpoint interpolation
//!    of its bitree diagonal, found from its position, whose two ends must be
//!    vertices; within `f32` rounding; or, for a mesh clipped from an
//!    extended grid, [`CheckOptions::clipped_border`], any height on the east
//!    and south borders, which check 5 bounds);
//! 2. **no degenerate or flipped triangle**: every triangle has positive area
//!    counter-clockwise seen from above;
//! 3. **conformity**: no directed edge appears twice (no overlap, no edge used by
//!    more than two triangles) and every edge without its reverse lies on the
//!    grid's border, so there is no T-junction and no crack inside;
//! 4. **exact coverage**: the triangles' areas add up to the rectangle's area.
//!    With (2) and (3) the mesh's boundary is the rectangle's boundary and its
//!    winding number is 1 everywhere inside: the triangles tile the rectangle
//!    exactly. Every sample is also checked to be covered.
//! 5. **the error bound**: the true |Δz| at **every** sample is at most the bound
//!    ([`crate::mesh::metrics::measure`]), with a slack of `1e-9·max(1, |h|max)` for
//!    floating-point rounding only.
//!
//! In non-conforming mode (the papers' faithful fictitious points, which leave
//! hanging vertices on their neighbour's edge) check 3 only forbids repeated
//! directed edges, and coverage rests on (4) plus the per-sample coverage test.
//!
//! Nothing above assumes the bitree's right triangles: (2)–(4) prove a tiling
//! for any triangles with vertices on samples (the sum of the triangles'
//! boundaries cancels on every matched interior edge, so it lies on the
//! rectangle's border and the covering count is the same almost everywhere;
//! the areas make it 1), and (5) scans any triangle exactly
//! ([`crate::mesh::raster`]). For a general triangulation, such as a TIN
//! ([`crate::tin`]), [`CheckOptions::tin`] adds two direct tests
//! ([`CheckOptions::general`]):
//! 6. **no vertex inside an edge**: every lattice point strictly inside every
//!    edge is looked up, and none may be a vertex (the T-junction itself,
//!    reported as [`Violation::VertexOnEdge`], even where another violation
//!    would also catch it);
//! 7. **every vertex used**: a vertex no triangle refers to is reported
//!    ([`Violation::UnusedVertex`]); an unused vertex lying on an edge would
//!    otherwise hide a T-junction from (3).

mod holes;
pub mod placed;

pub use placed::{check_placed_mesh, PlacedMesh, PlacedVertex, Region};

use rayon::prelude::*;

use super::holes::VoidMask;
use crate::grid::HeightGrid;
use crate::hierarchy::{diagonal_of, Hierarchy};
use crate::mesh::metrics::{measure_with_progress, Metrics};
use crate::mesh::{Mesh, MeshVertex};
use crate::progress::{Progress, Stages};

/// What [`check_mesh`] requires.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct CheckOptions {
    /// Required bound on |Δz| at every sample, metres. `None`: not checked.
    /// Default: `None`.
    pub max_error_m: Option<f64>,
    /// Require a conforming mesh (no T-junction). Default: true.
    pub conforming: bool,
    /// Accept fictitious points: a vertex whose height is not its sample's must
    /// equal, within `f32` rounding, the midpoint interpolation of its
    /// hierarchy diagonal, both ends being mesh vertices (their mesh heights
    /// are used). Default: false.
    pub allow_fictitious: bool,
    /// Largest difference allowed between a vertex's height and its sample's,
    /// metres: 0 requires the sample's height bit for bit; a quantized output
    /// (heights on a step `s`) needs `s/2`. Default: 0.
    pub height_tolerance_m: f64,
    /// Also run the direct tests for a general triangulation (module docs, 6
    /// and 7): no vertex strictly inside any edge, every vertex used by a
    /// triangle. Default: false.
    pub general: bool,
    /// The grid's voids are holes ([`super::holes`]): a vertex on a void,
    /// and a triangle with a void sample in or on it, are violations; the
    /// coverage required is of the valid region (every cell whose four
    /// corners are valid has its centre in a triangle) instead of the whole
    /// rectangle, so the area test is dropped and an edge without its
    /// reverse may also lie next to a void (a void among the corners of the
    /// cells on either side of it). Default: false.
    pub holes: bool,
    /// The mesh was clipped from a clamp-extended grid ([`crate::mesh::clip`]):
    /// a vertex on the east or south border (column `W − 1`, row `H − 1`)
    /// may carry the clipped mesh's height there instead of its sample's.
    /// Check 5 still bounds it, since that vertex is a sample. Default: false.
    pub clipped_border: bool,
}

impl CheckOptions {
    /// The defaults: conforming, true heights, no error bound.
    pub const DEFAULT: CheckOptions = CheckOptions {
        max_error_m: None,
        conforming: true,
        allow_fictitious: false,
        height_tolerance_m: 0.0,
        general: false,
        holes: false,
        clipped_border: false,
    };

    /// Conforming, true heights, and `|Δz| ≤ max_error_m` everywhere.
    pub const fn conforming(max_error_m: f64) -> Self {
        CheckOptions {
            max_error_m: Some(max_error_m),
            conforming: true,
            allow_fictitious: false,
            height_tolerance_m: 0.0,
            general: false,
            holes: false,
            clipped_border: false,
        }
    }

    /// A general triangulation (a TIN): conforming, true heights,
    /// `|Δz| ≤ max_error_m` everywhere, and the direct tests of
    /// [`CheckOptions::general`].
    pub const fn tin(max_error_m: f64) -> Self {
        CheckOptions::conforming(max_error_m).with_general(true)
    }

    /// Sets [`CheckOptions::max_error_m`].
    pub const fn with_max_error_m(mut self, e: Option<f64>) -> Self {
        self.max_error_m = e;
        self
    }

    /// Sets [`CheckOptions::conforming`].
    pub const fn with_conforming(mut self, yes: bool) -> Self {
        self.conforming = yes;
        self
    }

    /// Sets [`CheckOptions::height_tolerance_m`].
    pub const fn with_height_tolerance_m(mut self, tolerance_m: f64) -> Self {
        self.height_tolerance_m = tolerance_m;
        self
    }

    /// Sets [`CheckOptions::holes`].
    pub const fn with_holes(mut self, yes: bool) -> Self {
        self.holes = yes;
        self
    }

    /// Sets [`CheckOptions::clipped_border`].
    pub const fn with_clipped_border(mut self, yes: bool) -> Self {
        self.clipped_border = yes;
        self
    }

    /// Sets [`CheckOptions::general`].
    pub const fn with_general(mut self, yes: bool) -> Self {
        self.general = yes;
        self
    }

    /// Sets [`CheckOptions::allow_fictitious`].
    pub const fn with_allow_fictitious(mut self, yes: bool) -> Self {
        self.allow_fictitious = yes;
        self
    }
}

impl Default for CheckOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// One broken invariant.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Violation {
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {tri} refers to vertex {index}, but there are {count} vertices")]
    IndexOutOfRange {
        /// Triangle index.
        tri: usize,
        /// The bad vertex index.
        index: u32,
        /// Number of vertices.
        count: usize,
    },
    /// A vertex lies outside the grid.
    #[error("vertex {vertex} at column {col}, row {row} is outside the {width}x{height} grid")]
    VertexOffGrid {
        /// Vertex index.
        vertex: usize,
        /// Its column.
        col: u32,
        /// Its row.
        row: u32,
        /// Grid width.
        width: usize,
        /// Grid height.
        height: usize,
    },
    /// Two vertices on one sample.
    #[error("vertices {first} and {second} both sit on column {col}, row {row}")]
    DuplicateVertex {
        /// First vertex.
        first: usize,
        /// Second vertex.
        second: usize,
        /// Column.
        col: u32,
        /// Row.
        row: u32,
    },
    /// A vertex height differs from the sample's.
    #[error("vertex {vertex} at column {col}, row {row} has height {got} m, the sample has {expected} m")]
    WrongHeight {
        /// Vertex index.
        vertex: usize,
        /// Column.
        col: u32,
        /// Row.
        row: u32,
        /// Height in the mesh.
        got: f32,
        /// Height in the grid.
        expected: f32,
    },
    /// A vertex with an invented height that is not a fictitious point: its
    /// hierarchy diagonal's ends are not both mesh vertices.
    #[error("vertex {vertex} at column {col}, row {row} has height {got} m, the sample has {expected} m, and it is not a fictitious point (the ends of its hierarchy diagonal are not both vertices)")]
    FictitiousWithoutDiagonal {
        /// Vertex index.
        vertex: usize,
        /// Column.
        col: u32,
        /// Row.
        row: u32,
        /// Height in the mesh.
        got: f32,
        /// Height in the grid.
        expected: f32,
    },
    /// A fictitious point whose height is not the midpoint interpolation of its
    /// hierarchy diagonal.
    #[error("fictitious vertex {vertex} at column {col}, row {row} has height {got} m, the midpoint of its diagonal is at {expected} m")]
    WrongFictitiousHeight {
        /// Vertex index.
        vertex: usize,
        /// Column.
        col: u32,
        /// Row.
        row: u32,
        /// Height in the mesh.
        got: f32,
        /// The interpolated height.
        expected: f64,
    },
    /// A zero-area triangle.
    #[error("triangle {tri} is degenerate (zero area)")]
    Degenerate {
        /// Triangle index.
        tri: usize,
    },
    /// A clockwise triangle.
    #[error("triangle {tri} is clockwise seen from above")]
    Flipped {
        /// Triangle index.
        tri: usize,
    },
    /// A directed edge used twice: overlap or an edge in more than two triangles.
    #[error("edge {from}->{to} is used twice in the same direction (overlap or more than two triangles on one edge)")]
    EdgeOveruse {
        /// Edge start vertex.
        from: u32,
        /// Edge end vertex.
        to: u32,
    },
    /// An interior edge with a single triangle: a T-junction or a crack.
    #[error("edge between ({ac},{ar}) and ({bc},{br}) has one triangle but is not on the grid border (T-junction or crack)")]
    OpenEdge {
        /// Column of one end.
        ac: u32,
        /// Row of one end.
        ar: u32,
        /// Column of the other end.
        bc: u32,
        /// Row of the other end.
        br: u32,
    },
    /// A vertex lies strictly inside an edge: a T-junction.
    #[error("vertex at column {col}, row {row} lies inside the edge between ({ac},{ar}) and ({bc},{br}) (T-junction)")]
    VertexOnEdge {
        /// Column of the vertex.
        col: u32,
        /// Row of the vertex.
        row: u32,
        /// Column of one end of the edge.
        ac: u32,
        /// Row of one end of the edge.
        ar: u32,
        /// Column of the other end.
        bc: u32,
        /// Row of the other end.
        br: u32,
    },
    /// A vertex that no triangle uses.
    #[error("vertex {vertex} at column {col}, row {row} is used by no triangle")]
    UnusedVertex {
        /// Vertex index.
        vertex: usize,
        /// Column.
        col: u32,
        /// Row.
        row: u32,
    },
    /// Triangle areas do not add up to the grid's.
    #[error("triangles cover {got} half-cells, the grid has {expected}")]
    AreaMismatch {
        /// Twice the covered area, in cells.
        got: i64,
        /// Twice the grid's area, in cells.
        expected: i64,
    },
    /// With [`CheckOptions::holes`]: a vertex on a void sample.
    #[error("vertex {vertex} lies on the void sample at column {col}, row {row}")]
    VertexOnVoid {
        /// Vertex index.
        vertex: usize,
        /// Column.
        col: u32,
        /// Row.
        row: u32,
    },
    /// With [`CheckOptions::holes`]: a triangle with a void sample in or on it.
    #[error("triangle {tri} touches the void sample at column {col}, row {row}")]
    TriangleOnVoid {
        /// Triangle index.
        tri: usize,
        /// Column.
        col: u32,
        /// Row.
        row: u32,
    },
    /// With [`CheckOptions::holes`]: cells with four valid corners that no
    /// triangle covers.
    #[error("{count} cells with four valid corners are not covered, the first at column {col}, row {row}")]
    UncoveredCells {
        /// How many.
        count: usize,
        /// Its north-west corner's column.
        col: u32,
        /// Its north-west corner's row.
        row: u32,
    },
    /// Samples no triangle covers.
    #[error("{count} samples are not covered by any triangle")]
    Uncovered {
        /// How many.
        count: usize,
    },
    /// The error bound is exceeded.
    #[error("error {got} m at column {col}, row {row} exceeds the bound {bound} m")]
    ErrorBound {
        /// The true error there.
        got: f64,
        /// The bound.
        bound: f64,
        /// Column.
        col: u32,
        /// Row.
        row: u32,
    },
}

/// The checker found problems: the first few, and how many there were.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("mesh check failed with {total} violation(s); first: {}", .violations.first().map(|v| v.to_string()).unwrap_or_default())]
pub struct CheckError {
    /// Up to [`MAX_REPORTED`] violations.
    pub violations: Vec<Violation>,
    /// Total number of violations found.
    pub total: usize,
}

/// How many violations a [`CheckError`] keeps.
pub const MAX_REPORTED: usize = 20;

/// A passed check: the exact metrics of the mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CheckReport {
    /// Exact metrics over every sample.
    pub metrics: Metrics,
}

struct Found {
    list: Vec<Violation>,
    total: usize,
}

impl Found {
    fn push(&mut self, v: Violation) {
        self.total += 1;
        if self.list.len() < MAX_REPORTED {
            self.list.push(v);
        }
    }
}

/// Checks every invariant listed in the module docs.
///
/// # Errors
/// A [`CheckError`] listing the violations.
///
/// # Runtime
/// `O(W·H + T log T)` for `T` triangles.
pub fn check_mesh(
    grid: &HeightGrid,
    mesh: &Mesh,
    opts: &CheckOptions,
) -> Result<CheckReport, CheckError> {
    check_mesh_with_progress(grid, mesh, opts, crate::progress::NONE)
}

/// [`check_mesh`], telling `progress(done, total)` as it goes: the
/// vertices, the triangles, the general checks, the holes, then the
/// measure by rows, weighted by their share of the time (in thousandths,
/// [`crate::progress`]).
///
/// # Errors
/// As [`check_mesh`].
pub fn check_mesh_with_progress(
    grid: &HeightGrid,
    mesh: &Mesh,
    opts: &CheckOptions,
    progress: Progress<'_>,
) -> Result<CheckReport, CheckError> {
    crate::par::on_pool(|| check_on_pool(grid, mesh, opts, progress))
}

/// The relative times of [`check_mesh_with_progress`]'s stages: the
/// vertices, the triangles, the general checks, the holes, the measure
/// (measured on an SRTM 1" tile).
const CHECK_WEIGHTS: [usize; 5] = [2, 50, 5, 1, 42];

/// [`check_mesh`] on a pool thread: its parallel sections enter the pool once.
fn check_on_pool(
    grid: &HeightGrid,
    mesh: &Mesh,
    opts: &CheckOptions,
    progress: Progress<'_>,
) -> Result<CheckReport, CheckError> {
    let mut found = Found {
        list: Vec::new(),
        total: 0,
    };
    let stages = Stages::new(progress, &CHECK_WEIGHTS);
    let owner = check_vertices(grid, mesh, opts, &mut found);
    stages.finish(0);
    if found.total == 0 {
        check_triangles(grid, mesh, opts, &mut found);
    }
    stages.finish(1);
    if found.total == 0 && opts.general {
        check_general(grid, mesh, &owner, &mut found);
    }
    stages.finish(2);
    if found.total == 0 && opts.holes {
        holes::check_holes(grid, mesh, &mut found);
    }
    stages.finish(3);
    let metrics = measure_with_progress(grid, mesh, &stages.stage(4));
    stages.finish(4);
    if found.total == 0 {
        if metrics.uncovered > 0 && !opts.holes {
            found.push(Violation::Uncovered {
                count: metrics.uncovered,
            });
        }
        if let Some(bound) = opts.max_error_m {
            if metrics.max_error_m > bound + Metrics::rounding_allowance_m(grid) {
                found.push(Violation::ErrorBound {
                    got: metrics.max_error_m,
                    bound,
                    col: metrics.max_error_at[0],
                    row: metrics.max_error_at[1],
                });
            }
        }
    }
    if found.total > 0 {
        return Err(CheckError {
            violations: found.list,
            total: found.total,
        });
    }
    Ok(CheckReport {
        metrics: metrics.within_rounding_of(opts.max_error_m, grid),
    })
}

/// Checks each vertex; returns the vertex at each sample (`u32::MAX` for
/// none).
fn check_vertices(
    grid: &HeightGrid,
    mesh: &Mesh,
    opts: &CheckOptions,
    found: &mut Found,
) -> Vec<u32> {
    let (w, h) = (grid.width(), grid.height());
    let mut owner = vec![u32::MAX; w * h];
    for (k, v) in mesh.vertices.iter().enumerate() {
        if v.col as usize >= w || v.row as usize >= h {
            found.push(Violation::VertexOffGrid {
                vertex: k,
                col: v.col,
                row: v.row,
                width: w,
                height: h,
            });
            continue;
        }
        let i = v.row as usize * w + v.col as usize;
        if owner[i] != u32::MAX {
            found.push(Violation::DuplicateVertex {
                first: owner[i] as usize,
                second: k,
                col: v.col,
                row: v.row,
            });
        }
        owner[i] = k as u32;
        let truth = grid.heights()[i];
        if opts.holes && truth.is_nan() {
            found.push(Violation::VertexOnVoid {
                vertex: k,
                col: v.col,
                row: v.row,
            });
            continue;
        }
        let within = (f64::from(v.z_m) - f64::from(truth)).abs() <= opts.height_tolerance_m;
        let clipped = opts.clipped_border && (v.col as usize + 1 == w || v.row as usize + 1 == h);
        if v.z_m.to_bits() != truth.to_bits() && !opts.allow_fictitious && !within && !clipped {
            found.push(Violation::WrongHeight {
                vertex: k,
                col: v.col,
                row: v.row,
                got: v.z_m,
                expected: truth,
            });
        }
    }
    if opts.allow_fictitious && found.total == 0 {
        check_fictitious(grid, mesh, &owner, found);
    }
    owner
}

/// The direct tests for a general triangulation (module docs, 6 and 7).
/// `owner` maps each sample to its vertex. Every undirected edge is walked
/// once, lattice point by lattice point (`gcd(|dx|, |dy|) − 1` of them
/// strictly inside).
fn check_general(grid: &HeightGrid, mesh: &Mesh, owner: &[u32], found: &mut Found) {
    let mut used = vec![false; mesh.vertices.len()];
    let mut edges: Vec<(u32, u32)> = Vec::with_capacity(3 * mesh.triangles.len());
    for t in &mesh.triangles {
        for k in 0..3 {
            let (i, j) = (t[k], t[(k + 1) % 3]);
            used[i as usize] = true;
            edges.push((i.min(j), i.max(j)));
        }
    }
    edges.sort_unstable();
    edges.dedup();
    for &(i, j) in &edges {
        let (a, b) = (mesh.vertices[i as usize], mesh.vertices[j as usize]);
        let (dx, dy) = (b.col as i64 - a.col as i64, b.row as i64 - a.row as i64);
        let g = gcd(dx.unsigned_abs(), dy.unsigned_abs()) as i64;
        for s in 1..g {
            let (x, y) = (a.col as i64 + dx / g * s, a.row as i64 + dy / g * s);
            if owner[y as usize * grid.width() + x as usize] != u32::MAX {
                found.push(Violation::VertexOnEdge {
                    col: x as u32,
                    row: y as u32,
                    ac: a.col,
                    ar: a.row,
                    bc: b.col,
                    br: b.row,
                });
            }
        }
    }
    for (k, v) in mesh.vertices.iter().enumerate() {
        if !used[k] {
            found.push(Violation::UnusedVertex {
                vertex: k,
                col: v.col,
                row: v.row,
            });
        }
    }
}

fn gcd(mut a: u64, mut b: u64) -> u64 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// A vertex whose height is not its sample's must be a fictitious point: the
/// interpolation at the midpoint of its hierarchy diagonal (the hypotenuse of
/// the bitree diamond it splits, found from its position), whose two ends are
/// mesh vertices, using their mesh heights; equal within `f32` rounding (half
/// an `f32` ulp of the exact midpoint value, plus one ulp of slack).
fn check_fictitious(grid: &HeightGrid, mesh: &Mesh, owner: &[u32], found: &mut Found) {
    let w = grid.width();
    let hier = Hierarchy::new(w as u32, grid.height() as u32);
    for (k, v) in mesh.vertices.iter().enumerate() {
        let i = v.row as usize * w + v.col as usize;
        let truth = grid.heights()[i];
        if v.z_m.to_bits() == truth.to_bits() {
            continue;
        }
        let ends = diagonal_of([v.col, v.row], hier.size()).and_then(|(a, b)| {
            let id = |p: [u32; 2]| {
                (hier.contains(p) && owner[hier.index(p)] != u32::MAX)
                    .then(|| owner[hier.index(p)] as usize)
            };
            Some((id(a)?, id(b)?))
        });
        let Some((ia, ib)) = ends else {
            found.push(Violation::FictitiousWithoutDiagonal {
                vertex: k,
                col: v.col,
                row: v.row,
                got: v.z_m,
                expected: truth,
            });
            continue;
        };
        let mid = 0.5 * (mesh.vertices[ia].z_m as f64 + mesh.vertices[ib].z_m as f64);
        let tol = (mid as f32).abs().max(f32::MIN_POSITIVE) as f64 * f32::EPSILON as f64 * 1.5;
        if (v.z_m as f64 - mid).abs() > tol {
            found.push(Violation::WrongFictitiousHeight {
                vertex: k,
                col: v.col,
                row: v.row,
                got: v.z_m,
                expected: mid,
            });
        }
    }
}

fn check_triangles(grid: &HeightGrid, mesh: &Mesh, opts: &CheckOptions, found: &mut Found) {
    let n = mesh.vertices.len();
    let mut area2 = 0i64;
    for (k, t) in mesh.triangles.iter().enumerate() {
        if let Some(&bad) = t.iter().find(|&&i| i as usize >= n) {
            found.push(Violation::IndexOutOfRange {
                tri: k,
                index: bad,
                count: n,
            });
            continue;
        }
        let a = mesh.signed_area2(*t);
        if a == 0 {
            found.push(Violation::Degenerate { tri: k });
        } else if a < 0 {
            found.push(Violation::Flipped { tri: k });
        }
        area2 += a;
    }
    let voids = opts.holes.then(|| VoidMask::new(grid));
    let faults = Edges::new(mesh).faults(grid, mesh, opts.conforming, voids.as_ref());
    for (from, to) in faults.overused {
        found.push(Violation::EdgeOveruse { from, to });
    }
    for (a, b) in faults.open {
        found.push(Violation::OpenEdge {
            ac: a.col,
            ar: a.row,
            bc: b.col,
            br: b.row,
        });
    }
    let expected = 2 * (grid.width() as i64 - 1) * (grid.height() as i64 - 1);
    if area2 != expected && !opts.holes {
        found.push(Violation::AreaMismatch {
            got: area2,
            expected,
        });
    }
}

/// The directed edges of the triangles with valid indices, by their first
/// vertex (compressed rows), each vertex's second vertices sorted: so read
/// vertex by vertex they are all the edges in sorted order.
struct Edges {
    start: Vec<u32>,
    to: Vec<u32>,
}

impl Edges {
    fn new(mesh: &Mesh) -> Self {
        let n = mesh.vertices.len();
        let valid = |t: &&[u32; 3]| t.iter().all(|&i| (i as usize) < n);
        let mut start = vec![0u32; n + 1];
        for t in mesh.triangles.iter().filter(valid) {
            for &v in t {
                start[v as usize + 1] += 1;
            }
        }
        for i in 0..n {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut to = vec![0u32; start[n] as usize];
        for t in mesh.triangles.iter().filter(valid) {
            for e in 0..3 {
                let from = t[e] as usize;
                to[fill[from] as usize] = t[(e + 1) % 3];
                fill[from] += 1;
            }
        }
        let mut edges = Edges { start, to };
        let lists = split_lengths(&mut edges.to, &edges.start);
        lists.into_par_iter().for_each(|l| l.sort_unstable());
        edges
    }

    /// The second vertices of the edges leaving `v`, sorted.
    fn of(&self, v: u32) -> &[u32] {
        &self.to[self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
    }

    /// The edges used twice in one direction (once per repeat), and, when
    /// `conforming`, the ends of every edge without its reverse that is not on
    /// the grid's border; both in sorted edge order.
    fn faults(
        &self,
        grid: &HeightGrid,
        mesh: &Mesh,
        conforming: bool,
        voids: Option<&VoidMask>,
    ) -> Faults {
        let (w, h) = (grid.width() as u32, grid.height() as u32);
        let per_vertex: Vec<_> = (0..mesh.vertices.len() as u32)
            .into_par_iter()
            .with_min_len(1 << 12)
            .filter_map(|i| {
                let out = self.of(i);
                let overused: Vec<(u32, u32)> = out
                    .windows(2)
                    .filter(|p| p[0] == p[1])
                    .map(|p| (i, p[0]))
                    .collect();
                let open: Vec<(MeshVertex, MeshVertex)> = if conforming {
                    out.iter()
                        .filter(|&&j| self.of(j).binary_search(&i).is_err())
                        .map(|&j| (mesh.vertices[i as usize], mesh.vertices[j as usize]))
                        .filter(|(a, b)| {
                            !((a.col == 0 && b.col == 0)
                                || (a.col == w - 1 && b.col == w - 1)
                                || (a.row == 0 && b.row == 0)
                                || (a.row == h - 1 && b.row == h - 1))
                        })
                        .filter(|(a, b)| !voids.is_some_and(|m| holes::next_to_void(m, a, b)))
                        .collect()
                } else {
                    Vec::new()
                };
                (!overused.is_empty() || !open.is_empty()).then_some((overused, open))
            })
            .collect();
        let mut faults = Faults::default();
        for (o, p) in per_vertex {
            faults.overused.extend(o);
            faults.open.extend(p);
        }
        faults
    }
}

/// The edges' faults, in sorted edge order.
#[derive(Default)]
struct Faults {
    /// Edges used twice in one direction, once per repeat.
    overused: Vec<(u32, u32)>,
    /// The ends of edges without their reverse, off the grid's border.
    open: Vec<(MeshVertex, MeshVertex)>,
}

/// `v` cut into the consecutive slices the prefix `start` delimits.
fn split_lengths<'a>(v: &'a mut [u32], start: &[u32]) -> Vec<&'a mut [u32]> {
    let mut out = Vec::with_capacity(start.len().saturating_sub(1));
    let mut rest = v;
    for w in start.windows(2) {
        let (head, tail) = rest.split_at_mut((w[1] - w[0]) as usize);
        out.push(head);
        rest = tail;
    }
    out
}
