//! Binary glTF 2.0 (GLB) writer; the JSON is built with the `gltf-json` crate.
//!
//! Container (glTF 2.0 spec, "GLB File Format Specification"): a 12-byte
//! header (magic `glTF`, version 2, total length), a JSON chunk (type `JSON`,
//! padded with spaces to a multiple of 4 bytes) and a BIN chunk (type `BIN\0`,
//! padded with zeros to a multiple of 4), all little-endian.
//!
//! Content: one scene, one node, one mesh with one primitive, mode TRIANGLES
//! (the default, so not spelled out), one material (grey, non-metallic,
//! rough); [`write_glb_strip`] writes the same with one TRIANGLE_STRIP
//! primitive (mode 5) instead. The single buffer is the BIN chunk, holding three tightly packed
//! buffer views, each starting on a 4-byte boundary:
//! 1. POSITION: f32 VEC3, target ARRAY_BUFFER, with the accessor `min`/`max`
//!    the spec requires (computed from the f32 values written);
//! 2. NORMAL: f32 VEC3 of unit length, target ARRAY_BUFFER: area-weighted
//!    vertex normals in the output frame;
//! 3. indices: SCALAR u16 or u32 per [`IndexWidth`], target
//!    ELEMENT_ARRAY_BUFFER, triangles counter-clockwise seen from their front
//!    (glTF's front-face convention).
//!
//! Frames: the accessor data is in the frame chosen by
//! [`Coords`](super::Coords), z up — in local metres relative to the grid's
//! south-west sample, which keeps coordinates small (≤ the grid's extent) and
//! so f32-precise. glTF itself is y-up, so the node carries a rotation of −90°
//! about x, mapping (x, y, z) to (x, z, −y): viewers show the terrain upright
//! with east along +x and north along −z, while the data stays as documented.
//!
//! Georeference: `asset.extras` holds the CRS, the affine from samples to CRS
//! coordinates, the grid's own transform, the CRS coordinates of the
//! south-west sample (the local origin), the cell size in metres and the
//! coordinate mode; `asset.generator` is `cota`.

use std::collections::BTreeMap;
use std::io::Write;

use cota_core::{HeightGrid, Mesh};
use gltf_json as json;
use json::accessor::{ComponentType, GenericComponentType, Type};
use json::buffer::Target;
use json::material::{PbrBaseColorFactor, PbrMetallicRoughness, StrengthFactor};
use json::mesh::{Mode, Primitive, Semantic};
use json::scene::UnitQuaternion;
use json::validation::{Checked, USize64};
use json::{Accessor, Index};
use rayon::prelude::*;

use super::coords::{Frame, GeoInfo};
use super::error::ExportError;
use super::geometry::{check_mesh, push_f32s, to_f32, vertex_normals};
use super::options::{ExportOptions, IndexWidth};
use super::par::{on_pool, write_chunks};

/// `glTF` as a little-endian u32.
const MAGIC: u32 = 0x4654_6C67;
/// Container version.
const VERSION: u32 = 2;
/// Chunk type `JSON`.
const CHUNK_JSON: u32 = 0x4E4F_534A;
/// Chunk type `BIN\0`.
const CHUNK_BIN: u32 = 0x004E_4942;
/// Bytes of the file header and of a chunk header.
const HEADER_BYTES: u64 = 12;
/// Bytes of a chunk header (length and type).
const CHUNK_HEADER_BYTES: u64 = 8;
/// Largest vertex count with u16 indices (65 535 is the primitive restart value).
const MAX_U16_VERTICES: usize = 65_535;
/// Largest vertex count with u32 indices (u32::MAX is the restart value).
const MAX_U32_VERTICES: usize = u32::MAX as usize;

/// Writes `mesh` as a GLB to `w` (wrap files in a `BufWriter`, as
/// [`write_mesh`](super::write_mesh) does).
///
/// # Errors
/// [`ExportError::Io`] from `w`; the mesh checks of [`ExportError`];
/// [`ExportError::TooLarge`] when the indices do not fit the chosen
/// [`IndexWidth`] or the file would exceed 4 GiB; [`ExportError::Json`].
pub fn write_glb<W: Write + Send>(
    w: W,
    mesh: &Mesh,
    grid: &HeightGrid,
    opts: &ExportOptions,
) -> Result<(), ExportError> {
    on_pool(|| encode_glb(w, mesh, grid, opts))
}

/// The body of [`write_glb`], on the pool.
fn encode_glb<W: Write + Send>(
    w: W,
    mesh: &Mesh,
    grid: &HeightGrid,
    opts: &ExportOptions,
) -> Result<(), ExportError> {
    write_glb_primitive(w, mesh, None, grid, opts)
}

