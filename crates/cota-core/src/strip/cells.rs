//! Triangle strips by rows of re-triangulated unit cells.
//!
//! Papers `000_ebf7e3a88dffd361.txt` §4 and `001_49f2c365e8c41172.txt` strip
//! the bitree's leaves in traversal order ([`super`]). At full
//! resolution that mesh is the "4-8" pattern (diagonals alternate), where
//! half the vertices lie in 8 triangles and half in 4, so any strip of it
//! needs at least 1.25 references per triangle (the lower bound in
//! [`super`]). This module reaches about `1 + 3/(2W)` on a full grid
//! `W` samples wide by changing the diagonals first:
//!
//! 1. **Unit cells.** A unit cell is a 1×1 grid square covered by exactly two
//!    mesh triangles, the two unit leaves on either side of one of its
//!    diagonals. Its only samples are its four corners, all of them vertices,
//!    and no sample lies inside it or on its diagonal.
//! 2. **Re-triangulation is exact.** Replacing a cell's diagonal by the other
//!    one keeps its four corners, its four sides (so every neighbour still
//!    shares whole edges: no T-junction appears or disappears), the vertex
//!    set and the triangle count, and changes the surface only strictly
//!    inside the cell, where there is no sample: the error at every sample,
//!    and so every figure of [`crate::mesh::metrics`] and every bound the mesh
//!    met, is unchanged. Both new triangles are counter-clockwise seen from
//!    above like the mesh's.
//! 3. **Rows.** Maximal horizontal runs of unit cells, at least
//!    [`CellOptions::min_run_cells`] long, are each written as the classic
//!    row strip `t0 b0 t1 b1 …` (top and bottom corners alternately), one
//!    reference per triangle plus two per run: the cells of the run get the
//!    diagonal that strip implies, `/` (bottom-left to top-right) when the
//!    row is walked eastwards and `\` when walked westwards. Rows are walked
//!    alternately east and west (a serpentine): a run that starts on the
//!    corner where the previous one ended costs one extra index (a swap, as
//!    its first triangle comes on the other parity), any other join two or
//!    three (degenerate connectors; the orientation is kept by the strip's
//!    parity as in [`super`] step 3).
//! 4. **The rest.** The other unit cells get the diagonal `/`
//!    ([`CellOptions::parallel_rest`]): where they form patches every
//!    interior vertex then lies in 6 triangles instead of 4 or 8, so the
//!    1.25 bound no longer applies there. The triangles not in a run are
//!    stripped by [`super::guided::stripify_guided`] in the hierarchy's order,
//!    and the two strips are joined with degenerate connectors.
//!
//! On a full grid every cell is a unit cell and every row one run: `2W`
//! references per row plus one per join, `(H−1)(2W+1)−1` references for
//! `2(W−1)(H−1)` triangles, 1.0012 per triangle at 1201². On adaptive SRTM
//! meshes at 0.5–5 m it gives 1.24–1.43 where the guided strip of the
//! unchanged mesh gives 1.44, but at 10–20 m, where few unit cells are left,
//! it can be a little longer, so [`super::StripMethod::Cells`] keeps
//! whichever strip is shorter (`bench/README.md`, "Triangle strips").
//!
//! # Runtime
//! `O(T log T)` for the cell search (a sort of the unit triangles) plus the
//! guided strip of the remainder.

use super::emit::{finish, strip_from_order, Strip};
use super::guided::stripify_guided;
use crate::mesh::Mesh;

/// Options of [`stripify_cells`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub(crate) struct CellOptions {
    /// Shortest horizontal run of unit cells stripped as a row; shorter runs
    /// are left to the guided strip. Default: 16 (measured on S29W072 and
    /// N00E010 at 0.5–20 m: 8 gives up to 0.04 more references per triangle,
    /// 32 up to 0.012 more; a full grid's runs are whole rows either way).
    pub min_run_cells: usize,
    /// Give the unit cells not stripped by rows the diagonal `/` (parallel
    /// diagonals, every interior vertex of a patch in 6 triangles) before
    /// the guided strip; else they keep theirs. Default: true (0.11 fewer
    /// references per triangle at 0.5–1 m on S29W072, 0.07 at 2 m).
    pub parallel_rest: bool,
}

impl CellOptions {
    /// The defaults.
    pub const DEFAULT: CellOptions = CellOptions {
        min_run_cells: 16,
        parallel_rest: true,
    };
}

impl Default for CellOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// A strip of a re-triangulated mesh.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct CellStrip {
    /// The strip.
    pub strip: Strip,
    /// The triangles it encodes: the input mesh's, in the same slots, with
    /// the cells of the selected runs re-triangulated (same vertices).
    pub triangles: Vec<[u32; 3]>,
    /// Cells whose diagonal changed.
    pub flipped_cells: usize,
    /// Cells stripped by rows (flipped or already with the row's diagonal).
    pub row_cells: usize,
}

