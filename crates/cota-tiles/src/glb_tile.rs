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
//!   for it; with [`GlbGeometry::Meshopt`] it is u16 (normalized, stride 8)
//!   over the tile's box in east, north, up axes, the node matrix mapping
//!   `[0, 1]³` to the box (CesiumJS divides by 65 535 and applies it; its
//!   numbers rounded to 9 significant digits, the translation to 1 mm, for
//!   a shorter JSON chunk, and the positions quantized through the rounded
//!   matrix's inverse),
//!   compressed with `EXT_meshopt_compression` ([`cota_io::meshopt`]), and
//!   the indices too (triangles mode); the views' stand-in is a fallback
//!   buffer without data, both extensions required;
//! * indices `UNSIGNED_SHORT` up to 65 535 vertices, else `UNSIGNED_INT`;
//! * `CESIUM_tile_edges` with `left`, `bottom`, `right`, `top`: accessors
//!   (in one plain buffer view) of the vertices on the west, south, east and north edges, in the order
//!   CesiumJS hangs its skirts on them, counter-clockwise round the tile
//!   ([`ccw_edges`]: west south to north, south east to west, east north to
//!   south, north west to east; in any other order its skirts cut across
//!   the tile);
//! * `NORMAL` on request (unit float32 vectors in the node's axes, never
//!   compressed: CesiumJS reads meshopt normals as its own int8 octahedral
//!   pairs; with them the quantization box has one scale on all axes, as
//!   CesiumJS turns normals by the node matrix, not its inverse transpose).
//!
//! A second primitive of the same mesh, on request, is the tile's [`skirt`]
//! for clients that build none (CesiumJS reads the first primitive only):
//! the edge vertices and the same lowered by [`skirt_depth_m`], its
//! positions placed as the surface's (u16 in the same box with meshopt),
//! normals copied from the edge vertices.
//!
//! The tile is made from the decoded quantized-mesh tile of the same
//! hierarchy (same vertices, triangles and edges; the vertices where a
//! client of the quantized-mesh tile draws them), so both formats carry the
//! same bound. The only new error is float32's rounding of each local
//! coordinate, at most `2⁻²⁴·|c|`, or the u16 quantization;
//! [`float32_budget_m`] and [`u16_budget_m`] bound them and the pyramid's
//! check draws the positions as the client computes them.
//!
//! Per-tile metadata (minimum and maximum height, bounding sphere, horizon
//! occlusion point) goes to the subtree files ([`super::tileset3d`]); it is
//! also kept in `asset.extras.cota` (the values' f64 bits in hexadecimal,
//! one short string) so that a resumed run can rebuild the subtrees without
//! cutting the tile again.

use serde_json::{json, Value};

use super::decode::DecodedTile;
use super::ellipsoid::{ecef, oct_decode};
use cota_io::meshopt::{
    encode_index_sequence, encode_triangles_rotated, encode_vertex_buffer, MeshoptError,
};

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

/// Little-endian bytes of the binary chunk, with accessors' views; with
/// meshopt, the length of the fallback buffer the compressed views stand in.
#[derive(Default)]
struct Bin {
    bytes: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
    fallback: usize,
}

