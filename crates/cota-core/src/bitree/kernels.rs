//! Shortcuts for the small diamonds of the bitree build: each computes the
//! same code as the general path (`diamond_error` in the parent module)
//! for a split point whose diamond lies inside the grid, by scanning the
//! diamond directly, without building triangles or row spans.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §2 (the bitree and its error) and
//! `001_49f2c365e8c41172.txt` (one error per split point). Every plane value
//! is an exact sum of power-of-two fractions of the corner heights, so the
//! codes are bit-identical to the general path's, which the tests check on
//! every level. The samples on a triangle's legs are skipped (see *Legs* in
//! the parent module's docs).
//!
//! # Runtime
//! `O(s²)` per split point of `A(s)` or `B(s)`, with a small constant.

use super::error::{code_of, max_no_nan, row_max_dev, Codes};
use crate::hierarchy::{Hierarchy, Pt};

/// `B(2)` away from the grid's border: both triangles of the diamond are inside
/// and their only off-vertex sample is `m`, so `err[m] = |h(m) − mean(ends)|`.
/// The same value [`diamond_error`] computes, without building triangles.
/// `None` near the border (the general path decides there).
#[inline]
pub(super) fn fine_b2(heights: &[f32], hier: &Hierarchy, m: Pt) -> Option<u16> {
    let (w, h) = (hier.width() as usize, hier.height() as usize);
    let [x, y] = [m[0] as usize, m[1] as usize];
    let (a, b) = if y % 2 == 0 {
        // Horizontal side; apexes above and below.
        (y >= 1 && y + 1 < h && x + 1 < w).then(|| (y * w + x - 1, y * w + x + 1))?
    } else {
        // Vertical side; apexes left and right.
        (x >= 1 && x + 1 < w && y + 1 < h).then(|| ((y - 1) * w + x, (y + 1) * w + x))?
    };
    let hv = |i: usize| heights[i] as f64;
    Some(code_of((hv(y * w + x) - 0.5 * (hv(a) + hv(b))).abs()))
}

/// `A(2)` inside the grid: both square halves are inside; `err[m]` is the
/// deviation of the centre from its diagonal and the four side midpoints'
/// errors (the children). The same value as [`diamond_error`].
#[inline]
pub(super) fn fine_a2(heights: &[f32], hier: &Hierarchy, m: Pt, codes: Codes<'_>) -> Option<u16> {
    let (w, h) = (hier.width() as usize, hier.height() as usize);
    let [x, y] = [m[0] as usize, m[1] as usize];
    if x + 1 >= w || y + 1 >= h {
        return None;
    }
    let hv = |i: usize| heights[i] as f64;
    let even = ((x - 1) / 2 + (y - 1) / 2) % 2 == 0;
    let (a, b) = if even {
        ((y - 1) * w + x - 1, (y + 1) * w + x + 1)
    } else {
        ((y - 1) * w + x + 1, (y + 1) * w + x - 1)
    };
    let own = code_of((hv(y * w + x) - 0.5 * (hv(a) + hv(b))).abs());
    Some(own.max(side_children(codes, w, x, y, 1)))
}

