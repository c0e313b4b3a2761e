//! Issue 31 over real loopback sockets, bounded in count and time: 200
//! concurrent clients on distinct on-demand tiles of a 3601² input (every
//! answer 200 or 503 with `Retry-After`, the threads bounded), half-open
//! and idle connections closed by the header-read timeout, connections past
//! the limit answered 503, a server still starting answering 503, and HTTP
//! per RFC 9110 on the wire: ranges (one, several as multipart, ignored,
//! unsatisfiable), `If-None-Match` on tiles and the stream, `HEAD`, IPv6.
#![allow(clippy::unwrap_used, clippy::panic, reason = "tests")]

use crate::common;

use std::net::SocketAddr;
use std::sync::Arc;
use std::time::{Duration, Instant};

use cota_core::tiles::{LatticeOptions, TilerOptions};
use cota_core::HeightGrid;
use cota_server::{serve, DemandTileSource, DirTileSource, ServeOptions, ServerState};
use cota_tiles::{PyramidOptions, TileExtensions};
use tokio::io::{AsyncReadExt, AsyncWriteExt, BufReader};
use tokio::net::TcpStream;

/// A response: status, head (lower case), body.
struct Resp {
    status: u16,
    head: String,
    body: Vec<u8>,
}

impl Resp {
    fn header(&self, name: &str) -> Option<&str> {
        self.head
            .lines()
            .find_map(|l| l.strip_prefix(&format!("{name}:")))
            .map(str::trim)
    }
}

/// Reads one response; `head_only`: a HEAD answer (no body whatever the length).
async fn response(r: &mut BufReader<TcpStream>, head_only: bool) -> std::io::Result<Resp> {
    let mut head = Vec::new();
    while !head.ends_with(b"\r\n\r\n") {
        head.push(r.read_u8().await?);
        if head.len() > 64 << 10 {
            return Err(std::io::Error::other("head too long"));
        }
    }
    let text = String::from_utf8_lossy(&head).to_ascii_lowercase();
    let status = text.get(9..12).and_then(|s| s.parse().ok()).unwrap_or(0);
    let resp = Resp {
        status,
        head: text,
        body: Vec::new(),
    };
    let len = resp
        .header("content-length")
        .and_then(|v| v.parse::<usize>().ok())
        .unwrap_or(0);
    let mut body = vec![0; if head_only { 0 } else { len }];
    r.read_exact(&mut body).await?;
    Ok(Resp { body, ..resp })
}

async fn request(addr: SocketAddr, raw: &str) -> Resp {
    let s = TcpStream::connect(addr).await.unwrap();
    let mut r = BufReader::new(s);
    r.get_mut().write_all(raw.as_bytes()).await.unwrap();
    let head_only = raw.starts_with("HEAD ");
    tokio::time::timeout(Duration::from_secs(30), response(&mut r, head_only))
        .await
        .unwrap()
        .unwrap()
}

fn get(path: &str, headers: &str) -> String {
    format!("GET {path} HTTP/1.1\r\nHost: t\r\n{headers}\r\n")
}

type Server = (
    SocketAddr,
    tokio::sync::oneshot::Sender<()>,
    tokio::task::JoinHandle<std::io::Result<()>>,
);

async fn start(state: ServerState) -> Server {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let (tx, rx) = tokio::sync::oneshot::channel::<()>();
    let h = tokio::spawn(serve(listener, state, async move {
        let _ = rx.await;
    }));
    (addr, tx, h)
}

async fn stop(s: Server) {
    s.1.send(()).unwrap();
    tokio::time::timeout(Duration::from_secs(20), s.2)
        .await
        .unwrap()
        .unwrap()
        .unwrap();
}

