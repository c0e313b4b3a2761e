//! A criterion for voids left as holes (`--voids hole`): it wraps the
//! user's criterion and also splits every triangle larger than a unit
//! triangle whose bounding box holds a void sample, so that
//! [`cut_holes`](crate::mesh::holes::cut_holes) can drop the unit triangles
//! on voids afterwards (the scheme is in [`crate::mesh::holes`]). The
//! hierarchy's rules (paper `000_ebf7e3a88dffd361.txt` §2: a split needs its
//! diamond's splits) keep the refined mesh conforming.

use crate::criteria::{Criterion, Element};
use crate::mesh::holes::VoidMask;

/// A criterion that also splits every triangle larger than a unit triangle
/// whose bounding box holds a void (see the module docs).
pub struct AvoidVoids<'a> {
    /// The user's criterion.
    pub inner: &'a dyn Criterion,
    /// The voids of the grid before it was filled.
    pub voids: &'a VoidMask,
}

impl Criterion for AvoidVoids<'_> {
    fn wants_split(&self, e: &Element<'_>) -> bool {
        let xs = e.corners.iter().map(|c| c[0] as usize);
        let ys = e.corners.iter().map(|c| c[1] as usize);
        let (x0, x1) = (xs.clone().min().unwrap_or(0), xs.max().unwrap_or(0));
        let (y0, y1) = (ys.clone().min().unwrap_or(0), ys.max().unwrap_or(0));
        let unit = x1 - x0 <= 1 && y1 - y0 <= 1;
        (!unit && self.voids.count(x0, y0, x1, y1) > 0) || self.inner.wants_split(e)
    }

    fn name(&self) -> String {
        format!("{}, voids as holes", self.inner.name())
    }
}
