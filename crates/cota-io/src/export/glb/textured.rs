//! The textured GLB: a mesh with an image draped on it (paper
//! `004_ab8d08b3e6a5a70a.txt`'s pair of a mesh and a texture).
//!
//! Content: one scene, one node (z up turned to glTF's y up, as the plain
//! layout), one mesh with one TRIANGLES primitive, one material with
//! `KHR_materials_unlit` (the photograph's colours are shown as they are,
//! with no lighting) whose base colour texture is the image, embedded as a
//! PNG in the BIN chunk (one image, one texture, one sampler: linear
//! filtering, no mipmaps, clamped to the edge). The BIN chunk holds, each on
//! a 4-byte boundary:
//! 1. POSITION: f32 VEC3 in the chosen [`Coords`](super::super::Coords)
//!    frame, with `min`/`max`;
//! 2. TEXCOORD_0: f32 VEC2, `u = col/(W−1)`, `v = row/(H−1)`
//!    (`cota_core::texture::uv`): each vertex on the texel of its ground
//!    position in the texture raster that spans the DEM's samples;
//! 3. indices: u16 when the mesh has at most 65 535 vertices, else u32;
//! 4. the PNG.
//!
//! No normals (an unlit material needs none). The byte model of the pair
//! choice follows this layout exactly: `C(M)` = [`textured_mesh_bytes`]
//! (views 1–3, padded), `C(T)` = the PNG's length padded to 4, and the file
//! is `C(M) + C(T)` plus the frame (the 12-byte header, two 8-byte chunk
//! headers and the JSON padded to 4), which [`write_glb_textured`] returns.

use std::collections::BTreeMap;
use std::io::Write;

use cota_core::{HeightGrid, Mesh};
use gltf_json as json;
use json::accessor::{ComponentType, Type};
use json::buffer::Target;
use json::mesh::{Mode, Semantic};
use json::texture::{MagFilter, MinFilter, WrappingMode};
use json::validation::Checked;
use json::Index;
use rayon::prelude::*;

use super::super::coords::{Frame, GeoInfo};
use super::super::error::ExportError;
use super::super::geometry::{check_mesh, push_f32s, to_f32};
use super::super::options::ExportOptions;
use super::super::par::write_chunks;
use super::container::{
    accessor, asset, buffer, pad4, single_mesh_root, view, write_container, WithBounds,
};
use super::{bounds, index_type};

/// `C(M)`: the bytes `mesh` takes in a textured GLB's BIN chunk (positions
/// 12 and texture coordinates 8 per vertex, indices 2 or 4 per corner,
/// padded to 4).
pub fn textured_mesh_bytes(vertices: usize, triangles: usize) -> u64 {
    let index = if vertices <= super::MAX_U16_VERTICES {
        2
    } else {
        4
    };
    20 * vertices as u64 + pad4(3 * triangles as u64 * index)
}

/// Byte offsets of the BIN chunk's views.
struct Layout {
    vertices: u64,
    indices: u64,
    index: ComponentType,
    uv_at: u64,
    index_at: u64,
    index_bytes: u64,
    png_at: u64,
    png_bytes: u64,
}

impl Layout {
    fn new(mesh: &Mesh, png: &[u8], index: ComponentType) -> Self {
        let v = mesh.vertices.len() as u64;
        let indices = 3 * mesh.triangles.len() as u64;
        let index_bytes = indices * index.size() as u64;
        let png_at = 20 * v + pad4(index_bytes);
        Layout {
            vertices: v,
            indices,
            index,
            uv_at: 12 * v,
            index_at: 20 * v,
            index_bytes,
            png_at,
            png_bytes: png.len() as u64,
        }
    }
}

/// Writes `mesh` over `grid` as a textured GLB with `png` (an encoded PNG
/// of the texture raster, see the module docs) to `w`; returns the bytes
/// written.
///
/// # Errors
/// [`ExportError::Io`] from `w`; the mesh checks; [`ExportError::TooLarge`]
/// beyond 4 GiB or 2^32 vertices; [`ExportError::Json`].
pub fn write_glb_textured<W: Write + Send>(
    mut w: W,
    mesh: &Mesh,
    grid: &HeightGrid,
    png: &[u8],
    opts: &ExportOptions,
) -> Result<u64, ExportError> {
    super::super::par::on_pool(|| {
        check_mesh(mesh)?;
        let frame = Frame::new(grid, opts.coords);
        let positions: Vec<[f32; 3]> = mesh
            .vertices
            .par_iter()
            .map(|v| to_f32(frame.vertex(v)))
            .collect();
        let uvs: Vec<[f32; 2]> = mesh
            .vertices
            .par_iter()
            .map(|v| {
                cota_core::texture::uv(grid, f64::from(v.col), f64::from(v.row)).map(|x| x as f32)
            })
            .collect();
        let layout = Layout::new(
            mesh,
            png,
            index_type(mesh.vertices.len(), Default::default())?,
        );
        let root = build_root(&positions, &layout, &GeoInfo::new(grid, opts.coords))?;
        let mut counted = Counted {
            inner: &mut w,
            bytes: 0,
        };
        write_container(&mut counted, &root, layout.png_at + layout.png_bytes, |w| {
            write_chunks(w, &positions, 12, |_, c, buf| {
                push_f32s(buf, c.as_flattened());
                Ok(())
            })?;
            write_chunks(w, &uvs, 8, |_, c, buf| {
                push_f32s(buf, c.as_flattened());
                Ok(())
            })?;
            write_chunks(w, &mesh.triangles, 12, |_, chunk, buf| {
                for &t in chunk {
                    for i in frame.orient(t) {
                        match layout.index {
                            // Fits: index_type allowed u16 only up to 65 535 vertices.
                            ComponentType::U16 => buf.extend_from_slice(&(i as u16).to_le_bytes()),
                            _ => buf.extend_from_slice(&i.to_le_bytes()),
                        }
                    }
                }
                Ok(())
            })?;
            let pad = (pad4(layout.index_bytes) - layout.index_bytes) as usize;
            w.write_all(&[0u8; 3][..pad])?;
            w.write_all(png)?;
            Ok(())
        })?;
        Ok(counted.bytes)
    })
}

