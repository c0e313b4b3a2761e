//! The router driven without a socket: every route, its headers, ranges
//! whose prefixes decode to coarser crack-free meshes, and the bad-request
//! list answered 4xx (never a crash, never a file outside the served set).
#![allow(clippy::unwrap_used, clippy::panic, reason = "tests")]

use crate::common;

use std::sync::Arc;

use axum::body::{to_bytes, Body};
use axum::http::{header, Request, StatusCode};
use axum::Router;
use cota_core::{check_mesh, CheckOptions};
use cota_io::stream_file::StreamReader;
use cota_server::{router, DirTileSource, ServeError, StreamAsset};
use tower::ServiceExt;

async fn get(
    app: &Router,
    uri: &str,
    headers: &[(&str, &str)],
) -> (StatusCode, axum::http::HeaderMap, Vec<u8>) {
    let mut req = Request::get(uri);
    for (k, v) in headers {
        req = req.header(*k, *v);
    }
    let r = app
        .clone()
        .oneshot(req.body(Body::empty()).unwrap())
        .await
        .unwrap();
    let (parts, body) = r.into_parts();
    (
        parts.status,
        parts.headers,
        to_bytes(body, usize::MAX).await.unwrap().to_vec(),
    )
}

fn tiles_app() -> (Router, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    common::tile_dir(dir.path());
    let src = DirTileSource::open(dir.path()).unwrap();
    (router(common::state().with_tiles(Arc::new(src))), dir)
}

#[tokio::test]
async fn pages_health_and_meta() {
    let app = router(common::state());
    let (s, h, b) = get(&app, "/", &[]).await;
    assert_eq!(s, StatusCode::OK);
    assert!(h[header::CONTENT_TYPE]
        .to_str()
        .unwrap()
        .starts_with("text/html"));
    assert!(String::from_utf8_lossy(&b).contains("data-cota-page"));
    let (s, _, b) = get(&app, "/cesium", &[]).await;
    assert_eq!(s, StatusCode::OK);
    assert!(String::from_utf8_lossy(&b).contains("data-cota-page"));
    let (s, h, b) = get(&app, "/health", &[]).await;
    assert_eq!(s, StatusCode::OK);
    assert_eq!(h[header::ACCESS_CONTROL_ALLOW_ORIGIN], "*");
    let v: serde_json::Value = serde_json::from_slice(&b).unwrap();
    assert_eq!(v["status"], "ok");
    let (s, _, b) = get(&app, "/meta.json", &[]).await;
    assert_eq!(s, StatusCode::OK);
    let v: serde_json::Value = serde_json::from_slice(&b).unwrap();
    assert_eq!(v["width"], 257);
    assert!(v["steps"].as_array().unwrap().len() >= 8);
}

#[tokio::test]
async fn stream_whole_ranges_and_validators() {
    let st = common::state();
    let whole = st.stream().unwrap().bytes().clone();
    let ends: Vec<u64> = st
        .stream()
        .unwrap()
        .meta()
        .steps
        .iter()
        .map(|s| s.end_offset)
        .collect();
    let app = router(st);
    let (s, h, b) = get(&app, "/stream", &[]).await;
    assert_eq!(s, StatusCode::OK);
    assert_eq!(b, whole.to_vec());
    assert_eq!(h[header::ACCEPT_RANGES], "bytes");
    let etag = h[header::ETAG].to_str().unwrap().to_string();
    let (s, _, b) = get(&app, "/stream", &[("if-none-match", &etag)]).await;
    assert_eq!((s, b.len()), (StatusCode::NOT_MODIFIED, 0));
    // Every prefix ending on a step decodes to a crack-free mesh within its
    // stated error, coarser the shorter it is.
    let grid = common::grid();
    let mut last = 0;
    for (k, &end) in ends.iter().enumerate() {
        let range = format!("bytes=0-{}", end - 1);
        let (s, h, b) = get(&app, "/stream", &[("range", &range)]).await;
        assert_eq!(s, StatusCode::PARTIAL_CONTENT);
        assert_eq!(
            h[header::CONTENT_RANGE],
            format!("bytes 0-{}/{}", end - 1, whole.len()).as_str()
        );
        let mut r = StreamReader::new();
        let frames = r.push(&b).unwrap();
        assert_eq!(frames.len(), k + 1);
        let d = r.decoder().unwrap();
        let mesh = d.mesh();
        check_mesh(
            &grid,
            &mesh,
            &CheckOptions::conforming(d.max_error_m().unwrap()),
        )
        .unwrap();
        assert!(mesh.triangle_count() >= last);
        last = mesh.triangle_count();
    }
    let (s, _, b) = get(&app, "/stream", &[("range", "bytes=-10")]).await;
    assert_eq!(
        (s, b.as_slice()),
        (StatusCode::PARTIAL_CONTENT, &whole[whole.len() - 10..])
    );
    // If-Range naming another version: the whole stream.
    let (s, _, _) = get(
        &app,
        "/stream",
        &[("range", "bytes=0-9"), ("if-range", "\"old\"")],
    )
    .await;
    assert_eq!(s, StatusCode::OK);
}

