//! Bindings for one run's record: the `Trajectory` (the one trajectory type, subclassed by
//! `rotorfault.Trajectory`), its `Divergence` and its `SensingCounts`. Translation and shape
//! checks only; the record is the core's (`rfcore::flight::simulation::Trajectory`).

use numpy::{IntoPyArray, PyArray1, PyArrayMethods, PyUntypedArray, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PySlice, PyType};

use rfcore::flight::simulation::{Divergence, DivergenceKind, EstimateRow, SensingRecord, Trajectory};
use rfcore::state::{state_from_vector, state_vector, RigidBodyState, STATE_DIM};

use crate::convert::{deprecated, fixed_reals, pickle_protocol, read_only, real};

/// Why and when a run ended early: `time_s`, the `kind` (kebab-case: `crashed`, `tilt`, ...) and
/// the 12-element state vector at that moment (`rotorfault.Divergence`: the core's, used directly;
/// no Python copy). What follows from them is derived, not stored: the `description` of the kind
/// and, for a `crashed` run, the impact (speed, speed into the ground, tilt; else `None`), by the
/// core's `Divergence::impact`. Made by the simulator, or keyword-only from Python (a
/// constructed run's event): `time_s` finite, `kind` one of the core's, `state` 12 numbers.
///
/// Examples:
///
///     >>> import rotorfault as rf
///     >>> sim = rf.Simulator(rf.Airframe.preset("quad-x"))
///     >>> event = sim.run(rf.State(position=(0, 0, -1)), 3.0).divergence
///     >>> event.kind, round(event.time_s, 3), round(event.impact_speed_m_s, 3)
///     ('crashed', 0.452, 4.427)
#[pyclass(name = "Divergence", module = "rotorfault._rfcore", frozen)]
pub struct PyDivergence {
    time_s: f64,
    kind: DivergenceKind,
    state: [f64; STATE_DIM],
}

/// A finite real number for `field`.
fn finite_real(field: &str, value: &Bound<'_, PyAny>) -> PyResult<f64> {
    let x = real(field, value)?;
    if !x.is_finite() {
        return Err(PyValueError::new_err(format!("{field}: must be finite, got {x}")));
    }
    Ok(x)
}

/// How far a deprecated impact argument may lie from the derived impact (m/s or rad): a pickle of
/// the release that stored them carries the tilt computed from the quaternion, this one derives
/// it from the Euler angles of `state` (the same angle to rounding).
const IMPACT_AGREEMENT: f64 = 1e-6;

impl PyDivergence {
    const FIELDS: &'static [&'static str] = &["time_s", "kind", "state"];

    /// The core's divergence (the state from its vector): what the derived fields read.
    fn core(&self) -> Divergence {
        Divergence { time_s: self.time_s, kind: self.kind, state: state_from_vector(&self.state) }
    }

    /// The kind named `name`, or a `ValueError` listing the kinds.
    fn kind_named(field: &str, name: &str) -> PyResult<DivergenceKind> {
        DivergenceKind::from_name(name).ok_or_else(|| {
            let kinds: Vec<&str> = DivergenceKind::ALL.iter().map(|k| k.name()).collect();
            PyValueError::new_err(format!("{field}: expected one of {}, got {name:?}", kinds.join(", ")))
        })
    }

    /// A deprecated argument that is now derived: it must say what the derivation says.
    fn agrees(&self, py: Python<'_>, field: &str, given: Option<Bound<'_, PyAny>>, derived: Option<f64>) -> PyResult<()> {
        let Some(given) = given else { return Ok(()) };
        deprecated(py, &format!("Divergence({field}=...)"), &format!("Divergence.{field}, derived from kind and state"))?;
        let value = finite_real(field, &given)?;
        match derived {
            None => Err(PyValueError::new_err(format!(
                "{field}: only a crashed run has an impact, this one is {}, got {value:?}",
                self.kind.name()
            ))),
            Some(d) if (value - d).abs() > IMPACT_AGREEMENT => Err(PyValueError::new_err(format!(
                "{field}: derived from state as {d:?}, got {value:?} (they must agree within {IMPACT_AGREEMENT:?})"
            ))),
            Some(_) => Ok(()),
        }
    }
}

