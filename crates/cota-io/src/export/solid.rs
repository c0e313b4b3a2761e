//! Closing a terrain mesh into a watertight solid (STL `--base` for 3D printing).
//!
//! The terrain surface is kept as it is. Its boundary — the edges used by
//! exactly one triangle — must be the border of the axis-aligned grid
//! rectangle that the mesh covers (a mesh over the full rectangle, without
//! holes; intermediate vertices along the sides are fine). Then:
//! * **walls**: for each boundary edge `a→b` (directed as in its triangle, so
//!   the surface lies to its left seen from above), the quad `a b b' a'` down to
//!   the base is split into `(b, a, a')` and `(b, a', b')`, where `a'` is `a`
//!   moved to `z = base_m`; these use the edge as `b→a`, opposite to the surface;
//! * **base**: a fan from an added vertex at the rectangle's centre, one
//!   triangle `(b', a', centre)` per boundary edge. Every fan triangle has the
//!   centre strictly inside the rectangle and its other two vertices on one
//!   side, so none is degenerate even where boundary vertices are collinear.
//!
//! Every edge of the result is shared by exactly two triangles that use it in
//! opposite directions, all triangles are counter-clockwise seen from outside
//! in east/north/up, so the right-hand normals point outwards (up on the
//! terrain, out of the sides, down under the base).
//!
//! The new triangles are returned in grid space (column, row, metres), for the
//! writer to map through the same [`Frame`](super::coords::Frame) as the
//! surface, which keeps shared vertices bit-identical.

use cota_core::Mesh;
use rayon::slice::ParallelSliceMut;

use super::error::ExportError;

/// A point in grid space: column, row (fractional allowed), height in metres.
pub(crate) type GridPoint = [f64; 3];

/// Largest vertex count whose edge keys pack into a u64 (see [`edge_key`]).
const MAX_VERTICES: u64 = 1 << 31;

/// The walls and base that close `mesh` down to `base_m`, as triangles
/// counter-clockwise from outside in east/north/up (see the module doc).
///
/// # Errors
/// [`ExportError::BaseNotBelow`] unless `base_m` is finite and below every
/// vertex; [`ExportError::NotClosable`] when the boundary is not a rectangle's
/// border or the mesh is not an oriented manifold.
pub(crate) fn closing_triangles(
    mesh: &Mesh,
    base_m: f64,
) -> Result<Vec<[GridPoint; 3]>, ExportError> {
    check_base(mesh, base_m)?;
    let boundary = boundary_edges(mesh)?;
    let rect = Rect::of(mesh)?;
    check_boundary_is_border(mesh, &boundary, &rect)?;
    let centre = [
        (f64::from(rect.c0) + f64::from(rect.c1)) / 2.0,
        (f64::from(rect.r0) + f64::from(rect.r1)) / 2.0,
        base_m,
    ];
    let top = |i: u32| {
        let v = mesh.vertices[i as usize];
        [f64::from(v.col), f64::from(v.row), f64::from(v.z_m)]
    };
    let mut out = Vec::with_capacity(3 * boundary.len());
    for [a, b] in boundary {
        let (ta, tb) = (top(a), top(b));
        let (ba, bb) = ([ta[0], ta[1], base_m], [tb[0], tb[1], base_m]);
        out.push([tb, ta, ba]);
        out.push([tb, ba, bb]);
        out.push([bb, ba, centre]);
    }
    Ok(out)
}

/// The base must be finite and strictly below the lowest vertex.
fn check_base(mesh: &Mesh, base_m: f64) -> Result<(), ExportError> {
    let min_m = mesh
        .vertices
        .iter()
        .map(|v| v.z_m)
        .fold(f32::INFINITY, f32::min);
    if base_m.is_finite() && base_m < f64::from(min_m) {
        Ok(())
    } else {
        Err(ExportError::BaseNotBelow { base_m, min_m })
    }
}

/// Packs an edge: smaller index in bits 32–62, larger in bits 1–31, bit 0 set
/// when the edge runs from the smaller to the larger index.
#[inline]
fn edge_key(a: u32, b: u32) -> u64 {
    let (lo, hi) = (a.min(b), a.max(b));
    (u64::from(lo) << 32) | (u64::from(hi) << 1) | u64::from(a < b)
}

/// The directed edge packed by [`edge_key`].
#[inline]
fn edge_of(key: u64) -> [u32; 2] {
    let lo = (key >> 32) as u32;
    let hi = ((key >> 1) & 0x7fff_ffff) as u32;
    if key & 1 == 1 {
        [lo, hi]
    } else {
        [hi, lo]
    }
}

