//! `cota.Bitree`: the exact error of every split point, built once from a
//! numpy array (or a `Dem`), then meshes extracted, checked and measured
//! (`cota_core::Bitree`, `check_mesh`, `measure`).

use std::sync::{Arc, OnceLock};

use cota_core::tin::TinOptions;
use cota_core::{
    check_mesh, fill_voids, measure, Bitree as CoreBitree, CheckOptions, ExtractOptions,
    FillOptions, GeoRef, HeightGrid, Metrics, VoidPolicy,
};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::{arrays, errors, mesh::Mesh};

self_cell::self_cell!(
    /// The grid and the error map that borrows it, owned together.
    struct Prepared {
        owner: Arc<HeightGrid>,
        #[covariant]
        dependent: CoreBitree,
    }
);

/// The bitree of a height grid: the exact error of every triangle of the
/// right-triangle hierarchy, built once (`O(n log n)`), from which conforming
/// meshes are extracted at any bound or triangle budget.
#[pyclass(module = "cota", frozen)]
pub(crate) struct Bitree {
    prepared: Prepared,
    filled: usize,
    heights: OnceLock<Py<PyAny>>,
}

impl Bitree {
    /// Builds the error map of `grid` with the GIL released. `filled` is the
    /// number of voids filled before.
    pub(crate) fn prepare(py: Python<'_>, grid: Arc<HeightGrid>, filled: usize) -> PyResult<Self> {
        let prepared = py
            .detach(|| Prepared::try_new(grid, |g| CoreBitree::build(g)))
            .map_err(errors::mesh)?;
        Ok(Bitree {
            prepared,
            filled,
            heights: OnceLock::new(),
        })
    }

    fn grid(&self) -> &Arc<HeightGrid> {
        self.prepared.borrow_owner()
    }

    /// Refuses a mesh of another grid size.
    fn same_grid(&self, mesh: &Mesh) -> PyResult<()> {
        let (g, m) = (self.grid(), mesh.grid());
        if (g.width(), g.height()) != (m.width(), m.height()) {
            return Err(PyValueError::new_err(format!(
                "expected a mesh of this {}x{} grid, found one of a {}x{} grid",
                g.width(),
                g.height(),
                m.width(),
                m.height()
            )));
        }
        Ok(())
    }
}

/// The grid of `heights`, its voids filled or refused per `voids`.
fn grid_from(
    heights: arrays::Heights,
    cell_size_m: f64,
    voids: &str,
) -> PyResult<(HeightGrid, usize)> {
    if !(cell_size_m.is_finite() && cell_size_m > 0.0) {
        return Err(PyValueError::new_err(format!(
            "expected cell_size_m > 0, found {cell_size_m}"
        )));
    }
    let policy = match voids {
        "fill" => FillOptions::DEFAULT,
        "refuse" => FillOptions::DEFAULT.with_policy(VoidPolicy::Refuse),
        other => {
            return Err(PyValueError::new_err(format!(
                "expected voids=\"fill\" or \"refuse\", found {other:?}"
            )))
        }
    };
    let arrays::Heights {
        width,
        height,
        values,
    } = heights;
    let mut grid = HeightGrid::new(width, height, values, GeoRef::unreferenced(cell_size_m))
        .map_err(errors::value)?;
    let voids = grid.void_count();
    if voids > 0 {
        fill_voids(&mut grid, &policy).map_err(errors::mesh)?;
    }
    Ok((grid, voids))
}

/// The metrics as a dict (the keys of `cota.Metrics` in the stubs).
fn metrics_dict<'py>(py: Python<'py>, m: &Metrics) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("max_error_m", m.max_error_m)?;
    d.set_item("max_error_at", (m.max_error_at[0], m.max_error_at[1]))?;
    d.set_item("rmse_m", m.rmse_m)?;
    d.set_item("mean_abs_error_m", m.mean_abs_error_m)?;
    d.set_item("samples", m.samples)?;
    d.set_item("uncovered", m.uncovered)?;
    Ok(d)
}

#[pymethods]
impl Bitree {
    /// Builds the bitree of a 2-D array of heights in metres (rows x columns,
    /// row 0 north), dtype float32, float64 (rounded to float32) or int16, any
    /// strides. `cell_size_m`: the sample spacing in metres (both axes).
    ///
    /// NaN (and, with `nodata`, samples equal to it) marks voids:
    /// `voids="fill"` (default) fills them harmonically, as `cota mesh` does,
    /// and the meshes follow the filled surface; `voids="refuse"` raises
    /// `cota.MeshError` naming the first void. An all-NaN array raises
    /// `cota.MeshError` (nothing to fill from). The GIL is released while the
    /// voids are filled and the error map is built.
    #[new]
    #[pyo3(signature = (heights, cell_size_m = 30.0, voids = "fill", nodata = None))]
    fn new(
        py: Python<'_>,
        heights: &Bound<'_, PyAny>,
        cell_size_m: f64,
        voids: &str,
        nodata: Option<f64>,
    ) -> PyResult<Self> {
        let h = arrays::heights_from(heights, nodata)?;
        let voids = voids.to_string();
        let (grid, filled) = py.detach(|| grid_from(h, cell_size_m, &voids))?;
        Self::prepare(py, Arc::new(grid), filled)
    }