/// Writes `mesh` as a GLB whose primitive is one TRIANGLE_STRIP (mode 5) with
/// the indices `strip` (a standard strip of `mesh`'s triangles, as made by
/// `cota_core::strip::stripify_bitree`; odd triangles reversed, degenerate
/// triangles as connectors). `mesh` must be the mesh the strip encodes:
/// `MeshStrip::mesh`, which differs from the stripped mesh when unit cells
/// were re-triangulated; its triangles give the normals, and they are
/// checked to be exactly the strip's. Everything else is as in
/// [`write_glb`]. When the output frame is mirrored the strip gets one
/// leading repeated index, which flips every triangle's parity and so keeps
/// the front faces up.
///
/// # Errors
/// As [`write_glb`]; [`ExportError::VertexOutOfRange`] for a strip index out
/// of range (`triangle` is then the strip position minus 2);
/// [`ExportError::StripMismatch`] when the strip's triangles are not the
/// mesh's.
pub fn write_glb_strip<W: Write + Send>(
    w: W,
    mesh: &Mesh,
    strip: &[u32],
    grid: &HeightGrid,
    opts: &ExportOptions,
) -> Result<(), ExportError> {
    on_pool(|| encode_glb_strip(w, mesh, strip, grid, opts))
}

/// The body of [`write_glb_strip`], on the pool.
fn encode_glb_strip<W: Write + Send>(
    w: W,
    mesh: &Mesh,
    strip: &[u32],
    grid: &HeightGrid,
    opts: &ExportOptions,
) -> Result<(), ExportError> {
    write_glb_primitive(w, mesh, Some(strip), grid, opts)
}

/// [`ExportError::StripMismatch`] unless the strip's non-degenerate
/// triangles, with their drawn orientation, are the mesh's triangles, each
/// once. Indices are already known to be in range.
fn check_strip_triangles(mesh: &Mesh, strip: &[u32]) -> Result<(), ExportError> {
    use cota_core::strip::{canonical, strip_to_triangles};
    let mut got: Vec<[u32; 3]> = strip_to_triangles(strip)
        .into_iter()
        .map(canonical)
        .collect();
    let mut want: Vec<[u32; 3]> = mesh.triangles.iter().copied().map(canonical).collect();
    got.sort_unstable();
    want.sort_unstable();
    if got == want {
        return Ok(());
    }
    let foreign = got
        .iter()
        .filter(|t| want.binary_search(t).is_err())
        .count();
    Err(ExportError::StripMismatch {
        mesh_triangles: want.len(),
        strip_triangles: got.len(),
        foreign,
    })
}

/// [`write_glb`] (`strip = None`) or [`write_glb_strip`].
fn write_glb_primitive<W: Write + Send>(
    mut w: W,
    mesh: &Mesh,
    strip: Option<&[u32]>,
    grid: &HeightGrid,
    opts: &ExportOptions,
) -> Result<(), ExportError> {
    check_mesh(mesh)?;
    let frame = Frame::new(grid, opts.coords);
    let positions: Vec<[f32; 3]> = mesh
        .vertices
        .par_iter()
        .map(|v| to_f32(frame.vertex(v)))
        .collect();
    let normals = vertex_normals(mesh, &frame);
    let strip: Option<Vec<u32>> = match strip {
        None => None,
        Some(s) => {
            let nv = mesh.vertices.len();
            if let Some((k, &bad)) = s.iter().enumerate().find(|(_, &i)| i as usize >= nv) {
                return Err(ExportError::VertexOutOfRange {
                    index: bad,
                    count: nv,
                    triangle: k.saturating_sub(2),
                });
            }
            check_strip_triangles(mesh, s)?;
            let mut v = Vec::with_capacity(s.len() + 1);
            if frame.mirrored() {
                v.extend(s.first().copied());
            }
            v.extend_from_slice(s);
            Some(v)
        }
    };
    let index_count = match &strip {
        Some(s) => s.len() as u64,
        None => 3 * mesh.triangles.len() as u64,
    };
    let mode = if strip.is_some() {
        Mode::TriangleStrip
    } else {
        Mode::Triangles
    };
    let layout = Layout::new(
        mesh,
        index_count,
        index_type(mesh.vertices.len(), opts.index_width)?,
    );
    let root = build_root(&positions, &layout, mode, &GeoInfo::new(grid, opts.coords))?;
    let json = json::serialize::to_vec(&root).map_err(|e| ExportError::Json(e.to_string()))?;
    let json_padded = pad4(json.len() as u64);
    let bin_padded = pad4(layout.buffer_bytes);
    let total = HEADER_BYTES + 2 * CHUNK_HEADER_BYTES + json_padded + bin_padded;
    let total = u32::try_from(total).map_err(|_| ExportError::TooLarge {
        what: "bytes in a GLB",
        count: total,
        max: u64::from(u32::MAX),
    })?;
    write_u32s(&mut w, &[MAGIC, VERSION, total])?;
    write_chunk_header(&mut w, json_padded, CHUNK_JSON)?;
    w.write_all(&json)?;
    write_padding(&mut w, json.len() as u64, b' ')?;
    write_chunk_header(&mut w, bin_padded, CHUNK_BIN)?;
    write_bin(
        &mut w,
        mesh,
        strip.as_deref(),
        &frame,
        &positions,
        &normals,
        layout.index,
    )?;
    write_padding(&mut w, layout.buffer_bytes, 0)?;
    w.flush()?;
    Ok(())
}

