//! Parallel decimation: horizontal bands decimated independently with their
//! borders locked, then windows across the band borders relaxed.
//!
//! A *region* is a range of rows. A triangle whose three vertices lie in the
//! rows of a region (its boundary rows included) belongs to it; regions are
//! decimated independently, in parallel (rayon), each as its own
//! triangulation, and the other triangles are left as they are. A region's
//! vertices on its own border (shared with a triangle outside it) have open
//! stars that do not run along the grid's border, so [`super::decimate`]
//! never removes them: the region's outline never changes and the regions'
//! results fit back together exactly.
//!
//! 1. **Bands**: the rows cut into `K` bands of about as many seed vertices.
//! 2. **Windows**: a window of rows around each inner band border, where
//!    only the vertices the bands had to keep (on a border row, or on a
//!    triangle that crossed one) are visited, and whatever their removals
//!    touch.
//!
//! Every removal, in a band or in a window, is exact-checked, so the bound
//! holds whatever the cut.

use rayon::prelude::*;

use super::decimate::{decimate, Params};
use super::span::Heights;
use super::topo::{Topo, NONE};
use crate::mesh::{Mesh, MeshVertex};

/// `mesh` with its vertices in row-major order of their samples (a no-op
/// when they already are, as [`crate::Bitree::extract`] numbers them).
pub(crate) fn row_major(mesh: Mesh, width: usize) -> Mesh {
    let key = |v: &MeshVertex| v.row as u64 * width as u64 + v.col as u64;
    if mesh.vertices.windows(2).all(|p| key(&p[0]) < key(&p[1])) {
        return mesh;
    }
    let mut order: Vec<u32> = (0..mesh.vertices.len() as u32).collect();
    order.sort_unstable_by_key(|&i| key(&mesh.vertices[i as usize]));
    let mut id = vec![0u32; order.len()];
    for (new, &old) in order.iter().enumerate() {
        id[old as usize] = new as u32;
    }
    Mesh {
        vertices: order.iter().map(|&i| mesh.vertices[i as usize]).collect(),
        triangles: mesh
            .triangles
            .iter()
            .map(|t| t.map(|v| id[v as usize]))
            .collect(),
    }
}

/// What the regions work on: the vertices (row-major, never renumbered) and
/// the grid.
struct Ctx<'a> {
    vertices: &'a [MeshVertex],
    hs: &'a Heights<'a>,
    params: Params,
    locked: &'a [bool],
}

impl Ctx<'_> {
    /// The first vertex at or below `row`.
    fn first_at(&self, row: u32) -> usize {
        self.vertices.partition_point(|v| v.row < row)
    }

    /// Rows spanned by triangle `t`.
    fn rows(&self, t: &[u32; 3]) -> (u32, u32) {
        let r = t.map(|v| self.vertices[v as usize].row);
        (r[0].min(r[1]).min(r[2]), r[0].max(r[1]).max(r[2]))
    }

    /// Decimates every region of `regions` (sorted row ranges, overlapping
    /// at most at an end row) in parallel and returns all the triangles.
    /// Within a region only the vertices marked in `dirty` (all when `None`)
    /// are visited at first.
    fn regions(
        &self,
        tris: Vec<[u32; 3]>,
        regions: &[(u32, u32)],
        dirty: Option<&[bool]>,
    ) -> Vec<[u32; 3]> {
        let mut own: Vec<Vec<[u32; 3]>> = vec![Vec::new(); regions.len()];
        let mut rest = Vec::new();
        for t in tris {
            let (lo, hi) = self.rows(&t);
            let r = regions.partition_point(|&(a, _)| a <= lo);
            match r.checked_sub(1) {
                Some(r) if hi <= regions[r].1 => own[r].push(t),
                _ => rest.push(t),
            }
        }
        let done: Vec<Vec<[u32; 3]>> = own
            .into_par_iter()
            .zip(regions.par_iter())
            .map(|(tris, &(a, b))| self.one(tris, a, b, dirty))
            .collect();
        for d in done {
            rest.extend_from_slice(&d);
        }
        rest
    }

    /// Decimates the region of rows `a..=b` holding `tris`.
    fn one(&self, tris: Vec<[u32; 3]>, a: u32, b: u32, dirty: Option<&[bool]>) -> Vec<[u32; 3]> {
        if tris.is_empty() {
            return tris;
        }
        let (lo, hi) = (self.first_at(a), self.first_at(b + 1));
        let sub = Mesh {
            vertices: self.vertices[lo..hi].to_vec(),
            triangles: tris.iter().map(|t| t.map(|v| v - lo as u32)).collect(),
        };
        let mut topo = Topo::from_mesh(&sub);
        let mut marks = dirty.map_or_else(Vec::new, |d| d[lo..hi].to_vec());
        decimate(
            &mut topo,
            self.hs,
            &self.params,
            &self.locked[lo..hi],
            &mut marks,
        );
        topo.tris
            .iter()
            .filter(|t| t.v[0] != NONE)
            .map(|t| t.v.map(|v| v + lo as u32))
            .collect()
    }
}

