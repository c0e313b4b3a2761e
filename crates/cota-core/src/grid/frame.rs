//! The grid's local frame in metres: the one map from grid samples to a
//! metric east/north/up frame, shared by the criteria (distances, sizes,
//! view) and the exporters' local-metres output.
//!
//! `x = col·dx` east, `y = (H − 1 − row)·dy` north, `z` up (the height),
//! origin at the grid's south-west sample, with `[dx, dy]` =
//! [`HeightGrid::cell_size_m`]. For geographic grids that is the conversion
//! of degrees to metres at the grid's centre latitude applied to the whole
//! grid: a local tangent-plane approximation, good to a fraction of a percent
//! over a 1° tile.

use super::HeightGrid;

/// The local frame of one grid (see the module docs).
///
/// ```
/// use cota_core::{GeoRef, HeightGrid};
/// let g = HeightGrid::new(3, 2, vec![0.0; 6], GeoRef::unreferenced(30.0)).unwrap();
/// let f = g.local_frame();
/// assert_eq!(f.point_m(2.0, 0.0, 5.0), [60.0, 30.0, 5.0]);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LocalFrame {
    dx: f64,
    dy: f64,
    last_row: f64,
}

impl LocalFrame {
    /// The local frame of `grid`.
    pub fn of(grid: &HeightGrid) -> Self {
        let [dx, dy] = grid.cell_size_m();
        LocalFrame {
            dx,
            dy,
            last_row: grid.height() as f64 - 1.0,
        }
    }

    /// The cell size `[dx, dy]` in metres.
    pub fn cell_size_m(&self) -> [f64; 2] {
        [self.dx, self.dy]
    }

    /// The position in metres of the (possibly fractional) grid point
    /// (`col`, `row`) at height `z_m`.
    #[inline]
    pub fn point_m(&self, col: f64, row: f64, z_m: f64) -> [f64; 3] {
        [col * self.dx, (self.last_row - row) * self.dy, z_m]
    }
}
