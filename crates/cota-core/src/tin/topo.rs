//! The editable triangulation every TIN step works on: triangles with their
//! three neighbours, one incident triangle per vertex, and the local edits
//! (fan re-triangulation, split) that keep the adjacency consistent.
//!
//! This is the triangle-based adjacency of incremental triangulators (the
//! edge algebra of Guibas & Stolfi 1985; Garland & Heckbert 1995, "Fast
//! polygonal approximation of terrains and height fields", use the same local
//! edits for greedy insertion). Positions are integer grid samples
//! `(column, row)`; triangles are counter-clockwise seen from above (x east,
//! y north = −row), like [`Mesh`]. A triangle's corners and neighbours share
//! one record, and so do a vertex's position, height and triangle: a star
//! walk touches one cache line per triangle and per vertex. Triangles are
//! stored in the order of their first vertex (row-major), so that sweeps in
//! vertex order walk memory mostly forwards.

use crate::mesh::{Mesh, MeshVertex};

/// No triangle / no vertex.
pub(crate) const NONE: u32 = u32::MAX;

/// Twice the signed area of `(a, b, c)`, positive when counter-clockwise seen
/// from above (x = column east, y = −row north), as [`Mesh::signed_area2`].
#[inline]
pub(crate) fn orient(a: [i32; 2], b: [i32; 2], c: [i32; 2]) -> i64 {
    let (ax, ay, bx, by, cx, cy) = (
        a[0] as i64,
        a[1] as i64,
        b[0] as i64,
        b[1] as i64,
        c[0] as i64,
        c[1] as i64,
    );
    (by - ay) * (cx - ax) - (bx - ax) * (cy - ay)
}

/// A triangle: corners counter-clockwise from above (`v[0] == NONE` for a
/// free slot) and `n[k]`, the triangle across edge `k` (from corner `k` to
/// corner `k + 1`), `NONE` on the region's border.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Tri {
    pub(crate) v: [u32; 3],
    pub(crate) n: [u32; 3],
}

/// A vertex: sample position `(column, row)`, height in metres, and one live
/// triangle at it (`NONE` once removed).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Vert {
    pub(crate) p: [i32; 2],
    pub(crate) z: f32,
    pub(crate) t: u32,
}

/// `tris` sorted by their smallest vertex (a counting sort over `nv`
/// vertices), so that sweeps in vertex order walk the triangles forwards.
fn by_first_vertex(tris: &[[u32; 3]], nv: usize) -> Vec<[u32; 3]> {
    let first = |t: &[u32; 3]| t[0].min(t[1]).min(t[2]) as usize;
    let mut at = vec![0u32; nv + 1];
    for t in tris {
        at[first(t) + 1] += 1;
    }
    for i in 0..nv {
        at[i + 1] += at[i];
    }
    let mut order = vec![[0u32; 3]; tris.len()];
    for t in tris {
        let m = first(t);
        order[at[m] as usize] = *t;
        at[m] += 1;
    }
    order
}

/// A triangulation over grid samples, editable in place.
#[derive(Debug, Clone, Default)]
pub(crate) struct Topo {
    pub(crate) verts: Vec<Vert>,
    pub(crate) tris: Vec<Tri>,
    /// Free triangle slots, reused first.
    free: Vec<u32>,
}

