//! The coarse levels of the global hierarchy, above the window's bitree.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §2 (the bitree) over the whole world's
//! lattice. The window's [`Bitree`] holds the exact, monotone error of every
//! split point up to `A(T_a)` (the halves of alignment-zoom tiles): its
//! hierarchy is the global one there (see [`super::lattice`]), and outside the
//! window the terrain is 0 m, so a split point on the window's border has the
//! same error in both. Tiles coarser than the alignment zoom need the levels
//! above, `B(2·T_a)` up to `A(T_0)` (the centres of the root tiles). Only
//! split points near the window (within two squares of their level, see
//! `add_level`) can have a non-zero error; for those, level by level from
//! fine to coarse:
//!
//! 1. each diamond triangle's own error `e(T)`: the largest |plane − h| over
//!    its samples, those in the window read one by one, those beyond it
//!    (where `h = 0`) bounded by the ends of each row's span, since the plane
//!    is linear along a row;
//! 2. the code is the maximum of those and of the children's split points'
//!    errors (the window bitree's codes, decoded to their upper bound, for
//!    the level just above it), so it stays monotone and diamond-shared, and
//!    a split decided on it is conforming across the bitree/cap boundary.
//!
//! # Runtime
//! `O(window samples)` per level, two passes (sides and halves of each
//! square), in parallel; a few dozen coarse levels at most. Each triangle's
//! rows are read in two passes (`tiles/row_blocks.rs`): a few samples per
//! run of 16 columns first, then only the runs whose bound can exceed the
//! triangle's maximum so far, with the same result.

use rustc_hash::FxHashMap as HashMap;

use rayon::prelude::*;

use super::lattice::Lattice;
use super::row_blocks::{max_deviation, RowBlocks, RowSpan};
use crate::bitree::error_code;
use crate::bitree::{round_up_f32, Bitree};
use crate::hierarchy::{Pt, RowSpans, Tri};
use crate::mesh::raster::Plane;
use crate::progress::Progress;

/// The errors of the coarse split points (absent: 0).
#[derive(Debug, Clone, Default)]
pub(crate) struct Cap {
    errors: HashMap<u64, f32>,
}

/// The map key of a global lattice position.
#[inline]
fn key(p: Pt) -> u64 {
    (u64::from(p[0]) << 32) | u64::from(p[1])
}

impl Cap {
    /// The error of the coarse split point `m` (0 when it was not stored).
    pub(crate) fn error(&self, m: Pt) -> f32 {
        self.errors.get(&key(m)).copied().unwrap_or(0.0)
    }

    /// Number of stored split points.
    pub(crate) fn len(&self) -> usize {
        self.errors.len()
    }

    /// The coarse levels of `lattice`, whose window bitree is `tree`.
    pub(crate) fn build(lattice: &Lattice, tree: &Bitree<'_>, progress: Progress<'_>) -> Cap {
        let s = lattice.scheme();
        let top = s.cells_at(lattice.align_zoom());
        let window = lattice.window();
        let blocks = RowBlocks::new(lattice.grid());
        let own = |t: &Tri| own_error(lattice, &blocks, t);
        let below = |m: Pt| bitree_error(lattice, tree, m);
        Cap::build_with(s.root_cells(), window, top, own, below, progress)
    }

    /// The coarse levels above squares of side `top` over `window`, on a
    /// world of `root_cells` rows: `own(T)` the own error of a coarse
    /// triangle, `below(m)` the error of a split point of the level `top`
    /// (the window's bitree); tells `progress(levels_done, levels)`.
    pub(crate) fn build_with(
        root_cells: u64,
        window: [u64; 4],
        top: u64,
        own: impl Fn(&Tri) -> f32 + Sync,
        below: impl Fn(Pt) -> f32 + Sync,
        progress: Progress<'_>,
    ) -> Cap {
        let mut cap = Cap::default();
        let mut size = 2 * top;
        let levels = (root_cells / top.max(1)).max(1).ilog2() as usize;
        let mut done = 0;
        while size <= root_cells {
            let child = |cap: &Cap, m: Pt| {
                if size / 2 > top {
                    cap.error(m)
                } else {
                    below(m)
                }
            };
            cap.add_level(root_cells, window, size, &own, &child);
            size *= 2;
            done += 1;
            progress(done.min(levels), levels);
        }
        progress(levels, levels);
        cap
    }

