//! Judging one leaf of the refinement with its actual vertex heights (step 4
//! of [`super`]): the criterion sees the leaf's exact error, measured with
//! the mesh's own heights ([`crate::mesh::raster::max_deviation`]), and a
//! leaf it rejects selects its split point, or a fictitious vertex whose own
//! deviation is the cause (papers `001_49f2c365e8c41172.txt` and
//! `000_ebf7e3a88dffd361.txt` §2.2). A leaf accepted with the same heights is
//! not judged again ([`LeafKey`]).

use super::leaves::Leaf;
use super::marks::Marks;
use crate::criteria::{Criterion, Element};
use crate::grid::HeightGrid;
use crate::hierarchy::{Hierarchy, Pt};
use crate::mesh::raster::max_deviation;

/// A leaf and its vertex heights: its verdict cannot change while this holds.
pub(super) type LeafKey = (u64, u64, u64);

/// A multiply–rotate hasher for [`LeafKey`]s (well-mixed integer keys; no
/// denial-of-service concern here).
#[derive(Default, Clone, Copy)]
pub(super) struct FastHash;

impl std::hash::BuildHasher for FastHash {
    type Hasher = FastHasher;
    fn build_hasher(&self) -> FastHasher {
        FastHasher(0)
    }
}

pub(super) struct FastHasher(u64);

impl std::hash::Hasher for FastHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

pub(super) fn key(l: &Leaf, z: &[f32], hier: &Hierarchy) -> LeafKey {
    let k = |p: Pt| ((hier.index(p) as u64) << 32) | z[hier.index(p)].to_bits() as u64;
    (k(l.tri.a), k(l.tri.b), k(l.tri.c))
}

pub(super) enum Verdict {
    Accept,
    /// Points to select: the leaf's split point and up to three vertices.
    Select([Option<Pt>; 4]),
}

/// Asks the criterion about one leaf with its actual heights (rule 4).
pub(super) fn judge(
    grid: &HeightGrid,
    marks: &Marks,
    z: &[f32],
    l: &Leaf,
    criterion: &dyn Criterion,
) -> Verdict {
    let hier = marks.hierarchy();
    let t = l.tri;
    let p = [t.a, t.b, t.c];
    let zs = p.map(|q| z[hier.index(q)] as f64);
    let corners = [0, 1, 2].map(|k| [p[k][0] as f64, p[k][1] as f64, zs[k]]);
    let e = Element {
        corners: &corners,
        depth: l.depth,
        vertical_error_m: max_deviation(grid, p, zs),
        grid,
    };
    if !criterion.wants_split(&e) {
        return Verdict::Accept;
    }
    let mut out = [None; 4];
    if !t.is_unit() {
        out[0] = Some(t.mid());
    }
    let zero = Element {
        vertical_error_m: 0.0,
        ..e
    };
    let zero_wants = criterion.wants_split(&zero);
    for k in 0..3 {
        if !marks.is_fictitious(p[k]) || zero_wants {
            continue;
        }
        let dev = (zs[k] - grid.heights()[hier.index(p[k])] as f64).abs();
        let own = Element {
            vertical_error_m: dev,
            ..e
        };
        if dev > 0.0 && criterion.wants_split(&own) {
            out[k + 1] = Some(p[k]);
        }
    }
    Verdict::Select(out)
}
