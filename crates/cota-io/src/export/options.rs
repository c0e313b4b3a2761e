//! Options of the mesh writers: [`ExportOptions`], [`Coords`], [`IndexWidth`].

use std::fmt;

/// The coordinate frame the vertex positions are written in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Coords {
    /// Metres, x east, y north, z up, origin at the grid's south-west sample:
    /// `x = col·dx`, `y = (H−1−row)·dy`, `z = z_m`, with `[dx, dy]` =
    /// [`HeightGrid::cell_size_m`](cota_core::HeightGrid::cell_size_m). A
    /// right-handed frame; triangles keep the mesh's winding (normals up).
    #[default]
    LocalMetres,
    /// Grid units: `x = col`, `y = row` counted from the northern row (so y
    /// points south), `z = z_m` in metres. The frame is mirrored north–south, so
    /// the writers reverse every triangle's winding to keep normals pointing up
    /// (+z) by the right-hand rule.
    Grid,
}

impl Coords {
    /// The name used on the command line and in file metadata.
    pub const fn name(self) -> &'static str {
        match self {
            Coords::LocalMetres => "local-metres",
            Coords::Grid => "grid",
        }
    }
}

impl fmt::Display for Coords {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Width of the glTF index accessor (GLB only; PLY always writes `int`, OBJ
/// decimal text, STL no indices).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum IndexWidth {
    /// `u16` when the mesh has at most 65 535 vertices, else `u32`. (glTF
    /// forbids the largest value of the type as an index — it is the primitive
    /// restart value — so 65 535 itself cannot be used.)
    #[default]
    Auto,
    /// Always `u16`; meshes with more than 65 535 vertices are an error.
    U16,
    /// Always `u32`.
    U32,
}

/// Options of [`write_mesh`](super::write_mesh) and the per-format writers.
///
/// Build from [`ExportOptions::DEFAULT`] (also [`Default`]) with the `with_*`
/// setters:
///
/// ```
/// use cota_io::export::{Coords, ExportOptions};
/// let opts = ExportOptions::DEFAULT.with_coords(Coords::Grid).with_base_m(Some(-100.0));
/// assert_eq!(opts.coords, Coords::Grid);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct ExportOptions {
    /// Frame of the written positions. Default: [`Coords::LocalMetres`].
    pub coords: Coords,
    /// STL only: close the terrain into a solid for 3D printing, with side
    /// walls from the mesh boundary down to a flat base at this height in
    /// metres (which must lie below the lowest vertex). Ignored by the other
    /// formats. Default: `None` (the terrain surface alone).
    pub base_m: Option<f64>,
    /// glTF index type. Default: [`IndexWidth::Auto`].
    pub index_width: IndexWidth,
    /// OBJ and PLY: also write per-vertex normals (OBJ `vn`, PLY `nx ny nz`).
    /// GLB always has normals and STL always facet normals. Default: `false`.
    pub normals: bool,
    /// GLB only: write quantized attributes (`KHR_mesh_quantization`): 16-bit
    /// integer positions (columns and rows exact, heights on a power-of-two
    /// step), 8-bit normals and 16-bit indices, in primitives of at most
    /// 65 535 vertices; about half the size of the float layout. Heights move
    /// by at most half the step, which
    /// [`GlbQuantization::z_step_m`](super::GlbQuantization::z_step_m)
    /// reports. Ignored by the other formats; [`ExportOptions::index_width`]
    /// does not apply. Default: `false`.
    pub quantize: bool,
    /// Replace an existing read-only file (the CLI's `--force`); otherwise
    /// that is an error. Default: `false`.
    pub replace_read_only: bool,
    /// STL only: model units written per unit of the output frame (per metre
    /// in [`Coords::LocalMetres`]). Every STL coordinate, x, y and z alike
    /// (and so the base of [`ExportOptions::base_m`]), is multiplied by it,
    /// about the frame's origin (the south-west sample, height 0): 0.01
    /// writes millimetres at a print scale of 1:100000. Must be positive and
    /// finite. Ignored by the other formats. Default: 1.0.
    pub stl_units_per_m: f64,
}

impl ExportOptions {
    /// The defaults, as documented on each field.
    pub const DEFAULT: ExportOptions = ExportOptions {
        coords: Coords::LocalMetres,
        base_m: None,
        index_width: IndexWidth::Auto,
        normals: false,
        quantize: false,
        replace_read_only: false,
        stl_units_per_m: 1.0,
    };

    /// Sets [`ExportOptions::stl_units_per_m`].
    pub const fn with_stl_units_per_m(mut self, units_per_m: f64) -> Self {
        self.stl_units_per_m = units_per_m;
        self
    }

    /// Sets [`ExportOptions::replace_read_only`].
    pub const fn with_replace_read_only(mut self, replace: bool) -> Self {
        self.replace_read_only = replace;
        self
    }

    /// Sets [`ExportOptions::coords`].
    pub const fn with_coords(mut self, coords: Coords) -> Self {
        self.coords = coords;
        self
    }

    /// Sets [`ExportOptions::base_m`].
    pub const fn with_base_m(mut self, base_m: Option<f64>) -> Self {
        self.base_m = base_m;
        self
    }

    /// Sets [`ExportOptions::index_width`].
    pub const fn with_index_width(mut self, index_width: IndexWidth) -> Self {
        self.index_width = index_width;
        self
    }

    /// Sets [`ExportOptions::normals`].
    pub const fn with_normals(mut self, normals: bool) -> Self {
        self.normals = normals;
        self
    }

    /// Sets [`ExportOptions::quantize`].
    pub const fn with_quantize(mut self, quantize: bool) -> Self {
        self.quantize = quantize;
        self
    }
}

impl Default for ExportOptions {
    fn default() -> Self {
        ExportOptions::DEFAULT
    }
}
