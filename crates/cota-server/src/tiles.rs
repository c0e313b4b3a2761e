//! Quantized-mesh tiles (Cesium's `quantized-mesh-1.0`, TMS scheme) for
//! `/layer.json` and `/tiles/{z}/{x}/{y}.terrain`.
//!
//! A [`TileSource`] answers the layer description and single tiles. Today's
//! source is [`DirTileSource`], the directory `cota tiles` writes
//! (`OUT/layer.json`, `OUT/{z}/{x}/{y}.terrain`, raw or gzipped). A source
//! that makes tiles on demand from the in-memory hierarchy (and caches them)
//! plugs in through the same trait.
//!
//! A directory source only ever opens `root/{z}/{x}/{y}.terrain` built from
//! three parsed numbers inside the layer's bounds, refuses files whose real
//! path leaves the root (symbolic links), files larger than
//! [`MAX_TILE_BYTES`], and files that are neither gzip nor a plausible
//! quantized-mesh tile (too short for its header and vertex count).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::RwLock;

use axum::body::Bytes;
use serde_json::Value;

use crate::error::{Result, ServeError};
use crate::stream::fnv64;

/// Largest tile file served.
pub const MAX_TILE_BYTES: u64 = 16 << 20;
/// Largest `layer.json` read.
const MAX_LAYER_BYTES: u64 = 16 << 20;
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
        let y = y_file.strip_suffix(".terrain").ok_or_else(|| {
            ServeError::BadRequest(format!(
                "expected a tile file named {{y}}.terrain, found {:?}",
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
fn clip(s: &str) -> String {
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

/// Where tiles come from.
pub trait TileSource: Send + Sync + 'static {
    /// The `layer.json` to serve, its `tiles` template pointing at
    /// `tiles/{z}/{x}/{y}.terrain`.
    fn layer_json(&self) -> &Bytes;

    /// The tile `id`. May block (disk, or making the tile): the server calls
    /// it on the blocking pool.
    ///
    /// # Errors
    /// [`ServeError::NotFound`] for a tile the layer does not have,
    /// [`ServeError::BadRequest`] for coordinates outside the pyramid,
    /// [`ServeError::CorruptTile`] / [`ServeError::Io`] for a stored tile
    /// that cannot be served.
    fn tile(&self, id: TileId) -> Result<Tile>;

    /// The tile `id` if the source holds it in memory already: answered
    /// without the blocking pool. Default: `None`.
    fn cached(&self, id: TileId) -> Option<Tile> {
        let _ = id;
        None
    }
}

/// An inclusive rectangle of tiles of one level (`layer.json`'s `available`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct TileRange {
    start_x: u32,
    start_y: u32,
    end_x: u32,
    end_y: u32,
}

/// Bytes of tiles a [`DirTileSource`] keeps in memory.
pub const CACHE_BYTES: usize = 256 << 20;

/// The tiles of a `cota tiles` output directory. Tiles read once are kept in
/// memory (up to [`CACHE_BYTES`]): the directory is taken as immutable while
/// it is served.
#[derive(Debug)]
pub struct DirTileSource {
    root: PathBuf,
    layer: Bytes,
    max_zoom: u32,
    geographic: bool,
    available: Option<Vec<Vec<TileRange>>>,
    cache: RwLock<(HashMap<TileId, Tile>, usize)>,
}

impl DirTileSource {
    /// Opens `dir` and reads, checks and rewrites its `layer.json`.
    ///
    /// # Errors
    /// [`ServeError::Io`] when the directory or `layer.json` cannot be read,
    /// [`ServeError::BadTileSet`] when `layer.json` is not a quantized-mesh
    /// layer (not JSON, wrong `format`, bad `available` or `maxzoom`).
    pub fn open(dir: &Path) -> Result<Self> {
        let io = |path: &Path| {
            let path = path.to_path_buf();
            move |source| ServeError::Io { path, source }
        };
        let root = dir.canonicalize().map_err(io(dir))?;
        let layer_path = root.join("layer.json");
        let size = std::fs::metadata(&layer_path)
            .map_err(io(&layer_path))?
            .len();
        if size > MAX_LAYER_BYTES {
            return Err(bad_set(
                &layer_path,
                &format!("at most {MAX_LAYER_BYTES} bytes"),
                &format!("{size} bytes"),
            ));
        }
        let text = std::fs::read(&layer_path).map_err(io(&layer_path))?;
        let mut v: Value = serde_json::from_slice(&text)
            .map_err(|e| bad_set(&layer_path, "a JSON object", &format!("invalid JSON ({e})")))?;
        let parsed = parse_layer(&layer_path, &v)?;
        if let Some(obj) = v.as_object_mut() {
            obj.insert(
                "tiles".into(),
                Value::from(vec!["tiles/{z}/{x}/{y}.terrain"]),
            );
        }
        let layer = serde_json::to_vec_pretty(&v)
            .map_err(|e| bad_set(&layer_path, "JSON", &e.to_string()))?;
        Ok(DirTileSource {
            root,
            layer: Bytes::from(layer),
            max_zoom: parsed.0,
            geographic: parsed.1,
            available: parsed.2,
            cache: RwLock::new((HashMap::new(), 0)),
        })
    }

    /// Checks that `id` lies in the pyramid and in the layer.
    fn check(&self, id: TileId) -> Result<()> {
        let cols = if self.geographic {
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
        let listed = match &self.available {
            None => id.z <= self.max_zoom,
            Some(levels) => levels.get(id.z as usize).is_some_and(|rs| {
                rs.iter().any(|r| {
                    (r.start_x..=r.end_x).contains(&id.x) && (r.start_y..=r.end_y).contains(&id.y)
                })
            }),
        };
        if listed {
            Ok(())
        } else {
            Err(ServeError::NotFound(format!(
                "tile {}/{}/{} is not in the layer",
                id.z, id.x, id.y
            )))
        }
    }
}

fn bad_set(path: &Path, expected: &str, found: &str) -> ServeError {
    ServeError::BadTileSet {
        path: path.to_path_buf(),
        expected: expected.into(),
        found: found.into(),
    }
}

type Parsed = (u32, bool, Option<Vec<Vec<TileRange>>>);

/// `maxzoom`, whether the projection is geographic, and `available`.
fn parse_layer(path: &Path, v: &Value) -> Result<Parsed> {
    let obj = v
        .as_object()
        .ok_or_else(|| bad_set(path, "a JSON object", "another JSON value"))?;
    match obj.get("format").and_then(Value::as_str) {
        Some("quantized-mesh-1.0") => {}
        other => {
            return Err(bad_set(
                path,
                "\"format\": \"quantized-mesh-1.0\"",
                &format!("{other:?}"),
            ))
        }
    }
    let geographic = match obj.get("projection").and_then(Value::as_str) {
        None | Some("EPSG:4326") => true,
        Some("EPSG:3857") => false,
        Some(p) => return Err(bad_set(path, "EPSG:4326 or EPSG:3857", p)),
    };
    let available = match obj.get("available") {
        None => None,
        Some(a) => Some(parse_available(path, a)?),
    };
    let max_zoom = match obj.get("maxzoom") {
        None => available
            .as_ref()
            .map_or(0, |a| a.len().saturating_sub(1) as u32),
        Some(m) => m
            .as_u64()
            .filter(|&z| z <= MAX_ZOOM as u64)
            .ok_or_else(|| bad_set(path, "maxzoom from 0 to 30", &m.to_string()))?
            as u32,
    };
    Ok((max_zoom, geographic, available))
}

fn parse_available(path: &Path, a: &Value) -> Result<Vec<Vec<TileRange>>> {
    let expected =
        "\"available\": an array of levels, each an array of {startX, startY, endX, endY}";
    let bad = |found: &str| bad_set(path, expected, found);
    let levels = a.as_array().ok_or_else(|| bad("not an array"))?;
    if levels.len() > MAX_ZOOM as usize + 1 {
        return Err(bad(&format!("{} levels", levels.len())));
    }
    let field = |r: &Value, k: &str| -> Result<u32> {
        r.get(k)
            .and_then(Value::as_u64)
            .and_then(|x| u32::try_from(x).ok())
            .ok_or_else(|| {
                bad(&format!(
                    "a range without a valid {k}: {}",
                    clip(&r.to_string())
                ))
            })
    };
    levels
        .iter()
        .map(|l| {
            let rs = l
                .as_array()
                .ok_or_else(|| bad("a level that is not an array"))?;
            rs.iter()
                .map(|r| {
                    Ok(TileRange {
                        start_x: field(r, "startX")?,
                        start_y: field(r, "startY")?,
                        end_x: field(r, "endX")?,
                        end_y: field(r, "endY")?,
                    })
                })
                .collect()
        })
        .collect()
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

impl TileSource for DirTileSource {
    fn layer_json(&self) -> &Bytes {
        &self.layer
    }

    fn cached(&self, id: TileId) -> Option<Tile> {
        self.cache.read().ok()?.0.get(&id).cloned()
    }

    fn tile(&self, id: TileId) -> Result<Tile> {
        self.check(id)?;
        if let Some(t) = self.cached(id) {
            return Ok(t);
        }
        let t = self.read(id)?;
        if let Ok(mut c) = self.cache.write() {
            if c.1 + t.bytes.len() <= CACHE_BYTES {
                c.1 += t.bytes.len();
                c.0.insert(id, t.clone());
            }
        }
        Ok(t)
    }
}

impl DirTileSource {
    /// Reads and checks the file of tile `id`.
    fn read(&self, id: TileId) -> Result<Tile> {
        let rel = format!("{}/{}/{}.terrain", id.z, id.x, id.y);
        let missing = || ServeError::NotFound(format!("tile {rel}"));
        let path = self.root.join(&rel);
        // The real path must stay inside the root (a link may point elsewhere).
        let real = path.canonicalize().map_err(|_| missing())?;
        if !real.starts_with(&self.root) {
            return Err(missing());
        }
        let io = |source| ServeError::Io {
            path: path.clone(),
            source,
        };
        let meta = std::fs::metadata(&real).map_err(io)?;
        if !meta.is_file() {
            return Err(missing());
        }
        if meta.len() > MAX_TILE_BYTES {
            return Err(ServeError::CorruptTile {
                path: path.clone(),
                expected: format!("at most {MAX_TILE_BYTES} bytes"),
                found: format!("{} bytes", meta.len()),
            });
        }
        let bytes = std::fs::read(&real).map_err(io)?;
        check_tile_bytes(&bytes).map_err(|(expected, found)| ServeError::CorruptTile {
            path: path.clone(),
            expected,
            found,
        })?;
        Ok(Tile {
            gzip: is_gzip(&bytes),
            etag: format!("\"{:016x}\"", fnv64(&bytes)),
            bytes: Bytes::from(bytes),
        })
    }
}
