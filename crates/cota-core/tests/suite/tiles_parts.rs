//! Sharded tiling over parts of the lattice (issue 20): a part resampled
//! from a crop of the source holds the whole lattice's heights bit for bit,
//! and its bitree cuts every tile it holds exactly as the whole hierarchy
//! does, for every shard of 1 to 4.
#![allow(clippy::unwrap_used, clippy::panic)]

use cota_core::tiles::plan::plan;
use cota_core::tiles::{
    band_zoom, coarse_level_stats_in, owned_region, part_region, shard_plan, BandCorners,
    CoarseHierarchy, Lattice, LatticeFrame, LatticeOptions, LatticeStats, PartStats, Prepared,
    Shard, SourcePart, TilerOptions,
};
use cota_core::{Crs, GeoRef, HeightGrid, PixelIs};

/// A 1.2°×0.6° geographic grid at 0.002° with ridges at several scales.
fn source() -> HeightGrid {
    let (w, h) = (601, 301);
    let heights = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            400.0
                + 150.0 * (x * 0.031).sin() * (y * 0.043).cos()
                + 25.0 * (x * 0.37 + y * 0.21).sin()
                + 4.0 * ((x * 1.7).sin() * (y * 2.3).cos())
        })
        .collect();
    let georef = GeoRef {
        crs: Crs::WGS84,
        origin_x: 10.3,
        origin_y: 0.9,
        pixel_x: 0.002,
        pixel_y: -0.002,
        pixel_is: PixelIs::Point,
        known: true,
    };
    HeightGrid::new(w, h, heights, georef).unwrap()
}

/// Columns `c0..=c1` and rows `r0..=r1` of `g` as a grid of their own.
fn crop(g: &HeightGrid, [c0, r0, c1, r1]: [usize; 4]) -> HeightGrid {
    let heights = (r0..=r1)
        .flat_map(|r| (c0..=c1).map(move |c| (r, c)))
        .map(|(r, c)| g.get(c, r))
        .collect();
    let mut geo = g.georef().clone();
    geo.origin_x += c0 as f64 * geo.pixel_x;
    geo.origin_y += r0 as f64 * geo.pixel_y;
    HeightGrid::new(c1 - c0 + 1, r1 - r0 + 1, heights, geo).unwrap()
}

#[test]
fn parts_cut_the_tiles_of_the_whole_hierarchy() {
    let src = source();
    let whole = Lattice::resample(&src, &LatticeOptions::DEFAULT).unwrap();
    let opts = TilerOptions::DEFAULT.with_min_zoom(3);
    let prep = Prepared::new(&whole, &src, &opts).unwrap();
    let zooms = plan(&whole, &opts).unwrap();
    let stats = LatticeStats::of(&whole);
    let frame = whole.frame().clone();
    let mut parts_seen = 0;
    for n in 1..=4 {
        let band = band_zoom(&zooms, whole.align_zoom(), n);
        let mut merged = PartStats::default();
        let mut regions = Vec::new();
        let t_band = frame.scheme.cells_at(band);
        let mut corners = BandCorners::new(frame.window, t_band);
        for shard in shard_plan(&zooms, n).unwrap() {
            let shard = shard.from_zoom(band);
            let Some(region) = part_region(&shard, &frame.scheme, frame.window, band, false) else {
                continue;
            };
            let span = frame.source_span(region).unwrap();
            let sub = crop(&src, span);
            let part = SourcePart {
                grid: &sub,
                offset: [span[0], span[1]],
            };
            let lat = Lattice::resample_part(&frame, part, region).unwrap();
            parts_seen += usize::from(lat.is_part());
            merged = merged.merge(PartStats::of(&lat, t_band));
            corners.fill_from(&lat);
            regions.push(region);
            // Bit for bit the whole lattice's heights.
            for r in region[1]..=region[3] {
                for c in region[0]..=region[2] {
                    assert_eq!(
                        lat.height_at(c, r).to_bits(),
                        whole.height_at(c, r).to_bits(),
                        "({c}, {r})"
                    );
                }
            }
            let zs = cota_core::tiles::plan::plan_with(&frame, &stats, &opts).unwrap();
            assert_eq!(zs, zooms);
            let part_prep = Prepared::new_part(&lat, part, zs, &stats).unwrap();
            for t in shard.tiles() {
                assert!(part_prep.holds(t), "{t} n={n}");
                let (a, b) = (
                    prep.cut(t, true, true).unwrap(),
                    part_prep.cut(t, true, true).unwrap(),
                );
                assert_eq!(
                    format!("{:?}", a.mesh),
                    format!("{:?}", b.mesh),
                    "{t} n={n}"
                );
                assert_eq!(a.normals_enu, b.normals_enu, "{t} n={n}");
                assert_eq!(a.water_mask, b.water_mask, "{t} n={n}");
            }
            if lat.is_part() {
                // A tile above the band zoom straddles parts: refused.
                let coarse = prep.tiles().find(|t| t.z < whole.align_zoom());
                if let Some(t) = coarse {
                    assert!(part_prep.cut(t, false, false).is_err(), "{t}");
                }
            }
        }
        // The parts' statistics merge into the whole's, bit for bit: the
        // regions cover every pair of neighbouring samples of the window.
        assert_pairs_covered(&regions, frame.window, n);
        let height = |x: u64, y: u64| corners.height(x, y).unwrap_or(0.0);
        let coarse = coarse_level_stats_in(
            &frame.scheme,
            frame.window,
            frame.align_zoom,
            2 * t_band,
            &height,
        );
        merged.levels = merged.levels.merge(&coarse);
        let (got, want) = (merged.stats(), stats.clone());
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&got.levels.slope), bits(&want.levels.slope), "n={n}");
        assert_eq!(bits(&got.levels.span_m), bits(&want.levels.span_m), "n={n}");
        assert_eq!(got.lo_m.to_bits(), want.lo_m.to_bits(), "n={n}");
        assert_eq!(got.hi_m.to_bits(), want.hi_m.to_bits(), "n={n}");
        assert_eq!(got.max_step_m.to_bits(), want.max_step_m.to_bits(), "n={n}");
    }
    assert!(
        parts_seen >= 4,
        "only {parts_seen} parts smaller than the window"
    );
}

