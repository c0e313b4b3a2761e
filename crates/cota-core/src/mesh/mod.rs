//! The indexed triangle mesh that every extraction produces and every exporter
//! consumes.
//!
//! Vertices sit on grid samples: they carry the sample's integer (column, row)
//! and a height in metres. Triangles are counter-clockwise seen from above in
//! the east/north/up frame (x = column, y = north = −row), so their normals point
//! up. Exporters turn (column, row) into metres or grid units.
//!
//! The family also holds what every mesh is measured and proved with: the
//! exact spans of a triangle over the grid ([`raster`]), the exact metrics
//! over every sample ([`metrics`]) and the one invariant checker ([`check`]).

pub mod check;
pub mod clip;
pub mod holes;
pub mod metrics;
pub mod raster;

/// A mesh vertex on a grid sample.
///
/// All-zero bytes are a valid vertex ([`bytemuck::Zeroable`]), so large
/// vertex arrays can come zeroed from the allocator.
#[derive(Debug, Clone, Copy, PartialEq, bytemuck::Zeroable)]
pub struct MeshVertex {
    /// Column of the sample (0 = west).
    pub col: u32,
    /// Row of the sample (0 = north).
    pub row: u32,
    /// Height in metres: the sample's own height, or for a fictitious point the
    /// height interpolated on the edge it splits.
    pub z_m: f32,
}

/// An indexed triangle mesh over a height grid.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    /// The vertices.
    pub vertices: Vec<MeshVertex>,
    /// Triangles as vertex indices, counter-clockwise seen from above (+z).
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.vertices.len()
    }

    /// Twice the signed area of triangle `t` in grid units, positive when it is
    /// counter-clockwise seen from above (x east, y north).
    pub fn signed_area2(&self, t: [u32; 3]) -> i64 {
        let p = |i: u32| {
            let v = self.vertices[i as usize];
            (v.col as i64, -(v.row as i64))
        };
        let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
        (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0)
    }
}