impl Topo {
    /// The triangulation of `mesh` (assumed valid: conforming, CCW, tiling
    /// a region). Triangles are sorted by their smallest vertex id (a
    /// counting sort), then each directed edge is paired with its reverse
    /// through a per-vertex list of outgoing edges: `O(V + T)`.
    pub(crate) fn from_mesh(mesh: &Mesh) -> Topo {
        let mut verts: Vec<Vert> = mesh
            .vertices
            .iter()
            .map(|v| Vert {
                p: [v.col as i32, v.row as i32],
                z: v.z_m,
                t: NONE,
            })
            .collect();
        let order = by_first_vertex(&mesh.triangles, verts.len());
        // Outgoing edges per vertex (CSR): as many as its triangles.
        let mut start = vec![0u32; verts.len() + 1];
        for t in &order {
            for &a in t {
                start[a as usize + 1] += 1;
            }
        }
        for i in 0..verts.len() {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut out = vec![(0u32, 0u32); 3 * order.len()];
        for (ti, t) in order.iter().enumerate() {
            for k in 0..3 {
                let a = t[k] as usize;
                out[fill[a] as usize] = (t[(k + 1) % 3], ti as u32);
                fill[a] += 1;
            }
        }
        let across = |a: u32, b: u32| {
            let list = &out[start[b as usize] as usize..start[b as usize + 1] as usize];
            list.iter()
                .find(|&&(to, _)| to == a)
                .map_or(NONE, |&(_, u)| u)
        };
        let tris = order
            .iter()
            .enumerate()
            .map(|(ti, t)| {
                for &a in t {
                    verts[a as usize].t = ti as u32;
                }
                let n = [0, 1, 2].map(|k| across(t[k], t[(k + 1) % 3]));
                Tri { v: *t, n }
            })
            .collect();
        Topo {
            verts,
            tris,
            free: Vec::new(),
        }
    }

    /// The live triangles and vertices as a [`Mesh`] (vertices renumbered in
    /// the order of their ids).
    pub(crate) fn to_mesh(&self) -> Mesh {
        let mut id = vec![NONE; self.verts.len()];
        let mut vertices = Vec::new();
        for (i, v) in self.verts.iter().enumerate() {
            if v.t != NONE {
                id[i] = vertices.len() as u32;
                vertices.push(MeshVertex {
                    col: v.p[0] as u32,
                    row: v.p[1] as u32,
                    z_m: v.z,
                });
            }
        }
        let triangles = self
            .tris
            .iter()
            .filter(|t| t.v[0] != NONE)
            .map(|t| t.v.map(|v| id[v as usize]))
            .collect();
        Mesh {
            vertices,
            triangles,
        }
    }

    /// Whether vertex `v` is still in the triangulation.
    #[inline]
    pub(crate) fn alive(&self, v: u32) -> bool {
        self.verts[v as usize].t != NONE
    }

    /// Position of vertex `v`.
    #[inline]
    pub(crate) fn pos(&self, v: u32) -> [i32; 2] {
        self.verts[v as usize].p
    }

    /// Height of vertex `v`.
    #[inline]
    pub(crate) fn z(&self, v: u32) -> f32 {
        self.verts[v as usize].z
    }

    /// The corner of `t` holding vertex `v`.
    #[inline]
    pub(crate) fn corner(&self, t: u32, v: u32) -> usize {
        let tv = self.tris[t as usize].v;
        if tv[0] == v {
            0
        } else if tv[1] == v {
            1
        } else {
            2
        }
    }

    /// Allocates a triangle slot for corners `v` (no neighbours yet).
    pub(crate) fn alloc(&mut self, v: [u32; 3]) -> u32 {
        let t = Tri { v, n: [NONE; 3] };
        if let Some(s) = self.free.pop() {
            self.tris[s as usize] = t;
            s
        } else {
            self.tris.push(t);
            (self.tris.len() - 1) as u32
        }
    }

    /// Frees a triangle slot.
    pub(crate) fn release(&mut self, t: u32) {
        self.tris[t as usize] = Tri {
            v: [NONE; 3],
            n: [NONE; 3],
        };
        self.free.push(t);
    }

    /// Sets `t`'s neighbour across edge `k` to `u`, and `u`'s neighbour across
    /// the same edge (reversed) to `t`.
    pub(crate) fn set_nbr(&mut self, t: u32, k: usize, u: u32) {
        self.tris[t as usize].n[k] = u;
        if u != NONE {
            let tv = self.tris[t as usize].v;
            let (a, b) = (tv[k], tv[(k + 1) % 3]);
            let ut = &mut self.tris[u as usize];
            for j in 0..3 {
                if ut.v[j] == b && ut.v[(j + 1) % 3] == a {
                    ut.n[j] = t;
                    return;
                }
            }
            debug_assert!(false, "set_nbr: edge not found in the neighbour");
        }
    }

    /// Flips edge `k` of triangle `t` (shared with a neighbour): `(a, b, c)`
    /// and `(b, a, d)` become `(c, a, d)` and `(d, b, c)` in the same two
    /// slots. The caller checks that both are counter-clockwise.
    pub(crate) fn flip(&mut self, t: u32, k: usize) {
        let Tri { v: tv, n: tn } = self.tris[t as usize];
        let u = tn[k];
        let (a, b, c) = (tv[k], tv[(k + 1) % 3], tv[(k + 2) % 3]);
        let j = self.corner(u, b);
        let Tri { v: uv, n: un } = self.tris[u as usize];
        let d = uv[(j + 2) % 3];
        let (t_bc, t_ca) = (tn[(k + 1) % 3], tn[(k + 2) % 3]);
        let (u_ad, u_db) = (un[(j + 1) % 3], un[(j + 2) % 3]);
        self.tris[t as usize] = Tri {
            v: [c, a, d],
            n: [NONE, NONE, u],
        };
        self.tris[u as usize] = Tri {
            v: [d, b, c],
            n: [NONE, NONE, t],
        };
        self.set_nbr(t, 0, t_ca);
        self.set_nbr(t, 1, u_ad);
        self.set_nbr(u, 0, u_db);
        self.set_nbr(u, 1, t_bc);
        for (x, s) in [(a, t), (c, t), (d, u), (b, u)] {
            self.verts[x as usize].t = s;
        }
    }

    /// Adds a vertex at `p` with height `z` (not yet in any triangle) and
    /// returns its id.
    pub(crate) fn add_vertex(&mut self, p: [i32; 2], z: f32) -> u32 {
        self.verts.push(Vert { p, z, t: NONE });
        (self.verts.len() - 1) as u32
    }

    /// Splits triangle `t` at the new vertex `v` strictly inside it into
    /// three; the new triangles are pushed to `made`.
    pub(crate) fn split_inside(&mut self, t: u32, v: u32, made: &mut Vec<u32>) {
        let Tri {
            v: [a, b, c],
            n: [nab, nbc, nca],
        } = self.tris[t as usize];
        self.tris[t as usize] = Tri {
            v: [a, b, v],
            n: [NONE; 3],
        };
        let t1 = self.alloc([b, c, v]);
        let t2 = self.alloc([c, a, v]);
        self.tris[t as usize].n = [NONE, t1, t2];
        self.tris[t1 as usize].n = [NONE, t2, t];
        self.tris[t2 as usize].n = [NONE, t, t1];
        self.set_nbr(t, 0, nab);
        self.set_nbr(t1, 0, nbc);
        self.set_nbr(t2, 0, nca);
        for (x, s) in [(a, t), (b, t1), (c, t2), (v, t)] {
            self.verts[x as usize].t = s;
        }
        made.extend_from_slice(&[t, t1, t2]);
    }

    /// Splits edge `k` of triangle `t` at the new vertex `v` lying strictly
    /// between its ends; both triangles on the edge are split (one when the
    /// edge is on the border). The new triangles are pushed to `made`.
    pub(crate) fn split_edge(&mut self, t: u32, k: usize, v: u32, made: &mut Vec<u32>) {
        let Tri { v: tv, n: tn } = self.tris[t as usize];
        let (a, b, c) = (tv[k], tv[(k + 1) % 3], tv[(k + 2) % 3]);
        let (n_bc, n_ca, u) = (tn[(k + 1) % 3], tn[(k + 2) % 3], tn[k]);
        // (a, b, c) becomes t = (a, v, c) and t1 = (v, b, c).
        self.tris[t as usize] = Tri {
            v: [a, v, c],
            n: [NONE; 3],
        };
        let t1 = self.alloc([v, b, c]);
        self.tris[t as usize].n[1] = t1;
        self.tris[t1 as usize].n[2] = t;
        self.set_nbr(t, 2, n_ca);
        self.set_nbr(t1, 1, n_bc);
        for (x, s) in [(a, t), (c, t), (b, t1), (v, t)] {
            self.verts[x as usize].t = s;
        }
        made.extend_from_slice(&[t, t1]);
        if u == NONE {
            return;
        }
        // The neighbour (b, a, d) becomes u = (b, v, d) and u1 = (v, a, d).
        let j = self.corner(u, b);
        let Tri { v: uv, n: un } = self.tris[u as usize];
        let d = uv[(j + 2) % 3];
        let (u_ad, u_db) = (un[(j + 1) % 3], un[(j + 2) % 3]);
        self.tris[u as usize] = Tri {
            v: [b, v, d],
            n: [NONE; 3],
        };
        let u1 = self.alloc([v, a, d]);
        self.tris[u as usize].n[1] = u1;
        self.tris[u1 as usize].n[2] = u;
        self.set_nbr(u, 2, u_db);
        self.set_nbr(u1, 1, u_ad);
        self.set_nbr(u, 0, t1);
        self.set_nbr(u1, 0, t);
        self.verts[d as usize].t = u;
        made.extend_from_slice(&[u, u1]);
    }

    /// Replaces the star of `v` (triangles `star[i] = (v, link[i],
    /// link[i + 1])`, `closed` or open) by the triangles `new` over the link's
    /// vertices, which must tile the link polygon; `v` is removed. The new
    /// triangles' slots are pushed to `made`.
    pub(crate) fn replace_star(
        &mut self,
        v: u32,
        star: &[u32],
        link: &[u32],
        new: &[[u32; 3]],
        made: &mut Vec<u32>,
    ) {
        // Outer neighbours of the link edges.
        let outer: Vec<(u32, u32, u32)> = star
            .iter()
            .enumerate()
            .map(|(i, &t)| {
                let k = self.corner(t, v);
                (
                    link[i],
                    link[(i + 1) % link.len()],
                    self.tris[t as usize].n[(k + 1) % 3],
                )
            })
            .collect();
        for &t in star {
            self.release(t);
        }
        let first = made.len();
        for &t in new {
            let s = self.alloc(t);
            made.push(s);
        }
        for (i, &t) in new.iter().enumerate() {
            let s = made[first + i];
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if let Some(&(_, _, o)) = outer.iter().find(|&&(x, y, _)| x == a && y == b) {
                    self.set_nbr(s, k, o);
                    continue;
                }
                // Another new triangle on the reverse edge, or the border.
                let across = new
                    .iter()
                    .position(|u| (0..3).any(|m| u[m] == b && u[(m + 1) % 3] == a))
                    .map_or(NONE, |j| made[first + j]);
                self.tris[s as usize].n[k] = across;
            }
            for &c in &t {
                self.verts[c as usize].t = s;
            }
        }
        self.verts[v as usize].t = NONE;
    }

