//! `layer.json`, the TileJSON 2.1 manifest a quantized-mesh client reads
//! first (the quantized-mesh-1.0 specification's `layer.json`: `format`,
//! `tiles` URL templates, `scheme`, `projection`, `available` per zoom,
//! `extensions`, `minzoom`/`maxzoom`, `bounds`), and the run manifest that
//! lets a later run resume into the same directory.

use cota_core::tiles::Prepared;
use serde_json::{json, Value};

use super::quantized_mesh::TileExtensions;

/// The `layer.json` of a pyramid.
pub fn layer_json(prep: &Prepared<'_>, ext: &TileExtensions) -> Value {
    let lat = prep.lattice();
    let s = lat.scheme();
    let available: Vec<Value> = (0..=s.max_zoom)
        .map(|z| {
            let rects: Vec<Value> = prep
                .available(z)
                .iter()
                .map(|r| json!({"startX": r.x0, "startY": r.y0, "endX": r.x1, "endY": r.y1}))
                .collect();
            Value::Array(rects)
        })
        .collect();
    let errors: Vec<Value> = prep
        .zooms()
        .iter()
        .map(
            |p| json!({"zoom": p.zoom, "max_error_m": p.max_error_m, "threshold_m": p.threshold_m}),
        )
        .collect();
    let mut v = json!({
        "tilejson": "2.1.0",
        "name": "cota",
        "description": "quantized-mesh-1.0 terrain made by cota: every tile within its zoom's error bound at every sample of its lattice, after quantization",
        "version": "1.0.0",
        "format": "quantized-mesh-1.0",
        "attribution": "",
        "scheme": "tms",
        "projection": "EPSG:4326",
        "tiles": ["{z}/{x}/{y}.terrain?v={version}"],
        "minzoom": prep.zooms().first().map_or(0, |p| p.zoom),
        "maxzoom": s.max_zoom,
        // West > east across the antimeridian (RFC 7946's bounding boxes).
        "bounds": lat.footprint_deg(),
        "available": available,
        "extensions": ext.names(),
        "cota": {"tile_cells": s.tile_cells, "lattice_deg": s.cell_deg(), "errors": errors}
    });
    if ext.metadata {
        // Each tile's metadata lists its children: availability one level
        // at a time. CesiumJS then takes availability from the tiles (and
        // requires this key whenever tiles carry metadata); `available`
        // stays for the clients that read only this file.
        v["metadataAvailability"] = json!(1);
    }
    v
}

/// What decides the tiles' content: a run into a directory that holds
/// another run's manifest must match it to keep (skip) its tiles.
pub fn run_manifest(prep: &Prepared<'_>, ext: &TileExtensions, gzip: bool) -> Value {
    let lat = prep.lattice();
    let s = lat.scheme();
    let zooms: Vec<Value> = prep
        .zooms()
        .iter()
        .map(|p| json!([p.zoom, p.max_error_m, p.threshold_m]))
        .collect();
    json!({
        "cota_tiles": 1,
        "max_zoom": s.max_zoom,
        "tile_cells": s.tile_cells,
        "window": lat.window(),
        "zooms": zooms,
        "extensions": ext.names(),
        "gzip": gzip,
    })
}
