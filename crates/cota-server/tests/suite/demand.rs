//! Tiles made on demand (`DemandTileSource`) through the router, on a window
//! of the bundled SRTM tile: the URL layout (both layers' templates resolve
//! to the tile route), every tile of the layer served, byte for byte the
//! file `cota tiles` writes with the same options, decoded and within its
//! zoom's bound at every lattice sample (the one checker's placed mode),
//! and tiles outside the layer refused; over real loopback sockets, many
//! clients asking for the same tiles at once in different orders get the
//! same bytes, malformed tile requests get a 4xx, and
//! the server serves afterwards.
#![allow(clippy::unwrap_used, clippy::panic, reason = "tests")]

use crate::common;

use std::sync::Arc;

use axum::body::{to_bytes, Body};
use axum::http::{header, Request, StatusCode};
use axum::Router;
use cota_core::mesh::check::check_placed_mesh;
use cota_core::tiles::{LatticeOptions, TilerOptions};
use cota_server::{router, DemandTileSource, DirTileSource};
use cota_tiles::{decode, tile_path, write_pyramid, PyramidOptions, TileExtensions};
use tower::ServiceExt;

async fn get(app: &Router, uri: &str) -> (StatusCode, axum::http::HeaderMap, Vec<u8>) {
    let r = app
        .clone()
        .oneshot(
            Request::get(uri)
                .header(header::ACCEPT_ENCODING, "gzip")
                .body(Body::empty())
                .unwrap(),
        )
        .await
        .unwrap();
    let (parts, body) = r.into_parts();
    let b = to_bytes(body, usize::MAX).await.unwrap().to_vec();
    (parts.status, parts.headers, b)
}

fn gunzip(b: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    std::io::Read::read_to_end(&mut flate2::read::GzDecoder::new(b), &mut out).unwrap();
    out
}

const OPTIONS: PyramidOptions = PyramidOptions::DEFAULT
    .with_extensions(TileExtensions::with(true, false, true))
    .with_gzip(true);

#[tokio::test]
async fn tiles_on_demand_are_the_pyramid_s_tiles() {
    let grid = common::grid();
    let src = Arc::new(
        DemandTileSource::new(
            &grid,
            &LatticeOptions::DEFAULT,
            &TilerOptions::DEFAULT,
            OPTIONS,
        )
        .unwrap(),
    );
    let app = router(common::state().with_tiles(src.clone()));
    // The layer as `cota tiles` writes it at /tiles/layer.json (template
    // relative to /tiles/), and at /layer.json with `tiles/` in front.
    let (s, _, b) = get(&app, "/tiles/layer.json").await;
    assert_eq!(s, StatusCode::OK);
    let layer: serde_json::Value = serde_json::from_slice(&b).unwrap();
    assert_eq!(layer["tiles"][0], "{z}/{x}/{y}.terrain?v={version}");
    let (_, _, b) = get(&app, "/layer.json").await;
    let root: serde_json::Value = serde_json::from_slice(&b).unwrap();
    assert_eq!(root["tiles"][0], "tiles/{z}/{x}/{y}.terrain");
    assert_eq!(root["available"], layer["available"]);

    // The same pyramid written by `cota tiles`' writer, and served from it.
    let dir = tempfile::tempdir().unwrap();
    let prep = src.prepared();
    write_pyramid(prep, dir.path(), &OPTIONS, None, &|_| {}).unwrap();
    let from_dir =
        router(common::state().with_tiles(Arc::new(DirTileSource::open(dir.path()).unwrap())));
    let (_, _, b) = get(&from_dir, "/tiles/layer.json").await;
    assert_eq!(
        serde_json::from_slice::<serde_json::Value>(&b).unwrap(),
        layer
    );

    let mut served = 0;
    for t in prep.tiles() {
        let uri = format!("/tiles/{}/{}/{}.terrain", t.z, t.x, t.y);
        let (s, h, b) = get(&app, &uri).await;
        assert_eq!(s, StatusCode::OK, "{uri}");
        assert_eq!(h[header::CONTENT_TYPE], "application/vnd.quantized-mesh");
        assert_eq!(h[header::CONTENT_ENCODING], "gzip");
        assert_eq!(b, std::fs::read(tile_path(dir.path(), t)).unwrap(), "{uri}");
        assert_eq!(get(&from_dir, &uri).await.2, b, "{uri}");
        let decoded = decode(&gunzip(&b)).unwrap();
        let bound = prep.zoom(t.z).unwrap().max_error_m;
        let cells = prep.lattice().scheme().cells_at(t.z);
        let report = check_placed_mesh(&prep.region(t), &decoded.to_placed(cells), Some(bound))
            .unwrap_or_else(|e| panic!("{uri}: {e}"));
        assert!(report.metrics.max_error_m <= bound);
        served += 1;
    }
    assert_eq!(served, prep.tile_count());
    assert!(served > 20, "{served} tiles");

    // Outside the layer, outside the world, beyond the finest zoom.
    let z = prep.lattice().scheme().max_zoom;
    for (uri, status) in [
        ("/tiles/1/0/0.terrain".to_string(), StatusCode::NOT_FOUND),
        ("/tiles/0/2/0.terrain".to_string(), StatusCode::BAD_REQUEST),
        (
            format!("/tiles/{}/0/0.terrain", z + 1),
            StatusCode::NOT_FOUND,
        ),
    ] {
        assert_eq!(get(&app, &uri).await.0, status, "{uri}");
    }
}

