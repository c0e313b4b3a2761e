//! The quantized-mesh-1.0 encoder, written from the public specification
//! (CesiumGS/quantized-mesh).
//!
//! 1. **Header** (88 bytes, little-endian): the tile's centre in ECEF
//!    (3 × f64; here the bounding sphere's centre), the minimum and maximum
//!    height (2 × f32), the bounding sphere (centre 3 × f64, radius f64) of
//!    the decoded vertices in ECEF on WGS 84, and the horizon occlusion point
//!    (3 × f64) in ellipsoid-scaled ECEF ([`super::ellipsoid`]; NaN, "never
//!    occluded", for the root tiles, which no such point can serve).
//! 2. **Vertices**: `vertexCount: u32`, then the `u`, `v` and height arrays
//!    of `u16` in `0..=32767` (`u` west→east, `v` south→north, height
//!    min→max, each rounded to the nearest step), each delta-coded against
//!    the previous vertex and zig-zag encoded. Vertices are numbered in the
//!    order the triangles first use them.
//! 3. **Indices**: padding to 4 bytes when the indices are 32-bit (above
//!    65 536 vertices; 16-bit up to 65 536 inclusive), `triangleCount: u32`,
//!    then three indices per triangle, counter-clockwise seen from above,
//!    high-water-mark coded (`code = highest − index`; a new vertex is always
//!    `highest`, coded 0, which first-use order guarantees).
//! 4. **Edge indices**: the vertices on the west, south, east and north
//!    edges (`u = 0`, `v = 0`, `u = 32767`, `v = 32767`), each list a `u32`
//!    count and indices of the same width, sorted along the edge (south to
//!    north, west to east): what a client needs to hang skirts.
//! 5. **Extensions**, each an id byte and a `u32` length: 1, oct-encoded
//!    per-vertex normals (ECEF, two bytes a vertex); 2, the water mask (one
//!    byte, or 256×256); 4, metadata (a `u32` length and JSON).

use cota_core::tiles::{TileMesh, WaterMask, QUANTIZED_MAX};
use cota_core::Mesh;

use super::ellipsoid::{bounding_sphere, ecef, enu_axes, horizon_occlusion_point, oct_encode};

/// Why a mesh cannot be encoded.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum EncodeError {
    /// No triangle.
    #[error("expected a mesh with at least one triangle, found none")]
    Empty,
    /// A vertex outside the tile, a bad index or a height that is not finite.
    #[error("vertex {vertex} does not fit the tile: {why}")]
    BadVertex {
        /// The vertex.
        vertex: usize,
        /// What is wrong.
        why: String,
    },
    /// Extension data of the wrong length.
    #[error("expected {expected} normals, one per vertex, found {found}")]
    Normals {
        /// Vertices.
        expected: usize,
        /// Normals given.
        found: usize,
    },
}

/// Where a mesh in lattice coordinates lies: `cells[0] × cells[1]` cells
/// over the rectangle `[west, south, east, north]` in degrees; vertex
/// `(col, row)` with `col ≤ cells[0]`, `row ≤ cells[1]`, row 0 north.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TileFrame {
    /// Cells across and down.
    pub cells: [u64; 2],
    /// `[west, south, east, north]`, degrees.
    pub rect_deg: [f64; 4],
}

/// Extension data to append.
#[derive(Debug, Clone, Copy, Default)]
pub struct Extensions<'a> {
    /// Unit normals per vertex (east, north, up): extension 1.
    pub normals_enu: Option<&'a [[f32; 3]]>,
    /// The water mask: extension 2.
    pub water_mask: Option<&'a WaterMask>,
    /// A JSON object: extension 4.
    pub metadata_json: Option<&'a str>,
}

/// Which extensions [`encode_tile`] writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub struct TileExtensions {
    /// Oct-encoded normals (1). Default: false.
    pub normals: bool,
    /// Water mask (2). Default: false.
    pub watermask: bool,
    /// Metadata (4): child availability and the geometric error. Default: false.
    pub metadata: bool,
}

impl TileExtensions {
    /// No extension.
    pub const NONE: TileExtensions = TileExtensions {
        normals: false,
        watermask: false,
        metadata: false,
    };

    /// Sets the three flags.
    pub const fn with(normals: bool, watermask: bool, metadata: bool) -> Self {
        TileExtensions {
            normals,
            watermask,
            metadata,
        }
    }

    /// The names for `layer.json`'s `extensions`, in id order.
    pub fn names(&self) -> Vec<&'static str> {
        let mut v = Vec::new();
        if self.normals {
            v.push("octvertexnormals");
        }
        if self.watermask {
            v.push("watermask");
        }
        if self.metadata {
            v.push("metadata");
        }
        v
    }
}