pickle_protocol!(PyDivergence, {
    #[new]
    #[pyo3(signature = (*, time_s, kind=None, state, description=None, impact_speed_m_s=None,
        impact_vertical_speed_m_s=None, impact_tilt_rad=None, reason=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        time_s: Bound<'_, PyAny>,
        kind: Option<Bound<'_, PyAny>>,
        state: Bound<'_, PyAny>,
        description: Option<Bound<'_, PyAny>>,
        impact_speed_m_s: Option<Bound<'_, PyAny>>,
        impact_vertical_speed_m_s: Option<Bound<'_, PyAny>>,
        impact_tilt_rad: Option<Bound<'_, PyAny>>,
        reason: Option<Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let (field, kind) = match (kind, reason) {
            (Some(_), Some(_)) => return Err(PyTypeError::new_err("Divergence: give kind or the deprecated reason, not both")),
            (None, None) => return Err(PyTypeError::new_err("kind: required (the kind of divergence: crashed, tilt, ...)")),
            (Some(kind), None) => ("kind", kind),
            (None, Some(reason)) => {
                deprecated(py, "Divergence(reason=...)", "Divergence(kind=...)")?;
                ("reason", reason)
            }
        };
        let name: String = kind
            .extract()
            .map_err(|_| PyTypeError::new_err(format!("{field}: expected a string, got {}", kind.get_type().name().map(|n| n.to_string()).unwrap_or_default())))?;
        let this = PyDivergence {
            time_s: finite_real("time_s", &time_s)?,
            kind: Self::kind_named(field, &name)?,
            state: fixed_reals::<STATE_DIM>("state", "the 12-element state vector", &state)?,
        };
        if let Some(description) = description {
            deprecated(py, "Divergence(description=...)", "Divergence.description, derived from kind")?;
            let text: String = description.extract().map_err(|_| PyTypeError::new_err("description: expected a string"))?;
            if text != this.kind.describe() {
                return Err(PyValueError::new_err(format!(
                    "description: derived from kind {:?} as {:?}, got {text:?}",
                    this.kind.name(),
                    this.kind.describe()
                )));
            }
        }
        let impact = this.core().impact();
        this.agrees(py, "impact_speed_m_s", impact_speed_m_s, impact.map(|i| i.speed_m_s))?;
        this.agrees(py, "impact_vertical_speed_m_s", impact_vertical_speed_m_s, impact.map(|i| i.vertical_speed_m_s))?;
        this.agrees(py, "impact_tilt_rad", impact_tilt_rad, impact.map(|i| i.tilt_rad))?;
        Ok(this)
    }
    /// When the run ended, s.
    #[getter]
    fn time_s(&self) -> f64 {
        self.time_s
    }
    /// Why: a kebab-case code (`"crashed"`, `"tilt"`, `"non-finite-state"`, ...).
    #[getter]
    fn kind(&self) -> &'static str {
        self.kind.name()
    }
    /// The 12-element state vector when the run ended (read-only).
    #[getter]
    fn state<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        read_only(py, self.state.to_vec())
    }
    /// The kind in words.
    #[getter]
    fn description(&self) -> &'static str {
        self.kind.describe()
    }
    /// A crashed run's speed at contact, m/s (else `None`).
    #[getter]
    fn impact_speed_m_s(&self) -> Option<f64> {
        self.core().impact().map(|i| i.speed_m_s)
    }
    /// A crashed run's speed into the ground (NED down), m/s (else `None`).
    #[getter]
    fn impact_vertical_speed_m_s(&self) -> Option<f64> {
        self.core().impact().map(|i| i.vertical_speed_m_s)
    }
    /// A crashed run's tilt at contact (body z from vertical), rad (else `None`).
    #[getter]
    fn impact_tilt_rad(&self) -> Option<f64> {
        self.core().impact().map(|i| i.tilt_rad)
    }
    /// Deprecated name of `time_s` (the `Event`'s).
    #[getter]
    fn time(&self, py: Python<'_>) -> PyResult<f64> {
        deprecated(py, "Divergence.time", "Divergence.time_s")?;
        Ok(self.time_s)
    }
    /// Deprecated name of `kind` (the core's `Divergence`'s before it was used directly).
    #[getter]
    fn reason(&self, py: Python<'_>) -> PyResult<&'static str> {
        deprecated(py, "Divergence.reason", "Divergence.kind")?;
        Ok(self.kind.name())
    }
    fn __repr__(slf: &Bound<'_, Self>) -> PyResult<String> {
        let this = slf.get();
        Ok(format!("{}(time_s={:?}, kind='{}')", slf.get_type().name()?, this.time_s, this.kind.name()))
    }
    /// `crashed at t = <s> s: hit the ground at <speed> m/s (<down> m/s down), tilted <deg> deg`,
    /// or `diverged at t = <s> s: <description>`.
    fn __str__(&self) -> String {
        match self.core().impact() {
            Some(i) => format!(
                "crashed at t = {:.4} s: {} at {:.2} m/s ({:.2} m/s down), tilted {:.1} deg",
                self.time_s,
                self.kind.describe(),
                i.speed_m_s,
                i.vertical_speed_m_s,
                i.tilt_rad.to_degrees()
            ),
            None => format!("diverged at t = {:.4} s: {}", self.time_s, self.kind.describe()),
        }
    }
});