/// The boundary rows of `k` bands holding about as many vertices each:
/// `rows[0] = 0 < rows[1] < … < rows[k'] = last row` (`k' ≤ k`).
fn band_rows(vertices: &[MeshVertex], k: usize, last_row: u32) -> Vec<u32> {
    let n = vertices.len();
    let mut rows = vec![0u32];
    for b in 1..k {
        let r = vertices[(b * n / k).min(n - 1)].row;
        if r > *rows.last().unwrap_or(&0) && r < last_row {
            rows.push(r);
        }
    }
    rows.push(last_row);
    rows
}

/// Decimates `mesh` (vertices row-major) as `params` say, in about `k` bands
/// in parallel, then in windows across their borders; `locked[v]` vertices
/// stay. Returns the decimated mesh (vertices renumbered, row-major).
pub(crate) fn decimate_in_bands(
    mesh: &Mesh,
    hs: &Heights,
    params: &Params,
    locked: &[bool],
    k: usize,
) -> Mesh {
    let ctx = Ctx {
        vertices: &mesh.vertices,
        hs,
        params: *params,
        locked,
    };
    let rows = band_rows(&mesh.vertices, k.max(1), params.size[1] as u32 - 1);
    let bands: Vec<(u32, u32)> = rows.windows(2).map(|w| (w[0], w[1])).collect();
    let mut tris = ctx.regions(mesh.triangles.clone(), &bands, None);
    if bands.len() > 1 {
        // The vertices the bands kept: on an inner border row, or on a
        // triangle crossing one; the windows reach as far as those
        // triangles, and twice as far, within half a band.
        let inner = &rows[1..rows.len() - 1];
        let mut dirty: Vec<bool> = mesh
            .vertices
            .iter()
            .map(|v| inner.binary_search(&v.row).is_ok())
            .collect();
        let mut reach = 0;
        for t in &tris {
            let (lo, hi) = ctx.rows(t);
            let b = inner.partition_point(|&r| r <= lo);
            if b < inner.len() && inner[b] < hi {
                for &v in t {
                    dirty[v as usize] = true;
                }
                reach = reach.max(hi - lo);
            }
        }
        let windows: Vec<(u32, u32)> = (1..rows.len() - 1)
            .map(|b| {
                let half = (rows[b] - rows[b - 1]).min(rows[b + 1] - rows[b]) / 2;
                let m = (2 * reach + 8).min(half);
                (rows[b] - m, rows[b] + m)
            })
            .collect();
        tris = ctx.regions(tris, &windows, Some(&dirty));
    }
    compact(&mesh.vertices, tris)
}

/// The mesh of `tris` over the vertices they use, renumbered in order.
fn compact(vertices: &[MeshVertex], mut tris: Vec<[u32; 3]>) -> Mesh {
    let mut id = vec![NONE; vertices.len()];
    for t in &tris {
        for &v in t {
            id[v as usize] = 0;
        }
    }
    let mut out = Vec::new();
    for (i, v) in vertices.iter().enumerate() {
        if id[i] == 0 {
            id[i] = out.len() as u32;
            out.push(*v);
        }
    }
    for t in &mut tris {
        *t = t.map(|v| id[v as usize]);
    }
    Mesh {
        vertices: out,
        triangles: tris,
    }
}
