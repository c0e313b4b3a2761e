//! The standard (non-swap) triangle strip: writing one from triangles in a
//! visit order, and reading one back (step 3 of [`super`]). Strip
//! vocabulary after Evans, Skiena & Varshney, "Optimizing triangle strips for
//! fast rendering" (1996), as papers `000_ebf7e3a88dffd361.txt` §4 and
//! `001_49f2c365e8c41172.txt` use it.

use crate::mesh::Mesh;

/// A single standard triangle strip (no primitive restart).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Strip {
    /// Vertex indices; triangle `k` is `(i[k], i[k+1], i[k+2])`, drawn
    /// reversed when `k` is odd.
    pub indices: Vec<u32>,
    /// Non-degenerate triangles (the mesh's triangles).
    pub triangles: usize,
    /// Degenerate triangles (connectors and swaps).
    pub degenerate: usize,
}

impl Strip {
    /// Total index references.
    pub fn refs(&self) -> usize {
        self.indices.len()
    }

    /// The strip of `indices`, its triangles counted.
    pub fn from_indices(indices: Vec<u32>) -> Strip {
        finish(indices)
    }

    /// Its non-degenerate triangles in drawing orientation
    /// ([`drawn_triangles`]).
    pub fn drawn_triangles(&self) -> Vec<[u32; 3]> {
        drawn_triangles(&self.indices)
    }

    /// `Ok` when its non-degenerate triangles, with their drawn orientation,
    /// are `mesh`'s triangles, each once ([`validate_indices`]).
    ///
    /// # Errors
    /// [`StripMismatch`] otherwise.
    pub fn validate(&self, mesh: &Mesh) -> Result<(), StripMismatch> {
        validate_indices(&self.indices, mesh)
    }

    /// References per non-degenerate triangle (0 for an empty strip).
    pub fn refs_per_triangle(&self) -> f64 {
        if self.triangles == 0 {
            0.0
        } else {
            self.indices.len() as f64 / self.triangles as f64
        }
    }
}

/// A strip whose triangles are not its mesh's.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("expected the strip's triangles to be the mesh's {mesh_triangles}, found {strip_triangles}, {foreign} of them not in the mesh")]
pub struct StripMismatch {
    /// Triangles of the mesh.
    pub mesh_triangles: usize,
    /// Non-degenerate triangles of the strip.
    pub strip_triangles: usize,
    /// Strip triangles (with orientation) not in the mesh.
    pub foreign: usize,
}

/// `Ok` when the non-degenerate triangles of the strip `indices`, with their
/// drawn orientation, are `mesh`'s triangles, each once: the check every
/// strip passes (the GLB writer's, the tests').
///
/// # Errors
/// [`StripMismatch`] otherwise.
pub fn validate_indices(indices: &[u32], mesh: &Mesh) -> Result<(), StripMismatch> {
    let mut got: Vec<[u32; 3]> = drawn_triangles(indices)
        .into_iter()
        .map(canonical)
        .collect();
    let mut want: Vec<[u32; 3]> = mesh.triangles.iter().copied().map(canonical).collect();
    got.sort_unstable();
    want.sort_unstable();
    if got == want {
        return Ok(());
    }
    let foreign = got
        .iter()
        .filter(|t| want.binary_search(t).is_err())
        .count();
    Err(StripMismatch {
        mesh_triangles: want.len(),
        strip_triangles: got.len(),
        foreign,
    })
}

/// Where a strip is written while it is made: its indices
/// ([`Vec<u32>`]), or only their count and the last few ([`Tail`]), which
/// is all the writing reads back.
pub(crate) trait StripSink {
    /// Indices written so far.
    fn len(&self) -> usize;
    /// The index `k` places before the end (0: the last); `len() > k`.
    fn back(&self, k: usize) -> u32;
    /// Appends an index.
    fn push(&mut self, v: u32);
    /// Removes the last index (`len() > 0`).
    fn pop(&mut self);
    /// The last index, if any.
    fn last(&self) -> Option<u32> {
        (self.len() > 0).then(|| self.back(0))
    }
}

impl StripSink for Vec<u32> {
    fn len(&self) -> usize {
        Vec::len(self)
    }
    fn back(&self, k: usize) -> u32 {
        self[Vec::len(self) - 1 - k]
    }
    fn push(&mut self, v: u32) {
        Vec::push(self, v);
    }
    fn pop(&mut self) {
        Vec::pop(self);
    }
}

/// A strip's length and its last [`Tail::KEPT`] indices: the strip as
/// [`continue_run`] and [`start_run`] read it, without its indices (for
/// counting references in a fixed amount of memory).
#[derive(Debug, Clone, Default)]
pub(crate) struct Tail {
    len: usize,
    /// The last indices, the newest at `(len − 1) % KEPT`.
    ring: [u32; Tail::KEPT],
}

impl Tail {
    /// Indices kept: the writing reads at most three back, after at most
    /// one pop.
    const KEPT: usize = 8;
}

impl StripSink for Tail {
    fn len(&self) -> usize {
        self.len
    }
    fn back(&self, k: usize) -> u32 {
        debug_assert!(k < Tail::KEPT && k < self.len);
        self.ring[(self.len - 1 - k) % Tail::KEPT]
    }
    fn push(&mut self, v: u32) {
        self.ring[self.len % Tail::KEPT] = v;
        self.len += 1;
    }
    fn pop(&mut self) {
        self.len -= 1;
    }
}

/// Writes triangles, given in visit order and counter-clockwise, as one
/// standard strip (step 3 of the module docs). Works for any order; the
/// fewer consecutive triangles share an edge, the more connectors it needs.
pub(crate) fn strip_from_order(order: &[[u32; 3]]) -> Strip {
    let mut s: Vec<u32> = Vec::with_capacity(order.len() * 3 / 2 + 8);
    write_in_order(order, &mut s);
    finish(s)
}

