//! `cota-server`: cota's terrain over HTTP, for the browser.
//!
//! * `/`: the viewer (three.js), where detail follows the observer: it decodes
//!   the progressive stream in a Web Worker and remeshes incrementally by
//!   screen-space error (papers `000_ebf7e3a88dffd361.txt`, progressive
//!   transmission, and `001_49f2c365e8c41172.txt`, view-dependent remeshing).
//! * `/cesium`: a CesiumJS page over the quantized-mesh tiles.
//! * `/stream`: the `.cstream` bytes, with single HTTP ranges: a prefix ending
//!   on a step boundary decodes to a coarser crack-free mesh.
//! * `/meta.json`: size, cell size, steps (end offsets, stated errors).
//! * `/tiles/layer.json` (and `/layer.json`), `/tiles/{z}/{x}/{y}.terrain`:
//!   quantized-mesh tiles from a [`TileSource`]: a `cota tiles` directory
//!   ([`DirTileSource`]) or tiles made on demand from the in-memory
//!   hierarchy ([`DemandTileSource`]); see [`tiles`] for the URL layout.
//! * `/health`: liveness and what is served.
//!
//! [`router`] builds the whole service from a [`ServerState`] without a
//! socket (tests drive it directly); [`serve`] runs it on a listener until a
//! shutdown future resolves, and [`run`] does that on a fresh runtime until
//! SIGINT or SIGTERM.
//!
//! ```no_run
//! # fn main() -> Result<(), cota_server::ServeError> {
//! use cota_core::{GeoRef, HeightGrid};
//! use cota_server::{run, ServerState, StreamAsset};
//! let heights = (0..33 * 33).map(|i| (i % 33) as f32).collect();
//! let grid = HeightGrid::new(33, 33, heights, GeoRef::unreferenced(30.0)).expect("grid");
//! let state = ServerState::new(StreamAsset::from_grid(&grid, "ramp")?);
//! run("127.0.0.1:8080".parse().expect("address"), state, |addr| println!("http://{addr}/"))
//! # }
//! ```

pub mod assets;
pub mod error;
pub mod range;
mod routes;
pub mod stream;
pub mod tiles;

use std::future::Future;
use std::net::SocketAddr;
use std::sync::Arc;

use axum::body::Bytes;

pub use error::{status_of, Result, ServeError};
pub use routes::{router, MAX_URI_BYTES};
pub use stream::{StreamAsset, StreamMeta};
pub use tiles::{DemandTileSource, DirTileSource, Tile, TileId, TileSource};

/// What the server serves: the stream and, optionally, tiles.
#[derive(Clone)]
pub struct ServerState {
    stream: Arc<StreamAsset>,
    tiles: Option<Tiles>,
}

/// A tile source and its two layers (see [`tiles`]).
#[derive(Clone)]
pub(crate) struct Tiles {
    /// Where the tiles come from.
    pub(crate) source: Arc<dyn TileSource>,
    /// `/layer.json`: the source's layer, template relative to the root.
    pub(crate) root_layer: Bytes,
}

impl std::fmt::Debug for ServerState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ServerState")
            .field("stream_bytes", &self.stream.bytes().len())
            .field("tiles", &self.tiles.is_some())
            .finish()
    }
}

impl ServerState {
    /// A server of `stream`, without tiles.
    pub fn new(stream: StreamAsset) -> Self {
        ServerState {
            stream: Arc::new(stream),
            tiles: None,
        }
    }

    /// Adds a tile source for `/tiles/layer.json`, `/layer.json` and
    /// `/tiles/{z}/{x}/{y}.terrain`.
    pub fn with_tiles(mut self, source: Arc<dyn TileSource>) -> Self {
        let root_layer = tiles::root_layer(source.layer_json());
        self.tiles = Some(Tiles { source, root_layer });
        self
    }

    /// The stream.
    pub fn stream(&self) -> &StreamAsset {
        &self.stream
    }
}

/// Serves `state` on `listener` until `shutdown` resolves; requests in
/// flight are completed first. Connections get `TCP_NODELAY`: small tiles and
/// ranges leave at once instead of waiting on the client's delayed ACK.
///
/// # Errors
/// The listener's I/O error.
pub async fn serve(
    listener: tokio::net::TcpListener,
    state: ServerState,
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> std::io::Result<()> {
    use axum::serve::ListenerExt;
    let listener = listener.tap_io(|tcp| {
        // Without it a response may wait for the peer's delayed ACK; serving
        // goes on either way.
        let _ = tcp.set_nodelay(true);
    });
    axum::serve(listener, router(state))
        .with_graceful_shutdown(shutdown)
        .await
}

/// Resolves on SIGINT (Ctrl-C) or, on Unix, SIGTERM.
pub async fn shutdown_signal() {
    let ctrl_c = async {
        if tokio::signal::ctrl_c().await.is_err() {
            std::future::pending::<()>().await;
        }
    };
    #[cfg(unix)]
    let term = async {
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut s) => {
                s.recv().await;
            }
            Err(_) => std::future::pending::<()>().await,
        }
    };
    #[cfg(not(unix))]
    let term = std::future::pending::<()>();
    tokio::select! {
        () = ctrl_c => {},
        () = term => {},
    }
}

/// Binds `addr`, calls `ready` with the bound address, and serves until
/// SIGINT or SIGTERM (graceful: requests in flight finish).
///
/// # Errors
/// [`ServeError::Bind`] when the address cannot be bound,
/// [`ServeError::Internal`] when the runtime cannot start or the server fails.
pub fn run(addr: SocketAddr, state: ServerState, ready: impl FnOnce(SocketAddr)) -> Result<()> {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .map_err(|e| ServeError::Internal(format!("cannot start the runtime: {e}")))?;
    rt.block_on(async move {
        let bind = |source| ServeError::Bind {
            addr: addr.to_string(),
            source,
        };
        let listener = tokio::net::TcpListener::bind(addr).await.map_err(bind)?;
        ready(listener.local_addr().map_err(bind)?);
        serve(listener, state, shutdown_signal())
            .await
            .map_err(|e| ServeError::Internal(format!("server: {e}")))
    })
}
