//! Wavefront OBJ writer (text).
//!
//! Layout: `#` comment lines with the georeference (see [`GeoInfo`]), then one
//! `v x y z` line per vertex, optionally one `vn nx ny nz` line per vertex
//! ([`ExportOptions::normals`]), then one `f a b c` line per triangle with
//! 1-based vertex indices (`f a//a b//b c//c` with normals). Faces are
//! counter-clockwise seen from their front, the OBJ convention, so terrain
//! faces up (+z) in either coordinate mode (see [`Coords`](super::Coords)).
//!
//! Precision: x and y are computed in f64 and written rounded to 0.1 mm
//! (shortest decimal that reads back to that value); z is the mesh's f32
//! height written as the shortest decimal that reads back to the same f32, so
//! nothing is lost beyond the f32 heights themselves. In grid coordinates x
//! and y are whole numbers. Normals are written as f32.
//!
//! Numbers are formatted with `std`'s shortest round-trip float formatting,
//! chunks of lines in parallel (each into its own buffer), written in order.

use std::io::Write;

use cota_core::{HeightGrid, Mesh};

use super::coords::{Frame, GeoInfo};
use super::error::ExportError;
use super::geometry::{check_mesh, vertex_normals};
use super::options::ExportOptions;
use super::par::{on_pool, write_chunks};

/// Horizontal positions are rounded to this many steps per metre (0.1 mm).
const XY_STEPS_PER_UNIT: f64 = 1e4;

/// Writes `mesh` as OBJ text to `w` (wrap files in a `BufWriter`, as
/// [`write_mesh`](super::write_mesh) does).
///
/// # Errors
/// [`ExportError::Io`] from `w`; the mesh checks of [`ExportError`].
pub fn write_obj<W: Write + Send>(
    w: W,
    mesh: &Mesh,
    grid: &HeightGrid,
    opts: &ExportOptions,
) -> Result<(), ExportError> {
    on_pool(|| encode_obj(w, mesh, grid, opts))
}

/// The body of [`write_obj`], on the pool.
fn encode_obj<W: Write + Send>(
    mut w: W,
    mesh: &Mesh,
    grid: &HeightGrid,
    opts: &ExportOptions,
) -> Result<(), ExportError> {
    check_mesh(mesh)?;
    let frame = Frame::new(grid, opts.coords);
    write_header(&mut w, mesh, &GeoInfo::new(grid, opts.coords))?;
    write_vertices(&mut w, mesh, &frame)?;
    if opts.normals {
        write_normals(&mut w, mesh, &frame)?;
    }
    write_faces(&mut w, mesh, &frame, opts.normals)?;
    w.flush()?;
    Ok(())
}

/// The comment block.
fn write_header<W: Write>(w: &mut W, mesh: &Mesh, info: &GeoInfo) -> Result<(), ExportError> {
    for line in info.comment_lines() {
        writeln!(w, "# {line}")?;
    }
    writeln!(
        w,
        "# {} vertices, {} triangles",
        mesh.vertex_count(),
        mesh.triangle_count()
    )?;
    Ok(())
}

/// Rounds a horizontal coordinate to 0.1 mm.
#[inline]
fn round_xy(x: f64) -> f64 {
    (x * XY_STEPS_PER_UNIT).round() / XY_STEPS_PER_UNIT
}

/// `v x y z` lines.
fn write_vertices<W: Write + Send>(
    w: &mut W,
    mesh: &Mesh,
    frame: &Frame,
) -> Result<(), ExportError> {
    write_chunks(w, &mesh.vertices, 32, |_, chunk, buf| {
        for v in chunk {
            let [x, y, _] = frame.vertex(v);
            // Adding 0.0 turns a -0.0 into 0.0.
            writeln!(
                buf,
                "v {} {} {}",
                round_xy(x) + 0.0,
                round_xy(y) + 0.0,
                v.z_m + 0.0
            )?;
        }
        Ok(())
    })
}

/// `vn nx ny nz` lines.
fn write_normals<W: Write + Send>(
    w: &mut W,
    mesh: &Mesh,
    frame: &Frame,
) -> Result<(), ExportError> {
    let normals = vertex_normals(mesh, frame);
    write_chunks(w, &normals, 40, |_, chunk, buf| {
        for n in chunk {
            writeln!(buf, "vn {} {} {}", n[0], n[1], n[2])?;
        }
        Ok(())
    })
}

/// `f` lines, 1-based, in the frame's winding.
fn write_faces<W: Write + Send>(
    w: &mut W,
    mesh: &Mesh,
    frame: &Frame,
    normals: bool,
) -> Result<(), ExportError> {
    write_chunks(w, &mesh.triangles, 24, |_, chunk, buf| {
        for &t in chunk {
            let [a, b, c] = frame.orient(t).map(|i| u64::from(i) + 1);
            if normals {
                writeln!(buf, "f {a}//{a} {b}//{b} {c}//{c}")?;
            } else {
                writeln!(buf, "f {a} {b} {c}")?;
            }
        }
        Ok(())
    })
}
