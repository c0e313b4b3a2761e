//! The padded square of a W×H grid and how each triangle relates to the
//! grid's rectangle: inside, outside or straddling (see [`super`]). Paper
//! `000_ebf7e3a88dffd361.txt` §2 builds the bitree on a `2^k + 1` square;
//! cota pads any grid to the smallest such square and clips.

use super::tri::{Pt, Tri};

/// How a triangle relates to the grid rectangle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Placement {
    /// All three vertices are grid samples.
    Inside,
    /// It does not meet the rectangle's interior.
    Outside,
    /// Partly inside: must be split.
    Straddling,
}

/// The shape of the hierarchy for a W×H grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Hierarchy {
    width: u32,
    height: u32,
    size: u32,
}

impl Hierarchy {
    /// The hierarchy for a `width × height` grid (both at least 2 and below 2^30).
    pub fn new(width: u32, height: u32) -> Self {
        let span = width.max(height).saturating_sub(1).max(1);
        Hierarchy {
            width,
            height,
            size: span.next_power_of_two(),
        }
    }

    /// Grid width W.
    #[inline]
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Grid height H.
    #[inline]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Side `N` of the padded square (a power of two).
    #[inline]
    pub fn size(&self) -> u32 {
        self.size
    }

    /// The two root triangles (halves of the padded square cut along `\`).
    pub fn roots(&self) -> [Tri; 2] {
        let n = self.size;
        [
            Tri {
                a: [0, 0],
                b: [n, n],
                c: [n, 0],
            },
            Tri {
                a: [n, n],
                b: [0, 0],
                c: [0, n],
            },
        ]
    }

    /// True when `p` is a grid sample.
    #[inline]
    pub fn contains(&self, p: Pt) -> bool {
        p[0] < self.width && p[1] < self.height
    }

    /// Classifies `t` against the grid rectangle (see the module docs).
    #[inline]
    pub fn place(&self, t: &Tri) -> Placement {
        if self.contains(t.a) && self.contains(t.b) && self.contains(t.c) {
            return Placement::Inside;
        }
        let (lo, _) = t.bbox();
        if lo[0] >= self.width - 1 || lo[1] >= self.height - 1 {
            Placement::Outside
        } else {
            Placement::Straddling
        }
    }

    /// Linear index of a sample.
    #[inline]
    pub fn index(&self, p: Pt) -> usize {
        p[1] as usize * self.width as usize + p[0] as usize
    }
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::hierarchy::orient_up;

    #[test]
    fn padded_sizes() {
        assert_eq!(Hierarchy::new(2, 2).size(), 1);
        assert_eq!(Hierarchy::new(3, 2).size(), 2);
        assert_eq!(Hierarchy::new(513, 513).size(), 512);
        assert_eq!(Hierarchy::new(1201, 1201).size(), 2048);
        assert_eq!(Hierarchy::new(2401, 1201).size(), 4096);
        assert_eq!(Hierarchy::new(2, 17).size(), 16);
    }

    #[test]
    fn children_tile_parent_and_halve_area() {
        let h = Hierarchy::new(9, 9);
        for r in h.roots() {
            let area = orient_up(r.a, r.b, r.c).abs();
            let (l, rr) = r.children();
            assert_eq!(orient_up(l.a, l.b, l.c).abs() * 2, area);
            assert_eq!(orient_up(rr.a, rr.b, rr.c).abs() * 2, area);
            assert_eq!(l.c, r.mid());
        }
    }

    #[test]
    fn placement() {
        let h = Hierarchy::new(5, 3); // N = 4, rows 0..=2
        let [r0, r1] = h.roots();
        assert_eq!(h.place(&r0), Placement::Straddling);
        assert_eq!(h.place(&r1), Placement::Straddling);
        let unit_out = Tri {
            a: [0, 2],
            b: [1, 3],
            c: [0, 3],
        };
        assert_eq!(h.place(&unit_out), Placement::Outside);
        let unit_in = Tri {
            a: [0, 1],
            b: [1, 2],
            c: [0, 2],
        };
        assert_eq!(h.place(&unit_in), Placement::Inside);
    }
}
