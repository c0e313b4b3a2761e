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
use crate::later::{Later, Stage};
use crate::range::{boundary, multipart, parse_range, Ranges};
use crate::stream::StreamAsset;
use crate::tiles::{Tile, TileId, MAX_TILE_BYTES};
use crate::work::Key;
use crate::{ServerState, Tiles};

/// Longest request target (path and query) served; longer ones get 414.
pub const MAX_URI_BYTES: usize = 2048;

/// `Content-Type` of the stream.
const STREAM_TYPE: &str = "application/vnd.cota.stream";
/// `Content-Type` of a quantized-mesh tile.
const TILE_TYPE: &str = "application/vnd.quantized-mesh";
/// `Cache-Control` of tiles and imagery: a day, then revalidated by ETag.
const TILE_CACHE: &str = "public, max-age=86400";

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
            header::RETRY_AFTER,
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
        .route("/3dtiles/{*path}", get(tiles3d_file))
        .route("/imagery.json", get(imagery_json))
        .route("/imagery/{z}/{x}/{y}", get(imagery_tile))
        .route(crate::texture::TEXTURE_URL, get(texture_image))
        .route(crate::texture::PAIR_URL, get(texture_pair))
        .fallback(embedded)
        .layer(middleware::from_fn_with_state(state.clone(), check_request))
        .with_state(state)
        .layer(cors)
}

/// Refuses, before any route: targets longer than [`MAX_URI_BYTES`] (414)
/// and paths with `..` segments, backslashes, NUL or encoded separators
/// (400); then answers 503 for a request not answered within the request
/// timeout.
async fn check_request(State(s): State<ServerState>, req: Request, next: Next) -> Response {
    if let Err(e) = check_uri(req.uri()) {
        return e.into_response();
    }
    let limit = s.options.request_timeout();
    match tokio::time::timeout(limit, next.run(req)).await {
        Ok(r) => r,
        Err(_) => ServeError::Unavailable {
            reason: format!("no answer within {} s", limit.as_secs()),
            retry_after_s: s.options.retry_after_s,
        }
        .into_response(),
    }
}

/// The value of `later` once made; 503 with `Retry-After` until then.
fn ready<'a, T>(s: &ServerState, later: &'a Later<T>) -> Result<&'a T> {
    match later.stage() {
        Stage::Ready(v) => Ok(v),
        Stage::Pending => Err(ServeError::Unavailable {
            reason: format!("{} is still being made at start", later.what()),
            retry_after_s: s.options.retry_after_s,
        }),
        Stage::Failed(e) => Err(ServeError::Internal(format!("{}: {e}", later.what()))),
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

/// Whether an optional part is served: `"yes"`, `"no"`, `"pending"` or `"failed"`.
fn served<T>(later: &Later<Option<T>>) -> &'static str {
    match later.stage() {
        Stage::Ready(Some(_)) => "yes",
        Stage::Ready(None) => "no",
        Stage::Pending => "pending",
        Stage::Failed(_) => "failed",
    }
}

async fn health(State(s): State<ServerState>) -> Response {
    let stream = s.stream.get();
    let body = serde_json::json!({
        "status": "ok",
        "viewer": if assets::BUILT { "built" } else { "missing" },
        "stream": s.stream.word(),
        "stream_bytes": stream.map(|a| a.bytes().len()),
        "steps": stream.map(|a| a.meta().steps.len()),
        "tiles": served(&s.tiles),
        "imagery": served(&s.imagery),
        "tiles3d": tiles3d_word(&s),
        "texture": s.textures.as_ref().map_or("no", |t| if t.pair.is_some() { "yes, and a pair" } else { "yes" }),
        "warnings": s.warnings.len(),
        "work": s.work.summary(),
    });
    let mut r = axum::Json(body).into_response();
    r.headers_mut()
        .insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    r
}

/// `/health`'s word for the 3D Tiles: "yes" (given with --tiles, or made),
/// "on request" (the tiles' source makes them on the first request),
/// "pending" (the tiles are still being prepared), "no".
fn tiles3d_word(s: &ServerState) -> &'static str {
    if s.tiles3d.is_some() || matches!(s.tiles3d_made.get(), Some(Ok(_))) {
        return "yes";
    }
    match s.tiles.get() {
        Some(Some(t)) if t.source.makes_tiles3d() => "on request",
        None if s.tiles.word() == "pending" => "pending",
        _ => "no",
    }
}

