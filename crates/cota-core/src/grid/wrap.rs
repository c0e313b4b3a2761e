//! Longitudes taken modulo 360°: the whole turns to move each tile of a
//! geographic mosaic by so that tiles on both sides of the antimeridian
//! (an `E179` and a `W180` SRTM tile, say) become neighbours.
//!
//! The tiles' columns are counted on one grid, tile 0's. A turn is the
//! number of columns in 360° (an integer for the grids this is used on).
//! Each tile, in turn, is tried as the westmost one: every other tile is
//! moved by whole turns until its first column lies at or east of that
//! tile's, less than a turn away. The union's width is then the span from
//! that tile's first column to the last column of any tile. The narrowest
//! union wins; ties go to the candidate farthest west in the tiles' own
//! coordinates, so the result does not depend on the tiles' order.
//!
//! The moves are used only when that union is strictly narrower than the
//! tiles' union as they are: any set of tiles that is already contiguous
//! (a footprint that merely touches ±180°, or that lies well inside the
//! world) is laid out exactly as without this step. A union that wraps
//! but stays mostly empty (tiles across both 180° and 0°) is still refused
//! by the mosaic's hole check.
//!
//! # Runtime
//! O(n²) for n tiles, on their column ranges alone.

/// The tiles' first column and width (`(start, width)` each, columns of
/// one grid), and the columns in a turn: the turns to add to each tile's
/// start (`start + turns·turn`) for the narrowest union, or `None` when
/// that union is not narrower than the tiles' union as they are.
pub(crate) fn turns(tiles: &[(i64, i64)], turn: i64) -> Option<Vec<i64>> {
    if tiles.len() < 2 || turn <= 0 {
        return None;
    }
    let span = |starts: &mut dyn Iterator<Item = (i64, i64)>| -> i64 {
        let (lo, hi) = starts.fold((i64::MAX, i64::MIN), |(lo, hi), (s, w)| {
            (lo.min(s), hi.max(s + w))
        });
        hi - lo
    };
    let today = span(&mut tiles.iter().copied());
    // (span, west column, candidate)
    let mut best: Option<(i64, i64, usize)> = None;
    for (i, &(west, _)) in tiles.iter().enumerate() {
        let moved = tiles
            .iter()
            .map(|&(s, w)| (west + (s - west).rem_euclid(turn), w));
        let width = span(&mut moved.into_iter());
        if best.is_none_or(|(b, bw, _)| (width, west) < (b, bw)) {
            best = Some((width, west, i));
        }
    }
    let (width, west, _) = best?;
    (width < today).then(|| {
        tiles
            .iter()
            .map(|&(s, _)| (west + (s - west).rem_euclid(turn) - s) / turn)
            .collect()
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    /// One-degree tiles of 3 columns (a shared edge column) at 2 columns a
    /// degree: a turn is 720 columns.
    fn at(lon: i64) -> (i64, i64) {
        (2 * lon, 3)
    }

    #[test]
    fn tiles_across_the_antimeridian_are_moved_next_to_each_other() {
        // E179 and W180, in either order: W180 moves one turn east.
        assert_eq!(turns(&[at(179), at(-180)], 720), Some(vec![0, 1]));
        assert_eq!(turns(&[at(-180), at(179)], 720), Some(vec![1, 0]));
        // Three tiles, W180 W179 E179: the western ones move east.
        let t = [at(-180), at(179), at(-179)];
        assert_eq!(turns(&t, 720), Some(vec![1, 0, 1]));
    }

    #[test]
    fn contiguous_tiles_are_left_as_they_are() {
        assert_eq!(turns(&[at(10), at(11)], 720), None);
        assert_eq!(turns(&[at(178), at(179)], 720), None);
        assert_eq!(turns(&[at(-180), at(-179)], 720), None);
        assert_eq!(turns(&[at(10)], 720), None);
        // Two tiles half a world apart: no arrangement is narrower.
        assert_eq!(turns(&[at(0), at(180)], 720), None);
    }

    #[test]
    fn tiles_across_both_meridians_are_still_far_apart() {
        // W001 E000 E179 W180: the narrowest union still spans 182°.
        let t = [at(-1), at(0), at(179), at(-180)];
        let k = turns(&t, 720).unwrap();
        let starts: Vec<i64> = t.iter().zip(&k).map(|(a, k)| a.0 + k * 720).collect();
        let width = starts.iter().max().unwrap() + 3 - starts.iter().min().unwrap();
        assert_eq!(width, 2 * 182 + 1);
    }
}
