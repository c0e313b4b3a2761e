//! One 3D Tiles terrain tile as a GLB, for CesiumJS's
//! `Cesium3DTilesTerrainProvider` (experimental since CesiumJS 1.135) and any
//! 3D Tiles 1.1 client (3DTilesRendererJS, loaders.gl).
//!
//! Written from the glTF 2.0 specification (GLB container, accessors,
//! node matrices; glTF is Y-up and 3D Tiles turns it Z-up), the
//! `CESIUM_tile_edges` extension, and what CesiumJS 1.145 reads
//! (`Cesium3DTilesTerrainGeometryProcessor.js`, `decodeGltf`; notes in
//! `docs/3dtiles-terrain.md`):
//!
//! * exactly one scene, node, mesh and primitive (triangles); the node
//!   carries a `matrix` (CesiumJS unpacks it and applies the Y-up to Z-up
//!   turn after it), here a translation to the tile's centre;
//! * `POSITION`: float32 positions relative to that centre, in glTF axes
//!   (ECEF `x, z, −y`). CesiumJS reads plain positions as float32 whatever
//!   the accessor says, so `KHR_mesh_quantization` alone is not an option
//!   for it (only through `EXT_meshopt_compression`, not written yet);
//! * indices `UNSIGNED_SHORT` up to 65 535 vertices, else `UNSIGNED_INT`;
//! * `CESIUM_tile_edges` with `left`, `bottom`, `right`, `top`: accessors of
//!   the vertices on the west, south, east and north edges, in the order
//!   CesiumJS hangs its skirts on them, counter-clockwise round the tile
//!   ([`ccw_edges`]: west south to north, south east to west, east north to
//!   south, north west to east; in any other order its skirts cut across
//!   the tile);
//! * `NORMAL` on request (unit float32 vectors in glTF axes).
//!
//! The tile is made from the decoded quantized-mesh tile of the same
//! hierarchy (same vertices, triangles and edges; the vertices where a
//! client of the quantized-mesh tile draws them), so both formats carry the
//! same bound. The only new error is float32's rounding of each local
//! coordinate, at most `2⁻²⁴·|c|`; [`float32_budget_m`] bounds it and the
//! pyramid's check draws the float32 positions themselves.
//!
//! Per-tile metadata (minimum and maximum height, bounding sphere, horizon
//! occlusion point) goes to the subtree files ([`super::tileset3d`]); it is
//! also kept in `asset.extras.cota` so that a resumed run can rebuild the
//! subtrees without cutting the tile again.

use serde_json::{json, Value};

use super::decode::DecodedTile;
use super::ellipsoid::{ecef, oct_decode};

/// What the subtree files say of a tile (the quantized-mesh header's values).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TileMeta {
    /// Smallest height, metres.
    pub min_height_m: f64,
    /// Largest height, metres.
    pub max_height_m: f64,
    /// Bounding sphere: ECEF centre and radius, metres.
    pub sphere: [f64; 4],
    /// Horizon occlusion point, ellipsoid-scaled ECEF (NaN: never occluded).
    pub horizon_occlusion_point: [f64; 3],
}

impl TileMeta {
    /// The values of a decoded quantized-mesh tile's header.
    pub fn of(tile: &DecodedTile) -> TileMeta {
        let h = &tile.header;
        let c = h.sphere_center;
        TileMeta {
            min_height_m: f64::from(h.min_height_m),
            max_height_m: f64::from(h.max_height_m),
            sphere: [c[0], c[1], c[2], h.sphere_radius_m],
            horizon_occlusion_point: h.horizon_occlusion_point,
        }
    }
}

/// The ECEF positions of a decoded quantized-mesh tile's vertices over
/// `rect` (`[west, south, east, north]`, degrees), as its client computes them.
pub fn ecef_positions(tile: &DecodedTile, rect: [f64; 4]) -> Vec<[f64; 3]> {
    (0..tile.u.len())
        .map(|i| {
            let [lon, lat, h] = tile.geodetic(i, rect);
            ecef(lon, lat, h)
        })
        .collect()
}

/// The largest error float32's rounding of the local positions can add to
/// a tile whose vertices lie within `radius_m` of its centre: half an ulp per
/// axis, `√3·2⁻²⁴·radius`, metres.
pub fn float32_budget_m(radius_m: f64) -> f64 {
    3f64.sqrt() * radius_m * 2f64.powi(-24)
}

/// ECEF (Z-up) to glTF (Y-up) axes: `(x, z, −y)`.
fn to_gltf(p: [f64; 3]) -> [f64; 3] {
    [p[0], p[2], -p[1]]
}

