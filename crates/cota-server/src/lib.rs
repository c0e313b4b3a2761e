//! `cota-server`: cota's terrain over HTTP, for the browser.
//!
//! * `/`: the viewer (three.js), where detail follows the observer: it decodes
//!   the progressive stream in a Web Worker and remeshes incrementally by
//!   screen-space error (papers `000_ebf7e3a88dffd361.txt`, progressive
//!   transmission, and `001_49f2c365e8c41172.txt`, view-dependent remeshing).
//! * `/cesium`: a CesiumJS page over the quantized-mesh tiles.
//! * `/stream`: the `.cstream` bytes, with HTTP ranges (RFC 9110: one range,
//!   several as `multipart/byteranges`, unusable ones ignored): a prefix
//!   ending on a step boundary decodes to a coarser crack-free mesh.
//! * `/meta.json`: size, cell size, steps (end offsets, stated errors), the
//!   textures, and the warnings the input gave ([`ServerState::with_warnings`]).
//! * `/tiles/layer.json` (and `/layer.json`), `/tiles/{z}/{x}/{y}.terrain`:
//!   quantized-mesh tiles from a [`TileSource`]: a `cota tiles` directory
//!   ([`DirTileSource`]), an MBTiles archive ([`MbtilesTileSource`]) or tiles made on demand from the in-memory
//!   hierarchy ([`DemandTileSource`]); see [`tiles`] for the URL layout.
//! * `/imagery.json`, `/imagery/{z}/{x}/{y}.png`: shaded-relief imagery
//!   drawn from the DEM ([`Imagery`]), in the terrain tiles' geographic tiling.
//! * `/3dtiles/…`: a `cota tiles --format 3dtiles` pyramid (a directory or
//!   a `.3tz` archive) served as its files, or, without one, the same
//!   pyramid made from the on-demand tiles' hierarchy on the first request
//!   ([`tiles3d`]).
//! * `/texture.png`, `/texture-pair.png`: an image draped on the terrain by
//!   the viewer, and paper 004's chosen texture level ([`Textures`]).
//! * `/health`: liveness, what is served or still being made, the work counters.
//!
//! Work is bounded ([`ServeOptions`]): tiles are made on a fixed pool behind
//! a bounded queue (503 with `Retry-After` past it) and kept in a
//! byte-bounded LRU cache; connections are limited and timed out. What
//! takes time at start (the stream, the tiles' hierarchy, the imagery) may
//! be set after the server listens ([`ServerState::starting`]); until then
//! its routes answer 503 with `Retry-After`.
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
//! let addr: std::net::SocketAddr = "127.0.0.1:8080".parse().expect("address");
//! run(&[addr], state, |bound| println!("http://{}/", bound[0]))
//! # }
//! ```

pub mod assets;
mod cache;
pub mod error;
pub mod imagery;
mod later;
mod listen;
pub mod options;
mod pool;
pub mod range;
mod routes;
pub mod stream;
pub mod texture;
pub mod tiles;
pub mod tiles3d;
mod work;

use std::future::Future;
use std::net::SocketAddr;
use std::sync::Arc;

use axum::body::Bytes;

pub use error::{status_of, Result, ServeError};
pub use imagery::Imagery;
pub use listen::DRAIN_S;
pub use options::ServeOptions;
pub use routes::{router, MAX_URI_BYTES};
pub use stream::{StreamAsset, StreamMeta};
pub use texture::{TextureLevel, Textures};
pub use tiles::{DemandTileSource, DirTileSource, MbtilesTileSource, Tile, TileId, TileSource};

use later::Later;
use work::Work;

/// What the server serves: the stream, tiles and imagery, each either given
/// at once or made in the background after the server listens (until then
/// their routes answer 503 with `Retry-After`), and the bounded work that
/// makes tiles ([`ServeOptions`]).
#[derive(Clone)]
pub struct ServerState {
    stream: Arc<Later<StreamAsset>>,
    tiles: Arc<Later<Option<Tiles>>>,
    imagery: Arc<Later<Option<Arc<Imagery>>>>,
    textures: Option<Arc<Textures>>,
    tiles3d: Option<Arc<tiles3d::Tiles3dFiles>>,
    tiles3d_made: Arc<std::sync::OnceLock<std::result::Result<Arc<tiles3d::Tiles3dFiles>, String>>>,
    warnings: Arc<Vec<String>>,
    work: Arc<Work>,
    options: ServeOptions,
}

