//! The GLB container and the JSON pieces both GLB layouts share.
//!
//! Container (glTF 2.0 spec, "GLB File Format Specification"): a 12-byte
//! header (magic `glTF`, version 2, total length), a JSON chunk (type `JSON`,
//! padded with spaces to a multiple of 4 bytes) and a BIN chunk (type `BIN\0`,
//! padded with zeros to a multiple of 4), all little-endian.

use std::io::Write;

use gltf_json as json;
use json::accessor::{ComponentType, GenericComponentType, Type};
use json::buffer::Target;
use json::material::{PbrBaseColorFactor, PbrMetallicRoughness, StrengthFactor};
use json::scene::UnitQuaternion;
use json::validation::{Checked, USize64};
use json::{Accessor, Index};

use super::super::coords::GeoInfo;
use super::super::error::ExportError;

/// `glTF` as a little-endian u32.
const MAGIC: u32 = 0x4654_6C67;
/// Container version.
const VERSION: u32 = 2;
/// Chunk type `JSON`.
const CHUNK_JSON: u32 = 0x4E4F_534A;
/// Chunk type `BIN\0`.
const CHUNK_BIN: u32 = 0x004E_4942;
/// Bytes of the file header.
const HEADER_BYTES: u64 = 12;
/// Bytes of a chunk header (length and type).
const CHUNK_HEADER_BYTES: u64 = 8;

/// Writes the GLB: header, `root` as the JSON chunk, then the BIN chunk of
/// `bin_bytes` bytes (before padding) that `bin` writes.
///
/// # Errors
/// [`ExportError::Json`], [`ExportError::TooLarge`] beyond 4 GiB, the errors
/// of `w` and of `bin`.
pub(super) fn write_container<W: Write + ?Sized>(
    w: &mut W,
    root: &json::Root,
    bin_bytes: u64,
    bin: impl FnOnce(&mut W) -> Result<(), ExportError>,
) -> Result<(), ExportError> {
    let json = json::serialize::to_vec(root).map_err(|e| ExportError::Json(e.to_string()))?;
    let json_padded = pad4(json.len() as u64);
    let bin_padded = pad4(bin_bytes);
    let total = HEADER_BYTES + 2 * CHUNK_HEADER_BYTES + json_padded + bin_padded;
    let total = u32::try_from(total).map_err(|_| ExportError::TooLarge {
        what: "bytes in a GLB",
        count: total,
        max: u64::from(u32::MAX),
    })?;
    write_u32s(w, &[MAGIC, VERSION, total])?;
    write_chunk_header(w, json_padded, CHUNK_JSON)?;
    w.write_all(&json)?;
    write_padding(w, json.len() as u64, b' ')?;
    write_chunk_header(w, bin_padded, CHUNK_BIN)?;
    bin(w)?;
    write_padding(w, bin_bytes, 0)?;
    w.flush()?;
    Ok(())
}

/// The asset: generator `cota`, the georeference in `extras`.
pub(super) fn asset(info: &GeoInfo) -> Result<json::Asset, ExportError> {
    let extras = json::extras::RawValue::from_string(info.json().to_string())
        .map_err(|e| ExportError::Json(e.to_string()))?;
    Ok(json::Asset {
        generator: Some("cota".to_string()),
        extras: Some(extras),
        ..json::Asset::default()
    })
}

/// The one buffer (the BIN chunk).
pub(super) fn buffer(bytes: u64) -> json::Buffer {
    json::Buffer {
        byte_length: USize64(bytes),
        uri: None,
        extensions: None,
        extras: None,
    }
}

/// A view of `bytes` bytes at `offset` into the buffer.
pub(super) fn view(
    offset: u64,
    bytes: u64,
    stride: Option<u64>,
    target: Target,
) -> json::buffer::View {
    json::buffer::View {
        buffer: Index::new(0),
        byte_length: USize64(bytes),
        byte_offset: Some(USize64(offset)),
        byte_stride: stride.map(|s| json::buffer::Stride(s as usize)),
        target: Some(Checked::Valid(target)),
        extensions: None,
        extras: None,
    }
}

/// An accessor of `count` elements at the start of buffer view `view`.
pub(super) fn accessor(view: u32, count: u64, component: ComponentType, ty: Type) -> Accessor {
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
pub(super) trait WithBounds {
    /// The accessor with `min` and `max` set.
    fn with_bounds(self, min: serde_json::Value, max: serde_json::Value) -> Self;
}

impl WithBounds for Accessor {
    fn with_bounds(mut self, min: serde_json::Value, max: serde_json::Value) -> Self {
        self.min = Some(min);
        self.max = Some(max);
        self
    }
}

/// The rotation of −90° about x that turns the data's z-up frame into
/// glTF's y-up one: (x, y, z) ↦ (x, z, −y).
pub(super) fn z_up_to_y_up() -> UnitQuaternion {
    let half_turn = std::f32::consts::FRAC_1_SQRT_2;
    UnitQuaternion([-half_turn, 0.0, 0.0, half_turn])
}

/// Light grey, non-metallic, fully rough: reads as terrain under any light
/// (glTF's default material is fully metallic, which renders dark).
pub(super) fn terrain_material() -> json::Material {
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
pub(super) fn pad4(n: u64) -> u64 {
    n.div_ceil(4) * 4
}

/// Little-endian u32s.
fn write_u32s<W: Write + ?Sized>(w: &mut W, v: &[u32]) -> Result<(), ExportError> {
    for x in v {
        w.write_all(&x.to_le_bytes())?;
    }
    Ok(())
}

/// A chunk header: padded length and type. The length fits: the total was checked.
fn write_chunk_header<W: Write + ?Sized>(
    w: &mut W,
    length: u64,
    ty: u32,
) -> Result<(), ExportError> {
    write_u32s(w, &[length as u32, ty])
}

/// The bytes that pad `len` to a multiple of 4.
pub(super) fn write_padding<W: Write + ?Sized>(
    w: &mut W,
    len: u64,
    byte: u8,
) -> Result<(), ExportError> {
    let n = (pad4(len) - len) as usize;
    w.write_all(&[byte; 3][..n])?;
    Ok(())
}

/// A document's one mesh: one primitive (indices accessor 2, material 0,
/// the given attributes and mode) on one node turned from Z-up to glTF's
/// Y-up, in one scene; the callers fill in buffers, accessors, materials.
pub(super) fn single_mesh_root(
    attributes: std::collections::BTreeMap<Checked<json::mesh::Semantic>, Index<Accessor>>,
    mode: json::mesh::Mode,
) -> json::Root {
    json::Root {
        meshes: vec![json::Mesh {
            extensions: None,
            extras: None,
            primitives: vec![json::mesh::Primitive {
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
            rotation: Some(z_up_to_y_up()),
            ..json::Node::default()
        }],
        scenes: vec![json::Scene {
            extensions: None,
            extras: None,
            nodes: vec![Index::new(0)],
        }],
        scene: Some(Index::new(0)),
        ..json::Root::default()
    }
}