/// Every pair of neighbouring window samples (along a row or a column) lies
/// in one of `regions`.
fn assert_pairs_covered(regions: &[[u64; 4]], w: [u64; 4], n: u32) {
    let holds = |c: u64, r: u64, dc: u64, dr: u64| {
        regions
            .iter()
            .any(|g| g[0] <= c && c + dc <= g[2] && g[1] <= r && r + dr <= g[3])
    };
    for r in w[1]..=w[3] {
        for c in w[0]..=w[2] {
            assert!(
                c == w[2] || holds(c, r, 1, 0),
                "({c}, {r})-({}, {r}) n={n}",
                c + 1
            );
            assert!(
                r == w[3] || holds(c, r, 0, 1),
                "({c}, {r})-({c}, {}) n={n}",
                r + 1
            );
        }
    }
}

#[test]
fn a_part_refuses_a_source_crop_that_misses_what_it_reads() {
    let src = source();
    let whole = Lattice::resample(&src, &LatticeOptions::DEFAULT).unwrap();
    let frame = whole.frame().clone();
    let w = frame.window;
    let t = frame.scheme.cells_at(whole.align_zoom());
    let region = [w[0], w[1], w[2].min(w[0] + 4 * t), w[3]];
    let span = frame.source_span(region).unwrap();
    let sub = crop(&src, [span[0] + 2, span[1], span[2], span[3]]);
    let part = SourcePart {
        grid: &sub,
        offset: [span[0] + 2, span[1]],
    };
    let err = Lattice::resample_part(&frame, part, region).unwrap_err();
    assert!(err.to_string().contains("covering"), "{err}");
}

/// Shard `shard`'s part of the lattice of `src` (band zoom `band`), with
/// the source samples it was resampled from and their offset.
fn part_of(
    src: &HeightGrid,
    frame: &LatticeFrame,
    shard: &Shard,
    band: u8,
    normals: bool,
) -> Option<(Lattice, HeightGrid, [usize; 2])> {
    let region = part_region(shard, &frame.scheme, frame.window, band, normals)?;
    let span = frame.source_span(region).unwrap();
    let sub = crop(src, span);
    let offset = [span[0], span[1]];
    let part = SourcePart { grid: &sub, offset };
    let lat = Lattice::resample_part(frame, part, region).unwrap();
    Some((lat, sub, offset))
}