/// The bundled 3" tile resampled by 3 (bilinear) onto 3601 × 3601: the size
/// of a 1" SRTM tile, at the same place.
fn grid_3601() -> HeightGrid {
    let g = {
        let path = cota_fixtures::fixture(cota_fixtures::BUNDLED_TILE);
        let mut g = cota_io::read_dem(&path, &cota_io::ReadOptions::DEFAULT)
            .unwrap()
            .grid;
        cota_core::fill_voids(&mut g, &cota_core::FillOptions::DEFAULT).unwrap();
        g
    };
    let n = 3601;
    let mut z = Vec::with_capacity(n * n);
    for r in 0..n {
        let (r0, fr) = ((r / 3).min(1199), (r % 3) as f32 / 3.0);
        for c in 0..n {
            let (c0, fc) = ((c / 3).min(1199), (c % 3) as f32 / 3.0);
            let top = g.get(c0, r0) * (1.0 - fc) + g.get(c0 + 1, r0) * fc;
            let bottom = g.get(c0, r0 + 1) * (1.0 - fc) + g.get(c0 + 1, r0 + 1) * fc;
            z.push(top * (1.0 - fr) + bottom * fr);
        }
    }
    let mut geo = g.georef().clone();
    geo.pixel_x /= 3.0;
    geo.pixel_y /= 3.0;
    HeightGrid::new(n, n, z, geo).unwrap()
}

