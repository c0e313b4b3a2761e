//! numpy in and out.
//!
//! In: a 2-D array of heights in metres (rows × columns, row 0 north) of
//! dtype float32, float64 or int16, C-ordered or not (any strides: the values
//! are read in logical order). float64 is rounded to the nearest float32 (the
//! grid's type); int16 is exact. NaN marks a void; with `nodata`, samples equal
//! to it are voids too. ±∞ is refused by `HeightGrid::new`.
//!
//! Out: read-only numpy arrays owning a copy of the result (the arrays are
//! built once per object and cached by the caller).

use numpy::{PyArray1, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;

/// Heights taken from a numpy array, row-major.
pub(crate) struct Heights {
    pub width: usize,
    pub height: usize,
    pub values: Vec<f32>,
}

/// Reads a 2-D float32/float64/int16 array into row-major `f32` heights.
///
/// # Errors
/// `TypeError` for anything but such an array, `ValueError` for another
/// number of dimensions or an empty array.
pub(crate) fn heights_from(obj: &Bound<'_, PyAny>, nodata: Option<f64>) -> PyResult<Heights> {
    if let Ok(a) = obj.cast::<PyArrayDyn<f32>>() {
        collect(a, |v| v, nodata)
    } else if let Ok(a) = obj.cast::<PyArrayDyn<f64>>() {
        collect(a, |v| v as f32, nodata)
    } else if let Ok(a) = obj.cast::<PyArrayDyn<i16>>() {
        collect(a, f32::from, nodata)
    } else {
        Err(PyTypeError::new_err(format!(
            "expected a numpy array of heights with dtype float32, float64 or int16 (native byte \
             order), found {}",
            describe(obj)
        )))
    }
}

/// What `obj` is, for an error message: its dtype if it has one, else its type.
fn describe(obj: &Bound<'_, PyAny>) -> String {
    match obj.getattr("dtype") {
        Ok(d) => format!(
            "dtype {}",
            d.str().map(|s| s.to_string()).unwrap_or_default()
        ),
        Err(_) => format!(
            "a {}",
            obj.get_type()
                .name()
                .map(|s| s.to_string())
                .unwrap_or_default()
        ),
    }
}

/// The values of a 2-D array in logical (row-major) order, converted.
fn collect<T: numpy::Element + Copy>(
    a: &Bound<'_, PyArrayDyn<T>>,
    to_f32: impl Fn(T) -> f32,
    nodata: Option<f64>,
) -> PyResult<Heights> {
    let shape = a.shape().to_vec();
    if shape.len() != 2 {
        return Err(PyValueError::new_err(format!(
            "expected a 2-D array of heights (rows x columns), found {} dimension(s) with shape {:?}",
            shape.len(),
            shape
        )));
    }
    let (height, width) = (shape[0], shape[1]);
    if width == 0 || height == 0 {
        return Err(PyValueError::new_err(format!(
            "expected a non-empty array of heights, found shape ({height}, {width})"
        )));
    }
    let ro = a.try_readonly()?;
    let view = ro.as_array();
    let nodata = nodata.map(|v| v as f32);
    let values = view
        .iter()
        .map(|&v| {
            let h = to_f32(v);
            if Some(h) == nodata {
                f32::NAN
            } else {
                h
            }
        })
        .collect();
    Ok(Heights {
        width,
        height,
        values,
    })
}

/// A read-only `rows × cols` numpy array owning `values` (no copy of them).
pub(crate) fn readonly_2d<'py, T: numpy::Element>(
    py: Python<'py>,
    values: Vec<T>,
    rows: usize,
    cols: usize,
) -> PyResult<Bound<'py, PyAny>> {
    let a = PyArray1::from_vec(py, values).reshape([rows, cols])?;
    a.call_method1("setflags", (false,))?;
    Ok(a.into_any())
}

/// `obj` as a C-ordered 2-D array of `dtype` (numpy's `ascontiguousarray`).
fn as_2d<'py, T: numpy::Element>(
    py: Python<'py>,
    obj: &Bound<'py, PyAny>,
    dtype: &str,
    what: &str,
) -> PyResult<Bound<'py, numpy::PyArray2<T>>> {
    let np = py.import("numpy")?;
    let a = np.call_method1("ascontiguousarray", (obj, dtype))?;
    a.cast_into::<numpy::PyArray2<T>>()
        .map_err(|_| PyValueError::new_err(format!("expected {what} as a 2-D array")))
}

/// A mesh of `grid` from foreign arrays: vertices on samples (column, row in
/// the first two columns), heights from the grid, triangles as indices.
pub(crate) fn foreign_mesh(
    py: Python<'_>,
    grid: &cota_core::HeightGrid,
    vertices: &Bound<'_, PyAny>,
    triangles: &Bound<'_, PyAny>,
) -> PyResult<cota_core::Mesh> {
    let v = as_2d::<f64>(py, vertices, "float64", "vertices")?;
    let t = as_2d::<i64>(py, triangles, "int64", "triangles")?;
    let (v, t) = (v.try_readonly()?, t.try_readonly()?);
    let (v, t) = (v.as_array(), t.as_array());
    if v.ncols() < 2 || t.ncols() != 3 {
        return Err(PyValueError::new_err(format!(
            "expected vertices (n, 2 or 3) and triangles (m, 3), found {:?} and {:?}",
            v.shape(),
            t.shape()
        )));
    }
    let vertices = on_samples(grid, v)?;
    let triangles = indices_below(t, vertices.len())?;
    Ok(cota_core::Mesh {
        vertices,
        triangles,
    })
}

/// Each row's column and row as a vertex on its sample, with its height.
fn on_samples(
    grid: &cota_core::HeightGrid,
    v: numpy::ndarray::ArrayView2<'_, f64>,
) -> PyResult<Vec<cota_core::MeshVertex>> {
    let (w, h) = (grid.width() as f64, grid.height() as f64);
    let mut out = Vec::with_capacity(v.nrows());
    for (i, r) in v.outer_iter().enumerate() {
        let (c, row) = (r[0], r[1]);
        let on_grid = (0.0..w).contains(&c) && (0.0..h).contains(&row);
        if !on_grid || c.fract() != 0.0 || row.fract() != 0.0 {
            return Err(PyValueError::new_err(format!(
                "expected vertex {i} on a sample of the {w}x{h} grid, found ({c}, {row})"
            )));
        }
        let (col, row) = (c as u32, row as u32);
        let z_m = grid.get(col as usize, row as usize);
        out.push(cota_core::MeshVertex { col, row, z_m });
    }
    Ok(out)
}

/// Each row as a triangle of indices below `n`.
fn indices_below(t: numpy::ndarray::ArrayView2<'_, i64>, n: usize) -> PyResult<Vec<[u32; 3]>> {
    let n = n as i64;
    let mut out = Vec::with_capacity(t.nrows());
    for (i, r) in t.outer_iter().enumerate() {
        if r.iter().any(|&k| !(0..n).contains(&k)) {
            return Err(PyValueError::new_err(format!(
                "expected triangle {i}'s indices below {n}, found {:?}",
                r.to_vec()
            )));
        }
        out.push([r[0] as u32, r[1] as u32, r[2] as u32]);
    }
    Ok(out)
}
