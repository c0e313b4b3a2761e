//! The routes, the request checks every route shares, and the response
//! headers (types, ranges, validators, caching, CORS).

use axum::body::{Body, Bytes};
use axum::extract::{Path, Request, State};
use axum::http::header::{self, HeaderMap, HeaderName, HeaderValue};
use axum::http::{Method, StatusCode, Uri};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use axum::Router;
use tower_http::cors::{Any, CorsLayer};

use crate::assets;
use crate::error::{Result, ServeError};
use crate::range::parse_range;
use crate::tiles::TileId;
use crate::ServerState;

/// Longest request target (path and query) served; longer ones get 414.
pub const MAX_URI_BYTES: usize = 2048;

/// `Content-Type` of the stream.
const STREAM_TYPE: &str = "application/vnd.cota.stream";
/// `Content-Type` of a quantized-mesh tile.
const TILE_TYPE: &str = "application/vnd.quantized-mesh";

/// The whole service: routes, request checks, CORS. No socket involved.
pub fn router(state: ServerState) -> Router {
    let cors = CorsLayer::new()
        .allow_origin(Any)
        .allow_methods([Method::GET, Method::HEAD])
        .allow_headers([header::RANGE, header::IF_NONE_MATCH, header::IF_RANGE])
        .expose_headers([
            header::CONTENT_RANGE,
            header::CONTENT_LENGTH,
            header::ACCEPT_RANGES,
            header::ETAG,
            header::CONTENT_ENCODING,
        ]);
    Router::new()
        .route("/", get(index))
        .route("/cesium", get(cesium))
        .route("/health", get(health))
        .route("/meta.json", get(meta))
        .route("/stream", get(stream))
        .route("/layer.json", get(root_layer))
        .route("/tiles/layer.json", get(layer))
        .route("/tiles/{z}/{x}/{y}", get(tile))
        .fallback(embedded)
        .with_state(state)
        .layer(middleware::from_fn(check_request))
        .layer(cors)
}

/// Refuses, before any route: targets longer than [`MAX_URI_BYTES`] (414)
/// and paths with `..` segments, backslashes, NUL or encoded separators (400).
async fn check_request(req: Request, next: Next) -> Response {
    match check_uri(req.uri()) {
        Ok(()) => next.run(req).await,
        Err(e) => e.into_response(),
    }
}

fn check_uri(uri: &Uri) -> Result<()> {
    let len = uri.path_and_query().map_or(0, |p| p.as_str().len());
    if len > MAX_URI_BYTES {
        return Err(ServeError::UriTooLong {
            len,
            limit: MAX_URI_BYTES,
        });
    }
    let path = uri.path();
    let lower = path.to_ascii_lowercase();
    let encoded = ["%2e", "%2f", "%5c", "%00"]
        .iter()
        .any(|e| lower.contains(e));
    let dots = path.split('/').any(|s| s == ".." || s == ".");
    if encoded || dots || path.contains('\\') || path.contains('\0') {
        return Err(ServeError::BadRequest(format!(
            "expected a plain path without '..', '.', '\\' or encoded separators, found {:?}",
            path.chars().take(80).collect::<String>()
        )));
    }
    Ok(())
}

/// True when `If-None-Match` lists `etag` (or `*`).
fn not_modified(headers: &HeaderMap, etag: &str) -> bool {
    headers.get_all(header::IF_NONE_MATCH).iter().any(|v| {
        v.to_str().is_ok_and(|s| {
            s.split(',')
                .map(|t| t.trim().trim_start_matches("W/"))
                .any(|t| t == "*" || t == etag)
        })
    })
}

fn header_value(s: &str) -> HeaderValue {
    HeaderValue::from_str(s).unwrap_or_else(|_| HeaderValue::from_static("invalid"))
}

/// A 200 (or 304 when the client holds `etag`) with caching headers.
fn cached(headers: &HeaderMap, body: Bytes, extra: &[(HeaderName, &str)], etag: &str) -> Response {
    let mut r = if not_modified(headers, etag) {
        StatusCode::NOT_MODIFIED.into_response()
    } else {
        (StatusCode::OK, body).into_response()
    };
    let h = r.headers_mut();
    h.insert(header::ETAG, header_value(etag));
    for (k, v) in extra {
        h.insert(k.clone(), header_value(v));
    }
    r
}

fn embedded_file(headers: &HeaderMap, path: &str) -> Result<Response> {
    let f = assets::find(path).ok_or_else(|| ServeError::NotFound(format!("/{path}")))?;
    let etag = format!("\"{}\"", f.etag);
    Ok(cached(
        headers,
        Bytes::from_static(f.bytes),
        &[
            (header::CONTENT_TYPE, assets::mime(path)),
            (header::CACHE_CONTROL, assets::cache_control(path)),
        ],
        &etag,
    ))
}

async fn index(headers: HeaderMap) -> Result<Response> {
    embedded_file(&headers, "index.html")
}

async fn cesium(headers: HeaderMap) -> Result<Response> {
    embedded_file(&headers, "cesium.html")
}

async fn embedded(headers: HeaderMap, uri: Uri) -> Result<Response> {
    let path = uri.path().trim_start_matches('/');
    embedded_file(&headers, path)
}

