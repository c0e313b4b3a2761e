//! Binary STL writer, optionally closing the terrain into a printable solid.
//!
//! Binary STL: an 80-byte header (here a short ASCII note with the coordinate
//! mode, CRS and the CRS coordinates of the south-west sample, zero-padded,
//! never starting with `solid`, which readers take for ASCII STL), a
//! little-endian u32 triangle count, then 50 bytes per triangle: the facet
//! normal and the three vertices as little-endian f32 triples, and a u16
//! attribute byte count of 0. Vertices are counter-clockwise seen from
//! outside and the facet normal is the unit right-hand normal of the written
//! (f64) vertices — zero for a degenerate facet — so terrain facets point up
//! (+z) in either coordinate mode. STL has no units: the numbers are metres in
//! local metres, grid units horizontally in grid coordinates, each multiplied
//! by [`ExportOptions::stl_units_per_m`] (e.g. millimetres at a print scale;
//! the header then notes the factor).
//!
//! With [`ExportOptions::base_m`] the surface is closed with side walls and a
//! flat base into a watertight solid (walls from the boundary edges, the base a
//! fan from an added centre vertex): every edge
//! is shared by exactly two facets, with outward normals.

use std::io::Write;

use cota_core::{HeightGrid, Mesh};

use super::coords::{Frame, GeoInfo};
use super::error::ExportError;
use super::geometry::{check_mesh, push_f32s, to_f32, triangle_points, unit_face_normal_f32};
use super::options::ExportOptions;
use super::par::{on_pool, write_chunks};
use super::solid::{closing_triangles, GridPoint};

/// Writes `mesh` as binary STL to `w` (wrap files in a `BufWriter`, as
/// [`write_mesh`](super::write_mesh) does).
///
/// # Errors
/// [`ExportError::Io`] from `w`; the mesh checks of [`ExportError`];
/// [`ExportError::BaseNotBelow`] or [`ExportError::NotClosable`] with
/// [`ExportOptions::base_m`]; [`ExportError::TooLarge`] beyond 2^32−1 facets.
pub fn write_stl<W: Write + Send>(
    w: W,
    mesh: &Mesh,
    grid: &HeightGrid,
    opts: &ExportOptions,
) -> Result<(), ExportError> {
    on_pool(|| encode_stl(w, mesh, grid, opts))
}

/// The body of [`write_stl`], on the pool.
fn encode_stl<W: Write + Send>(
    mut w: W,
    mesh: &Mesh,
    grid: &HeightGrid,
    opts: &ExportOptions,
) -> Result<(), ExportError> {
    check_mesh(mesh)?;
    let scale = opts.stl_units_per_m;
    if !(scale.is_finite() && scale > 0.0) {
        return Err(ExportError::BadOption {
            what: "stl_units_per_m",
            expected: "a positive finite factor",
            found: scale.to_string(),
        });
    }
    let closing = match opts.base_m {
        Some(base_m) => closing_triangles(mesh, base_m)?,
        None => Vec::new(),
    };
    let count = facet_count(mesh.triangles.len() + closing.len())?;
    let frame = Frame::new(grid, opts.coords);
    w.write_all(&GeoInfo::new(grid, opts.coords).stl_header(scale))?;
    w.write_all(&count.to_le_bytes())?;
    write_chunks(&mut w, &mesh.triangles, FACET_BYTES, |_, chunk, buf| {
        for &t in chunk {
            push_facet(buf, triangle_points(mesh, &frame, frame.orient(t)), scale);
        }
        Ok(())
    })?;
    write_chunks(&mut w, &closing, FACET_BYTES, |_, chunk, buf| {
        for t in chunk {
            let p = t.map(|g: GridPoint| frame.point(g[0], g[1], g[2]));
            push_facet(buf, frame.orient(p), scale);
        }
        Ok(())
    })?;
    w.flush()?;
    Ok(())
}

/// The facet count as the header's u32.
fn facet_count(n: usize) -> Result<u32, ExportError> {
    u32::try_from(n).map_err(|_| ExportError::TooLarge {
        what: "facets in a binary STL",
        count: n as u64,
        max: u64::from(u32::MAX),
    })
}

/// Bytes of a facet record.
const FACET_BYTES: usize = 50;

/// Appends one 50-byte facet record: the unit normal, the three vertices
/// (times `scale`) and a zero attribute byte count.
fn push_facet(buf: &mut Vec<u8>, p: [[f64; 3]; 3], scale: f64) {
    let p = p.map(|v| v.map(|c| c * scale));
    let n = unit_face_normal_f32(p);
    for v in [n, to_f32(p[0]), to_f32(p[1]), to_f32(p[2])] {
        push_f32s(buf, &v);
    }
    buf.extend_from_slice(&[0, 0]);
}
