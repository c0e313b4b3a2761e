//! The shard plan: a deterministic split of a pyramid's tiles into `N`
//! disjoint parts aligned to the tile grid, so that `N` processes (or
//! machines) can each write one part into the same directory.
//!
//! Reference: the tiling of paper `001_49f2c365e8c41172.txt` (one hierarchy
//! over a mosaic), on the geographic TMS of the quantized-mesh-1.0
//! specification (CesiumGS/quantized-mesh).
//!
//! The finest zoom's range is cut along its longer axis (columns, or TMS
//! rows) into `N` bands of (nearly) equal width: band `i` holds the positions
//! `⌊i·L/N⌋ .. ⌊(i+1)·L/N⌋` of the `L` along that axis. A tile of a coarser
//! zoom `z` at position `p` goes to the shard whose band holds its first
//! descendant at the finest zoom, `p·2^(max−z)` (clamped into the range), so
//! every tile of every zoom belongs to exactly one shard, and a shard's
//! tiles at each zoom are one rectangle (a [`TileRange`]). The plan depends
//! only on the zooms' ranges and `N`: every process computes the same one.
//! A shard may be empty when `N` exceeds the bands the range allows.
//!
//! # Parts of the lattice
//! The tiles of the *band zoom* ([`band_zoom`]: the coarsest zoom whose
//! tiles are at most a quarter of a band, and not coarser than the lattice's
//! alignment zoom) and finer are cut by each shard from its own part of the
//! lattice ([`part_region`]): the squares of its tiles there, grown by half a
//! band-zoom tile (the reach of their split points' diamonds) and rounded
//! outwards to band-zoom tiles with the global diagonals. The tiles coarser
//! than the band zoom straddle bands; they need the whole lattice.

use super::cut::NORMAL_REACH_CELLS;
use super::error::TilesError;
use super::plan::{TileRange, ZoomPlan};
use super::scheme::{GeographicScheme, TileId};

/// One shard's part of the pyramid.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Shard {
    /// This shard, `0..shards`.
    pub index: u32,
    /// The number of shards.
    pub shards: u32,
    /// Its share of the window's tiles, zoom by zoom, coarse to fine (zooms
    /// where it has none are left out): what its part of the lattice and
    /// its owned squares follow.
    pub ranges: Vec<(u8, TileRange)>,
    /// The tiles it makes: its ranges' tiles that meet the data.
    pub made: Vec<(u8, TileRange)>,
}

impl Shard {
    /// True when tile `t` is one this shard makes.
    pub fn contains(&self, t: TileId) -> bool {
        self.made
            .iter()
            .any(|(z, r)| *z == t.z && r.contains(t.x, t.y))
    }

    /// Number of tiles it makes.
    pub fn tile_count(&self) -> u64 {
        self.made.iter().map(|(_, r)| r.count()).sum()
    }

    /// The tiles it makes, zoom by zoom (rows, then columns, as
    /// [`super::Prepared::tiles`] orders them). Like every range of the
    /// plan, these are lattice tiles: [`GeographicScheme::address`] gives
    /// their addresses (the same unless the lattice counts from 0°).
    pub fn tiles(&self) -> impl Iterator<Item = TileId> + '_ {
        self.made.iter().flat_map(|&(z, r)| {
            (r.y0..=r.y1).flat_map(move |y| (r.x0..=r.x1).map(move |x| TileId { z, x, y }))
        })
    }
}

impl Shard {
    /// The same shard without its tiles coarser than zoom `z`.
    pub fn from_zoom(&self, z: u8) -> Shard {
        let keep = |v: &[(u8, TileRange)]| v.iter().filter(|(k, _)| *k >= z).copied().collect();
        Shard {
            ranges: keep(&self.ranges),
            made: keep(&self.made),
            ..self.clone()
        }
    }
}

/// The band zoom of `shards` shards over `zooms` (coarse to fine) on a
/// lattice of alignment zoom `align_zoom`: the coarsest zoom, not coarser
/// than `align_zoom` nor the first of `zooms`, whose tiles span at most a
/// quarter of the narrowest band (at least the finest zoom).
pub fn band_zoom(zooms: &[ZoomPlan], align_zoom: u8, shards: u32) -> u8 {
    let (Some(first), Some(finest)) = (zooms.first(), zooms.last()) else {
        return align_zoom;
    };
    let f = finest.window_range;
    let len = (f.x1 - f.x0).max(f.y1 - f.y0) + 1;
    let band = len / shards.max(1);
    let mut z = finest.zoom;
    while z > first.zoom.max(align_zoom) && (1u32 << (finest.zoom - z + 1)) <= band / 4 {
        z -= 1;
    }
    z
}

