//! Errors of the mesh writers.
//!
//! [`ExportError`] is what encoding a mesh can go wrong with, independent of
//! where the bytes go; [`WriteError`] adds the file. Both display on one line,
//! and a [`WriteError`] always names the file.

use std::io;
use std::path::{Path, PathBuf};

/// A failure to encode a mesh (no file involved: see [`WriteError`] for that).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ExportError {
    /// The destination refused the bytes.
    #[error(transparent)]
    Io(#[from] io::Error),
    /// The mesh has no triangles.
    #[error("expected a mesh with at least one triangle, found none")]
    EmptyMesh,
    /// A triangle refers to a vertex that does not exist.
    #[error("expected vertex indices below {count}, found {index} in triangle {triangle}")]
    VertexOutOfRange {
        /// Index of the triangle.
        triangle: usize,
        /// The bad vertex index.
        index: u32,
        /// Number of vertices in the mesh.
        count: usize,
    },
    /// A vertex height is NaN or infinite.
    #[error("expected finite vertex heights, found {z_m} at vertex {vertex}")]
    NonFiniteHeight {
        /// Index of the vertex.
        vertex: usize,
        /// Its height.
        z_m: f32,
    },
    /// The STL base is not below the terrain.
    #[error("expected a base height below the lowest vertex ({min_m} m), found {base_m} m")]
    BaseNotBelow {
        /// The requested base height.
        base_m: f64,
        /// The lowest vertex height of the mesh.
        min_m: f32,
    },
    /// The mesh cannot be closed into a solid (holes, non-manifold edges, ...).
    #[error("cannot build a closed solid: {0}")]
    NotClosable(String),
    /// A count exceeds what the format can hold.
    #[error("expected at most {max} {what}, found {count}")]
    TooLarge {
        /// What is counted (e.g. "vertices for 16-bit glTF indices").
        what: &'static str,
        /// The count.
        count: u64,
        /// The format's limit.
        max: u64,
    },
    /// The glTF JSON could not be encoded.
    #[error("cannot encode the glTF JSON: {0}")]
    Json(String),
    /// A strip does not encode the mesh given with it (normals would come
    /// from other triangles): pass the mesh the strip was made for.
    #[error("expected a strip of the mesh's {mesh_triangles} triangles (the mesh returned with the strip), found {strip_triangles} strip triangles of which {foreign} are not the mesh's")]
    StripMismatch {
        /// Triangles of the mesh.
        mesh_triangles: usize,
        /// Non-degenerate triangles of the strip.
        strip_triangles: usize,
        /// Strip triangles (with orientation) not in the mesh.
        foreign: usize,
    },
    /// An option out of its range.
    #[error("{what}: expected {expected}, found {found}")]
    BadOption {
        /// The option (its field name in [`ExportOptions`](super::ExportOptions)).
        what: &'static str,
        /// What it may be.
        expected: &'static str,
        /// What it was.
        found: String,
    },
    /// Two options that cannot go together.
    #[error("expected {expected}, found {found}")]
    Incompatible {
        /// What would work.
        expected: &'static str,
        /// What was asked.
        found: &'static str,
    },
}

/// A failure to write a mesh file. Displays on one line and names the file.
///
/// * [`WriteError::Io`]: `cannot write FILE: what the OS said` (missing
///   directory, permission denied, path is a directory, disk full, ...).
/// * [`WriteError::UnknownFormat`]: `FILE: expected .obj, .ply, .stl or .glb, found .xyz`.
/// * [`WriteError::Export`]: `FILE: what is wrong with the mesh or options`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum WriteError {
    /// The file could not be created, written, synced or renamed into place.
    #[error("cannot write {}: {error}", path.display())]
    Io {
        /// The output file.
        path: PathBuf,
        /// What the OS said.
        error: io::Error,
    },
    /// The file name's extension names no supported format.
    #[error("{}: expected .obj, .ply, .stl or .glb, found {found}", path.display())]
    UnknownFormat {
        /// The output file.
        path: PathBuf,
        /// The extension found (with its dot), or "no extension".
        found: String,
    },
    /// The mesh or the options cannot be encoded in the format.
    #[error("{}: {error}", path.display())]
    Export {
        /// The output file.
        path: PathBuf,
        /// What is wrong.
        error: ExportError,
    },
}

impl WriteError {
    /// The output file the error is about.
    pub fn path(&self) -> &Path {
        match self {
            WriteError::Io { path, .. }
            | WriteError::UnknownFormat { path, .. }
            | WriteError::Export { path, .. } => path,
        }
    }

    /// An I/O failure on `path`.
    pub(crate) fn io(path: &Path, error: io::Error) -> Self {
        WriteError::Io {
            path: path.to_path_buf(),
            error,
        }
    }

    /// Attaches `path` to an encoding failure; I/O failures become [`WriteError::Io`].
    pub(crate) fn export(path: &Path, error: ExportError) -> Self {
        match error {
            ExportError::Io(e) => WriteError::io(path, e),
            other => WriteError::Export {
                path: path.to_path_buf(),
                error: other,
            },
        }
    }
}
