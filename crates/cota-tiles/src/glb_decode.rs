//! An independent decoder of the 3D Tiles terrain GLBs of
//! [`super::glb_tile`], reading them as CesiumJS does: the GLB chunks, the
//! first primitive's `POSITION` (float32, or `KHR_mesh_quantization`'s
//! normalized u16 as `q / 65535` in float32), indices and `CESIUM_tile_edges`,
//! each buffer view plain or `EXT_meshopt_compression`-compressed (decoded
//! by [`cota_io::meshopt::decode`], which shares no code with the encoders),
//! and the first node's `matrix` followed by glTF's Y-up to Z-up turn, to
//! ECEF positions in f64. It shares no code with the encoder, so the
//! pyramid's check measures the bytes a client draws. A second primitive
//! (the skirt for other clients) is decoded apart, positions and triangles,
//! and never enters the check.

use std::borrow::Cow;

use serde_json::Value;

use super::glb_tile::TileMeta;
use cota_io::meshopt::{
    decode_index_sequence, decode_triangles, decode_vertex_buffer, MeshoptError,
};

/// Why a GLB tile cannot be read.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[error("GLB tile: {0}")]
pub struct GlbError(pub String);

/// A decoded GLB tile.
#[derive(Debug, Clone, PartialEq)]
pub struct DecodedGlb {
    /// Vertex positions, ECEF metres (Z up).
    pub positions: Vec<[f64; 3]>,
    /// Triangles.
    pub triangles: Vec<[u32; 3]>,
    /// Vertices on the west, south, east and north edges (`left`, `bottom`,
    /// `right`, `top`).
    pub edges: [Vec<u32>; 4],
    /// Unit normals in ECEF, when the tile has them.
    pub normals: Option<Vec<[f64; 3]>>,
    /// `asset.extras.cota`, when present.
    pub meta: Option<TileMeta>,
    /// With `KHR_mesh_quantization` positions: the node matrix's scale per
    /// axis (the length of each column: the size of the box the u16 values
    /// span, metres).
    pub quantized_scale: Option<[f64; 3]>,
    /// The second primitive (the skirt for clients that build none, which
    /// CesiumJS never reads): its ECEF positions and triangles, when present.
    pub skirt: Option<Triangles>,
}

/// A primitive's ECEF positions (metres) and triangles.
pub type Triangles = (Vec<[f64; 3]>, Vec<[u32; 3]>);

fn bad(what: impl Into<String>) -> GlbError {
    GlbError(what.into())
}

fn u32_at(b: &[u8], at: usize) -> Result<u32, GlbError> {
    b.get(at..at + 4)
        .and_then(|s| s.try_into().ok())
        .map(u32::from_le_bytes)
        .ok_or_else(|| bad(format!("truncated at byte {at}")))
}

/// The JSON and BIN chunks of a GLB.
fn chunks(b: &[u8]) -> Result<(Value, &[u8]), GlbError> {
    if b.get(0..4) != Some(b"glTF") || u32_at(b, 4)? != 2 {
        return Err(bad("expected the magic glTF and version 2"));
    }
    let json_len = u32_at(b, 12)? as usize;
    if b.get(16..20) != Some(b"JSON") {
        return Err(bad("the first chunk is not JSON"));
    }
    let text = b
        .get(20..20 + json_len)
        .ok_or_else(|| bad("truncated JSON chunk"))?;
    let doc: Value = serde_json::from_slice(text).map_err(|e| bad(e.to_string()))?;
    let at = 20 + json_len;
    let bin_len = u32_at(b, at)? as usize;
    if b.get(at + 4..at + 8) != Some(b"BIN\0") {
        return Err(bad("the second chunk is not BIN"));
    }
    let bin = b
        .get(at + 8..at + 8 + bin_len)
        .ok_or_else(|| bad("truncated BIN chunk"))?;
    Ok((doc, bin))
}

fn index(v: &Value, what: &str) -> Result<usize, GlbError> {
    v.as_u64()
        .map(|i| i as usize)
        .ok_or_else(|| bad(format!("{what}: expected an index, found {v}")))
}

