//! [`MbtilesTileSource`]: the tiles of a `cota tiles … -o OUT.mbtiles`
//! archive (`cota serve --tiles OUT.mbtiles`), with the same checks as a
//! directory's: its `layer.json` (the archive's `json` metadata) parsed and
//! checked, tiles asked only inside the layer's bounds and `available`,
//! each refused when larger than [`MAX_TILE_BYTES`] or neither gzip nor a
//! plausible quantized-mesh tile.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use axum::body::Bytes;
use cota_tiles::MbtilesReader;

use super::dir::LayerIndex;
use super::{check_tile_bytes, etag_of, is_gzip, Tile, TileId, TileSource, MAX_TILE_BYTES};
use crate::error::{Result, ServeError};

/// The tiles of an MBTiles archive (taken as immutable while served).
#[derive(Debug)]
pub struct MbtilesTileSource {
    path: PathBuf,
    /// SQLite connections are not shared between threads: one, locked per
    /// read (a read is one indexed row).
    reader: Mutex<MbtilesReader>,
    index: LayerIndex,
}

impl MbtilesTileSource {
    /// Opens the archive at `path` and reads and checks its `layer.json`.
    ///
    /// # Errors
    /// [`ServeError::BadTileSet`] for a file that is not a quantized-mesh
    /// MBTiles archive, or whose `layer.json` is not a quantized-mesh layer.
    pub fn open(path: &Path) -> Result<Self> {
        let bad = |found: String| ServeError::BadTileSet {
            path: path.to_path_buf(),
            expected: "an MBTiles archive of quantized-mesh tiles (cota tiles -o OUT.mbtiles)"
                .into(),
            found,
        };
        let reader = MbtilesReader::open(path).map_err(|e| bad(e.to_string()))?;
        let text = reader.layer_json().map_err(|e| bad(e.to_string()))?;
        let index = LayerIndex::parse(path, text.into_bytes())?;
        Ok(MbtilesTileSource {
            path: path.to_path_buf(),
            reader: Mutex::new(reader),
            index,
        })
    }
}

impl TileSource for MbtilesTileSource {
    fn layer_json(&self) -> &Bytes {
        &self.index.layer
    }

    fn has(&self, id: TileId) -> Result<()> {
        self.index.check(id)
    }

    fn tile(&self, id: TileId) -> Result<Tile> {
        self.index.check(id)?;
        let corrupt = |expected: String, found: String| ServeError::CorruptTile {
            path: self.path.clone(),
            expected,
            found,
        };
        let read = {
            let reader = self.reader.lock().unwrap_or_else(|p| p.into_inner());
            reader.tile(id.z, id.x, id.y)
        };
        let bytes = read
            .map_err(|e| corrupt("a readable tile".into(), e.to_string()))?
            .ok_or_else(|| ServeError::NotFound(format!("tile {}/{}/{}", id.z, id.x, id.y)))?;
        if bytes.len() as u64 > MAX_TILE_BYTES {
            return Err(corrupt(
                format!("at most {MAX_TILE_BYTES} bytes"),
                format!("{} bytes", bytes.len()),
            ));
        }
        check_tile_bytes(&bytes).map_err(|(e, f)| corrupt(e, f))?;
        Ok(Tile {
            gzip: is_gzip(&bytes),
            etag: etag_of(&bytes),
            bytes: Bytes::from(bytes),
        })
    }
}
