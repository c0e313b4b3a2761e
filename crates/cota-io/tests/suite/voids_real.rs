//! Void filling (`cota_core::grid::voids`) on real DEMs with voids: the Pyrenees SRTM
//! tile N42E001 (7652 voids), an SRTM GeoTIFF of Mt Fuji (2437), Luxembourg
//! (3942 of 8550 samples, its outside is nodata) and a 10 m ASCII grid (2028 of
//! 4180). After a harmonic fill no NaN remains, every filled sample lies within
//! the range of its void's border (maximum principle), and the default tolerance
//! is met against a much tighter solve. Times are printed, not asserted.
//! (These tests stay in cota-io: two of their grids are GeoTIFFs, which only
//! cota-io reads; `cota-fixtures` reads SRTM and ASCII grids only.)

#![allow(clippy::unwrap_used, clippy::panic, reason = "tests fail loudly")]

use crate::common;

use std::path::Path;
use std::time::Instant;

use common::shared_data;
use cota_core::grid::voids::{fill_voids, FillMethod, FillOptions, FillReport, VoidPolicy};
use cota_core::{GridError, HeightGrid};
use cota_io::{read_dem, ReadOptions};

fn read(path: &Path) -> HeightGrid {
    read_dem(path, &ReadOptions::DEFAULT)
        .unwrap_or_else(|e| panic!("{e}"))
        .grid
}

/// For every 4-connected void component of `g`: its samples (indices) and the
/// range of the valid samples 4-adjacent to it. Written independently of the
/// library's own component search.
fn components_with_border_range(g: &HeightGrid) -> Vec<(Vec<usize>, f32, f32)> {
    let (w, h) = (g.width(), g.height());
    let hs = g.heights();
    let mut label = vec![usize::MAX; hs.len()];
    let mut out = Vec::new();
    for start in 0..hs.len() {
        if !hs[start].is_nan() || label[start] != usize::MAX {
            continue;
        }
        let id = out.len();
        let (mut cells, mut lo, mut hi) = (Vec::new(), f32::INFINITY, f32::NEG_INFINITY);
        let mut queue = vec![start];
        label[start] = id;
        while let Some(i) = queue.pop() {
            cells.push(i);
            let (x, y) = (i % w, i / w);
            let mut nbs = Vec::with_capacity(4);
            if x > 0 {
                nbs.push(i - 1);
            }
            if x + 1 < w {
                nbs.push(i + 1);
            }
            if y > 0 {
                nbs.push(i - w);
            }
            if y + 1 < h {
                nbs.push(i + w);
            }
            for j in nbs {
                if hs[j].is_nan() {
                    if label[j] == usize::MAX {
                        label[j] = id;
                        queue.push(j);
                    }
                } else {
                    lo = lo.min(hs[j]);
                    hi = hi.max(hs[j]);
                }
            }
        }
        out.push((cells, lo, hi));
    }
    out
}

/// Fills `name` with the default options and checks: no NaN, valid samples
/// untouched, maximum principle per component, and the default tolerance met
/// against a solve with a 1e-6 m tolerance.
fn fill_and_check(rel: &str, expected_voids: usize) -> Option<FillReport> {
    let data = shared_data()?;
    let path = data.join(rel);
    let original = read(&path);
    assert_eq!(original.void_count(), expected_voids, "{rel}");
    let components = components_with_border_range(&original);

    let mut filled = original.clone();
    let t = Instant::now();
    let report = fill_voids(&mut filled, &FillOptions::DEFAULT).unwrap();
    let elapsed = t.elapsed();
    println!(
        "{rel}: {} voids in {} components (largest {}) filled in {:.1} ms, {} cycles at most, {} sweeps in all, last change {:.2e} m, converged {}",
        report.filled,
        report.components,
        report.largest_component,
        elapsed.as_secs_f64() * 1e3,
        report.max_iterations_used,
        report.total_sweeps,
        report.last_change_m,
        report.converged
    );
    assert_eq!(report.filled, expected_voids);
    assert_eq!(report.components, components.len());
    assert!(report.converged, "{report:?}");
    assert_eq!(filled.void_count(), 0, "{rel}: NaN left after the fill");
    for (a, b) in original.heights().iter().zip(filled.heights()) {
        assert!(a.is_nan() || a == b, "{rel}: a valid sample changed");
    }
    for (cells, lo, hi) in &components {
        for &i in cells {
            let v = filled.heights()[i];
            assert!(
                v >= *lo && v <= *hi,
                "{rel}: sample ({}, {}) filled with {v} outside its border range [{lo}, {hi}]",
                i % original.width(),
                i / original.width()
            );
        }
    }

    let mut reference = original.clone();
    let tight = FillOptions::DEFAULT.with_tolerance_m(1e-6);
    let t = Instant::now();
    let tight_report = fill_voids(&mut reference, &tight).unwrap();
    let max_diff = filled
        .heights()
        .iter()
        .zip(reference.heights())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    println!(
        "{rel}: with tolerance 1e-6 m: {:.1} ms, {} cycles; largest difference from the default fill {max_diff:.2e} m",
        t.elapsed().as_secs_f64() * 1e3,
        tight_report.max_iterations_used
    );
    // f32 storage rounds to about 1.2e-4 m at 1000-2000 m, 2.4e-4 m at 2000-4000 m.
    assert!(
        max_diff < 1e-3 + 2.5e-4,
        "{rel}: default fill is {max_diff} m from the converged one"
    );
    Some(report)
}

#[test]
fn pyrenees_srtm_tile_n42e001() {
    fill_and_check("srtm/N42E001.hgt.zip", 7652);
}

#[test]
fn mt_fuji_srtm_geotiff() {
    fill_and_check("geotiff/mt_fuji_90m.tif", 2437);
}

#[test]
fn luxembourg_outside_is_nodata() {
    fill_and_check("geotiff/luxembourg_elev_terra.tif", 3942);
}

#[test]
fn hugo_site_ascii_grid() {
    fill_and_check("asc/hugo_site.asc", 2028);
}

#[test]
fn inverse_distance_on_n42e001() {
    let Some(data) = shared_data() else { return };
    let original = read(&data.join("srtm/N42E001.hgt.zip"));
    let components = components_with_border_range(&original);
    let mut g = original.clone();
    let opts = FillOptions::DEFAULT.with_policy(VoidPolicy::Fill(FillMethod::InverseDistance));
    let t = Instant::now();
    let report = fill_voids(&mut g, &opts).unwrap();
    println!(
        "N42E001 inverse distance: {} voids in {:.1} ms",
        report.filled,
        t.elapsed().as_secs_f64() * 1e3
    );
    assert_eq!(g.void_count(), 0);
    for (cells, lo, hi) in &components {
        assert!(cells
            .iter()
            .all(|&i| g.heights()[i] >= *lo && g.heights()[i] <= *hi));
    }
}

#[test]
fn refuse_policy_names_count_and_first_void() {
    let Some(data) = shared_data() else { return };
    let mut g = read(&data.join("srtm/N42E001.hgt.zip"));
    let (col, row) = g.first_void().unwrap();
    let opts = FillOptions::DEFAULT.with_policy(VoidPolicy::Refuse);
    let err = fill_voids(&mut g, &opts).unwrap_err();
    assert_eq!(
        err,
        cota_core::grid::voids::VoidError::Refused(GridError::HasVoids {
            count: 7652,
            col,
            row
        })
    );
    assert!(err.to_string().contains("7652 void samples"), "{err}");
}
