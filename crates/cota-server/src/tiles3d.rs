//! 3D Tiles terrain written by `cota tiles --format 3dtiles`, served as the
//! files they are at `/3dtiles/…` (`tileset.json`, the subtrees, the GLBs):
//! from the pyramid's directory, or from a 3D Tiles Archive (`.3tz`) read
//! through its index ([`cota_tiles::Tz3Reader`]), for CesiumJS's
//! `Cesium3DTilesTerrainProvider` (`/cesium?3dtiles`), 3DTilesRendererJS or
//! loaders.gl; or, without such a pyramid, made in memory from the
//! on-demand tiles' hierarchy on the first request and kept
//! ([`Tiles3dFiles::Memory`]). Names starting with a dot (the run's manifest and journals)
//! are not served; paths with `..` are refused before any route.

use std::path::{Path, PathBuf};

use cota_tiles::{is_3tz, Tz3Reader};

/// Where the files come from.
pub enum Tiles3dFiles {
    /// A directory holding `tileset.json`.
    Dir(PathBuf),
    /// A 3D Tiles Archive.
    Archive(Tz3Reader),
    /// Made in memory from the tiles' hierarchy on the first request
    /// ([`crate::TileSource::tiles3d`]).
    Memory(std::collections::HashMap<String, Vec<u8>>),
}

impl std::fmt::Debug for Tiles3dFiles {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Tiles3dFiles::Dir(d) => write!(f, "Dir({})", d.display()),
            Tiles3dFiles::Archive(a) => write!(f, "Archive({} files)", a.len()),
            Tiles3dFiles::Memory(m) => write!(f, "Memory({} files)", m.len()),
        }
    }
}

/// True when `path` is a 3D Tiles pyramid `cota serve --tiles` takes: a
/// `.3tz` (or `.3dtiles.zip`) name, or a directory with `tileset.json`.
pub fn is_tiles3d(path: &Path) -> bool {
    is_3tz(path) || path.join("tileset.json").is_file()
}

impl Tiles3dFiles {
    /// Opens a 3D Tiles directory or archive.
    ///
    /// # Errors
    /// A message naming `path` and what was expected: a directory without
    /// `tileset.json`, or an archive that cannot be read or holds none.
    pub fn open(path: &Path) -> Result<Tiles3dFiles, String> {
        if is_3tz(path) {
            let a = Tz3Reader::open(path).map_err(|e| e.to_string())?;
            return match a.get("tileset.json") {
                Ok(Some(_)) => Ok(Tiles3dFiles::Archive(a)),
                Ok(None) => Err(format!(
                    "{}: expected tileset.json in the 3D Tiles Archive, found none",
                    path.display()
                )),
                Err(e) => Err(format!("{}: {e}", path.display())),
            };
        }
        if !path.join("tileset.json").is_file() {
            return Err(format!(
                "{}: expected a 3D Tiles directory with tileset.json, found none",
                path.display()
            ));
        }
        Ok(Tiles3dFiles::Dir(path.to_path_buf()))
    }

    /// The bytes of the file at `rel` (a path below the pyramid's root), or
    /// `None` when there is none (or its name starts with a dot).
    ///
    /// # Errors
    /// The file's read error.
    pub fn get(&self, rel: &str) -> std::io::Result<Option<Vec<u8>>> {
        let rel = rel.trim_start_matches('/');
        if rel.is_empty() || rel.split('/').any(|p| p.is_empty() || p.starts_with('.')) {
            return Ok(None);
        }
        match self {
            Tiles3dFiles::Archive(a) => a.get(rel),
            Tiles3dFiles::Memory(m) => Ok(m.get(rel).cloned()),
            Tiles3dFiles::Dir(d) => match std::fs::read(d.join(rel)) {
                Ok(b) => Ok(Some(b)),
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::NotFound | std::io::ErrorKind::IsADirectory
                    ) || d.join(rel).is_dir() =>
                {
                    Ok(None)
                }
                Err(e) => Err(e),
            },
        }
    }
}
