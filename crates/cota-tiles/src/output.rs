//! One entry for a whole pyramid, whatever its format and container:
//! [`write_output`] chooses the writer from [`PyramidOptions::format`] and
//! the output's name, so that `cota tiles` and `cota.tiles` (Python) write
//! the same bytes through the same code:
//!
//! | format | `OUT` | writer |
//! |---|---|---|
//! | quantized-mesh | a directory | [`write_pyramid`] |
//! | quantized-mesh | `*.mbtiles` | [`write_mbtiles`] |
//! | 3D Tiles | a directory | [`write_tiles3d`] |
//! | 3D Tiles | `*.3tz`, `*.3dtiles.zip` | [`write_3tz`] |
//!
//! What a format cannot carry is refused before any work, in words.

use std::path::Path;

use cota_core::tiles::{Prepared, TilesError};

use super::archive3tz::{is_3tz, write_3tz};
use super::drawn::Against;
use super::mbtiles::{is_mbtiles, write_mbtiles};
use super::pyramid::{write_pyramid, PyramidError, PyramidOptions, PyramidReport, TileFormat};
use super::pyramid3d::write_tiles3d;

/// Refuses settings that `opts.format` and the output `out` cannot hold:
/// gzip, water mask or metadata in 3D Tiles; meshopt or no skirts in
/// quantized-mesh; 3D Tiles into `.mbtiles`; quantized-mesh into `.3tz`.
///
/// # Errors
/// [`PyramidError::Tiles`] with [`TilesError::BadOptions`] saying what was
/// expected.
pub fn check_output(out: &Path, opts: &PyramidOptions) -> Result<(), PyramidError> {
    let bad = |what: String| Err(PyramidError::Tiles(TilesError::BadOptions(what)));
    let name = out.display();
    match opts.format {
        TileFormat::Tiles3d => {
            let e = &opts.extensions;
            if opts.gzip || e.watermask || e.metadata {
                return bad("3D Tiles take neither gzip, a water mask nor quantized-mesh metadata: expected the quantized-mesh format with them".into());
            }
            if is_mbtiles(out) {
                return bad(format!("{name}: expected a directory or a .3tz archive for 3D Tiles, found an .mbtiles name"));
            }
        }
        TileFormat::QuantizedMesh => {
            if opts.meshopt || !opts.skirts {
                return bad("meshopt and skirts are settings of 3D Tiles GLBs: expected the 3dtiles format with them (quantized-mesh clients build their own skirts)".into());
            }
            if is_3tz(out) {
                return bad(format!("{name}: a .3tz archive holds 3D Tiles: expected the 3dtiles format with it (quantized-mesh archives: .mbtiles)"));
            }
        }
    }
    Ok(())
}

/// Writes the whole pyramid of `prep` to `out` with the writer its format
/// and name call for (the table above), after [`check_output`].
///
/// # Errors
/// As [`check_output`] and the chosen writer.
pub fn write_output(
    prep: &Prepared<'_>,
    out: &Path,
    opts: &PyramidOptions,
    source: Option<&Against<'_>>,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<PyramidReport, PyramidError> {
    check_output(out, opts)?;
    match opts.format {
        TileFormat::Tiles3d if is_3tz(out) => write_3tz(prep, out, opts, source, progress),
        TileFormat::Tiles3d => write_tiles3d(prep, out, opts, source, progress),
        TileFormat::QuantizedMesh if is_mbtiles(out) => {
            write_mbtiles(prep, out, opts, source, progress)
        }
        TileFormat::QuantizedMesh => write_pyramid(prep, out, opts, source, progress),
    }
}
