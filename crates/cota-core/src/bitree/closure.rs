//! The monotone closure of a per-sample quantity over the bitree: for each
//! split point, the largest value over every sample its diamond and its
//! descendants cover.
//!
//! Paper `000_ebf7e3a88dffd361.txt` §2–3: a split point's error is the
//! maximum of its diamond's own errors and of its children's, so that a
//! decision per split point is monotone up the tree. The same closure of
//! any non-negative per-sample value (here: how far the source's own samples
//! lie from the lattice near each lattice point, [`crate::tiles::fit`])
//! gives a monotone term that a decision may add to the error and stay
//! conforming.
//!
//! # Runtime
//! `O(n)`: one pass per level over its split points, in parallel over rows.

use super::by_level::fill_level;
use super::error::Codes;
use super::error_code::{decode, encode_up};
use crate::hierarchy::{levels, Hierarchy, Level, Pt};

/// For every split point of `hier`'s grid (`W × H`, row-major), the code
/// ([`super::error_code`]) of the largest `own` value over the samples of
/// its diamond and of all its descendants. `own` holds one code per sample.
pub(crate) fn max_closure(hier: &Hierarchy, own: &[u16]) -> Vec<u16> {
    let mut codes = vec![0u16; own.len()];
    for level in levels(hier.size()) {
        fill_level(hier, level, &mut codes, |m, codes| match level {
            // The diamond of B(2): its split point and its four neighbours.
            Level::B(2) => max_at(hier, m, 1, false, own).max(own[index(hier, m)]),
            _ => children_max(hier, level, m, &codes),
        });
    }
    codes
}

/// The index of `p` in the grid.
#[inline]
fn index(hier: &Hierarchy, p: Pt) -> usize {
    p[1] as usize * hier.width() as usize + p[0] as usize
}

/// The largest of `v` at the four points `m ± (d, 0)`, `m ± (0, d)`
/// (`diagonal`: `m ± (d, ±d)`) that lie in the grid.
#[inline]
fn max_at(hier: &Hierarchy, m: Pt, d: u32, diagonal: bool, v: &[u16]) -> u16 {
    let [x, y] = m;
    let pts: [(Option<u32>, Option<u32>); 4] = if diagonal {
        [
            (x.checked_sub(d), y.checked_sub(d)),
            (x.checked_add(d), y.checked_sub(d)),
            (x.checked_sub(d), y.checked_add(d)),
            (x.checked_add(d), y.checked_add(d)),
        ]
    } else {
        [
            (x.checked_sub(d), Some(y)),
            (x.checked_add(d), Some(y)),
            (Some(x), y.checked_sub(d)),
            (Some(x), y.checked_add(d)),
        ]
    };
    let mut c = 0u16;
    for p in pts {
        if let (Some(px), Some(py)) = p {
            if hier.contains([px, py]) {
                c = c.max(v[index(hier, [px, py])]);
            }
        }
    }
    c
}

/// The largest code of the split points of the children of `m`'s diamond
/// at `level` (above `B(2)`): for `A(s)`, the midpoints of its square's
/// sides; for `B(s)`, the centres of the four `s/2`-squares around it.
#[inline]
fn children_max(hier: &Hierarchy, level: Level, m: Pt, codes: &Codes<'_>) -> u16 {
    let [x, y] = m;
    let (d, diagonal) = match level {
        Level::A(s) => (s / 2, false),
        Level::B(s) => (s / 4, true),
    };
    let pts: [(Option<u32>, Option<u32>); 4] = if diagonal {
        [
            (x.checked_sub(d), y.checked_sub(d)),
            (x.checked_add(d), y.checked_sub(d)),
            (x.checked_sub(d), y.checked_add(d)),
            (x.checked_add(d), y.checked_add(d)),
        ]
    } else {
        [
            (x.checked_sub(d), Some(y)),
            (x.checked_add(d), Some(y)),
            (Some(x), y.checked_sub(d)),
            (Some(x), y.checked_add(d)),
        ]
    };
    let mut c = 0u16;
    for p in pts {
        if let (Some(px), Some(py)) = p {
            if hier.contains([px, py]) {
                c = c.max(codes[index(hier, [px, py])]);
            }
        }
    }
    c
}

/// The closure that bounds a split point's error against the source's own
/// samples ([`crate::tiles::source_error`]): below squares of side `from`,
/// the sum of the lattice error's code `e` and the residuals' closure `d`
/// (a triangle within `e` of the lattice is within `e + d` of the source,
/// see [`crate::tiles::fit`]); from squares of side `from` up, the maximum
/// of the split point's own error against the source, `own`, and its
/// children's. Monotone: each level's value is at least its children's, and
/// at `from` the sums below are at most the maxima above.
pub(crate) fn source_closure(hier: &Hierarchy, [e, d, own]: [&[u16]; 3], from: u32) -> Vec<u16> {
    let mut codes = vec![0u16; own.len()];
    for level in levels(hier.size()) {
        let side = match level {
            Level::A(s) | Level::B(s) => s,
        };
        fill_level(hier, level, &mut codes, |m, codes| {
            let i = index(hier, m);
            if side < from {
                let sum = f64::from(decode(e[i])) + f64::from(decode(d[i]));
                return encode_up(super::round_up_f32(sum));
            }
            let below = if level == Level::B(2) {
                0
            } else {
                children_max(hier, level, m, &codes)
            };
            own[i].max(below)
        });
    }
    codes
}

/// The per-sample codes of `values` (metres, non-negative), rounded up.
pub(crate) fn codes_of(values: &[f32]) -> Vec<u16> {
    values.iter().map(|&v| encode_up(v)).collect()
}

#[cfg(test)]
mod test {
    use super::*;
    use crate::hierarchy::{diamond, Placement};

    /// A single spike: every split point whose diamond or descendants
    /// reach it carries it, and the codes grow up the tree.
    #[test]
    fn a_spike_reaches_exactly_its_ancestors() {
        let (w, h) = (17usize, 17usize);
        let hier = Hierarchy::new(w as u32, h as u32);
        let mut own = vec![0u16; w * h];
        own[5 * w + 6] = encode_up(3.0);
        let d = max_closure(&hier, &own);
        // The root's centre reaches everything.
        assert!(decode(d[8 * w + 8]) >= 3.0);
        // A split point far from the spike does not.
        assert_eq!(d[14 * w + 14], 0);
        // Monotone: each split point at least its children's.
        let n = hier.size();
        for y in 0..h as u32 {
            for x in 0..w as u32 {
                let Some(level) = crate::hierarchy::level_of([x, y], n) else {
                    continue;
                };
                if level == Level::B(2) {
                    continue;
                }
                for t in diamond(level, [x, y], n).into_iter().flatten() {
                    if hier.place(&t) == Placement::Outside {
                        continue;
                    }
                    let (c0, c1) = t.children();
                    for q in [c0.mid(), c1.mid()] {
                        if hier.contains(q) {
                            assert!(
                                d[y as usize * w + x as usize]
                                    >= d[q[1] as usize * w + q[0] as usize]
                            );
                        }
                    }
                }
            }
        }
    }
}
