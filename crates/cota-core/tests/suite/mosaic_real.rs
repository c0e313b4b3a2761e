//! Mosaics (`cota_core::mosaic`) of real adjacent SRTM tiles, as paper 001
//! merges adjacent `.hgt` tiles into one region: the three adjacent pairs of
//! the shared data (west–east at the equator, south–north in the Pyrenees and in
//! Bavaria), input order, a 2×2 arrangement with a missing tile (fabricated by
//! moving a tile's georeference) whose hole is then filled, and the refusals
//! (different resolution, tiles far apart, no georeference).

#![allow(clippy::unwrap_used, clippy::panic, reason = "tests fail loudly")]

use crate::common;

use std::time::Instant;

use cota_core::grid::mosaic::{mosaic, Mosaic, MosaicError, MosaicOptions, SeamPolicy};
use cota_core::grid::voids::{fill_voids, FillOptions};
use cota_core::{GeoRef, GridError, HeightGrid};

/// Reads the named SRTM tiles, or `None` when the shared data is absent.
fn tiles(names: &[&str]) -> Option<Vec<HeightGrid>> {
    names.iter().map(|n| common::shared_srtm(n)).collect()
}

fn same(a: f32, b: f32) -> bool {
    a == b || (a.is_nan() && b.is_nan())
}

/// Asserts that `tile` appears unchanged in `m` at output (`col`, `row`).
fn assert_placed(m: &Mosaic, tile: &HeightGrid, col: usize, row: usize, name: &str) {
    for r in 0..tile.height() {
        for c in 0..tile.width() {
            let (a, b) = (m.grid.get(col + c, row + r), tile.get(c, r));
            assert!(
                same(a, b),
                "{name}: tile ({c},{r}) = {b}, mosaic ({},{}) = {a}",
                col + c,
                row + r
            );
        }
    }
}

fn print_report(label: &str, m: &Mosaic, ms: f64) {
    let s = &m.seams;
    println!(
        "{label}: {}x{} in {ms:.1} ms; seam: {} overlapping samples, {} compared, max diff {} m{}, mean diff {} m; holes {}",
        m.grid.width(),
        m.grid.height(),
        s.overlap_samples,
        s.compared,
        s.max_abs_diff_m,
        s.max_diff_at
            .map(|p| format!(" at ({:.5}, {:.5}) between tiles {} and {}", p.x, p.y, p.tiles[0], p.tiles[1]))
            .unwrap_or_default(),
        s.mean_abs_diff_m,
        m.hole_samples
    );
}

/// Mosaics an adjacent pair in both orders and checks size, origin, the shared
/// edge, and that each tile appears unchanged at its offset.
/// `offset` is the (column, row) of the second tile when the first is at (0, 0)
/// or vice versa (negative components mean the first tile is east/south of it).
fn check_pair(names: [&str; 2], size: (usize, usize), origin: (f64, f64), at: [(usize, usize); 2]) {
    let Some(ts) = tiles(&names) else { return };
    let input = ts.clone();
    let t = Instant::now();
    let m = mosaic(input, &MosaicOptions::DEFAULT).unwrap();
    let label = format!("{} + {}", names[0], names[1]);
    print_report(&label, &m, t.elapsed().as_secs_f64() * 1e3);
    assert_eq!((m.grid.width(), m.grid.height()), size, "{label}");
    let g = m.grid.georef();
    assert_eq!((g.origin_x, g.origin_y), origin, "{label}");
    assert_eq!((g.pixel_x, g.pixel_y), (1.0 / 1200.0, -1.0 / 1200.0));
    assert_eq!(g.crs, ts[0].georef().crs);
    assert_eq!(m.hole_samples, 0);
    assert_eq!(m.seams.overlap_samples, 1201, "{label}: one shared edge");
    assert_eq!(
        m.seams.max_abs_diff_m, 0.0,
        "{label}: the shared edge is identical in both files"
    );
    assert_eq!(m.seams.max_diff_at, None);
    for (i, (tile, &(col, row))) in ts.iter().zip(&at).enumerate() {
        assert_eq!(
            (m.placements[i].col, m.placements[i].row),
            (col, row),
            "{label}"
        );
        assert_placed(&m, tile, col, row, names[i]);
    }
    // Input order does not matter for the placement (nor, with identical
    // edges, for the values).
    let reversed = mosaic(vec![ts[1].clone(), ts[0].clone()], &MosaicOptions::DEFAULT).unwrap();
    assert_eq!(reversed.grid.georef(), m.grid.georef());
    assert_eq!(
        (reversed.placements[0].col, reversed.placements[0].row),
        at[1]
    );
    assert_eq!(
        (reversed.placements[1].col, reversed.placements[1].row),
        at[0]
    );
    assert!(reversed
        .grid
        .heights()
        .iter()
        .zip(m.grid.heights())
        .all(|(a, b)| same(*a, *b)));
    assert_eq!(reversed.seams.compared, m.seams.compared);
}