/// `B(4)` with both triangles inside the grid: the samples to scan are the
/// three inside the hypotenuse and the one inside each triangle (5 in the
/// diamond; see *Legs* in the module docs), whose plane values are exact quarter sums of the
/// corner heights; the children are the four `A(2)` points beside `m`. The
/// same value as [`diamond_error`] (every value is exact), about 5× faster
/// than the general row scan at this size.
#[inline]
pub(super) fn fine_b4(heights: &[f32], hier: &Hierarchy, m: Pt, codes: Codes<'_>) -> Option<u16> {
    let (w, h) = (hier.width() as usize, hier.height() as usize);
    let [x, y] = [m[0] as usize, m[1] as usize];
    // (along, across): unit steps along the hypotenuse and towards an apex.
    let (along, across) = if y % 4 == 0 {
        (y >= 2 && y + 2 < h && x + 2 < w).then_some((1isize, w as isize))?
    } else {
        (x >= 2 && x + 2 < w && y + 2 < h).then_some((w as isize, 1isize))?
    };
    let c = (y * w + x) as isize;
    let hv = |i: isize| heights[i as usize] as f64;
    let (ha, hb) = (hv(c - 2 * along), hv(c + 2 * along));
    // The hypotenuse's three inner samples (shared by both triangles).
    let mut e = (hv(c - along) - (3.0 * ha + hb) * 0.25).abs();
    e = max_no_nan(e, (hv(c) - (ha + hb) * 0.5).abs());
    e = max_no_nan(e, (hv(c + along) - (ha + 3.0 * hb) * 0.25).abs());
    let mut code = 0u16;
    for side in [-1isize, 1] {
        let row = c + side * across;
        let hc = hv(c + 2 * side * across);
        e = max_no_nan(e, (hv(row) - (ha + hb + 2.0 * hc) * 0.25).abs());
        code = code
            .max(codes[(row - along) as usize])
            .max(codes[(row + along) as usize]);
    }
    Some(code.max(code_of(e)))
}

/// `A(4)` with the whole 4×4 square inside the grid: the 9 samples inside
/// the square (its sides are its triangles' legs; see *Legs* in the module docs), each against
/// the plane of the half it lies in (both halves for the diagonal, where the
/// planes agree); the children are the `B(4)` points at the square's side
/// midpoints. The same value as [`diamond_error`].
#[inline]
pub(super) fn fine_a4(heights: &[f32], hier: &Hierarchy, m: Pt, codes: Codes<'_>) -> Option<u16> {
    let (w, h) = (hier.width() as usize, hier.height() as usize);
    let [x, y] = [m[0] as usize, m[1] as usize];
    if x + 2 >= w || y + 2 >= h {
        return None;
    }
    let (x0, y0) = (x - 2, y - 2);
    let hv = |i: usize, j: usize| heights[(y0 + j) * w + x0 + i] as f64;
    let (h00, h40, h04, h44) = (hv(0, 0), hv(4, 0), hv(0, 4), hv(4, 4));
    let even = ((x0 / 4) + (y0 / 4)) % 2 == 0;
    let mut e = 0f64;
    for j in 1..=3usize {
        for i in 1..=3usize {
            let (fi, fj) = (i as f64, j as f64);
            // Four times the plane, exactly.
            let p4 = if even {
                // Diagonal (0,0)–(4,4).
                if j <= i {
                    4.0 * h00 + fi * (h40 - h00) + fj * (h44 - h40)
                } else {
                    4.0 * h00 + fi * (h44 - h04) + fj * (h04 - h00)
                }
            } else if i + j >= 4 {
                // Diagonal (4,0)–(0,4), south-east half.
                4.0 * h44 + (4.0 - fi) * (h04 - h44) + (4.0 - fj) * (h40 - h44)
            } else {
                4.0 * h00 + fi * (h40 - h00) + fj * (h04 - h00)
            };
            e = max_no_nan(e, (hv(i, j) - p4 * 0.25).abs());
        }
    }
    Some(code_of(e).max(side_children(codes, w, x, y, 2)))
}

/// The largest side handled by [`small_b`] and [`small_a`]: above it the
/// general row scan's set-up is small beside the triangles' samples.
pub(super) const SMALL_MAX: u32 = 64;