    /// Adds the `B(size)` then the `A(size)` split points whose squares meet
    /// the window's interior.
    fn add_level(
        &mut self,
        root_cells: u64,
        window: [u64; 4],
        size: u64,
        own: &(impl Fn(&Tri) -> f32 + Sync),
        child: &(impl Fn(&Cap, Pt) -> f32 + Sync),
    ) {
        let squares = level_squares(root_cells, window, size);
        // Sides: the four triangles with a side as hypotenuse and the centre as apex.
        let sides: Vec<(Pt, f32)> = squares
            .par_iter()
            .flat_map_iter(|&[i, j]| {
                square_tris(i, j, size).0.map(|t| {
                    let (c0, c1) = t.children();
                    let e = own(&t)
                        .max(child(self, c0.mid()))
                        .max(child(self, c1.mid()));
                    (t.mid(), e)
                })
            })
            .collect();
        for (m, e) in sides {
            let slot = self.errors.entry(key(m)).or_insert(0.0);
            *slot = slot.max(e);
        }
        // Halves: the two triangles with the diagonal as hypotenuse.
        let halves: Vec<(Pt, f32)> = squares
            .par_iter()
            .map(|&[i, j]| {
                let tris = square_tris(i, j, size).1;
                let mut e = 0f32;
                for t in tris {
                    let (c0, c1) = t.children();
                    e = e
                        .max(own(&t))
                        .max(self.error(c0.mid()))
                        .max(self.error(c1.mid()));
                }
                (tris[0].mid(), e)
            })
            .collect();
        for (m, e) in halves {
            if e > 0.0 {
                self.errors.insert(key(m), e);
            }
        }
        self.errors.retain(|_, e| *e > 0.0);
    }
}

/// The error of the split point `m` of the window's bitree (its code's
/// upper bound; 0 beyond the window).
fn bitree_error(lattice: &Lattice, tree: &Bitree<'_>, m: Pt) -> f32 {
    let [x0, y0, x1, y1] = lattice.window();
    let (x, y) = (u64::from(m[0]), u64::from(m[1]));
    if x < x0 || x > x1 || y < y0 || y > y1 {
        return 0.0;
    }
    let w = lattice.grid().width();
    let i = (y - y0) as usize * w + (x - x0) as usize;
    error_code::decode(tree.error_codes()[i])
}

/// The squares of side `size` of a coarse level: every square within two
/// squares of the window (a split point outside it inherits errors through
/// the closure from split points nearer the window, up to
/// `s/2 + s/4 + … < s` away at level `s` per level above; none at the
/// bitree's levels, see `lattice::zero_band`), so beyond them every error
/// is 0.
pub(crate) fn level_squares(root_cells: u64, window: [u64; 4], size: u64) -> Vec<[u64; 2]> {
    let [x0, y0, x1, y1] = window;
    let (nx, ny) = (2 * root_cells / size, root_cells / size);
    let first = |v: u64| (v / size).saturating_sub(2);
    (first(y0)..=(y1 / size + 2).min(ny - 1))
        .flat_map(|j| (first(x0)..=(x1 / size + 2).min(nx - 1)).map(move |i| [i, j]))
        .collect()
}

/// The square `(i, j)` of side `size`: its four side triangles (hypotenuse a
/// side, apex the centre) and its two halves, cut along `\` when `i + j` is
/// even and `/` when odd (the hierarchy's diagonals).
pub(crate) fn square_tris(i: u64, j: u64, size: u64) -> ([Tri; 4], [Tri; 2]) {
    let (x0, y0) = ((i * size) as u32, (j * size) as u32);
    let s = size as u32;
    let (nw, ne, sw, se) = ([x0, y0], [x0 + s, y0], [x0, y0 + s], [x0 + s, y0 + s]);
    let c = [x0 + s / 2, y0 + s / 2];
    let side = |a: Pt, b: Pt| Tri { a, b, c };
    let sides = [side(nw, ne), side(ne, se), side(se, sw), side(sw, nw)];
    let halves = square_halves([nw, ne, sw, se], (i + j).is_multiple_of(2));
    (sides, halves)
}

/// The two halves of a square with corners `[nw, ne, sw, se]`, split along
/// the diagonal its parity gives (`even`: nw–se), each as a bitree root
/// (hypotenuse a–b, right angle at c); the tiles' checkerboard of squares.
pub(crate) fn square_halves([nw, ne, sw, se]: [Pt; 4], even: bool) -> [Tri; 2] {
    if even {
        [
            Tri {
                a: nw,
                b: se,
                c: ne,
            },
            Tri {
                a: se,
                b: nw,
                c: sw,
            },
        ]
    } else {
        [
            Tri {
                a: ne,
                b: sw,
                c: se,
            },
            Tri {
                a: sw,
                b: ne,
                c: nw,
            },
        ]
    }
}

/// The own error `e(T)` of a global triangle over the lattice (window
/// samples one by one, the 0 m beyond by the ends of each row's span),
/// rounded up to `f32`.
fn own_error(lattice: &Lattice, blocks: &RowBlocks, t: &Tri) -> f32 {
    let z = t_heights(t, |x, y| lattice.height_at(x, y));
    round_up_f32(own_rows(
        lattice.window(),
        t,
        z,
        true,
        Some((lattice, lattice.window(), Some(blocks))),
    ))
}