async fn meta(State(s): State<ServerState>, headers: HeaderMap) -> Result<Response> {
    let a = ready(&s, &s.stream)?;
    let mut v =
        serde_json::to_value(a.meta()).map_err(|e| ServeError::Internal(format!("meta: {e}")))?;
    if let Some(o) = v.as_object_mut() {
        o.insert("tiles".into(), (served(&s.tiles) != "no").into());
        o.insert("imagery".into(), (served(&s.imagery) != "no").into());
        let tex = s.textures.as_ref().map(|t| t.meta());
        let tex =
            serde_json::to_value(tex).map_err(|e| ServeError::Internal(format!("meta: {e}")))?;
        o.insert("texture".into(), tex);
        o.insert("warnings".into(), s.warnings.as_slice().into());
    }
    let body = serde_json::to_vec(&v).map_err(|e| ServeError::Internal(format!("meta: {e}")))?;
    // The ETag of the body, not of the stream: the same stream served with
    // another texture, other warnings or tiles must not be answered 304.
    let etag = crate::tiles::etag_of(&body);
    Ok(cached(
        &headers,
        Bytes::from(body),
        &[
            (header::CONTENT_TYPE, "application/json"),
            (header::CACHE_CONTROL, "no-cache"),
        ],
        &etag,
    ))
}

/// `If-Range` naming another version: the range does not apply.
fn if_range_stale(headers: &HeaderMap, etag: &str) -> bool {
    headers
        .get(header::IF_RANGE)
        .is_some_and(|v| v.as_bytes() != etag.as_bytes())
}

async fn stream(State(s): State<ServerState>, headers: HeaderMap) -> Result<Response> {
    let a = ready(&s, &s.stream)?;
    let extra = [
        (header::CONTENT_TYPE, STREAM_TYPE),
        (header::CACHE_CONTROL, "no-cache"),
        (header::ACCEPT_RANGES, "bytes"),
    ];
    let whole = || cached(&headers, a.bytes().clone(), &extra, a.etag());
    if if_range_stale(&headers, a.etag()) || not_modified(&headers, a.etag()) {
        return Ok(whole());
    }
    let (status, body, content_type, content_range) =
        match parse_range(&headers, a.bytes().len() as u64)? {
            Ranges::Whole => return Ok(whole()),
            Ranges::One(first, last) => one_range(a, first, last),
            Ranges::Many(parts) => match many_ranges(a, &parts) {
                Some(r) => r,
                None => return Ok(whole()),
            },
        };
    let mut r = (status, Body::from(body)).into_response();
    let h = r.headers_mut();
    h.insert(header::ETAG, header_value(a.etag()));
    for (k, v) in extra {
        h.insert(k, HeaderValue::from_static(v));
    }
    h.insert(header::CONTENT_TYPE, header_value(&content_type));
    if let Some(cr) = content_range {
        h.insert(header::CONTENT_RANGE, header_value(&cr));
    }
    Ok(r)
}

/// Status, body, type and `Content-Range` of a ranged answer.
type Ranged = (StatusCode, Bytes, String, Option<String>);

fn one_range(a: &StreamAsset, first: u64, last: u64) -> Ranged {
    let len = a.bytes().len();
    (
        StatusCode::PARTIAL_CONTENT,
        a.bytes().slice(first as usize..=last as usize),
        STREAM_TYPE.into(),
        Some(format!("bytes {first}-{last}/{len}")),
    )
}

/// `multipart/byteranges`, or `None` when no boundary fits (send the whole).
fn many_ranges(a: &StreamAsset, parts: &[(u64, u64)]) -> Option<Ranged> {
    let b = boundary(a.bytes(), parts, a.etag())?;
    let body = multipart(a.bytes(), parts, STREAM_TYPE, &b);
    Some((
        StatusCode::PARTIAL_CONTENT,
        Bytes::from(body),
        format!("multipart/byteranges; boundary={b}"),
        None,
    ))
}

/// The tile set, 503 while it is prepared, 404 when there is none.
fn tiles_of(s: &ServerState) -> Result<&Tiles> {
    ready(s, &s.tiles)?.as_ref().ok_or_else(|| {
        ServeError::NotFound(
            "no tile set: `cota serve` makes tiles from a geographic source, or serves --tiles DIR"
                .into(),
        )
    })
}

/// The imagery, 503 while it is prepared, 404 when there is none.
fn imagery_of(s: &ServerState) -> Result<&std::sync::Arc<crate::Imagery>> {
    ready(s, &s.imagery)?.as_ref().ok_or_else(|| {
        ServeError::NotFound("no imagery: it is drawn from a geographic source".into())
    })
}