/// [`strip_from_order`]'s references, counted without the strip.
pub(crate) fn refs_in_order(order: &[[u32; 3]]) -> usize {
    let mut s = Tail::default();
    write_in_order(order, &mut s);
    s.len()
}

/// Writes `order` into `s` as [`strip_from_order`] does.
fn write_in_order(order: &[[u32; 3]], s: &mut impl StripSink) {
    for (k, &t) in order.iter().enumerate() {
        let next = order.get(k + 1).copied();
        if s.len() >= 3 && continue_run(s, t) {
            continue;
        }
        start_run(s, t, next);
    }
}

/// Builds the [`Strip`] counts from its indices.
pub(crate) fn finish(indices: Vec<u32>) -> Strip {
    let mut triangles = 0;
    let mut degenerate = 0;
    for w in indices.windows(3) {
        if w[0] == w[1] || w[1] == w[2] || w[0] == w[2] {
            degenerate += 1;
        } else {
            triangles += 1;
        }
    }
    Strip {
        indices,
        triangles,
        degenerate,
    }
}

/// True when `(x, y, z)` is a rotation of `t` (same orientation).
fn same_turn(t: [u32; 3], x: u32, y: u32, z: u32) -> bool {
    (0..3).any(|r| t[r] == x && t[(r + 1) % 3] == y && t[(r + 2) % 3] == z)
}

/// The orientation the window ending at the strip's last index is drawn with
/// (`(x, y, z)` reordered by parity), for the indices `x y z` at its end.
fn drawn(len: usize, x: u32, y: u32, z: u32) -> (u32, u32, u32) {
    // The window starts at len - 3.
    if (len - 3).is_multiple_of(2) {
        (x, y, z)
    } else {
        (y, x, z)
    }
}

/// Appends `t` as a natural continuation or a swap; false (and `s` unchanged)
/// when neither keeps the orientation.
pub(crate) fn continue_run(s: &mut impl StripSink, t: [u32; 3]) -> bool {
    let n = s.len();
    let (o, p, q) = (s.back(2), s.back(1), s.back(0));
    let has = |v: u32| t.contains(&v);
    let third = |u: u32, v: u32| t.iter().copied().find(|&x| x != u && x != v);
    if p != q && has(p) && has(q) {
        if let Some(r) = third(p, q) {
            let (x, y, z) = drawn(n + 1, p, q, r);
            if same_turn(t, x, y, z) {
                s.push(r);
                return true;
            }
        }
    }
    if o != q && o != p && has(o) && has(q) {
        if let Some(r) = third(o, q) {
            // ... o p q  ->  ... o p o q r
            let (x, y, z) = drawn(n + 2, o, q, r);
            if same_turn(t, x, y, z) {
                s.pop();
                s.push(o);
                s.push(q);
                s.push(r);
                return true;
            }
        }
    }
    false
}

/// Starts a new run with `t`: connectors, then `t` rotated so that its last
/// two vertices are the edge it shares with `next` (when it shares one) and
/// ordered to be drawn counter-clockwise at the current parity.
pub(crate) fn start_run(s: &mut impl StripSink, t: [u32; 3], next: Option<[u32; 3]>) {
    // The vertex not on the edge shared with `next`.
    let lead = next
        .and_then(|nx| {
            let shared: Vec<u32> = t.iter().copied().filter(|v| nx.contains(v)).collect();
            if shared.len() == 2 {
                t.iter().position(|v| !shared.contains(v))
            } else {
                None
            }
        })
        .or_else(|| s.last().and_then(|q| t.iter().position(|&v| v == q)))
        .unwrap_or(0);
    let u = t[lead];
    let (a, b) = (t[(lead + 1) % 3], t[(lead + 2) % 3]);
    if let Some(q) = s.last() {
        if q != u {
            s.push(q);
            s.push(u);
        }
    }
    s.push(u);
    // (u, a, b) is counter-clockwise; at an odd window (u, b, a) is drawn
    // as (b, u, a), a rotation of it.
    if (s.len() - 1).is_multiple_of(2) {
        s.push(a);
        s.push(b);
    } else {
        s.push(b);
        s.push(a);
    }
}

/// The non-degenerate triangles of a standard strip, in drawing orientation
/// (odd windows reversed), degenerate ones dropped: the validator's view.
pub fn drawn_triangles(indices: &[u32]) -> Vec<[u32; 3]> {
    indices
        .windows(3)
        .enumerate()
        .filter(|(_, w)| w[0] != w[1] && w[1] != w[2] && w[0] != w[2])
        .map(|(k, w)| {
            if k % 2 == 0 {
                [w[0], w[1], w[2]]
            } else {
                [w[1], w[0], w[2]]
            }
        })
        .collect()
}

/// A triangle rotated to start at its smallest index (orientation kept), for
/// comparing triangle multisets.
pub(crate) fn canonical(t: [u32; 3]) -> [u32; 3] {
    let r = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
    [t[r], t[(r + 1) % 3], t[(r + 2) % 3]]
}

#[cfg(test)]
mod test {
    #![allow(clippy::unwrap_used, reason = "tests")]
    use super::*;

    #[test]
    fn validator_fixes_parity() {
        // 0 1 2 3: triangles (0,1,2) and (2,1,3).
        assert_eq!(drawn_triangles(&[0, 1, 2, 3]), vec![[0, 1, 2], [2, 1, 3]]);
        assert_eq!(drawn_triangles(&[0, 1, 1, 2]), Vec::<[u32; 3]>::new());
    }
}
