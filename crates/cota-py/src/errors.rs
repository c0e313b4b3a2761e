//! The Python exceptions: one base class, one subclass per stage. Each carries
//! the `Display` text of cota's error (which names the file and says what was
//! expected and what was found). Bad arguments (a wrong dtype or shape, an
//! empty array, an absurd size) are `TypeError` / `ValueError` instead.

use std::fmt::Display;

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::PyErr;

create_exception!(cota, CotaError, PyException, "Base class of cota's errors.");
create_exception!(
    cota,
    ReadError,
    CotaError,
    "A DEM file could not be read or joined."
);
create_exception!(
    cota,
    MeshError,
    CotaError,
    "A grid could not be prepared or meshed (voids refused, a grid too small, a bad bound or budget)."
);
create_exception!(
    cota,
    CheckError,
    CotaError,
    "The invariant checker found a violation (coverage, T-junction or the error bound)."
);
create_exception!(
    cota,
    WriteError,
    CotaError,
    "A mesh file could not be written."
);

/// A `ReadError` with `e`'s message.
pub(crate) fn read(e: impl Display) -> PyErr {
    ReadError::new_err(e.to_string())
}

/// A `MeshError` with `e`'s message.
pub(crate) fn mesh(e: impl Display) -> PyErr {
    MeshError::new_err(e.to_string())
}

/// A `CheckError` with `e`'s message.
pub(crate) fn check(e: impl Display) -> PyErr {
    CheckError::new_err(e.to_string())
}

/// A `WriteError` with `e`'s message.
pub(crate) fn write(e: impl Display) -> PyErr {
    WriteError::new_err(e.to_string())
}

/// A `ValueError` with `e`'s message.
pub(crate) fn value(e: impl Display) -> PyErr {
    pyo3::exceptions::PyValueError::new_err(e.to_string())
}