    /// Extracts the coarsest conforming mesh whose error is at most
    /// `max_error` metres at every sample, or the mesh with the smallest error
    /// that has at most `max_triangles` triangles. Give exactly one.
    /// `tin=True`: an irregular triangulation (cota's TIN: the bitree's mesh
    /// decimated under the same exact bound, fewer triangles, slower). Raises
    /// `cota.MeshError` for a negative bound or a budget below the coarsest
    /// mesh. The GIL is released.
    #[pyo3(signature = (*, max_error = None, max_triangles = None, tin = false))]
    fn extract(
        &self,
        py: Python<'_>,
        max_error: Option<f64>,
        max_triangles: Option<usize>,
        tin: bool,
    ) -> PyResult<Mesh> {
        let (opts, tin_opts) = match (max_error, max_triangles) {
            (Some(e), None) => (ExtractOptions::max_error_m(e), TinOptions::max_error_m(e)),
            (None, Some(n)) => (
                ExtractOptions::max_triangles(n),
                TinOptions::max_triangles(n),
            ),
            _ => {
                return Err(PyValueError::new_err(
                    "expected exactly one of max_error= or max_triangles=",
                ))
            }
        };
        let bitree = self.prepared.borrow_dependent();
        let x = py
            .detach(|| match tin {
                false => bitree.extract(&opts),
                true => cota_core::tin::build_from(bitree, &tin_opts),
            })
            .map_err(errors::mesh)?;
        Ok(Mesh::new(
            x.mesh,
            Arc::clone(self.grid()),
            x.threshold_m,
            tin,
        ))
    }

    /// Proves `mesh` with cota's invariant checker against this grid: it
    /// covers the grid exactly, has no T-junction, its vertices carry their
    /// samples' heights, and |mesh - grid| <= `bound` metres at every sample.
    /// A TIN or a mesh from arrays also gets the direct tests of a general
    /// triangulation (no vertex inside an edge, every vertex used). Returns
    /// the metrics (as `metrics`); raises `cota.CheckError` with the first
    /// violation. The GIL is released.
    fn check<'py>(
        &self,
        py: Python<'py>,
        mesh: PyRef<'py, Mesh>,
        bound: f64,
    ) -> PyResult<Bound<'py, PyDict>> {
        self.same_grid(&mesh)?;
        let (grid, m) = (self.grid().as_ref(), mesh.core());
        let opts = CheckOptions::conforming(bound).with_general(mesh.general());
        let report = py
            .detach(|| check_mesh(grid, m, &opts))
            .map_err(errors::check)?;
        metrics_dict(py, &report.metrics)
    }

    /// The exact error of `mesh` against this grid, over every sample:
    /// `max_error_m`, `max_error_at` (column, row), `rmse_m`,
    /// `mean_abs_error_m`, `samples`, `uncovered`. The GIL is released.
    fn metrics<'py>(
        &self,
        py: Python<'py>,
        mesh: PyRef<'py, Mesh>,
    ) -> PyResult<Bound<'py, PyDict>> {
        self.same_grid(&mesh)?;
        let (grid, m) = (self.grid().as_ref(), mesh.core());
        let metrics = py.detach(|| measure(grid, m));
        metrics_dict(py, &metrics)
    }

    /// A `Mesh` of this grid from another mesher's arrays, to measure or
    /// check it with cota: `vertices` (n, 2 or more) with integer column and
    /// row in the first two columns (further columns are ignored: heights are
    /// the grid's samples), `triangles` (m, 3) indices into `vertices`.
    /// Raises `ValueError` for a vertex off the grid or not on a sample, or an
    /// index out of range.
    fn mesh_from_arrays(
        &self,
        py: Python<'_>,
        vertices: &Bound<'_, PyAny>,
        triangles: &Bound<'_, PyAny>,
    ) -> PyResult<Mesh> {
        let mesh = arrays::foreign_mesh(py, self.grid(), vertices, triangles)?;
        Ok(Mesh::new(mesh, Arc::clone(self.grid()), f64::NAN, true))
    }

    /// The (filled) heights the bitree was built on, float32, read-only.
    #[getter]
    fn heights(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        if let Some(a) = self.heights.get() {
            return Ok(a.clone_ref(py));
        }
        let g = self.grid();
        let a = arrays::readonly_2d(py, g.heights().to_vec(), g.height(), g.width())?.unbind();
        Ok(self.heights.get_or_init(|| a).clone_ref(py))
    }

    /// Number of columns.
    #[getter]
    fn width(&self) -> usize {
        self.grid().width()
    }

    /// Number of rows.
    #[getter]
    fn height(&self) -> usize {
        self.grid().height()
    }

    /// Voids filled before the build (0 for a `Dem`: `cota.read` fills them).
    #[getter]
    fn voids_filled(&self) -> usize {
        self.filled
    }

    fn __repr__(&self) -> String {
        format!("Bitree({}x{})", self.width(), self.height())
    }
}
