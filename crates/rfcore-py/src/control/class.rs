//! The one trait every Python class of a Rust controller implements (its own file so that the
//! controllers' files and the registry in `control/mod.rs` both use it without importing each
//! other).

use pyo3::prelude::*;
use rfcore::control::Controller;

/// A Python class of a Rust controller: it gives the simulator a fresh core controller per run.
/// Implemented once by each class of the registry (`controller_registry!` in `control/mod.rs`).
pub(crate) trait ControllerClass {
    fn core(&self, py: Python<'_>) -> PyResult<Box<dyn Controller>>;
}
