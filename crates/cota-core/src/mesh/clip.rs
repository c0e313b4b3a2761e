//! A bitree mesh of a clamp-extended grid ([`crate::grid::extend`]) clipped
//! back to the real rectangle `[0, W − 1] × [0, H − 1]`.
//!
//! Each triangle is cut by the half-planes `x ≤ W − 1` and `y ≤ H − 1`
//! (Sutherland & Hodgman 1974, "Reentrant polygon clipping"). The bitree's
//! edges are axis-aligned or diagonal, so every crossing with those integer
//! lines is a sample: the clipped polygon (at most five vertices, convex,
//! counter-clockwise like the triangle) is fanned from its first vertex into
//! triangles with vertices on samples. A new vertex on an edge `u`–`v` takes
//! the height interpolated along that edge, computed from its end that comes
//! first in row-major order, so the two triangles sharing the edge give it
//! the same bits: no crack, and no T-junction since both cut the edge at the
//! same sample. The only point that can fall inside a triangle is the
//! corner `(W − 1, H − 1)`; it takes the triangle's plane there. The surface
//! over the real rectangle is thus exactly the extended mesh's, so a bound
//! that held at every extended sample holds at every real one; the clipped
//! border vertices carry the mesh's height there, not the sample's, which
//! the checker accepts with [`crate::mesh::check::CheckOptions::clipped_border`].

use std::collections::HashMap;

use super::{Mesh, MeshVertex};

type P = (i64, i64);

/// `mesh` (vertices at integer samples, triangles with axis-aligned or
/// diagonal edges, such as a bitree mesh) clipped to the `width × height`
/// rectangle of samples from (0, 0), in place. A mesh inside it comes back
/// unchanged; otherwise the vertices and triangles keep their order, each
/// cut triangle replaced by one of its pieces, its other pieces and the new
/// vertices appended.
pub fn clip_to(mut mesh: Mesh, width: u32, height: u32) -> Mesh {
    let (xm, ym) = (i64::from(width) - 1, i64::from(height) - 1);
    let inside = |v: &MeshVertex| i64::from(v.col) <= xm && i64::from(v.row) <= ym;
    if mesh.vertices.iter().all(inside) {
        return mesh;
    }
    let mut remap = vec![u32::MAX; mesh.vertices.len()];
    let mut next = 0;
    for (k, v) in mesh.vertices.iter().enumerate() {
        if inside(v) {
            remap[k] = next;
            next += 1;
        }
    }
    // The cut triangles' corners, before the vertices outside go.
    let cuts = cut_corners(&mesh, &remap);
    mesh.vertices.retain(inside);
    let mut out = Clipper {
        vertices: mesh.vertices,
        added: HashMap::new(),
        max: (xm, ym),
        orphans: false,
    };
    let triangles = out.triangles(mesh.triangles, &remap, &cuts);
    let clipped = Mesh {
        vertices: out.vertices,
        triangles,
    };
    // A conforming mesh leaves no vertex unused (every vertex in the
    // rectangle has a triangle around it meeting the rectangle's interior);
    // only a cut-away triangle with a vertex inside could.
    if out.orphans {
        compact(clipped)
    } else {
        clipped
    }
}

/// The triangles of `mesh` with a vertex outside (`remap` gives
/// `u32::MAX`), in order.
fn cut_corners(mesh: &Mesh, remap: &[u32]) -> Vec<Corners> {
    let corner = |i: u32| {
        let v = mesh.vertices[i as usize];
        ((i64::from(v.col), i64::from(v.row)), f64::from(v.z_m))
    };
    mesh.triangles
        .iter()
        .filter(|t| t.iter().any(|&i| remap[i as usize] == u32::MAX))
        .map(|t| Corners {
            ids: t.map(|i| remap[i as usize]),
            at: t.map(|i| corner(i).0),
            z_m: t.map(|i| corner(i).1),
        })
        .collect()
}

/// A triangle to cut: its corners' new vertex numbers (`u32::MAX` outside
/// the rectangle), positions and heights.
struct Corners {
    ids: [u32; 3],
    at: [P; 3],
    z_m: [f64; 3],
}