/// The metadata extension's JSON for a tile: its geometric error and its
/// children's availability (`available[0]` is the next zoom).
pub fn metadata_json(tile: &TileMesh) -> String {
    let mut v = serde_json::json!({ "geometricerror": tile.max_error_m });
    if !tile.children.is_empty() {
        let rects: Vec<serde_json::Value> = tile
            .children
            .iter()
            .map(
                |c| serde_json::json!({"startX": c.x0, "startY": c.y0, "endX": c.x1, "endY": c.y1}),
            )
            .collect();
        v["available"] = serde_json::json!([rects]);
    }
    v.to_string()
}

/// Encodes a tile cut by [`cota_core::tiles::Prepared::cut`].
///
/// # Errors
/// [`EncodeError`] for an empty mesh, a vertex off the tile or normals of
/// the wrong count.
pub fn encode_tile(tile: &TileMesh, ext: &TileExtensions) -> Result<Vec<u8>, EncodeError> {
    let json = ext.metadata.then(|| metadata_json(tile));
    let frame = TileFrame {
        cells: [tile.cells; 2],
        rect_deg: tile.rect_deg,
    };
    let extensions = Extensions {
        normals_enu: if ext.normals {
            tile.normals_enu.as_deref()
        } else {
            None
        },
        water_mask: if ext.watermask {
            Some(tile.water_mask.as_ref().unwrap_or(&WaterMask::Uniform(0)))
        } else {
            None
        },
        metadata_json: json.as_deref(),
    };
    encode(&tile.mesh, &frame, &extensions)
}

/// The vertices in first-use order: `(order, new index of each old vertex)`.
fn first_use(mesh: &Mesh) -> Result<(Vec<u32>, Vec<u32>), EncodeError> {
    let n = mesh.vertices.len();
    let mut new_of = vec![u32::MAX; n];
    let mut order = Vec::with_capacity(n);
    for t in &mesh.triangles {
        for &i in t {
            let slot = new_of
                .get_mut(i as usize)
                .ok_or_else(|| EncodeError::BadVertex {
                    vertex: i as usize,
                    why: format!("index out of range ({n} vertices)"),
                })?;
            if *slot == u32::MAX {
                *slot = order.len() as u32;
                order.push(i);
            }
        }
    }
    Ok((order, new_of))
}

/// `round(a · 32767 / b)` in integers.
fn quantize(a: u64, b: u64) -> u16 {
    let q = u64::from(QUANTIZED_MAX);
    ((2 * a * q + b) / (2 * b)) as u16
}

/// Quantized `u`, `v`, height per vertex (in `order`) and the height range.
fn quantized(
    mesh: &Mesh,
    frame: &TileFrame,
    order: &[u32],
) -> Result<(Vec<[u16; 3]>, f32, f32), EncodeError> {
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for &i in order {
        let v = mesh.vertices[i as usize];
        if !v.z_m.is_finite()
            || u64::from(v.col) > frame.cells[0]
            || u64::from(v.row) > frame.cells[1]
        {
            return Err(EncodeError::BadVertex {
                vertex: i as usize,
                why: format!(
                    "at column {}, row {}, height {} m, in a tile of {}x{} cells",
                    v.col, v.row, v.z_m, frame.cells[0], frame.cells[1]
                ),
            });
        }
        lo = lo.min(v.z_m);
        hi = hi.max(v.z_m);
    }
    let span = f64::from(hi) - f64::from(lo);
    let q = f64::from(QUANTIZED_MAX);
    let out = order
        .iter()
        .map(|&i| {
            let v = mesh.vertices[i as usize];
            let h = if span > 0.0 {
                ((f64::from(v.z_m) - f64::from(lo)) / span * q).round() as u16
            } else {
                0
            };
            [
                quantize(u64::from(v.col), frame.cells[0]),
                quantize(frame.cells[1] - u64::from(v.row), frame.cells[1]),
                h,
            ]
        })
        .collect();
    Ok((out, lo, hi))
}

/// Longitude, latitude, height of a quantized vertex as a client decodes it.
fn geodetic(q: [u16; 3], frame: &TileFrame, lo: f32, hi: f32) -> [f64; 3] {
    let m = f64::from(QUANTIZED_MAX);
    let [w, s, e, n] = frame.rect_deg;
    [
        w + f64::from(q[0]) / m * (e - w),
        s + f64::from(q[1]) / m * (n - s),
        f64::from(lo) + f64::from(q[2]) / m * (f64::from(hi) - f64::from(lo)),
    ]
}

fn put_f64(out: &mut Vec<u8>, v: f64) {
    out.extend_from_slice(&v.to_le_bytes());
}

