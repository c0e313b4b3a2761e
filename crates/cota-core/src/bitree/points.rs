//! Point accounting shared by the two hierarchies: which mesh vertices the
//! criterion selected and which the hierarchy's dependencies added.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §5 (Table 1) counts, per tolerance, the
//! points each model *adds* to avoid cracks ("puntos agregados"), the points to
//! *transmit* and the triangles. Pajarola 1998 is the restricted quadtree it
//! compares against ([`crate::quadtree`]).
//!
//! Paper 000's Figure 14 starts both hierarchies "from the same set of selected
//! points", so one definition serves both. Every grid sample other than the
//! padded square's corners is the split point of one diamond of the right-
//! triangle hierarchy ([`crate::hierarchy`]); Pajarola's restricted quadtree
//! uses the same points with the same dependencies (paper 000 §2.2): a block
//! centre splits the block's two halves, a side midpoint the two triangles
//! (corner, corner, centre) on either side of the side, which are exactly the
//! quadtree templates' side pieces ([`crate::quadtree::templates`]).
//!
//! 1. A point's **own error** is the largest exact `e(T)` of the (one or two)
//!    triangles of its diamond that lie inside the grid: the largest
//!    `|plane − h|` over every sample in or on them, paper 000 §3.2's measure
//!    (not the monotone value the bitree propagates from finer levels).
//! 2. A mesh vertex is **base** when it is a corner of the padded square (it
//!    splits nothing), **selected** when its own error exceeds the tolerance,
//!    and **added** otherwise: present only because of dependencies (the
//!    bitree's monotone propagation, the quadtree's restriction and its
//!    templates' centres) or because a triangle of its diamond straddles the
//!    grid's border (own error `+∞`, always split).
//!
//! The quadtree also reports a split-based count ([`crate::quadtree`]: points
//! introduced only by forced splits), valid for any criterion.
//!
//! In a conforming mesh every vertex carries its true height, so all of them
//! must be transmitted; a fictitious-point mode transmits the vertices with a
//! real height only (paper 000 §3.3, [`crate::refine`](mod@crate::refine)).

use super::{round_up_f32, Bitree};
use crate::mesh::Mesh;

/// How the vertices of a mesh split into base, selected and added points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PointCounts {
    /// Mesh vertices.
    pub vertices: usize,
    /// Mesh triangles.
    pub triangles: usize,
    /// Vertices of the coarsest mesh (root corners; quadtree: and root centre).
    pub base: usize,
    /// Vertices the criterion selected.
    pub selected: usize,
    /// Vertices added only by the hierarchy's dependencies.
    pub added: usize,
}

impl Bitree<'_> {
    /// Classifies the vertices of `mesh` for the tolerance `max_error_m` (see
    /// the module docs). `mesh` is any mesh whose vertices are samples of this
    /// tree's grid: the bitree's own, or the restricted quadtree's.
    ///
    /// # Runtime
    /// One exact diamond error per vertex: `O(area of the vertices' diamonds)`.
    pub fn point_counts(&self, mesh: &Mesh, max_error_m: f64) -> PointCounts {
        let mut c = PointCounts {
            vertices: mesh.vertex_count(),
            triangles: mesh.triangle_count(),
            ..PointCounts::default()
        };
        for v in &mesh.vertices {
            match self.own_error_at([v.col, v.row]) {
                None => c.base += 1,
                Some(e) if e.is_infinite() => c.added += 1,
                Some(e) if round_up_f32(e) as f64 > max_error_m => c.selected += 1,
                Some(_) => c.added += 1,
            }
        }
        c
    }
}
