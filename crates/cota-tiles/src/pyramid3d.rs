//! Writing a 3D Tiles 1.1 terrain pyramid: `OUT/tileset.json`, the subtree
//! files and one GLB per tile ([`super::tileset3d`], [`super::glb_tile`]).
//!
//! The tiles are the quantized-mesh pyramid's, plus *fill* tiles: every
//! quadrant of a refined tile that does not meet the data, cut from the
//! same hierarchy ([`Prepared::cut_fill`]: the ellipsoid beyond the data, a
//! few triangles; no children), since 3D Tiles' REPLACE refinement leaves
//! a refined tile's missing quadrants empty (quantized-mesh's Cesium client
//! upsamples the parent instead, so that pyramid stays as it is). All are
//! cut with the same bound per zoom: each is cut, encoded and (with
//! [`PyramidOptions::check`]) checked as a quantized-mesh tile at every
//! lattice sample of its square, then turned into a GLB from its decoded
//! vertices. The check then decodes the GLB with the independent decoder
//! ([`super::glb_decode`]), requires the same triangles and edges, and draws
//! the float32 positions (with [`PyramidOptions::meshopt`], the u16
//! positions dequantised as CesiumJS does: `q / 65535` in float32 through
//! the node matrix) as flat ECEF triangles against the source's samples
//! and the ellipsoid away from the data, within the zoom's bound plus
//! float32's rounding ([`super::glb_tile::float32_budget_m`]) or the
//! quantization's ([`super::glb_tile::u16_budget_m`]). With meshopt the
//! triangles may be turned (same winding): compared as such. With
//! [`PyramidOptions::skirts`] each GLB also carries its skirt for clients
//! that build none, [`skirt_depth`] deep (a second primitive, which
//! CesiumJS and the check never read).
//!
//! Atomic and resumable as the quantized-mesh writer: each file goes to a
//! temporary name and is renamed; the manifest `OUT/.cota-tiles.json` says
//! `"format": "3dtiles"`; a resumed run keeps the tiles there and reads their
//! metadata back from `asset.extras.cota`. The subtrees, then
//! `tileset.json`, are written last, so a client never sees a tileset whose
//! tiles are missing.

use std::collections::HashMap;
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use cota_core::tiles::{Prepared, TileId, TilesError};
use rayon::prelude::*;

use super::decode::{decode, DecodeError, DecodedTile};
use super::drawn::{Against, DrawnTile};
use super::glb_decode::{decode_glb, same_triangles};
use super::glb_tile::{
    ccw_edges, encode_glb, float32_budget_m, skirt_depth_m, u16_budget_m, GlbGeometry, TileMeta,
    SKIRT_LEVELS,
};
use super::pyramid::{
    check_drawn, finish_tile, fold, io_err, manifest, write_file_atomically, MadeTile, Outcome,
    PyramidError, PyramidOptions, PyramidReport,
};
use super::tileset3d::{glb_rel_path, subtree_bytes, subtree_levels, subtrees, tileset_json};

/// A GLB error as the pyramid reports it.
fn glb_error(t: TileId, e: impl ToString) -> PyramidError {
    PyramidError::Decode {
        tile: t,
        source: DecodeError::Invalid(e.to_string()),
    }
}

/// Cuts tile `t`, checks it as quantized-mesh, makes its GLB and (with
/// `opts.check` and `source`) checks the GLB as drawn.
///
/// # Errors
/// As [`super::make_tile`], for the GLB too.
pub fn make_glb_tile(
    prep: &Prepared<'_>,
    t: TileId,
    opts: &PyramidOptions,
    source: Option<&Against<'_>>,
) -> Result<(MadeTile, TileMeta), PyramidError> {
    let normals = opts.extensions.normals;
    let tile = if prep.is_fill(t) {
        prep.cut_fill(t, normals)?
    } else {
        prep.cut(t, normals, false)?
    };
    let (rect, bounds) = (tile.rect_deg, [tile.max_error_m, tile.source_bound_m]);
    let qm = PyramidOptions {
        gzip: false,
        ..*opts
    };
    let mut made = finish_tile(tile, &qm, Some(&prep.region(t)), None)?;
    let decoded = decode(&made.bytes).map_err(|source| PyramidError::Decode { tile: t, source })?;
    let geometry = if opts.meshopt {
        GlbGeometry::Meshopt
    } else {
        GlbGeometry::Float32
    };
    let skirt = opts.skirts.then(|| skirt_depth(prep, t.z));
    made.bytes = encode_glb(&decoded, rect, opts.extensions.normals, geometry, skirt)
        .map_err(|e| glb_error(t, e))?;
    if opts.check {
        if let Some(against) = source {
            [made.drawn_error_m, made.between_m] =
                check_glb(&made.bytes, &decoded, rect, t, bounds, against)?;
        }
    }
    Ok((made, TileMeta::of(&decoded)))
}

