//! The order of a bitree mesh's triangles in the hierarchy: the Sierpinski
//! traversal of paper `001_49f2c365e8c41172.txt` (its sequence types A, B, C)
//! and paper `000_ebf7e3a88dffd361.txt` §4, recovered from the mesh alone
//! (steps 1 and 2 of [`super`]).

use crate::hierarchy::{orient_up, walk, Hierarchy, Placement, Pt, Tri, Visitor};
use crate::mesh::{Mesh, MeshVertex};

/// Why a mesh cannot be stripped from the hierarchy.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum StripError {
    /// A triangle is not a right isosceles triangle of the bitree.
    #[error("expected triangle {0} to be a bitree triangle (right isosceles, on the hierarchy)")]
    NotBitree(usize),
    /// Some triangles were not reached by the traversal (or appear twice).
    #[error("expected the triangles to tile the grid as bitree leaves; {missed} of {total} were not reached")]
    NotTiling {
        /// Triangles not visited.
        missed: usize,
        /// Triangles of the mesh.
        total: usize,
    },
    /// A vertex index out of range.
    #[error("expected vertex indices below {vertices}, found {index}")]
    BadIndex {
        /// The offending index.
        index: u32,
        /// Number of vertices.
        vertices: usize,
    },
}

/// The mesh's triangles (counter-clockwise, as in the mesh) in the Sierpinski
/// order of the hierarchy (step 2).
///
/// # Errors
/// As [`super::stripify_bitree`].
pub fn bitree_order(mesh: &Mesh) -> Result<Vec<[u32; 3]>, StripError> {
    Ok(bitree_order_ids(mesh)?
        .into_iter()
        .map(|k| mesh.triangles[k as usize])
        .collect())
}

/// The triangles of `mesh`, which is consumed, in [`bitree_order`]: moved
/// into that order in place, the vertices dropped first (the order needs
/// only the triangles' indices), so the peak is the mesh and the order's
/// indices, not a second copy of the triangles.
///
/// # Errors
/// As [`super::stripify_bitree`].
pub(crate) fn into_bitree_order(mesh: Mesh) -> Result<Vec<[u32; 3]>, StripError> {
    let mut ids = match order_by_keys(mesh.vertices.len(), &mesh.triangles, |i| {
        mesh.vertices.get(i as usize).map(|v| [v.col, v.row])
    }) {
        Some(ids) => ids,
        None => bitree_order_ids(&mesh)?,
    };
    let Mesh {
        vertices,
        mut triangles,
    } = mesh;
    drop(vertices);
    if !is_permutation(&ids) {
        // A triangle reached twice (and another not at all): as bitree_order.
        return Ok(ids.into_iter().map(|k| triangles[k as usize]).collect());
    }
    // Cycle by cycle: position i takes triangle ids[i]; a done entry of
    // `ids` is set to u32::MAX.
    for i in 0..ids.len() {
        if ids[i] == u32::MAX {
            continue;
        }
        let first = triangles[i];
        let mut j = i;
        loop {
            let k = ids[j] as usize;
            ids[j] = u32::MAX;
            if k == i {
                triangles[j] = first;
                break;
            }
            triangles[j] = triangles[k];
            j = k;
        }
    }
    Ok(triangles)
}

