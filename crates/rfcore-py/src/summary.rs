//! Bindings for per-run summaries (campaigns): the verdict criteria, a columnar batch of
//! summaries, and `simulate_summaries`, each run with its own vehicle, actuators, settings and
//! setpoint. Translation only.

use nalgebra::Vector3;
use numpy::{IntoPyArray, PyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use rfcore::flight::simulation::RotorFault;
use rfcore::flight::summary::{
    simulate_summaries as core_summaries, RunSummary, SummaryRun, VerdictCriteria,
};
use rfcore::flight::vehicle::Vehicle;
use rfcore::state::RigidBodyState;

use crate::airframe::PyAirframe;
use crate::control::{boxed, ControllerArg};
use crate::convert::{detached, pickle_protocol, to_py_err};
use crate::flight::{build_actuators, ActuatorArg, PyDrag, PySimulationConfig};

/// The verdict thresholds; defaults are the core's (`VerdictCriteria::default`).
#[pyclass(name = "VerdictCriteria", module = "rotorfault._rfcore", frozen)]
pub struct PyVerdictCriteria {
    pub(crate) inner: VerdictCriteria,
}

impl PyVerdictCriteria {
    const FIELDS: &'static [&'static str] =
        &["window_s", "hold_horizontal_m", "hold_altitude_m", "hold_speed_m_s", "circling_turn_rad", "spin_growth_span_s"];
}

pickle_protocol!(PyVerdictCriteria, {
    #[new]
    #[pyo3(signature = (*, window_s=None, hold_horizontal_m=None, hold_altitude_m=None, hold_speed_m_s=None, circling_turn_rad=None, spin_growth_span_s=None))]
    fn new(
        window_s: Option<f64>,
        hold_horizontal_m: Option<f64>,
        hold_altitude_m: Option<f64>,
        hold_speed_m_s: Option<f64>,
        circling_turn_rad: Option<f64>,
        spin_growth_span_s: Option<f64>,
    ) -> PyResult<Self> {
        let d = VerdictCriteria::default();
        let inner = VerdictCriteria {
            window_s: window_s.unwrap_or(d.window_s),
            hold_horizontal_m: hold_horizontal_m.unwrap_or(d.hold_horizontal_m),
            hold_altitude_m: hold_altitude_m.unwrap_or(d.hold_altitude_m),
            hold_speed_m_s: hold_speed_m_s.unwrap_or(d.hold_speed_m_s),
            circling_turn_rad: circling_turn_rad.unwrap_or(d.circling_turn_rad),
            spin_growth_span_s: spin_growth_span_s.unwrap_or(d.spin_growth_span_s),
        };
        inner.check().map_err(to_py_err)?;
        Ok(PyVerdictCriteria { inner })
    }
    #[getter]
    fn window_s(&self) -> f64 {
        self.inner.window_s
    }
    #[getter]
    fn hold_horizontal_m(&self) -> f64 {
        self.inner.hold_horizontal_m
    }
    #[getter]
    fn hold_altitude_m(&self) -> f64 {
        self.inner.hold_altitude_m
    }
    #[getter]
    fn hold_speed_m_s(&self) -> f64 {
        self.inner.hold_speed_m_s
    }
    #[getter]
    fn circling_turn_rad(&self) -> f64 {
        self.inner.circling_turn_rad
    }
    #[getter]
    fn spin_growth_span_s(&self) -> f64 {
        self.inner.spin_growth_span_s
    }
});

/// Summaries of a batch, one entry per run in input order, as columns.
#[pyclass(name = "SummaryBatch", module = "rotorfault._rfcore", frozen)]
pub struct PySummaryBatch {
    runs: Vec<RunSummary>,
}

