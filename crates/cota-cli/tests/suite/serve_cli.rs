//! `cota serve` refuses bad inputs at start, naming them, with a non-zero
//! exit (the server itself is tested in cota-server's tests and, end to end
//! with a browser, by crates/cota-server/viewer/test-browser/run.mjs).
#![allow(clippy::unwrap_used, clippy::panic, reason = "tests")]

use crate::common;

use common::cota;

#[test]
fn a_missing_or_corrupt_tile_set_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nowhere");
    let out = cota(&[
        "serve",
        "--tiles",
        missing.to_str().unwrap(),
        "--addr",
        "127.0.0.1:0",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--tiles") && err.contains("nowhere"), "{err}");
    std::fs::write(dir.path().join("layer.json"), "{ not json").unwrap();
    let out = cota(&[
        "serve",
        "--tiles",
        dir.path().to_str().unwrap(),
        "--addr",
        "127.0.0.1:0",
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("layer.json") && err.contains("JSON"), "{err}");
}

#[test]
fn a_corrupt_stream_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("bad.cstream");
    let mut b = b"COTASTRM".to_vec();
    b.extend_from_slice(&[1, 0, 200, 0, 0, 0, 7, 7]);
    std::fs::write(&f, b).unwrap();
    let out = cota(&["serve", f.to_str().unwrap(), "--addr", "127.0.0.1:0"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.cstream") && err.contains("truncated"),
        "{err}"
    );
}

fn s(p: &std::path::Path) -> &str {
    p.to_str().unwrap()
}

/// `cota serve ARGS --addr 127.0.0.1:0` refused before listening, its
/// message holding every one of `words`.
fn refused(args: &[&str], words: &[&str]) {
    let mut all = vec!["serve"];
    all.extend_from_slice(args);
    all.extend(["--addr", "127.0.0.1:0"]);
    let out = cota(&all);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{all:?} served");
    assert!(words.iter().all(|w| err.contains(w)), "{all:?}: {err}");
    assert!(!String::from_utf8_lossy(&out.stdout).contains("listening"));
}

#[test]
fn a_bad_texture_is_refused_before_serving() {
    let dir = tempfile::tempdir().unwrap();
    let (dem, img) = (
        common::fixture("olinda_dem_utm25s.tif"),
        common::fixture("L7_ETMs.tif"),
    );
    let none = dir.path().join("none.tif");
    refused(&[s(&dem), "--texture", s(&none)], &["none.tif"]);
    // Not an image; bands the image lacks; bands that do not parse.
    let junk = dir.path().join("junk.png");
    std::fs::write(&junk, b"not an image at all").unwrap();
    refused(
        &[s(&dem), "--texture", s(&junk)],
        &["junk.png", "expected an image"],
    );
    refused(
        &[s(&dem), "--texture", s(&img), "--bands", "9,2,1"],
        &["L7_ETMs.tif", "9,2,1", "found 6 bands"],
    );
    refused(
        &[s(&dem), "--texture", s(&img), "--bands", "red"],
        &["--bands", "red"],
    );
    refused(&[s(&dem), "--bands", "3,2,1"], &["--bands", "--texture"]);
    // An image in another CRS, and one that lies elsewhere (a world file
    // placing the JPEG far from the DEM).
    let srtm = common::fixture("S29W072.hgt.zip");
    refused(
        &[s(&srtm), "--texture", s(&img), "--bands", "3,2,1"],
        &["L7_ETMs.tif", "EPSG:4326", "EPSG:31985"],
    );
    let far = dir.path().join("far.jpg");
    std::fs::copy(common::fixture("L7_ETMs_321.jpg"), &far).unwrap();
    std::fs::write(
        dir.path().join("far.jgw"),
        "28.5\n0\n0\n-28.5\n1000\n2000\n",
    )
    .unwrap();
    refused(
        &[s(&dem), "--texture", s(&far), "--assume-same-crs"],
        &["far.jpg", "expected an image covering the DEM"],
    );
}

/// Reads `cota serve`'s standard output until its `listening` line; the URL.
fn listening(child: &mut std::process::Child) -> String {
    use std::io::BufRead;
    let out = child.stdout.take().unwrap();
    let mut lines = std::io::BufReader::new(out).lines();
    let line = lines
        .find_map(|l| l.ok().filter(|l| l.starts_with("listening")))
        .unwrap();
    std::thread::spawn(move || lines.for_each(drop));
    let url = line.split_whitespace().nth(1).unwrap();
    url.trim_start_matches("http://")
        .trim_end_matches('/')
        .into()
}

/// `GET path` from `addr` (HTTP/1.1, one connection): status and body,
/// waiting out 503 answers (the stream still being made).
fn get(addr: &str, path: &str) -> (u16, Vec<u8>) {
    let (status, _, body) = get_with_headers(addr, path);
    (status, body)
}

/// [`get`], with the response's header block (lower-cased).
fn get_with_headers(addr: &str, path: &str) -> (u16, String, Vec<u8>) {
    use std::io::{Read, Write};
    for _ in 0..600 {
        let mut c = std::net::TcpStream::connect(addr).unwrap();
        let req = format!("GET {path} HTTP/1.1\r\nHost: t\r\nConnection: close\r\n\r\n");
        c.write_all(req.as_bytes()).unwrap();
        let mut all = Vec::new();
        c.read_to_end(&mut all).unwrap();
        let end = all.windows(4).position(|w| w == b"\r\n\r\n").unwrap();
        let status: u16 = String::from_utf8_lossy(&all[9..12]).parse().unwrap();
        if status != 503 {
            let head = String::from_utf8_lossy(&all[..end]).to_ascii_lowercase();
            return (status, head, all[end + 4..].to_vec());
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    panic!("{path}: 503 for a minute");
}

/// `cota serve ARGS --addr 127.0.0.1:0` started, and the address it listens on.
fn serving(args: &[&str]) -> (std::process::Child, String) {
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_cota"))
        .arg("serve")
        .args(args)
        .args(["--addr", "127.0.0.1:0"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let addr = listening(&mut child);
    (child, addr)
}

/// Stops a server started by [`serving`].
fn stop(mut child: std::process::Child) {
    child.kill().unwrap();
    child.wait().unwrap();
}

#[test]
fn the_texture_and_the_inputs_warnings_are_served() {
    let (dem, img) = (
        common::fixture("olinda_dem_utm25s.tif"),
        common::fixture("L7_ETMs.tif"),
    );
    let (child, addr) = serving(&[
        s(&dem),
        "--texture",
        s(&img),
        "--bands",
        "3,2,1",
        "--texture-max-side",
        "100",
    ]);
    let (status, png) = get(&addr, "/texture.png");
    let (_, meta) = get(&addr, "/meta.json");
    stop(child);
    assert_eq!(status, 200);
    // The PNG's IHDR: 100 x 100 (the image's own 347 held to the bound).
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let be = |k: usize| u32::from_be_bytes(png[k..k + 4].try_into().unwrap());
    assert_eq!((be(16), be(20)), (100, 100));
    let meta: serde_json::Value = serde_json::from_slice(&meta).unwrap();
    assert_eq!(meta["texture"]["image"]["about"]["bands"], "3,2,1");
    assert_eq!(meta["warnings"], serde_json::json!([]));
    // The bundled SRTM tile has 21 voids: filled, and said in the meta.
    let srtm = common::fixture("S29W072.hgt.zip");
    let (child, addr) = serving(&[s(&srtm)]);
    let (_, meta) = get(&addr, "/meta.json");
    stop(child);
    let meta: serde_json::Value = serde_json::from_slice(&meta).unwrap();
    let w = meta["warnings"].as_array().unwrap();
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].as_str().unwrap().contains("21 void samples"), "{w:?}");
}

/// Two SRTM tiles across the antimeridian (the real N00E010 and N00E011
/// relabelled N00E179 and N00W180) are served as one grid: the stream, and
/// on-demand tiles and relief imagery on both sides of 180° (`available` in
/// two ranges).
#[test]
fn a_pair_across_the_antimeridian_is_served_as_one_grid() {
    let (Some(a), Some(b)) = (
        common::shared("srtm/N00E010.hgt"),
        common::shared("srtm/N00E011.hgt.zip"),
    ) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let (e179, w180) = (
        dir.path().join("N00E179.hgt"),
        dir.path().join("N00W180.hgt.zip"),
    );
    std::fs::copy(a, &e179).unwrap();
    std::fs::copy(b, &w180).unwrap();
    let (child, addr) = serving(&[s(&e179), s(&w180)]);
    let (_, meta) = get(&addr, "/meta.json");
    let (_, layer) = get(&addr, "/tiles/layer.json");
    // Zoom 9: 179°..180° is address column 1022, 180°..181° column 0.
    let east = get(&addr, "/tiles/9/1022/256.terrain");
    let west = get(&addr, "/tiles/9/0/256.terrain");
    // The relief imagery on both sides too (zoom 8: columns 511 and 0).
    let (_, imagery) = get(&addr, "/imagery.json");
    let relief = [
        get(&addr, "/imagery/8/511/128.png"),
        get(&addr, "/imagery/8/0/128.png"),
    ];
    stop(child);
    let imagery: serde_json::Value = serde_json::from_slice(&imagery).unwrap();
    let bounds: Vec<f64> = serde_json::from_value(imagery["bounds"].clone()).unwrap();
    let want = [179.0, 0.0, -179.0, 1.0];
    assert!(
        bounds.iter().zip(want).all(|(b, w)| (b - w).abs() < 1e-9),
        "{bounds:?}: west > east across 180 degrees"
    );
    for (status, png) in relief {
        assert_eq!(status, 200);
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    }
    let meta: serde_json::Value = serde_json::from_slice(&meta).unwrap();
    assert_eq!(meta["width"], 2401, "{meta}");
    let layer: serde_json::Value = serde_json::from_slice(&layer).unwrap();
    assert_eq!(
        layer["available"][9].as_array().unwrap().len(),
        2,
        "{layer}"
    );
    for (status, body) in [east, west] {
        assert_eq!(status, 200);
        let tile = cota_tiles::decode(&body).unwrap();
        assert!(tile.u.len() > 4, "{} vertices", tile.u.len());
    }
}

/// `cota tiles DEM --format 3dtiles --meshopt EXTRA -o OUT`, which must succeed.
fn tiles3d(dem: &std::path::Path, out: &std::path::Path, extra: &[&str]) {
    let r = std::process::Command::new(env!("CARGO_BIN_EXE_cota"))
        .args(["tiles", s(dem), "--format", "3dtiles", "--meshopt"])
        .args(extra)
        .arg("-o")
        .arg(out)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
}

/// `cota serve --tiles OUT.3tz` (and the same pyramid as a directory): the
/// 3D Tiles files at /3dtiles/ with their media types, the run's hidden
/// manifest and missing files 404, quantized-mesh tiles still made on
/// demand, `/health` saying both.
#[test]
fn three_d_tiles_from_an_archive_or_a_directory_are_served_as_files() {
    let dir = tempfile::tempdir().unwrap();
    let dem = common::fixture("S29W072.hgt.zip");
    let (archive, plain) = (dir.path().join("t.3tz"), dir.path().join("t3d"));
    for out in [&archive, &plain] {
        tiles3d(&dem, out, &["--max-zoom", "6"]);
    }
    let glb = "0/6/38/21.glb";
    let want = std::fs::read(plain.join(glb)).unwrap();
    for given in [&archive, &plain] {
        let (child, addr) = serving(&[s(&dem), "--tiles", s(given)]);
        let (status, head, tileset) = get_with_headers(&addr, "/3dtiles/tileset.json");
        let (glb_status, glb_head, body) = get_with_headers(&addr, &format!("/3dtiles/{glb}"));
        let hidden = get(&addr, "/3dtiles/.cota-tiles.json").0;
        let missing = get(&addr, "/3dtiles/0/6/0/0.glb").0;
        let (_, health) = get(&addr, "/health");
        let qm = get(&addr, "/tiles/0/0/0.terrain").0;
        stop(child);
        assert_eq!(status, 200, "{}", given.display());
        assert!(head.contains("content-type: application/json"), "{head}");
        assert_eq!(tileset, std::fs::read(plain.join("tileset.json")).unwrap());
        assert_eq!(glb_status, 200);
        assert!(
            glb_head.contains("content-type: model/gltf-binary"),
            "{glb_head}"
        );
        assert_eq!(body, want, "{glb} from {}", given.display());
        assert_eq!((hidden, missing, qm), (404, 404, 200));
        let health: serde_json::Value = serde_json::from_slice(&health).unwrap();
        assert_eq!(health["tiles3d"], "yes", "{health}");
    }
}

/// `cota serve DEM` without `--tiles`: the 3D Tiles pyramid made from the
/// on-demand tiles' hierarchy on the first request, byte for byte the
/// files `cota tiles --format 3dtiles --meshopt --normals` writes.
#[test]
fn three_d_tiles_are_made_on_request_as_cota_tiles_writes_them() {
    let dir = tempfile::tempdir().unwrap();
    let dem = common::fixture("S29W072.hgt.zip");
    let plain = dir.path().join("t3d");
    tiles3d(&dem, &plain, &["--normals"]);
    let (child, addr) = serving(&[s(&dem)]);
    // Once the tiles are prepared (the layer answers), before any 3D tile.
    assert_eq!(get(&addr, "/tiles/layer.json").0, 200);
    let (_, before) = get(&addr, "/health");
    let files = [
        "tileset.json",
        "0/subtrees/0/0/0.subtree",
        "0/6/38/21.glb",
        "0/12/2456/1400.glb",
    ];
    let got: Vec<_> = files
        .iter()
        .map(|f| get(&addr, &format!("/3dtiles/{f}")))
        .collect();
    let (_, after) = get(&addr, "/health");
    let missing = get(&addr, "/3dtiles/0/6/0/0.glb").0;
    stop(child);
    let word =
        |b: &[u8]| serde_json::from_slice::<serde_json::Value>(b).unwrap()["tiles3d"].clone();
    assert_eq!(
        (word(&before), word(&after)),
        ("on request".into(), "yes".into())
    );
    for (f, (status, body)) in files.iter().zip(got) {
        assert_eq!(status, 200, "{f}");
        assert_eq!(body, std::fs::read(plain.join(f)).unwrap(), "{f}");
    }
    assert_eq!(missing, 404);
}