/// The skirt depth of zoom `z`'s tiles ([`skirt_depth_m`]): its bound and
/// the bound [`SKIRT_LEVELS`] zooms coarser (the first zoom's, nearer the
/// roots).
pub fn skirt_depth(prep: &Prepared<'_>, z: u8) -> f64 {
    let e = |z: u8| prep.zoom(z).map_or(0.0, |p| p.max_error_m);
    let first = prep.zooms().first().map_or(0, |p| p.zoom);
    skirt_depth_m(e(z), e(z.saturating_sub(SKIRT_LEVELS).max(first)))
}

/// The GLB decoded independently, its structure against the quantized-mesh
/// tile's, and drawn from its float32 positions.
fn check_glb(
    glb: &[u8],
    decoded: &DecodedTile,
    rect: [f64; 4],
    t: TileId,
    [bound, at_source]: [f64; 2],
    against: &Against<'_>,
) -> Result<[f64; 2], PyramidError> {
    let g = decode_glb(glb).map_err(|e| glb_error(t, e))?;
    if !same_triangles(&g.triangles, &decoded.triangles) || g.edges != ccw_edges(decoded) {
        return Err(glb_error(t, "the GLB's triangles or edges (counter-clockwise round the tile) differ from the tile's"));
    }
    let c = decoded.header.center;
    let radius = g
        .positions
        .iter()
        .map(|p| ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt())
        .fold(0.0, f64::max);
    let extra = g
        .quantized_scale
        .map_or(float32_budget_m(radius), u16_budget_m);
    let drawn = DrawnTile::new(decoded, rect).with_positions(&g.positions);
    check_drawn(&drawn, t, [bound + extra, at_source + extra], against)
}

/// One tile: made and written, or (not `force`) read back from the output.
fn one_tile(
    prep: &Prepared<'_>,
    out: &Path,
    t: TileId,
    opts: &PyramidOptions,
    source: Option<&Against<'_>>,
) -> Result<(TileId, TileMeta, Outcome), PyramidError> {
    let path = out.join(glb_rel_path(t));
    if !opts.force && path.is_file() {
        let bytes = std::fs::read(&path).map_err(io_err(&path))?;
        let meta = decode_glb(&bytes)
            .map_err(|e| glb_error(t, e))?
            .meta
            .ok_or_else(|| {
                glb_error(
                    t,
                    format!("{}: no asset.extras.cota; use --force", path.display()),
                )
            })?;
        return Ok((t, meta, Outcome::skipped(t)));
    }
    let (made, meta) = make_glb_tile(prep, t, opts, source)?;
    write_file_atomically(&path, &made.bytes, opts.force)?;
    Ok((t, meta, Outcome::made(t, &made)))
}

/// The tiles of a 3D Tiles pyramid: the pyramid's, then the fill tiles
/// that give every refined tile its four children
/// ([`Prepared::is_fill`]; REPLACE refinement draws a refined tile only
/// through its children).
pub fn tiles3d(prep: &Prepared<'_>) -> Vec<TileId> {
    prep.tiles().chain(prep.fills()).collect()
}