    /// Triangulates the simple polygon `poly` (vertex ids, counter-clockwise)
    /// by ear clipping into `out`: an ear is a strictly convex corner whose
    /// triangle holds no other polygon vertex, inside or on its edges.
    /// Returns false if the polygon has no ear left (not simple).
    pub(crate) fn ear_clip(&self, poly: &[u32], out: &mut Vec<[u32; 3]>) -> bool {
        out.clear();
        let mut p: Vec<u32> = poly.to_vec();
        while p.len() > 3 {
            let n = p.len();
            let ear = (0..n).find(|&i| {
                let (a, b, c) = (p[(i + n - 1) % n], p[i], p[(i + 1) % n]);
                let (pa, pb, pc) = (self.pos(a), self.pos(b), self.pos(c));
                orient(pa, pb, pc) > 0
                    && p.iter().all(|&q| {
                        if q == a || q == b || q == c {
                            return true;
                        }
                        let pq = self.pos(q);
                        !(orient(pa, pb, pq) >= 0
                            && orient(pb, pc, pq) >= 0
                            && orient(pc, pa, pq) >= 0)
                    })
            });
            let Some(i) = ear else {
                return false;
            };
            out.push([p[(i + n - 1) % n], p[i], p[(i + 1) % n]]);
            p.remove(i);
        }
        let ok = orient(self.pos(p[0]), self.pos(p[1]), self.pos(p[2])) > 0;
        out.push([p[0], p[1], p[2]]);
        ok
    }