/// Little-endian bytes of the binary chunk, with accessors' views.
#[derive(Default)]
struct Bin {
    bytes: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Bin {
    /// Appends a view (4-byte aligned) and an accessor over it; its index.
    fn push(&mut self, data: &[u8], target: Option<u32>, accessor: Value) -> usize {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        let mut view =
            json!({"buffer": 0, "byteOffset": self.bytes.len(), "byteLength": data.len()});
        if let Some(t) = target {
            view["target"] = json!(t);
        }
        self.bytes.extend_from_slice(data);
        let mut accessor = accessor;
        accessor["bufferView"] = json!(self.views.len());
        self.views.push(view);
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// An index accessor (u16 when `wide` is false).
    fn indices(&mut self, ids: &[u32], wide: bool, target: Option<u32>) -> usize {
        let (bytes, component): (Vec<u8>, u32) = if wide {
            (ids.iter().flat_map(|i| i.to_le_bytes()).collect(), 5125)
        } else {
            (
                ids.iter().flat_map(|&i| (i as u16).to_le_bytes()).collect(),
                5123,
            )
        };
        let accessor = json!({"componentType": component, "count": ids.len(), "type": "SCALAR"});
        self.push(&bytes, target, accessor)
    }

    /// A float32 VEC3 accessor, with its min and max when `bounds`.
    fn vec3(&mut self, values: &[[f32; 3]], bounds: bool) -> usize {
        let bytes: Vec<u8> = values
            .iter()
            .flat_map(|v| v.iter().flat_map(|c| c.to_le_bytes()))
            .collect();
        let mut accessor = json!({"componentType": 5126, "count": values.len(), "type": "VEC3"});
        if bounds {
            let mut lo = [f32::INFINITY; 3];
            let mut hi = [f32::NEG_INFINITY; 3];
            for v in values {
                for k in 0..3 {
                    lo[k] = lo[k].min(v[k]);
                    hi[k] = hi[k].max(v[k]);
                }
            }
            accessor["min"] = json!(lo);
            accessor["max"] = json!(hi);
        }
        self.push(&bytes, Some(34962), accessor)
    }
}

/// The GLB of a decoded quantized-mesh tile over `rect`, with vertex normals
/// when `normals` (and the tile has them).
pub fn encode_glb(tile: &DecodedTile, rect: [f64; 4], normals: bool) -> Vec<u8> {
    let centre = tile.header.center;
    let local: Vec<[f32; 3]> = ecef_positions(tile, rect)
        .into_iter()
        .map(|p| {
            let d = to_gltf([p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]]);
            d.map(|c| c as f32)
        })
        .collect();
    let wide = local.len() > 65_535;
    let mut bin = Bin::default();
    let position = bin.vec3(&local, true);
    let flat: Vec<u32> = tile.triangles.iter().flatten().copied().collect();
    let indices = bin.indices(&flat, wide, Some(34963));
    let edges: Vec<usize> = ccw_edges(tile)
        .iter()
        .map(|e| bin.indices(e, wide, None))
        .collect();
    let mut attributes = json!({"POSITION": position});
    if let (true, Some(oct)) = (normals, &tile.normals) {
        let n: Vec<[f32; 3]> = oct
            .iter()
            .map(|&e| to_gltf(oct_decode(e)).map(|c| c as f32))
            .collect();
        attributes["NORMAL"] = json!(bin.vec3(&n, false));
    }
    let t = to_gltf(centre);
    let meta = TileMeta::of(tile);
    let doc = json!({
        "asset": {"version": "2.0", "generator": "cota", "extras": {"cota": meta_json(&meta)}},
        "extensionsUsed": ["CESIUM_tile_edges"],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, t[0], t[1], t[2], 1]}],
        "meshes": [{"primitives": [{
            "attributes": attributes,
            "indices": indices,
            "mode": 4,
            "extensions": {"CESIUM_tile_edges": {
                "left": edges[0], "bottom": edges[1], "right": edges[2], "top": edges[3]
            }}
        }]}],
        "accessors": bin.accessors,
        "bufferViews": bin.views,
        "buffers": [{"byteLength": bin.bytes.len()}],
    });
    glb(&doc, bin.bytes)
}

/// The tile's edge lists (sorted along each edge, south to north and west
/// to east) counter-clockwise round the tile: the south and east reversed.
pub fn ccw_edges(tile: &DecodedTile) -> [Vec<u32>; 4] {
    let mut e = tile.edges.clone();
    e[1].reverse();
    e[2].reverse();
    e
}

impl TileMeta {
    /// The nine values in order: minimum, maximum, sphere, occlusion point.
    pub fn values(&self) -> [f64; 9] {
        let (s, h) = (self.sphere, self.horizon_occlusion_point);
        [
            self.min_height_m,
            self.max_height_m,
            s[0],
            s[1],
            s[2],
            s[3],
            h[0],
            h[1],
            h[2],
        ]
    }

    /// From [`TileMeta::values`].
    pub fn from_values(v: [f64; 9]) -> TileMeta {
        TileMeta {
            min_height_m: v[0],
            max_height_m: v[1],
            sphere: [v[2], v[3], v[4], v[5]],
            horizon_occlusion_point: [v[6], v[7], v[8]],
        }
    }
}

/// `TileMeta` as JSON, NaN (never occluded) as null; `f64_bits` holds the
/// same values as hexadecimal IEEE 754 bits, read back exactly on resume
/// (decimal text does not always parse back to the same f64).
pub(crate) fn meta_json(m: &TileMeta) -> Value {
    let num = |v: f64| if v.is_finite() { json!(v) } else { Value::Null };
    let bits: Vec<String> = m
        .values()
        .iter()
        .map(|v| format!("{:016x}", v.to_bits()))
        .collect();
    json!({
        "f64_bits": bits,
        "min_height_m": m.min_height_m,
        "max_height_m": m.max_height_m,
        "sphere": m.sphere.map(num),
        "horizon_occlusion_point": m.horizon_occlusion_point.map(num),
    })
}

/// The GLB container: header, JSON chunk (space-padded), BIN chunk
/// (zero-padded), each to 4 bytes.
fn glb(doc: &Value, mut bin: Vec<u8>) -> Vec<u8> {
    let mut text = doc.to_string().into_bytes();
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + text.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&text);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}