/// The 88-byte header.
fn header(out: &mut Vec<u8>, q: &[[u16; 3]], frame: &TileFrame, lo: f32, hi: f32) {
    let pts: Vec<[f64; 3]> = q
        .iter()
        .map(|&v| {
            let [lon, lat, h] = geodetic(v, frame, lo, hi);
            ecef(lon, lat, h)
        })
        .collect();
    let (c, r) = bounding_sphere(&pts);
    let hop = horizon_occlusion_point(c, &pts).unwrap_or([f64::NAN; 3]);
    for v in c {
        put_f64(out, v);
    }
    out.extend_from_slice(&lo.to_le_bytes());
    out.extend_from_slice(&hi.to_le_bytes());
    for v in c {
        put_f64(out, v);
    }
    put_f64(out, r);
    for v in hop {
        put_f64(out, v);
    }
}

fn zigzag(d: i32) -> u16 {
    ((d << 1) ^ (d >> 31)) as u16
}

/// Encodes `mesh` (vertices on the frame's lattice, triangles
/// counter-clockwise seen from above) as one quantized-mesh-1.0 tile.
///
/// # Errors
/// [`EncodeError`] for an empty mesh, a bad index or vertex, or normals of
/// the wrong count.
pub fn encode(
    mesh: &Mesh,
    frame: &TileFrame,
    ext: &Extensions<'_>,
) -> Result<Vec<u8>, EncodeError> {
    if mesh.triangles.is_empty() {
        return Err(EncodeError::Empty);
    }
    let (order, new_of) = first_use(mesh)?;
    let (q, lo, hi) = quantized(mesh, frame, &order)?;
    let n = order.len();
    let mut out = Vec::with_capacity(88 + 6 * n + 6 * mesh.triangles.len() + 64);
    header(&mut out, &q, frame, lo, hi);
    out.extend_from_slice(&(n as u32).to_le_bytes());
    for k in 0..3 {
        let mut prev = 0i32;
        for v in &q {
            out.extend_from_slice(&zigzag(i32::from(v[k]) - prev).to_le_bytes());
            prev = i32::from(v[k]);
        }
    }
    let wide = n > 65_536;
    let put = |out: &mut Vec<u8>, x: u32| {
        if wide {
            out.extend_from_slice(&x.to_le_bytes());
        } else {
            out.extend_from_slice(&(x as u16).to_le_bytes());
        }
    };
    while out.len() % if wide { 4 } else { 2 } != 0 {
        out.push(0);
    }
    out.extend_from_slice(&(mesh.triangles.len() as u32).to_le_bytes());
    let mut highest = 0u32;
    for t in &mesh.triangles {
        for &i in t {
            let j = new_of[i as usize];
            put(&mut out, highest - j);
            if j == highest {
                highest += 1;
            }
        }
    }
    let m = QUANTIZED_MAX as u16;
    // West, south, east, north: (axis on the edge, its value, axis to sort by).
    for (axis, value, along) in [(0, 0, 1), (1, 0, 0), (0, m, 1), (1, m, 0)] {
        let mut list: Vec<u32> = (0..n as u32)
            .filter(|&i| q[i as usize][axis] == value)
            .collect();
        list.sort_by_key(|&i| q[i as usize][along]);
        out.extend_from_slice(&(list.len() as u32).to_le_bytes());
        for i in list {
            put(&mut out, i);
        }
    }
    extensions(&mut out, mesh, frame, &order, &q, ext)?;
    Ok(out)
}

fn extension(out: &mut Vec<u8>, id: u8, data: &[u8]) {
    out.push(id);
    out.extend_from_slice(&(data.len() as u32).to_le_bytes());
    out.extend_from_slice(data);
}

fn extensions(
    out: &mut Vec<u8>,
    mesh: &Mesh,
    frame: &TileFrame,
    order: &[u32],
    q: &[[u16; 3]],
    ext: &Extensions<'_>,
) -> Result<(), EncodeError> {
    if let Some(normals) = ext.normals_enu {
        if normals.len() != mesh.vertices.len() {
            return Err(EncodeError::Normals {
                expected: mesh.vertices.len(),
                found: normals.len(),
            });
        }
        let mut data = Vec::with_capacity(2 * order.len());
        for (k, &i) in order.iter().enumerate() {
            let [lon, lat, _] = geodetic(q[k], frame, 0.0, 0.0);
            let [e, n, u] = enu_axes(lon, lat);
            let l = normals[i as usize].map(f64::from);
            let v = [0, 1, 2].map(|c| l[0] * e[c] + l[1] * n[c] + l[2] * u[c]);
            data.extend_from_slice(&oct_encode(v));
        }
        extension(out, 1, &data);
    }
    match ext.water_mask {
        Some(WaterMask::Uniform(v)) => extension(out, 2, &[*v]),
        Some(WaterMask::Grid(g)) => extension(out, 2, g),
        None => {}
    }
    if let Some(json) = ext.metadata_json {
        let mut data = Vec::with_capacity(4 + json.len());
        data.extend_from_slice(&(json.len() as u32).to_le_bytes());
        data.extend_from_slice(json.as_bytes());
        extension(out, 4, &data);
    }
    Ok(())
}
