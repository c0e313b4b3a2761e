//! The 16 triangulation templates of a restricted-quadtree leaf.
//!
//! Pajarola 1998 ("Large scale terrain visualization using the restricted
//! quadtree triangulation") and papers `002_9d6c1367b8962b6c.txt`,
//! `003_3a32b63e0cff3a64.txt`, `004_ab8d08b3e6a5a70a.txt`: a leaf block is
//! triangulated as a fan around its centre; a side whose neighbour across it is
//! finer contributes its midpoint, so the fan has two triangles on that side
//! instead of one and no T-junction remains.
//!
//! 1. A template is a 4-bit mask of the sides that carry their midpoint:
//!    [`NORTH`], [`EAST`], [`SOUTH`], [`WEST`] (16 patterns, from 4 to 8
//!    triangles).
//! 2. Positions are in half-block units inside the block: corners at 0 and 2,
//!    centre at (1, 1), column east and row south (row 0 north).
//! 3. Every triangle is counter-clockwise seen from above (x east, y north),
//!    as [`crate::Mesh`] requires, and has the centre as its third vertex.

use crate::hierarchy::{orient_up, Pt};

/// The north side (row 0) carries its midpoint.
pub const NORTH: u8 = 1;
/// The east side carries its midpoint.
pub const EAST: u8 = 2;
/// The south side carries its midpoint.
pub const SOUTH: u8 = 4;
/// The west side (column 0) carries its midpoint.
pub const WEST: u8 = 8;

/// The four sides in the order of [`NORTH`], [`EAST`], [`SOUTH`], [`WEST`]:
/// each side's first corner, midpoint and second corner in half-block units.
pub const SIDES: [[Pt; 3]; 4] = [
    [[2, 0], [1, 0], [0, 0]],
    [[2, 2], [2, 1], [2, 0]],
    [[0, 2], [1, 2], [2, 2]],
    [[0, 0], [0, 1], [0, 2]],
];

/// The block centre in half-block units.
pub const CENTRE: Pt = [1, 1];

/// Triangles of one template: at most 8, `len` of them used.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Template {
    /// The triangles in half-block units, counter-clockwise seen from above.
    pub tris: [[Pt; 3]; 8],
    /// How many of `tris` are used (4 to 8).
    pub len: usize,
}

impl Template {
    /// The used triangles.
    pub fn triangles(&self) -> &[[Pt; 3]] {
        &self.tris[..self.len]
    }
}

/// The pieces of side `side` (0..4, in [`SIDES`] order): one triangle
/// (corner, corner, centre) without its midpoint, two with it. Counter-clockwise
/// seen from above.
pub fn side_pieces(side: usize, with_mid: bool) -> ([Pt; 3], Option<[Pt; 3]>) {
    let [a, m, b] = SIDES[side % 4];
    if with_mid {
        (ccw([a, m, CENTRE]), Some(ccw([m, b, CENTRE])))
    } else {
        (ccw([a, b, CENTRE]), None)
    }
}

/// The template for the sides in `mask` (bits [`NORTH`] | [`EAST`] | [`SOUTH`] |
/// [`WEST`]; higher bits are ignored).
pub fn template(mask: u8) -> Template {
    let mut t = Template {
        tris: [[[0, 0]; 3]; 8],
        len: 0,
    };
    for side in 0..4 {
        let (p, q) = side_pieces(side, mask & (1 << side) != 0);
        t.tris[t.len] = p;
        t.len += 1;
        if let Some(q) = q {
            t.tris[t.len] = q;
            t.len += 1;
        }
    }
    t
}

/// `t` reordered to be counter-clockwise seen from above.
fn ccw(t: [Pt; 3]) -> [Pt; 3] {
    if orient_up(t[0], t[1], t[2]) < 0 {
        [t[1], t[0], t[2]]
    } else {
        t
    }
}

#[cfg(test)]
mod test {
    use super::*;
    use std::collections::HashMap;

    #[test]
    fn all_16_patterns_tile_the_block_ccw_without_t_junctions() {
        for mask in 0u8..16 {
            let t = template(mask);
            assert_eq!(t.len, 4 + mask.count_ones() as usize, "mask {mask}");
            let mut area = 0;
            let mut edges: HashMap<(Pt, Pt), usize> = HashMap::new();
            for tri in t.triangles() {
                let a2 = orient_up(tri[0], tri[1], tri[2]);
                assert!(a2 > 0, "mask {mask}: {tri:?} not counter-clockwise");
                area += a2;
                for k in 0..3 {
                    *edges.entry((tri[k], tri[(k + 1) % 3])).or_default() += 1;
                }
            }
            // The block is 2x2 half-units: twice its area is 8.
            assert_eq!(area, 8, "mask {mask}");
            for (&(p, q), &n) in &edges {
                assert_eq!(n, 1, "mask {mask}: directed edge repeated");
                if !edges.contains_key(&(q, p)) {
                    // A boundary edge: on the block's border, and whole or half
                    // exactly as the mask says (no T-junction with a neighbour).
                    let on_border = |r: Pt| r[0] == 0 || r[0] == 2 || r[1] == 0 || r[1] == 2;
                    assert!(on_border(p) && on_border(q), "mask {mask}: inner edge open");
                    let len = p[0].abs_diff(q[0]) + p[1].abs_diff(q[1]);
                    let side = SIDES
                        .iter()
                        .position(|s| s.contains(&p) && s.contains(&q))
                        .unwrap();
                    let split = mask & (1 << side) != 0;
                    assert_eq!(len, if split { 1 } else { 2 }, "mask {mask} side {side}");
                }
            }
        }
    }
}
