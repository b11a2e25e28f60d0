//! `surftrack._surftrack`: the Python bindings (the `surftrack` package re-exports them).
//!
//! A thin layer over the `surftrack` facade: arrays are checked into meshes and
//! proposals ([`convert`]), [`surftrack::Tracker`] runs either backend with named
//! attributes, options by name go through the harness's options-as-data
//! (`bench_harness::options`), scenes through `bench_harness::scenes`, repair through
//! `grid_tracker::fix_with`. No algorithm lives here. Every call that computes releases
//! the GIL, and every call runs under [`convert::guarded`], so no Rust panic reaches
//! Python.
#![forbid(unsafe_code)]

mod convert;
mod mesh;
mod tracker;

use pyo3::prelude::*;

/// The extension module.
#[pymodule]
fn _surftrack(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<mesh::PyMesh>()?;
    m.add_class::<mesh::PyValidationReport>()?;
    m.add_class::<mesh::PyFixReport>()?;
    m.add_class::<tracker::PyTracker>()?;
    m.add_class::<tracker::PyStepReport>()?;
    m.add_function(wrap_pyfunction!(mesh::generate, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::fix, m)?)?;
    m.add_function(wrap_pyfunction!(tracker::option_names, m)?)?;
    m.add("TrackError", m.py().get_type::<convert::TrackError>())?;
    m.add(
        "BACKENDS",
        surftrack::Backend::ALL.map(|b| b.name()).to_vec(),
    )?;
    Ok(())
}