/// `/tiles/layer.json`: the layer as the source has it.
async fn layer(State(s): State<ServerState>, headers: HeaderMap) -> Result<Response> {
    let t = tiles_of(&s)?;
    Ok(json_layer(&headers, t.source.layer_json().clone()))
}

/// `/layer.json`: the layer with its template relative to the root.
async fn root_layer(State(s): State<ServerState>, headers: HeaderMap) -> Result<Response> {
    let t = tiles_of(&s)?;
    Ok(json_layer(&headers, t.root_layer.clone()))
}

/// `/imagery.json`: where the relief tiles are (bounds, zooms, template).
async fn imagery_json(State(s): State<ServerState>, headers: HeaderMap) -> Result<Response> {
    let i = imagery_of(&s)?;
    Ok(json_layer(&headers, i.json().clone()))
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
    let src = tiles_of(&s)?.source.clone();
    let id = TileId::parse(&z, &x, &y)?;
    src.has(id)?;
    let t = s.work.get(Key::Terrain(id), move || src.tile(id)).await?;
    let vary = [(header::VARY, "Accept-Encoding")];
    if !t.gzip {
        return Ok(tile_response(&headers, t.bytes, &t.etag, TILE_TYPE, &vary));
    }
    if accepts_gzip(&headers) {
        let extra = [
            (header::VARY, "Accept-Encoding"),
            (header::CONTENT_ENCODING, "gzip"),
        ];
        return Ok(tile_response(&headers, t.bytes, &t.etag, TILE_TYPE, &extra));
    }
    // A client that does not take gzip gets the tile decompressed, under
    // its own validator.
    let plain = gunzip(&t.bytes)?;
    let etag = format!("{}-identity\"", t.etag.trim_end_matches('"'));
    Ok(tile_response(&headers, plain, &etag, TILE_TYPE, &vary))
}

/// The 3D Tiles pyramid made in memory from the tiles' source, on the
/// first request (later ones wait for it, then share it).
async fn made_tiles3d(s: &ServerState) -> Result<std::sync::Arc<crate::tiles3d::Tiles3dFiles>> {
    let source = tiles_of(s)?.source.clone();
    if !source.makes_tiles3d() {
        return Err(ServeError::NotFound(
            "no 3D Tiles: serve a cota tiles --format 3dtiles pyramid with --tiles DIR or OUT.3tz"
                .into(),
        ));
    }
    let once = s.tiles3d_made.clone();
    let made = tokio::task::spawn_blocking(move || {
        once.get_or_init(|| match source.tiles3d() {
            Some(Ok(files)) => Ok(std::sync::Arc::new(crate::tiles3d::Tiles3dFiles::Memory(
                files.into_iter().collect(),
            ))),
            Some(Err(e)) => Err(e),
            None => Err("the tiles' source makes no 3D Tiles".into()),
        })
        .clone()
    })
    .await
    .map_err(|e| ServeError::Internal(format!("3D Tiles: {e}")))?;
    made.map_err(|e| ServeError::Internal(format!("3D Tiles: {e}")))
}

/// `/3dtiles/{path}`: a file of the 3D Tiles pyramid given with `--tiles`.
async fn tiles3d_file(
    State(s): State<ServerState>,
    Path(path): Path<String>,
    headers: HeaderMap,
) -> Result<Response> {
    let files = match s.tiles3d.clone() {
        Some(f) => f,
        None => made_tiles3d(&s).await?,
    };
    let rel = path.clone();
    let bytes = tokio::task::spawn_blocking(move || files.get(&rel))
        .await
        .map_err(|e| ServeError::Internal(format!("3D Tiles: {e}")))?
        .map_err(|e| ServeError::Internal(format!("3D Tiles {path}: {e}")))?
        .ok_or_else(|| ServeError::NotFound(format!("/3dtiles/{path}")))?;
    let etag = crate::tiles::etag_of(&bytes);
    // tileset.json, GLBs and subtrees: the embedded files' media types.
    let kind = crate::assets::mime(&path);
    Ok(tile_response(
        &headers,
        Bytes::from(bytes),
        &etag,
        kind,
        &[],
    ))
}

