//! `cota.Mesh`: an extracted mesh with numpy `vertices` and `triangles`, and
//! `write` through `cota_io::export::write_mesh` (atomic, any format).

use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

use cota_core::{HeightGrid, Mesh as CoreMesh};
use cota_io::export::{write_mesh, Coords, ExportOptions};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::{arrays, errors};

/// A conforming triangle mesh of a grid, every vertex on a sample.
#[pyclass(module = "cota", frozen)]
pub(crate) struct Mesh {
    mesh: CoreMesh,
    grid: Arc<HeightGrid>,
    threshold_m: f64,
    general: bool,
    vertices: OnceLock<Py<PyAny>>,
    triangles: OnceLock<Py<PyAny>>,
}

impl Mesh {
    /// `general`: a TIN or foreign triangles, checked as a general
    /// triangulation.
    pub(crate) fn new(
        mesh: CoreMesh,
        grid: Arc<HeightGrid>,
        threshold_m: f64,
        general: bool,
    ) -> Self {
        Mesh {
            mesh,
            grid,
            threshold_m,
            general,
            vertices: OnceLock::new(),
            triangles: OnceLock::new(),
        }
    }

    pub(crate) fn core(&self) -> &CoreMesh {
        &self.mesh
    }

    pub(crate) fn general(&self) -> bool {
        self.general
    }

    pub(crate) fn grid(&self) -> &HeightGrid {
        &self.grid
    }
}

/// `cached`'s array, made by `make` on first use.
fn cached(
    py: Python<'_>,
    cell: &OnceLock<Py<PyAny>>,
    make: impl FnOnce() -> PyResult<Py<PyAny>>,
) -> PyResult<Py<PyAny>> {
    if let Some(a) = cell.get() {
        return Ok(a.clone_ref(py));
    }
    let a = make()?;
    Ok(cell.get_or_init(|| a).clone_ref(py))
}

#[pymethods]
impl Mesh {
    /// Vertices, float64, shape (n, 3): column, row (from the northern row)
    /// and height in metres; read-only, exact.
    #[getter]
    fn vertices(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        cached(py, &self.vertices, || {
            let flat: Vec<f64> = self
                .mesh
                .vertices
                .iter()
                .flat_map(|v| [f64::from(v.col), f64::from(v.row), f64::from(v.z_m)])
                .collect();
            let n = self.mesh.vertices.len();
            Ok(arrays::readonly_2d(py, flat, n, 3)?.unbind())
        })
    }

    /// Triangles, uint32 indices into `vertices`, shape (m, 3),
    /// counter-clockwise seen from above (north up); read-only.
    #[getter]
    fn triangles(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        cached(py, &self.triangles, || {
            let flat: Vec<u32> = self.mesh.triangles.iter().flatten().copied().collect();
            let m = self.mesh.triangles.len();
            Ok(arrays::readonly_2d(py, flat, m, 3)?.unbind())
        })
    }

    /// The error threshold used, metres: every sample is within it.
    #[getter]
    fn threshold_m(&self) -> f64 {
        self.threshold_m
    }

    /// Number of vertices.
    #[getter]
    fn vertex_count(&self) -> usize {
        self.mesh.vertex_count()
    }

    /// Number of triangles.
    #[getter]
    fn triangle_count(&self) -> usize {
        self.mesh.triangle_count()
    }

    /// Writes the mesh to `path` atomically (temp file + rename), in the
    /// format of its extension: .obj, .ply, .stl or .glb. `coords="local"`
    /// (default): metres, x east, y north, z up, origin at the south-west
    /// sample; `"grid"`: x = column, y = row, z = metres. `quantize=True`
    /// (.glb only): 16-bit positions, about half the size. Raises
    /// `cota.WriteError` naming the file; nothing is left behind on error.
    /// The GIL is released.
    #[pyo3(signature = (path, *, coords = "local", quantize = false))]
    fn write(&self, py: Python<'_>, path: PathBuf, coords: &str, quantize: bool) -> PyResult<()> {
        let coords = match coords {
            "local" => Coords::LocalMetres,
            "grid" => Coords::Grid,
            other => {
                return Err(PyValueError::new_err(format!(
                    "expected coords=\"local\" or \"grid\", found {other:?}"
                )))
            }
        };
        let opts = ExportOptions::DEFAULT
            .with_coords(coords)
            .with_quantize(quantize);
        let (mesh, grid) = (&self.mesh, self.grid.as_ref());
        py.detach(|| write_mesh(&path, mesh, grid, &opts))
            .map_err(errors::write)
    }

    fn __len__(&self) -> usize {
        self.mesh.triangle_count()
    }

    fn __repr__(&self) -> String {
        format!(
            "Mesh({} vertices, {} triangles, threshold_m={})",
            self.mesh.vertex_count(),
            self.mesh.triangle_count(),
            self.threshold_m
        )
    }
}
