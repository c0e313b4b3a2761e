//! Binary glTF 2.0 (GLB) writer; the JSON is built with the `gltf-json` crate,
//! the container is written by `container` (header, JSON chunk, BIN chunk).
//! With [`ExportOptions::quantize`] the layout is `quantized`'s instead
//! (`KHR_mesh_quantization`); what follows is the default, float layout.
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
use json::accessor::{ComponentType, Type};
use json::buffer::Target;
use json::mesh::{Mode, Semantic};
use json::validation::Checked;
use json::Index;
use rayon::prelude::*;

use self::container::{
    accessor, asset, buffer, single_mesh_root, terrain_material, view, write_container, WithBounds,
};
use super::coords::{Frame, GeoInfo};
use super::error::ExportError;
use super::geometry::{check_mesh, to_f32, vertex_normals};
use super::options::{ExportOptions, IndexWidth};
use super::par::{on_pool, put_f32s, put_u32s, write_fixed};
use super::quantize::GlbQuantization;

mod container;
mod quantized;
mod textured;

pub use textured::{encode_png, textured_mesh_bytes, write_glb_textured};

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
    mut w: W,
    mesh: &Mesh,
    grid: &HeightGrid,
    opts: &ExportOptions,
) -> Result<(), ExportError> {
    if opts.quantize {
        check_mesh(mesh)?;
        let q = GlbQuantization::plan(mesh, &Frame::new(grid, opts.coords))?;
        return quantized::write_quantized(&mut w, mesh, grid, opts, &q);
    }
    write_glb_primitive(w, mesh, None, grid, opts)
}

/// Writes `mesh` as the quantized GLB `q` plans (made by
/// [`GlbQuantization::new`] for this mesh, grid and options): what
/// [`write_glb`] writes with [`ExportOptions::quantize`], without planning
/// again.
///
/// # Errors
/// As [`write_glb`].
pub fn write_glb_quantized<W: Write + Send>(
    mut w: W,
    mesh: &Mesh,
    grid: &HeightGrid,
    opts: &ExportOptions,
    q: &GlbQuantization,
) -> Result<(), ExportError> {
    on_pool(|| quantized::write_quantized(&mut w, mesh, grid, opts, q))
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
    if opts.quantize {
        return Err(ExportError::Incompatible {
            expected: "a triangle list in a quantized GLB",
            found: "a triangle strip",
        });
    }
    write_glb_primitive(w, mesh, Some(strip), grid, opts)
}

/// [`ExportError::StripMismatch`] unless the strip's non-degenerate
/// triangles, with their drawn orientation, are the mesh's triangles, each
/// once. Indices are already known to be in range.
fn check_strip_triangles(mesh: &Mesh, strip: &[u32]) -> Result<(), ExportError> {
    cota_core::strip::validate_indices(strip, mesh).map_err(|e| ExportError::StripMismatch {
        mesh_triangles: e.mesh_triangles,
        strip_triangles: e.strip_triangles,
        foreign: e.foreign,
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
    let bounds = bounds(&mesh.vertices, |v| to_f32(frame.vertex(v)));
    let root = build_root(bounds, &layout, mode, &GeoInfo::new(grid, opts.coords))?;
    write_container(&mut w, &root, layout.buffer_bytes, |w| {
        write_bin(w, mesh, strip.as_deref(), &frame, &normals, layout.index)
    })
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
    (min, max): ([f32; 3], [f32; 3]),
    layout: &Layout,
    mode: Mode,
    info: &GeoInfo,
) -> Result<json::Root, ExportError> {
    let view = |offset: u64, bytes: u64, target: Target| view(offset, bytes, None, target);
    let mut attributes = BTreeMap::new();
    attributes.insert(Checked::Valid(Semantic::Positions), Index::new(0));
    attributes.insert(Checked::Valid(Semantic::Normals), Index::new(1));
    Ok(json::Root {
        asset: asset(info)?,
        buffers: vec![buffer(layout.buffer_bytes)],
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
            accessor(0, layout.vertices, ComponentType::F32, Type::Vec3)
                .with_bounds(serde_json::json!(min), serde_json::json!(max)),
            accessor(1, layout.vertices, ComponentType::F32, Type::Vec3),
            accessor(2, layout.indices, layout.index, Type::Scalar),
        ],
        materials: vec![terrain_material()],
        ..single_mesh_root(attributes, mode)
    })
}

/// Component-wise minimum and maximum of the written (f32) positions,
/// `position(item)` for each of `items` (at least one; no value is NaN, so
/// the order of the reduction does not matter).
fn bounds<T: Sync>(items: &[T], position: impl Fn(&T) -> [f32; 3] + Sync) -> ([f32; 3], [f32; 3]) {
    let init = || ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    let widen = |(mut lo, mut hi): ([f32; 3], [f32; 3]), p: [f32; 3]| {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
        (lo, hi)
    };
    items
        .par_iter()
        .fold(init, |b, v| widen(b, position(v)))
        .reduce(init, |a, b| widen(widen(a, b.0), b.1))
}

/// The BIN chunk's content: positions (converted as they are encoded),
/// normals, indices (each section encoded in parallel chunks, written in
/// order).
fn write_bin<W: Write + Send>(
    w: &mut W,
    mesh: &Mesh,
    strip: Option<&[u32]>,
    frame: &Frame,
    normals: &[[f32; 3]],
    index: ComponentType,
) -> Result<(), ExportError> {
    write_fixed::<12, _, _, _>(w, &mesh.vertices, |_, v, out| {
        put_f32s(out, &to_f32(frame.vertex(v)));
    })?;
    write_fixed::<12, _, _, _>(w, normals, |_, n, out| put_f32s(out, n))?;
    // Fits: index_type allowed u16 only for at most 65 535 vertices.
    match (strip, index) {
        // The chunk's padding follows (write_glb_primitive).
        (Some(s), ComponentType::U16) => write_fixed::<2, _, _, _>(w, s, |_, &i, out| {
            *out = (i as u16).to_le_bytes();
        }),
        (Some(s), _) => write_fixed::<4, _, _, _>(w, s, |_, &i, out| *out = i.to_le_bytes()),
        (None, ComponentType::U16) => {
            write_fixed::<6, _, _, _>(w, &mesh.triangles, |_, &t, out| {
                let t = frame.orient(t);
                for (o, i) in out.chunks_exact_mut(2).zip(t) {
                    o.copy_from_slice(&(i as u16).to_le_bytes());
                }
            })
        }
        (None, _) => write_fixed::<12, _, _, _>(w, &mesh.triangles, |_, &t, out| {
            put_u32s(out, &frame.orient(t));
        }),
    }
}