/// `B(s)` for `8 ≤ s ≤ SMALL_MAX` with both triangles inside the grid. The
/// same samples, planes and arithmetic as [`diamond_error`] (every plane value
/// is an exact sum of power-of-two fractions), without building triangles or
/// row spans: the diamond is scanned row by row, each row as one or two
/// segments of a plane. About 4× faster than the general path at `s = 8`.
/// `None` near the border.
#[inline]
pub(super) fn small_b(
    heights: &[f32],
    hier: &Hierarchy,
    s: u32,
    m: Pt,
    codes: Codes<'_>,
) -> Option<u16> {
    let (w, hh) = (hier.width() as usize, hier.height() as usize);
    let [x, y] = [m[0] as usize, m[1] as usize];
    let (s, h, q) = (s as usize, s as usize / 2, s as usize / 4);
    let hv = |i: usize| heights[i] as f64;
    let sf = s as f64;
    let hf = h as f64;
    let mut e = 0f64;
    if y % s == 0 {
        // Horizontal hypotenuse (x−h, y)–(x+h, y); apexes above and below.
        if !(y >= h && y + h < hh && x + h < w) {
            return None;
        }
        let (ha, hb) = (hv(y * w + x - h), hv(y * w + x + h));
        let gx = (hb - ha) / sf;
        let mid = (ha + hb) * 0.5;
        for dir in [-1isize, 1] {
            let hc = hv((y as isize + dir * h as isize) as usize * w + x);
            // Plane change per row away from the hypotenuse.
            let gd = (hc - mid) / hf;
            // The hypotenuse row (d = 0) is shared: scan it once. Each row
            // skips its two samples on the legs (see *Legs* in the module docs).
            let d0 = if dir < 0 { 0 } else { 1 };
            for d in d0..h {
                let row = (y as isize + dir * d as isize) as usize;
                let start = row * w + x - h + d + 1;
                let base = ha + gx * (d + 1) as f64 + gd * d as f64;
                e = max_no_nan(
                    e,
                    row_max_dev(&heights[start..start + 2 * (h - d) - 1], base, gx),
                );
            }
        }
    } else {
        // Vertical hypotenuse (x, y−h)–(x, y+h); apexes left and right.
        if !(x >= h && x + h < w && y + h < hh) {
            return None;
        }
        let (ha, hb) = (hv((y - h) * w + x), hv((y + h) * w + x));
        let gy = (hb - ha) / sf;
        let mid = (ha + hb) * 0.5;
        let (hl, hr) = (hv(y * w + x - h), hv(y * w + x + h));
        // Plane change per column: towards the left apex, then away from
        // the hypotenuse towards the right one.
        let (gl, gr) = ((mid - hl) / hf, (hr - mid) / hf);
        // The first and last rows are the hypotenuse's ends; each row skips
        // its two samples on the legs (see *Legs* in the module docs).
        for j in 1..s {
            let r = j.min(s - j);
            let row = (y - h + j) * w;
            let along = ha + gy * j as f64;
            // Left: columns x−r+1 ..= x (the hypotenuse sample included).
            let start = row + x + 1 - r;
            e = max_no_nan(
                e,
                row_max_dev(&heights[start..=row + x], along - gl * (r - 1) as f64, gl),
            );
            if r > 1 {
                let start = row + x + 1;
                e = max_no_nan(
                    e,
                    row_max_dev(&heights[start..start + r - 1], along + gr, gr),
                );
            }
        }
    }
    let mut code = code_of(e);
    for c in [
        (y - q) * w + x - q,
        (y - q) * w + x + q,
        (y + q) * w + x - q,
        (y + q) * w + x + q,
    ] {
        code = code.max(codes[c]);
    }
    Some(code)
}

