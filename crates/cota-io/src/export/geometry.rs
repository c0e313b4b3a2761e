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

use cota_core::Mesh;
use rayon::prelude::*;

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
    // The common case first, in parallel and vectorisable: the largest index
    // and whether every height is finite. Only a failing mesh is searched for
    // its first offender.
    let count = mesh.vertices.len();
    let largest = mesh
        .triangles
        .par_chunks(CHECK_CHUNK)
        .map(|c| c.as_flattened().iter().copied().max().unwrap_or(0))
        .max()
        .unwrap_or(0);
    if largest as usize >= count {
        let (triangle, index) = mesh
            .triangles
            .iter()
            .enumerate()
            .find_map(|(k, t)| t.iter().find(|&&i| i as usize >= count).map(|&i| (k, i)))
            .unwrap_or((0, largest));
        return Err(ExportError::VertexOutOfRange {
            triangle,
            index,
            count,
        });
    }
    let finite = mesh
        .vertices
        .par_chunks(CHECK_CHUNK)
        .all(|c| c.iter().fold(true, |ok, v| ok & v.z_m.is_finite()));
    if !finite {
        if let Some((vertex, v)) = mesh
            .vertices
            .iter()
            .enumerate()
            .find(|(_, v)| !v.z_m.is_finite())
        {
            return Err(ExportError::NonFiniteHeight { vertex, z_m: v.z_m });
        }
    }
    Ok(())
}

/// Records per parallel task of [`check_mesh`].
const CHECK_CHUNK: usize = 1 << 16;

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
    let mut out = vec![[0.0f32; 3]; mesh.vertices.len()];
    for_each_normal_sum(mesh, frame, &mut out, |s| {
        normalize(s).map_or([0.0, 0.0, 1.0], to_f32)
    });
    out
}

/// Sets `out[v] = finish(sum)` for every vertex `v`, where `sum` is the sum of
/// the face normals of the triangles that use `v` (once per corner), added in
/// triangle order. `out` has one entry per vertex.
///
/// In parallel and bit-identical to the sequential loop: the vertices are cut
/// into a few contiguous parts per thread, and each part walks the triangles
/// in order, adding the face normals of those with a corner in its range, so
/// each vertex sees the same additions in the same order (f64 addition does
/// not commute bit for bit). The triangles are first bounded by runs of
/// [`RUN`] (the least and greatest vertex index of each run, one parallel
/// pass), so that a part skips the runs that miss its range and walks those
/// inside it without a test per corner: cota's meshes are numbered row by
/// row and their triangles come in spatial order, so almost every run lies
/// in one part, and each face normal is computed about once.
pub(crate) fn for_each_normal_sum<T, F>(mesh: &Mesh, frame: &Frame, out: &mut [T], finish: F)
where
    T: Send,
    F: Fn([f64; 3]) -> T + Sync,
{
    let runs = run_bounds(&mesh.triangles);
    let parts = (PARTS_PER_THREAD * rayon::current_num_threads()).clamp(1, 256);
    let per_part = out.len().div_ceil(parts).max(MIN_VERTICES_PER_PART);
    out.par_chunks_mut(per_part)
        .enumerate()
        .for_each(|(k, out)| {
            let mut sum = vec![[0.0f64; 3]; out.len()];
            part_sums(mesh, frame, &runs, k * per_part, &mut sum);
            for (o, s) in out.iter_mut().zip(sum) {
                *o = finish(s);
            }
        });
}

/// Adds into `sum` (the vertices `v0..v0 + sum.len()`) the face normals of
/// the triangles with a corner there, in triangle order.
fn part_sums(mesh: &Mesh, frame: &Frame, runs: &[(u32, u32)], v0: usize, sum: &mut [[f64; 3]]) {
    let (lo, hi) = (v0 as u64, (v0 + sum.len()) as u64);
    let mut add = |i: u32, n: [f64; 3]| {
        if let Some(s) = (i as usize).checked_sub(v0).and_then(|j| sum.get_mut(j)) {
            s[0] += n[0];
            s[1] += n[1];
            s[2] += n[2];
        }
    };
    for (r, &(a, b)) in runs.iter().enumerate() {
        let (a, b) = (u64::from(a), u64::from(b));
        if b < lo || a >= hi {
            continue;
        }
        let inside = a >= lo && b < hi;
        let end = ((r + 1) * RUN).min(mesh.triangles.len());
        for &t in &mesh.triangles[r * RUN..end] {
            if !inside && !t.iter().any(|&i| (lo..hi).contains(&u64::from(i))) {
                continue;
            }
            let t = frame.orient(t);
            let n = face_normal(triangle_points(mesh, frame, t));
            for i in t {
                add(i, n);
            }
        }
    }
}

/// Triangles per run of [`run_bounds`].
const RUN: usize = 256;

/// The least and greatest vertex index of each run of [`RUN`] triangles
/// (`(u32::MAX, 0)` for none).
fn run_bounds(triangles: &[[u32; 3]]) -> Vec<(u32, u32)> {
    triangles
        .par_chunks(RUN)
        .map(|run| {
            run.iter().fold((u32::MAX, 0), |(lo, hi), t| {
                (
                    lo.min(t[0].min(t[1]).min(t[2])),
                    hi.max(t[0].max(t[1]).max(t[2])),
                )
            })
        })
        .collect()
}

/// Vertex parts per thread in [`for_each_normal_sum`]: work for a thread
/// that finishes early, few enough that runs across parts stay rare.
const PARTS_PER_THREAD: usize = 4;

/// Fewest vertices worth a part of their own in [`for_each_normal_sum`].
const MIN_VERTICES_PER_PART: usize = 1 << 15;

/// Appends little-endian f32s to `buf`.
#[inline]
pub(crate) fn push_f32s(buf: &mut Vec<u8>, v: &[f32]) {
    for x in v {
        buf.extend_from_slice(&x.to_le_bytes());
    }
}
