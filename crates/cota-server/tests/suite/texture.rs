//! `/texture.png`, `/texture-pair.png` and what `/meta.json` says of them
//! and of the input's warnings, over a real loopback socket: the Olinda
//! DEM + Landsat pair of `fixtures/` draped by `cota_io::image::drape_file`
//! under a texel bound, served, fetched and decoded.
#![allow(clippy::unwrap_used, clippy::panic, reason = "tests")]

use std::net::SocketAddr;

use cota_core::texture::DrapeOptions;
use cota_io::image::{drape_file, Bands, DrapeFileOptions, ImageOptions};
use cota_io::{read_dem, ReadOptions};
use cota_server::{serve, ServerState, StreamAsset, TextureLevel, Textures};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;

/// One `GET path` on a fresh connection: status, headers (lower case), body.
async fn get(addr: SocketAddr, path: &str) -> (u16, String, Vec<u8>) {
    let mut s = TcpStream::connect(addr).await.unwrap();
    let req = format!("GET {path} HTTP/1.1\r\nHost: t\r\nConnection: close\r\n\r\n");
    s.write_all(req.as_bytes()).await.unwrap();
    let mut all = Vec::new();
    s.read_to_end(&mut all).await.unwrap();
    let end = all.windows(4).position(|w| w == b"\r\n\r\n").unwrap();
    let head = String::from_utf8_lossy(&all[..end]).to_ascii_lowercase();
    let status = head[9..12].parse().unwrap();
    (status, head, all[end + 4..].to_vec())
}

fn decode_png(b: &[u8]) -> (u32, u32, Vec<u8>) {
    let mut r = png::Decoder::new(std::io::Cursor::new(b))
        .read_info()
        .unwrap();
    let mut buf = vec![0; r.output_buffer_size().unwrap()];
    let info = r.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    assert_eq!(info.color_type, png::ColorType::Rgb);
    (info.width, info.height, buf)
}

/// The olinda state: the Landsat image (bands 3,2,1) at most `max_side`
/// texels a side, and one warning.
fn olinda(max_side: usize) -> (ServerState, cota_core::texture::RgbImage) {
    let dem = cota_fixtures::fixture("olinda_dem_utm25s.tif");
    let grid = read_dem(&dem, &ReadOptions::DEFAULT).unwrap().grid;
    let opts = DrapeFileOptions::DEFAULT
        .with_image(ImageOptions::DEFAULT.with_bands(Some(Bands::Rgb([3, 2, 1]))))
        .with_drape(DrapeOptions::DEFAULT.with_max_side_texels(max_side));
    let img = cota_fixtures::fixture("L7_ETMs.tif");
    let d = drape_file(&img, &grid, &opts).unwrap();
    let about = serde_json::json!({"bands": d.bands.text()});
    let level = TextureLevel::from_rgb(&d.texture, "/texture.png", about).unwrap();
    let textures = Textures {
        image: level,
        pair: None,
    };
    let state = ServerState::new(StreamAsset::from_grid(&grid, "olinda").unwrap())
        .with_textures(textures)
        .with_warnings(vec!["olinda: 3 void samples filled".into()]);
    (state, d.texture)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_texture_is_served_decodable_at_its_bounded_size() {
    let (state, texture) = olinda(200);
    // The image's own resolution over the DEM is 347 texels a side: the
    // bound holds it to 200.
    assert_eq!([texture.width(), texture.height()], [200, 200]);
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let (tx, rx) = tokio::sync::oneshot::channel::<()>();
    let h = tokio::spawn(serve(listener, state, async move {
        let _ = rx.await;
    }));
    let (status, head, body) = get(addr, "/texture.png").await;
    assert_eq!(status, 200);
    assert!(head.contains("content-type: image/png"), "{head}");
    let (w, h_px, px) = decode_png(&body);
    assert_eq!((w, h_px), (200, 200));
    assert_eq!(px, texture.as_bytes(), "the PNG holds the draped texels");
    // Landsat true colour over Olinda: a dark, bluish scene, not a blank.
    let mean = |k: usize| {
        px.iter()
            .skip(k)
            .step_by(3)
            .map(|&v| f64::from(v))
            .sum::<f64>()
            / 40_000.0
    };
    assert!(
        (20.0..160.0).contains(&mean(0)) && mean(2) > mean(0),
        "{} {}",
        mean(0),
        mean(2)
    );

    let (status, _, body) = get(addr, "/meta.json").await;
    assert_eq!(status, 200);
    let meta: serde_json::Value = serde_json::from_slice(&body).unwrap();
    let t = &meta["texture"]["image"];
    assert_eq!(
        (t["url"].as_str(), t["width"].as_u64(), t["height"].as_u64()),
        (Some("/texture.png"), Some(200), Some(200))
    );
    assert_eq!(t["about"]["bands"], "3,2,1");
    assert!(meta["texture"]["pair"].is_null());
    assert_eq!(
        meta["warnings"],
        serde_json::json!(["olinda: 3 void samples filled"])
    );

    let (status, _, body) = get(addr, "/texture-pair.png").await;
    assert_eq!(status, 404, "{}", String::from_utf8_lossy(&body));
    tx.send(()).unwrap();
    h.await.unwrap().unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn without_a_texture_meta_says_so_and_the_route_is_404() {
    let grid = crate::common::grid();
    let state = ServerState::new(StreamAsset::from_grid(&grid, "w").unwrap());
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let (tx, rx) = tokio::sync::oneshot::channel::<()>();
    let h = tokio::spawn(serve(listener, state, async move {
        let _ = rx.await;
    }));
    let (_, _, body) = get(addr, "/meta.json").await;
    let meta: serde_json::Value = serde_json::from_slice(&body).unwrap();
    assert!(meta["texture"].is_null());
    assert_eq!(meta["warnings"], serde_json::json!([]));
    let (status, _, body) = get(addr, "/texture.png").await;
    assert_eq!(status, 404);
    assert!(String::from_utf8_lossy(&body).contains("--texture"));
    tx.send(()).unwrap();
    h.await.unwrap().unwrap();
}

#[tokio::test]
async fn meta_is_validated_by_its_own_body_not_the_streams() {
    use tower::ServiceExt;
    // The same stream with and without a warning: a client holding the
    // first meta must not be told 304 by the second server.
    let grid = crate::common::grid();
    let plain = ServerState::new(StreamAsset::from_grid(&grid, "w").unwrap());
    let warned = plain
        .clone()
        .with_warnings(vec!["w: 1 void sample filled".into()]);
    let etag = |state: ServerState| async move {
        let req = axum::http::Request::get("/meta.json")
            .body(axum::body::Body::empty())
            .unwrap();
        let r = cota_server::router(state).oneshot(req).await.unwrap();
        r.headers()["etag"].to_str().unwrap().to_string()
    };
    let (a, b) = (etag(plain).await, etag(warned).await);
    assert_ne!(a, b);
}