#[tokio::test]
async fn tiles_types_encodings_and_validators() {
    let (app, _dir) = tiles_app();
    let (s, _, b) = get(&app, "/layer.json", &[]).await;
    assert_eq!(s, StatusCode::OK);
    let v: serde_json::Value = serde_json::from_slice(&b).unwrap();
    assert_eq!(v["tiles"][0], "tiles/{z}/{x}/{y}.terrain");
    // The tile set mounted at /tiles/: its layer as written, template relative.
    let (s, _, b) = get(&app, "/tiles/layer.json", &[]).await;
    assert_eq!(s, StatusCode::OK);
    let v: serde_json::Value = serde_json::from_slice(&b).unwrap();
    assert_eq!(v["tiles"][0], "{z}/{x}/{y}.terrain?v={version}");
    let (s, h, b) = get(&app, "/tiles/0/0/0.terrain", &[]).await;
    assert_eq!(s, StatusCode::OK);
    assert_eq!(h[header::CONTENT_TYPE], "application/vnd.quantized-mesh");
    assert!(h.get(header::CONTENT_ENCODING).is_none());
    assert_eq!(b, common::raw_tile(0));
    assert!(h[header::CACHE_CONTROL]
        .to_str()
        .unwrap()
        .contains("max-age"));
    let etag = h[header::ETAG].to_str().unwrap().to_string();
    let (s, _, _) = get(&app, "/tiles/0/0/0.terrain", &[("if-none-match", &etag)]).await;
    assert_eq!(s, StatusCode::NOT_MODIFIED);
    // A gzip tile: gzip to clients that take it, inflated (under its own
    // ETag) to those that do not; both vary on Accept-Encoding.
    let gz = [("accept-encoding", "br, gzip;q=0.5")];
    let (s, h, b) = get(&app, "/tiles/0/1/0.terrain", &gz).await;
    assert_eq!(s, StatusCode::OK);
    assert_eq!(h[header::CONTENT_ENCODING], "gzip");
    assert_eq!(h[header::VARY], "Accept-Encoding");
    assert_eq!(&b[..2], &[0x1f, 0x8b]);
    let gz_etag = h[header::ETAG].to_str().unwrap().to_string();
    for plain in [
        &[][..],
        &[("accept-encoding", "identity")],
        &[("accept-encoding", "gzip;q=0")],
    ] {
        let (s, h, b) = get(&app, "/tiles/0/1/0.terrain", plain).await;
        assert_eq!(s, StatusCode::OK, "{plain:?}");
        assert!(h.get(header::CONTENT_ENCODING).is_none(), "{plain:?}");
        assert_eq!(h[header::VARY], "Accept-Encoding");
        assert_eq!(b, common::raw_tile(1), "{plain:?}");
        assert_ne!(h[header::ETAG].to_str().unwrap(), gz_etag);
        let etag = h[header::ETAG].to_str().unwrap().to_string();
        let (s, _, _) = get(&app, "/tiles/0/1/0.terrain", &[("if-none-match", &etag)]).await;
        assert_eq!(s, StatusCode::NOT_MODIFIED);
    }
    // A corrupt tile is an error, not a crash; the server goes on serving.
    let (s, _, _) = get(&app, "/tiles/2/7/3.terrain", &[]).await;
    assert_eq!(s, StatusCode::INTERNAL_SERVER_ERROR);
    let (s, _, _) = get(&app, "/tiles/2/6/3.terrain", &[]).await;
    assert_eq!(s, StatusCode::OK);
}

