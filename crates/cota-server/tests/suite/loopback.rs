//! The server over real loopback sockets: a bounded load of 200 concurrent
//! clients fetching tiles and stream ranges (latencies printed: p50, p99),
//! raw malformed requests answered 4xx, serving going on afterwards, and a
//! graceful shutdown. Figures: `cargo test --release -p cota-server --test
//! loopback -- --nocapture`.
#![allow(clippy::unwrap_used, clippy::panic, reason = "tests")]

use crate::common;

use std::net::SocketAddr;
use std::sync::Arc;
use std::time::{Duration, Instant};

use cota_server::{serve, DirTileSource};
use tokio::io::{AsyncReadExt, AsyncWriteExt, BufReader};
use tokio::net::TcpStream;

/// Clients at once.
const CLIENTS: usize = 200;
/// Requests per client (keep-alive), half tiles, half stream ranges.
const REQUESTS: usize = 20;

/// Reads one response: status and body (every response has a Content-Length).
async fn response(r: &mut BufReader<TcpStream>) -> std::io::Result<(u16, Vec<u8>)> {
    let mut head = Vec::new();
    while !head.ends_with(b"\r\n\r\n") {
        let b = r.read_u8().await?;
        head.push(b);
        if head.len() > 64 << 10 {
            return Err(std::io::Error::other("head too long"));
        }
    }
    let text = String::from_utf8_lossy(&head).to_ascii_lowercase();
    let status = text.get(9..12).and_then(|s| s.parse().ok()).unwrap_or(0);
    let len = text
        .lines()
        .find_map(|l| l.strip_prefix("content-length:"))
        .and_then(|v| v.trim().parse::<usize>().ok())
        .unwrap_or(0);
    let mut body = vec![0; len];
    r.read_exact(&mut body).await?;
    Ok((status, body))
}

async fn start() -> (
    SocketAddr,
    tokio::sync::oneshot::Sender<()>,
    tokio::task::JoinHandle<std::io::Result<()>>,
    tempfile::TempDir,
) {
    let dir = tempfile::tempdir().unwrap();
    common::tile_dir(dir.path());
    let state = common::state().with_tiles(Arc::new(DirTileSource::open(dir.path()).unwrap()));
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let (tx, rx) = tokio::sync::oneshot::channel::<()>();
    let h = tokio::spawn(serve(listener, state, async move {
        let _ = rx.await;
    }));
    (addr, tx, h, dir)
}

/// One client: REQUESTS requests on one connection; (is a tile, latency ms).
async fn client(addr: SocketAddr, id: usize, stream_len: u64) -> Vec<(bool, f64)> {
    let s = TcpStream::connect(addr).await.unwrap();
    s.set_nodelay(true).unwrap();
    let mut r = BufReader::new(s);
    let mut lat = Vec::with_capacity(REQUESTS);
    for k in 0..REQUESTS {
        let req = if k % 2 == 0 {
            let z = (id + k) % 3;
            let (x, y) = ((id * 7 + k) % (2 << z), (id + k) % (1 << z));
            let (x, y) = if (z, x, y) == (2, 7, 3) {
                (6, 3)
            } else {
                (x, y)
            };
            format!("GET /tiles/{z}/{x}/{y}.terrain HTTP/1.1\r\nHost: t\r\n\r\n")
        } else {
            let a = ((id * 7919 + k * 104_729) as u64) % (stream_len - 1);
            let b = (a + 65_535).min(stream_len - 1);
            format!("GET /stream HTTP/1.1\r\nHost: t\r\nRange: bytes={a}-{b}\r\n\r\n")
        };
        let t = Instant::now();
        r.get_mut().write_all(req.as_bytes()).await.unwrap();
        let (status, _) = response(&mut r).await.unwrap();
        lat.push((k % 2 == 0, t.elapsed().as_secs_f64() * 1e3));
        assert!(status == 200 || status == 206, "{req}: {status}");
    }
    lat
}

fn pct(v: &[f64], p: f64) -> f64 {
    v[((v.len() as f64 * p) as usize).min(v.len() - 1)]
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn two_hundred_clients_then_abuse_then_shutdown() {
    let (addr, stop, handle, _dir) = start().await;
    let len = common::state().stream().unwrap().bytes().len() as u64;
    let t = Instant::now();
    let tasks: Vec<_> = (0..CLIENTS)
        .map(|id| tokio::spawn(client(addr, id, len)))
        .collect();
    let mut all = Vec::new();
    for task in tasks {
        all.extend(
            tokio::time::timeout(Duration::from_secs(120), task)
                .await
                .unwrap()
                .unwrap(),
        );
    }
    let secs = t.elapsed().as_secs_f64();
    assert_eq!(all.len(), CLIENTS * REQUESTS);
    for (name, tile) in [("tiles", true), ("stream ranges of 64 KiB", false)] {
        let mut v: Vec<f64> = all.iter().filter(|a| a.0 == tile).map(|a| a.1).collect();
        v.sort_by(f64::total_cmp);
        println!(
            "load: {CLIENTS} clients at once, {} {name} in {secs:.2} s (all requests): p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms, 0 errors",
            v.len(),
            pct(&v, 0.5),
            pct(&v, 0.99),
            v[v.len() - 1]
        );
    }
    abuse(addr).await;
    stop.send(()).unwrap();
    tokio::time::timeout(Duration::from_secs(10), handle)
        .await
        .unwrap()
        .unwrap()
        .unwrap();
}

/// Raw requests a client library would not send; each must get a 4xx.
async fn abuse(addr: SocketAddr) {
    let huge = "a".repeat(100_000);
    let raw: Vec<String> = vec![
        "GET /stream HTTP/1.1\r\nHost: t\r\nRange: bytes=18446744073709551615-\r\n\r\n".into(),
        "GET /tiles/0/0/../../../../etc/passwd HTTP/1.1\r\nHost: t\r\n\r\n".into(),
        "GET /tiles/%2e%2e/%2e%2e/etc/passwd HTTP/1.1\r\nHost: t\r\n\r\n".into(),
        "GET /tiles/x/y/z.terrain HTTP/1.1\r\nHost: t\r\n\r\n".into(),
        format!("GET /{huge} HTTP/1.1\r\nHost: t\r\n\r\n"),
        "GARBAGE\r\n\r\n".into(),
        "GET /health HTTP/9.9\r\n\r\n".into(),
    ];
    for req in &raw {
        let s = TcpStream::connect(addr).await.unwrap();
        let mut r = BufReader::new(s);
        r.get_mut().write_all(req.as_bytes()).await.unwrap();
        let status = match tokio::time::timeout(Duration::from_secs(10), response(&mut r)).await {
            Ok(Ok((s, _))) => s,
            other => panic!("{}: no response ({other:?})", &req[..req.len().min(60)]),
        };
        assert!(
            (400..500).contains(&status),
            "{}: {status}",
            &req[..req.len().min(60)]
        );
    }
    let s = TcpStream::connect(addr).await.unwrap();
    let mut r = BufReader::new(s);
    r.get_mut()
        .write_all(b"GET /health HTTP/1.1\r\nHost: t\r\n\r\n")
        .await
        .unwrap();
    assert_eq!(response(&mut r).await.unwrap().0, 200);
}
