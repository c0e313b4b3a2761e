//! Mesh checks and normals shared by the writers.
//!
//! # Normals
//! * Face normal: `(b − a) × (c − a)` of the triangle as written (after
//!   [`Frame::orient`]), computed in the output frame, so it points up (+z) for
//!   terrain in either coordinate mode. Its length is twice the triangle's area.
//! * Vertex normal: the sum of the face normals of the triangles that use the
//!   vertex — the area-weighted average of the adjacent face normals —
//!   normalised to unit length. Computed in f64 in the output frame (so a grid
//!   with dx ≠ dy gets the normals of its true shape in local metres, and those
//!   of the stretched shape in grid units). A vertex that no triangle uses, or
//!   whose faces cancel out, gets (0, 0, 1).

use std::io::Write;

use cota_core::Mesh;

use super::coords::Frame;
use super::error::ExportError;

/// Checks that the writers can encode `mesh`: at least one triangle, every
/// index in range, every height finite.
///
/// # Errors
/// [`ExportError::EmptyMesh`], [`ExportError::VertexOutOfRange`] or
/// [`ExportError::NonFiniteHeight`].
pub(crate) fn check_mesh(mesh: &Mesh) -> Result<(), ExportError> {
    if mesh.triangles.is_empty() {
        return Err(ExportError::EmptyMesh);
    }
    let count = mesh.vertices.len();
    for (triangle, t) in mesh.triangles.iter().enumerate() {
        if let Some(&index) = t.iter().find(|&&i| i as usize >= count) {
            return Err(ExportError::VertexOutOfRange {
                triangle,
                index,
                count,
            });
        }
    }
    if let Some((vertex, v)) = mesh
        .vertices
        .iter()
        .enumerate()
        .find(|(_, v)| !v.z_m.is_finite())
    {
        return Err(ExportError::NonFiniteHeight { vertex, z_m: v.z_m });
    }
    Ok(())
}

/// `(b − a) × (c − a)`: normal of the counter-clockwise triangle `a b c`,
/// of length twice its area.
#[inline]
pub(crate) fn face_normal(p: [[f64; 3]; 3]) -> [f64; 3] {
    let u = sub(p[1], p[0]);
    let v = sub(p[2], p[0]);
    [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ]
}

/// `a − b`.
#[inline]
fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `v` scaled to unit length, or `None` when it has no direction.
#[inline]
pub(crate) fn normalize(v: [f64; 3]) -> Option<[f64; 3]> {
    let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    (len > 0.0 && len.is_finite()).then(|| [v[0] / len, v[1] / len, v[2] / len])
}

/// Unit face normal in f32, or zero for a degenerate triangle (the STL convention).
pub(crate) fn unit_face_normal_f32(p: [[f64; 3]; 3]) -> [f32; 3] {
    normalize(face_normal(p)).map_or([0.0; 3], to_f32)
}

/// Converts a vector to f32.
#[inline]
pub(crate) fn to_f32(v: [f64; 3]) -> [f32; 3] {
    [v[0] as f32, v[1] as f32, v[2] as f32]
}

/// Output positions of the triangle `t` (indices already oriented).
#[inline]
pub(crate) fn triangle_points(mesh: &Mesh, frame: &Frame, t: [u32; 3]) -> [[f64; 3]; 3] {
    t.map(|i| frame.vertex(&mesh.vertices[i as usize]))
}

/// Area-weighted unit vertex normals of `mesh` in `frame` (see the module doc).
/// Call [`check_mesh`] first: indices must be in range.
pub(crate) fn vertex_normals(mesh: &Mesh, frame: &Frame) -> Vec<[f32; 3]> {
    let mut sum = vec![[0.0f64; 3]; mesh.vertices.len()];
    for &t in &mesh.triangles {
        let t = frame.orient(t);
        let n = face_normal(triangle_points(mesh, frame, t));
        for i in t {
            let s = &mut sum[i as usize];
            s[0] += n[0];
            s[1] += n[1];
            s[2] += n[2];
        }
    }
    sum.into_iter()
        .map(|s| normalize(s).map_or([0.0, 0.0, 1.0], to_f32))
        .collect()
}

/// Little-endian f32s.
#[inline]
pub(crate) fn write_f32s<W: Write>(w: &mut W, v: &[f32]) -> Result<(), ExportError> {
    let mut buf = [0u8; 12];
    for chunk in v.chunks(3) {
        let n = 4 * chunk.len();
        for (k, x) in chunk.iter().enumerate() {
            buf[4 * k..4 * k + 4].copy_from_slice(&x.to_le_bytes());
        }
        w.write_all(&buf[..n])?;
    }
    Ok(())
}
