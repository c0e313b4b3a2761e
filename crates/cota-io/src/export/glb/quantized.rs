//! The quantized GLB layout (`KHR_mesh_quantization`, required): what
//! [`GlbQuantization`] plans, as glTF.
//!
//! * One node per primitive, each the child of a root node that carries the
//!   z-up-to-y-up rotation (as in the float layout). A primitive's node has
//!   the translation and (non-uniform) scale that map its integer positions
//!   to the output frame, z up; each node has its own mesh of one primitive,
//!   mode TRIANGLES, the shared terrain material.
//! * The BIN chunk has three buffer views, one per attribute kind, each
//!   primitive's accessor at its own offset:
//!   1. POSITION: `u16` VEC3 (X, Y, height code), byte stride 8 (glTF aligns
//!      vertex attributes to 4 bytes), with the accessor `min`/`max`;
//!   2. NORMAL: normalised `i8` VEC3, byte stride 4;
//!   3. indices: `u16` SCALAR, three per triangle, counter-clockwise seen from
//!      the front, local to the primitive.
//!
//! Sizes: 12 bytes per written vertex and 6 per triangle, against 24 and 6
//! or 12 in the float layout.

use std::collections::BTreeMap;
use std::io::Write;

use cota_core::{HeightGrid, Mesh};
use gltf_json as json;
use json::accessor::{ComponentType, GenericComponentType, Type};
use json::buffer::Target;
use json::mesh::{Mode, Primitive, Semantic};
use json::validation::{Checked, USize64};
use json::{Accessor, Index};
use rayon::prelude::*;

use super::container::{
    asset, buffer, terrain_material, view, write_container, z_up_to_y_up, WithBounds,
};
use crate::export::coords::GeoInfo;
use crate::export::error::ExportError;
use crate::export::options::ExportOptions;
use crate::export::par::write_chunks_of;
use crate::export::quantize::{GlbQuantization, Part};

/// The extension's name.
const EXTENSION: &str = "KHR_mesh_quantization";

/// Bytes of a stored position (three u16 and two bytes of padding).
const POSITION_BYTES: u64 = 8;
/// Bytes of a stored normal (three i8 and one byte of padding).
const NORMAL_BYTES: u64 = 4;
/// Bytes of a triangle's indices.
const TRIANGLE_BYTES: u64 = 6;

/// Writes the quantized GLB of `mesh` planned by `q`. The mesh has been
/// checked.
pub(super) fn write_quantized<W: Write + Send + ?Sized>(
    w: &mut W,
    mesh: &Mesh,
    grid: &HeightGrid,
    opts: &ExportOptions,
    q: &GlbQuantization,
) -> Result<(), ExportError> {
    let layout = Layout::new(&q.parts);
    let root = build_root(mesh, q, &layout, &GeoInfo::new(grid, opts.coords))?;
    let normals = &q.normals;
    write_container(w, &root, layout.bytes(), |w| {
        write_chunks_of(w, &q.parts, 1, 1 << 18, |_, parts, buf| {
            parts.iter().for_each(|p| push_positions(buf, mesh, q, p));
            Ok(())
        })?;
        write_chunks_of(w, &q.parts, 1, 1 << 17, |_, parts, buf| {
            parts.iter().for_each(|p| push_normals(buf, normals, q, p));
            Ok(())
        })?;
        write_chunks_of(w, &q.parts, 1, 1 << 18, |_, parts, buf| {
            for p in parts {
                p.indices
                    .iter()
                    .for_each(|i| buf.extend_from_slice(&i.to_le_bytes()));
            }
            Ok(())
        })
    })
}

/// Where each part's data sits in the three views.
struct Layout {
    /// Vertices written before each part, and in all.
    vertices_before: Vec<u64>,
    /// Triangles written before each part, and in all.
    triangles_before: Vec<u64>,
}