/// [`bitree_order_ids`] in less memory, for a mesh whose triangles are
/// bitree triangles that the traversal reaches once each (what every
/// extraction and refinement makes): each triangle's place in the
/// traversal is a key, the path of first/second choices from its root
/// (found by descending towards its centroid, entering each triangle as
/// the traversal does), left-aligned in 64 bits with its length in the low
/// 6; the indices sorted by key are the traversal's order exactly when no
/// triangle's key interval meets the next one's (no triangle twice, none
/// inside another). `None` for any other mesh (a bad index, a triangle not
/// of the hierarchy, two vertices on one sample, overlaps, a hierarchy too
/// deep for the key): [`bitree_order_ids`] then gives the answer or the
/// error. Holds 8 bytes per triangle for the keys and 4 for the order,
/// instead of the sample table, the 20-byte leaf records and their rows.
pub(crate) fn order_by_keys(
    vertex_count: usize,
    triangles: &[[u32; 3]],
    pos: impl Fn(u32) -> Option<Pt> + Sync,
) -> Option<Vec<u32>> {
    use rayon::prelude::*;
    if triangles.is_empty() || u32::try_from(triangles.len()).is_err() {
        return None;
    }
    let (mut w, mut h) = (2u32, 2u32);
    for i in 0..vertex_count as u32 {
        let p = pos(i)?;
        w = w.max(p[0].saturating_add(1));
        h = h.max(p[1].saturating_add(1));
    }
    // Two vertices on one sample: the sample table keeps one of them.
    let mut seen = vec![0u64; (w as usize * h as usize).div_ceil(64)];
    for i in 0..vertex_count as u32 {
        let p = pos(i)?;
        let k = p[1] as usize * w as usize + p[0] as usize;
        let (word, bit) = (k / 64, 1u64 << (k % 64));
        if seen[word] & bit != 0 {
            return None;
        }
        seen[word] |= bit;
    }
    drop(seen);
    let hier = Hierarchy::new(w, h);
    // 1 root bit and 2 per level of the padded square: at most 58 bits.
    if 1 + 2 * u64::from(hier.size().trailing_zeros()) > 58 {
        return None;
    }
    let keys: Vec<u64> = triangles
        .par_iter()
        .map(|t| {
            let p = [pos(t[0])?, pos(t[1])?, pos(t[2])?];
            traversal_key(&hier, p)
        })
        .collect::<Option<_>>()?;
    let mut ids: Vec<u32> = (0..triangles.len() as u32).collect();
    ids.par_sort_unstable_by_key(|&k| keys[k as usize]);
    let span = |k: u64| (k & !63, (k & !63) as u128 + (1u128 << (64 - (k & 63))));
    let disjoint = ids.windows(2).all(|pair| {
        let (_, end) = span(keys[pair[0] as usize]);
        let (start, _) = span(keys[pair[1] as usize]);
        end <= start as u128
    });
    disjoint.then_some(ids)
}

/// The traversal key of the bitree triangle with corners `p` (see
/// [`order_by_keys`]); `None` when it is not a triangle of `hier` that the
/// traversal can reach.
fn traversal_key(hier: &Hierarchy, p: [Pt; 3]) -> Option<u64> {
    let apex = right_angle(p)?;
    let (c, a, b) = (p[apex], p[(apex + 1) % 3], p[(apex + 2) % 3]);
    let leg2 = |t: &Tri| {
        let dx = t.c[0] as i64 - t.a[0] as i64;
        let dy = t.c[1] as i64 - t.a[1] as i64;
        dx * dx + dy * dy
    };
    let target = Tri { a, b, c };
    let size = leg2(&target);
    // Three times the centroid: strictly inside the triangle, so strictly
    // on one side of every split line of its ancestors.
    let g = [0, 1].map(|k| p.iter().map(|q| i128::from(q[k])).sum::<i128>());
    let side = |u: Pt, v: Pt, q: [i128; 2], scale: i128| {
        let (ux, uy) = (i128::from(u[0]) * scale, i128::from(u[1]) * scale);
        let (vx, vy) = (i128::from(v[0]) * scale, i128::from(v[1]) * scale);
        ((vx - ux) * (q[1] - uy) - (vy - uy) * (q[0] - ux)).signum()
    };
    let roots = hier.roots();
    // Root 0 (north-east of the `\` diagonal) is visited first.
    let second_root = g[1] > g[0];
    let mut t = roots[usize::from(second_root)];
    let mut enter = t.a;
    let mut key = u64::from(second_root);
    let mut bits = 1u32;
    loop {
        if t.c == c && ((t.a == a && t.b == b) || (t.a == b && t.b == a)) {
            break;
        }
        if t.is_unit() || hier.place(&t) == Placement::Outside || leg2(&t) <= size {
            return None;
        }
        let (near_a, near_b) = t.children();
        let m = t.mid();
        // near_a lies on t.a's side of the split line t.c–m.
        let in_a =
            side(t.c, m, g, 3) == side(t.c, m, [t.a[0], t.a[1]].map(|x| 3 * i128::from(x)), 3);
        let first_is_a = enter == t.a;
        let (next, second) = match (in_a, first_is_a) {
            (true, true) => ((near_a, t.a), false),
            (false, true) => ((near_b, t.c), true),
            (false, false) => ((near_b, t.b), false),
            (true, false) => ((near_a, t.c), true),
        };
        (t, enter) = next;
        key = (key << 1) | u64::from(second);
        bits += 1;
    }
    Some((key << (64 - bits)) | u64::from(bits))
}

