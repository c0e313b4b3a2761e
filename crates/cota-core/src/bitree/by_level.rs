//! The level-by-level build: one parallel pass over the rows of each level's
//! split points, each point's code from its diamond (a shortcut kernel where
//! one applies, else the general span scan). The build uses it for the levels
//! neither fused nor banded, and the tests take it as the reference every
//! faster path must match (papers `000_ebf7e3a88dffd361.txt` §2 and
//! `001_49f2c365e8c41172.txt`).

use rayon::prelude::*;

use super::error::{diamond_error, Codes};
use super::kernels::{fine_a2, fine_a4, fine_b2, fine_b4, small_a, small_b, SMALL_MAX};
use crate::hierarchy::{first_col, level_rows, level_side, Hierarchy, Level, Pt};

/// Computes `err` for every split point of `level` and writes it into
/// `codes`, in parallel over its rows: the level-by-level build, for the
/// levels neither fused nor banded (see [`Bitree::build`]) and for the tests.
pub(super) fn build_level(heights: &[f32], hier: &Hierarchy, level: Level, codes: &mut [u16]) {
    fill_level(hier, level, codes, |m, codes| {
        point_code(heights, hier, level, m, codes)
    });
}

/// Writes `code(m, codes)` for every split point `m` of `level` into `codes`,
/// computed in parallel over its rows from a read-only view of the codes.
pub(super) fn fill_level(
    hier: &Hierarchy,
    level: Level,
    codes: &mut [u16],
    code: impl Fn(Pt, Codes<'_>) -> u16 + Sync,
) {
    let (w, h) = (hier.width(), hier.height());
    let (first, step) = level_rows(level);
    let rows: Vec<u32> = (first..h).step_by(step as usize).collect();
    let s = level_side(level);
    let computed: Vec<Vec<u16>> = {
        let codes = Codes { c: codes, base: 0 };
        rows.par_iter()
            .map(|&y| {
                let mut out = Vec::with_capacity((w / s + 1) as usize);
                let mut x = first_col(level, y);
                while x < w {
                    out.push(code([x, y], codes));
                    x += s;
                }
                out
            })
            .collect()
    };
    // Write back in parallel, one grid row per task.
    let mut by_row: Vec<Option<Vec<u16>>> = vec![None; h as usize];
    for (&y, row) in rows.iter().zip(computed) {
        by_row[y as usize] = Some(row);
    }
    codes
        .par_chunks_mut(w as usize)
        .zip(by_row.into_par_iter())
        .enumerate()
        .for_each(|(y, (line, row))| {
            if let Some(row) = row {
                let x0 = first_col(level, y as u32) as usize;
                for (slot, e) in line.iter_mut().skip(x0).step_by(s as usize).zip(row) {
                    *slot = e;
                }
            }
        });
}

/// The code of the split point `m` of `level`: a shortcut where one applies,
/// else the general path. Every child's code must be final.
#[inline]
fn point_code(heights: &[f32], hier: &Hierarchy, level: Level, m: Pt, codes: Codes<'_>) -> u16 {
    let fast = match level {
        Level::B(2) => fine_b2(heights, hier, m),
        Level::A(2) => fine_a2(heights, hier, m, codes),
        Level::B(4) => fine_b4(heights, hier, m, codes),
        Level::A(4) => fine_a4(heights, hier, m, codes),
        Level::B(s) if s <= SMALL_MAX => small_b(heights, hier, s, m, codes),
        Level::A(s) if s <= SMALL_MAX => small_a(heights, hier, s, m, codes),
        _ => None,
    };
    fast.unwrap_or_else(|| diamond_error(heights, hier, level, m, codes))
}