impl Layout {
    fn new(parts: &[Part]) -> Self {
        let prefix = |f: &dyn Fn(&Part) -> u64| {
            let mut acc = 0;
            let mut v: Vec<u64> = parts
                .iter()
                .map(|p| {
                    let a = acc;
                    acc += f(p);
                    a
                })
                .collect();
            v.push(acc);
            v
        };
        Layout {
            vertices_before: prefix(&|p| p.vertices.len() as u64),
            triangles_before: prefix(&|p| p.triangles as u64),
        }
    }

    fn vertices(&self) -> u64 {
        self.vertices_before.last().copied().unwrap_or(0)
    }

    fn triangles(&self) -> u64 {
        self.triangles_before.last().copied().unwrap_or(0)
    }

    /// Bytes of the positions, normals and indices views.
    fn view_bytes(&self) -> [u64; 3] {
        [
            POSITION_BYTES * self.vertices(),
            NORMAL_BYTES * self.vertices(),
            TRIANGLE_BYTES * self.triangles(),
        ]
    }

    /// Bytes of the buffer.
    fn bytes(&self) -> u64 {
        self.view_bytes().iter().sum()
    }
}

/// The glTF JSON document.
fn build_root(
    mesh: &Mesh,
    q: &GlbQuantization,
    layout: &Layout,
    info: &GeoInfo,
) -> Result<json::Root, ExportError> {
    let [pos, nrm, idx] = layout.view_bytes();
    let mut root = json::Root {
        asset: asset(info)?,
        buffers: vec![buffer(layout.bytes())],
        buffer_views: vec![
            view(0, pos, Some(POSITION_BYTES), Target::ArrayBuffer),
            view(pos, nrm, Some(NORMAL_BYTES), Target::ArrayBuffer),
            view(pos + nrm, idx, None, Target::ElementArrayBuffer),
        ],
        materials: vec![terrain_material()],
        extensions_used: vec![EXTENSION.to_string()],
        extensions_required: vec![EXTENSION.to_string()],
        scene: Some(Index::new(0)),
        scenes: vec![json::Scene {
            extensions: None,
            extras: None,
            nodes: vec![Index::new(0)],
        }],
        ..json::Root::default()
    };
    root.nodes.push(json::Node {
        rotation: Some(z_up_to_y_up()),
        children: Some((1..=q.parts.len() as u32).map(Index::new).collect()),
        ..json::Node::default()
    });
    let bounds: Vec<_> = q
        .parts
        .par_iter()
        .map(|p| stored_bounds(mesh, q, p))
        .collect();
    for (k, (p, (min, max))) in q.parts.iter().zip(bounds).enumerate() {
        let first = 3 * k as u32;
        let v0 = layout.vertices_before[k];
        root.accessors.push(
            at(0, POSITION_BYTES * v0, p.vertices.len(), ComponentType::U16)
                .with_bounds(serde_json::json!(min), serde_json::json!(max)),
        );
        let mut normal = at(1, NORMAL_BYTES * v0, p.vertices.len(), ComponentType::I8);
        normal.normalized = true;
        root.accessors.push(normal);
        let t0 = layout.triangles_before[k];
        let mut index = at(2, TRIANGLE_BYTES * t0, 3 * p.triangles, ComponentType::U16);
        index.type_ = Checked::Valid(Type::Scalar);
        root.accessors.push(index);
        root.meshes.push(primitive_mesh(first));
        root.nodes.push(part_node(q, p, k as u32));
    }
    Ok(root)
}

/// A VEC3 accessor of `count` elements at `offset` bytes into view `view`.
fn at(view: u32, offset: u64, count: usize, component: ComponentType) -> Accessor {
    Accessor {
        buffer_view: Some(Index::new(view)),
        byte_offset: Some(USize64(offset)),
        count: USize64(count as u64),
        component_type: Checked::Valid(GenericComponentType(component)),
        extensions: None,
        extras: None,
        type_: Checked::Valid(Type::Vec3),
        min: None,
        max: None,
        normalized: false,
        sparse: None,
    }
}