/// True when `ids` holds each of `0..ids.len()` once.
fn is_permutation(ids: &[u32]) -> bool {
    let mut seen = vec![0u64; ids.len().div_ceil(64)];
    ids.iter().all(|&k| {
        let k = k as usize;
        let (word, bit) = (k / 64, 1u64 << (k % 64));
        let fresh = k < ids.len() && seen[word] & bit == 0;
        if fresh {
            seen[word] |= bit;
        }
        fresh
    })
}

/// [`bitree_order`] as indices into `mesh.triangles`.
///
/// # Errors
/// As [`super::stripify_bitree`].
pub(crate) fn bitree_order_ids(mesh: &Mesh) -> Result<Vec<u32>, StripError> {
    if mesh.triangles.is_empty() {
        return Ok(Vec::new());
    }
    let samples = Samples::new(mesh);
    let leaves = Leaves::new(mesh)?;
    let hier = samples.hier;
    let mut order = Vec::with_capacity(mesh.triangles.len());
    let roots = hier.roots();
    // Root 0 from (0,0) to (N,N), root 1 back from (N,N) to (0,0).
    let mut stack: Vec<(Tri, Pt)> = vec![(roots[1], roots[1].a), (roots[0], roots[0].a)];
    while let Some((t, enter)) = stack.pop() {
        if let Some(k) = samples.id_of(t.c).and_then(|c| leaves.find(c, &t)) {
            order.push(k);
            continue;
        }
        if t.is_unit() || hier.place(&t) == Placement::Outside {
            continue;
        }
        let (near_a, near_b) = t.children();
        let (first, second) = if enter == t.a {
            ((near_a, t.a), (near_b, t.c))
        } else {
            ((near_b, t.b), (near_a, t.c))
        };
        stack.push(second);
        stack.push(first);
    }
    if order.len() != mesh.triangles.len() {
        return Err(StripError::NotTiling {
            missed: mesh.triangles.len() - order.len().min(mesh.triangles.len()),
            total: mesh.triangles.len(),
        });
    }
    Ok(order)
}

/// The grid a mesh lies on, read from its vertices, and the vertex on each
/// sample: a dense table when the grid is not much larger than the mesh,
/// else a binary search over sorted sample keys (vertices are usually
/// numbered row-major already).
struct Samples {
    hier: Hierarchy,
    dense: Vec<u32>,
    by_key: Vec<(u64, u32)>,
}

impl Samples {
    fn new(mesh: &Mesh) -> Self {
        let (mut w, mut h) = (2u32, 2u32);
        for v in &mesh.vertices {
            w = w.max(v.col.saturating_add(1));
            h = h.max(v.row.saturating_add(1));
        }
        let hier = Hierarchy::new(w, h);
        let key = |v: &MeshVertex| v.row as u64 * w as u64 + v.col as u64;
        let samples = w as u64 * h as u64;
        let mut s = Samples {
            hier,
            dense: Vec::new(),
            by_key: Vec::new(),
        };
        if samples <= 16 * mesh.vertices.len() as u64 {
            s.dense = vec![u32::MAX; samples as usize];
            for (i, v) in mesh.vertices.iter().enumerate() {
                s.dense[key(v) as usize] = i as u32;
            }
        } else {
            s.by_key = mesh
                .vertices
                .iter()
                .enumerate()
                .map(|(i, v)| (key(v), i as u32))
                .collect();
            if !s.by_key.is_sorted() {
                s.by_key.sort_unstable();
            }
        }
        s
    }

    /// The vertex on sample `p`, if any.
    fn id_of(&self, p: Pt) -> Option<u32> {
        let (w, h) = (self.hier.width(), self.hier.height());
        if p[0] >= w || p[1] >= h {
            return None;
        }
        let key = p[1] as u64 * w as u64 + p[0] as u64;
        if !self.dense.is_empty() {
            return self
                .dense
                .get(key as usize)
                .copied()
                .filter(|&i| i != u32::MAX);
        }
        self.by_key
            .binary_search_by_key(&key, |&(k, _)| k)
            .ok()
            .map(|i| self.by_key[i].1)
    }
}

/// The mesh's triangles by their right-angle vertex (compressed rows), each
/// with its hypotenuse's ends.
struct Leaves {
    start: Vec<u32>,
    by_apex: Vec<(Pt, Pt, u32)>,
}

