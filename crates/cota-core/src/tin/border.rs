//! Locked borders: the grid's border meshed from the border samples alone,
//! so that adjacent tiles share their border vertices exactly.
//!
//! Each side of the rectangle is a profile of samples. It is simplified on
//! its own by the Douglas–Peucker recursion (Douglas & Peucker 1973,
//! "Algorithms for the reduction of the number of points required to
//! represent a digitized line or its caricature") with the *vertical* error:
//! a segment between two kept samples is split at its sample farthest from
//! the chord (the first one along the side, in increasing column or row,
//! among equals) while that distance exceeds the bound `E`. The kept samples
//! depend only on the side's heights and on `E`, so two tiles that share a
//! side (the same row or column of samples) and are meshed with the same
//! bound keep the same vertices there, and every border sample is within `E`
//! of its border edge.
//!
//! The seed (the bitree mesh at `E`, whose border vertices depend on the
//! triangles inside) is then re-bordered: the kept samples it lacks are
//! inserted by splitting their border edge, its other border vertices are
//! removed (their star re-triangulated by a fan from a border neighbour, or by
//! ear clipping when neither fan is valid), and the triangles this touched
//! are repaired by greedy insertion (Garland & Heckbert 1995, "Fast polygonal
//! approximation of terrains and height fields"): a triangle whose largest
//! error inside the grid exceeds `E` gets a vertex at that sample, until
//! none does. Border samples never need one, so the border stays as
//! simplified. Decimation then keeps every border vertex.

use super::decimate::{fan_valid, gather, Local};
use super::exact;
use super::span::Heights;
use super::topo::{orient, Topo, NONE};
use crate::grid::HeightGrid;
use crate::mesh::Mesh;

/// The samples (of `len`, heights `h(i)` in order along the side) the
/// vertical Douglas–Peucker simplification at `e` keeps; the two ends are
/// always kept. Errors within `margin` of `e` are decided exactly.
pub(crate) fn simplify_side(
    len: usize,
    h: impl Fn(usize) -> f32,
    e: f64,
    margin: f64,
) -> Vec<bool> {
    let mut keep = vec![false; len];
    keep[0] = true;
    keep[len - 1] = true;
    let mut stack = vec![(0usize, len - 1)];
    while let Some((a, b)) = stack.pop() {
        if b - a < 2 {
            continue;
        }
        let (ha, hb) = (h(a), h(b));
        let slope = (hb as f64 - ha as f64) / (b - a) as f64;
        let mut worst = (0f64, a);
        for i in a + 1..b {
            let d = (ha as f64 + slope * (i - a) as f64 - h(i) as f64).abs();
            if d > worst.0 {
                worst = (d, i);
            }
        }
        // Split at the farthest sample when it is beyond `e`. Near the
        // bound, every sample in the margin is decided exactly (a tie at `e`
        // is within), and the split goes to the farthest beyond.
        let split = if worst.0 <= e - margin {
            None
        } else if worst.0 > e + margin {
            Some(worst.1)
        } else {
            let chord = |i: usize| (ha as f64 + slope * (i - a) as f64 - h(i) as f64).abs();
            let len = (b - a) as i64;
            (a + 1..b)
                .filter(|&i| {
                    chord(i) > e - margin
                        && !exact::chord_within(len, (i - a) as i64, ha, hb, h(i), e)
                })
                .max_by(|&i, &j| chord(i).total_cmp(&chord(j)).then(j.cmp(&i)))
        };
        if let Some(at) = split {
            keep[at] = true;
            stack.push((a, at));
            stack.push((at, b));
        }
    }
    keep
}

/// The kept border samples of the four sides.
pub(crate) struct Border {
    w: i32,
    h: i32,
    /// Rows 0 and `h − 1`, by column.
    top: Vec<bool>,
    bottom: Vec<bool>,
    /// Columns 0 and `w − 1`, by row.
    left: Vec<bool>,
    right: Vec<bool>,
}

impl Border {
    /// The border of `grid` simplified at `e` metres.
    pub(crate) fn new(grid: &HeightGrid, e: f64) -> Border {
        let (w, h) = (grid.width(), grid.height());
        let z = |x: usize, y: usize| grid.heights()[y * w + x];
        let m = Heights::of(grid).margin;
        Border {
            w: w as i32,
            h: h as i32,
            top: simplify_side(w, |x| z(x, 0), e, m),
            bottom: simplify_side(w, |x| z(x, h - 1), e, m),
            left: simplify_side(h, |y| z(0, y), e, m),
            right: simplify_side(h, |y| z(w - 1, y), e, m),
        }
    }