    /// Checks the adjacency (tests only): every neighbour link is mutual,
    /// every live triangle is counter-clockwise, every vertex's triangle
    /// holds it.
    #[cfg(test)]
    pub(crate) fn validate(&self) {
        for (ti, t) in self.tris.iter().enumerate() {
            if t.v[0] == NONE {
                continue;
            }
            let p = t.v.map(|v| self.pos(v));
            assert!(orient(p[0], p[1], p[2]) > 0, "triangle {ti} not CCW");
            for k in 0..3 {
                let u = t.n[k];
                if u != NONE {
                    let (a, b) = (t.v[k], t.v[(k + 1) % 3]);
                    let ut = self.tris[u as usize];
                    let j = (0..3)
                        .find(|&j| ut.v[j] == b && ut.v[(j + 1) % 3] == a)
                        .expect("the neighbour shares the edge");
                    assert_eq!(ut.n[j], ti as u32, "neighbour link not mutual");
                }
            }
        }
        for (vi, v) in self.verts.iter().enumerate() {
            if v.t != NONE {
                assert!(self.tris[v.t as usize].v.contains(&(vi as u32)));
            }
        }
    }
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::grid::{GeoRef, HeightGrid};

    fn grid() -> HeightGrid {
        let (w, h) = (17, 13);
        let v = (0..w * h)
            .map(|i| ((i % w) as f32 * 0.4).sin() * 6.0 + (i / w) as f32 * 0.3)
            .collect();
        HeightGrid::new(w, h, v, GeoRef::unreferenced(1.0)).unwrap()
    }

