//! The accept loop: connections up to [`ServeOptions::max_connections`]
//! (one more is answered 503 and closed), HTTP/1.1 by hyper with a
//! header-read timeout (a request whose head never completes, or a
//! kept-alive connection left idle, is closed after
//! [`ServeOptions::header_timeout_s`]), `TCP_NODELAY`, and a graceful
//! shutdown that lets requests in flight finish (at most
//! [`DRAIN_S`] seconds).

use std::future::Future;
use std::sync::Arc;
use std::time::Duration;

use axum::Router;
use hyper_util::rt::{TokioIo, TokioTimer};
use hyper_util::service::TowerToHyperService;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{watch, OwnedSemaphorePermit, Semaphore};

use crate::options::ServeOptions;

/// Seconds the shutdown waits for requests in flight.
pub const DRAIN_S: u64 = 10;

/// Serves `app` on every listener until `shutdown` resolves.
pub(crate) async fn serve_all(
    listeners: Vec<TcpListener>,
    app: Router,
    opts: ServeOptions,
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> std::io::Result<()> {
    let limit = Arc::new(Semaphore::new(opts.max_connections));
    let (stop_tx, stop_rx) = watch::channel(false);
    let mut loops = tokio::task::JoinSet::new();
    for l in listeners {
        loops.spawn(accept(l, app.clone(), limit.clone(), stop_rx.clone(), opts));
    }
    shutdown.await;
    let _ = stop_tx.send(true);
    while loops.join_next().await.is_some() {}
    let all = u32::try_from(opts.max_connections).unwrap_or(u32::MAX);
    // Every connection holds a permit: all back means all closed.
    let _ = tokio::time::timeout(Duration::from_secs(DRAIN_S), limit.acquire_many(all)).await;
    Ok(())
}

async fn accept(
    listener: TcpListener,
    app: Router,
    limit: Arc<Semaphore>,
    mut stop: watch::Receiver<bool>,
    opts: ServeOptions,
) {
    loop {
        let accepted = tokio::select! {
            _ = stop.changed() => return,
            a = listener.accept() => a,
        };
        let tcp = match accepted {
            Ok((tcp, _)) => tcp,
            Err(_) => {
                // Out of file descriptors or the like: let some close.
                tokio::time::sleep(Duration::from_millis(50)).await;
                continue;
            }
        };
        // Without it a response may wait for the peer's delayed ACK.
        let _ = tcp.set_nodelay(true);
        match limit.clone().try_acquire_owned() {
            Ok(permit) => {
                tokio::spawn(connection(tcp, app.clone(), permit, stop.clone(), opts));
            }
            Err(_) => {
                tokio::spawn(refuse(tcp, opts.retry_after_s));
            }
        }
    }
}

async fn connection(
    tcp: TcpStream,
    app: Router,
    _permit: OwnedSemaphorePermit,
    mut stop: watch::Receiver<bool>,
    opts: ServeOptions,
) {
    let mut builder = hyper::server::conn::http1::Builder::new();
    builder
        .timer(TokioTimer::new())
        .header_read_timeout(opts.header_timeout())
        .max_buf_size(64 << 10);
    let conn = builder.serve_connection(TokioIo::new(tcp), TowerToHyperService::new(app));
    tokio::pin!(conn);
    tokio::select! {
        _ = conn.as_mut() => {}
        _ = stop.changed() => {
            conn.as_mut().graceful_shutdown();
            let _ = tokio::time::timeout(Duration::from_secs(DRAIN_S), conn).await;
        }
    }
}

/// Answers a connection past the limit with 503 and closes it, reading
/// what the client sent first (within a second) so that the close does not
/// reset the connection before the client reads the answer.
async fn refuse(mut tcp: TcpStream, retry_after_s: u64) {
    let msg = format!(
        "HTTP/1.1 503 Service Unavailable\r\nRetry-After: {retry_after_s}\r\n\
         Content-Type: text/plain; charset=utf-8\r\nContent-Length: 32\r\nConnection: close\r\n\r\n\
         too many connections; try later\n"
    );
    let second = Duration::from_secs(1);
    let _ = tokio::time::timeout(second, tcp.write_all(msg.as_bytes())).await;
    let _ = tcp.shutdown().await;
    let mut sink = [0u8; 4096];
    let _ = tokio::time::timeout(second, tcp.read(&mut sink)).await;
}