/// The bytes of buffer view `v` from `offset`: from the BIN chunk, or
/// decoded from it when the view is `EXT_meshopt_compression`-compressed.
fn view_bytes<'b>(
    doc: &Value,
    bin: &'b [u8],
    v: usize,
    offset: usize,
) -> Result<Cow<'b, [u8]>, GlbError> {
    let view = &doc["bufferViews"][v];
    let len = index(&view["byteLength"], "bufferView byteLength")?;
    let slice = |start: usize, n: usize| {
        bin.get(start..start.saturating_add(n))
            .ok_or_else(|| bad(format!("bufferView {v} outside the BIN chunk")))
    };
    let ext = &view["extensions"]["EXT_meshopt_compression"];
    if ext.is_null() {
        let start = view["byteOffset"].as_u64().unwrap_or(0) as usize;
        return Ok(Cow::Borrowed(
            slice(start, len)?.get(offset..).unwrap_or(&[]),
        ));
    }
    if index(&ext["buffer"], "meshopt buffer")? != 0 {
        return Err(bad("meshopt data outside the BIN chunk"));
    }
    let packed = slice(
        ext["byteOffset"].as_u64().unwrap_or(0) as usize,
        index(&ext["byteLength"], "meshopt byteLength")?,
    )?;
    let stride = index(&ext["byteStride"], "meshopt byteStride")?;
    let count = index(&ext["count"], "meshopt count")?;
    if stride.checked_mul(count) != Some(len) {
        return Err(bad(format!(
            "bufferView {v}: {count} × {stride} bytes is not its byteLength {len}"
        )));
    }
    let wide = |ids: Vec<u32>| -> Vec<u8> {
        match stride {
            2 => ids.iter().flat_map(|&i| (i as u16).to_le_bytes()).collect(),
            _ => ids.iter().flat_map(|&i| i.to_le_bytes()).collect(),
        }
    };
    let meshopt = |e: MeshoptError| bad(format!("bufferView {v}: {e}"));
    let raw = match ext["mode"].as_str() {
        Some("ATTRIBUTES") => decode_vertex_buffer(packed, count, stride).map_err(meshopt)?,
        Some("TRIANGLES") if stride == 2 || stride == 4 => {
            wide(decode_triangles(packed, count).map_err(meshopt)?)
        }
        Some("INDICES") if stride == 2 || stride == 4 => {
            wide(decode_index_sequence(packed, count).map_err(meshopt)?)
        }
        m => {
            return Err(bad(format!(
                "bufferView {v}: meshopt mode {m:?} with stride {stride}"
            )))
        }
    };
    Ok(Cow::Owned(raw.get(offset..).unwrap_or(&[]).to_vec()))
}

/// An accessor's bytes (from its start), count, component type and
/// element stride.
type Accessor<'b> = (Cow<'b, [u8]>, usize, u64, Option<usize>);

/// Accessor `a`.
fn accessor<'b>(doc: &Value, bin: &'b [u8], a: usize) -> Result<Accessor<'b>, GlbError> {
    let acc = &doc["accessors"][a];
    let count = index(&acc["count"], "accessor count")?;
    let component = acc["componentType"].as_u64().unwrap_or(0);
    let v = index(&acc["bufferView"], "accessor bufferView")?;
    let stride = doc["bufferViews"][v]["byteStride"]
        .as_u64()
        .map(|s| s as usize);
    let bytes = view_bytes(
        doc,
        bin,
        v,
        acc["byteOffset"].as_u64().unwrap_or(0) as usize,
    )?;
    Ok((bytes, count, component, stride))
}

fn indices(doc: &Value, bin: &[u8], a: usize) -> Result<Vec<u32>, GlbError> {
    let (bytes, count, component, _) = accessor(doc, bin, a)?;
    let out: Vec<u32> = match component {
        5123 => bytes
            .chunks_exact(2)
            .map(|c| u32::from(u16::from_le_bytes([c[0], c[1]])))
            .collect(),
        5125 => bytes
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect(),
        c => return Err(bad(format!("indices of component type {c}"))),
    };
    out.get(..count).map(<[u32]>::to_vec).ok_or_else(|| {
        bad(format!(
            "accessor {a}: {count} indices, found {}",
            out.len()
        ))
    })
}

/// A VEC3 accessor as float32 values, as CesiumJS reads them: float32
/// components as they are, normalized u16 ones (`KHR_mesh_quantization`)
/// as `q / 65535` rounded to float32.
fn floats(doc: &Value, bin: &[u8], a: usize) -> Result<Vec<[f32; 3]>, GlbError> {
    let (bytes, count, component, stride) = accessor(doc, bin, a)?;
    let normalized = doc["accessors"][a]["normalized"].as_bool() == Some(true);
    let (size, read): (usize, fn(&[u8]) -> f32) = match (component, normalized) {
        (5126, _) => (4, |c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])),
        (5123, true) => (2, |c| {
            (f64::from(u16::from_le_bytes([c[0], c[1]])) / 65535.0) as f32
        }),
        _ => {
            return Err(bad(format!(
                "expected float32 or normalized u16 vectors, found component type {component}"
            )))
        }
    };
    let stride = stride.unwrap_or(3 * size).max(3 * size);
    let v: Vec<[f32; 3]> = (0..count)
        .map_while(|i| {
            let e = bytes.get(i * stride..i * stride + 3 * size)?;
            Some(std::array::from_fn(|k| read(&e[k * size..])))
        })
        .collect();
    if v.len() != count {
        return Err(bad(format!(
            "accessor {a}: {count} vectors, found {}",
            v.len()
        )));
    }
    Ok(v)
}