    /// A valid triangulation that covers the grid (bound unchecked).
    fn tiles(g: &HeightGrid, t: &Topo) {
        t.validate();
        crate::check_mesh(
            g,
            &t.to_mesh(),
            &crate::CheckOptions::DEFAULT.with_general(true),
        )
        .unwrap();
    }

    #[test]
    fn local_edits_keep_a_valid_tiling() {
        let g = grid();
        let seed = crate::Bitree::build(&g)
            .unwrap()
            .extract(&crate::ExtractOptions::max_error_m(3.0))
            .unwrap()
            .mesh;
        let mut t = Topo::from_mesh(&seed);
        tiles(&g, &t);
        let mut made = Vec::new();
        // Split a triangle inside, at a sample strictly inside it.
        let inside = (0..t.tris.len() as u32).find_map(|ti| {
            let p = t.tris[ti as usize].v.map(|v| t.pos(v));
            let (x0, x1) = (p.iter().map(|q| q[0]).min()?, p.iter().map(|q| q[0]).max()?);
            let (y0, y1) = (p.iter().map(|q| q[1]).min()?, p.iter().map(|q| q[1]).max()?);
            (x0..=x1)
                .flat_map(|x| (y0..=y1).map(move |y| [x, y]))
                .find_map(|q| {
                    (orient(p[0], p[1], q) > 0
                        && orient(p[1], p[2], q) > 0
                        && orient(p[2], p[0], q) > 0)
                        .then_some((ti, q))
                })
        });
        let (ti, q) = inside.expect("a triangle with a sample inside");
        let v = t.add_vertex(q, g.get(q[0] as usize, q[1] as usize));
        t.split_inside(ti, v, &mut made);
        tiles(&g, &t);
        // Flip every flippable edge of the first triangles.
        let mut flips = 0;
        for ti in 0..8u32 {
            for k in 0..3 {
                let tr = t.tris[ti as usize];
                let u = tr.n[k];
                if u == NONE {
                    continue;
                }
                let (a, b, c) = (tr.v[k], tr.v[(k + 1) % 3], tr.v[(k + 2) % 3]);
                let d = t.tris[u as usize].v[(t.corner(u, b) + 2) % 3];
                let (pa, pb, pc, pd) = (t.pos(a), t.pos(b), t.pos(c), t.pos(d));
                if orient(pc, pa, pd) > 0 && orient(pd, pb, pc) > 0 {
                    t.flip(ti, k);
                    tiles(&g, &t);
                    flips += 1;
                }
            }
        }
        assert!(flips > 0);
        // Remove a vertex by ear clipping its link polygon.
        let v = (0..t.verts.len() as u32)
            .find(|&v| {
                let p = t.pos(v);
                t.alive(v) && p[0] > 0 && p[1] > 0 && p[0] < 16 && p[1] < 12
            })
            .unwrap();
        let mut l = super::super::decimate::Local::default();
        assert!(super::super::decimate::gather(&t, v, &mut l, [17, 13]));
        let mut new = Vec::new();
        assert!(t.ear_clip(&l.link, &mut new));
        t.replace_star(v, &l.tris, &l.link, &new, &mut made);
        tiles(&g, &t);
        assert!(!t.alive(v));
    }
}