#[test]
fn a_projected_source_gives_no_tiles() {
    let mut grid = common::grid();
    let mut g = grid.georef().clone();
    g.crs = cota_core::Crs::Epsg(32719);
    grid.set_georef(g);
    let e = DemandTileSource::new(
        &grid,
        &LatticeOptions::DEFAULT,
        &TilerOptions::DEFAULT,
        OPTIONS,
    )
    .unwrap_err();
    assert!(e.to_string().contains("32719"), "{e}");
}

/// One request on its own connection (`Connection: close`): status, body.
async fn fetch_raw(addr: std::net::SocketAddr, target: &str) -> (u16, Vec<u8>) {
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    let mut s = tokio::net::TcpStream::connect(addr).await.unwrap();
    let req = format!(
        "GET {target} HTTP/1.1\r\nHost: t\r\nAccept-Encoding: gzip\r\nConnection: close\r\n\r\n"
    );
    s.write_all(req.as_bytes()).await.unwrap();
    let mut all = Vec::new();
    s.read_to_end(&mut all).await.unwrap();
    let split = all.windows(4).position(|w| w == b"\r\n\r\n").unwrap();
    let status = std::str::from_utf8(&all[9..12]).unwrap().parse().unwrap();
    (status, all[split + 4..].to_vec())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn concurrent_clients_get_the_same_tiles_and_bad_requests_4xx() {
    let src = DemandTileSource::new(
        &common::grid(),
        &LatticeOptions::DEFAULT,
        &TilerOptions::DEFAULT,
        OPTIONS,
    )
    .unwrap();
    let uris: Vec<String> = src
        .prepared()
        .tiles()
        .map(|t| format!("/tiles/{}/{}/{}.terrain", t.z, t.x, t.y))
        .collect();
    let state = common::state().with_tiles(Arc::new(src));
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let (tx, rx) = tokio::sync::oneshot::channel::<()>();
    let server = tokio::spawn(cota_server::serve(listener, state, async move {
        let _ = rx.await;
    }));

    // 16 clients, each walking every tile from its own starting point.
    let clients: Vec<_> = (0..16)
        .map(|c| {
            let uris = uris.clone();
            tokio::spawn(async move {
                let n = uris.len();
                let mut got = vec![Vec::new(); n];
                for k in 0..n {
                    let i = (k + c * 7) % n;
                    let (status, body) = fetch_raw(addr, &uris[i]).await;
                    assert_eq!(status, 200, "{}", uris[i]);
                    got[i] = body;
                }
                got
            })
        })
        .collect();
    let mut first: Option<Vec<Vec<u8>>> = None;
    for c in clients {
        let got = c.await.unwrap();
        match &first {
            None => first = Some(got),
            Some(f) => assert!(f == &got, "clients got different bytes for a tile"),
        }
    }

    for bad in [
        "/tiles/x/0/0.terrain",
        "/tiles/0/0/0.png",
        "/tiles/0/9/0.terrain",
        "/tiles/99/0/0.terrain",
        "/tiles/0/0/99999999999.terrain",
        "/tiles/0/%2e%2e/0.terrain",
        "/tiles/../../etc/passwd",
    ] {
        let (status, _) = fetch_raw(addr, bad).await;
        assert!((400..500).contains(&status), "{bad}: {status}");
    }
    assert_eq!(fetch_raw(addr, &uris[0]).await.0, 200);
    tx.send(()).unwrap();
    server.await.unwrap().unwrap();
}