/// The node matrix then Y-up to Z-up: `(x, y, z) → (x, −z, y)`.
fn place(m: &[f64; 16], p: [f32; 3], w: f64) -> [f64; 3] {
    let p = p.map(f64::from);
    let q: [f64; 3] =
        std::array::from_fn(|r| m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + w * m[12 + r]);
    [q[0], -q[2], q[1]]
}

/// Whether two triangle lists are the same triangles in the same order,
/// each possibly turned (same winding): a meshopt-compressed GLB turns
/// triangles to code them shorter.
pub fn same_triangles(a: &[[u32; 3]], b: &[[u32; 3]]) -> bool {
    let turn = |t: &[u32; 3]| {
        let k = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
        [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
    };
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| turn(x) == turn(y))
}

/// Decodes a GLB tile.
///
/// # Errors
/// [`GlbError`] naming what was expected and found.
pub fn decode_glb(bytes: &[u8]) -> Result<DecodedGlb, GlbError> {
    let (doc, bin) = chunks(bytes)?;
    let m: Vec<f64> = doc["nodes"][0]["matrix"]
        .as_array()
        .ok_or_else(|| bad("nodes[0].matrix is missing"))?
        .iter()
        .filter_map(Value::as_f64)
        .collect();
    let m: [f64; 16] = m
        .try_into()
        .map_err(|_| bad("nodes[0].matrix: expected 16 numbers"))?;
    let prim = &doc["meshes"][0]["primitives"][0];
    let position = &doc["accessors"][index(&prim["attributes"]["POSITION"], "POSITION")?];
    let column = |k: usize| (m[4 * k].powi(2) + m[4 * k + 1].powi(2) + m[4 * k + 2].powi(2)).sqrt();
    let quantized_scale = (position["componentType"].as_u64() == Some(5123))
        .then(|| [column(0), column(1), column(2)]);
    let local = floats(
        &doc,
        bin,
        index(&prim["attributes"]["POSITION"], "POSITION")?,
    )?;
    let positions = local.iter().map(|&p| place(&m, p, 1.0)).collect();
    let flat = indices(&doc, bin, index(&prim["indices"], "indices")?)?;
    let triangles = flat.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
    let e = &prim["extensions"]["CESIUM_tile_edges"];
    let mut edges: [Vec<u32>; 4] = Default::default();
    for (k, name) in ["left", "bottom", "right", "top"].iter().enumerate() {
        edges[k] = indices(&doc, bin, index(&e[name], name)?)?;
    }
    let normals = match prim["attributes"].get("NORMAL") {
        Some(a) => Some(
            floats(&doc, bin, index(a, "NORMAL")?)?
                .iter()
                .map(|&n| {
                    // As CesiumJS: through the node matrix, then normalized.
                    let v = place(&m, n, 0.0);
                    let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                    v.map(|c| c / len)
                })
                .collect(),
        ),
        None => None,
    };
    let meta = read_meta(&doc["asset"]["extras"]["cota"]);
    let skirt = match doc["meshes"][0]["primitives"].get(1) {
        Some(p) => {
            let local = floats(&doc, bin, index(&p["attributes"]["POSITION"], "POSITION")?)?;
            let flat = indices(&doc, bin, index(&p["indices"], "indices")?)?;
            Some((
                local.iter().map(|&q| place(&m, q, 1.0)).collect(),
                flat.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
            ))
        }
        None => None,
    };
    Ok(DecodedGlb {
        positions,
        triangles,
        edges,
        normals,
        meta,
        quantized_scale,
        skirt,
    })
}

/// `asset.extras.cota`: nine f64 as 144 hexadecimal digits, exactly.
fn read_meta(v: &Value) -> Option<TileMeta> {
    let text = v.as_str()?;
    if text.len() != 144 || !text.is_ascii() {
        return None;
    }
    let values: Vec<f64> = (0..9)
        .map(|k| {
            u64::from_str_radix(&text[16 * k..16 * k + 16], 16)
                .ok()
                .map(f64::from_bits)
        })
        .collect::<Option<_>>()?;
    Some(TileMeta::from_values(values.try_into().ok()?))
}
