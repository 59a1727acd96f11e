//! `fdem._core`: the native module behind the `fdem` Python package.
//!
//! This crate only converts: numpy arrays in, numpy copies out, Rust errors
//! into Python exceptions. It holds no physics. Every entry point runs inside
//! [`guard`], so a Rust panic surfaces as a `RuntimeError` (and poisons the
//! simulation) instead of crossing into Python as a `PanicException`.

mod convert;
mod functions;
mod simulation;

use std::panic::{catch_unwind, AssertUnwindSafe};

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

/// Runs `f`, turning a panic into a `RuntimeError`.
pub(crate) fn guard<T>(f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(payload) => {
            let msg = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown panic".into());
            Err(PyRuntimeError::new_err(format!("internal error in the fdem kernel: {msg} (please report this)")))
        }
    }
}

/// The native module.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<simulation::PySimulation>()?;
    m.add_function(wrap_pyfunction!(functions::validate_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(functions::material_point, m)?)?;
    m.add_function(wrap_pyfunction!(functions::triangulate, m)?)?;
    m.add_function(wrap_pyfunction!(functions::split_along_edges, m)?)?;
    m.add_function(wrap_pyfunction!(functions::_panic_selftest, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
