//! `cota serve --tiles OUT.mbtiles`: an archive written by `cota tiles`
//! served as its directory twin is, response for response (bytes,
//! `Content-Encoding`, ETag, 404 beyond `available`), and a file that is
//! not such an archive refused at start, named.
#![allow(clippy::unwrap_used, clippy::panic)]

use crate::common;

use std::sync::Arc;

use axum::body::{to_bytes, Body};
use axum::http::{header, Request, StatusCode};
use axum::Router;
use cota_core::tiles::{Lattice, LatticeOptions, Prepared, TilerOptions};
use cota_core::{fill_voids, FillOptions};
use cota_server::{router, DirTileSource, MbtilesTileSource, ServeError};
use cota_tiles::{write_mbtiles, write_pyramid, PyramidOptions, TileExtensions};
use tower::ServiceExt;

async fn get(app: &Router, uri: &str, gzip: bool) -> (StatusCode, Option<String>, Vec<u8>) {
    let mut req = Request::get(uri);
    if gzip {
        req = req.header(header::ACCEPT_ENCODING, "gzip");
    }
    let r = app
        .clone()
        .oneshot(req.body(Body::empty()).unwrap())
        .await
        .unwrap();
    let (parts, body) = r.into_parts();
    let enc = parts
        .headers
        .get(header::CONTENT_ENCODING)
        .map(|v| v.to_str().unwrap().to_string());
    (
        parts.status,
        enc,
        to_bytes(body, usize::MAX).await.unwrap().to_vec(),
    )
}

#[tokio::test]
async fn an_archive_serves_as_its_directory_does() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/S29W072.hgt.zip");
    let mut grid = cota_io::read_dem(&path, &cota_io::ReadOptions::DEFAULT)
        .unwrap()
        .grid;
    fill_voids(&mut grid, &FillOptions::DEFAULT).unwrap();
    let lattice =
        Lattice::resample(&grid, &LatticeOptions::DEFAULT.with_max_zoom(Some(8))).unwrap();
    let prep = Prepared::new(&lattice, &grid, &TilerOptions::DEFAULT).unwrap();
    let opts = PyramidOptions::DEFAULT
        .with_extensions(TileExtensions::with(true, false, true))
        .with_gzip(true);
    let dir = tempfile::tempdir().unwrap();
    let (tree, archive) = (dir.path().join("tree"), dir.path().join("t.mbtiles"));
    write_pyramid(&prep, &tree, &opts, None, &|_| {}).unwrap();
    write_mbtiles(&prep, &archive, &opts, None, &|_| {}).unwrap();
    let from_dir =
        router(common::state().with_tiles(Arc::new(DirTileSource::open(&tree).unwrap())));
    let from_mbt =
        router(common::state().with_tiles(Arc::new(MbtilesTileSource::open(&archive).unwrap())));

    let mut uris = vec!["/tiles/layer.json".to_string()];
    uris.extend(
        prep.tiles()
            .map(|t| format!("/tiles/{}/{}/{}.terrain", t.z, t.x, t.y)),
    );
    // Beyond `available`, and outside the world.
    uris.push("/tiles/8/0/0.terrain".into());
    uris.push("/tiles/3/99/0.terrain".into());
    for uri in &uris {
        for gzip in [true, false] {
            let a = get(&from_dir, uri, gzip).await;
            let b = get(&from_mbt, uri, gzip).await;
            assert_eq!(a, b, "{uri} (gzip accepted: {gzip})");
        }
    }
    let (s, enc, _) = get(&from_mbt, &uris[1], true).await;
    assert_eq!((s, enc.as_deref()), (StatusCode::OK, Some("gzip")));
    assert_eq!(
        get(&from_mbt, "/tiles/8/0/0.terrain", true).await.0,
        StatusCode::NOT_FOUND
    );
}

#[test]
fn a_file_that_is_not_an_archive_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("fake.mbtiles");
    std::fs::write(&f, "not sqlite at all").unwrap();
    let e = MbtilesTileSource::open(&f).unwrap_err();
    assert!(matches!(e, ServeError::BadTileSet { .. }), "{e}");
    assert!(e.to_string().contains("fake.mbtiles"), "{e}");
    let missing = MbtilesTileSource::open(&dir.path().join("none.mbtiles")).unwrap_err();
    assert!(missing.to_string().contains("none.mbtiles"), "{missing}");
}