impl From<Divergence> for PyDivergence {
    fn from(d: Divergence) -> Self {
        PyDivergence { time_s: d.time_s, kind: d.kind, state: state_vector(&d.state) }
    }
}

/// The sensor counts class from one list of its fields (each a `u64`): first the fields every
/// release has had (required), then each added field with the default an older pickle loads with
/// (a pickle gives the fields of its own release by keyword, so an added field needs one).
macro_rules! counts_class {
    ($($name:ident),+ ; $($added:ident = $default:literal),* $(,)?) => {
        /// A run's sensor counts (`Trajectory.sensing_counts`); keyword-only from Python (pickling).
        /// `thinned_measurements` is 0 when not given: a pickle made before fixes were thinned
        /// (that release fused every fix).
        #[pyclass(name = "SensingCounts", module = "rotorfault._rfcore", frozen, get_all)]
        pub struct PySensingCounts {
            $($name: u64,)+
            $($added: u64,)*
        }

        impl PySensingCounts {
            const FIELDS: &'static [&'static str] = &[$(stringify!($name),)+ $(stringify!($added),)*];
        }

        pickle_protocol!(PySensingCounts, {
            #[new]
            #[pyo3(signature = (*, $($name,)+ $($added = $default,)*))]
            fn new($($name: u64,)+ $($added: u64,)*) -> Self {
                PySensingCounts { $($name,)+ $($added,)* }
            }
        });
    };
}

counts_class!(
    imu_samples,
    gyro_saturated_samples,
    accel_saturated_samples,
    fused_measurements,
    rejected_measurements,
    late_measurements;
    thinned_measurements = 0,
);

impl From<&SensingRecord> for PySensingCounts {
    fn from(r: &SensingRecord) -> Self {
        PySensingCounts {
            imu_samples: r.imu_samples,
            gyro_saturated_samples: r.gyro_saturated_samples,
            accel_saturated_samples: r.accel_saturated_samples,
            fused_measurements: r.fusion.fused,
            rejected_measurements: r.fusion.rejected,
            late_measurements: r.fusion.late,
            thinned_measurements: r.fusion.thinned,
        }
    }
}

/// What the estimator gave the controller, one row per recorded control step beside the truth of
/// the same row (a run with `rotorfault.Sensing`; `Trajectory.estimate`): the estimate at the
/// newest IMU sample carried to the control time; the divergence row is NaN (no command was
/// computed). The core's record used directly (no Python copy): `state` packs the estimate
/// (position m, velocity m/s, quaternion `w x y z`, body rates rad/s; 13 columns), read as
/// `position`, `velocity`, `quaternion`, `omega` (views), with `euler` (rad), `std` (one sigma of
/// the filter's 15-element error state: position m, velocity m/s, attitude rad, gyro bias rad/s,
/// accelerometer bias m/s^2, at its fusion horizon; `position_std_m`, `velocity_std_m_s`,
/// `attitude_std_rad` are its blocks), `gyro_saturated` / `accel_saturated` (rows whose newest IMU
/// sample was clamped at the range) and `counts` (the run's totals: IMU samples, clamped samples,
/// measurements fused, refused by the innovation gate, late). Keyword-only from Python (the
/// estimate's parts, as before); frozen; picklable.
///
/// Examples:
///
///     >>> import rotorfault as rf
///     >>> sim = rf.Simulator(rf.Airframe.preset("quad-x"), sensing=rf.Sensing(suite="mocap"))
///     >>> run = sim.run(rf.State(position=(0, 0, -1)), 0.2, controller=rf.lqr_hover(sim, position=(0, 0, -1)))
///     >>> run.estimate.position.shape == run.position.shape
///     True
#[pyclass(name = "Estimates", module = "rotorfault._rfcore", frozen)]
pub struct PyEstimates {
    state: Py<PyAny>,
    euler: Py<PyAny>,
    std: Py<PyAny>,
    gyro_saturated: Py<PyAny>,
    accel_saturated: Py<PyAny>,
    counts: Py<PySensingCounts>,
}

