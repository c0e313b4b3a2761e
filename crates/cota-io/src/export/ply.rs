//! Stanford PLY writer, `binary_little_endian 1.0`.
//!
//! Header (ASCII, `\n` line ends): `ply`, `format binary_little_endian 1.0`,
//! `comment` lines with the georeference (see [`GeoInfo`]), then
//! ```text
//! element vertex N
//! property float x
//! property float y
//! property float z
//! [property float nx / ny / nz]      (with ExportOptions::normals)
//! element face T
//! property list uchar int vertex_indices
//! end_header
//! ```
//! followed by N vertex records (3 or 6 little-endian f32) and T face records
//! (the byte 3, then three little-endian i32 indices, 0-based). Faces are
//! counter-clockwise seen from their front (PLY's usual convention), so
//! terrain faces up (+z) in either coordinate mode.
//!
//! Precision: positions are `float` (f32). In local metres, positions are
//! relative to the grid's south-west sample, so the largest coordinate is the
//! grid's extent: over a 1201×1201 SRTM tile (~110 km) an f32 resolves ~8 mm
//! horizontally, well below the 30–90 m sample spacing and below the heights'
//! own f32 resolution at that scale; acceptable for a terrain mesh, and half the
//! size of `double`. Grid coordinates (whole numbers below 2^24) are exact.

use std::io::Write;

use cota_core::{HeightGrid, Mesh};

use super::coords::{Frame, GeoInfo};
use super::error::ExportError;
use super::geometry::{check_mesh, push_f32s, to_f32, vertex_normals};
use super::options::ExportOptions;
use super::par::{on_pool, write_chunks};

/// Writes `mesh` as binary little-endian PLY to `w` (wrap files in a
/// `BufWriter`, as [`write_mesh`](super::write_mesh) does).
///
/// # Errors
/// [`ExportError::Io`] from `w`; the mesh checks of [`ExportError`];
/// [`ExportError::TooLarge`] beyond 2^31−1 vertices (PLY `int` indices).
pub fn write_ply<W: Write + Send>(
    w: W,
    mesh: &Mesh,
    grid: &HeightGrid,
    opts: &ExportOptions,
) -> Result<(), ExportError> {
    on_pool(|| encode_ply(w, mesh, grid, opts))
}

/// The body of [`write_ply`], on the pool.
fn encode_ply<W: Write + Send>(
    mut w: W,
    mesh: &Mesh,
    grid: &HeightGrid,
    opts: &ExportOptions,
) -> Result<(), ExportError> {
    check_mesh(mesh)?;
    check_int_indices(mesh)?;
    let frame = Frame::new(grid, opts.coords);
    write_header(&mut w, mesh, &GeoInfo::new(grid, opts.coords), opts.normals)?;
    let normals = if opts.normals {
        vertex_normals(mesh, &frame)
    } else {
        Vec::new()
    };
    write_vertices(&mut w, mesh, &frame, &normals)?;
    write_faces(&mut w, mesh, &frame)?;
    w.flush()?;
    Ok(())
}

/// PLY `int` indices are signed 32-bit.
fn check_int_indices(mesh: &Mesh) -> Result<(), ExportError> {
    let max = i32::MAX as u64;
    let count = mesh.vertices.len() as u64;
    if count > max {
        return Err(ExportError::TooLarge {
            what: "vertices in a PLY with int indices",
            count,
            max,
        });
    }
    Ok(())
}

/// The ASCII header through `end_header`.
fn write_header<W: Write>(
    w: &mut W,
    mesh: &Mesh,
    info: &GeoInfo,
    normals: bool,
) -> Result<(), ExportError> {
    w.write_all(b"ply\nformat binary_little_endian 1.0\n")?;
    for line in info.comment_lines() {
        writeln!(w, "comment {line}")?;
    }
    writeln!(w, "element vertex {}", mesh.vertex_count())?;
    w.write_all(b"property float x\nproperty float y\nproperty float z\n")?;
    if normals {
        w.write_all(b"property float nx\nproperty float ny\nproperty float nz\n")?;
    }
    writeln!(w, "element face {}", mesh.triangle_count())?;
    w.write_all(b"property list uchar int vertex_indices\nend_header\n")?;
    Ok(())
}

/// Vertex records: x y z [nx ny nz] as little-endian f32.
fn write_vertices<W: Write + Send>(
    w: &mut W,
    mesh: &Mesh,
    frame: &Frame,
    normals: &[[f32; 3]],
) -> Result<(), ExportError> {
    write_chunks(w, &mesh.vertices, 24, |first, chunk, buf| {
        for (k, v) in chunk.iter().enumerate() {
            push_f32s(buf, &to_f32(frame.vertex(v)));
            if let Some(n) = normals.get(first + k) {
                push_f32s(buf, n);
            }
        }
        Ok(())
    })
}

/// Face records: count byte 3 and three little-endian i32 indices.
fn write_faces<W: Write + Send>(w: &mut W, mesh: &Mesh, frame: &Frame) -> Result<(), ExportError> {
    write_chunks(w, &mesh.triangles, 13, |_, chunk, buf| {
        for &t in chunk {
            buf.push(3);
            for i in frame.orient(t) {
                // Fits: check_int_indices bounds every index below i32::MAX.
                buf.extend_from_slice(&i.to_le_bytes());
            }
        }
        Ok(())
    })
}
