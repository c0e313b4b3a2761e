//! The clipped top-down walk of the bitree: the one traversal that the
//! criterion-driven refinement, the progressive streams and their decoder
//! share.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §2 (a triangle exists iff its parent is
//! split) with the clipping of [`super`]: from the roots, depth first, the
//! first child ([`Tri::children`]) before the second,
//! 1. a triangle **outside** the grid is skipped with everything under it;
//! 2. a **straddling** triangle is always split (the visitor is told, e.g. to
//!    give its split point a height when it lies inside the grid);
//! 3. an **inside** triangle that is not a unit triangle is split when the
//!    visitor says so; its descendants are inside too, so they are not
//!    placed again;
//! 4. an inside triangle kept whole, or an inside unit triangle, is a
//!    **leaf** of the mesh; straddling unit triangles cannot occur (a unit
//!    cell meeting the grid's interior lies inside it).
//!
//! A split triangle hands its children a value of the visitor's choosing
//! (its depth, whether it was split before), and a visitor may stop the walk
//! with an error (a corrupted stream). The walk is iterative, with an
//! explicit stack of at most two entries per level.

use super::padded::{Hierarchy, Placement};
use super::tri::Tri;

/// What the walk asks about the triangles it meets (see the module docs).
pub(crate) trait Visitor {
    /// What a split triangle hands its children.
    type Down: Copy;
    /// What stops the walk.
    type Error;

    /// A straddling triangle, always split; returns what its children get.
    ///
    /// # Errors
    /// Whatever stops the walk.
    fn straddling(&mut self, t: &Tri, down: Self::Down) -> Result<Self::Down, Self::Error>;

    /// An inside triangle that is not a unit triangle: `Some` (what its
    /// children get) to split it, `None` to keep it as a leaf.
    ///
    /// # Errors
    /// Whatever stops the walk.
    fn inside(&mut self, t: &Tri, down: Self::Down) -> Result<Option<Self::Down>, Self::Error>;

    /// A leaf: an inside triangle kept whole, or an inside unit triangle.
    fn leaf(&mut self, _t: &Tri, _down: Self::Down) {}
}

/// Walks the trees under `roots` (the hierarchy's roots, or some of them, in
/// the order given), each root getting `down`.
///
/// # Errors
/// The first error of the visitor; the walk stops there.
pub(crate) fn walk<V: Visitor>(
    hier: &Hierarchy,
    roots: &[Tri],
    down: V::Down,
    v: &mut V,
) -> Result<(), V::Error> {
    let mut stack: Vec<(Tri, bool, V::Down)> =
        roots.iter().rev().map(|&r| (r, false, down)).collect();
    while let Some((t, inside, down)) = stack.pop() {
        let inside = inside
            || match hier.place(&t) {
                Placement::Outside => continue,
                Placement::Straddling => false,
                Placement::Inside => true,
            };
        let next = if t.is_unit() {
            if inside {
                v.leaf(&t, down);
            }
            continue;
        } else if inside {
            match v.inside(&t, down)? {
                Some(next) => next,
                None => {
                    v.leaf(&t, down);
                    continue;
                }
            }
        } else {
            v.straddling(&t, down)?
        };
        let (c0, c1) = t.children();
        stack.push((c1, inside, next));
        stack.push((c0, inside, next));
    }
    Ok(())
}

/// Collects the walk's leaves: the largest triangles inside the grid when
/// nothing inside splits.
struct InsideRoots(Vec<Tri>);

impl Visitor for InsideRoots {
    type Down = ();
    type Error = std::convert::Infallible;

    fn straddling(&mut self, _t: &Tri, _down: ()) -> Result<(), Self::Error> {
        Ok(())
    }

    fn inside(&mut self, _t: &Tri, _down: ()) -> Result<Option<()>, Self::Error> {
        Ok(None)
    }

    fn leaf(&mut self, t: &Tri, _down: ()) {
        self.0.push(*t);
    }
}

impl Hierarchy {
    /// The largest triangles of the hierarchy inside the grid, in depth-first
    /// order: the roots, split while they straddle the grid's border. A
    /// [`crate::Bitree`] computes them once; every extraction starts from them.
    pub(crate) fn inside_roots(&self) -> Vec<Tri> {
        let mut v = InsideRoots(Vec::new());
        let Ok(()) = walk(self, &self.roots(), (), &mut v);
        v.0
    }
}

#[cfg(test)]
mod test {
    use super::*;

    /// Counts every kind of triangle the walk meets on a grid that straddles.
    struct Census {
        straddling: usize,
        leaves: Vec<(Tri, u32)>,
    }

    impl Visitor for Census {
        type Down = u32;
        type Error = ();

        fn straddling(&mut self, _t: &Tri, depth: u32) -> Result<u32, ()> {
            self.straddling += 1;
            Ok(depth + 1)
        }

        fn inside(&mut self, t: &Tri, depth: u32) -> Result<Option<u32>, ()> {
            // Split down to the squares of side 2.
            Ok(
                (!t.is_unit() && t.a[0].abs_diff(t.b[0]).max(t.a[1].abs_diff(t.b[1])) > 2)
                    .then_some(depth + 1),
            )
        }

        fn leaf(&mut self, t: &Tri, depth: u32) {
            self.leaves.push((*t, depth));
        }
    }

    #[test]
    fn leaves_tile_the_grid_and_inside_roots_are_the_top() {
        let h = Hierarchy::new(7, 5); // N = 8
        let mut c = Census {
            straddling: 0,
            leaves: Vec::new(),
        };
        walk(&h, &h.roots(), 0, &mut c).unwrap();
        assert!(c.straddling > 0);
        let area: i64 = c
            .leaves
            .iter()
            .map(|(t, _)| super::super::orient_up(t.a, t.b, t.c).abs())
            .sum();
        assert_eq!(area, 2 * 6 * 4);
        assert!(c
            .leaves
            .iter()
            .all(|(t, _)| h.place(t) == Placement::Inside));
        let tops = h.inside_roots();
        let top_area: i64 = tops
            .iter()
            .map(|t| super::super::orient_up(t.a, t.b, t.c).abs())
            .sum();
        assert_eq!(top_area, 2 * 6 * 4);
    }

    #[test]
    fn an_error_stops_the_walk() {
        struct Stop(usize);
        impl Visitor for Stop {
            type Down = ();
            type Error = usize;
            fn straddling(&mut self, _t: &Tri, _d: ()) -> Result<(), usize> {
                self.0 += 1;
                Err(self.0)
            }
            fn inside(&mut self, _t: &Tri, _d: ()) -> Result<Option<()>, usize> {
                Ok(Some(()))
            }
        }
        let h = Hierarchy::new(7, 5);
        assert_eq!(walk(&h, &h.roots(), (), &mut Stop(0)), Err(1));
    }
}