/// `A(s)` for `8 ≤ s ≤ SMALL_MAX` with the whole square inside the grid: each
/// row of the square is two segments, one in each half, each scanned against
/// its half's plane; the children are the `B(s)` points at the square's side
/// midpoints. The same value as [`diamond_error`]. `None` near the border.
#[inline]
pub(super) fn small_a(
    heights: &[f32],
    hier: &Hierarchy,
    s: u32,
    m: Pt,
    codes: Codes<'_>,
) -> Option<u16> {
    let (w, hh) = (hier.width() as usize, hier.height() as usize);
    let [x, y] = [m[0] as usize, m[1] as usize];
    let (s, h) = (s as usize, s as usize / 2);
    if x + h >= w || y + h >= hh {
        return None;
    }
    let (x0, y0) = (x - h, y - h);
    let hv = |i: usize, j: usize| heights[(y0 + j) * w + x0 + i] as f64;
    let (h00, hs0, h0s, hss) = (hv(0, 0), hv(s, 0), hv(0, s), hv(s, s));
    let sf = s as f64;
    let even = ((x0 / s) + (y0 / s)).is_multiple_of(2);
    let mut e = 0f64;
    // The square's sides are its triangles' legs (see *Legs* in the module docs): rows and
    // columns 1 ..= s−1 only.
    for j in 1..s {
        let row = (y0 + j) * w + x0;
        let jf = j as f64;
        // (first column of the second segment, plane of the first segment at
        // column 0 and its slope, plane of the second at that column and its
        // slope).
        let (split, base1, g1, base2, g2) = if even {
            // Diagonal (0,0)–(s,s): columns 0..j below it, j..=s above.
            let (gl, gu) = ((hss - h0s) / sf, (hs0 - h00) / sf);
            let lower = h00 + (h0s - h00) / sf * jf;
            let upper = h00 + gu * jf + (hss - hs0) / sf * jf;
            (j, lower, gl, upper, gu)
        } else {
            // Diagonal (s,0)–(0,s): columns 0..=s−j above it, the rest below.
            let (gu, gl) = ((hs0 - h00) / sf, (hss - h0s) / sf);
            let upper = h00 + (h0s - h00) / sf * jf;
            let c = s - j + 1;
            let lower = hs0 + gl * (c as f64 - sf) + (hss - hs0) / sf * jf;
            (c, upper, gu, lower, gl)
        };
        if split > 1 {
            e = max_no_nan(
                e,
                row_max_dev(&heights[row + 1..row + split], base1 + g1, g1),
            );
        }
        if split < s {
            e = max_no_nan(e, row_max_dev(&heights[row + split..row + s], base2, g2));
        }
    }
    Some(code_of(e).max(side_children(codes, w, x, y, h)))
}

/// The largest code of the four children of an `A` split point `(x, y)`:
/// the `B` points at its square's side midpoints, `d` samples away.
#[inline]
fn side_children(codes: Codes<'_>, w: usize, x: usize, y: usize, d: usize) -> u16 {
    codes[y * w + x - d]
        .max(codes[y * w + x + d])
        .max(codes[(y - d) * w + x])
        .max(codes[(y + d) * w + x])
}

#[cfg(test)]
mod test {
    use super::super::error::diamond_error;
    use super::super::test::grid;
    use super::super::Bitree;
    use super::*;
    use crate::hierarchy::{first_col, levels, Level};

    #[test]
    fn fine_level_shortcuts_match_the_general_path() {
        for (w, h) in [
            (17, 17),
            (20, 13),
            (2, 9),
            (33, 8),
            (29, 37),
            (130, 75),
            (67, 141),
        ] {
            let g = grid(w, h, |x, y| {
                ((x * 37 + y * 11) % 13) as f32 * 1.7 - (x * y) as f32 * 0.03
            });
            let t = Bitree::build(&g).unwrap();
            let hier = t.hierarchy();
            for level in levels(hier.size()) {
                let s = match level {
                    Level::A(s) | Level::B(s) => s,
                };
                for y in 0..h as u32 {
                    let on_row = match level {
                        Level::A(_) => y % s == s / 2,
                        Level::B(_) => y % (s / 2) == 0,
                    };
                    let mut x = first_col(level, y);
                    while on_row && x < w as u32 {
                        let general = diamond_error(
                            g.heights(),
                            hier,
                            level,
                            [x, y],
                            Codes {
                                c: t.error_codes(),
                                base: 0,
                            },
                        );
                        let i = hier.index([x, y]);
                        assert_eq!(
                            t.error_codes()[i],
                            general,
                            "{level:?} at {x},{y} on {w}x{h}"
                        );
                        x += s;
                    }
                }
            }
        }
    }
}
