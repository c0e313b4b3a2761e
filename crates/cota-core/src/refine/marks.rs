//! Which points a bitree mesh needs, and which of them are *fictitious*: the
//! dependency closure of a set of selected points.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §2.2 ("puntos ficticios"). Every grid point
//! `p` other than the padded square's corners is the midpoint of the diagonal
//! (hypotenuse) shared by the two triangles `T1`, `T2` of its *diamond* (one only
//! on the square's border); its level follows from its position alone
//! (`level_of`). A triangle exists in the mesh iff its parent is split, and the
//! parent's split point is the triangle's right-angle apex. Hence:
//! 1. a **selected** point (chosen by the criterion, real height) splits both
//!    `T1` and `T2`, so it depends on both apexes `p1`, `p2`;
//! 2. a **fictitious** point (needed only to complete the hierarchy) splits only
//!    the triangle `Tk` one of whose children is needed, so it depends on one
//!    apex `pk`, which may itself be fictitious; its height is interpolated at
//!    the midpoint of its diagonal from the mesh heights of the diagonal's ends;
//! 3. "triangle `T` must be split" walks up the parents (`T`'s apex, then the
//!    apex of the parent, …) until it meets a triangle already split: the chain
//!    is linear and each triangle is marked at most once.
//!
//! The closure comes in three variants, one per [`Mode`]:
//! * **Conforming** ([`Mode::Conforming`]): every point made present is promoted to selected (real
//!   height, both sides split): the forced-split closure of ROAM/RTIN, no
//!   fictitious point, no T-junction.
//! * **Faithful** (the paper, `Mode::Fictitious { watertight: false }`):
//!   rules 1–3 only. Where only one side of a
//!   fictitious point's diagonal is split, the point hangs on the unsplit
//!   neighbour's edge, exactly on it in exact arithmetic (its height is the
//!   interpolation along that very edge; stored as `f32`, so within half an
//!   ulp), but it is a T-junction; paper 000's
//!   strips join such neighbours with one degenerate "line triangle" per hanging
//!   vertex ([`Marks::hanging_vertices`]).
//! * **Watertight** (`Mode::Fictitious { watertight: true }`): rules 1–3,
//!   and every present point also splits both its
//!   diamond triangles (recursively requiring their parents). Splitting a
//!   triangle through a point interpolated on its own hypotenuse leaves the
//!   surface unchanged, so the surface is the faithful one (a few more
//!   fictitious points, never transmitted) without T-junctions.
//!
//! State: one byte per sample (selected flag and one "split" bit per side of
//! the point's diamond). Triangles straddling the grid's border are always
//! split (see [`crate::hierarchy`]); their split points inside the grid are the
//! base selection ([`Marks::seed_border`]): they cannot be interpolated since a
//! diagonal end may lie outside the grid.

use super::mode::Mode;
use crate::hierarchy::{diamond, level_of, parent, walk, Hierarchy, Placement, Pt, Tri, Visitor};

/// The selected flag.
const SEL: u8 = 1;
/// Split bits for side 0 and side 1 of a diamond (see [`side_of`]).
const SIDES: [u8; 2] = [2, 4];
/// Either split bit.
const ANY_SIDE: u8 = 2 | 4;

/// Which side of its split point `m`'s diamond the triangle with apex `c` is
/// on: the two apexes are symmetric about `m`, so comparing (row, column)
/// tells them apart.
#[inline]
fn side_of(c: Pt, m: Pt) -> usize {
    usize::from((c[1], c[0]) >= (m[1], m[0]))
}

/// The walk of [`Marks::seed_border`]: selects the split point of every
/// straddling triangle that lies inside the grid, and stops at inside ones.
struct Border<'m>(&'m mut Marks);

impl Visitor for Border<'_> {
    type Down = ();
    type Error = std::convert::Infallible;

    fn straddling(&mut self, t: &Tri, _down: ()) -> Result<(), Self::Error> {
        let m = t.mid();
        if self.0.hier.contains(m) {
            self.0.select(m);
        }
        Ok(())
    }

    fn inside(&mut self, _t: &Tri, _down: ()) -> Result<Option<()>, Self::Error> {
        Ok(None)
    }
}

/// The closure state: which points are selected and which triangles split.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Marks {
    hier: Hierarchy,
    mode: Mode,
    flags: Vec<u8>,
    /// Points that became present and still need the closure's rule.
    pending: Vec<Pt>,
}

impl Marks {
    /// No point selected, nothing split, over a `hier`-shaped grid. Call
    /// [`Marks::seed_border`] before selecting when the grid is not
    /// `2^k + 1` square.
    pub fn new(hier: Hierarchy, mode: Mode) -> Self {
        let n = hier.width() as usize * hier.height() as usize;
        Marks {
            hier,
            mode,
            flags: vec![0; n],
            pending: Vec::new(),
        }
    }

