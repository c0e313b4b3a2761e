//! Shaded-relief imagery as PNG tiles ([`cota_core::relief`]): one tile
//! encoded in memory ([`relief_png`], what `cota serve` sends at
//! `/imagery/{z}/{x}/{y}.png`), or every tile over the data written to a
//! directory ([`write_relief_tiles`], `cota tiles --imagery`):
//! `DIR/{z}/{x}/{y}.png` (TMS rows, the geographic tiling of the terrain
//! tiles) and `DIR/imagery.json` saying where they are.

use std::path::{Path, PathBuf};

use cota_core::relief::Relief;

/// Writing relief tiles failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ReliefWriteError {
    /// A file or directory could not be written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
}

/// Tile `z/x/y` (TMS) as an RGBA PNG, or `None` when it holds none of the
/// data.
pub fn relief_png(relief: &Relief, z: u8, x: u32, y: u32) -> Option<Vec<u8>> {
    let rgba = relief.tile_rgba(z, x, y)?;
    let px = relief.tile_px();
    let mut out = Vec::with_capacity(rgba.len() / 4);
    let mut enc = png::Encoder::new(&mut out, px, px);
    enc.set_color(png::ColorType::Rgba);
    enc.set_depth(png::BitDepth::Eight);
    enc.set_compression(png::Compression::Fast);
    // Writing to memory fails only on a size mismatch, which cannot happen.
    let mut w = enc.write_header().ok()?;
    w.write_image_data(&rgba).ok()?;
    w.finish().ok()?;
    Some(out)
}

/// The description of a relief tile set (also served by `cota serve` at
/// `/imagery.json`, with the template relative to the server's root). Its
/// `bounds` are west, south, east, north within ±180°: across the
/// antimeridian west is greater than east (RFC 7946's bounding boxes, as
/// `layer.json` says it and `Rectangle.fromDegrees` takes it).
pub fn imagery_json(relief: &Relief, template: &str) -> serde_json::Value {
    let [w, s, e, n] = relief.bounds_deg();
    let within = |lon: f64| {
        if lon > 180.0 {
            lon - 360.0
        } else if lon < -180.0 {
            lon + 360.0
        } else {
            lon
        }
    };
    serde_json::json!({
        "format": "png",
        "scheme": "tms",
        "projection": "EPSG:4326",
        "tileSize": relief.tile_px(),
        "minzoom": 0,
        "maxzoom": relief.max_zoom(),
        "bounds": [within(w), s, within(e), n],
        "tiles": [template],
        "description": "shaded relief: hillshade (light from the north-west, 45 degrees up) over a hypsometric tint of the data's heights",
    })
}

/// Writes every tile over the data from zoom 0 to `max_zoom` into `dir`
/// (`{z}/{x}/{y}.png`, TMS) and `dir/imagery.json`; returns the tiles
/// written. `progress` is called after each tile with the count so far.
///
/// # Errors
/// [`ReliefWriteError::Io`] naming the file that could not be written.
pub fn write_relief_tiles(
    relief: &Relief,
    dir: &Path,
    max_zoom: u8,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<usize, ReliefWriteError> {
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| ReliefWriteError::Io { path, source }
    };
    let mut written = 0;
    for z in 0..=max_zoom {
        for (x, y) in relief.tiles_at(z) {
            let Some(png) = relief_png(relief, z, x, y) else {
                continue;
            };
            let col = dir.join(format!("{z}/{x}"));
            std::fs::create_dir_all(&col).map_err(io(&col))?;
            let file = col.join(format!("{y}.png"));
            std::fs::write(&file, png).map_err(io(&file))?;
            written += 1;
            progress(written);
        }
    }
    let meta = dir.join("imagery.json");
    let text = format!("{:#}\n", imagery_json(relief, "{z}/{x}/{y}.png"));
    std::fs::write(&meta, text).map_err(io(&meta))?;
    Ok(written)
}