#[test]
fn west_east_n00e010_n00e011() {
    check_pair(
        ["N00E010.hgt", "N00E011.hgt.zip"],
        (2401, 1201),
        (10.0, 1.0),
        [(0, 0), (1200, 0)],
    );
}

#[test]
fn south_north_n41e001_n42e001() {
    check_pair(
        ["N41E001.hgt.zip", "N42E001.hgt.zip"],
        (1201, 2401),
        (1.0, 43.0),
        [(0, 1200), (0, 0)],
    );
}

#[test]
fn south_north_n49e011_n50e011() {
    check_pair(
        ["N49E011.hgt.zip", "N50E011.hgt.zip"],
        (1201, 2401),
        (11.0, 51.0),
        [(0, 1200), (0, 0)],
    );
}

#[test]
fn shared_column_equals_both_tiles() {
    let Some(ts) = tiles(&["N00E010.hgt", "N00E011.hgt.zip"]) else {
        return;
    };
    for policy in [SeamPolicy::Mean, SeamPolicy::First] {
        let m = mosaic(ts.clone(), &MosaicOptions::DEFAULT.with_seam_policy(policy)).unwrap();
        for r in 0..1201 {
            assert_eq!(m.grid.get(1200, r), ts[0].get(1200, r));
            assert_eq!(m.grid.get(1200, r), ts[1].get(0, r));
        }
        assert_eq!(m.seams.compared, 1201);
    }
}

/// A copy of `tile` whose georeference is moved by (`dlon`, `dlat`) degrees.
fn moved(tile: &HeightGrid, dlon: f64, dlat: f64) -> HeightGrid {
    let mut t = tile.clone();
    let mut g = t.georef().clone();
    g.origin_x += dlon;
    g.origin_y += dlat;
    t.set_georef(g);
    t
}

#[test]
fn two_by_two_with_a_missing_tile_then_filled() {
    let Some(ts) = tiles(&["N00E010.hgt", "N00E011.hgt.zip", "N41E001.hgt.zip"]) else {
        return;
    };
    // N41E001 moved to S01E010, below N00E010; S01E011 is missing.
    let south_west = moved(&ts[2], 9.0, -42.0);
    let set = vec![ts[0].clone(), ts[1].clone(), south_west.clone()];
    let t = Instant::now();
    let m = mosaic(set, &MosaicOptions::DEFAULT).unwrap(); // the set was built before timing
    print_report(
        "N00E010 + N00E011 + N41E001 moved to S01E010",
        &m,
        t.elapsed().as_secs_f64() * 1e3,
    );
    assert_eq!((m.grid.width(), m.grid.height()), (2401, 2401));
    assert_eq!(
        (m.grid.georef().origin_x, m.grid.georef().origin_y),
        (10.0, 1.0)
    );
    assert_eq!(m.hole_samples, 1200 * 1200);
    for r in 1201..2401 {
        for c in 1201..2401 {
            assert!(m.grid.get(c, r).is_nan());
        }
    }
    // Two seams: the shared column of the northern pair (identical) and the
    // shared row of N00E010 and the moved tile (real terrain 42° apart).
    assert_eq!(m.seams.overlap_samples, 1201 + 1201 - 1);
    assert!(m.seams.max_abs_diff_m > 0.0);
    let at = m.seams.max_diff_at.unwrap();
    assert_eq!(at.row, 1200);
    assert!(at.tiles.contains(&2), "{at:?}");
    // Under the first-wins policy every given tile appears unchanged (the
    // corner shared by three tiles is averaged under the default policy).
    let first = MosaicOptions::DEFAULT.with_seam_policy(SeamPolicy::First);
    let f = mosaic(
        vec![ts[0].clone(), ts[1].clone(), south_west.clone()],
        &first,
    )
    .unwrap();
    assert_placed(&f, &ts[0], 0, 0, "N00E010");
    assert_placed(&f, &ts[1], 1200, 0, "N00E011");
    let corner = (ts[0].get(1200, 1200) + ts[1].get(0, 1200) + south_west.get(1200, 0)) / 3.0;
    assert!((m.grid.get(1200, 1200) - corner).abs() < 1e-3);
    // Placement does not depend on the order.
    let permuted = mosaic(
        vec![south_west, ts[1].clone(), ts[0].clone()],
        &MosaicOptions::DEFAULT,
    )
    .unwrap();
    assert_eq!(permuted.grid.georef(), m.grid.georef());
    assert_eq!(permuted.hole_samples, m.hole_samples);
    assert_eq!(
        (permuted.placements[0].col, permuted.placements[0].row),
        (0, 1200)
    );
    assert!(permuted
        .grid
        .heights()
        .iter()
        .zip(m.grid.heights())
        .all(|(a, b)| same(*a, *b)));

    // The hole is one 1200x1200 void bordered by real terrain: fill it.
    let mut grid = m.grid;
    let border = border_range(&grid);
    let voids = grid.void_count();
    let t = Instant::now();
    let report = fill_voids(&mut grid, &FillOptions::DEFAULT).unwrap();
    println!(
        "filling the mosaic: {} voids in {} components (largest {}) in {:.0} ms, {} cycles, {} sweeps in all, converged {}",
        report.filled,
        report.components,
        report.largest_component,
        t.elapsed().as_secs_f64() * 1e3,
        report.max_iterations_used,
        report.total_sweeps,
        report.converged
    );
    assert_eq!(report.filled, voids);
    assert!(report.largest_component >= 1200 * 1200);
    assert_eq!(grid.void_count(), 0);
    let (lo, hi) = border;
    for r in 1201..2401 {
        for c in 1201..2401 {
            let v = grid.get(c, r);
            assert!(v >= lo && v <= hi, "({c},{r}) = {v} outside [{lo}, {hi}]");
        }
    }
}