/// The region (`[x0, y0, x1, y1]` global lattice, inclusive) of the window
/// `window` that `shard`'s tiles of zoom `band` and finer need (see the
/// module docs), and with `normals` what the normals of its vertices of
/// coarser tiles read ([`NORMAL_REACH_CELLS`]); `None` when it has none
/// there.
pub fn part_region(
    shard: &Shard,
    scheme: &GeographicScheme,
    window: [u64; 4],
    band: u8,
    normals: bool,
) -> Option<[u64; 4]> {
    let t = scheme.cells_at(band);
    let mut bbox: Option<[u64; 4]> = None;
    for &(z, r) in shard.ranges.iter().filter(|(z, _)| *z >= band) {
        let c = scheme.cells_at(z);
        let ny = u64::from(GeographicScheme::tiles_at(z)[1]);
        let sq = [
            u64::from(r.x0) * c,
            (ny - 1 - u64::from(r.y1)) * c,
            (u64::from(r.x1) + 1) * c,
            (ny - u64::from(r.y0)) * c,
        ];
        bbox = Some(bbox.map_or(sq, |b| {
            [
                b[0].min(sq[0]),
                b[1].min(sq[1]),
                b[2].max(sq[2]),
                b[3].max(sq[3]),
            ]
        }));
    }
    let b = bbox?;
    // Half a band tile (the split points' reach), and with `normals` the
    // normals' reach (the coarse tiles' vertex normals, computed by the
    // shards).
    let g = if normals {
        (t / 2).max(NORMAL_REACH_CELLS)
    } else {
        t / 2
    };
    let lo = |v: u64, min: u64| (v.saturating_sub(g) / t * t).max(min);
    let hi = |v: u64, max: u64| ((v + g).div_ceil(t) * t).min(max);
    let (mut x0, mut y0) = (lo(b[0], window[0]), lo(b[1], window[1]));
    let (x1, y1) = (hi(b[2], window[2]), hi(b[3], window[3]));
    // The global diagonals: `(x0 + y0) / t` even (the window's origin is).
    if !(x0 / t + y0 / t).is_multiple_of(2) {
        if x0 >= window[0] + t {
            x0 -= t;
        } else {
            y0 -= t;
        }
    }
    Some([x0, y0, x1, y1])
}

/// The samples whose coarse maxima `shard` computes ([`super::partial`]):
/// the squares of its tiles at zoom `band`, `[x0, y0, x1, y1]` inclusive
/// (global lattice), `None` when it has none there. The shards' regions
/// cover the window (the band zoom's tiles are the window's).
pub fn owned_region(shard: &Shard, scheme: &GeographicScheme, band: u8) -> Option<[u64; 4]> {
    let (_, r) = shard.ranges.iter().find(|(z, _)| *z == band)?;
    let c = scheme.cells_at(band);
    let ny = u64::from(GeographicScheme::tiles_at(band)[1]);
    Some([
        u64::from(r.x0) * c,
        (ny - 1 - u64::from(r.y1)) * c,
        (u64::from(r.x1) + 1) * c,
        (ny - u64::from(r.y0)) * c,
    ])
}

/// The band of each position along the cut axis at the finest zoom:
/// the shard of finest position `q` (`start..start+len`).
fn band_of(q: u64, start: u64, len: u64, shards: u64) -> u32 {
    let k = q.clamp(start, start + len - 1) - start;
    // The largest i with ⌊i·len/shards⌋ ≤ k.
    let mut i = (k * shards) / len;
    while i + 1 < shards && ((i + 1) * len) / shards <= k {
        i += 1;
    }
    while i > 0 && (i * len) / shards > k {
        i -= 1;
    }
    i as u32
}

/// The plan of `shards` shards over the zooms `zooms` (coarse to fine, as
/// [`super::Prepared::zooms`] or [`super::plan::plan`] give them).
///
/// # Errors
/// [`TilesError::BadOptions`] when `shards` is 0 or `zooms` is empty.
pub fn shard_plan(zooms: &[ZoomPlan], shards: u32) -> Result<Vec<Shard>, TilesError> {
    let Some(finest) = zooms.last() else {
        return Err(TilesError::BadOptions(
            "expected at least one zoom to shard, found none".into(),
        ));
    };
    if shards == 0 {
        return Err(TilesError::BadOptions(
            "expected at least one shard, found 0".into(),
        ));
    }
    let f = finest.window_range;
    let by_columns = f.x1 - f.x0 >= f.y1 - f.y0;
    let (start, len) = if by_columns {
        (u64::from(f.x0), u64::from(f.x1 - f.x0) + 1)
    } else {
        (u64::from(f.y0), u64::from(f.y1 - f.y0) + 1)
    };
    let bands = Bands {
        by_columns,
        start,
        len,
        shards: u64::from(shards),
        finest: finest.zoom,
    };
    let mut out: Vec<Shard> = (0..shards)
        .map(|index| Shard {
            index,
            shards,
            ranges: Vec::new(),
            made: Vec::new(),
        })
        .collect();
    for p in zooms {
        for (owner, part) in bands.split(p) {
            let shard = &mut out[owner as usize];
            shard.ranges.push((p.zoom, part));
            if let Some(made) = intersect(part, p.range) {
                shard.made.push((p.zoom, made));
            }
        }
    }
    Ok(out)
}