/// The subtree files and, last, `tileset.json` of a pyramid whose tiles
/// have `metas`: (path relative to the output, bytes).
fn index_files(prep: &Prepared<'_>, metas: &HashMap<TileId, TileMeta>) -> Vec<(String, Vec<u8>)> {
    let (first, last) = (prep.zooms().first(), prep.zooms().last());
    let (e0, max_zoom) = (
        first.map_or(0.0, |p| p.max_error_m),
        last.map_or(0, |p| p.zoom),
    );
    let levels = subtree_levels(max_zoom);
    let mut files: Vec<(String, Vec<u8>)> = subtrees(metas, levels)
        .into_iter()
        .map(|s| (s.rel_path(), subtree_bytes(s, levels, metas)))
        .collect();
    let lo = metas.values().map(|m| m.min_height_m).fold(0.0, f64::min);
    let hi = metas.values().map(|m| m.max_height_m).fold(0.0, f64::max);
    let tileset = tileset_json(max_zoom, e0, lo, hi);
    files.push(("tileset.json".into(), format!("{tileset:#}\n").into_bytes()));
    files
}

/// The whole 3D Tiles pyramid of `prep` in memory, as [`write_tiles3d`]
/// would write it with `opts` (no check against the source): every GLB
/// ([`tiles3d`]), the subtrees and `tileset.json`, each with its path
/// relative to the output. For `cota serve`'s 3D Tiles made on request.
///
/// # Errors
/// As [`write_tiles3d`], but nothing is written.
pub fn make_tiles3d(
    prep: &Prepared<'_>,
    opts: &PyramidOptions,
) -> Result<Vec<(String, Vec<u8>)>, PyramidError> {
    if prep.zooms().first().is_none_or(|p| p.zoom != 0) {
        return Err(PyramidError::Tiles(TilesError::BadOptions(
            "3D Tiles terrain starts at the two zoom-0 roots (implicit tiling): expected a first zoom of 0".into(),
        )));
    }
    let made: Vec<(TileId, Vec<u8>, TileMeta)> = tiles3d(prep)
        .par_iter()
        .map(|&t| make_glb_tile(prep, t, opts, None).map(|(m, meta)| (t, m.bytes, meta)))
        .collect::<Result<_, _>>()?;
    let metas: HashMap<TileId, TileMeta> = made.iter().map(|m| (m.0, m.2)).collect();
    let index = index_files(prep, &metas);
    Ok(made
        .into_iter()
        .map(|(t, bytes, _)| (glb_rel_path(t), bytes))
        .chain(index)
        .collect())
}

/// Writes every tile of `prep` and the fill tiles ([`tiles3d`]) under `out`
/// as a 3D Tiles terrain pyramid, then its subtrees and `tileset.json`;
/// `progress(done)` after each tile.
///
/// # Errors
/// [`PyramidError`]: the first tile that failed, an unwritable output, an
/// output made with other settings, or a pyramid that does not start at
/// zoom 0 (implicit tiling starts at the two roots).
pub fn write_tiles3d(
    prep: &Prepared<'_>,
    out: &Path,
    opts: &PyramidOptions,
    source: Option<&Against<'_>>,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<PyramidReport, PyramidError> {
    let t0 = Instant::now();
    let (Some(first), Some(_)) = (prep.zooms().first(), prep.zooms().last()) else {
        return Err(PyramidError::Tiles(TilesError::BadOptions(
            "no zoom to write".into(),
        )));
    };
    if first.zoom != 0 {
        return Err(PyramidError::Tiles(TilesError::BadOptions(format!(
            "3D Tiles terrain starts at the two zoom-0 roots (implicit tiling); found a first zoom of {}: use --min-zoom 0",
            first.zoom
        ))));
    }
    manifest(prep, out, opts)?;
    let tiles = tiles3d(prep);
    let done = AtomicU64::new(0);
    let results: Vec<(TileId, TileMeta, Outcome)> = tiles
        .par_iter()
        .map(|&t| {
            let r = one_tile(prep, out, t, opts, source).map(|mut r| {
                r.2.fill = prep.is_fill(t);
                r
            });
            progress(done.fetch_add(1, Ordering::Relaxed) + 1);
            r
        })
        .collect::<Result<_, _>>()?;
    let metas: HashMap<TileId, TileMeta> = results.iter().map(|r| (r.0, r.1)).collect();
    for (rel, bytes) in index_files(prep, &metas) {
        write_file_atomically(&out.join(rel), &bytes, opts.force)?;
    }
    let outcomes: Vec<Outcome> = results.into_iter().map(|r| r.2).collect();
    Ok(PyramidReport {
        zooms: fold(prep, &outcomes),
        seconds: t0.elapsed().as_secs_f64(),
    })
}