    /// Whether `p` is on the grid's border.
    pub(crate) fn on_border(&self, p: [i32; 2]) -> bool {
        p[0] == 0 || p[1] == 0 || p[0] == self.w - 1 || p[1] == self.h - 1
    }

    /// Whether border sample `p` is kept.
    pub(crate) fn kept(&self, p: [i32; 2]) -> bool {
        (p[1] == 0 && self.top[p[0] as usize])
            || (p[1] == self.h - 1 && self.bottom[p[0] as usize])
            || (p[0] == 0 && self.left[p[1] as usize])
            || (p[0] == self.w - 1 && self.right[p[1] as usize])
    }

    /// Every kept sample, side by side (corners repeated).
    fn points(&self) -> Vec<[i32; 2]> {
        let mut out = Vec::new();
        let side = |keep: &[bool], at: &dyn Fn(i32) -> [i32; 2], out: &mut Vec<[i32; 2]>| {
            for (i, &k) in keep.iter().enumerate() {
                if k {
                    out.push(at(i as i32));
                }
            }
        };
        side(&self.top, &|x| [x, 0], &mut out);
        side(&self.bottom, &|x| [x, self.h - 1], &mut out);
        side(&self.left, &|y| [0, y], &mut out);
        side(&self.right, &|y| [self.w - 1, y], &mut out);
        out
    }
}

/// The side of the grid's border an edge `a`–`b` lies along, with its lower
/// coordinate along that side: (side, coordinate).
fn side_key(a: [i32; 2], b: [i32; 2], size: [i32; 2]) -> Option<(u8, i32)> {
    if a[1] == b[1] && (a[1] == 0 || a[1] == size[1] - 1) {
        Some((u8::from(a[1] != 0), a[0].min(b[0])))
    } else if a[0] == b[0] && (a[0] == 0 || a[0] == size[0] - 1) {
        Some((2 + u8::from(a[0] != 0), a[1].min(b[1])))
    } else {
        None
    }
}

/// The side of border sample `p` (not a corner) and its coordinate along it.
fn side_of(p: [i32; 2], size: [i32; 2]) -> (u8, i32) {
    if p[1] == 0 || p[1] == size[1] - 1 {
        (u8::from(p[1] != 0), p[0])
    } else {
        (2 + u8::from(p[0] != 0), p[1])
    }
}

/// Records the border edges of triangle `t` in `edges`, by (side, lower
/// coordinate).
fn note_border_edges(
    topo: &Topo,
    t: u32,
    size: [i32; 2],
    edges: &mut std::collections::BTreeMap<(u8, i32), (u32, usize)>,
) {
    let tr = &topo.tris[t as usize];
    for k in 0..3 {
        if tr.n[k] == NONE {
            let (a, b) = (topo.pos(tr.v[k]), topo.pos(tr.v[(k + 1) % 3]));
            if let Some(key) = side_key(a, b, size) {
                edges.insert(key, (t, k));
            }
        }
    }
}

/// Inserts every kept border sample `topo` lacks, splitting the border edge
/// that holds it; the new triangles go to `touched`.
fn insert_kept(topo: &mut Topo, grid: &HeightGrid, border: &Border, touched: &mut Vec<u32>) {
    let size = [grid.width() as i32, grid.height() as i32];
    // The border edges by (side, lower coordinate). A split rewrites its
    // triangles' slots, so their border edges are noted again after it (a
    // corner triangle has two).
    let mut edges = std::collections::BTreeMap::new();
    for t in 0..topo.tris.len() as u32 {
        if topo.tris[t as usize].v[0] != NONE {
            note_border_edges(topo, t, size, &mut edges);
        }
    }
    let have: std::collections::HashSet<[i32; 2]> = topo.verts.iter().map(|v| v.p).collect();
    let mut made = Vec::new();
    for p in border.points() {
        if have.contains(&p) {
            continue;
        }
        let (side, x) = side_of(p, size);
        let Some((&key, &(t, k))) = edges.range(..=(side, x)).next_back() else {
            continue;
        };
        if key.0 != side {
            continue;
        }
        let z = grid.heights()[p[1] as usize * grid.width() + p[0] as usize];
        let v = topo.add_vertex(p, z);
        made.clear();
        topo.split_edge(t, k, v, &mut made);
        for &m in &made {
            note_border_edges(topo, m, size, &mut edges);
        }
        touched.extend_from_slice(&made);
    }
}