/// A mesh of one primitive whose accessors start at `first` (POSITION,
/// NORMAL, indices).
fn primitive_mesh(first: u32) -> json::Mesh {
    let mut attributes = BTreeMap::new();
    attributes.insert(Checked::Valid(Semantic::Positions), Index::new(first));
    attributes.insert(Checked::Valid(Semantic::Normals), Index::new(first + 1));
    json::Mesh {
        extensions: None,
        extras: None,
        primitives: vec![Primitive {
            attributes,
            extensions: None,
            extras: None,
            indices: Some(Index::new(first + 2)),
            material: Some(Index::new(0)),
            mode: Checked::Valid(Mode::Triangles),
            targets: None,
        }],
        weights: None,
    }
}

/// The node of part `p` (mesh `k`): the translation and scale from its
/// stored integers to the output frame, z up.
fn part_node(q: &GlbQuantization, p: &Part, k: u32) -> json::Node {
    let scale = node_scale(q, p);
    let (ax, ay) = q.axes;
    let translation = [
        ax[0] * f64::from(p.origin[0]) + ax[1],
        ay[0] * f64::from(p.origin[1]) + ay[1],
        q.z_base_m,
    ];
    json::Node {
        mesh: Some(Index::new(k)),
        translation: Some(translation.map(|x| x as f32)),
        scale: Some(scale.map(|x| x as f32)),
        ..json::Node::default()
    }
}

/// The output-frame length of one stored unit along each axis of part `p`.
fn node_scale(q: &GlbQuantization, p: &Part) -> [f64; 3] {
    let (ax, ay) = q.axes;
    [
        ax[0].abs() / f64::from(p.k[0]),
        ay[0].abs() / f64::from(p.k[1]),
        q.z_step_m,
    ]
}

/// The stored position of vertex `i` in part `p`.
#[inline]
fn stored(mesh: &Mesh, q: &GlbQuantization, p: &Part, i: u32) -> [u16; 3] {
    let v = mesh.vertices[i as usize];
    let along = |x: u32, origin: u32, ascending: bool, k: u32| {
        let d = if ascending { x - origin } else { origin - x };
        // Fits: the span times k is at most 65 535 (quantize::placement).
        (d * k) as u16
    };
    [
        along(v.col, p.origin[0], p.ascending[0], p.k[0]),
        along(v.row, p.origin[1], p.ascending[1], p.k[1]),
        q.quantize(v.z_m),
    ]
}

/// Component-wise minimum and maximum of part `p`'s stored positions.
fn stored_bounds(mesh: &Mesh, q: &GlbQuantization, p: &Part) -> ([u16; 3], [u16; 3]) {
    p.vertices
        .iter()
        .fold(([u16::MAX; 3], [0; 3]), |(lo, hi), &i| {
            let s = stored(mesh, q, p, i);
            (
                [lo[0].min(s[0]), lo[1].min(s[1]), lo[2].min(s[2])],
                [hi[0].max(s[0]), hi[1].max(s[1]), hi[2].max(s[2])],
            )
        })
}

/// Appends part `p`'s positions (8 bytes each).
fn push_positions(buf: &mut Vec<u8>, mesh: &Mesh, q: &GlbQuantization, p: &Part) {
    for &i in &p.vertices {
        for x in stored(mesh, q, p, i) {
            buf.extend_from_slice(&x.to_le_bytes());
        }
        buf.extend_from_slice(&[0, 0]);
    }
}

/// Appends part `p`'s normals (4 bytes each), encoded for its node's scale.
fn push_normals(buf: &mut Vec<u8>, normals: &[[f32; 3]], q: &GlbQuantization, p: &Part) {
    let scale = node_scale(q, p);
    let start = buf.len();
    buf.resize(start + 4 * p.vertices.len(), 0);
    buf[start..]
        .par_chunks_mut(4)
        .zip(p.vertices.par_iter())
        .for_each(|(out, &i)| {
            let [x, y, z] = encode_normal(normals[i as usize], scale);
            out[..3].copy_from_slice(&[x as u8, y as u8, z as u8]);
        });
}