/// The clipping state: the output vertices, those added by position.
struct Clipper {
    vertices: Vec<MeshVertex>,
    added: HashMap<P, u32>,
    max: P,
    /// A triangle with a vertex in the rectangle was cut away entirely.
    orphans: bool,
}

impl Clipper {
    /// `triangles` renumbered by `remap` in place, each with a vertex
    /// outside replaced by its pieces (`cuts`, in the same order).
    fn triangles(
        &mut self,
        mut triangles: Vec<[u32; 3]>,
        remap: &[u32],
        cuts: &[Corners],
    ) -> Vec<[u32; 3]> {
        let (mut kept, mut extra, mut cuts) = (0, Vec::new(), cuts.iter());
        for k in 0..triangles.len() {
            let t = triangles[k].map(|i| remap[i as usize]);
            if !t.contains(&u32::MAX) {
                triangles[kept] = t;
                kept += 1;
                continue;
            }
            let mut pieces = cuts.next().map_or_else(Vec::new, |c| self.cut(c));
            if !pieces.is_empty() {
                triangles[kept] = pieces.swap_remove(0);
                kept += 1;
                extra.append(&mut pieces);
            }
        }
        triangles.truncate(kept);
        triangles.append(&mut extra);
        triangles
    }

    /// The pieces of `t`, which has a vertex outside the rectangle.
    fn cut(&mut self, t: &Corners) -> Vec<[u32; 3]> {
        let (xm, ym) = self.max;
        let poly = cut(&t.at, |p| p.0 <= xm, |a, b| cross_x(a, b, xm));
        let mut poly = cut(&poly, |p| p.1 <= ym, |a, b| cross_y(a, b, ym));
        poly.dedup();
        while poly.len() > 1 && poly.first() == poly.last() {
            poly.pop();
        }
        if poly.len() < 3 {
            self.orphans |= t.ids.iter().any(|&i| i != u32::MAX);
            return Vec::new();
        }
        let ids: Vec<u32> = poly.iter().map(|&p| self.vertex_at(t, p)).collect();
        (1..ids.len() - 1)
            .filter(|&k| area2(poly[0], poly[k], poly[k + 1]) != 0)
            .map(|k| [ids[0], ids[k], ids[k + 1]])
            .collect()
    }

    /// The output vertex at `p`, a point of triangle `t`.
    fn vertex_at(&mut self, t: &Corners, p: P) -> u32 {
        let c = &t.at;
        if let Some(k) = c.iter().position(|&q| q == p) {
            return t.ids[k];
        }
        if let Some(&id) = self.added.get(&p) {
            return id;
        }
        let z_m = height_at(t, p);
        let id = self.vertices.len() as u32;
        self.vertices.push(MeshVertex {
            col: p.0 as u32,
            row: p.1 as u32,
            z_m: z_m as f32,
        });
        self.added.insert(p, id);
        id
    }
}

/// The height at `p` of triangle `t`: interpolated along the edge it lies on
/// (from the end first in row-major order: the same bits from both
/// triangles of the edge), else on the triangle's plane.
fn height_at(t: &Corners, p: P) -> f64 {
    let (c, z) = (&t.at, &t.z_m);
    match (0..3).find(|&k| on_segment(c[k], c[(k + 1) % 3], p)) {
        Some(k) => {
            let (i, j) = (k, (k + 1) % 3);
            let (u, v) = if (c[i].1, c[i].0) <= (c[j].1, c[j].0) {
                (i, j)
            } else {
                (j, i)
            };
            let n = (c[v].0 - c[u].0).abs().max((c[v].1 - c[u].1).abs()) as f64;
            let s = (p.0 - c[u].0).abs().max((p.1 - c[u].1).abs()) as f64;
            (z[u] * (n - s) + z[v] * s) / n
        }
        None => {
            let a = area2(c[0], c[1], c[2]) as f64;
            (z[0] * area2(p, c[1], c[2]) as f64
                + z[1] * area2(c[0], p, c[2]) as f64
                + z[2] * area2(c[0], c[1], p) as f64)
                / a
        }
    }
}

