//! Mesh writers: Wavefront OBJ, binary PLY, binary STL and binary glTF (GLB),
//! each written atomically.
//!
//! # API
//! * [`write_mesh`]`(path, mesh, grid, opts)`: picks the format from the file
//!   extension ([`MeshFormat::from_path`]: `.obj`, `.ply`, `.stl`, `.glb`, any
//!   case) and writes the file atomically ([`write_atomically`]).
//! * [`write_mesh_as`] writes a file in a format chosen by the caller;
//!   [`write_mesh_to`] and the per-format [`write_obj`], [`write_ply`],
//!   [`write_stl`], [`write_glb`] encode to any [`Write`].
//! * [`ExportOptions`]: coordinate frame, STL base, glTF index width, OBJ/PLY
//!   normals; start from [`ExportOptions::DEFAULT`].
//! * Errors: [`WriteError`] (names the file) wraps [`ExportError`].
//!
//! ```
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use cota_core::{GeoRef, HeightGrid, Mesh, MeshVertex};
//! use cota_io::export::{write_mesh, ExportOptions};
//! let grid = HeightGrid::new(2, 2, vec![1.0, 2.0, 3.0, 4.0], GeoRef::unreferenced(30.0))?;
//! let v = |col, row| MeshVertex { col, row, z_m: grid.get(col as usize, row as usize) };
//! let mesh = Mesh { vertices: vec![v(0, 0), v(1, 0), v(0, 1), v(1, 1)], triangles: vec![[2, 1, 0], [2, 3, 1]] };
//! let dir = tempfile::tempdir()?;
//! write_mesh(&dir.path().join("tile.glb"), &mesh, &grid, &ExportOptions::DEFAULT)?;
//! assert!(write_mesh(&dir.path().join("tile.xyz"), &mesh, &grid, &ExportOptions::DEFAULT).is_err());
//! # Ok(())
//! # }
//! ```
//!
//! # Conventions
//! * **Coordinates** ([`Coords`]): by default local metres, x east, y north,
//!   z up, origin at the grid's south-west sample: `x = col·dx`,
//!   `y = (H−1−row)·dy`, `z = z_m`, with `[dx, dy]` =
//!   [`HeightGrid::cell_size_m`](cota_core::HeightGrid::cell_size_m). For
//!   geographic grids that is the degree-to-metre conversion at the grid's
//!   centre latitude applied to the whole grid (a local tangent-plane
//!   approximation). With [`Coords::Grid`]: `x = col`, `y = row` from the
//!   northern row (pointing south), `z = z_m` metres.
//! * **Winding**: the mesh's triangles are counter-clockwise seen from above in
//!   east/north/up. Local metres keep that order; grid coordinates are a
//!   mirrored frame (y south), so the writers reverse every triangle there. In
//!   both modes the right-hand normal of every written triangle points up
//!   (+z), which is the front face for OBJ, PLY, STL and glTF alike.
//! * **Normals** (GLB always; OBJ/PLY with [`ExportOptions::normals`]): the
//!   area-weighted average of the adjacent face normals, computed in f64 in the
//!   output frame and normalised; a vertex no triangle uses gets (0, 0, 1). STL facet normals are the
//!   unit face normals.
//! * **Georeference**: the CRS, the affine from samples to CRS coordinates, the
//!   CRS coordinates of the south-west sample (the local origin), the cell size
//!   in metres and the coordinate mode go into glTF `asset.extras`, OBJ `#`
//!   comments and PLY `comment` lines; the STL header carries a short note
//!   (mode, CRS, south-west sample).
//! * **Precision**: OBJ writes x, y to 0.1 mm and z as the exact f32 height;
//!   PLY, STL and GLB write f32 positions, relative to the south-west sample, so
//!   ~8 mm resolution at the far corner of a 110 km SRTM tile.
//! * **Atomic**: a file is written to a temporary file in its directory,
//!   flushed, fsynced and renamed over the target; on any error nothing is
//!   left behind and an existing target keeps its content.
//!
//! Every writer first checks the mesh: at least one triangle, indices in
//! range, finite heights.
//!
//! **Parallel encoding**: each writer runs on rayon's pool; records (lines,
//! vertices, triangles, facets) are encoded in chunks on every thread and
//! written in order, the next batch encoded while one is written (`par`), and
//! vertex normals are summed in parallel in the same order as a sequential
//! loop. The bytes are those of a sequential writer, whatever the thread
//! count. So the writers take `W: Write + Send`.

