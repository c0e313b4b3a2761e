//! The data's footprints on the lattice, as polygons in global lattice
//! coordinates, and whether a tile's square meets one with a positive area
//! (Sutherland–Hodgman clipping). A tile is made only where it does: the
//! tiles of paper `001_49f2c365e8c41172.txt`'s mosaic cover the data, not a
//! window of whole tiles around it.

/// The footprints of the data on the lattice: a tile is made when its
/// square meets one of them with a positive area.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Coverage {
    /// Closed polygons, global lattice coordinates.
    pub polygons: Vec<Vec<[f64; 2]>>,
}

impl Coverage {
    /// Whether the square `[x0, x1] × [y0, y1]` meets a footprint with a
    /// positive area.
    pub fn meets(&self, [x0, y0, x1, y1]: [f64; 4]) -> bool {
        self.polygons
            .iter()
            .any(|p| clipped_area(p, [x0, y0, x1, y1]) > 1e-9)
    }
}

/// The area of `poly` clipped to the box (Sutherland–Hodgman).
fn clipped_area(poly: &[[f64; 2]], [x0, y0, x1, y1]: [f64; 4]) -> f64 {
    let mut pts: Vec<[f64; 2]> = poly.to_vec();
    // Each half-plane: (axis, bound, keep below).
    for (axis, bound, below) in [(0, x0, false), (0, x1, true), (1, y0, false), (1, y1, true)] {
        let inside = |p: &[f64; 2]| {
            if below {
                p[axis] <= bound
            } else {
                p[axis] >= bound
            }
        };
        let mut out = Vec::with_capacity(pts.len() + 4);
        for k in 0..pts.len() {
            let (a, b) = (pts[k], pts[(k + 1) % pts.len()]);
            let (ia, ib) = (inside(&a), inside(&b));
            if ia {
                out.push(a);
            }
            if ia != ib {
                let t = (bound - a[axis]) / (b[axis] - a[axis]);
                out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
            }
        }
        pts = out;
        if pts.is_empty() {
            return 0.0;
        }
    }
    let mut area = 0.0;
    for k in 0..pts.len() {
        let (a, b) = (pts[k], pts[(k + 1) % pts.len()]);
        area += a[0] * b[1] - b[0] * a[1];
    }
    area.abs() / 2.0
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn clipping_measures_the_overlap() {
        let square = vec![[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]];
        assert!((clipped_area(&square, [2.0, 2.0, 6.0, 6.0]) - 4.0).abs() < 1e-12);
        assert_eq!(clipped_area(&square, [4.0, 0.0, 8.0, 4.0]), 0.0);
        let c = Coverage {
            polygons: vec![square],
        };
        assert!(c.meets([3.0, 3.0, 5.0, 5.0]));
        assert!(!c.meets([4.0, 0.0, 6.0, 2.0]));
    }
}