/// Columns `from..to` of a table (a view).
fn columns<'py>(table: &Bound<'py, PyAny>, from: isize, to: isize) -> PyResult<Bound<'py, PyAny>> {
    let py = table.py();
    table.get_item((PySlice::full(py), PySlice::new(py, from, to, 1)))
}

impl PyEstimates {
    const FIELDS: &'static [&'static str] = &[
        "position", "velocity", "quaternion", "euler", "omega", "std", "gyro_saturated", "accel_saturated", "counts",
    ];
}

pickle_protocol!(PyEstimates, {
    #[new]
    #[pyo3(signature = (*, position, velocity, quaternion, euler, omega, std, gyro_saturated, accel_saturated, counts))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        position: Bound<'_, PyAny>,
        velocity: Bound<'_, PyAny>,
        quaternion: Bound<'_, PyAny>,
        euler: Bound<'_, PyAny>,
        omega: Bound<'_, PyAny>,
        std: Bound<'_, PyAny>,
        gyro_saturated: Bound<'_, PyAny>,
        accel_saturated: Bound<'_, PyAny>,
        counts: Py<PySensingCounts>,
    ) -> PyResult<Self> {
        shaped("position", &position, 2, None, &[3])?;
        let rows = Some(position.len()?);
        for (field, value, ndim, width) in [
            ("velocity", &velocity, 2, 3),
            ("quaternion", &quaternion, 2, 4),
            ("euler", &euler, 2, 3),
            ("omega", &omega, 2, 3),
            ("std", &std, 2, 15),
            ("gyro_saturated", &gyro_saturated, 1, 1),
            ("accel_saturated", &accel_saturated, 1, 1),
        ] {
            shaped(field, value, ndim, rows, &[width])?;
        }
        let packed = py.import("numpy")?.getattr("hstack")?.call1(([position, velocity, quaternion, omega],))?;
        Ok(PyEstimates {
            state: packed.unbind(),
            euler: euler.unbind(),
            std: std.unbind(),
            gyro_saturated: gyro_saturated.unbind(),
            accel_saturated: accel_saturated.unbind(),
            counts,
        })
    }
    /// The estimate packed per row (13: position, velocity, quaternion `w x y z`, body rates).
    #[getter]
    fn state(&self, py: Python<'_>) -> Py<PyAny> {
        self.state.clone_ref(py)
    }
    /// NED position, m (a view of `state`).
    #[getter]
    fn position<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        columns(self.state.bind(py), 0, 3)
    }
    /// NED velocity, m/s (a view of `state`).
    #[getter]
    fn velocity<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        columns(self.state.bind(py), 3, 6)
    }
    /// Attitude quaternion `w x y z` (a view of `state`).
    #[getter]
    fn quaternion<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        columns(self.state.bind(py), 6, 10)
    }
    /// Body rates p, q, r, rad/s (a view of `state`).
    #[getter]
    fn omega<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        columns(self.state.bind(py), 10, 13)
    }
    /// Z-Y-X Euler angles roll, pitch, yaw, rad.
    #[getter]
    fn euler(&self, py: Python<'_>) -> Py<PyAny> {
        self.euler.clone_ref(py)
    }
    /// One sigma of the filter's 15-element error state per row.
    #[getter]
    fn std(&self, py: Python<'_>) -> Py<PyAny> {
        self.std.clone_ref(py)
    }
    #[getter]
    fn gyro_saturated(&self, py: Python<'_>) -> Py<PyAny> {
        self.gyro_saturated.clone_ref(py)
    }
    #[getter]
    fn accel_saturated(&self, py: Python<'_>) -> Py<PyAny> {
        self.accel_saturated.clone_ref(py)
    }
    /// The run's sensor totals.
    #[getter]
    fn counts(&self, py: Python<'_>) -> Py<PySensingCounts> {
        self.counts.clone_ref(py)
    }
    /// One sigma of the position, m (columns 0-2 of `std`).
    #[getter]
    fn position_std_m<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        columns(self.std.bind(py), 0, 3)
    }
    /// One sigma of the velocity, m/s (columns 3-5 of `std`).
    #[getter]
    fn velocity_std_m_s<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        columns(self.std.bind(py), 3, 6)
    }
    /// One sigma of the attitude error, rad (columns 6-8 of `std`).
    #[getter]
    fn attitude_std_rad<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        columns(self.std.bind(py), 6, 9)
    }
    /// The 12-element state vector per row (position, velocity, Euler angles, body rates).
    #[getter]
    fn vector<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let parts = [self.position(py)?, self.velocity(py)?, self.euler.bind(py).clone(), self.omega(py)?];
        py.import("numpy")?.getattr("hstack")?.call1((parts,))
    }
});