async fn imagery_tile(
    State(s): State<ServerState>,
    Path((z, x, y)): Path<(String, String, String)>,
    headers: HeaderMap,
) -> Result<Response> {
    let img = imagery_of(&s)?.clone();
    let id = TileId::parse_file(&z, &x, &y, ".png")?;
    img.check(id)?;
    let t: Tile = s.work.get(Key::Imagery(id), move || img.tile(id)).await?;
    Ok(tile_response(&headers, t.bytes, &t.etag, "image/png", &[]))
}

/// `/texture.png`: the image draped on the terrain.
async fn texture_image(State(s): State<ServerState>, headers: HeaderMap) -> Result<Response> {
    let t = s.textures.as_ref().ok_or_else(|| {
        ServeError::NotFound("no texture: `cota serve DEM --texture IMAGE` drapes one".into())
    })?;
    Ok(png_response(&headers, &t.image))
}

/// `/texture-pair.png`: paper 004's chosen texture level.
async fn texture_pair(State(s): State<ServerState>, headers: HeaderMap) -> Result<Response> {
    let t = s.textures.as_ref().and_then(|t| t.pair.as_ref());
    let t = t.ok_or_else(|| {
        ServeError::NotFound(
            "no pair: `cota serve DEM --texture IMAGE --pair-budget-bytes N` chooses one".into(),
        )
    })?;
    Ok(png_response(&headers, t))
}

fn png_response(headers: &HeaderMap, t: &crate::TextureLevel) -> Response {
    let extra = [
        (header::CONTENT_TYPE, "image/png"),
        (header::CACHE_CONTROL, "no-cache"),
    ];
    cached(headers, t.png().clone(), &extra, t.etag())
}

fn tile_response(
    headers: &HeaderMap,
    body: Bytes,
    etag: &str,
    content_type: &str,
    extra: &[(HeaderName, &str)],
) -> Response {
    let mut all = vec![
        (header::CONTENT_TYPE, content_type),
        (header::CACHE_CONTROL, TILE_CACHE),
    ];
    all.extend(extra.iter().cloned());
    cached(headers, body, &all, etag)
}

/// True when `Accept-Encoding` lists gzip (or `*`) with a nonzero quality.
/// Without the header the tile is sent decompressed: RFC 9110 §12.5.3
/// would allow any coding, but clients that send none (curl, scripts)
/// expect the plain bytes.
fn accepts_gzip(headers: &HeaderMap) -> bool {
    let mut gzip = None;
    let mut star = None;
    for v in headers.get_all(header::ACCEPT_ENCODING) {
        let Ok(s) = v.to_str() else { continue };
        for item in s.split(',') {
            let mut parts = item.split(';');
            let coding = parts.next().unwrap_or("").trim().to_ascii_lowercase();
            let q = parts
                .find_map(|p| p.trim().strip_prefix("q=").or(p.trim().strip_prefix("Q=")))
                .and_then(|q| q.trim().parse::<f32>().ok())
                .unwrap_or(1.0);
            match coding.as_str() {
                "gzip" | "x-gzip" => gzip = Some(q > 0.0),
                "*" => star = Some(q > 0.0),
                _ => {}
            }
        }
    }
    gzip.or(star).unwrap_or(false)
}

/// Decompresses a stored gzip tile, at most [`MAX_TILE_BYTES`].
fn gunzip(b: &[u8]) -> Result<Bytes> {
    use std::io::Read;
    let mut out = Vec::new();
    let mut d = flate2::read::MultiGzDecoder::new(b).take(MAX_TILE_BYTES + 1);
    d.read_to_end(&mut out)
        .map_err(|e| ServeError::Internal(format!("a stored gzip tile does not inflate: {e}")))?;
    if out.len() as u64 > MAX_TILE_BYTES {
        return Err(ServeError::Internal(format!(
            "a stored gzip tile inflates past {MAX_TILE_BYTES} bytes"
        )));
    }
    Ok(Bytes::from(out))
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
    fn gzip_acceptance() {
        let acc = |v: Option<&str>| {
            let mut h = HeaderMap::new();
            if let Some(v) = v {
                h.insert(header::ACCEPT_ENCODING, HeaderValue::from_str(v).unwrap());
            }
            accepts_gzip(&h)
        };
        assert!(acc(Some("gzip, deflate, br")));
        assert!(acc(Some("br;q=1.0, gzip;q=0.8")));
        assert!(acc(Some("*")));
        assert!(!acc(None));
        assert!(!acc(Some("identity")));
        assert!(!acc(Some("gzip;q=0")));
        assert!(!acc(Some("*, gzip;q=0")));
        assert!(!acc(Some("br")));
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
