//! Judging one leaf of the refinement with its actual vertex heights (step 4
//! of [`super`]): the criterion sees the leaf's exact error, measured with
//! the mesh's own heights ([`crate::mesh::raster::max_deviation`]), and a
//! leaf it rejects selects its split point, or a fictitious vertex whose own
//! deviation is the cause (papers `001_49f2c365e8c41172.txt` and
//! `000_ebf7e3a88dffd361.txt` §2.2). A leaf accepted with the same heights is
//! not judged again ([`Accepted`]).

use super::leaves::Leaf;
use super::marks::Marks;
use crate::criteria::{Criterion, Element};
use crate::grid::HeightGrid;
use crate::hierarchy::{Hierarchy, Pt};
use crate::mesh::raster::max_deviation;

/// The leaves accepted in an earlier round whose vertex heights have not
/// changed since: one bit per hierarchy triangle, which is its apex and the
/// direction from there to its hypotenuse (every sample but the padded
/// square's corners is the split point of one diamond, so it is the apex of
/// at most four triangles, in four directions; the roots' apexes are those
/// corners). A leaf's acceptance depends only on its triangle and its
/// vertices' heights, so judging it again would accept it again: skipping
/// it only saves the time (one byte per sample, where a set of the leaves'
/// keys held tens).
pub(super) struct Accepted {
    bits: Vec<u8>,
}

impl Accepted {
    /// None accepted, for a hierarchy of `samples` samples.
    pub(super) fn new(samples: usize) -> Self {
        Accepted {
            bits: vec![0; samples],
        }
    }

    /// The byte and bit of leaf `l`.
    pub(super) fn slot(l: &Leaf, hier: &Hierarchy) -> (usize, u8) {
        let t = &l.tri;
        // Twice the vector from the apex to the hypotenuse's midpoint.
        let d = |k: usize| i64::from(t.a[k]) + i64::from(t.b[k]) - 2 * i64::from(t.c[k]);
        let dir = (d(0).signum() + 1) * 3 + (d(1).signum() + 1);
        // 0..=8 without 4 (the apex is never the midpoint).
        let dir = if dir > 4 { dir - 1 } else { dir };
        (hier.index(t.c), 1 << dir)
    }

    /// True when `l` was accepted and not since forgotten.
    pub(super) fn holds(&self, l: &Leaf, hier: &Hierarchy) -> bool {
        let (i, bit) = Accepted::slot(l, hier);
        self.bits[i] & bit != 0
    }

    /// Records `l` as accepted (`yes`) or forgets it.
    pub(super) fn set(&mut self, l: &Leaf, hier: &Hierarchy, yes: bool) {
        let (i, bit) = Accepted::slot(l, hier);
        if yes {
            self.bits[i] |= bit;
        } else {
            self.bits[i] &= !bit;
        }
    }
}

/// The points a rejected leaf selects, each packed as `col << 32 | row`
/// (`u64::MAX`: none): two thirds of [`Verdict::Select`]'s size.
pub(super) type Picks = [u64; 4];

/// The points of [`Picks`], in order.
pub(super) fn unpack(picks: Picks) -> impl Iterator<Item = Pt> {
    picks
        .into_iter()
        .filter(|&p| p != u64::MAX)
        .map(|p| [(p >> 32) as u32, p as u32])
}

pub(super) enum Verdict {
    Accept,
    /// Points to select: the leaf's split point and up to three vertices.
    Select([Option<Pt>; 4]),
}

impl Verdict {
    /// The points to select, `None` for [`Verdict::Accept`].
    pub(super) fn picks(self) -> Option<Picks> {
        match self {
            Verdict::Accept => None,
            Verdict::Select(points) => Some(
                points.map(|p| p.map_or(u64::MAX, |p| (u64::from(p[0]) << 32) | u64::from(p[1]))),
            ),
        }
    }
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

#[cfg(test)]
mod test {
    use super::*;
    use crate::hierarchy::{walk, Tri, Visitor};
    use std::collections::HashMap;

    /// Every triangle inside the grid, each split down to the unit ones.
    struct All(Vec<Tri>);

    impl Visitor for All {
        type Down = ();
        type Error = std::convert::Infallible;
        fn straddling(&mut self, _t: &Tri, _down: ()) -> Result<(), Self::Error> {
            Ok(())
        }
        fn inside(&mut self, t: &Tri, _down: ()) -> Result<Option<()>, Self::Error> {
            self.0.push(*t);
            Ok(Some(()))
        }
        fn leaf(&mut self, t: &Tri, _down: ()) {
            self.0.push(*t);
        }
    }

    /// The accepted-leaf slot (apex, direction) is one triangle's alone,
    /// on square, padded and odd-sized grids.
    #[test]
    fn each_triangle_has_its_own_slot() {
        for (w, h) in [(2, 2), (9, 9), (17, 12), (65, 33), (100, 37), (257, 256)] {
            let hier = Hierarchy::new(w, h);
            let mut all = All(Vec::new());
            let Ok(()) = walk(&hier, &hier.roots(), (), &mut all);
            let mut seen: HashMap<(usize, u8), Tri> = HashMap::new();
            for t in all.0 {
                let slot = Accepted::slot(&Leaf { tri: t, depth: 0 }, &hier);
                if let Some(other) = seen.insert(slot, t) {
                    assert_eq!(other, t, "{w}x{h}: two triangles in slot {slot:?}");
                }
            }
        }
    }
}