/// Edges used by exactly one triangle, directed as in that triangle. Fails
/// when an edge has more than two triangles or two that run it the same way.
fn boundary_edges(mesh: &Mesh) -> Result<Vec<[u32; 2]>, ExportError> {
    let count = mesh.vertices.len() as u64;
    if count > MAX_VERTICES {
        return Err(ExportError::TooLarge {
            what: "vertices for a closed solid",
            count,
            max: MAX_VERTICES,
        });
    }
    let mut keys = Vec::with_capacity(3 * mesh.triangles.len());
    for (k, t) in mesh.triangles.iter().enumerate() {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            if a == b {
                return Err(not_closable(format!("triangle {k} repeats vertex {a}")));
            }
            keys.push(edge_key(a, b));
        }
    }
    keys.par_sort_unstable();
    let mut boundary = Vec::new();
    for run in keys.chunk_by(|x, y| x >> 1 == y >> 1) {
        match run {
            [one] => boundary.push(edge_of(*one)),
            [x, y] if x != y => {}
            _ => return Err(bad_edge(mesh, run)),
        }
    }
    Ok(boundary)
}

/// The error for an edge shared badly by `run.len()` triangles.
fn bad_edge(mesh: &Mesh, run: &[u64]) -> ExportError {
    let [a, b] = run.first().map_or([0, 0], |&k| edge_of(k));
    let what = if run.len() == 2 {
        "is used twice in the same direction (triangles not consistently oriented)".to_string()
    } else {
        format!("is shared by {} triangles (not a manifold)", run.len())
    };
    not_closable(format!("edge {} {what}", describe_edge(mesh, a, b)))
}

/// `(col,row)-(col,row)` of an edge.
fn describe_edge(mesh: &Mesh, a: u32, b: u32) -> String {
    let p = |i: u32| {
        mesh.vertices
            .get(i as usize)
            .map_or_else(|| format!("#{i}"), |v| format!("({},{})", v.col, v.row))
    };
    format!("{}-{}", p(a), p(b))
}

/// [`ExportError::NotClosable`].
fn not_closable(reason: String) -> ExportError {
    ExportError::NotClosable(reason)
}

/// The bounding rectangle of the vertices used by triangles, in grid units.
#[derive(Debug, Clone, Copy)]
struct Rect {
    c0: u32,
    c1: u32,
    r0: u32,
    r1: u32,
}

impl Rect {
    /// Bounding rectangle of the triangles' vertices; must have positive area.
    fn of(mesh: &Mesh) -> Result<Rect, ExportError> {
        let mut r = Rect {
            c0: u32::MAX,
            c1: 0,
            r0: u32::MAX,
            r1: 0,
        };
        for &i in mesh.triangles.iter().flatten() {
            let v = mesh.vertices[i as usize];
            r.c0 = r.c0.min(v.col);
            r.c1 = r.c1.max(v.col);
            r.r0 = r.r0.min(v.row);
            r.r1 = r.r1.max(v.row);
        }
        if r.c1 > r.c0 && r.r1 > r.r0 {
            Ok(r)
        } else {
            Err(not_closable(
                "the mesh covers no area (a single row or column)".to_string(),
            ))
        }
    }

    /// Length of the border in grid units.
    fn perimeter(&self) -> u64 {
        2 * (u64::from(self.c1 - self.c0) + u64::from(self.r1 - self.r0))
    }

    /// Length of `a→b` when it runs along the border counter-clockwise seen
    /// from above (east along the south side, north along the east side, west
    /// along the north side, south along the west side); `None` otherwise.
    fn border_run(&self, a: (u32, u32), b: (u32, u32)) -> Option<u64> {
        let ((ca, ra), (cb, rb)) = (a, b);
        let along_row = ra == rb && ((ra == self.r1 && cb > ca) || (ra == self.r0 && cb < ca));
        let along_col = ca == cb && ((ca == self.c1 && rb < ra) || (ca == self.c0 && rb > ra));
        if along_row {
            Some(u64::from(ca.abs_diff(cb)))
        } else if along_col {
            Some(u64::from(ra.abs_diff(rb)))
        } else {
            None
        }
    }
}

/// Every boundary edge runs counter-clockwise along the rectangle's border and
/// together they cover it once: then the boundary is exactly that border.
fn check_boundary_is_border(
    mesh: &Mesh,
    boundary: &[[u32; 2]],
    rect: &Rect,
) -> Result<(), ExportError> {
    let at = |i: u32| {
        let v = mesh.vertices[i as usize];
        (v.col, v.row)
    };
    let mut length = 0u64;
    for &[a, b] in boundary {
        match rect.border_run(at(a), at(b)) {
            Some(l) => length += l,
            None => {
                return Err(not_closable(format!(
                    "boundary edge {} does not run along the border of the mesh's \
                     rectangle (columns {}..={}, rows {}..={}); the mesh must cover the \
                     rectangle without holes",
                    describe_edge(mesh, a, b),
                    rect.c0,
                    rect.c1,
                    rect.r0,
                    rect.r1
                )))
            }
        }
    }
    if length == rect.perimeter() {
        Ok(())
    } else {
        Err(not_closable(format!(
            "the boundary edges cover {length} of the rectangle's {} border units",
            rect.perimeter()
        )))
    }
}