/// Re-borders `seed` (within `e` of `grid`) so that its border vertices are
/// exactly `border`'s kept samples, and repairs it back within `e`.
pub(crate) fn reborder(seed: &Mesh, grid: &HeightGrid, border: &Border, e: f64) -> Mesh {
    let mut topo = Topo::from_mesh(seed);
    let hs = Heights::of(grid);
    let size = [grid.width() as i32, grid.height() as i32];
    let mut touched = Vec::new();
    // 1. Insert the kept samples the seed lacks.
    insert_kept(&mut topo, grid, border, &mut touched);
    // 2. Remove the other border vertices (never a corner: always kept).
    let mut l = Local::default();
    let mut tris = Vec::new();
    for v in 0..topo.verts.len() as u32 {
        let p = topo.pos(v);
        if !topo.alive(v) || !border.on_border(p) || border.kept(p) {
            continue;
        }
        if !gather(&topo, v, &mut l, size) {
            continue;
        }
        let d = l.link.len();
        if let Some(j) = [0, d - 1].into_iter().find(|&j| fan_valid(&l, j)) {
            // The fan from a border neighbour.
            let first = if j == 0 { 1 } else { 0 };
            tris.clear();
            tris.extend((first..first + d - 2).map(|i| [l.link[j], l.link[i], l.link[i + 1]]));
        } else if !topo.ear_clip(&l.link, &mut tris) {
            continue;
        }
        topo.replace_star(v, &l.tris, &l.link, &tris, &mut touched);
    }
    // 3. Repair by greedy insertion.
    repair(&mut topo, &hs, border, e, touched, true);
    topo.to_mesh()
}

/// Inserts, into each triangle of `work` (and the triangles this makes) whose
/// largest error at a sample off the grid's border exceeds `e`, a vertex at
/// that sample.
pub(crate) fn repair(
    topo: &mut Topo,
    hs: &Heights,
    border: &Border,
    e: f64,
    mut work: Vec<u32>,
    skip_border: bool,
) {
    let mut made = Vec::new();
    while let Some(t) = work.pop() {
        let tr = topo.tris[t as usize];
        if tr.v[0] == NONE {
            continue;
        }
        let p = tr.v.map(|v| topo.pos(v));
        let z = tr.v.map(|v| topo.z(v));
        let count = |s: [i32; 2]| !skip_border || !border.on_border(s);
        if hs.fits_where(p, z, e, count) {
            continue;
        }
        let (_, q) = hs.tri_error_at(p, z, count);
        if p.contains(&q) {
            // A degenerate triangle (never made here): nothing to insert.
            debug_assert!(false, "repair: degenerate triangle {p:?}");
            continue;
        }
        let nv = topo.add_vertex(q, hs.h[q[1] as usize * hs.w + q[0] as usize]);
        made.clear();
        match (0..3).find(|&k| orient(p[k], p[(k + 1) % 3], q) == 0) {
            Some(k) => topo.split_edge(t, k, nv, &mut made),
            None => topo.split_inside(t, nv, &mut made),
        }
        work.extend_from_slice(&made);
    }
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::grid::GeoRef;

    #[test]
    fn repair_brings_a_coarse_mesh_within_the_bound() {
        let (w, h) = (40, 30);
        let v: Vec<f32> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32, (i / w) as f32);
                30.0 * (x * 0.3).sin() * (y * 0.2).cos() + ((i * 7919) % 13) as f32
            })
            .collect();
        let g = HeightGrid::new(w, h, v, GeoRef::unreferenced(1.0)).unwrap();
        let tree = crate::Bitree::build(&g).unwrap();
        let seed = tree
            .extract(&crate::ExtractOptions::max_error_m(8.0))
            .unwrap()
            .mesh;
        let mut topo = Topo::from_mesh(&seed);
        let hs = Heights::of(&g);
        let all: Vec<u32> = (0..topo.tris.len() as u32).collect();
        let b = Border::new(&g, 1.0);
        repair(&mut topo, &hs, &b, 4.0, all, false);
        topo.validate();
        let m = topo.to_mesh();
        crate::check_mesh(&g, &m, &crate::CheckOptions::tin(4.0)).unwrap();
    }
}