/// One run sampled at the control rate, the one trajectory type (`rotorfault.Trajectory`
/// subclasses it, adding what reads it in Python: tables, plots, derived arrays). Its arrays are
/// NumPy arrays with one row per recorded step, made once: by the simulator from the core's
/// record, or given keyword-only (a batch's views, a constructed run), their shapes checked
/// here. Frozen; picklable.
#[pyclass(name = "Trajectory", module = "rotorfault._rfcore", frozen, subclass, get_all)]
pub struct PyTrajectory {
    /// Time of each row, s.
    t: Py<PyAny>,
    /// NED position, m.
    position: Py<PyAny>,
    /// NED velocity, m/s.
    velocity: Py<PyAny>,
    /// Attitude quaternion `w x y z` (body to world).
    quaternion: Py<PyAny>,
    /// Z-Y-X Euler angles roll, pitch, yaw, rad.
    euler: Py<PyAny>,
    /// Body rates p, q, r (FRD), rad/s.
    omega: Py<PyAny>,
    /// Body z in the world frame (Ke's n3).
    primary_axis: Py<PyAny>,
    /// The commands (N per rotor for fixed pitch; speed and pitch interleaved for variable pitch).
    rotor_command: Py<PyAny>,
    /// The rotors' produced thrusts, N.
    rotor_thrust: Py<PyAny>,
    /// Rotor efficiencies applied at each row (faults included), 0 to 1.
    efficiency: Py<PyAny>,
    /// Sensor readings as the core recorded them (12 columns with sensor noise, else none).
    recorded_measurements: Py<PyAny>,
    /// What the controller flew on: `"truth"`, `"paper-noise"` or the sensor suite's name.
    sensed: String,
    /// Why and when the run ended early, or `None`.
    divergence: Option<Py<PyDivergence>>,
    /// With sensing, the estimate per row (13: position, velocity, quaternion `w x y z`, body
    /// rates); else `None`.
    estimate_state: Option<Py<PyAny>>,
    /// With sensing, the estimate's Euler angles per row, rad; else `None`.
    estimate_euler: Option<Py<PyAny>>,
    /// With sensing, one sigma of the estimator's 15-element error state per row; else `None`.
    estimate_std: Option<Py<PyAny>>,
    /// With sensing, per row: the newest IMU sample's gyroscope was clamped; else `None`.
    gyro_saturated: Option<Py<PyAny>>,
    /// With sensing, per row: the newest IMU sample's accelerometer was clamped; else `None`.
    accel_saturated: Option<Py<PyAny>>,
    /// With sensing, the run's totals (IMU samples, clamped samples, measurements fused, refused
    /// by the gate, late); else `None`.
    sensing_counts: Option<Py<PySensingCounts>>,
}

/// The estimate fields, present together (a run with sensing) or not at all.
const ESTIMATE_FIELDS: [&str; 6] = ["estimate_state", "estimate_euler", "estimate_std", "gyro_saturated", "accel_saturated", "sensing_counts"];

