//! The invariant checker on real data at several tolerances: every shared SRTM
//! tile, a two-tile mosaic, Puget Sound 1025² and Fuji (issue 3).
#![allow(clippy::unwrap_used, reason = "tests unwrap to fail loudly")]

use crate::common;
use common::*;

use cota_core::grid::mosaic::{mosaic, MosaicOptions};
use cota_core::grid::voids::{fill_voids, FillOptions};
use cota_core::{check_mesh, Bitree, CheckOptions, ExtractOptions, HeightGrid};
use cota_io::{read_dem, PngEncoding, ReadOptions};

fn filled(mut g: HeightGrid) -> HeightGrid {
    fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
    g
}

fn check_at(g: &HeightGrid, tolerances: &[f64]) -> Vec<usize> {
    let tin = Bitree::build(g).unwrap();
    let mut counts = Vec::new();
    for &e in tolerances {
        let mesh = tin.extract(&ExtractOptions::max_error_m(e)).unwrap().mesh;
        let r = check_mesh(g, &mesh, &CheckOptions::conforming(e))
            .map_err(|err| format!("E = {e} m: {err}"))
            .unwrap();
        assert!(r.metrics.max_error_m <= e);
        counts.push(mesh.triangle_count());
    }
    // Coarser tolerance, fewer triangles.
    assert!(counts.windows(2).all(|w| w[0] >= w[1]), "{counts:?}");
    counts
}

#[test]
fn every_shared_srtm_tile() {
    let names = [
        "N00E010.hgt",
        "N00E011.hgt.zip",
        "N41E001.hgt.zip",
        "N42E001.hgt.zip",
        "N49E011.hgt.zip",
        "N50E011.hgt.zip",
        "S29W072.hgt.zip",
    ];
    for n in names {
        let Some(p) = shared(&format!("srtm/{n}")) else {
            return;
        };
        let g = filled(read_dem(&p, &ReadOptions::DEFAULT).unwrap().grid);
        let c = check_at(&g, &[0.0, 2.0, 10.0]);
        eprintln!("{n}: {c:?} triangles at 0, 2, 10 m");
    }
}

#[test]
fn bundled_sample_lossless_reproduces_every_height() {
    let g = filled(
        read_dem(&fixture("S29W072.hgt.zip"), &ReadOptions::DEFAULT)
            .unwrap()
            .grid,
    );
    let c = check_at(&g, &[0.0, 0.5, 1.0, 5.0, 20.0, 50.0]);
    assert!(
        c[0] < 2 * 1200 * 1200,
        "lossless still simplifies flat sea: {c:?}"
    );
}

#[test]
fn two_tile_mosaic() {
    let (Some(a), Some(b)) = (shared("srtm/N00E010.hgt"), shared("srtm/N00E011.hgt.zip")) else {
        return;
    };
    let tiles = vec![
        read_dem(&a, &ReadOptions::DEFAULT).unwrap().grid,
        read_dem(&b, &ReadOptions::DEFAULT).unwrap().grid,
    ];
    let m = mosaic(tiles, &MosaicOptions::DEFAULT).unwrap();
    assert_eq!((m.grid.width(), m.grid.height()), (2401, 1201));
    check_at(&filled(m.grid), &[1.0, 5.0, 25.0]);
}

#[test]
fn puget_sound_and_fuji() {
    if let Some(p) = shared("png/ps_height_1k.png") {
        let o = ReadOptions::DEFAULT
            .with_png_encoding(Some(PngEncoding::Gray16))
            .with_gray(0.1, 0.0);
        let g = read_dem(&p, &o).unwrap().grid;
        assert_eq!(g.width(), 1025);
        check_at(&g, &[0.5, 2.0, 10.0, 50.0]);
    }
    if let Some(p) = shared("png/fuji.png") {
        let g = read_dem(&p, &ReadOptions::DEFAULT).unwrap().grid;
        check_at(&g, &[1.0, 5.0, 10.0, 50.0]);
    }
}
