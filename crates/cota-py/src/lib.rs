//! # cota-py
//!
//! The Python extension module `cota._cota`, re-exported by the `cota` package
//! (`python/cota/__init__.py`, typed in `__init__.pyi`). A thin layer: it
//! converts numpy arrays and Python arguments, calls `cota-core` and `cota-io`
//! with the GIL released, and turns their errors into Python exceptions that
//! carry cota's messages. No meshing logic lives here.
//!
//! * `arrays`: 2-D numpy heights (float32, float64, int16, any strides) to a
//!   `HeightGrid`, and read-only numpy views of results;
//! * `dem`: `cota.read` and `cota.Dem` (`cota_io::read_region`);
//! * `bitree`: `cota.Bitree` (`cota_core::Bitree`: build once, extract,
//!   check, measure);
//! * `mesh`: `cota.Mesh` (numpy vertices and triangles, `write`);
//! * `tiles`: `cota.tiles` (a quantized-mesh pyramid, whole or one shard),
//!   `cota.tiles_plan`, `cota.tiles_plan_layout`, `cota.tiles_plan_part`,
//!   `cota.tiles_plan_step`, `cota.tiles_reduce` (used by `cota.dask`).

use pyo3::prelude::*;

mod arrays;
mod bitree;
mod dem;
mod errors;
mod mesh;
mod tiles;

/// The extension module: classes, `read`, and the exception hierarchy.
#[pymodule]
fn _cota(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_class::<dem::Dem>()?;
    m.add_class::<bitree::Bitree>()?;
    m.add_class::<mesh::Mesh>()?;
    m.add_function(wrap_pyfunction!(dem::read, m)?)?;
    m.add_function(wrap_pyfunction!(tiles::tiles, m)?)?;
    m.add_function(wrap_pyfunction!(tiles::tiles_plan, m)?)?;
    m.add_function(wrap_pyfunction!(tiles::tiles_plan_step, m)?)?;
    m.add_function(wrap_pyfunction!(tiles::tiles_plan_layout, m)?)?;
    m.add_function(wrap_pyfunction!(tiles::tiles_plan_part, m)?)?;
    m.add_function(wrap_pyfunction!(tiles::tiles_reduce, m)?)?;
    m.add_function(wrap_pyfunction!(tiles::shard_record, m)?)?;
    m.add_function(wrap_pyfunction!(tiles::shard_frame, m)?)?;
    m.add("CotaError", py.get_type::<errors::CotaError>())?;
    m.add("ReadError", py.get_type::<errors::ReadError>())?;
    m.add("MeshError", py.get_type::<errors::MeshError>())?;
    m.add("CheckError", py.get_type::<errors::CheckError>())?;
    m.add("WriteError", py.get_type::<errors::WriteError>())?;
    Ok(())
}