async fn health(State(s): State<ServerState>) -> Response {
    let body = serde_json::json!({
        "status": "ok",
        "viewer": if assets::BUILT { "built" } else { "missing" },
        "stream_bytes": s.stream.bytes().len(),
        "steps": s.stream.meta().steps.len(),
        "tiles": s.tiles.is_some(),
    });
    let mut r = axum::Json(body).into_response();
    r.headers_mut()
        .insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    r
}

async fn meta(State(s): State<ServerState>, headers: HeaderMap) -> Result<Response> {
    let mut v = serde_json::to_value(s.stream.meta())
        .map_err(|e| ServeError::Internal(format!("meta: {e}")))?;
    if let Some(o) = v.as_object_mut() {
        o.insert("tiles".into(), s.tiles.is_some().into());
    }
    let body = serde_json::to_vec(&v).map_err(|e| ServeError::Internal(format!("meta: {e}")))?;
    Ok(cached(
        &headers,
        Bytes::from(body),
        &[
            (header::CONTENT_TYPE, "application/json"),
            (header::CACHE_CONTROL, "no-cache"),
        ],
        s.stream.etag(),
    ))
}

/// `If-Range` naming another version: the range does not apply.
fn if_range_stale(headers: &HeaderMap, etag: &str) -> bool {
    headers
        .get(header::IF_RANGE)
        .is_some_and(|v| v.as_bytes() != etag.as_bytes())
}

async fn stream(State(s): State<ServerState>, headers: HeaderMap) -> Result<Response> {
    let a = &s.stream;
    let len = a.bytes().len() as u64;
    let range = parse_range(&headers, len)?;
    let extra = [
        (header::CONTENT_TYPE, STREAM_TYPE),
        (header::CACHE_CONTROL, "no-cache"),
        (header::ACCEPT_RANGES, "bytes"),
    ];
    let (first, last) = match range {
        Some(r) if !if_range_stale(&headers, a.etag()) && !not_modified(&headers, a.etag()) => r,
        _ => return Ok(cached(&headers, a.bytes().clone(), &extra, a.etag())),
    };
    let body = a.bytes().slice(first as usize..=last as usize);
    let mut r = (StatusCode::PARTIAL_CONTENT, Body::from(body)).into_response();
    let h = r.headers_mut();
    h.insert(header::ETAG, header_value(a.etag()));
    for (k, v) in extra {
        h.insert(k, HeaderValue::from_static(v));
    }
    h.insert(
        header::CONTENT_RANGE,
        header_value(&format!("bytes {first}-{last}/{len}")),
    );
    Ok(r)
}

fn no_tiles() -> ServeError {
    ServeError::NotFound(
        "no tile set: `cota serve` makes tiles from a geographic source, or serves --tiles DIR"
            .into(),
    )
}

/// `/tiles/layer.json`: the layer as the source has it.
async fn layer(State(s): State<ServerState>, headers: HeaderMap) -> Result<Response> {
    let t = s.tiles.as_ref().ok_or_else(no_tiles)?;
    Ok(json_layer(&headers, t.source.layer_json().clone()))
}

/// `/layer.json`: the layer with its template relative to the root.
async fn root_layer(State(s): State<ServerState>, headers: HeaderMap) -> Result<Response> {
    let t = s.tiles.as_ref().ok_or_else(no_tiles)?;
    Ok(json_layer(&headers, t.root_layer.clone()))
}

fn json_layer(headers: &HeaderMap, body: Bytes) -> Response {
    let etag = crate::tiles::etag_of(&body);
    cached(
        headers,
        body,
        &[
            (header::CONTENT_TYPE, "application/json"),
            (header::CACHE_CONTROL, "no-cache"),
        ],
        &etag,
    )
}

async fn tile(
    State(s): State<ServerState>,
    Path((z, x, y)): Path<(String, String, String)>,
    headers: HeaderMap,
) -> Result<Response> {
    let src = s.tiles.as_ref().ok_or_else(no_tiles)?.source.clone();
    let id = TileId::parse(&z, &x, &y)?;
    let t = match src.cached(id) {
        Some(t) => t,
        None => tokio::task::spawn_blocking(move || src.tile(id))
            .await
            .map_err(|e| ServeError::Internal(format!("tile task: {e}")))??,
    };
    let mut extra = vec![
        (header::CONTENT_TYPE, TILE_TYPE),
        (header::CACHE_CONTROL, "public, max-age=86400"),
    ];
    if t.gzip {
        extra.push((header::CONTENT_ENCODING, "gzip"));
    }
    Ok(cached(&headers, t.bytes, &extra, &t.etag))
}

#[cfg(test)]
mod test {
    use super::*;

    #[test]
    fn uri_checks() {
        let ok = |s: &str| check_uri(&s.parse::<Uri>().unwrap()).is_ok();
        assert!(ok("/tiles/1/2/3.terrain"));
        assert!(ok("/assets/main.js?x=1"));
        assert!(!ok("/tiles/../../etc/passwd"));
        assert!(!ok("/assets/%2e%2e/%2E%2E/etc/passwd"));
        assert!(!ok("/a/%2F/b"));
        assert!(!ok("/a/./b"));
        assert!(!ok(&format!("/{}", "a".repeat(3000))));
    }

    #[test]
    fn etag_lists() {
        let mut h = HeaderMap::new();
        h.insert(
            header::IF_NONE_MATCH,
            HeaderValue::from_static("\"x\", W/\"y\""),
        );
        assert!(not_modified(&h, "\"y\""));
        assert!(!not_modified(&h, "\"z\""));
    }
}
