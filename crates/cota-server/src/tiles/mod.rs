//! Quantized-mesh tiles (Cesium's `quantized-mesh-1.0`, TMS scheme) for
//! `/tiles/layer.json`, `/layer.json` and `/tiles/{z}/{x}/{y}.terrain`.
//!
//! A [`TileSource`] answers the layer description and single tiles:
//! * [`DirTileSource`]: the directory `cota tiles` writes (`OUT/layer.json`,
//!   `OUT/{z}/{x}/{y}.terrain`, raw or gzipped);
//! * [`DemandTileSource`]: tiles made on demand from a prepared hierarchy in
//!   memory ([`cota_core::tiles::Prepared`], [`cota_tiles::make_tile`]).
//!
//! Sources neither cache nor limit: the server calls [`TileSource::tile`]
//! on its bounded worker pool, once per tile at a time, and keeps what it
//! sends in its byte-bounded cache (`ServeOptions`).
//!
//! **URL layout.** The tile set is mounted at `/tiles/` exactly as `cota
//! tiles` lays it out: `/tiles/layer.json` is the layer as written, whose
//! relative template `{z}/{x}/{y}.terrain` resolves to the route
//! `/tiles/{z}/{x}/{y}.terrain`, so a client pointed at `/tiles/` reads the
//! same bytes as from a static copy of the directory. `/layer.json` serves
//! the same layer for clients pointed at the server's root, its template
//! prefixed with `tiles/` ([`root_layer`]).

mod demand;
mod dir;
mod mbtiles;

use axum::body::Bytes;
use serde_json::Value;

use crate::error::{Result, ServeError};

pub use demand::DemandTileSource;
pub use dir::DirTileSource;
pub use mbtiles::MbtilesTileSource;

/// Largest tile file served.
pub const MAX_TILE_BYTES: u64 = 16 << 20;
/// Deepest zoom level accepted.
pub const MAX_ZOOM: u32 = 30;
/// Bytes of a quantized-mesh header (centre, heights, sphere, horizon point).
const QM_HEADER_BYTES: usize = 88;

/// A tile's address in the TMS pyramid (`y` counts from the south).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TileId {
    /// Zoom level.
    pub z: u32,
    /// Column from the west.
    pub x: u32,
    /// Row from the south.
    pub y: u32,
}

impl TileId {
    /// Parses the three path segments of `/tiles/{z}/{x}/{y}.terrain`.
    ///
    /// # Errors
    /// [`ServeError::BadRequest`] unless each is a decimal number of at most
    /// 10 digits (the last followed by `.terrain`) and `z ≤` [`MAX_ZOOM`].
    pub fn parse(z: &str, x: &str, y_file: &str) -> Result<Self> {
        Self::parse_file(z, x, y_file, ".terrain")
    }

    /// As [`TileId::parse`], the last segment ending in `ext` (`.png`).
    ///
    /// # Errors
    /// As [`TileId::parse`].
    pub fn parse_file(z: &str, x: &str, y_file: &str, ext: &str) -> Result<Self> {
        let y = y_file.strip_suffix(ext).ok_or_else(|| {
            ServeError::BadRequest(format!(
                "expected a tile file named {{y}}{ext}, found {:?}",
                clip(y_file)
            ))
        })?;
        let num = |what: &str, s: &str| -> Result<u32> {
            if s.is_empty() || s.len() > 10 || !s.bytes().all(|c| c.is_ascii_digit()) {
                return Err(ServeError::BadRequest(format!(
                    "expected a decimal tile {what}, found {:?}",
                    clip(s)
                )));
            }
            s.parse()
                .map_err(|_| ServeError::BadRequest(format!("tile {what} {s} is out of range")))
        };
        let id = TileId {
            z: num("level", z)?,
            x: num("column", x)?,
            y: num("row", y)?,
        };
        if id.z > MAX_ZOOM {
            return Err(ServeError::BadRequest(format!(
                "expected a tile level of at most {MAX_ZOOM}, found {}",
                id.z
            )));
        }
        Ok(id)
    }
}

/// At most 40 characters of `s`, for messages.
pub(crate) fn clip(s: &str) -> String {
    s.chars().take(40).collect()
}

/// One tile as served.
#[derive(Debug, Clone)]
pub struct Tile {
    /// The bytes, as stored (gzipped or not).
    pub bytes: Bytes,
    /// True when the bytes are gzip (sent with `Content-Encoding: gzip`).
    pub gzip: bool,
    /// Strong ETag, quoted.
    pub etag: String,
}

/// Files of a pyramid: each path (relative to its root) and bytes.
pub type Files = Vec<(String, Vec<u8>)>;