/// A tile source and its two layers (see [`tiles`]).
#[derive(Clone)]
pub(crate) struct Tiles {
    /// Where the tiles come from.
    pub(crate) source: Arc<dyn TileSource>,
    /// `/layer.json`: the source's layer, template relative to the root.
    pub(crate) root_layer: Bytes,
}

impl Tiles {
    fn new(source: Arc<dyn TileSource>) -> Self {
        let root_layer = tiles::root_layer(source.layer_json());
        Tiles { source, root_layer }
    }
}

impl std::fmt::Debug for ServerState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ServerState")
            .field("stream", &self.stream.word())
            .field("tiles", &self.tiles.word())
            .field("imagery", &self.imagery.word())
            .field("textures", &self.textures.is_some())
            .field("warnings", &self.warnings.len())
            .field("options", &self.options)
            .finish()
    }
}

impl ServerState {
    /// A server of `stream`, without tiles or imagery, with the default
    /// [`ServeOptions`].
    pub fn new(stream: StreamAsset) -> Self {
        let s = Self::starting(ServeOptions::default());
        s.stream.set(Ok(stream));
        s.tiles.set(Ok(None));
        s.imagery.set(Ok(None));
        s
    }

    /// A server whose stream, tiles and imagery are still to come: set them
    /// with [`ServerState::set_stream`], [`ServerState::set_tiles`] and
    /// [`ServerState::set_imagery`] (from any thread, once each).
    pub fn starting(options: ServeOptions) -> Self {
        ServerState {
            stream: Later::pending("the stream"),
            tiles: Later::pending("the tiles"),
            imagery: Later::pending("the imagery"),
            textures: None,
            tiles3d: None,
            tiles3d_made: Arc::default(),
            warnings: Arc::new(Vec::new()),
            work: Arc::new(Work::new(&options)),
            options,
        }
    }

    /// The same content served under `options` (a fresh pool and cache).
    pub fn with_options(mut self, options: ServeOptions) -> Self {
        self.work = Arc::new(Work::new(&options));
        self.options = options;
        self
    }

    /// Adds a tile source for `/tiles/layer.json`, `/layer.json` and
    /// `/tiles/{z}/{x}/{y}.terrain`.
    pub fn with_tiles(mut self, source: Arc<dyn TileSource>) -> Self {
        self.tiles = Later::ready("the tiles", Some(Tiles::new(source)));
        self
    }

    /// Adds the shaded-relief imagery (`/imagery.json`,
    /// `/imagery/{z}/{x}/{y}.png`).
    pub fn with_imagery(mut self, imagery: Imagery) -> Self {
        self.imagery = Later::ready("the imagery", Some(Arc::new(imagery)));
        self
    }

    /// Adds the textures the viewer drapes (`/texture.png`,
    /// `/texture-pair.png`, described in `/meta.json`).
    pub fn with_textures(mut self, textures: Textures) -> Self {
        self.textures = Some(Arc::new(textures));
        self
    }

    /// Adds a 3D Tiles terrain pyramid served as files at `/3dtiles/…`
    /// ([`tiles3d`]).
    pub fn with_tiles3d(mut self, files: tiles3d::Tiles3dFiles) -> Self {
        self.tiles3d = Some(Arc::new(files));
        self
    }

    /// Adds what the input gave warning of (seams between tiles that
    /// disagree, voids filled, heights held as f32 past a millimetre, ...),
    /// one sentence each: `/meta.json` carries them for the viewer's panel.
    pub fn with_warnings(mut self, warnings: Vec<String>) -> Self {
        self.warnings = Arc::new(warnings);
        self
    }