/// The bad-request list: each answered 4xx.
pub const BAD: &[(&str, &[(&str, &str)])] = &[
    ("/tiles/a/0/0.terrain", &[]),
    ("/tiles/0/0/-1.terrain", &[]),
    ("/tiles/0/0/0.png", &[]),
    ("/tiles/0/0/0", &[]),
    ("/tiles/99/0/0.terrain", &[]),
    ("/tiles/0/2/0.terrain", &[]),
    ("/tiles/0/0/1.terrain", &[]),
    ("/tiles/3/0/0.terrain", &[]),
    ("/tiles/0/0/99999999999.terrain", &[]),
    ("/tiles/0/0/0x1.terrain", &[]),
    ("/tiles/../../../etc/passwd", &[]),
    ("/tiles/0/..%2F..%2F/0.terrain", &[]),
    ("/tiles/%2e%2e/%2e%2e/etc/passwd", &[]),
    ("/assets/..%5c..%5cCargo.toml", &[]),
    ("/../Cargo.toml", &[]),
    ("/Cargo.toml", &[]),
    ("/layer.json/../Cargo.toml", &[]),
    ("/tiles/0/0/0.terrain%00", &[]),
    ("/stream", &[("range", "bytes=99999999999-")]),
    ("/stream", &[("range", "bytes=-0")]),
    ("/nothing-here", &[]),
];

#[tokio::test]
async fn bad_requests_are_4xx_and_serving_goes_on() {
    let (app, _dir) = tiles_app();
    let mut requests: Vec<(String, Vec<(&str, &str)>)> = BAD
        .iter()
        .map(|(u, h)| (u.to_string(), h.to_vec()))
        .collect();
    requests.push((format!("/tiles/0/0/{}.terrain", "9".repeat(5000)), vec![]));
    requests.push((format!("/?q={}", "x".repeat(3000)), vec![]));
    for (uri, headers) in &requests {
        let (s, _, b) = get(&app, uri, headers).await;
        assert!(
            s.is_client_error(),
            "{uri} {headers:?}: {s} {}",
            String::from_utf8_lossy(&b)
        );
        assert!(
            !String::from_utf8_lossy(&b).contains("[package]"),
            "{uri} leaked a file"
        );
    }
    let r = app
        .clone()
        .oneshot(Request::post("/stream").body(Body::empty()).unwrap())
        .await
        .unwrap();
    assert_eq!(r.status(), StatusCode::METHOD_NOT_ALLOWED);
    let (s, _, _) = get(&app, "/tiles/1/3/1.terrain", &[]).await;
    assert_eq!(s, StatusCode::OK);
    let (s, _, _) = get(&app, "/health", &[]).await;
    assert_eq!(s, StatusCode::OK);
}

#[tokio::test]
async fn a_link_out_of_the_tile_set_is_not_followed() {
    let dir = tempfile::tempdir().unwrap();
    common::tile_dir(dir.path());
    let outside = tempfile::NamedTempFile::new().unwrap();
    std::fs::write(outside.path(), common::raw_tile(9)).unwrap();
    std::fs::remove_file(dir.path().join("1/0/0.terrain")).unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink(outside.path(), dir.path().join("1/0/0.terrain")).unwrap();
    let app =
        router(common::state().with_tiles(Arc::new(DirTileSource::open(dir.path()).unwrap())));
    let (s, _, _) = get(&app, "/tiles/1/0/0.terrain", &[]).await;
    assert_eq!(s, StatusCode::NOT_FOUND);
}

#[test]
fn corrupt_tile_sets_and_streams_are_errors() {
    let open = |layer: Option<&str>| {
        let dir = tempfile::tempdir().unwrap();
        if let Some(l) = layer {
            std::fs::write(dir.path().join("layer.json"), l).unwrap();
        }
        DirTileSource::open(dir.path()).map(|_| ())
    };
    assert!(matches!(open(None), Err(ServeError::Io { .. })));
    for bad in [
        "{ not json",
        "[]",
        r#"{"format": "pbf"}"#,
        r#"{"format": "quantized-mesh-1.0", "projection": "EPSG:2154"}"#,
        r#"{"format": "quantized-mesh-1.0", "available": [[{"startX": -1}]]}"#,
        r#"{"format": "quantized-mesh-1.0", "maxzoom": 99}"#,
    ] {
        let e = open(Some(bad)).unwrap_err();
        assert!(matches!(e, ServeError::BadTileSet { .. }), "{bad}: {e}");
        assert!(e.to_string().contains("layer.json"), "{e}");
    }
    assert!(open(Some(common::LAYER)).is_ok());
    let good = StreamAsset::from_grid(&common::grid(), "g")
        .unwrap()
        .bytes()
        .to_vec();
    for bad in [b"garbage!".to_vec(), good[..good.len() / 2].to_vec(), {
        let mut b = good.clone();
        b[200] ^= 1;
        b
    }] {
        let e = StreamAsset::from_stream_bytes(bad, "x.cstream").unwrap_err();
        assert!(e.to_string().starts_with("stream x.cstream"), "{e}");
    }
    assert!(StreamAsset::from_stream_bytes(good, "ok.cstream").is_ok());
}
