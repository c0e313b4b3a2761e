//! [`DirTileSource`]: the tiles of a `cota tiles` output directory.
//!
//! It only ever opens `root/{z}/{x}/{y}.terrain` built from three parsed
//! numbers inside the layer's bounds, refuses files whose real path leaves
//! the root (symbolic links), files larger than [`MAX_TILE_BYTES`], and
//! files that are neither gzip nor a plausible quantized-mesh tile (too
//! short for its header and vertex count). Layout: the quantized-mesh-1.0
//! specification (CesiumGS/quantized-mesh), `layer.json` as TileJSON 2.1.

use std::path::{Path, PathBuf};

use axum::body::Bytes;
use serde_json::Value;

use super::{
    check_in_world, check_tile_bytes, clip, etag_of, is_gzip, Tile, TileId, TileSource,
    MAX_TILE_BYTES, MAX_ZOOM,
};
use crate::error::{Result, ServeError};

/// Largest `layer.json` read.
const MAX_LAYER_BYTES: u64 = 16 << 20;

/// An inclusive rectangle of tiles of one level (`layer.json`'s `available`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct TileRange {
    start_x: u32,
    start_y: u32,
    end_x: u32,
    end_y: u32,
}

/// The tiles of a `cota tiles` output directory (the server keeps those it
/// sent in its cache: the directory is taken as immutable while it is
/// served).
#[derive(Debug)]
pub struct DirTileSource {
    root: PathBuf,
    index: LayerIndex,
}

/// A `layer.json` served as it is, and what decides which tiles it has.
#[derive(Debug)]
pub(crate) struct LayerIndex {
    pub(crate) layer: Bytes,
    max_zoom: u32,
    geographic: bool,
    available: Option<Vec<Vec<TileRange>>>,
}

impl LayerIndex {
    /// Parses and checks `text`, the `layer.json` found at `path`.
    pub(crate) fn parse(path: &Path, text: Vec<u8>) -> Result<Self> {
        let v: Value = serde_json::from_slice(&text)
            .map_err(|e| bad_set(path, "a JSON object", &format!("invalid JSON ({e})")))?;
        let (max_zoom, geographic, available) = parse_layer(path, &v)?;
        Ok(LayerIndex {
            layer: Bytes::from(text),
            max_zoom,
            geographic,
            available,
        })
    }

    /// Checks that `id` lies in the pyramid and in the layer.
    pub(crate) fn check(&self, id: TileId) -> Result<()> {
        check_in_world(id, self.geographic)?;
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

impl DirTileSource {
    /// Opens `dir` and reads and checks its `layer.json` (served as it is).
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
        let text = match cota_io::limits::read_file_capped(&layer_path, MAX_LAYER_BYTES) {
            Err(e) if e.kind() == std::io::ErrorKind::FileTooLarge => {
                return Err(bad_set(
                    &layer_path,
                    &format!("at most {MAX_LAYER_BYTES} bytes"),
                    "more",
                ))
            }
            r => r.map_err(io(&layer_path))?,
        };
        let index = LayerIndex::parse(&layer_path, text)?;
        Ok(DirTileSource { root, index })
    }
}

pub(crate) fn bad_set(path: &Path, expected: &str, found: &str) -> ServeError {
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

impl TileSource for DirTileSource {
    fn layer_json(&self) -> &Bytes {
        &self.index.layer
    }

    fn has(&self, id: TileId) -> Result<()> {
        self.index.check(id)
    }

    fn tile(&self, id: TileId) -> Result<Tile> {
        self.index.check(id)?;
        self.read(id)
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
        // Stops at the limit while reading, whatever the size said (a file
        // that grows).
        let bytes = match cota_io::limits::read_file_capped(&real, MAX_TILE_BYTES) {
            Err(e) if e.kind() == std::io::ErrorKind::FileTooLarge => {
                return Err(ServeError::CorruptTile {
                    path: path.clone(),
                    expected: format!("at most {MAX_TILE_BYTES} bytes"),
                    found: "more".into(),
                })
            }
            r => r.map_err(io)?,
        };
        check_tile_bytes(&bytes).map_err(|(expected, found)| ServeError::CorruptTile {
            path: path.clone(),
            expected,
            found,
        })?;
        Ok(Tile {
            gzip: is_gzip(&bytes),
            etag: etag_of(&bytes),
            bytes: Bytes::from(bytes),
        })
    }
}