/// The index component type for `vertices` vertices.
fn index_type(vertices: usize, width: IndexWidth) -> Result<ComponentType, ExportError> {
    let (ty, max) = match width {
        IndexWidth::Auto if vertices <= MAX_U16_VERTICES => (ComponentType::U16, MAX_U16_VERTICES),
        IndexWidth::U16 => (ComponentType::U16, MAX_U16_VERTICES),
        IndexWidth::Auto | IndexWidth::U32 => (ComponentType::U32, MAX_U32_VERTICES),
    };
    if vertices > max {
        return Err(ExportError::TooLarge {
            what: if ty == ComponentType::U16 {
                "vertices for 16-bit glTF indices"
            } else {
                "vertices for 32-bit glTF indices"
            },
            count: vertices as u64,
            max: max as u64,
        });
    }
    Ok(ty)
}

/// Byte layout of the BIN chunk.
#[derive(Debug, Clone, Copy)]
struct Layout {
    vertices: u64,
    /// Index count (3 per triangle, or the strip's length).
    indices: u64,
    index: ComponentType,
    /// Bytes of the positions view, and of the normals view.
    vec3_bytes: u64,
    /// Bytes of the index view.
    index_bytes: u64,
    /// Bytes of the buffer (all views, before the chunk's padding).
    buffer_bytes: u64,
}

impl Layout {
    /// Positions, normals, indices, back to back (each a multiple of 4 bytes
    /// from the start, since 12·n is).
    fn new(mesh: &Mesh, indices: u64, index: ComponentType) -> Self {
        let vertices = mesh.vertices.len() as u64;
        let vec3_bytes = 12 * vertices;
        let index_bytes = indices * index.size() as u64;
        Layout {
            vertices,
            indices,
            index,
            vec3_bytes,
            index_bytes,
            buffer_bytes: 2 * vec3_bytes + index_bytes,
        }
    }
}

/// The glTF JSON document.
fn build_root(
    positions: &[[f32; 3]],
    layout: &Layout,
    mode: Mode,
    info: &GeoInfo,
) -> Result<json::Root, ExportError> {
    let (min, max) = bounds(positions);
    let extras = json::extras::RawValue::from_string(info.json().to_string())
        .map_err(|e| ExportError::Json(e.to_string()))?;
    let view = |offset: u64, bytes: u64, target: Target| json::buffer::View {
        buffer: Index::new(0),
        byte_length: USize64(bytes),
        byte_offset: Some(USize64(offset)),
        byte_stride: None,
        target: Some(Checked::Valid(target)),
        extensions: None,
        extras: None,
    };
    let mut attributes = BTreeMap::new();
    attributes.insert(Checked::Valid(Semantic::Positions), Index::new(0));
    attributes.insert(Checked::Valid(Semantic::Normals), Index::new(1));
    let half_turn = std::f32::consts::FRAC_1_SQRT_2;
    Ok(json::Root {
        asset: json::Asset {
            generator: Some("cota".to_string()),
            extras: Some(extras),
            ..json::Asset::default()
        },
        buffers: vec![json::Buffer {
            byte_length: USize64(layout.buffer_bytes),
            uri: None,
            extensions: None,
            extras: None,
        }],
        buffer_views: vec![
            view(0, layout.vec3_bytes, Target::ArrayBuffer),
            view(layout.vec3_bytes, layout.vec3_bytes, Target::ArrayBuffer),
            view(
                2 * layout.vec3_bytes,
                layout.index_bytes,
                Target::ElementArrayBuffer,
            ),
        ],
        accessors: vec![
            accessor(0, layout.vertices, ComponentType::F32, Type::Vec3).with_bounds(&min, &max),
            accessor(1, layout.vertices, ComponentType::F32, Type::Vec3),
            accessor(2, layout.indices, layout.index, Type::Scalar),
        ],
        materials: vec![terrain_material()],
        meshes: vec![json::Mesh {
            extensions: None,
            extras: None,
            primitives: vec![Primitive {
                attributes,
                extensions: None,
                extras: None,
                indices: Some(Index::new(2)),
                material: Some(Index::new(0)),
                mode: Checked::Valid(mode),
                targets: None,
            }],
            weights: None,
        }],
        nodes: vec![json::Node {
            mesh: Some(Index::new(0)),
            rotation: Some(UnitQuaternion([-half_turn, 0.0, 0.0, half_turn])),
            ..json::Node::default()
        }],
        scenes: vec![json::Scene {
            extensions: None,
            extras: None,
            nodes: vec![Index::new(0)],
        }],
        scene: Some(Index::new(0)),
        ..json::Root::default()
    })
}