/// A unit cell covered by two mesh triangles.
#[derive(Debug, Clone, Copy)]
struct Cell {
    col: u32,
    row: u32,
    /// Corner vertices: top-left, top-right, bottom-left, bottom-right (row
    /// 0 is north).
    tl: u32,
    tr: u32,
    bl: u32,
    br: u32,
    /// The mesh slots of its two triangles.
    slots: [u32; 2],
    /// True when its diagonal runs from bottom-left to top-right (`/`).
    slash: bool,
}

/// The unit cells of a mesh, sorted by row then column. Triangles with a bad
/// index are ignored (the caller validated the mesh).
fn unit_cells(mesh: &Mesh) -> Vec<Cell> {
    let pos = |i: u32| mesh.vertices.get(i as usize).map(|v| (v.col, v.row));
    let mut units: Vec<(u64, u32)> = mesh
        .triangles
        .iter()
        .enumerate()
        .filter_map(|(k, t)| {
            let p = [pos(t[0])?, pos(t[1])?, pos(t[2])?];
            let (c0, c1) = (p.iter().map(|q| q.0).min()?, p.iter().map(|q| q.0).max()?);
            let (r0, r1) = (p.iter().map(|q| q.1).min()?, p.iter().map(|q| q.1).max()?);
            (c1 - c0 == 1 && r1 - r0 == 1).then_some(((r0 as u64) << 32 | c0 as u64, k as u32))
        })
        .collect();
    units.sort_unstable();
    let mut cells = Vec::with_capacity(units.len() / 2);
    let mut i = 0;
    while i + 1 < units.len() {
        let ((key, a), (key2, b)) = (units[i], units[i + 1]);
        if key != key2 || units.get(i + 2).is_some_and(|u| u.0 == key) {
            // A lone unit triangle (its cell's other half belongs to a larger
            // triangle), or a malformed cell: skip the key.
            let mut j = i + 1;
            while j < units.len() && units[j].0 == key {
                j += 1;
            }
            i = j;
            continue;
        }
        i += 2;
        let (col, row) = (key as u32, (key >> 32) as u32);
        if let Some(cell) = make_cell(mesh, col, row, [a, b]) {
            cells.push(cell);
        }
    }
    cells
}

/// The cell at `(col, row)` from its two triangles, when they tile it (they
/// miss opposite corners).
fn make_cell(mesh: &Mesh, col: u32, row: u32, slots: [u32; 2]) -> Option<Cell> {
    // Corner ids by (dc + 2·dr): 0 tl, 1 tr, 2 bl, 3 br.
    let mut corner = [u32::MAX; 4];
    let mut missing = [0usize; 2];
    for (s, &slot) in slots.iter().enumerate() {
        let t = mesh.triangles.get(slot as usize)?;
        let mut seen = [false; 4];
        for &v in t {
            let p = mesh.vertices.get(v as usize)?;
            let k = (p.col - col) as usize + 2 * (p.row - row) as usize;
            seen[k] = true;
            corner[k] = v;
        }
        missing[s] = seen.iter().position(|&x| !x)?;
    }
    if missing[0] + missing[1] != 3 || corner.contains(&u32::MAX) {
        return None;
    }
    Some(Cell {
        col,
        row,
        tl: corner[0],
        tr: corner[1],
        bl: corner[2],
        br: corner[3],
        slots,
        // Missing tl or br: the diagonal joins tr and bl.
        slash: missing[0] == 0 || missing[0] == 3,
    })
}

/// The two triangles of a cell in the order a row strip visits them,
/// counter-clockwise seen from above: with `/` when walked eastwards, with
/// `\` when walked westwards.
fn row_triangles(c: &Cell, east: bool) -> [[u32; 3]; 2] {
    if east {
        [[c.tl, c.bl, c.tr], [c.bl, c.br, c.tr]]
    } else {
        [[c.tl, c.br, c.tr], [c.tl, c.bl, c.br]]
    }
}