/// A writer that counts what passes through it.
struct Counted<'w, W: Write> {
    inner: &'w mut W,
    bytes: u64,
}

impl<W: Write> Write for Counted<'_, W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.bytes += n as u64;
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// The unlit, textured material.
fn material() -> json::Material {
    let mut m = json::Material::default();
    m.pbr_metallic_roughness.base_color_texture = Some(json::texture::Info {
        index: Index::new(0),
        tex_coord: 0,
        extensions: None,
        extras: None,
    });
    m.pbr_metallic_roughness.metallic_factor = json::material::StrengthFactor(0.0);
    m.pbr_metallic_roughness.roughness_factor = json::material::StrengthFactor(1.0);
    m.extensions = Some(json::extensions::material::Material {
        unlit: Some(json::extensions::material::Unlit {}),
    });
    m
}

/// The image, its texture and sampler.
fn image_parts() -> (json::Image, json::Texture, json::texture::Sampler) {
    let image = json::Image {
        buffer_view: Some(Index::new(3)),
        mime_type: Some(json::image::MimeType("image/png".to_string())),
        uri: None,
        extensions: None,
        extras: None,
    };
    let texture = json::Texture {
        sampler: Some(Index::new(0)),
        source: Index::new(0),
        extensions: None,
        extras: None,
    };
    let sampler = json::texture::Sampler {
        mag_filter: Some(Checked::Valid(MagFilter::Linear)),
        min_filter: Some(Checked::Valid(MinFilter::Linear)),
        wrap_s: Checked::Valid(WrappingMode::ClampToEdge),
        wrap_t: Checked::Valid(WrappingMode::ClampToEdge),
        extensions: None,
        extras: None,
    };
    (image, texture, sampler)
}

/// The glTF JSON document.
fn build_root(
    positions: &[[f32; 3]],
    l: &Layout,
    info: &GeoInfo,
) -> Result<json::Root, ExportError> {
    let (min, max) = bounds(positions, |p| *p);
    let mut attributes = BTreeMap::new();
    attributes.insert(Checked::Valid(Semantic::Positions), Index::new(0));
    attributes.insert(Checked::Valid(Semantic::TexCoords(0)), Index::new(1));
    let (image, texture, sampler) = image_parts();
    let mut png_view = view(l.png_at, l.png_bytes, None, Target::ArrayBuffer);
    png_view.target = None;
    Ok(json::Root {
        asset: asset(info)?,
        buffers: vec![buffer(l.png_at + l.png_bytes)],
        buffer_views: vec![
            view(0, 12 * l.vertices, None, Target::ArrayBuffer),
            view(l.uv_at, 8 * l.vertices, None, Target::ArrayBuffer),
            view(l.index_at, l.index_bytes, None, Target::ElementArrayBuffer),
            png_view,
        ],
        accessors: vec![
            accessor(0, l.vertices, ComponentType::F32, Type::Vec3)
                .with_bounds(serde_json::json!(min), serde_json::json!(max)),
            accessor(1, l.vertices, ComponentType::F32, Type::Vec2),
            accessor(2, l.indices, l.index, Type::Scalar),
        ],
        materials: vec![material()],
        images: vec![image],
        textures: vec![texture],
        samplers: vec![sampler],
        extensions_used: vec!["KHR_materials_unlit".to_string()],
        ..single_mesh_root(attributes, Mode::Triangles)
    })
}

/// Encodes `image` as an 8-bit RGB PNG (default compression, adaptive
/// filters): the texture of a textured GLB.
///
/// # Errors
/// [`ExportError::Io`] when the encoder fails.
pub fn encode_png(image: &cota_core::texture::RgbImage) -> Result<Vec<u8>, ExportError> {
    let mut out = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut out, image.width() as u32, image.height() as u32);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.set_filter(png::Filter::Adaptive);
        let mut wr = enc.write_header().map_err(png_error)?;
        wr.write_image_data(image.as_bytes()).map_err(png_error)?;
        wr.finish().map_err(png_error)?;
    }
    Ok(out)
}

fn png_error(e: png::EncodingError) -> ExportError {
    ExportError::Io(std::io::Error::other(e.to_string()))
}