/// Where tiles come from.
pub trait TileSource: Send + Sync + 'static {
    /// The pyramid's `layer.json` as `cota tiles` writes it, served at
    /// `/tiles/layer.json`: its relative template `{z}/{x}/{y}.terrain`
    /// resolves to the `/tiles/{z}/{x}/{y}.terrain` route.
    fn layer_json(&self) -> &Bytes;

    /// Checks that the layer has tile `id`, cheaply (no disk, no making):
    /// the server asks before it queues [`TileSource::tile`].
    ///
    /// # Errors
    /// As [`TileSource::tile`] for a tile that is not in the layer.
    fn has(&self, id: TileId) -> Result<()>;

    /// The tile `id`. May block (disk, or making the tile): the server calls
    /// it on its worker pool.
    ///
    /// # Errors
    /// [`ServeError::NotFound`] for a tile the layer does not have,
    /// [`ServeError::BadRequest`] for coordinates outside the pyramid,
    /// [`ServeError::CorruptTile`] / [`ServeError::Io`] for a stored tile
    /// that cannot be served.
    fn tile(&self, id: TileId) -> Result<Tile>;

    /// The whole pyramid as 3D Tiles terrain, made in memory (path relative
    /// to `/3dtiles/`, bytes), for a source that can make it; `None` (the
    /// default) for one that cannot (a directory or an archive of
    /// quantized-mesh tiles). May take long: the server calls it once, off
    /// its async threads.
    fn tiles3d(&self) -> Option<std::result::Result<Files, String>> {
        None
    }

    /// True when [`TileSource::tiles3d`] can make them (cheap).
    fn makes_tiles3d(&self) -> bool {
        false
    }
}

/// Checks that `b` can be a tile: gzip, or a quantized-mesh header followed
/// by a vertex count that the file is long enough to hold.
pub fn check_tile_bytes(b: &[u8]) -> std::result::Result<(), (String, String)> {
    if is_gzip(b) {
        return if b.len() >= 18 {
            Ok(())
        } else {
            Err((
                "a gzip member of at least 18 bytes".into(),
                format!("{} bytes", b.len()),
            ))
        };
    }
    let Some(&[v0, v1, v2, v3]) = b.get(QM_HEADER_BYTES..QM_HEADER_BYTES + 4) else {
        return Err((
            "a quantized-mesh tile of at least 92 bytes, or gzip".into(),
            format!("{} bytes", b.len()),
        ));
    };
    let vertices = u32::from_le_bytes([v0, v1, v2, v3]) as u64;
    let need = (QM_HEADER_BYTES as u64 + 4) + 6 * vertices;
    if vertices < 3 || need > b.len() as u64 {
        return Err((
            format!("a quantized-mesh tile with at least 3 vertices and {need} bytes"),
            format!("{vertices} vertices in {} bytes", b.len()),
        ));
    }
    Ok(())
}

/// True when `b` starts with the gzip magic and the deflate method.
pub fn is_gzip(b: &[u8]) -> bool {
    b.starts_with(&[0x1f, 0x8b, 0x08])
}

/// The layer for `/layer.json`: `layer` with its `tiles` template set to
/// `tiles/{z}/{x}/{y}.terrain` (relative to the server's root); `layer`
/// itself when it is not a JSON object.
pub fn root_layer(layer: &Bytes) -> Bytes {
    let Ok(mut v) = serde_json::from_slice::<Value>(layer) else {
        return layer.clone();
    };
    let Some(obj) = v.as_object_mut() else {
        return layer.clone();
    };
    obj.insert(
        "tiles".into(),
        Value::from(vec!["tiles/{z}/{x}/{y}.terrain"]),
    );
    serde_json::to_vec_pretty(&v).map_or_else(|_| layer.clone(), Bytes::from)
}

/// Checks that `id` lies in the world's pyramid: `2^(z+1) × 2^z` tiles in
/// the geographic scheme, `2^z × 2^z` in the Mercator one.
///
/// # Errors
/// [`ServeError::BadRequest`] naming the tile and the level's size.
pub(crate) fn check_in_world(id: TileId, geographic: bool) -> Result<()> {
    let cols = if geographic {
        2u64 << id.z
    } else {
        1u64 << id.z
    };
    let rows = 1u64 << id.z;
    if id.x as u64 >= cols || id.y as u64 >= rows {
        return Err(ServeError::BadRequest(format!(
            "expected a tile within {cols}x{rows} at level {}, found column {}, row {}",
            id.z, id.x, id.y
        )));
    }
    Ok(())
}

/// The strong ETag of a tile's bytes.
pub(crate) fn etag_of(bytes: &[u8]) -> String {
    format!("\"{:016x}\"", crate::stream::fnv64(bytes))
}
