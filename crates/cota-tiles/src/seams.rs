//! Seams between same-zoom neighbours, measured on decoded tiles: the check
//! the tests run on cota's pyramids and the benchmark runs on its peers'.
//!
//! Two tiles that share a border must decode to the same border vertices:
//! the same positions along it (same-zoom tiles have the same extent, so the
//! same quantized coordinate), and heights equal within the two tiles'
//! quantization (half a height step of each). A border vertex of one tile
//! with no vertex at its position in the other is a T-junction or a crack:
//! a client shows a gap or a wall there.

use super::decode::DecodedTile;

/// Where the second tile lies relative to the first.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Neighbour {
    /// The second tile is east of the first (`x + 1`).
    East,
    /// The second tile is north of the first (`y + 1` in TMS).
    North,
}

/// What comparing one shared border found.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BorderCheck {
    /// Distinct border positions in either tile.
    pub positions: usize,
    /// Positions with a vertex in one tile only.
    pub missing: usize,
    /// Positions in both whose heights differ by more than the two tiles'
    /// half height steps.
    pub height_mismatches: usize,
    /// The largest height difference at a shared position, metres.
    pub max_height_diff_m: f64,
}

impl BorderCheck {
    /// Mismatches of either kind.
    pub fn mismatches(&self) -> usize {
        self.missing + self.height_mismatches
    }
}

/// Half a tile's height step, metres.
fn half_step(t: &DecodedTile) -> f64 {
    0.5 * (f64::from(t.header.max_height_m) - f64::from(t.header.min_height_m)) / 32767.0
}

/// `(position along the border, height)` of a tile's vertices whose `axis`
/// coordinate (0: u, 1: v) equals `value`, sorted by position.
fn border(t: &DecodedTile, axis: usize, value: u16) -> Vec<(u16, f64)> {
    let (on, along) = if axis == 0 {
        (&t.u, &t.v)
    } else {
        (&t.v, &t.u)
    };
    let mut out: Vec<(u16, f64)> = (0..t.u.len())
        .filter(|&i| on[i] == value)
        .map(|i| (along[i], t.height_m(i)))
        .collect();
    out.sort_by_key(|p| p.0);
    out
}

/// Compares the border that `a` shares with its neighbour `b`.
pub fn compare_border(a: &DecodedTile, b: &DecodedTile, b_is: Neighbour) -> BorderCheck {
    let (pa, pb) = match b_is {
        Neighbour::East => (border(a, 0, 32767), border(b, 0, 0)),
        Neighbour::North => (border(a, 1, 32767), border(b, 1, 0)),
    };
    let tol = half_step(a) + half_step(b) + 1e-6;
    let mut c = BorderCheck::default();
    let (mut i, mut j) = (0, 0);
    while i < pa.len() || j < pb.len() {
        c.positions += 1;
        match (pa.get(i), pb.get(j)) {
            (Some(x), Some(y)) if x.0 == y.0 => {
                let d = (x.1 - y.1).abs();
                c.max_height_diff_m = c.max_height_diff_m.max(d);
                if d > tol {
                    c.height_mismatches += 1;
                }
                i += 1;
                j += 1;
            }
            (Some(x), Some(y)) if x.0 < y.0 => {
                c.missing += 1;
                i += 1;
            }
            (Some(_), None) => {
                c.missing += 1;
                i += 1;
            }
            _ => {
                c.missing += 1;
                j += 1;
            }
        }
    }
    c
}

/// Whether the tile's four edge lists hold exactly its vertices on each edge.
pub fn edge_lists_match(t: &DecodedTile) -> bool {
    let sides = [(0, 0u16), (1, 0), (0, 32767), (1, 32767)];
    sides.iter().zip(&t.edges).all(|(&(axis, value), list)| {
        let on = if axis == 0 { &t.u } else { &t.v };
        let mut want: Vec<u32> = (0..t.u.len() as u32)
            .filter(|&i| on[i as usize] == value)
            .collect();
        let mut got = list.clone();
        want.sort_unstable();
        got.sort_unstable();
        want == got
    })
}