impl Leaves {
    /// # Errors
    /// [`StripError::BadIndex`] or [`StripError::NotBitree`] for the first
    /// triangle, in mesh order, with a bad index or not of the bitree.
    fn new(mesh: &Mesh) -> Result<Self, StripError> {
        let nv = mesh.vertices.len();
        let pos = |i: u32| -> Result<Pt, StripError> {
            mesh.vertices
                .get(i as usize)
                .map(|v| [v.col, v.row])
                .ok_or(StripError::BadIndex {
                    index: i,
                    vertices: nv,
                })
        };
        // Triangle k: its right-angle vertex and its hypotenuse's ends
        // (found twice, once to count and once to place, rather than kept).
        let apex_of = |k: usize, t: &[u32; 3]| -> Result<(u32, Pt, Pt), StripError> {
            let p = [pos(t[0])?, pos(t[1])?, pos(t[2])?];
            let apex = right_angle(p).ok_or(StripError::NotBitree(k))?;
            Ok((t[apex], p[(apex + 1) % 3], p[(apex + 2) % 3]))
        };
        let mut start = vec![0u32; nv + 1];
        for (k, t) in mesh.triangles.iter().enumerate() {
            start[apex_of(k, t)?.0 as usize + 1] += 1;
        }
        for i in 0..nv {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut by_apex: Vec<(Pt, Pt, u32)> = vec![([0, 0], [0, 0], 0); mesh.triangles.len()];
        for (k, t) in mesh.triangles.iter().enumerate() {
            let (c, a, b) = apex_of(k, t)?;
            by_apex[fill[c as usize] as usize] = (a, b, k as u32);
            fill[c as usize] += 1;
        }
        Ok(Leaves { start, by_apex })
    }

    /// The mesh triangle that is the hierarchy triangle `t`, whose apex is
    /// the vertex `c`.
    fn find(&self, c: u32, t: &Tri) -> Option<u32> {
        let c = c as usize;
        self.by_apex[self.start[c] as usize..self.start[c + 1] as usize]
            .iter()
            .find(|&&(a, b, _)| (a == t.a && b == t.b) || (a == t.b && b == t.a))
            .map(|&(_, _, k)| k)
    }
}

/// The index (0..3) of the right-angle vertex of a right isosceles triangle.
fn right_angle(p: [Pt; 3]) -> Option<usize> {
    let d2 = |u: Pt, v: Pt| {
        let dx = u[0] as i64 - v[0] as i64;
        let dy = u[1] as i64 - v[1] as i64;
        dx * dx + dy * dy
    };
    (0..3).find(|&k| {
        let (u, v) = (p[(k + 1) % 3], p[(k + 2) % 3]);
        let (l1, l2, hyp) = (d2(p[k], u), d2(p[k], v), d2(u, v));
        l1 > 0 && l1 == l2 && hyp == 2 * l1
    })
}

/// The full-resolution bitree mesh of a `width × height` grid (every unit
/// triangle inside it, heights 0): what extraction at `E = 0` gives on a
/// rough grid, for reporting the strip of the full grid. The second root's
/// triangles come first.
pub(crate) fn full_bitree_mesh(width: u32, height: u32) -> Mesh {
    let hier = Hierarchy::new(width.max(2), height.max(2));
    let (w, h) = (hier.width(), hier.height());
    let vertices = (0..h)
        .flat_map(|row| (0..w).map(move |col| MeshVertex { col, row, z_m: 0.0 }))
        .collect();
    let mut all = UnitLeaves {
        hier,
        triangles: Vec::new(),
    };
    let [r0, r1] = hier.roots();
    let Ok(()) = walk(&hier, &[r1, r0], (), &mut all);
    Mesh {
        vertices,
        triangles: all.triangles,
    }
}

/// Every inside triangle splits down to the unit ones, each kept
/// counter-clockwise in sample indices.
struct UnitLeaves {
    hier: Hierarchy,
    triangles: Vec<[u32; 3]>,
}

impl Visitor for UnitLeaves {
    type Down = ();
    type Error = std::convert::Infallible;

    fn straddling(&mut self, _t: &Tri, _down: ()) -> Result<(), Self::Error> {
        Ok(())
    }

    fn inside(&mut self, _t: &Tri, _down: ()) -> Result<Option<()>, Self::Error> {
        Ok(Some(()))
    }

    fn leaf(&mut self, t: &Tri, _down: ()) {
        let (a, b) = if orient_up(t.a, t.b, t.c) > 0 {
            (t.a, t.b)
        } else {
            (t.b, t.a)
        };
        self.triangles
            .push([a, b, t.c].map(|p| self.hier.index(p) as u32));
    }
}