impl Bin {
    /// Appends a view (4-byte aligned) and an accessor over it; its index.
    fn push(&mut self, data: &[u8], target: Option<u32>, accessor: Value) -> usize {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        let mut view = json!({"buffer": 0, "byteLength": data.len()});
        if !self.bytes.is_empty() {
            view["byteOffset"] = json!(self.bytes.len());
        }
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

    /// A view of `raw_len` bytes in the fallback buffer whose data is
    /// `packed` (`EXT_meshopt_compression`, `mode`, `[stride, count]`) in the
    /// binary chunk, and an accessor over it; its index.
    fn packed(
        &mut self,
        raw_len: usize,
        [stride, count]: [usize; 2],
        mode: &str,
        packed: &[u8],
        target: Option<u32>,
        accessor: Value,
    ) -> usize {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        self.fallback = self.fallback.next_multiple_of(4);
        let mut ext = json!({"buffer": 0, "byteLength": packed.len(),
            "byteStride": stride, "count": count, "mode": mode});
        if !self.bytes.is_empty() {
            ext["byteOffset"] = json!(self.bytes.len());
        }
        let mut view = json!({"buffer": 1, "byteLength": raw_len,
            "extensions": {"EXT_meshopt_compression": ext}});
        if self.fallback > 0 {
            view["byteOffset"] = json!(self.fallback);
        }
        if mode == "ATTRIBUTES" {
            view["byteStride"] = json!(stride);
        }
        if let Some(t) = target {
            view["target"] = json!(t);
        }
        self.bytes.extend_from_slice(packed);
        self.fallback += raw_len;
        let mut accessor = accessor;
        accessor["bufferView"] = json!(self.views.len());
        self.views.push(view);
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// An index accessor (u16 when `wide` is false), compressed in meshopt's
    /// `mode` when given.
    fn indices(
        &mut self,
        ids: &[u32],
        wide: bool,
        target: Option<u32>,
        mode: Option<&str>,
    ) -> Result<usize, MeshoptError> {
        let (bytes, component): (Vec<u8>, u32) = if wide {
            (ids.iter().flat_map(|i| i.to_le_bytes()).collect(), 5125)
        } else {
            (
                ids.iter().flat_map(|&i| (i as u16).to_le_bytes()).collect(),
                5123,
            )
        };
        let accessor = json!({"componentType": component, "count": ids.len(), "type": "SCALAR"});
        let stride = if wide { 4 } else { 2 };
        Ok(match mode {
            None => self.push(&bytes, target, accessor),
            Some(m) => {
                let packed = if m == "TRIANGLES" {
                    encode_triangles_rotated(ids)?.0
                } else {
                    encode_index_sequence(ids)?
                };
                self.packed(
                    bytes.len(),
                    [stride, ids.len()],
                    m,
                    &packed,
                    target,
                    accessor,
                )
            }
        })
    }

    /// The four edge lists in one plain view, an accessor each.
    fn edges(&mut self, lists: &[Vec<u32>; 4], wide: bool) -> [usize; 4] {
        let size = if wide { 4 } else { 2 };
        let flat: Vec<u8> = lists
            .iter()
            .flatten()
            .flat_map(|&i| {
                if wide {
                    i.to_le_bytes().to_vec()
                } else {
                    (i as u16).to_le_bytes().to_vec()
                }
            })
            .collect();
        let first = self.push(&flat, None, json!({}));
        let view = self
            .accessors
            .pop()
            .map_or(json!(0), |a| a["bufferView"].clone());
        let mut offset = 0;
        std::array::from_fn(|k| {
            let mut a = json!({"bufferView": view, "componentType": if wide { 5125 } else { 5123 },
                "count": lists[k].len(), "type": "SCALAR"});
            if offset > 0 {
                a["byteOffset"] = json!(offset);
            }
            offset += lists[k].len() * size;
            self.accessors.push(a);
            first + k
        })
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

/// How a GLB tile stores its geometry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum GlbGeometry {
    /// Float32 positions, plain indices.
    #[default]
    Float32,
    /// `KHR_mesh_quantization` positions (u16 over the tile's box) and
    /// `EXT_meshopt_compression` positions, indices and edges.
    Meshopt,
}

/// Where a tile's local positions go in the GLB: float32 about the centre
/// (the node matrix a translation), or u16 over a box in the node's axes.
struct Placement {
    /// The node matrix (column-major).
    matrix: Vec<f64>,
    /// The node's axes, in glTF axes (identity for float32).
    frame: [[f64; 3]; 3],
    /// With meshopt: what takes a local position to `[0, 1]³` through the
    /// (rounded) node matrix: the shift to add (tile centre minus the
    /// matrix's translation) and the inverse of its 3 × 3 part, rows.
    boxed: Option<([f64; 3], [[f64; 3]; 3])>,
}

/// The placement of `sets` of local positions about the centre `t`: a
/// translation for float32; for u16 a matrix from `[0, 1]³` to the box of
/// all of them, with one scale on all three axes when `uniform` (a tile
/// with normals: CesiumJS turns normals by the node matrix itself, not its
/// inverse transpose, so a scale differing per axis would bend them; with
/// one scale both agree).
fn placement(
    sets: &[&[[f64; 3]]],
    [t, rect]: [[f64; 4]; 2],
    geometry: GlbGeometry,
    uniform: bool,
) -> Placement {
    if geometry == GlbGeometry::Float32 {
        let matrix = vec![
            1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, t[0], t[1], t[2], 1.0,
        ];
        return Placement {
            matrix,
            frame: IDENTITY,
            boxed: None,
        };
    }
    let frame = enu_frame(rect);
    let turned: Vec<[f64; 3]> = sets.iter().flat_map(|s| turn(&frame, s)).collect();
    let (lo, mut scale) = quantization_box(&turned);
    if uniform {
        scale = [scale.iter().copied().fold(0.0, f64::max); 3];
    }
    let mut m = vec![0.0; 16];
    for (k, axis) in frame.iter().enumerate() {
        for r in 0..3 {
            m[4 * k + r] = axis[r] * scale[k];
            m[12 + r] += axis[r] * lo[k];
        }
    }
    for r in 0..3 {
        m[12 + r] += t[r];
    }
    m[15] = 1.0;
    // Shorter JSON: the columns to 9 significant digits, the translation to
    // 1 mm; the positions are quantized through this matrix's inverse, so
    // they land where the client puts them (within half a step per axis).
    for (k, v) in m.iter_mut().enumerate().take(15) {
        *v = if k >= 12 {
            (*v * 1e3).round() / 1e3
        } else {
            format!("{v:.8e}").parse().unwrap_or(*v)
        };
    }
    let columns: [[f64; 3]; 3] = std::array::from_fn(|k| [m[4 * k], m[4 * k + 1], m[4 * k + 2]]);
    let shift = [t[0] - m[12], t[1] - m[13], t[2] - m[14]];
    Placement {
        matrix: m,
        frame,
        boxed: Some((shift, inverse(columns))),
    }
}

/// The inverse of the 3 × 3 matrix with columns `c` (row-major rows), by
/// cofactors; the zero matrix when `c` is singular.
fn inverse(c: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let rows = [cross(c[1], c[2]), cross(c[2], c[0]), cross(c[0], c[1])];
    let det: f64 = (0..3).map(|r| rows[0][r] * c[0][r]).sum();
    if det == 0.0 || !det.is_finite() {
        return [[0.0; 3]; 3];
    }
    rows.map(|row| row.map(|v| v / det))
}

/// `local` in the node's axes `frame`.
fn turn(frame: &[[f64; 3]; 3], local: &[[f64; 3]]) -> Vec<[f64; 3]> {
    local
        .iter()
        .map(|p| frame.map(|axis| axis[0] * p[0] + axis[1] * p[1] + axis[2] * p[2]))
        .collect()
}

/// The accessor of the local positions `local` placed as `place` says:
/// float32, or u16 over the box (`KHR_mesh_quantization`, compressed with
/// `EXT_meshopt_compression` in mode `ATTRIBUTES`, stride 8).
fn positions(bin: &mut Bin, local: &[[f64; 3]], place: &Placement) -> Result<usize, MeshoptError> {
    let Some((shift, inv)) = place.boxed else {
        let f: Vec<[f32; 3]> = local.iter().map(|p| p.map(|c| c as f32)).collect();
        return Ok(bin.vec3(&f, true));
    };
    let q: Vec<[u16; 3]> = local
        .iter()
        .map(|p| {
            let d = [p[0] + shift[0], p[1] + shift[1], p[2] + shift[2]];
            inv.map(|row| {
                ((row[0] * d[0] + row[1] * d[1] + row[2] * d[2]) * 65535.0)
                    .round()
                    .clamp(0.0, 65535.0) as u16
            })
        })
        .collect();
    let raw: Vec<u8> = q
        .iter()
        .flat_map(|v| [v[0], v[1], v[2], 0].into_iter().flat_map(u16::to_le_bytes))
        .collect();
    let packed = encode_vertex_buffer(&raw, 8)?;
    let mut min = [u16::MAX; 3];
    let mut max = [0u16; 3];
    for v in &q {
        for k in 0..3 {
            min[k] = min[k].min(v[k]);
            max[k] = max[k].max(v[k]);
        }
    }
    let accessor = json!({"componentType": 5123, "normalized": true, "count": q.len(), "type": "VEC3", "min": min, "max": max});
    Ok(bin.packed(
        raw.len(),
        [8, q.len()],
        "ATTRIBUTES",
        &packed,
        Some(34962),
        accessor,
    ))
}

const IDENTITY: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// East, north and up at the centre of `rect` (degrees), in glTF axes: the
/// axes of the quantization box, so that u16 steps follow the terrain (the
/// vertex stream compresses better). For a tile wider or taller than 10°
/// the glTF axes themselves: the Khronos validator rejects some rotated
/// matrices with scales of thousands of kilometres as not TRS (it works in
/// float32), and those few coarse tiles weigh nothing in the pyramid.
fn enu_frame(rect: [f64; 4]) -> [[f64; 3]; 3] {
    if rect[2] - rect[0] > 10.0 || rect[3] - rect[1] > 10.0 {
        return IDENTITY;
    }
    let lon = (0.5 * (rect[0] + rect[2])).to_radians();
    let lat = (0.5 * (rect[1] + rect[3])).to_radians();
    let (so, co, sa, ca) = (lon.sin(), lon.cos(), lat.sin(), lat.cos());
    [
        to_gltf([-so, co, 0.0]),
        to_gltf([-sa * co, -sa * so, ca]),
        to_gltf([ca * co, ca * so, sa]),
    ]
}

/// The smallest corner and the size per axis (1 m where the vertices do
/// not spread) of the box of `local`.
pub fn quantization_box(local: &[[f64; 3]]) -> ([f64; 3], [f64; 3]) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in local {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let lo = lo.map(|c| if c.is_finite() { c } else { 0.0 });
    let scale = std::array::from_fn(|k| {
        let s = hi[k] - lo[k];
        if s.is_finite() && s > 0.0 {
            s
        } else {
            1.0
        }
    });
    (lo, scale)
}

/// The largest error `KHR_mesh_quantization` positions add to a tile whose
/// box has sides `scale` (metres), as CesiumJS dequantises them (`q / 65535`
/// rounded to float32, then the node matrix in f64): per axis half a step,
/// `s / 131070`, plus float32's half ulp of a value in `[0, 1]`, `2⁻²⁵·s`;
/// the three axes together.
pub fn u16_budget_m(scale: [f64; 3]) -> f64 {
    let per_axis = |s: f64| s * (1.0 / 131_070.0 + 2f64.powi(-25));
    scale
        .map(|s| per_axis(s).powi(2))
        .iter()
        .sum::<f64>()
        .sqrt()
}

/// How many levels coarser than a tile a neighbour may be whose gap its
/// skirt still closes ([`skirt_depth_m`]; `docs/3dtiles-terrain.md` argues
/// the figure for screen-space-error clients).
pub const SKIRT_LEVELS: u8 = 4;

/// How deep a tile's skirt hangs: the widest gap between its edge and a
/// neighbour's, `e_m + coarse_e_m`, where `e_m` is the tile's zoom's bound
/// and `coarse_e_m` the bound [`SKIRT_LEVELS`] zooms coarser (each drawn
/// edge lies within its tile's bound of the same surface, so the two edges
/// lie within the sum of each other), plus 5 % for the quantization and
/// float32 budgets both tiles add to their bounds (under 0.5 % of a bound in
/// the bundled fixture's pyramid), metres.
pub fn skirt_depth_m(e_m: f64, coarse_e_m: f64) -> f64 {
    1.05 * (e_m + coarse_e_m)
}

/// A tile's skirt for 3D Tiles clients that build none (all but CesiumJS,
/// which builds its own from `CESIUM_tile_edges` and reads only the first
/// primitive): every edge vertex copied, and copied again lowered along the
/// ellipsoid normal, two triangles per edge segment facing outwards.
#[derive(Debug, Clone, PartialEq)]
pub struct Skirt {
    /// ECEF positions, metres: per edge (in [`ccw_edges`] order) its
    /// vertices, then the same lowered.
    pub positions: Vec<[f64; 3]>,
    /// The tile's vertex each skirt vertex copies.
    pub from: Vec<u32>,
    /// Triangles (indices into `positions`), counter-clockwise seen from
    /// outside the tile.
    pub triangles: Vec<u32>,
}

/// The skirt of a decoded quantized-mesh tile over `rect` hanging
/// `depth_m` below its edges. The top vertices are computed as
/// [`ecef_positions`] computes them, so they are the surface's edge
/// vertices bit for bit.
pub fn skirt(tile: &DecodedTile, rect: [f64; 4], depth_m: f64) -> Skirt {
    let mut s = Skirt {
        positions: Vec::new(),
        from: Vec::new(),
        triangles: Vec::new(),
    };
    for list in ccw_edges(tile) {
        let base = s.positions.len() as u32;
        let n = list.len() as u32;
        for lower in [0.0, depth_m] {
            for &i in &list {
                let [lon, lat, h] = tile.geodetic(i as usize, rect);
                s.positions.push(ecef(lon, lat, h - lower));
                s.from.push(i);
            }
        }
        // The lists run clockwise seen from above (west side south to north,
        // ...), so (top i, top i+1, bottom i) turns counter-clockwise seen
        // from outside.
        for k in 0..n.saturating_sub(1) {
            if list[k as usize] == list[k as usize + 1] {
                continue;
            }
            let (t0, t1, b0, b1) = (base + k, base + k + 1, base + n + k, base + n + k + 1);
            s.triangles.extend_from_slice(&[t0, t1, b0, t1, b1, b0]);
        }
    }
    s
}

/// The GLB of a decoded quantized-mesh tile over `rect`, with vertex normals
/// when `normals` (and the tile has them), its geometry as `geometry` says,
/// and with `skirt_depth_m` a second primitive in the mesh: the tile's
/// [`skirt`] hanging that deep (positions in the same node frame, u16 in the
/// same box with meshopt, which then grows to hold it; normals copied from
/// the edge vertices; no `CESIUM_tile_edges`).
///
/// # Errors
/// [`MeshoptError`] when meshopt cannot hold the tile's indices (more than
/// 2³⁰ vertices).
pub fn encode_glb(
    tile: &DecodedTile,
    rect: [f64; 4],
    normals: bool,
    geometry: GlbGeometry,
    skirt_depth_m: Option<f64>,
) -> Result<Vec<u8>, MeshoptError> {
    let centre = tile.header.center;
    let to_local = |p: [f64; 3]| to_gltf([p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]]);
    let local: Vec<[f64; 3]> = ecef_positions(tile, rect)
        .into_iter()
        .map(to_local)
        .collect();
    let skirt = skirt_depth_m.map(|d| skirt(tile, rect, d));
    let skirt_local: Vec<[f64; 3]> = skirt
        .iter()
        .flat_map(|s| s.positions.iter().map(|&p| to_local(p)))
        .collect();
    let wide = local.len() > 65_535;
    let packed = geometry == GlbGeometry::Meshopt;
    let mut bin = Bin::default();
    let t = to_gltf(centre);
    let with_normals = normals && tile.normals.is_some();
    let place = placement(
        &[&local, &skirt_local],
        [[t[0], t[1], t[2], 0.0], rect],
        geometry,
        with_normals,
    );
    let position = positions(&mut bin, &local, &place)?;
    let flat: Vec<u32> = tile.triangles.iter().flatten().copied().collect();
    let indices = bin.indices(&flat, wide, Some(34963), packed.then_some("TRIANGLES"))?;
    let edges = bin.edges(&ccw_edges(tile), wide);
    let frame = place.frame;
    // Unit normals in the node's frame (turned with the quantization box).
    let turned_normals: Option<Vec<[f32; 3]>> =
        tile.normals.as_ref().filter(|_| normals).map(|oct| {
            oct.iter()
                .map(|&e| {
                    let n = to_gltf(oct_decode(e));
                    frame.map(|axis| (axis[0] * n[0] + axis[1] * n[1] + axis[2] * n[2]) as f32)
                })
                .collect()
        });
    let mut attributes = json!({"POSITION": position});
    if let Some(n) = &turned_normals {
        attributes["NORMAL"] = json!(bin.vec3(n, false));
    }
    let mut primitives = vec![json!({
        "attributes": attributes,
        "indices": indices,
        "mode": 4,
        "extensions": {"CESIUM_tile_edges": {
            "left": edges[0], "bottom": edges[1], "right": edges[2], "top": edges[3]
        }}
    })];
    if let Some(s) = &skirt {
        let copied = turned_normals
            .as_ref()
            .map(|n| s.from.iter().map(|&i| n[i as usize]).collect::<Vec<_>>());
        primitives.push(skirt_primitive(
            &mut bin,
            s,
            &skirt_local,
            &place,
            copied.as_deref(),
        )?);
    }
    let meta = TileMeta::of(tile);
    let mut buffers = vec![json!({"byteLength": bin.bytes.len()})];
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": "cota", "extras": {"cota": meta_json(&meta)}},
        "extensionsUsed": ["CESIUM_tile_edges"],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "matrix": place.matrix}],
        "meshes": [{"primitives": primitives}],
    });
    if packed {
        buffers.push(json!({"byteLength": bin.fallback, "extensions": {"EXT_meshopt_compression": {"fallback": true}}}));
        doc["extensionsUsed"] = json!([
            "CESIUM_tile_edges",
            "EXT_meshopt_compression",
            "KHR_mesh_quantization"
        ]);
        doc["extensionsRequired"] = json!(["EXT_meshopt_compression", "KHR_mesh_quantization"]);
    }
    doc["accessors"] = json!(bin.accessors);
    doc["bufferViews"] = json!(bin.views);
    doc["buffers"] = json!(buffers);
    Ok(glb(&doc, bin.bytes))
}