/// One Sutherland–Hodgman pass: the polygon `poly` cut by the half-plane
/// `keep`, `cross(a, b)` giving where `a`–`b` leaves or enters it.
fn cut(poly: &[P], keep: impl Fn(P) -> bool, cross: impl Fn(P, P) -> P) -> Vec<P> {
    let mut out = Vec::with_capacity(poly.len() + 2);
    for (k, &b) in poly.iter().enumerate() {
        let a = poly[(k + poly.len() - 1) % poly.len()];
        match (keep(a), keep(b)) {
            (true, true) => out.push(b),
            (true, false) => out.push(cross(a, b)),
            (false, true) => {
                out.push(cross(a, b));
                out.push(b);
            }
            (false, false) => {}
        }
    }
    out
}

/// Where `a`–`b` crosses the column `x` (edges are axis-aligned or
/// diagonal, so the row is an integer).
fn cross_x(a: P, b: P, x: i64) -> P {
    (x, a.1 + (b.1 - a.1) * (x - a.0) / (b.0 - a.0))
}

/// Where `a`–`b` crosses the row `y`.
fn cross_y(a: P, b: P, y: i64) -> P {
    (a.0 + (b.0 - a.0) * (y - a.1) / (b.1 - a.1), y)
}

/// Twice the signed area of `(a, b, c)` in (column, row) coordinates.
fn area2(a: P, b: P, c: P) -> i64 {
    (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0)
}

/// Whether `p` lies on the segment `a`–`b`.
fn on_segment(a: P, b: P, p: P) -> bool {
    area2(a, b, p) == 0
        && p.0 >= a.0.min(b.0)
        && p.0 <= a.0.max(b.0)
        && p.1 >= a.1.min(b.1)
        && p.1 <= a.1.max(b.1)
}

/// `mesh` without the vertices no triangle uses (kept in order).
fn compact(mesh: Mesh) -> Mesh {
    let mut used = vec![false; mesh.vertices.len()];
    for t in &mesh.triangles {
        for &i in t {
            used[i as usize] = true;
        }
    }
    if used.iter().all(|&u| u) {
        return mesh;
    }
    let mut remap = vec![u32::MAX; used.len()];
    let mut vertices = Vec::with_capacity(used.len());
    for (k, v) in mesh.vertices.iter().enumerate() {
        if used[k] {
            remap[k] = vertices.len() as u32;
            vertices.push(*v);
        }
    }
    let triangles = mesh
        .triangles
        .iter()
        .map(|t| t.map(|i| remap[i as usize]))
        .collect();
    Mesh {
        vertices,
        triangles,
    }
}

#[cfg(test)]
mod test {
    use super::*;

    fn v(col: u32, row: u32, z_m: f32) -> MeshVertex {
        MeshVertex { col, row, z_m }
    }

    #[test]
    fn two_root_triangles_of_513_clip_to_two_of_512() {
        // The two halves of [0, 512]², cut along `\`, counter-clockwise
        // seen from above (rows grow south).
        let mesh = Mesh {
            vertices: vec![
                v(0, 0, 0.0),
                v(512, 0, 0.0),
                v(0, 512, 0.0),
                v(512, 512, 512.0),
            ],
            triangles: vec![[0, 3, 1], [3, 0, 2]],
        };
        let c = clip_to(mesh, 512, 512);
        assert_eq!(c.triangle_count(), 2);
        assert!(c.triangles.iter().all(|&t| c.signed_area2(t) > 0));
        let corner = c.vertices.iter().find(|v| v.col == 511 && v.row == 511);
        assert_eq!(corner.map(|v| v.z_m), Some(511.0));
    }

    #[test]
    fn inside_mesh_unchanged() {
        let mesh = Mesh {
            vertices: vec![v(0, 0, 1.0), v(1, 0, 2.0), v(0, 1, 3.0)],
            triangles: vec![[0, 2, 1]],
        };
        assert_eq!(clip_to(mesh.clone(), 2, 2), mesh);
    }
}
