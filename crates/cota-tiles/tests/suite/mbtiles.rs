//! MBTiles archives (issue 29, item 2): the same bytes as the directory
//! output tile for tile, the layer as `json` metadata, rows in TMS order,
//! a finished archive re-run skipped, other settings refused, an
//! interrupted one never under the final name.
#![allow(clippy::unwrap_used, clippy::panic)]

use cota_core::tiles::{Lattice, LatticeOptions, Prepared, TilerOptions};
use cota_core::{fill_voids, FillOptions, HeightGrid};
use cota_io::{read_dem, ReadOptions};
use cota_tiles::mbtiles::partial_path;
use cota_tiles::{
    decode, tile_path, write_mbtiles, write_pyramid, MbtilesReader, PyramidError, PyramidOptions,
    TileExtensions,
};

/// The bundled SRTM tile, voids filled.
fn fixture_grid() -> HeightGrid {
    let path = cota_fixtures::fixture("S29W072.hgt.zip");
    let mut g = read_dem(&path, &ReadOptions::DEFAULT).unwrap().grid;
    fill_voids(&mut g, &FillOptions::DEFAULT).unwrap();
    g
}

fn options() -> PyramidOptions {
    PyramidOptions::DEFAULT
        .with_extensions(TileExtensions::with(true, true, true))
        .with_gzip(true)
}

#[test]
fn archive_holds_the_directory_tiles_byte_for_byte() {
    let grid = fixture_grid();
    let lattice =
        Lattice::resample(&grid, &LatticeOptions::DEFAULT.with_max_zoom(Some(9))).unwrap();
    let prep = Prepared::new(&lattice, &grid, &TilerOptions::DEFAULT).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let (tree, archive) = (dir.path().join("tree"), dir.path().join("out.mbtiles"));
    let opts = options();
    let a = write_pyramid(&prep, &tree, &opts, None, &|_| {}).unwrap();
    let b = write_mbtiles(&prep, &archive, &opts, None, &|_| {}).unwrap();
    assert_eq!(a.written(), prep.tile_count());
    assert_eq!(b.written(), prep.tile_count());
    assert_eq!(a.bytes(), b.bytes());
    assert!(!partial_path(&archive).exists());

    let r = MbtilesReader::open(&archive).unwrap();
    let layer = std::fs::read_to_string(tree.join("layer.json")).unwrap();
    assert_eq!(r.layer_json().unwrap(), layer);
    let ids = r.tile_ids().unwrap();
    assert_eq!(ids.len() as u64, prep.tile_count());
    for t in prep.tiles() {
        let stored = r.tile(u32::from(t.z), t.x, t.y).unwrap().unwrap();
        assert_eq!(stored, std::fs::read(tile_path(&tree, t)).unwrap(), "{t}");
    }
    // TMS rows, counted from the south: the data (29° S to 28° S) lies in
    // rows (90 − 29)/180·512 = 173.5 to (90 − 28)/180·512 = 176.4 at zoom 9
    // (XYZ rows would be 335 to 338).
    let rows: Vec<u32> = ids.iter().filter(|i| i.0 == 9).map(|i| i.2).collect();
    assert!(
        !rows.is_empty() && rows.iter().all(|r| (173..=176).contains(r)),
        "{rows:?}"
    );
    // Every stored tile decodes (gzip inflated first).
    let (z, x, y) = ids[0];
    let raw = r.tile(z, x, y).unwrap().unwrap();
    let mut inflated = Vec::new();
    std::io::Read::read_to_end(&mut flate2::read::GzDecoder::new(&raw[..]), &mut inflated).unwrap();
    decode(&inflated).unwrap();
}

#[test]
fn rerun_skips_other_settings_refused_and_force_starts_afresh() {
    let grid = fixture_grid();
    let lattice =
        Lattice::resample(&grid, &LatticeOptions::DEFAULT.with_max_zoom(Some(7))).unwrap();
    let prep = Prepared::new(&lattice, &grid, &TilerOptions::DEFAULT).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let archive = dir.path().join("o.mbtiles");
    let opts = options();
    write_mbtiles(&prep, &archive, &opts, None, &|_| {}).unwrap();
    let again = write_mbtiles(&prep, &archive, &opts, None, &|_| {}).unwrap();
    assert_eq!((again.written(), again.skipped()), (0, prep.tile_count()));

    let plain = PyramidOptions::DEFAULT;
    let e = write_mbtiles(&prep, &archive, &plain, None, &|_| {}).unwrap_err();
    assert!(matches!(e, PyramidError::Changed { .. }), "{e}");
    let forced = write_mbtiles(&prep, &archive, &plain.with_force(true), None, &|_| {}).unwrap();
    assert_eq!(forced.written(), prep.tile_count());

    // A file that is not an archive is refused, not overwritten.
    let text = dir.path().join("notes.mbtiles");
    std::fs::write(&text, "not sqlite").unwrap();
    let e = write_mbtiles(&prep, &text, &opts, None, &|_| {}).unwrap_err();
    assert!(e.to_string().contains("notes.mbtiles"), "{e}");
    assert_eq!(std::fs::read_to_string(&text).unwrap(), "not sqlite");
}

#[test]
fn an_interrupted_archive_resumes_under_its_partial_name() {
    let grid = fixture_grid();
    let lattice =
        Lattice::resample(&grid, &LatticeOptions::DEFAULT.with_max_zoom(Some(7))).unwrap();
    let prep = Prepared::new(&lattice, &grid, &TilerOptions::DEFAULT).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let archive = dir.path().join("o.mbtiles");
    let opts = options();
    // A finished archive stands in for an interrupted one once renamed back
    // and stripped of its metadata and of half its tiles.
    write_mbtiles(&prep, &archive, &opts, None, &|_| {}).unwrap();
    let partial = partial_path(&archive);
    std::fs::rename(&archive, &partial).unwrap();
    let conn = rusqlite::Connection::open(&partial).unwrap();
    conn.execute("DELETE FROM metadata WHERE name != 'cota_manifest'", [])
        .unwrap();
    let removed = conn
        .execute(
            "DELETE FROM tiles WHERE (tile_column + tile_row) % 2 = 0",
            [],
        )
        .unwrap() as u64;
    drop(conn);
    assert!(removed > 0);
    // Without its metadata a reader refuses it: it never looks complete.
    assert!(MbtilesReader::open(&partial).unwrap().layer_json().is_err());
    let r = write_mbtiles(&prep, &archive, &opts, None, &|_| {}).unwrap();
    assert_eq!(r.written(), removed);
    assert_eq!(r.skipped(), prep.tile_count() - removed);
    assert!(archive.is_file() && !partial.exists());
    assert_eq!(
        MbtilesReader::open(&archive)
            .unwrap()
            .tile_ids()
            .unwrap()
            .len() as u64,
        prep.tile_count()
    );
}