fn threads() -> usize {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("Threads:"))
                .and_then(|v| v.trim().parse().ok())
        })
        .unwrap_or(0)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn two_hundred_clients_on_distinct_tiles_of_a_3601_input() {
    let t = Instant::now();
    let src = DemandTileSource::new(
        &grid_3601(),
        &LatticeOptions::DEFAULT,
        &TilerOptions::DEFAULT,
        PyramidOptions::DEFAULT
            .with_extensions(TileExtensions::with(true, false, true))
            .with_gzip(true),
    )
    .unwrap();
    let prep = src.prepared();
    let deepest = prep.lattice().scheme().max_zoom;
    let mut tiles: Vec<String> = prep
        .tiles()
        .filter(|t| t.z + 1 >= deepest)
        .map(|t| format!("/tiles/{}/{}/{}.terrain", t.z, t.x, t.y))
        .collect();
    tiles.truncate(400);
    println!("3601² prepared in {:.1} s", t.elapsed().as_secs_f64());
    // Two workers and one waiting job: 200 clients at once must see 503s.
    let opts = ServeOptions::default().with_workers(2).with_queue(1);
    let state = common::state().with_options(opts).with_tiles(Arc::new(src));
    let server = start(state).await;
    let addr = server.0;
    let before = threads();
    let tiles = Arc::new(tiles);
    let clients: Vec<_> = (0..200)
        .map(|c| {
            let tiles = tiles.clone();
            tokio::spawn(async move {
                let mut seen = Vec::new();
                for k in 0..2 {
                    let r =
                        request(addr, &get(&tiles[2 * c + k], "Accept-Encoding: gzip\r\n")).await;
                    seen.push((r.status, r.header("retry-after").is_some()));
                }
                seen
            })
        })
        .collect();
    let mut peak = 0;
    let mut all = Vec::new();
    for c in clients {
        peak = peak.max(threads());
        all.extend(c.await.unwrap());
    }
    let ok = all.iter().filter(|a| a.0 == 200).count();
    let busy = all.iter().filter(|a| a.0 == 503).count();
    println!(
        "200 clients, 400 distinct deep tiles: {ok} 200, {busy} 503 (all with Retry-After), threads {before} → peak {peak}, {:.1} s",
        t.elapsed().as_secs_f64()
    );
    assert!(
        all.iter()
            .all(|&(s, retry)| s == 200 || (s == 503 && retry)),
        "{all:?}"
    );
    assert!(ok > 0 && busy > 0, "{ok} 200, {busy} 503");
    assert!(peak < 64, "{peak} threads");
    let h = request(addr, &get("/health", "")).await;
    let v: serde_json::Value = serde_json::from_slice(&h.body).unwrap();
    assert_eq!(v["work"]["refused"], busy as u64);
    stop(server).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn half_open_and_idle_connections_are_closed() {
    let opts = ServeOptions::default().with_header_timeout_s(1);
    let server = start(common::state().with_options(opts)).await;
    let addr = server.0;
    let closes_within = |sent: &'static [u8]| async move {
        let mut s = TcpStream::connect(addr).await.unwrap();
        s.write_all(sent).await.unwrap();
        let t = Instant::now();
        let mut buf = Vec::new();
        tokio::time::timeout(Duration::from_secs(30), s.read_to_end(&mut buf))
            .await
            .expect("the server must close a half-open request")
            .ok();
        (t.elapsed(), buf)
    };
    let (after, _) = closes_within(b"GET /health HTTP/1.1\r\nHost: t\r\n").await;
    assert!(after < Duration::from_secs(5), "{after:?}");
    let (after, _) = closes_within(b"").await;
    assert!(
        after < Duration::from_secs(5),
        "silent connection: {after:?}"
    );
    // A kept-alive connection: answered, then closed once idle.
    let (after, buf) = closes_within(b"GET /health HTTP/1.1\r\nHost: t\r\n\r\n").await;
    assert!(buf.starts_with(b"HTTP/1.1 200"));
    assert!(after < Duration::from_secs(5), "idle keep-alive: {after:?}");
    stop(server).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn connections_past_the_limit_get_503() {
    let opts = ServeOptions::default().with_max_connections(2);
    let server = start(common::state().with_options(opts)).await;
    let addr = server.0;
    let held: Vec<TcpStream> = vec![
        TcpStream::connect(addr).await.unwrap(),
        TcpStream::connect(addr).await.unwrap(),
    ];
    tokio::time::sleep(Duration::from_millis(200)).await;
    let r = request(addr, &get("/health", "")).await;
    assert_eq!(r.status, 503);
    assert_eq!(r.header("retry-after"), Some("1"));
    drop(held);
    tokio::time::sleep(Duration::from_millis(200)).await;
    assert_eq!(request(addr, &get("/health", "")).await.status, 200);
    stop(server).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_starting_server_answers_503_until_ready() {
    let state = ServerState::starting(ServeOptions::default());
    let server = start(state.clone()).await;
    let addr = server.0;
    for path in [
        "/stream",
        "/meta.json",
        "/tiles/layer.json",
        "/imagery.json",
    ] {
        let r = request(addr, &get(path, "")).await;
        assert_eq!((path, r.status), (path, 503));
        assert!(r.header("retry-after").is_some(), "{path}");
    }
    let h = request(addr, &get("/health", "")).await;
    let v: serde_json::Value = serde_json::from_slice(&h.body).unwrap();
    assert_eq!(
        (v["stream"].as_str(), v["tiles"].as_str()),
        (Some("pending"), Some("pending"))
    );
    state.set_stream(Ok(common::state().stream().unwrap().clone()));
    state.set_tiles(Ok(None));
    assert_eq!(request(addr, &get("/stream", "")).await.status, 200);
    assert_eq!(
        request(addr, &get("/tiles/layer.json", "")).await.status,
        404
    );
    stop(server).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ranges_validators_and_head_on_the_wire() {
    let dir = tempfile::tempdir().unwrap();
    common::tile_dir(dir.path());
    let state = common::state().with_tiles(Arc::new(DirTileSource::open(dir.path()).unwrap()));
    let whole = state.stream().unwrap().bytes().clone();
    let len = whole.len();
    let server = start(state).await;
    let addr = server.0;
    let ranged = |r: &str| get("/stream", &format!("Range: {r}\r\n"));
    // One range.
    let r = request(addr, &ranged("bytes=10-19")).await;
    assert_eq!((r.status, r.body.as_slice()), (206, &whole[10..20]));
    assert_eq!(
        r.header("content-range"),
        Some(format!("bytes 10-19/{len}").as_str())
    );
    // Unknown unit, invalid spec, two Range lines: ignored, the whole body.
    for bad in [
        ranged("items=0-5"),
        ranged("bytes=9-2"),
        ranged("bytes=abc"),
        get("/stream", "Range: bytes=0-1\r\nRange: bytes=2-3\r\n"),
    ] {
        let r = request(addr, &bad).await;
        assert_eq!((r.status, r.body.len()), (200, len), "{bad}");
    }
    // Unsatisfiable: 416 with the length.
    let r = request(addr, &ranged(&format!("bytes={len}-"))).await;
    assert_eq!(r.status, 416);
    assert_eq!(
        r.header("content-range"),
        Some(format!("bytes */{len}").as_str())
    );
    // Several: multipart/byteranges, each part with its Content-Range.
    let r = request(addr, &ranged("bytes=0-3, 100-103, -4")).await;
    assert_eq!(r.status, 206);
    let ct = r.header("content-type").unwrap().to_string();
    let b = ct.split("boundary=").nth(1).unwrap().to_string();
    let body = r.body.clone();
    let parts: Vec<&[u8]> = split(&body, format!("--{b}").as_bytes());
    let want = [(0, 3), (100, 103), (len - 4, len - 1)];
    assert_eq!(parts.len(), want.len() + 2, "preamble, parts, epilogue");
    for (p, (a, z)) in parts[1..=want.len()].iter().zip(want) {
        let split_at = p.windows(4).position(|w| w == b"\r\n\r\n").unwrap();
        let head = String::from_utf8_lossy(&p[..split_at]).to_ascii_lowercase();
        assert!(
            head.contains(&format!("content-range: bytes {a}-{z}/{len}")),
            "{head}"
        );
        assert_eq!(&p[split_at + 4..p.len() - 2], &whole[a..=z]);
    }
    // If-None-Match on the stream and on a tile.
    for path in ["/stream", "/tiles/0/0/0.terrain"] {
        let r = request(addr, &get(path, "")).await;
        let etag = r.header("etag").unwrap().to_string();
        assert!(r.header("cache-control").is_some(), "{path}");
        let r = request(
            addr,
            &get(path, &format!("If-None-Match: W/\"x\", {etag}\r\n")),
        )
        .await;
        assert_eq!((r.status, r.body.len()), (304, 0), "{path}");
    }
    // HEAD: the headers of GET, no body.
    for path in ["/stream", "/tiles/0/0/0.terrain", "/health"] {
        let g = request(addr, &get(path, "")).await;
        let h = request(
            addr,
            &format!("HEAD {path} HTTP/1.1\r\nHost: t\r\nConnection: close\r\n\r\n"),
        )
        .await;
        assert_eq!(h.status, 200, "{path}");
        assert_eq!(h.header("content-type"), g.header("content-type"), "{path}");
        if path != "/health" {
            assert_eq!(
                h.header("content-length"),
                Some(g.body.len().to_string().as_str()),
                "{path}"
            );
        }
    }
    stop(server).await;
}

fn split<'a>(b: &'a [u8], sep: &[u8]) -> Vec<&'a [u8]> {
    let mut out = Vec::new();
    let mut start = 0;
    let mut i = 0;
    while i + sep.len() <= b.len() {
        if &b[i..i + sep.len()] == sep {
            out.push(&b[start..i]);
            i += sep.len();
            start = i;
        } else {
            i += 1;
        }
    }
    out.push(&b[start..]);
    out
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ipv6_loopback() {
    let Ok(listener) = tokio::net::TcpListener::bind("[::1]:0").await else {
        println!("SKIPPED: no IPv6 loopback on this machine");
        return;
    };
    let addr = listener.local_addr().unwrap();
    let (tx, rx) = tokio::sync::oneshot::channel::<()>();
    let h = tokio::spawn(serve(listener, common::state(), async move {
        let _ = rx.await;
    }));
    assert_eq!(request(addr, &get("/health", "")).await.status, 200);
    tx.send(()).unwrap();
    h.await.unwrap().unwrap();
}
