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
use super::error_code::encode_up;
use crate::hierarchy::{diamond, levels, Hierarchy, Level, Placement, Pt};

/// For every split point of `hier`'s grid (`W × H`, row-major), the code
/// ([`super::error_code`]) of the largest `own` value over the samples of
/// its diamond's triangles that meet the grid and of all their
/// descendants. `own` holds one code per sample.
pub(crate) fn max_closure(hier: &Hierarchy, own: &[u16]) -> Vec<u16> {
    let mut codes = vec![0u16; own.len()];
    let (w, n) = (hier.width() as usize, hier.size());
    let at = |p: Pt| p[1] as usize * w + p[0] as usize;
    for level in levels(n) {
        fill_level(hier, level, &mut codes, |m, codes| {
            let mut c = 0u16;
            for t in diamond(level, m, n).into_iter().flatten() {
                if hier.place(&t) == Placement::Outside {
                    continue;
                }
                if level == Level::B(2) {
                    for p in [t.a, t.b, t.c, m] {
                        if hier.contains(p) {
                            c = c.max(own[at(p)]);
                        }
                    }
                    continue;
                }
                let (c0, c1) = t.children();
                for q in [c0.mid(), c1.mid()] {
                    if hier.contains(q) {
                        c = c.max(codes[at(q)]);
                    }
                }
            }
            c
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
    use super::super::error_code::decode;
    use super::*;

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
