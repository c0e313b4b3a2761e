//! `cota.read` and `cota.Dem`: one or more DEM files read, mosaicked and (by
//! default) void-filled by `cota_io::read_region`, as `cota mesh` reads them.

use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

use cota_core::{FillOptions, HeightGrid, PixelIs};
use cota_io::{read_region, RegionOptions};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::{arrays, bitree, errors};

/// Reads one DEM file or several adjacent tiles (SRTM .hgt/.hgt.zip, GeoTIFF,
/// PNG terrain encodings, ESRI ASCII; formats detected from content) into one
/// grid, mosaicked by georeference.
///
/// `fill=True` (default) fills the voids harmonically, as `cota mesh` does;
/// `fill=False` leaves them NaN in `Dem.heights` (a `Bitree` then refuses
/// them unless it fills them itself). Raises `cota.ReadError` with the
/// message naming the file. The GIL is released while reading.
#[pyfunction]
#[pyo3(signature = (paths, fill = true))]
pub(crate) fn read(py: Python<'_>, paths: &Bound<'_, PyAny>, fill: bool) -> PyResult<Dem> {
    let paths: Vec<PathBuf> = match paths.extract::<PathBuf>() {
        Ok(p) => vec![p],
        Err(_) => paths.extract()?,
    };
    let opts = RegionOptions::DEFAULT.with_fill(if fill {
        Some(FillOptions::DEFAULT)
    } else {
        None
    });
    let region = py
        .detach(|| read_region(&paths, &opts))
        .map_err(errors::read)?;
    Ok(Dem {
        grid: Arc::new(region.grid),
        files: region
            .files
            .iter()
            .map(|f| f.path.display().to_string())
            .collect(),
        voids: region.voids,
        filled: fill,
        heights: OnceLock::new(),
    })
}

/// A DEM read by `cota.read`: heights in metres, georeference, voids.
#[pyclass(module = "cota", frozen)]
pub(crate) struct Dem {
    grid: Arc<HeightGrid>,
    files: Vec<String>,
    voids: usize,
    filled: bool,
    heights: OnceLock<Py<PyAny>>,
}

#[pymethods]
impl Dem {
    /// Heights in metres, float32, shape (rows, columns), row 0 north;
    /// read-only. NaN marks voids when read with `fill=False`.
    #[getter]
    fn heights(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        if let Some(a) = self.heights.get() {
            return Ok(a.clone_ref(py));
        }
        let (w, h) = (self.grid.width(), self.grid.height());
        let a = arrays::readonly_2d(py, self.grid.heights().to_vec(), h, w)?.unbind();
        Ok(self.heights.get_or_init(|| a).clone_ref(py))
    }

    /// Number of columns.
    #[getter]
    fn width(&self) -> usize {
        self.grid.width()
    }

    /// Number of rows.
    #[getter]
    fn height(&self) -> usize {
        self.grid.height()
    }

    /// Void samples of the joined grid before any fill (the files' voids and
    /// the samples no file covers).
    #[getter]
    fn voids(&self) -> usize {
        self.voids
    }

    /// Whether the voids were filled (`read(..., fill=True)`).
    #[getter]
    fn filled(&self) -> bool {
        self.filled
    }

    /// The files read, in input order.
    #[getter]
    fn files(&self) -> Vec<String> {
        self.files.clone()
    }

    /// Cell size in metres, (x, y), at the grid's centre.
    #[getter]
    fn cell_size_m(&self) -> (f64, f64) {
        let [dx, dy] = self.grid.cell_size_m();
        (dx, dy)
    }

    /// The georeference: `crs` (e.g. "EPSG:4326" or "unknown"), `origin_x`,
    /// `origin_y`, `pixel_x`, `pixel_y` (CRS units; `pixel_y` negative when
    /// rows go south), `pixel_is` ("area" or "point") and `known`.
    #[getter]
    fn georef<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let g = self.grid.georef();
        let d = PyDict::new(py);
        d.set_item("crs", g.crs.to_string())?;
        d.set_item("origin_x", g.origin_x)?;
        d.set_item("origin_y", g.origin_y)?;
        d.set_item("pixel_x", g.pixel_x)?;
        d.set_item("pixel_y", g.pixel_y)?;
        let pixel_is = match g.pixel_is {
            PixelIs::Area => "area",
            PixelIs::Point => "point",
        };
        d.set_item("pixel_is", pixel_is)?;
        d.set_item("known", g.known)?;
        Ok(d)
    }

    /// Builds the error hierarchy of this DEM (sharing its grid, no copy).
    /// Raises `cota.MeshError` if voids remain (read with `fill=False`).
    fn bitree(&self, py: Python<'_>) -> PyResult<bitree::Bitree> {
        bitree::Bitree::prepare(py, Arc::clone(&self.grid), 0)
    }

    fn __repr__(&self) -> String {
        format!(
            "Dem({}x{}, {} void(s){}, files={:?})",
            self.grid.width(),
            self.grid.height(),
            self.voids,
            if self.filled { " filled" } else { "" },
            self.files
        )
    }
}