/// Range of the valid samples 4-adjacent to a void.
fn border_range(g: &HeightGrid) -> (f32, f32) {
    let (w, h) = (g.width(), g.height());
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for r in 0..h {
        for c in 0..w {
            let v = g.get(c, r);
            if v.is_nan() {
                continue;
            }
            let near_void = (c > 0 && g.get(c - 1, r).is_nan())
                || (c + 1 < w && g.get(c + 1, r).is_nan())
                || (r > 0 && g.get(c, r - 1).is_nan())
                || (r + 1 < h && g.get(c, r + 1).is_nan());
            if near_void {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
    }
    (lo, hi)
}

#[test]
fn different_resolution_is_refused() {
    let Some(ts) = tiles(&["N00E010.hgt", "N00E011.hgt.zip"]) else {
        return;
    };
    // A fabricated 1" copy of N00E011: same samples, a third of the spacing.
    let mut fine = ts[1].clone();
    let mut g = fine.georef().clone();
    g.pixel_x = 1.0 / 3600.0;
    g.pixel_y = -1.0 / 3600.0;
    fine.set_georef(g);
    let err = mosaic(vec![ts[0].clone(), fine], &MosaicOptions::DEFAULT).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.contains("tiles of different resolution: 1/1200° vs 1/3600°"),
        "{msg}"
    );
    assert!(msg.contains("resampling is not supported"), "{msg}");
    println!("{msg}");
}

#[test]
fn misaligned_tile_is_refused() {
    let Some(ts) = tiles(&["N00E010.hgt", "N00E011.hgt.zip"]) else {
        return;
    };
    let half_pixel = moved(&ts[1], 0.5 / 1200.0, 0.0);
    let err = mosaic(vec![ts[0].clone(), half_pixel], &MosaicOptions::DEFAULT).unwrap_err();
    assert!(
        matches!(err, MosaicError::NotAligned { index: 1, .. }),
        "{err}"
    );
    println!("{err}");
}

#[test]
fn far_apart_tiles_are_refused_before_allocating() {
    let Some(ts) = tiles(&["N00E010.hgt", "N50E011.hgt.zip", "S29W072.hgt.zip"]) else {
        return;
    };
    // 2401 x 61201 samples, 98% of them holes: refused by the hole guard.
    let err = mosaic(vec![ts[0].clone(), ts[1].clone()], &MosaicOptions::DEFAULT).unwrap_err();
    assert!(
        matches!(
            err,
            MosaicError::TooSparse {
                width: 2401,
                height: 61201,
                ..
            }
        ),
        "{err}"
    );
    println!("{err}");
    // 98401 x 34801 samples: more than any grid may hold, even with holes allowed.
    let anything = MosaicOptions::DEFAULT.with_max_hole_fraction(1.0);
    let err = mosaic(vec![ts[0].clone(), ts[2].clone()], &anything).unwrap_err();
    assert!(
        matches!(err, MosaicError::Grid(GridError::TooLarge { .. })),
        "{err}"
    );
    println!("{err}");
}

#[test]
fn unreferenced_tile_is_refused() {
    let Some(ts) = tiles(&["N00E010.hgt"]) else {
        return;
    };
    let mut png_like = ts[0].clone();
    png_like.set_georef(GeoRef::unreferenced(92.6));
    let err = mosaic(vec![ts[0].clone(), png_like], &MosaicOptions::DEFAULT).unwrap_err();
    assert_eq!(err, MosaicError::Unreferenced { index: 1 });
}

#[test]
fn single_tile_is_returned_as_is() {
    let Some(ts) = tiles(&["N42E001.hgt.zip"]) else {
        return;
    };
    let m = mosaic(ts.clone(), &MosaicOptions::DEFAULT).unwrap();
    assert!(m
        .grid
        .heights()
        .iter()
        .zip(ts[0].heights())
        .all(|(a, b)| same(*a, *b)));
    assert_eq!(m.grid.georef(), ts[0].georef());
    assert_eq!(m.seams.compared, 0);
}
