//! The server's errors and the one function that maps them to HTTP statuses
//! ([`status_of`], as martin's `map_internal_error` does for its server).

use std::path::PathBuf;

use axum::http::{header, HeaderValue, StatusCode};
use axum::response::{IntoResponse, Response};

/// Everything a request or the server's start can fail with.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ServeError {
    /// Nothing is served at this path, or the tile does not exist.
    #[error("not found: {0}")]
    NotFound(String),
    /// A malformed request: bad tile coordinates, a bad `Range`, `..` in a path.
    #[error("bad request: {0}")]
    BadRequest(String),
    /// A well-formed `Range` that selects no byte of the stream, or several ranges.
    #[error("range not satisfiable: {range:?} for {len} bytes")]
    RangeNotSatisfiable {
        /// The `Range` header as received (cut to 64 characters).
        range: String,
        /// Length of the resource.
        len: u64,
    },
    /// A request target longer than the server reads.
    #[error("URI too long: {len} bytes, at most {limit} are served")]
    UriTooLong {
        /// Its length.
        len: usize,
        /// The limit.
        limit: usize,
    },
    /// A tile file that is not a quantized-mesh tile (raw or gzipped).
    #[error("corrupt tile {path}: expected {expected}, found {found}")]
    CorruptTile {
        /// The file.
        path: PathBuf,
        /// What a tile needs.
        expected: String,
        /// What the file holds.
        found: String,
    },
    /// A tile directory that cannot be served (at start).
    #[error("bad tile set {path}: expected {expected}, found {found}")]
    BadTileSet {
        /// The directory or its `layer.json`.
        path: PathBuf,
        /// What was expected.
        expected: String,
        /// What was found.
        found: String,
    },
    /// Tiles cannot be made from the source (at start).
    #[error("tiles: {0}")]
    Tiling(#[from] cota_core::tiles::TilesError),
    /// Shaded relief cannot be drawn from the source (at start).
    #[error("imagery: {0}")]
    Relief(#[from] cota_core::relief::ReliefError),
    /// A texture cannot be encoded (at start).
    #[error("texture: {0}")]
    Texture(#[from] cota_io::export::ExportError),
    /// Reading a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// The stream given to the server does not decode.
    #[error("stream {name}: {reason}")]
    BadStream {
        /// Where it came from.
        name: String,
        /// Why it was refused.
        reason: String,
    },
    /// The listening socket cannot be opened.
    #[error("cannot listen on {addr}")]
    Bind {
        /// The address asked for.
        addr: String,
        /// The cause.
        source: std::io::Error,
    },
    /// The server cannot answer now: its tile queue is full, or what the
    /// request needs is still being made at start (the stream, the tiles).
    /// Sent as 503 with `Retry-After`.
    #[error("service unavailable: {reason}; retry in {retry_after_s} s")]
    Unavailable {
        /// Why.
        reason: String,
        /// Seconds to wait.
        retry_after_s: u64,
    },
    /// One error shared by every request that waited on the same work.
    #[error(transparent)]
    Shared(std::sync::Arc<ServeError>),
    /// Our bug: a task panicked or was cancelled.
    #[error("internal error: {0}")]
    Internal(String),
}

/// The server's result type.
pub type Result<T> = std::result::Result<T, ServeError>;

/// The HTTP status of an error: the one place where errors meet statuses.
pub fn status_of(e: &ServeError) -> StatusCode {
    match e {
        ServeError::NotFound(_) => StatusCode::NOT_FOUND,
        ServeError::BadRequest(_) => StatusCode::BAD_REQUEST,
        ServeError::RangeNotSatisfiable { .. } => StatusCode::RANGE_NOT_SATISFIABLE,
        ServeError::UriTooLong { .. } => StatusCode::URI_TOO_LONG,
        ServeError::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
            StatusCode::NOT_FOUND
        }
        ServeError::Unavailable { .. } => StatusCode::SERVICE_UNAVAILABLE,
        ServeError::Shared(e) => status_of(e),
        ServeError::CorruptTile { .. }
        | ServeError::BadTileSet { .. }
        | ServeError::Tiling(_)
        | ServeError::Relief(_)
        | ServeError::Texture(_)
        | ServeError::Io { .. }
        | ServeError::BadStream { .. }
        | ServeError::Bind { .. }
        | ServeError::Internal(_) => StatusCode::INTERNAL_SERVER_ERROR,
    }
}

impl IntoResponse for ServeError {
    fn into_response(self) -> Response {
        let status = status_of(&self);
        let inner = match &self {
            ServeError::Shared(e) => e.as_ref(),
            e => e,
        };
        // Server-side failures name files on disk: log them, tell the client less.
        let body = if let ServeError::Unavailable { .. } = inner {
            format!("{inner}\n")
        } else if status.is_server_error() {
            eprintln!("cota serve: {self}");
            match inner {
                ServeError::CorruptTile { .. } => "corrupt tile\n".to_string(),
                _ => "internal server error\n".to_string(),
            }
        } else {
            format!("{self}\n")
        };
        let mut r = (status, body).into_response();
        let h = r.headers_mut();
        match inner {
            ServeError::RangeNotSatisfiable { len, .. } => {
                if let Ok(v) = HeaderValue::from_str(&format!("bytes */{len}")) {
                    h.insert(header::CONTENT_RANGE, v);
                }
            }
            ServeError::Unavailable { retry_after_s, .. } => {
                h.insert(header::RETRY_AFTER, HeaderValue::from(*retry_after_s));
                h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
            }
            _ => {}
        }
        r
    }
}