/// An accessor over the whole of buffer view `view`.
fn accessor(view: u32, count: u64, component: ComponentType, ty: Type) -> Accessor {
    Accessor {
        buffer_view: Some(Index::new(view)),
        byte_offset: None,
        count: USize64(count),
        component_type: Checked::Valid(GenericComponentType(component)),
        extensions: None,
        extras: None,
        type_: Checked::Valid(ty),
        min: None,
        max: None,
        normalized: false,
        sparse: None,
    }
}

/// Sets an accessor's `min` and `max`.
trait WithBounds {
    /// The accessor with `min` and `max` set.
    fn with_bounds(self, min: &[f32; 3], max: &[f32; 3]) -> Self;
}

impl WithBounds for Accessor {
    fn with_bounds(mut self, min: &[f32; 3], max: &[f32; 3]) -> Self {
        self.min = Some(serde_json::json!(min));
        self.max = Some(serde_json::json!(max));
        self
    }
}

/// Component-wise minimum and maximum (the mesh has at least one vertex; no
/// value is NaN, so the order of the reduction does not matter).
fn bounds(positions: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    let init = || ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    let widen = |(mut lo, mut hi): ([f32; 3], [f32; 3]), p: &[f32; 3]| {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
        (lo, hi)
    };
    positions
        .par_iter()
        .fold(init, widen)
        .reduce(init, |a, b| widen(widen(a, &b.0), &b.1))
}

/// Light grey, non-metallic, fully rough: reads as terrain under any light
/// (glTF's default material is fully metallic, which renders dark).
fn terrain_material() -> json::Material {
    json::Material {
        pbr_metallic_roughness: PbrMetallicRoughness {
            base_color_factor: PbrBaseColorFactor([0.8, 0.8, 0.8, 1.0]),
            metallic_factor: StrengthFactor(0.0),
            roughness_factor: StrengthFactor(1.0),
            ..PbrMetallicRoughness::default()
        },
        ..json::Material::default()
    }
}

/// `n` rounded up to a multiple of 4.
fn pad4(n: u64) -> u64 {
    n.div_ceil(4) * 4
}

/// Little-endian u32s.
fn write_u32s<W: Write>(w: &mut W, v: &[u32]) -> Result<(), ExportError> {
    for x in v {
        w.write_all(&x.to_le_bytes())?;
    }
    Ok(())
}

/// A chunk header: padded length and type. The length fits: the total was checked.
fn write_chunk_header<W: Write>(w: &mut W, length: u64, ty: u32) -> Result<(), ExportError> {
    write_u32s(w, &[length as u32, ty])
}

/// The bytes that pad `len` to a multiple of 4.
fn write_padding<W: Write>(w: &mut W, len: u64, byte: u8) -> Result<(), ExportError> {
    let n = (pad4(len) - len) as usize;
    w.write_all(&[byte; 3][..n])?;
    Ok(())
}

/// The BIN chunk's content: positions, normals, indices (each section
/// encoded in parallel chunks, written in order).
fn write_bin<W: Write + Send>(
    w: &mut W,
    mesh: &Mesh,
    strip: Option<&[u32]>,
    frame: &Frame,
    positions: &[[f32; 3]],
    normals: &[[f32; 3]],
    index: ComponentType,
) -> Result<(), ExportError> {
    for section in [positions, normals] {
        write_chunks(w, section, 12, |_, chunk, buf| {
            push_f32s(buf, chunk.as_flattened());
            Ok(())
        })?;
    }
    // Fits: index_type allowed u16 only for at most 65 535 vertices.
    let push_index = |buf: &mut Vec<u8>, i: u32| match index {
        ComponentType::U16 => buf.extend_from_slice(&(i as u16).to_le_bytes()),
        _ => buf.extend_from_slice(&i.to_le_bytes()),
    };
    match strip {
        // The chunk's padding follows (write_glb_primitive).
        Some(s) => write_chunks(w, s, 4, |_, chunk, buf| {
            chunk.iter().for_each(|&i| push_index(buf, i));
            Ok(())
        }),
        None => write_chunks(w, &mesh.triangles, 12, |_, chunk, buf| {
            for &t in chunk {
                frame.orient(t).into_iter().for_each(|i| push_index(buf, i));
            }
            Ok(())
        }),
    }
}