macro_rules! column {
    ($($name:ident),*) => {
        #[pymethods]
        impl PySummaryBatch {
            /// Outcome codes (`holds-position`, `circling`, `off-station` or a divergence kind;
            /// the codes before the verdicts, kept for one release).
            #[getter]
            fn outcome(&self) -> Vec<&'static str> {
                self.runs.iter().map(|r| r.outcome.name()).collect()
            }
            /// Verdicts (`holds`, `drifts`, `circles`, `crashed`, `diverged`), decided by the core.
            #[getter]
            fn verdict(&self) -> Vec<&'static str> {
                self.runs.iter().map(|r| r.outcome.verdict().name()).collect()
            }
            /// How each lost run was lost (the divergence kind); an empty string for a run flown
            /// to the end.
            #[getter]
            fn cause(&self) -> Vec<&'static str> {
                self.runs.iter().map(|r| r.outcome.cause().unwrap_or("")).collect()
            }
            fn __len__(&self) -> usize {
                self.runs.len()
            }
            $(
                #[getter]
                fn $name<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
                    self.runs.iter().map(|r| r.$name).collect::<Vec<f64>>().into_pyarray(py)
                }
            )*
        }
    };
}

column!(
    lost_at_s,
    time_to_loss_s,
    max_altitude_loss_m,
    max_horizontal_error_m,
    final_horizontal_error_m,
    final_altitude_error_m,
    window_horizontal_error_m,
    window_altitude_error_m,
    window_speed_m_s,
    window_mean_horizontal_speed_m_s,
    peak_tilt_rad,
    steady_spin_rad_s,
    steady_n3z,
    window_spin_growth_rad_s,
    window_final_spin_rad_s,
    peak_command,
    saturated_s,
    flown_s
);

/// Many runs in parallel, keeping only their summaries; every list has one entry per run.
#[pyfunction]
#[allow(clippy::too_many_arguments)]
pub fn simulate_summaries<'py>(
    py: Python<'py>,
    airframes: Vec<PyRef<'py, PyAirframe>>,
    actuators: Vec<ActuatorArg<'py>>,
    drags: Vec<PyRef<'py, PyDrag>>,
    controllers: Vec<Option<ControllerArg<'py>>>,
    x0s: Vec<[f64; 13]>,
    fault_lists: Vec<Vec<(usize, f64, f64)>>,
    settles: Vec<Option<Vec<f64>>>,
    configs: Vec<PyRef<'py, PySimulationConfig>>,
    setpoints: Vec<[f64; 3]>,
    criteria: PyRef<'py, PyVerdictCriteria>,
) -> PyResult<PySummaryBatch> {
    let n = airframes.len();
    if [
        actuators.len(),
        drags.len(),
        controllers.len(),
        x0s.len(),
        fault_lists.len(),
        settles.len(),
        configs.len(),
        setpoints.len(),
    ]
    .iter()
    .any(|&k| k != n)
    {
        return Err(PyValueError::new_err(
            "runs: airframes, actuators, drags, controllers, initial states, fault lists, initial commands, configs and setpoints must have one entry per run",
        ));
    }
    let mut runs = Vec::with_capacity(n);
    for i in 0..n {
        let airframe = &airframes[i];
        let mut actuator = build_actuators(airframe, &actuators[i]).map_err(to_py_err)?;
        if let Some(command) = &settles[i] {
            actuator.settle(command).map_err(to_py_err)?;
        }
        let count = actuator.channels() * airframe.inner.rotor_count();
        runs.push(SummaryRun {
            vehicle: Vehicle::new(&airframe.inner, drags[i].inner).map_err(to_py_err)?,
            actuators: actuator,
            controller: boxed(controllers[i].as_ref(), count)?,
            initial_efficiency: airframe.inner.efficiency(),
            faults: fault_lists[i]
                .iter()
                .map(|&(rotor, time_s, efficiency)| RotorFault {
                    rotor,
                    time_s,
                    efficiency,
                })
                .collect(),
            x0: RigidBodyState::from_packed(&x0s[i]),
            config: configs[i].inner.clone(),
            setpoint_m: Vector3::from(setpoints[i]),
        });
    }
    let criteria = criteria.inner;
    let runs = detached(py, |cancel| core_summaries(runs, &criteria, cancel))?;
    Ok(PySummaryBatch { runs })
}