/// The shards' partial maxima, merged, cut every tile coarser than the band
/// zoom exactly as the whole hierarchy does: meshes, normals and water
/// masks, for 1 to 11 shards (band zooms at and below the alignment zoom),
/// from zoom 0 (the cap's levels) on.
#[test]
fn merged_partial_maxima_cut_the_coarse_tiles_of_the_whole_hierarchy() {
    let mut src = source();
    // Some samples at or below sea level, for the water masks.
    let lowered: Vec<f32> = src.heights().iter().map(|h| h - 430.0).collect();
    src = HeightGrid::new(src.width(), src.height(), lowered, src.georef().clone()).unwrap();
    let lopts = LatticeOptions::DEFAULT.with_tile_cells(16);
    let whole = Lattice::resample(&src, &lopts).unwrap();
    let opts = TilerOptions::DEFAULT;
    let prep = Prepared::new(&whole, &src, &opts).unwrap();
    let zooms = plan(&whole, &opts).unwrap();
    let stats = LatticeStats::of(&whole);
    let frame = whole.frame().clone();
    let mut below_align = 0;
    for n in [1, 2, 3, 5, 8, 11] {
        let band = band_zoom(&zooms, whole.align_zoom(), n);
        below_align += usize::from(band > whole.align_zoom());
        let mut corners = BandCorners::new(frame.window, frame.scheme.cells_at(band));
        let mut partials = Vec::new();
        for shard in shard_plan(&zooms, n).unwrap() {
            let shard = shard.from_zoom(band);
            let Some((lat, sub, offset)) = part_of(&src, &frame, &shard, band, true) else {
                continue;
            };
            corners.fill_from(&lat);
            let owned = owned_region(&shard, &frame.scheme, band).unwrap();
            partials.push((lat, sub, offset, owned));
        }
        let mut got = Vec::new();
        for (lat, sub, offset, owned) in &partials {
            let source = SourcePart {
                grid: sub,
                offset: *offset,
            };
            let part_prep = Prepared::new_part(lat, source, zooms.clone(), &stats).unwrap();
            got.push(
                part_prep
                    .coarse_partial(*owned, band, &corners, source, true, true)
                    .unwrap(),
            );
        }
        let merged =
            CoarseHierarchy::new(&frame, &stats, zooms.clone(), band, corners, got).unwrap();
        let mut cut = 0;
        for t in merged.tiles() {
            let (a, b) = (
                prep.cut(t, true, true).unwrap(),
                merged.cut(t, true, true).unwrap(),
            );
            assert_eq!(
                format!("{:?}", a.mesh),
                format!("{:?}", b.mesh),
                "{t} n={n}"
            );
            assert_eq!(a.normals_enu, b.normals_enu, "{t} n={n}");
            assert_eq!(a.water_mask, b.water_mask, "{t} n={n}");
            assert_eq!(a.children, b.children, "{t} n={n}");
            cut += 1;
        }
        assert_eq!(cut, prep.tiles().filter(|t| t.z < band).count(), "n={n}");
    }
    assert!(below_align > 0, "no band zoom below the alignment zoom");
}

/// A lost partial is refused, not silently cut as flat terrain.
#[test]
fn a_missing_partial_is_refused() {
    let src = source();
    let whole = Lattice::resample(&src, &LatticeOptions::DEFAULT).unwrap();
    let zooms = plan(&whole, &TilerOptions::DEFAULT).unwrap();
    let stats = LatticeStats::of(&whole);
    let frame = whole.frame().clone();
    let band = band_zoom(&zooms, whole.align_zoom(), 3);
    let mut corners = BandCorners::new(frame.window, frame.scheme.cells_at(band));
    corners.fill_from(&whole);
    let shards = shard_plan(&zooms, 3).unwrap();
    let mut partials = Vec::new();
    for shard in shards.iter().skip(1) {
        let shard = shard.from_zoom(band);
        let (lat, sub, offset) = part_of(&src, &frame, &shard, band, false).unwrap();
        let owned = owned_region(&shard, &frame.scheme, band).unwrap();
        let source = SourcePart { grid: &sub, offset };
        let p = Prepared::new_part(&lat, source, zooms.clone(), &stats).unwrap();
        partials.push(
            p.coarse_partial(owned, band, &corners, source, false, false)
                .unwrap(),
        );
    }
    let err = CoarseHierarchy::new(&frame, &stats, zooms, band, corners, partials).unwrap_err();
    assert!(err.to_string().contains("missing"), "{err}");
}
