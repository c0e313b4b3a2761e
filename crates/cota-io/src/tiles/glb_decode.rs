//! An independent decoder of the 3D Tiles terrain GLBs of
//! [`super::glb_tile`], reading them as CesiumJS does: the GLB chunks, the
//! first primitive's `POSITION` (float32), indices and `CESIUM_tile_edges`,
//! and the first node's `matrix` followed by glTF's Y-up to Z-up turn, to
//! ECEF positions in f64. It shares no code with the encoder, so the
//! pyramid's check measures the bytes a client draws.

use serde_json::Value;

use super::glb_tile::TileMeta;

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
}

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

/// The bytes of accessor `a` and its count and component type.
fn accessor<'b>(doc: &Value, bin: &'b [u8], a: usize) -> Result<(&'b [u8], usize, u64), GlbError> {
    let acc = &doc["accessors"][a];
    let count = index(&acc["count"], "accessor count")?;
    let component = acc["componentType"].as_u64().unwrap_or(0);
    let view = &doc["bufferViews"][index(&acc["bufferView"], "accessor bufferView")?];
    let start = view["byteOffset"].as_u64().unwrap_or(0) as usize
        + acc["byteOffset"].as_u64().unwrap_or(0) as usize;
    let len = index(&view["byteLength"], "bufferView byteLength")?;
    let bytes = bin
        .get(start..start + len)
        .ok_or_else(|| bad(format!("accessor {a} outside the BIN chunk")))?;
    Ok((bytes, count, component))
}

fn indices(doc: &Value, bin: &[u8], a: usize) -> Result<Vec<u32>, GlbError> {
    let (bytes, count, component) = accessor(doc, bin, a)?;
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

fn floats(doc: &Value, bin: &[u8], a: usize) -> Result<Vec<[f32; 3]>, GlbError> {
    let (bytes, count, component) = accessor(doc, bin, a)?;
    if component != 5126 {
        return Err(bad(format!(
            "expected float32 positions, found component type {component}"
        )));
    }
    let f: Vec<f32> = bytes
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    let v: Vec<[f32; 3]> = f.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    v.get(..count)
        .map(<[[f32; 3]]>::to_vec)
        .ok_or_else(|| bad(format!("accessor {a}: {count} vectors, found {}", v.len())))
}

/// The node matrix then Y-up to Z-up: `(x, y, z) → (x, −z, y)`.
fn place(m: &[f64; 16], p: [f32; 3], w: f64) -> [f64; 3] {
    let p = p.map(f64::from);
    let q: [f64; 3] =
        std::array::from_fn(|r| m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + w * m[12 + r]);
    [q[0], -q[2], q[1]]
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
                .map(|&n| place(&m, n, 0.0))
                .collect(),
        ),
        None => None,
    };
    let meta = read_meta(&doc["asset"]["extras"]["cota"]);
    Ok(DecodedGlb {
        positions,
        triangles,
        edges,
        normals,
        meta,
    })
}

/// `asset.extras.cota`: its `f64_bits`, exactly.
fn read_meta(v: &Value) -> Option<TileMeta> {
    let bits = v["f64_bits"].as_array()?;
    let values: Vec<f64> = bits
        .iter()
        .map(|b| {
            u64::from_str_radix(b.as_str()?, 16)
                .ok()
                .map(f64::from_bits)
        })
        .collect::<Option<_>>()?;
    Some(TileMeta::from_values(values.try_into().ok()?))
}