/// Strips `mesh` (a bitree mesh, `order` its triangle slots in the
/// hierarchy's order, as from [`super::bitree_order`]) by rows
/// of re-triangulated unit cells and the guided strip of the rest (module
/// docs). Slots missing from `order` or out of range are left out of the
/// strip (not of [`CellStrip::triangles`]), so pass every slot once.
pub(crate) fn stripify_cells(mesh: &Mesh, order: &[u32], opts: &CellOptions) -> CellStrip {
    let cells = unit_cells(mesh);
    let mut triangles = mesh.triangles.clone();
    let mut in_row = vec![false; mesh.triangles.len()];
    let mut row_order: Vec<[u32; 3]> = Vec::new();
    let mut flipped_cells = 0;
    let mut row_cells = 0;
    // Runs: maximal stretches of consecutive cells in one row.
    let mut runs: Vec<&[Cell]> = Vec::new();
    let mut start = 0;
    for i in 1..=cells.len() {
        let ends = i == cells.len()
            || cells[i].row != cells[i - 1].row
            || cells[i].col != cells[i - 1].col + 1;
        if ends {
            if i - start >= opts.min_run_cells.max(1) {
                runs.push(&cells[start..i]);
            }
            start = i;
        }
    }
    // Serpentine: each row's runs, eastwards on even rows, westwards on odd.
    let mut r = 0;
    while r < runs.len() {
        let row = runs[r][0].row;
        let mut end = r;
        while end < runs.len() && runs[end][0].row == row {
            end += 1;
        }
        let east = row.is_multiple_of(2);
        let mut visit = |run: &[Cell]| {
            let mut put = |c: &Cell| {
                let tris = row_triangles(c, east);
                for (k, t) in tris.iter().enumerate() {
                    triangles[c.slots[k] as usize] = *t;
                    in_row[c.slots[k] as usize] = true;
                }
                row_order.extend_from_slice(&tris);
                flipped_cells += usize::from(c.slash != east);
                row_cells += 1;
            };
            if east {
                run.iter().for_each(&mut put);
            } else {
                run.iter().rev().for_each(&mut put);
            }
        };
        if east {
            runs[r..end].iter().for_each(|run| visit(run));
        } else {
            runs[r..end].iter().rev().for_each(|run| visit(run));
        }
        r = end;
    }
    if opts.parallel_rest {
        for c in cells.iter().filter(|c| !in_row[c.slots[0] as usize]) {
            let tris = row_triangles(c, true);
            triangles[c.slots[0] as usize] = tris[0];
            triangles[c.slots[1] as usize] = tris[1];
            flipped_cells += usize::from(!c.slash);
        }
    }
    let mut s = strip_from_order(&row_order).indices;
    let rest: Vec<[u32; 3]> = order
        .iter()
        .filter(|&&k| in_row.get(k as usize) == Some(&false))
        .map(|&k| triangles[k as usize])
        .collect();
    if !rest.is_empty() {
        append(&mut s, &stripify_guided(&rest).indices);
    }
    CellStrip {
        strip: finish(s),
        triangles,
        flipped_cells,
        row_cells,
    }
}

/// Appends strip `t` to strip `s` with degenerate connectors, keeping the
/// parity of `t`'s triangles (an even offset).
fn append(s: &mut Vec<u32>, t: &[u32]) {
    let (Some(&q), Some(&u)) = (s.last(), t.first()) else {
        s.extend_from_slice(t);
        return;
    };
    if q == u {
        // `… p q` + `q t1 …`: (p, q, q) and (q, q, t1) are degenerate; one
        // more `q` first when the offset would be odd.
        if !s.len().is_multiple_of(2) {
            s.push(q);
        }
        s.extend_from_slice(t);
        return;
    }
    s.push(q);
    s.push(u);
    if !s.len().is_multiple_of(2) {
        s.push(u);
    }
    // Offset is now s.len(), even.
    s.extend_from_slice(t);
}

#[cfg(test)]
mod test {
    use super::super::emit::{canonical, drawn_triangles as strip_to_triangles};
    use super::*;

    #[test]
    fn append_keeps_parity() {
        // A strip of (3,4,5), even, after prefixes of either length parity
        // and one ending on its first vertex.
        for pre in [
            vec![0, 1, 2],
            vec![0, 0, 1, 2],
            vec![0, 1, 3],
            vec![1, 0, 0, 3],
        ] {
            let mut s = pre.clone();
            append(&mut s, &[3, 4, 5]);
            let mut want: Vec<_> = strip_to_triangles(&pre)
                .into_iter()
                .map(canonical)
                .collect();
            want.push([3, 4, 5]);
            let mut got: Vec<_> = strip_to_triangles(&s).into_iter().map(canonical).collect();
            want.sort_unstable();
            got.sort_unstable();
            assert_eq!(got, want, "{s:?}");
        }
    }

    #[test]
    fn unit_cells_of_a_3x3_full_grid() {
        let mesh = super::super::full_bitree_mesh(3, 3);
        let cells = unit_cells(&mesh);
        assert_eq!(cells.len(), 4);
        // The 4-8 pattern: diagonals alternate.
        let slash: Vec<bool> = cells.iter().map(|c| c.slash).collect();
        assert_eq!(slash[0], !slash[1]);
        assert_eq!(slash[0], !slash[2]);
        assert_eq!(slash[0], slash[3]);
    }
}