/// An array `field` of `ndim` dimensions with `rows` rows and, for a table, a width in `widths`
/// (any width when empty); returns its width.
fn shaped(field: &str, value: &Bound<'_, PyAny>, ndim: usize, rows: Option<usize>, widths: &[usize]) -> PyResult<usize> {
    let array = value.cast::<PyUntypedArray>().map_err(|_| {
        PyTypeError::new_err(format!("{field}: expected a NumPy array, got {}", value.get_type().name().map(|n| n.to_string()).unwrap_or_default()))
    })?;
    let shape = array.shape();
    if shape.len() != ndim {
        return Err(PyValueError::new_err(format!("{field}: expected {ndim} dimensions, got shape {shape:?}")));
    }
    if let Some(rows) = rows {
        if shape[0] != rows {
            return Err(PyValueError::new_err(format!(
                "{field}: expected {rows} rows (one per time in t), got shape {shape:?}"
            )));
        }
    }
    let width = if ndim == 2 { shape[1] } else { 1 };
    if !widths.is_empty() && !widths.contains(&width) {
        let allowed: Vec<String> = widths.iter().map(|w| w.to_string()).collect();
        return Err(PyValueError::new_err(format!(
            "{field}: expected {} columns, got shape {shape:?}",
            allowed.join(" or ")
        )));
    }
    Ok(width)
}

impl PyTrajectory {
    const FIELDS: &'static [&'static str] = &[
        "t", "position", "velocity", "quaternion", "euler", "omega", "primary_axis", "rotor_command",
        "rotor_thrust", "efficiency", "recorded_measurements", "sensed", "divergence",
        "estimate_state", "estimate_euler", "estimate_std", "gyro_saturated", "accel_saturated",
        "sensing_counts",
    ];

    /// The core's record as the constructor's keywords, each array made once (the record's own
    /// vectors moved, not copied).
    fn record_kwargs(py: Python<'_>, run: Trajectory) -> PyResult<Bound<'_, PyDict>> {
        let n = run.t_s.len();
        let table = |values: Vec<f64>| -> PyResult<Py<PyAny>> {
            let cols = values.len().checked_div(n).unwrap_or(0);
            Ok(values.into_pyarray(py).reshape([n, cols])?.into_any().unbind())
        };
        let states = &run.states;
        let per_state = |f: fn(&RigidBodyState) -> [f64; 3]| table(rows(states, f));
        let kwargs = PyDict::new(py);
        kwargs.set_item("sensed", run.sensed())?;
        kwargs.set_item("position", per_state(|s| s.position_m.into())?)?;
        kwargs.set_item("velocity", per_state(|s| s.velocity_m_s.into())?)?;
        kwargs.set_item(
            "quaternion",
            table(rows(states, |s| {
                let q = s.attitude.quaternion();
                [q.w, q.i, q.j, q.k]
            }))?,
        )?;
        kwargs.set_item("euler", per_state(|s| s.euler_rad())?)?;
        kwargs.set_item("omega", per_state(|s| s.omega_rad_s.into())?)?;
        kwargs.set_item("primary_axis", per_state(|s| s.primary_axis().into())?)?;
        if let Some(r) = run.sensing.as_ref() {
            let flags = |f: fn(&EstimateRow) -> bool| r.rows.iter().map(f).collect::<Vec<bool>>().into_pyarray(py);
            kwargs.set_item("estimate_state", table(rows(&r.rows, |row| row.state.to_packed()))?)?;
            kwargs.set_item("estimate_euler", table(rows(&r.rows, |row| row.state.euler_rad()))?)?;
            kwargs.set_item("estimate_std", table(rows(&r.rows, |row| row.std))?)?;
            kwargs.set_item("gyro_saturated", flags(|row| row.gyro_saturated))?;
            kwargs.set_item("accel_saturated", flags(|row| row.accel_saturated))?;
            kwargs.set_item("sensing_counts", Py::new(py, PySensingCounts::from(r))?)?;
        }
        kwargs.set_item("rotor_command", table(run.rotor_command)?)?;
        kwargs.set_item("rotor_thrust", table(run.rotor_thrust_n)?)?;
        kwargs.set_item("efficiency", table(run.efficiency)?)?;
        kwargs.set_item("recorded_measurements", table(run.recorded_measurements)?)?;
        kwargs.set_item("divergence", run.divergence.map(|d| Py::new(py, PyDivergence::from(d))).transpose()?)?;
        kwargs.set_item("t", run.t_s.into_pyarray(py))?;
        Ok(kwargs)
    }

    /// `extra`'s names (the keywords a Python subclass of `Trajectory` adds): strings that are not
    /// a field the run records (`FIELDS`), which they would replace. Checked before the run.
    pub(crate) fn check_extra(extra: Option<&Bound<'_, PyDict>>) -> PyResult<()> {
        for key in extra.map(|e| e.keys()).into_iter().flatten() {
            let Ok(name) = key.extract::<String>() else {
                return Err(PyTypeError::new_err(format!(
                    "extra: names must be strings, got {}",
                    key.get_type().name()?
                )));
            };
            if Self::FIELDS.contains(&name.as_str()) {
                return Err(PyValueError::new_err(format!(
                    "extra: {name:?} is a field the run records (a keyword of extra may not replace it; recorded: {})",
                    Self::FIELDS.join(", ")
                )));
            }
        }
        Ok(())
    }

    /// The core's record as one `trajectory_type` (`Trajectory` or a Python subclass of it, which
    /// gets `extra` keywords too, none a recorded field): made once, by the type's constructor
    /// (one shape check).
    pub(crate) fn from_run<'py>(
        py: Python<'py>,
        run: Trajectory,
        trajectory_type: Option<&Bound<'py, PyType>>,
        extra: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let base = py.get_type::<PyTrajectory>();
        let cls = trajectory_type.unwrap_or(&base);
        if !cls.is_subclass(&base)? {
            return Err(PyTypeError::new_err(format!(
                "trajectory_type: expected a subclass of rotorfault._rfcore.Trajectory, got {}",
                cls.name()?
            )));
        }
        Self::check_extra(extra)?;
        let kwargs = Self::record_kwargs(py, run)?;
        if let Some(extra) = extra {
            kwargs.update(extra.as_mapping())?;
        }
        cls.call((), Some(&kwargs))
    }
}

