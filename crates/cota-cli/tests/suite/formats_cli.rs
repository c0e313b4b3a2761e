//! The CLI on the new input formats: a Terrarium WebP tile meshed and
//! checked, a PMTiles archive listed by `cota info` and read by `--input-zoom` (and the deprecated `--zoom`)
//! and `--bbox`, an `.npz` with `--array`, a USGS `.dem`; and their refusals
//! (a one-line error naming the file, nothing written).
#![allow(clippy::unwrap_used, clippy::panic)]

use crate::common;

use std::path::Path;

use common::{cota, fixture, stderr, stdout};
use cota_fixtures::formats::{self, ArchiveTile};

fn ok(args: &[&str]) -> String {
    let o = cota(args);
    assert!(o.status.success(), "{args:?}: {}", stderr(&o));
    stdout(&o)
}

/// Runs `args`, expecting a failure that names `file` and writes no `out`.
fn refused(args: &[&str], file: &str, out: &Path, needles: &[&str]) {
    let o = cota(args);
    let err = stderr(&o);
    assert!(!o.status.success(), "{args:?} succeeded");
    assert!(err.contains(file), "{err:?} does not name {file}");
    for n in needles {
        assert!(err.contains(n), "{err:?} lacks {n:?}");
    }
    assert!(!out.exists(), "{} was written", out.display());
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn webp_tile_meshes_and_checks() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("t.glb");
    let webp = fixture("terrarium.webp");
    let text = ok(&[
        "mesh",
        s(&webp),
        "--cell-size-m",
        "30",
        "--max-error",
        "2",
        "--check",
        "-o",
        s(&out),
    ]);
    assert!(out.exists(), "{text}");
    let info = ok(&["info", s(&webp)]);
    assert!(info.contains("WebP (terrarium)"), "{info}");

    let bytes = std::fs::read(&webp).unwrap();
    let cut = dir.path().join("cut.webp");
    std::fs::write(&cut, &bytes[..bytes.len() / 3]).unwrap();
    let out = dir.path().join("cut.glb");
    refused(
        &["mesh", s(&cut), "-o", s(&out)],
        "cut.webp",
        &out,
        &["truncated"],
    );
}

#[test]
fn pmtiles_info_and_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let tile = std::fs::read(fixture("terrarium.webp")).unwrap();
    // The bundled tile at two made-up addresses (its own is not recorded).
    let tiles = [
        ArchiveTile {
            z: 9,
            x: 150,
            y: 200,
            bytes: tile.clone(),
        },
        ArchiveTile {
            z: 10,
            x: 300,
            y: 400,
            bytes: tile,
        },
    ];
    let (bytes, _) = formats::pmtiles(&tiles, 4, [-74.6, 36.2, -74.2, 36.7]);
    let archive = dir.path().join("terrain.pmtiles");
    std::fs::write(&archive, bytes).unwrap();

    let info = ok(&["info", s(&archive)]);
    assert!(
        info.contains("zooms       9..10") && info.contains("-74.6,36.2,-74.2,36.7"),
        "{info}"
    );
    let json = ok(&["info", s(&archive), "--json"]);
    assert!(json.contains("\"max_zoom\": 10"), "{json}");

    // Tile 10/300/400 spans lon -74.53..-74.18, lat 36.30..36.60.
    let out = dir.path().join("a.obj");
    let bbox = "--bbox=-74.4,36.4,-74.3,36.5";
    let text = ok(&[
        "mesh",
        s(&archive),
        "--input-zoom",
        "10",
        bbox,
        "--max-error",
        "2",
        "--check",
        "-o",
        s(&out),
    ]);
    assert!(out.exists(), "{text}");
    let info = ok(&["info", s(&archive), "--zoom", "10", bbox]);
    assert!(
        info.contains("256 x 256") && info.contains("EPSG:3857"),
        "{info}"
    );

    let out = dir.path().join("b.obj");
    refused(
        &["mesh", s(&archive), "-o", s(&out)],
        "terrain.pmtiles",
        &out,
        &["--input-zoom"],
    );
    let far = "--bbox=10,10,11,11";
    refused(
        &["mesh", s(&archive), "--zoom", "10", far, "-o", s(&out)],
        "terrain.pmtiles",
        &out,
        &["at least one tile of zoom 10", "none in the archive"],
    );
}

#[test]
fn npz_with_array_and_usgs_dem() {
    let dir = tempfile::tempdir().unwrap();
    let hugo = cota_fixtures::bundled("hugo_site.asc");
    let (w, h) = (hugo.width, hugo.height);
    let npz = formats::npz(&[
        ("a", formats::npy_f32(&hugo.heights, w, h)),
        ("b", formats::npy_f32(&hugo.heights, w, h)),
    ]);
    let p = dir.path().join("two.npz");
    std::fs::write(&p, npz).unwrap();
    let out = dir.path().join("n.ply");
    refused(
        &["mesh", s(&p), "-o", s(&out)],
        "two.npz",
        &out,
        &["a, b", "--array"],
    );
    ok(&[
        "mesh",
        s(&p),
        "--array",
        "b",
        "--cell-size-m",
        "10",
        "--max-error",
        "1",
        "--check",
        "-o",
        s(&out),
    ]);
    assert!(out.exists());

    let srtm = cota_fixtures::bundled_tile().crop(0, 0, 201, 201);
    let dem = formats::usgs_dem(&srtm.heights, 201, -72.0, -29.0, 3.0, 201);
    let p = dir.path().join("S29W072.dem");
    std::fs::write(&p, &dem).unwrap();
    let info = ok(&["info", s(&p)]);
    assert!(
        info.contains("USGS ASCII DEM") && info.contains("201 x 201"),
        "{info}"
    );
    let bad = formats::usgs_dem(&srtm.heights, 201, -72.0, -29.0, 3.0, 202);
    let p = dir.path().join("bad.dem");
    std::fs::write(&p, &bad).unwrap();
    let out = dir.path().join("d.stl");
    refused(
        &["mesh", s(&p), "-o", s(&out)],
        "bad.dem",
        &out,
        &["202 profiles"],
    );
}