    /// The warnings served in `/meta.json`.
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Sets the stream (`Err`: why it could not be made; `/stream` then
    /// answers 500). Ignored when set before.
    pub fn set_stream(&self, stream: std::result::Result<StreamAsset, String>) {
        self.stream.set(stream);
    }

    /// Sets the tiles (`Ok(None)`: none are served, 404).
    pub fn set_tiles(&self, source: std::result::Result<Option<Arc<dyn TileSource>>, String>) {
        self.tiles.set(source.map(|s| s.map(Tiles::new)));
    }

    /// Sets the imagery (`Ok(None)`: none is served, 404).
    pub fn set_imagery(&self, imagery: std::result::Result<Option<Imagery>, String>) {
        self.imagery.set(imagery.map(|i| i.map(Arc::new)));
    }

    /// The stream, once made.
    pub fn stream(&self) -> Option<&StreamAsset> {
        self.stream.get()
    }

    /// The bounds this server keeps.
    pub fn options(&self) -> &ServeOptions {
        &self.options
    }
}

/// Serves `state` on `listener` until `shutdown` resolves; requests in
/// flight are completed first (at most [`DRAIN_S`] seconds). Bounds from
/// the state's [`ServeOptions`]: connections, header-read and request
/// timeouts (see [`serve_all`]).
///
/// # Errors
/// The listener's I/O error.
pub async fn serve(
    listener: tokio::net::TcpListener,
    state: ServerState,
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> std::io::Result<()> {
    serve_all(vec![listener], state, shutdown).await
}

/// [`serve`] on several listeners at once (the addresses a host name such
/// as `localhost` resolves to, IPv4 and IPv6).
///
/// # Errors
/// The listeners' I/O error.
pub async fn serve_all(
    listeners: Vec<tokio::net::TcpListener>,
    state: ServerState,
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> std::io::Result<()> {
    let opts = state.options;
    listen::serve_all(listeners, router(state), opts, shutdown).await
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

/// Binds every address of `addrs` it can (at least one), calls `ready` with
/// the bound addresses, and serves until SIGINT or SIGTERM (graceful:
/// requests in flight finish). The runtime has
/// [`ServeOptions::io_threads`] threads and at most 4 blocking threads;
/// tiles are made on the state's own pool.
///
/// # Errors
/// [`ServeError::Bind`] when no address can be bound,
/// [`ServeError::Internal`] when the runtime cannot start or the server fails.
pub fn run(
    addrs: &[SocketAddr],
    state: ServerState,
    ready: impl FnOnce(&[SocketAddr]),
) -> Result<()> {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(state.options.io_threads)
        .max_blocking_threads(4)
        .thread_name("cota-io")
        .enable_all()
        .build()
        .map_err(|e| ServeError::Internal(format!("cannot start the runtime: {e}")))?;
    rt.block_on(async move {
        let (listeners, bound) = bind_all(addrs).await?;
        ready(&bound);
        serve_all(listeners, state, shutdown_signal())
            .await
            .map_err(|e| ServeError::Internal(format!("server: {e}")))
    })
}

/// Binds each address; fails only when none binds (with the first error).
async fn bind_all(addrs: &[SocketAddr]) -> Result<(Vec<tokio::net::TcpListener>, Vec<SocketAddr>)> {
    let mut listeners = Vec::new();
    let mut bound = Vec::new();
    let mut first_err = None;
    for &addr in addrs {
        let r = async {
            let l = tokio::net::TcpListener::bind(addr).await?;
            let a = l.local_addr()?;
            Ok::<_, std::io::Error>((l, a))
        };
        match r.await {
            Ok((l, a)) => {
                listeners.push(l);
                bound.push(a);
            }
            Err(source) => {
                first_err.get_or_insert(ServeError::Bind {
                    addr: addr.to_string(),
                    source,
                });
            }
        }
    }
    match (bound.is_empty(), first_err) {
        (true, Some(e)) => Err(e),
        (true, None) => Err(ServeError::Internal("no address to listen on".into())),
        _ => Ok((listeners, bound)),
    }
}