/// The heights of `t`'s corners `a`, `b`, `c`.
pub(crate) fn t_heights(t: &Tri, height: impl Fn(u64, u64) -> f32) -> [f64; 3] {
    [t.a, t.b, t.c].map(|q| f64::from(height(u64::from(q[0]), u64::from(q[1]))))
}

/// Largest |plane − h| of a coarse triangle `t` whose corners have heights
/// `z`, over the window `window`: with `beyond`, the 0 m outside the window
/// (by the ends of each row's span, the plane being linear along a row);
/// with `inside = (lattice, clip)`, the window samples in `clip` read one by
/// one from `lattice` (runs that cannot hold the maximum skipped with
/// `blocks`, the same result: [`super::row_blocks`]). The maxima of the parts (the 0 m beyond, and clips
/// covering the window) combine into the whole's exactly: each value is
/// computed the same way in every part.
pub(crate) fn own_rows(
    window: [u64; 4],
    t: &Tri,
    z: [f64; 3],
    beyond: bool,
    inside: Option<(&Lattice, [u64; 4], Option<&RowBlocks>)>,
) -> f64 {
    let [x0, y0, x1, y1] = window;
    let p = [t.a, t.b, t.c];
    let lo = [p.iter().map(|q| q[0]).min(), p.iter().map(|q| q[1]).min()];
    let hi = [p.iter().map(|q| q[0]).max(), p.iter().map(|q| q[1]).max()];
    let (Some(lx), Some(ly), Some(hx), Some(hy)) = (lo[0], lo[1], hi[0], hi[1]) else {
        return 0.0;
    };
    // Entirely on the 0 m outside the window's interior: the plane is 0 too.
    if u64::from(hx) <= x0 || u64::from(lx) >= x1 || u64::from(hy) <= y0 || u64::from(ly) >= y1 {
        return 0.0;
    }
    let Some(plane) = Plane::new(p, z) else {
        return 0.0;
    };
    let z_abs = z.iter().fold(0f64, |m, v| m.max(v.abs()));
    let spans = RowSpans::new(p.map(|q| [i64::from(q[0]), i64::from(q[1])]));
    let (ya, yb) = spans.rows();
    // With `blocks`, two passes: exact values at a few samples of each row
    // (`floor: None`), then only the runs that can exceed their maximum.
    let row_error = |y: i64, floor: Option<f64>| -> f64 {
        let (l, r) = spans.at(y);
        if l > r {
            return 0.0;
        }
        let bg = |x: i64| plane.at(x as f64, y as f64).abs();
        let (wx0, wx1) = (x0 as i64, x1 as i64);
        if y < y0 as i64 || y > y1 as i64 || r < wx0 || l > wx1 {
            return if beyond && floor.is_none() {
                bg(l).max(bg(r))
            } else {
                0.0
            };
        }
        let (a, b) = (l.max(wx0), r.min(wx1));
        let mut e = 0f64;
        if beyond && floor.is_none() && l < a {
            e = e.max(bg(l)).max(bg(a - 1));
        }
        if beyond && floor.is_none() && r > b {
            e = e.max(bg(b + 1)).max(bg(r));
        }
        if let Some((lattice, clip, blocks)) = inside {
            let (ca, cb) = (a.max(clip[0] as i64), b.min(clip[2] as i64));
            if y < clip[1] as i64 || y > clip[3] as i64 || ca > cb {
                return e;
            }
            let g = lattice.grid();
            let [ox, oy] = lattice.origin();
            let r = (y - oy as i64) as usize;
            let row = &g.heights()[r * g.width()..(r + 1) * g.width()];
            let span = RowSpan {
                row,
                r,
                i: (ca - ox as i64) as usize,
                j: (cb - ox as i64) as usize,
                x_i: ca,
                y: y as f64,
            };
            e = e.max(match (blocks, floor) {
                (Some(b), None) => b.row_seed(&plane, span),
                (Some(b), Some(f)) => b.row_rest(&plane, span, (z_abs, f)),
                (None, _) => max_deviation(&plane, ca, span.y, &row[span.i..=span.j]),
            });
        }
        e
    };
    let pass = |floor: Option<f64>| {
        if yb - ya > 256 {
            (ya..=yb)
                .into_par_iter()
                .map(|y| row_error(y, floor))
                .reduce(|| 0.0, f64::max)
        } else {
            (ya..=yb).map(|y| row_error(y, floor)).fold(0.0, f64::max)
        }
    };
    let seed = pass(None);
    match inside {
        Some((_, _, Some(_))) => seed.max(pass(Some(seed))),
        _ => seed,
    }
}