/// `f` of every row, flattened row-major (no allocation per row).
fn rows<R, const N: usize>(rows: &[R], f: impl Fn(&R) -> [f64; N]) -> Vec<f64> {
    rows.iter().flat_map(f).collect()
}

pickle_protocol!(PyTrajectory, {
    #[new]
    #[pyo3(signature = (*, t, position, velocity, quaternion, euler, omega, primary_axis, rotor_command,
        rotor_thrust, efficiency, recorded_measurements, sensed=None, divergence=None,
        estimate_state=None, estimate_euler=None, estimate_std=None, gyro_saturated=None,
        accel_saturated=None, sensing_counts=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        t: Bound<'_, PyAny>,
        position: Bound<'_, PyAny>,
        velocity: Bound<'_, PyAny>,
        quaternion: Bound<'_, PyAny>,
        euler: Bound<'_, PyAny>,
        omega: Bound<'_, PyAny>,
        primary_axis: Bound<'_, PyAny>,
        rotor_command: Bound<'_, PyAny>,
        rotor_thrust: Bound<'_, PyAny>,
        efficiency: Bound<'_, PyAny>,
        recorded_measurements: Bound<'_, PyAny>,
        sensed: Option<String>,
        divergence: Option<Py<PyDivergence>>,
        estimate_state: Option<Bound<'_, PyAny>>,
        estimate_euler: Option<Bound<'_, PyAny>>,
        estimate_std: Option<Bound<'_, PyAny>>,
        gyro_saturated: Option<Bound<'_, PyAny>>,
        accel_saturated: Option<Bound<'_, PyAny>>,
        sensing_counts: Option<Py<PySensingCounts>>,
    ) -> PyResult<Self> {
        shaped("t", &t, 1, None, &[])?;
        let rows = Some(t.len()?);
        for (field, value, width) in [
            ("position", &position, 3),
            ("velocity", &velocity, 3),
            ("quaternion", &quaternion, 4),
            ("euler", &euler, 3),
            ("omega", &omega, 3),
            ("primary_axis", &primary_axis, 3),
        ] {
            shaped(field, value, 2, rows, &[width])?;
        }
        let rotors = shaped("efficiency", &efficiency, 2, rows, &[])?;
        shaped("rotor_thrust", &rotor_thrust, 2, rows, &[rotors])?;
        shaped("rotor_command", &rotor_command, 2, rows, &[rotors, 2 * rotors])?;
        shaped("recorded_measurements", &recorded_measurements, 2, rows, &[0, STATE_DIM])?;
        let given = [&estimate_state, &estimate_euler, &estimate_std, &gyro_saturated, &accel_saturated]
            .iter()
            .filter(|v| v.is_some())
            .count()
            + usize::from(sensing_counts.is_some());
        if given != 0 && given != ESTIMATE_FIELDS.len() {
            return Err(PyValueError::new_err(format!(
                "{}: give all or none (a run with sensing has all)",
                ESTIMATE_FIELDS.join(", ")
            )));
        }
        for (field, value, ndim, width) in [
            ("estimate_state", &estimate_state, 2, 13),
            ("estimate_euler", &estimate_euler, 2, 3),
            ("estimate_std", &estimate_std, 2, 15),
            ("gyro_saturated", &gyro_saturated, 1, 1),
            ("accel_saturated", &accel_saturated, 1, 1),
        ] {
            if let Some(value) = value {
                shaped(field, value, ndim, rows, &[width])?;
            }
        }
        let keep = |v: Option<Bound<'_, PyAny>>| v.map(Bound::unbind);
        Ok(PyTrajectory {
            t: t.unbind(),
            position: position.unbind(),
            velocity: velocity.unbind(),
            quaternion: quaternion.unbind(),
            euler: euler.unbind(),
            omega: omega.unbind(),
            primary_axis: primary_axis.unbind(),
            rotor_command: rotor_command.unbind(),
            rotor_thrust: rotor_thrust.unbind(),
            efficiency: efficiency.unbind(),
            recorded_measurements: recorded_measurements.unbind(),
            // What a run without noise or sensing flew on (the simulator's name for it).
            sensed: sensed.unwrap_or_else(|| "truth".to_string()),
            divergence,
            estimate_state: keep(estimate_state),
            estimate_euler: keep(estimate_euler),
            estimate_std: keep(estimate_std),
            gyro_saturated: keep(gyro_saturated),
            accel_saturated: keep(accel_saturated),
            sensing_counts,
        })
    }
    /// Whether the run ended early (it has a `divergence`).
    #[getter]
    fn diverged(&self) -> bool {
        self.divergence.is_some()
    }
    /// With sensing, the estimate beside the truth (`Estimates`, views of this run's estimate
    /// fields); else `None`.
    #[getter]
    fn estimate(&self, py: Python<'_>) -> Option<PyEstimates> {
        let (Some(state), Some(euler), Some(std), Some(gyro), Some(accel), Some(counts)) = (
            &self.estimate_state,
            &self.estimate_euler,
            &self.estimate_std,
            &self.gyro_saturated,
            &self.accel_saturated,
            &self.sensing_counts,
        ) else {
            return None;
        };
        Some(PyEstimates {
            state: state.clone_ref(py),
            euler: euler.clone_ref(py),
            std: std.clone_ref(py),
            gyro_saturated: gyro.clone_ref(py),
            accel_saturated: accel.clone_ref(py),
            counts: counts.clone_ref(py),
        })
    }
    /// `Trajectory(<rows> rows to <end> s, <how it ended>)`: the arrays are too long to print.
    fn __repr__(slf: &Bound<'_, Self>) -> PyResult<String> {
        let this = slf.get();
        let py = slf.py();
        let t = this.t.bind(py);
        let rows = t.len()?;
        let end = if rows == 0 { "no rows".to_string() } else { format!("{rows} rows to {} s", t.get_item(rows - 1)?.str()?) };
        let ended = match &this.divergence {
            None => "no divergence".to_string(),
            Some(d) => {
                let d = d.get();
                format!("{} at {} s", d.kind.name(), d.time_s)
            }
        };
        Ok(format!("{}({end}, {ended}, sensed={:?})", slf.get_type().name()?, this.sensed))
    }
});