/// Largest departure from unit length the Khronos validator accepts for a
/// decoded normal (its `ACCESSOR_VECTOR3_NON_UNIT` check allows 0.00674),
/// with a margin.
const UNIT_TOLERANCE: f64 = 0.006;

/// The normalised byte triple stored for the unit normal `n` (output frame)
/// under a node of scale `scale`: among the byte triples near `127·S·n`
/// (renormalised) whose length is within [`UNIT_TOLERANCE`] of 127, the one
/// whose decoded direction `S⁻¹·c` is closest to `n`. The eight roundings
/// are tried first (almost always enough), then the 27 and 125 triples
/// around the nearest.
pub(crate) fn encode_normal(n: [f32; 3], scale: [f64; 3]) -> [i8; 3] {
    let n = n.map(f64::from);
    let s = [n[0] * scale[0], n[1] * scale[1], n[2] * scale[2]];
    let len = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
    if !(len > 0.0 && len.is_finite()) {
        return [0, 0, 127];
    }
    let t = s.map(|c| 127.0 * c / len);
    let floor = t.map(|x| x.floor().clamp(-127.0, 126.0));
    // Each corner picks floor or floor + 1 per axis: its squared length, its
    // decoded direction's dot with n and squared length are sums of one term
    // per axis, two choices each.
    let terms: [[[f64; 3]; 2]; 3] = std::array::from_fn(|a| {
        std::array::from_fn(|up| {
            let c = floor[a] + up as f64;
            let d = c / scale[a];
            [c * c, d * n[a], d * d]
        })
    });
    let (lo, hi) = unit_band();
    let mut best: Option<(u32, f64)> = None;
    for k in 0..8u32 {
        let pick = |a: usize| terms[a][(k >> a & 1) as usize];
        let (x, y, z) = (pick(0), pick(1), pick(2));
        let len2 = x[0] + y[0] + z[0];
        if !(lo..=hi).contains(&len2) {
            continue;
        }
        let cos = (x[1] + y[1] + z[1]) / (x[2] + y[2] + z[2]).sqrt();
        if best.is_none_or(|(_, b)| cos > b) {
            best = Some((k, cos));
        }
    }
    match best {
        Some((k, _)) => std::array::from_fn(|a| (floor[a] + f64::from(k >> a & 1)) as i8),
        None => encode_normal_wide(n, scale, t),
    }
}

/// The band of squared lengths (in byte units) the validator takes for unit.
fn unit_band() -> (f64, f64) {
    let (lo, hi) = (
        127.0 * (1.0 - UNIT_TOLERANCE),
        127.0 * (1.0 + UNIT_TOLERANCE),
    );
    (lo * lo, hi * hi)
}

/// [`encode_normal`] when no rounding of `t` (= `127·S·n` renormalised) has
/// unit length: the 27, then 125 triples around its nearest.
fn encode_normal_wide(n: [f64; 3], scale: [f64; 3], t: [f64; 3]) -> [i8; 3] {
    let (lo, hi) = unit_band();
    for r in [1i32, 2] {
        let w = 2 * r + 1;
        let mut best: Option<([i8; 3], f64)> = None;
        for k in 0..w * w * w {
            let off = [k % w - r, k / w % w - r, k / (w * w) - r];
            let c: [f64; 3] =
                std::array::from_fn(|a| (t[a].round() + f64::from(off[a])).clamp(-127.0, 127.0));
            let len2 = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
            if !(lo..=hi).contains(&len2) {
                continue;
            }
            let d = [c[0] / scale[0], c[1] / scale[1], c[2] / scale[2]];
            let cos = (d[0] * n[0] + d[1] * n[1] + d[2] * n[2])
                / (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            if best.is_none_or(|(_, b)| cos > b) {
                best = Some((c.map(|x| x as i8), cos));
            }
        }
        if let Some((c, _)) = best {
            return c;
        }
    }
    t.map(|x| x.round().clamp(-127.0, 127.0) as i8)
}