/// The skirt's primitive: its positions placed as the surface's, its
/// triangles, and with `normals` (copied from the edge vertices, in the
/// node's frame) a float32 NORMAL, as the surface's. (Normalized i8
/// normals compressed with meshopt made the fixture's gzipped meshopt
/// pyramid 0.8 % larger: gzip codes the float32 copies as repeats of the
/// surface's normals.)
fn skirt_primitive(
    bin: &mut Bin,
    s: &Skirt,
    local: &[[f64; 3]],
    place: &Placement,
    normals: Option<&[[f32; 3]]>,
) -> Result<Value, MeshoptError> {
    let packed = place.boxed.is_some();
    let position = positions(bin, local, place)?;
    let wide = local.len() > 65_535;
    let indices = bin.indices(
        &s.triangles,
        wide,
        Some(34963),
        packed.then_some("TRIANGLES"),
    )?;
    let mut attributes = json!({"POSITION": position});
    if let Some(n) = normals {
        attributes["NORMAL"] = json!(bin.vec3(n, false));
    }
    Ok(json!({"attributes": attributes, "indices": indices, "mode": 4}))
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

/// `TileMeta` for `asset.extras.cota`: the nine values' IEEE 754 bits as
/// one string of 144 hexadecimal digits (16 per value, in
/// [`TileMeta::values`] order), read back exactly on resume (decimal text
/// does not always parse back to the same f64).
pub(crate) fn meta_json(m: &TileMeta) -> Value {
    let bits: String = m
        .values()
        .iter()
        .map(|v| format!("{:016x}", v.to_bits()))
        .collect();
    json!(bits)
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