/// The tiles in both ranges, if any.
fn intersect(a: TileRange, b: TileRange) -> Option<TileRange> {
    let r = TileRange {
        x0: a.x0.max(b.x0),
        x1: a.x1.min(b.x1),
        y0: a.y0.max(b.y0),
        y1: a.y1.min(b.y1),
    };
    (r.x0 <= r.x1 && r.y0 <= r.y1).then_some(r)
}

/// The cut of the finest zoom's range into bands.
struct Bands {
    by_columns: bool,
    start: u64,
    len: u64,
    shards: u64,
    finest: u8,
}

impl Bands {
    /// The shard of position `pos` at `zoom`.
    fn owner(&self, pos: u32, zoom: u8) -> u32 {
        let q = u64::from(pos) << u32::from(self.finest - zoom);
        band_of(q, self.start, self.len, self.shards)
    }

    /// Zoom `p`'s window range as (shard, rectangle) runs along the cut axis.
    fn split(&self, p: &ZoomPlan) -> Vec<(u32, TileRange)> {
        let r = p.window_range;
        let (a, b) = if self.by_columns {
            (r.x0, r.x1)
        } else {
            (r.y0, r.y1)
        };
        let mut parts = Vec::new();
        let mut pos = a;
        while pos <= b {
            let owner = self.owner(pos, p.zoom);
            let mut end = pos;
            while end < b && self.owner(end + 1, p.zoom) == owner {
                end += 1;
            }
            let part = if self.by_columns {
                TileRange {
                    x0: pos,
                    x1: end,
                    ..r
                }
            } else {
                TileRange {
                    y0: pos,
                    y1: end,
                    ..r
                }
            };
            parts.push((owner, part));
            pos = end + 1;
        }
        parts
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn zoom(z: u8, x0: u32, x1: u32, y0: u32, y1: u32) -> ZoomPlan {
        ZoomPlan {
            zoom: z,
            range: TileRange { x0, x1, y0, y1 },
            window_range: TileRange { x0, x1, y0, y1 },
            max_error_m: 1.0,
            margin_m: 0.1,
            threshold_m: 0.9,
        }
    }

    fn pyramid() -> Vec<ZoomPlan> {
        vec![
            zoom(0, 0, 1, 0, 0),
            zoom(1, 1, 1, 0, 1),
            zoom(2, 2, 3, 1, 2),
            zoom(3, 5, 7, 3, 4),
            zoom(4, 11, 15, 7, 8),
        ]
    }

    #[test]
    fn every_tile_in_exactly_one_shard() {
        let zooms = pyramid();
        let all: Vec<TileId> = zooms
            .iter()
            .flat_map(|p| {
                let r = p.range;
                (r.y0..=r.y1)
                    .flat_map(move |y| (r.x0..=r.x1).map(move |x| TileId { z: p.zoom, x, y }))
            })
            .collect();
        for n in 1..=7 {
            let plan = shard_plan(&zooms, n).unwrap();
            assert_eq!(plan.len(), n as usize);
            for t in &all {
                assert_eq!(
                    plan.iter().filter(|s| s.contains(*t)).count(),
                    1,
                    "{t} n={n}"
                );
            }
            let total: u64 = plan.iter().map(Shard::tile_count).sum();
            assert_eq!(total, all.len() as u64);
            assert_eq!(plan, shard_plan(&zooms, n).unwrap(), "deterministic");
        }
    }

    #[test]
    fn finest_zoom_bands_are_balanced() {
        let plan = shard_plan(&pyramid(), 2).unwrap();
        let finest: Vec<u64> = plan
            .iter()
            .map(|s| {
                s.ranges
                    .iter()
                    .filter(|(z, _)| *z == 4)
                    .map(|(_, r)| r.count())
                    .sum()
            })
            .collect();
        assert_eq!(finest, vec![4, 6]);
        // A coarse tile goes with its first finest descendant.
        assert!(plan[0].contains(TileId { z: 0, x: 0, y: 0 }));
        assert!(plan[0].contains(TileId { z: 3, x: 6, y: 3 }));
        assert!(plan[1].contains(TileId { z: 3, x: 7, y: 3 }));
    }

    #[test]
    fn zero_shards_refused() {
        assert!(shard_plan(&pyramid(), 0).is_err());
        assert!(shard_plan(&[], 2).is_err());
    }
}