    /// The hierarchy's shape.
    pub fn hierarchy(&self) -> &Hierarchy {
        &self.hier
    }

    /// The mode whose closure rule these marks follow.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// True when every point selected in `other` is selected here and every
    /// triangle split in `other` is split here (`other` is a coarser step of
    /// the same hierarchy).
    pub fn contains(&self, other: &Marks) -> bool {
        self.hier == other.hier
            && self
                .flags
                .iter()
                .zip(&other.flags)
                .all(|(&a, &b)| b & !a == 0)
    }

    /// Selects the split points of every triangle straddling the grid's
    /// border (those inside the grid): the coarsest mesh, always present.
    pub fn seed_border(&mut self) {
        let hier = self.hier;
        let Ok(()) = walk(&hier, &hier.roots(), (), &mut Border(self));
        self.close();
    }

    /// True when `p` is selected (a real height, transmitted).
    #[inline]
    pub fn is_selected(&self, p: Pt) -> bool {
        self.flags[self.hier.index(p)] & SEL != 0
    }

    /// True when `p` splits at least one triangle (it is a mesh vertex).
    #[inline]
    pub fn is_present(&self, p: Pt) -> bool {
        self.flags[self.hier.index(p)] & ANY_SIDE != 0
    }

    /// True when `p` is present and not selected.
    #[inline]
    pub fn is_fictitious(&self, p: Pt) -> bool {
        let f = self.flags[self.hier.index(p)];
        f & SEL == 0 && f & ANY_SIDE != 0
    }

    /// True when the inside triangle `t` (not a unit triangle) is split.
    #[inline]
    pub fn splits(&self, t: &Tri) -> bool {
        let m = t.mid();
        self.flags[self.hier.index(m)] & SIDES[side_of(t.c, m)] != 0
    }

    /// Selects `m` (real height): both triangles of its diamond must split.
    /// Returns false when it already was selected. Call [`Marks::close`] after
    /// a batch of selections.
    pub fn select(&mut self, m: Pt) -> bool {
        if !self.hier.contains(m) {
            return false;
        }
        let i = self.hier.index(m);
        if self.flags[i] & SEL != 0 {
            return false;
        }
        self.flags[i] |= SEL;
        self.split_both(m);
        true
    }

    /// Applies the closure's rule to every point made present since the last
    /// call, until nothing changes.
    pub fn close(&mut self) {
        while let Some(p) = self.pending.pop() {
            match self.mode {
                Mode::Conforming => {
                    self.select(p);
                }
                Mode::Fictitious { watertight: true } => self.split_both(p),
                Mode::Fictitious { watertight: false } => {}
            }
        }
    }

    /// Requires both (non-outside) triangles of `m`'s diamond to split.
    fn split_both(&mut self, m: Pt) {
        let n = self.hier.size();
        let Some(level) = level_of(m, n) else {
            return;
        };
        for t in diamond(level, m, n).into_iter().flatten() {
            if self.hier.place(&t) != Placement::Outside {
                self.require_split(t);
            }
        }
    }

    /// Requires `t` to exist and split: marks it, then its parent, … up to a
    /// triangle already split or a root. A triangle whose split point is off
    /// the grid straddles the border and is always split, as are its ancestors.
    fn require_split(&mut self, t: Tri) {
        let n = self.hier.size();
        let mut t = t;
        loop {
            let m = t.mid();
            if !self.hier.contains(m) {
                return;
            }
            let i = self.hier.index(m);
            let bit = SIDES[side_of(t.c, m)];
            if self.flags[i] & bit != 0 {
                return;
            }
            if self.flags[i] & ANY_SIDE == 0 {
                self.pending.push(m);
            }
            self.flags[i] |= bit;
            match parent(&t, n) {
                Some(p) => t = p,
                None => return,
            }
        }
    }

    /// Fictitious points that hang on an unsplit neighbour's edge (faithful
    /// closure only; 0 otherwise): one split side, the other side inside or
    /// straddling the grid but not split. Each needs one degenerate "line
    /// triangle" to close the T-junction (paper 000 §4).
    pub fn hanging_vertices(&self) -> usize {
        let n = self.hier.size();
        let w = self.hier.width();
        let mut count = 0;
        for (i, &f) in self.flags.iter().enumerate() {
            if f & SEL != 0 || f & ANY_SIDE == 0 || f & ANY_SIDE == ANY_SIDE {
                continue;
            }
            let m = [i as u32 % w, i as u32 / w];
            let Some(level) = level_of(m, n) else {
                continue;
            };
            let unsplit = diamond(level, m, n).into_iter().flatten().any(|t| {
                self.hier.place(&t) != Placement::Outside && f & SIDES[side_of(t.c, m)] == 0
            });
            if unsplit {
                count += 1;
            }
        }
        count
    }
}
