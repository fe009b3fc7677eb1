//! Python bindings for rfcore (module `rotorfault._rfcore`): translation only, one file per core
//! room (`analysis`, `allocation`, `control`, `flight`, plus `airframe`) and one `convert` for
//! the helpers they share. Arrays come in as read-only numpy views, heavy calls run with the GIL
//! released (`convert::detached`, which also turns Ctrl-C into a cancelled call and a
//! `KeyboardInterrupt`), and every core error becomes a `ValueError` carrying the core's message,
//! which names the field and the rule.

mod airframe;
mod allocation;
mod analysis;
mod control;
mod convert;
mod flight;
mod recording;
mod sensing;
mod summary;
mod trajectory;

use pyo3::prelude::*;

#[pymodule]
fn _rfcore(module: &Bound<'_, PyModule>) -> PyResult<()> {
    convert::prepare_threads(module.py())?;
    module.add_class::<airframe::PyAirframe>()?;
    module.add_class::<analysis::PyControllabilityReport>()?;
    module.add_class::<analysis::PyFailureCase>()?;
    module.add_class::<analysis::PyAcaiResult>()?;
    module.add_class::<analysis::PyAcaiBatch>()?;
    module.add_class::<allocation::PyAllocationBatch>()?;
    module.add_class::<allocation::PyDirectionalLimit>()?;
    module.add_class::<allocation::PyHoverMargin>()?;
    module.add_class::<flight::PyFixedPitch>()?;
    module.add_class::<flight::PyDrag>()?;
    module.add_class::<flight::PyDivergenceLimits>()?;
    module.add_class::<flight::PySensorNoise>()?;
    module.add_class::<flight::PySimulationConfig>()?;
    module.add_class::<sensing::PySensing>()?;
    module.add_class::<trajectory::PySensingCounts>()?;
    module.add_class::<trajectory::PyTrajectory>()?;
    module.add_class::<trajectory::PyDivergence>()?;
    module.add_class::<trajectory::PyEstimates>()?;
    module.add_class::<control::ke::PyKeGains>()?;
    module.add_class::<control::ke::PyFtcPreset>()?;
    module.add_class::<flight::PyVariablePitch>()?;
    module.add_class::<flight::PyVariablePitchPreset>()?;
    module.add_class::<allocation::PyAllocationProblem>()?;
    module.add_class::<allocation::PyAllocationSettings>()?;
    module.add_class::<allocation::PyCertificate>()?;
    module.add_class::<allocation::PySingleAllocation>()?;
    module.add_class::<control::lanzon::PyLanzonModel>()?;
    module.add_class::<control::lanzon::PyLanzonOuterLoop>()?;
    module.add_class::<control::lanzon::PyLanzonVehicle>()?;
    module.add_class::<control::indi::PyIndiGains>()?;
    module.add_class::<control::indi::PyIndiFailureMode>()?;
    // The Rust controllers, declared once in `control::controller_registry!`: each class, and
    // `CONTROLLERS`, the `(name, class)` pairs Python derives its lists from.
    let controllers = control::registry(module.py());
    for (_, class) in &controllers {
        module.add(class.name()?, class)?;
    }
    module.add("CONTROLLERS", pyo3::types::PyTuple::new(module.py(), controllers)?)?;
    module.add_function(wrap_pyfunction!(control::replay, module)?)?;
    module.add_function(wrap_pyfunction!(allocation::allocate, module)?)?;
    module.add_function(wrap_pyfunction!(analysis::scale_free_rank, module)?)?;
    module.add_function(wrap_pyfunction!(allocation::time_allocations, module)?)?;
    module.add_function(wrap_pyfunction!(allocation::max_along_direction, module)?)?;
    module.add_function(wrap_pyfunction!(allocation::hover_thrust_margin, module)?)?;
    module.add_function(wrap_pyfunction!(flight::simulate, module)?)?;
    module.add_function(wrap_pyfunction!(flight::simulate_batch, module)?)?;
    module.add_function(wrap_pyfunction!(flight::state_derivative, module)?)?;
    module.add_class::<recording::PyBatchColumns>()?;
    module.add_function(wrap_pyfunction!(recording::simulate_batch_columns, module)?)?;
    module.add_class::<summary::PyVerdictCriteria>()?;
    module.add_class::<summary::PySummaryBatch>()?;
    module.add_function(wrap_pyfunction!(summary::simulate_summaries, module)?)?;
    module.add_function(wrap_pyfunction!(analysis::acai, module)?)?;
    module.add_function(wrap_pyfunction!(analysis::acai_batch, module)?)?;
    module.add_function(wrap_pyfunction!(analysis::acai_batch_with_hover, module)?)?;
    module.add_function(wrap_pyfunction!(analysis::acai_from_matrix, module)?)?;
    module.add_function(wrap_pyfunction!(analysis::controllability, module)?)?;
    module.add_function(wrap_pyfunction!(analysis::failure_table, module)?)?;
    module.add_function(wrap_pyfunction!(analysis::_controllability_report, module)?)?;
    module.add_function(wrap_pyfunction!(analysis::_failure_case, module)?)?;
    module.add_function(wrap_pyfunction!(analysis::format_acai, module)?)?;
    module.add_function(wrap_pyfunction!(analysis::acai_label, module)?)?;
    module.add_class::<analysis::relaxed_hover::PyRelaxedHoverSettings>()?;
    module.add_class::<analysis::relaxed_hover::PyRelaxedHoverSolution>()?;
    module.add_class::<analysis::relaxed_hover::PyRelaxedHoverAnalysis>()?;
    module.add_function(wrap_pyfunction!(analysis::relaxed_hover::relaxed_hover, module)?)?;
    module.add_function(wrap_pyfunction!(analysis::relaxed_hover::relaxed_hover_residual, module)?)?;
    module.add_class::<control::relaxed_hover::PyRelaxedHoverOuterLoop>()?;
    module.add("RANK_RTOL", rfcore::analysis::RANK_RTOL)?;
    module.add("ZERO_RTOL", rfcore::analysis::ZERO_RTOL)?;
    module.add("DEFAULT_GRAVITY_M_S2", rfcore::DEFAULT_GRAVITY_M_S2)?;
    module.add(
        "MAX_RATE_STEP",
        rfcore::flight::simulation::MAX_RATE_STEP,
    )?;
    module.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