mod atomic;
mod coords;
mod error;
mod geometry;
mod glb;
mod obj;
mod options;
mod par;
mod ply;
mod quantize;
mod solid;
mod stl;

use std::fmt;
use std::io::Write;
use std::path::Path;

use cota_core::{HeightGrid, Mesh};

pub use atomic::{write_atomically, write_atomically_forced};
pub use error::{ExportError, WriteError};
pub use glb::{
    encode_png, textured_mesh_bytes, write_glb, write_glb_quantized, write_glb_strip,
    write_glb_textured,
};
pub use obj::write_obj;
pub use options::{Coords, ExportOptions, IndexWidth};
pub use ply::write_ply;
pub use quantize::GlbQuantization;
pub use stl::write_stl;

/// A mesh file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront OBJ, text.
    Obj,
    /// Stanford PLY, binary little-endian.
    Ply,
    /// STL, binary.
    Stl,
    /// glTF 2.0 binary container.
    Glb,
}

impl MeshFormat {
    /// All formats, in the order of the error message.
    pub const ALL: [MeshFormat; 4] = [
        MeshFormat::Obj,
        MeshFormat::Ply,
        MeshFormat::Stl,
        MeshFormat::Glb,
    ];

    /// The file extension, without the dot.
    pub const fn extension(self) -> &'static str {
        match self {
            MeshFormat::Obj => "obj",
            MeshFormat::Ply => "ply",
            MeshFormat::Stl => "stl",
            MeshFormat::Glb => "glb",
        }
    }

    /// The format named by `path`'s extension, in any case.
    ///
    /// # Errors
    /// [`WriteError::UnknownFormat`]: `FILE: expected .obj, .ply, .stl or .glb, found .xyz`.
    pub fn from_path(path: &Path) -> Result<MeshFormat, WriteError> {
        let ext = path.extension().map(|e| e.to_string_lossy());
        let found = ext.as_deref().and_then(|e| {
            MeshFormat::ALL
                .into_iter()
                .find(|f| f.extension().eq_ignore_ascii_case(e))
        });
        found.ok_or_else(|| WriteError::UnknownFormat {
            path: path.to_path_buf(),
            found: ext.map_or_else(|| "no extension".to_string(), |e| format!(".{e}")),
        })
    }
}

impl fmt::Display for MeshFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.extension())
    }
}

/// Writes `mesh` (over `grid`) to `path` atomically, in the format named by
/// the extension (`.obj`, `.ply`, `.stl`, `.glb`).
///
/// # Errors
/// [`WriteError::UnknownFormat`] for another extension (before touching the
/// file system); [`WriteError::Io`] when the file cannot be written;
/// [`WriteError::Export`] when the mesh or options cannot be encoded. On any
/// error nothing is created and an existing file is left as it was.
pub fn write_mesh(
    path: &Path,
    mesh: &Mesh,
    grid: &HeightGrid,
    opts: &ExportOptions,
) -> Result<(), WriteError> {
    let format = MeshFormat::from_path(path)?;
    write_mesh_as(path, format, mesh, grid, opts)
}

/// Writes `mesh` to `path` atomically in `format`, whatever the extension.
///
/// # Errors
/// As [`write_mesh`], less the extension check.
pub fn write_mesh_as(
    path: &Path,
    format: MeshFormat,
    mesh: &Mesh,
    grid: &HeightGrid,
    opts: &ExportOptions,
) -> Result<(), WriteError> {
    write_atomically_forced(path, opts.replace_read_only, |w| {
        write_mesh_to(w, format, mesh, grid, opts)
    })
}

/// Encodes `mesh` in `format` to `w`. Buffer `w` when it is a file.
///
/// # Errors
/// As the per-format writers.
pub fn write_mesh_to<W: Write + Send>(
    w: W,
    format: MeshFormat,
    mesh: &Mesh,
    grid: &HeightGrid,
    opts: &ExportOptions,
) -> Result<(), ExportError> {
    match format {
        MeshFormat::Obj => write_obj(w, mesh, grid, opts),
        MeshFormat::Ply => write_ply(w, mesh, grid, opts),
        MeshFormat::Stl => write_stl(w, mesh, grid, opts),
        MeshFormat::Glb => write_glb(w, mesh, grid, opts),
    }
}
